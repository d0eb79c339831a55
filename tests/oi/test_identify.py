"""Telling robots apart (oi/identify.py): the banner's release, the checksum convention and
the mode + 1 reading each narrow the profiles."""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.identify import (
    FirmwareVersion,
    checksum_covers_header,
    identify,
    parse_banner,
    parse_firmware,
    stream_readings,
)
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600, RobotProfile
from roomba_bt.oi.stream import StreamParser

#: A Roomba 620's banner as posted on robotics.stackexchange.com (question 12846).
ROOMBA620_BANNER = (
    b"bootloader id: #x47135160 6BFA3FFF\r\nbootloader info rev: #xF000\r\n"
    b"bootloader rev: #x0001\r\nRoomba by iRobot!\r\nbattery-current-zero 258\r\n"
    b"r3_robot/tags/release-3.2.6:4975 CLEAN\r\n"
)


def test_the_firmware_release_and_whether_it_wakes_by_brc_on_the_dock() -> None:
    assert parse_firmware("r3_robot/tags/release-stm32-3.7.7") == FirmwareVersion(
        "release-stm32", (3, 7, 7)
    )
    cases = {
        "release-3.2.6": False,
        "release-3.8.1": False,
        "release-3.8.2": True,
        "release-3.10.0": True,
        "release-stm32-3.7.6": False,
        "release-stm32-3.7.7": True,
    }
    for text, wakes in cases.items():
        version = parse_firmware(text)
        assert version is not None and version.text == text
        assert version.wakes_by_brc_on_dock is wakes, text
    assert parse_firmware("2012-03-22-1549-L") is None


def test_a_banner_is_text_with_its_release_and_garbage_is_none() -> None:
    banner = parse_banner(ROOMBA620_BANNER)
    assert banner is not None and banner.firmware is not None
    assert banner.firmware.text == "release-3.2.6"
    assert not banner.firmware.wakes_by_brc_on_dock
    assert parse_banner(b"") is None
    assert parse_banner(bytes(range(0, 40))) is None


def test_the_checksum_convention_of_a_frame() -> None:
    for profile, covers in ((CREATE2, True), (ROOMBA500, False)):
        layout = layout_for((7, 35), profile, True)
        frame = layout.stream_frame({7: 1, 35: 2}, profile.checksum_includes_header)
        assert checksum_covers_header(frame) is covers, profile.name
    assert checksum_covers_header(bytes([19, 2, 7, 1])) is None  # wrong length
    assert checksum_covers_header(C.start().data) is None


def test_the_evidence_narrows_the_profiles() -> None:
    assert identify(mode_plus_one=True, header_in_checksum=True).candidates == (ROOMBA600,)
    # a checksum over the header and the mode as is: a Create 2, a 600 on firmware without
    # the mode + 1 bug, or a 500 that sums the header (its profile takes both)
    either = identify(mode_plus_one=False, header_in_checksum=True)
    assert either.candidates == (CREATE2, ROOMBA600, ROOMBA500) and not either.decided
    assert identify(mode_plus_one=False, header_in_checksum=False).candidates == (ROOMBA500,)
    silent = identify(mode_plus_one=None, header_in_checksum=None, reset_tried=True)
    assert silent.candidates == (ROOMBA500,)
    banner = parse_banner(ROOMBA620_BANNER)
    printed = identify(mode_plus_one=None, header_in_checksum=None, banner=banner, reset_tried=True)
    assert set(printed.candidates) == {CREATE2, ROOMBA600}
    assert identify(mode_plus_one=True, header_in_checksum=False).best is None


def test_a_checksum_over_the_header_does_not_make_a_robot_a_create2() -> None:
    """Which checksum rule a real 500 follows is not certain (the roomba500 profile takes
    both): a checksum that covers the header ruled the 500 out, and a 500 that had ignored
    Reset then fitted no profile. What is not known is said, with what would tell it."""
    from roomba_bt.oi.identify import telling_apart

    either = identify(mode_plus_one=False, header_in_checksum=True)
    assert "or a Roomba 500" in either.evidence[0]
    assert either.cautious is ROOMBA500  # sends no Reset or Stop, which a 500 lacks
    assert telling_apart(either.candidates) == [
        "a wall signal (27) over 1023, which only the Roomba 500 series reads",
        "a stasis (58) over 1, which only the iRobot Create 2 or Roomba 600 series reads",
    ]
    ignored = identify(mode_plus_one=False, header_in_checksum=True, reset_tried=True)
    assert ignored.candidates == (ROOMBA500,) and ignored.decided
    assert telling_apart((CREATE2,)) == []


