"""A subtree's own blackboard keys (session 36): a subtree definition may declare
``blackboard:`` of its own, keys of each use's own (``leg#1/here``, ``leg#2/here``), hiding a
mission key of the same name in its body. Before, every key was the whole mission's, so two
libraries could not both use a key named ``here`` and a library's scratch key had to be
declared by every mission that used it ("unknown key 'here'", or an unknown field
``blackboard`` in the subtree)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from runtime.own_keys import CountInto  # tests/runtime: the plugin the run tests use too

from roomba_bt.behaviours import default_registry
from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.cli import main
from roomba_bt.mission import CompiledMission, Diagnostic, compile_mission
from roomba_bt.mission.plan import Node

Errors = Callable[..., list[str]]


def short(d: Diagnostic) -> str:
    return f"{d.line}:{d.column}: {d.message}"


#: a subtree that marks where it starts and drives until 5 cm from there, used twice; the
#: mission has a key ``here`` of its own, of another type, which the body does not see
TWO_MARKS = """
mission: two_marks
blackboard:
  here: {type: int, initial: 7}
subtrees:
  leg:
    blackboard:
      here: mark
      n: {type: int, initial: 0}
    tree:
      sequence:
        - mark: {key: here}
        - drive: {distance: 10cm}
        - odometry: {since: here, distance: 5cm}
        - set: {key: n, value: 1}
tree:
  sequence:
    - mode: safe
    - subtree: leg
    - check: {key: here, value: 7}
    - subtree: leg
"""


def leaves(mission: CompiledMission) -> list[Node]:
    return [node for node in mission.plan.walk() if node.kind == "leaf"]


def test_each_use_has_keys_of_its_own(compile_text: Callable[..., CompiledMission]) -> None:
    mission = compile_text(TWO_MARKS)
    assert {k: t.name for k, t in mission.blackboard_keys.items()} == {
        "here": "int",
        "leg#1/here": "mark",
        "leg#1/n": "int",
        "leg#2/here": "mark",
        "leg#2/n": "int",
    }
    assert mission.blackboard_initial == {"here": 7, "leg#1/n": 0, "leg#2/n": 0}
    keys = [
        (node.name, node.params.get("key") or node.params.get("since")) for node in leaves(mission)
    ]
    assert [k for k in keys if k[1] is not None] == [
        ("mark(here)", "leg#1/here"),
        ("odometry(since=here, distance=5cm)", "leg#1/here"),
        ("set(key=n, value=1)", "leg#1/n"),
        ("check(key=here, value=7)", "here"),  # the mission's, outside the body
        ("mark(here)", "leg#2/here"),
        ("odometry(since=here, distance=5cm)", "leg#2/here"),
        ("set(key=n, value=1)", "leg#2/n"),
    ]


def test_a_key_of_the_mission_hidden_by_one_of_another_type_is_warned_of_at_each_use(
    compile_text: Callable[..., CompiledMission],
) -> None:
    warnings = [short(w) for w in compile_text(TWO_MARKS).warnings]
    said = (
        "subtree 'leg' has its own blackboard key 'here' (mark), which hides the mission's "
        "'here' (int) in its body: here there is each use's own; rename one of them if the "
        "body should read the mission's"
    )
    assert warnings == [f"18:7: {said}", f"20:7: {said}"]
    assert {w.severity for w in compile_text(TWO_MARKS).warnings} == {"warning"}
    same_type = TWO_MARKS.replace("here: {type: int, initial: 7}", "here: mark").replace(
        "    - check: {key: here, value: 7}\n", ""
    )
    assert compile_text(same_type).warnings == ()


def test_an_own_key_read_before_it_is_written_is_the_subtrees_error_said_once(
    mission_file: Callable[..., Path],
) -> None:
    """Nothing outside the body reads or writes its own keys: the body alone decides,
    and the error is the subtree's own, once, at its line (a library's alone finds it)."""
    text = TWO_MARKS.replace("        - mark: {key: here}\n", "")
    mission, diagnostics = compile_mission(mission_file(text))
    assert mission is None
    assert [short(d) for d in diagnostics] == [
        "12:29: odometry(since=here, distance=5cm) reads blackboard key 'here' (subtree leg's "
        "own) before anything writes it on some path: give it an initial value under "
        "blackboard:, or write it first (set, mark, for_each)"
    ]
    library = text.replace("mission: two_marks", "description: a library").split("tree:\n  seq")
    path = mission_file(library[0], "lib.yaml")
    found = [short(d) for d in compile_mission(path, require_tree=False)[1]]
    assert found == [short(diagnostics[0])]


def test_an_own_key_is_judged_in_its_body_and_a_missions_key_in_the_mission(
    errors_of: Errors,
) -> None:
    """The body's mark may come from the mission's key ``start`` written before the use:
    the mission's keys are judged over the whole tree, as before."""
    text = """
    mission: m
    blackboard: {start: mark}
    subtrees:
      leg:
        blackboard: {here: mark}
        tree:
          sequence:
            - odometry: {since: start, distance: 1cm}
            - mark: {key: here}
            - odometry: {since: here, distance: 1cm}
    tree:
      sequence: [{mode: safe}, {mark: {key: start}}, {subtree: leg}]
    """
    assert errors_of(text) == []
    assert errors_of(text.replace("{mark: {key: start}}, ", "")) == [
        "8:29: odometry(since=start, distance=1cm) reads blackboard key 'start' before anything "
        "writes it on some path: give it an initial value under blackboard:, or write it "
        "first (set, mark, for_each)"
    ]


