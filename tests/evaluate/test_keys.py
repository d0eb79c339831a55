"""``eval --key NAME``: what a mission learned (a blackboard key's value at each episode's end)
as a column of ``--out``, a summary line and ``--json``; and the coverage line's count of the
episodes it leaves out."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from roomba_bt.behaviours.blackboard import write_key
from roomba_bt.cli import main
from roomba_bt.evaluate import EpisodeResult, EpisodeSpec, run_episode
from roomba_bt.evaluate.coverage import summarize_coverage
from roomba_bt.evaluate.episode import Coverage
from roomba_bt.evaluate.keys import summarize_keys
from roomba_bt.evaluate.records import read_results

#: A drive toward whatever is ahead: an episode that meets a wall within 1.2 m writes
#: ``hit`` true, ``side`` and ``far`` 50 cm; one that does not, ``hit`` false and ``far`` 1 m,
#: and never writes ``side``. ``legs`` starts at 0 and is set to 1.
LEARNS = """
mission: learns
blackboard:
  legs: {type: int, initial: 0}
  side: str
  far: distance
  hit: bool
  wp: {fields: {distance: distance, turn: angle}}
  start: mark
tree:
  sequence:
    - mode: safe
    - mark: start
    - set: {key: legs, value: 1}
    - fallback:
        - sequence:
            - drive: {velocity: 300 mm/s, distance: 1.2 m}
              until: {bump: {}}
            - bump: {}
            - set: {key: hit, value: true}
            - set: {key: side, value: wall}
            - set: {key: far, value: 50cm}
        - sequence:
            - set: {key: hit, value: false}
            - set: {key: far, value: 1m}
