from __future__ import annotations

import math
import re

import pytest

from roomba_bt.behaviours.units import (
    ANGLE,
    BOOL,
    DISTANCE,
    DURATION,
    FLOAT,
    INT,
    PERCENT,
    SPEED,
    STR,
    UnitError,
    closest,
    compatible,
    enum,
    format_quantity,
    parse_quantity,
    with_article,
)


@pytest.mark.parametrize(
    ("dimension", "text", "value"),
    [
        ("duration", "500ms", 0.5),
        ("duration", "30s", 30.0),
        ("duration", "2min", 120.0),
        ("duration", "1.5 s", 1.5),
        ("duration", "1h", 3600.0),
        ("speed", "200 mm/s", 200.0),
        ("speed", "0.2 m/s", 200.0),
        ("speed", "-20cm/s", -200.0),
        ("distance", "1.5 m", 1500.0),
        ("distance", "300 mm", 300.0),
        ("distance", "30cm", 300.0),
        ("angle", "90deg", 90.0),
        ("angle", "90°", 90.0),
        ("angle", "0.5turn", 180.0),
        ("percent", "20%", 20.0),
        ("distance", 0, 0.0),
        ("distance", "0", 0.0),
    ],
)
def test_quantities_parse_into_canonical_units(dimension: str, text: object, value: float) -> None:
    assert parse_quantity(dimension, text) == pytest.approx(value)


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("1d", 86400.0), ("1h30min", 5400.0), ("2h 15min", 8100.0), ("1d 6h", 108000.0),
     ("1 h 30 min", 5400.0), ("1s500ms", 1.5), ("1.5h30sec", 5430.0)],
)  # fmt: skip
def test_a_duration_in_days_or_in_several_units_adds_up(text: str, seconds: float) -> None:
    """The soak's ``--timeout 1d`` and ``1h30min`` were refused (``90min`` was not): a
    patrol's shift is said in hours and minutes. The mission's values read the same."""
    assert DURATION.parse(text) == pytest.approx(seconds)


@pytest.mark.parametrize(
    ("text", "message"),
    [("30min1h", "written the largest unit first, each once, e.g. 1h30min"),
     ("1h1h", "written the largest unit first, each once"),
     ("1s2sec", "written the largest unit first, each once"),
     ("1h30", "in several units, each part has its own unit and none a sign (e.g. 1h30min"),
     ("-1h30min", "in several units, each part has its own unit and none a sign"),
     ("1h 30 mins", "unknown duration unit 'mins' in '1h 30 mins'; use one of: ms, s, sec, "
      "min, h, d"),
     ("1e400h30min", "is too large a number for a duration")],
)  # fmt: skip
def test_a_duration_in_several_units_written_wrong_says_how(text: str, message: str) -> None:
    with pytest.raises(UnitError, match=re.escape(message)):
        DURATION.parse(text)


def test_a_full_stop_after_the_unit_is_not_said_to_be_a_second_part() -> None:
    """``2 min.`` (a sentence's full stop) was told "in several units, each part has its own
    unit": no second part was written. The full stop is named, with the value to write."""
    with pytest.raises(UnitError) as refused:
        DURATION.parse("2 min.")
    assert str(refused.value) == (
        "expected a duration such as 500ms, 30s or 2min, got '2 min.': a stray '.' after the "
        "value: write 2 min"
    )


def test_several_units_are_a_duration_s_only() -> None:
    with pytest.raises(UnitError, match="expected a distance such as"):
        DISTANCE.parse("1m30cm")


def test_radians_convert_to_degrees() -> None:
    assert parse_quantity("angle", f"{math.pi}rad") == pytest.approx(180.0)


def test_a_bare_number_is_refused_with_the_unit_to_write() -> None:
    with pytest.raises(UnitError, match=r"write the unit: 200mm/s"):
        SPEED.parse(200)


def test_an_unknown_unit_lists_the_known_ones() -> None:
    with pytest.raises(UnitError, match=r"unknown speed unit 'km/h' in '3 km/h'; use one of"):
        SPEED.parse("3 km/h")


def test_a_unitless_text_says_which_units_exist() -> None:
    with pytest.raises(UnitError, match=r"'5' has no unit; a duration needs one of: ms, s"):
        DURATION.parse("5")


def test_wrong_shapes_are_described() -> None:
    with pytest.raises(UnitError, match="a list"):
        DISTANCE.parse([1])
    with pytest.raises(UnitError, match="expected an integer, got a boolean"):
        INT.parse(True)
    with pytest.raises(UnitError, match="expected true or false"):
        BOOL.parse("yes please")
    with pytest.raises(UnitError, match="expected a text"):
        STR.parse({"a": 1})
    with pytest.raises(UnitError, match="expected one of left, right, got 'up'"):
        enum("left", "right").parse("up")


def test_compatibility_between_types() -> None:
    assert compatible(INT, INT)
    assert not compatible(SPEED, DISTANCE)
    assert not compatible(ANGLE, PERCENT)
    assert compatible(enum("left", "right"), enum("left", "right", "any"))
    assert not compatible(enum("left", "up"), enum("left", "right", "any"))
    assert not compatible(STR, enum("left", "right"))  # a text key could hold any word


