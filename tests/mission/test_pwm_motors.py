"""``pwm_motors`` as a mission writes it: percents refused out of their range at validate,
with the file's line and column, what was found and what is allowed; the spec's duty cycle
written as a bare number said as the percent that sends it; ``motors`` given a percent
pointed to ``pwm_motors``; the mode check's Safe/Full, and the JSON Schema's entry."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import load_mission_text, validate_files
from roomba_bt.mission.schema import mission_schema


def _said(tmp_path: Path, leaf: str, before: str = "    - mode: safe\n") -> list[str]:
    path = tmp_path / "gentle.yaml"
    path.write_text(f"mission: g\ntree:\n  sequence:\n{before}    - {leaf}\n")
    return [f"{d.line}:{d.column}: {d.message}" for d in validate_files([path])]


def test_percents_in_their_ranges_are_taken(tmp_path: Path) -> None:
    leaf = "pwm_motors: {main_brush: -40%, side_brush: 100%, vacuum: 50%}"
    assert _said(tmp_path, leaf) == []
    mission = load_mission_text(f"mission: g\ntree:\n  sequence:\n    - mode: safe\n    - {leaf}\n")
    assert [c.name for c in mission.root.iterate()][-2] == (
        "pwm_motors(main_brush=-40% outward, side_brush=100% counterclockwise, vacuum=50%)"
    )


@pytest.mark.parametrize(
    ("written", "said"),
    [
        ("{main_brush: -150%}", "5:32: pwm_motors: main_brush -150 % is out of range: allowed "
         "-100..100 %"),
        ("{side_brush: 101%}", "5:32: pwm_motors: side_brush 101 % is out of range: allowed "
         "-100..100 %"),
        ("{vacuum: -10%}", "5:28: pwm_motors: vacuum -10 % is out of range: allowed 0..100 %"),
        ("{vacuum: 64}", "5:28: pwm_motors.vacuum: expected a percent 0..100% (0% off, 100% "
         "full), got 64: the spec's duty cycle 0..127 is written as a percent here: 64 is 50%; "
         "or 64% if that was meant"),
        ("{main_brush: -127}", "5:32: pwm_motors.main_brush: expected a percent -100..100% (0% "
         "off, 100% full, below 0% the other way), got -127: the spec's duty cycle -127..127 "
         "is written as a percent here: -127 is -100%"),
        ("{vacuum: 300}", "5:28: pwm_motors.vacuum: expected a percent 0..100% (0% off, 100% "
         "full), got 300"),
        ("{vacuum: on}", "5:28: pwm_motors.vacuum: expected a percent 0..100% (0% off, 100% "
         "full), got a boolean (true): write 100%"),
    ],
)  # fmt: skip
def test_a_value_out_of_range_or_unit_is_refused_at_its_place(
    tmp_path: Path, written: str, said: str
) -> None:
    assert _said(tmp_path, f"pwm_motors: {written}") == [said]


@pytest.mark.parametrize(
    ("leaf", "said"),
    [
        ("motors: {vacuum: 50%}", "5:24: motors.vacuum: expected true or false, got '50%': a "
         "motor's power is pwm_motors's (PWM Motors 144): `pwm_motors: {vacuum: 50%}`; motors "
         "switches it on at full power or off"),
        ("motors: {main_brush_outward: 30%}", "5:36: motors.main_brush_outward: expected true "
         "or false, got '30%': a motor's power is pwm_motors's (PWM Motors 144): `pwm_motors: "
         "{main_brush: -30%}`; motors switches it on at full power or off"),
        ("vacuum: 40%", "5:15: vacuum.on: expected true or false, got '40%': a motor's power "
         "is pwm_motors's (PWM Motors 144): `pwm_motors: {vacuum: 40%}`; motors switches it on "
         "at full power or off"),
        ("motors: {vacuum: maybe}", "5:24: motors.vacuum: expected true or false, got 'maybe'"),
    ],
)  # fmt: skip
def test_a_percent_given_to_a_switch_points_to_pwm_motors(
    tmp_path: Path, leaf: str, said: str
) -> None:
    """``motors: {vacuum: 50%}`` said "expected true or false" with no word of the leaf
    that runs a motor at a part of its power."""
    assert _said(tmp_path, leaf) == [said]


def test_it_needs_safe_or_full_unless_it_runs_nothing(tmp_path: Path) -> None:
    """Declared once (``sends`` PWM Motors 144): the mode check refuses it where the tree
    may reach it in Passive, and takes one that runs no motor there (``stops_only``), as
    ``motors: {}``."""
    [refused] = _said(tmp_path, "pwm_motors: {vacuum: 1%}", before="")
    assert refused == (
        "4:7: pwm_motors sends PWM Motors (144), accepted only in Safe or Full mode, but it "
        "can be reached in Passive mode: put a mode change (mode: safe or mode: full) before "
        "it on every path"
    )
    assert _said(tmp_path, "pwm_motors: {vacuum: 0%}", before="") == []
    assert _said(tmp_path, "pwm_motors: {}", before="") == []


def test_the_schema_takes_its_percents() -> None:
    leaf = mission_schema()["$defs"]["pwm_motors"]
    assert set(leaf["then"]["properties"]) == {
        "main_brush", "side_brush", "vacuum",
    }  # fmt: skip
