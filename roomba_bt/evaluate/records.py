"""Results as data: one flat record per episode, written as JSON Lines or CSV and read back.

``roomba-bt eval ... --out results.jsonl`` (or ``.csv``, chosen by the suffix) writes one
record per episode in spec order; :func:`read_results` reads either back into
:class:`~roomba_bt.evaluate.episode.EpisodeResult` values that summarise to the same
:class:`~roomba_bt.evaluate.stats.Summary` (floats are written with ``repr``, which reads back
exactly). In pandas::

    import pandas as pd
    df = pd.read_json("results.jsonl", lines=True)
    df.groupby("outcome").mission_time.median()

Columns (:data:`COLUMNS`): ``outcome`` is the word the run summary prints (``SUCCESS``,
``FAILURE``, ``TIMEOUT``, ...); times in seconds, positions and distances in metres, headings
in degrees. ``params`` is an object in JSON Lines and ``name=value;name=value`` in CSV. The
per-bump contact steps are not written: they are for figures, not tables. An episode run for a
plot (``eval --plot``) has a ``path`` column: its trajectory as the plot draws it
(:func:`kept_path`: to the mm, the points a straight line passes within 5 mm of left out;
``[[x, y], ...]`` in metres, ``x:y;x:y`` in CSV), so that ``eval --resume --plot`` draws the
episodes read back from it instead of running them again; absent (an empty cell in CSV) without
``--plot``. Readers should ignore columns they do not know: later versions add columns, never
rename or drop one. ``falls`` counts the robot's own falls to Passive (the run summary's
``falls`` line: a cliff or a wheel drop in Safe, the charger) and ``falls_by_cause`` splits
them (``{"cliff": 4}``; ``cliff=4;wheel drop=1`` in CSV); ``hazard_falls`` counts those of them
that were no docking (every cause but ``charger``: a dock mission that docks in Safe falls to
Passive on the charger in every episode, which ``falls > 0`` read as a hazard); a file written
before they were recorded reads back as episodes without a fall. ``mission_said`` is the
mission's last words (``run``'s ``mission said`` line; empty when it said nothing, and in files
written before it was recorded): which way it ended, e.g. a patrol's ``patrol done (laps: 1)``
or its docking on a low battery, both a ``SUCCESS``. ``profile`` is the robot model the mission
ran as (``create2``, ``roomba600``...; empty in files written before it was recorded).
``undeclared_keys`` holds each blackboard key a behaviour wrote that the mission does not
declare, with who wrote it first and where (``{"secret": "by 'probe' at lab.py:17"}``; its JSON
text in CSV; empty or absent: none, or a file written before it was recorded): the warning
``run`` says, which the summary of a resumed run or of ``eval --from`` says again.
``slowest_tick_in`` names the behaviour that held the episode's slowest tick on the wall clock
(a plugin's ``time.sleep`` or I/O in its ``update``: ``sleepy (Sleepy.update at
sleepy.py:11)``, as the report's ``slowest tick ... in ...`` warning and ``--json``'s
``slow_ticks`` name it) and ``slowest_tick`` that tick's host seconds; empty (null) for an
episode no behaviour held, in files written before they were recorded, and under
``--reproducible`` (measured on the host, as ``wall_time`` is). ``refused_actions`` holds each
action of the user's own code (a plugin's) whose commands the mode guard refused, with its
class and where it is defined (``{"passive_drive": "PassiveDrive (lab.py:7)"}``; its JSON text
in CSV; empty or absent: none, or a file written before it was recorded): what ``run`` tells
its author on stderr, which the summary says again. ``undeclared_like`` holds, of the
``undeclared_keys``, each that may be a misspelling of a key the mission declares, with that
key (``{"dirt_levl": "dirt_level"}``; its JSON text in CSV; empty or absent: none, or a file
written before it was recorded): the summary's `` (did you mean 'dirt_level'?)``, as ``run``
says it. ``frames_lost`` counts the robot's sensor frames the run never read (the line's
faults; absent from files written before it was recorded: 0).

Coverage (:data:`COVERAGE_COLUMNS`, after the others) is empty (``null`` / an empty cell) for
an episode whose brushes never ran: ``coverage`` is the fraction of the start area (or of all
the reachable floor: ``coverage_area`` empty) cleaned at the end, ``coverage_5min`` ...
``coverage_20min`` the same at those mission times (after an episode's end: its final
coverage if it succeeded, empty if it was cut short or failed: :func:`coverage_at`),
``coverage_overall`` of all the reachable floor, ``coverage_by_area`` per named room,
``coverage_curve`` the samples every 30 s (``[[t, c], ...]``; in CSV ``t:c;t:c``),
``longest_idle`` the longest brush time (s) without new floor. In pandas,
``df.groupby("mission").coverage_10min.describe()`` (NaN, not counted, where cut short).

Each ``eval --key NAME`` adds a column ``key:NAME`` (last in CSV): the blackboard key's value
when the episode ended, null / an empty cell when it never wrote it
(:mod:`roomba_bt.evaluate.keys`).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import re
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import IO, Any, NoReturn

from roomba_bt.evaluate.episode import Coverage, EpisodeResult
from roomba_bt.evaluate.keys import KEY_PREFIX
from roomba_bt.evaluate.paths import PATH_TOLERANCE_M as PATH_TOLERANCE_M  # re-exported
from roomba_bt.evaluate.paths import kept_path as kept_path  # re-exported: callers name it here
from roomba_bt.printable import escaped, shortened
from roomba_bt.runtime.claimed import ClaimedFile
from roomba_bt.runtime.recording import (
    DuplicateKey,
    bounded_lines,
    json_read,
    long_number,
    over_line_limit,
    twice,
)
from roomba_bt.runtime.summary import falls_in_order, hazard_falls

FORMATS = (".jsonl", ".csv")

#: The values a number's column allows besides its kind's (both ends included; None: any):
#: a count, a time or a distance is never below 0, a coverage never above 1 (a results file
#: of ``"bumps": -3`` or ``"coverage": 1.5`` was summarised as -3.0 bumps an episode)
Allowed = tuple[float, float] | None
AT_LEAST_0: Allowed = (0.0, math.inf)
FRACTION: Allowed = (0.0, 1.0)
#: how a message says each range
_ALLOWED_SAID = {AT_LEAST_0: "0 or more", FRACTION: "from 0 to 1"}

#: record column -> (EpisodeResult field, kind, the values it allows); start/end are split
#: into x, y, heading. The one table :func:`to_record` writes and :func:`from_record` reads
COLUMNS: dict[str, tuple[str, str, Allowed]] = {
    "mission": ("mission", "str", None),
    "world": ("world", "str", None),
    "seed": ("seed", "int", None),
    "outcome": ("outcome", "outcome", None),
    "reason": ("reason", "str", None),
    "stage": ("stage", "str", None),
    "mission_time": ("time_s", "float", AT_LEAST_0),
    "wall_time": ("wall_s", "float?", AT_LEAST_0),
    "ticks": ("ticks", "int", AT_LEAST_0),
    "start_x": ("start", "0", None),
    "start_y": ("start", "1", None),
    "start_heading": ("start", "2", None),
    "end_x": ("end", "0", None),
    "end_y": ("end", "1", None),
    "end_heading": ("end", "2", None),
    "params": ("params", "params", None),
    "distance": ("distance_m", "float", AT_LEAST_0),
    "bumps": ("bumps", "int", AT_LEAST_0),
    "cliffs": ("cliffs", "int", AT_LEAST_0),
    "fell": ("fell", "bool", None),
    "docked": ("docked", "bool", None),
    "charging": ("charging", "bool", None),
    "violations": ("violations", "int", AT_LEAST_0),
    "commands_sent": ("commands_sent", "int", AT_LEAST_0),
    "commands_refused": ("commands_refused", "int", AT_LEAST_0),
    "loops": ("loops", "float", None),
    "longest_stall": ("longest_stall_s", "float", AT_LEAST_0),
    "longest_trapped": ("longest_trapped_s", "float?", AT_LEAST_0),
    "worker": ("worker", "str", None),
    "cpu_time": ("cpu_s", "float?", AT_LEAST_0),
    "falls": ("falls", "falls total", AT_LEAST_0),
    "falls_by_cause": ("falls", "falls by cause", None),
    "hazard_falls": ("falls", "hazard falls", AT_LEAST_0),
    "mission_said": ("said", "str?", None),
    "profile": ("profile", "str?", None),
    "undeclared_keys": ("undeclared", "undeclared", None),
    "slowest_tick": ("slowest_tick_s", "float?", AT_LEAST_0),
    "slowest_tick_in": ("slowest_in", "str?", None),
    "refused_actions": ("refused_actions", "refused", None),
    "undeclared_like": ("undeclared_like", "like", None),
    "frames_lost": ("frames_lost", "int?", AT_LEAST_0),
}

#: the coverage columns (empty when the episode did not clean): name -> (Coverage field,
#: the values it allows: each area's and each sample's fraction for ``by_area`` and ``curve``)
COVERAGE_COLUMNS: dict[str, tuple[str, Allowed]] = {
    "coverage": ("final", FRACTION),
    "coverage_area": ("area", None),
    "coverage_5min": ("at:300", FRACTION),
    "coverage_10min": ("at:600", FRACTION),
    "coverage_20min": ("at:1200", FRACTION),
    "coverage_overall": ("overall", FRACTION),
    "coverage_by_area": ("by_area", FRACTION),
    "coverage_curve": ("curve", FRACTION),
    "longest_idle": ("longest_idle_s", AT_LEAST_0),
    "cleaning_time": ("cleaning_s", AT_LEAST_0),
}


#: what made the episodes (after the coverage columns; the same in each row of a mission):
#: the roomba-bt release, the world file's SHA-256, each file the mission was compiled from
#: by its path from the results file's folder (``{"../missions/dock.yaml": SHA-256}``; in
#: CSV ``name=SHA-256;...``) and each installed plugin its tree used (``{"roomba-bt-lab":
#: {"version": "0.3.1", "sha256": ...}}``; in CSV ``name=version:SHA-256;...``), as a
#: record's header has them. Empty in a file written before, and in rows written without them
PROVENANCE_COLUMNS = ("roomba_bt_version", "world_sha256", "sources", "plugins")
#: the trajectory as a plot draws it (:func:`kept_path`), in an episode run for one
PATH_COLUMN = "path"
#: the columns ``--reproducible`` leaves empty: measured on the wall clock, or naming a
#: process, they differ on every run of the same episodes (whether a behaviour is found
#: holding a tick, and for how long, is the host's: the watch looks on the wall clock)
MEASURED_COLUMNS = ("wall_time", "cpu_time", "worker", "slowest_tick", "slowest_tick_in")


class ResultsFileError(ValueError):
    """A results file that cannot be read back: the message names the file and line."""


def results_format(path: str | Path) -> str:
    """The format a path's suffix chooses; ValueError naming the allowed ones otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{path}: unknown results format {suffix or '(no suffix)'!r}; "
                         f"allowed: {', '.join(FORMATS)}")  # fmt: skip
    return suffix


