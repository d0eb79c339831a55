"""The encoder: typed arguments in, exact bytes out, or an :class:`EncodeError` and no bytes.

Every command goes through :func:`encode`, which checks each argument against the opcode table
(type and range) before a single byte is built, so a malformed sequence (one the robot would
sit waiting on for its missing data bytes) cannot be produced. The named helpers below give
readable arguments (special radii, LEDs and motors by name, songs as notes, days, ASCII).

Drive (137), velocity -200 mm/s, radius 500 mm (the spec's example)::

    [137][0xFF][0x38][0x01][0xF4]  ==  [137][255][56][1][244]

A program reaches it as ``from roomba_bt import commands`` (or ``from roomba_bt.oi import
commands``): pycreate2's methods as functions that build a :class:`Command`, which
``Connection.send`` writes (``robot.send(commands.drive_direct(200, 200))``, in mm/s).
"""

from __future__ import annotations

import operator
import struct
import sys
import types
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import SupportsIndex, cast

from roomba_bt.oi.bits import DIGIT_ASCII, day_bits
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.opcodes import (
    COMMANDS,
    COMMANDS_BY_NAME,
    NOTE_STEPS_PER_SECOND,
    PLAYABLE_NOTES,  # noqa: F401  (the name's old home: roomba_bt.oi.encode.PLAYABLE_NOTES)
    SONG_LENGTH,
    ArgSpec,
    CommandSpec,
)

#: What ``from roomba_bt.commands import *`` gives and ``help(roomba_bt.commands)`` lists:
#: the commands and what they are built of, not this module's own imports (``sys``,
#: ``struct``, ``cast``... came with the star, and a type checker refused them)
__all__ = [
    "BAUD_CODES",
    "BAUD_RATES",
    "NAMED_NOTES",
    "NOTE_NAMES",
    "STRAIGHT_RADII",
    "Command",
    "EncodeError",
    "Note",
    "Radius",
    "baud",
    "baud_rate",
    "buttons",
    "clean",
    "command_size",
    "control",
    "day_number",
    "decode_command",
    "digit_leds_ascii",
    "digit_leds_raw",
    "drive",
    "drive_direct",
    "drive_pwm",
    "drive_straight",
    "encode",
    "full",
    "halt",
    "leds",
    "max_clean",
    "motors",
    "motors_off",
    "note_name",
    "note_number",
    "pause_stream",
    "play",
    "power",
    "pwm_motors",
    "query_list",
    "reset",
    "resume_stream",
    "safe",
    "schedule",
    "schedule_times",
    "scheduling_leds",
    "seek_dock",
    "sensors",
    "set_day_time",
    "song",
    "song_seconds",
    "spin",
    "spot",
    "start",
    "stop",
    "stream",
    "turns_wheels",
]


class Radius(IntEnum):
    """Drive (137)'s special radii, sent as is and never clamped into -2000..2000."""

    STRAIGHT = 0x8000  # 32768; 0x7FFF (32767) means straight too
    STRAIGHT_ALT = 0x7FFF
    TURN_CLOCKWISE = -1
    TURN_COUNTER_CLOCKWISE = 1


#: Radius values that mean "straight": 0x8000 (also written -32768, its signed reading) and
#: 0x7FFF. They lie outside -2000..2000 and are sent unchanged.
STRAIGHT_RADII = frozenset({0x8000, 0x7FFF, -0x8000})
_RADIUS_ALLOWED = "in -2000..2000 mm, or 32768/32767 (straight) or -1/1 (spin in place)"


#: what ``send()`` takes, as its refusal of raw bytes or an opcode says it (a connection's
#: and a behaviour's): the import a program writes, not the module path that warns
COMMAND_WANTED = (
    "a Command from roomba_bt.commands (from roomba_bt import commands: "
    "commands.drive(200, 32767), commands.safe())"
)