def test_an_own_keys_type_is_checked_where_the_body_reads_it(errors_of: Errors) -> None:
    text = TWO_MARKS.replace("- set: {key: n, value: 1}", "- check: {key: here, value: 1}")
    assert errors_of(text) == [
        "14:24: check.key: blackboard key 'here' is mark; check needs a key holding a value "
        "(not a mark)"
    ]


LEG_WITH_SPEED = """
mission: speeds
subtrees:
  leg:
    parameters:
      start: {type: speed, default: 100 mm/s}
    blackboard:
      v: {type: speed, initial: "${start}"}
    tree:
      drive: {velocity: "@v", distance: 1cm}
tree:
  sequence:
    - mode: safe
    - subtree: leg
    - subtree: {id: leg, start: 200 mm/s}
"""


def test_an_initial_value_may_be_the_subtrees_parameter_given_at_each_use(
    compile_text: Callable[..., CompiledMission], errors_of: Errors
) -> None:
    assert compile_text(LEG_WITH_SPEED).blackboard_initial == {"leg#1/v": 100.0, "leg#2/v": 200.0}
    assert errors_of(LEG_WITH_SPEED.replace("200 mm/s", "700 mm/s")) == [
        "7:33: initial value of blackboard key 'v' (subtree leg's own): drive's velocity reads "
        "it as @v (at 9:25): velocity 700 mm/s is out of range: allowed -500..500 mm/s"
    ]


def test_a_body_does_not_see_the_own_keys_of_the_body_it_is_used_in(errors_of: Errors) -> None:
    """Each body's own keys are its alone: a library's subtree used inside another reads
    the mission's keys, never its caller's scratch keys."""
    text = """
    mission: nested
    subtrees:
      inner:
        tree: {check: {key: here, value: 1}}
      outer:
        blackboard:
          here: {type: int, initial: 1}
        tree:
          sequence: [{check: {key: here, value: 1}}, {subtree: inner}]
    tree: {subtree: outer}
    """
    assert errors_of(text) == [
        "4:25: check.key: unknown blackboard key 'here' (subtree outer's own key 'here' is not "
        "seen in the subtrees it uses: pass its name down as a text parameter, parameters: "
        "{out: {type: str}} in inner, subtree: {id: inner, out: here} at the use, and name the "
        'key "${out}" in inner)'
    ]


