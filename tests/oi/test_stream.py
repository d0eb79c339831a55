"""The stream parser against the specs' frames, firmware text, truncation and every chunking;
the reply parser; the bandwidth check."""

from __future__ import annotations

import zlib

import pytest

from roomba_bt.oi import commands as c
from roomba_bt.oi.errors import BandwidthError, EncodeError
from roomba_bt.oi.frames import layout_for, stream_frame_size
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600, RobotProfile
from roomba_bt.oi.stream import (
    ReplyParser,
    StreamParser,
    byte_sum_for,
    check_bandwidth,
    stream_budget,
)

SPEC_600 = bytes([19, 5, 29, 2, 25, 13, 0, 163])  # checksum covers the header
SPEC_500 = bytes([19, 5, 29, 2, 25, 13, 0, 182])  # checksum leaves the header out
BANNER = (
    b"bl-start\r\nSTR730\r\nbootloader id: #x47186549 82ECCFFF\r\n"
    b"bootloader info rev: #xF000\r\nbootloader rev: #x0001\r\n2007-05-14-1715-L   \r\n"
    b"Roomba by iRobot!\r\nstr730\r\n2012-03-22-1549-L   \r\nbattery-current-zero 252\r\n"
    b"r3_robot/tags/release-3.3.0:4384 CLEAN\r\n"
)


def _counters_balance(parser: StreamParser) -> None:
    k = parser.counters
    assert k.skipped_bytes + k.frames * parser.layout.frame_size + parser.pending == k.bytes_fed


def test_600_spec_frame_decodes_packet_29_to_537() -> None:
    parser = StreamParser([29, 13], CREATE2)
    (frame,) = parser.feed(SPEC_600)
    assert frame[29] == 537  # 0x0219; the prose's "549" is a typo
    assert frame[13] == 0
    assert parser.counters.frames == 1 and parser.counters.checksum_failures == 0
    _counters_balance(parser)


def test_500_spec_frame_decodes_on_the_500_profile() -> None:
    parser = StreamParser([29, 13], ROOMBA500)
    (frame,) = parser.feed(SPEC_500)
    assert (frame[29], frame[13]) == (537, 0)


def test_the_500_profile_accepts_both_checksums() -> None:
    parser = StreamParser([29, 13], ROOMBA500)
    assert len(parser.feed(SPEC_600 + SPEC_500 + SPEC_600)) == 3


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600], ids=lambda p: p.name)
def test_600_profiles_refuse_the_500_checksum(profile: RobotProfile) -> None:
    parser = StreamParser([29, 13], profile)
    assert parser.feed(SPEC_500) == []
    assert parser.counters.checksum_failures == 1
    _counters_balance(parser)


def test_the_stream_command_and_its_frame_agree() -> None:
    assert c.stream([29, 13]).data == bytes([148, 2, 29, 13])
    layout = layout_for((29, 13), CREATE2)
    assert layout.frame_size == stream_frame_size([29, 13]) == len(SPEC_600)
    assert layout.stream_frame({29: 537, 13: 0}) == SPEC_600
    assert layout.stream_frame({29: 537, 13: 0}, include_header=False) == SPEC_500


def test_firmware_text_is_skipped() -> None:
    layout = layout_for((7, 35), CREATE2)
    f1 = layout.stream_frame({7: 1, 35: 1})
    f2 = layout.stream_frame({7: 2, 35: 2})
    parser = StreamParser([7, 35])
    frames = parser.feed(f1 + BANNER + f2 + b"\r\nCharging\r\n" + f1)
    assert [f[7] for f in frames] == [1, 2, 1]
    assert parser.counters.skipped_bytes == len(BANNER) + len(b"\r\nCharging\r\n")
    _counters_balance(parser)


def test_a_truncated_frame_does_not_hide_the_next() -> None:
    layout = layout_for((100,), CREATE2)
    whole = layout.stream_frame({22: 15000, 35: 2})
    parser = StreamParser([100])
    frames = parser.feed(whole[:40] + whole + whole[:3] + whole)
    assert [f.voltage_mv for f in frames] == [15000, 15000]
    # the cut frame completed by the next one's bytes: a checksum failure, or out of range
    assert parser.counters.checksum_failures + parser.counters.implausible >= 1
    _counters_balance(parser)


def test_a_header_byte_inside_data_is_not_a_frame() -> None:
    layout = layout_for((22,), CREATE2)
    frames = [layout.stream_frame({22: v}) for v in (0x1313, 0x0513, 0x1305)]
    parser = StreamParser([22])
    assert [f[22] for f in parser.feed(b"\x13\x13\x13" + b"".join(frames))] == [
        0x1313,
        0x0513,
        0x1305,
    ]


