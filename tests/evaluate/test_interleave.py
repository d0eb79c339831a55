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


def test_the_bars_callback_keeps_nothing_per_episode() -> None:
    """To find each result's variant, the callback kept a deque per episode (760 bytes,
    held to the end of the run): 76 MB at 100 000 episodes; then each episode's batch by its
    key, 10 MB. A result's variant names its batch: what it keeps is the same for 4000
    episodes as for 4, and stays so as their results come."""
    import dataclasses
    import tracemalloc

    batches = [
        episode_specs(BUMP, runs=2000, params=(("duration", duration),), trace_every=0)
        for duration in ("1s", "2s")
    ]
    work = Interleaved.of(batches)
    counted = [0, 0]

    def bar(b: int):  # type: ignore[no-untyped-def]
        def progress(done: int, total: int, result: EpisodeResult) -> None:
            counted[b] = done

        return progress

    result = EpisodeResult(seed=0, outcome="success", reason="", time_s=1.0, wall_s=0.1,
                           ticks=1, start=(0, 0, 0), end=(0, 0, 0), bumps=0, contact_steps=(),
                           docked=False, charging=False, cliffs=0, fell=False, violations=0,
                           loops=0.0, longest_stall_s=0.0)  # fmt: skip
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        callback = work.progress([bar(0), bar(1)])
        assert callback is not None
        held = tracemalloc.get_traced_memory()[0] - before
        for spec in work.specs:
            callback(0, 0, dataclasses.replace(result, mission=spec.mission, params=spec.params,
                                               seed=spec.seed))  # fmt: skip
        left = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert counted == [2000, 2000]
    assert held < 4000, held  # 400 000 bytes before
    assert left < 4000, left


@pytest.mark.parametrize("sizes", [(3, 3), (3, 1), (1, 4, 2), (0, 2), (2, 0, 2), (5,)])
def test_each_place_is_that_of_the_spec_taken_by_seed(sizes: tuple[int, ...]) -> None:
    """Batches of any sizes: the specs in the order A1 B1 C1 A2 C2 ..., a shorter batch left
    out once it is done, each found in its batch at its place."""
    batches = [[f"{'ABC'[b]}{i + 1}" for i in range(n)] for b, n in enumerate(sizes)]
    order = [(b, i) for i in range(max(sizes)) for b, n in enumerate(sizes) if i < n]
    work = Interleaved.of(batches)  # type: ignore[arg-type]
    assert [work.place(i) for i in range(len(work.specs))] == order
    assert list(work.specs) == [batches[b][i] for b, i in order]
    assert [work.specs[i] for i in range(len(order))] == list(work.specs)


def test_the_interleaved_plans_of_a_million_episodes_are_made_as_they_are_taken() -> None:
    """A sweep's specs were made before the first episode ran, every one (``eval --runs
    100000``: about 100 MB held before the first result), and put in one list again by
    seed. A plan makes each as it is taken: its last is found in a two-variant
    million-episode sweep with almost nothing held."""
    import tracemalloc

    from roomba_bt.evaluate import episode_plan

    tracemalloc.start()
    try:
        plans = [episode_plan(BUMP, runs=1_000_000, params=(("duration", d),)) for d in "12"]
        work = Interleaved.of(plans)
        last = work.specs[len(work.specs) - 1]
        held = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert (last.seed, last.params) == (999_999, (("duration", "2"),))
    assert held < 100_000, held


def test_a_batch_given_twice_has_each_result_counted_on_its_own_bar_in_turn() -> None:
    """Two batches of the same specs (the same key twice): the first result of a key goes
    to the first batch holding it, the next to the next."""
    import dataclasses

    a = _ab(2)[0]
    work = Interleaved.of([a, a])
    seen: list[tuple[int, int]] = []
    callback = work.progress(
        [
            lambda done, total, r: seen.append((0, r.seed)),
            lambda done, total, r: seen.append((1, r.seed)),
        ]
    )
    assert callback is not None
    result = run_episodes(a[:1])[0]
    for spec in work.specs:
        callback(0, 0, dataclasses.replace(result, seed=spec.seed))
    assert seen == [(0, 5), (1, 5), (0, 6), (1, 6)]