def test_a_mode_read_as_is_rules_no_model_out() -> None:
    """The mode + 1 is some 600 firmware's bug (``reports_mode_plus_one``: expected, not
    certain; the runtime learns the offset on any profile): a Passive read as 1 ruled the 600
    out, and doctor told a Roomba 650 owner whose ROOMBA_BT_PROFILE said roomba600 that the
    robot was none. A 2 still tells a 600."""
    as_is = identify(mode_plus_one=False, header_in_checksum=None)
    assert as_is.candidates == (CREATE2, ROOMBA600, ROOMBA500)
    assert as_is.evidence == (
        "it reports the OI mode as is (a Create 2 or a Roomba 500; a 600 on fixed firmware too)",
    )
    assert identify(mode_plus_one=True, header_in_checksum=None).candidates == (ROOMBA600,)


def test_the_profile_assumed_is_the_one_that_fits_else_the_default_else_the_cautious() -> None:
    """What ``doctor`` goes on with and ``--profile auto`` runs with: one fitting profile;
    of a Create 2 or a 500 that sums the header, the Create 2 (the default, the likelier,
    named with the other), and so of any several with the default among them; none fitting,
    the default."""
    assert identify(mode_plus_one=True, header_in_checksum=True).assumed is ROOMBA600
    assert identify(mode_plus_one=False, header_in_checksum=False).assumed is ROOMBA500
    assert identify(mode_plus_one=False, header_in_checksum=True).assumed is CREATE2
    assert identify(mode_plus_one=None, header_in_checksum=None).assumed is CREATE2
    assert identify(mode_plus_one=True, header_in_checksum=False).assumed is CREATE2  # none


def test_a_reading_only_one_models_range_allows_rules_the_others_out() -> None:
    wall = identify(mode_plus_one=None, header_in_checksum=None, readings={27: 2000})
    assert wall.candidates == (ROOMBA500,)  # the 600's wall signal stops at 1023
    assert wall.evidence == ("its wall signal (27) read 2000, in range for roomba500",)
    dirty = identify(mode_plus_one=None, header_in_checksum=None, readings={58: 2})
    assert set(dirty.candidates) == {CREATE2, ROOMBA600}  # stasis 2: the wheel too dirty
    common = identify(mode_plus_one=None, header_in_checksum=None, readings={27: 10, 58: 1})
    assert len(common.candidates) == 3 and common.evidence == ()


def test_stream_readings_cut_a_frame_by_the_packet_table() -> None:
    frame = layout_for((7, 27, 58), CREATE2, True).stream_frame({7: 3, 27: 900, 58: 2})
    assert stream_readings(frame) == {7: 3, 27: 900, 58: 2}
    assert stream_readings(frame[:-2] + frame[-1:]) == {}  # cut short: no reading


def test_the_parser_counts_frames_passing_the_other_checksum_rule() -> None:
    """A Roomba 500's frames (header left out of the checksum) fed to the Create 2's parser:
    none taken, each counted as passing the other rule; noise is not; the 500's parser, which
    takes either rule, has no other rule to count."""
    from roomba_bt.oi.stream import StreamParser

    layout = layout_for((7, 35), ROOMBA500, True)
    frames = b"".join(layout.stream_frame({7: 0, 35: 1}, False) for _ in range(5))
    parser = StreamParser((7, 35), CREATE2)
    assert parser.feed(frames) == []
    assert parser.counters.checksum_failures == parser.counters.other_checksum == 5
    noise = StreamParser((7, 35), CREATE2)
    noise.feed(bytes([19, 4, 7, 0, 35, 1, 77]) * 5)
    assert noise.counters.checksum_failures == 5 and noise.counters.other_checksum == 0
    both = StreamParser((7, 35), ROOMBA500)
    assert len(both.feed(frames)) == 5 and both.counters.other_checksum == 0
    assert CREATE2.checksum_sums == {0} and ROOMBA500.checksum_sums == {0, 19}


