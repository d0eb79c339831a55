"""The smaller findings of session 36's stranger about mission files: a plugin named by
module, look-alike letters, names that must be ASCII, and suggestions worked out for
errors never shown."""

from __future__ import annotations

import gc
import json
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.behaviours import units
from roomba_bt.cli import main
from roomba_bt.mission import Permissions, compile_mission
from roomba_bt.mission.diagnostics import MAX_REPORTED


def _problems(path: Path, *, plugin_files: bool = False) -> list[str]:
    permissions = Permissions(plugin_files=plugin_files)
    _, problems = compile_mission(path, permissions=permissions)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def _mission(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "m.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("allowed", [True, False])
@pytest.mark.parametrize("entry", ["json.decoder", "rbt_good"])
def test_a_plugin_named_by_module_is_told_plugins_takes_files(
    tmp_path: Path, entry: str, allowed: bool
) -> None:
    """It was "plugin file 'json.decoder' not found", or without --allow-plugin-files, to
    allow plugin files: neither helps, as plugins: never takes a module."""
    path = _mission(tmp_path, f"mission: m\nplugins: [{entry}]\ntree: stop\n")
    (problem,) = _problems(path, plugin_files=allowed)
    assert problem.startswith(f"2:11: plugin file '{entry}' not found: '{entry}' looks like a "
                              "module name, and plugins: takes files")  # fmt: skip
    assert "entry point in the group roomba_bt.behaviours" in problem


def test_a_plugin_path_not_found_is_still_said_as_a_path(tmp_path: Path) -> None:
    path = _mission(tmp_path, "mission: m\nplugins: [lib/gone.py]\ntree: stop\n")
    assert _problems(path, plugin_files=True) == [
        "2:11: plugin file 'lib/gone.py' not found (paths are relative to the file naming it)"
    ]


def test_a_lookalike_letter_is_named_by_its_code_point(tmp_path: Path) -> None:
    """``dr\\u0456ve`` said "unknown node 'dr\\u0456ve' (did you mean 'drive'?)", which read
    on screen as the word it suggests; a fullwidth word had no suggestion at all."""
    path = _mission(
        tmp_path,
        "mission: m\ntree:\n  sequence:\n    - mode: safe\n"
        "    - dr\u0456ve: {velocity: 200 mm/s, duration: 1s}\n"
        "    - \uff44\uff52\uff49\uff56\uff45: {velocity: 200 mm/s, duration: 1s}\n"
        "    - drive: {velocity: 200 mm/s, duration: 1s, dur\u0430tion: 1s}\n",
    )
    assert _problems(path) == [
        "5:7: unknown node 'dr\u0456ve' (did you mean 'drive'? '\u0456' (U+0456 CYRILLIC "
        "SMALL LETTER BYELORUSSIAN-UKRAINIAN I) is not the ASCII letter 'i')",
        "6:7: unknown node '\uff44\uff52\uff49\uff56\uff45' (did you mean 'drive'? '\uff44' "
        "(U+FF44 FULLWIDTH LATIN SMALL LETTER D) is not the ASCII letter 'd')",
        "7:49: drive: unknown parameter 'dur\u0430tion' (did you mean 'duration'? '\u0430' "
        "(U+0430 CYRILLIC SMALL LETTER A) is not the ASCII letter 'a'); known: velocity, "
        "radius, left, right, distance, angle, duration",
    ]


def test_a_name_that_is_not_ascii_is_told_it_must_be(tmp_path: Path) -> None:
    """ "blackboard key 'vitesse_é' must be snake_case": it is; ASCII is what is meant."""
    path = _mission(
        tmp_path,
        "mission: m\nparameters:\n  \u901f\u5ea6: {type: speed, default: 200 mm/s}\n"
        "blackboard:\n  vitesse_\u00e9: {type: speed, initial: 100 mm/s}\n"
        "tree:\n  sequence: [mode: safe, drive: {velocity: '${\u901f\u5ea6}', duration: 1s}]\n",
    )
    rule = "must be ASCII snake_case (a-z, 0-9 and _, not starting with a digit): "
    problems = _problems(path)
    assert problems[:2] == [
        f"3:3: parameter name '\u901f\u5ea6' {rule}'\u901f' (U+901F CJK UNIFIED "
        "IDEOGRAPH-901F) is not ASCII",
        f"5:3: blackboard key 'vitesse_\u00e9' {rule}'\u00e9' (U+00E9 LATIN SMALL LETTER E "
        "WITH ACUTE) is not ASCII (write 'vitesse_e')",
    ]
    assert "a parameter is ${name}: an ASCII letter or _, then ASCII letters" in problems[2]


def test_a_plain_snake_case_mistake_is_said_as_before(tmp_path: Path) -> None:
    path = _mission(tmp_path, "mission: m\nblackboard:\n  MySpeed: int\ntree: stop\n")
    said = "3:3: blackboard key 'MySpeed' must be snake_case (write 'my_speed')"
    assert _problems(path) == [said]


def test_suggestions_are_worked_out_only_for_the_errors_shown(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """68,000 unknown parameters took 15 s, a third of it difflib's suggestions for the
    67,900 errors never printed. The 100 printed have theirs; the JSON counts the rest."""
    count = 3 * MAX_REPORTED
    given = ", ".join(f"velocty{i}: 1" for i in range(count))
    path = _mission(tmp_path, f"mission: m\ntree:\n  sequence: [mode: safe, drive: {{{given}}}]\n")
    asked: list[str] = []
    suggest = units.closest_name

    def counted(word: str, candidates: list[str]) -> str | None:
        asked.append(word)
        return suggest(word, candidates)

    monkeypatch.setattr(units, "closest_name", counted)
    assert main(["validate", "--format", "json", str(path)]) == 2
    report = json.loads(capsys.readouterr().out)
    assert report["files"][0]["diagnostics_omitted"] == count - MAX_REPORTED
    shown = report["diagnostics"]
    assert len(shown) == MAX_REPORTED
    assert all("(did you mean 'velocity'?)" in d["message"] for d in shown)
    assert len(asked) == MAX_REPORTED, len(asked)
    _, problems = compile_mission(path)  # one not shown still says it, when asked
    assert "(did you mean 'velocity'?)" in str(problems[-1])


@pytest.mark.parametrize("enabled", [True, False])
@pytest.mark.parametrize("fails", [False, True])
def test_the_cycle_collector_is_paused_while_a_file_is_compiled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, enabled: bool, fails: bool
) -> None:
    """68,000 unknown parameters spent 1.0 s of their 2.5 s CPU in ten full collections,
    each walking every YAML node, place and finding made so far (none of them garbage in a
    cycle). Paused while the file is compiled, and as it was after, a compile that fails
    inside too; one the caller paused stays paused."""
    from roomba_bt.mission import compiler

    seen: list[bool] = []
    checked = compiler._checked

    def spied(*args: Any, **kwargs: Any) -> Any:
        seen.append(gc.isenabled())
        if fails:
            raise RuntimeError("a compiler bug")
        return checked(*args, **kwargs)

    monkeypatch.setattr(compiler, "_checked", spied)
    path = _mission(tmp_path, "mission: m\ntree: {sequence: [mode: safe, drive: {velocty: 1}]}\n")
    (gc.enable if enabled else gc.disable)()
    try:
        _, problems = compile_mission(path)
        after = gc.isenabled()
    finally:
        gc.enable()
    assert seen == [False] and after is enabled
    said = "internal error while compiling" if fails else "unknown parameter 'velocty'"
    assert said in problems[0].message, problems


def test_an_unknown_node_says_what_is_allowed(tmp_path: Path) -> None:
    """Session 37's stranger: ``wander`` (nothing close) said no more than "unknown node",
    and ``dock`` offered only the firmware's ``seek_dock``, where a reader of ``roomba-bt run
    dock`` meant the docking subtree that mission uses: each now says where to look."""
    path = _mission(
        tmp_path,
        "mission: m\ntree:\n  sequence:\n    - mode: safe\n"
        "    - wander: {speed: 200 mm/s}\n    - dock\n",
    )
    assert _problems(path) == [
        "5:7: unknown node 'wander'; roomba-bt behaviours lists the actions and conditions "
        "there are",
        "6:7: unknown node 'dock' (did you mean 'seek_dock'?); or, for the subtree the shipped "
        "missions use: include: [roomba-bt:lib/docking.yaml] and subtree: {id: dock}",
    ]
