"""``roomba-bt schema`` and ``roomba-bt validate`` agree on a corpus of missions: every
parameter of every built-in behaviour at its minimum and maximum and just outside, and the
cases a mission writer checking the schema with jsonschema met (session 28: the schema
accepted ``reactive_sequence`` with ``memory: true``, ``@key`` where options are read when
the tree is built, negative durations, a blackboard key with no type; it refused ``wait:
"0"`` and ``log: 5``, which validate accepts).

Where they disagree, the case is one of the known exceptions below, each documented in
docs/missions.md ("The JSON Schema"): what JSON Schema cannot express, so the schema is
more lenient than validate, never stricter.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import pytest
import yaml

from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.registry import default_registry
from roomba_bt.behaviours.units import UNITS
from roomba_bt.mission import compile_mission
from roomba_bt.mission.schema import RANGE_NOT_IN_SCHEMA, mission_schema

#: What the schema accepts and validate refuses, by the words of validate's error: the
#: schema's answer is ``valid`` for each, and validate's error says one of these.
KNOWN_EXCEPTIONS: dict[str, tuple[str, ...]] = {
    # a quantity's range: a pattern cannot compare numbers (its sign it can: refused)
    "range": ("is out of range", "must be at least"),
    # a comparison's text: packet names, operators, ranges
    "sensor": ("sensor.test:",),
    # an action (or a node that may be RUNNING) under held / until
    "condition child": ("as a condition",),
    # a selected: name two children answer to
    "selected twice": ("give each its own name",),
    # a behaviour's own rules between its values (declared constraints: drive's ends,
    # spiral's radii, wall_follow's hysteresis)
    "behaviour rule": ("never", "must be less than", "must be at most"),
    # a duration in several units: the largest first, each once (a pattern could list the
    # orders, but not readably: validate says how to write it)
    "order of units": ("the largest unit first",),
}
_UNIT_OF = {"speed": "mm/s", "distance": "mm", "duration": "s", "angle": "deg", "percent": "%"}
#: a value of each type for a required parameter the case does not vary
_SAMPLE = {"angle": "90deg", "duration": "1s", "str": "k", "distance": "10cm", "int": 1}


@functools.cache
def _validator() -> Any:
    import jsonschema

    schema = mission_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _schema_ok(mission: dict[str, Any]) -> bool:
    return _validator().is_valid(mission)


def _validate_errors(mission: dict[str, Any], tmp_path: Path, name: str) -> list[str]:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(mission, allow_unicode=True), encoding="utf-8")
    _, diagnostics = compile_mission(path)
    return [d.message for d in diagnostics if d.severity == "error"]


#: the types whose parameters' bounds are numbers the schema holds (``power_color`` is a
#: colour's name too, its number the byte: session 33)
_NUMBERED = ("int", "float", "power_color")


def _written(param: Param, value: float) -> Any:
    if param.type.name in ("int", "power_color"):
        return int(value)
    if param.type.name == "float":
        return value
    return f"{value:g}{_UNIT_OF[param.type.name]}"


#: the cases whose value is a negative quantity where the minimum is 0: no "range"
#: exception, the schema refuses them (``wait: "-1s"`` was schema-valid)
NEGATIVE: set[str] = {"negative wait", "negative delay", "negative tenth wait"}


def _edge_cases() -> list[tuple[str, dict[str, Any]]]:
    """One mission per bound of each parameter with a range: at it, and just outside."""
    cases = []
    for decl in default_registry():
        if decl.origin != "builtin":
            continue
        for param in decl.params:
            if param.type.name not in (*_NUMBERED, *UNITS):
                continue
            step = 1 if param.type.name == "int" else 0.5
            bounds = [("min", param.minimum, -step), ("max", param.maximum, step)]
            for label, bound, outside in bounds:
                if bound is None:
                    continue
                for suffix, value in (("", bound), ("_out", bound + outside)):
                    params = {
                        q.name: _SAMPLE.get(q.type.name, "x")
                        for q in decl.params
                        if q.required and q.name != param.name
                    }
                    params[param.name] = _written(param, value)
                    if decl.name == "drive" and param.name in ("left", "right"):
                        params = {"left": "100mm/s", "right": "100mm/s", **params}
                    node = {decl.name: params}
                    tree = {"sequence": [{"mode": "safe"}, node]} if decl.kind == "action" else node
                    mission: dict[str, Any] = {"tree": tree}
                    if decl.name in ("mark", "odometry"):
                        mission["blackboard"] = {"k": "mark"}
                    name = f"{decl.name}.{param.name}.{label}{suffix}"
                    if value < 0 <= (param.minimum or 0) and param.type.name in UNITS:
                        NEGATIVE.add(name)  # a minus sign the schema's pattern refuses
                    cases.append((name, mission))
    return cases


def _tree(tree: Any, **sections: Any) -> dict[str, Any]:
    return {**sections, "tree": tree}


_WAIT = {"wait": "1s"}
_KEYS = {"k": {"type": "int", "initial": 2}, "kb": {"type": "bool", "initial": True},
         "d": {"type": "duration", "initial": "1s"}}  # fmt: skip
#: (case, mission, validate's answer: True = valid) from the session-28 report
REPORTED: list[tuple[str, dict[str, Any], bool]] = [
    ("reactive memory", _tree({"reactive_sequence": {"memory": True, "children": [_WAIT]}}),
     False),
    ("reactive no memory", _tree({"reactive_sequence": {"memory": False, "children": [_WAIT]}}),
     True),
    ("parallel memory", _tree({"parallel": {"memory": True, "children": [_WAIT]}}), False),
    ("selected without policy", _tree({"parallel": {"policy": "all", "selected": ["a"],
                                                     "children": [{**_WAIT, "name": "a"}]}}),
     False),
    ("policy selected without selected", _tree({"parallel": {"policy": "selected",
                                                              "children": [_WAIT]}}), False),
    ("policy selected", _tree({"parallel": {"policy": "selected", "selected": ["a"],
                                             "children": [{**_WAIT, "name": "a"}]}}), True),
    ("repeat times @key", _tree({"repeat": {"times": "@k", "do": _WAIT}}, blackboard=_KEYS),
     False),
    ("timeout after @key", _tree({"timeout": {"after": "@d", "do": _WAIT}}, blackboard=_KEYS),
     False),
    ("sequence memory @key", _tree({"sequence": {"memory": "@kb", "children": [_WAIT]}},
                                   blackboard=_KEYS), False),
    ("mode to @key", _tree({"mode": {"to": "@k"}}, blackboard=_KEYS), False),
    ("wait @key", _tree({"wait": "@d"}, blackboard=_KEYS), True),
    ("timeout after ${p}", _tree({"timeout": {"after": "${t}", "do": _WAIT}},
                                 parameters={"t": {"type": "duration", "default": "1s"}}), True),
    ("negative wait", _tree({"wait": "-1s"}), False),
    ("negative delay", _tree({"delay": {"for": "-1s", "do": _WAIT}}), False),
    # a minus on a zero is 0: validate took "-0s" and the schema refused it
    ("negative zero wait", _tree({"wait": "-0s"}), True),
    ("negative zero wait spaced", _tree({"wait": "- 0 s"}), False),
    ("negative zero wait decimal", _tree({"wait": "-0.0 ms"}), True),
    ("negative zero wait exponent", _tree({"wait": "-0e3s"}), True),
    ("negative zero delay", _tree({"delay": {"for": "-0min", "do": _WAIT}}), True),
    ("negative zero as text", _tree({"wait": "-0"}), True),
    ("negative tenth wait", _tree({"wait": "-0.1s"}), False),
    ("negative zero turn speed", _tree({"sequence": [{"mode": "safe"},
                                                     {"turn": {"angle": "90deg",
                                                               "speed": "-0 mm/s"}}]}), False),
    ("negative drive", _tree({"sequence": [{"mode": "safe"},
                                           {"drive": {"velocity": "-100 mm/s",
                                                      "duration": "1s"}}]}), True),
    ("timeout shorter than a tick", _tree({"timeout": {"after": "10ms", "do": _WAIT}}), False),
    ("key without type", _tree(_WAIT, blackboard={"x": {"initial": 3}}), False),
    ("key with fields", _tree(_WAIT, blackboard={"x": {"fields": {"d": "distance"}}}), True),
    ("key not snake_case", _tree(_WAIT, blackboard={"Bad-Key": "int"}), False),
    ("parameter not snake_case", _tree(_WAIT, parameters={"Bad": {"type": "int",
                                                                  "default": 1}}), False),
    ("repeat times and for", _tree({"repeat": {"times": 2, "for": "1s", "do": _WAIT}}), False),
    ("wait 0 as text", _tree({"wait": "0"}), True),
    ("wait in days", _tree({"wait": "1d"}), True),
    ("wait in several units", _tree({"wait": "1h30min"}), True),
    ("timeout in several units", _tree({"timeout": {"after": "2h 15min", "do": _WAIT}}), True),
    ("wait in several units, smallest first", _tree({"wait": "30min1h"}), False),
    ("wait in several units, one signed", _tree({"wait": "1h-30min"}), False),
    ("log a number", _tree({"log": 5}), True),
    ("log a boolean", _tree({"log": True}), False),
    ("sensor text", _tree({"sensor": "voltage = 100"}), False),
    ("action under held", _tree({"held": {"for": "1s", "do": {"sequence": [
        {"mode": "safe"}, {"drive": {"velocity": "100 mm/s", "duration": "1s"}}]}}}), False),
    ("selected twice", _tree({"parallel": {"policy": "selected", "selected": ["a"], "children": [
        {**_WAIT, "name": "a"}, {"wait": "2s", "name": "a"}]}}), False),
]  # fmt: skip


def _leds(power_color: Any) -> dict[str, Any]:
    return _tree({"sequence": [{"mode": "safe"}, {"leds": {"power_color": power_color}}]})


#: the power LED's colour by name (session 33), or a name it does not have
POWER_COLORS = [
    ("power colour amber", _leds("amber"), True),
    ("power colour red", _leds("red"), True),
    ("power colour blue", _leds("blue"), False),
    ("power colour as a quoted byte", _leds("128"), False),
]


def _parameter(declaration: dict[str, Any], tree: dict[str, Any]) -> dict[str, Any]:
    return {**_tree(tree), "parameters": {"p": declaration}, "blackboard": {"leg": "distance"}}


_EACH_LEG = {"for_each": {"key": "leg", "in": "${p}", "do": _WAIT}}
#: list and notes parameters (session 35), and the colour as an enum or an int parameter
PARAMETERS = [
    ("list parameter in for_each", _parameter(
        {"type": "list", "items": "distance", "default": ["1m", "2m"]}, _EACH_LEG), True),
    ("list parameter of marks", _parameter(
        {"type": "list", "items": "mark", "default": []}, _EACH_LEG), False),
    ("notes parameter in a song", _parameter({"type": "notes", "default": ["C4 200ms"]}, {
        "sequence": [{"mode": "safe"}, {"song": {"number": 0, "notes": "${p}"}}]}), True),
    ("enum parameter as the power colour", _parameter(
        {"type": "enum", "choices": ["green", "red"], "default": "red"}, _leds("${p}")["tree"]),
        True),
    ("int parameter as the power colour", _parameter(
        {"type": "int", "default": 200}, _leds("${p}")["tree"]), True),
    # an option another type does not read: the schema accepted these, validate refuses
    ("items on a distance parameter", _parameter(
        {"type": "distance", "items": "distance", "default": "1m"}, _WAIT), False),
    ("choices on a str parameter", _parameter(
        {"type": "str", "choices": ["a", "b"], "default": "a"}, _WAIT), False),
    ("list parameter without items", _parameter({"type": "list", "default": []}, _WAIT),
     False),
    ("enum parameter without choices", _parameter({"type": "enum", "default": "a"}, _WAIT),
     False),
    ("enum parameter with items", _parameter(
        {"type": "enum", "choices": ["a"], "items": "str", "default": "a"}, _WAIT), False),
]  # fmt: skip


def _own_keys(keys: Any, tree: Any) -> dict[str, Any]:
    """A mission using twice a subtree that declares ``keys`` of its own (session 36)."""
    return _tree({"sequence": [{"mode": "safe"}, {"subtree": "leg"}, {"subtree": "leg"}]},
                 subtrees={"leg": {"blackboard": keys, "tree": tree}})  # fmt: skip


_MARK_AND_MEASURE = {"sequence": [{"mark": {"key": "here"}},
                                  {"odometry": {"since": "here", "distance": "1cm"}}]}  # fmt: skip
#: a subtree's own ``blackboard:`` (session 36), declared as the mission's are
OWN_KEYS = [
    ("subtree's own mark", _own_keys({"here": "mark"}, _MARK_AND_MEASURE), True),
    ("subtree's own key with initial", _own_keys(
        {"n": {"type": "int", "initial": 0}}, {"set": {"key": "n", "value": 1}}), True),
    ("subtree's own record", _own_keys(
        {"wp": {"fields": {"d": "distance"}}}, {"set": {"key": "wp", "value": {"d": "1m"}}}),
        True),
    ("subtree's own key without type", _own_keys({"n": {"initial": 0}}, _WAIT), False),
    ("subtree's own key not snake_case", _own_keys({"Here": "mark"}, _WAIT), False),
    ("subtree's own key of an unknown type", _own_keys({"n": "integer"}, _WAIT), False),
]  # fmt: skip

_CASES = (
    [(name, mission, None) for name, mission in _edge_cases()]
    + REPORTED
    + POWER_COLORS
    + PARAMETERS
    + OWN_KEYS
)


@pytest.mark.parametrize(("name", "mission", "validate_says"), _CASES, ids=[c[0] for c in _CASES])
def test_the_schema_and_validate_agree(
    name: str, mission: dict[str, Any], validate_says: bool | None, tmp_path: Path
) -> None:
    errors = _validate_errors(mission, tmp_path, name.replace(" ", "_").replace("$", "p"))
    validate_ok = not errors
    if validate_says is not None:
        assert validate_ok is validate_says, errors
    schema_ok = _schema_ok(mission)
    if schema_ok == validate_ok:
        return
    assert name not in NEGATIVE, f"{name}: the schema accepts a negative value: {errors}"
    # the only disagreement allowed: the schema more lenient, for a reason it cannot express
    assert schema_ok and not validate_ok, f"the schema refuses what validate accepts: {name}"
    known = [
        why
        for why, words in KNOWN_EXCEPTIONS.items()
        if any(word in error for word in words for error in errors)
    ]
    assert known, f"{name}: validate says {errors}, the schema accepts it"


def test_the_schema_says_where_it_cannot_hold_a_range() -> None:
    """A quantity's range is in its description, with why the schema does not check it."""
    wait = mission_schema()["$defs"]["timeout"]["properties"]["after"]
    assert RANGE_NOT_IN_SCHEMA in wait["description"]
    drive = mission_schema()["$defs"]["drive"]["then"]
    assert RANGE_NOT_IN_SCHEMA in drive["properties"]["velocity"]["description"]
    assert "-500..500 mm/s" in drive["properties"]["velocity"]["description"]