def to_record(result: EpisodeResult) -> dict[str, Any]:
    """One episode as a flat mapping of :data:`COLUMNS` (params as a mapping)."""
    out: dict[str, Any] = {}
    for column, (name, kind, _) in COLUMNS.items():
        value = getattr(result, name)
        if kind == "outcome":
            value = value.upper()
        elif kind in ("0", "1", "2"):
            value = value[int(kind)]
        elif kind == "params":
            value = dict(value)
        elif kind == "falls total":
            value = sum(times for _, times in value)
        elif kind == "falls by cause":
            value = dict(value)
        elif kind == "hazard falls":
            value = sum(hazard_falls(dict(value)).values())
        elif kind in ("undeclared", "refused", "like"):
            value = dict(value)
        out[column] = value
    if not result.slowest_in:  # no behaviour held its ticks: no such tick, not one of 0 s
        out["slowest_tick"] = None
    out.update(_coverage_record(result))
    if result.trajectory:  # an episode run for a plot: what the plot draws of it
        out[PATH_COLUMN] = [[x, y] for x, y in kept_path(result.trajectory)]
    out.update((KEY_PREFIX + name, value) for name, value in result.keys)
    return out


def _path_from(raw: Any) -> tuple[tuple[float, float], ...]:
    """A record's ``path`` as a trajectory: a list of ``[x, y]`` in JSON Lines, ``x:y;...``
    in CSV; none when the column is empty or absent (an episode run without ``--plot``)."""
    if raw is None or raw == "":
        return ()
    if isinstance(raw, str):
        raw = [point.split(":") for point in raw.split(";") if point]
    if not isinstance(raw, list):
        raise ValueError(f"path {raw!r}: expected [x, y] points")
    return tuple((_finite(x), _finite(y)) for x, y in raw)