@dataclass(frozen=True, slots=True)
class Command:
    """An encoded command: its table entry, its argument values and its bytes."""

    spec: CommandSpec
    args: tuple[int, ...]
    data: bytes

    @property
    def opcode(self) -> int:
        return self.spec.opcode

    @property
    def name(self) -> str:
        return self.spec.name

    def __repr__(self) -> str:
        return f"Command({self.spec.name}, {list(self.data)})"


#: What an argument must be, said before its range in a refusal ("an integer in -500..500")
_INTEGER = "an integer (int, or a type with __index__ such as numpy's; not a bool)"


def _as_int(value: object) -> int | None:
    """``value`` as a plain int, or None if it is no integer. Anything with ``__index__`` is
    one (``numpy.int64`` from a computed velocity, an IntEnum); a bool is not (``True`` for
    a velocity is a slip), nor is a float or a Decimal (no ``__index__``: never rounded)."""
    if type(value) is int:  # nearly every argument: no further test (Drive takes this way)
        return value
    # the type's own __index__, not isinstance(value, SupportsIndex): a runtime protocol
    # check costs thousands of instructions, paid per Drive (bench.icount: +0.5 % a tick)
    if isinstance(value, bool) or getattr(type(value), "__index__", None) is None:
        return None
    try:
        return operator.index(cast("SupportsIndex", value))
    except TypeError:  # an __index__ that refuses (numpy's bool_ has one, which raises)
        return None


def _check(spec: CommandSpec, arg: ArgSpec, value: object) -> int:
    number = _as_int(value)
    if number is None:
        raise EncodeError(spec.name, arg.name, f"{_INTEGER} {arg.allowed}", value)
    if not arg.accepts(number):
        raise EncodeError(spec.name, arg.name, arg.allowed, value)
    return number


def _spec(command: int | str | CommandSpec) -> CommandSpec:
    if isinstance(command, CommandSpec):
        return command
    try:
        return COMMANDS[command] if isinstance(command, int) else COMMANDS_BY_NAME[command]
    except (KeyError, TypeError):
        raise EncodeError("encode", "command", "a known opcode or command name", command) from None


#: How a command of the table with fixed arguments only is checked and packed: the table's
#: entry, the Struct of its bytes and each argument's (minimum, maximum).
_FixedForm = tuple[CommandSpec, struct.Struct, tuple[tuple[int, int], ...]]


def _fixed_form(spec: CommandSpec) -> _FixedForm | None:
    """``spec``'s :data:`_FixedForm`, or None for a command :func:`encode` always checks in
    full: Drive (137, whose radius has special values), the tails of Song, Stream and Query
    List, an argument limited to chosen values (a packet id)."""
    if spec.opcode == 137 or spec.tail is not None:
        return None
    if any(arg.choices is not None for arg in spec.args):
        return None
    packer = struct.Struct(">B" + "".join(arg.code for arg in spec.args))
    return spec, packer, tuple((arg.minimum, arg.maximum) for arg in spec.args)


#: :func:`_fixed_form` of each opcode that has one (built at import: about 30 Structs)
_FIXED_FORMS: dict[int, _FixedForm] = {
    opcode: form
    for opcode, form in ((opcode, _fixed_form(spec)) for opcode, spec in COMMANDS.items())
    if form is not None
}  # (a walrus here left its ``form`` a name of the module, in help() and the star import)


