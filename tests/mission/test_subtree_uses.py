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

from roomba_bt.mission import CompiledMission, Diagnostic, SubtreeUse, compile_mission

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