def test_every_chunk_size_gives_the_same_frames() -> None:
    layout = layout_for((7, 43, 44, 35), CREATE2)
    frames = [layout.stream_frame({7: i % 16, 43: i * 7, 44: -i, 35: 2}) for i in range(12)]
    data = (
        BANNER[:30]
        + frames[0]
        + b"\x13\x06"
        + b"".join(frames[1:6])
        + b"xx\x13"
        + b"".join(frames[6:])
    )
    expected = [f[7] for f in StreamParser([7, 43, 44, 35]).feed(data)]
    assert len(expected) == 12
    for size in range(1, len(data) + 1):
        parser = StreamParser([7, 43, 44, 35])
        got = []
        for i in range(0, len(data), size):
            got += [f[7] for f in parser.feed(data[i : i + size])]
        assert got == expected, f"chunk size {size}"
        _counters_balance(parser)


def test_a_frame_cut_at_the_end_waits() -> None:
    parser = StreamParser([29, 13])
    assert parser.feed(SPEC_600[:5]) == []
    assert parser.pending == 5
    assert len(parser.feed(SPEC_600[5:])) == 1
    assert parser.pending == 0
    parser.feed(SPEC_600[:3])
    parser.reset()
    assert parser.pending == 0


def test_group_ids_in_a_stream() -> None:
    layout = layout_for((6, 101), CREATE2)
    assert layout.frame_size == 3 + 1 + 52 + 1 + 28
    frame = layout.stream_frame({7: 3, 58: 1, 43: 100})
    (decoded,) = StreamParser([6, 101]).feed(frame)
    assert (decoded[7], decoded[58], decoded[43]) == (3, 1, 100)


def test_a_frame_with_the_wrong_ids_is_not_accepted() -> None:
    # Same n-bytes, valid checksum, but ids 29/13 swapped for 28/13: not the requested list.
    other = layout_for((28, 13), CREATE2).stream_frame({28: 537})
    parser = StreamParser([29, 13])
    assert parser.feed(other) == []
    assert parser.counters.checksum_failures == 0


def test_the_reply_parser_cuts_by_length() -> None:
    parser = ReplyParser([7, 13])
    assert parser.expected_size == 2
    assert parser.feed(b"\x01") is None
    frame = parser.feed(b"\x01\xaa")
    assert frame is not None and (frame[7], frame[13]) == (1, 1)
    assert parser.leftover == b"\xaa"


def test_a_query_list_reply_for_the_spec_example() -> None:
    assert c.query_list([7, 13]).data == bytes([149, 2, 7, 13])
    frame = ReplyParser([7, 13]).feed(b"\x02\x00")
    assert frame is not None and frame.bumps.bump_left and not frame.virtual_wall


# -- bandwidth -------------------------------------------------------------------------------


@pytest.mark.parametrize(("baud", "budget"), [(115200, 172), (57600, 86), (19200, 28)])
def test_stream_budget(baud: int, budget: int) -> None:
    assert stream_budget(baud) == budget


ELEVEN_ONE_BYTE_PACKETS = [7, 8, 9, 10, 11, 12, 13, 14, 15, 17, 18]


def test_bandwidth_boundary_at_19200() -> None:
    fits = [29, *ELEVEN_ONE_BYTE_PACKETS]
    assert check_bandwidth(fits, 19200) == 28
    with pytest.raises(BandwidthError, match="29 bytes does not fit in 15 ms at 19200 baud"):
        check_bandwidth([*fits[:-1], 22], 19200)  # one 1-byte packet swapped for a 2-byte one


def test_group_100_fits_at_57600_and_115200_only() -> None:
    assert check_bandwidth([100], 115200) == 84
    assert check_bandwidth([100], 57600) == 84
    with pytest.raises(BandwidthError) as caught:
        check_bandwidth([100], 19200)
    assert (caught.value.frame_bytes, caught.value.budget, caught.value.baud) == (84, 28, 19200)


def test_two_group_100s_do_not_fit_at_115200() -> None:
    with pytest.raises(BandwidthError):
        check_bandwidth([100, 100, 6], 115200)


def test_bandwidth_check_names_unknown_ids() -> None:
    with pytest.raises(EncodeError, match="stream: packet_id must be one of"):
        check_bandwidth([7, 104], 115200)


LONGEST = (100, 100, 100, 19, 22, 25, 7)  # 254 payload bytes: a 257-byte frame


def test_the_longest_frames_use_the_exact_byte_sum() -> None:
    layout = layout_for(LONGEST, CREATE2)
    assert layout.payload_size == 254
    frame = layout.stream_frame({22: 0xFFFF, 25: 0xFFFF, 19: -1, 43: -1, 44: -1})
    broken = bytearray(frame)
    broken[100] ^= 0x01
    parser = StreamParser(LONGEST)
    assert len(parser.feed(frame + bytes(broken) + frame)) == 2
    assert parser.counters.checksum_failures >= 1


def test_a_stream_too_long_for_its_n_byte_is_refused() -> None:
    with pytest.raises(EncodeError, match="at most 255 bytes of ids and data per frame, got 257"):
        StreamParser((*LONGEST, 22))


