"""A diagnostic about a node of a subtree's body names the use of the subtree it was found
at, beside the definition's line (``in subtree nudge, used at m.yaml:12:7``): the body is
expanded at each use, and the definition's line alone did not say which use was meant. The
same finding at two uses is said once, naming both; one whose text differs with the use (a
parameter's value in it) is said at each, with its own."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import (
    CompiledMission,
    Diagnostic,
    SubtreeUse,
    compile_mission,
    validate_file,
)
from roomba_bt.mission.plan import Node
from roomba_bt.oi.profiles import ROOMBA500

#: a subtree whose second step can never run: its drive has no end
NUDGE = """\
subtrees:
  nudge:
    parameters:
      speed: {type: speed, default: 100 mm/s}
    tree:
      sequence:
        - drive: {velocity: "${speed}"}
        - log: after
tree:
  sequence:
    - mode: safe
"""


def _blocked(mission: CompiledMission) -> list[Diagnostic]:
    return [w for w in mission.warnings if w.message.startswith("log(after) can never run")]


def test_a_warning_in_a_subtree_names_its_use(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(NUDGE + "    - fallback: [{subtree: nudge}, {log: cut}]\n")
    [warning] = _blocked(mission)
    assert (warning.line, warning.column) == (8, 11)  # the definition's line, as before
    path = warning.file
    assert warning.used_in == ((SubtreeUse(path, 12, 19, "nudge"),),)
    assert str(warning).endswith(
        f"(in subtree nudge, used at {path}:12:19) [subtrees.nudge.tree.sequence[1].log]"
    )


def test_the_same_warning_at_two_uses_is_said_once_naming_both(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """Two uses found the same: one line, not the same text twice at the definition."""
    mission = compile_text(NUDGE + "    - subtree: nudge\n    - subtree: nudge\n")
    [warning] = _blocked(mission)
    path = warning.file
    assert warning.uses_said() == (f" (in subtree nudge, used at {path}:12:7 and at {path}:13:7)")


def test_a_warning_that_differs_with_the_use_is_said_at_each(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """Each use's drive named with its own speed: two findings, each with its own use."""
    mission = compile_text(
        NUDGE
        + "    - subtree: {id: nudge, speed: 200 mm/s}\n"
        + "    - subtree: {id: nudge, speed: 300 mm/s}\n"
    )
    said = [
        (w.used_in[0][0].line, "200" in w.message, "300" in w.message) for w in _blocked(mission)
    ]
    assert said == [(12, True, False), (13, False, True)]


