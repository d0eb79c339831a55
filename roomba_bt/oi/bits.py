"""Bit fields, both ways: sensor bytes decoded into named booleans, and readable command
arguments (LEDs, motors, days, buttons, digits) encoded into data bytes.

Decoded values are frozen and precomputed for every byte value, so decoding a bit field is a
tuple lookup, not an allocation.

Layouts (bit 7 left, bit 0 right)::

    packet 7   bumps/wheel drops  [ - - - - | drop L | drop R | bump L | bump R ]
                                  (WHEEL_DROP_BITS 0b1100, BUMP_BITS 0b0011)
    packet 14  overcurrents       [ - - - | wheel L | wheel R | main brush | - | side brush ]
    packet 18  buttons            [ clock | schedule | day | hour | minute | dock | spot | clean ]
    packet 34  charging sources   [ - - - - - - | home base | internal charger ]
    packet 45  light bumper       [ - - | R | FR | CR | CL | FL | L ]
                                  (LIGHT_BUMPER_AHEAD_BITS 0b011110: FR CR CL FL)
    opcode 138 motors             [ - - - | main dir | side CW | main | vacuum | side ]
    opcode 139 LEDs               [ - - - - | check robot | dock | spot | debris ]
    opcode 162 weekday LEDs, opcode 167 days
                                  [ - | sat | fri | thu | wed | tue | mon | sun ]
    opcode 162 scheduling LEDs    [ - - - | schedule | clock | AM | PM | colon ]
    opcode 163 digit segments     [ - | G | F | E | D | C | B | A ]
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import TYPE_CHECKING, Any, ClassVar, Self

from roomba_bt.oi.errors import EncodeError


class _ByteView:
    """A bit field's view of one byte: its flags are its fields after ``raw``, in the order of
    their bits, then any :func:`_union` of bits. Each subclass decodes the 256 byte values
    once (:meth:`_decode_every_byte`), so that :meth:`from_byte` is a lookup."""

    __slots__ = ()
    by_byte: ClassVar[tuple[Any, ...]] = ()
    #: (field name, bits) of each :func:`_union` field, in field order
    _unions: ClassVar[tuple[tuple[str, int], ...]] = ()

    if TYPE_CHECKING:  # each subclass is a dataclass of these
        raw: int

        def __init__(self, raw: int, *flags: bool) -> None: ...

    def __post_init__(self) -> None:
        for name, bits in self._unions:
            object.__setattr__(self, name, self.raw & bits != 0)

    @classmethod
    def from_byte(cls, value: int) -> Self:
        view: Self = cls.by_byte[value & 0xFF]
        return view

    @classmethod
    def _decode_every_byte(cls, bits: Iterable[int]) -> None:
        """Fill :attr:`by_byte`: its flags read ``bits`` (bit numbers, in field order). Done
        for every bit field at import, by every command: each flag is computed in a list,
        not by a function called from a generator (a fifth fewer instructions)."""
        numbers = tuple(bits)
        own = fields(cls)  # type: ignore[arg-type]
        cls._unions = tuple((f.name, f.metadata[_UNION]) for f in own if _UNION in f.metadata)
        cls.by_byte = tuple(cls(v, *[v >> n & 1 == 1 for n in numbers]) for v in range(256))

    @classmethod
    def flag_names(cls) -> tuple[str, ...]:
        """The flags' names in the order of their bits."""
        return tuple(f.name for f in fields(cls) if f.init and f.name != "raw")  # type: ignore[arg-type]


_UNION = "union of bits"


def _union(bits: int) -> Any:
    """A flag set when any of ``bits`` is (either bump, any light-bumper sensor ahead):
    computed with the view (:meth:`_ByteView.__post_init__`) and stored, not a property,
    because the hazards are read on every tick."""
    return field(init=False, repr=False, compare=False, metadata={_UNION: bits})


#: Packet 7's two bump bits (bit 1 left, bit 0 right) and two wheel-drop bits (bit 3 left,
#: bit 2 right); bits 4-7 are not used.
BUMP_BITS = 0b0011
WHEEL_DROP_BITS = 0b1100


@dataclass(frozen=True, slots=True)
class BumpsWheelDrops(_ByteView):
    """Packet 7. Bit 0 is bump RIGHT, bit 1 bump LEFT (a peer driver has them swapped)."""

    raw: int
    bump_right: bool
    bump_left: bool
    wheel_drop_right: bool
    wheel_drop_left: bool
    #: either bump / either wheel drop
    any_bump: bool = _union(BUMP_BITS)
    any_wheel_drop: bool = _union(WHEEL_DROP_BITS)


