"""Every sensor packet id and group id, decoded from bytes. ``EXPECTED_PACKETS`` and
``EXPECTED_GROUPS`` are compared against the tables, so a packet or group added without a case
here fails the coverage tests."""

from __future__ import annotations

import pytest

from roomba_bt.oi.bits import ChargingState, Stasis
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.frames import SensorFrame, layout_for
from roomba_bt.oi.ir import IRSource
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.packets import GROUP_SIZES, GROUPS, PACKETS, data_size, expand
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600
from roomba_bt.oi.stream import StreamParser, decode_reply

#: packet id -> (reply bytes, the value they decode to on create2). Multi-byte values are high
#: byte first; signed packets use two's complement.
EXPECTED_PACKETS: dict[int, tuple[bytes, int]] = {
    7: (b"\x05", 5),  # bump right + wheel drop right
    8: (b"\x01", 1),
    9: (b"\x01", 1),
    10: (b"\x00", 0),
    11: (b"\x01", 1),
    12: (b"\x00", 0),
    13: (b"\x01", 1),
    14: (b"\x1d", 29),
    15: (b"\xff", 255),
    16: (b"\x00", 0),
    17: (b"\xa8", 168),
    18: (b"\x81", 129),
    19: (b"\xff\x38", -200),
    20: (b"\x00\x5a", 90),
    21: (b"\x02", 2),
    22: (b"\x3a\x98", 15000),
    23: (b"\xfe\x0c", -500),
    24: (b"\xfb", -5),
    25: (b"\x0a\x8c", 2700),
    26: (b"\x0b\xb8", 3000),
    27: (b"\x0f\xff", 4095),  # above the 600 text's 1023: decoded, not clamped
    28: (b"\x02\x25", 549),
    29: (b"\x02\x19", 537),
    30: (b"\x0f\xff", 4095),
    31: (b"\x00\x00", 0),
    32: (b"\x00", 0),
    33: (b"\x00\x00", 0),
    34: (b"\x02", 2),
    35: (b"\x03", 3),
    36: (b"\x0f", 15),  # the robot may report up to 15 although Song takes 0-4
    37: (b"\x01", 1),
    38: (b"\x6c", 108),
    39: (b"\xfe\x0c", -500),
    40: (b"\x80\x00", -32768),  # "straight" as the robot echoes it
    41: (b"\x01\xf4", 500),
    42: (b"\xff\x9c", -100),
    43: (b"\xff\xfa", -6),
    44: (b"\x7f\xff", 32767),
    45: (b"\x3f", 63),
    46: (b"\x0f\xff", 4095),
    47: (b"\x00\x01", 1),
    48: (b"\x01\x00", 256),
    49: (b"\x00\x10", 16),
    50: (b"\x08\x00", 2048),
    51: (b"\x00\x64", 100),
    52: (b"\xa4", 164),
    53: (b"\xf8", 248),
    54: (b"\xff\xff", -1),
    55: (b"\x00\xc8", 200),
    56: (b"\x80\x00", -32768),
    57: (b"\x7f\xff", 32767),
    58: (b"\x02", 2),
}

#: group id -> (size in bytes, members): both specs' "Group Packet Sizes and Contents".
EXPECTED_GROUPS: dict[int, tuple[int, range]] = {
    0: (26, range(7, 27)),
    1: (10, range(7, 17)),
    2: (6, range(17, 21)),
    3: (10, range(21, 27)),
    4: (14, range(27, 35)),
    5: (12, range(35, 43)),
    6: (52, range(7, 43)),
    100: (80, range(7, 59)),
    101: (28, range(43, 59)),
    106: (12, range(46, 52)),
    107: (9, range(54, 59)),
}


def test_every_packet_has_a_case() -> None:
    assert set(EXPECTED_PACKETS) == set(PACKETS)


def test_every_group_has_a_case() -> None:
    assert set(EXPECTED_GROUPS) == set(GROUPS)


