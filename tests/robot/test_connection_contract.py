"""The connection contract, run on every backend (see ``conftest.py``): start-up, stream,
guarded commands, and what is on the wire after every kind of ending."""

from __future__ import annotations

import logging
import threading
import time

import pytest
from waits import HANG_S, waited  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Radius
from roomba_bt.oi.errors import BandwidthError, UnsupportedCommandError
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import ROOMBA500
from roomba_bt.robot.connection import Connection, LinkStatus
from roomba_bt.robot.discovery import PROBE_QUERY
from roomba_bt.robot.errors import ConnectionFailed, ModeError, PortLost, StreamStalled

from .conftest import Link
from .fake_robot import FakeRobot

PACKETS = (7, 9, 10, 11, 12, 34, 35, 43, 44)
#: drive 0, motors off, pause stream, Start: the end of every ending from Safe or Full.
STOP_TO_PASSIVE = bytes([137, 0, 0, 0, 0, 138, 0, 150, 0, 128])
STOP_TO_OFF = bytes([137, 0, 0, 0, 0, 138, 0, 150, 0, 173])
#: pause the stream, Start: the end of every ending from Passive (no actuator byte there).
PASSIVE_TO_PASSIVE = bytes([150, 0, 128])


def frames_until(connection: Connection, predicate: object, timeout: float = HANG_S) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        connection.poll(0.05)
        if callable(predicate) and predicate():
            return
    raise AssertionError(f"condition not reached while polling for {timeout:g} s")


def no_actuator_outside_safe(robot: FakeRobot) -> None:
    bad = robot.actuator_commands_outside_safe_or_full()
    assert bad == [], f"actuator commands reached the robot in Passive/Off: {bad}"


def test_start_confirms_enters_mode_and_streams(link: Link) -> None:
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        arrived = connection.poll(2.0)
        assert arrived, "no frame within 2 s of the stream's start"
        first = arrived[0]
        assert first.index == 1 and first.frame.packet_ids == PACKETS
        frames_until(connection, lambda: connection.counters.frames >= 5)
        assert connection.mode is OIMode.SAFE
        assert connection.status is LinkStatus.STREAMING
        latest = connection.latest
        assert latest is not None and latest.index >= 5 and latest.time >= first.time
        assert connection.counters.checksum_failures == 0
    if link.robot is not None:
        link.robot.wait_for_stop(STOP_TO_PASSIVE)
        assert link.robot.opcodes()[:6] == [
            128,
            150,
            149,
            149,
            131,
            148,
        ]  # 149 twice: two replies agree
        assert link.robot.mode is OIMode.PASSIVE
        no_actuator_outside_safe(link.robot)


def test_normal_exit_ends_with_drive_0_motors_off_pause_and_start(link: Link) -> None:
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        connection.send(oi.drive(100, Radius.STRAIGHT))
        connection.poll(0.05)
    assert connection.status is LinkStatus.CLOSED
    assert connection.safe_stopped is True
    robot = link.scripted()
    robot.wait_for_stop(STOP_TO_PASSIVE)
    assert robot.wait_until(lambda r: r.mode is OIMode.PASSIVE)


def test_exception_inside_the_block_still_stops_the_robot(link: Link) -> None:
    robot = link.scripted()
    with pytest.raises(RuntimeError, match="mission crashed"), link.connect() as connection:
        connection.start("full", PACKETS)
        connection.send(oi.drive_direct(200, 200))
        raise RuntimeError("mission crashed")
    robot.wait_for_stop(STOP_TO_PASSIVE)


def test_end_in_stop_sends_stop_on_profiles_that_have_it(link: Link) -> None:
    robot = link.scripted()
    with link.connect(end_in="stop") as connection:
        connection.start("safe", PACKETS)
    # the stop is the last bytes, or (a robot double held before it: a loaded machine) its
    # Stop is written again after the question that confirmed it (the next test)
    assert robot.wait_until(
        lambda r: STOP_TO_OFF in r.received and r.received.endswith(bytes([173]))
        and r.mode is OIMode.OFF
    )  # fmt: skip
    assert connection.mode is OIMode.OFF


