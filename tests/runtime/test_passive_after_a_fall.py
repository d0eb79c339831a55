"""A wheel or motor leaf that starts after the robot fell to Passive by itself fails in the
tick it starts, its reason the mode, when the run saw the fall, its cause and the fix.

Picked up in Safe, the robot falls to Passive (wheel drop; the spec's, and the simulator's).
A ``turn`` that started afterwards sent nothing and stayed RUNNING for ever: the run ended
at ``--timeout`` with "ran out in turn" (maker finding 2, session 32).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

import roomba_bt
from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import motor_bits
from roomba_bt.oi.modes import OIMode
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.summary import Outcome

from .simrun import LEDGE, RunMission

#: picked up (both wheels) at 1 s for half a second
LIFTED = """\
name: lifted
rooms: [{rect: [0, 0, 4, 4]}]
robot: {start: {at: [2, 2], heading: 0}}
events: [{at: 1, kind: lift, side: both, duration: 0.5}]
"""

LIFT_THEN_TURN = """\
mission: lift then turn
tree:
  sequence: [{mode: safe}, {wait: 3s}, {turn: 90deg}]
"""

FIX = "turn needs Safe or Full; put `mode: safe` before it, e.g. in a retry"


def test_a_turn_started_in_passive_after_a_wheel_drop_fails_at_once(
    run_mission: RunMission, tmp_path: Path
) -> None:
    (tmp_path / "lifted.yaml").write_text(LIFTED)
    seen: list[tuple[float, float | None]] = []

    def observer(runner: MissionRunner) -> None:
        change = runner.snapshot.last_fallback
        seen.append((runner.snapshot.time, None if change is None else change.mission_time))

    run = run_mission(
        LIFT_THEN_TURN, world=str(tmp_path / "lifted.yaml"), timeout=30.0, observer=observer
    )
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    # placed in mission time, on the tick that first showed it
    fell_at = next(placed for _, placed in seen if placed is not None)
    assert fell_at == next(t for t, placed in seen if placed is not None)
    assert 0.9 <= fell_at < 1.1  # mission time begins after the start-up
    assert summary.reason == (
        f"turn(90deg left): the robot is in Passive since t={fell_at:.3f} (wheel drop and "
        f"cliff): {FIX}"
    )
    assert 3.0 <= summary.mission_time_s < 3.05  # the turn's first tick, not the timeout
    assert oi.spin(100, clockwise=False).data not in run.link.written
    assert summary.refused_commands == 0


def test_a_retry_with_safe_first_takes_the_robot_back_and_turns(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """The fix the message names: the turn in a retry, Safe again before it: the turn
    fails in Passive, Safe is entered and the attempt fails, the next attempt turns."""
    (tmp_path / "lifted.yaml").write_text(LIFTED)
    mission = """\
mission: lift then turn, again
tree:
  sequence:
    - mode: safe
    - wait: 3s
    - retry:
        times: 2
        do:
          fallback:
            - turn: 90deg
            - force_failure: {mode: safe}
"""
    run = run_mission(mission, world=str(tmp_path / "lifted.yaml"), timeout=30.0)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert oi.spin(100, clockwise=False).data in run.link.written


def test_the_vacuum_switched_on_after_a_fall_fails_and_nothing_is_refused(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """Forward over a ledge (a cliff: Passive by itself, the drive fails a second on),
    then the vacuum on with no Safe again: the leaf fails naming the mode and the cliff;
    the guard had refused its Motors and the leaf said SUCCESS for a vacuum that never
    ran."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    mission = """\
mission: vacuum after the edge
tree:
  sequence:
    - mode: safe
    - fallback:
        - drive: {velocity: 200 mm/s, distance: 2 m}
        - vacuum: true
"""
    run = run_mission(mission, world=str(tmp_path / "ledge.yaml"))
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    assert "the robot is in Passive since t=" in summary.reason
    assert "(cliff): vacuum needs Safe or Full; put `mode: safe` before it" in summary.reason
    assert summary.refused_commands == 0
    assert oi.motors(motor_bits(vacuum=True)).data not in run.link.written


def _lift_then(leaf: str) -> str:
    return (
        "mission: lift then a leaf\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - song: {number: 0, notes: [C4 250ms]}\n"
        "    - wait: 3s\n"
        f"    - {leaf}\n"
    )


@pytest.mark.parametrize(
    ("leaf", "said"),
    [("leds: {dock: true}", "leds (LEDs 139) needs Safe or Full"),
     ("play: 0", "play (Play 141) needs Safe or Full")],
)  # fmt: skip
def test_leds_and_play_after_a_wheel_drop_fail_at_once_sending_nothing(
    run_mission: RunMission, tmp_path: Path, leaf: str, said: str
) -> None:
    """They said SUCCESS until session 33: the guard refused their bytes after the tick,
    and the run went on (and ended SUCCESS) as if the LEDs had lit or the song had played."""
    (tmp_path / "lifted.yaml").write_text(LIFTED)
    run = run_mission(_lift_then(leaf), world=str(tmp_path / "lifted.yaml"), timeout=30.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    assert "the robot is in Passive since t=" in summary.reason and said in summary.reason
    assert summary.refused_commands == 0


@pytest.mark.parametrize("leaf", ["stop: {motors: true}", "motors: {}", "vacuum: off"])
def test_a_stop_after_a_wheel_drop_succeeds_sending_nothing(
    run_mission: RunMission, tmp_path: Path, leaf: str
) -> None:
    """The robot stopped its wheels and motors when it fell: ``stop``'s ask holds, and its
    Drive 0 is not written for the guard to refuse (docs/protocol.md, "Actuators in
    Passive"). The motors switched off likewise (their Motors 0 was written, refused and
    counted until session 34, failing ``--strict``)."""
    (tmp_path / "lifted.yaml").write_text(LIFTED)
    run = run_mission(_lift_then(leaf), world=str(tmp_path / "lifted.yaml"))
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert run.summary.refused_commands == 0


def test_a_stop_after_mode_passive_validates_and_succeeds_sending_nothing(
    run_mission: RunMission,
) -> None:
    """What ``validate`` accepts since session 34 (a stop in Passive with no cycle the tree
    started) the run does: SUCCESS, and no Drive or Motors after the Start for the guard
    to refuse. ``mode: passive`` switched the vacuum off before its Start."""
    mission = """\
