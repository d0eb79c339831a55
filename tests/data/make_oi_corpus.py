"""Writes the protocol corpus in ``tests/data/oi/``: byte streams as the robot sends them,
and ``manifest.json`` saying, for each, the packets asked for, the profile and the frames a
correct parser returns.

These streams are *constructed*, not captured from hardware (no robot is attached where this
project is built): the specs' own worked examples, and streams built from the packet table
with the firmware behaviour the specs and GUIDE.md describe (the reset banner, text on the
charger, encoders rolling over, the 600's "mode + 1", corrupted bytes). The expected frames
come from how each stream was built, never from running the parser. Re-run after changing a
stream: ``.venv/bin/python tests/data/make_oi_corpus.py``.
"""

from __future__ import annotations

import json
import pathlib
import random

from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import PROFILES

HERE = pathlib.Path(__file__).parent / "oi"

BANNER = (
    b"bl-start\r\nSTR730\r\nbootloader id: #x47186549 82ECCFFF\r\n"
    b"bootloader info rev: #xF000\r\nbootloader rev: #x0001\r\n2007-05-14-1715-L   \r\n"
    b"Roomba by iRobot!\r\nstr730\r\n2012-03-22-1549-L   \r\n"
    b"r3_robot/tags/release-3.3.0:4384 CLEAN\r\nbattery-current-zero 252\r\n"
)


def _entry(
    name: str,
    description: str,
    packets: list[int],
    profile: str,
    data: bytes,
    frames: list[dict[int, int]],
    kind: str = "stream",
) -> dict[str, object]:
    (HERE / f"{name}.bin").write_bytes(data)
    return {
        "file": f"{name}.bin",
        "kind": kind,
        "description": description,
        "packets": packets,
        "profile": profile,
        "frames": [{str(k): v for k, v in f.items()} for f in frames],
        "generated": True,
    }


def _frames(
    packets: list[int], profile: str, values: list[dict[int, int]], header: bool | None = None
) -> tuple[bytes, list[dict[int, int]]]:
    """Stream frames for ``values``; the expected decoded frames (every member, missing = 0)."""
    p = PROFILES[profile]
    layout = layout_for(tuple(packets), p, True)
    include = p.checksum_includes_header if header is None else header
    data = b"".join(layout.stream_frame(v, include_header=include) for v in values)
    expected = [dict(layout.decode(layout.pack(v))) for v in values]
    return data, expected


#: The specs' own worked examples, byte for byte: name, what it shows, packets asked for,
#: profile, the bytes, the frames they decode to, stream or reply. The two stream examples
#: differ only in the profile and the checksum byte: whether the header is summed.
SPEC_EXAMPLES: tuple[tuple[str, str, list[int], str, bytes, list[dict[int, int]], str], ...] = (
    ("spec_600_example", "The 600 / Create 2 spec's stream example: checksum over the header too.",
     [29, 13], "create2", bytes([19, 5, 29, 2, 25, 13, 0, 163]), [{29: 537, 13: 0}], "stream"),
    ("spec_500_example", "The 500 spec's stream example: checksum without the header.",
     [29, 13], "roomba500", bytes([19, 5, 29, 2, 25, 13, 0, 182]), [{29: 537, 13: 0}], "stream"),
    ("query_list_reply",
     "Reply to the specs' Query List example [149][2][7][13]: no header, no checksum.",
     [7, 13], "create2", bytes([0b01, 1]), [{7: 1, 13: 1}], "reply"),
)  # fmt: skip


