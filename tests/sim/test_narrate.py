"""``sim --log``: the commands the simulated robot hears, what it ignores, and its events."""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.sim.narrate import Narrator, command_text

from .helpers import Host, make


def narrated() -> tuple[Host, Narrator, list[str]]:
    """A robot just switched on (Off) and its log, as text after the time."""
    lines: list[str] = []
    host = make(mode=None)
    narrator = Narrator(host.sim, lambda line: lines.append(line.split(" s  ", 1)[1].rstrip()))
    return host, narrator, lines


def test_each_command_is_named_with_its_arguments_and_bytes_and_what_followed_it() -> None:
    host, narrator, lines = narrated()
    host.send(C.start(), C.drive(200, 500))
    host.send(C.safe(), C.drive(-200, 500))
    host.sim.step()
    narrator.catch_up()
    assert lines[0].startswith("heard Start (128)") and lines[0].endswith(" 80")
    assert lines[1] == "mode: Off->Passive (start)"
    assert lines[2].startswith("heard Drive (137) velocity 200, radius 500")
    assert lines[2].endswith("89 00 c8 01 f4")
    assert lines[3] == "ignored Drive (137): not accepted in Passive"
    assert lines[4].startswith("heard Safe (131)")
    assert lines[5] == "mode: Passive->Safe (safe)"
    assert lines[6].startswith("heard Drive (137) velocity -200, radius 500")
    assert len(lines) == 7


def test_a_drive_sent_again_unchanged_has_no_line_and_stray_bytes_are_counted() -> None:
    host, narrator, lines = narrated()
    host.send(C.start(), C.safe())
    host.send(C.drive(100, 0x8000))
    before = len(lines)
    for _ in range(5):
        host.send(C.drive(100, 0x8000))  # a client sending the same Drive every frame
    assert len(lines) == before
    host.send(b"\x01")  # no opcode
    narrator.catch_up()
    assert lines[-1] == "ignored 1 byte(s): no opcode, or sent at another baud rate"


def test_bytes_a_robot_asleep_ignores_are_said_ignored_because_it_sleeps() -> None:
    """``sim --asleep --log`` under a run's start-up said "ignored 35 byte(s): no opcode, or
    sent at another baud rate" of a robot that only slept: its user looked at the rate."""
    host, narrator, lines = narrated()
    host.send(C.start())
    host.sim.fall_asleep("test")
    narrator.catch_up()
    host.send(bytes(3))  # the zeros a start-up sends to set the robot's parser in step
    narrator.catch_up()
    assert lines[-1] == (
        "ignored 3 byte(s): the robot is asleep, deaf to the line until a BRC pulse wakes it "
        "(on a pty a hang-up: roomba-bt doctor or run --baud auto gives one)"
    )
    host.sim.set_brc(True)  # a pulse: low, then released
    host.sim.set_brc(False)
    assert not host.sim.deaf
    host.send(b"\x01")
    narrator.catch_up()
    assert lines[-1] == "ignored 1 byte(s): no opcode, or sent at another baud rate"


def test_every_wheel_command_sent_again_unchanged_has_no_line() -> None:
    """Drive Direct (145) and Drive PWM (146) as well as Drive: ``clean`` sends a Drive
    Direct every frame, alone or in one write with other commands."""
    host, _narrator, lines = narrated()
    host.send(C.start(), C.safe())
    for command in (C.drive_direct(200, 150), C.drive_pwm(100, -100)):
        host.send(command)
        before = len(lines)
        for _ in range(5):
            host.send(command)
            host.send(C.motors(1), command)  # in one write with another command
        heard = [line for line in lines[before:] if line.startswith("heard")]
        assert len(heard) == 5  # the Motors, each heard
        assert all(line.startswith("heard Motors (138)") for line in heard)
        assert host.sim.requested_left != 0.0


def test_a_wheel_command_sent_again_after_a_stop_has_its_line() -> None:
    host, _narrator, lines = narrated()
    host.send(C.start(), C.safe(), C.drive_direct(200, 200))
    host.send(C.safe())  # a mode command stops the wheels
    host.send(C.drive_direct(200, 200))
    assert lines[-1].startswith("heard Drive Direct (145) right_velocity 200")
    assert host.sim.requested_left > 0.0


def test_a_variable_tail_is_listed_after_the_fixed_arguments() -> None:
    assert command_text(C.stream([7, 35]).spec, bytes([2, 7, 35])) == (
        "Stream (148) packet_count 2, then 7, 35"
    )
    assert command_text(C.start().spec, b"") == "Start (128)"


def test_nobody_is_told_without_a_narrator() -> None:
    assert make().sim.heard is None