BumpsWheelDrops._decode_every_byte(range(4))


@dataclass(frozen=True, slots=True)
class Overcurrents(_ByteView):
    """Packet 14: bit 0 side brush, bit 2 main brush, bit 3 right wheel, bit 4 left wheel."""

    raw: int
    side_brush: bool
    main_brush: bool
    right_wheel: bool
    left_wheel: bool

    @property
    def any(self) -> bool:
        return self.raw & 0b11101 != 0


Overcurrents._decode_every_byte((0, 2, 3, 4))
#: Each motor's bit of packet 14 (``side_brush`` 0b1 ... ``left_wheel`` 0b10000), read back
#: from the decoded views: the simulator's ``overcurrent`` event sets the bit a mission's
#: ``overcurrent: main_brush`` reads, with no second list of them to drift.
OVERCURRENT_BITS: dict[str, int] = {
    name: next(1 << n for n in range(8) if getattr(Overcurrents.by_byte[1 << n], name))
    for name in Overcurrents.flag_names()
}


@dataclass(frozen=True, slots=True)
class Buttons(_ByteView):
    """Packet 18 (and the data byte of opcode 165)."""

    raw: int
    clean: bool
    spot: bool
    dock: bool
    minute: bool
    hour: bool
    day: bool
    schedule: bool
    clock: bool

    @property
    def any(self) -> bool:
        return self.raw != 0


Buttons._decode_every_byte(range(8))
BUTTON_NAMES: tuple[str, ...] = Buttons.flag_names()
#: how long a press shows in packet 18: Buttons (165) releases them after 1/6 s (the opcode
#: table's doc); the simulator holds a world's ``press`` event as long
PRESS_SECONDS = 1.0 / 6.0
#: the buttons that, pressed in Passive, start the robot's own cycle (Clean, Spot, Seek
#: Dock), as their commands do ("the same as pressing Roomba's Clean button", docs/simulator.md)
CYCLE_BUTTONS: tuple[str, ...] = ("clean", "spot", "dock")


@dataclass(frozen=True, slots=True)
class ChargingSources(_ByteView):
    """Packet 34: 1 = charging source present and powered."""

    raw: int
    internal_charger: bool
    home_base: bool

    @property
    def any(self) -> bool:
        return self.internal_charger or self.home_base


ChargingSources._decode_every_byte(range(2))


#: Packet 45's four front sensors (front-left, centre-left, centre-right, front-right, bits
#: 1-4): something ahead of the robot rather than beside it.
LIGHT_BUMPER_AHEAD_BITS = 0b011110
#: Packet 45's six sensors (bits 0-5).
LIGHT_BUMPER_BITS = 0b111111


@dataclass(frozen=True, slots=True)
class LightBumper(_ByteView):
    """Packet 45: which of the six light-bumper sensors sees an obstacle."""

    raw: int
    left: bool
    front_left: bool
    center_left: bool
    center_right: bool
    front_right: bool
    right: bool
    #: any of the six / any of the four front ones
    any: bool = _union(LIGHT_BUMPER_BITS)
    ahead: bool = _union(LIGHT_BUMPER_AHEAD_BITS)


LightBumper._decode_every_byte(range(6))
LIGHT_BUMPER_NAMES: tuple[str, ...] = LightBumper.flag_names()


class ChargingState(IntEnum):
    """Packet 21."""

    NOT_CHARGING = 0
    RECONDITIONING = 1
    FULL_CHARGING = 2
    TRICKLE_CHARGING = 3
    WAITING = 4
    FAULT = 5

    @property
    def is_charging(self) -> bool:
        return self in (
            ChargingState.RECONDITIONING,
            ChargingState.FULL_CHARGING,
            ChargingState.TRICKLE_CHARGING,
            ChargingState.WAITING,
        )


class Stasis(IntEnum):
    """Packet 58. The 600 spec adds 2 = the stasis wheel is too dirty to read."""

    NO_PROGRESS = 0
    FORWARD_PROGRESS = 1
    DIRTY = 2
    RESERVED = 3


# ----------------------------------------------------------------- encoding side


def _flags(command: str, argument: str, names: Iterable[str], known: tuple[str, ...]) -> int:
    value = 0
    for name in names:
        if not isinstance(name, str):
            raise EncodeError(command, argument, f"made of {', '.join(known)}", name)
        try:
            value |= 1 << known.index(name)
        except ValueError:
            raise EncodeError(command, argument, f"made of {', '.join(known)}", name) from None
    return value


