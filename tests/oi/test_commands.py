"""Every opcode, byte for byte: the specs' worked examples first, then one or more cases for
each remaining command. ``EXPECTED`` is keyed by opcode and compared against the table, so a
command added to ``COMMANDS`` without a case here fails ``test_every_opcode_has_a_case``."""

from __future__ import annotations

import sys
from collections.abc import Callable

import pytest

from roomba_bt.oi import commands as c
from roomba_bt.oi.bits import (
    button_bits,
    day_bits,
    led_bits,
    motor_bits,
    scheduling_led_bits,
    segment_bits,
)
from roomba_bt.oi.encode import (
    NAMED_NOTES,
    Command,
    Note,
    Radius,
    command_size,
    decode_command,
    encode,
    note_name,
    note_number,
)
from roomba_bt.oi.opcodes import COMMANDS

Case = tuple[str, Callable[[], Command], list[int]]

#: opcode -> (label, how to build it, the bytes on the wire). "spec" labels quote an example
#: printed in both specifications.
EXPECTED: dict[int, list[Case]] = {
    7: [("reset", c.reset, [7])],
    128: [("start", c.start, [128])],
    129: [
        ("baud code 11", lambda: c.baud(11), [129, 11]),
        ("baud 57600 by rate", lambda: c.baud_rate(57600), [129, 10]),
        ("baud 19200 by rate", lambda: c.baud_rate(19200), [129, 7]),
    ],
    130: [("control", c.control, [130])],
    131: [("safe", c.safe, [131])],
    132: [("full", c.full, [132])],
    133: [("power", c.power, [133])],
    134: [("spot", c.spot, [134])],
    135: [("clean", c.clean, [135])],
    136: [("max", c.max_clean, [136])],
    137: [
        ("spec: reverse -200 mm/s, radius 500", lambda: c.drive(-200, 500), [137, 255, 56, 1, 244]),
        ("straight 0x8000", lambda: c.drive_straight(200), [137, 0, 200, 128, 0]),
        ("straight 0x8000 by enum", lambda: c.drive(200, Radius.STRAIGHT), [137, 0, 200, 128, 0]),
        ("straight 0x7FFF", lambda: c.drive(200, Radius.STRAIGHT_ALT), [137, 0, 200, 127, 255]),
        ("straight as 32767", lambda: c.drive(200, 32767), [137, 0, 200, 127, 255]),
        ("straight as -32768", lambda: c.drive(200, -32768), [137, 0, 200, 128, 0]),
        ("spin clockwise = -1", lambda: c.spin(100, clockwise=True), [137, 0, 100, 255, 255]),
        ("spin counter-clockwise = 1", lambda: c.spin(100, clockwise=False), [137, 0, 100, 0, 1]),
        ("radius -2000", lambda: c.drive(500, -2000), [137, 1, 244, 248, 48]),
        ("halt", c.halt, [137, 0, 0, 0, 0]),
    ],
    138: [
        (
            "spec: main brush inward + side brush clockwise",
            lambda: c.motors(
                motor_bits(main_brush=True, side_brush=True, side_brush_clockwise=True)
            ),
            [138, 13],
        ),
        ("off", c.motors_off, [138, 0]),
        ("vacuum", lambda: c.motors(motor_bits(vacuum=True)), [138, 2]),
        ("main brush outward", lambda: c.motors(motor_bits(main_brush_outward=True)), [138, 16]),
    ],
    139: [
        (
            "spec: Home LED, power green half",
            lambda: c.leds(led_bits("dock"), 0, 128),
            [139, 4, 0, 128],
        ),
        (
            "all four LEDs, red full",
            lambda: c.leds(led_bits("debris", "spot", "dock", "check_robot"), 255, 255),
            [139, 15, 255, 255],
        ),
    ],
    140: [
        ("one note: 4 data bytes", lambda: c.song(0, [(60, 32)]), [140, 0, 1, 60, 32]),
        (
            "notes by name",
            lambda: c.song(
                4,
                [
                    Note(note_number("G1"), 16),
                    Note(note_number("A4"), 64),
                    Note(note_number("rest"), 8),
                ],
            ),
            [140, 4, 3, 31, 16, 69, 64, 0, 8],
        ),
    ],
    141: [("play 0", lambda: c.play(0), [141, 0]), ("play 4", lambda: c.play(4), [141, 4])],
    142: [
        ("all sensors", lambda: c.sensors(100), [142, 100]),
        ("group 6", lambda: c.sensors(6), [142, 6]),
    ],
    143: [("seek dock", c.seek_dock, [143])],
    144: [
        ("25% = 32; side brush reversed", lambda: c.pwm_motors(32, -32, 127), [144, 32, 224, 127])
    ],
    145: [("right first", lambda: c.drive_direct(100, -100), [145, 0, 100, 255, 156])],
    146: [("right first", lambda: c.drive_pwm(255, -255), [146, 0, 255, 255, 1])],
    148: [
        (
            "spec: cliff front left signal + virtual wall",
            lambda: c.stream([29, 13]),
            [148, 2, 29, 13],
        ),
        ("group 100", lambda: c.stream([100]), [148, 1, 100]),
    ],
    149: [("spec: bumps + virtual wall", lambda: c.query_list([7, 13]), [149, 2, 7, 13])],
    150: [("pause", c.pause_stream, [150, 0]), ("resume", c.resume_stream, [150, 1])],
    162: [
        (
            "Mon + Fri, colon + PM",
            lambda: c.scheduling_leds(day_bits("mon", "fri"), scheduling_led_bits("colon", "pm")),
            [162, 34, 3],
        )
    ],
    163: [
        (
            "digits 1, 7, blank, 0",
            lambda: c.digit_leds_raw(
                [segment_bits("b", "c"), segment_bits("a", "b", "c"), 0, segment_bits(*"abcdef")]
            ),
            [163, 6, 7, 0, 63],
        )
    ],
    164: [
        ("spec: ABCD", lambda: c.digit_leds_ascii("ABCD"), [164, 65, 66, 67, 68]),
        ("padded with spaces", lambda: c.digit_leds_ascii("Hi"), [164, 72, 105, 32, 32]),
    ],
    165: [("press clean + dock", lambda: c.buttons(button_bits("clean", "dock")), [165, 5])],
    167: [
        (
            "spec: Wed 15:00 and Fri 10:36",
            lambda: c.schedule({"wed": (15, 0), "fri": (10, 36)}),
            [167, 40, 0, 0, 0, 0, 0, 0, 15, 0, 0, 0, 10, 36, 0, 0],
        ),
        ("spec: disable", lambda: c.schedule({}), [167] + [0] * 15),
        (
            "days by their whole names",
            lambda: c.schedule({"Wednesday": (15, 0), "FRIDAY": (10, 36)}),
            [167, 40, 0, 0, 0, 0, 0, 0, 15, 0, 0, 0, 10, 36, 0, 0],
        ),
    ],
    168: [
        ("Wednesday 15:00 by name", lambda: c.set_day_time("wednesday", 15, 0), [168, 3, 15, 0]),
        ("Saturday 23:59 by code", lambda: c.set_day_time(6, 23, 59), [168, 6, 23, 59]),
    ],
    173: [("stop", c.stop, [173])],
}

