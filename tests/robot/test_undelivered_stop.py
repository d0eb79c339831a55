"""A stop that cannot reach the robot is reported as such, with the robot's last known state,
and the mode model follows only what was written (on the simulator, the port failing)."""

from __future__ import annotations

import logging
import re
import threading
from collections.abc import Callable
from typing import Any, TypeVar

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS, describe_activity
from roomba_bt.robot.errors import DEFAULT_WATCHDOG, PortLost, StreamStalled
from roomba_bt.robot.link import LinkStatus
from roomba_bt.runtime.ending import mode_of, stop_robot, undelivered_said
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.runtime.tick_guard import halt_blocked
from roomba_bt.sim import Faults, SimLink, Simulator, parse_world

BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""
PACKETS = (7, 9, 10, 11, 12, 35, 43, 44)


class Pullable:
    """A simulator link whose cable can be pulled: every later write raises."""

    def __init__(self, link: SimLink) -> None:
        self.link = link
        self.pulled = False

    def write(self, data: bytes) -> None:
        if self.pulled:
            raise OSError(5, "Input/output error")
        self.link.write(data)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


Linked = TypeVar("Linked", bound=Pullable)


def driving(
    link_type: type[Linked] = Pullable,  # type: ignore[assignment]
    name: str = "sim://",
) -> tuple[Connection, Linked]:
    """A connection driving at 200 mm/s in Safe over a ``link_type`` link named ``name``,
    frames coming."""
    link = link_type(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2), name))
    connection = Connection(link, CREATE2)
    connection.start("safe", PACKETS)
    connection.send_many([oi.drive(200, 32767)])
    while connection.counters.frames < 10:
        connection.poll(0.05)
    return connection, link


def test_a_batch_that_was_never_written_does_not_move_the_mode_model() -> None:
    connection, link = driving()
    link.pulled = True
    with pytest.raises(PortLost):
        connection.send_many([oi.full(), oi.drive(100, 0)])
    assert connection.mode is OIMode.SAFE  # Full was queued, never written
    assert connection.activity() == "at 200 mm/s"


def test_a_stop_that_cannot_be_written_is_reported_undelivered() -> None:
    connection, link = driving()
    link.pulled = True
    assert connection.safe_stop() is False
    # what to do now, for a robot that may still be moving
    assert connection.stop_report == (
        "last seen in Safe at 200 mm/s; the stop was not delivered: the port is gone: the robot "
        "may still be moving: pick it up or press its Clean or power button; reseat the cable, "
        "then roomba-bt doctor --port sim://box"
    )
    assert connection.mode is OIMode.SAFE  # not advanced to Passive by the unsent Start
    assert connection.safe_stopped is False


def test_a_stop_not_delivered_to_a_pty_says_its_path_will_not_come_back() -> None:
    """A pty's number goes to the next program that opens one: doctor --port at it (the
    advice a device path gets) wrote Query Lists and a hang-up into another session's
    simulator. Nothing is opened again there (``LinkWords.reopens``), and nothing sent."""
    connection, link = driving(name="/dev/pts/7")
    link.pulled = True
    assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Safe at 200 mm/s; the stop was not delivered: the port is gone: the robot "
        "may still be moving: pick it up or press its Clean or power button; /dev/pts/7 will "
        "not come back (a pty's number goes to the next program that opens one: doctor there "
        "would talk to that program): start the simulator or bridge again and use the path it "
        "prints"
    )


def paused(packets: tuple[int, ...] = PACKETS) -> tuple[Connection, Pullable]:
    """A connection that drove at 200 mm/s in Safe, then was paused as the monitor pauses a
    run (drive 0, motors off, Start: :func:`~roomba_bt.monitor.session.pause_sequence`),
    the stream running on."""
    link = Pullable(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2), "sim://"))
    connection = Connection(link, CREATE2)
    connection.start("safe", packets)
    connection.send_many([oi.drive(200, 32767)])
    while connection.counters.frames < 10:
        connection.poll(0.05)
    connection.send_many([oi.halt(), oi.motors_off(), oi.start()])
    return connection, link