def encode(command: int | str | CommandSpec, *args: int, tail: Sequence[int] = ()) -> Command:
    """Encode ``command`` with its fixed arguments (in table order) and, for Song, Stream and
    Query List, the ``tail`` items whose count the fixed arguments give. Every value is
    checked before a byte is built; prefer the named helpers below.

    A command of fixed arguments only whose values are all plain integers within their
    limits (every Drive Direct a docking run sends) is packed by its prepared
    :data:`_FixedForm`, with no further call; anything else, and every error, goes the full
    way below, which says what is wrong. Drive Direct cost about 29,000 instructions the
    full way (callgrind), a few thousand this way."""
    if type(command) is int and type(tail) is tuple and not tail:
        form = _FIXED_FORMS.get(command)
        if form is not None:
            spec, packer, limits = form
            if len(args) == len(limits):
                for value, (low, high) in zip(args, limits):  # noqa: B905 (lengths equal)
                    # type(...) is int: not a bool, nor an int subclass (the full way's checks)
                    if type(value) is not int or not low <= value <= high:
                        break
                else:
                    return Command(spec, args, packer.pack(command, *args))
    spec = _spec(command)
    if len(args) != len(spec.args):
        names = ", ".join(a.name for a in spec.args)
        raise EncodeError(spec.name, "arguments", f"{len(spec.args)} values ({names})", len(args))
    if spec.opcode == 137:
        checked = [_check(spec, spec.args[0], args[0]), _radius(spec, args[1])]
        wire = [checked[0], checked[1] - 0x10000 if checked[1] > 0x7FFF else checked[1]]
    else:
        checked = [_check(spec, a, v) for a, v in zip(spec.args, args, strict=True)]
        wire = checked
    data = struct.pack(">B" + "".join(a.code for a in spec.args), spec.opcode, *wire)
    tail_values = _check_tail(spec, checked, tail)
    return Command(spec, tuple(checked) + tail_values, data + bytes(tail_values))


def _check_tail(spec: CommandSpec, checked: list[int], tail: Sequence[int]) -> tuple[int, ...]:
    # a tuple or a list is a Sequence: asked first, as CPython 3.11 answers isinstance(x,
    # Sequence) for a class registered with it directly (tuple: every command's default
    # tail) through three Python calls every time, never from its cache: about 4,600
    # instructions of the 29,000 that encoding a Drive Direct took (callgrind)
    kind = type(tail)
    if (
        kind is not tuple
        and kind is not list
        and (isinstance(tail, str) or not isinstance(tail, Sequence))
    ):
        raise EncodeError(spec.name, "data bytes", "a sequence of integers", tail)
    if spec.tail is None:
        if tail:
            raise EncodeError(spec.name, "data bytes", "none after the fixed arguments", list(tail))
        return ()
    expected = spec.tail_bytes(checked)
    if len(tail) != expected:
        items = " + ".join(a.name for a in spec.tail.item)
        raise EncodeError(
            spec.name, "data bytes", f"{expected} ({spec.tail.count_arg} x {items})", len(tail)
        )
    item = spec.tail.item
    return tuple(_check(spec, item[i % len(item)], v) for i, v in enumerate(tail))


def _radius(spec: CommandSpec, value: object) -> int:
    number = _as_int(value)
    if number is None:
        raise EncodeError(spec.name, "radius", f"{_INTEGER} {_RADIUS_ALLOWED}", value)
    if number in STRAIGHT_RADII:
        return 0x7FFF if number == 0x7FFF else 0x8000
    if not spec.args[1].accepts(number):
        raise EncodeError(spec.name, "radius", _RADIUS_ALLOWED, value)
    return number


def decode_command(data: bytes | bytearray) -> tuple[Command, int] | None:
    """The first command in ``data`` and the number of bytes it takes, or ``None`` while it is
    incomplete (the robot, too, waits for the missing data bytes).

    The robot's side of :func:`encode`: the opcode table says how many data bytes follow, and
    for Song / Stream / Query List the count byte says how many more. Raises
    :class:`EncodeError` for an unknown opcode or a value out of range."""
    size = command_size(data)
    if size is None:
        return None
    spec = _spec(data[0])
    fixed = spec.fixed_data_bytes
    values = list(struct.unpack_from(">" + "".join(a.code for a in spec.args), data, 1))
    if spec.opcode == 137 and values[1] == -0x8000:
        values[1] = 0x8000
    return encode(spec, *values, tail=list(data[1 + fixed : size])), size