@pytest.mark.parametrize("kind", ["pty", "tcp"])
def test_end_in_stop_not_confirmed_is_asked_after_and_written_again(
    fake_links: object, kind: str
) -> None:
    """A Stop (173) the quiet after it cannot confirm (the robot silent before it) is asked
    after, which needs Start (the OI answers nothing in Off): the robot answers in Passive,
    and Stop is written again, so it ends in the Off asked for. It was left in Passive while
    the summary said ``final mode Off``."""
    link: Link = fake_links(kind)  # type: ignore[operator]
    robot = link.scripted()
    with link.connect(end_in="stop") as connection:
        connection.start("safe", PACKETS)
        connection.send(oi.drive(100, Radius.STRAIGHT))
        frames_until(connection, lambda: connection.counters.frames >= 3)  # the stream read
        robot.muted = True  # no frame before the stop: its quiet after shows nothing
        time.sleep(0.1)  # over three stream periods of silence (more under load: the same)

    def stopped_again(r: FakeRobot) -> bool:
        """The Stop, the question (its Start among it) and the Stop again, the robot in Off:
        a robot that took only the first Stop ends with the question, in Passive."""
        written = bytes(r.received)
        after = written[written.find(STOP_TO_OFF) + len(STOP_TO_OFF) :]
        asked = STOP_TO_OFF in written and PROBE_QUERY in after and bytes([128]) in after
        return asked and after.endswith(bytes([173])) and r.mode is OIMode.OFF

    assert robot.wait_until(stopped_again), bytes(robot.received[-40:]).hex(" ")
    assert connection.safe_stopped is True and connection.mode is OIMode.OFF
    assert connection.ending.found_at.startswith("the Stop (173) was not confirmed at first")


def test_end_in_stop_falls_back_to_start_on_the_500(
    fake_links: object, caplog: pytest.LogCaptureFixture
) -> None:
    link: Link = fake_links("pty", ROOMBA500)  # type: ignore[operator]
    robot = link.scripted()
    with caplog.at_level(logging.WARNING), link.connect(end_in="stop") as connection:
        connection.start("safe", PACKETS)
        with pytest.raises(UnsupportedCommandError, match="stop is not available on roomba500"):
            connection.send(oi.stop())
    assert "has no Stop (173)" in caplog.text
    robot.wait_for_stop(STOP_TO_PASSIVE)


def test_fall_to_passive_refuses_the_next_drive_and_names_the_cause(link: Link) -> None:
    robot = link.scripted()
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        connection.send(oi.drive(150, Radius.STRAIGHT))
        assert robot.wait_until(lambda r: 137 in r.opcodes())  # taken before the fall
        robot.fall_to_passive({7: 0b0100})  # right wheel dropped
        frames_until(connection, lambda: connection.mode is OIMode.PASSIVE)
        fallback = connection.last_fallback
        assert fallback is not None and fallback.cause.startswith("wheel drop")
        assert fallback.previous is OIMode.SAFE
        sent_before = len(robot.received)
        with pytest.raises(ModeError) as refused:
            connection.send(oi.drive(150, Radius.STRAIGHT))
        message = str(refused.value)
        assert message.startswith("drive needs Safe or Full; the robot is in Passive since ")
        assert ", after a wheel drop" in message
        connection.poll(0.05)
        assert len(robot.received) == sent_before  # nothing of it reached the wire
        assert connection.counters.commands_refused == 1
    # from Passive the ending sends no actuator byte: pause the stream, then Start, first
    # and last (a Query List after it asks whether it was heard, where the robot had been
    # silent before it: a robot double held by a loaded machine)
    robot.wait_for_stop(PASSIVE_TO_PASSIVE)
    ending = bytes(robot.received[sent_before:])
    assert ending.startswith(PASSIVE_TO_PASSIVE), f"the ending wrote {list(ending)}"
    no_actuator_outside_safe(robot)


def test_cliff_and_charger_causes_are_reported(link: Link) -> None:
    robot = link.scripted()
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        robot.fall_to_passive({10: 1})
        frames_until(connection, lambda: connection.mode is OIMode.PASSIVE)
        assert connection.last_fallback is not None
        assert connection.last_fallback.cause == "cliff"
        robot.set_values({10: 0, 34: 0b10})
        connection.send(oi.safe())
        frames_until(connection, lambda: connection.counters.frames > 3)
        robot.fall_to_passive({})
        frames_until(connection, lambda: connection.mode is OIMode.PASSIVE)
        assert connection.last_fallback.cause == "charger"