def frames_for(connection: Connection, count: int) -> None:
    """Read ``count`` more frames."""
    until = connection.counters.frames + count
    while connection.counters.frames < until:
        connection.poll(0.05)


def stopped_pulled(
    connection: Connection, link: Pullable, caplog: pytest.LogCaptureFixture
) -> list[str]:
    """The cable pulled, then the safe stop (not delivered): the levels it logged at."""
    link.pulled = True
    caplog.clear()
    with caplog.at_level("DEBUG", logger="roomba_bt.robot.ending"):
        assert connection.safe_stop() is False
    return [r.levelname for r in caplog.records]


#: a stream without packet 35 (the OI mode), as a program's ``Connection.start`` may ask for
UNMODED = (7, 9, 10, 11, 12, 43, 44)
#: what a stop not delivered says of a robot seen stopped in Passive by its frames
IN_PASSIVE = (
    "last seen stopped in Passive, in the frames it sent after every command written (it "
    "stays stopped unless something else moves it: its buttons, a schedule)"
)
#: the same on a stream without packet 35, its frames showing the requested wheel speeds at 0
NO_MODE_STREAMED = (
    "last seen stopped, its requested wheel speeds at 0 in the frames it sent after every "
    "command written (the stream carries no OI mode, packet 35: Passive was written, not "
    "seen; it stays stopped unless something else moves it: its buttons, a schedule)"
)


@pytest.mark.parametrize(
    ("packets", "words"),
    [
        (PACKETS, IN_PASSIVE),
        ((*PACKETS, 41, 42), IN_PASSIVE),
        ((*UNMODED, 39), NO_MODE_STREAMED),
        ((*UNMODED, 41, 42), NO_MODE_STREAMED),
        ((*UNMODED, 39, 41, 42), NO_MODE_STREAMED),
    ],
    ids=["encoders", "velocities", "no mode, 39", "no mode, 41/42", "no mode, 39-42"],
)
def test_a_paused_robot_seen_stopped_is_not_said_to_be_moving(
    packets: tuple[int, ...], words: str, caplog: pytest.LogCaptureFixture
) -> None:
    """The cable pulled while the operator held the run paused: the summary and the banner
    said "last seen in Passive stopped; ... the robot may still be moving: pick it up",
    though the pause's own stop had been seen taken in every frame since. On a stream
    without packet 35 (until session 39 still "may still be moving") the frames show the
    requested wheel speeds at 0 (packet 39, Drive's velocity; 41/42, Drive Direct's):
    said as known, stopped, its mode not streamed (Passive written, not seen)."""
    connection, link = paused(packets)
    frames_for(connection, 20)  # seconds of a pause, shortened
    assert stopped_pulled(connection, link, caplog) == ["WARNING"]
    assert connection.stop_report == (
        f"{words}; the stop was not delivered: the port is gone: reseat the cable, then "
        "roomba-bt doctor --port sim://box"
    )


def test_a_robot_whose_frames_show_neither_its_mode_nor_its_wheels_may_still_be_moving() -> None:
    """Without packet 35 the words come only where the frames show the wheels at 0: no
    requested velocity streamed (the encoders alone, one frame kept), no frame since the
    stop was heard, a requested wheel speed not 0."""
    connection, link = paused(UNMODED)
    frames_for(connection, 20)
    link.pulled = True
    assert connection.safe_stop() is False
    assert "the robot may still be moving: pick it up" in str(connection.stop_report)
    connection, link = paused((*UNMODED, 41, 42))
    link.pulled = True  # no frame since the pause's stop
    assert connection.safe_stop() is False
    assert "the robot may still be moving: pick it up" in str(connection.stop_report)
    connection, link = paused((*UNMODED, 39, 41, 42))
    frames_for(connection, 20)
    last = connection.link.frame
    assert last is not None
    values = list(last.values)  # its right wheel asked for 100 mm/s (its drive 0 not heard)
    values[last.layout.index[41]] = 100
    connection.link.frame = SensorFrame(last.layout, tuple(values))
    link.pulled = True
    assert connection.safe_stop() is False
    assert "the robot may still be moving: pick it up" in str(connection.stop_report)


