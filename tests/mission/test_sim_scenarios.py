"""The shipped missions, run end to end on the simulator on the virtual clock
(``roomba-bt run MISSION --fast``): compiled, streamed, ticked, and ended safely."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"


@pytest.mark.parametrize(
    ("mission", "extra"),
    [
        ("square.yaml", ["-p", "side=50cm"]),
        ("custom_condition.yaml", ["--world", "corridor", "--allow-plugin-files"]),
        ("guarded_patrol.yaml", ["--world", "corridor", "-p", "laps=1"]),
        ("show_off.yaml", []),
        ("dock.yaml", []),
    ],
)
def test_example_runs_to_success_in_the_simulator(
    mission: str, extra: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", str(EXAMPLES / mission), "--fast", "--display", "none", "--seed", "1"]
    code = main([*argv, "--timeout", "5min", *extra])
    out, err = capsys.readouterr()
    assert code == 0, out + err
    assert "SUCCESS" in out + err


def test_a_guard_ends_a_patrol_that_meets_the_dock(capsys: pytest.CaptureFixture[str]) -> None:
    """In the empty room the dock is ahead: its charger drops Safe to Passive, and the
    ``while: {oi_mode: safe}`` guard fails the mission (exit 1) instead of driving on."""
    argv = ["run", str(EXAMPLES / "guarded_patrol.yaml"), "--fast", "--display", "none"]
    assert main([*argv, "--world", "empty-room", "--timeout", "5min"]) == 1
