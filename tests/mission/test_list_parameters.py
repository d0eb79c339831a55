"""List-valued parameters (session 35's library report, finding 4): a waypoint patrol or a
tune could not be a reusable subtree. ``for_each.in: "${legs}"`` was "must be a list, got
the text", and ``type: notes`` was an unknown type though the Values table listed it. Now
``{type: list, items: TYPE}`` and ``{type: notes}`` are parameters, given as a list in the
file, to a subtree, or with ``-p legs=[1m, 2m]`` (YAML's flow list), each item checked at
validate time at its own place."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.mission import CompiledMission, compile_mission

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]

ROUTE = """
mission: route
parameters:
  back: {type: list, items: distance, default: [30cm, 20cm]}
blackboard:
  leg: distance
subtrees:
  route:
    parameters:
      legs: {type: list, items: distance}
    tree:
      for_each:
        key: leg
        in: "${legs}"
        do: {drive: {velocity: 200 mm/s, distance: "@leg"}}
  sing:
    parameters:
      tune: {type: notes, default: [C4 200ms]}
    tree: {song: {number: 0, notes: "${tune}"}}
tree:
  sequence:
    - mode: safe
    - subtree: {id: route, legs: [1m, 2m]}
    - subtree: {id: route, legs: "${back}"}
    - subtree: {id: sing, tune: [C4 200ms, E4 100ms]}
    - for_each: {key: leg, in: "${back}", do: {wait: 1s}}
    - mode: passive
"""


def _option(mission: CompiledMission, kind: str, name: str) -> list[Any]:
    """``name`` of each node of class ``kind`` in the tree, in order."""
    return [getattr(n, name) for n in mission.root.iterate() if type(n).__name__ == kind]


def test_a_list_parameter_fills_for_each_and_a_subtree_and_notes_fill_a_song(
    compile_text: Compile,
) -> None:
    mission = compile_text(ROUTE)
    assert [list(items) for items in _option(mission, "ForEach", "items")] == [
        [1000.0, 2000.0],
        [300.0, 200.0],
        [300.0, 200.0],
    ]
    [song] = [n for n in mission.root.iterate() if type(n).__name__ == "Song"]
    assert song.params["notes"] == ((60, 13), (64, 6))


def test_a_list_given_with_p_is_read_as_yaml_s_flow_list(compile_text: Compile) -> None:
    mission = compile_text(ROUTE, {"back": "[1m, 50cm]"})
    assert [list(items) for items in _option(mission, "ForEach", "items")][1:] == [
        [1000.0, 500.0],
        [1000.0, 500.0],
    ]


def test_show_says_the_list_as_written(compile_text: Compile) -> None:
    names = [node.name for node in compile_text(ROUTE).reviewed().iterate()]
    # each use with the list it gave, then the body's root with the list it reads
    assert "subtree route(legs=[1m, 2m]): for_each(key=leg, in=[1m, 2m])" in names
    assert "subtree route(legs=[30cm, 20cm]): for_each(key=leg, in=[30cm, 20cm])" in names
    assert (
        'subtree sing(tune=[C4 200ms, E4 100ms]): song(number=0, notes="[C4 200ms, E4 100ms]")'
        in names
    )


@pytest.mark.parametrize(
    ("declaration", "said"),
    [
        ("{type: list, items: distance, default: [1m, 5, 2 parsecs]}", [
            "2:50: parameter p: expected a distance with a unit such as 300 mm, 30cm or 1.5 m, "
            "got 5 (write the unit: 5mm)",
            "2:53: parameter p: unknown distance unit 'parsecs' in '2 parsecs'; use one of: mm, "
            "cm, m",
        ]),
        ("{type: notes, default: [C4 200ms, H4 1s]}", [
            "2:40: parameter p: note 2 of 2: unknown note 'H4': H is B in German names: write B4",
        ]),
        ("{type: list, default: [1]}", [
            "2:13: parameter 'p' of type list needs items: TYPE, the type of each item (one of "
            "duration, speed, distance, angle, percent, int, float, bool, str, radius), or "
            "{fields: {NAME: TYPE, ...}} for records",
        ]),
        ("{type: int, items: int, default: 1}", [
            "2:25: parameter 'p': items only goes with type: list (a list of values of one "
            "type), not with type: int: drop items, or write type: list",
        ]),
        ("{type: list, items: mark}", [
            "2:26: unknown item type 'mark'; known types: duration, speed, distance, angle, "
            "percent, int, float, bool, str, radius",
        ]),
    ],
)  # fmt: skip
def test_each_bad_item_and_declaration_is_said_at_its_place(
    errors_of: Errors, declaration: str, said: list[str]
) -> None:
    assert errors_of(f"parameters:\n  p: {declaration}\ntree: stop\n") == said


_USES = """
parameters:
  legs: {type: list, items: distance, default: [1m]}
  fast: {type: list, items: speed, default: [1m/s]}
  none: {type: list, items: distance, default: []}