def test_a_library_of_two_subtrees_each_with_a_key_here_and_two_such_libraries(
    mission_file: Callable[..., Path],
) -> None:
    mission_file(
        """
        description: marks
        subtrees:
          out:
            blackboard: {here: mark}
            tree:
              sequence: [{mark: {key: here}}, {odometry: {since: here, distance: 1cm}}]
          count:
            blackboard: {here: {type: int, initial: 0}}
            tree: {set: {key: here, value: 1}}
        """,
        "a.yaml",
    )
    mission_file(
        """
        subtrees:
          back:
            blackboard: {here: mark}
            tree:
              sequence: [{mark: {key: here}}, {odometry: {since: here, angle: 1deg}}]
        """,
        "b.yaml",
    )
    path = mission_file(
        """
        mission: both
        include: [a.yaml, b.yaml]
        tree:
          sequence:
            - mode: safe
            - subtree: out
            - subtree: count
            - subtree: back
            - subtree: out
        """
    )
    for library in ("a.yaml", "b.yaml"):
        assert compile_mission(path.parent / library, require_tree=False)[1] == []
    mission, diagnostics = compile_mission(path)
    assert diagnostics == [] and mission is not None
    assert {k: t.name for k, t in mission.blackboard_keys.items()} == {
        "out#1/here": "mark",
        "count#1/here": "int",
        "back#1/here": "mark",
        "out#2/here": "mark",
    }


def test_a_subtree_without_own_keys_still_reads_and_writes_the_missions(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(
        """
        mission: shared
        blackboard: {n: {type: int, initial: 0}}
        subtrees:
          bump_n: {tree: {set: {key: n, value: 1}}}
        tree: {sequence: [{subtree: bump_n}, {check: {key: n, value: 1}}]}
        """
    )
    assert list(mission.blackboard_keys) == ["n"]
    assert [node.params["key"] for node in leaves(mission)] == ["n", "n"]


def test_a_blackboard_value_in_the_body_reads_the_uses_own_key(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(LEG_WITH_SPEED)
    refs = [node.params["velocity"] for node in leaves(mission) if node.name.startswith("drive")]
    assert refs == [BlackboardRef("leg#1/v"), BlackboardRef("leg#2/v")]


def test_a_plugins_key_parameter_in_a_body_names_the_uses_own_key(
    mission_file: Callable[..., Path],
) -> None:
    """A plugin's behaviour writes the key its parameter names: in a body, the use's own."""
    path = mission_file(
        """
        mission: plugin_key
        blackboard: {level: {type: int, initial: 0}}
        subtrees:
          seen:
            blackboard: {level: int}
            tree: {sequence: [{count_into: {key: level}}, {check: {key: level, value: 1}}]}
        tree: {sequence: [{subtree: seen}, {count_into: {key: level}}]}
        """
    )
    registry = default_registry().with_behaviours([CountInto])
    mission, diagnostics = compile_mission(path, registry=registry)
    assert diagnostics == [] and mission is not None
    assert [node.params["key"] for node in leaves(mission)] == ["seen#1/level"] * 2 + ["level"]


def test_show_says_each_uses_own_keys_and_the_library_lists_them(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    path = mission_file(TWO_MARKS)
    assert main(["show", str(path)]) == 0
    out = capsys.readouterr().out
    assert "{-} subtree leg [own keys: leg#1/here, leg#1/n]\n" in out
    assert "{-} subtree leg [own keys: leg#2/here, leg#2/n]\n" in out
    library = mission_file(
        """
        description: a library
        subtrees:
          leg:
            doc: one leg
            blackboard:
              here: mark
              n: {type: int, initial: 0, doc: legs driven}
            tree: {mark: {key: here}}
        """,
        "lib.yaml",
    )
    assert main(["show", str(library)]) == 0
    out = capsys.readouterr().out
    listed = "leg  one leg\n    own key here: mark\n    own key n: int, initial 0  legs driven\n"
    assert listed in out
