"""A leaf that started a built-in cycle ends it when it is halted or fails (its cycle drove
on in Passive, where nothing else the tree sends stops it), and so does ``mode: passive``;
on the simulator's virtual clock, every byte tapped."""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command
from roomba_bt.oi.modes import OIMode
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.summary import Outcome

from .simrun import Run, RunMission

#: Safe, drive 0, motors off, Start: the cycle's end, in one write
END = b"".join(c.data for c in (oi.safe(), oi.halt(), oi.motors_off(), oi.start()))
#: after the cycle's end the robot is still: the mission checks its own odometry
STILL_AFTER = """
    - mark: s
    - wait: 3s
    - inverter: {odometry: {since: s, distance: 2cm}}
"""
#: the seek_dock halted by a timeout around it (the report's m/seek.yaml)
HALTED_SEEK = """
mission: seek halted
blackboard: {s: mark}
tree:
  sequence:
    - mode: safe
    - turn: 180deg
    - force_success:
        timeout:
          after: 2s
          do: seek_dock
"""
#: the seek_dock that fails by its own timeout (the report's m/seek2.yaml)
FAILED_SEEK = """
mission: seek failed
blackboard: {s: mark}
tree:
  sequence:
    - mode: safe
    - turn: 180deg
    - fallback:
        - seek_dock: {timeout: 2s}
        - log: gave up docking
"""
#: a clean its `while:` guard stops at the first bump (the sim's Clean drives until one)
GUARDED_CLEAN = """
mission: clean until a bump
blackboard: {s: mark}
tree:
  sequence:
    - force_success:
        sequence:
          children:
            - mode: passive
            - clean
            - wait: 60s
        while: {inverter: {bump: any}}
"""
#: a Clean that runs on after its leaf succeeded, then `mode: passive`
PASSIVE_AFTER_CLEAN = """
mission: clean then passive
blackboard: {s: mark}
tree:
  sequence:
    - mode: passive
    - clean
    - wait: 2s
    - mode: passive
"""


def _run(run_mission: RunMission, mission: str) -> Run:
    return run_mission(mission + STILL_AFTER, world="apartment", timeout=90.0)


def _written_after(run: Run, opcode: int) -> list[tuple[float, bytes]]:
    """What was written after the first write of ``opcode``, by the time it was written
    at (the commands of one tick together)."""
    at_times: dict[float, bytes] = {}
    seen = False
    for at, data in run.link.writes:
        if seen:
            at_times[at] = at_times.get(at, b"") + data
        seen = seen or data[:1] == bytes((opcode,))
    return list(at_times.items())


@pytest.mark.parametrize(
    ("mission", "ended_at"),
    [(HALTED_SEEK, 2.0), (FAILED_SEEK, 2.0)],
    ids=["halted by a timeout", "failed by its own timeout"],
)
def test_a_seek_dock_that_does_not_dock_ends_its_cycle(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture, mission: str, ended_at: float
) -> None:
    caplog.set_level(logging.INFO)
    run = _run(run_mission, mission)
    # the robot stood still after the halt (it drove 1.4 m in 5 s before: the firmware's
    # dock search in Passive, the tree waiting)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    sent_at = next(t for t, data in run.link.writes if data == oi.seek_dock().data)
    (at, data), *later = _written_after(run, oi.seek_dock().opcode)
    assert data == END
    assert at - sent_at == pytest.approx(ended_at, abs=0.05)
    # nothing more until the run's own end: the safe stop finds no cycle to end
    assert [d for _, d in later] == [oi.pause_stream().data + oi.start().data]
    assert run.summary.refused_commands == 0
    assert "packet 35 reports" not in caplog.text and "left Safe" not in caplog.text


def test_a_clean_its_guard_stops_ends_its_cycle(run_mission: RunMission) -> None:
    run = _run(run_mission, GUARDED_CLEAN)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    [(_, data), *_] = _written_after(run, oi.clean().opcode)
    assert data == END
    assert run.simulator.builtin is None and run.simulator.motor_bits == 0


def test_mode_passive_ends_a_cycle_that_may_still_drive(run_mission: RunMission) -> None:
    run = _run(run_mission, PASSIVE_AFTER_CLEAN)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    sent_at = next(t for t, data in run.link.writes if data == oi.clean().data)
    [(at, data), *_] = _written_after(run, oi.clean().opcode)
    assert data == END and at - sent_at == pytest.approx(2.0, abs=0.05)