blackboard: {leg: distance, n: int}
tree:
  sequence:
    - for_each: {key: leg, in: "${fast}", do: {log: leg}}
    - for_each: {key: leg, in: "@leg", do: {log: leg}}
    - for_each: {key: n, in: "${legs}", do: {log: leg}}
    - song: {number: 1, notes: "${legs}"}
    - for_each: {key: leg, in: "${none}", do: {log: leg}}
"""


def test_a_list_that_does_not_fit_is_said_at_the_use(errors_of: Errors) -> None:
    assert errors_of(_USES) == [
        "8:32: for_each.in: parameter ${fast} is a list of speed (mm/s), but for_each.in needs "
        "list of distance (mm)",
        "9:32: for_each.in: a blackboard value (@key) is not allowed here (for_each.in is known "
        "when the mission is validated, each item checked against the ranges of the key's "
        'readers: write the list, or give a list parameter, "${legs}" with legs: {type: list, '
        "items: distance})",
        "10:30: for_each.in: parameter ${legs} is a list of distance (mm), but for_each.in needs "
        "list of int",
        "11:32: song.notes: parameter ${legs} is a list of distance (mm), but song.notes needs "
        "notes",
        "12:32: for_each.in is an empty list: give at least one item, a value of the key's type "
        "(${none} is [], the default of parameter none at 4:48: give params={'none': 'VALUE'}, or "
        "another default there)",
    ]


def test_a_text_parameter_in_a_list_slot_says_how_to_declare_a_list(errors_of: Errors) -> None:
    """The report's ``legs: {type: str, default: "[1m, 2m]"}``: a text is never read as a
    list, and the error says what to declare (for a record key, the list of records: until
    session 36 "no list parameter holds items of record")."""
    text = """
    parameters: {t: {type: str, default: x}}
    blackboard:
      leg: distance
      wp: {fields: {distance: distance, turn: angle}}
    tree:
      sequence:
        - for_each: {key: leg, in: "${t}", do: stop}
        - for_each: {key: wp, in: "${t}", do: stop}
        - song: {number: 0, notes: "${t}"}
    """
    said = "parameter ${t} is a str, but"
    assert errors_of(text) == [
        f"7:32: for_each.in: {said} for_each.in takes a list, never read from a text: declare "
        "the parameter {type: list, items: distance}",
        f"8:31: for_each.in: {said} for_each.in takes a list, never read from a text: declare "
        "the parameter {type: list, items: {fields: {distance: distance, turn: angle}}}",
        f"9:32: song.notes: {said} song.notes takes a list, never read from a text: declare the "
        "parameter {type: notes}",
    ]


# ------------------------------------------------------------ a list of records (waypoints)

#: a patrol of waypoints as a parameter: each item a record, as the key ``wp`` holds
WAYPOINTS = """
parameters:
  route:
    type: list
    items: {fields: {distance: distance, turn: angle}}
    default: [{distance: 30cm, turn: 90deg}, {distance: 20cm, turn: -90deg}]
blackboard:
  wp: {fields: {distance: distance, turn: angle}}
tree:
  sequence:
    - mode: safe
    - for_each:
        key: wp
        in: "${route}"
        do:
          sequence:
            - drive: {velocity: 100 mm/s, distance: "@wp.distance"}
            - turn: "@wp.turn"