CASES = [
    pytest.param(opcode, build, wire, id=f"{opcode}-{label}")
    for opcode, cases in EXPECTED.items()
    for label, build, wire in cases
]


def test_every_opcode_has_a_case() -> None:
    assert set(EXPECTED) == set(COMMANDS), (
        f"untested opcodes: {sorted(set(COMMANDS) - set(EXPECTED))}; "
        f"cases for opcodes not in the table: {sorted(set(EXPECTED) - set(COMMANDS))}"
    )


@pytest.mark.parametrize(("opcode", "build", "wire"), CASES)
def test_bytes_on_the_wire(opcode: int, build: Callable[[], Command], wire: list[int]) -> None:
    command = build()
    assert command.opcode == opcode
    assert list(command.data) == wire


@pytest.mark.parametrize(("opcode", "build", "wire"), CASES)
def test_length_matches_the_table(
    opcode: int, build: Callable[[], Command], wire: list[int]
) -> None:
    command = build()
    fixed = command.args[: len(command.spec.args)]
    assert len(command.data) == 1 + command.spec.data_bytes(fixed)


@pytest.mark.parametrize(("opcode", "build", "wire"), CASES)
def test_the_robot_reads_back_what_was_sent(
    opcode: int, build: Callable[[], Command], wire: list[int]
) -> None:
    decoded = decode_command(bytes(wire) + b"\x80\x83")  # followed by more commands
    assert decoded is not None
    command, size = decoded
    assert size == len(wire)
    assert command == build()


