"""``leds`` as someone who read the spec writes it: ``power_intensity`` as the spec's byte
(``128``: the hint was ``write the unit: 128%``, then out of range) and ``home``, the 600
spec's name for the dock LED (no hint was given)."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import validate_files


def _said(tmp_path: Path, leds: str) -> list[str]:
    path = tmp_path / "leds.yaml"
    path.write_text(f"mission: l\ntree:\n  sequence:\n    - mode: safe\n    - leds: {leds}\n")
    return [f"{d.line}:{d.column}: {d.message}" for d in validate_files([path])]


@pytest.mark.parametrize(
    ("written", "said"),
    [
        ("128", "128 is 50%"),
        ("255", "255 is 100%"),
        ("127", "127 is 50% (sent as 128)"),
        ("50", "50 is 20% (sent as 51); or 50% if that was meant"),
    ],
)
def test_a_bare_intensity_is_said_as_the_percent_that_sends_that_byte(
    tmp_path: Path, written: str, said: str
) -> None:
    [message] = _said(tmp_path, f"{{power_intensity: {written}}}")
    assert message == (
        f"5:31: leds.power_intensity: expected a percent 0..100% (0% off, 100% full), got "
        f"{written}: the spec's byte 0..255 is written as a percent here: {said}"
    )


def test_an_intensity_past_a_byte_is_said_with_the_range_alone(tmp_path: Path) -> None:
    assert _said(tmp_path, "{power_intensity: 300}") == [
        "5:31: leds.power_intensity: expected a percent 0..100% (0% off, 100% full), got 300"
    ]


def test_an_intensity_written_as_a_percent_is_taken(tmp_path: Path) -> None:
    assert _said(tmp_path, "{power_intensity: 50%}") == []


@pytest.mark.parametrize("written", ["home", "Home"])
def test_the_specs_home_led_is_pointed_to_dock(tmp_path: Path, written: str) -> None:
    [message] = _said(tmp_path, f"{{{written}: true}}")
    assert message.startswith(
        f"5:14: leds: unknown parameter {written!r} (did you mean 'dock'? Home is the spec's "
        "name for it); known: debris, spot, dock"
    )
