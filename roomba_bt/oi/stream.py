"""The incremental stream parser, reply parsing and the stream bandwidth check.

A stream frame on the wire (opcode 148, every 15 ms)::

    [19][n][id1][data1...][id2][data2...]...[checksum]
     |   |  '------------ n bytes ------------'  |
     |   '- n-bytes: bytes between n and checksum |
     '- header                                    '- sum of all bytes (header included on
                                                      600 / Create 2) == 0 mod 256

How garbage is handled (the parser never raises on bad bytes):

* before a frame (noise, firmware ASCII text such as the reset banner): bytes up to the next
  ``19`` are skipped and counted in ``skipped_bytes``;
* a ``19`` followed by the wrong n-bytes for the requested list, or by packet ids that are not
  the requested ones, is not a frame: one byte is skipped and the search goes on;
* a candidate whose checksum fails is counted in ``checksum_failures`` and only its header byte
  is skipped, so a valid frame that starts inside it (after a truncated frame) is still found;
* a candidate that passes the checksum but carries a value out of its range is not a frame
  either: counted in ``implausible`` and, like a checksum failure, only its header byte is
  skipped. The OI checksum is an 8-bit sum: two flips of the same bit in opposite directions
  cancel (1 pair in 16), and a truncated frame completed by the next one's bytes passes about
  1 time in 256; the ranges catch most of those. The checksum is judged first, even where a
  reserved bit already rules the candidate out: one that fails it is a checksum failure, and
  one that passes the other model's rule counts in ``other_checksum`` too (a Roomba 500's wall
  signal over 1023, read with a 600's profile, is its own model's frame, not noise). Out of
  range means: a reserved bit set (packet 7 bits 4-7, 14 bits 5-7, 45 bit 7, the high nibble
  of a 12-bit signal...), a value past its table limit (charging state 0-5, requested
  velocities -500..500, packet 35 0-3, or 1-4 on firmware that reports the mode + 1), or an
  encoder step larger than the wheels turn in the frames since the last accepted one
  (:data:`~roomba_bt.oi.odometry.MAX_COUNTS_PER_SLOT` each; two consecutive frames that agree
  re-anchor the encoders after a real gap);
* a frame cut at the end of a chunk waits for the next ``feed``.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import lru_cache

from roomba_bt.oi.errors import BandwidthError
from roomba_bt.oi.frames import (
    SLOT_SECONDS,
    STREAM_HEADER,
    FrameLayout,
    SensorFrame,
    layout_for,
    stream_frame_size,
)
from roomba_bt.oi.modes import OI_MODE_PACKET
from roomba_bt.oi.odometry import MAX_COUNTS_PER_SLOT
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile


def stream_budget(baud: int) -> int:
    """Bytes that fit in one 15 ms slot: 10 bits a byte (start, 8 data, stop).

    115200 -> 172, 57600 -> 86, 19200 -> 28.
    """
    return baud * 15 // 10_000


def check_bandwidth(packet_ids: Iterable[int], baud: int) -> int:
    """Raise :class:`BandwidthError` if a stream of ``packet_ids`` cannot fit in 15 ms at
    ``baud``; return the frame size in bytes otherwise."""
    from roomba_bt.oi.frames import stream_frame_size

    size = stream_frame_size(packet_ids)
    budget = stream_budget(baud)
    if size > budget:
        raise BandwidthError(size, budget, baud)
    return size


_new_object = object.__new__
_from_bytes = int.from_bytes

ByteSum = Callable[[bytes | bytearray | memoryview], int]


def byte_sum_for(frame_size: int) -> tuple[ByteSum, int]:
    """How to sum a frame's bytes for its checksum, and what that way adds to the sum.

    A checksum needs only the low byte of the sum. ``zlib.adler32`` keeps 1 + the sum,
    modulo 65521, in its low 16 bits and runs in C: exact while the sum cannot reach 65521,
    i.e. for frames up to 256 bytes (every frame that fits a 15 ms slot). Longer frames are
    summed by ``sum``. The parser and the simulator both take their sums from here."""
    if frame_size * 255 < 65521:
        return zlib.adler32, 1
    return sum, 0


#: Text the firmware prints when it restarts (at 115200 baud, whatever the OI's rate): any of
#: these in the bytes read means the robot reset and its OI is Off. The bootloader's first
#: line and the product line, as captured on a Create 2 / Roomba 600.
RESET_BANNER_MARKERS: tuple[bytes, ...] = (b"bl-start", b"bootloader id", b"Roomba by iRobot")


def shows_reset_banner(data: bytes, stream: StreamParser | None = None) -> bool:
    """Whether ``data`` holds a line of the firmware's start-up banner and, given a fresh
    ``stream`` parser of the stream that ran, no valid frame of it after the banner's last
    line: a robot that reset has its OI Off, which streams nothing, so a banner the stream
    went on after is text the parser skipped, not a reset (a stop unconfirmed after one
    said "the robot reset" and wrote Start again)."""
    at = max(data.rfind(marker) for marker in RESET_BANNER_MARKERS)
    return at >= 0 and not (stream is not None and stream.feed(data[at:]))


@dataclass(slots=True)
class ParserCounters:
    frames: int = 0
    checksum_failures: int = 0
    skipped_bytes: int = 0
    bytes_fed: int = 0
    #: candidates that passed the checksum with a value out of range (dropped)
    implausible: int = 0
    #: a header and the right n-bytes, but an id byte wrong: most likely a frame cut short
    #: (the next one's bytes where its ids should be)
    cut_frames: int = 0
    #: of the checksum failures, the frames whose sum the other checksum rule takes (the
    #: header 19 summed in or left out): every frame failing so is a robot of another model
    #: (:func:`~roomba_bt.oi.identify.checksum_mismatch`); counted on a failure only
    other_checksum: int = 0


class StreamParser:
    """Feed it chunks of bytes; it returns the checked frames they complete, in order.

    A candidate at a ``19`` becomes a frame only if four things agree: the n-bytes byte is the
    payload size of the requested list, every packet-id byte is the requested id at its
    place, and the low byte of the sum of the whole frame is right for the profile (0 when
    the checksum covers the header, 19 when it does not; ``roomba500`` takes either).
    Counters always balance: ``bytes_fed == skipped_bytes + frames x frame size + pending``.
    """

    __slots__ = (
        "_anchor", "_buffer", "_byte_sum", "_checks", "_encoders", "_mask", "_n", "_ok_sums",
        "_other_sums", "_size", "_suspect", "_template", "_unpack", "counters", "layout",
        "out_of_range",
    )  # fmt: skip

    def __init__(
        self,
        packet_ids: Iterable[int],
        profile: RobotProfile = DEFAULT_PROFILE,
        *,
        mode_plus_one: bool | None = None,
    ) -> None:
        """``mode_plus_one``: whether packet 35 reads the mode + 1 (1-4 in range instead of
        0-3), as the session learned at start-up; None: as the profile expects. The frames'
        :attr:`~roomba_bt.oi.frames.SensorFrame.oi_mode` reads the mode with it undone."""
        self.layout: FrameLayout = layout_for(packet_ids, profile, True, mode_plus_one)
        layout = self.layout
        plus_one = layout.mode_plus_one
        checks = list(layout.range_checks)
        if OI_MODE_PACKET in layout.index:
            checks.append((layout.index[OI_MODE_PACKET], int(plus_one), 3 + int(plus_one)))
        # a value unpacked unsigned is never below 0: a lowest of 0 needs no test there
        unsigned = frozenset(
            slot for slot, pid in enumerate(layout.members) if not profile.packet(pid).signed
        )
        self._checks = _compile_checks(tuple(checks), unsigned)
        self._encoders = layout.encoder_slots
        # (left, right, byte offset in the stream, time) of the last accepted frame, and of
        # the last frame refused for its encoder step alone
        self._anchor: _EncoderMark | None = None
        self._suspect: _EncoderMark | None = None
        self.counters = ParserCounters()
        #: the last candidate that passed the checksum with a value out of the profile's
        #: range (its bytes, header to checksum), kept on that failure only: which packet
        #: and value it was is worked out when a stream is declared lost
        #: (:func:`~roomba_bt.oi.identify.range_mismatch`), never on the tick path
        self.out_of_range: bytes | None = None
        self._buffer = bytearray()
        self._n = self.layout.payload_size
        self._size = self._n + 3
        sums = profile.checksum_sums
        other = {0, STREAM_HEADER} - sums  # the other rule's sum (none on the roomba500)
        # Header, n-bytes and every id byte checked at once: the candidate read as one
        # big-endian integer, masked to those positions, must equal the layout's template.
        self._mask = self.layout.frame_mask
        self._template = self.layout.frame_template
        self._unpack = self.layout.struct.unpack_from
        # the accepted low bytes, shifted by what the byte-sum function adds
        self._byte_sum, shift = byte_sum_for(self._size)
        self._ok_sums: frozenset[int] = frozenset((total + shift) & 0xFF for total in sums)
        self._other_sums: frozenset[int] = frozenset((total + shift) & 0xFF for total in other)

    @property
    def pending(self) -> int:
        """Bytes held back, waiting for the rest of a frame."""
        return len(self._buffer)

    def reset(self) -> None:
        self._buffer.clear()

    def plausible(self, values: tuple[int, ...], at: int, now: float | None = None) -> bool:
        """True if every value of a frame starting at byte ``at`` of the stream, read at
        ``now`` (seconds, any clock; None: unknown) is in range (the layout's reserved bits
        are already checked with the frame's fixed bytes). The frames since the last
        accepted one are counted in bytes, or in 15 ms slots of ``now`` where more (frames
        lost whole, with no bytes)."""
        checks = self._checks
        if checks is not None and not checks(values):
            return False
        encoders = self._encoders
        if encoders is None:
            return True
        left, right = values[encoders[0]], values[encoders[1]]
        anchor = self._anchor
        if (
            anchor is not None  # within one slot's step is within any limit: no _limit then
            and (
                (left - anchor[0] + MAX_COUNTS_PER_SLOT) & 0xFFFF > _ONE_SLOT_SPAN
                or (right - anchor[1] + MAX_COUNTS_PER_SLOT) & 0xFFFF > _ONE_SLOT_SPAN
            )
            and not _steps_within(anchor, left, right, self._limit(anchor, at, now))
        ):
            suspect = self._suspect
            self._suspect = (left, right, at, now, self._failed())
            if suspect is None or not _steps_within(
                suspect, left, right, self._limit(suspect, at, now)
            ):
                return False
        self._suspect = None
        counters = self.counters  # what _failed() says, without the call (once a frame)
        refused = counters.checksum_failures + counters.implausible + counters.cut_frames
        self._anchor = (left, right, at, now, refused)
        return True

    def _failed(self) -> int:
        """Candidates refused so far (cut short, checksum failures, out of range)."""
        counters = self.counters
        return counters.checksum_failures + counters.implausible + counters.cut_frames

    def _limit(self, since: _EncoderMark, at: int, now: float | None) -> int:
        """Most counts the wheels can turn between the frame ``since`` and one at ``at``.
        Bytes between them that are not whole frames count as one more frame, and so does
        each candidate refused (checksum, range) since: a frame cut short or corrupted on the
        line took its 15 ms on the robot, so the next one may be two steps on."""
        slots = -(-(at - since[2]) // self._size)
        # each candidate refused since was most likely a frame: one slot each
        slots = max(slots, 1 + self._failed() - since[4])
        then = since[3]
        if now is not None and then is not None:
            slots = max(slots, round((now - then) / SLOT_SECONDS))
        return MAX_COUNTS_PER_SLOT * max(1, slots)

    def feed(
        self, data: bytes | bytearray | memoryview, now: float | None = None
    ) -> list[SensorFrame]:
        """The frames ``data`` completes; ``now``: when it arrived (seconds, for the
        encoder step check across frames lost whole), None if unknown."""
        frame = self.take(data, now)
        return [frame] if frame is not None else self.search(data, now)

    def search(
        self, data: bytes | bytearray | memoryview, now: float | None = None
    ) -> list[SensorFrame]:
        """:meth:`feed` for ``data`` that :meth:`take` did not take: added to what is held
        back, and the frames searched for."""
        self._buffer += data
        self.counters.bytes_fed += len(data)
        return self._scan(0, now)

    def take(
        self, data: bytes | bytearray | memoryview, now: float | None = None
    ) -> SensorFrame | None:
        """The frame ``data`` is, in the common case: one whole frame, nothing held back
        before it, its ids, reserved bits and checksum right, its values in range and its
        encoders within one slot's step of the last frame's. Counted like :meth:`feed`;
        otherwise None and nothing changed (:meth:`feed` it then: the search, the counters
        of what is refused, a frame cut short).

        What one read brings on the tick path: the four checks of :meth:`_scan` and the
        common case of :meth:`plausible` in one method, without copying into the buffer.

        The functions kept in the parser's slots (the byte sum, the unpacking) are read into
        a local and called from there: ``self._byte_sum(data)`` is a method-call lookup,
        which CPython 3.11 specialises only for methods of the class, not for a function in
        an attribute (so it took the generic lookup every frame); ``int.from_bytes`` too
        (a class method read off the type), bound once at import instead."""
        size = self._size
        byte_sum = self._byte_sum
        if (
            len(data) != size
            or self._buffer
            or _from_bytes(data, "big") & self._mask != self._template
            or byte_sum(data) & 0xFF not in self._ok_sums
        ):
            return None
        unpack = self._unpack
        values = unpack(data, 2)
        checks = self._checks
        if checks is not None and not checks(values):
            return None
        counters = self.counters
        encoders = self._encoders
        if encoders is not None:
            anchor = self._anchor
            if anchor is None:
                return None
            left, right = values[encoders[0]], values[encoders[1]]
            # fmt: off
            if (
                (left - anchor[0] + MAX_COUNTS_PER_SLOT) & 0xFFFF > _ONE_SLOT_SPAN
                or (right - anchor[1] + MAX_COUNTS_PER_SLOT) & 0xFFFF > _ONE_SLOT_SPAN
            ):
                return None
            # fmt: on
            refused = counters.checksum_failures + counters.implausible + counters.cut_frames
            self._anchor = (left, right, counters.bytes_fed, now, refused)
            self._suspect = None
        counters.bytes_fed += size
        counters.frames += 1
        # SensorFrame(layout, values), without the class call's __init__ (a Python call from
        # C): a third of the instructions of making the frame, once a frame
        frame = _new_object(SensorFrame)
        frame.layout = self.layout
        frame.values = values
        return frame

    def _scan(self, first: int, now: float | None) -> list[SensorFrame]:
        """The frames in the buffer from byte ``first`` on; the bytes they used or skipped
        leave the buffer. Over 60 lines on purpose: :meth:`plausible`'s common case inline, as
        a call per candidate cost 35 % more a frame of 4 KiB reads (median, 30 rounds A/B)."""
        buf = self._buffer
        size = self._size
        counters = self.counters
        base = counters.bytes_fed - len(buf)  # the stream's byte offset of buf[0]
        plausible, checks, encoders = self.plausible, self._checks, self._encoders
        frames: list[SensorFrame] = []
        layout = self.layout
        ok_sums = self._ok_sums
        mask, template, unpack, byte_sum = self._mask, self._template, self._unpack, self._byte_sum
        id_mask = self.layout.frame_id_mask
        from_bytes = int.from_bytes
        n = self._n
        pos = skipped = first
        end = len(buf)
        while True:
            start = buf.find(STREAM_HEADER, pos)
            if start < 0:
                skipped += end - pos
                pos = end
                break
            skipped += start - pos
            pos = start
            if end - pos < size:
                if end - pos >= 2 and buf[pos + 1] != n:
                    skipped += 1
                    pos += 1
                    continue
                break
            window = buf[pos : pos + size]
            bits = from_bytes(window, "big")
            if bits & mask != template:
                if bits & id_mask == template:  # a frame, but a reserved bit is set
                    # its checksum judged first, as for any frame: one failing ours and
                    # passing the other rule is another model's (a 500's wall signal over
                    # 1023 sets bits the 600's range leaves clear)
                    total = byte_sum(window) & 0xFF
                    if total in ok_sums:
                        counters.implausible += 1
                        self.out_of_range = bytes(window)
                    else:
                        counters.checksum_failures += 1
                        if total in self._other_sums:
                            counters.other_checksum += 1
                elif window[1] == n:
                    counters.cut_frames += 1
                skipped += 1
                pos += 1
            elif byte_sum(window) & 0xFF in ok_sums:
                values = unpack(window, 2)
                # plausible(), its common case inline: in range, one slot's encoder step
                if checks is not None and not checks(values):
                    ok = False
                    self.out_of_range = bytes(window)
                elif encoders is None:
                    ok = True
                else:
                    left, right, anchor = values[encoders[0]], values[encoders[1]], self._anchor
                    if (
                        anchor is not None
                        and (left - anchor[0] + MAX_COUNTS_PER_SLOT) & 0xFFFF <= _ONE_SLOT_SPAN
                        and (right - anchor[1] + MAX_COUNTS_PER_SLOT) & 0xFFFF <= _ONE_SLOT_SPAN
                    ):
                        refused = (
                            counters.checksum_failures + counters.implausible + counters.cut_frames
                        )  # what _failed() says, without the call
                        self._anchor = (left, right, base + pos, now, refused)
                        self._suspect = None
                        ok = True
                    else:
                        ok = plausible(values, base + pos, now)
                if ok:
                    frames.append(SensorFrame(layout, values))
                    pos += size
                else:
                    counters.implausible += 1
                    skipped += 1
                    pos += 1
            else:
                counters.checksum_failures += 1
                if byte_sum(window) & 0xFF in self._other_sums:  # a failure only: summed again
                    counters.other_checksum += 1
                skipped += 1
                pos += 1
        if pos:
            del buf[:pos]
        counters.frames += len(frames)
        counters.skipped_bytes += skipped
        return frames


#: ``(step + MAX_COUNTS_PER_SLOT) mod 2**16`` at most this: a step within one slot's limit
_ONE_SLOT_SPAN = 2 * MAX_COUNTS_PER_SLOT

ValueCheck = Callable[[tuple[int, ...]], bool]


@lru_cache(maxsize=256)
def _compile_checks(
    checks: tuple[tuple[int, int, int], ...], unsigned: frozenset[int] = frozenset()
) -> ValueCheck | None:
    """One function testing every ``(slot, lowest, highest)`` of a layout: a chained
    comparison per packet, built once per layout (a loop over the tuple costs twice as much
    on the tick path); only the highest where the lowest is 0 and the slot is in ``unsigned``
    (its values are never negative: half the operations, every frame). None when there is
    nothing to test.

    Cached, so that the parser a safe stop makes to listen after it (robot/ending.py) finds
    its function made: the stop of a script's connection runs at exit (atexit), and an
    ``eval`` of a text there makes CPython (3.11, 3.12) forget that the program ended on
    Ctrl-C: it exited 1, not by SIGINT (130 in a shell)."""
    if not checks:
        return None
    body = " and ".join(
        f"v[{slot}] <= {hi}" if lo == 0 and slot in unsigned else f"{lo} <= v[{slot}] <= {hi}"
        for slot, lo, hi in checks
    )
    function: ValueCheck = eval(f"lambda v: {body}", {"__builtins__": {}})
    return function


#: left and right counts, byte offset in the stream, arrival time, candidates refused so far
_EncoderMark = tuple[int, int, int, float | None, int]


def stream_period(packet_ids: Iterable[int], rate: int) -> float:
    """Seconds from one stream frame of ``packet_ids`` to the next at ``rate`` baud: the
    15 ms slot, or the frame's own transfer time where that is longer (10 bits a byte:
    group 100, 84 bytes, takes 44 ms at 19200)."""
    return max(SLOT_SECONDS, stream_frame_size(packet_ids) * 10 / rate)


def _steps_within(anchor: _EncoderMark, left: int, right: int, limit: int) -> bool:
    """Both encoders moved at most ``limit`` counts from ``anchor`` (modulo 2**16)."""
    return (
        abs(((left - anchor[0] + 0x8000) & 0xFFFF) - 0x8000) <= limit
        and abs(((right - anchor[1] + 0x8000) & 0xFFFF) - 0x8000) <= limit
    )


class ReplyParser:
    """Replies to Sensors (142) and Query List (149): no header, no checksum, so they are
    cut by the expected length of the packets asked for."""

    __slots__ = ("_buffer", "layout")

    def __init__(
        self,
        packet_ids: Iterable[int],
        profile: RobotProfile = DEFAULT_PROFILE,
        *,
        mode_plus_one: bool | None = None,
    ) -> None:
        """``mode_plus_one`` as :class:`StreamParser` takes it."""
        self.layout = layout_for(packet_ids, profile, False, mode_plus_one)
        self._buffer = bytearray()

    @property
    def expected_size(self) -> int:
        return self.layout.payload_size

    def feed(self, data: bytes | bytearray) -> SensorFrame | None:
        """Add bytes; return the decoded reply once complete (extra bytes stay buffered)."""
        self._buffer += data
        size = self.layout.payload_size
        if len(self._buffer) < size:
            return None
        frame = self.layout.decode(self._buffer, 0)
        del self._buffer[:size]
        return frame

    @property
    def leftover(self) -> bytes:
        return bytes(self._buffer)


def decode_reply(
    packet_ids: Iterable[int],
    data: bytes,
    profile: RobotProfile = DEFAULT_PROFILE,
    *,
    mode_plus_one: bool | None = None,
) -> SensorFrame:
    """Decode a complete reply to 142/149; ``ValueError`` if it has the wrong length.
    ``mode_plus_one`` as :class:`StreamParser` takes it."""
    packet_ids = tuple(packet_ids)
    layout = layout_for(packet_ids, profile, False, mode_plus_one)
    if len(data) != layout.payload_size:
        raise ValueError(
            f"reply to {list(packet_ids)} must be {layout.payload_size} bytes, got {len(data)}"
        )
    return layout.decode(data)