def _banner_then_group_100() -> dict[str, object]:
    """Reset banner, then a group-100 stream of a robot driving forward: encoders rolling
    over."""
    values = []
    left, right = 65_500, 65_510
    for tick in range(12):
        left, right = (left + 7) % 65_536, (right + 7) % 65_536
        values.append(
            {22: 15_800 - tick, 23: -900, 25: 2_300, 26: 2_696, 35: 2, 39: 100, 40: -32768,
             43: left - 65_536 if left > 32_767 else left,
             44: right - 65_536 if right > 32_767 else right, 58: 1}
        )  # fmt: skip
    frames, expected = _frames([100], "create2", values)
    return _entry(
        "banner_then_group_100",
        "The reset banner (ASCII, as the 600 spec describes), then 12 group-100 frames of"
        " a robot driving forward whose encoders roll over 65535 -> 0.",
        [100],
        "create2",
        BANNER + frames,
        expected,
    )


def _docking_with_charger_text() -> dict[str, object]:
    """IR characters of the 600 dock, charging text, then charging on the home base."""
    dock = [(0, 0, 0), (168, 0, 0), (172, 0, 0), (164, 0, 0), (173, 0, 0), (161, 2, 0)]
    values = [{17: ir, 34: sources, 21: state, 35: 1, 7: 0} for ir, sources, state in dock]
    values.append({17: 161, 34: 2, 21: 2, 35: 1, 7: 0})
    first, expected_first = _frames([17, 34, 21, 35, 7], "roomba600", values[:6])
    last, expected_last = _frames([17, 34, 21, 35, 7], "roomba600", values[6:])
    return _entry(
        "docking_with_charger_text",
        "Approaching a 600 dock (red, red+green, green, all three, force field), docked,"
        " the firmware printing text as charging starts.",
        [17, 34, 21, 35, 7],
        "roomba600",
        first + b"\r\nCharging\r\ndo-charging-reset\r\n" + last,
        expected_first + expected_last,
    )


def _mode_plus_one() -> dict[str, object]:
    """Roomba 600 firmware reporting OI mode + 1 (4 = Full): decoded as sent."""
    frames, expected = _frames([35, 7], "roomba600", [{35: 2}, {35: 3}, {35: 4}])
    return _entry(
        "mode_plus_one",
        "Packet 35 from a 600 with the 'mode + 1' bug: 2, 3, 4. The parser reports raw"
        " values; correcting them is the robot layer's job.",
        [35, 7],
        "roomba600",
        frames,
        expected,
    )


def _corrupted_1_percent() -> dict[str, object]:
    """1% of bytes corrupted: only the untouched frames are expected."""
    rng = random.Random(7)
    layout = layout_for((7, 19, 20, 43, 44), PROFILES["create2"], True)
    data = bytearray()
    expected = []
    for i in range(300):
        v = {7: i % 4, 19: i, 20: -i, 43: i * 3, 44: -i * 3}
        frame = bytearray(layout.stream_frame(v))
        touched = False
        for j in range(len(frame)):
            if rng.random() < 0.01:
                frame[j] ^= rng.randrange(1, 256)
                touched = True
        if not touched:
            expected.append(dict(layout.decode(layout.pack(v))))
        data += frame
    return _entry(
        "corrupted_1_percent",
        "300 frames with 1% of their bytes changed at random (seed 7); the untouched"
        " frames, and only those, come out.",
        [7, 19, 20, 43, 44],
        "create2",
        bytes(data),
        expected,
    )


def main() -> None:
    HERE.mkdir(exist_ok=True)
    entries = [
        *(_entry(*example) for example in SPEC_EXAMPLES),
        _banner_then_group_100(),
        _docking_with_charger_text(),
        _mode_plus_one(),
        _corrupted_1_percent(),
    ]
    path = HERE / "manifest.json"
    by_hand = []  # entries added by hand (real captures) are kept as they are
    if path.exists():
        by_hand = [e for e in json.loads(path.read_text())["streams"] if not e.get("generated")]
    manifest = {"about": (__doc__ or "").strip().splitlines()[0], "streams": entries + by_hand}
    path.write_text(json.dumps(manifest, indent=1) + "\n")
    print(f"wrote {len(entries)} streams to {HERE}")


if __name__ == "__main__":
    main()