def test_closest_suggests_a_near_name_only() -> None:
    assert closest("velocty", ["velocity", "radius"]) == " (did you mean 'velocity'?)"
    assert closest("zzz", ["velocity"]) == ""


def test_format_quantity() -> None:
    assert format_quantity("speed", 200.0) == "200 mm/s"
    assert format_quantity("percent", 20.0) == "20%"


def test_a_long_wrong_value_is_quoted_short() -> None:
    with pytest.raises(UnitError) as info:
        SPEED.parse("a" * 500)
    assert str(info.value).endswith("got '" + "a" * 59 + "... (500 characters)")


@pytest.mark.parametrize("text", ["1e400 s", "-1e400 s", "1e309ms"])
def test_a_number_too_large_for_a_float_is_refused_not_infinity(text: str) -> None:
    """``wait: 1e400 s`` was taken as a wait of inf s (``inf s`` itself was refused)."""
    with pytest.raises(UnitError, match="is too large a number for a duration"):
        parse_quantity("duration", text)
    assert parse_quantity("duration", "1e300 s") == 1e300


@pytest.mark.parametrize(
    ("value", "message"),
    [(90, "expected an angle with a unit such as 90deg or 1.57rad, got 90"),
     ("fast", "expected an angle such as 90deg or 1.57rad, got 'fast'"),
     ("90", "'90' has no unit; an angle needs one of: ")],
)  # fmt: skip
def test_an_angle_is_an_angle_in_the_messages(value: object, message: str) -> None:
    """The stranger's units.yaml read "expected a angle with a unit"."""
    with pytest.raises(UnitError) as caught:
        ANGLE.parse(value)
    assert str(caught.value).startswith(message)


def test_a_noun_takes_the_article_its_first_sound_wants() -> None:
    assert [with_article(n) for n in ("speed", "angle", "int", "duration")] == [
        "a speed", "an angle", "an int", "a duration"
    ]  # fmt: skip
    assert with_article("one of left, right") == "one of left, right"


@pytest.mark.parametrize(
    ("text", "found"),
    [("1\u09ea0 mm/s", "'\u09ea' (U+09EA BENGALI DIGIT FOUR) is not an ASCII digit"),
     ("\uff12\uff10\uff10 mm/s", "'\uff12' (U+FF12 FULLWIDTH DIGIT TWO) is not an ASCII digit"),
     ("\U0001d7d0\U0001d7ce\U0001d7ce mm/s",
      "'\U0001d7d0' (U+1D7D0 MATHEMATICAL BOLD DIGIT TWO) is not an ASCII digit"),
     ("200\xa0mm/s", "'\\xa0' (U+00A0 NO-BREAK SPACE) is not a plain space")],
)  # fmt: skip
def test_a_digit_or_space_that_is_not_ascii_is_refused_and_named(text: str, found: str) -> None:
    """``\\d`` and ``\\s`` took any script's: ``1\u09ea0 mm/s`` (a Bengali 4, which reads like an 8)
    was 140 mm/s, the tree showing the text as written."""
    with pytest.raises(UnitError) as caught:
        SPEED.parse(text)
    assert str(caught.value) == (
        f"expected a speed such as 200 mm/s or 0.2 m/s, got {text!r}: {found}"
        + ("; digits must be 0-9" if "digit" in found else "; write a space ' ' or nothing")
    )


def test_a_comparisons_number_must_be_ascii_digits() -> None:
    from roomba_bt.behaviours.conditions import _parse_comparison

    with pytest.raises(
        UnitError, match=r"'\u0968' \(U\+0968 DEVANAGARI DIGIT TWO\) is not an ASCII"
    ):
        _parse_comparison("battery_charge < \u0968\u0966\u0966")


@pytest.mark.parametrize(
    ("value", "message"),
    [("1e400", "1e400 is too large a number: out of range (not finite)"),
     (math.inf, "expected a finite number, got inf"),
     ("2e3", "expected a number, got the text '2e3': YAML reads an exponent as a number only "
             "with a decimal point and a sign (1.0e+3)")],
)  # fmt: skip
def test_a_float_too_large_or_written_as_text_says_so(value: object, message: str) -> None:
    """``1e400`` (text to YAML 1.1) was "expected a number"; ``1.0e+400`` was infinity."""
    with pytest.raises(UnitError) as caught:
        FLOAT.parse(value)
    assert str(caught.value) == message
    assert FLOAT.parse(1.5) == 1.5


@pytest.mark.parametrize(("text", "meant"), [("true", True), ("No", False), ("on", True)])
def test_a_boolean_written_as_a_text_is_told_it_is_one(text: str, meant: bool) -> None:
    """A plugin's ``Param("x", BOOL, default="true")`` (and a mission's quoted ``"no"``) was
    refused with "expected true or false, got 'true'", which reads as its own contradiction:
    it is said a text, with the boolean it means."""
    with pytest.raises(UnitError) as refused:
        BOOL.parse(text)
    assert str(refused.value) == (
        f"expected true or false, got the text '{text}': write {str(meant).lower()} unquoted "
        f"({meant} in Python)"
    )
    with pytest.raises(UnitError, match=r"got 'yes please'$"):
        BOOL.parse("yes please")
