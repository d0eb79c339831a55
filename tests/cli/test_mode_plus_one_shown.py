"""A Roomba 600 reports packet 35 as the mode + 1. The connection corrects it, yet
``roomba-bt sensors`` printed the raw reading: ``35 oi_mode 2 safe`` for a robot in Passive.
The table shows the mode corrected now, and says so; ``run``'s display and summary read the
mode model (corrected) and show Passive too."""

from __future__ import annotations

from pathlib import Path

import pytest
from robot.sim_backend import sim_pty_server  # tests/robot: the simulator on a pty

from roomba_bt.cli import main
from roomba_bt.oi.profiles import ROOMBA600


def _mode_row(out: str) -> str:
    return next(line for line in out.splitlines() if line.split()[:2] == ["35", "oi_mode"])


def test_sensors_shows_a_600s_mode_corrected(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sensors", "--profile", "roomba600", "--count", "1"]) == 0
    row = _mode_row(capsys.readouterr().out)
    assert "1 passive (reads 2: a 600's mode + 1)" in row, row


def test_sensors_on_a_600_over_a_pty_with_the_default_profile(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The create2 profile does not expect the bug; the connection learns it at start-up."""
    with sim_pty_server(ROOMBA600) as port:
        assert main(["sensors", "--port", port, "--count", "1"]) == 0
    row = _mode_row(capsys.readouterr().out)
    assert "1 passive (reads 2" in row and "safe" not in row, row


def test_sensors_on_a_create2_shows_the_reading_as_is(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sensors", "--count", "1"]) == 0
    row = _mode_row(capsys.readouterr().out)
    assert row.split()[2:4] == ["1", "passive"] and "reads" not in row, row


def test_run_on_a_600_shows_passive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text("mission: sit\ntree:\n  wait: 0.1s\n")
    code = main(["run", str(mission), "--profile", "roomba600", "--fast", "--display", "tree"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "mode=Passive" in out and "mode=Safe" not in out  # the tree's sensor line
    assert "final mode   Passive" in out