"""

#: the seeds whose starts in the apartment meet a wall (and those that do not): seeds 1..8
KEYS = ["--key", "hit", "--key", "far", "--key", "side", "--key", "legs"]


def _mission(folder: Path) -> str:
    path = folder / "learns.yaml"
    path.write_text(LEARNS, encoding="utf-8")
    return str(path)


def _evaluated(folder: Path, *extra: str) -> int:
    argv = ["eval", _mission(folder), "--world", "apartment", "--runs", "8", "--seed", "1"]
    return main([*argv, "--no-progress", *KEYS, *extra])


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_key_s_final_value_is_a_column_a_summary_line_and_reads_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    """A plugin author's sweep wanted "how often is the dirt found": the key's value at the
    end of each episode, which neither ``--out`` nor the summary held."""
    out = tmp_path / f"learned{suffix}"
    assert _evaluated(tmp_path, "--out", str(out)) == 0
    text = capsys.readouterr().out
    results = read_results(out)
    hits = [dict(r.keys)["hit"] for r in results]
    met = hits.count(True)
    assert 0 < met < 8, hits  # some episodes met a wall, some did not
    assert f"key          hit: {'true' if met >= 4 else 'false'} " in text
    assert f"true {met}" in text and f"false {8 - met}" in text
    mean = (met * 500 + (8 - met) * 1000) / 8
    assert f"key          far: mean {mean:.4g} mm (sd " in text and "500..1000 mm) over 8" in text
    assert f"key          side: wall {met}; {8 - met} never wrote it" in text
    assert "key          legs: mean 1 (sd 0, 1..1) over 8 episodes" in text
    for result in results:  # each episode's own values, typed again from a CSV's text
        keys = dict(result.keys)
        assert list(keys) == ["hit", "far", "side", "legs"]
        assert keys["far"] == (500.0 if keys["hit"] else 1000.0)
        assert keys["side"] == ("wall" if keys["hit"] else None)
        assert keys["legs"] == 1 and type(keys["legs"]) is int
    header = out.read_text(encoding="utf-8").splitlines()[0]
    assert "key:hit" in header and "key:side" in header


def test_the_json_summary_holds_each_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _evaluated(tmp_path, "--json") == 0
    keys = json.loads(capsys.readouterr().out)["variants"][0]["keys"]
    assert list(keys) == ["hit", "far", "side", "legs"]
    met = keys["hit"]["counts"]["true"]
    assert keys["hit"] == {"unit": "", "written": 8, "never_written": 0,
                           "counts": {"true": met, "false": 8 - met}}  # fmt: skip
    assert keys["far"]["unit"] == "mm" and keys["far"]["min"] == 500.0
    assert keys["side"] == {"unit": "", "written": met, "never_written": 8 - met,
                            "counts": {"wall": met}}  # fmt: skip


@pytest.mark.parametrize(
    ("key", "said"),
    [
        ("nope", "--key nope: mission {mission} declares no blackboard key 'nope' (its keys: "
                 "legs, side, far, hit, wp, start)"),
        ("hits", "declares no blackboard key 'hits' (did you mean 'hit'?)"),
        ("start", "--key start: 'start' of {mission} is an odometry mark, not one value"),
        ("wp", "'wp' of {mission} is a record: name one of its fields (wp.distance, wp.turn)"),
        ("wp.dist", "the record 'wp' of {mission} has no field 'dist' (did you mean 'distance'?)"),
        ("hit.x", "--key hit.x: blackboard key 'hit' of {mission} is no record"),
    ],
)  # fmt: skip
def test_a_key_the_mission_cannot_report_exits_2_before_any_episode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str, said: str
) -> None:
    mission = _mission(tmp_path)
    assert main(["eval", mission, "--runs", "1", "--no-progress", "--key", key]) == 2
    captured = capsys.readouterr()
    assert said.format(mission=mission) in captured.err
    assert captured.out == ""  # no episode ran, no summary


def test_a_record_s_field_is_reported_as_check_reads_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = _mission(tmp_path)
    assert main(["eval", mission, "--runs", "2", "--no-progress", "--key", "wp.turn"]) == 0
    assert "key          wp.turn: no value; 2 never wrote it" in capsys.readouterr().out


def _result(tmp_path: Path) -> EpisodeResult:
    return run_episode(EpisodeSpec(_mission(tmp_path), "apartment", seed=1, keys=("side",)))


def test_a_key_the_episode_before_wrote_is_not_this_episode_s(tmp_path: Path) -> None:
    """py_trees' blackboard is one for the process, and its values stay after a run: an
    evaluation's worker runs episode after episode, and a key one episode wrote was read as
    the next one's (``--key`` reported it; a ``check`` on it was True). A run's set-up now
    unwrites the keys declared without an initial value."""
    write_key("wp", {"distance": 300.0, "turn": 90.0})  # the mission never writes it
    write_key("legs", 7)
    spec = EpisodeSpec(_mission(tmp_path), "empty-room", seed=1, keys=("wp.turn", "legs"))
    assert dict(run_episode(spec).keys) == {"wp.turn": None, "legs": 1}


def test_numbers_are_spread_and_other_values_counted(tmp_path: Path) -> None:
    result = _result(tmp_path)
    results = [replace(result, keys=(("n", n), ("w", w))) for n, w in
               [(2, "a"), (4, "b"), (None, "a"), (6.0, None)]]  # fmt: skip
    n, w = summarize_keys(results, ["n", "w"], {"n": "mm"})
    assert (n.written, n.unwritten, n.counts) == (3, 1, ())
    assert n.numbers is not None and (n.numbers.mean, n.numbers.low, n.numbers.high) == (4, 2, 6)
    assert n.line() == "key          n: mean 4 mm (sd 2, 2..6 mm) over 3 episodes; 1 never wrote it"
    assert w.numbers is None and w.counts == (("a", 2), ("b", 1))
    assert w.line() == "key          w: a 2, b 1; 1 never wrote it"
    assert w.to_dict() == {"unit": "", "written": 3, "never_written": 1,
                           "counts": {"a": 2, "b": 1}}  # fmt: skip


def test_the_coverage_line_says_how_many_episodes_never_ran_the_brushes(tmp_path: Path) -> None:
    """``coverage     of the reachable floor, 9 episodes`` out of 30, without a word of why:
    the others never ran their brushes (a mission that cleans only where it finds dirt)."""
    result = _result(tmp_path)
    cleaned = replace(result, coverage=Coverage("", 0.5, ((0.0, 0.0),), 0.5, (), 1.0, 60.0))
    summary = summarize_coverage([cleaned, result, cleaned, result, result])
    assert summary is not None and summary.never_cleaned == 3
    assert str(summary).startswith(
        "coverage     of the reachable floor, 2 episodes (3 never ran the brushes): mean"
    )
    assert summary.to_dict()["never_cleaned"] == 3
    every = summarize_coverage([cleaned, cleaned])
    assert every is not None and "never ran" not in str(every)
