"""Connection behaviour that needs one backend only: the "mode + 1" robot end to end,
batches, start-up refusals, firmware text in the stream, the simulator for every profile."""

from __future__ import annotations

import logging
from typing import Any

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import ROOMBA600, get_profile
from roomba_bt.robot.connection import Connection, LinkStatus
from roomba_bt.robot.discovery import PROBE_QUERY
from roomba_bt.robot.errors import ConnectionFailed, ModeError
from roomba_bt.transport import SerialTransport

from .conftest import Link
from .sim_backend import make_sim_link
from .test_connection_contract import PACKETS, STOP_TO_PASSIVE, frames_until


def test_a_600_that_reports_mode_plus_one_is_corrected_end_to_end(fake_links: Any) -> None:
    link: Link = fake_links("pty", ROOMBA600, plus_one=True)
    robot = link.scripted()
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        assert connection.modes.plus_one is True
        frames_until(connection, lambda: connection.counters.frames >= 10)
        assert connection.mode is OIMode.SAFE and connection.last_fallback is None
        robot.fall_to_passive({9: 1})
        frames_until(connection, lambda: connection.mode is OIMode.PASSIVE)
        assert connection.last_fallback is not None
        assert connection.last_fallback.cause == "cliff"
        connection.send(oi.full())
        frames_until(connection, lambda: connection.counters.frames >= 40)
        assert connection.mode is OIMode.FULL  # reads 4: no crash, no false report
    robot.wait_for_stop(STOP_TO_PASSIVE)


def test_send_many_writes_allowed_commands_in_one_batch_and_reports_refusals() -> None:
    transport = SerialTransport.open("loop://")
    connection = Connection(transport)
    connection.send_many([oi.start(), oi.safe(), oi.drive(100, 0), oi.start()])
    with pytest.raises(ModeError, match="leds needs Safe or Full"):
        connection.send_many([oi.leds(0, 0, 0), oi.drive(1, 0), oi.sensors(7)])
    data = transport.read(0.1)
    assert data == bytes([128, 131, 137, 0, 100, 0, 0, 128, 142, 7])
    assert connection.counters.commands_refused == 2
    connection.close()


def test_start_refuses_off_and_unknown_modes() -> None:
    connection = Connection(SerialTransport.open("loop://"))
    with pytest.raises(ValueError, match="Passive, Safe or Full"):
        connection.start("off")
    with pytest.raises(ValueError, match="unknown OI mode 'turbo'"):
        connection.start("turbo")
    with pytest.raises(ValueError, match="end_in"):
        Connection(SerialTransport.open("loop://"), end_in="sleep")  # type: ignore[arg-type]
    connection.close()


def test_loop_back_is_no_robot() -> None:
    connection = Connection.open("loop://")
    with pytest.raises(
        ConnectionFailed,
        match=r"loop://: the port gives back what is written to it \(it answered 149",
    ):
        connection.start("safe", (35,), confirm_timeout=0.2)
    connection.close()


def test_open_failure_names_the_port_and_causes() -> None:
    with pytest.raises(ConnectionFailed, match=r"^/dev/no-such-roomba: could not open the port"):
        Connection.open("/dev/no-such-roomba")


def test_a_port_held_already_is_named_as_such_alone() -> None:
    """The cause is known: no list of what else to check. Held by this same process, it is
    said as its own (another program's: tests/transport/test_serial_transport.py)."""
    import os

    master, slave = os.openpty()
    try:
        holder = SerialTransport.open(os.ttyname(slave))
        with pytest.raises(ConnectionFailed) as failed:
            Connection.open(os.ttyname(slave))
        assert "this process has it open already" in str(failed.value)
        assert failed.value.likely_causes == ()
        holder.close()
    finally:
        os.close(master)
        os.close(slave)


@pytest.mark.parametrize("settings", [{"watchdog": -1.0}, {"end_in": "sleep"}])
def test_settings_refused_leave_the_port_closed(silent_port: str, settings: Any) -> None:
    """A setting :class:`Connection` refuses, after ``open`` opened the port: the port is
    closed, not held until the garbage collector came (its locks with it: the program's
    ``except ValueError as exc:`` that opens again with the setting mended was told "this
    process has it open already")."""
    try:
        Connection.open(silent_port, **settings)
    except ValueError:  # the program's retry, the refusal's traceback (its frames) still held
        Connection.open(silent_port).close()
    else:
        pytest.fail(f"{settings} was not refused")


def test_firmware_text_in_the_stream_is_skipped_and_frames_go_on(fake_links: Any) -> None:
    link: Link = fake_links("pty")
    robot = link.scripted()
    with link.connect() as connection:
        connection.start("safe", PACKETS)
        frames_until(connection, lambda: connection.counters.frames >= 3)
        robot.inject(b"bl-start\r\nRoomba by iRobot!\r\n\x13\x05garbage")
        before = connection.counters.frames
        frames_until(connection, lambda: connection.counters.frames >= before + 10)
        counters = connection.counters
        assert counters.skipped_bytes >= len(b"bl-start\r\nRoomba by iRobot!\r\n")
        assert connection.mode is OIMode.SAFE and connection.status is LinkStatus.STREAMING
    robot.wait_for_stop(STOP_TO_PASSIVE)


