"""Which parameters fill which slots, one rule for them all (session 35's library report,
finding 2): ``leds.power_color`` could be made a parameter only as an untyped ``str``. An
enum of exactly the colour words was "one of green, orange, red, but leds.power_color
needs power_color", an ``int`` was refused though the slot takes the spec's byte, and a
``str`` holding ``200`` was refused by a message saying numbers 0..255 are allowed, without
saying the value was set on the command line."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from roomba_bt.behaviours.actions import POWER_COLOR
from roomba_bt.behaviours.units import INT, RADIUS, STR, compatible, enum
from roomba_bt.mission import CompiledMission
from roomba_bt.mission.loader import Permissions
from roomba_bt.mission.wording import COMMAND_LINE

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]
#: the messages as the command line says them (-p, not params=)
CLI = Permissions(wording=COMMAND_LINE)


def _show(declaration: str) -> str:
    """A mission whose power LED colour is the parameter ``color`` declared so."""
    return f"""
    mission: show
    parameters:
      color: {declaration}
    tree:
      sequence:
        - mode: safe
        - leds: {{power_color: "${{color}}"}}
        - mode: passive
    """


def _colour_sent(mission: CompiledMission) -> Any:
    [leds] = [node for node in mission.root.iterate() if type(node).__name__ == "Leds"]
    return leds.params["power_color"]


@pytest.mark.parametrize(
    ("declaration", "params", "byte"),
    [
        ("{type: enum, choices: [green, orange, red], default: orange}", None, 128),
        ("{type: enum, choices: [green, orange, red], default: orange}", {"color": "red"}, 255),
        ("{type: int, default: 200}", None, 200),
        ("{type: int, default: 0}", {"color": "64"}, 64),
        ("{type: str, default: amber}", None, 128),
        ("{type: str, default: green}", {"color": "200"}, 200),  # the number it promises
    ],
)
def test_an_enum_an_int_and_a_text_each_fill_the_colour(
    compile_text: Compile, declaration: str, params: dict[str, str] | None, byte: int
) -> None:
    assert _colour_sent(compile_text(_show(declaration), params)) == byte


def test_an_enum_with_a_word_the_slot_does_not_take_names_that_word(errors_of: Errors) -> None:
    [said] = errors_of(_show("{type: enum, choices: [green, blue, red], default: red}"))
    assert said.startswith(
        "7:27: leds.power_color: parameter ${color} is one of green, blue, red, but "
        "leds.power_color does not take 'blue' (expected a power LED colour, got 'blue'"
    )
    assert said.endswith("an enum fills a slot when each of its choices is a value the slot takes")


#: what -p color=300 is said to be, set on the command line
_SET_300 = "(${color} is color=300, set on the command line)"


@pytest.mark.parametrize(
    ("declaration", "params", "origin"),
    [
        ("{type: int, default: 0}", {"color": "300"}, _SET_300),
        ("{type: str, default: red}", {"color": "300"}, _SET_300),
        ("{type: int, default: 300}", None, "(${color} is 300, the default of parameter color "
         "at 3:31: give -p color=255, or another default there)"),
    ],
)  # fmt: skip
def test_a_number_past_the_byte_is_refused_naming_where_it_was_set(
    errors_of: Errors, declaration: str, params: dict[str, str] | None, origin: str
) -> None:
    assert errors_of(_show(declaration), params, permissions=CLI) == [
        f"7:27: leds: power_color 300 is out of range: allowed 0..255 {origin}"
    ]


def test_a_text_the_colour_refuses_says_it_was_set_on_the_command_line(errors_of: Errors) -> None:
    [said] = errors_of(_show("{type: str, default: red}"), {"color": "blue"}, permissions=CLI)
    assert said.startswith("7:27: leds.power_color: expected a power LED colour, got 'blue'")
    assert said.endswith("(${color} is color=blue, set on the command line)")


def test_the_rule_is_every_slot_s_not_the_colour_s_alone() -> None:
    assert compatible(enum("straight", "spin_left"), RADIUS)  # a radius takes these words
    assert not compatible(enum("straight", "curve"), RADIUS)
    assert compatible(enum("red", "green"), POWER_COLOR)
    assert compatible(enum("a", "b"), STR)
    assert compatible(INT, POWER_COLOR)
    assert not compatible(STR, POWER_COLOR)  # a text is read when its value is known
    # a blackboard key's value is used as stored: a colour word would reach the robot as text
    assert not compatible(enum("red", "green"), POWER_COLOR, as_stored=True)
    assert compatible(enum("straight", "spin_left"), RADIUS, as_stored=True)
