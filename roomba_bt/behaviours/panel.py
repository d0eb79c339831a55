"""The robot's clock panel and buttons: the digit display (Digit LEDs ASCII 164), the
scheduling LEDs (Scheduling LEDs 162) and pressing buttons (Buttons 165).

The display and the scheduling LEDs are the Roomba 560/570's panel (both specs' words), which
the 600 series' scheduling models have too; the Create 2 has neither, and only the Clean, Spot
and Dock buttons. Each leaf's ``needs`` asks the chosen profile (``RobotProfile.has_display``,
``RobotProfile.buttons``), so validate refuses ``display`` for ``--profile create2`` at the
leaf rather than the robot showing nothing. The opcodes, their modes and ranges are the
opcode table's; the names (days, LEDs, buttons) are :mod:`roomba_bt.oi.bits`'.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from py_trees.common import Status

from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.declare import Param, declare
from roomba_bt.behaviours.units import STR, UnitError, ValueType, closest, described
from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import (
    BUTTON_NAMES,
    CYCLE_BUTTONS,
    DIGIT_ASCII,
    SCHEDULING_LED_NAMES,
    WEEKDAYS,
    button_bits,
    day_bits,
    scheduling_led_bits,
)
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME, opcodes
from roomba_bt.oi.profiles import RobotProfile

#: the display's digits, one per byte of Digit LEDs ASCII (164), read from the opcode table
DISPLAY_DIGITS = len(COMMANDS_BY_NAME["digit_leds_ascii"].args)
_FIRST, _LAST = COMMANDS_BY_NAME["digit_leds_ascii"].args[0].minimum, 126
#: the characters in the byte range that the spec's table leaves out (no segments for them)
_NOT_SHOWN = "".join(chr(code) for code in range(_FIRST, _LAST + 1) if code not in DIGIT_ASCII)


def _display_text(value: object) -> str:
    """A text the display can show as written: at most :data:`DISPLAY_DIGITS` characters,
    each in the spec's table. Longer text is refused rather than cut or scrolled: a scroll
    is a choice of speed and of the blank between repeats the mission should make (several
    ``display`` leaves with ``wait`` between them), and a cut text says something else."""
    text = str(STR.parse(value))
    for index, char in enumerate(text):
        if ord(char) not in DIGIT_ASCII:
            raise UnitError(
                f"character {index + 1}, {described(char)} (code {ord(char)}), is not on the "
                f"display: it shows ASCII {_FIRST}..{_LAST} but {' '.join(_NOT_SHOWN)} (the "
                "Digit LEDs ASCII table of the spec)"
            )
    if len(text) > DISPLAY_DIGITS:
        said = f"the display has {DISPLAY_DIGITS} digits; {described(text)} has {len(text)} "
        digits = text.replace(":", "", 1)
        if len(digits) == DISPLAY_DIGITS and text.index(":") == 2:  # a clock's time, 12:30
            raise UnitError(
                f"{said}characters, and its colon is none of them: the colon between the "
                f'second and third digits is a scheduling LED (display: "{digits}" with '
                "schedule_leds: {leds: [colon]} shows " + text + ")"
            )
        raise UnitError(
            f"{said}characters: show it in parts, display leaves with a wait between them"
        )
    return text


DISPLAY_TEXT = ValueType(
    "display_text",
    _display_text,
    json_schema=(("type", "string"), ("maxLength", DISPLAY_DIGITS)),
)


def _names(what: str, known: tuple[str, ...]) -> ValueType:
    """A list of ``known`` names (or one name alone), each unknown one said with the
    closest: ``days: [mon, wen]`` -> ``unknown day 'wen' (did you mean 'wed'?)``."""

    def parse(value: object) -> tuple[str, ...]:
        names = (value,) if isinstance(value, str) else value
        if not isinstance(names, list | tuple) or not all(isinstance(n, str) for n in names):
            raise UnitError(f"expected a list of {what} names, got {described(value)}")
        for name in names:
            if name not in known:
                raise UnitError(
                    f"unknown {what} {name!r}{closest(name, known)}; known: {', '.join(known)}"
                )
        return tuple(names)

    item = {"enum": list(known)}
    schema = {"anyOf": [item, {"type": "array", "items": item}]}
    return ValueType(f"{what}_names", parse, json_schema=tuple(schema.items()))


DAYS = _names("day", WEEKDAYS)
SCHEDULING_LEDS = _names("LED", SCHEDULING_LED_NAMES)
BUTTONS = _names("button", BUTTON_NAMES)


def _needs_display(params: Mapping[str, Any], profile: RobotProfile) -> str | None:
    return profile.display_missing()


def _needs_buttons(params: Mapping[str, Any], profile: RobotProfile) -> str | None:
    return profile.buttons_missing(params.get("buttons", ()))


def _cycle_in_passive(params: Mapping[str, Any]) -> str | None:
    """What a press of Clean, Spot or Dock does in Passive: the robot's own cycle starts
    (both specs: in Passive the robot answers its buttons as a finger pressed them), so the
    robot drives off, vacuuming, while the mission goes on."""
    starting = [name for name in params.get("buttons", ()) if name in CYCLE_BUTTONS]
    if not starting:
        return None
    return (
        f"{' and '.join(starting)} pressed in Passive starts the robot's own cycle (it drives "
        "off as after a finger on the button): put mode: safe before it to show the press in "
        "packet 18 only, as Safe and Full do not answer the buttons"
    )


@declare(
    "display",
    kind="action",
    at_once=True,
    params=(
        Param("text", DISPLAY_TEXT, required=True, from_blackboard=False,
              doc=f"at most {DISPLAY_DIGITS} characters, ASCII {_FIRST}..{_LAST} but "
                  f"{' '.join(_NOT_SHOWN)}; lowercase shows as capitals; padded with spaces"),
    ),
    sends=opcodes("digit_leds_ascii"),
    primary="text",
    needs=_needs_display,
)  # fmt: skip
class Display(Action):
    """Show text on the four-digit display (Digit LEDs ASCII 164); Roomba 500/600 only."""

    def update(self) -> Status:
        return self.send_accepted(oi.digit_leds_ascii(str(self.value("text"))))


@declare(
    "schedule_leds",
    kind="action",
    at_once=True,
    params=(
        Param("days", DAYS, from_blackboard=False,
              doc=f"the weekday LEDs on: {', '.join(WEEKDAYS)}"),
        Param("leds", SCHEDULING_LEDS, from_blackboard=False,
              doc=f"the scheduling LEDs on: {', '.join(SCHEDULING_LED_NAMES)}"),
    ),
    sends=opcodes("scheduling_leds"),
    needs=_needs_display,
)  # fmt: skip
class ScheduleLeds(Action):
    """Light the weekday and scheduling LEDs named, the others off (Scheduling LEDs 162);
    Roomba 500/600 only."""

    def update(self) -> Status:
        days = day_bits(*(self.value("days") or ()))
        leds = scheduling_led_bits(*(self.value("leds") or ()))
        return self.send_accepted(oi.scheduling_leds(days, leds))


@declare(
    "press",
    kind="action",
    at_once=True,
    params=(
        Param("buttons", BUTTONS, required=True, from_blackboard=False,
              doc="pressed together; released by the robot after 1/6 s. In Passive clean, "
                  "spot and dock start the robot's own cycle"),
    ),
    sends=opcodes("buttons"),
    primary="buttons",
    needs=_needs_buttons,
    in_passive=_cycle_in_passive,
)  # fmt: skip
class Press(Action):
    """Press the robot's buttons named (Buttons 165), as a finger would for 1/6 s."""

    def update(self) -> Status:
        self.send(oi.buttons(button_bits(*self.value("buttons"))))
        return Status.SUCCESS


PANEL: tuple[type[Action], ...] = (Display, ScheduleLeds, Press)