def command_size(data: bytes | bytearray) -> int | None:
    """How many bytes the first command in ``data`` takes, or ``None`` while it is incomplete:
    :func:`decode_command`'s reading without the command built and checked (a replay's
    compare asks only where each command ends, once a command: building it cost a quarter of
    the replay). Raises :class:`EncodeError` for an unknown opcode or a count out of range."""
    if not data:
        return None
    spec = _spec(data[0])
    fixed = spec.fixed_data_bytes
    if len(data) < 1 + fixed:
        return None
    size = 1 + fixed
    if spec.tail is not None:  # the count must be valid before it says how much to wait for
        values = struct.unpack_from(">" + "".join(a.code for a in spec.args), data, 1)
        index = [a.name for a in spec.args].index(spec.tail.count_arg)
        _check(spec, spec.args[index], values[index])
        size += spec.tail_bytes(list(values))
    return size if len(data) >= size else None


# ----------------------------------------------------------------- named helpers


def _without_arguments(name: str) -> Callable[[], Command]:
    """The helper of an argument-less command: the table entry called ``name`` encoded once
    (its one opcode byte never changes), returned by every call."""
    command = encode(name)

    def helper() -> Command:
        return command

    helper.__doc__ = f"{command.spec.title} ({command.opcode}): ``{list(command.data)}``."
    return helper


start = _without_arguments("start")
reset = _without_arguments("reset")
stop = _without_arguments("stop")
control = _without_arguments("control")
safe = _without_arguments("safe")
full = _without_arguments("full")
power = _without_arguments("power")
spot = _without_arguments("spot")
clean = _without_arguments("clean")
max_clean = _without_arguments("max")
seek_dock = _without_arguments("seek_dock")


def baud(baud_code: int) -> Command:
    """Baud (129) by the spec's code, 0-11 (7 is 19200, 11 is 115200); :func:`baud_rate`
    takes the rate in bps. A program's connection changes it with ``Connection.set_baud``,
    which waits the 100 ms the spec asks and moves the port with it."""
    return encode(129, baud_code)


BAUD_CODES: dict[int, int] = {
    300: 0, 600: 1, 1200: 2, 2400: 3, 4800: 4, 9600: 5, 14400: 6, 19200: 7, 28800: 8,
    38400: 9, 57600: 10, 115200: 11,
}  # fmt: skip
#: The same table the other way round: the rate in bps each Baud (129) code sets.
BAUD_RATES: Mapping[int, int] = {code: rate for rate, code in BAUD_CODES.items()}


def baud_rate(rate: int) -> Command:
    """Baud (129) by rate in bps rather than code: ``baud_rate(57600) -> [129][10]``."""
    number = _as_int(rate)
    if number is None or number not in BAUD_CODES:
        raise EncodeError("baud", "rate", f"one of {sorted(BAUD_CODES)} bps", rate)
    return baud(BAUD_CODES[number])


def drive(velocity: int, radius: int | Radius) -> Command:
    """Drive (137). ``radius`` in -2000..2000 mm, or a :class:`Radius` special value.

    ``drive(-200, 500) -> [137][255][56][1][244]``;
    ``drive(200, Radius.STRAIGHT) -> [137][0][200][128][0]`` (never ``[7][208]``, 2000 mm)."""
    return encode(137, velocity, radius)


def drive_straight(velocity: int) -> Command:
    """Drive (137) straight at ``velocity`` mm/s, -500..500 (negative backs up): :func:`drive`
    with :attr:`Radius.STRAIGHT`, ``drive_straight(200) -> [137][0][200][128][0]``."""
    return encode(137, velocity, Radius.STRAIGHT)


def spin(velocity: int, clockwise: bool) -> Command:
    """Turn in place at wheel speed ``velocity`` (0..500 mm/s) in the direction ``clockwise``
    names. A negative speed is refused: on the wire it turns the other way (radius -1 with
    -100 turns counter-clockwise), so ``spin(-100, clockwise=True)`` would do the opposite
    of what it says; a caller who wants a signed speed uses :func:`drive` with a
    :class:`Radius`."""
    if not isinstance(clockwise, bool):
        raise EncodeError("drive", "clockwise", "True or False", clockwise)
    speed = _as_int(velocity)
    if speed is not None and speed < 0:
        raise EncodeError(
            "drive", "velocity", "0..500 mm/s for spin (clockwise gives the direction)", velocity
        )
    radius = Radius.TURN_CLOCKWISE if clockwise else Radius.TURN_COUNTER_CLOCKWISE
    return encode(137, velocity, radius)