def test_many_uses_of_a_subtree_in_its_own_file_say_how_many_more(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """The five uses named, then "and 95 more": as a finding said at a library's use says
    it, not "and at 95 more" (a count is no place)."""
    mission = compile_text(NUDGE + "    - subtree: nudge\n" * 100)
    [warning] = _blocked(mission)
    path = warning.file
    named = " and at ".join(f"{path}:{line}:7" for line in range(12, 17))
    assert warning.uses_said() == f" (in subtree nudge, used at {named} and 95 more)"


def test_a_subtree_in_a_subtree_names_both_uses(
    compile_text: Callable[..., CompiledMission],
) -> None:
    text = NUDGE.replace(
        "tree:\n  sequence:\n    - mode: safe\n",
        "  twice:\n    tree:\n      sequence: [{log: go}, {subtree: nudge}]\n"
        "tree:\n  sequence:\n    - mode: safe\n    - subtree: twice\n",
    )
    [warning] = _blocked(compile_text(text))
    path = warning.file
    assert warning.uses_said() == (
        f" (in subtree nudge, used at {path}:11:30 in subtree twice at {path}:15:7)"
    )


def test_an_error_in_a_subtree_names_its_use(mission_file: Callable[..., Path]) -> None:
    """The mode check: the subtree's drive reached in Passive at the second use only."""
    path = mission_file(
        "subtrees:\n  go:\n    tree:\n      drive: {velocity: 100 mm/s, duration: 1s}\n"
        "tree:\n  sequence:\n    - mode: safe\n    - subtree: go\n    - mode: passive\n"
        "    - subtree: go\n"
    )
    _, [error] = compile_mission(path)
    assert (error.line, error.column) == (4, 7)
    assert error.message.startswith("drive sends Drive (137)"), error
    assert error.used_in == ((SubtreeUse(str(path), 10, 7, "go"),),)


def test_validate_says_the_use_on_the_line_and_in_json(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    from roomba_bt.cli import main

    path = mission_file(NUDGE + "    - subtree: nudge\n    - subtree: nudge\n")
    assert main(["validate", str(path)]) == 0
    [line] = [x for x in capsys.readouterr().out.splitlines() if "log(after)" in x]
    assert f"(in subtree nudge, used at {path}:12:7 and at {path}:13:7)" in line
    assert main(["validate", "--format", "json", str(path)]) == 0
    [found] = [
        d
        for d in json.loads(capsys.readouterr().out)["diagnostics"]
        if "log(after)" in d["message"]
    ]
    assert found["used_in"] == [
        [{"subtree": "nudge", "file": str(path), "line": line, "column": 7}] for line in (12, 13)
    ]


#: a library (its own file) of subtrees: each is right on its own, wrong only as a use
#: below uses it
LIBRARY = """\
subtrees:
  leg:
    tree:
      drive: {velocity: 100 mm/s, distance: 10cm}
  say:
    parameters:
      t: {type: str, default: "OK"}
    tree:
      display: "${t}"
  count_into:
    parameters:
      out: {type: str}
    tree:
      check: {key: "${out}", op: ">=", value: 1}
  go:
    parameters:
      speed: {type: speed, default: 100 mm/s}
    tree:
      drive: {velocity: "${speed}", distance: 10cm}
"""


def _library_and_mission(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, tree: str, library: str = LIBRARY
) -> list[Diagnostic]:
    """The diagnostics ``validate`` gives the mission ``m.yaml`` (``tree`` its steps, after
    an include of ``lib.yaml`` and a bool key ``flag``), the library alone having none."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lib.yaml").write_text(library)
    (tmp_path / "m.yaml").write_text(
        "include: [lib.yaml]\nblackboard:\n  flag: {type: bool, initial: false}\n"
        "tree:\n  sequence:\n" + tree
    )
    assert validate_file("lib.yaml", profile=ROOMBA500).diagnostics == []
    return validate_file("m.yaml", profile=ROOMBA500).diagnostics


@pytest.mark.parametrize(
    ("tree", "line", "message", "in_library"),
    [
        pytest.param(  # a: the use is where the tree reaches the drive in Passive
            "    - subtree: leg\n", 6, "drive sends Drive (137)", (4, 7), id="mode"
        ),
        pytest.param(  # b: a text given at the use
            "    - mode: safe\n    - subtree: {id: say, t: TOOLONG}\n",
            7, "display.text: the display has 4 digits; 'TOOLONG'", (9, 16), id="text",
        ),
        pytest.param(  # c: a key the use names types the check's value
            "    - mode: safe\n    - subtree: {id: count_into, out: flag}\n",
            7, "check.value: expected true or false, got 1", (14, 47), id="key",
        ),
        pytest.param(  # d: a number given at the use
            "    - mode: safe\n    - subtree: {id: go, speed: 900 mm/s}\n",
            7, "drive: velocity 900 mm/s is out of range", (19, 25), id="number",
        ),
    ],
)  # fmt: skip
def test_an_error_a_use_causes_in_a_library_is_the_missions(
    tree: str,
    line: int,
    message: str,
    in_library: tuple[int, int],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Said at the use (the file counted and annotated), the library's line beside it."""
    [error] = _library_and_mission(tmp_path, monkeypatch, tree)
    assert (error.file, error.line, error.column) == ("m.yaml", line, 7)
    assert error.message.startswith(message), error
    assert error.included_from == ()  # the mission's own: not "an included file has errors"
    [inside] = error.in_subtree
    assert (inside.file, inside.line, inside.column) == ("lib.yaml", *in_library)
    # the use's YAML path is the line's; the body's is said with the body's place
    assert error.yaml_path == f"tree.sequence[{line - 6}].subtree"
    assert inside.path.startswith(f"subtrees.{inside.name}.tree.")
    body = f"lib.yaml:{in_library[0]}:{in_library[1]} [{inside.path}]"
    assert f"(in subtree {inside.name}, {body}) [{error.yaml_path}]" in str(error)


def test_an_error_of_the_library_itself_stays_at_the_library(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A default out of range is wrong at every use: the library's, naming the default."""
    library = LIBRARY.replace("default: 100 mm/s", "default: 650 mm/s")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lib.yaml").write_text(library)
    [alone] = validate_file("lib.yaml").diagnostics
    (tmp_path / "m.yaml").write_text(
        "include: [lib.yaml]\ntree:\n  sequence:\n    - mode: safe\n    - subtree: go\n"
    )
    [error] = validate_file("m.yaml").diagnostics
    assert error.located() == alone
    assert (error.file, error.line, error.in_subtree) == ("lib.yaml", 19, ())
    assert error.message.endswith(
        "(${speed} is 650 mm/s, the default of parameter speed at 17:37: "
        "give speed: 500mm/s at the use, or another default there)"
    ), error


def test_a_subtree_in_a_library_subtree_names_the_use_between(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    library = LIBRARY + "  twice:\n    tree:\n      sequence: [{subtree: leg}, {subtree: leg}]\n"
    errors = _library_and_mission(tmp_path, monkeypatch, "    - subtree: twice\n", library)
    assert [(e.file, e.line) for e in errors] == [("m.yaml", 6)] * 2
    assert str(errors[0]).startswith("m.yaml:6:7: drive sends Drive (137)")
    assert (
        "(in subtree leg, lib.yaml:4:7 [subtrees.leg.tree.drive], used at lib.yaml:22:19 in "
        "subtree twice)"
    ) in str(errors[0])


def test_a_library_subtree_used_many_times_is_said_once_at_its_first_use(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A hundred uses reached in Passive: one line, at the mission's first use (the file
    counted), naming the first five uses and how many more; in JSON, every use. A finding
    whose text differs with the use (each use's own speed) stays one a use."""
    tree = "    - subtree: leg\n" * 100 + "    - mode: safe\n"
    tree += "    - subtree: {id: go, speed: 900 mm/s}\n    - subtree: {id: go, speed: 800 mm/s}\n"
    leg, *speeds = _library_and_mission(tmp_path, monkeypatch, tree)
    assert (leg.file, leg.line, leg.column) == ("m.yaml", 6, 7)
    assert [chain[-1].line for chain in leg.used_in] == list(range(6, 106))
    assert leg.uses_said() == (
        " (in subtree leg, lib.yaml:4:7 [subtrees.leg.tree.drive], used here and at "
        "m.yaml:7:7 and at m.yaml:8:7 and at m.yaml:9:7 and at m.yaml:10:7 and 95 more)"
    )
    assert [(d.line, d.message.split()[2]) for d in speeds] == [(107, "900"), (108, "800")]
    assert [len(d.used_in) for d in speeds] == [1, 1]
    assert leg.included_from == ()  # the mission's own error, counted there


#: a subtree's text with a lone "$$" (its own text: every use has it) and "$${speed}"
#: (the text "${speed}" only where the mission declares speed: warned of there alone)
DOLLARS = """\
  priced:
    tree:
      log: "cost $${speed}"
      name: "a $$ b"
"""


def test_a_warning_parsing_a_subtree_body_names_its_use(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """In the mission's own file: at the body's line, naming each use, said once."""
    mission = compile_text(
        "subtrees:\n" + DOLLARS + "tree:\n  sequence:\n    - subtree: priced\n"
        "    - subtree: priced\n"
    )
    [doubled] = mission.warnings
    path = doubled.file
    assert (doubled.line, doubled.message.split(":")[0]) == (5, "name")
    assert doubled.uses_said() == (f" (in subtree priced, used at {path}:8:7 and at {path}:9:7)")


def test_a_warning_a_use_causes_in_a_library_body_is_the_missions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The library's own text is warned of at the library, once (the fix is there, for
    every use); the "$${speed}" only the mission's parameter makes a warning is said at its uses."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lib.yaml").write_text("subtrees:\n" + DOLLARS)
    (tmp_path / "m.yaml").write_text(
        "include: [lib.yaml]\nparameters:\n  speed: {type: speed, default: 100 mm/s}\n"
        "tree:\n  sequence:\n    - subtree: priced\n    - subtree: priced\n"
    )
    own, used = validate_file("m.yaml").diagnostics
    assert (own.file, own.line, own.used_in, own.in_subtree) == ("lib.yaml", 5, (), ())
    assert [site.file for site in own.included_from] == ["m.yaml"]
    assert (used.file, used.line, used.severity) == ("m.yaml", 6, "warning")
    assert '"$${speed}" is the text' in used.message
    # said at the mission's use, it names the file whose top the literal: goes at
    assert used.message.endswith("say so at the top of lib.yaml: literal: [speed]")
    assert used.uses_said() == (
        " (in subtree priced, lib.yaml:4:18 [subtrees.priced.tree.log], used here and at "
        "m.yaml:7:7)"
    )


def test_a_library_validated_alone_says_its_own_warnings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``validate lib.yaml`` said "ok" of a library whose lone "$$" it warned of where a
    mission included it: alone it says the same warning, and ``--strict`` fails on it (7),
    as for a mission. The "$${speed}" is no warning there: no speed is in scope alone."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lib.yaml").write_text("subtrees:\n" + DOLLARS)
    [own] = validate_file("lib.yaml").diagnostics
    assert (own.file, own.line, own.severity, own.included_from) == ("lib.yaml", 5, "warning", ())
    assert main(["validate", "lib.yaml"]) == 0
    assert main(["validate", "--strict", "lib.yaml"]) == 7
    out = capsys.readouterr().out
    assert out.count("lib.yaml:5:16: warning: name:") == 2, out
    assert "lib.yaml: failed --strict (1 warning)" in out
    assert main(["show", "lib.yaml"]) == 0  # its warnings are validate's to say


def test_each_node_of_nested_subtrees_is_marked_once_with_its_whole_chain(
    compile_text: Callable[..., CompiledMission], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Eight levels of a subtree using the next twice: each node of the expanded tree is
    given its uses once, the innermost first (marking each nested use's whole body again
    took 30 such levels from 0.24 s to 0.46 s of CPU, O(nodes x depth))."""
    from roomba_bt.mission import nodes

    marked: list[int] = []
    mark = nodes._mark_used

    def counted(node: Node, uses: tuple[SubtreeUse, ...]) -> None:
        marked.append(id(node))
        mark(node, uses)

    monkeypatch.setattr(nodes, "_mark_used", counted)
    levels = "".join(
        f"  s{i}:\n    tree: {{sequence: [{{subtree: s{i + 1}}}, {{subtree: s{i + 1}}}]}}\n"
        for i in range(8)
    )
    mission = compile_text(
        f"subtrees:\n{levels}  s8:\n    tree: {{log: leaf}}\ntree: {{subtree: s0}}\n"
    )
    walked = list(mission.plan.walk())
    assert sorted(marked) == sorted(id(node) for node in walked)  # each once, and all
    leaves = [node for node in walked if node.kind == "leaf"]
    assert len(leaves) == 2**8
    chain = leaves[0].loc.used_in
    assert [use.name for use in chain] == [f"s{i}" for i in range(8, -1, -1)]
    assert (chain[0].path, chain[-1].path) == (
        "subtrees.s7.tree.sequence[0].subtree",
        "tree.subtree",
    )