"""


def test_a_list_of_records_fills_for_each_over_a_record_key(compile_text: Compile) -> None:
    """Session 35's lists held one value each: a patrol of waypoints could not be a
    parameter ("no list parameter holds items of record")."""
    [items] = _option(compile_text(WAYPOINTS), "ForEach", "items")
    assert list(items) == [{"distance": 300.0, "turn": 90.0}, {"distance": 200.0, "turn": -90.0}]


def test_a_list_of_records_given_with_p_is_read_by_the_one_parser(compile_text: Compile) -> None:
    """``-p 'route=[{distance: 1m, turn: 45deg}]'``: YAML's flow list of flow mappings, each
    field read by its type; a parameter's fields may be listed in another order than the
    key's (the same record)."""
    given = {"route": "[{distance: 1m, turn: 45deg}, {turn: 0.5turn, distance: 5cm}]"}
    [items] = _option(compile_text(WAYPOINTS, given), "ForEach", "items")
    assert list(items) == [{"distance": 1000.0, "turn": 45.0}, {"distance": 50.0, "turn": 180.0}]
    reordered = WAYPOINTS.replace(
        "items: {fields: {distance: distance, turn: angle}}",
        "items: {fields: {turn: angle, distance: distance}}",
    )
    [items] = _option(compile_text(reordered), "ForEach", "items")
    assert items[0] == {"distance": 300.0, "turn": 90.0}


def test_show_says_the_records_as_written(compile_text: Compile) -> None:
    names = [node.name for node in compile_text(WAYPOINTS).reviewed().iterate()]
    assert (
        "for_each(key=wp, in=[{distance: 30cm, turn: 90deg}, {distance: 20cm, turn: -90deg}])"
        in names
    ), names


@pytest.mark.parametrize(
    ("default", "said"),
    [
        ("[{distance: 30cm, turn: 90m}]", [
            "5:38: parameter route.turn: unknown angle unit 'm' in '90m'; use one of: deg, °, "
            "rad, turn, turns",
        ]),
        ("[{distance: 30cm, turn: 1deg}, {distance: 1m}]", [
            "5:45: parameter route: missing field 'turn'; fields: distance, turn",
        ]),
        ("[{distance: 30cm, turn: 1deg, speed: 1m/s}]", [
            "5:15: parameter route: unknown field 'speed'; known: distance, turn",
        ]),
        ("[30cm]", [
            "5:15: parameter route: expected a mapping with distance, turn",
        ]),
    ],
)  # fmt: skip
def test_each_bad_record_in_a_default_is_said_at_its_place(
    errors_of: Errors, default: str, said: list[str]
) -> None:
    text = WAYPOINTS.replace(
        "default: [{distance: 30cm, turn: 90deg}, {distance: 20cm, turn: -90deg}]",
        f"default: {default}",
    )
    assert errors_of(text) == said


#: (the mission, its list parameter and where it is declared, what ``-p`` gives, what is said)
BAD_GIVEN = [
    pytest.param(ROUTE, "back", "3:3", "[1m, 5]",
                 "item 2 of 2: expected a distance with a unit such as 300 mm, 30cm or 1.5 m, "
                 "got 5 (write the unit: 5mm)", id="list: an item without its unit"),
    pytest.param(ROUTE, "back", "3:3", "1m",
                 "expected a list of distance (mm) written in brackets, [a, b], got '1m'",
                 id="list: one value, no brackets"),
    pytest.param(ROUTE, "back", "3:3", "[1m, [2m]",
                 "'[1m, [2m]' is no list YAML reads (expected ',' or ']', but got "
                 "'<stream end>'): write [a, b]", id="list: a bracket left open"),
    pytest.param(WAYPOINTS, "route", "2:3", "[{distance: 1m}]",
                 "missing field 'turn'; fields: distance, turn", id="records: a field missing"),
    pytest.param(WAYPOINTS, "route", "2:3", "[{distance: 1m, turn: 1deg, speed: 1m/s}]",
                 "unknown field 'speed'; fields: distance, turn", id="records: an unknown field"),
    pytest.param(WAYPOINTS, "route", "2:3",
                 "[{distance: 1m, turn: 1deg}, {distance: 1m, turn: 4m}]",
                 "item 2 of 2: field turn: unknown angle unit 'm' in '4m'; use one of: deg, °, "
                 "rad, turn, turns", id="records: a field's bad unit in the second item"),
    pytest.param(WAYPOINTS, "route", "2:3", "[1m]",
                 "expected a mapping with distance, turn", id="records: an item not a record"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "name", "where", "given", "said"), BAD_GIVEN)
def test_a_bad_list_given_with_p_is_said_with_its_item_and_what_to_write(
    errors_of: Errors, text: str, name: str, where: str, given: str, said: str
) -> None:
    """A list (or a list of records) given with ``-p`` is said at the parameter's
    declaration, with the value as given and what is wrong: the item, the field."""
    [error] = errors_of(text, {name: given})
    assert error.startswith(f"{where}: parameter {name}={given} (")
    assert error.endswith(f"): {said}")


