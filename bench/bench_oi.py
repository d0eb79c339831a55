"""Protocol layer against two peers, measured side by side in this process.

(a) Decoding a group-100 reply (80 bytes, every packet 7-58): ours against pycreate2's
    ``SensorPacketDecoder``, then the same bytes decoded both ways to show where pycreate2's
    bump and overcurrent bits are wrong.
(b) Framing a sensor stream: our :class:`StreamParser` against PyRoombaAdapter's
    ``data_stream_read`` (driven through an in-memory fake serial port), on a clean stream and
    with 1% of the bytes corrupted; throughput and the share of intact frames each one keeps.

Ratios only mean something within one run: both sides run here, on the same bytes.
"""

from __future__ import annotations

import functools
import random
import time
from collections.abc import Callable
from typing import Any

from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser

#: The stream the framing benchmark sends: a mission's typical packets (bumps, wheel drops,
#: cliffs, IR, odometry, battery, mode, requested motion), 60 bytes a frame.
STREAM_IDS: tuple[int, ...] = (
    7, 8, 9, 10, 11, 12, 13, 17, 19, 20, 21, 22, 25, 26, 34, 35, 39, 40, 43, 44, 45, 52, 53, 58,
)  # fmt: skip
FRAMES = 20_000
CORRUPTION = 0.01
SEED = 1


def _per_call(fn: Callable[[], object], calls: int, repeat: int = 5) -> float:
    """Best-of-``repeat`` seconds per call."""
    best = float("inf")
    for _ in range(repeat):
        started = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - started) / calls)
    return best


def _group_100_reply(bumps: int, overcurrents: int) -> bytes:
    values = {
        7: bumps, 14: overcurrents, 22: 15_210, 23: -1_120, 24: 27, 25: 2_400, 26: 2_696,
        35: 2, 39: 200, 40: -32768, 43: 1_234, 44: 65_000 - 65_536, 45: 0b100001, 58: 1,
    }  # fmt: skip
    return layout_for((100,), CREATE2, False).pack(values)


def bench_decode() -> None:
    print("(a) group-100 reply decode, 80 bytes")
    data = _group_100_reply(bumps=0b01, overcurrents=0b10000)
    layout = layout_for((100,), CREATE2, False)

    def ours() -> object:
        return layout.decode(data)

    def ours_with_bits() -> object:
        f = layout.decode(data)
        return (f.bumps, f.overcurrents, f.buttons, f.charging_sources, f.light_bumper, f.stasis)

    try:
        from pycreate2.packets import SensorPacketDecoder
    except ImportError as exc:
        print(f"   pycreate2: not installed ({exc}); install the 'bench' extra")
        return

    def theirs() -> object:
        return SensorPacketDecoder(data)

    ours_s = ours_bits_s = theirs_s = float("inf")
    for _ in range(5):  # alternate, so that a busy machine slows all three alike
        ours_s = min(ours_s, _per_call(ours, 10_000, 1))
        ours_bits_s = min(ours_bits_s, _per_call(ours_with_bits, 10_000, 1))
        theirs_s = min(theirs_s, _per_call(theirs, 2_000, 1))
    print(f"   ours, raw values:              {ours_s * 1e6:7.2f} us")
    print(f"   ours, + every bit field read:  {ours_bits_s * 1e6:7.2f} us")
    print(f"   pycreate2 SensorPacketDecoder: {theirs_s * 1e6:7.2f} us")
    print(
        f"   ratio: {theirs_s / ours_s:.1f}x faster (raw), "
        f"{theirs_s / ours_bits_s:.1f}x faster (with every bit field)  [target >= 3x]"
    )
    _show_pycreate2_bits(SensorPacketDecoder)


def _show_pycreate2_bits(decoder: Callable[[bytes], Any]) -> None:
    print("   same bytes, both decoders (spec: packet 7 bit 0 = bump RIGHT; packet 14 bits")
    print("   0 side brush, 2 main brush, 3 right wheel, 4 left wheel):")
    layout = layout_for((100,), CREATE2, False)
    cases = [
        ("packet 7 = 0b00001 (right bumper)", 0b00001, 0),
        ("packet 14 = 0b10000 (left wheel)", 0, 0b10000),
        ("packet 14 = 0b01000 (right wheel)", 0, 0b01000),
        ("packet 14 = 0b00100 (main brush)", 0, 0b00100),
    ]
    for label, bumps, oc in cases:
        data = _group_100_reply(bumps, oc)
        f = layout.decode(data)
        p = decoder(data)
        if bumps:
            ours = f"bump_right={f.bumps.bump_right} bump_left={f.bumps.bump_left}"
            theirs = (
                f"bump_right={p.bumps_wheeldrops.bump_right} "
                f"bump_left={p.bumps_wheeldrops.bump_left}"
            )
        else:
            o = f.overcurrents
            ours = _flags(
                side=o.side_brush, main=o.main_brush, right=o.right_wheel, left=o.left_wheel
            )
            q = p.overcurrents
            theirs = _flags(
                side=q.side_brush_overcurrent,
                main=q.main_brush_overcurrent,
                right=q.right_wheel_overcurrent,
                left=q.left_wheel_overcurrent,
            )
        verdict = "agree" if ours == theirs else "pycreate2 WRONG"
        print(f"     {label:36s} ours: {ours:32s} pycreate2: {theirs:32s} {verdict}")


