"""SimLink: the Transport contract on the virtual clock."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.stream import StreamParser
from roomba_bt.sim import SimLink, Simulator

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


def test_close_and_set_baud() -> None:
    ln = link()
    ln.set_baud(57600)
    assert ln.baud == 57600
    ln.close()
    assert not ln.is_open
    with pytest.raises(ConnectionError, match="closed"):
        ln.write(b"\x80")
    with pytest.raises(ConnectionError):
        ln.read(0.1)
