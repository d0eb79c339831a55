"""Byte streams for the parser's property tests: intact frames with honest garbage between
and inside them, and an oracle that says exactly which frames a correct parser returns.

Garbage is honest: it contains header bytes (19), truncated frames (a right header, n-bytes
and ids, then cut), frames with a byte changed, inserted or dropped, and firmware text. So a
window of garbage, or garbage running into the next frame, can by chance be a valid frame
(header, n-bytes, every id byte and the checksum all agree; a truncated frame needs only its
checksum to come out right, about 1 in 256). Such a window is indistinguishable from a frame
on the wire, for any parser. The oracle therefore does not assume it away:

* it lists every position inside garbage where a valid window starts (``accidental``);
* if there is none, the expected output is exactly the intact frames, in order;
* otherwise it is what a plain left-to-right scan accepts (``reference_scan``: at each
  position, a valid window is taken whole, anything else skips one byte), written here
  independently of :class:`~roomba_bt.oi.stream.StreamParser`.
"""

from __future__ import annotations

import functools
import math
import random
from dataclasses import dataclass

from roomba_bt.oi.frames import FrameLayout, layout_for
from roomba_bt.oi.odometry import MAX_COUNTS_PER_SLOT
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600, RobotProfile

FIRMWARE_TEXT = (
    b"bl-start\r\n",
    b"Roomba by iRobot!\r\n",
    b"r3_robot/tags/release-3.3.0:4384 CLEAN\r\n",
    b"battery-current-zero 252\r\n",
    b"Charging\r\n",
    b"do-charging-reset\r\n",
    b"\x13\r\n",
)

#: (packet ids, profile): small and large frames, groups, both checksum conventions.
LAYOUTS: tuple[tuple[tuple[int, ...], RobotProfile], ...] = (
    ((29, 13), CREATE2),
    ((17,), CREATE2),
    ((100,), CREATE2),
    ((7, 35, 43, 44), ROOMBA500),
    ((6, 101), ROOMBA600),
)


def ok_sums(profile: RobotProfile) -> frozenset[int]:
    """Low byte of the sum of a whole frame, header included, that makes it valid."""
    if profile.checksum_accepts_both:
        return frozenset({0, 19})
    return frozenset({0}) if profile.checksum_includes_header else frozenset({19})


#: Encoder counts of intact frames: any two differ by less than one 15 ms step of the wheels,
#: so the parser's step check keeps every intact frame whatever the order.
ENCODER_VALUES = (0, 13)
#: Packet 35 of intact frames: a mode with and without the "mode + 1" offset.
MODE_VALUES = (1, 3)


def random_values(rng: random.Random, layout: FrameLayout) -> dict[int, int]:
    out: dict[int, int] = {}
    for pid in layout.members:
        spec = layout.profile.packet(pid)
        if pid in (43, 44):
            out[pid] = rng.randint(*ENCODER_VALUES)
        elif pid == 35:
            out[pid] = rng.randint(*MODE_VALUES)
        else:
            out[pid] = rng.randint(spec.minimum, spec.maximum)
    return out


def in_range(data: bytes, i: int, layout: FrameLayout) -> bool:
    """Every value of the window at ``i`` within the packet table's range (packet 35: 0-3, or
    1-4 on a profile that reports the mode + 1)."""
    frame = layout.decode(data, i + 2)
    for pid, value in frame:
        spec = layout.profile.packet(pid)
        low, high = spec.minimum, spec.maximum
        if pid == 35 and layout.profile.reports_mode_plus_one:
            low, high = 1, 4
        if not low <= value <= high:
            return False
    return True


def _step(a: int, b: int) -> int:
    return abs(((b - a + 0x8000) & 0xFFFF) - 0x8000)


POOL_SIZE = 256


@functools.cache
def frame_pool(layout: FrameLayout) -> tuple[tuple[bytes, bytes, dict[int, int]], ...]:
    """Frames of ``layout`` with random in-range values (seeded): checksum over the header,
    checksum without it, and the values. Built once: framing tests need many frames, not
    many values (value round trips are tested in ``test_properties``)."""
    rng = random.Random(layout.payload_size)
    pool = []
    for _ in range(POOL_SIZE):
        values = random_values(rng, layout)
        pool.append((layout.stream_frame(values), layout.stream_frame(values, False), values))
    return tuple(pool)


def make_frame(rng: random.Random, layout: FrameLayout) -> tuple[bytes, dict[int, int]]:
    with_header, without_header, values = frame_pool(layout)[rng.randrange(POOL_SIZE)]
    include_header = layout.profile.checksum_includes_header
    if layout.profile.checksum_accepts_both:
        include_header = rng.random() < 0.5
    return (with_header if include_header else without_header), values


def is_valid_at(data: bytes, i: int, layout: FrameLayout, sums: frozenset[int]) -> bool:
    size = layout.frame_size
    if i + size > len(data) or data[i] != 19 or data[i + 1] != layout.payload_size:
        return False
    ids_ok = all(
        data[i + 2 + off] == pid
        for off, pid in zip(layout.id_offsets, layout.packet_ids, strict=True)
    )
    return ids_ok and sum(data[i : i + size]) & 0xFF in sums and in_range(data, i, layout)


def refused_at(data: bytes, i: int, layout: FrameLayout, sums: frozenset[int]) -> bool:
    """A candidate the parser counts as refused: a header and the right n-bytes, then an id
    wrong (cut short), a reserved bit set, the sum wrong or a value out of range (the encoder
    step aside: the scan counts that one)."""
    size = layout.frame_size
    if i + size > len(data) or data[i] != 19:
        return False
    if data[i + 1] != layout.payload_size:
        return False  # no candidate at all
    # a frame cut short (an id wrong), a reserved bit set, the sum wrong, or out of range
    return not is_valid_at(data, i, layout, sums)


