"""The tick loop on the simulator's virtual clock: endings, safe stop bytes, reaction, clock."""

from __future__ import annotations

import itertools
import signal
from pathlib import Path
from typing import Any

import py_trees
import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import motor_bits
from roomba_bt.oi.frames import SLOT_SECONDS, stream_frame_size
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Faults, Simulator, load_world

from .simrun import (
    DRIVE_TO_WALL,
    DRIVE_TO_WALL_AND_BACK_OFF,
    LEDGE,
    SPIN,
    RunMission,
    TapLink,
    over_the_edge,
)

HALT = oi.halt().data
MOTORS_OFF = oi.motors_off().data
PAUSE = oi.pause_stream().data
START = oi.start().data
STOP = oi.stop().data
SAFE_END = HALT + MOTORS_OFF + PAUSE + START


def test_success_ends_with_the_safe_stop_bytes(run_mission: RunMission) -> None:
    run = run_mission(DRIVE_TO_WALL)
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.summary.exit_code == 0
    assert run.link.written.endswith(SAFE_END)
    assert run.simulator.mode is OIMode.PASSIVE
    assert run.simulator.requested_left == 0 and run.simulator.requested_right == 0
    assert run.summary.final_mode is OIMode.PASSIVE
    assert run.summary.distance_mm > 100
    assert run.summary.battery_percent is not None
    assert run.simulator.violations == []


def test_stop_ending_sends_stop_173(run_mission: RunMission) -> None:
    run = run_mission(DRIVE_TO_WALL, end_in="stop")
    assert run.link.written.endswith(HALT + MOTORS_OFF + PAUSE + STOP)
    assert run.simulator.mode is OIMode.OFF


def test_failure_is_exit_1_and_names_the_failed_leaf(run_mission: RunMission) -> None:
    run = run_mission(
        """
        tree:
          sequence:
            - mode: safe
            - charging: {}
        """
    )
    assert run.summary.outcome is Outcome.FAILURE
    assert run.summary.exit_code == 1
    assert "charging" in run.summary.reason
    assert run.link.written.endswith(SAFE_END)


def test_timeout_counts_mission_time(run_mission: RunMission) -> None:
    run = run_mission(SPIN, timeout=1.5)
    assert run.summary.outcome is Outcome.TIMEOUT
    assert run.summary.exit_code == 1
    assert run.summary.mission_time_s == pytest.approx(1.5, abs=0.016)
    assert run.summary.ticks == round(1.5 / 0.015) + 1
    assert run.link.written.endswith(SAFE_END)


#: what :func:`_bump_raises_after` raises to stand for Ctrl-C: the signal itself
SIGINT_NOW = KeyboardInterrupt("the signal")


def _bump_raises_after(monkeypatch: pytest.MonkeyPatch, error: BaseException, ticks: int) -> None:
    """The bump condition returns FAILURE for ``ticks`` ticks, then raises ``error``."""
    from roomba_bt.behaviours import conditions

    calls = {"n": 0}

    def update(self: object) -> py_trees.common.Status:
        calls["n"] += 1
        if calls["n"] > ticks:
            if error is SIGINT_NOW:
                signal.raise_signal(signal.SIGINT)
            raise error
        return py_trees.common.Status.FAILURE

    monkeypatch.setattr(conditions.Bump, "update", update)


def test_exception_in_a_behaviour_still_stops_the_robot(
    run_mission: RunMission, monkeypatch: pytest.MonkeyPatch
) -> None:
    _bump_raises_after(monkeypatch, RuntimeError("sensor model exploded"), 20)
    run = run_mission(DRIVE_TO_WALL)
    assert run.summary.outcome is Outcome.ERROR
    assert "sensor model exploded" in run.summary.reason
    assert run.link.written.endswith(SAFE_END)
    assert run.simulator.requested_left == 0 and run.simulator.requested_right == 0


def test_ctrl_c_is_exit_130_after_the_safe_stop(
    run_mission: RunMission, monkeypatch: pytest.MonkeyPatch
) -> None:
    _bump_raises_after(monkeypatch, SIGINT_NOW, 20)  # a behaviour's own raise: its error
    run = run_mission(DRIVE_TO_WALL)
    assert run.summary.outcome is Outcome.INTERRUPTED
    assert run.summary.exit_code == 130
    assert run.link.written.endswith(SAFE_END)