def same_episode(one: EpisodeResult, other: EpisodeResult) -> bool:
    """Whether two records are of the same episode, made alike: their rows the same but for
    the wall-clock columns and the ``path`` (one written under ``--plot``, the other not)."""
    return compared_row(one) == compared_row(other)


def compared_row(result: EpisodeResult) -> dict[str, Any]:
    """What :func:`same_episode` compares of an episode: its row but for the wall-clock
    columns and the path (a reader of many records keeps the first's, not every line)."""
    row = written_record(result, reproducible=True)
    row.pop(PATH_COLUMN, None)
    return row


def coverage_at(result: EpisodeResult, seconds: float) -> float | None:
    """The floor cleaned at ``seconds`` of mission time (None: the brushes never ran). After
    the episode's end: its final coverage if it succeeded (the mission was done, the floor
    would not change), None otherwise (cut by the timeout, failed, an error: what it would
    have cleaned is unknown, and carrying its last value mixed it with measured ones)."""
    coverage = result.coverage
    if coverage is None:
        return None
    if result.time_s < seconds - 1e-6:
        return coverage.final if result.succeeded else None
    return coverage.at(seconds)


def _coverage_record(result: EpisodeResult) -> dict[str, Any]:
    coverage = result.coverage
    out: dict[str, Any] = {}
    for column, (name, _) in COVERAGE_COLUMNS.items():
        if coverage is None:
            out[column] = None
        elif name.startswith("at:"):
            out[column] = coverage_at(result, float(name[3:]))
        elif name in ("by_area", "curve"):
            out[column] = (
                {a: c for a, c in coverage.by_area}
                if name == "by_area"
                else [[t, c] for t, c in coverage.curve]
            )
        else:
            out[column] = getattr(coverage, name)
    return out


def _coverage_from(record: dict[str, Any]) -> Coverage | None:
    """The episode's coverage from its record, None when it did not clean (or the file was
    written before coverage was recorded); ValueError naming the column of a value not a
    number or out of its range (:data:`COVERAGE_COLUMNS`)."""
    final = record.get("coverage")
    if final is None or final == "":
        return None
    by_area, curve = record["coverage_by_area"], record["coverage_curve"]
    if isinstance(by_area, str):  # CSV
        by_area = {a: c for a, _, c in (p.partition("=") for p in by_area.split(";") if p)}
        curve = [p.split(":") for p in curve.split(";") if p]
    return Coverage(
        area=str(record["coverage_area"] or ""),
        final=_coverage_number("coverage", final),
        curve=tuple(_sample(record, point) for point in curve),
        overall=_coverage_number("coverage_overall", record["coverage_overall"]),
        by_area=tuple(
            (str(a), _coverage_number("coverage_by_area", c, {a: c})) for a, c in by_area.items()
        ),
        longest_idle_s=_coverage_number("longest_idle", record["longest_idle"]),
        cleaning_s=_coverage_number("cleaning_time", record["cleaning_time"]),
    )


def _coverage_number(column: str, raw: Any, shown: Any = None) -> float:
    """A coverage column's number (``shown`` as the value found: an area's ``{area: c}``),
    in the range :data:`COVERAGE_COLUMNS` gives it."""
    kind = _JSON_COLUMNS[column]
    try:
        value = _finite(raw)
    except (TypeError, ValueError):
        _bad(column, kind, raw if shown is None else shown)
    _within(column, kind, COVERAGE_COLUMNS[column][1], value, raw if shown is None else shown)
    return value


def _sample(record: dict[str, Any], point: Any) -> tuple[float, float]:
    """A ``coverage_curve`` sample ``[t, c]``: a time 0 or more, a fraction from 0 to 1."""
    try:
        t, c = (_finite(v) for v in point)
    except (TypeError, ValueError):  # not two numbers
        _bad("coverage_curve", "coverage curve", point)
    if t < 0 or not 0.0 <= c <= 1.0:
        expected = f"{_EXPECTED['coverage curve']} (t 0 or more, fraction from 0 to 1)"
        raise ValueError(f"column 'coverage_curve': found {_found(point)}; expected {expected}")
    return t, c


#: what a column of each kind holds, as a message about a bad value says it (a CSV cell:
#: the same, as text)
_EXPECTED = {
    "str": "a string", "str?": "a string or null", "int": "a whole number",
    "int?": "a whole number or null",
    "float": "a finite number", "float?": "a finite number or null",
    "bool": "true or false (True or False in CSV)",
    "outcome": "the outcome's word in capitals (SUCCESS, FAILURE, TIMEOUT, ...)",
    "params": "an object of name: value text (name=value;... in CSV)",
    "falls total": "a whole number or null", "hazard falls": "a whole number or null",
    "falls by cause": "an object of cause: count, or null",
    "undeclared": "an object of key: writer, or null",
    "refused": "an object of action: its class and where, or null",
    "like": "an object of key: the declared key it may be a misspelling of, or null",
    "coverage": "a finite number or null", "coverage text": "a string or null",
    "coverage by area": "an object of area: fraction, or null",
    "coverage curve": "a list of [t, fraction], or null",
    "provenance text": "a string or null", "provenance map": "an object, or null",
    "path": "a list of [x, y] points, or null",
}  # fmt: skip