@pytest.mark.parametrize(
    ("items", "said"),
    [
        ("{fields: {distance: distanse}}", "4:32: unknown type 'distanse' (did you mean "
         "'distance'?); known types: duration, speed, distance, angle, percent, int, float, "
         "bool, str, radius"),
        ("{field: {distance: distance}}", "4:13: parameter 'route' items: unknown key 'field' "
         "(did you mean 'fields'?); known: fields"),
        ("{}", "4:12: parameter 'route': items of records need fields: {NAME: TYPE, ...}, as "
         "a blackboard key's"),
    ],
)  # fmt: skip
def test_a_bad_declaration_of_records_is_said_at_its_place(
    errors_of: Errors, items: str, said: str
) -> None:
    text = WAYPOINTS.replace(
        "items: {fields: {distance: distance, turn: angle}}", f"items: {items}"
    )
    assert errors_of(text)[0] == said


def test_records_of_other_fields_do_not_fill_the_key(errors_of: Errors) -> None:
    """A waypoint with a speed is not the key's record: said with both records' fields."""
    text = (
        WAYPOINTS.replace(
            "items: {fields: {distance: distance, turn: angle}}",
            "items: {fields: {distance: distance, turn: angle, speed: speed}}",
        )
        .replace("turn: 90deg}", "turn: 90deg, speed: 1m/s}")
        .replace("-90deg}", "-90deg, speed: 1m/s}")
    )
    assert errors_of(text) == [
        "13:13: for_each.in: parameter ${route} is a list of record {distance: distance, turn: "
        "angle, speed: speed}, but for_each.in needs list of record {distance: distance, turn: "
        "angle}"
    ]


def test_the_schema_takes_a_list_of_records_as_validate_does() -> None:
    """``items: {fields: {...}}`` is in the JSON Schema too (an editor's check agrees)."""
    import jsonschema
    import yaml

    from roomba_bt.mission.schema import mission_schema

    validator = jsonschema.Draft202012Validator(mission_schema())
    assert validator.is_valid(yaml.safe_load(WAYPOINTS))
    wrong = WAYPOINTS.replace("items: {fields:", "items: {field:")
    assert not validator.is_valid(yaml.safe_load(wrong))


def test_a_list_parameters_default_item_out_of_range_is_said_at_the_item(
    errors_of: Errors, mission_file: Callable[..., Path]
) -> None:
    """An item of a list parameter's default was said at the ``for_each``'s ``in:``
    (13:13), which holds no 9000 deg: now at the item in the default (the line to change),
    naming the ``for_each`` and the reader. One set with -p is said at the use, naming
    where it was set; a library subtree's default at its item in the library."""
    text = WAYPOINTS.replace("turn: -90deg}]", "turn: 9000deg}]")
    reader = "turn's angle reads it as @wp.turn (at 17:21): angle 9000 deg is out of range"
    assert errors_of(text) == [
        "5:46: for_each item of blackboard key 'wp' (item 2 of the default of parameter route, "
        f"for_each.in at 13:13): {reader}: allowed -3600..3600 deg"
    ]
    given = {"route": "[{distance: 1m, turn: 9000deg}]"}
    assert errors_of(text, given) == [
        "13:13: for_each item of blackboard key 'wp' (${route} is route=[{distance: 1m, turn: "
        f"9000deg}}], given in params): {reader}: allowed -3600..3600 deg"
    ]
    lib = mission_file(
        """
        subtrees:
          walk:
            parameters:
              legs: {type: list, items: distance, default: [10cm, -3cm]}
            blackboard: {d: distance}
            tree: {for_each: {key: d, in: "${legs}", do: {drive: {distance: "@d"}}}}
        """,
        "lib.yaml",
    )
    said = (
        "4:59: for_each item of blackboard key 'd' (subtree walk's own) (item 2 of the default "
        "of parameter legs, for_each.in at 6:35): drive's distance reads it as @d (at 6:69): "
        "distance -30 mm is out of range: allowed 0 mm or more"
    )
    used = "mission: m\ninclude: [lib.yaml]\ntree: {sequence: [{mode: safe}, {subtree: walk}]}\n"
    found = compile_mission(mission_file(used))[1]
    assert [(d.file, f"{d.line}:{d.column}: {d.message}") for d in found] == [(str(lib), said)]
