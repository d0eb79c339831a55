"""The clock panel's leaves: ``display`` (Digit LEDs ASCII 164), ``schedule_leds``
(Scheduling LEDs 162) and ``press`` (Buttons 165). A maker's toy had only a plugin for them,
whose text was checked at run time (``display: "Hey, you"`` validated and ended the run
with an EncodeError), and the 163 warning advised a command no mission could send. Now
each is a mission behaviour, checked at validate at the value's file:line:col, and refused
for a robot without the hardware (the Create 2 has no display and only three buttons)."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import validate_files
from roomba_bt.oi.profiles import CREATE2, PROFILES, ROOMBA500, ROOMBA600


def _mission(tmp_path: Path, *leaves: str) -> Path:
    path = tmp_path / "panel.yaml"
    path.write_text(
        "mission: panel\ntree:\n  sequence:\n    - mode: safe\n"
        + "".join(f"    - {leaf}\n" for leaf in leaves)
    )
    return path


PANEL_LEAVES = (
    'display: "hi!"',
    "schedule_leds: {days: [mon, fri], leds: [clock, colon]}",
    "press: [clean, minute]",
)


def test_the_panel_leaves_validate_on_the_robots_with_a_panel(tmp_path: Path) -> None:
    path = _mission(tmp_path, *PANEL_LEAVES)
    for profile in (ROOMBA500, ROOMBA600):
        assert validate_files([path], profile=profile) == [], profile.name


def test_the_create2_has_no_display_and_three_buttons_said_at_each_leaf(tmp_path: Path) -> None:
    found = validate_files([_mission(tmp_path, *PANEL_LEAVES)], profile=CREATE2)
    assert [(d.severity, d.line, d.column) for d in found] == [
        ("error", line, 7) for line in (5, 6, 7)
    ]
    assert found[0].message.startswith(
        "display: the iRobot Create 2 (create2) has no digit display or scheduling LEDs"
    )
    assert found[1].message.startswith("schedule_leds: the iRobot Create 2 (create2) has no")
    assert "has no minute button: its buttons are clean, spot, dock" in found[2].message
    assert all(d.message.endswith("or leave this node out)")
               for d in found)  # fmt: skip
    assert validate_files([_mission(tmp_path, "press: [clean, spot, dock]")], profile=CREATE2) == []


@pytest.mark.parametrize(
    ("leaf", "column", "said"),
    [
        ('display: "a*b"', 16, "character 2, '*' (code 42), is not on the display: it shows "
                               "ASCII 32..126 but * + @"),
        ('display: "h\u00e9"', 16, "character 2, '\u00e9' (code 233), is not on the display"),
        ('display: "Hey, you"', 16, "the display has 4 digits; 'Hey, you' has 8 characters"),
        ("schedule_leds: {days: [mon, wen]}", 29, "unknown day 'wen' (did you mean 'wed'?)"),
        ("schedule_leds: {leds: clok}", 29, "unknown LED 'clok' (did you mean 'clock'?)"),
        ("press: [clean, minutes]", 14, "unknown button 'minutes' (did you mean 'minute'?)"),
    ],
)  # fmt: skip
def test_a_bad_value_is_said_at_its_place(
    tmp_path: Path, leaf: str, column: int, said: str
) -> None:
    found = validate_files([_mission(tmp_path, leaf)], profile=ROOMBA500)
    assert len(found) == 1 and (found[0].line, found[0].column) == (5, column), found
    assert said in found[0].message


def test_the_display_takes_what_the_spec_table_shows(tmp_path: Path) -> None:
    """Lowercase (the table shows 97 as the A of 65), digits as a number, the punctuation
    the table has, fewer than four characters (padded with spaces when sent)."""
    leaves = ('display: "abcd"', "display: 1234", 'display: "$.:~"', 'display: ""')
    assert validate_files([_mission(tmp_path, *leaves)], profile=ROOMBA600) == []


def test_every_profile_keeps_the_163_warning_and_names_the_display_behaviour() -> None:
    for profile in PROFILES.values():
        text = profile.command_warning(163)
        assert text is not None and "mission behaviour display" in text, profile.name
    assert "has no digit display at all" in str(CREATE2.command_warning(163))