mission: a stop after passive
tree:
  sequence:
    - mode: safe
    - vacuum: on
    - drive: {velocity: 100 mm/s, distance: 5 cm}
    - mode: passive
    - stop: {motors: true}
    - motors: {}
"""
    run = run_mission(mission)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert run.summary.refused_commands == 0
    written = run.link.written
    after_start = written[written.index(oi.motors_off().data + oi.start().data) :]
    assert oi.halt().data not in after_start[2:]
    assert oi.motors_off().data not in after_start[2:]


#: the wall charger's plug put in the robot's socket at 1 s (packet 34 bit 0)
PLUGGED_IN = """\
name: plugged in
rooms: [{rect: [0, 0, 4, 4]}]
robot: {start: {at: [1, 2], heading: 0}}
events: [{at: 1, kind: plug, duration: 30}]
"""


def test_the_wall_charger_plugged_in_mid_drive_is_followed_and_named(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """Safe mode's third stop (both specs: "Charger plugged in and powered"): the robot
    drops to Passive by itself, the mode machine follows it there, and the run's ending
    words name the plug, not the dock (no word of undocking)."""
    (tmp_path / "plugged.yaml").write_text(PLUGGED_IN)
    mission = """\
mission: drive while someone plugs the charger in
tree:
  sequence: [{mode: safe}, {drive: {velocity: 100 mm/s, distance: 1 m}}]
"""
    run = run_mission(mission, world=str(tmp_path / "plugged.yaml"), timeout=30.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE
    assert summary.falls == {"internal charger": 1}
    assert "(internal charger)" in summary.reason and "undock" not in summary.reason
    assert summary.final_mode is OIMode.PASSIVE
    assert "the robot fell to Passive by itself once (internal charger)" in "\n".join(
        summary.lines()
    )
    assert_quoted("docs/simulator.md", "falls the robot fell", "\n".join(summary.lines()))


@pytest.mark.parametrize(
    ("mission", "running"),
    [
        ("bump-and-turn", "bump and turn for a while"),
        ("wall-follow", "follow the wall for a while"),
    ],
)
def test_a_shipped_mission_picked_up_says_wheel_drop_not_a_cliff(
    run_mission: RunMission, tmp_path: Path, mission: str, running: str
) -> None:
    """A robot lifted off the floor reads its wheel drops and every cliff sensor in the same
    frame. The shipped missions' guards named the first cliff they checked: picked up, the
    owner read ``stopped: cliff on the left``, of a robot in their hands. The wheel drop is
    checked first now, and the robot is left stopped in Passive as before."""
    (tmp_path / "lifted.yaml").write_text(LIFTED)
    text = (Path(roomba_bt.__file__).parent / "missions" / f"{mission}.yaml").read_text()
    run = run_mission(text, world=str(tmp_path / "lifted.yaml"), timeout=30.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    assert summary.reason.startswith(f"stopped: wheel drop, while '{running}' ran"), summary.reason
    sim = run.simulator
    assert sim.mode.label == "Passive" and sim.requested_left == sim.requested_right == 0


def test_patrol_picked_up_ends_naming_the_wheel_drop(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """patrol's header says a failure names a wheel drop; it had no check of one. Lifted, it
    took the drop for a cliff: it wrote Safe and a back-off each second into the robot in
    its owner's hands (the firmware dropping it to Passive each time) and, put down, drove
    its laps on from there, SUCCESS. It ends at the lift now, naming it, stopped in Passive."""
    (tmp_path / "lifted.yaml").write_text(LIFTED.replace("duration: 0.5", "duration: 3"))
    text = (Path(roomba_bt.__file__).parent / "missions" / "patrol.yaml").read_text()
    run = run_mission(text, world=str(tmp_path / "lifted.yaml"), timeout=300.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    assert summary.reason.startswith(
        "stopped: a wheel has dropped, as when the robot is lifted or a wheel goes over an "
        "edge, while 'patrol' ran"
    ), summary.reason
    assert summary.mission_time_s < 1.5  # at the lift (1 s), not after laps
    sim = run.simulator
    assert sim.mode.label == "Passive" and sim.requested_left == sim.requested_right == 0
