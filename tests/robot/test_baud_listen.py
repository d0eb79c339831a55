"""Listening at another rate takes only frames sent after the switch: over a network serial
server (RFC 2217) the old rate's frames are still in flight when the port changes its rate
(in the server, on the network, in pyserial's queue) and came out valid at the new one: a
robot that never changed its rate was "followed" to 19200 and the stop sent where it could
not hear it (the simulator: ``ignored 3 byte(s) ... sent at another baud rate``)."""

from __future__ import annotations

import pytest

from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.link import StreamLink
from roomba_bt.robot.silence import FRAMES_TO_FOLLOW, listen_window
from roomba_bt.sim.link import at_wrong_baud

PACKETS = (7, 35, 43, 44)
LAYOUT = layout_for(PACKETS, CREATE2)
SLOT = 0.015
STEP = 0.001


class InFlightLine:
    """A robot streaming at ``robot_rate`` every 15 ms behind a line that holds its bytes
    ``delay`` s in flight. A frame is decoded at the rate the port has when it leaves the
    robot (the server's UART: scrambled if the rates differ) and is read ``delay`` later,
    whatever the port's rate is by then. The clock is virtual: reads move it."""

    name = "inflight://"
    is_open = True

    def __init__(self, robot_rate: int, port_rate: int, delay: float) -> None:
        self.robot_rate = robot_rate
        self.baud = port_rate
        self.delay = delay
        self.clock = 0.0
        self._next = 0.0
        self._count = 0
        self._wire: list[tuple[float, bytes]] = []

    def now(self) -> float:
        return self.clock

    def set_baud(self, baud: int) -> None:
        self.baud = baud

    def write(self, data: bytes) -> None:
        """Nothing the robot does here depends on what it hears."""

    def close(self) -> None:
        self.is_open = False

    def _emit(self) -> None:
        while self._next <= self.clock:
            self._count += 1
            frame = LAYOUT.stream_frame({7: 0, 35: 1, 43: self._count & 0xFFFF, 44: 0})
            sent = frame if self.baud == self.robot_rate else at_wrong_baud(frame)
            self._wire.append((self._next + self.delay, sent))
            self._next += SLOT

    def read(self, timeout: float) -> bytes:
        end = self.clock + timeout
        while True:
            self._emit()
            ready = [data for at, data in self._wire if at <= self.clock]
            if ready or self.clock >= end:
                break
            self.clock = min(end, self.clock + STEP)
        self._wire = self._wire[len(ready) :]
        return b"".join(ready)


def _link(line: InFlightLine) -> StreamLink:
    link = StreamLink(
        line, CREATE2, watchdog=0.1, reconcile=lambda *_: None, report=lambda _: None,
        halt=lambda: False,
    )  # fmt: skip
    link.new_stream(PACKETS, line.now())
    line.read(1.0)  # a second of stream before the listen
    return link


def _listen(line: InFlightLine) -> bool:
    return _link(line).listen_at(19200, listen_window(PACKETS, 19200), FRAMES_TO_FOLLOW)


@pytest.mark.parametrize("delay", [0.0, 0.03, 0.06])
def test_the_old_rates_frames_in_flight_do_not_make_a_baud_change(delay: float) -> None:
    line = InFlightLine(robot_rate=115200, port_rate=115200, delay=delay)
    assert not _listen(line), "frames sent at 115200 before the switch taken for 19200's"
    assert line.baud == 115200, "the port is put back"


@pytest.mark.parametrize("delay", [0.0, 0.03, 0.06])
def test_a_robot_that_did_change_its_rate_is_still_found(delay: float) -> None:
    line = InFlightLine(robot_rate=19200, port_rate=115200, delay=delay)
    assert _listen(line)
    assert line.baud == 19200, "the port is left where the robot talks"


def test_a_frame_cut_by_a_late_read_is_not_garbage() -> None:
    """A read that ends inside a frame (the rest still on the network) holds its first bytes
    as the start of a frame: not garbage, so no listen at other rates is begun for them."""
    line = InFlightLine(robot_rate=115200, port_rate=115200, delay=0.0)
    link = _link(line)
    frame = LAYOUT.stream_frame({7: 0, 35: 1, 43: 1, 44: 0})
    line._wire = [(line.clock, frame[: len(frame) - 1])]
    line._next = line.clock + 1.0  # nothing more for now
    link.read_checked(0.0)
    assert link.bytes_since_frame == len(frame) - 1
    assert link.garbage_since_frame == 0
    line._wire = [(line.clock, b"\xaa" * 40)]
    link.read_checked(0.0)
    assert link.garbage_since_frame >= 16