def test_a_banner_the_stream_went_on_after_is_no_reset_at_the_stop(
    fake_links: Any, caplog: pytest.LogCaptureFixture
) -> None:
    """The robot silent before the stop (held for 0.1 s, as a loaded machine holds a robot
    double), the stop is asked after; a reset banner read before frames that went on is
    firmware text, not a reset: no Start written again before the Query List, and no "the
    robot reset" said (both were, the banner still in the link's last chunks)."""
    link: Link = fake_links("pty")
    robot = link.scripted()
    with caplog.at_level(logging.INFO), link.connect() as connection:
        connection.start("safe", PACKETS)
        frames_until(connection, lambda: connection.counters.frames >= 3)
        robot.inject(b"bl-start\r\nRoomba by iRobot!\r\n")
        before = connection.counters.frames
        frames_until(connection, lambda: connection.counters.frames >= before + 3)
        robot.muted = True
        connection.poll(0.1)
    assert connection.safe_stopped is True
    robot.wait_for_stop(STOP_TO_PASSIVE)
    assert robot.received.endswith(STOP_TO_PASSIVE + PROBE_QUERY), list(robot.received[-30:])
    assert "reset" not in caplog.text


@pytest.mark.parametrize("profile_name", ["create2", "roomba600", "roomba500"])
def test_the_simulator_in_process_for_every_profile(profile_name: str) -> None:
    profile = get_profile(profile_name)
    link, robot = make_sim_link(profile)
    with Connection(link, profile) as connection:
        connection.start("full", PACKETS)
        assert connection.modes.plus_one is profile.reports_mode_plus_one
        frames = []
        while len(frames) < 20:
            frames += connection.poll(0.1)
        assert connection.mode is OIMode.FULL and connection.last_fallback is None
        assert connection.counters.checksum_failures == 0
        assert frames[-1].time - frames[0].time == pytest.approx(19 * 0.015)
        connection.send(oi.drive_direct(100, 100))
    assert bytes(robot.received).endswith(STOP_TO_PASSIVE)
    assert robot.mode is OIMode.PASSIVE
    assert robot.actuator_commands_outside_safe_or_full() == []


def test_counters_run_across_a_new_stream_request() -> None:
    """A second Stream (148) starts a new parser; the frames the first one counted stay in
    :attr:`Connection.counters` (they are since the connection was made)."""
    link, _ = make_sim_link(get_profile("create2"))
    with Connection(link, "create2") as connection:
        connection.start("safe", PACKETS)
        while connection.counters.frames < 10:
            connection.poll(0.1)
        before = connection.counters.frames
        connection.send(oi.stream(PACKETS[:2]))
        after: list[object] = []
        while len(after) < 5:
            after += connection.poll(0.1)
        assert connection.counters.frames >= before + 5


def test_a_hold_on_motion_writes_no_command_that_sets_the_robot_going() -> None:
    """While a tree is stopped (CommandWriter.hold_motion), a wheel command that turns a
    wheel, a built-in cycle and a motor turned on are not written, whichever way they come;
    drive 0, motors off, a mode and the LEDs are; the hold's end writes them again."""
    transport = SerialTransport.open("loop://")
    connection = Connection(transport)
    connection.send_many([oi.start(), oi.safe()])
    held: list[oi.Command] = []
    connection.writer.hold_motion(held.append)
    going = [oi.drive(300, 32767), oi.drive_direct(0, 50), oi.motors(7), oi.pwm_motors(0, 0, 9)]
    for command in going:
        connection.send(command)
    connection.send_many([oi.leds(0, 0, 0), oi.clean(), oi.halt(), oi.motors_off(), oi.full()])
    assert held == [*going, oi.clean()]
    assert connection.writer.last_wheels == oi.halt()
    connection.writer.hold_motion(None)
    connection.send(oi.drive(100, 32767))
    sent = [oi.start(), oi.safe(), oi.leds(0, 0, 0), oi.halt(), oi.motors_off(), oi.full()]
    expected = b"".join(c.data for c in [*sent, oi.drive(100, 32767)])
    assert transport.read(0.1) == expected
    connection.close()


def test_the_robot_s_own_falls_warn_once_a_cause_then_count(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The shipped clean, in Safe, meets each cliff through the firmware's stop: 18 warnings
    a run, each read as an alarm. The first fall of a cause warns, later ones are INFO with
    their count; the charger's is never a warning (docking ends so)."""
    from collections import Counter

    from roomba_bt.robot.connection import _say_change
    from roomba_bt.robot.interface import ModeChange

    said: Counter[str] = Counter()
    caplog.set_level(logging.INFO, logger="roomba_bt.robot.connection")
    for cause in ("cliff", "cliff", "charger", "wheel drop", "cliff"):
        _say_change("sim://", ModeChange(OIMode.SAFE, OIMode.PASSIVE, 0, 0.0, cause), said)
    assert [(r.levelname, r.getMessage().split("by itself ")[1]) for r in caplog.records] == [
        ("WARNING", "(cliff)"),
        ("INFO", "(cliff), 2 times so far"),
        ("INFO", "(charger)"),
        ("WARNING", "(wheel drop)"),
        ("INFO", "(cliff), 3 times so far"),
    ]
