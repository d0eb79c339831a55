"""The robot's own falls to Passive (a cliff in Safe, ...) in an evaluation: per episode, in
its records, and summed in the report, in the run summary's words. ``eval`` counted none: 200
episodes of a cleaning mission could fall off a stair edge 4 times each and the report said
nothing of it."""

from __future__ import annotations

import csv
import json
import pickle
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from runtime.simrun import LEDGE, TWICE_OVER_THE_EDGE  # tests/runtime: the room with a drop

from roomba_bt.cli import main
from roomba_bt.evaluate import EpisodeResult, episode_specs, run_episodes, summarize
from roomba_bt.evaluate.episode import HUNG
from roomba_bt.evaluate.parallel import Engine, evaluate
from roomba_bt.evaluate.records import (
    ResultsFileError,
    from_record,
    read_results,
    to_record,
    write_results,
)
from roomba_bt.mission import Permissions
from roomba_bt.runtime.summary import falls_said

from .test_wall_limit import _STUCK as STUCK_PLUGIN

#: For LEDGE (its starts 0.6..1.6 m from the edge): Safe, then 1 m forward: over the edge
#: (a fall, the drive fails) or short of it (success).
TOWARD_THE_EDGE = """\
mission: toward the edge
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: 1 m}
"""

RUNS = 8
CLIFF_ONCE = (("cliff", 1),)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    folder = tmp_path_factory.mktemp("falls")
    texts = {"ledge": LEDGE, "toward": TOWARD_THE_EDGE, "twice": TWICE_OVER_THE_EDGE}
    for name, text in texts.items():
        (folder / f"{name}.yaml").write_text(text, encoding="utf-8")
    return {name: str(folder / f"{name}.yaml") for name in texts}


@pytest.fixture(scope="module")
def toward(files: dict[str, str]) -> list[EpisodeResult]:
    """The episodes toward the edge, on two worker processes: each result crossed a pickle."""
    specs = episode_specs(files["toward"], world=files["ledge"], runs=RUNS, seed=0,
                          timeout_s=30.0)  # fmt: skip
    return run_episodes(specs, jobs=2)


def test_each_episode_carries_its_falls_and_the_report_sums_them(
    toward: list[EpisodeResult],
) -> None:
    fell = [r for r in toward if r.falls]
    assert {r.falls for r in toward} == {(), CLIFF_ONCE}, "some reach the edge, some do not"
    assert all(not r.succeeded for r in fell) and all(r.succeeded for r in toward if not r.falls)
    assert pickle.loads(pickle.dumps(toward)) == toward
    summary = summarize("toward", "ledge", toward)
    assert summary.falls == (("cliff", len(fell)),)
    assert summary.episodes_with_falls == len(fell)
    assert (
        f"falls        the robot fell to Passive by itself {len(fell)} times (cliff) in "
        f"{len(fell)} of {RUNS} episodes"
    ) in summary.lines()
    assert summary.to_dict()["falls"] == {"cliff": len(fell)}
    assert summary.to_dict()["episodes_with_falls"] == len(fell)
    assert_quoted("docs/evaluation.md", "falls the robot fell to Passive by itself 5 times",
                  "\n".join(summary.lines()), numbers=True)  # fmt: skip