@pytest.mark.parametrize(("opcode", "build", "wire"), CASES)
def test_an_incomplete_command_waits(
    opcode: int, build: Callable[[], Command], wire: list[int]
) -> None:
    for cut in range(len(wire)):
        assert decode_command(bytes(wire[:cut])) is None


@pytest.mark.parametrize(("opcode", "build", "wire"), CASES)
def test_a_commands_size_is_read_as_the_robot_reads_it(
    opcode: int, build: Callable[[], Command], wire: list[int]
) -> None:
    """command_size: where decode_command's command ends, without building it (a replay's
    compare)."""
    assert command_size(bytes(wire) + b"\x80\x83") == len(wire)
    for cut in range(len(wire)):
        assert command_size(bytes(wire[:cut])) is None


def test_generic_encode_by_name_and_opcode_agree() -> None:
    assert encode("drive", -200, 500) == encode(137, -200, 500) == c.drive(-200, 500)
    assert encode(148, 2, tail=[29, 13]).data == bytes([148, 2, 29, 13])


def test_special_radii_are_never_clamped() -> None:
    # GUIDE §4: a peer sends [137,0,200,7,208] (radius 2000) for "straight".
    for command in (c.drive_straight(200), c.drive(200, Radius.STRAIGHT)):
        assert command.data[3:] != bytes([7, 208])
        assert command.data[3:] == bytes([0x80, 0x00])
    assert c.drive(200, Radius.TURN_CLOCKWISE).data[3:] == bytes([0xFF, 0xFF])
    assert c.drive(200, Radius.TURN_COUNTER_CLOCKWISE).data[3:] == bytes([0x00, 0x01])


def test_note_names_follow_midi_and_the_spec_table() -> None:
    assert note_number("G1") == 31  # the lowest note the robot plays
    assert note_number("A4") == 69  # 440 Hz in the spec's table
    assert note_number("C#5") == 73
    assert note_number("B7") == 107  # the highest in the table
    assert note_number("REST") == 0


def test_a_note_the_robot_does_not_play_is_sent_as_the_rest_the_spec_makes_it() -> None:
    """Both specs: "Roomba considers all musical notes outside the range of 31 - 127 as rest
    notes": any byte is a note number, sent as it is (31-127 sound, the rest are rests)."""
    rests = [(number, 8) for number in (0, 1, 30, 128, 255)]
    assert c.song(0, rests).data == bytes([140, 0, 5, 0, 8, 1, 8, 30, 8, 128, 8, 255, 8])


def test_every_note_name_reads_back_as_its_number() -> None:
    """``note_name`` names every number ``note_number`` reads (rest, C0 to B9), and no
    other: 11 was "B-1" and 132 "C10", names ``note_number`` refuses."""
    for number in (0, *NAMED_NOTES):
        assert note_number(note_name(number)) == number
    assert (note_name(NAMED_NOTES[0]), note_name(NAMED_NOTES[-1])) == ("C0", "B9")


def test_tails_and_id_lists_may_be_bytes() -> None:
    assert encode(148, 2, tail=b"\x1d\x0d").data == bytes([148, 2, 29, 13])
    assert c.query_list(b"\x07\x0d").data == bytes([149, 2, 7, 13])


def test_pack_wraps_values_as_the_robot_counters_do() -> None:
    from roomba_bt.oi.frames import layout_for

    layout = layout_for((43, 7), with_ids=False)
    assert layout.pack({43: 65_536 + 5, 7: 257}) == bytes([0, 5, 1])
    assert layout.pack({43: -1}) == bytes([0xFF, 0xFF, 0])


def test_the_commands_module_is_importable_by_the_name_the_docs_give_it() -> None:
    """docs/plugins.md: ``from roomba_bt.oi import commands``, "a Command from
    roomba_bt.oi.commands", with no warning (the module path ``import roomba_bt.oi.commands``
    gives it too, and warns: tests/test_moved_names.py)."""
    from roomba_bt.oi import commands

    assert commands is c is sys.modules["roomba_bt.oi.encode"]