@pytest.mark.parametrize("packet_id", sorted(EXPECTED_PACKETS))
def test_packet_decodes(packet_id: int) -> None:
    data, value = EXPECTED_PACKETS[packet_id]
    assert len(data) == PACKETS[packet_id].size == data_size(packet_id)
    frame = decode_reply([packet_id], data)
    assert frame[packet_id] == value
    assert dict(frame) == {packet_id: value}


@pytest.mark.parametrize("packet_id", sorted(EXPECTED_PACKETS))
def test_packet_packs_back_to_the_same_bytes(packet_id: int) -> None:
    data, value = EXPECTED_PACKETS[packet_id]
    assert layout_for((packet_id,), CREATE2, False).pack({packet_id: value}) == data


@pytest.mark.parametrize("group_id", sorted(EXPECTED_GROUPS))
def test_group_size_and_members(group_id: int) -> None:
    size, members = EXPECTED_GROUPS[group_id]
    assert GROUP_SIZES[group_id] == size
    assert expand(group_id) == tuple(members)
    reply = bytes(range(size))
    frame = decode_reply([group_id], reply)
    assert frame.packet_ids == tuple(members)


@pytest.mark.parametrize("group_id", sorted(EXPECTED_GROUPS))
def test_group_reply_decodes_like_its_members_one_by_one(group_id: int) -> None:
    members = expand(group_id)
    reply = b"".join(EXPECTED_PACKETS[m][0] for m in members)
    frame = decode_reply([group_id], reply)
    assert dict(frame) == {m: EXPECTED_PACKETS[m][1] for m in members}


def test_groups_102_to_105_do_not_exist() -> None:
    for undefined in (102, 103, 104, 105, 59, 99, 108):
        with pytest.raises(EncodeError, match="packet_id must be one of 0-58, 100-101, 106-107"):
            decode_reply([undefined], b"")


def test_packet_16_occupies_a_byte_in_groups_0_1_6() -> None:
    for group in (0, 1, 6, 100):
        assert 16 in expand(group)
    frame = decode_reply([1], bytes([0, 0, 0, 0, 0, 0, 0, 0, 42, 0]))
    assert frame[15] == 42  # dirt detect is byte 9, the unused byte after it is byte 10


def test_packets_32_33_make_group_4_fourteen_bytes() -> None:
    assert (PACKETS[32].size, PACKETS[33].size) == (1, 2)
    assert GROUP_SIZES[4] == 14
    frame = decode_reply([4], bytes(13) + b"\x03")
    assert frame.charging_sources.raw == 3


def test_wrong_reply_length_is_refused() -> None:
    with pytest.raises(ValueError, match="reply to \\[100\\] must be 80 bytes, got 79"):
        decode_reply([100], bytes(79))


def test_unknown_packet_in_a_frame_names_it() -> None:
    frame = decode_reply([7], b"\x00")
    with pytest.raises(KeyError, match=r"packet 35 \(oi_mode\) is not in this frame"):
        frame[35]
    with pytest.raises(KeyError, match="no sensor packet is called 'speed'"):
        frame.value("speed")
    assert frame.get(35) is None
    assert frame.value("bumps_wheel_drops") == 0


def _full_frame() -> SensorFrame:
    reply = b"".join(EXPECTED_PACKETS[m][0] for m in expand(100))
    return decode_reply([100], reply)


