"""A stream of valid frames with garbage between and inside them yields exactly the intact
frames, in order, with consistent counters, whatever the chunking. The oracle (see
:mod:`.streams`) knows which frames are intact and which garbage windows happen to be valid.

Two drivers: a seeded ``random.Random`` loop of 10^5 cases (fast, reproducible: a failure
prints its case number) and hypothesis (shrinks a failure to a small stream)."""

from __future__ import annotations

import random

from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt.oi.frames import FrameLayout
from roomba_bt.oi.stream import StreamParser

from .streams import (
    Case,
    CaseBuilder,
    garbage_kinds,
    layouts,
    make_frame,
    random_case,
    random_chunks,
)

CASES = 100_000
SEED = 20260522


def _parse(case: Case, chunks: list[bytes]) -> tuple[list[dict[int, int]], StreamParser]:
    parser = StreamParser(case.layout.packet_ids, case.layout.profile)
    out: list[dict[int, int]] = []
    for chunk in chunks:
        out += [dict(frame) for frame in parser.feed(chunk)]
    return out, parser


def _values_at(case: Case, starts: list[int]) -> list[dict[int, int]]:
    layout = case.layout
    return [dict(layout.decode(case.data, s + 2)) for s in starts]


def _check(case: Case, chunks: list[bytes], label: str) -> bool:
    """Assert the parser's output against the oracle; True if the case had accidental frames."""
    got, parser = _parse(case, chunks)
    accidental = case.accidental()
    expected = case.intact_values if not accidental else _values_at(case, case.expected_starts())
    assert got == expected, f"{label}: {case.data.hex()} (accidental at {accidental})"
    k = parser.counters
    size = case.layout.frame_size
    assert k.frames == len(expected), label
    assert k.bytes_fed == len(case.data), label
    assert k.skipped_bytes + k.frames * size + parser.pending == k.bytes_fed, label
    if not accidental:
        assert k.skipped_bytes + parser.pending == len(case.garbage_positions), label
    return bool(accidental)


def test_100k_seeded_random_streams() -> None:
    rng = random.Random(SEED)
    all_layouts = layouts()
    accidental_cases = 0
    intact_frames = 0
    for n in range(CASES):
        layout = all_layouts[n % len(all_layouts)]
        case = random_case(rng, layout, segments=rng.randrange(1, 7))
        intact_frames += len(case.intact_starts)
        accidental_cases += _check(case, random_chunks(rng, case.data), f"case {n}")
    # The oracle must not have degenerated into "whatever the reference scan says".
    assert accidental_cases < CASES // 100, accidental_cases
    assert intact_frames > CASES  # about two intact frames per case


def test_one_byte_at_a_time_and_whole() -> None:
    rng = random.Random(SEED + 1)
    for n, layout in enumerate(layouts() * 40):
        case = random_case(rng, layout, segments=8)
        data = case.data
        _check(case, [data[i : i + 1] for i in range(len(data))], f"bytewise {n}")
        _check(case, [data], f"whole {n}")


@st.composite
def cases(draw: st.DrawFn) -> Case:
    layout: FrameLayout = draw(st.sampled_from(layouts()))
    rng = random.Random(draw(st.integers(0, 2**32)))
    builder = CaseBuilder(layout)
    for is_frame in draw(st.lists(st.booleans(), max_size=10)):
        frame, values = make_frame(rng, layout)
        if is_frame:
            builder.frame(frame, values)
        elif draw(st.booleans()):
            builder.garbage(garbage_kinds(rng, frame))
        else:
            builder.garbage(draw(st.binary(min_size=1, max_size=12)))
    return builder.build()


@settings(max_examples=300, deadline=None)
@given(case=cases(), cuts=st.lists(st.integers(min_value=1, max_value=50), max_size=20))
def test_hypothesis_streams(case: Case, cuts: list[int]) -> None:
    chunks: list[bytes] = []
    i = 0
    for cut in cuts:
        chunks.append(case.data[i : i + cut])
        i += cut
    chunks.append(case.data[i:])
    _check(case, chunks, "hypothesis")