def test_a_pause_not_yet_seen_taken_is_still_said_to_be_maybe_moving() -> None:
    """The same words only where frames show it: the cable pulled as the pause's stop is
    written, no frame since (the robot may not have heard it), or a Safe written after the
    last frame (a command that could set it going)."""
    connection, link = paused()
    link.pulled = True
    assert connection.safe_stop() is False
    assert "the robot may still be moving: pick it up" in str(connection.stop_report)
    connection, link = paused()
    frames_for(connection, 20)
    connection.send_many([oi.safe()])
    link.pulled = True
    assert connection.safe_stop() is False
    assert "the robot may still be moving: pick it up" in str(connection.stop_report)


def _brushing_then_passive(connection: Connection) -> None:
    """Safe, the main brush on, Start: Passive with a Motors command that runs a brush the
    last one written (whether the robot's Passive stops it, nothing here shows)."""
    connection.send_many([oi.safe(), oi.motors(0x04), oi.start()])


@pytest.mark.parametrize(
    ("before_the_pull", "calm"),
    [
        (lambda c: frames_for(c, 20), True),
        (lambda c: None, False),  # no frame since the pause's stop
        (lambda c: (frames_for(c, 20), c.send_many([oi.safe()])), False),  # a command since
        (lambda c: (_brushing_then_passive(c), frames_for(c, 20)), False),  # a brush left on
    ],
    ids=["seen stopped", "no frame since", "a command since", "a brush on"],
)
def test_the_summary_of_a_stop_not_delivered_is_calm_only_for_a_robot_seen_stopped(
    before_the_pull: Callable[[Connection], object], calm: bool
) -> None:
    """The rule: ``NOT DELIVERED:`` in capitals only where the robot may be moving. A cable
    pulled while the monitor held the run paused, the pause's stop seen taken in the frames
    since (Passive, the wheels asked for 0, no brush nor vacuum left on, nothing written
    after them): the summary said ``NOT DELIVERED: last seen stopped in Passive, ...``
    (session 38's decision) and ``final mode unknown: last seen in Passive, the stop was not
    delivered``; it says ``seen stopped; ...``. No frame since the stop, a command written
    after the last frame, or a brush left running keep the capitals."""
    connection, link = paused()
    before_the_pull(connection)
    link.pulled = True
    summary = RunSummary(mission="m")
    stop_robot(connection, summary)
    summary.final_mode = mode_of(connection)  # as the run's end sums it up
    assert summary.stop_delivered is False
    if calm:
        assert summary.safe_stop == f"seen stopped; {connection.stop_report}"
        assert summary.safe_stop.startswith(f"seen stopped; {IN_PASSIVE}; the stop was not ")
        assert summary.final_mode_text() == (
            "unknown: last seen stopped in Passive, the stop was not delivered"
        )
    else:
        assert summary.safe_stop == f"NOT DELIVERED: {connection.stop_report}"
        assert "the robot may still be moving: pick it up" in summary.safe_stop
        assert summary.final_mode_text().endswith(", the stop was not delivered")
        assert "stopped" not in summary.final_mode_text()
    assert undelivered_said(connection) == summary.safe_stop[: -len(str(connection.stop_report))]


def test_a_delivered_stop_leaves_no_report() -> None:
    connection, _ = driving()
    assert connection.safe_stop() is True
    assert connection.stop_report is None
    assert connection.mode is OIMode.PASSIVE