def test_a_docked_seek_dock_sends_nothing_more(run_mission: RunMission) -> None:
    """Docked, Seek Dock's cycle has ended: neither its SUCCESS nor a ``mode: passive``
    after it (nor a parent started over on the dock) sends the cycle's end."""
    run = run_mission(
        """
        mission: dock twice
        tree:
          repeat:
            times: 2
            do:
              sequence: [{mode: passive}, seek_dock, {wait: 1s}, {mode: passive}]
        """,
        world="empty-room",
        timeout=600.0,
    )
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert END not in run.link.written


def test_the_safe_stop_after_a_docked_seek_dock_goes_straight_to_passive(
    run_mission: RunMission,
) -> None:
    """dock-builtin's ending: Seek Dock docked, its cycle ended on the contacts, and the run's
    safe stop is Pause Stream and Start alone. It sent Safe (131), drive 0 and motors off
    first, as for a cycle that may still drive: the 600 / Create 2 spec says charging
    terminates on entering Safe, and a powered charger drops Safe to Passive at once, so the
    robot's charge was cut for nothing. The connection, told nothing more, is not left
    warning of a cycle at the program's end."""
    run = run_mission(
        "tree: {sequence: [{mode: passive}, seek_dock, dock_wait_charge, {mode: passive}]}",
        world="empty-room",
        timeout=600.0,
    )
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert run.simulator.docked
    later = [data for _, data in _written_after(run, oi.seek_dock().opcode)]
    assert later == [oi.pause_stream().data + oi.start().data]
    assert run.runner.connection.running_cycle is None
    assert run.summary.final_mode is OIMode.PASSIVE and run.summary.refused_commands == 0