def test_the_encoder_refuses_the_stream_the_parser_could_not_frame() -> None:
    """The same limit in ``commands.stream``: a library user's ``link.write(c.stream(...))``
    asked for a stream the robot cannot frame (it was encoded)."""
    assert c.stream(LONGEST).data[:2] == bytes((148, len(LONGEST)))
    with pytest.raises(EncodeError, match="at most 255 bytes of ids and data per frame, got 257"):
        c.stream((*LONGEST, 22))


def test_adler32_holds_one_plus_the_byte_sum_up_to_256_bytes() -> None:
    """The parser and the simulator take a frame's byte sum from ``zlib.adler32``."""
    for data in (bytes(256), b"\xff" * 256, bytes(range(256)), b"\x13\x05" * 100):
        assert zlib.adler32(bytearray(data)) & 0xFFFF == 1 + sum(data)


@pytest.mark.parametrize("size", [1, 80, 256, 257, 300])
def test_byte_sum_for_gives_the_low_byte_of_the_sum(size: int) -> None:
    """What the parser and the simulator sum frames with: exact in the low byte at every
    size, adler32 up to 256 bytes, ``sum`` beyond."""
    summer, added = byte_sum_for(size)
    assert (summer is zlib.adler32) == (size <= 256)
    for data in (b"\xff" * size, bytes(i * 7 & 0xFF for i in range(size))):
        assert (summer(data) - added) & 0xFF == sum(data) & 0xFF


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA500, ROOMBA600])
@pytest.mark.parametrize("ids", [(100,), LONGEST], ids=["adler32", "sum"])
def test_frames_checked_on_both_sum_paths(profile: RobotProfile, ids: tuple[int, ...]) -> None:
    """A right frame passes and a wrong checksum does not, whether the byte sum comes from
    adler32 (frames up to 256 bytes) or from ``sum`` (the 257-byte longest frame)."""
    layout = layout_for(ids, profile)
    frame = layout.stream_frame({pid: 0 for pid in layout.members} | {35: 2})
    parser = StreamParser(ids, profile)
    assert len(parser.feed(frame)) == 1
    assert parser.feed(frame[:-1] + bytes([(frame[-1] + 1) & 0xFF])) == []


def test_one_whole_frame_per_feed_and_a_frame_sized_non_frame() -> None:
    """One frame per read is the common case (it has a shortcut); a chunk of exactly a
    frame's size that is not a frame must still go through the search."""
    layout = layout_for((7, 35), CREATE2)
    good = layout.stream_frame({7: 3, 35: 2})
    parser = StreamParser([7, 35])
    assert [f[7] for f in parser.feed(good)] == [3]
    bad_sum = good[:-1] + bytes([(good[-1] + 1) & 0xFF])
    assert parser.feed(bad_sum) == []
    assert parser.counters.checksum_failures == 1
    shifted = good[3:] + good[:3]  # the tail of one frame, the head of the next
    assert parser.feed(shifted) == []
    assert [f[7] for f in parser.feed(good[3:])] == [3]
    assert parser.counters.frames == 2
    _counters_balance(parser)


def _state(parser: StreamParser) -> tuple[object, ...]:
    """Everything a parser keeps between reads that :meth:`StreamParser.take` may change."""
    return (repr(parser.counters), parser.pending, parser._anchor, parser._suspect)


def test_take_takes_one_whole_frame_and_counts_it_as_feed_does() -> None:
    layout = layout_for((7, 43, 44, 35), CREATE2)
    frames = [layout.stream_frame({7: 1, 43: 10 * i, 44: 7 * i, 35: 2}) for i in range(3)]
    fed, taken = StreamParser([7, 43, 44, 35]), StreamParser([7, 43, 44, 35])
    assert fed.feed(frames[0], 0.0) == taken.feed(frames[0], 0.0)  # the encoders' anchor
    for i, frame in enumerate(frames[1:], 1):
        got = taken.take(frame, 0.015 * i)
        assert got is not None and got == fed.feed(frame, 0.015 * i)[0]
        assert _state(taken) == _state(fed)
    _counters_balance(taken)


def test_take_leaves_anything_else_to_feed_and_changes_nothing() -> None:
    layout = layout_for((7, 43, 44, 35), CREATE2)
    first = layout.stream_frame({43: 100, 44: 100, 35: 2})
    far = layout.stream_frame({43: 900, 44: 100, 35: 2})  # an encoder step past one slot's
    bad_sum = first[:-1] + bytes(((first[-1] + 1) & 0xFF,))
    out_of_range = layout.stream_frame({43: 100, 44: 100, 35: 7})
    fresh = StreamParser([7, 43, 44, 35])
    before = _state(fresh)
    assert fresh.take(first) is None  # no anchor yet: the first frame is fed
    assert _state(fresh) == before
    parser = StreamParser([7, 43, 44, 35])
    assert len(parser.feed(first, 0.0)) == 1
    for data in (first[:-1], first + first[:1], bad_sum, out_of_range, far):
        before = _state(parser)
        assert parser.take(data, 0.015) is None, data
        assert _state(parser) == before
    parser.feed(first[:5])
    before = _state(parser)
    assert parser.take(first, 0.03) is None  # bytes held back: the frame cannot start here
    assert _state(parser) == before
