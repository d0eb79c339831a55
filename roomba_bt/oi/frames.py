"""Sensor frames: the layout of a requested packet list, and the immutable decoded frame.

A :class:`FrameLayout` is computed once per packet list (and cached): one precompiled
``struct.Struct`` for the whole payload, so decoding a frame is one ``unpack_from`` and one
small object. Typed views (bit fields, enums, IR characters) are looked up on access from
precomputed tables; nothing is decoded that nobody reads.

Two payload shapes::

    stream (148) frame   [19][n][id1][data1...][id2][data2...]...[checksum]
    reply to 142 / 149                [data1...]    [data2...]...        (no ids, no checksum)

A group id (e.g. 100) in a stream frame is followed by the data of all its members.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Iterator, Mapping
from functools import lru_cache
from typing import Protocol, TypeVar, cast

from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.bits import (
    BUMP_BITS,
    BUMPS_BY_BYTE,
    BUTTONS_BY_BYTE,
    CHARGING_SOURCES_BY_BYTE,
    LIGHT_BUMPER_AHEAD_BITS,
    LIGHT_BUMPER_BY_BYTE,
    OVERCURRENTS_BY_BYTE,
    WHEEL_DROP_BITS,
    ChargingState,
    Stasis,
)
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.ir import IR_CHARACTERS
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode, mode_from_packet
from roomba_bt.oi.opcodes import COMMANDS
from roomba_bt.oi.packets import PACKETS, PACKETS_BY_NAME, VALID_PACKET_IDS, PacketSpec, expand
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile

STREAM_HEADER = 19
#: One stream slot, the OI's clock: the robot updates its sensors and sends a stream frame
#: every 15 ms. Defined here once; the stream parser, the odometry bound, the runner's mission
#: time and the simulator's step all read it.
SLOT_SECONDS = 0.015
PACKET_ID_ARG = COMMANDS[142].args[0]
#: the single sensor packets a frame may carry, as a message says them ("7-58")
_PACKET_RANGE = f"{min(PACKETS)}-{max(PACKETS)}"

# Which packets each group of :class:`SensorFrame` accessors reads: for a behaviour's
# ``reads=`` (the packets its mission must stream), so no layer above names them by number.
#: :attr:`SensorFrame.any_bump`, :attr:`~SensorFrame.any_wheel_drop`, :attr:`~SensorFrame.bumps`
BUMPS_PACKETS: tuple[int, ...] = (7,)
#: :attr:`SensorFrame.any_cliff` and the four ``cliff_*`` accessors (left, front left,
#: front right, right)
CLIFF_PACKETS: tuple[int, ...] = (9, 10, 11, 12)
#: :attr:`SensorFrame.any_hazard`: bumps, wheel drops, cliffs
HAZARD_PACKETS: tuple[int, ...] = BUMPS_PACKETS + CLIFF_PACKETS
VIRTUAL_WALL_PACKETS: tuple[int, ...] = (13,)
#: :attr:`SensorFrame.light_bumper` (the robot's own detection bits)
LIGHT_BUMPER_PACKETS: tuple[int, ...] = (45,)
#: the six ``light_bump_*_signal`` accessors, left to right
LIGHT_BUMP_SIGNAL_PACKETS: tuple[int, ...] = (46, 47, 48, 49, 50, 51)
#: :attr:`SensorFrame.ir_omni`, :attr:`~SensorFrame.ir_left`, :attr:`~SensorFrame.ir_right`
IR_PACKETS: tuple[int, ...] = (17, 52, 53)
#: :attr:`SensorFrame.charging_sources`
CHARGING_SOURCES_PACKETS: tuple[int, ...] = (34,)
#: :attr:`SensorFrame.charging_state`
CHARGING_STATE_PACKETS: tuple[int, ...] = (21,)
#: :attr:`SensorFrame.left_encoder_counts`, :attr:`~SensorFrame.right_encoder_counts`
ENCODER_PACKETS: tuple[int, ...] = (43, 44)
#: :attr:`SensorFrame.battery_percent` (charge, capacity)
BATTERY_PACKETS: tuple[int, ...] = (25, 26)
#: :attr:`SensorFrame.requested_velocity`, :attr:`~SensorFrame.requested_radius` (Drive)
REQUESTED_DRIVE_PACKETS: tuple[int, ...] = (39, 40)
#: :attr:`SensorFrame.requested_right_velocity`, :attr:`~SensorFrame.requested_left_velocity`
#: (Drive Direct)
REQUESTED_WHEELS_PACKETS: tuple[int, ...] = (41, 42)


class FrameLayout:
    """Where each packet sits in a payload for one requested packet list."""

    __slots__ = (
        "encoder_slots", "frame_id_mask", "frame_mask", "frame_template", "id_offsets", "index",
        "members", "mode_plus_one", "oi_modes", "packet_ids", "payload_size", "profile",
        "range_checks", "struct", "with_ids",
    )  # fmt: skip

    def __init__(
        self,
        packet_ids: tuple[int, ...],
        profile: RobotProfile,
        with_ids: bool,
        mode_plus_one: bool | None = None,
    ) -> None:
        """``mode_plus_one``: packet 35 reads the mode + 1 (the Roomba 600's firmware bug),
        as the session learned it; None: as the profile says. The frames decoded here read
        their mode through it, so a library user of a 600 does not read Passive as Safe."""
        _check_ids("sensors", packet_ids)
        self.packet_ids = packet_ids
        self.with_ids = with_ids
        self.profile = profile
        self.mode_plus_one: bool = (
            profile.reports_mode_plus_one if mode_plus_one is None else mode_plus_one
        )
        #: packet 35 by byte, the offset undone: :attr:`SensorFrame.oi_mode` reads it
        self.oi_modes = _OI_MODES_BY_BYTE[self.mode_plus_one]
        places = _Places(packet_ids, profile, with_ids)
        index = places.index
        self.members = tuple(places.members)
        self.index: Mapping[int, int] = index
        #: (value slot, lowest, highest) for each packet whose range the mask below cannot say
        self.range_checks: tuple[tuple[int, int, int], ...] = tuple(places.range_checks)
        #: value slots of the left and right encoder counts (packets 43, 44), if both are here
        self.encoder_slots: tuple[int, int] | None = (
            (index[43], index[44]) if 43 in index and 44 in index else None
        )
        self.struct = struct.Struct(">" + "".join(places.codes))
        offset = places.offset
        self.payload_size = offset
        if with_ids:
            refuse_unframeable(offset)
        self.id_offsets = tuple(places.id_offsets)
        self._set_masks(places.zero_bits)

    def _set_masks(self, zero_bits: list[tuple[int, int]]) -> None:
        """For the stream parser: header, n-bytes and every id byte of a whole frame, as a mask
        and the values under it, each one big-endian integer (one test per candidate)."""
        offset = self.payload_size
        mask = bytearray(offset + 3)
        template = bytearray(offset + 3)
        # The values' reserved bits are in the same mask, with 0 in the template: a frame whose
        # bytes set one is out of range, and costs the parser no second test.
        if self.with_ids:
            fixed = [(0, STREAM_HEADER), (1, offset & 0xFF)]
            fixed += [
                (2 + off, pid) for off, pid in zip(self.id_offsets, self.packet_ids, strict=True)
            ]
            for position, value in fixed:
                mask[position], template[position] = 0xFF, value
        #: the mask of the fixed bytes alone (header, n-bytes, ids): tells a candidate with
        #: a reserved bit set (out of range) from one that is no frame at all
        self.frame_id_mask = int.from_bytes(mask, "big")
        if self.with_ids:
            for position, bits in zero_bits:
                mask[2 + position] |= bits
        self.frame_mask = int.from_bytes(mask, "big")
        self.frame_template = int.from_bytes(template, "big")

    def __reduce__(self) -> tuple[Callable[..., FrameLayout], tuple[object, ...]]:
        """Pickled (and copied) as what it is made from: unpickled through
        :func:`layout_for`, so a process gets its own cached layout back (the compiled
        ``struct.Struct`` does not pickle, and one layout a packet list is shared)."""
        return layout_for, (self.packet_ids, self.profile, self.with_ids, self.mode_plus_one)

    @property
    def frame_size(self) -> int:
        """Bytes of one stream frame on the wire: header, n-bytes, payload, checksum."""
        return self.payload_size + 3

    def decode(self, buffer: bytes | bytearray | memoryview, offset: int = 0) -> SensorFrame:
        """Decode a payload starting at ``offset`` (ids, if any, are not checked here)."""
        return SensorFrame(self, self.struct.unpack_from(buffer, offset))

    def pack(self, values: Mapping[int, int]) -> bytes:
        """The payload for ``values`` (packet id -> raw value); the simulator's encoder.

        Missing packets are sent as 0. Each value is taken modulo 2**(8 x size), as the robot's
        own counters wrap: an ever-growing encoder count, or -1 for a signed packet, packs to
        the bytes the robot would send."""
        out = bytearray()
        for pid in self.packet_ids:
            if self.with_ids:
                out.append(pid)
            for member in expand(pid):
                spec = self.profile.packet(member)
                raw = int(values.get(member, 0))
                if spec.size == 2:
                    out += (raw & 0xFFFF).to_bytes(2, "big")
                else:
                    out.append(raw & 0xFF)
        return bytes(out)

    def stream_frame(self, values: Mapping[int, int], include_header: bool = True) -> bytes:
        """A whole stream frame ``[19][n][payload][checksum]`` for ``values``."""
        payload = self.pack(values)
        body = bytes((STREAM_HEADER, len(payload))) + payload
        total = sum(body) if include_header else sum(body) - STREAM_HEADER
        return body + bytes(((-total) & 0xFF,))


class _Places:
    """Where each packet of a list sits in the payload: the struct codes, each packet's value
    slot, the id bytes' offsets, and what its range rule says (:func:`_range_rule`)."""

    def __init__(self, packet_ids: tuple[int, ...], profile: RobotProfile, with_ids: bool) -> None:
        self.codes: list[str] = []
        self.index: dict[int, int] = {}
        self.members: list[int] = []
        self.id_offsets: list[int] = []
        self.offset = 0
        # bits no in-range value sets (reserved bits, the high nibble of a 12-bit signal),
        # by the byte offset in the payload
        self.zero_bits: list[tuple[int, int]] = []
        self.range_checks: list[tuple[int, int, int]] = []
        for pid in packet_ids:
            if with_ids:
                self.id_offsets.append(self.offset)
                self.codes.append("x")
                self.offset += 1
            for member in expand(pid):
                self._place(profile.packet(member))

    def _place(self, spec: PacketSpec) -> None:
        if spec.id in self.index:  # a packet asked for twice: keep the first, skip the bytes
            self.codes.append(f"{spec.size}x")
        else:
            zeros, check = _range_rule(spec)
            self.zero_bits += [(self.offset + i, byte) for i, byte in enumerate(zeros) if byte]
            if check is not None:
                self.range_checks.append((len(self.members), *check))
            self.index[spec.id] = len(self.members)
            self.members.append(spec.id)
            self.codes.append(spec.struct_code)
        self.offset += spec.size


def _range_rule(spec: PacketSpec) -> tuple[bytes, tuple[int, int] | None]:
    """How a value of ``spec`` is checked against its range: the bits of its bytes that no
    value in range sets (big-endian, as on the wire), and a (lowest, highest) test for what
    those bits cannot say (0-5, 0-108, -500..500), or None.

    ``bumps_wheel_drops`` (0-15) -> ``b"\xf0"``, no test; ``wall_signal`` (0-1023) ->
    ``b"\xfc\x00"``; ``charging_state`` (0-5) -> ``b"\xf8"`` and (0, 5); packet 35 (the OI
    mode) gets only its bits: the parser tests its range, which the "mode + 1" firmware moves.
    """
    bits = 8 * spec.size
    if spec.signed:
        full = spec.minimum == -(1 << (bits - 1)) and spec.maximum == (1 << (bits - 1)) - 1
        return bytes(spec.size), None if full else (spec.minimum, spec.maximum)
    top = spec.maximum + 1 if spec.id != OI_MODE_PACKET else spec.maximum + 2
    width = max(top - 1, 0).bit_length()
    zeros = (((1 << bits) - 1) & ~((1 << width) - 1)).to_bytes(spec.size, "big")
    exact = spec.minimum == 0 and top == 1 << width
    if exact or spec.id == OI_MODE_PACKET:
        return zeros, None
    return zeros, (spec.minimum, spec.maximum)


def layout_for(
    packet_ids: Iterable[int],
    profile: RobotProfile = DEFAULT_PROFILE,
    with_ids: bool = True,
    mode_plus_one: bool | None = None,
) -> FrameLayout:
    """The (cached) layout of ``packet_ids`` as a stream frame (``with_ids``) or a reply;
    ``mode_plus_one`` as :class:`FrameLayout` takes it. Any iterable of ids is taken (a list
    raised a bare "unhashable type" from the cache); a wrong id is an :class:`EncodeError`."""
    if isinstance(packet_ids, (str, bytes)) or not isinstance(packet_ids, Iterable):
        raise EncodeError("sensors", "packet ids", "a list of packet ids", packet_ids)
    if mode_plus_one is None:
        mode_plus_one = profile.reports_mode_plus_one
    return _cached_layout(tuple(packet_ids), profile, with_ids, mode_plus_one)


@lru_cache(maxsize=256)
def _cached_layout(
    packet_ids: tuple[int, ...], profile: RobotProfile, with_ids: bool, mode_plus_one: bool
) -> FrameLayout:
    return FrameLayout(packet_ids, profile, with_ids, mode_plus_one)


def _check_ids(command: str, packet_ids: Iterable[int]) -> None:
    for pid in packet_ids:
        if isinstance(pid, bool) or not isinstance(pid, int) or pid not in VALID_PACKET_IDS:
            raise EncodeError(command, PACKET_ID_ARG.name, PACKET_ID_ARG.allowed, pid)


#: n-bytes is one byte: a stream whose ids and data are more cannot be framed
MAX_STREAM_PAYLOAD = 255


def refuse_unframeable(payload_size: int) -> None:
    """Raise :class:`EncodeError` for a stream payload (ids and data) over
    :data:`MAX_STREAM_PAYLOAD`: the encoder's Stream and a stream layout say the same."""
    if payload_size > MAX_STREAM_PAYLOAD:
        raise EncodeError(
            "stream",
            "packet ids",
            f"at most {MAX_STREAM_PAYLOAD} bytes of ids and data per frame",
            payload_size,
        )


def stream_frame_size(packet_ids: Iterable[int]) -> int:
    """Bytes one stream frame of ``packet_ids`` takes on the wire: header, n-bytes, an id byte
    and the data of each packet, checksum. ``[29, 13]`` -> 8."""
    ids = tuple(packet_ids)
    _check_ids("stream", ids)
    return 3 + sum(1 + sum(PACKETS[m].size for m in expand(pid)) for pid in ids)


# ------------------------------------------------------------- the frame's accessors
# Most of :class:`SensorFrame`'s properties read one packet: its raw value, a test of some of
# its bits, or its typed view looked up by byte. Each is made here from its packet id (and
# mask or table), so the slot lookup and the KeyError for a packet the frame lacks are
# written once. Each binds its packet id (mask, table) as a default argument: read as a local,
# which is faster than a closure's cell (about 8 ns a read on CPython 3.11).

_T = TypeVar("_T")
_T_co = TypeVar("_T_co", covariant=True)


class _Accessor(Protocol[_T_co]):
    """What a made property gives a type checker: the value type on a frame."""

    def __get__(self, frame: SensorFrame, owner: type[SensorFrame] | None = None) -> _T_co: ...


#: Packet id -> its typed view, for :meth:`SensorFrame.as_dict`: each table :func:`_decoded`
#: reads.
_VIEWS: dict[int, Callable[[int], object]] = {}


def _raw(packet_id: int) -> _Accessor[int]:
    """A property: packet ``packet_id``'s raw value (``frame[packet_id]``, without the call)."""

    def read(frame: SensorFrame, packet_id: int = packet_id) -> int:
        try:
            return frame.values[frame.layout.index[packet_id]]
        except KeyError:
            raise frame._missing(packet_id) from None

    doc = f"Packet {packet_id} ({PACKETS[packet_id].name}) as sent."
    return cast("_Accessor[int]", property(read, doc=doc))


def _bits_set(packet_id: int, mask: int = 0xFF) -> _Accessor[bool]:
    """A property: True if any of ``mask``'s bits is set in packet ``packet_id`` (the whole
    byte by default: a one-bit packet such as wall 8 or cliff left 9)."""

    def read(frame: SensorFrame, packet_id: int = packet_id, mask: int = mask) -> bool:
        try:
            return frame.values[frame.layout.index[packet_id]] & mask != 0
        except KeyError:
            raise frame._missing(packet_id) from None

    doc = f"Packet {packet_id} ({PACKETS[packet_id].name}) has a bit of {mask:#b} set."
    return cast("_Accessor[bool]", property(read, doc=doc))


def _decoded(packet_id: int, by_byte: tuple[_T, ...]) -> _Accessor[_T]:
    """A property: packet ``packet_id``'s typed view, ``by_byte[value & 0xFF]`` (a table of
    every byte value decoded once: no allocation)."""

    def read(
        frame: SensorFrame, packet_id: int = packet_id, by_byte: tuple[_T, ...] = by_byte
    ) -> _T:
        try:
            return by_byte[frame.values[frame.layout.index[packet_id]] & 0xFF]
        except KeyError:
            raise frame._missing(packet_id) from None

    _VIEWS[packet_id] = by_byte.__getitem__
    doc = f"Packet {packet_id} ({PACKETS[packet_id].name}) as {type(by_byte[0]).__name__}."
    return cast("_Accessor[_T]", property(read, doc=doc))


def _by_byte(decode: Callable[[int], _T]) -> tuple[_T, ...]:
    return tuple(decode(value) for value in range(256))


#: Packets 21 and 58 by byte: a charging state past the enum reads as a fault; stasis keeps
#: its two low bits.
_CHARGING_STATE_BY_BYTE = _by_byte(lambda v: ChargingState(v) if v <= 5 else ChargingState.FAULT)


def _oi_modes_by_byte(plus_one: bool) -> tuple[OIMode, ...]:
    """Packet 35 by byte through :func:`~roomba_bt.oi.modes.mode_from_packet` (the one place
    that undoes the "mode + 1"); a byte that is no mode reads as the nearest end (Full past
    it, as the 600's reading 4 did before; Off below), so the view never raises."""

    def mode(raw: int) -> OIMode:
        found = mode_from_packet(raw, plus_one)
        if found is not None:
            return found
        return OIMode.OFF if raw < int(plus_one) else OIMode.FULL

    return _by_byte(mode)


#: indexed by ``mode_plus_one`` (False, True): each layout picks its table once
_OI_MODES_BY_BYTE = (_oi_modes_by_byte(False), _oi_modes_by_byte(True))
_STASIS_BY_BYTE = _by_byte(lambda v: Stasis(v & 3))


class MissingPacket(KeyError, RoombaBtError):
    """A packet read from a frame that does not carry it (a behaviour that reads a packet
    its declaration does not list: the runtime's message says where to add it)."""

    def __init__(self, packet_id: object, message: str) -> None:
        super().__init__(message)
        self.packet_id = packet_id


class SensorFrame:
    """One decoded set of sensor values (a stream frame or a reply), read-only.

    ``frame[packet_id]`` is the raw integer the robot sent (signed where the packet is signed);
    the properties give typed views. Asking for a packet the frame does not carry raises
    ``KeyError`` naming it.

    Read-only by contract: :attr:`layout` and :attr:`values` are set once, when the frame is
    made, and nothing assigns them after (a frame is shared: the tick's snapshot, the mode
    model's frame before, a recording). Nothing else can be set (no instance dict:
    ``AttributeError``). The two are plain slots, not properties guarded by a
    ``__setattr__`` that refuses: a frame is made for every 15 ms of the stream, and read
    many times a tick (a slot's read is no call); with that guard, making one cost twice as
    many instructions.
    """

    __slots__ = ("layout", "values")

    #: where each packet sits in :attr:`values`
    layout: FrameLayout
    #: the raw values in the layout's order: ``SensorFrame(f.layout, f.values) == f``
    values: tuple[int, ...]

    def __init__(self, layout: FrameLayout, values: tuple[int, ...]) -> None:
        self.layout = layout
        self.values = values

    def __reduce__(self) -> tuple[type[SensorFrame], tuple[FrameLayout, tuple[int, ...]]]:
        """Pickled as ``SensorFrame(layout, values)`` (multiprocessing, Dask, a saved frame);
        ``copy.copy`` and ``deepcopy`` make an equal frame on the same layout."""
        return SensorFrame, (self.layout, self.values)

    @property
    def packet_ids(self) -> tuple[int, ...]:
        return self.layout.members

    def __contains__(self, packet_id: object) -> bool:
        return packet_id in self.layout.index

    def __getitem__(self, packet_id: int) -> int:
        try:
            return self.values[self.layout.index[packet_id]]
        except (KeyError, TypeError):
            raise self._missing(packet_id) from None

    def _missing(self, packet_id: object) -> MissingPacket:
        carried = list(self.layout.members)
        if packet_id not in PACKETS:  # no frame carries it: not a packet to declare
            return MissingPacket(
                packet_id,
                f"packet {packet_id!r} does not exist: the Open Interface's sensor packets "
                f"are {_PACKET_RANGE} (roomba_bt.oi.packets; by name: packet_ids('wall_signal', "
                f"...)); this frame carries {carried}",
            )
        name = PACKETS[packet_id].name  # type: ignore[index]
        return MissingPacket(
            packet_id, f"packet {packet_id} ({name}) is not in this frame; it carries {carried}"
        )

    def carries(self, packet_ids: Iterable[int]) -> bool:
        """Whether the frame holds every one of ``packet_ids`` (one of the groups above, so
        that a reader of a stream that may lack them need not name packets by number)."""
        index = self.layout.index
        return all(packet_id in index for packet_id in packet_ids)

    def get(self, packet_id: int, default: int | None = None) -> int | None:
        i = self.layout.index.get(packet_id)
        return default if i is None else self.values[i]

    def __iter__(self) -> Iterator[tuple[int, int]]:
        return zip(self.layout.members, self.values, strict=True)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SensorFrame):
            return NotImplemented
        return dict(self) == dict(other)

    def __hash__(self) -> int:
        return hash(tuple(sorted(dict(self).items())))

    def __repr__(self) -> str:
        body = ", ".join(f"{PACKETS[p].name}={v}" for p, v in self)
        return f"SensorFrame({body})"

    def value(self, name: str) -> int:
        """Raw value by packet name (``frame.value("voltage")``)."""
        spec = PACKETS_BY_NAME.get(name)
        if spec is None:
            raise KeyError(f"no sensor packet is called {name!r}")
        return self[spec.id]

    def as_dict(self) -> dict[str, object]:
        """Every packet by name, decoded to its typed view where one exists."""
        out: dict[str, object] = {}
        for pid, raw in self:
            name = PACKETS[pid].name
            view = _VIEWS.get(pid)
            out[name] = view(raw) if view is not None else raw
        if OI_MODE_PACKET in self.layout.index:
            # the mode corrected as :attr:`oi_mode` is; a byte that is no mode stays as sent
            raw = self[OI_MODE_PACKET]
            mode = mode_from_packet(raw, self.layout.mode_plus_one)
            out[PACKETS[OI_MODE_PACKET].name] = raw if mode is None else mode
        return out

    # The readings: each reads its value straight from the slots (no ``__getitem__`` call:
    # the hazards are read on every tick); a missing packet raises the same KeyError as
    # ``frame[id]``. Flags first, then typed views, raw values, and the readings of several
    # packets.
    #: Either bumper pressed (packet 7, bits 0-1).
    any_bump = _bits_set(7, BUMP_BITS)
    #: Either wheel dropped (packet 7, bits 2-3 only; the unused bits 4-7 are not read).
    any_wheel_drop = _bits_set(7, WHEEL_DROP_BITS)
    wall = _bits_set(8)
    cliff_left = _bits_set(9)
    cliff_front_left = _bits_set(10)
    cliff_front_right = _bits_set(11)
    cliff_right = _bits_set(12)
    virtual_wall = _bits_set(13)
    song_playing = _bits_set(37)
    #: One of the four front light-bumper sensors (packet 45 bits 1-4) sees something.
    light_bumper_ahead = _bits_set(45, LIGHT_BUMPER_AHEAD_BITS)

    bumps = _decoded(7, BUMPS_BY_BYTE)
    overcurrents = _decoded(14, OVERCURRENTS_BY_BYTE)
    ir_omni = _decoded(17, IR_CHARACTERS)
    buttons = _decoded(18, BUTTONS_BY_BYTE)
    charging_state = _decoded(21, _CHARGING_STATE_BY_BYTE)
    charging_sources = _decoded(34, CHARGING_SOURCES_BY_BYTE)
    light_bumper = _decoded(45, LIGHT_BUMPER_BY_BYTE)
    ir_left = _decoded(52, IR_CHARACTERS)
    ir_right = _decoded(53, IR_CHARACTERS)
    stasis = _decoded(58, _STASIS_BY_BYTE)

    dirt_detect = _raw(15)
    distance_mm = _raw(19)
    angle_deg = _raw(20)
    voltage_mv = _raw(22)
    current_ma = _raw(23)
    temperature_c = _raw(24)
    battery_charge_mah = _raw(25)
    battery_capacity_mah = _raw(26)
    wall_signal = _raw(27)
    #: Packet 35 as sent: on a 600 that reports the mode + 1, one more than :attr:`oi_mode`.
    oi_mode_raw = _raw(35)
    song_number = _raw(36)
    stream_packet_count = _raw(38)
    requested_velocity = _raw(39)
    requested_radius = _raw(40)
    requested_right_velocity = _raw(41)
    requested_left_velocity = _raw(42)
    left_encoder_counts = _raw(43)
    right_encoder_counts = _raw(44)
    light_bump_left_signal = _raw(46)
    light_bump_front_left_signal = _raw(47)
    light_bump_center_left_signal = _raw(48)
    light_bump_center_right_signal = _raw(49)
    light_bump_front_right_signal = _raw(50)
    light_bump_right_signal = _raw(51)

    @property
    def oi_mode(self) -> OIMode:
        """Packet 35 as the OI mode, the "mode + 1" of the layout (the profile, or what the
        session learned) undone: a roomba600 in Passive reads Passive, not Safe."""
        try:
            return self.layout.oi_modes[self.values[self.layout.index[OI_MODE_PACKET]] & 0xFF]
        except KeyError:
            raise self._missing(OI_MODE_PACKET) from None

    @property
    def any_cliff(self) -> bool:
        """One of the four cliff sensors (packets 9-12) sees a drop."""
        values, index = self.values, self.layout.index
        try:
            return bool(values[index[9]] or values[index[10]] or values[index[11]]
                        or values[index[12]])  # fmt: skip
        except KeyError as exc:
            raise self._missing(exc.args[0]) from None

    @property
    def any_hazard(self) -> bool:
        """A bump, a wheel drop or a cliff (packets 7, 9-12): the union of the three."""
        values, index = self.values, self.layout.index
        try:
            return bool(values[index[7]] & (BUMP_BITS | WHEEL_DROP_BITS) or values[index[9]]
                        or values[index[10]] or values[index[11]] or values[index[12]])  # fmt: skip
        except KeyError as exc:
            raise self._missing(exc.args[0]) from None

    @property
    def battery_percent(self) -> float:
        capacity = self[26]
        return 100.0 * self[25] / capacity if capacity else 0.0

    @property
    def cliff_signals(self) -> tuple[int, int, int, int]:
        return (self[28], self[29], self[30], self[31])

    @property
    def light_bump_signals(self) -> tuple[int, int, int, int, int, int]:
        """Left, front left, centre left, centre right, front right, right (packets 46-51),
        read from the slots in one accessor (the wall followers read all six every tick)."""
        values, index = self.values, self.layout.index
        try:
            return (values[index[46]], values[index[47]], values[index[48]],
                    values[index[49]], values[index[50]], values[index[51]])  # fmt: skip
        except KeyError as exc:
            raise self._missing(exc.args[0]) from None

    @property
    def motor_currents_ma(self) -> tuple[int, int, int, int]:
        """Left wheel, right wheel, main brush, side brush."""
        return (self[54], self[55], self[56], self[57])
