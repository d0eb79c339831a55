"""Values written as people say them: ``500ms``, ``30s``, ``200 mm/s``, ``1.5 m``, ``90deg``.

Each value type parses a YAML scalar into one canonical unit, so every behaviour computes in
the same units and every error names what was allowed::

    duration  -> seconds   500ms, 30s, 2min, 1h, 1d, 1h30min, 0
    speed     -> mm/s      200 mm/s, 0.2 m/s, 20cm/s, 0
    distance  -> mm        300 mm, 30cm, 1.5 m, 0
    angle     -> degrees   90deg, 90°, 1.57rad, 0.25turn, 0
    percent   -> percent   20%, 20 %

A bare number is refused for a dimensioned type (except 0): ``speed: 200`` could be mm/s or
m/s, and a robot that drives 1000 times too fast is the error this module exists to prevent.

A duration may be written in several units, the largest first, each once (``1h30min``,
``2h 15min``, ``1d 6h``; :func:`compound_duration`): a patrol's shift or a charge is said so,
and ``90min`` for it made the user do the sum. One grammar for a mission's values and the
command line's ``--timeout`` (``roomba_bt.cli.arguments.parse_timeout``), which read it here.
"""

from __future__ import annotations

import math
import numbers
import re
import sys
import unicodedata
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from roomba_bt.errors import RoombaBtError
from roomba_bt.yamlsource import (
    QUOTE_LIMIT,
    TYPOGRAPHIC_QUOTES,
    named_character,
    quoted,
    typographic_quote,
)

_NUMBER = r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
_UNSIGNED = _NUMBER.removeprefix("[-+]?")
#: ASCII digits and spaces only: ``\d`` took any script's (``1\u09ea0 mm/s``, whose Bengali 4
#: reads like an 8, was 140 mm/s) and ``\s`` a no-break space (:func:`miswritten`)
_QUANTITY = re.compile(rf"^\s*({_NUMBER})\s*([A-Za-z°%/]*)\s*$", re.ASCII)

#: unit -> factor to the canonical unit, per dimension.
UNITS: dict[str, dict[str, float]] = {
    "duration": {"ms": 0.001, "s": 1.0, "sec": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0},
    "speed": {"mm/s": 1.0, "cm/s": 10.0, "m/s": 1000.0},
    "distance": {"mm": 1.0, "cm": 10.0, "m": 1000.0},
    "angle": {"deg": 1.0, "°": 1.0, "rad": 180.0 / math.pi, "turn": 360.0, "turns": 360.0},
    "percent": {"%": 1.0},
}
CANONICAL: dict[str, str] = {
    "duration": "s",
    "speed": "mm/s",
    "distance": "mm",
    "angle": "deg",
    "percent": "%",
}
EXAMPLES: dict[str, str] = {
    "duration": "500ms, 30s or 2min",
    "speed": "200 mm/s or 0.2 m/s",
    "distance": "300 mm, 30cm or 1.5 m",
    "angle": "90deg or 1.57rad",
    "percent": "20%",
}


class UnitError(ValueError, RoombaBtError):
    """A value that does not parse; the message says what was expected."""


class ItemErrors(UnitError):
    """Items of a list value that do not parse, each with its index in the list (from 0)
    and what was wrong with it (found, and what is allowed). The message names each item's
    place (``note 3 of 8: ...``) for a caller that knows the list alone; a mission says
    each at its item's own line and column (a song's bad note on the third line of its
    list was said at the list's first)."""

    def __init__(self, noun: str, count: int, problems: Sequence[tuple[int, str]]) -> None:
        self.noun, self.count, self.problems = noun, count, tuple(problems)
        super().__init__("; ".join(self.said(index, problem) for index, problem in problems))

    def said(self, index: int, problem: str) -> str:
        """``note 3 of 8: unknown note 'H4': ...``; a list of one: the problem alone."""
        return problem if self.count == 1 else f"{self.noun} {index + 1} of {self.count}: {problem}"


class BareNumber(UnitError):
    """A bare number where a quantity needs its unit (``max_radius: 1``). The message
    suggests the unit that reads it inside the allowed range, when the caller knows the
    range (:meth:`within`): ``1`` for a radius of 50..5000 mm is ``1m``, not ``1mm``."""

    def __init__(self, dimension: str, value: float) -> None:
        self.dimension, self.value = dimension, value
        super().__init__(self._message(None, None))

    def within(self, lo: float | None, hi: float | None) -> BareNumber:
        """The same error, its suggestion chosen for the range ``lo..hi`` (canonical unit)."""
        self.args = (self._message(lo, hi),)
        return self

    def _message(self, lo: float | None, hi: float | None) -> str:
        dimension, value = self.dimension, self.value
        if not math.isfinite(value):  # .inf, .nan: no unit makes one of them a quantity
            return (
                f"expected {with_article(dimension)} with a unit such as {EXAMPLES[dimension]}, "
                f"got {quoted(value)}: it must be a finite number"
            )
        unit = CANONICAL[dimension]
        units = UNITS[dimension]
        for candidate in (unit, *units):  # the canonical unit first, then the dimension's order
            scaled = value * units[candidate]
            if (lo is None or scaled >= lo) and (hi is None or scaled <= hi):
                unit = candidate
                break
        return (
            f"expected {with_article(dimension)} with a unit such as {EXAMPLES[dimension]}, "
            f"got {quoted(value)} (write the unit: {value}{unit})"
        )