def test_an_episode_s_falls_are_the_ones_its_run_summary_says(
    files: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """The same seed run alone (``roomba-bt run --random-start --seed``) prints the falls
    line the episode's record holds, word for word."""
    (episode,) = run_episodes(episode_specs(files["twice"], world=files["ledge"], runs=1,
                                            seed=3, timeout_s=30.0))  # fmt: skip
    assert episode.falls == (("cliff", 2),)
    main(["run", files["twice"], "--world", files["ledge"], "--fast", "--random-start",
          "--seed", "3", "--display", "none"])  # fmt: skip
    said = f"falls        {falls_said(dict(episode.falls))}"
    assert said == "falls        the robot fell to Passive by itself 2 times (cliff)"
    assert said in capsys.readouterr().out.splitlines()


def _episode(seed: int, falls: tuple[tuple[str, int], ...]) -> EpisodeResult:
    return EpisodeResult(seed, "failure", "", 1.0, 0.1, 1, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0,
                         (), False, False, 0, False, 0, 0.0, 0.0, falls=falls)  # fmt: skip


def test_falls_of_several_causes_are_summed_the_commonest_first() -> None:
    results = [
        _episode(1, (("cliff", 3),)),
        _episode(2, ()),
        _episode(3, (("cliff", 1), ("wheel drop", 1))),
        _episode(4, (("charger", 1),)),
    ]
    summary = summarize("m", "w", results)
    assert summary.falls_text() == (
        "the robot fell to Passive by itself 5 times (cliff 4, wheel drop 1) "
        "in 2 of 4 episodes (cliff in 2, wheel drop in 1)"
    )
    assert summary.to_dict()["episodes_with_falls_by_cause"] == {
        "cliff": 2, "charger": 1, "wheel drop": 1
    }  # fmt: skip
    none = summarize("m", "w", [_episode(1, ())])
    assert not any(line.startswith(("falls", "charger")) for line in none.lines())
    assert none.to_dict()["falls"] == {} and none.to_dict()["episodes_with_falls"] == 0


def test_the_charger_s_falls_are_dockings_said_apart_from_the_hazards() -> None:
    """A dock mission that docks in Safe falls to Passive on the charger in every episode:
    its success. The report counted those with the cliffs, ``fell to Passive by itself 13
    times (charger 10, cliff 3) in 10 of 10 episodes``: a hazard in every episode. Now the
    falls line has the hazards alone, as ``run``'s summary does, and a charger line the
    dockings; ``--json`` has both apart."""
    docked = (("charger", 1),)
    results = [_episode(seed, (("charger", 1), ("cliff", 1)) if seed in (1, 3, 8) else docked)
               for seed in range(1, 11)]  # fmt: skip
    summary = summarize("dock", "apartment", results)
    lines = summary.lines()
    assert (
        "falls        the robot fell to Passive by itself 3 times (cliff) in 3 of 10 episodes"
        in lines
    )
    assert (
        "charger      docked 10 times in 10 of 10 episodes (the robot drops to Passive by itself "
        "on the charger: how docking in Safe ends, not a hazard)"
    ) in lines
    assert_quoted(
        "docs/evaluation.md", "falls the robot fell to Passive by itself 3 times", str(summary)
    )
    assert_quoted("docs/evaluation.md", "charger docked 10 times in 10 of 10", str(summary))
    said = summary.to_dict()
    assert (said["hazard_falls"], said["episodes_with_hazard_falls"]) == ({"cliff": 3}, 3)
    assert (said["charger_arrivals"], said["episodes_with_charger_arrivals"]) == (10, 10)
    assert said["falls"] == {"charger": 10, "cliff": 3}  # every cause, as it was
    assert said["episodes_with_falls"] == 10
    only_docked = summarize("dock", "apartment", [_episode(1, docked)])
    assert not any(line.startswith("falls") for line in only_docked.lines())
    assert "charger      docked once in 1 of 1 episodes" in str(only_docked)
    assert only_docked.to_dict()["hazard_falls"] == {}
    assert to_record(results[0])["hazard_falls"] == 1 and to_record(results[1])["hazard_falls"] == 0


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_eval_with_two_jobs_reports_and_records_the_falls(
    files: dict[str, str],
    toward: list[EpisodeResult],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    suffix: str,
) -> None:
    out = tmp_path / f"falls{suffix}"
    code = main(["eval", files["toward"], "--world", files["ledge"], "--runs", str(RUNS),
                 "--timeout", "30s", "--jobs", "2", "--no-progress",
                 "--out", str(out)])  # fmt: skip
    assert code == 0
    fell = sum(1 for r in toward if r.falls)
    assert (
        f"falls        the robot fell to Passive by itself {fell} times (cliff) in {fell} of "
        f"{RUNS} episodes"
    ) in capsys.readouterr().out.splitlines()
    again = read_results(out)
    assert [r.falls for r in again] == [r.falls for r in toward]
    assert summarize("toward", "ledge", again).falls == (("cliff", fell),)
    if suffix == ".jsonl":
        records = [json.loads(line) for line in out.read_text().splitlines()]
        assert [(r["falls"], r["falls_by_cause"]) for r in records] == [
            (1, {"cliff": 1}) if r.falls else (0, {}) for r in toward
        ]
    else:
        assert "falls,falls_by_cause" in out.read_text().splitlines()[0]
        assert ",1,cliff=1," in out.read_text()


def test_eval_json_has_the_falls(
    files: dict[str, str], toward: list[EpisodeResult], capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["eval", files["toward"], "--world", files["ledge"], "--runs", str(RUNS),
                 "--timeout", "30s", "--no-progress", "--json"])  # fmt: skip
    assert code == 0
    (variant,) = json.loads(capsys.readouterr().out)["variants"]
    fell = sum(1 for r in toward if r.falls)
    assert variant["falls"] == {"cliff": fell} and variant["episodes_with_falls"] == fell
    assert variant["hazard_falls"] == {"cliff": fell}
    assert variant["episodes_with_hazard_falls"] == fell and variant["charger_arrivals"] == 0


def test_a_record_written_before_falls_were_recorded_still_loads(
    toward: list[EpisodeResult], tmp_path: Path
) -> None:
    """Files from before: no ``falls``, ``falls_by_cause`` nor ``hazard_falls`` column, read
    as no falls."""
    record = to_record(next(r for r in toward if r.falls))
    old = {k: v for k, v in record.items() if k not in ("falls", "falls_by_cause", "hazard_falls")}
    assert from_record(old).falls == ()
    path = tmp_path / "old.jsonl"
    path.write_text(json.dumps(old) + "\n", encoding="utf-8")
    (loaded,) = read_results(path)
    assert loaded.falls == () and loaded.seed == record["seed"]
    csv_path = tmp_path / "old.csv"
    write_results(csv_path, toward)
    with open(csv_path, encoding="utf-8", newline="") as src:
        rows = list(csv.DictReader(src))
    with open(csv_path, "w", encoding="utf-8", newline="") as out:
        columns = [c for c in rows[0] if c not in ("falls", "falls_by_cause", "hazard_falls")]
        writer = csv.DictWriter(out, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    assert "falls" not in csv_path.read_text(encoding="utf-8").splitlines()[0]
    assert [r.falls for r in read_results(csv_path)] == [()] * RUNS


def test_a_bad_falls_cell_names_the_line(tmp_path: Path, toward: list[EpisodeResult]) -> None:
    record = to_record(toward[0])
    path = tmp_path / "bad.jsonl"
    no_fall = {"falls_by_cause": {"cliff": 0}, "falls": 0, "hazard_falls": 0}  # their sums
    path.write_text(json.dumps({**record, **no_fall}) + "\n")
    assert read_results(path)[0].falls == ()  # counted 0: no fall
    for bad in ({"cliff": -1}, {"cliff": "often"}, {"cliff": 1.5}, [1]):
        path.write_text(json.dumps({**record, "falls_by_cause": bad}) + "\n", encoding="utf-8")
        with pytest.raises(ResultsFileError, match=r"bad.jsonl:1: bad value"):
            read_results(path)


@pytest.mark.extra("cluster")
def test_a_dask_worker_hands_back_the_falls(
    files: dict[str, str], toward: list[EpisodeResult]
) -> None:
    """On a local Dask cluster of 2 worker processes, the same falls as in local processes."""
    specs = episode_specs(files["toward"], world=files["ledge"], runs=RUNS, seed=0,
                          timeout_s=30.0)  # fmt: skip
    (done,) = evaluate([specs], Engine("dask", jobs=2))
    assert [r.falls for r in done.results] == [r.falls for r in toward]
    on_dask, local = summarize("t", "l", done.results), summarize("t", "l", toward)
    assert (on_dask.falls, on_dask.episodes_with_falls) == (local.falls, local.episodes_with_falls)


def test_a_hung_episode_keeps_the_falls_before_it_was_stuck(
    files: dict[str, str], tmp_path: Path
) -> None:
    """Stuck after a fall: the record of an episode ended at ``--wall-limit`` has the falls
    the connection counted by then (the runner copies them into its summary only at a run's
    end, which a stuck episode never reaches)."""
    (tmp_path / "stuck.py").write_text(STUCK_PLUGIN)
    mission = tmp_path / "fall-then-stuck.yaml"
    mission.write_text(
        "plugins: [./stuck.py]\ntree:\n  sequence:\n    - mode: safe\n    - fallback:\n"
        "        - drive: {velocity: 200 mm/s, distance: 3 m}\n        - cliff: any\n"
        "    - stuck\n"
    )
    specs = episode_specs(str(mission), world=files["ledge"], runs=1, seed=3, timeout_s=30.0,
                          permissions=Permissions(plugin_files=True))  # fmt: skip
    (hung,) = run_episodes(specs, jobs=1, wall_limit_s=2.0)
    assert hung.outcome == HUNG and hung.stage == "stuck"
    assert hung.falls == CLIFF_ONCE