def reference_scan(data: bytes, layout: FrameLayout, sums: frozenset[int]) -> list[int]:
    """Start positions a plain left-to-right scan accepts: valid windows whose encoder step
    from the last accepted one is at most MAX_COUNTS_PER_SLOT per frame size between them,
    or, after one refused for its step alone, from that one."""
    starts: list[int] = []
    size = layout.frame_size
    anchor: tuple[int, int, int, int] | None = None
    suspect: tuple[int, int, int, int] | None = None
    encoders = 43 in layout.members and 44 in layout.members
    failures = 0  # candidates refused so far, as the parser counts them

    def near(ref: tuple[int, int, int, int], left: int, right: int, at: int) -> bool:
        slots = max(math.ceil((at - ref[2]) / size), 1 + failures - ref[3])
        limit = MAX_COUNTS_PER_SLOT * max(1, slots)
        return _step(ref[0], left) <= limit and _step(ref[1], right) <= limit

    i = 0
    while i < len(data):
        if refused_at(data, i, layout, sums):
            failures += 1
        if is_valid_at(data, i, layout, sums):
            if encoders:
                frame = layout.decode(data, i + 2)
                left, right = frame[43], frame[44]
                if anchor is not None and not near(anchor, left, right, i):
                    refused = suspect
                    suspect = (left, right, i, failures)
                    if refused is None or not near(refused, left, right, i):
                        failures += 1
                        i += 1
                        continue
                anchor, suspect = (left, right, i, failures), None
            starts.append(i)
            i += size
        else:
            i += 1
    return starts


@dataclass
class Case:
    data: bytes
    layout: FrameLayout
    intact_starts: list[int]
    intact_values: list[dict[int, int]]
    garbage_positions: list[int]

    @property
    def sums(self) -> frozenset[int]:
        return ok_sums(self.layout.profile)

    def accidental(self) -> list[int]:
        d, lay, s = self.data, self.layout, self.sums
        return [i for i in self.garbage_positions if d[i] == 19 and is_valid_at(d, i, lay, s)]

    def expected_starts(self) -> list[int]:
        """Where the frames a correct parser returns start (see the module docstring)."""
        if not self.accidental():
            return self.intact_starts
        return reference_scan(self.data, self.layout, self.sums)


class CaseBuilder:
    """Appends segments to a stream, remembering which bytes are intact frames."""

    def __init__(self, layout: FrameLayout) -> None:
        self.layout = layout
        self.data = bytearray()
        self.intact_starts: list[int] = []
        self.intact_values: list[dict[int, int]] = []
        self.garbage_positions: list[int] = []

    def frame(self, frame: bytes, values: dict[int, int]) -> None:
        self.intact_starts.append(len(self.data))
        self.intact_values.append(values)
        self.data += frame

    def garbage(self, chunk: bytes) -> None:
        self.garbage_positions.extend(range(len(self.data), len(self.data) + len(chunk)))
        self.data += chunk

    def build(self) -> Case:
        return Case(
            bytes(self.data),
            self.layout,
            self.intact_starts,
            self.intact_values,
            self.garbage_positions,
        )


def garbage_kinds(rng: random.Random, frame: bytes) -> bytes:
    """One piece of garbage, made from ``frame`` (a valid frame of the stream's layout)."""
    kind = rng.randrange(6)
    if kind == 0:  # noise, rich in header bytes
        return bytes(
            19 if rng.random() < 0.2 else rng.randrange(256) for _ in range(rng.randrange(1, 16))
        )
    if kind == 1:  # firmware text
        return rng.choice(FIRMWARE_TEXT)
    if kind == 2:  # a truncated frame
        return frame[: rng.randrange(1, len(frame))]
    if kind == 3:  # a frame with one byte changed
        i = rng.randrange(len(frame))
        return frame[:i] + bytes([(frame[i] + rng.randrange(1, 256)) & 0xFF]) + frame[i + 1 :]
    if kind == 4:  # a frame with a byte inserted
        i = rng.randrange(1, len(frame))
        return frame[:i] + bytes([rng.randrange(256)]) + frame[i:]
    return frame[:-1] if len(frame) > 1 else b"\x13"  # a frame that lost its checksum


def random_case(rng: random.Random, layout: FrameLayout, segments: int) -> Case:
    builder = CaseBuilder(layout)
    for _ in range(segments):
        frame, values = make_frame(rng, layout)
        if rng.random() < 0.55:
            builder.frame(frame, values)
        else:
            builder.garbage(garbage_kinds(rng, frame))
    return builder.build()


def random_chunks(rng: random.Random, data: bytes) -> list[bytes]:
    chunks: list[bytes] = []
    i = 0
    while i < len(data):
        n = (
            rng.choice((1, 2, 3, 7, 16, 64, len(data)))
            if rng.random() < 0.5
            else rng.randrange(1, 40)
        )
        chunks.append(data[i : i + n])
        i += n
    return chunks


def layouts() -> list[FrameLayout]:
    return [layout_for(ids, profile, True) for ids, profile in LAYOUTS]


__all__ = [
    "LAYOUTS",
    "ROOMBA500",
    "Case",
    "CaseBuilder",
    "garbage_kinds",
    "layouts",
    "make_frame",
    "random_case",
    "random_chunks",
    "reference_scan",
]
