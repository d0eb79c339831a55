"""Out-of-range and wrong-typed arguments, for every argument of every command, read from the
opcode table itself (so a new entry is covered the day it is added). Each must raise
:class:`EncodeError` naming the command, the argument, what is allowed and the value given;
no :class:`Command` (no byte) is ever produced."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from roomba_bt.oi import commands as c
from roomba_bt.oi.bits import day_bits, led_bits
from roomba_bt.oi.encode import command_size, decode_command, encode
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.opcodes import COMMANDS, ArgSpec, CommandSpec

WRONG_TYPES: list[object] = [1.5, "7", True, None, b"\x01", [1]]


def _valid(arg: ArgSpec) -> int:
    """A value the argument accepts (the smallest allowed)."""
    if arg.choices is not None:
        return min(arg.choices)
    return max(arg.minimum, 1) if arg.name in ("packet_count", "song_length") else arg.minimum


def _valid_args(spec: CommandSpec) -> list[int]:
    return [_valid(a) for a in spec.args]


def _valid_tail(spec: CommandSpec, args: list[int]) -> list[int]:
    if spec.tail is None:
        return []
    item = spec.tail.item
    return [_valid(item[i % len(item)]) for i in range(spec.tail_bytes(args))]


def _bad_values(arg: ArgSpec) -> list[object]:
    bad: list[object] = [arg.minimum - 1, arg.maximum + 1, *WRONG_TYPES]
    if arg.choices is not None:
        bad += [v for v in range(arg.minimum, arg.maximum + 1) if v not in arg.choices]
    return bad


ARG_CASES = [
    pytest.param(spec, i, value, id=f"{spec.name}-{arg.name}-{value!r}")
    for spec in COMMANDS.values()
    for i, arg in enumerate(spec.args)
    for value in _bad_values(arg)
]


def test_the_baseline_arguments_are_valid() -> None:
    for spec in COMMANDS.values():
        args = _valid_args(spec)
        command = encode(spec, *args, tail=_valid_tail(spec, args))
        assert command.opcode == spec.opcode


@pytest.mark.parametrize(("spec", "index", "value"), ARG_CASES)
def test_every_argument_refuses_bad_values(spec: CommandSpec, index: int, value: object) -> None:
    args: list[object] = list(_valid_args(spec))
    args[index] = value
    arg = spec.args[index]
    with pytest.raises(EncodeError) as caught:
        encode(spec, *args)  # type: ignore[arg-type]
    error = caught.value
    assert error.command == spec.name
    assert error.argument == arg.name
    assert error.value == value or error.value is value
    message = str(error)
    assert message.startswith(f"{spec.name}: {arg.name} must be ")
    assert repr(value) in message
    if arg.choices is None:
        assert f"{arg.minimum}..{arg.maximum}" in message


TAIL_COMMANDS = [s for s in COMMANDS.values() if s.tail is not None]


@pytest.mark.parametrize("spec", TAIL_COMMANDS, ids=lambda s: s.name)
def test_a_tail_must_match_its_count(spec: CommandSpec) -> None:
    args = _valid_args(spec)
    tail = _valid_tail(spec, args)
    for wrong in (tail[:-1], [*tail, tail[0]], []):
        if len(wrong) == len(tail):
            continue
        with pytest.raises(EncodeError, match=rf"^{spec.name}: data bytes must be {len(tail)} "):
            encode(spec, *args, tail=wrong)


@pytest.mark.parametrize("spec", TAIL_COMMANDS, ids=lambda s: s.name)
def test_every_tail_item_is_checked(spec: CommandSpec) -> None:
    assert spec.tail is not None
    args = _valid_args(spec)
    tail = _valid_tail(spec, args)
    for position, arg in enumerate(spec.tail.item):
        for value in _bad_values(arg):
            wrong: list[object] = list(tail)
            wrong[position] = value
            with pytest.raises(EncodeError) as caught:
                encode(spec, *args, tail=wrong)  # type: ignore[arg-type]
            assert caught.value.argument == arg.name
            assert caught.value.value == value or caught.value.value is value


@pytest.mark.parametrize(
    "spec", [s for s in COMMANDS.values() if s.tail is None], ids=lambda s: s.name
)
def test_fixed_commands_take_no_tail(spec: CommandSpec) -> None:
    with pytest.raises(EncodeError, match="none after the fixed arguments"):
        encode(spec, *_valid_args(spec), tail=[0])


@pytest.mark.parametrize("spec", list(COMMANDS.values()), ids=lambda s: s.name)
def test_the_argument_count_is_checked(spec: CommandSpec) -> None:
    with pytest.raises(EncodeError, match=rf"^{spec.name}: arguments must be {len(spec.args)} "):
        encode(spec, *_valid_args(spec), 0)


def test_unknown_commands() -> None:
    for unknown in (147, 151, 0, "fly", 3.0):
        with pytest.raises(EncodeError, match="a known opcode or command name"):
            encode(unknown)  # type: ignore[arg-type]
    with pytest.raises(EncodeError):
        decode_command(bytes([147]))  # Digital Outputs: removed from the OI
    with pytest.raises(EncodeError):
        command_size(bytes([147]))
    with pytest.raises(EncodeError):  # a song of 17 notes: its count is out of range
        command_size(bytes([140, 0, 17]))


HELPER_ERRORS: list[tuple[str, Callable[[], object], str]] = [
    ("radius 2001 is not straight", lambda: c.drive(100, 2001), "radius"),
    ("radius 32766", lambda: c.drive(100, 32766), "radius"),
    ("radius as float", lambda: c.drive(100, 1.0), "radius"),  # type: ignore[arg-type]
    ("velocity 501", lambda: c.drive_straight(501), "velocity"),
    ("spin direction not bool", lambda: c.spin(100, 1), "clockwise"),  # type: ignore[arg-type]
    # a negative speed turned the other way than ``clockwise`` says
    ("spin negative clockwise", lambda: c.spin(-100, clockwise=True), "velocity"),
    ("spin negative counter-clockwise", lambda: c.spin(-100, clockwise=False), "velocity"),
    ("baud rate not in table", lambda: c.baud_rate(9601), "rate"),
    ("baud code 12", lambda: c.baud(12), "baud_code"),
    ("digit '*' not displayable", lambda: c.digit_leds_ascii("A*"), "character"),
    ("digit '+' not displayable", lambda: c.digit_leds_ascii("+"), "character"),
    ("digit '@' not displayable", lambda: c.digit_leds_ascii("@"), "character"),
    ("digit non-ASCII", lambda: c.digit_leds_ascii("é"), "character"),
    ("digit text too long", lambda: c.digit_leds_ascii("ABCDE"), "text"),
    ("digit text not str", lambda: c.digit_leds_ascii(1234), "text"),  # type: ignore[arg-type]
    ("raw digits: 3 masks", lambda: c.digit_leds_raw([1, 2, 3]), "digits"),
    ("raw digits: not a list", lambda: c.digit_leds_raw(5), "digits"),  # type: ignore[arg-type]
    ("raw digit 256", lambda: c.digit_leds_raw([0, 0, 0, 256]), "digit_0_bits"),
    ("song of 0 notes", lambda: c.song(0, []), "notes"),
    ("song of 17 notes", lambda: c.song(0, [(60, 8)] * 17), "notes"),
    ("song number 5", lambda: c.song(5, [(60, 8)]), "song_number"),
    ("song note 256", lambda: c.song(0, [(256, 8)]), "note_number"),
    ("song duration -1", lambda: c.song(0, [(60, -1)]), "note_duration"),
    ("song note malformed", lambda: c.song(0, [(60,)]), "note"),  # type: ignore[list-item]
    ("song notes a string", lambda: c.song(0, "C4"), "notes"),  # type: ignore[arg-type]
    ("note name", lambda: c.note_number("H2"), "note"),
    ("note name empty", lambda: c.note_number(""), "note"),
    ("no name for MIDI 11 (B-1)", lambda: c.note_name(11), "note"),
    ("no name for MIDI 132 (C10)", lambda: c.note_name(132), "note"),
    ("no name for a byte's 300", lambda: c.note_name(300), "note"),
    ("play 5", lambda: c.play(5), "song_number"),
    ("stream group 102", lambda: c.stream([102]), "packet_id"),
    ("stream 256 ids", lambda: c.stream([7] * 256), "packet ids"),
    ("stream ids a string", lambda: c.stream("7"), "packet ids"),  # type: ignore[arg-type]
    ("query list empty", lambda: c.query_list([]), "packet_count"),
    ("query packet 59", lambda: c.query_list([59]), "packet_id"),
    ("sensors 105", lambda: c.sensors(105), "packet_id"),
    ("schedule day", lambda: c.schedule({"someday": (1, 0)}), "day"),
    ("schedule day's first letters", lambda: c.schedule({"monkey": (1, 0)}), "day"),
    ("schedule day twice", lambda: c.schedule({"mon": (1, 0), "Monday": (2, 0)}), "day"),
    ("set_day_time day's first letters", lambda: c.set_day_time("wedge", 1, 0), "day"),
    ("schedule hour 24", lambda: c.schedule({"mon": (24, 0)}), "mon_hour"),
    ("schedule minute 60", lambda: c.schedule({"sun": (1, 60)}), "sun_minute"),
    ("schedule time shape", lambda: c.schedule({"sun": 10}), "sun time"),  # type: ignore[dict-item]
    ("schedule not a mapping", lambda: c.schedule([("sun", (1, 0))]), "times"),  # type: ignore[arg-type]
    ("set day name", lambda: c.set_day_time("funday", 1, 0), "day"),
    ("set day 7", lambda: c.set_day_time(7, 1, 0), "day"),
    ("led name", lambda: c.leds(led_bits("home"), 0, 0), "led_bits"),
    ("day name not str", lambda: day_bits(3), "day_bits"),  # type: ignore[arg-type]
    ("pwm vacuum negative", lambda: c.pwm_motors(0, 0, -1), "vacuum_pwm"),
    ("motors 32", lambda: c.motors(32), "motor_bits"),
    # n-bytes is one byte: 4 x group 100 (324 bytes), 5 x group 6 (265) cannot be framed
    ("stream of 324 bytes", lambda: c.stream([100] * 4), "packet ids"),
    ("stream of 265 bytes", lambda: c.stream([6] * 5), "packet ids"),
    ("stream of 264 bytes", lambda: c.stream(list(range(7, 59)) * 2), "packet ids"),
]


@pytest.mark.parametrize(
    ("build", "argument"), [pytest.param(b, a, id=label) for label, b, a in HELPER_ERRORS]
)
def test_named_helpers_refuse_bad_input(build: Callable[[], object], argument: str) -> None:
    with pytest.raises(EncodeError) as caught:
        build()
    assert caught.value.argument == argument
    assert " must be " in str(caught.value)


def test_motor_bits_take_booleans_only() -> None:
    from roomba_bt.oi.bits import motor_bits

    with pytest.raises(EncodeError, match="side_brush"):
        motor_bits(side_brush=2)  # type: ignore[arg-type]


class _Index:
    """An integer type that is no ``int`` (as ``numpy.int64`` is not): it has ``__index__``."""

    def __init__(self, value: int) -> None:
        self.value = value

    def __index__(self) -> int:
        return self.value

    def __repr__(self) -> str:
        return f"_Index({self.value})"


def test_anything_with_index_is_an_integer_argument() -> None:
    """A velocity computed with numpy (``np.int64(200)``) was refused as "must be an integer"."""
    assert c.drive(_Index(200), _Index(100)).data == c.drive(200, 100).data  # type: ignore[arg-type]
    assert c.drive_direct(_Index(-100), _Index(100)).data == bytes((145, 255, 156, 0, 100))  # type: ignore[arg-type]
    assert c.baud_rate(_Index(57600)).data == bytes((129, 10))  # type: ignore[arg-type]
    assert c.spin(_Index(0), clockwise=True).args == (0, -1)  # type: ignore[arg-type]


@pytest.mark.parametrize("value", [True, 200.0, "200"], ids=["bool", "float", "str"])
def test_what_is_no_integer_is_refused_saying_what_is_allowed(value: object) -> None:
    with pytest.raises(EncodeError, match=r"an integer \(int, or a type with __index__"):
        c.drive(value, 100)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "said"),
    [("C4", "song: note_number must be a MIDI number 0-255 (note_number('C4') gives 60), got 'C4'"),
     ("H4", "song: note_number must be a MIDI number 0-255 (note_number('C4') gives one for a "
            "name like C4, C#5 or rest), got 'H4'")],
)  # fmt: skip
def test_a_song_note_given_by_name_says_the_call_that_gives_its_number(
    name: str, said: str
) -> None:
    """A mission writes ``"C4 250ms"``; a program that wrote ``song(0, [("C4", 16)])`` was
    told "note_number must be an integer (int, or a type with __index__ such as numpy's; not a
    bool) in 0..255 MIDI", with nothing of :func:`note_number`, which turns the name into
    one."""
    with pytest.raises(EncodeError) as caught:
        c.song(0, [(name, 16)])  # type: ignore[list-item]
    assert str(caught.value) == said