def drive_direct(right_velocity: int, left_velocity: int) -> Command:
    """Drive Direct (145), right wheel first:
    ``drive_direct(100, -100) -> [145][0][100][255][156]``."""
    return encode(145, right_velocity, left_velocity)


def drive_pwm(right_pwm: int, left_pwm: int) -> Command:
    """Drive PWM (146), right wheel first, each -255..255 of the battery's voltage (255 full
    forward). No speed control: the speed follows the load and the charge, so odometry, not
    the value, says how far it went."""
    return encode(146, right_pwm, left_pwm)


def halt() -> Command:
    """Drive 0: what every safe ending sends. ``[137][0][0][0][0]``; encoded once (a command
    is immutable), as a leaf sends it on every halt."""
    return _HALT


_HALT = encode(137, 0, 0)


def turns_wheels(command: Command) -> bool:
    """Whether a command sets the wheels turning: Drive (137) with a velocity (its radius
    alone moves nothing: ``[137][0][0][128][0]`` stands still), Drive Direct (145) or Drive
    PWM (146) with either wheel's value; any other command (``spec.drives_wheels`` false)
    turns none. The one rule for the behaviours' halt, the tick guard, the run's wheels sent
    again and the tree's stop (``robot.hazards.sets_going``)."""
    spec = command.spec
    if spec.opcode == _HALT.opcode:
        return command.args[0] != 0
    return any(command.args) and spec.drives_wheels


def motors(motor_bits: int) -> Command:
    """Motors (138) from raw bits; see :func:`roomba_bt.oi.bits.motor_bits` for names."""
    return encode(138, motor_bits)


def motors_off() -> Command:
    """Motors (138) with no bit set, ``[138][0]``: side brush, main brush and vacuum off
    (what every safe ending sends after drive 0)."""
    return encode(138, 0)


def pwm_motors(main_brush_pwm: int, side_brush_pwm: int, vacuum_pwm: int) -> Command:
    """PWM Motors (144): the main and side brush -127..127 (negative turns one the other
    way), the vacuum 0..127, each a share of the battery's voltage (127 full)."""
    return encode(144, main_brush_pwm, side_brush_pwm, vacuum_pwm)


def leds(led_bits: int, power_color: int, power_intensity: int) -> Command:
    """LEDs (139), by name with ``led_bits``, which lives in :mod:`roomba_bt.oi.bits` (not
    here: ``oi.led_bits`` is no name)::

        from roomba_bt.oi.bits import led_bits

        leds(led_bits("dock"), 0, 128)  # [139][4][0][128]
    """
    return encode(139, led_bits, power_color, power_intensity)


def scheduling_leds(weekday_bits: int, scheduling_bits: int) -> Command:
    """Scheduling LEDs (162): the days, bit 0 Sunday to bit 6 Saturday (:func:`day_bits
    <roomba_bt.oi.bits.day_bits>`), and colon, PM, AM, clock and schedule, bits 0-4
    (:func:`scheduling_led_bits <roomba_bt.oi.bits.scheduling_led_bits>`)."""
    return encode(162, weekday_bits, scheduling_bits)


def _int_sequence(command: str, argument: str, values: object, length: int) -> list[int]:
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence):
        raise EncodeError(command, argument, f"a sequence of {length} integers", values)
    if len(values) != length:
        raise EncodeError(command, argument, f"{length} values", list(values))
    return list(values)


def digit_leds_raw(digits: Sequence[int]) -> Command:
    """Digit LEDs Raw (163): four segment masks, digit 3 (left) first. Broken on current Create 2
    and Roomba 500/600 firmware: see :func:`roomba_bt.oi.profiles.command_warning`."""
    return encode(163, *_int_sequence("digit_leds_raw", "digits", digits, 4))


