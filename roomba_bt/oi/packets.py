"""The sensor packet table (ids 7-58) and the group table (0-6, 100, 101, 106, 107).

Defined once; the decoder, the stream parser, the bandwidth check, the mission validator and
the simulator all read it. Ranges are the union of both specifications (the decoder never
clamps: it returns what the robot sent); where the specs disagree the profile says which holds
(see :mod:`roomba_bt.oi.profiles` and ``docs/protocol.md``).

Multi-byte values are big-endian ("high byte first")::

    packet 22 (voltage, 2 bytes, unsigned):  [0x3A][0x98]  -> 15000 mV
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType


@dataclass(frozen=True, slots=True)
class PacketSpec:
    """One single-value sensor packet."""

    id: int
    name: str
    size: int
    signed: bool
    minimum: int
    maximum: int
    unit: str = ""
    title: str = ""

    @property
    def struct_code(self) -> str:
        return {(1, False): "B", (1, True): "b", (2, False): "H", (2, True): "h"}[
            (self.size, self.signed)
        ]


def _p(
    pid: int, name: str, size: int, signed: bool, lo: int, hi: int, unit: str = "", title: str = ""
) -> PacketSpec:
    return PacketSpec(pid, name, size, signed, lo, hi, unit, title or name.replace("_", " "))


_PACKET_LIST: tuple[PacketSpec, ...] = (
    _p(7, "bumps_wheel_drops", 1, False, 0, 15, "bits", "Bumps and wheel drops"),
    _p(8, "wall", 1, False, 0, 1, "bool", "Wall"),
    _p(9, "cliff_left", 1, False, 0, 1, "bool", "Cliff left"),
    _p(10, "cliff_front_left", 1, False, 0, 1, "bool", "Cliff front left"),
    _p(11, "cliff_front_right", 1, False, 0, 1, "bool", "Cliff front right"),
    _p(12, "cliff_right", 1, False, 0, 1, "bool", "Cliff right"),
    _p(13, "virtual_wall", 1, False, 0, 1, "bool", "Virtual wall"),
    _p(14, "overcurrents", 1, False, 0, 31, "bits", "Wheel and brush overcurrents"),
    _p(15, "dirt_detect", 1, False, 0, 255, "", "Dirt detect"),
    _p(16, "unused_16", 1, False, 0, 255, "", "Unused byte"),
    _p(17, "ir_omni", 1, False, 0, 255, "IR character", "Infrared character omni"),
    _p(18, "buttons", 1, False, 0, 255, "bits", "Buttons"),
    _p(19, "distance", 2, True, -32768, 32767, "mm", "Distance"),
    _p(20, "angle", 2, True, -32768, 32767, "deg", "Angle"),
    _p(21, "charging_state", 1, False, 0, 5, "enum", "Charging state"),
    _p(22, "voltage", 2, False, 0, 65535, "mV", "Voltage"),
    _p(23, "current", 2, True, -32768, 32767, "mA", "Current"),
    _p(24, "temperature", 1, True, -128, 127, "degC", "Temperature"),
    _p(25, "battery_charge", 2, False, 0, 65535, "mAh", "Battery charge"),
    _p(26, "battery_capacity", 2, False, 0, 65535, "mAh", "Battery capacity"),
    _p(27, "wall_signal", 2, False, 0, 4095, "", "Wall signal"),
    _p(28, "cliff_left_signal", 2, False, 0, 4095, "", "Cliff left signal"),
    _p(29, "cliff_front_left_signal", 2, False, 0, 4095, "", "Cliff front left signal"),
    _p(30, "cliff_front_right_signal", 2, False, 0, 4095, "", "Cliff front right signal"),
    _p(31, "cliff_right_signal", 2, False, 0, 4095, "", "Cliff right signal"),
    _p(32, "unused_32", 1, False, 0, 255, "", "Unused"),
    _p(33, "unused_33", 2, False, 0, 65535, "", "Unused"),
    _p(34, "charging_sources", 1, False, 0, 3, "bits", "Charging sources available"),
    _p(35, "oi_mode", 1, False, 0, 3, "enum", "OI mode"),
    _p(36, "song_number", 1, False, 0, 15, "", "Song number"),
    _p(37, "song_playing", 1, False, 0, 1, "bool", "Song playing"),
    _p(38, "stream_packets", 1, False, 0, 108, "", "Number of stream packets"),
    _p(39, "requested_velocity", 2, True, -500, 500, "mm/s", "Requested velocity"),
    _p(40, "requested_radius", 2, True, -32768, 32767, "mm", "Requested radius"),
    _p(41, "requested_right_velocity", 2, True, -500, 500, "mm/s", "Requested right velocity"),
    _p(42, "requested_left_velocity", 2, True, -500, 500, "mm/s", "Requested left velocity"),
    _p(43, "left_encoder_counts", 2, True, -32768, 32767, "counts", "Left encoder counts"),
    _p(44, "right_encoder_counts", 2, True, -32768, 32767, "counts", "Right encoder counts"),
    _p(45, "light_bumper", 1, False, 0, 127, "bits", "Light bumper"),
    _p(46, "light_bump_left_signal", 2, False, 0, 4095, "", "Light bump left signal"),
    _p(47, "light_bump_front_left_signal", 2, False, 0, 4095, "", "Light bump front left signal"),
    _p(48, "light_bump_center_left_signal", 2, False, 0, 4095, "", "Light bump center left"),
    _p(49, "light_bump_center_right_signal", 2, False, 0, 4095, "", "Light bump center right"),
    _p(50, "light_bump_front_right_signal", 2, False, 0, 4095, "", "Light bump front right"),
    _p(51, "light_bump_right_signal", 2, False, 0, 4095, "", "Light bump right signal"),
    _p(52, "ir_left", 1, False, 0, 255, "IR character", "Infrared character left"),
    _p(53, "ir_right", 1, False, 0, 255, "IR character", "Infrared character right"),
    _p(54, "left_motor_current", 2, True, -32768, 32767, "mA", "Left motor current"),
    _p(55, "right_motor_current", 2, True, -32768, 32767, "mA", "Right motor current"),
    _p(56, "main_brush_current", 2, True, -32768, 32767, "mA", "Main brush motor current"),
    _p(57, "side_brush_current", 2, True, -32768, 32767, "mA", "Side brush motor current"),
    _p(58, "stasis", 1, False, 0, 3, "enum", "Stasis"),
)

PACKETS: Mapping[int, PacketSpec] = MappingProxyType({p.id: p for p in _PACKET_LIST})
PACKETS_BY_NAME: Mapping[str, PacketSpec] = MappingProxyType({p.name: p for p in _PACKET_LIST})


def packet_ids(*names: str) -> tuple[int, ...]:
    """The ids of the packets named (``packet_ids("battery_charge", "battery_capacity")`` ->
    ``(25, 26)``): for a reader's list of what it reads, without the numbers. A name the table
    does not have raises KeyError when the reader is defined."""
    return tuple(PACKETS_BY_NAME[name].id for name in names)


#: Group id -> member packet ids, in the order the robot sends them.
GROUPS: Mapping[int, tuple[int, ...]] = MappingProxyType(
    {
        0: tuple(range(7, 27)),
        1: tuple(range(7, 17)),
        2: tuple(range(17, 21)),
        3: tuple(range(21, 27)),
        4: tuple(range(27, 35)),
        5: tuple(range(35, 43)),
        6: tuple(range(7, 43)),
        100: tuple(range(7, 59)),
        101: tuple(range(43, 59)),
        106: tuple(range(46, 52)),
        107: tuple(range(54, 59)),
    }
)

#: Every id that Sensors (142), Query List (149) and Stream (148) accept.
VALID_PACKET_IDS: frozenset[int] = frozenset(PACKETS) | frozenset(GROUPS)


def expand(packet_id: int) -> tuple[int, ...]:
    """The single packets a (possibly group) id stands for."""
    if packet_id in GROUPS:
        return GROUPS[packet_id]
    if packet_id in PACKETS:
        return (packet_id,)
    raise KeyError(packet_id)


def data_size(packet_id: int) -> int:
    """Bytes of data the robot sends for ``packet_id`` (a group: all its members)."""
    return sum(PACKETS[m].size for m in expand(packet_id))


GROUP_SIZES: Mapping[int, int] = MappingProxyType({g: data_size(g) for g in GROUPS})