def test_a_robot_never_told_to_move_has_its_undelivered_stop_said_quietly(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """``roomba-bt sensors`` with its cable pulled: "ERROR ... last seen in Passive with its
    wheels never commanded; the stop was not delivered" under the error that the port is
    gone, about a robot nothing had asked to move. Reported (the summary's line), logged at
    DEBUG; a robot that was driving is still an ERROR."""
    link = Pullable(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2)))
    connection = Connection(link, CREATE2)
    connection.start("passive", PACKETS)
    frames_for(connection, 10)
    assert stopped_pulled(connection, link, caplog) == ["DEBUG"]
    assert connection.stop_report == (
        "last seen in Passive with its wheels never commanded; the stop was not delivered: "
        "the port is gone"
    )
    assert stopped_pulled(*driving(), caplog) == ["ERROR"]


LEDGE = """
name: ledge
rooms: [[[0, 0], [4, 0], [4, 3.5], [0, 3.5]]]
drops: [{name: ledge, rect: [2.0, 0.0, 4.0, 3.5]}]
robot: {start: {at: [1.6, 1.75], heading: 0}}
"""


def test_wheels_stopped_by_the_robot_s_own_fall_are_not_said_never_commanded() -> None:
    """The soak: a patrol that drove 488 m, docked (the OI's own drop to Passive on the
    charger) and fell asleep there was "last seen in Passive with its wheels never
    commanded". The fall forgets the last wheel command (the robot stopped them); what is
    said is what stopped them, until the next wheel command."""
    link = Pullable(SimLink(Simulator(parse_world(LEDGE, "<test>"), profile=CREATE2)))
    connection = Connection(link, CREATE2)
    connection.start("safe", PACKETS)
    connection.send_many([oi.drive(200, 32767)])
    while connection.mode is not OIMode.PASSIVE:  # over the edge: the OI drops to Passive
        connection.poll(0.05)
    assert connection.falls == {"cliff": 1}
    assert connection.activity() == "with its wheels stopped by its own fall to Passive (cliff)"
    link.pulled = True
    assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Passive with its wheels stopped by its own fall to Passive (cliff); the "
        "stop was not delivered: the port is gone"
    )


def test_a_wheel_command_after_a_fall_is_said_as_itself() -> None:
    assert describe_activity(None, "charger") == (
        "with its wheels stopped by its own fall to Passive (charger)"
    )
    assert describe_activity(None) == "with its wheels never commanded"
    assert describe_activity(oi.drive(100, 32767), "charger") == "at 100 mm/s"


@pytest.mark.parametrize("straight", [0x8000, 0x7FFF])
def test_driving_straight_is_said_without_a_radius(straight: int) -> None:
    """``radius: straight`` is sent as 0x8000: it was said "radius 32768 mm"."""
    assert describe_activity(oi.drive(200, straight)) == "at 200 mm/s"
    assert describe_activity(oi.drive(200, -1000)) == "at 200 mm/s, radius -1000 mm"


class CutTx:
    """A simulator link as a cable whose host-to-robot wire can die: once ``cut``, every
    write is dropped without an error (the port cannot tell), while the robot's frames
    still come. On the wall clock as a port is (the stop is checked against the stream
    there); ``mute`` drops what the robot sends instead (it falls silent)."""

    wall_clock = True

    def __init__(self, link: SimLink) -> None:
        self.link = link
        self.cut = False
        self.mute = False
        self.dropped: list[bytes] = []

    def write(self, data: bytes) -> None:
        if self.cut:
            self.dropped.append(bytes(data))
        else:
            self.link.write(data)

    def read(self, timeout: float) -> bytes:
        data = self.link.read(timeout)
        return b"" if self.mute else data

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


