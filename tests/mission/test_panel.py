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
        # a clock's time: its colon is the scheduling LED between the digits, not "in parts"
        ('display: "12:30"', 16, "the display has 4 digits; '12:30' has 5 characters, and its "
         "colon is none of them: the colon between the second and third digits is a scheduling "
         'LED (display: "1230" with schedule_leds: {leds: [colon]} shows 12:30)'),
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


def _validated(tmp_path: Path, text: str) -> list[tuple[str, int, int, str]]:
    """What validate says of the mission ``text`` for a Create 2: severity, place, message."""
    path = tmp_path / "buttons.yaml"
    path.write_text(text)
    return [(d.severity, d.line, d.column, d.message)
            for d in validate_files([path], profile=CREATE2)]  # fmt: skip


def test_a_cycle_button_pressed_in_passive_is_warned_with_the_fix(tmp_path: Path) -> None:
    """In Passive a press of Clean, Spot or Dock starts the robot's own cycle (the simulator
    does it, as the robot does): a warning where the mode pass finds the press reachable in
    Passive, with ``mode: safe`` as the fix; after ``mode: safe``, none."""
    found = _validated(
        tmp_path,
        "mission: p\ntree:\n  sequence:\n    - press: [spot, dock]\n"
        "    - mode: safe\n    - press: clean\n",
    )
    [(severity, line, column, message)] = found  # the press in Safe: nothing said
    assert (severity, line, column) == ("warning", 4, 7)
    assert message.startswith(
        "press: spot and dock pressed in Passive starts the robot's own cycle"
    )
    assert message.endswith(
        "put mode: safe before it to show the press in packet 18 only, as Safe and Full do "
        "not answer the buttons"
    )


@pytest.mark.parametrize("condition", ["button", "button_pressed"])
@pytest.mark.parametrize("name", ["minute", "hour", "day", "schedule", "clock"])
def test_a_clock_panel_button_read_on_a_create2_is_warned_at_its_name(
    tmp_path: Path, condition: str, name: str
) -> None:
    """The Create 2's top has Clean, Spot and Dock only: packet 18's other bits read 0 for
    ever there, so a condition on one never holds. A warning (the bit exists, and the same
    mission may be meant for a 500 or 600), at the condition's file:line:col."""
    text = f"mission: b\ntree:\n  sequence:\n    - wait: 1s\n      until: {{{condition}: {name}}}\n"
    [(severity, line, column, message)] = _validated(tmp_path, text)
    assert (severity, line, column) == ("warning", 5, 15)
    assert message.startswith(f"{condition}: the iRobot Create 2 (create2) has no {name} button")
    assert message.endswith(f"packet 18's {name} bit reads 0 there for ever: this never holds")
    path = tmp_path / "buttons.yaml"
    assert validate_files([path], profile=ROOMBA600) == []
    # in Safe: in Passive the Dock button starts the robot's own cycle, a warning of its own
    path.write_text(text.replace(name, "dock").replace("- wait", "- mode: safe\n    - wait"))
    assert validate_files([path], profile=CREATE2) == []
