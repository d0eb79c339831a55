"""Stream fuzz: the parser fed long noisy streams in random chunks, counted against what was sent.

Run as a script for the figures in docs/reliability.md (10^6 bytes per case)::

    python tests/oi/fuzz.py                 # every case, 10^6 bytes each
    python tests/oi/fuzz.py --bytes 200000  # smaller

The cases, each for two packet lists (group 100, and the stream ``roomba-bt run`` asks for
bump-and-turn: what the mission reads plus the runtime's and the summary's packets):

* ``random``        random bytes: no frame was sent, any frame accepted is corrupted;
* ``garbage``       valid frames with honest garbage between them: random bytes, header bytes,
                    the firmware's banner lines, frames cut short (the next one follows);
* ``flips 1e-3``    valid frames back to back, each byte with one bit flipped at that rate
                    (a noisy line), and ``flips 1e-2``.

Fed in chunks of 1 B to 4 KiB, each with its arrival time (the slot of its last byte: 15 ms a
frame sent, cut short or not).
Counted: exceptions (must be 0); intact frames (sent and not touched) kept, in % (the bar is
99.99 %); corrupted frames accepted, *before* the checks (what a checksum-only scan of the
same bytes accepts: the parser before range checks) and *after* (what the parser returns
that was not sent as such). tests/oi/test_fuzz.py pins a smaller seeded case's "after".

Only :mod:`roomba_bt` is imported: it runs as a script, and the test imports it.
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from roomba_bt.oi.frames import STREAM_HEADER, FrameLayout, layout_for
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.oi.stream import StreamParser

#: ``roomba-bt run bump-and-turn``'s stream: bumps and wheel drops, the cliffs, battery charge
#: and capacity, charging sources, the OI mode and the encoders.
MISSION_PACKETS: tuple[int, ...] = (7, 9, 10, 11, 12, 25, 26, 34, 35, 43, 44)
PACKET_LISTS: dict[str, tuple[int, ...]] = {"group 100": (100,), "bump-and-turn": MISSION_PACKETS}
BANNER_LINES = (
    b"bl-start\r\n",
    b"STR730\r\n",
    b"bootloader id: #x47186549 82ECCFFF\r\n",
    b"Roomba by iRobot!\r\n",
    b"battery-current-zero 252\r\n",
)
CASES = ("random", "garbage", "flips 1e-3", "flips 1e-2")


@dataclass
class Result:
    case: str
    packets: str
    bytes_fed: int = 0
    sent_frames: int = 0
    intact_frames: int = 0
    kept: int = 0
    corrupted_before: int = 0
    corrupted_after: int = 0
    exceptions: int = 0
    seconds: float = 0.0

    @property
    def kept_percent(self) -> float:
        return 100.0 * self.kept / self.intact_frames if self.intact_frames else 100.0

    def row(self) -> str:
        return (
            f"| {self.case} | {self.packets} | {self.bytes_fed} | {self.intact_frames} | "
            f"{self.kept_percent:.4f} % | {self.corrupted_before} | {self.corrupted_after} | "
            f"{self.exceptions} |"
        )


class Frames:
    """Valid frames of one layout as a robot streams them: encoders advancing a few counts a
    frame, the mode steady, every other value random within its range."""

    def __init__(self, layout: FrameLayout, rng: random.Random) -> None:
        self.layout = layout
        self.rng = rng
        self.left = self.right = 0

    def next(self) -> bytes:
        rng, layout = self.rng, self.layout
        self.left = (self.left + rng.randint(0, 20)) & 0xFFFF
        self.right = (self.right + rng.randint(0, 20)) & 0xFFFF
        values: dict[int, int] = {}
        for pid in layout.members:
            spec = layout.profile.packet(pid)
            if pid == 43:
                values[pid] = self.left - 0x10000 if self.left > 0x7FFF else self.left
            elif pid == 44:
                values[pid] = self.right - 0x10000 if self.right > 0x7FFF else self.right
            elif pid == 35:
                values[pid] = 2
            else:
                values[pid] = rng.randint(spec.minimum, spec.maximum)
        return layout.stream_frame(values)


def flip_bits(data: bytes, rate: float, rng: random.Random) -> bytes:
    buf = bytearray(data)
    for i in range(len(buf)):
        if rng.random() < rate:
            buf[i] ^= 1 << rng.randrange(8)
    return bytes(buf)


def make_stream(
    case: str, layout: FrameLayout, size: int, rng: random.Random
) -> tuple[bytes, list[int], list[bytes], set[bytes]]:
    """The bytes; where each 15 ms slot's bytes end (the robot's clock: a frame cut short
    still took its slot); every frame sent (as generated); the frames that went out
    untouched."""
    out = bytearray()
    slot_ends: list[int] = []
    sent: list[bytes] = []
    intact: set[bytes] = set()
    if case == "random":
        data = rng.randbytes(size)
        step = layout.payload_size + 3
        return data, list(range(step, len(data) + step, step)), sent, intact
    frames = Frames(layout, rng)
    rate = {"flips 1e-3": 1e-3, "flips 1e-2": 1e-2}.get(case)
    while len(out) < size:
        if sent:
            slot_ends.append(len(out))
        frame = frames.next()
        sent.append(frame)
        if rate is not None:
            wire = flip_bits(frame, rate, rng)
            if wire == frame:
                intact.add(frame)
            out += wire
            continue
        roll = rng.random()
        if roll < 0.1:  # cut short: the next frame follows at once
            out += frame[: rng.randrange(1, len(frame))]
            continue
        out += frame
        intact.add(frame)
        if roll < 0.3:
            out += rng.randbytes(rng.randint(1, 40))
        elif roll < 0.35:
            out += bytes([STREAM_HEADER]) * rng.randint(1, 3)
        elif roll < 0.4:
            out += rng.choice(BANNER_LINES)
    slot_ends.append(len(out))
    return bytes(out), slot_ends, sent, intact


def checksum_only_scan(data: bytes, layout: FrameLayout, profile: RobotProfile) -> list[bytes]:
    """Windows a parser that checks only the header, n-bytes, ids and checksum accepts, left
    to right (a valid window taken whole, anything else skips a byte): no range checks."""
    size = layout.payload_size + 3
    mask, template = layout.frame_id_mask, layout.frame_template
    ok = {0} if profile.checksum_includes_header else {STREAM_HEADER}
    if profile.checksum_accepts_both:
        ok = {0, STREAM_HEADER}
    found: list[bytes] = []
    i = data.find(STREAM_HEADER)
    while 0 <= i <= len(data) - size:
        window = data[i : i + size]
        if int.from_bytes(window, "big") & mask == template & mask and sum(window) & 0xFF in ok:
            found.append(window)
            i = data.find(STREAM_HEADER, i + size)
        else:
            i = data.find(STREAM_HEADER, i + 1)
    return found


def chunks(data: bytes, slot_ends: list[int], rng: random.Random) -> Iterator[tuple[bytes, float]]:
    """``data`` cut at random sizes of 1 B to 4 KiB; each chunk with the time its last byte
    was sent (15 ms a slot)."""
    at = 0
    slot = 0
    while at < len(data):
        end = min(len(data), at + rng.randint(1, 4096))
        while slot_ends[slot] < end:
            slot += 1
        yield data[at:end], slot * 0.015
        at = end


def run_case(case: str, name: str, size: int, seed: int, profile: RobotProfile = CREATE2) -> Result:
    packets = PACKET_LISTS[name]
    layout = layout_for(packets, profile, True)
    rng = random.Random(f"{case}:{name}:{seed}")
    data, slot_ends, sent, intact = make_stream(case, layout, size, rng)
    result = Result(case, name, len(data), len(sent), len(intact))
    parser = StreamParser(packets, profile)
    accepted: list[bytes] = []
    started = time.perf_counter()
    for chunk, arrival in chunks(data, slot_ends, rng):
        try:
            frames = parser.feed(chunk, arrival)
        except Exception:  # the count is the result: the bar is 0
            result.exceptions += 1
            continue
        accepted += [layout.stream_frame(dict(frame)) for frame in frames]
    result.seconds = time.perf_counter() - started
    result.kept = sum(1 for frame in accepted if frame in intact)
    result.corrupted_after = sum(1 for frame in accepted if frame not in intact)
    result.corrupted_before = sum(
        1 for frame in checksum_only_scan(data, layout, profile) if frame not in intact
    )
    return result


HEADER = (
    "| case | packets | bytes | intact frames | intact kept | corrupted accepted, checksum "
    "only | corrupted accepted, with the checks | exceptions |\n|---|---|---|---|---|---|---|---|"
)


def main(argv: list[str] | None = None, out: Callable[[str], None] = print) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--bytes", type=int, default=1_000_000, help="bytes per case")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    out(HEADER)
    worst = 0
    for case in CASES:
        for name in PACKET_LISTS:
            result = run_case(case, name, args.bytes, args.seed)
            out(result.row())
            if result.exceptions or result.kept_percent < 99.99:
                worst = 1
    return worst


if __name__ == "__main__":
    sys.exit(main())