def test_the_encoder_module_is_reached_as_a_module_by_every_import() -> None:
    """``import roomba_bt.oi.encode`` then ``roomba_bt.oi.encode.drive`` was an
    AttributeError: the package exported the function ``encode`` under the module's name,
    so its own path, ``import ... as`` too, gave the function. The function stays where the
    docs name it: ``roomba_bt.oi.encode.encode``, the commands module's ``encode``."""
    import roomba_bt.oi.encode
    import roomba_bt.oi.encode as imported_as
    from roomba_bt import commands as top_commands
    from roomba_bt.oi import commands
    from roomba_bt.oi import encode as imported_from

    module = sys.modules["roomba_bt.oi.encode"]
    assert roomba_bt.oi.encode is imported_as is imported_from is module
    assert roomba_bt.oi.encode.drive(-200, 500).data == bytes([137, 255, 56, 1, 244])
    assert module.encode is encode is commands.encode is top_commands.encode
    assert "encode" not in roomba_bt.oi.__all__  # no name of the package hides a submodule


def test_the_commands_module_names_its_commands_and_not_its_imports() -> None:
    """``roomba_bt.commands`` had no ``__all__``: ``from roomba_bt.oi.encode import *`` gave
    ``sys``, ``struct``, ``warnings``, ``cast``, ``dataclass`` (and ``form``, a walrus's
    leftover) beside the commands, which ``mypy --strict`` refused as not exported, and
    ``help()`` listed them as the module's data. Every public function and class it defines
    is named, and nothing it merely imports but the error every command raises (its
    own path, ``roomba_bt.oi.encode``: ``roomba_bt.commands`` as a path warns until 0.3.0)."""
    import inspect
    import types

    from roomba_bt import commands as top_commands

    assert "__all__" in vars(c) and top_commands is c
    starred: dict[str, object] = {}
    exec("from roomba_bt.oi.encode import *", starred)  # its module by its own path
    starred.pop("__builtins__")
    assert sorted(starred) == sorted(c.__all__)
    assert not [name for name, value in starred.items() if isinstance(value, types.ModuleType)]
    defined = {
        name
        for name, value in vars(c).items()
        if not name.startswith("_")
        and (inspect.isfunction(value) or inspect.isclass(value))
        and value.__module__ == c.__name__
    }
    assert defined - {"EncodeError"} <= set(c.__all__), defined - set(c.__all__)
    assert "form" not in vars(c)


def test_the_leds_example_runs_as_its_docstring_writes_it() -> None:
    """``oi.leds``'s example named ``led_bits`` as if it were beside it: ``oi.led_bits`` was an
    AttributeError, and nothing said where it lives."""
    from roomba_bt.oi import commands as oi

    doc = oi.leds.__doc__ or ""
    example = "\n".join(line.strip() for line in doc.split("::", 1)[1].splitlines())
    namespace: dict[str, object] = {"leds": oi.leds}
    exec(example.replace("\nleds(", "\nresult = leds(", 1), namespace)  # its imports too
    assert namespace["result"].data == bytes([139, 4, 0, 128])  # type: ignore[attr-defined]


def test_every_command_function_says_what_it_sends() -> None:
    """What an editor shows on hover, or ``help(commands.play)``: pycreate2's user reads the
    unit and the range there (``drive_pwm``'s -255..255, ``play``'s 0-4 and its mode), and
    ten of them showed nothing."""
    import inspect

    from roomba_bt.oi import encode as module

    bare = [
        name
        for name, function in vars(module).items()
        if inspect.isfunction(function)
        and function.__module__ == module.__name__
        and not name.startswith("_")
        and not (function.__doc__ or "").strip()
    ]
    assert bare == []


def test_schedule_times_reads_a_schedule_back_and_skips_days_whose_bit_is_clear() -> None:
    """The robot's side of ``schedule``: the simulator and ``roomba-bt clock`` read a
    Schedule (167)'s bytes with it. A day's hour and minute without its bit clean at no
    time (the days byte says which days clean)."""
    times = {"sun": (7, 0), "wed": (15, 0), "fri": (10, 36)}
    assert c.schedule_times(c.schedule(times).data[1:]) == times
    assert c.schedule_times(bytes([40, 0, 0, 9, 30, 0, 0, 15, 0, 0, 0, 10, 36, 0, 0])) == {
        "wed": (15, 0),
        "fri": (10, 36),
    }  # Monday's 09:30 has no bit: not a day it cleans
    assert c.schedule_times(bytes(15)) == {}
    assert c.day_number("Saturday") == 6 and c.day_number("SUN") == 0