def _flags(**flags: bool) -> str:
    on = [name for name, value in flags.items() if value]
    return "overcurrent " + ("+".join(on) if on else "none")


# ------------------------------------------------------------------------------ framing


class FakeSerial:
    """Just enough of ``serial.Serial`` for PyRoombaAdapter: reads come from memory."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0
        self.written = bytearray()

    def read(self, size: int = 1) -> bytes:
        chunk = self.data[self.pos : self.pos + size]
        self.pos += len(chunk)
        return chunk

    def write(self, data: bytes) -> int:
        self.written += data
        return len(data)

    def close(self) -> None:
        pass

    @property
    def remaining(self) -> int:
        return len(self.data) - self.pos


def _stream(corruption: float) -> tuple[bytes, set[int]]:
    """``FRAMES`` frames; packet 43 carries the frame's index. Returns the bytes and the
    indexes of the frames left intact."""
    rng = random.Random(SEED)
    layout = layout_for(STREAM_IDS, CREATE2, True)
    out = bytearray()
    intact: set[int] = set()
    for index in range(FRAMES):
        frame = bytearray(layout.stream_frame({43: index, 22: 15_000, 35: 2, 7: index % 4}))
        touched = False
        for i in range(len(frame)):
            if rng.random() < corruption:
                frame[i] = (frame[i] + rng.randrange(1, 256)) & 0xFF
                touched = True
        if not touched:
            intact.add(index)
        out += frame
    return bytes(out), intact


def _ours(data: bytes, chunk: int) -> list[int]:
    parser = StreamParser(STREAM_IDS, CREATE2)
    kept: list[int] = []
    for i in range(0, len(data), chunk):
        kept += [f[43] for f in parser.feed(data[i : i + chunk])]
    return kept


def _theirs(data: bytes) -> tuple[list[int], int]:
    from pyroombaadapter import PyRoombaAdapter

    by_id = {pid: name for name, (pid, _size, _signed) in PyRoombaAdapter.SENSOR.items()}
    adapter = PyRoombaAdapter.__new__(PyRoombaAdapter)  # skip __init__: it opens a port
    fake = FakeSerial(b"")
    adapter.serial_con = fake
    adapter.data_stream_start([by_id[pid] for pid in STREAM_IDS])
    fake.data, fake.pos = data, 0
    position_of_43 = STREAM_IDS.index(43)
    kept: list[int] = []
    crashes = 0
    while fake.remaining:
        try:
            values = adapter.data_stream_read()
        except (KeyError, IndexError):
            crashes += 1  # a checksum-valid frame with an id it did not ask for
            continue
        if len(values) == len(STREAM_IDS):
            kept.append(values[position_of_43])
    adapter.serial_con = None  # its __del__ would write to the port and sleep 0.1 s
    return kept, crashes


def _timed_pair(
    ours: Callable[[], Any], theirs: Callable[[], Any], repeat: int = 3
) -> tuple[Any, float, Any, float]:
    """Best-of-``repeat`` seconds of each side, alternating them so that a busy machine
    slows both alike."""
    ours_best = theirs_best = float("inf")
    ours_result: Any = None
    theirs_result: Any = None
    for _ in range(repeat):
        started = time.perf_counter()
        ours_result = ours()
        ours_best = min(ours_best, time.perf_counter() - started)
        started = time.perf_counter()
        theirs_result = theirs()
        theirs_best = min(theirs_best, time.perf_counter() - started)
    return ours_result, ours_best, theirs_result, theirs_best


def bench_framing() -> None:
    frame_size = layout_for(STREAM_IDS, CREATE2, True).frame_size
    print(f"(b) stream framing, {FRAMES} frames of {frame_size} bytes ({len(STREAM_IDS)} packets)")
    try:
        import pyroombaadapter  # noqa: F401
    except ImportError as exc:
        print(f"   PyRoombaAdapter: not installed ({exc}); install the 'bench' extra")
        return
    for corruption in (0.0, CORRUPTION):
        data, intact = _stream(corruption)
        ours_kept, ours_s, (theirs_kept, crashes), theirs_s = _timed_pair(
            functools.partial(_ours, data, 4096), functools.partial(_theirs, data)
        )
        assert _ours(data, frame_size) == ours_kept  # the chunking does not change the result
        print(
            f"   {corruption:4.0%} corruption: {len(intact)} intact frames, "
            f"{FRAMES - len(intact)} corrupted"
        )
        for name, kept, seconds in (
            ("ours (4 KiB reads)", ours_kept, ours_s),
            ("PyRoombaAdapter   ", theirs_kept, theirs_s),
        ):
            good = len(intact.intersection(kept))
            bad = len([k for k in kept if k not in intact])
            print(
                f"     {name} {len(data) / seconds / 1e6:6.2f} MB/s "
                f"({FRAMES / seconds:9.0f} frames/s)  kept {good / len(intact):7.2%} of intact"
                + (f", {bad} corrupted frames accepted" if bad else "")
            )
        if corruption:
            print(
                "     (1% of the bytes changed at random. A frame with two changes that cancel in"
                " the 8-bit sum passes any checksum test: both parsers accept those alike.)"
            )
        if crashes:
            print(f"     PyRoombaAdapter raised on {crashes} frames (ids it had not asked for)")
        print(f"     ratio: {theirs_s / ours_s:.1f}x faster  [target >= 5x]")


def main() -> None:
    bench_decode()
    bench_framing()


if __name__ == "__main__":
    main()
