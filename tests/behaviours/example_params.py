"""The parameters each built-in needs in a test that ticks it (canonical units): its
required ones, and for a leaf that sets something going, what makes it move (``motors``
and ``pwm_motors`` with none given switch all off; a ``drive`` needs a velocity; ``leds`` and
``schedule_leds`` with none given still send). One table for every test
that ticks the built-ins, so a new one with a required parameter is added here once."""

from __future__ import annotations

from typing import Any

EXAMPLE_PARAMS: dict[str, dict[str, Any]] = {
    "vacuum": {"on": True},
    "song": {"number": 1, "notes": ((60, 16),)},
    "log": {"message": "hello"},
    "set": {"key": "k", "value": 1},
    "mark": {"key": "here"},
    "display": {"text": "hi!"},
    "play": {"number": 1},
    "press": {"buttons": ("clean",)},
    "turn": {"angle": 90.0},
    "motors": {"main_brush": True},
    "pwm_motors": {"vacuum": 50.0},
    "drive": {"velocity": 100.0},
    "backtrack": {"distance": 100.0},
}