def test_lost_stream_trips_the_watchdog_and_stops(run_mission: RunMission) -> None:
    run = run_mission(SPIN, stall_after=1.0, timeout=5.0)
    assert run.summary.outcome is Outcome.CONNECTION_LOST
    assert run.summary.exit_code == 8
    assert "the sensor stream stopped: nothing arrived for 2.0 s" in run.summary.reason
    assert "the watchdog sent drive 0 after 100 ms" in run.summary.reason
    # The watchdog's drive 0 first, then the whole safe stop.
    assert HALT in [b for t, b in run.link.writes if t > 1.0]
    assert run.link.written.endswith(SAFE_END)
    assert run.simulator.requested_left == 0 and run.simulator.requested_right == 0


def test_unplugged_link_is_exit_8_and_says_the_stop_was_not_sent(run_mission: RunMission) -> None:
    run = run_mission(SPIN, faults=Faults(disconnect_at=1.0))
    assert run.summary.outcome is Outcome.CONNECTION_LOST
    assert run.summary.exit_code == 8
    assert run.summary.safe_stop == (
        "NOT DELIVERED: last seen in Safe spinning left at 100 mm/s; "
        "the stop was not delivered: the port is gone: the robot may still be moving: pick it "
        "up or press its Clean or power button; reseat the cable, then roomba-bt doctor --port "
        "sim://empty-room"
    )
    assert "final mode   unknown: last seen in Safe, the stop was not delivered" in (
        run.summary.lines()
    )


def test_a_bump_changes_the_drive_command_within_one_frame(run_mission: RunMission) -> None:
    # A bump's onset is confirmed by the next frame (robot/hazards.py): the reaction is
    # written in the tick of the bump's second frame, 15 ms after the first, never later.
    run = run_mission(DRIVE_TO_WALL_AND_BACK_OFF)
    assert run.summary.outcome is Outcome.SUCCESS
    # Find the read that completed the first frame with a bump bit, and the next write.
    parser = StreamParser(run.runner.packets)
    bump_time = None
    for t, data in run.link.reads:
        if any(f[7] & 0b11 for f in parser.feed(data)):
            bump_time = t
            break
    assert bump_time is not None
    after = [(t, b) for t, b in run.link.writes if t >= bump_time]
    assert after, "nothing was written after the bump"
    assert after[0][0] <= bump_time + 0.015 + 1e-9
    after = [b for _, b in after]
    assert after[0][0] == 137 and after[0] != oi.drive(200, oi.Radius.STRAIGHT).data
    assert after[0] in (HALT, oi.drive(-100, oi.Radius.STRAIGHT).data)


#: Safe, then 3 s of mission time counted in slots.
WAIT_3S = """
tree:
  sequence:
    - mode: safe
    - wait: {duration: 3s}
"""


def test_stale_frames_are_dropped_not_queued(run_mission: RunMission) -> None:
    # Frames arrive three at a time (a host that fell behind): only the newest is ticked,
    # the two older ones are dropped and counted, and mission time still counts every slot.
    run = run_mission(WAIT_3S, burst=3, watchdog=0.5)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert summary.stale_frames_dropped >= 2 * (summary.ticks - 2)
    assert summary.frames_lost == 0
    assert summary.mission_time_s == pytest.approx(3.0, abs=3 * 0.015 + 0.02)
    assert summary.ticks == pytest.approx(3.0 / 0.015 / 3, abs=3)


def test_lost_frames_are_measured_and_the_clock_keeps_slots(run_mission: RunMission) -> None:
    run = run_mission(WAIT_3S, faults=Faults(drop_rate=0.2), watchdog=1.0)
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.summary.frames_lost > 0
    # 3 s of mission time, whatever was lost: the wait counts slots, not frames.
    assert run.summary.mission_time_s == pytest.approx(3.0, abs=0.1)
    assert run.summary.ticks < round(3.0 / 0.015)


#: Safe, then a wait that a 1 s hold of Safe ends (``held``: Snapshot.previous_tick)
HELD_1S = """
tree:
  sequence:
    - mode: safe
    - wait: 10s
      until: {held: {for: 1s, do: {oi_mode: safe}}}
"""


