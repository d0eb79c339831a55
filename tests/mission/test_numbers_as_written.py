"""A plain number means the digits written, or is refused at its place: YAML 1.1 read a
leading zero as octal and ``a:b`` as base 60, so ``power_color: 0200`` validated and sent 128,
``times: 010`` ran 8 times, ``-p c=0200`` gave 128 and a world's ``heading: -0100`` was -64
degrees, while ``show`` printed 0200 (session 27, mission files, finding 1)."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import compile_mission
from roomba_bt.sim.world import WorldError, parse_world

HEADER = "mission: m\n"


def _problems(tmp_path: Path, text: str, params: dict[str, str] | None = None) -> list[str]:
    path = tmp_path / "m.yaml"
    path.write_text(text)
    _, problems = compile_mission(path, params)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def test_an_int_slot_with_a_leading_zero_is_refused_saying_how_yaml_reads_it(
    tmp_path: Path,
) -> None:
    text = HEADER + (
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - leds: {power_color: 0200, power_intensity: 100%}\n"
        "    - repeat: {times: 010, do: {log: tick}}\n"
    )
    assert _problems(tmp_path, text) == [
        "5:27: '0200' is read by YAML 1.1 as the octal number 128 (a leading zero), not as "
        "written: write 200 (or 128 if octal was meant); quote it where a text is meant",
        "6:23: '010' is read by YAML 1.1 as the octal number 8 (a leading zero), not as "
        "written: write 10 (or 8 if octal was meant); quote it where a text is meant",
    ]


@pytest.mark.parametrize(
    ("written", "message"),
    [
        ("1:30", "'1:30' is read by YAML 1.1 as the base-60 number 90 (a ':'), not as written: "
                 "write 90; quote it where a text is meant"),
        ("-017", "'-017' is read by YAML 1.1 as the octal number -15 (a leading zero), not as "
                 "written: write -17 (or -15 if octal was meant); quote it where a text is meant"),
        ("00", "'00' is read by YAML 1.1 as the octal number 0 (a leading zero), not as "
               "written: write 0; quote it where a text is meant"),
    ],
)  # fmt: skip
def test_base_60_and_signed_octal_are_refused_too(
    tmp_path: Path, written: str, message: str
) -> None:
    text = (
        HEADER + f"tree:\n  sequence:\n    - mode: safe\n    - leds: {{power_color: {written}}}\n"
    )
    assert _problems(tmp_path, text) == [f"5:27: {message}"]


def test_a_text_slot_refuses_it_the_same_way_and_a_quoted_one_is_the_text(tmp_path: Path) -> None:
    """``log: 010`` logged 8 and a str parameter's ``default: 010`` became '8'."""
    text = HEADER + (
        "parameters:\n"
        "  n: {type: str, default: 010}\n"
        "tree:\n"
        "  sequence:\n"
        "    - log: 010\n"
        "    - log: '010 ${n}'\n"
    )
    problems = _problems(tmp_path, text)
    assert [p.split(" is read")[0] for p in problems] == ["3:27: '010'", "6:12: '010'"]
    quoted = HEADER + "parameters:\n  n: {type: str, default: '010'}\ntree: {log: '${n}'}\n"
    assert _problems(tmp_path, quoted) == []


def test_decimal_hex_and_zero_are_numbers_as_written(tmp_path: Path) -> None:
    for written in ("200", "0x1F", "0", "-0", "2_00"):
        text = HEADER + f"tree:\n  sequence: [mode: safe, leds: {{power_color: {written}}}]\n"
        assert _problems(tmp_path, text) == [], written


@pytest.mark.parametrize(("value", "reading"), [("0200", "128"), ("1:30", "90"), ("010", "8")])
def test_a_command_line_number_with_a_leading_zero_or_colon_is_refused(
    tmp_path: Path, value: str, reading: str
) -> None:
    text = HEADER + (
        "parameters: {c: {type: int, default: 0}, n: {type: str, default: x}}\n"
        "tree: {repeat: {times: 2, do: {log: '${n} ${c}'}}}\n"
    )
    (problem,) = _problems(tmp_path, text, {"c": value})
    assert f"as the {'octal' if ':' not in value else 'base-60'} number {reading}" in problem
    assert "(given in params)" in problem and "quote it" not in problem
    assert _problems(tmp_path, text, {"n": value}) == []  # a text parameter: the text


def test_a_world_heading_with_a_leading_zero_is_refused_at_its_place() -> None:
    world = (
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nrobot:\n  start: {at: [2, 1], heading: -0100}\n"
    )
    with pytest.raises(WorldError) as caught:
        parse_world(world, "w.yaml")
    (problem,) = caught.value.problems
    assert (problem.line, problem.column) == (3, 32)
    assert "'-0100' is read by YAML 1.1 as the octal number -64" in str(problem)


# A number too large once converted: each was "internal error while compiling ...; please
# report it" at 1:1, or (wait, drive) an infinite duration or distance taken as valid
# (session 27, mission files, finding 2).

BIG = "9" * 400


