"""What a mission learned, across a batch of episodes: ``eval --key NAME``.

A mission's outcome says whether it succeeded; what it found out on the way (the dirt a
plugin measured, the leg it reached, the side it turned to) is on its blackboard. ``eval
--key dirt_level`` reads the key's value when each episode ends (``episode.final_values``), writes
it as a column of ``--out`` (``key:dirt_level``, :data:`KEY_PREFIX`) and summarises it over
the episodes (:func:`summarize_keys`): for numbers their mean, sd and min..max, for anything
else (bools, enum words, text) how many episodes ended with each value; and, either way, how
many episodes never wrote the key (its value None at the end). Before, the only way to see
it was to make the mission fail on it and read the success rate, which mixed it with the
real failures. The name is checked against the mission's ``blackboard:`` declaration before
any episode runs (:func:`key_problem`).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from roomba_bt.behaviours.units import MARK, ValueType, closest
from roomba_bt.evaluate.coverage import Spread
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.printable import ANY_CONTROL, escaped

#: A key's column in ``--out`` is its name after this (``key:dirt_level``, ``key:wp.distance``):
#: a key's name has no ``:``, so it can never be taken for one of the other columns.
KEY_PREFIX = "key:"


def key_problem(name: str, declared: Mapping[str, ValueType], mission: str) -> str | None:
    """What is wrong with ``--key name`` for ``mission``, whose ``blackboard:`` declares
    ``declared``: a key it does not declare, a field its record lacks (``wp.distance``,
    as ``check`` reads one), a record named whole or an odometry mark (neither is one value
    a table can hold); None when the key can be reported."""
    key, dot, field = name.partition(".")
    vtype = declared.get(key)
    if vtype is None:
        keys = f"its keys: {', '.join(declared)}" if declared else "it has no blackboard: section"
        return (
            f"--key {name}: mission {mission} declares no blackboard key {key!r}"
            f"{closest(key, list(declared))} ({keys})"
        )
    fields = dict(vtype.fields)
    if dot and not fields:
        return f"--key {name}: blackboard key {key!r} of {mission} is no record (no fields)"
    if dot and field not in fields:
        return (
            f"--key {name}: the record {key!r} of {mission} has no field {field!r}"
            f"{closest(field, list(fields))} (its fields: {', '.join(fields)})"
        )
    if fields and not dot:
        named = ", ".join(f"{key}.{f}" for f in fields)
        return f"--key {name}: {key!r} of {mission} is a record: name one of its fields ({named})"
    if vtype is MARK:
        return (
            f"--key {name}: {key!r} of {mission} is an odometry mark, not one value; --key "
            "reports numbers, bools, words and text"
        )
    return None


def key_unit(name: str, declared: Mapping[str, ValueType]) -> str:
    """The canonical unit a key's numbers are in (``mm``, ``s``; "" for a plain number),
    as :func:`key_problem` found it declared."""
    key, _, field = name.partition(".")
    vtype = declared[key]
    return dict(vtype.fields)[field].unit if field else vtype.unit


def _numeric(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@dataclass(frozen=True)
class KeySummary:
    """One ``--key``'s values over a batch of episodes."""

    name: str
    #: the unit its numbers are in ("" for none: a count, a fraction, text)
    unit: str
    #: the episodes that wrote it, and those that never did (its value None at the end)
    written: int
    unwritten: int
    #: mean, sd, min and max when every value written is a number; else None
    numbers: Spread | None
    #: how many episodes ended with each value, the commonest first (not for numbers)
    counts: tuple[tuple[Any, int], ...]

    def line(self) -> str:
        """``key          dirt_level: mean 2.5 (sd 1.2, 0..4) over 27 episodes; 3 never
        wrote it``, or ``key          side: left 12, right 15 ...`` for words."""
        unit = f" {self.unit}" if self.unit else ""
        if self.numbers is not None:
            n = self.numbers
            said = f"mean {n.mean:.4g}{unit} (sd {n.sd:.3g}, {n.low:.4g}..{n.high:.4g}{unit})"
        elif self.counts:
            said = ", ".join(f"{_shown(value)} {count}" for value, count in self.counts)
        else:
            said = "no value"
        over = f" over {self.written} episodes" if self.numbers is not None else ""
        never = f"; {self.unwritten} never wrote it" if self.unwritten else ""
        return escaped(f"key          {self.name}: {said}{over}{never}", ANY_CONTROL)

    def to_dict(self) -> dict[str, Any]:
        """For ``eval --json``: ``written``, ``never_written``, and ``mean``, ``sd``, ``min``
        and ``max`` for numbers, else ``counts`` by value (``true``/``false`` for bools)."""
        out: dict[str, Any] = {
            "unit": self.unit,
            "written": self.written,
            "never_written": self.unwritten,
        }
        if self.numbers is not None:
            return {**out, **self.numbers.to_dict()}
        return {**out, "counts": {_shown(value): count for value, count in self.counts}}


def _shown(value: Any) -> str:
    """A value as the summary says it: bools as ``true``/``false`` (as YAML writes them)."""
    return str(value).lower() if isinstance(value, bool) else str(value)


def summarize_keys(
    results: Sequence[EpisodeResult], names: Sequence[str], units: Mapping[str, str]
) -> list[KeySummary]:
    """Each of ``names`` over ``results`` (``units``: each one's, :func:`key_unit`)."""
    out = []
    for name in names:
        values = [dict(r.keys).get(name) for r in results]
        written = [v for v in values if v is not None]
        numeric = bool(written) and all(_numeric(v) and math.isfinite(v) for v in written)
        counts = Counter(written)
        out.append(
            KeySummary(
                name,
                units.get(name, ""),
                len(written),
                len(values) - len(written),
                Spread.of([float(v) for v in written]) if numeric else None,
                () if numeric else tuple(sorted(counts.items(), key=lambda c: (-c[1], str(c[0])))),
            )
        )
    return out