def spinning(
    relay: type[CutTx] = CutTx, latency: float = 0.0
) -> tuple[Connection, CutTx, Simulator]:
    """Spinning left at 100 mm/s in Safe, ten frames read; ``latency``: the simulator's
    robot-to-host delay (its fault; the watchdog then waits for the first frame that long)."""
    simulator = Simulator(
        parse_world(BOX, "<test>"), profile=CREATE2, faults=Faults(latency=latency)
    )
    link = relay(SimLink(simulator))
    connection = Connection(link, CREATE2, watchdog=DEFAULT_WATCHDOG + latency)
    connection.start("safe", PACKETS)
    connection.send_many([oi.drive(100, 1)])
    while connection.counters.frames < 10:
        connection.poll(0.05)
    return connection, link, simulator


STOP = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data
#: the stop as written three times to a robot that streams on: at first, then twice after
#: zeros that end any command a lost byte may have left the robot's parser in
STOP_THRICE = [STOP, STOP_RESYNC_ZEROS + STOP, STOP_RESYNC_ZEROS + STOP]


def test_a_stop_the_robot_streams_on_after_is_not_received_and_is_written_again() -> None:
    """The host-to-robot wire dead, the robot's still fine: the stop was said ``sent`` and the
    final mode Passive while the robot spun on in Safe. Frames still coming after Pause
    Stream say it was not heard: the stop is written twice more, each after zeros (a long
    command a lost byte made may have taken it as its data), then reported not received,
    with what the robot was last seen doing (before the stop), and the model stays in Safe."""
    connection, link, simulator = spinning()
    link.cut = True
    assert connection.safe_stop() is False
    assert link.dropped == STOP_THRICE  # the whole stop, three times
    report = connection.stop_report or ""
    assert report.startswith(
        "last seen in Safe (the last wheel command written: spinning left at 100 mm/s); the "
        "stop was written 3 times but not received: "
    ), report
    assert "sensor frames came in the 0.15 s after Pause Stream" in report
    assert "packet 35 still reading Safe, the wheels turning (-" in report  # spinning left
    assert connection.mode is OIMode.SAFE
    assert connection.safe_stopped is False
    assert simulator.mode is OIMode.SAFE  # as the robot truly is


def test_a_stop_the_robot_heard_is_confirmed_by_the_stream_going_quiet() -> None:
    connection, _, simulator = spinning()
    assert connection.safe_stop() is True
    assert connection.stop_report is None
    assert connection.mode is OIMode.PASSIVE and simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0


@pytest.mark.parametrize("latency", [0.06, 0.2, 0.5])
def test_a_stop_over_a_link_with_latency_is_confirmed_when_its_frames_in_flight_have_come(
    latency: float,
) -> None:
    """The frames the robot sent before it heard Pause Stream come ``latency`` s after it was
    written: more than three in the 0.15 s listened, they were taken for a robot streaming
    on, the stop written again from the mode they read (Safe: Drive and Motors into a robot
    in Passive) and said not received. The start-up's Query List measures the round trip;
    the frames within twice it are on their way, not the robot's answer."""
    connection, link, simulator = spinning(latency=latency)
    assert connection.ending.round_trip >= latency
    written: list[bytes] = []
    write = link.write
    link.write = lambda data: (written.append(bytes(data)), write(data))[1]  # type: ignore[method-assign]
    assert connection.safe_stop() is True, connection.stop_report
    assert written == [STOP]  # once
    assert connection.stop_report is None
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    assert simulator.violations == []  # no actuator byte in a mode that refuses it