_NUMBER = frozenset({int, float})
_NONE = type(None)
#: each kind's JSON types as eval --out writes them (a bool is no number: ``type`` is
#: compared, not ``isinstance``); a number is also finite (NaN, and 1e400 read as inf, were
#: summarised as "median nan s")
_JSON_TYPES: dict[str, frozenset[type]] = {
    "str": frozenset({str}), "str?": frozenset({str, _NONE}), "int": frozenset({int}),
    "int?": frozenset({int, _NONE}),
    "float": _NUMBER, "float?": _NUMBER | {_NONE}, "0": _NUMBER, "1": _NUMBER, "2": _NUMBER,
    "bool": frozenset({bool}), "outcome": frozenset({str}), "params": frozenset({dict}),
    "falls total": frozenset({int, _NONE}), "hazard falls": frozenset({int, _NONE}),
    "falls by cause": frozenset({dict, _NONE}), "undeclared": frozenset({dict, _NONE}),
    "refused": frozenset({dict, _NONE}), "like": frozenset({dict, _NONE}),
    "coverage": _NUMBER | {_NONE}, "coverage text": frozenset({str, _NONE}),
    "coverage by area": frozenset({dict, _NONE}), "coverage curve": frozenset({list, _NONE}),
    "provenance text": frozenset({str, _NONE}), "provenance map": frozenset({dict, _NONE}),
    "path": frozenset({list, _NONE}),
}  # fmt: skip
_EXPECTED["0"] = _EXPECTED["1"] = _EXPECTED["2"] = _EXPECTED["float"]

#: every column eval --out writes (but ``key:`` ones, of any value) and its kind: the table
#: a JSON line is checked against; a column not in it is a later version's, and ignored
_JSON_COLUMNS: dict[str, str] = {
    **{column: kind for column, (_, kind, _) in COLUMNS.items()},
    **{column: "coverage" for column in COVERAGE_COLUMNS},
    "coverage_area": "coverage text", "coverage_by_area": "coverage by area",
    "coverage_curve": "coverage curve",
    "roomba_bt_version": "provenance text", "world_sha256": "provenance text",
    "sources": "provenance map", "plugins": "provenance map", PATH_COLUMN: "path",
}  # fmt: skip
#: an outcome as the writer writes it: the word of an episode's end in capitals (a later
#: version's new word reads; ``"\x1b[2J"`` does not)
_OUTCOME = re.compile(r"[A-Z]+(?: [A-Z]+)*")


def _found(raw: Any) -> str:
    """A bad cell's value as a message quotes it: its JSON text, escaped and shortened
    (``1e400``, which JSON reads as an infinity, said so)."""
    if type(raw) is float and math.isinf(raw):
        return f"{'-' if raw < 0 else ''}Infinity (a number too large to hold, such as 1e400)"
    try:  # a text as before ('z', a CSV cell's too); a JSON value in JSON's words (true)
        text = repr(raw) if isinstance(raw, str) else json.dumps(raw)
    except (TypeError, ValueError):  # not JSON's (a test's own object): as Python says it
        text = repr(raw)
    return escaped(shortened(text, 60))


def _number(value: Any) -> bool:
    return type(value) in _NUMBER


def _pair(value: Any) -> bool:
    return type(value) is list and len(value) == 2 and all(type(v) in _NUMBER for v in value)


#: what each value of an object column, or each item of a list column, is as eval --out
#: writes it (``{"kitchen": "0.5"}`` was read as the fraction 0.5)
_JSON_PARTS: dict[str, Callable[[Any], bool]] = {
    "coverage by area": _number, "coverage curve": _pair, "path": _pair,
    "falls by cause": lambda value: type(value) is int,
}  # fmt: skip


def _check_parts(column: str, kind: str, raw: dict[str, Any] | list[Any]) -> None:
    """ValueError naming the first value of an object column, or item of a list column,
    that is not as :data:`_JSON_PARTS` says, said alone (``{"kitchen": "0.5"}``)."""
    ok = _JSON_PARTS[kind]
    if isinstance(raw, dict):
        for key, value in raw.items():
            if not ok(value):
                _bad(column, kind, {key: value})
    else:
        for item in raw:
            if not ok(item):
                _bad(column, kind, item)


def check_json_record(record: dict[str, Any]) -> None:
    """ValueError naming the first column of a JSON Lines record that is not of the type
    eval --out writes there (:data:`_JSON_COLUMNS`: ``"mission": 5``, ``"params": [1]``,
    ``"mission_time": NaN``), what was found and what is allowed. :func:`from_record` read
    them as Python converts them: ``5`` was the mission "5", ``[1]`` the parameter
    ``-p [1]=``, ``true`` a seed of 1. A CSV row's text is read by the kinds' converters."""
    for column, kind in _JSON_COLUMNS.items():
        if column not in record:  # absent: from_record says which are required
            continue
        raw: Any = record[column]
        if type(raw) not in _JSON_TYPES[kind] and not (raw is None and column in MEASURED_COLUMNS):
            _bad(column, kind, raw)
        if type(raw) is float and not math.isfinite(raw):
            _bad(column, kind, raw)
        if kind == "params" and not all(type(v) is str for v in raw.values()):
            _bad(column, kind, raw)
        if kind == "outcome" and not _OUTCOME.fullmatch(raw):
            _bad(column, kind, raw)
        if raw is not None and kind in _JSON_PARTS:  # an object's values, a list's items
            _check_parts(column, kind, raw)


def _bad(column: str, kind: str, raw: Any) -> NoReturn:
    raise ValueError(f"column {column!r}: found {_found(raw)}; expected {_EXPECTED[kind]}")


def _within(column: str, kind: str, allowed: Allowed, value: float, raw: Any) -> None:
    """ValueError when ``value``, read from ``raw``, is outside the column's ``allowed``."""
    if allowed is not None and not allowed[0] <= value <= allowed[1]:
        raise ValueError(f"column {column!r}: found {_found(raw)}; expected "
                         f"{_EXPECTED[kind]} ({_ALLOWED_SAID[allowed]})")  # fmt: skip


def _finite(raw: Any) -> float:
    """A number's cell (JSON's number or CSV's text) as a float; ValueError for NaN or an
    infinity (``nan``, ``inf``, ``1e400``), which no episode measures."""
    value = float(raw)
    if not math.isfinite(value):
        raise ValueError(f"{raw!r} is not a finite number")
    return value


