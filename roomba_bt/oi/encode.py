"""The encoder: typed arguments in, exact bytes out, or an :class:`EncodeError` and no bytes.

Every command goes through :func:`encode`, which checks each argument against the opcode table
(type and range) before a single byte is built, so a malformed sequence (one the robot would
sit waiting on for its missing data bytes) cannot be produced. The named helpers below give
readable arguments (special radii, LEDs and motors by name, songs as notes, days, ASCII).

Drive (137), velocity -200 mm/s, radius 500 mm (the spec's example)::

    [137][0xFF][0x38][0x01][0xF4]  ==  [137][255][56][1][244]
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum
from typing import Iterable, Sequence

from roomba_bt.oi.bits import DIGIT_ASCII, day_bits
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.opcodes import COMMANDS, COMMANDS_BY_NAME, ArgSpec, CommandSpec
from roomba_bt.oi.packets import GROUPS, VALID_PACKET_IDS


class Radius(IntEnum):
    """Drive (137)'s special radii, sent as is and never clamped into -2000..2000."""

    STRAIGHT = 0x8000  # 32768; 0x7FFF (32767) means straight too
    STRAIGHT_ALT = 0x7FFF
    TURN_CLOCKWISE = -1
    TURN_COUNTER_CLOCKWISE = 1


_STRAIGHT_VALUES = frozenset({0x8000, 0x7FFF, -0x8000})


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