@pytest.mark.parametrize("latency", [0.2, 0.5])
def test_the_old_mode_frames_on_their_way_read_is_no_fall_to_passive(
    latency: float, caplog: pytest.LogCaptureFixture
) -> None:
    """Safe written, the frames of the next ``latency`` s still read Passive (sent before
    the robot heard it): past the mode model's 0.1 s settle they were a fall to Passive
    ("went from Safe to Passive by itself"), then a resync back to Safe, in every run over a
    link with 0.2 s of latency. The settle is at least the frames' time on their way."""
    caplog.set_level(logging.WARNING)
    simulator = Simulator(
        parse_world(BOX, "<test>"), profile=CREATE2, faults=Faults(latency=latency)
    )
    connection = Connection(SimLink(simulator), CREATE2, watchdog=DEFAULT_WATCHDOG + latency)
    connection.start("passive", PACKETS)  # as a run starts: the tree's `mode: safe` later
    while connection.counters.frames < 5:
        connection.poll(0.05)
    connection.send(oi.safe())
    while connection.counters.frames < 5 + 3 * latency / 0.015:
        connection.poll(0.05)
    assert simulator.mode is OIMode.SAFE
    assert connection.falls == {}
    assert connection.mode is OIMode.SAFE
    assert [r.getMessage() for r in caplog.records] == []
    connection.close()


def test_a_stop_unheard_on_a_slow_link_goes_again_from_the_mode_streamed_after() -> None:
    """The host-to-robot wire dead on a link with latency: the frames past those on their
    way still come, and packet 35 in them (Safe, not the old frames' reading) decides the
    stop written again, drive 0 in it."""
    connection, link, simulator = spinning(latency=0.2)
    link.cut = True
    assert connection.safe_stop() is False
    assert link.dropped == STOP_THRICE
    report = connection.stop_report or ""
    assert "sensor frames came in the 0.15 s after Pause Stream (past the 0." in report, report
    assert "packet 35 still reading Safe" in report
    assert connection.mode is OIMode.SAFE and simulator.mode is OIMode.SAFE


def test_a_stop_after_the_robot_fell_silent_is_unconfirmed() -> None:
    """Ctrl-C a second into a silence (the watchdog tripped, the grace not yet out): it said
    ``sent`` and the final mode Passive, nothing having been heard for over a second."""
    connection, link, _ = spinning()
    link.mute = True
    stalled = 0
    start = link.now()
    while link.now() - start < 1.2:
        try:
            connection.poll(0.05)
        except StreamStalled:
            stalled += 1
    assert stalled == 1
    assert connection.safe_stop() is False
    report = connection.stop_report or ""
    assert report.startswith(  # the watchdog's drive 0, no frame since: not said "stopped"
        "last seen in Safe spinning left at 100 mm/s (then the watchdog's drive 0, which no "
        "frame showed heard); the stop was written but is unconfirmed: the robot had sent no "
        "valid frame for 1."
    ), report


def test_an_unconfirmed_stop_says_what_was_seen_before_it_not_the_stop_itself() -> None:
    """``last seen in Passive stopped``: read off the model after the stop's own Start and
    drive 0 had moved it; the robot was last seen in Safe, spinning."""
    connection, link, _ = spinning()
    connection.unheard = "the robot answers nothing"
    link.mute = True  # as it says: the Query List asked after the stop is not answered
    assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Safe spinning left at 100 mm/s; the stop was written but is "
        "unconfirmed: the robot answers nothing"
    )