def digit_leds_ascii(text: str) -> Command:
    """Digit LEDs ASCII (164): ``digit_leds_ascii("ABCD") -> [164][65][66][67][68]``.

    Shorter text is padded with spaces on the right; characters the display does not
    implement (``*``, ``+``, ``@`` and anything outside 32-126) are refused rather than shown
    as blanks."""
    if not isinstance(text, str) or len(text) > 4:
        raise EncodeError("digit_leds_ascii", "text", "a string of at most 4 characters", text)
    for ch in text:
        if ord(ch) not in DIGIT_ASCII:
            raise EncodeError(
                "digit_leds_ascii", "character", "printable ASCII 32-126 except * + @", ch
            )
    return encode(164, *(ord(c) for c in text.ljust(4)))


def buttons(button_bits: int) -> Command:
    """Buttons (165): pushes the robot's buttons, packet 18's bits (clean, spot, dock, minute,
    hour, day, schedule, clock from bit 0; :func:`button_bits
    <roomba_bt.oi.bits.button_bits>`); the robot releases them itself."""
    return encode(165, button_bits)


@dataclass(frozen=True, slots=True)
class Note:
    """A song note: MIDI number (31-127 sound, anything else in 0-255 is a rest:
    :data:`~roomba_bt.oi.opcodes.PLAYABLE_NOTES`) and duration in 1/64 s."""

    number: int
    duration: int


NOTE_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")
#: the MIDI numbers a name of :func:`note_number` stands for: C0 (12) to B9 (131)
NAMED_NOTES = range(12, 12 * 11)


def note_name(number: int) -> str:
    """``note_name(69) == "A4"``: the inverse of :func:`note_number` (0: ``rest``). A number
    no name stands for (11 would be ``B-1``, 132 ``C10``, which :func:`note_number` refuses)
    is an :class:`EncodeError`."""
    if number == 0:
        return "rest"
    note = _as_int(number)
    if note is None or note not in NAMED_NOTES:
        raise EncodeError(
            "song", "note", f"0 (rest) or {NAMED_NOTES[0]} (C0) to {NAMED_NOTES[-1]} (B9)", number
        )
    return f"{NOTE_NAMES[note % 12]}{note // 12 - 1}"


def note_number(name: str) -> int:
    """MIDI number of a note written like ``"A4"`` (69), ``"C#5"`` or ``"rest"`` (0)."""
    if not isinstance(name, str) or len(name) < 2:
        raise EncodeError("song", "note", "a name like A4, C#5 or rest", name)
    if name.lower() == "rest":
        return 0
    pitch, octave = name[:-1].upper(), name[-1]
    if pitch not in NOTE_NAMES or not octave.isdigit():
        raise EncodeError("song", "note", "a name like A4, C#5 or rest", name)
    return 12 * (int(octave) + 1) + NOTE_NAMES.index(pitch)


def song(song_number: int, notes: Sequence[Note | tuple[int, int]]) -> Command:
    """Song (140): ``[140][number][length][note 1][duration 1]...``; 1-16 notes, each a
    MIDI number 0-255 (31-127 sound; any other is a rest, as the spec defines it, and is sent
    as it is) and a duration 0-255 in 1/64 s. A value outside a byte is an
    :class:`EncodeError` naming it (``note_number``, ``note_duration``): nothing is built.

    ``song(0, [(60, 32)]) -> [140][0][1][60][32]`` (middle C for half a second)."""
    lengths = f"{SONG_LENGTH.minimum} to {SONG_LENGTH.maximum}"
    if isinstance(notes, (str, bytes)) or not isinstance(notes, Sequence):
        raise EncodeError("song", "notes", f"a sequence of {lengths} (note, duration) pairs", notes)
    if not SONG_LENGTH.minimum <= len(notes) <= SONG_LENGTH.maximum:
        raise EncodeError("song", "notes", f"{lengths} notes", len(notes))
    tail: list[int] = []
    for note in notes:
        if isinstance(note, Note):
            tail += (note.number, note.duration)
        elif isinstance(note, tuple) and len(note) == 2:
            if isinstance(note[0], str):  # a name, as a mission writes it: said how to give it
                raise EncodeError("song", "note_number", _named_note_said(note[0]), note[0])
            tail += note
        else:
            raise EncodeError("song", "note", "a Note or a (number, duration) pair", note)
    return encode(140, song_number, len(notes), tail=tail)


