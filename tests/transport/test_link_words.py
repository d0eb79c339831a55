"""A network link's words: every message a ``socket://`` or ``rfc2217://`` run can reach
names the network and the bridge by its HOST:PORT, never a cable, a device or a USB
adapter there is none of (transport/link_kind.py)."""

from __future__ import annotations

import errno
from dataclasses import fields

import pytest

from roomba_bt.robot.errors import RobotAsleep, RobotReset
from roomba_bt.robot.startup import no_answer_causes, not_a_mode
from roomba_bt.transport.link_kind import LinkWords, link_of
from roomba_bt.transport.open_failure import error_number, open_failure

#: what a serial adapter's words say and a network link's must not
CABLE_WORDS = ("cable", "device", "usb", "adapter", "unplug")
BRIDGES = ("socket://192.168.4.1:23", "rfc2217://192.168.4.1:23")
#: the fields that say where the line is: each names the bridge at its address
NAMING = (
    "between", "line", "open_fix", "unreachable", "lossy", "bad_line", "byte_check",
    "serial_side", "wiring", "pulse_fix", "reach", "check", "went_silent",
)  # fmt: skip


def _texts(words: LinkWords) -> dict[str, str]:
    """Every phrase of ``words`` by its field (a tuple's joined)."""
    said = {}
    for field in fields(words):
        value = getattr(words, field.name)
        if isinstance(value, tuple):
            said[field.name] = "; ".join(value)
        elif isinstance(value, str):
            said[field.name] = value
    return said


@pytest.mark.parametrize("port", BRIDGES)
def test_no_network_phrase_names_a_cable_or_a_device(port: str) -> None:
    for name, text in _texts(link_of(port)).items():
        assert not any(word in text.lower() for word in CABLE_WORDS), (name, text)


@pytest.mark.parametrize("port", BRIDGES)
@pytest.mark.parametrize("name", NAMING)
def test_a_network_phrase_about_the_line_names_the_bridge(port: str, name: str) -> None:
    assert "the bridge at 192.168.4.1:23" in _texts(link_of(port))[name]


@pytest.mark.parametrize("code", [errno.EHOSTUNREACH, errno.ENETUNREACH, errno.ETIMEDOUT])
def test_a_bridge_that_cannot_be_reached_is_said_so_by_its_address(code: int) -> None:
    """ "No route to host" had the device path's fix (ls /dev/ttyUSB*)."""
    said = open_failure("socket://192.0.2.10:8888", code)
    assert said is not None and said.startswith("the bridge at 192.0.2.10:8888 cannot be reached")
    assert open_failure("/dev/ttyUSB0", code) is None  # a device's error says it itself


def test_a_connect_that_timed_out_is_etimedout() -> None:
    """pyserial's socket:// handler wraps the connect's ``socket.timeout`` (no number)."""
    try:
        try:
            raise TimeoutError("timed out")
        except TimeoutError as exc:
            raise OSError("could not open port socket://192.0.2.10:8888") from exc
    except OSError as wrapped:
        assert error_number(wrapped) == errno.ETIMEDOUT


@pytest.mark.parametrize("port", BRIDGES)
def test_the_robot_s_errors_on_a_bridge_name_it(port: str) -> None:
    bridge = "the bridge at 192.168.4.1:23"
    messages = [
        str(RobotReset(port, halted=True, after_write=0.05)),
        str(RobotAsleep(port, 300.0, keep_awake=True, pulses=False)),
        str(RobotAsleep(port, 300.0, keep_awake=True, pulses=True)),
        no_answer_causes(port)[2],
        str(not_a_mode(port, 149)),
    ]
    for message in messages:
        assert bridge in message, message
        assert not any(word in message.lower() for word in CABLE_WORDS), message


def test_a_raw_bridge_s_sleep_advice_does_not_send_a_docked_robot_to_safe() -> None:
    """Keep-awake's warning on ``socket://`` said "a robot left 5 minutes in Passive (waiting
    on its dock) sleeps: keep it in Safe": on a powered dock Safe does not hold (both specs,
    "Safe Mode": the charger drops it to Passive, as the simulator does) and the battery does
    not charge in it. Safe is the advice off the dock only."""
    advice = link_of("socket://192.168.4.1:23").sleep_advice
    assert advice == (
        "a robot left 5 minutes in Passive sleeps, on its dock too, where Safe does not hold "
        "(the powered charger drops it to Passive, both specs): keep it in Safe off the dock"
    )


def test_a_device_path_keeps_the_cable_s_words() -> None:
    """The words docs/reliability.md and docs/doctor.md quote, on a device path."""
    assert no_answer_causes("/dev/ttyUSB0")[2] == (
        "wrong cable or wiring (TX/RX swapped, adapter not a 5 V TTL serial)"
    )
    assert "(a bad cable: a data byte 7 after it is read as Reset)" in str(
        RobotReset("/dev/ttyUSB0", halted=True, after_write=0.05)
    )
    assert "check that the cable wires BRC to RTS or DTR" in str(
        RobotAsleep("/dev/ttyUSB0", 300.0, keep_awake=True, pulses=True)
    )


