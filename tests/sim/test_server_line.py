"""The line model of the real-time server (sim/server.py): the pty's speed and the RFC 2217
client's rate against the robot's (a client at another rate is not heard and reads
garbage), and the modem lines that RFC 2217 carries to the BRC pin."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest
import serial
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as C
from roomba_bt.oi.modes import OIMode
from roomba_bt.sim import Faults
from roomba_bt.sim.link import at_wrong_baud
from roomba_bt.sim.server import PtyEndpoint, Rfc2217Endpoint

from .served import Served


@pytest.fixture
def served() -> Iterator[list[Served]]:
    made: list[Served] = []
    yield made
    for one in made:
        one.close()


def _pty(made: list[Served], baud: int, asleep: bool = False) -> Served:
    one = Served(PtyEndpoint(), baud, asleep)
    made.append(one)
    return one


def _rfc(made: list[Served], baud: int, asleep: bool = False) -> Served:
    one = Served(Rfc2217Endpoint("127.0.0.1", 0, baud), baud, asleep)
    made.append(one)
    return one


#: How long an answer the robot's thread gives is waited for: the read ends at its byte, so
#: this bounds only one that never comes (the port's own 0.3 s is the quiet that shows none):
#: the suite's hang bound (10 s before, which a robot's thread kept from the cores may need)
ANSWER_S = HANG_S


def _mode_reply(port: serial.Serial, wait: float = 0.0) -> bytes:
    """The answer to Start and Query List [35]: read for the port's timeout, and again until
    ``wait`` has passed (the port's settings untouched: an RFC 2217 client sends them to the
    server again when its timeout changes)."""
    port.reset_input_buffer()
    port.write(C.start().data + C.query_list([35]).data)
    deadline = time.monotonic() + wait
    reply = bytes(port.read(1))
    while not reply and time.monotonic() < deadline:
        reply = bytes(port.read(1))
    return reply


@pytest.mark.parametrize("robot_baud", [19200, 115200])
def test_the_pty_answers_only_a_client_at_the_robots_rate(
    served: list[Served], robot_baud: int
) -> None:
    one = _pty(served, robot_baud)
    other = 115200 if robot_baud == 19200 else 19200
    port = serial.Serial(one.endpoint.address, other, timeout=0.3)
    try:
        assert one.endpoint.line_baud() == other, "the client's tcsetattr is what the pty says"
        assert _mode_reply(port) == b""
        assert one.simulator.mode is OIMode.OFF, "nothing reached the robot"
        assert one.simulator.ignored_bytes > 0
        port.baudrate = robot_baud
        assert _mode_reply(port, ANSWER_S) == b"\x01"
        assert one.simulator.mode is OIMode.PASSIVE  # type: ignore[comparison-overlap]
    finally:
        port.close()


def test_a_client_at_another_rate_reads_the_robots_bytes_scrambled(served: list[Served]) -> None:
    one = _pty(served, 19200)
    port = serial.Serial(one.endpoint.address, 19200, timeout=ANSWER_S)  # 64 bytes each read
    try:
        port.write(C.start().data + C.stream([35]).data)  # frames: [19][2][35][1][checksum]
        assert port.read(64)
        port.baudrate = 115200
        port.reset_input_buffer()
        seen = bytes(port.read(64))
        frame = bytes([19, 2, 35, 1, (-(19 + 2 + 35 + 1)) & 0xFF])
        assert seen and frame not in seen
        assert at_wrong_baud(frame) in seen
    finally:
        port.close()


# pyserial's RFC 2217 client names its reader thread with the deprecated setDaemon/setName
@pytest.mark.filterwarnings("ignore:set(Daemon|Name)\\(\\) is deprecated:DeprecationWarning")
def test_rfc2217_carries_the_rate_and_the_modem_lines_to_brc(served: list[Served]) -> None:
    one = _rfc(served, 19200, asleep=True)
    port: serial.Serial = serial.serial_for_url(
        one.endpoint.address, do_not_open=True, baudrate=19200
    )
    port.timeout = 0.3
    port.rts = port.dtr = False  # opened with BRC high: no pulse yet
    port.open()
    try:
        assert one.endpoint.line_baud() == 19200
        assert _mode_reply(port) == b"", "asleep: deaf"
        port.rts = True  # BRC low: the falling edge wakes it
        port.rts = False
        assert _mode_reply(port, ANSWER_S) == b"\x01"
        assert one.simulator.brc_pulses == 1
        port.dtr = True  # DTR drives BRC too (some cables wire that one)
        port.dtr = False
        assert _mode_reply(port, ANSWER_S) == b"\x01"
        assert one.simulator.brc_pulses == 2
        port.baudrate = 115200
        assert one.endpoint.line_baud() == 115200
        assert _mode_reply(port) == b""
    finally:
        port.close()


def test_a_pty_hang_up_is_brc_high_and_the_rates_return_the_falling_edge_that_wakes(
    served: list[Served], until: Callable[..., None]
) -> None:
    """A pty has no modem lines to set, but speed 0 (B0) drops DTR and RTS and a real speed
    asserts them (POSIX): the endpoint reads them so, and opening is no pulse."""
    one = _pty(served, 115200, asleep=True)
    port = serial.Serial(one.endpoint.address, 115200, timeout=0.3)
    try:
        with pytest.raises(OSError, match="Inappropriate ioctl"):
            port.rts = True
        assert one.endpoint.wake_line() is True, "a real speed: lines asserted, BRC low"
        assert _mode_reply(port) == b"", "opening woke nothing: still asleep, deaf"
        assert one.simulator.brc_pulses == 0
        port.baudrate = 0
        assert one.endpoint.wake_line() is False, "B0: lines dropped, BRC high"
        until(lambda: not one.simulator.brc_low)
        port.baudrate = 115200
        until(lambda: one.simulator.brc_pulses == 1)
        assert _mode_reply(port, ANSWER_S) == b"\x01", "woken by the falling edge, into Passive"
    finally:
        port.close()


def test_the_sleep_at_fault_is_the_power_saving_sleep_start_does_not_wake_it(
    served: list[Served], until: Callable[..., None]
) -> None:
    """``sim --sleep-at``: the robot sleeps as after five idle minutes in Passive, its motors
    off, deaf to every byte: Start does not wake it (the 600 spec wakes this sleep by a BRC
    pulse only; Start is what Off listens for), the pty's hang-up pulse does. Due while it
    drives in Safe, which never sleeps, the sleep waits until Start puts it in Passive."""
    one = Served(PtyEndpoint(), faults=Faults(sleep_at=1.5))
    served.append(one)
    sim = one.simulator
    port = serial.Serial(one.endpoint.address, 115200, timeout=0.3)
    try:
        port.write(C.start().data + C.safe().data + C.drive(200, 1).data)
        until(lambda: sim.mode is OIMode.SAFE and sim.requested_left != 0)
        until(lambda: sim.time > 1.6)
        assert not sim.asleep and sim.mode is OIMode.SAFE, "Safe never sleeps"
        port.write(C.start().data)
        until(lambda: sim.asleep)
        assert sim.mode is OIMode.PASSIVE
        assert sim.requested_left == sim.requested_right == 0
        assert _mode_reply(port) == b"", "Start and Query List do not reach a sleeping robot"
        assert sim.asleep
        port.baudrate = 0  # the pty's BRC pulse: a hang-up, then the rate's return
        until(lambda: not sim.brc_low)
        port.baudrate = 115200
        until(lambda: sim.brc_pulses == 1)
        assert _mode_reply(port, ANSWER_S) == b"\x01", "woken by the pulse, into Passive"
    finally:
        port.close()