def test_no_actuator_byte_ever_leaves_in_passive_or_off(link: Link) -> None:
    connection = link.connect()
    for actuator in (oi.drive(100, 0), oi.motors(1), oi.leds(0, 0, 0), oi.play(0)):
        with pytest.raises(ModeError, match=r"the robot is in Off .*send start first"):
            connection.send(actuator)
    with connection:
        connection.start("passive", PACKETS)
        for actuator in (oi.drive_direct(100, 100), oi.drive_pwm(0, 0), oi.pwm_motors(0, 0, 0)):
            with pytest.raises(ModeError, match="send safe or full first"):
                connection.send(actuator)
        # one tick's outbox: the mode change comes first, so the drive behind it passes
        connection.send_many([oi.safe(), oi.drive(100, Radius.STRAIGHT)])
        assert connection.mode is OIMode.SAFE
        connection.send(oi.start())  # back to Passive
        with pytest.raises(ModeError):
            connection.send_many([oi.drive(50, 0), oi.sensors(7)])
        connection.poll(0.05)
    robot = link.scripted()
    robot.wait_for_stop(PASSIVE_TO_PASSIVE)
    no_actuator_outside_safe(robot)
    opcodes = robot.opcodes()
    assert opcodes.count(137) == 1  # the one drive sent after safe in the batch
    assert 142 in opcodes  # the allowed command of the refused batch still left


def test_watchdog_sends_drive_0_and_reports_a_stalled_stream(link: Link) -> None:
    robot = link.scripted()
    with link.connect(watchdog=0.3) as connection:
        connection.start("safe", PACKETS)
        connection.send(oi.drive(100, Radius.STRAIGHT))
        frames_until(connection, lambda: connection.counters.frames >= 3)
        robot.muted = True
        with pytest.raises(StreamStalled, match=r"no valid sensor frame .*drive 0 sent"):
            for _ in range(200):
                connection.poll(0.02)
        assert connection.status is LinkStatus.STALLED
        assert connection.counters.watchdog_trips == 1
        assert robot.wait_until(lambda r: r.received.endswith(bytes([137, 0, 0, 0, 0])))
        robot.muted = False
        frames_until(connection, lambda: connection.status is LinkStatus.STREAMING)
    robot.wait_for_stop(STOP_TO_PASSIVE)


def test_robot_that_does_not_answer_fails_with_the_port_and_likely_causes(
    fake_links: object,
) -> None:
    link: Link = fake_links("pty", silent=True)  # type: ignore[operator]
    connection = link.connect()
    with pytest.raises(ConnectionFailed) as failed:
        connection.start("safe", PACKETS, confirm_timeout=0.2)
    message = str(failed.value)
    assert message.startswith(link.url + ": the robot did not answer")
    assert "wrong baud rate" in message and "no power" in message
    assert "wrong cable" not in message  # a pty: the program at its other end, not a cable
    assert "a cable behind a bridge such as socat wired wrong" in message
    connection.close()


def test_a_stream_that_does_not_fit_is_refused_before_any_byte(link: Link) -> None:
    connection = link.connect(baud=19200)
    with pytest.raises(BandwidthError, match="does not fit in 15 ms at 19200 baud"):
        connection.start("safe", (100,))
    connection.close()
    if link.robot is not None:
        time.sleep(0.05)
        assert bytes(link.robot.received) == b""


def test_lost_port_is_reported_at_once_and_close_does_not_hang(link: Link) -> None:
    robot = link.scripted()
    connection = link.connect()
    connection.start("safe", PACKETS)
    frames_until(connection, lambda: connection.counters.frames >= 2)
    robot.hang_up()
    waited(robot.closed, "the robot's seeing its cable pulled")  # an event
    with pytest.raises(PortLost, match="the link is lost"):
        for _ in range(100):
            connection.poll(0.02)
            connection.send(oi.drive(0, 0))
    assert connection.status is LinkStatus.LOST
    closed: list[bool] = []
    done = threading.Event()

    def close() -> None:
        closed.append(connection.close())
        done.set()

    threading.Thread(target=close, daemon=True).start()
    waited(done, "close() on a lost port")  # an event, not a timing
    assert closed == [False]
    assert connection.safe_stopped is False


def test_baud_command_changes_the_port_rate_after_the_wait(link: Link) -> None:
    robot = link.scripted()
    with link.connect() as connection:
        connection.start("passive", (7, 35))
        connection.set_baud(57600)
        assert connection.baud == 57600
        assert connection.transport.baud == 57600  # type: ignore[attr-defined]
        with pytest.raises(BandwidthError):
            connection.set_baud(9600 // 8)
    assert [r.command.args for r in robot.commands if r.command.opcode == 129] == [(10,)]


def test_digit_leds_raw_warns_on_600_firmware(link: Link, caplog: pytest.LogCaptureFixture) -> None:
    with link.connect() as connection:
        connection.start("safe", (35,))
        with caplog.at_level(logging.WARNING):
            connection.send(oi.digit_leds_raw([1, 2, 3, 4]))
    assert "does not work on" in caplog.text


def test_query_is_refused_while_streaming(link: Link) -> None:
    with link.connect() as connection:
        connection.start("safe", (35,))
        with pytest.raises(Exception, match="stream paused"):
            connection.query((7,))