def test_a_cycle_ended_on_a_powered_dock_says_no_fall(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """Safe on the home base's contacts drops the OI to Passive at once; the Start sent
    after it leaves the model there: no fall to Passive, no resync is said, and the run
    ends in Passive with nothing refused. (Seek Dock's own end on the dock is never sent:
    the test asks for the end once docked, as a Clean sent there and halted would.)"""
    caplog.set_level(logging.INFO)
    asked: list[float] = []

    def end_once_docked(runner: MissionRunner) -> None:
        snap = runner.snapshot
        if not asked and snap.cycle_may_run and snap.frame.charging_sources.home_base:
            asked.append(snap.time)
            runner.outbox.end_cycle(None)

    run = run_mission(
        "tree: {sequence: [{mode: passive}, seek_dock, {wait: 2s}]}",
        world="empty-room",
        timeout=600.0,
        observer=end_once_docked,
    )
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert asked and END in run.link.written
    assert run.simulator.docked
    assert "by itself" not in caplog.text and "packet 35 reports" not in caplog.text
    assert run.summary.refused_commands == 0 and run.summary.final_mode is OIMode.PASSIVE


#: the owner's "spot, then dock" (roomba600-owner finding 2): Seek Dock while the spiral runs
SPOT_THEN_DOCK = """
mission: spot then dock
tree:
  sequence:
    - mode: passive
    - spot
    - wait: 10s
    - seek_dock: {timeout: 5min}
"""
#: clean-builtin's repeat: Clean again while the first cycle still runs
CLEAN_AGAIN = """
mission: clean again
tree:
  sequence:
    - parallel:
        policy: one
        children:
          - wait: 25s
          - repeat:
              do:
                sequence:
                  - mode: passive
                  - clean
                  - wait: 10s
    - mode: safe
    - stop: {motors: true}
    - mode: passive
"""


def test_a_cycle_command_into_a_running_cycle_ends_that_cycle_first(
    run_mission: RunMission,
) -> None:
    """By the spec a cycle command pauses a cycle in progress: the runtime ends the running
    one (Safe, drive 0, motors off, Start) before it sends the next, so the simulator that
    pauses as the spec says docks, and a second Clean starts a cycle."""
    run = run_mission(SPOT_THEN_DOCK, timeout=400.0, cycle_commands_pause=True)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    [(_, data), *_] = _written_after(run, oi.spot().opcode)
    assert data == END + oi.seek_dock().data
    assert not any("paused" in e.detail for e in run.simulator.events if e.kind == "builtin")

    run = run_mission(CLEAN_AGAIN, timeout=60.0, cycle_commands_pause=True)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    ticks: dict[float, bytes] = {}
    for at, data in run.link.writes:
        ticks[at] = ticks.get(at, b"") + data
    cleans = [data for data in ticks.values() if data.endswith(oi.clean().data)]
    assert len(cleans) == 3  # at 0, 10 and 20 s
    assert cleans[1] == cleans[2] == END + oi.clean().data
    assert not any("paused" in e.detail for e in run.simulator.events if e.kind == "builtin")


@pytest.mark.parametrize(
    ("first", "second"),
    [("spot", "{seek_dock: {wait: false}}"), ("{seek_dock: {wait: false}}", "max"),
     ("clean", "spot")],
)  # fmt: skip
def test_two_cycle_leaves_in_one_tick_are_both_written_the_first_ended_between(
    run_mission: RunMission, first: str, second: str
) -> None:
    """``[spot, seek_dock: {wait: false}]`` ends both leaves in one tick: one command per
    channel kept only Seek Dock, and ``spot`` showed SUCCESS for a Spot never sent (session
    28). Both are written, in the tree's order, the first's cycle ended between them (the
    second, written straight after, would pause it: 600 / Create 2 spec)."""
    run = run_mission(f"tree:\n  sequence: [{{mode: safe}}, {first}, {second}, {{wait: 1s}}]\n")
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    cycles = {"spot": oi.spot(), "max": oi.max_clean(), "clean": oi.clean()}
    one, two = (cycles.get(leaf, oi.seek_dock()).data for leaf in (first, second))
    at = next(t for t, data in run.link.writes if data == one)
    written = b"".join(data for t, data in run.link.writes if t == at)
    assert written == one + END + two
    assert run.summary.refused_commands == 0


#: a mission that waits in Passive (the run's start): nothing of it drives the robot
WAITS_IN_PASSIVE = "mission: waits in passive\ntree:\n  wait: 4s\n"
#: the stop from Passive with a cycle that may drive: Safe, drive 0, motors off, pause, Start
STOP_ENDING_A_CYCLE = b"".join(
    c.data for c in (oi.safe(), oi.halt(), oi.motors_off(), oi.pause_stream(), oi.start())
)


@pytest.mark.parametrize(
    "press", [oi.buttons(1), oi.clean()], ids=["clean-button", "clean-from-elsewhere"]
)
def test_a_cycle_the_robot_started_by_itself_is_ended_and_said(
    run_mission: RunMission, press: Command
) -> None:
    """Someone pushes Clean (or the robot's schedule fires) 1 s into a mission waiting in
    Passive: the robot drove 0.7 m in Passive with no warning, and the stop was Start alone
    (Safe first only for a cycle the run wrote), which ends no cycle (docs/protocol.md)."""
    pressed: list[float] = []

    def push(runner: MissionRunner) -> None:
        simulator = runner.connection.transport.simulator  # type: ignore[attr-defined]
        if not pressed and runner.snapshot.time >= 1.0:
            simulator.receive(press.data)  # not through the run: the robot's own doing
            pressed.append(simulator.time)

    run = run_mission(WAITS_IN_PASSIVE, observer=push, cycle_commands_pause=True)
    assert pressed and run.summary.outcome is Outcome.SUCCESS
    assert run.summary.distance_mm > 300.0, "the cycle drove the robot"
    said = run.summary.robot_cycle
    assert said.startswith("the robot started a cycle by itself"), said
    assert "the safe stop ends it with Safe first" in said
    assert f"robot cycle  {said}" in str(run.summary)
    assert run.link.written.endswith(STOP_ENDING_A_CYCLE)
    assert run.summary.safe_stop.startswith("sent safe, drive, motors, pause_resume_stream")
    simulator = run.simulator
    assert simulator.builtin is None and simulator.paused_cycle is None
    assert simulator.mode is OIMode.PASSIVE
    x, y = simulator.x, simulator.y
    for _ in range(100):
        simulator.step()
    assert (simulator.x, simulator.y) == (x, y), "stopped for good"


#: a mission that waits in Passive for longer than the looks take to tell a cycle (3 s)
WAITS_LONG_IN_PASSIVE = "mission: waits long\ntree:\n  sequence:\n    - wait: 20s\n"


def pressing_at(press: Command, at: float, pressed: list[float]) -> Callable[[MissionRunner], None]:
    """An observer that has ``press`` reach the simulated robot at ``at`` s of mission time,
    not through the run (a button pushed, the robot's schedule); when, in ``pressed``."""

    def press_once(runner: MissionRunner) -> None:
        simulator = runner.connection.transport.simulator  # type: ignore[attr-defined]
        if not pressed and runner.snapshot.time >= at:
            simulator.receive(press.data)
            pressed.append(runner.snapshot.time)

    return press_once


def test_a_cycle_the_robot_started_during_the_run_ends_it_at_once(
    run_mission: RunMission,
) -> None:
    """The Clean button pushed 1 s into a 20 s wait in Passive: the robot cleaned the room
    for the 19 s left, the tree taking it for idle, and was said only at the end. The
    once-a-second look sees it drive by itself at three looks running: the run ends there,
    FAILURE (exit 1), and its safe stop ends the cycle with Safe first (docs/protocol.md)."""
    pressed: list[float] = []
    run = run_mission(WAITS_LONG_IN_PASSIVE, observer=pressing_at(oi.buttons(1), 1.0, pressed))
    summary = run.summary
    assert pressed and summary.outcome is Outcome.FAILURE and summary.exit_code == 1
    assert summary.reason.startswith("the robot started a cycle by itself"), summary.reason
    assert "while the tree ran in wait; the run ended there" in summary.reason
    assert summary.mission_time_s <= pressed[0] + 4.0, "three looks after the press, or four"
    assert summary.robot_cycle.endswith("the safe stop ends it with Safe first")
    assert run.link.written.endswith(STOP_ENDING_A_CYCLE)
    assert run.simulator.builtin is None and run.simulator.mode is OIMode.PASSIVE


def pushing(start: float, seconds: float, speed: float) -> Callable[[MissionRunner], None]:
    """An observer that pushes the simulated robot by hand from ``start`` s of mission time
    for ``seconds`` at ``speed`` mm/s: its wheels turn (its encoders count), no motor
    drives them, no cycle runs (the simulator's next step in Passive stops them again)."""

    def push(runner: MissionRunner) -> None:
        simulator = runner.connection.transport.simulator  # type: ignore[attr-defined]
        if start <= runner.snapshot.time < start + seconds:
            simulator._move(speed, speed, 0.015)  # a hand, not the robot: no command

    return push


@pytest.mark.parametrize(
    ("start", "seconds", "speed"),
    [(1.2, 0.5, 400.0), (1.8, 0.5, 400.0), (2.9, 0.5, 600.0)],
    ids=["between-looks", "across-a-look", "at-the-end"],
)  # fmt: skip
def test_a_robot_pushed_by_hand_in_passive_is_no_cycle(
    run_mission: RunMission, start: float, seconds: float, speed: float
) -> None:
    """0.2-0.3 m pushed by hand in half a second, in Passive, was taken for a cycle the robot
    started by itself (over 100 mm driven in Passive), said so, and ended with Safe first. A
    cycle drives on: a push, over in a moment, is none. One in the run's last second, which
    the looks had no time to tell from a cycle, is said as either, and the stop sends Safe
    first all the same (Start alone would leave a cycle driving after the run)."""
    run = run_mission(WAITS_IN_PASSIVE, observer=pushing(start, seconds, speed))
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert run.summary.distance_mm > 150.0, "the hand moved it"
    said = run.summary.robot_cycle
    assert not said.startswith("the robot started a cycle by itself"), said
    at_the_end = start + seconds > 3.0  # the last look
    assert run.link.written.endswith(STOP_ENDING_A_CYCLE) is at_the_end
    if at_the_end:
        assert said.startswith("the robot was moving in Passive with no command of the run's")
        assert "a cycle it started by itself (its Clean, Spot or Dock button, or its " in said
        assert said.endswith("or a hand; the safe stop ends it with Safe first"), said
    else:
        assert said == ""


def test_a_mission_that_stays_in_passive_sees_no_cycle_of_the_robot_s(
    run_mission: RunMission,
) -> None:
    run = run_mission(WAITS_IN_PASSIVE)
    assert run.summary.robot_cycle == ""
    assert not run.link.written.endswith(STOP_ENDING_A_CYCLE)


def test_a_drive_before_mode_passive_is_not_taken_for_a_cycle(run_mission: RunMission) -> None:
    """The path is measured from the ``mode: passive`` written: the run's own drive before
    it is not a cycle of the robot's."""
    run = run_mission(
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 500 mm/s, duration: 1s}\n"
        "    - mode: passive\n    - wait: 1s\n"
    )
    assert run.summary.outcome is Outcome.SUCCESS and run.summary.robot_cycle == ""