@pytest.mark.parametrize(
    "link",
    [{}, {"burst": 3}, {"faults": Faults(drop_rate=0.2), "watchdog": 1.0}],
    ids=["every frame", "stale frames", "lost frames"],
)
def test_each_snapshot_names_the_tick_before_it_and_a_hold_spans_missing_frames(
    run_mission: RunMission, link: dict[str, Any]
) -> None:
    """``previous_tick`` is the tick of the snapshot before (the slots between are frames
    dropped as stale or lost, not ticks the tree missed): a ``held`` ticked on every tick
    holds through them, 1 s after Safe (it never held with a tick-1 rule, whose every stale
    batch restarted it), and the wait ends there, not after its 10 s."""
    seen: list[tuple[int, int | None]] = []
    run = run_mission(
        HELD_1S, observer=lambda r: seen.append((r.snapshot.tick, r.snapshot.previous_tick)),
        **link,
    )  # fmt: skip
    assert run.summary.outcome is Outcome.SUCCESS
    assert all(now[1] == before[0] for before, now in itertools.pairwise(seen))
    assert seen[0][1] == -1  # the run's first snapshot: no tick before it
    assert 1.0 <= run.summary.mission_time_s <= 1.2


def test_same_seed_same_bytes(run_mission: RunMission) -> None:
    first = run_mission(DRIVE_TO_WALL)
    second = run_mission(DRIVE_TO_WALL)
    assert first.link.written == second.link.written
    assert first.summary.ticks == second.summary.ticks


def test_snapshot_is_on_the_blackboard_under_one_key(run_mission: RunMission) -> None:
    # A condition reading the one key the runtime writes each tick sees this tick's frame.
    run = run_mission(
        """
        tree:
          sequence:
            - mode: safe
            - wait: 300ms
        """
    )
    assert run.summary.ticks > 0
    # The key is unregistered at the end of a run, so runs do not leak into each other.
    reader = py_trees.blackboard.Client(name="test reader")
    assert not reader.is_registered("/roomba/snapshot")
    assert "/roomba/snapshot" not in py_trees.blackboard.Blackboard.storage
    assert run.runner.snapshot.frame[35] in (1, 2)


@pytest.mark.parametrize("activity_stream", [False, True])
def test_every_tick_the_blackboard_holds_that_ticks_snapshot(
    run_mission: RunMission, activity_stream: bool
) -> None:
    """Read through a py_trees client after every tick; with py_trees' activity stream on
    (someone watching the blackboard), the runtime's writes show up in it."""
    reader = py_trees.blackboard.Client(name="test reader")
    reader.register_key(key="/roomba/snapshot", access=py_trees.common.Access.READ)
    seen: list[bool] = []
    if activity_stream:
        py_trees.blackboard.Blackboard.enable_activity_stream()
    try:
        run = run_mission(
            "tree:\n  sequence:\n    - mode: safe\n    - wait: 300ms\n",
            observer=lambda runner: seen.append(reader.get("/roomba/snapshot") is runner.snapshot),
        )
        stream = py_trees.blackboard.Blackboard.activity_stream
        writes = (
            [item for item in stream.data if item.key == "/roomba/snapshot"]
            if stream is not None
            else []
        )
    finally:
        py_trees.blackboard.Blackboard.disable_activity_stream()
        reader.unregister(clear=False)
    assert len(seen) == run.summary.ticks > 10 and all(seen)
    assert (len(writes) >= run.summary.ticks) is activity_stream


def test_a_builtin_cycle_is_ended_by_the_safe_stop(run_mission: RunMission) -> None:
    # Clean drives the robot in Passive, where drive 0 is refused: the stop enters Safe first.
    run = run_mission(
        """
        tree:
          sequence:
            - mode: safe
            - clean: {}
            - wait: 1s
        """
    )
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.link.written.endswith(oi.safe().data + SAFE_END)
    assert run.simulator.builtin is None
    assert run.simulator.requested_left == 0 and run.simulator.requested_right == 0
    assert run.simulator.violations == []


def test_without_a_builtin_cycle_passive_ends_with_pause_and_start(
    run_mission: RunMission,
) -> None:
    run = run_mission(
        """
        tree:
          sequence:
            - mode: safe
            - mode: passive
            - wait: 100ms
        """
    )
    assert run.link.written.endswith(PAUSE + START)
    assert not run.link.written.endswith(oi.safe().data + SAFE_END)