def _read_column(values: dict[str, Any], name: str, kind: str, raw: Any) -> None:
    """``raw``, a record's cell of ``kind``, read into ``values[name]`` (a start or end
    coordinate into its place); TypeError or ValueError when it is not of that kind."""
    if kind == "str":
        values[name] = "" if raw is None else str(raw)
    elif kind == "int":
        values[name] = int(raw)
    elif kind == "float":
        values[name] = _finite(raw)
    elif kind == "bool":
        if not isinstance(raw, bool) and raw not in ("True", "False"):
            raise ValueError(f"{raw!r} is not True or False")
        values[name] = raw if isinstance(raw, bool) else raw == "True"
    elif kind == "outcome":
        if not isinstance(raw, str) or not _OUTCOME.fullmatch(raw):
            raise ValueError(f"{raw!r} is no outcome")
        values[name] = raw.lower()
    elif kind == "params":
        values[name] = _params(raw)
    else:
        values[name][int(kind)] = _finite(raw)


def from_record(record: dict[str, Any]) -> EpisodeResult:
    """The inverse of :func:`to_record` (contact steps empty; the trajectory the ``path``
    kept, or none); values may be strings (CSV). KeyError/ValueError on a missing column or
    a bad value."""
    values: dict[str, Any] = {"start": [0.0] * 3, "end": [0.0] * 3}
    for column, (name, kind, allowed) in COLUMNS.items():
        if kind in ("float?", "int?"):  # a column later versions added: absent from older files
            raw = record.get(column)
            number: Callable[[Any], float] = _finite if kind == "float?" else int
            try:
                values[name] = number(0) if raw is None or raw == "" else number(raw)
            except (TypeError, ValueError):
                _bad(column, kind, raw)
            _within(column, kind, allowed, values[name], raw)
            continue
        if kind == "str?":  # the same, a text
            values[name] = str(record.get(column) or "")
            continue
        if kind in ("falls total", "hazard falls"):  # sums of falls_by_cause: checked after
            continue
        if kind == "falls by cause":
            try:
                values[name] = _falls(record.get(column))
            except (TypeError, ValueError):  # "-1 is not a count of falls" named no column
                _bad(column, kind, record.get(column))
            continue
        if kind in ("undeclared", "refused", "like"):
            values[name] = _undeclared(record.get(column), column, _EXPECTED[kind])
            continue
        raw = record[column]
        try:
            _read_column(values, name, kind, raw)
        except (TypeError, ValueError):  # "invalid literal for int()" named no column
            _bad(column, kind, raw)
        if kind in ("int", "float"):
            _within(column, kind, allowed, values[name], raw)
    _falls_add_up(record, dict(values["falls"]))
    values["start"], values["end"] = tuple(values["start"]), tuple(values["end"])
    known = {f.name for f in fields(EpisodeResult)}
    defaults = {"contact_steps": ()}
    values["trajectory"] = _path_from(record.get(PATH_COLUMN))
    values["coverage"] = _coverage_from(record)
    values["keys"] = tuple(
        (column.removeprefix(KEY_PREFIX), _key_value(raw))
        for column, raw in record.items()
        if column.startswith(KEY_PREFIX)
    )
    read = EpisodeResult(**{**defaults, **{k: v for k, v in values.items() if k in known}})
    return read.sharing_words()  # kept until the report: each word once, not once a line


def _key_value(raw: Any) -> Any:
    """A ``key:`` column's value as it was: JSON Lines keep its type; a CSV cell is text,
    read back as the bool, whole number or number it spells (``True``, ``3``, ``2.5``),
    None when empty (never written), else the text itself (a text key's value that spells
    a number reads back as that number)."""
    if not isinstance(raw, str):
        return raw
    if raw in ("", "True", "False"):
        return None if raw == "" else raw == "True"
    for number in (int, float):
        try:
            return number(raw)
        except ValueError:
            continue
    return raw


def _falls(raw: Any) -> tuple[tuple[str, int], ...]:
    """``falls_by_cause`` as :attr:`EpisodeResult.falls`: an object in JSON Lines,
    ``cliff=4;wheel drop=1`` in CSV; none when the column is empty or absent (a file written
    before falls were recorded reads as episodes without any); a cause counted 0 is no fall
    (an episode with ``{"cliff": 0}`` is not one of the summary's episodes with a fall)."""
    if raw is None or raw == "":
        return ()
    if isinstance(raw, dict):
        pairs = list(raw.items())
    elif isinstance(raw, str):
        pairs = [item.partition("=")[::2] for item in raw.split(";") if item]
    else:
        raise ValueError(f"falls_by_cause {raw!r}: expected cause=count pairs")
    counts = {str(cause): _count(times) for cause, times in pairs}
    return falls_in_order({cause: times for cause, times in counts.items() if times})


def _falls_add_up(record: dict[str, Any], causes: dict[str, int]) -> None:
    """ValueError when ``falls`` or ``hazard_falls`` is not what the writer sums of
    ``falls_by_cause`` (``causes``): ``"falls": 3`` with no cause was 3 falls in the
    summary's words and none in its table of causes. Absent or empty: a file written before."""
    sums = {"falls": (sum(causes.values()), "the sum of falls_by_cause's counts"),
            "hazard_falls": (sum(hazard_falls(causes).values()),
                             "the sum of falls_by_cause's counts but the charger's")}  # fmt: skip
    for column, (total, what) in sums.items():
        raw = record.get(column)
        if raw is None or raw == "":
            continue
        kind, allowed = COLUMNS[column][1:]
        try:
            count = int(raw)
        except (TypeError, ValueError):
            _bad(column, kind, raw)
        _within(column, kind, allowed, count, raw)
        if count != total:
            raise ValueError(f"column {column!r}: found {_found(raw)}; expected {what}, "
                             f"{total}")  # fmt: skip


def _undeclared(
    raw: Any, column: str = "undeclared_keys", expected: str = "an object of key: writer"
) -> tuple[tuple[str, str], ...]:
    """``undeclared_keys`` as :attr:`EpisodeResult.undeclared` (and ``refused_actions`` as
    :attr:`EpisodeResult.refused_actions`): an object in JSON Lines, its JSON text in a CSV
    cell (who wrote a key, ``by 'probe' at lab.py:17``, may hold any separator); none when
    the column is empty or absent (a file written before it was recorded: its summary then
    has no warning the episodes would have said)."""
    if raw is None or raw == "":
        return ()
    if isinstance(raw, str):
        raw = json.loads(raw)
    if not isinstance(raw, dict):
        raise ValueError(f"{column} {raw!r}: expected {expected.removesuffix(', or null')}")
    return tuple((str(key), str(where)) for key, where in raw.items())