#: waits for the Clean button in Passive (a mission that reads packet 18), then Safe and on
WAITS_FOR_CLEAN = """\
mission: waits for clean
tree:
  sequence:
    - wait: 10s
      until: {button: clean}
    - wait: 2s
    - mode: safe
    - wait: 1s
"""


def test_the_clean_button_pressed_in_passive_ends_the_run_at_the_press(
    run_mission: RunMission,
) -> None:
    """Maker finding 3 (session 32): the mission waited in Passive for the Clean button,
    which started the robot's own cleaning cycle; it drove 0.61 m during the next ``wait:
    2s``, the mission's ``mode: safe`` ended it, and the run said nothing. With the buttons
    in the stream, the press is the cycle's start (the OI spec): the run ends there,
    FAILURE, said, the cycle ended by the safe stop with Safe first."""
    pressed: list[float] = []
    run = run_mission(WAITS_FOR_CLEAN, observer=pressing_at(oi.buttons(1), 1.0, pressed))
    summary = run.summary
    assert pressed and summary.outcome is Outcome.FAILURE, summary.reason
    assert summary.reason.startswith(
        "the robot started a cycle by itself: its Clean button was pressed in Passive "
        "(packet 18), where it starts the robot's own cycle"
    ), summary.reason
    assert "a mission that waits for a button puts `mode: safe` first" in summary.reason
    assert summary.mission_time_s <= pressed[0] + 0.1, "at the press"
    assert summary.distance_mm < 100.0
    assert summary.robot_cycle.endswith("the safe stop ends it with Safe first")
    assert run.link.written.endswith(STOP_ENDING_A_CYCLE)
    assert run.simulator.builtin is None and run.simulator.mode is OIMode.PASSIVE


