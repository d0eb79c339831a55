"""``--end-in stop`` on a Roomba 500, which has no Stop (173): it was a warning at run time,
and the run ended in Passive with exit 0. Now a usage error (exit 2) before anything is
sent, naming the option, the profile and what is allowed."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main

MISSION = "mission: sit\ntree:\n  wait: 0.1s\n"


def test_end_in_stop_on_a_roomba500_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    record = tmp_path / "run.jsonl"
    code = main(["run", str(mission), "--fast", "--display", "none", "--profile", "roomba500",
                 "--end-in", "stop", "--record", str(record)])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert (
        "argument --end-in: found stop, but the Roomba 500 series (--profile roomba500) has no "
        "Stop (173); allowed: --end-in passive"
    ) in err
    assert not record.exists() and "outcome" not in out  # nothing ran, nothing was sent


@pytest.mark.parametrize("profile", ["create2", "roomba600"])
def test_end_in_stop_where_the_profile_has_it_runs(
    profile: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    code = main(["run", str(mission), "--fast", "--display", "none", "--profile", profile,
                 "--end-in", "stop"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, out + err
    assert "safe stop    sent" in out and out.rstrip().splitlines()[-1] != ""


def test_a_record_of_a_run_ended_in_stop_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The record says how its stop ended (``"end_in": "stop"`` in its header) and the replay
    ends so too: it ended with Start, and the record's Stop was its first difference at its
    last byte ("expected Stop (173) ad, sent Start (128) 80", exit 1)."""
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    record = tmp_path / "run.jsonl"
    assert main(["run", str(mission), "--fast", "--display", "none", "--end-in", "stop",
                 "--record", str(record)]) == 0  # fmt: skip
    assert "final mode   Off" in capsys.readouterr().out
    assert '"end_in": "stop"' in record.read_text().splitlines()[0]
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "first difference" not in out and "final mode   Off" in out, out
    assert "the tree wrote the same 25 bytes as the recorded run" in out, out