def with_article(noun: str) -> str:
    """``noun`` with its article, for a message: "a speed", "an angle", "an int" (the
    dimension names start with the sound of their letter); "one of a, b" takes none."""
    if noun.startswith("one of"):
        return noun
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _number_said(digits: str) -> str:
    """A number of a message as written, or its length when a page long (a generated file)."""
    return digits if len(digits) <= 24 else f"a number of {len(digits):,} characters"


#: a number and a unit of any characters but digits, spaces, points and commas (any script's:
#: a no-break space or a Bengali digit is :func:`miswritten`'s to name): what reads as "a unit"
#: to a person though :data:`_QUANTITY`'s ASCII units do not take it (``100µs``)
_ANY_UNIT = re.compile(rf"^[ \t]*({_NUMBER})[ \t]*([^\s\d.,]+)[ \t]*$")
#: durations a person writes that roomba-bt has no unit for, in seconds: said in ms
_SHORTER_THAN_MS = {"us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6, "ns": 1e-9}


#: units a person writes as words, plurals or another abbreviation, each with the unit of
#: the same size a mission writes (``2 mins``, ``90 degrees``, ``3 hours`` were unknown units
#: and no more); a unit in capitals (``30 S``, ``5 MM``) is its lower-case one
_WRITTEN_OTHERWISE: dict[str, dict[str, str]] = {
    "duration": {
        **dict.fromkeys(("msec", "msecs", "millisecond", "milliseconds"), "ms"),
        **dict.fromkeys(("secs", "second", "seconds"), "s"),
        **dict.fromkeys(("mins", "minute", "minutes"), "min"),
        **dict.fromkeys(("hr", "hrs", "hour", "hours"), "h"),
        **dict.fromkeys(("day", "days"), "d"),
    },
    "speed": {"mm/sec": "mm/s", "cm/sec": "cm/s", "m/sec": "m/s"},
    "distance": {
        **dict.fromkeys(("millimeter", "millimeters", "millimetre", "millimetres"), "mm"),
        **dict.fromkeys(("centimeter", "centimeters", "centimetre", "centimetres"), "cm"),
        **dict.fromkeys(("meter", "meters", "metre", "metres"), "m"),
    },
    "angle": {
        **dict.fromkeys(("degs", "degree", "degrees"), "deg"),
        **dict.fromkeys(("rads", "radian", "radians"), "rad"),
    },
    "percent": {},
}


def _unknown_unit(dimension: str, value: str, number: str, unit: str) -> str:
    """The message for a unit ``dimension`` has not: the units it has, a microsecond's
    duration in milliseconds (``100µs`` is 0.1ms: the shortest unit is ms), and the unit of
    the same size a mission writes for a word, a plural or capitals (``2 mins``: write
    ``2 min``); ``2m`` for a duration is two metres to roomba-bt: a minute is ``min``."""
    message = (
        f"unknown {dimension} unit {unit!r} in {quoted(value)}; use one of: "
        f"{', '.join(UNITS[dimension])}"
    )
    number = number.strip()
    if not math.isfinite(float(number)):  # 1e400: the unit is said first, the hint is none
        return message
    if dimension == "duration" and unit in _SHORTER_THAN_MS:
        in_ms = float(number) * _SHORTER_THAN_MS[unit] * 1000
        message += f" ({number}{unit} is {in_ms:g}ms)"
    elif dimension == "duration" and unit.lower() == "m":
        message += f" (m is metres: for minutes write {number} min)"
    else:
        lower = unit.lower()
        instead = lower if lower in UNITS[dimension] else _WRITTEN_OTHERWISE[dimension].get(lower)
        if instead is not None:
            message += f" (write {number} {instead})"
    return message


#: a duration in two units or more (``1h30min``, ``2h 15min``): each part a number without a
#: sign and its unit (:func:`compound_duration`)
_COMPOUND = re.compile(rf"^\s*(?:{_UNSIGNED}\s*[A-Za-z]+\s*){{2,}}$", re.ASCII)
_COMPOUND_PART = re.compile(rf"({_UNSIGNED})\s*([A-Za-z]+)", re.ASCII)
#: how a compound duration is written, for its errors
COMPOUND_EXAMPLES = "1h30min, 2h 15min or 1d 6h"


def compound_duration(value: str) -> float | None:
    """``1h30min`` -> 5400.0: a duration in several units, each part a number without a sign
    and a duration unit, the largest unit first and each once (``30min1h`` and ``1h1h`` are
    refused: a slip, not a sum meant). None for a text not of that shape (one unit, a sign, a
    part without its unit): :func:`parse_quantity` says what is wrong with it. Raises
    :class:`UnitError` for an unknown unit or the wrong order."""
    if _COMPOUND.match(value) is None:
        return None
    units = UNITS["duration"]
    total, larger = 0.0, math.inf
    for number, unit in _COMPOUND_PART.findall(value):
        factor = units.get(unit)
        if factor is None:
            raise UnitError(_unknown_unit("duration", value, number, unit))
        if factor >= larger:
            raise UnitError(
                f"{quoted(value)}: a duration in several units is written the largest unit "
                f"first, each once, e.g. {COMPOUND_EXAMPLES}"
            )
        larger = factor
        total += float(number) * factor
    if not math.isfinite(total):
        raise UnitError(f"{quoted(value)} is too large a number for a duration")
    return total


#: a unit followed by another number: a duration in several units meant (``1h30``, ``1h .5``);
#: a point alone after the unit is none (``2 min.``, a sentence's full stop, was said to be
#: several units)
_SEVERAL_PARTS = re.compile(r"[0-9.]\s*[A-Za-z]+\s*[-+]?\.?[0-9]", re.ASCII)


def _compound_hint(dimension: str, value: str) -> str:
    """For a duration that reads as several parts but is not one (``1h30``, ``-1h30min``):
    how a compound duration is written; "" for any other value."""
    if dimension != "duration" or _SEVERAL_PARTS.search(value) is None:
        return ""
    return (
        f": in several units, each part has its own unit and none a sign (e.g. {COMPOUND_EXAMPLES})"
    )


#: what a value is often written with that is no part of it: a list's comma after a block
#: mapping's value (``angle: 90 deg,``), a sentence's semicolon or full stop
_STRAY_PUNCTUATION = ",;."


def _stray_punctuation_hint(dimension: str, value: str) -> str:
    """For a quantity with a comma, semicolon or full stop after it (``90 deg,``): the
    punctuation named and the value without it; "" when the value without it does not read
    either (then the punctuation is not what is wrong)."""
    written = value.strip()
    meant = written.rstrip(_STRAY_PUNCTUATION + " \t")
    if not meant or meant == written:
        return ""
    try:
        parse_quantity(dimension, meant)
    except UnitError:
        return ""
    stray = written[len(meant) :].strip()
    return f": a stray {stray!r} after the value: write {meant}"


#: a fraction and a unit (``1/4 turn``, ``1/2m``): a mission writes a decimal number
_FRACTION = re.compile(r"^\s*([0-9]+)\s*/\s*([0-9]+)(\s*)([A-Za-z°%/]+)\s*$", re.ASCII)


def _fraction_hint(dimension: str, value: str) -> str:
    """For a fraction with a unit of ``dimension`` (``1/4 turn``): its decimal in that unit,
    and in the canonical unit when that is another (``write 0.25 turn or 90 deg``), spaced
    as the value was; "" for any other value."""
    match = _FRACTION.match(value)
    if match is None:
        return ""
    numerator, denominator, space, unit = match.groups()
    units = UNITS[dimension]
    if int(denominator) == 0 or unit not in units:
        return ""
    number = int(numerator) / int(denominator)
    said = f"{number:g}{space}{unit}"
    canonical = CANONICAL[dimension]
    if units[unit] != units[canonical]:
        said += f" or {number * units[unit]:g}{space}{canonical}"
    return f": a fraction does not read as a number: write {said}"


#: a number written as no finite one: ``inf``, ``-Infinity``, ``nan``, YAML's ``.inf`` as a
#: text (``.inf mm``), with what follows it taken for its unit
_NOT_FINITE = re.compile(r"^\s*([-+]?\.?(?:inf(?:inity)?|nan))\s*(\S*)\s*$", re.IGNORECASE)


def _not_finite(dimension: str, value: str) -> str | None:
    """What to say of a quantity whose number is no finite one (``inf mm/s`` given as a
    distance, ``nan m``), the unit too where it is not the dimension's; None for any other
    value. It was "expected a distance such as 300 mm, 30cm or 1.5 m, got 'inf mm'", which
    named neither the number nor the unit as the trouble."""
    match = _NOT_FINITE.match(value)
    if match is None:
        return None
    number, unit = match.groups()
    units = UNITS[dimension]
    said = f"{quoted(value)}: {number} is not a finite number"
    if unit and unit not in units:
        said += f", and {unit!r} is no {dimension} unit"
    return f"{said}; {_allowed(dimension)}"


def _allowed(dimension: str) -> str:
    """What a quantity of ``dimension`` is: "a distance is a finite number in mm, cm or m
    (e.g. 300 mm, 30cm or 1.5 m)"."""
    *most, last = UNITS[dimension]
    units = f"{', '.join(most)} or {last}" if most else last
    return f"{with_article(dimension)} is a finite number in {units} (e.g. {EXAMPLES[dimension]})"


def parse_quantity(dimension: str, value: object) -> float:
    """``parse_quantity("speed", "0.2 m/s") == 200.0``; raises :class:`UnitError`."""
    units = UNITS[dimension]
    what = with_article(dimension)
    if _is_number(value):
        if value == 0:
            return 0.0
        if isinstance(value, int):  # 10**1000: no float holds it, and the hint computes one
            _not_too_large(value)
        raise BareNumber(dimension, value)  # type: ignore[arg-type]
    if not isinstance(value, str):
        raise UnitError(f"expected {what} such as {EXAMPLES[dimension]}, got {described(value)}")
    match = _QUANTITY.match(value)
    if match is None:
        if dimension == "duration" and (compound := compound_duration(value)) is not None:
            return compound
        # a value that reads without the punctuation after it (``90 deg,``, ``1h30min,``)
        # is said so before the unit it seems to have (``mm/s;``) or several parts
        stray = _stray_punctuation_hint(dimension, value)
        spelled = _ANY_UNIT.match(value)  # 100µs, 90º: a number and a unit not in ASCII
        if not stray and spelled is not None and math.isfinite(float(spelled.group(1))):
            raise UnitError(_unknown_unit(dimension, value, *spelled.groups()) + miswritten(value))
        not_finite = _not_finite(dimension, value)
        if not_finite is not None:
            raise UnitError(not_finite)
        raise UnitError(
            f"expected {what} such as {EXAMPLES[dimension]}, got {quoted(value)}"
            + (
                miswritten(value)
                or stray
                or _compound_hint(dimension, value)
                or _fraction_hint(dimension, value)
            )
        )
    number, unit = float(match.group(1)), match.group(2)
    # the unit before the number's size: ``1e400 mm/s`` given as a distance was "too large a
    # number for a distance", and its user made it smaller, to be told the unit next
    if unit not in units:
        known = ", ".join(units)
        if unit == "":
            if number == 0:
                return 0.0
            raise UnitError(
                f"{value!r} has no unit; {what} needs one of: {known} (e.g. {EXAMPLES[dimension]})"
            )
        unknown = _unknown_unit(dimension, value, match.group(1), unit)
        if not math.isfinite(number):  # both said at once: 1e400 mm/s as a distance
            unknown += f"; and {_number_said(match.group(1))} is too large: it must be finite"
        raise UnitError(unknown)
    canonical = number * units[unit]
    # 1e400 overflows to inf, 1e308 h to inf in seconds (an "internal error" once): what is
    # allowed said beside it, as the largest in the unit written
    if not math.isfinite(canonical):
        largest = sys.float_info.max / units[unit]
        said = _number_said(match.group(1)) + (f" {unit}" if math.isfinite(number) else "")
        raise UnitError(
            f"{quoted(value)}: {said} is too large a number for {what} (it must be finite: "
            f"at most {largest:.3g} {unit})"
        )
    return canonical


#: Characters a chat app, a word processor or a phone keyboard writes for an ASCII one, each
#: with what it is taken for and what to write instead: a value holding one does not read,
#: and "expected a speed" did not say why: ``\u2212200 mm/s`` (the Unicode minus), ``90\u00ba``
#: (an ordinal indicator) and ``\u201c200 mm/s\u201d`` (typographic quotes) look right
_TYPOGRAPHIC_QUOTES = {quote: "'" if quote < "\u201c" else '"' for quote in TYPOGRAPHIC_QUOTES}
_MINUS_LOOKALIKES = "\u2212\u2012\u2013\u2014\ufe63\uff0d"
_DEGREE_LOOKALIKES = "\u00ba\u02da\u2070\u2218"
DEGREE_SIGN = "\u00b0"
#: a decimal comma: ``1,5 m`` (ASCII, so :func:`miswritten` looks for it apart)
_DECIMAL_COMMA = re.compile(r"([0-9]),([0-9])")


def miswritten(text: str) -> str:
    r"""What to add to an error for a value that does not read, when a character in it looks
    like what it is not, named, with what to write: a typographic quote used as a YAML quote
    (``\u201c200 mm/s\u201d``), the Unicode minus or a dash (``\u2212200 mm/s``), a degree
    lookalike (``90\u00ba``, U+00BA, or ``90\u02da``), a digit that is not 0-9 (fullwidth,
    Devanagari, bold: Python's ``float`` and ``\d`` take them), a space that is not a plain one
    (a no-break space), a decimal comma (``1,5 m``). Empty if none: the first such character
    is said."""
    for char in text:
        if char.isascii():
            continue
        shown = named_character(char)
        if char in _TYPOGRAPHIC_QUOTES:
            return f": {typographic_quote(char)} ({_rewritten(text)})"
        if char in _MINUS_LOOKALIKES:
            return f": {shown} is not the ASCII minus: write {_rewritten(text)}"
        if char in _DEGREE_LOOKALIKES:
            return (
                f": {shown} is not a degree sign: write {_rewritten(text)} or "
                f"{_rewritten(text, degree=DEGREE_SIGN)}"
            )
        if char.isdigit():
            return f": {shown} is not an ASCII digit; digits must be 0-9"
        if char.isspace():
            return f": {shown} is not a plain space; write a space ' ' or nothing"
    if _DECIMAL_COMMA.search(text):
        return f": a decimal comma: write {_rewritten(text)}"
    return ""


def _rewritten(text: str, degree: str = "deg") -> str:
    """``text`` with each character :func:`miswritten` knows written as meant, as it is to be
    written (no repr: ``"200 mm/s"``, not ``'"200 mm/s"'``), a long one cut."""
    for wrong, right in _TYPOGRAPHIC_QUOTES.items():
        text = text.replace(wrong, right)
    for wrong in _MINUS_LOOKALIKES:
        text = text.replace(wrong, "-")
    for wrong in _DEGREE_LOOKALIKES:
        text = text.replace(wrong, degree)
    text = _DECIMAL_COMMA.sub(r"\1.\2", text.strip())
    return text if len(text) <= QUOTE_LIMIT else f"{text[:QUOTE_LIMIT]}..."


def _miswritten_text(value: object) -> str:
    """:func:`miswritten` of a text, "" for another value (an int slot given ``\u22122``, an
    enum ``\u2018safe\u2019``: the character named, not only difflib's guess)."""
    return miswritten(value) if isinstance(value, str) else ""


def described(value: object) -> str:
    """What a value the user wrote is, in their terms: "nothing (null)", "a list", a text
    quoted (never Python's ``None`` or ``['C4', 250]``)."""
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return quoted(value)


def format_quantity(dimension: str, value: float) -> str:
    """The canonical spelling: ``format_quantity("speed", 200.0) == "200 mm/s"``."""
    text = f"{value:g}"
    return (
        f"{text}{CANONICAL[dimension]}"
        if dimension == "percent"
        else (f"{text} {CANONICAL[dimension]}")
    )


def shown(vtype: ValueType, value: Any) -> str:
    """A value as a mission would write it: ``150 mm/s`` rather than ``150.0``; a list's
    items so, in YAML's brackets (``[1 m, 2 m]``)."""
    if vtype.name in CANONICAL and isinstance(value, int | float):
        return format_quantity(vtype.name, value)
    if vtype.item is not None and isinstance(value, list | tuple):
        return "[" + ", ".join(shown(vtype.item, item) for item in value) + "]"
    return str(value)


@dataclass(frozen=True, slots=True)
class ValueType:
    """One parameter type: its name in missions and schema, how to parse a YAML value into
    the canonical unit, and the JSON Schema fragment editors get."""

    name: str
    parse: Callable[[object], Any]
    unit: str = ""
    json_schema: tuple[tuple[str, Any], ...] = ()
    choices: tuple[str, ...] = ()
    #: a record's fields (blackboard keys declared with ``fields:``), in order
    fields: tuple[tuple[str, ValueType], ...] = ()
    #: the other types whose every value this one reads as its own (:func:`compatible`): a
    #: float an int, a radius a distance, the power LED's colour an int (the spec's byte)
    takes: tuple[str, ...] = ()
    #: a list's item type (a parameter declared ``{type: list, items: distance}``)
    item: ValueType | None = None

    def describe(self) -> str:
        if self.choices:
            return "one of " + ", ".join(self.choices)
        if self.item is not None:
            return f"list of {self.item.describe()}"
        return f"{self.name} ({self.unit})" if self.unit else self.name

    def schema(self) -> dict[str, Any]:
        if self.choices:
            return {"enum": list(self.choices)}
        return dict(self.json_schema)


#: a number written as zero (``0``, ``0.0``, ``.0e5``), without its sign
_ZERO_NUMBER = r"(?:0+(?:\.0*)?|\.0+)(?:[eE][-+]?[0-9]+)?"
#: a text :func:`parse_quantity` reads as 0 with no unit (``"0"``, ``"-0.0"``): a JSON Schema
#: pattern (``wait: "0"`` is valid; the schema refused it)
ZERO_TEXT_PATTERN = rf"^\s*[-+]?{_ZERO_NUMBER}\s*$"
_ZERO_TEXT = re.compile(ZERO_TEXT_PATTERN)


def percent_sign_kept(vtype: ValueType, text: str) -> str:
    """A value's text as its uses insert and its nodes' names show it, a percent's bare zero
    (``-p low=0``, ``default: 0``, a subtree's ``below: 0``) as ``0%``: every other percent
    shows with its sign (``-p low=0.2`` as ``20%``), and ``battery(below=0)`` beside
    ``battery(below=20%)`` read as a number of another kind. Any other text is as it is."""
    if vtype.name == "percent" and _ZERO_TEXT.match(text):
        return "0%"
    return text


def quantity_schema(dimension: str, *, signed: bool = True) -> dict[str, Any]:
    """The JSON Schema of a quantity of ``dimension`` as :func:`parse_quantity` reads it:
    a number and a unit, a 0 (a number or a text). ``signed=False``: no minus sign but on a
    zero (a parameter whose minimum is not below 0: a pattern can exclude a negative value,
    though it cannot hold a range; ``-0s`` is 0, which validate takes and the schema
    refused)."""
    unsigned = _NUMBER.removeprefix("[-+]?")
    number = _NUMBER if signed else rf"(?:\+?{unsigned}|-{_ZERO_NUMBER})"
    units = "|".join(re.escape(u) for u in UNITS[dimension])
    compound = (
        # a duration in several units (compound_duration); the order of its units is
        # validate's to check, as a range is
        [{"type": "string", "pattern": rf"^\s*(?:{unsigned}\s*(?:{units})\s*){{2,}}$"}]
        if dimension == "duration"
        else []
    )
    return {
        "anyOf": [
            {"type": "string", "pattern": rf"^\s*{number}\s*({units})\s*$"},
            *compound,
            {"type": "string", "pattern": ZERO_TEXT_PATTERN},
            {"const": 0},
        ]
    }


def _quantity_type(dimension: str) -> ValueType:
    return ValueType(
        dimension,
        lambda v: parse_quantity(dimension, v),
        CANONICAL[dimension],
        (("anyOf", quantity_schema(dimension)["anyOf"]),
         ("description", f"{with_article(dimension)}, e.g. {EXAMPLES[dimension]}")),
    )  # fmt: skip


def _parse_int(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise UnitError(f"expected an integer, got {described(value)}{_miswritten_text(value)}")
    return _not_too_large(value)


#: the most bits of an integer ``str()`` writes in decimal (4,300 digits by default)
_BITS_STR_TAKES = int(sys.get_int_max_str_digits() / math.log10(2)) - 8


def _not_too_large(value: int) -> int:
    """``value``, or :class:`UnitError` when no float holds it: a range check, a comparison
    and a plugin compute with floats, and an integer of 400 digits (or 0xfff... of 300) was
    "internal error (OverflowError)" at 1:1."""
    try:
        float(value)
    except OverflowError:
        # str() refuses past 4,300 digits (0xfff... of a page): then the count from its bits
        size = (
            f"{len(str(abs(value))):,}"
            if value.bit_length() <= _BITS_STR_TAKES
            else f"about {math.floor(value.bit_length() * math.log10(2)) + 1:,}"
        )
        raise UnitError(
            f"an integer of {size} digits is too large a number: at most about "
            f"{sys.float_info.max:.3g}"
        ) from None
    return value


#: a number YAML 1.1 reads as text: an exponent without a decimal point and a sign (``1e400``,
#: ``2e3``, ``1.0e3``; ``1.0e+3`` is a number)
_NUMBER_TEXT = re.compile(rf"\s*{_NUMBER}\s*", re.ASCII)


def _parse_float(value: object) -> float:
    """A number, finite: ``1e400`` (text to YAML) was "expected a number", ``1.0e400`` and
    ``.inf`` were taken as infinity."""
    if isinstance(value, str) and _NUMBER_TEXT.fullmatch(value):
        if not math.isfinite(float(value)):
            raise UnitError(f"{value.strip()} is too large a number: out of range (not finite)")
        raise UnitError(
            f"expected a number, got the text {quoted(value)}: YAML reads an exponent as a "
            "number only with a decimal point and a sign (1.0e+3)"
        )
    if not _is_number(value):
        raise UnitError(f"expected a number, got {described(value)}{_miswritten_text(value)}")
    if isinstance(value, int):
        return float(_not_too_large(value))
    if not math.isfinite(value):  # type: ignore[arg-type]
        raise UnitError(f"expected a finite number, got {value}")
    return float(value)  # type: ignore[arg-type]


#: the words a boolean is written as, each with the boolean it means: quoted, a text
_BOOLEAN_WORDS = {"true": True, "yes": True, "on": True, "false": False, "no": False, "off": False}


def _parse_bool(value: object) -> bool:
    """A boolean; a quoted ``'true'`` is told it is a text, and how to write the boolean: a
    plugin's ``Param("x", BOOL, default="true")`` was refused with "expected true or false,
    got 'true'", which reads as its own contradiction."""
    if not isinstance(value, bool):
        said = described(value)
        meant = _BOOLEAN_WORDS.get(value.strip().lower()) if isinstance(value, str) else None
        if meant is not None:
            said = f"the text {said}: write {str(meant).lower()} unquoted ({meant} in Python)"
        raise UnitError(f"expected true or false, got {said}")
    return value


def _parse_str(value: object) -> str:
    if isinstance(value, bool):  # `default: no`: the text was meant
        raise UnitError(
            f"expected a text, got {described(value)}: YAML 1.1 reads yes/no, on/off and "
            "true/false as booleans: quote the text"
        )
    if not isinstance(value, str | int | float):
        raise UnitError(f"expected a text, got {described(value)}")
    return str(value)


def _parse_str_list(value: object) -> tuple[str, ...]:
    if isinstance(value, str):
        return (value,)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise UnitError(f"expected a list of texts, got {described(value)}")
    return tuple(value)


DURATION = _quantity_type("duration")
SPEED = _quantity_type("speed")
DISTANCE = _quantity_type("distance")
ANGLE = _quantity_type("angle")
PERCENT = _quantity_type("percent")
#: the words PyYAML (YAML 1.1) reads as a boolean and a YAML 1.2 reader (an editor's YAML
#: extension, check-jsonschema) as a text, by the boolean: ``vacuum: on`` is true to
#: ``validate``, the text "on" to an editor, so the schema takes them where a boolean may stand
#: (``y``/``n`` are texts to both: PyYAML leaves them out of its booleans)
YAML11_BOOLEAN_WORDS: dict[bool, tuple[str, ...]] = {
    value: tuple(form for word in words for form in (word, word.title(), word.upper()))
    for value, words in ((True, ("yes", "on")), (False, ("no", "off")))
}
#: an integer as PyYAML (YAML 1.1) reads it that a YAML 1.2 reader takes as a text: with
#: ``_`` between its digits (``1_000``), or binary (``0b101``); validate warns of both
#: (yamlsource.yaml12_text_number). Octal (``010``) and base 60 (``1:30``) validate refuses.
YAML11_INT_TEXT = r"[-+]?(?:0b[01_]+|0x[0-9a-fA-F]*_[0-9a-fA-F_]*|[1-9][0-9]*_[0-9_]*)"
#: a float as PyYAML reads it, with ``_`` between its digits (``1_000.5``), a text to YAML 1.2
YAML11_FLOAT_TEXT = (
    r"(?:[-+]?(?:[0-9]+_[0-9_]*\.[0-9_]*|[0-9][0-9_]*\.[0-9]*_[0-9_]*)(?:[eE][-+][0-9]+)?"
    r"|\.[0-9]*_[0-9_]*(?:[eE][-+][0-9]+)?)"
)


def boolean_schema(only: bool | None = None) -> dict[str, Any]:
    """A boolean (``only``: that one) as JSON Schema, with the YAML 1.1 words for it that a
    YAML 1.2 reader sees as texts (:data:`YAML11_BOOLEAN_WORDS`): the schema is never
    stricter than ``validate``, which reads the file with PyYAML."""
    values = (True, False) if only is None else (only,)
    words = [word for value in values for word in YAML11_BOOLEAN_WORDS[value]]
    exact = {"type": "boolean"} if only is None else {"const": only}
    return {"anyOf": [exact, {"enum": words}]}


def _yaml11_text(pattern: str) -> dict[str, Any]:
    return {"type": "string", "pattern": f"^{pattern}$"}


INT = ValueType(
    "int",
    _parse_int,
    json_schema=(("anyOf", [{"type": "integer"}, _yaml11_text(YAML11_INT_TEXT)]),),
)
FLOAT = ValueType(
    "float",
    _parse_float,
    takes=("int",),
    json_schema=(
        ("anyOf", [{"type": "number"}, _yaml11_text(f"(?:{YAML11_INT_TEXT}|{YAML11_FLOAT_TEXT})")]),
    ),
)
BOOL = ValueType("bool", _parse_bool, json_schema=tuple(boolean_schema().items()))
#: a number is a text too (``log: 5`` logs "5"), a boolean is not (``default: no``)
STR = ValueType(
    "str", _parse_str, json_schema=(("anyOf", [{"type": "string"}, {"type": "number"}]),)
)
STR_LIST = ValueType(
    "str_list",
    _parse_str_list,
    json_schema=(("anyOf", [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]),),
)

#: The words a drive radius may be instead of a distance (``drive``'s special radii).
RADIUS_WORDS: tuple[str, ...] = ("straight", "spin_left", "spin_right")


def _parse_radius(value: object) -> object:
    if isinstance(value, str) and value in RADIUS_WORDS:
        return value
    try:
        return parse_quantity("distance", value)
    except UnitError as exc:
        raise UnitError(f"{exc}; or one of {', '.join(RADIUS_WORDS)}") from None


#: A turn radius: a distance (positive turns left) or one of :data:`RADIUS_WORDS`.
RADIUS = ValueType(
    "radius",
    _parse_radius,
    "mm",
    (("anyOf", [{"enum": list(RADIUS_WORDS)}, dict(DISTANCE.schema())]),),
    takes=("distance",),
)

#: Types a mission parameter or a blackboard key may be declared with.
VALUE_TYPES: dict[str, ValueType] = {
    t.name: t for t in (DURATION, SPEED, DISTANCE, ANGLE, PERCENT, INT, FLOAT, BOOL, STR, RADIUS)
}


def enum(*choices: str) -> ValueType:
    """A closed set of words: ``enum("left", "right", "any")``."""

    def parse(value: object) -> str:
        if not isinstance(value, str) or value not in choices:
            hint = _miswritten_text(value)
            if not hint and isinstance(value, str):
                hint = closest(value, choices)
            if isinstance(value, bool):
                hint = _boolean_word(value, choices)
            raise UnitError(f"expected one of {', '.join(choices)}, got {described(value)}{hint}")
        return value

    return ValueType("enum", parse, choices=tuple(choices))


def list_of(item: ValueType) -> ValueType:
    """A list of values of ``item`` type, as a tuple: a list parameter's type (``{type:
    list, items: distance}``, BehaviorTree.CPP's vector port). Every item that does not
    parse is said (:class:`ItemErrors`: a mission says each at its own place)."""

    def parse(value: object) -> tuple[Any, ...]:
        if not isinstance(value, list | tuple):
            raise UnitError(
                f"expected a list of {item.describe()} written in brackets, [a, b], got "
                f"{described(value)}"
            )
        items, problems = [], []
        for index, each in enumerate(value):
            try:
                items.append(item.parse(each))
            except UnitError as exc:
                problems.append((index, str(exc)))
        if problems:
            raise ItemErrors("item", len(value), problems)
        return tuple(items)

    schema = (("type", "array"), ("items", item.schema()))
    return ValueType("list", parse, json_schema=schema, item=item)


#: the words YAML 1.1 reads as a boolean, by the boolean
_YAML11_BOOLEANS = {True: ("yes", "on", "true"), False: ("no", "off", "false")}


def _boolean_word(value: bool, choices: Sequence[str]) -> str:
    """For an enum given a boolean: the choice YAML 1.1 read as it, and how to keep it a
    word (``oi_mode: off`` said "got a boolean (false)" and no more)."""
    meant = [c for c in choices if c.lower() in _YAML11_BOOLEANS[value]]
    if not meant:
        return ""
    return (f": YAML 1.1 reads {meant[0]} as the boolean {str(value).lower()}: quote it, "
            f"'{meant[0]}'")  # fmt: skip


def compatible(source: ValueType, target: ValueType, *, as_stored: bool = False) -> bool:
    """May a value of ``source`` type fill a slot of ``target`` type? Any value fills an
    ``any`` slot (a key whose declaration was refused is typed ``any``: its reader's
    ``${p}`` was "an int, but check.value needs any", an error after the real one). An
    enum fills any slot that reads each of its words (:func:`enum_misfits`): a ``str``
    slot, an enum of more words, the power LED's colour, a radius; one rule for every slot
    that takes words, where only ``str`` and enums were listed (an enum of exactly the
    colour words was "one of green, orange, red, but leds.power_color needs power_color").
    ``as_stored``: the value is a blackboard key's, used as stored (no parsing during a
    tick), so each word must read as itself. A type that ``takes`` another reads its values
    as they are (:attr:`ValueType.takes`)."""
    if target.name == "any":
        return True
    if source.item is not None or target.item is not None:  # lists: item by item
        return (
            source.item is not None
            and target.item is not None
            and compatible(source.item, target.item, as_stored=as_stored)
        )
    if source.name == target.name and source.choices == target.choices:
        return dict(source.fields) == dict(target.fields)  # a record's, in any order
    if source.choices:
        return not enum_misfits(source, target, as_stored=as_stored)
    return source.name in target.takes


def enum_misfits(
    source: ValueType, target: ValueType, *, as_stored: bool = False
) -> list[tuple[str, str]]:
    """The words of the enum ``source`` that a ``target`` slot does not read, each with why
    (what the slot's type says of it); ``as_stored``: those it reads as another value too
    (``red``, the colour byte 255). None: the enum fills the slot."""
    misfits = []
    for word in source.choices:
        try:
            value = target.parse(word)
        except ValueError as exc:  # UnitError, or a plugin type's own
            misfits.append((word, str(exc)))
            continue
        if as_stored and value != word:
            misfits.append((word, f"it is read as {value!r}, and a stored value is used as it is"))
    return misfits


def convert(source: ValueType, target: ValueType, value: Any) -> Any:
    """``value`` (already of ``source`` type) as ``target`` wants it: an enum's word read by
    the slot's type (``red``: the colour byte 255), an int as a float."""
    if source.item is not None and target.item is not None:
        return tuple(convert(source.item, target.item, each) for each in value)
    if target.choices or source.choices:
        return target.parse(value)
    return float(value) if target.name == "float" else value


def closest(word: str, candidates: Sequence[str]) -> str:
    """ " (did you mean 'x'?)" or ""; the difflib suggestion every unknown name gets. A
    word with a letter that is not ASCII among names that all are has it named, with the
    ASCII letter it stands for where the suggestion shows it (:func:`lookalike_letter`):
    ``dr\u0456ve`` (a Cyrillic i) read on screen "unknown node 'drive' (did you mean
    'drive'?)"."""
    found = closest_name(word, candidates)
    odd = lookalike_letter(word, found, candidates)
    if found is None:
        return f" ({odd})" if odd else ""
    return f" (did you mean {found!r}?{' ' + odd if odd else ''})"


def closest_name(word: str, candidates: Sequence[str]) -> str | None:
    """The candidate :func:`closest` suggests, or None: for a caller that goes on as if it
    had been written (a misspelt ``paramaters:`` read as ``parameters:``). The word is
    compared NFKC-folded: a fullwidth ``\uff44\uff52\uff49\uff56\uff45`` is ``drive``."""
    import difflib

    folded = unicodedata.normalize("NFKC", word) if not word.isascii() else word
    if folded != word and folded in candidates:
        return folded
    found = difflib.get_close_matches(folded, list(candidates), n=1, cutoff=0.6)
    return found[0] if found else None


def lookalike_letter(word: str, meant: str | None, candidates: Sequence[str]) -> str:
    """``'\u0456' (U+0456 CYRILLIC SMALL LETTER BYELORUSSIAN-UKRAINIAN I) is not the ASCII
    letter 'i'``: the first letter or digit of ``word`` that is not ASCII, where the names
    it may be (``candidates``) all are; the ASCII letter it is not, from its NFKC form
    (fullwidth ``\uff44``: 'd') or the suggestion ``meant`` at its place (same length);
    "" for an ASCII word, or names that are not ASCII themselves."""
    if word.isascii() or not all(name.isascii() for name in candidates):
        return ""
    for index, char in enumerate(word):
        if char.isascii() or not char.isalnum():
            continue
        shown = named_character(char)
        folded = unicodedata.normalize("NFKC", char)
        if folded.isascii() and len(folded) == 1:
            kind = "digit" if folded.isdigit() else "letter"
            return f"{shown} is not the ASCII {kind} {folded!r}"
        if meant is not None and len(meant) == len(word) and meant[index] != char:
            return f"{shown} is not the ASCII letter {meant[index]!r}"
        return f"{shown} is not an ASCII letter"
    return ""


def _parse_any(value: object) -> object:
    return value


#: Any YAML value; the compiler types it from context (``set``'s value by its key).
ANY = ValueType("any", _parse_any, json_schema=())


def _parse_mark(value: object) -> object:
    raise UnitError("a mark has no written form: the `mark` action writes it")


#: An odometry mark on the blackboard (written by ``mark``, read by ``odometry``).
MARK = ValueType("mark", _parse_mark, json_schema=(("type", "null"),))
VALUE_TYPES["mark"] = MARK


def _real(value: object) -> bool:
    """A finite number, not a bool (numpy's numbers too: a plugin computes with them)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    return math.isfinite(value)


#: what each plain type holds when written in code (``write_key``), and how to say it
_HELD: dict[str, tuple[Callable[[object], bool], str]] = {
    "int": (lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool), "an integer"),
    "float": (_real, "a finite number"),
    "bool": (lambda v: isinstance(v, bool), "true or false (a bool)"),
    "str": (lambda v: isinstance(v, str), "a text"),
    "str_list": (
        lambda v: isinstance(v, list | tuple) and all(isinstance(i, str) for i in v),
        "a list of texts",
    ),
    "radius": (
        lambda v: _real(v) or v in RADIUS_WORDS,
        f"a number of mm or one of {', '.join(RADIUS_WORDS)}",
    ),
}


def held(vtype: ValueType, value: object) -> str | None:
    """None if ``value`` is one of ``vtype`` as the readers of a key of that type take it
    (its canonical form: a speed is a number of mm/s, not ``"200 mm/s"``), else what was
    allowed and what was found. A value written in code (``write_key``) has no parser
    between it and its readers: this is the check a parser would have made. A mark's form
    is the robot's (``Odometry``): its writer checks that."""
    if vtype.fields:
        return _held_record(vtype, value)
    check: Callable[[object], bool]
    if vtype.choices:
        check, allowed = vtype.choices.__contains__, vtype.describe()
    elif vtype.name in CANONICAL:
        check, allowed = _real, f"a number of {vtype.unit}"
    elif vtype.name in _HELD:
        check, allowed = _HELD[vtype.name]
    else:  # any, mark
        return None
    if check(value):
        return None
    return f"expected {allowed}, got {_found(value)}"


def _found(value: object) -> str:
    """What a value is, for a message about code's value: ``'fast' (a str)``."""
    told = described(value)
    plain = value is None or isinstance(value, bool | list | dict)
    return told if plain else f"{told} ({with_article(type(value).__name__)})"


def _held_record(vtype: ValueType, value: object) -> str | None:
    fields = dict(vtype.fields)
    if not isinstance(value, Mapping) or set(value) != set(fields):
        return f"expected a mapping of {', '.join(fields)}, got {_found(value)}"
    for name, ftype in fields.items():
        problem = held(ftype, value[name])
        if problem is not None:
            return f"field {name}: {problem}"
    return None