def test_a_500_beside_a_wall_read_as_a_create2_is_still_named_by_its_checksum() -> None:
    """Its wall signal (27) over 1023 sets bits the 600's range leaves clear: the frames
    were counted implausible before their checksum was judged, so the "most likely a Roomba
    500" hint never came and the user was told the line was garbled."""
    from roomba_bt.oi.identify import checksum_mismatch
    from roomba_bt.oi.stream import StreamParser

    layout = layout_for((100,), ROOMBA500, True)
    frames = b"".join(layout.stream_frame({27: 2263, 35: 1, 43: i, 44: i}, False) for i in range(6))
    parser = StreamParser((100,), CREATE2)
    assert parser.feed(frames) == []
    counters = parser.counters
    assert counters.checksum_failures == counters.other_checksum == 6
    mismatch = checksum_mismatch(
        CREATE2, frames=counters.frames, failures=counters.checksum_failures,
        other_checksum=counters.other_checksum,
    )  # fmt: skip
    assert mismatch is not None and mismatch.likely == (ROOMBA500,)
    # a 600's own frame with a reserved bit set (its checksum right) is still implausible
    wrong = layout_for((100,), CREATE2, True).stream_frame({27: 2263, 35: 1})
    refused = StreamParser((100,), CREATE2)
    assert refused.feed(wrong) == [] and refused.counters.implausible == 1
    assert refused.counters.checksum_failures == 0


def _refused_by(profile: RobotProfile, frames: bytes) -> StreamParser:
    parser = StreamParser((100,), profile)
    assert parser.feed(frames) == []
    return parser


def test_a_500_summing_the_header_beside_a_wall_is_named_by_its_range() -> None:
    """A Roomba 500 whose firmware sums the header (the rule a real 500 follows is not
    certain) read with the default profile: its frames pass the checksum and fail only the
    range of packet 27. The stream was lost as "noise on the line, or a wrong baud rate"."""
    from roomba_bt.oi.identify import RangeMismatch, range_mismatch

    layout = layout_for((100,), ROOMBA500, True)
    frames = b"".join(layout.stream_frame({27: 2263, 35: 1, 43: i, 44: i}) for i in range(6))
    parser = _refused_by(CREATE2, frames)
    counters = parser.counters
    assert counters.implausible == 6 and counters.checksum_failures == 0
    found = range_mismatch(
        CREATE2, parser.out_of_range, (100,), refused=counters.implausible,
        checksum_failures=counters.checksum_failures,
    )  # fmt: skip
    assert isinstance(found, RangeMismatch)
    assert (found.packet, found.value, found.likely) == (27, 2263, (ROOMBA500,))
    assert "wall signal (27) read 2263, over 1023 (iRobot Create 2)" in found.explained
    assert "within the Roomba 500 series range 0-4095" in found.explained
    assert found.fails == "the create2 profile's range"


def test_a_range_mismatch_needs_a_value_another_model_holds_and_no_noise() -> None:
    """Not named: too few refused, more checksum failures than refusals (noise), a value no
    profile holds (a charging state of 9), or a robot the profile's range holds."""
    from roomba_bt.oi.identify import range_mismatch

    wall = layout_for((100,), ROOMBA500, True).stream_frame({27: 2263, 35: 1})
    assert range_mismatch(CREATE2, wall, (100,), refused=1, checksum_failures=0) is None
    assert range_mismatch(CREATE2, wall, (100,), refused=5, checksum_failures=40) is None
    assert range_mismatch(ROOMBA500, wall, (100,), refused=5, checksum_failures=0) is None
    assert range_mismatch(CREATE2, None, (100,), refused=5, checksum_failures=0) is None
    nowhere = layout_for((100,), ROOMBA500, True).stream_frame({21: 9, 35: 1})
    assert range_mismatch(CREATE2, nowhere, (100,), refused=5, checksum_failures=0) is None
    # an unsigned 500 encoder reading past 32767 is in the 600's signed range: not a mismatch
    counts = layout_for((100,), ROOMBA500, True).stream_frame({35: 1, 43: 40000, 44: 40000})
    assert range_mismatch(CREATE2, counts, (100,), refused=5, checksum_failures=0) is None
