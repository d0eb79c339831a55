"""An A/B's episodes run by seed (A1 B1 A2 B2 ...): an interrupted sweep still holds pairs,
and each variant's results come back in its own spec order, the same episodes as before."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.evaluate import EpisodeResult, episode_specs, run_episodes
from roomba_bt.evaluate.interleave import Interleaved
from roomba_bt.evaluate.parallel import Engine, evaluate
from roomba_bt.evaluate.records import written_record

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")
#: in this process, one episode after another: the order they run in is the order given
IN_PROCESS = Engine("local", 1, wall_limit_s=None)


def _ab(runs: int = 3) -> list[list]:  # type: ignore[type-arg]
    return [
        episode_specs(BUMP, runs=runs, seed=5, params=(("duration", duration),), timeout_s=3.0)
        for duration in ("1s", "2s")
    ]


def _rows(results: list[EpisodeResult]) -> list[dict[str, object]]:
    """The records as ``--reproducible`` writes them: the wall-clock times left out."""
    return [written_record(r, reproducible=True) for r in results]


def test_the_batches_are_taken_by_seed_and_handed_back_per_batch() -> None:
    a, b = _ab()
    shorter = b[:2]
    work = Interleaved.of([a, shorter])
    assert [(s.params[0][1], s.seed) for s in work.specs] == [
        ("1s", 5), ("2s", 5), ("1s", 6), ("2s", 6), ("1s", 7),
    ]  # fmt: skip
    finished = {i: f"result {i}" for i in (4, 0, 3)}  # as they finished
    assert work.split(finished) == [["result 0", "result 4"], ["result 3"]]  # type: ignore[arg-type]


def test_the_episodes_run_by_seed_and_each_bar_counts_its_own() -> None:
    """The same results as each batch run alone, in its order; the progress bars saw
    A5 B5 A6 B6 A7 B7, each counting 1..3 of its own 3."""
    seen: list[tuple[str, int, int, int]] = []

    def bar(name: str):  # type: ignore[no-untyped-def]
        def progress(done: int, total: int, result: EpisodeResult) -> None:
            seen.append((name, result.seed, done, total))

        return progress

    batches = _ab()
    done = evaluate(batches, IN_PROCESS, [bar("A"), bar("B")])
    alone = [run_episodes(batch) for batch in batches]
    assert [_rows(e.results) for e in done] == [_rows(results) for results in alone]
    assert seen == [
        ("A", 5, 1, 3), ("B", 5, 1, 3), ("A", 6, 2, 3), ("B", 6, 2, 3),
        ("A", 7, 3, 3), ("B", 7, 3, 3),
    ]  # fmt: skip
    assert not any(e.interrupted for e in done)


def test_an_ab_interrupted_after_three_episodes_holds_a_pair() -> None:
    """A Ctrl-C after A5 B5 A6: B had no episode when variants ran one after another."""
    count = 0

    def ctrl_c_after_three(done: int, total: int, result: EpisodeResult) -> None:
        nonlocal count
        count += 1
        if count == 3:
            raise KeyboardInterrupt

    done = evaluate(_ab(), IN_PROCESS, [ctrl_c_after_three, ctrl_c_after_three])
    assert [[r.seed for r in e.results] for e in done] == [[5, 6], [5]]
    assert all(e.interrupted and e.interruption is not None for e in done)
    assert done[1].interruption is not None and done[1].interruption.cause == "SIGINT"


@pytest.mark.parametrize("jobs", [1, 2])
def test_nothing_to_run_starts_no_pool(jobs: int) -> None:
    """Every episode read back (``eval --resume``): an empty result per batch."""
    done = evaluate([[], []], Engine("local", jobs, wall_limit_s=5.0))
    assert [(e.results, e.interrupted) for e in done] == [([], False), ([], False)]