def _count(raw: Any) -> int:
    """A fall count: a whole number 0 or more (``int("")`` says only "invalid literal")."""
    count = int(raw)
    if count < 0 or isinstance(raw, bool) or (isinstance(raw, float) and raw != count):
        raise ValueError(f"falls_by_cause: {raw!r} is not a count of falls")
    return count


def _params(raw: Any) -> tuple[tuple[str, str], ...]:
    if isinstance(raw, dict):
        return tuple((str(k), str(v)) for k, v in raw.items())
    text = str(raw or "")
    pairs = [item.partition("=") for item in text.split(";") if item]
    return tuple((name, value) for name, _, value in pairs)


def written_record(
    result: EpisodeResult,
    provenance: Mapping[str, Mapping[str, Any]] | None = None,
    *,
    reproducible: bool = False,
) -> dict[str, Any]:
    """One episode's row as a results file holds it: :func:`to_record`'s columns with its
    mission's :data:`PROVENANCE_COLUMNS` (:func:`write_results`' arguments)."""
    record = to_record(result)
    if reproducible:
        record.update(dict.fromkeys(MEASURED_COLUMNS))
    made_by = (provenance or {}).get(result.mission, {})
    record.update({column: made_by.get(column) for column in PROVENANCE_COLUMNS})
    return record


def write_results(
    path: str | Path,
    results: Iterable[EpisodeResult],
    provenance: Mapping[str, Mapping[str, Any]] | None = None,
    *,
    reproducible: bool = False,
) -> int:
    """Write the records to ``path`` (format by suffix); the number written. ``provenance``:
    each mission's :data:`PROVENANCE_COLUMNS`, by the mission as its rows name it (None:
    left empty); ``reproducible``: the :data:`MEASURED_COLUMNS` left empty, so that the same
    episodes run again write the same bytes. A file another roomba-bt writes is refused
    (FileInUse, an OSError) before it is emptied."""
    fmt = results_format(path)
    records = [written_record(result, provenance, reproducible=reproducible) for result in results]
    with ClaimedFile(path).open_text(newline="") as out:
        if fmt == ".jsonl":
            for record in records:
                out.write(json.dumps(record) + "\n")
        else:
            keys = dict.fromkeys(c for r in records for c in r if c.startswith(KEY_PREFIX))
            paths = [PATH_COLUMN] if any(PATH_COLUMN in r for r in records) else []
            names = [*COLUMNS, *COVERAGE_COLUMNS, *PROVENANCE_COLUMNS, *paths, *keys]
            writer = csv.DictWriter(out, fieldnames=names)
            writer.writeheader()
            for record in records:
                writer.writerow({**record, **_csv_cells(record)})  # str(float) is its repr
    return len(records)


class PartialResults:
    """Each episode's record as it finishes, one JSON line flushed at a time, into
    ``OUT.partial.jsonl`` beside ``--out OUT`` (which is written, in the episodes' order,
    only at the end): a sweep killed by the OOM killer or a ``kill -9`` lost every record.
    :meth:`done` removes it once ``OUT`` is written; :func:`read_results` reads it.

    The partial file is the sweep's hold on ``OUT``: claimed (an exclusive ``flock``,
    :class:`~roomba_bt.runtime.claimed.ClaimedFile`) for the whole sweep, so a second sweep
    given the same ``--out`` is refused at its start (FileInUse, an OSError) before it
    empties it; two sweeps both said "results written" and ``OUT`` held one sweep's
    episodes. ``OUT`` itself is not made before the end: a killed sweep leaves none.

    Its rows are ``OUT``'s (:func:`written_record`, ``provenance`` and ``reproducible`` as
    :func:`write_results` takes them): they had no provenance columns, and the records a
    killed sweep left said nothing of the release, the world or the mission files that made
    them."""

    def __init__(
        self,
        out: str | Path,
        provenance: Mapping[str, Mapping[str, Any]] | None = None,
        *,
        reproducible: bool = False,
    ) -> None:
        self.path = Path(f"{out}.partial.jsonl")
        self.provenance = provenance
        self.reproducible = reproducible
        self._file = ClaimedFile(self.path).open_text()  # closed in done: the lock let go

    def add(self, result: EpisodeResult) -> None:
        record = written_record(result, self.provenance, reproducible=self.reproducible)
        self._file.write(json.dumps(record) + "\n")
        self._file.flush()

    def done(self, keep: bool = False) -> None:
        """Closed; removed unless ``keep`` (the final file could not be written)."""
        if not keep:  # removed while still locked: a sweep starting now makes its own
            self.path.unlink(missing_ok=True)
        self._file.close()


def _csv_cells(record: dict[str, Any]) -> dict[str, str]:
    """The record's structured values as CSV cells (``None`` is an empty cell already)."""
    undeclared, refused = record["undeclared_keys"], record["refused_actions"]
    like = record["undeclared_like"]
    cells = {
        "params": ";".join(f"{k}={v}" for k, v in record["params"].items()),
        "falls_by_cause": ";".join(f"{c}={n}" for c, n in record["falls_by_cause"].items()),
        "undeclared_keys": json.dumps(undeclared) if undeclared else "",  # a writer's ; and =
        "refused_actions": json.dumps(refused) if refused else "",
        "undeclared_like": json.dumps(like) if like else "",
    }
    if record.get("sources") is not None:
        cells["sources"] = ";".join(f"{n}={d}" for n, d in record["sources"].items())
    if record.get("plugins") is not None:
        cells["plugins"] = ";".join(
            f"{n}={p['version']}:{p['sha256']}" for n, p in record["plugins"].items()
        )
    if record.get(PATH_COLUMN) is not None:
        cells[PATH_COLUMN] = ";".join(f"{x!r}:{y!r}" for x, y in record[PATH_COLUMN])
    if record["coverage_by_area"] is not None:
        cells["coverage_by_area"] = ";".join(
            f"{a}={c!r}" for a, c in record["coverage_by_area"].items()
        )
        cells["coverage_curve"] = ";".join(f"{t!r}:{c!r}" for t, c in record["coverage_curve"])
    return cells