def test_a_gap_nobody_read_is_counted_and_said(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """A laptop suspended mid-run, a process stopped: when it runs again every frame sent
    meanwhile is there at once, and the watchdog (which watches the link from the running
    process) saw no silence. The robot drove on with its last command; the run says so."""
    run = run_mission(SPIN, freeze=(1.0, 2.5), timeout=4.0, watchdog=0.3)
    summary = run.summary
    assert summary.outcome is Outcome.TIMEOUT
    assert summary.unread_gaps == 1 and summary.stalls == 0
    assert summary.longest_unread_s == pytest.approx(2.5, abs=0.03)
    assert "unread       1 gap(s) with no frame read, the longest 2.5" in str(summary)
    assert_quoted("docs/runtime.md", "unread 1 gap(s)", str(summary), numbers=True)  # 4 s there
    assert "no frame was read for 2.5" in caplog.text
    assert summary.mission_time_s == pytest.approx(4.0, abs=0.05)  # the slots still count


def test_frames_a_full_buffer_dropped_in_a_gap_nobody_read_are_not_the_line_s(
    tmp_path: Path,
) -> None:
    """A run stopped 45 s (SIGSTOP, a laptop's lid) on a pty: the port's buffer held 10 s of
    the robot's frames and dropped the rest, and the summary said ``link poor: 73 % of the
    robot's frames lost (2309 of 3163) ... check the cable``, of a line that lost nothing.
    Those frames are counted lost (mission time is the robot's) and said in the unread
    line, as the computer's; the link line judges the line's alone."""
    path = tmp_path / "spin.yaml"
    path.write_text(SPIN)
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0), freeze=(1.0, 20.0))
    link.buffer = 8192
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2,
                     timeout_s=30.0)  # fmt: skip
    summary = stack.run()
    assert summary.outcome is Outcome.TIMEOUT
    assert summary.unread_gaps == 1 and summary.stalls == 0
    lost, held = summary.frames_lost, 8192 // stream_frame_size(stack.runner.packets)
    assert lost == pytest.approx(20.0 / SLOT_SECONDS - held, abs=3)
    assert summary.mission_time_s == pytest.approx(30.0, abs=0.1)  # the robot's time
    said = str(summary)
    assert "link " not in said, said
    assert 0 <= lost - summary.frames_lost_unread <= 1  # (and the frame the buffer cut short)
    assert (
        f"; {summary.frames_lost_unread} of the frames lost were lost in them (the port's "
        "buffer full" in said
    )


def test_a_gap_under_a_second_is_not_said(run_mission: RunMission) -> None:
    """(A stall the watchdog saw and the run rode through is not one either:
    test_ride_through.py.)"""
    summary = run_mission(SPIN, freeze=(1.0, 0.6), timeout=3.0, watchdog=1.0).summary
    assert summary.unread_gaps == 0 and "unread" not in str(summary)


def test_the_summary_counts_every_command_the_run_wrote(run_mission: RunMission) -> None:
    """The bump reflex's drive 0 (and the watchdog's, a pause's, a resend) went to the
    robot past the outbox, and the summary's "commands N written" left them out."""
    from roomba_bt.oi.encode import decode_command

    run = run_mission(DRIVE_TO_WALL_AND_BACK_OFF)
    assert run.summary.outcome is Outcome.SUCCESS
    names, rest = [], run.link.written
    while rest and (decoded := decode_command(rest)) is not None:
        command, size = decoded
        names.append(command.spec.name)
        rest = rest[size:]
    stop = len(run.summary.safe_stop.removeprefix("sent ").split(", "))
    ran = names[names.index("stream") + 1 : -stop]  # after the start-up, before the safe stop
    assert ran.count("drive") >= 3  # forward, the reflex's drive 0, backing off (and its halt)
    assert run.summary.commands_written == len(ran), ran


def test_jitter_makes_no_lost_frames_and_the_clock_keeps_the_robots_slots(
    run_mission: RunMission,
) -> None:
    # Every frame is read, each up to 10 ms late (then on time again): late+early pairs of
    # 5..25 ms gaps. No frame was lost, so none is counted, and mission time is the frames'
    # slots. (Before: a gap of 22.5 ms or more took two slots, an early frame none back:
    # frames "lost" and a clock running fast.)
    run = run_mission(WAIT_3S, jitter=0.010)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert summary.frames_lost == 0
    assert summary.stale_frames_dropped == 0
    parser = StreamParser(run.runner.packets)
    frames = sum(len(parser.feed(data)) for _, data in run.link.reads)
    assert summary.ticks == frames
    assert summary.mission_time_s == pytest.approx((summary.ticks - 1) * 0.015, abs=1e-9)