def test_a_tree_that_ends_at_the_press_still_has_the_cycle_said_and_ended(
    run_mission: RunMission,
) -> None:
    """The tree's last leaf waits for the button: it ends SUCCESS on the press's tick, before
    any look, and before the cycle has moved the robot; the stop's Start alone would have
    left the cycle driving after the run."""
    pressed: list[float] = []
    mission = "mission: last\ntree:\n  wait: 10s\n  until: {button: clean}\n"
    run = run_mission(mission, observer=pressing_at(oi.buttons(1), 0.5, pressed))
    assert pressed and run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert run.summary.robot_cycle.startswith("the robot started a cycle by itself: its Clean")
    assert run.link.written.endswith(STOP_ENDING_A_CYCLE)
    assert run.simulator.builtin is None


def test_a_short_cycle_the_tree_ends_with_safe_is_said(run_mission: RunMission) -> None:
    """The same press with no buttons in the stream: the cycle drove between two looks
    (fewer than the three that tell it from a hand), and the mission's own ``mode: safe``
    ended it. It is judged as the Safe is written, and said: the robot drove in Passive by
    itself, the run's Safe ended it; the run goes on (the tree has the robot again)."""
    pressed: list[float] = []
    mission = "mission: short\ntree:\n  sequence: [{wait: 2.5s}, {mode: safe}, {wait: 1s}]\n"
    run = run_mission(mission, observer=pressing_at(oi.buttons(1), 1.0, pressed))
    summary = run.summary
    assert pressed and summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.distance_mm > 200.0, "the cycle drove the robot"
    said = summary.robot_cycle
    assert said.startswith("the robot was moving in Passive with no command of the run's as "
                           "the run left Passive ("), said  # fmt: skip
    assert said.endswith("or a hand; the run's Safe (131) at t=2.505 ended it"), said
    assert f"robot cycle  {said}" in str(summary)
    assert summary.safe_stop.startswith("sent drive, motors"), summary.safe_stop  # no Safe
    assert run.simulator.builtin is None
