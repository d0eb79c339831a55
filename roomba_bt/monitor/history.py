"""A recorded run's every tick, packed: the monitor's timeline of a whole record.

``roomba-bt monitor RECORD`` keeps every tick so the page can seek anywhere in the run. As
:class:`~roomba_bt.monitor.feed.TickRecord` tuples (a tuple of the frame's values, an
:class:`~roomba_bt.robot.interface.Odometry`, floats and ints, each a Python object) a tick
took about 1.5 KB: 718 MB for a 2-hour record, more than a Raspberry Pi has beside the
robot. Here a tick is one fixed-size binary row (its numbers) and the frame's payload as the
robot sent it (:attr:`~roomba_bt.oi.frames.FrameLayout.struct`), about 170 bytes; the
strings and mappings a tick shares with others (its statuses, the nodes that flipped, the
failure reasons) are kept once each and named by number. :meth:`PackedRing.get` rebuilds a
tick's record when the page asks for it (a seek reads about twenty, and the path up to
there 1 500 to 3 000).
"""

from __future__ import annotations

import struct
from collections.abc import Hashable, Mapping
from time import monotonic
from typing import Generic, TypeVar

from roomba_bt.monitor.feed import Ring, TickRecord
from roomba_bt.oi.frames import FrameLayout
from roomba_bt.robot.interface import Odometry

_Value = TypeVar("_Value")

#: tick, time, statuses, changed, reasons, frame (payload offset, -1: none), layout, mode,
#: frames lost, sent, refused, board, tree, ticked, odometry given, its 6 floats, its counts,
#: the motors' standing command (-1: none)
_ROW = struct.Struct("<qdiiiqhhiqqii??6dqqi")
_NO_COUNT = -(1 << 63)  # an odometry without encoder counts (None)


class _Interned(Generic[_Value]):
    """Values kept once each, named by their number (found by ``key``)."""

    def __init__(self) -> None:
        self.values: list[_Value] = []
        self._numbers: dict[Hashable, int] = {}

    def number(self, value: _Value, key: Hashable) -> int:
        number = self._numbers.get(key)
        if number is None:
            number = self._numbers[key] = len(self.values)
            self.values.append(value)
        return number


class PackedRing(Ring):
    """Every record appended (a :class:`~roomba_bt.monitor.feed.Ring` without a size), each
    packed into a row; ``layouts`` is the feed's list of frame layouts (a record names its
    own by index). ``keep_from``: the records of an earlier mission time are counted, not
    kept (``monitor RECORD --from``: a window of a long record, in the memory of the
    window), so the ring starts later, as a live one that has dropped its oldest does."""

    def __init__(self, layouts: list[FrameLayout], keep_from: float = 0.0) -> None:
        super().__init__(None)
        self._keep_from = keep_from
        #: the sequence number of the first record kept (:attr:`first`)
        self._first = 0
        self._layouts = layouts
        self._rows = bytearray()
        self._payloads = bytearray()
        self._last_frame: tuple[tuple[int, ...] | None, int, int] = (None, -1, -1)
        self._statuses: _Interned[str] = _Interned()
        self._changed: _Interned[tuple[int, ...]] = _Interned()
        self._reasons: _Interned[Mapping[int, str]] = _Interned()
        self._motors: _Interned[bytes] = _Interned()  # a run sets the motors a few ways
        self._truths: dict[int, tuple[float, float, float]] = {}  # a record has none

    @property
    def first(self) -> int:
        return self._first

    def append(self, record: TickRecord) -> None:
        """Tick thread only; ``record.seq`` must be ``count``."""
        if record.time < self._keep_from:  # before the window: counted, not kept
            self._first = self.count = record.seq + 1
            self.ended = monotonic()
            return
        reasons = record.reasons
        odometry = record.odometry or Odometry()
        left, right = odometry.left_counts, odometry.right_counts
        self._rows += _ROW.pack(
            record.tick, record.time,
            self._statuses.number(record.statuses, record.statuses),
            self._changed.number(record.changed, record.changed),
            self._reasons.number(reasons, tuple(sorted(reasons.items()))),
            self._frame_at(record), record.layout, record.mode, record.frames_lost,
            record.sent, record.refused, record.board, record.tree, record.ticked,
            record.odometry is not None, odometry.x_mm, odometry.y_mm, odometry.theta_rad,
            odometry.distance_mm, odometry.angle_rad, odometry.path_mm,
            _NO_COUNT if left is None else left, _NO_COUNT if right is None else right,
            -1 if record.motors is None else self._motors.number(record.motors, record.motors),
        )  # fmt: skip
        if record.truth is not None:
            self._truths[record.seq] = record.truth
        self.count = record.seq + 1
        self.ended = monotonic()

    def _frame_at(self, record: TickRecord) -> int:
        """Where the record's frame payload is (a frame the same as the last one's shares
        it: a robot on its dock sends the same frame for hours); -1: no frame."""
        values = record.frame
        if values is None:
            return -1
        last, layout, at = self._last_frame
        if values == last and record.layout == layout:
            return at
        at = len(self._payloads)
        self._payloads += self._layouts[record.layout].struct.pack(*values)
        self._last_frame = (values, record.layout, at)
        return at

    def get(self, seq: int) -> TickRecord | None:
        if not self._first <= seq < self.count:
            return None
        (
            tick, time, statuses, changed, reasons, frame_at, layout, mode, frames_lost, sent,
            refused, board, tree, ticked, has_odometry, x, y, theta, distance, angle, path,
            left, right, motors,
        ) = _ROW.unpack_from(self._rows, (seq - self._first) * _ROW.size)  # fmt: skip
        frame = (
            self._layouts[layout].struct.unpack_from(self._payloads, frame_at)
            if frame_at >= 0
            else None
        )
        odometry = None
        if has_odometry:
            left_counts = None if left == _NO_COUNT else left
            right_counts = None if right == _NO_COUNT else right
            odometry = Odometry(x, y, theta, distance, angle, left_counts, right_counts, path)
        return TickRecord(
            seq, tick, time, self._statuses.values[statuses], self._changed.values[changed],
            self._reasons.values[reasons], frame, layout, mode, odometry, frames_lost,
            self._truths.get(seq), sent, refused, board, tree, ticked,
            self._motors.values[motors] if motors >= 0 else None,
        )  # fmt: skip

    def since(self, seq: int) -> list[TickRecord]:
        out = [self.get(s) for s in range(max(seq, self._first), self.count)]
        return [r for r in out if r is not None]
