"""A subtree's own key passed down to a subtree it uses, by name (session 36): a text
parameter used as a key name is a key of the body where its value was written, as BT.CPP's
SubTree remaps a port to the caller's key. Before, ``subtree: {id: measure, out: here}`` in
a body that owns ``here`` had ``measure`` look ``here`` up among the mission's keys alone:
"unknown blackboard key 'here'", and no way to let a nested subtree fill the caller's key."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from docs_inputs import OWN_KEY  # tests/docs_inputs.py: the mission docs/missions.md quotes
from runtime.own_keys import PASSED  # tests/runtime: the mission the run test runs

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.mission import CompiledMission, compile_mission
from roomba_bt.mission.plan import Node

Errors = Callable[..., list[str]]


def leaves(mission: CompiledMission) -> list[Node]:
    return [node for node in mission.plan.walk() if node.kind == "leaf"]


def test_a_use_passes_its_own_key_down_by_name(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(PASSED)
    assert mission.blackboard_keys.keys() == {"leg#1/here", "leg#2/here"}
    written = [(n.params["key"], n.params["value"]) for n in leaves(mission) if n.kind == "leaf"
               and n.decl is not None and n.decl.name == "set"]  # fmt: skip
    assert written == [("leg#1/here", 100), ("leg#2/here", 200)]  # mm
    read = [n.params["distance"] for n in leaves(mission) if "distance" in n.params]
    assert read == [BlackboardRef("leg#1/here"), BlackboardRef("leg#2/here")]


def test_passed_on_through_a_body_that_does_not_own_it(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """``mid`` owns nothing and passes ``${out}`` on: the key is still ``leg``'s."""
    mission = compile_text(
        """
        mission: through
        subtrees:
          measure:
            parameters: {out: {type: str}}
            tree: {set: {key: "${out}", value: 3}}
          mid:
            parameters: {out: {type: str}}
            tree: {subtree: {id: measure, out: "${out}"}}
          leg:
            blackboard: {n: int}
            tree:
              sequence:
                - subtree: {id: mid, out: n}
                - check: {key: n, value: 3}
        tree: {subtree: leg}
        """
    )
    keys = [n.params["key"] for n in leaves(mission)]
    assert keys == ["leg#1/n", "leg#1/n"]