def test_jitter_does_not_hide_frames_really_lost(run_mission: RunMission) -> None:
    # Frames dropped by the robot's side and every frame read up to 10 ms late: the lost
    # ones are counted all the same, on a jittery link once the frames after them have come
    # late for the run's window (1.4 s at that spread; those lost during it, by the next
    # one): every frame the exact run had counted two windows before the end, none it had not.
    counted: list[tuple[float, int]] = []  # the exact run's (robot's time, frames lost)

    def lost_by(runner: MissionRunner) -> None:  # the link's clock: the simulator's
        counted.append((runner.connection.link.transport.now(), runner.summary.frames_lost))

    wait_6s = WAIT_3S.replace("3s", "6s")
    run = run_mission(wait_6s, faults=Faults(drop_rate=0.2), watchdog=1.0, jitter=0.010)
    exact = run_mission(wait_6s, faults=Faults(drop_rate=0.2), watchdog=1.0, observer=lost_by)
    assert run.summary.outcome is exact.summary.outcome is Outcome.SUCCESS
    window = run.runner._clock.schedule.run_window()
    assert 1.0 < window < 1.7
    by_then = max(n for at, n in counted if at <= run.simulator.time - 2 * window)
    assert by_then > 0.2 * 2.0 / 0.015  # a fifth of 2 s of frames
    assert by_then <= run.summary.frames_lost <= exact.summary.frames_lost
    assert run.summary.mission_time_s == pytest.approx(6.0, abs=0.1)


def test_the_robot_s_own_fall_forgets_its_wheel_and_motor_commands(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """Brushes and vacuum on, forward into a drop: the robot falls to Passive by itself and
    stops its wheels and its motors (the OI does both). From the tick that sees the fall the
    run no longer holds either command as standing (``FALL_STOPS``), so neither a stall's
    ride-through nor the monitor's resume sends it again; before the fall both stood."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    mission = over_the_edge(brushes=True)
    standing: list[tuple[bool, tuple[str, ...]]] = []

    def observer(runner: MissionRunner) -> None:
        fell = runner.snapshot.last_fallback is not None
        standing.append((fell, tuple(sorted(c for c in runner.last_sent if c != "mode"))))

    run = run_mission(mission, world=str(tmp_path / "ledge.yaml"), observer=observer)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    fell_at = next(i for i, (fell, _) in enumerate(standing) if fell)
    assert standing[fell_at - 1] == (False, ("motors", "wheels"))  # both stood until the fall
    assert all(channels == () for _, channels in standing[fell_at:]), standing[fell_at:]
    on = oi.motors(motor_bits(main_brush=True, vacuum=True))
    assert on.data in run.link.written  # the leaf's brushes and vacuum went out


def test_after_every_tick_what_stands_is_what_the_tree_asked_for_until_the_fall(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """The runner's standing commands (``last_sent``: what a ride-through and a resume send
    again) are the outbox's own record, beside what the tree asked for (``last_on``): after
    every tick both name the same command on each channel, until the robot falls to Passive
    by itself; from then on the wheels and the motors no longer stand, and the tree's last
    asks are still known (a ``mode: passive`` stops the motors first by them)."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    ticks: list[tuple[bool, dict[str, bool], dict[str, bool]]] = []

    def observer(runner: MissionRunner) -> None:
        fell = runner.snapshot.last_fallback is not None
        asked = {c: runner.outbox.last_on(c) is not None for c in ("wheels", "motors")}
        same = {c: runner.outbox.last_on(c) is sent for c, sent in runner.last_sent.items()}
        assert runner.last_sent is runner.outbox.standing  # one record, not a copy
        ticks.append((fell, asked, same))

    run = run_mission(
        over_the_edge(brushes=True), world=str(tmp_path / "ledge.yaml"), observer=observer
    )
    assert run.summary.outcome is Outcome.SUCCESS and run.summary.refused_commands == 0
    fell_at = next(i for i, (fell, _, _) in enumerate(ticks) if fell)
    for _, asked, same in ticks[:fell_at]:
        assert all(same.values()) and set(same) == {c for c, a in asked.items() if a}
    assert ticks[fell_at - 1][2] == {"wheels": True, "motors": True}  # both stood
    for _, asked, same in ticks[fell_at:]:
        assert asked == {"wheels": True, "motors": True} and same == {}, (asked, same)