def test_the_stop_tried_again_at_close_says_what_was_seen_before_the_first(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A flat battery: the run's stop unconfirmed, ``close()`` tries once more and said
    ``last seen in Passive stopped``, the model moved on by the first stop's Start, beside
    the summary's ``last seen in Safe``: one robot, two modes."""
    connection, link, _ = spinning()
    connection.unheard = "the robot answers nothing"
    link.mute = True  # as it says: the Query List asked after the stop is not answered
    assert connection.safe_stop() is False
    first = connection.stop_report
    caplog.set_level(logging.ERROR, logger="roomba_bt.robot.ending")
    caplog.clear()
    connection.close()
    assert connection.stop_report == first
    assert connection.ending.last_seen is OIMode.SAFE
    assert [r.getMessage() for r in caplog.records] == []  # said once, by the first stop


def test_a_stop_soon_after_the_robot_fell_silent_is_unconfirmed() -> None:
    """The cable pulled 0.05 s before Ctrl-C: the watchdog (0.1 s) had not tripped, the link
    still read STREAMING, and the quiet after the stop was taken for the robot hearing it (a
    confirmed safe stop of a robot nothing had been heard from since before it)."""
    connection, link, _ = spinning()
    link.mute = True
    while link.now() - connection.link.silent_since < 0.05:
        connection.poll(0.01)
    assert connection.status is LinkStatus.STREAMING  # the watchdog has not tripped
    silent = link.now() - connection.link.silent_since
    assert connection.safe_stop() is False
    said = re.fullmatch(
        r"last seen in Safe spinning left at 100 mm/s; the stop was written but is unconfirmed: "
        r"the robot had sent no valid frame for (\d\.\d\d) s before it, and none after it",
        connection.stop_report or "",
    )
    assert said is not None, connection.stop_report
    # up to the stop's write: this link's read of what waited unread before it (nothing)
    # steps its clock once or twice more
    assert silent - 0.005 <= float(said.group(1)) <= silent + 0.035


class Unplugged(CutTx):
    """A link whose port fails on every read after the next write, once ``armed`` (the USB
    adapter pulled as the stop went out)."""

    armed = False

    def write(self, data: bytes) -> None:
        super().write(data)
        self.cut = self.armed

    def read(self, timeout: float) -> bytes:
        if self.cut:
            raise OSError(5, "Input/output error")
        return super().read(timeout)


def test_a_stop_whose_listening_the_port_failed_in_is_unconfirmed() -> None:
    """The port failed in the 0.15 s the stop is listened after: nothing showed it heard,
    yet it was a confirmed stop (the quiet cut short taken for the robot's), the link said
    stopped, not lost."""
    connection, link, _ = spinning(Unplugged)
    assert isinstance(link, Unplugged)
    link.armed = True
    assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Safe spinning left at 100 mm/s; the stop was written but is unconfirmed: "
        "the port failed while the robot was listened to after it"
    )
    assert connection.status is LinkStatus.LOST


class StandingClock(Pullable):
    """A wall-clock link whose clock stops once ``stood``: reads bring nothing and the time
    does not move (a transport of one's own that keeps its clock badly, a virtual clock at
    its float's last bit). Every wait of the safe stop ends on that clock."""

    wall_clock = True

    def __init__(self, link: SimLink) -> None:
        super().__init__(link)
        self.stood_at: float | None = None

    def read(self, timeout: float) -> bytes:
        return b"" if self.stood_at is not None else bytes(self.link.read(timeout))

    def now(self) -> float:
        return self.stood_at if self.stood_at is not None else float(self.link.now())


def test_a_stop_whose_waits_never_end_on_the_link_clock_is_given_up_in_wall_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The listening after the stop waits for a quiet on the link's clock; that clock stands
    still. It read for ever (signals held by the stop: only SIGKILL ended it); now it gives
    up after the stop's bound in wall time, written but unconfirmed, and says why."""
    monkeypatch.setattr("roomba_bt.robot.ending.STOP_WALL_S", 0.2)
    connection, link = driving(StandingClock)
    link.stood_at = link.now()
    stopped: list[bool] = []
    stopping = threading.Thread(target=lambda: stopped.append(connection.safe_stop()), daemon=True)
    stopping.start()
    stopping.join(timeout=HANG_S)
    assert stopped == [False], "the stop's wait never ended"
    report = connection.stop_report or ""
    assert "the stop was written but is unconfirmed: " in report, report
    assert "the safe stop's wait for the robot was given up after 0.2 s of wall time" in report
    assert link.link.simulator.requested_left == 0  # written, and heard by the robot


class Stallable(Pullable):
    """A pullable link whose stream can go quiet first (``stalled``: reads bring nothing,
    the port still open), as a Wi-Fi bridge that is dropping does."""

    stalled = False

    def read(self, timeout: float) -> bytes:
        data = self.link.read(timeout)
        return b"" if self.stalled else data