def _named_note_said(name: str) -> str:
    """What :func:`song` says of a note given by name (``("C4", 16)``): a MIDI number, and
    the call that gives the name's (``note_number('C4')``, 60)."""
    try:
        return f"a MIDI number 0-255 (note_number({name!r}) gives {note_number(name)})"
    except EncodeError:
        return "a MIDI number 0-255 (note_number('C4') gives one for a name like C4, C#5 or rest)"


def song_seconds(command: Command) -> float:
    """How long the song a Song (140) command defines plays: its notes' durations (every
    second byte of the tail, in 1/64 s) summed. ``song_seconds(song(0, [(60, 32)])) == 0.5``."""
    if command.spec.opcode != 140:
        raise EncodeError("song_seconds", "command", "a Song (140) command", command)
    return sum(command.data[4::2]) / NOTE_STEPS_PER_SECOND


def play(song_number: int) -> Command:
    """Play (141) song 0-4, stored before with :func:`song`; in Safe or Full only (a song may
    be stored in Passive)."""
    return encode(141, song_number)


def _packet_ids(command: str, packet_ids: Iterable[int]) -> list[int]:
    if isinstance(packet_ids, str) or not isinstance(packet_ids, Iterable):
        raise EncodeError(command, "packet ids", "a list of packet ids", packet_ids)
    ids = list(packet_ids)
    if len(ids) > 255:
        raise EncodeError(command, "packet ids", "at most 255 ids", len(ids))
    return ids


def sensors(packet_id: int) -> Command:
    """Sensors (142): ``sensors(100) -> [142][100]``; the reply has no header or checksum."""
    return encode(142, packet_id)


def query_list(packet_ids: Iterable[int]) -> Command:
    """Query List (149): ``query_list([7, 13]) -> [149][2][7][13]``."""
    ids = _packet_ids("query_list", packet_ids)
    return encode(149, len(ids), tail=ids)


def stream(packet_ids: Iterable[int]) -> Command:
    """Stream (148): ``stream([29, 13]) -> [148][2][29][13]``. See
    :func:`roomba_bt.oi.stream.check_bandwidth` for the 15 ms budget. A list whose ids and
    data pass 255 bytes is refused: n-bytes could not say it, so the robot could never send
    a frame of it (``[100, 100, 100, 100]``, 324 bytes, was encoded)."""
    # here, not at the top: frames imports profiles, which imports this module's baud codes
    from roomba_bt.oi.frames import refuse_unframeable, stream_frame_size

    ids = _packet_ids("stream", packet_ids)
    command = encode(148, len(ids), tail=ids)  # each id checked first, with its own message
    refuse_unframeable(stream_frame_size(ids) - 3)
    return command


def pause_stream() -> Command:
    """Pause/Resume Stream (150) 0: the stream stops and keeps its packet list
    (:func:`resume_stream` starts it again). ``Connection.query`` needs it paused."""
    return encode(150, 0)


def resume_stream() -> Command:
    """Pause/Resume Stream (150) 1: the stream paused by :func:`pause_stream` goes on, with
    the packet list the last Stream (148) gave."""
    return encode(150, 1)


_DAYS = ("sun", "mon", "tue", "wed", "thu", "fri", "sat")
#: a day as written: its three letters or its whole English name, any case ("Monday" is
#: "mon"; "monkey" is no day: it was Monday by its first three letters)
_DAY_NAMES = {
    **{day: day for day in _DAYS},
    **{
        name: name[:3]
        for name in ("sunday", "monday", "tuesday", "wednesday", "thursday", "friday",
                     "saturday")
    },
}  # fmt: skip