@pytest.mark.parametrize(
    ("leaf", "found"),
    [
        ("timeout: {after: 1e308 h, do: {wait: 1s}}", "5:24: timeout.after: '1e308 h': 1e308 h "
         "is too large a number for a duration (it must be finite: at most 4.99e+304 h)"),
        ("repeat: {for: 1e308 h, do: {wait: 1s}}", "5:21: repeat.for: '1e308 h'"),
        ("delay: {for: 1e308 h, do: {wait: 1s}}", "5:20: delay.for: '1e308 h'"),
        ("until: {held: {for: 1e308 h, do: {bump: any}}}\n      wait: 1s",
         "5:27: held.for: '1e308 h'"),
        ("wait: 1e308 h", "5:13: wait.duration: '1e308 h'"),
        ("drive: {velocity: 100 mm/s, distance: 1e306 m}", "5:45: drive.distance: '1e306 m': "
         "1e306 m is too large a number for a distance (it must be finite: at most 1.8e+305 m)"),
        (f"leds: {{power_color: {BIG}}}", "5:27: leds.power_color: an integer of 400 "
         "digits is too large a number: at most about 1.8e+308"),
        (f"leds: {{power_color: 0x{'f' * 300}}}", "5:27: leds.power_color: an integer of "
         "362 digits is too large a number"),
        (f"wall_follow: {{kp: {BIG}, duration: 1s}}", "5:25: wall_follow.kp: an integer of "
         "400 digits is too large a number"),
        (f"until: {{sensor: 'wall_signal > {BIG}'}}\n      wait: 1s", "5:23: sensor.test: "
         "'99999999999999999999999999999999999999999999999999999999999... (400 characters) is "
         "too large a number to compare wall_signal with: wall_signal reads 0..4095"),
    ],
)  # fmt: skip
def test_a_number_too_large_once_converted_is_refused_at_its_value(
    tmp_path: Path, leaf: str, found: str
) -> None:
    text = HEADER + f"tree:\n  sequence:\n    - mode: safe\n    - {leaf}\n"
    problems = _problems(tmp_path, text)
    assert len(problems) == 1 and problems[0].startswith(found), problems


@pytest.mark.parametrize(
    ("leaf", "found"),
    [
        ("drive: {velocity: 100 mm/s, distance: 1e400 mm/s}", "5:45: drive.distance: unknown "
         "distance unit 'mm/s' in '1e400 mm/s'; use one of: mm, cm, m"),
        ("drive: {velocity: 1e400 m, distance: 1 m}", "5:25: drive.velocity: unknown speed "
         "unit 'm' in '1e400 m'; use one of: mm/s, cm/s, m/s"),
        ("wait: 1e400 us", "5:13: wait.duration: unknown duration unit 'us' in '1e400 us'; use "
         "one of: ms, s, sec, min, h, d"),
        ("drive: {velocity: 100 mm/s, distance: '1e400'}", "5:45: drive.distance: '1e400' has "
         "no unit; a distance needs one of: mm, cm, m"),
        ("drive: {velocity: 100 mm/s, distance: 1e400 m}", "5:45: drive.distance: '1e400 m': "
         "1e400 is too large a number for a distance"),
    ],
)  # fmt: skip
def test_a_number_too_large_in_the_wrong_unit_is_told_the_unit_first(
    tmp_path: Path, leaf: str, found: str
) -> None:
    """``1e400 mm/s`` as a distance said "too large a number for a distance": made smaller, it
    was then told the unit. What was found (the unit) and what is allowed come first; the
    size only of a value in a unit of its own."""
    text = HEADER + f"tree:\n  sequence:\n    - mode: safe\n    - {leaf}\n"
    problems = _problems(tmp_path, text)
    assert len(problems) == 1 and problems[0].startswith(found), problems


ALLOWED_DISTANCE = "a distance is a finite number in mm, cm or m (e.g. 300 mm, 30cm or 1.5 m)"


@pytest.mark.parametrize(
    ("distance", "found"),
    [
        ("inf mm", "'inf mm': inf is not a finite number; " + ALLOWED_DISTANCE),
        ("nan mm", "'nan mm': nan is not a finite number; " + ALLOWED_DISTANCE),
        ("-Infinity m", "'-Infinity m': -Infinity is not a finite number; " + ALLOWED_DISTANCE),
        ("inf", "'inf': inf is not a finite number; " + ALLOWED_DISTANCE),
        ("inf mm/s", "'inf mm/s': inf is not a finite number, and 'mm/s' is no distance unit; "
         + ALLOWED_DISTANCE),
        ("1e400 mm/s", "unknown distance unit 'mm/s' in '1e400 mm/s'; use one of: mm, cm, m; "
         "and 1e400 is too large: it must be finite"),
        ("1e400 mm", "'1e400 mm': 1e400 is too large a number for a distance (it must be "
         "finite: at most 1.8e+308 mm)"),
    ],
)  # fmt: skip
def test_a_distance_that_is_no_finite_number_says_so_and_what_is_allowed(
    tmp_path: Path, distance: str, found: str
) -> None:
    """``inf mm/s``, ``nan mm`` (and ``1e400 mm/s``) given as a distance said "expected a
    distance such as 300 mm, 30cm or 1.5 m, got 'inf mm'": neither the number nor the unit
    named as the trouble, nor that a distance is a finite number in mm, cm or m."""
    text = (
        HEADER
        + f"tree:\n  sequence:\n    - mode: safe\n    - backtrack: {{distance: {distance}}}\n"
    )
    problems = _problems(tmp_path, text)
    assert problems == [f"5:29: backtrack.distance: {found}"]
