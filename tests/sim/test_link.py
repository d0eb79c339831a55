"""SimLink: the Transport contract on the virtual clock."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.stream import StreamParser
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator

from .helpers import BOX, world


def link() -> SimLink:
    return SimLink(Simulator(world(BOX)))


def test_reading_drives_the_virtual_clock_one_frame_per_15_ms() -> None:
    ln = link()
    assert ln.now() == 0.0 and ln.is_open and ln.name == "sim://box"
    ln.write(C.start().data + C.stream([35]).data)
    parser = StreamParser([35])
    frames = []
    while ln.now() < 1.5 - 1e-9:
        frames += parser.feed(ln.read(1.0))
    assert len(frames) == 100
    assert ln.now() == pytest.approx(1.5)


def test_replies_are_there_at_once_and_no_time_passes() -> None:
    ln = link()
    ln.write(C.start().data + C.sensors(35).data)
    assert ln.read(1.0) == bytes([1])
    assert ln.now() == 0.0


def test_read_times_out_on_the_virtual_clock_with_nothing_to_say() -> None:
    ln = link()
    assert ln.read(0.3) == b""
    assert ln.now() == pytest.approx(0.3)


def test_close() -> None:
    ln = link()
    ln.close()
    assert not ln.is_open
    with pytest.raises(ConnectionError, match="closed"):
        ln.write(b"\x80")
    with pytest.raises(ConnectionError):
        ln.read(0.1)


@pytest.mark.parametrize("clock", ["virtual", "realtime"])
def test_after_baud_129_the_link_must_follow_or_it_reads_garbage(clock: str) -> None:
    ln = link() if clock == "virtual" else realtime_link()[0]
    ln.write(C.start().data + C.stream([35, 7]).data)
    parser = StreamParser([35, 7])
    assert parser.feed(ln.read(0.1))
    ln.write(C.baud_rate(57600).data)
    garbled = b"".join(ln.read(0.1) for _ in range(20))
    assert len(garbled) == 20 * 7 and parser.feed(garbled) == []
    ln.write(C.full().data)  # at the wrong rate: never arrives
    assert ln.simulator.mode.name == "PASSIVE"
    ln.set_baud(57600)
    parser.reset()
    frames = parser.feed(b"".join(ln.read(0.1) for _ in range(10)))
    assert len(frames) >= 9 and frames[-1].oi_mode_raw == 1
    ln.write(C.full().data)
    assert ln.simulator.mode.name == "FULL"


class WallClock:
    """A wall clock that moves only when told to, or when the link sleeps on it."""

    def __init__(self) -> None:
        self.now = 100.0
        self.slept: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)
        self.now += seconds


def realtime_link() -> tuple[RealtimeSimLink, WallClock]:
    wall = WallClock()
    return RealtimeSimLink(Simulator(world(BOX)), clock=wall, sleep=wall.sleep), wall


def test_the_realtime_link_waits_for_each_slot_and_never_runs_ahead_of_the_wall() -> None:
    ln, wall = realtime_link()
    ln.write(C.start().data + C.stream([35]).data)
    parser = StreamParser([35])
    frames = []
    for _ in range(10):
        frames += parser.feed(ln.read(1.0))
        assert ln.now() <= wall.now - 100.0 + 1e-9
    assert len(frames) == 10
    assert wall.now - 100.0 == pytest.approx(0.150)
    assert wall.slept == pytest.approx([0.015] * 10)


def test_while_the_host_is_busy_the_robot_streams_on_and_the_frames_queue() -> None:
    """A tick that took half a second: on a robot 33 frames are waiting in the port and the
    robot drove on meanwhile; the simulated world does not stop while the host thinks."""
    ln, wall = realtime_link()
    ln.write(C.start().data + C.safe().data + C.stream([35, 19]).data)
    parser = StreamParser([35, 19])
    assert len(parser.feed(ln.read(1.0))) == 1
    ln.write(C.drive_direct(200, 200).data)
    wall.now += 0.5  # the host busy: nothing read
    frames = parser.feed(ln.read(1.0))
    assert len(frames) == 33
    assert wall.slept == [pytest.approx(0.015)]  # the catching up did not wait
    assert ln.now() == pytest.approx(0.015 + 33 * 0.015)
    assert sum(f.values[1] for f in frames) == pytest.approx(200 * 0.5, abs=10)  # mm driven


def test_a_write_reaches_the_robot_at_the_wall_time_it_is_written() -> None:
    """Written after the host was busy (or by the tick guard during a long tick), a command
    acts from now: the robot drove on its last command until then."""
    ln, wall = realtime_link()
    ln.write(C.start().data + C.safe().data + C.stream([35, 19]).data)
    parser = StreamParser([35, 19])
    parser.feed(ln.read(1.0))
    ln.write(C.drive_direct(200, 200).data)
    wall.now += 0.3
    ln.write(C.drive_direct(0, 0).data)
    assert ln.now() == pytest.approx(0.015 + 20 * 0.015)
    wall.now += 0.3
    frames = parser.feed(ln.read(1.0))
    assert len(frames) == 40
    assert sum(f.values[1] for f in frames) == pytest.approx(200 * 0.3, abs=10)