def _check(spec: CommandSpec, arg: ArgSpec, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise EncodeError(
            spec.name, arg.name, f"an integer in {arg.minimum}..{arg.maximum}", value
        )
    if not arg.minimum <= value <= arg.maximum:
        unit = f" {arg.unit}" if arg.unit and arg.unit != "bits" else ""
        raise EncodeError(spec.name, arg.name, f"in {arg.minimum}..{arg.maximum}{unit}", value)
    return value


def _spec(command: int | str | CommandSpec) -> CommandSpec:
    if isinstance(command, CommandSpec):
        return command
    try:
        return COMMANDS[command] if isinstance(command, int) else COMMANDS_BY_NAME[command]
    except KeyError:
        raise EncodeError("encode", "command", "a known opcode or command name", command) from None


def encode(command: int | str | CommandSpec, *args: int, tail: Sequence[int] = ()) -> Command:
    """Encode ``command`` with its fixed arguments (in table order) and, for variable-length
    commands, the checked ``tail`` bytes. Prefer the named helpers below."""
    spec = _spec(command)
    if len(args) != len(spec.args):
        raise EncodeError(
            spec.name, "arguments", f"{len(spec.args)} values ({', '.join(a.name for a in spec.args)})",
            len(args),
        )  # fmt: skip
    if is_drive := (spec.opcode == 137):
        checked = [_check(spec, spec.args[0], args[0]), _radius(spec, args[1])]
    else:
        checked = [_check(spec, a, v) for a, v in zip(spec.args, args)]
    if spec.variable is None and tail:
        raise EncodeError(spec.name, "data bytes", "none beyond the fixed arguments", list(tail))
    fmt = ">B" + "".join(a.code for a in spec.args)
    values = list(checked)
    if is_drive:
        values[1] = values[1] - 0x10000 if values[1] > 0x7FFF else values[1]
    data = struct.pack(fmt, spec.opcode, *values)
    for b in tail:
        if isinstance(b, bool) or not isinstance(b, int) or not 0 <= b <= 255:
            raise EncodeError(spec.name, "data byte", "an integer in 0..255", b)
    return Command(spec, tuple(checked) + tuple(tail), data + bytes(tail))


def _radius(spec: CommandSpec, value: object) -> int:
    if isinstance(value, Radius):
        return int(value) if value is not Radius.STRAIGHT_ALT else 0x7FFF
    if isinstance(value, int) and not isinstance(value, bool) and value in _STRAIGHT_VALUES:
        return 0x8000 if value != 0x7FFF else 0x7FFF
    return _check(spec, spec.args[1], value)


# ----------------------------------------------------------------- named helpers


def start() -> Command:
    return encode(128)


def reset() -> Command:
    return encode(7)


def stop() -> Command:
    return encode(173)


def baud(baud_code: int) -> Command:
    return encode(129, baud_code)


BAUD_CODES: dict[int, int] = {
    300: 0, 600: 1, 1200: 2, 2400: 3, 4800: 4, 9600: 5, 14400: 6, 19200: 7, 28800: 8,
    38400: 9, 57600: 10, 115200: 11,
}  # fmt: skip


def baud_rate(rate: int) -> Command:
    """Baud (129) by rate in bps rather than code."""
    if rate not in BAUD_CODES:
        raise EncodeError("baud", "rate", f"one of {sorted(BAUD_CODES)}", rate)
    return baud(BAUD_CODES[rate])


def control() -> Command:
    return encode(130)


def safe() -> Command:
    return encode(131)


def full() -> Command:
    return encode(132)


def power() -> Command:
    return encode(133)


def spot() -> Command:
    return encode(134)


def clean() -> Command:
    return encode(135)


def max_clean() -> Command:
    return encode(136)


def seek_dock() -> Command:
    return encode(143)


def drive(velocity: int, radius: int | Radius) -> Command:
    """Drive (137). ``radius`` in -2000..2000 mm, or a :class:`Radius` special value."""
    return encode(137, velocity, radius)


def drive_straight(velocity: int) -> Command:
    return encode(137, velocity, Radius.STRAIGHT)


def spin(velocity: int, clockwise: bool) -> Command:
    """Turn in place; ``velocity`` is the wheel speed (its sign flips the direction)."""
    return encode(137, velocity, Radius.TURN_CLOCKWISE if clockwise else Radius.TURN_COUNTER_CLOCKWISE)


def drive_direct(right_velocity: int, left_velocity: int) -> Command:
    return encode(145, right_velocity, left_velocity)


def drive_pwm(right_pwm: int, left_pwm: int) -> Command:
    return encode(146, right_pwm, left_pwm)


def halt() -> Command:
    """Drive 0: what every safe ending sends. ``[137][0][0][0][0]``."""
    return encode(137, 0, 0)


def motors(motor_bits: int) -> Command:
    return encode(138, motor_bits)


def motors_off() -> Command:
    return encode(138, 0)


def pwm_motors(main_brush_pwm: int, side_brush_pwm: int, vacuum_pwm: int) -> Command:
    return encode(144, main_brush_pwm, side_brush_pwm, vacuum_pwm)


def leds(led_bits: int, power_color: int, power_intensity: int) -> Command:
    return encode(139, led_bits, power_color, power_intensity)


def scheduling_leds(weekday_bits: int, scheduling_bits: int) -> Command:
    return encode(162, weekday_bits, scheduling_bits)


def digit_leds_raw(digits: Sequence[int]) -> Command:
    """Digit LEDs Raw (163): four segment masks, digit 3 (left) first."""
    if len(digits) != 4:
        raise EncodeError("digit_leds_raw", "digits", "4 segment masks", list(digits))
    return encode(163, *digits)


def digit_leds_ascii(text: str) -> Command:
    """Digit LEDs ASCII (164): ``digit_leds_ascii("ABCD") -> [164][65][66][67][68]``.

    Shorter text is padded with spaces on the right; characters the display does not
    implement are refused rather than shown as blanks."""
    if not isinstance(text, str) or len(text) > 4:
        raise EncodeError("digit_leds_ascii", "text", "a string of at most 4 characters", text)
    padded = text.ljust(4)
    for ch in padded:
        if ord(ch) not in DIGIT_ASCII:
            raise EncodeError(
                "digit_leds_ascii", "character", "printable ASCII 32-126 except * + @", ch
            )
    return encode(164, *(ord(c) for c in padded))


def buttons(button_bits: int) -> Command:
    return encode(165, button_bits)


@dataclass(frozen=True, slots=True)
class Note:
    """A song note: MIDI number (31-127 sound, anything else in 0-255 is a rest) and
    duration in 1/64 s."""

    number: int
    duration: int


NOTE_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")


def note_number(name: str) -> int:
    """MIDI number of a note written like ``"A4"``, ``"C#5"`` or ``"rest"`` (0)."""
    if name.lower() == "rest":
        return 0
    pitch, octave = name[:-1].upper().replace("B#", "C"), name[-1]
    if pitch not in NOTE_NAMES or not octave.isdigit():
        raise EncodeError("song", "note", "a name like A4, C#5 or rest", name)
    return 12 * (int(octave) + 1) + NOTE_NAMES.index(pitch)


def song(song_number: int, notes: Sequence[Note | tuple[int, int]]) -> Command:
    """Song (140): ``[140][number][length][note1][dur1]...``; 1-16 notes."""
    if not 1 <= len(notes) <= 16:
        raise EncodeError("song", "notes", "1 to 16 notes", len(notes))
    tail: list[int] = []
    for note in notes:
        number, duration = (note.number, note.duration) if isinstance(note, Note) else note
        for label, v in (("note number", number), ("note duration", duration)):
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 255:
                raise EncodeError("song", label, "an integer in 0..255", v)
        tail += (number, duration)
    return encode(140, song_number, len(notes), tail=tail)


def play(song_number: int) -> Command:
    return encode(141, song_number)


def _packet_list(command: str, packet_ids: Iterable[int], minimum: int) -> list[int]:
    ids = list(packet_ids)
    if len(ids) < minimum or len(ids) > 255:
        raise EncodeError(command, "packet ids", f"{minimum} to 255 ids", len(ids))
    for pid in ids:
        if pid not in VALID_PACKET_IDS:
            raise EncodeError(
                command, "packet id", f"one of 7-58 or groups {sorted(GROUPS)}", pid
            )
    return ids


def sensors(packet_id: int) -> Command:
    _packet_list("sensors", [packet_id], 1)
    return encode(142, packet_id)


def query_list(packet_ids: Iterable[int]) -> Command:
    """Query List (149): ``query_list([7, 13]) -> [149][2][7][13]``."""
    ids = _packet_list("query_list", packet_ids, 1)
    return encode(149, len(ids), tail=ids)


def stream(packet_ids: Iterable[int]) -> Command:
    """Stream (148): ``stream([29, 13]) -> [148][2][29][13]``. See
    :func:`roomba_bt.oi.stream.check_bandwidth` for the 15 ms budget."""
    ids = _packet_list("stream", packet_ids, 0)
    return encode(148, len(ids), tail=ids)


def pause_stream() -> Command:
    return encode(150, 0)


def resume_stream() -> Command:
    return encode(150, 1)


def schedule(times: dict[str, tuple[int, int]]) -> Command:
    """Schedule (167) from ``{"wed": (15, 0), "fri": (10, 36)}``; ``{}`` disables it.

    The spec's example, Wednesday 15:00 and Friday 10:36, is
    ``[167][40][0][0][0][0][0][0][15][0][0][0][10][36][0][0]``."""
    days = ("sun", "mon", "tue", "wed", "thu", "fri", "sat")
    unknown = [d for d in times if d.lower()[:3] not in days]
    if unknown:
        raise EncodeError("schedule", "day", f"one of {', '.join(days)}", unknown[0])
    normal = {d.lower()[:3]: t for d, t in times.items()}
    args: list[int] = [day_bits(*normal)]
    for day in days:
        hour, minute = normal.get(day, (0, 0))
        args += (hour, minute)
    return encode(167, *args)


def set_day_time(day: int | str, hour: int, minute: int) -> Command:
    days = ("sun", "mon", "tue", "wed", "thu", "fri", "sat")
    if isinstance(day, str):
        if day.lower()[:3] not in days:
            raise EncodeError("set_day_time", "day", f"one of {', '.join(days)}", day)
        day = days.index(day.lower()[:3])
    return encode(168, day, hour, minute)