def test_a_stop_not_delivered_sends_a_pty_s_user_to_no_path_that_may_be_another_s() -> None:
    """After a run lost a pty (the simulator killed), its user was told "reseat the cable,
    then roomba-bt doctor --port /dev/pts/0"; the kernel gives that number to the next
    program that opens a pty, and doctor wrote its Query Lists and a hang-up into another
    session's simulator. A device path and a bridge come back, and keep doctor's advice."""
    pty = link_of("/dev/pts/0").reach
    assert pty.startswith("/dev/pts/0 will not come back")
    assert "start the simulator or bridge again and use the path it prints" in pty
    assert "doctor --port" not in pty and "cable" not in pty
    for port in ("/dev/ttyUSB0", "/dev/serial/by-id/usb-FTDI_X-if00-port0"):
        assert link_of(port).reach == f"reseat the cable, then roomba-bt doctor --port {port}"
    assert link_of(BRIDGES[0]).reach.endswith(f"then roomba-bt doctor --port {BRIDGES[0]}")


def test_a_pty_that_failed_is_said_its_program_s_end_not_a_cable() -> None:
    """A run whose simulator (``sim --pty``) was killed ended "the port is gone (the cable was
    pulled or the adapter reset)" while the advice under it spoke of the simulator: one
    table, the link's kind, words both."""
    pty = link_of("/dev/pts/3").gone
    assert "the simulator or a bridge such as socat" in pty and "cable" not in pty
    for port in ("/dev/ttyUSB0", "/dev/serial/by-id/usb-FTDI_X-if00-port0"):
        assert link_of(port).gone == "the cable was pulled or the adapter reset"


#: the fields that name the line: on a pty, the simulator first, and a cable only behind a
#: bridge such as socat (which may carry the bytes to a real adapter)
PTY_LINE = ("line", "froze", "check", "lossy", "bad_line", "byte_check", "serial_side")


@pytest.mark.parametrize("name", PTY_LINE)
def test_a_pty_s_line_is_the_simulator_or_a_cable_behind_a_bridge(name: str) -> None:
    """A run on ``sim --pty --host-drop-rate 0.05`` said "(a loose or noisy cable?)", "so the
    cable is a likely cause" and "check the cable and its adapter" of a simulator told to
    drop bytes; socat to a real adapter is a pty too, so both are said. A device path keeps
    the cable's words."""
    pty = _texts(link_of("/dev/pts/3"))[name]
    assert "simulator" in pty and "socat" in pty, pty
    assert pty.index("simulator") < pty.index("cable"), pty
    device = _texts(link_of("/dev/ttyUSB0"))[name]
    assert "cable" in device and "simulator" not in device, device


def test_a_pty_s_stream_that_froze_and_a_silent_robot_name_the_simulator_first() -> None:
    """The outcome's words, where a pty's user read of a cable: a stream that stopped and
    came back, and one that stopped for good."""
    from roomba_bt.robot.errors import StreamLost

    froze = str(StreamLost("/dev/pts/3", 2.5, 2.0, 0, watchdog=0.1, halted=True, came_back=3.1))
    assert "came back (a stalled simulator, or the adapter or cable behind a bridge" in froze
    silent = str(StreamLost("/dev/pts/3", 2.5, 2.0, 0, watchdog=0.1, halted=True))
    assert "or the program at the pty's other end (the simulator, or a bridge such" in silent
    assert "(a frozen adapter or cable?)" in str(
        StreamLost("/dev/ttyUSB0", 2.5, 2.0, 0, watchdog=0.1, halted=True, came_back=3.1)
    )


#: the fields of a robot's start-up and keep-awake messages that name the line: a pty's
#: kept the cable's words after its line, froze and check had theirs
PTY_START = ("between", "wiring", "echo_causes", "pulse_fix")


@pytest.mark.parametrize("name", PTY_START)
def test_a_pty_s_start_up_words_name_the_simulator_not_a_cable_alone(name: str) -> None:
    """``run --port`` on ``sim --pty --asleep`` listed "wrong cable or wiring (TX/RX swapped,
    adapter not a 5 V TTL serial)" among its causes, and a pty that gave back its bytes
    "loop:// or another test port given as the robot's": the simulator first, a cable only
    behind a bridge such as socat. A device path keeps the cable's words."""
    pty = _texts(link_of("/dev/pts/3"))[name]
    assert "simulator" in pty and "socat" in pty, pty
    assert "cable" not in pty or pty.index("simulator") < pty.index("cable"), pty
    assert "loop://" not in pty and "the wrong device" not in pty, pty
    device = _texts(link_of("/dev/ttyUSB0"))[name]
    assert "simulator" not in device and "socat" not in device, device


def test_the_robot_s_errors_on_a_pty_name_what_is_at_its_other_end() -> None:
    """The messages a run on ``sim --pty`` meets at its start: no answer (``--asleep``), an
    echo, and keep-awake's BRC fix where the pty cannot pulse."""
    port = "/dev/pts/3"
    assert no_answer_causes(port)[2].startswith("a pty that is not the simulator's")
    echo = str(not_a_mode(port, 149))
    assert "a program at the pty's other end that gives back what it is sent" in echo, echo
    assert "loop://" not in echo
    asleep = str(RobotAsleep(port, 300.0, keep_awake=True, pulses=False))
    assert "a pty carries no modem lines: roomba-bt sim --rfc2217 carries BRC" in asleep, asleep
    assert "use a USB cable" not in asleep


def test_a_pty_path_that_is_not_there_is_said_a_pty_not_an_unplugged_cable() -> None:
    """``run --port /dev/pts/7`` after the simulator ended said "no such device: the cable
    unplugged, or the adapter has another name"; a device path keeps those words."""
    said = open_failure("/dev/pts/7", errno.ENOENT)
    assert said is not None and said.startswith("no such pty: the program that made it")
    assert "cable" not in said
    device = open_failure("/dev/ttyUSB7", errno.ENOENT)
    assert device is not None and device.startswith("no such device: the cable unplugged")