def tripped_then_pulled(packets: tuple[int, ...] = PACKETS) -> tuple[Connection, Stallable]:
    """Driving at 200 mm/s in Safe, the stream then quiet until the watchdog writes its drive
    0, then the port gone: a bridge that dropped mid-run."""
    link = Stallable(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2), "sim://"))
    connection = Connection(link, CREATE2)
    connection.start("safe", packets)
    connection.send_many([oi.drive(200, 32767)])
    frames_for(connection, 10)
    link.stalled = True
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(100):
            connection.poll(0.05)
    assert stalled.value.halted  # the watchdog's drive 0 went out
    return connection, link


#: what an undelivered stop says of a robot whose last wheel command before the watchdog's
#: drive 0 drove it at 200 mm/s, no frame since
WATCHDOG_UNHEARD = (
    "last seen in Safe at 200 mm/s (then the watchdog's drive 0, which no frame showed "
    "heard); the stop was not delivered: the port is gone: the robot may still be "
    "moving: pick it up or press its Clean or power button; reseat the cable, then roomba-bt "
    "doctor --port sim://box"
)


def test_the_watchdog_s_drive_0_no_frame_showed_heard_is_not_said_stopped() -> None:
    """A Wi-Fi bridge dropped mid-run: the watchdog tripped and wrote its drive 0 into the
    dying socket, then the port was found gone. The report named that drive 0, the last
    wheel command written, and said "last seen in Safe stopped" of a robot last seen
    driving: it names the command before it, and the drive 0 as unconfirmed."""
    connection, link = tripped_then_pulled()
    link.pulled = True
    assert connection.safe_stop() is False
    assert connection.stop_report == WATCHDOG_UNHEARD
    assert connection.activity() == (
        "at 200 mm/s (then the watchdog's drive 0, which no frame showed heard)"
    )
    assert undelivered_said(connection) == "NOT DELIVERED: "


@pytest.mark.parametrize(
    ("packets", "then", "said"),
    [
        ((*PACKETS, 41, 42), None, "last seen in Safe stopped; "),
        (PACKETS, None, WATCHDOG_UNHEARD),
        (PACKETS, oi.halt(), "last seen in Safe stopped; "),
        (PACKETS, oi.drive(100, 32767), "last seen in Safe at 100 mm/s; "),
    ],
    ids=["requested speeds at 0", "encoders alone", "its own drive 0", "its own drive"],
)
def test_frames_or_a_command_after_the_watchdog_s_drive_0(
    packets: tuple[int, ...], then: Command | None, said: str
) -> None:
    """Frames back after the watchdog's drive 0 showing the requested wheel speeds at 0
    (packets 41/42): it was heard, and the robot is said stopped; the encoders alone (one
    frame) show nothing of it. The program's own wheel command after it stands as written:
    its own drive 0 is said stopped, its own drive at its speed."""
    connection, link = tripped_then_pulled(packets)
    link.stalled = False
    frames_for(connection, 10)
    if then is not None:
        connection.send_many([then])
    link.pulled = True
    assert connection.safe_stop() is False
    assert str(connection.stop_report).startswith(said)


@pytest.mark.parametrize(
    ("own_stop", "said"),
    [
        (lambda c: c.hold_forward(), "the bump reflex's drive 0"),
        (halt_blocked, "the tick guard's drive 0"),
    ],
    ids=["bump reflex", "tick guard"],
)
def test_the_run_s_other_own_drive_0s_no_frame_showed_heard_are_not_said_stopped(
    own_stop: Callable[[Connection], object], said: str
) -> None:
    """The bump reflex's hold and the tick guard's stop write a drive 0 of the run's own, as
    the watchdog does: the port gone right after, the robot was said stopped."""
    connection, link = driving()
    own_stop(connection)
    link.pulled = True
    assert connection.safe_stop() is False
    assert str(connection.stop_report).startswith(
        f"last seen in Safe at 200 mm/s (then {said}, which no frame showed heard); "
    )
