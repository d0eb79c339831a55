"""A bad patch of line is ridden through: the watchdog still stops the wheels 100 ms after the
last valid frame, the run waits the grace for valid frames, then the tree goes on and the
wheels get their command again; a loss longer than the grace ends as exit 8, its cause named
(a stopped stream, a garbled line, a reset)."""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.display import MissionClockFormatter, use_mission_clock
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Faults, Simulator, load_world
from roomba_bt.sim.protocol import DEFAULT_FIRMWARE, reset_banner

from .simrun import LEDGE, SPIN, RunMission, TapLink, over_the_edge

SPIN_COMMAND = oi.drive(100, oi.Radius.TURN_COUNTER_CLOCKWISE).data
HALT = oi.halt().data


class BadPatchLink(TapLink):
    """Between ``start`` and ``end`` s of simulated time the robot's bytes arrive garbled
    (every byte inverted: nothing frames), or not at all (``silent``); ``banner`` sends the
    firmware's reset banner at ``start`` and nothing after (as the simulator's Reset does)."""

    def __init__(
        self, simulator: Simulator, start: float, end: float, kind: str = "garbled"
    ) -> None:
        super().__init__(simulator)
        self.start, self.end, self.kind = start, end, kind
        self.bannered = False

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        now = self.simulator.time
        if not self.start <= now < self.end:
            return data
        if self.kind == "banner":
            if self.bannered:
                return b""
            self.bannered = True
            return reset_banner(DEFAULT_FIRMWARE)
        if self.kind == "silent":
            return b""
        return bytes(b ^ 0xFF for b in data)


def run(
    tmp_path: Path, link_of: type[BadPatchLink], *args: object, mission: str = SPIN, **run: float
) -> tuple[RunSummary, BadPatchLink]:
    path = tmp_path / "m.yaml"
    path.write_text(mission)
    mission = load_mission(path, {}, profile=CREATE2)
    link = link_of(Simulator(load_world("empty-room"), CREATE2, 0), *args)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=run.get("timeout", 4.0),
                     grace=run.get("grace", 2.0))  # fmt: skip
    return stack.run(), link


def writes_between(link: TapLink, start: float, end: float) -> list[bytes]:
    return [b for t, b in link.writes if start <= t < end]


def test_a_garbled_second_is_ridden_through_and_the_wheels_get_their_command_again(
    tmp_path: Path,
) -> None:
    summary, link = run(tmp_path, BadPatchLink, 1.0, 2.0)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason  # the mission went on
    assert summary.stalls == 1 and summary.stalls_ridden == 1
    assert summary.unread_gaps == 0  # the watchdog saw this gap: not one nobody read
    # drive 0 within 150 ms of the last valid frame, nothing else while garbled
    halts = [t for t, b in link.writes if b == HALT and 1.0 <= t < 2.0]
    assert halts and halts[0] <= 1.0 + 0.15
    assert writes_between(link, halts[0] + 0.001, 2.0) == []
    # the spin again in the first tick after the line came back
    back = [(t, b) for t, b in link.writes if t >= 2.0]
    assert back[0][1] == SPIN_COMMAND and back[0][0] < 2.0 + 0.05
    assert link.simulator.time >= 4.0


MOTORS_ON = oi.motors(7).data


def test_a_stall_with_the_brushes_on_stops_them_too_and_gives_them_back_after(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The watchdog sent drive 0 alone: a stalled stream left the brushes and vacuum running
    on the spot, while the tick guard stopped them. Now drive 0 and motors off go in one
    write at the trip, and once frames are back the wheels and the motors get the tree's
    commands again, wheels first."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    brushes = SPIN.replace(
        "    - mode: safe\n",
        "    - mode: safe\n    - motors: {main_brush: true, side_brush: true, vacuum: true}\n",
    )
    summary, link = run(tmp_path, BadPatchLink, 1.0, 2.0, mission=brushes)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason  # the mission went on
    assert summary.stalls == summary.stalls_ridden == 1
    written = [b for t, b in link.writes if t < 1.0]
    assert MOTORS_ON in written and SPIN_COMMAND in written
    assert writes_between(link, 1.0, 2.0) == [HALT + oi.motors_off().data]  # one write
    assert [b for t, b in link.writes if t >= 2.0][:2] == [SPIN_COMMAND, MOTORS_ON]
    [tripped] = [r.getMessage() for r in caplog.records if "waiting up to" in r.getMessage()]
    assert "drive 0 sent, and motors off; waiting up to 2 s" in tripped


