"""The shipped missions, run end to end on the simulator on the virtual clock
(``roomba-bt run MISSION --fast``): compiled, streamed, ticked, and ended safely."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.oi import commands as oi

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"


@pytest.mark.parametrize(
    ("mission", "extra"),
    [
        ("square.yaml", ["-p", "side=50cm"]),
        ("custom_condition.yaml", ["--world", "corridor", "--allow-plugin-files"]),
        ("guarded_patrol.yaml", ["--world", "corridor", "-p", "laps=1"]),
        ("show_off.yaml", []),
        ("gentle_sweep.yaml", ["-p", "vacuum=30%"]),
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


#: a room whose robot's main brush jams 2 s into the run (packet 14's bit, for 2 s)
JAMMED = """\
name: jam
rooms: [[[0, 0], [4, 0], [4, 3.5], [0, 3.5]]]
robot: {start: {at: [2, 1.75], heading: 0}}
events:
  - {at: 2, kind: overcurrent, motor: main_brush, duration: 2}
"""


def test_the_gentle_sweep_unwinds_a_jammed_main_brush(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The example's other branch: a jam (packet 14) ends the spiral, the main brush turns
    outward at 30% for a second (``[144][-38][0][0]``), then every motor goes off, said."""
    world, record = tmp_path / "jam.yaml", tmp_path / "run.jsonl"
    world.write_text(JAMMED)
    argv = ["run", str(EXAMPLES / "gentle_sweep.yaml"), "--fast", "--display", "none"]
    assert main([*argv, "--world", str(world), "--record", str(record)]) == 1
    out, err = capsys.readouterr()
    assert "mission said the main brush jammed: unwound, stopped" in out, out + err
    assert "outcome      FAILURE (the main brush jammed: " in out
    lines = record.read_text().splitlines()[1:]
    sent = [bytes.fromhex(e["b"]) for e in map(json.loads, lines) if e.get("d") == "out"]
    pwm = [b for b in sent if b[0] == 144]
    assert pwm == [oi.pwm_motors(51, 51, 64).data, oi.pwm_motors(-38, 0, 0).data,
                   oi.pwm_motors(0, 0, 0).data]  # fmt: skip
