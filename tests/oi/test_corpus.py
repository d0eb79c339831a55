"""The byte-stream corpus in ``tests/data/oi`` (see ``tests/data/make_oi_corpus.py``): each
stream, fed whole and one byte at a time, yields exactly the frames its manifest lists."""

from __future__ import annotations

import itertools
import json
import pathlib
from typing import Any

import pytest

from roomba_bt.oi.profiles import get_profile
from roomba_bt.oi.stream import ReplyParser, StreamParser

CORPUS = pathlib.Path(__file__).parents[1] / "data" / "oi"
MANIFEST: list[dict[str, Any]] = json.loads((CORPUS / "manifest.json").read_text())["streams"]


def _expected(entry: dict[str, Any]) -> list[dict[int, int]]:
    return [{int(k): v for k, v in frame.items()} for frame in entry["frames"]]


def test_the_corpus_is_there() -> None:
    files = {p.name for p in CORPUS.glob("*.bin")}
    assert files == {e["file"] for e in MANIFEST}
    assert len(files) >= 7


@pytest.mark.parametrize("entry", MANIFEST, ids=lambda e: e["file"])
def test_corpus_stream(entry: dict[str, Any]) -> None:
    data = (CORPUS / entry["file"]).read_bytes()
    profile = get_profile(entry["profile"])
    if entry["kind"] == "reply":
        frame = ReplyParser(entry["packets"], profile).feed(data)
        assert frame is not None and [dict(frame)] == _expected(entry)
        return
    whole = StreamParser(entry["packets"], profile)
    assert [dict(f) for f in whole.feed(data)] == _expected(entry)
    bytewise = StreamParser(entry["packets"], profile)
    got = []
    for i in range(len(data)):
        got += [dict(f) for f in bytewise.feed(data[i : i + 1])]
    assert got == _expected(entry)
    k = whole.counters
    assert k.skipped_bytes + k.frames * whole.layout.frame_size + whole.pending == len(data)


def test_banner_stream_encoders_roll_over() -> None:
    from roomba_bt.oi.odometry import encoder_delta

    entry = next(e for e in MANIFEST if e["file"] == "banner_then_group_100.bin")
    lefts = [f[43] for f in _expected(entry)]
    unsigned = [v & 0xFFFF for v in lefts]
    assert any(b < a for a, b in itertools.pairwise(unsigned))  # 65535 -> 0 happens
    assert all(encoder_delta(a, b) == 7 for a, b in itertools.pairwise(lefts))
    assert all(encoder_delta(a, b) == 7 for a, b in itertools.pairwise(unsigned))