def read_results(path: str | Path) -> list[EpisodeResult]:
    """Read a file :func:`write_results` wrote; ResultsFileError naming file:line otherwise."""
    return [result for _, _, result in iter_rows(path)]


def _csv_row(path: str | Path, n: int, row: dict[str | None, Any]) -> dict[str, Any]:
    """Row ``n`` of a CSV results file, a cell under each column of its header;
    ResultsFileError when it has fewer (a row cut short: the cells it lacks read as None,
    and a column's reading said "float() argument must be ... not 'NoneType'") or more."""
    header = len(row) - (None in row)
    if None in row:  # csv.DictReader keeps the cells past the header under None
        raise ResultsFileError(f"{path}:{n}: {header + len(row[None])} cells in a header of "
                               f"{header} columns; expected a cell under each column, as eval "
                               "--out writes them")  # fmt: skip
    cells = sum(1 for value in row.values() if value is not None)
    if cells < header:
        raise ResultsFileError(f"{path}:{n}: {cells} cells in a header of {header} columns "
                               "(the row cut short?); expected a cell under each column, as "
                               "eval --out writes them")  # fmt: skip
    return {str(column): value for column, value in row.items()}


#: what JSON calls the values a line of a results file must not be, by their Python type
_JSON_KINDS = {"list": "array", "str": "string", "int": "number", "float": "number",
               "bool": "true or false", "NoneType": "null"}  # fmt: skip


def _json_row(path: str | Path, n: int, text: str) -> dict[str, Any]:
    """Line ``n`` of a JSON Lines results file, an object; ResultsFileError naming the
    file, line and column, what was found and what a line holds. A line without its end
    of line is said to be cut short: the last one a sweep killed while writing left."""
    cut = "" if text.endswith("\n") else ", the line cut short (the file ends inside it)"
    try:  # each key once: JSON keeps the last of two "seed"s, a record no writer wrote
        record = json_read(text)
    except DuplicateKey as exc:
        raise ResultsFileError(f"{path}:{n}: {twice(exc)}, as eval --out writes it") from None
    except json.JSONDecodeError as exc:
        raise ResultsFileError(
            f"{path}:{n}:{exc.colno}: not JSON ({exc.msg}){cut}; expected "
            "one JSON object a line, as eval --out writes it"
        ) from None
    except RecursionError:  # json's decoder recurses: nested thousands deep
        raise ResultsFileError(f"{path}:{n}: nested too deeply for a result") from None
    except ValueError as exc:  # a number too long to read: said without the file before
        raise ResultsFileError(f"{path}:{n}: {long_number(exc)}") from None
    if not isinstance(record, dict):
        found = _JSON_KINDS.get(type(record).__name__, "value")
        raise ResultsFileError(f"{path}:{n}: found a JSON {found}; expected an object per "
                               "line, as eval --out writes it")  # fmt: skip
    return record


@dataclass(frozen=True)
class CutShort:
    """The last record of a results file, cut short: the file ends inside it, without its
    end of line. The trace a sweep leaves when it is killed as it writes a record (a ``kill
    -9``, the OOM killer, a power cut) or the disk fills: its writer ends every record with
    one. :func:`read_rows` given a list drops it there, and ``eval --resume`` runs its
    episode again; a line bad in the middle of a file, or one bad with its end of line, is
    no such trace and is refused as before."""

    path: str
    line: int
    #: what the part written names, None where it was cut before it (a value followed by
    #: the next column's, so that ``"seed": 12`` cut from 123 is not read as seed 12)
    seed: int | None
    mission: str | None

    def said(self, name_mission: bool) -> str:
        """``r.jsonl:75: the record of seed 37 was cut short as it was written (...)``;
        its mission named too when ``name_mission`` (of several) and the part written
        names it."""
        of = f" of {self.mission}" if name_mission and self.mission is not None else ""
        what = "the last record" if self.seed is None else f"the record of seed {self.seed}{of}"
        return (f"{self.path}:{self.line}: {what} was cut short as it was written (the file "
                "ends inside it: the sweep was killed, or the disk was full)")  # fmt: skip


#: a record's first columns as a JSON line holds them (json.dumps' separators), each ended
_JSON_MISSION = re.compile(r'^\{"mission": ("(?:[^"\\]|\\.)*"),')
_JSON_SEED = re.compile(r'"seed": (\d{1,20}),')  # a longer one is no seed int() reads


def _cut_json(path: str | Path, line: int, text: str) -> CutShort:
    """What the part of a JSON line written before the cut names."""
    mission, seed = _JSON_MISSION.match(text), _JSON_SEED.search(text)
    return CutShort(str(path), line, int(seed[1]) if seed else None,
                    json.loads(mission[1]) if mission else None)  # fmt: skip


def _cut_csv(path: str | Path, line: int, row: dict[str | None, Any]) -> CutShort:
    """What the part of a CSV row written before the cut names: a cell followed by the
    next column's is whole."""
    whole = [column for column, value in row.items() if value is not None][:-1]
    seed = row["seed"] if "seed" in whole and str(row["seed"]).isdigit() else None
    return CutShort(str(path), line, None if seed is None else int(seed),
                    str(row["mission"]) if "mission" in whole else None)  # fmt: skip


#: a byte that is not UTF-8, as the stream's decoder keeps it (``surrogateescape``): no UTF-8
#: text holds one
_NOT_UTF8 = re.compile("[\udc80-\udcff]")