LED_NAMES: tuple[str, ...] = ("debris", "spot", "dock", "check_robot")
#: the LEDs a spec names otherwise: the 600 spec's "Home" LED is the dock LED ("Home and
#: Spot use green LEDs"), so a mission writing ``home`` is pointed to ``dock``
LED_SPEC_NAMES: dict[str, str] = {"dock": "Home"}


def led_bits(*leds: str) -> int:
    """LEDs by name: ``led_bits("dock") == 4`` (the spec's Home LED example)."""
    return _flags("leds", "led_bits", leds, LED_NAMES)


WEEKDAYS: tuple[str, ...] = ("sun", "mon", "tue", "wed", "thu", "fri", "sat")


def day_bits(*days: str) -> int:
    """Days by three-letter name: ``day_bits("wed", "fri") == 40`` (the Schedule example)."""
    names = (d.lower()[:3] if isinstance(d, str) else d for d in days)
    return _flags("schedule", "day_bits", names, WEEKDAYS)


SCHEDULING_LED_NAMES: tuple[str, ...] = ("colon", "pm", "am", "clock", "schedule")


def scheduling_led_bits(*leds: str) -> int:
    return _flags("scheduling_leds", "scheduling_bits", leds, SCHEDULING_LED_NAMES)


def button_bits(*buttons: str) -> int:
    return _flags("buttons", "button_bits", buttons, BUTTON_NAMES)


#: the buttons whose press makes the robot ignore Schedule (167) and Set Day/Time (168): both
#: specs, "If Roomba's schedule or clock button is pressed, this command will be ignored"
CLOCK_BUTTONS: tuple[str, ...] = ("clock", "schedule")


def held_clock_buttons(pressed: int) -> str:
    """Which of :data:`CLOCK_BUTTONS` packet 18's ``pressed`` bits hold, said (``"clock"``,
    ``"clock and schedule"``), or "" for neither."""
    return " and ".join(name for name in CLOCK_BUTTONS if pressed & button_bits(name))


def motor_bits(
    *,
    side_brush: bool = False,
    vacuum: bool = False,
    main_brush: bool = False,
    side_brush_clockwise: bool = False,
    main_brush_outward: bool = False,
) -> int:
    """Motors (138): ``motor_bits(main_brush=True, side_brush=True,
    side_brush_clockwise=True) == 13`` (the spec's example)."""
    flags = {
        "side_brush": side_brush,
        "vacuum": vacuum,
        "main_brush": main_brush,
        "side_brush_clockwise": side_brush_clockwise,
        "main_brush_outward": main_brush_outward,
    }
    for name, flag in flags.items():
        if not isinstance(flag, bool):
            raise EncodeError("motors", name, "True or False", flag)
    return (
        side_brush
        | vacuum << 1
        | main_brush << 2
        | side_brush_clockwise << 3
        | main_brush_outward << 4
    )


#: Motors (138)'s bits that run a motor (side brush, vacuum, main brush: bits 0-2); bits 3-4
#: only set the brushes' directions
MOTOR_RUN_BITS = 0b00111


SEGMENT_NAMES: tuple[str, ...] = ("a", "b", "c", "d", "e", "f", "g")


def segment_bits(*segments: str) -> int:
    names = (s.lower() if isinstance(s, str) else s for s in segments)
    return _flags("digit_leds_raw", "digit bits", names, SEGMENT_NAMES)


#: Characters the 7-segment display implements (Digit LEDs ASCII table). 42 '*', 43 '+' and
#: 64 '@' are in the byte range 32-126 but absent from the table: they would show nothing.
DIGIT_ASCII: frozenset[int] = frozenset(range(32, 127)) - {42, 43, 64}


#: Every byte value decoded once, for the frame's typed views (a lookup, no allocation).
BUMPS_BY_BYTE: tuple[BumpsWheelDrops, ...] = BumpsWheelDrops.by_byte
OVERCURRENTS_BY_BYTE: tuple[Overcurrents, ...] = Overcurrents.by_byte
BUTTONS_BY_BYTE: tuple[Buttons, ...] = Buttons.by_byte
CHARGING_SOURCES_BY_BYTE: tuple[ChargingSources, ...] = ChargingSources.by_byte
LIGHT_BUMPER_BY_BYTE: tuple[LightBumper, ...] = LightBumper.by_byte