def _day_name(command: str, day: object) -> str:
    name = _DAY_NAMES.get(day.lower()) if isinstance(day, str) else None
    if name is None:
        allowed = f"one of {', '.join(_DAYS)}, or a day's whole name (monday)"
        raise EncodeError(command, "day", allowed, day)
    return name


def schedule(times: Mapping[str, tuple[int, int]]) -> Command:
    """Schedule (167) from ``{"wed": (15, 0), "fri": (10, 36)}``; ``{}`` disables it.

    The spec's example, Wednesday 15:00 and Friday 10:36, is
    ``[167][40][0][0][0][0][0][0][15][0][0][0][10][36][0][0]``."""
    if not isinstance(times, Mapping):
        raise EncodeError("schedule", "times", "a mapping of day -> (hour, minute)", times)
    normal: dict[str, tuple[int, int]] = {}
    for day, at in times.items():
        name = _day_name("schedule", day)
        if name in normal:  # "mon" and "Monday": one would have been kept without a word
            raise EncodeError("schedule", "day", "each day once", f"{name} twice ({day!r})")
        if not (isinstance(at, tuple) and len(at) == 2):
            raise EncodeError("schedule", f"{name} time", "an (hour, minute) pair", at)
        normal[name] = at
    args: list[int] = [day_bits(*normal)]
    for day in _DAYS:
        hour, minute = normal.get(day, (0, 0))
        args += (hour, minute)
    return encode(167, *args)


def schedule_times(data: bytes | bytearray) -> dict[str, tuple[int, int]]:
    """The robot's side of :func:`schedule`: the 15 data bytes of Schedule (167) as the days
    it cleans on and their (hour, minute), Sunday first; ``{}`` for a schedule disabled.
    A day whose bit is clear cleans at no time, whatever its bytes say::

        [40][0][0][0][0][0][0][15][0][0][0][10][36][0][0]  ->  {"wed": (15, 0), "fri": (10, 36)}
    """
    days, times = data[0], data[1:]
    return {day: (times[2 * i], times[2 * i + 1]) for i, day in enumerate(_DAYS) if days >> i & 1}


def day_number(day: str, command: str = "set_day_time") -> int:
    """A day as written, its three letters or its whole English name in any case, as the OI
    numbers it: ``day_number("Wednesday") == 3`` (0 Sunday .. 6 Saturday). Anything else
    is an :class:`EncodeError` of ``command`` saying what is allowed."""
    return _DAYS.index(_day_name(command, day))


def set_day_time(day: int | str, hour: int, minute: int) -> Command:
    """Set Day/Time (168): ``set_day_time("wed", 15, 0) -> [168][3][15][0]``."""
    if isinstance(day, str):
        day = day_number(day)
    return encode(168, day, hour, minute)


#: What a 0.1.0 spelling's call says (the CLI shows this one DeprecationWarning, which Python
#: hides by default outside ``__main__``: its readers are plugin authors running roomba-bt).
ENCODE_MODULE_CALLED = (
    "roomba_bt.oi.encode is the encoder's module since 0.2.0, and calling it as 0.1.0's "
    "function is deprecated (it goes in a later release): call "
    "roomba_bt.oi.encode.encode(...) (`from roomba_bt.oi.encode import encode`) or a named "
    "helper such as roomba_bt.commands.leds(...)"
)


class _CallableForOldPlugins(types.ModuleType):
    """This module's class: a module that 0.1.0's ``from roomba_bt.oi import encode`` (then
    the function) can still call, as the plugins written for 0.1.0 do, with a warning that
    names the new spelling. Without it their first ``encode(...)`` raised Python's bare
    "'module' object is not callable" mid-run (on a robot, maybe an hour into a mission)."""

    def __call__(
        self, command: int | str | CommandSpec, *args: int, tail: Sequence[int] = ()
    ) -> Command:
        warnings.warn(ENCODE_MODULE_CALLED, DeprecationWarning, stacklevel=2)
        return encode(command, *args, tail=tail)


sys.modules[__name__].__class__ = _CallableForOldPlugins