class _Lines:
    """The lines of a results file as text, read a line at a time (the file was read whole,
    decoded whole and split whole: 200,000 lines took 2.2 GB), split as before at any line
    end (``newline=""``, none translated), each at most a record's longest
    (:data:`~roomba_bt.runtime.recording.MAX_RECORD_LINE` characters: one was read whole,
    however long). ResultsFileError at a byte that is not UTF-8, but
    for a character cut short at the very end when ``cut`` is given (a kill between the
    bytes of a character: the record it ends is cut short anyway), which is left out.
    :attr:`whole` tells, once read through, whether the last line had its end of line."""

    def __init__(self, path: str | Path, file: IO[bytes], cut: list[CutShort] | None) -> None:
        self.path, self.cut = path, cut
        self.text = io.TextIOWrapper(file, encoding="utf-8", errors="surrogateescape", newline="")
        self.whole = True

    def __iter__(self) -> Iterator[str]:
        for number, line in enumerate(bounded_lines(self.text), 1):
            if over_line_limit(line):  # a 100 MB line was read whole (334 MB), then parsed
                raise ResultsFileError(
                    f"{self.path}:{number}: a line of more than {len(line) - 1:,} characters "
                    "(the rest of it not read); allowed: at most that, as a record's line "
                    "(eval --out writes an episode a line, a few KB)"
                )
            self.whole = line.endswith(("\n", "\r"))
            # ASCII (known without a look at it) holds no escaped byte: 40 % of the read
            yield line if line.isascii() or _NOT_UTF8.search(line) is None else self._decoded(line)

    def _decoded(self, line: str) -> str:
        data = line.encode("utf-8", "surrogateescape")
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as exc:
            at_the_end = not self.whole and exc.end == len(data)
            if self.cut is None or not at_the_end or exc.reason != "unexpected end of data":
                raise ResultsFileError(f"{self.path}: not UTF-8 text (byte 0x{data[exc.start]:02x}"
                                       "); expected results as eval --out writes them (.jsonl "
                                       "or .csv)") from None  # fmt: skip
            return data[: exc.start].decode("utf-8")  # the first error: all before it decodes


def _csv_rows(
    path: str | Path, lines: _Lines, cut: list[CutShort] | None
) -> Iterator[tuple[int, dict[str, Any]]]:
    """The rows of a CSV results file; with ``cut``, a last row without its end of line (the
    writer ends each: this one was cut, and a cell cut short may read as another value) is
    dropped into it. A row is held until the next is read: the last is known at the end."""
    held: tuple[int, dict[str | None, Any]] | None = None
    n = 1
    try:
        for n, row in enumerate(csv.DictReader(lines), 2):
            if held is not None:
                yield held[0], _csv_row(path, *held)
            held = (n, row)
    except csv.Error as exc:  # a cell longer than csv's limit (128 KiB), a stray quote...
        raise ResultsFileError(f"{path}:{n + 1}: not CSV as eval --out writes it ({exc})") from None
    if held is None:
        return
    if cut is not None and not lines.whole:
        cut.append(_cut_csv(path, *held))
    else:
        yield held[0], _csv_row(path, *held)


def _json_rows(
    path: str | Path, lines: _Lines, cut: list[CutShort] | None, seen: set[bytes] | None
) -> Iterator[tuple[int, dict[str, Any]]]:
    """The records of a JSON Lines results file, blank lines skipped; with ``cut``, a last
    line without its end of line that is not a whole object (the kill's trace) is dropped
    into it; with ``seen``, a line the same to the character as one given before is skipped
    unread (:func:`iter_rows`)."""
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        if seen is not None:
            digest = hashlib.blake2b(line.encode("utf-8", "surrogateescape"), digest_size=16)
            if digest.digest() in seen:
                continue
        if cut is None or lines.whole:
            yield n, _json_row(path, n, line)
            if seen is not None:  # asked for the next: this one read, checked and taken
                seen.add(digest.digest())
            continue
        try:  # the last line, without its end of line
            row = _json_row(path, n, line)
        except ResultsFileError:  # never a whole object: the kill's trace
            cut.append(_cut_json(path, n, line))
            return
        yield n, row


def read_rows(
    path: str | Path, cut: list[CutShort] | None = None
) -> list[tuple[int, dict[str, Any], EpisodeResult]]:
    """Each record of a file :func:`write_results` wrote, as (line, the row as written, the
    episode): the row keeps what :func:`from_record` leaves out (the provenance columns,
    which ``eval --resume`` checks); ResultsFileError naming file:line otherwise. Given
    ``cut``, a last record cut short (:class:`CutShort`) is dropped and put there instead
    of refused: a JSON line without its end of line that is not a whole object, a CSV row
    without its end of line. :func:`iter_rows` reads them one at a time."""
    return list(iter_rows(path, cut))


def iter_rows(
    path: str | Path, cut: list[CutShort] | None = None, seen: set[bytes] | None = None
) -> Iterator[tuple[int, dict[str, Any], EpisodeResult]]:
    """:func:`read_rows`' records one at a time, as the file is read: ``eval --from`` keeps
    only what its report needs (an episode once), not every line. Given ``seen`` (digests
    of lines, kept across files), a JSON line the same to the character as one given before
    (whose record the caller took: it asked for the next) is skipped before it is parsed:
    the same text is the same record, and 200,000 copies of one line were each parsed,
    checked and made an episode to be found the same (23 s)."""
    expected = "expected results as eval --out writes them (.jsonl or .csv)"
    if Path(path).is_dir():  # said as what it is: not "Is a directory", not "no suffix"
        raise ResultsFileError(f"{path}: a directory; {expected}")
    fmt = results_format(path)
    # a pipe waited in open() for a writer for ever; a device (/dev/zero linked as
    # results.jsonl) was read without end
    if Path(path).exists() and not Path(path).is_file():
        raise ResultsFileError(f"{path}: a device or a pipe, not a file; {expected}")
    with _opened(path) as file:
        lines = _Lines(path, file, cut)
        if fmt == ".csv":
            rows = _csv_rows(path, lines, cut)
        else:
            rows = _json_rows(path, lines, cut, seen)
        for line, row in rows:
            try:
                if fmt == ".jsonl":  # typed as written; a CSV cell is text, read by its kind
                    check_json_record(row)
                result = from_record(row)
            except KeyError as exc:
                raise ResultsFileError(
                    f"{path}:{line}: missing column {exc.args[0]!r}; "
                    "expected a record as eval --out writes it"
                ) from None
            except (TypeError, ValueError) as exc:
                raise ResultsFileError(f"{path}:{line}: bad value ({exc})") from None
            yield line, row, result


def _opened(path: str | Path) -> IO[bytes]:
    """The results file, opened to be read; ResultsFileError saying why it cannot be."""
    try:
        return Path(path).open("rb")
    except OSError as exc:
        raise ResultsFileError(f"{path}: {exc.strerror or exc}") from None
