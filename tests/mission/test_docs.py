"""docs/missions.md documents every word of the language and every built-in behaviour."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.behaviours.actions import ACTIONS
from roomba_bt.behaviours.conditions import CONDITIONS
from roomba_bt.mission.compiler import TOP_LEVEL
from roomba_bt.mission.ir import LANGUAGE_WORDS, MODIFIERS

DOC = (Path(__file__).resolve().parents[2] / "docs" / "missions.md").read_text(encoding="utf-8")


def test_every_language_word_is_documented() -> None:
    for word in (*LANGUAGE_WORDS, *MODIFIERS, *TOP_LEVEL):
        assert f"`{word}" in DOC, word


def test_every_builtin_behaviour_and_parameter_is_documented() -> None:
    for cls in (*ACTIONS, *CONDITIONS):
        decl = cls.declaration
        assert f"**`{decl.name}`**" in DOC, decl.name
        for param in decl.params:
            assert f"| `{param.name}` |" in DOC, f"{decl.name}.{param.name}"
