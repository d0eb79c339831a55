"""The frame's hazard accessors (bumps, wheel drops, cliffs, their union, the light bumper
ahead, the IR receivers) against the bit layouts of packets 7, 9-12, 45, 17/52/53."""

from __future__ import annotations

import itertools

import pytest

from roomba_bt.oi.bits import LIGHT_BUMPER_AHEAD_BITS, BumpsWheelDrops, LightBumper
from roomba_bt.oi.frames import (
    BATTERY_PACKETS,
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CHARGING_STATE_PACKETS,
    CLIFF_PACKETS,
    ENCODER_PACKETS,
    HAZARD_PACKETS,
    IR_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    LIGHT_BUMPER_PACKETS,
    REQUESTED_DRIVE_PACKETS,
    REQUESTED_WHEELS_PACKETS,
    VIRTUAL_WALL_PACKETS,
    SensorFrame,
    layout_for,
)
from roomba_bt.oi.ir import IR_CHARACTERS
from roomba_bt.oi.packets import PACKETS

_ALL = (7, 9, 10, 11, 12, 13, 17, 45, 46, 47, 48, 49, 50, 51, 52, 53)


def _frame(values: dict[int, int], ids: tuple[int, ...] = _ALL) -> SensorFrame:
    layout = layout_for(ids, with_ids=False)
    return layout.decode(layout.pack(values))


@pytest.mark.parametrize("byte", range(16))
def test_packet_7_bumps_and_wheel_drops(byte: int) -> None:
    f = _frame({7: byte})
    bump_right, bump_left, drop_right, drop_left = (bool(byte >> n & 1) for n in range(4))
    assert f.any_bump is (bump_left or bump_right)
    assert f.any_wheel_drop is (drop_left or drop_right)
    assert f.any_hazard is (bump_left or bump_right or drop_left or drop_right)
    view = BumpsWheelDrops.from_byte(byte)
    assert (view.any_bump, view.any_wheel_drop) == (f.any_bump, f.any_wheel_drop)


def test_packet_7_unused_bits_are_no_hazard() -> None:
    f = _frame({7: 0b1111_0000})
    assert not (f.any_bump or f.any_wheel_drop or f.any_hazard)


@pytest.mark.parametrize("cliffs", list(itertools.product((0, 1), repeat=4)))
def test_cliffs_and_the_union(cliffs: tuple[int, int, int, int]) -> None:
    f = _frame(dict(zip(CLIFF_PACKETS, cliffs, strict=True)))
    assert (f.cliff_left, f.cliff_front_left, f.cliff_front_right, f.cliff_right) == tuple(
        bool(c) for c in cliffs
    )
    assert f.any_cliff is any(cliffs)
    assert f.any_hazard is any(cliffs)
    assert not f.any_bump and not f.any_wheel_drop


@pytest.mark.parametrize("byte", range(256))
def test_light_bumper_ahead_is_the_four_front_sensors(byte: int) -> None:
    f = _frame({45: byte})
    view = LightBumper.from_byte(byte)
    front = view.front_left or view.center_left or view.center_right or view.front_right
    assert f.light_bumper_ahead is front is view.ahead
    assert view.any is (front or view.left or view.right)
    assert bool(byte & LIGHT_BUMPER_AHEAD_BITS) is front


def test_light_bump_signals_each_by_name() -> None:
    signals = dict(zip(LIGHT_BUMP_SIGNAL_PACKETS, (4095, 1, 256, 16, 2048, 100), strict=True))
    f = _frame(signals)
    named = (
        f.light_bump_left_signal,
        f.light_bump_front_left_signal,
        f.light_bump_center_left_signal,
        f.light_bump_center_right_signal,
        f.light_bump_front_right_signal,
        f.light_bump_right_signal,
    )
    assert named == f.light_bump_signals == (4095, 1, 256, 16, 2048, 100)


@pytest.mark.parametrize("code", [0, 161, 164, 168, 172, 242, 248, 252, 130, 255])
def test_ir_receivers(code: int) -> None:
    f = _frame({17: code, 52: (code + 1) & 0xFF, 53: (code + 2) & 0xFF})
    assert f.ir_omni is IR_CHARACTERS[code]
    assert f.ir_left is IR_CHARACTERS[(code + 1) & 0xFF]
    assert f.ir_right is IR_CHARACTERS[(code + 2) & 0xFF]


@pytest.mark.parametrize(
    ("accessor", "packet"),
    [
        ("any_bump", 7),
        ("any_wheel_drop", 7),
        ("any_cliff", 9),
        ("any_hazard", 7),
        ("light_bumper_ahead", 45),
        ("light_bump_center_left_signal", 48),
        ("light_bump_signals", 46),
        ("ir_omni", 17),
        ("ir_left", 52),
        ("ir_right", 53),
    ],
)
def test_a_missing_packet_is_named(accessor: str, packet: int) -> None:
    f = _frame({35: 2}, ids=(35,))
    with pytest.raises(KeyError, match=f"packet {packet} \\({PACKETS[packet].name}\\)"):
        getattr(f, accessor)


def test_any_cliff_names_the_missing_cliff_packet() -> None:
    f = _frame({}, ids=(9, 10))
    with pytest.raises(KeyError, match="packet 11 \\(cliff_front_right\\)"):
        _ = f.any_cliff


def test_light_bump_signals_names_the_first_missing_signal() -> None:
    f = _frame({}, ids=(46, 47, 48))
    with pytest.raises(KeyError, match="packet 49 \\(light_bump_center_right_signal\\)"):
        _ = f.light_bump_signals


@pytest.mark.parametrize(
    ("ids", "names"),
    [
        (BUMPS_PACKETS, ("bumps_wheel_drops",)),
        (CLIFF_PACKETS, ("cliff_left", "cliff_front_left", "cliff_front_right", "cliff_right")),
        (HAZARD_PACKETS, ("bumps_wheel_drops", "cliff_left", "cliff_front_left",
                          "cliff_front_right", "cliff_right")),
        (VIRTUAL_WALL_PACKETS, ("virtual_wall",)),
        (LIGHT_BUMPER_PACKETS, ("light_bumper",)),
        (LIGHT_BUMP_SIGNAL_PACKETS, tuple(f"light_bump_{s}_signal" for s in (
            "left", "front_left", "center_left", "center_right", "front_right", "right"))),
        (IR_PACKETS, ("ir_omni", "ir_left", "ir_right")),
        (CHARGING_SOURCES_PACKETS, ("charging_sources",)),
        (CHARGING_STATE_PACKETS, ("charging_state",)),
        (ENCODER_PACKETS, ("left_encoder_counts", "right_encoder_counts")),
        (BATTERY_PACKETS, ("battery_charge", "battery_capacity")),
        (REQUESTED_DRIVE_PACKETS, ("requested_velocity", "requested_radius")),
        (REQUESTED_WHEELS_PACKETS, ("requested_right_velocity", "requested_left_velocity")),
    ],
)  # fmt: skip
def test_accessor_packet_groups_name_their_packets(
    ids: tuple[int, ...], names: tuple[str, ...]
) -> None:
    assert tuple(PACKETS[i].name for i in ids) == names


def test_a_frame_carries_a_group_only_whole() -> None:
    partial = _frame({}, ids=(7, 9, 10, 11))
    assert partial.carries(BUMPS_PACKETS)
    assert not partial.carries(CLIFF_PACKETS)  # 12 is missing
    assert not partial.carries(HAZARD_PACKETS)
    assert _frame({}).carries(HAZARD_PACKETS)