def test_typed_views_of_a_group_100_reply() -> None:
    f = _full_frame()
    assert f.bumps.bump_right and not f.bumps.bump_left
    assert f.bumps.wheel_drop_right and not f.bumps.wheel_drop_left
    assert f.wall and f.cliff_left and not f.cliff_front_left and f.cliff_front_right
    assert f.any_cliff and f.virtual_wall
    oc = f.overcurrents  # 29 = 0b11101
    assert (oc.side_brush, oc.main_brush, oc.right_wheel, oc.left_wheel) == (True,) * 4
    assert f.dirt_detect == 255
    assert f.ir_omni.source is IRSource.DOCK and f.ir_omni.red_buoy and not f.ir_omni.green_buoy
    assert f.buttons.clean and f.buttons.clock and not f.buttons.spot
    assert (f.distance_mm, f.angle_deg) == (-200, 90)
    assert f.charging_state is ChargingState.FULL_CHARGING and f.charging_state.is_charging
    assert (f.voltage_mv, f.current_ma, f.temperature_c) == (15000, -500, -5)
    assert f.battery_percent == pytest.approx(90.0)
    assert f.wall_signal == 4095
    assert f.cliff_signals == (549, 537, 4095, 0)
    assert f.charging_sources.home_base and not f.charging_sources.internal_charger
    assert f.oi_mode is OIMode.FULL and f.oi_mode_raw == 3
    assert (f.song_number, f.song_playing, f.stream_packet_count) == (15, True, 108)
    assert (f.requested_velocity, f.requested_radius) == (-500, -32768)
    assert (f.requested_right_velocity, f.requested_left_velocity) == (500, -100)
    assert (f.left_encoder_counts, f.right_encoder_counts) == (-6, 32767)
    assert f.light_bumper.any and f.light_bumper.left and f.light_bumper.right
    assert f.light_bump_signals == (4095, 1, 256, 16, 2048, 100)
    assert f.ir_left.green_buoy and not f.ir_left.red_buoy
    assert f.ir_right.source is IRSource.DISCOVERY_DOCK and f.ir_right.red_buoy
    assert f.motor_currents_ma == (-1, 200, -32768, 32767)
    assert f.stasis is Stasis.DIRTY


def test_as_dict_gives_every_packet_by_name_with_typed_views() -> None:
    d = _full_frame().as_dict()
    assert set(d) == {PACKETS[p].name for p in range(7, 59)}
    assert d["oi_mode"] is OIMode.FULL
    assert d["stasis"] is Stasis.DIRTY
    assert d["voltage"] == 15000


def test_frames_are_immutable_values() -> None:
    a = decode_reply([7, 13], b"\x01\x00")
    b = decode_reply([7, 13], b"\x01\x00")
    assert a == b and hash(a) == hash(b)
    assert a != decode_reply([7, 13], b"\x02\x00")
    with pytest.raises(AttributeError):
        a.anything = 1  # type: ignore[attr-defined]
    assert "bumps_wheel_drops=1" in repr(a)


def test_a_frame_the_parser_takes_is_the_frame_its_values_make() -> None:
    parser = StreamParser((7, 35), CREATE2)
    layout = parser.layout
    taken = parser.take(layout.stream_frame({7: 3, 35: 2}))  # the one-frame path
    assert type(taken) is SensorFrame and taken == SensorFrame(layout, (3, 2))
    assert taken.layout is layout and taken.values == (3, 2) and taken.any_bump
    with pytest.raises(AttributeError):
        taken.other = 1  # type: ignore[attr-defined]


def test_a_packet_asked_twice_keeps_the_first_value() -> None:
    frame = decode_reply([7, 7], b"\x01\x02")
    assert frame[7] == 1


def test_out_of_range_enums_do_not_crash() -> None:
    f = decode_reply([21, 35, 58], b"\x09\x04\x03")
    assert f.charging_state is ChargingState.FAULT
    assert f.oi_mode is OIMode.FULL  # 4 only comes from the mode + 1 bug: Full
    assert f.oi_mode_raw == 4
    assert f.stasis is Stasis.RESERVED


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600, ROOMBA500], ids=lambda p: p.name)
def test_encoder_signedness_per_profile(profile: object) -> None:
    frame = decode_reply([43, 44], b"\xff\xfa\x80\x00", profile)  # type: ignore[arg-type]
    if profile is ROOMBA500:  # the 500 spec: unsigned, 0-65535
        assert (frame[43], frame[44]) == (65530, 32768)
    else:  # the 600 spec: signed
        assert (frame[43], frame[44]) == (-6, -32768)


def test_packets_43_is_left_and_44_is_right() -> None:
    assert PACKETS[43].name == "left_encoder_counts"
    assert PACKETS[44].name == "right_encoder_counts"
