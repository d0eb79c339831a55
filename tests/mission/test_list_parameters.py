"""List-valued parameters (session 35's library report, finding 4): a waypoint patrol or a
tune could not be a reusable subtree. ``for_each.in: "${legs}"`` was "must be a list, got
the text", and ``type: notes`` was an unknown type though the Values table listed it. Now
``{type: list, items: TYPE}`` and ``{type: notes}`` are parameters, given as a list in the
file, to a subtree, or with ``-p legs=[1m, 2m]`` (YAML's flow list), each item checked at
validate time at its own place."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from roomba_bt.mission import CompiledMission

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
            "duration, speed, distance, angle, percent, int, float, bool, str, radius)",
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


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ("[1m, 5]", "item 2 of 2: expected a distance with a unit such as 300 mm, 30cm or 1.5 m, "
         "got 5 (write the unit: 5mm)"),
        ("1m", "expected a list of distance (mm) written in brackets, [a, b], got '1m'"),
        ("[1m, [2m]", "'[1m, [2m]' is no list YAML reads (expected ',' or ']', but got "
         "'<stream end>'): write [a, b]"),
    ],
)  # fmt: skip
def test_a_bad_list_given_with_p_is_said_with_what_to_write(
    errors_of: Errors, given: str, said: str
) -> None:
    [error] = errors_of(ROUTE, {"back": given})
    assert error.startswith(f"3:3: parameter back={given} (")
    assert error.endswith(f"): {said}")


def test_a_text_parameter_in_a_list_slot_says_how_to_declare_a_list(errors_of: Errors) -> None:
    """The report's ``legs: {type: str, default: "[1m, 2m]"}``: a text is never read as a
    list, and the error says what to declare (or that no list parameter holds records)."""
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
        f"8:31: for_each.in: {said} for_each.in takes a list, never read from a text: no list "
        "parameter holds items of record: write the list here",
        f"9:32: song.notes: {said} song.notes takes a list, never read from a text: declare the "
        "parameter {type: notes}",
    ]