def test_the_trip_and_the_frames_return_are_stamped_each_with_its_own_mission_time(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """No tick moves the mission clock during a stall: both lines read the last frame's
    time, and the log did not show when the wheels stopped or how long they stood."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    run(tmp_path, BadPatchLink, 1.0, 2.0)
    formatter = MissionClockFormatter()  # no clock: a line is stamped with its own time
    lines = [formatter.format(r) for r in caplog.records if "valid frame" in r.getMessage()]
    assert len(lines) == 2, lines
    tripped, back = (float(line.split()[0].removeprefix("t=")) for line in lines)
    assert "waiting up to 2 s" in lines[0] and "are back after" in lines[1]
    # garbled from 1.0 s to 2.0 s of the robot's time: drive 0 about 0.1 s in, frames back
    # at its end (the mission's clock began a little after the robot's)
    assert back - tripped == pytest.approx(0.9, abs=0.05)


class StampedThen(logging.Handler):
    """Each line formatted when it is written, as the command line's handler does, beside
    the virtual clock's time then."""

    def __init__(self, link: BadPatchLink) -> None:
        super().__init__(logging.WARNING)
        self.setFormatter(MissionClockFormatter())
        self.link = link
        self.lines: list[tuple[float, str]] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append((self.link.now(), self.format(record)))


def test_a_line_logged_during_a_stall_is_stamped_with_the_time_it_was_written(
    tmp_path: Path,
) -> None:
    """Log lines were stamped with the last tick's time: no tick moves the mission clock
    while frames stop, so the ending's line, written after the 2 s grace and the BRC pulse
    that asked the robot, read the last frame's time (before the watchdog's own trip). Each
    is stamped with the mission time on the run's clock (here the virtual clock) when it was
    written: the last frame's time and the time since it arrived."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    mission = load_mission(path, {}, profile=CREATE2)
    link = BadPatchLink(Simulator(load_world("empty-room"), CREATE2, 0), 1.0, 99.0, "silent")
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=10.0)
    stamped = StampedThen(link)
    logger = logging.getLogger("roomba_bt")
    logger.addHandler(stamped)
    use_mission_clock(stack.runner)
    try:
        summary = stack.run()
    finally:
        use_mission_clock(None)
        logger.removeHandler(stamped)
    assert summary.outcome is Outcome.CONNECTION_LOST, summary.reason

    def stamp_of(line: str) -> float:
        return float(line.split()[0].removeprefix("t="))

    tripped = next(stamp_of(line) for _, line in stamped.lines if "waiting up to" in line)
    ended = [(stamp_of(line), at) for at, line in stamped.lines if "unconfirmed" in line]
    assert ended, stamped.lines
    stamp, written_at = ended[0]
    since_last_frame = written_at - stack.connection.link.arrival
    assert since_last_frame > 2.0  # the grace waited, then the robot asked
    assert stamp == pytest.approx(summary.mission_time_s + since_last_frame, abs=0.0011)
    assert stamp > tripped + 2.0


def test_a_stream_stopped_past_the_grace_is_exit_8_named_stopped(tmp_path: Path) -> None:
    summary, link = run(tmp_path, BadPatchLink, 1.0, 99.0, "silent", timeout=10.0)
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 8
    assert "the sensor stream stopped: nothing arrived for 2.0 s" in summary.reason
    assert "the watchdog sent drive 0 after 100 ms" in summary.reason
    assert [t for t, b in link.writes if b == HALT and 1.0 <= t <= 1.15]
    assert summary.stalls == 1 and summary.stalls_ridden == 0


def test_a_garbled_line_past_the_grace_is_exit_8_named_garbled(tmp_path: Path) -> None:
    summary, _ = run(tmp_path, BadPatchLink, 1.0, 99.0, "garbled", timeout=10.0, grace=0.5)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the line is garbled: no valid sensor frame for 0.5 s while" in summary.reason
    assert "bytes arrived (noise on the line, or a wrong baud rate)" in summary.reason
    # the stop went out at the run's rate, where nothing valid came from: not known to arrive
    assert not summary.stop_delivered
    assert "the stop was written but is unconfirmed: the line is garbled" in summary.safe_stop


def test_a_reset_banner_is_named_at_once(tmp_path: Path) -> None:
    summary, link = run(tmp_path, BadPatchLink, 1.0, 99.0, "banner", timeout=10.0)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert summary.reason.endswith(
        "the robot reset: its start-up banner was on the line and the stream stopped (the OI "
        "is Off after a reset: a battery or power dip, a firmware fault, the power button "
        "held); drive 0 sent"
    )
    assert link.simulator.time < 1.3  # named when the watchdog trips, no grace waited


def test_grace_0_ends_when_the_watchdog_trips(tmp_path: Path) -> None:
    summary, link = run(tmp_path, BadPatchLink, 1.0, 2.0, grace=0.0)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "no valid sensor frame for" in summary.reason
    assert link.simulator.time < 1.3


FORWARD = oi.drive(200, oi.Radius.STRAIGHT).data


def test_a_stall_after_the_robot_s_own_fall_does_not_send_the_drive_from_before_it(
    tmp_path: Path,
) -> None:
    """Forward into a drop: the robot falls to Passive by itself (4.3 s), the tree enters
    Safe again and waits; a garbled half second follows. After the ride-through the runtime
    sent the tree's last wheel command again, the forward Drive from before the fall, and
    the robot drove back over the edge (a second fall). The fall ended that command."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    (tmp_path / "edge.yaml").write_text(over_the_edge("4s"))
    mission = load_mission(tmp_path / "edge.yaml", {}, profile=CREATE2)
    link = BadPatchLink(Simulator(load_world(tmp_path / "ledge.yaml"), CREATE2, 0), 5.0, 5.5)
    summary = RunStack(mission, link, profile=CREATE2, timeout_s=12.0).run()
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.stalls == summary.stalls_ridden == 1
    falls = [t for t, b in link.writes if b == FORWARD]
    assert len(falls) == 1 and falls[0] < 1.0, link.writes  # only the tree's own, at its start
    assert [b for t, b in link.writes if 5.0 <= t < 8.0] == [HALT]  # the watchdog's, no more


def test_a_run_that_lost_many_of_the_robot_s_frames_says_the_link_is_poor(
    run_mission: RunMission,
) -> None:
    """A line that lost 13,395 of 16,014 frames ended SUCCESS with no word of the line (the
    flaky-cable trial): the summary now judges it, from 5 % of the frames lost."""
    mission = "tree:\n  sequence:\n    - mode: safe\n    - wait: 5s\n"
    poor = run_mission(mission, faults=Faults(drop_rate=0.3), watchdog=1.0).summary
    assert poor.outcome is Outcome.SUCCESS
    [line] = [line for line in poor.lines() if line.startswith("link ")]
    sent = poor.ticks + poor.stale_frames_dropped + poor.frames_lost
    assert line == (
        f"link         poor: {100 * poor.frames_lost / sent:.0f} % of the robot's frames lost "
        f"({poor.frames_lost} of {sent}), 0 checksum failures: the tree saw the robot late; "
        "check the cable and its adapter (roomba-bt doctor)"
    )
    clean = run_mission(mission).summary
    assert clean.frames_lost == 0 and not any(line.startswith("link ") for line in clean.lines())


def test_a_stall_with_the_wheels_at_rest_is_not_said_to_have_sent_drive_0() -> None:
    """553 stalls "(watchdog drive 0)" on a robot resting on its dock: 11 had sent one."""
    assert RunSummary("m", stalls=3, stall_halts=3, stalls_ridden=3).stall_text() == (
        "3 (watchdog drive 0), 3 ridden through"
    )
    assert RunSummary("m", stalls=553, stall_halts=11, stalls_ridden=553).stall_text() == (
        "553 (watchdog drive 0 in 11, the wheels at rest in the others), 553 ridden through"
    )


def test_after_the_robot_s_own_fall_nothing_from_before_it_is_held_or_moving(
    tmp_path: Path,
) -> None:
    """Forward into a drop: the robot falls to Passive by itself and stops its wheels; Safe
    again leaves them at rest. The writer kept the forward Drive from before the fall as the
    wheels' command: the tick guard (``wheels_moving``) took the robot for moving, and a bump
    onset's hold wrote drive 0 and gave that Drive back to be sent again (over the edge),
    while the runtime's outbox had forgotten it at the fall."""
    from roomba_bt.oi.modes import OIMode
    from roomba_bt.robot.connection import Connection
    from roomba_bt.runtime.tick_guard import wheels_moving

    (tmp_path / "ledge.yaml").write_text(LEDGE)
    link = TapLink(Simulator(load_world(tmp_path / "ledge.yaml"), CREATE2, 0))
    connection = Connection(link, CREATE2)
    connection.start(OIMode.SAFE, packets=(7, 9, 10, 11, 12, 35))
    connection.send(oi.drive(200, oi.Radius.STRAIGHT))
    assert wheels_moving(connection)
    while connection.mode is not OIMode.PASSIVE:
        assert link.simulator.time < 10.0, "no fall"
        connection.poll_frames(0.1)
    assert connection.falls == {"cliff": 1}
    connection.send(oi.safe())
    link.writes.clear()
    assert not wheels_moving(connection)
    connection.hold_forward()
    assert link.writes == []  # no drive 0: nothing drives
    assert connection.release_forward() is None  # nothing to send again
    connection.close()


class LatePatchesLink(BadPatchLink):
    """Silent for 0.3 s every 5 s of simulated time from 1 s on (a loaded machine's late
    frames), and once, at ``long_at``, for 1.5 s: past half the 2 s grace."""

    def __init__(self, simulator: Simulator, long_at: float) -> None:
        super().__init__(simulator, 0.0, 0.0, "silent")
        self.long_at = long_at

    def read(self, timeout: float) -> bytes:
        now = self.simulator.time
        late = now >= 1.0 and (now - 1.0) % 5.0 < 0.3
        if late or self.long_at <= now < self.long_at + 1.5:
            BadPatchLink.read(self, timeout)  # the simulator goes on; its bytes are lost
            return b""
        return BadPatchLink.read(self, timeout)


def test_stalls_ridden_through_in_a_minute_are_summed_up_and_a_long_one_is_still_said(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A run paused in the monitor over the pty simulator on a loaded machine said two
    warnings at every late frame (21 in 5 minutes), which nobody can act on. The first
    stall is said in full; those ridden through in the next minute are counted and said as
    one line a minute (how many, the longest); a stall that lasts half its grace is said at
    once all the same."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    summary, _ = run(tmp_path, LatePatchesLink, 93.0, timeout=130.0)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason  # the mission went on
    assert summary.stalls == summary.stalls_ridden >= 26
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.runtime.loop"]
    tripped = [line for line in said if "waiting up to 2 s" in line]
    assert len(tripped) == 2, said  # the first, and the long one at half its grace
    assert "still none" not in tripped[0]
    assert re.search(r"still none 10\d\d ms after the last \(half the grace\)", tripped[1])
    summed = [line for line in said if "frames were late" in line]
    # once a minute, not at each, and those counted since at the run's end
    assert len(summed) == 2, said
    assert re.search(r"late 1[1-3] more times in the last 1 min( \d+ s)? \(longest 3\d\d ms, "
                     r"from t=\d+\.\d{3}\)", summed[0]), summed  # fmt: skip
    assert "drive 0 sent in 1" in summed[0]
    assert "said once a minute" in summed[0] and "said at the run's end" in summed[1]
    # 2 stalls said in full, trip and return, 1 line summing up 12 of the rest, 1 the others
    assert len(said) == 6, said


def test_stalls_counted_and_not_yet_said_are_said_at_the_run_s_end(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A run that ended within a minute of its first stall said only that one: the others
    were counted for a line a minute later that never came, and the summary's stalls line
    has their count, not the longest gap nor where it was (5 % of the robot's bytes lost:
    23 stalls, 1 line). Said at the run's end, with the longest and where it began."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    summary, _ = run(tmp_path, LatePatchesLink, 1000.0, timeout=17.0)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason
    assert summary.stalls == summary.stalls_ridden == 4  # at 1, 6, 11 and 16 s
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.runtime.loop"]
    [summed] = [line for line in said if "frames were late" in line]
    assert re.search(
        r"late 3 more times in the last 1\d s \(longest 3\d\d ms, from t=(5|10|15)\.\d{3}\), "
        r"each back within the grace: drive 0 sent in 3 .*said at the run's end",
        summed,
    ), summed


class StopsInAStall(BadPatchLink):
    """Silent from 3 s of simulated time on; the program stops the run 0.5 s into it (a
    Ctrl-C, the monitor's stop, a wall-clock limit: the run ends before its grace does)."""

    stop: Callable[[], None] = staticmethod(lambda: None)

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator, 3.0, 100.0, "silent")

    def read(self, timeout: float) -> bytes:
        if self.simulator.time >= 3.5:
            self.stop()
        return super().read(timeout)


def test_a_run_that_ends_in_a_stall_says_how_long_and_since_when(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A stall still open when the run ended (stopped within its grace) was said nowhere but
    as one more stall than those ridden through in the summary's count."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    link = StopsInAStall(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2)
    link.stop = stack.runner.request_stop
    summary = stack.run()
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert (summary.stalls, summary.stalls_ridden) == (1, 0)
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.runtime.loop"]
    [ended] = [line for line in said if "the run ended in a stall" in line]
    assert re.search(
        r"no valid frame for its last 5\d\d ms \(since t=2\.9\d\d\); the watchdog had sent "
        r"drive 0",
        ended,
    ), ended


def test_a_stall_that_ends_the_run_is_not_said_again_as_one_the_run_ended_in(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    summary, _ = run(tmp_path, BadPatchLink, 1.0, 10.0, "silent", timeout=8.0)
    assert summary.outcome is Outcome.CONNECTION_LOST  # its reason says the stall
    assert not [r for r in caplog.records if "the run ended in a stall" in r.getMessage()]


def test_with_v_each_stall_ridden_through_is_said_at_debug(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Summed up at WARNING, every stall is still a line at DEBUG (``run -v``): someone tracing
    a bad cable sees each trip and each return, with its own gap."""
    caplog.set_level(logging.DEBUG, logger="roomba_bt.runtime.loop")
    summary, _ = run(tmp_path, LatePatchesLink, 93.0, timeout=130.0)
    records = [r for r in caplog.records if r.name == "roomba_bt.runtime.loop"]
    counted = [r.getMessage() for r in records if "counted: said once a minute" in r.getMessage()]
    assert all(r.levelno == logging.DEBUG for r in records if "counted:" in r.getMessage())
    trips = [line for line in counted if "waiting up to 2 s for valid frames" in line]
    backs = [line for line in counted if "valid frames are back after" in line]
    # every trip but the first (the long one's is counted, then said at half its grace)
    assert len(trips) == summary.stalls - 1, counted
    # every return but those of the two stalls said in full
    assert len(backs) == summary.stalls_ridden - 2, counted


class DroppingBridgeLink(BadPatchLink):
    """A Wi-Fi bridge that drops mid-run: silent from ``start`` to ``end`` (a stall ridden
    through), silent again from ``quiet`` (the watchdog's drive 0 written into it), and gone
    from ``gone`` (reads and writes fail)."""

    def __init__(self, simulator: Simulator, quiet: float, gone: float) -> None:
        super().__init__(simulator, 1.0, 1.3, "silent")
        self.quiet, self.gone = quiet, gone

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        if self.simulator.time >= self.gone:
            raise ConnectionError("the bridge is gone")
        return b"" if self.simulator.time >= self.quiet else data

    def write(self, data: bytes) -> None:
        if self.simulator.time >= self.gone:
            raise ConnectionError("the bridge is gone")
        super().write(data)


def test_a_bridge_lost_after_the_watchdog_s_drive_0_is_not_said_stopped(
    tmp_path: Path,
) -> None:
    """A stall ridden through (the spin sent again), then the bridge quiet, the watchdog's
    drive 0 written into it, then gone: the summary said "NOT DELIVERED: last seen in Safe
    stopped" of a robot last seen spinning, the drive 0 the last wheel command written and no
    frame after it. It names the spin, and the drive 0 unconfirmed."""
    summary, link = run(tmp_path, DroppingBridgeLink, 2.0, 2.2)
    assert summary.outcome is Outcome.CONNECTION_LOST, summary.reason
    assert summary.stalls == 2 and summary.stalls_ridden == 1
    assert [b for t, b in link.writes if t > 1.9] == [HALT]  # the watchdog's, the last one
    assert summary.safe_stop.startswith(
        "NOT DELIVERED: last seen in Safe spinning left at 100 mm/s (then the watchdog's drive "
        "0, which no frame showed heard); the stop was not delivered: the port is gone: the "
        "robot may still be moving: pick it up"
    ), summary.safe_stop
    assert summary.stop_report == summary.safe_stop.removeprefix("NOT DELIVERED: ")
