"""``Connection.poll_frames``, the runtime's read: the frames ``poll`` gives, with no
``TimedFrame`` made for each; their arrival and numbers are the link's."""

from __future__ import annotations

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.link import TimedFrame

IDS = (7, 35, 43, 44)
LAYOUT = layout_for(IDS, CREATE2)


def _frame(bump: int, left: int) -> bytes:
    return LAYOUT.stream_frame({7: bump, 35: 2, 43: left, 44: 7})


#: one frame a read (the parser's take), two in one read, garbage, a frame cut over two
#: reads (its search), a frame out of range (packet 35 = 3 is Full: in range; 9 is not)
CHUNKS = [
    _frame(0, 100),
    _frame(1, 101) + _frame(1, 102),
    b"\x55\x13\xaa",
    _frame(0, 103)[:5],
    _frame(0, 103)[5:],
    LAYOUT.stream_frame({7: 0, 35: 9, 43: 104, 44: 7}),
    _frame(2, 105),
]


class Chunks:
    """The Transport contract over chunks given in advance: one a read, 15 ms a read."""

    name = "chunks://"
    is_open = True
    baud = 115200

    def __init__(self) -> None:
        self.at = 0
        self.time = 0.0

    def read(self, timeout: float) -> bytes:
        self.time += 0.015
        self.at += 1
        return CHUNKS[self.at - 1] if self.at <= len(CHUNKS) else b""

    def now(self) -> float:
        return self.time

    def write(self, data: bytes) -> None:
        pass

    def set_baud(self, baud: int) -> None:
        pass

    def set_wake_line(self, low: bool) -> None:
        pass

    def close(self) -> None:
        pass


def _streaming() -> Connection:
    connection = Connection(Chunks(), CREATE2, watchdog=0.0)
    connection.modes.calibrate(1, 0.0)  # the robot answered Passive right after Start
    connection.send(oi.start())
    connection.send(oi.safe())
    connection.send(oi.stream(IDS))
    return connection


def test_poll_frames_are_polls_frames_with_the_links_arrival_and_numbers() -> None:
    timed, alone = _streaming(), _streaming()
    assert timed.latest is None and alone.latest is None
    batches = 0
    for _ in CHUNKS:
        got = timed.poll(0.0)
        frames = alone.poll_frames(0.0)
        link = alone.link
        assert [t.frame for t in got] == list(frames)
        first = link.index - len(frames) + 1
        assert got == [TimedFrame(f, link.arrival, i) for i, f in enumerate(frames, first)]
        assert alone.latest == timed.latest
        if frames:
            assert alone.latest == TimedFrame(frames[-1], link.arrival, link.index)
            batches += 1
    assert alone.counters == timed.counters
    assert alone.counters.frames == 5 and alone.counters.implausible_frames == 1
    assert batches == 4  # two frames in one read came in one batch