def test_a_name_the_mission_gives_is_the_missions_key_even_where_the_body_owns_one(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """Where the value was written decides: the mission's ``here``, not ``measure``'s."""
    mission = compile_text(
        """
        mission: outer_name
        blackboard: {here: int}
        subtrees:
          measure:
            parameters: {out: {type: str}}
            blackboard: {here: {type: int, initial: 0}}
            tree:
              sequence:
                - set: {key: "${out}", value: 4}
                - set: {key: here, value: 5}
        tree: {subtree: {id: measure, out: here}}
        """
    )
    keys = [n.params["key"] for n in leaves(mission)]
    assert keys == ["here", "measure#1/here"]


def test_for_each_writes_a_key_passed_down(compile_text: Callable[..., CompiledMission]) -> None:
    mission = compile_text(
        """
        mission: each
        subtrees:
          count:
            parameters: {out: {type: str}}
            tree:
              for_each: {key: "${out}", in: [1, 2], do: {check: {key: "${out}", value: 2}}}
          leg:
            blackboard: {i: int}
            tree: {subtree: {id: count, out: i}}
        tree: {subtree: leg}
        """
    )
    (loop,) = [n for n in mission.plan.walk() if n.kind == "for_each"]
    assert loop.options["key"] == "leg#1/i"
    assert [n.params["key"] for n in leaves(mission)] == ["leg#1/i"]


def test_the_key_type_is_the_callers(errors_of: Errors) -> None:
    """What the nested body writes or reads is held to the caller's key's type."""
    text = """
    mission: typed
    subtrees:
      measure:
        parameters: {out: {type: str}}
        tree: {mark: {key: "${out}"}}
      leg:
        blackboard: {here: distance}
        tree:
          sequence: [{subtree: {id: measure, out: here}}, {drive: {distance: "@here"}}]
    tree: {subtree: leg}
    """
    (error,) = [e for e in errors_of(text) if "mark.key" in e]
    assert error.startswith("5:24: mark.key (${out} is here, given at ")
    assert error.endswith(
        "to subtree measure): blackboard key 'here' is distance (mm); mark needs a key of type mark"
    )


def test_read_before_written_through_the_use(errors_of: Errors) -> None:
    """Said at the use that passes the key (leg's line, the body to fix), naming the read
    in the nested body: said at that read (5:25), in ``measure``, which has no key ``n``,
    it did not say which use passed it."""
    text = OWN_KEY  # docs/missions.md quotes what it says
    assert errors_of(text) == [
        "9:19: subtree measure(out=n) reads blackboard key 'n' (subtree leg's own) before "
        "anything writes it on some path (passed down to check(key=n, value=1) at 5:25): "
        "give it an initial value under blackboard:, or write it first (set, mark, for_each)"
    ]
    written_first = text.replace(
        "[{subtree: {id: measure, out: n}}, {set: {key: n, value: 1}}]",
        "[{set: {key: n, value: 1}}, {subtree: {id: measure, out: n}}]",
    )
    assert errors_of(written_first) == []


def test_read_before_written_two_levels_down_is_said_at_the_use_in_the_owning_body(
    mission_file: Callable[..., Path],
) -> None:
    """``leg`` passes its ``n`` to ``mid``, which passes it on to ``measure``, which reads
    it: said once (leg used twice), at leg's use of ``mid``, the read in another file named
    with its file; ``validate`` of the library alone says the same."""
    mission_file(
        """
        subtrees:
          measure:
            parameters: {out: {type: str}}
            tree:
              sequence:
                - check: {key: "${out}", value: 1}
        """,
        "inner.yaml",
    )
    lib = mission_file(
        """
        include: [inner.yaml]
        subtrees:
          mid:
            parameters: {out: {type: str}}
            tree: {subtree: {id: measure, out: "${out}"}}
          leg:
            blackboard: {n: int}
            tree:
              sequence:
                - wait: 1s
                - subtree: {id: mid, out: n}
                - set: {key: n, value: 1}
        """,
        "lib.yaml",
    )
    mission = mission_file(
        "mission: deeper\ninclude: [lib.yaml]\ntree: {sequence: [{subtree: leg}, {subtree: leg}]}\n"
    )
    said = (
        "subtree mid(out=n) reads blackboard key 'n' (subtree leg's own) before anything "
        f"writes it on some path (passed down to check(key=n, value=1) at {lib.parent}"
        "/inner.yaml:6:24): give it an initial value under blackboard:, or write it first "
        "(set, mark, for_each)"
    )
    for path, require_tree in ((mission, True), (lib, False)):
        found = compile_mission(path, require_tree=require_tree)[1]
        assert [f"{d.file}:{d.line}:{d.column}: {d.message}" for d in found] == [
            f"{lib}:11:11: {said}"
        ]


def test_a_name_the_caller_does_not_have(errors_of: Errors) -> None:
    text = """
    mission: nothing
    subtrees:
      measure:
        parameters: {out: {type: str}}
        tree: {set: {key: "${out}", value: 1}}
      leg:
        blackboard: {n: int}
        tree: {subtree: {id: measure, out: m}}
    tree: {subtree: leg}
    """
    (error,) = errors_of(text)
    assert "set.key (${out} is m, given at " in error
    assert error.endswith("unknown blackboard key 'm'; known: n")  # the caller's keys


def test_at_key_in_a_nested_body_hints_at_passing_it(errors_of: Errors) -> None:
    text = """
    mission: hint
    subtrees:
      inner:
        tree: {drive: {distance: "@here"}}
      outer:
        blackboard: {here: {type: distance, initial: 1cm}}
        tree: {subtree: inner}
    tree: {subtree: outer}
    """
    (error,) = [e for e in errors_of(text) if "blackboard" in e]
    assert "unknown blackboard key 'here' (subtree outer's own key 'here' is not seen" in error
    assert "subtree: {id: inner, out: here} at the use" in error


def test_a_blackboard_value_of_a_key_passed_down(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """``"@${out}"`` reads the key of the body that gave the name, as ``key: "${out}"``."""
    mission = compile_text(
        """
        mission: read_passed
        subtrees:
          go:
            parameters: {out: {type: str}}
            tree: {drive: {distance: "@${out}"}}
          leg:
            blackboard: {here: {type: distance, initial: 5cm}}
            tree: {subtree: {id: go, out: here}}
        tree: {sequence: [{mode: safe}, {subtree: leg}, {subtree: leg}]}
        """
    )
    read = [n.params["distance"] for n in leaves(mission) if "distance" in n.params]
    assert read == [BlackboardRef("leg#1/here"), BlackboardRef("leg#2/here")]
