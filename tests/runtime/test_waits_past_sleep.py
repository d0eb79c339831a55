"""A ``wait`` longer than the 5 minutes a robot sleeps after in Passive, on a link whose
keep-awake cannot pulse BRC: named when the run starts, and the ending says the robot slept
on its dock (session 37's stranger: ``patrol -p charge_for=10min`` on a pty docked, slept 5
minutes into the charge wait, and the run exited 8 with only a generic "Passive sleeps after
5 min" line at its start)."""

from __future__ import annotations

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import load_mission, load_mission_text
from roomba_bt.mission.shipped import find_mission
from roomba_bt.robot.errors import RobotAsleep

WAIT_IN_SAFE = """
mission: waits-in-safe
tree:
  sequence:
    - mode: safe
    - wait: 10min
    - mode: passive
"""


def _charge_wait() -> str:
    """Where patrol.yaml's charge wait stands, ``patrol.yaml:LINE:COL`` (read from the file:
    an edit above it moves it)."""
    path = find_mission("patrol").path
    assert path is not None
    lines = path.read_text().splitlines()
    [(line, col)] = [
        (number, text.index("wait:") + 1)
        for number, text in enumerate(lines, 1)
        if 'wait: "${charge_for}"' in text
    ]
    return f"patrol.yaml:{line}:{col}"


def test_the_long_waits_that_may_run_in_passive_are_known_at_compile_time() -> None:
    (said,) = load_mission("patrol", {"charge_for": "10min"}).waits_past_sleep
    assert said.endswith(f"{_charge_wait()}: wait(10min)"), said
    assert load_mission("patrol", {"charge_for": "5min"}).waits_past_sleep == ()
    assert load_mission_text(WAIT_IN_SAFE).waits_past_sleep == ()  # Safe does not sleep


def test_the_run_names_the_wait_at_its_start_and_the_dock_at_its_end(
    capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """The stranger's run on the virtual clock (keep-awake off where the pty had no lines):
    docked on a low battery, asleep 5 minutes into the 10-minute charge wait."""
    code = main([
        "run", "patrol", "-p", "charge_for=10min", "--world", "corridor",
        "--battery", "15.5%", "--fast", "--no-keep-awake",
    ])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 8, out
    [said] = [r.getMessage() for r in caplog.records if "may run in Passive" in r.getMessage()]
    assert f"{_charge_wait()}: wait(10min) may run in Passive" in said
    assert "keep-awake is off (--no-keep-awake): it cannot finish" in said
    assert "the robot fell asleep: 300 s in Passive" in out
    assert "on its dock (charging: it sits there still)" in out


def test_asleep_off_the_dock_says_no_dock() -> None:
    text = str(RobotAsleep("/dev/ttyUSB0", 300.0, keep_awake=True, pulses=True))
    assert "the robot fell asleep" in text and "dock (charging" not in text


CYCLE_ONCE = """
mission: one-cycle-beside-a-wait
tree:
  parallel:
    policy: one
    children:
      - wait: 30min
      - sequence: [{mode: passive}, clean, {wait: 30min}]
"""


def test_a_wait_beside_a_branch_that_starts_the_robot_s_cycle_over_and_over_is_not_named(
    capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """clean-builtin's ``wait: ${duration}`` (20 min) runs beside a ``repeat`` that sends
    Clean every ``${cycle}``: the robot cleans all along, and a cycle runs no sleep. On a
    link without keep-awake (a raw TCP bridge, a pty, ``--no-keep-awake``) every run of it
    began "wait(20min) may run in Passive ... it cannot finish (the robot falls asleep 5
    minutes into it and the run ends, exit 8)", and ended SUCCESS. A cycle started once
    beside a long wait ends and leaves the robot idle: that wait is still named."""
    assert load_mission("clean-builtin", profile="roomba600").waits_past_sleep == ()
    code = main(["run", "clean-builtin", "--profile", "roomba600", "--fast", "--no-keep-awake"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert not [r for r in caplog.records if "may run in Passive" in r.getMessage()]
    (said,) = load_mission_text(CYCLE_ONCE).waits_past_sleep
    assert said.endswith(":7:9: wait(30min)"), said
