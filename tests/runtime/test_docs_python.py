"""The Python example of docs/runtime.md ("From Python: a tree built by hand") runs as
written: a hand-built tree of a plain py_trees behaviour and roomba-bt leaves, on the
simulator, to SUCCESS."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[2] / "docs" / "runtime.md"
SECTION = "## From Python: a tree built by hand"


def _example() -> str:
    text = DOC.read_text(encoding="utf-8")
    assert SECTION in text, f"docs/runtime.md lost its section {SECTION!r}"
    section = text.split(SECTION, 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    assert len(blocks) == 1, "the section holds one Python example"
    return str(blocks[0])


def test_the_hand_built_tree_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    namespace: dict[str, object] = {"__name__": "docs_example"}
    exec(compile(_example(), f"{DOC}:example", "exec"), namespace)
    out = capsys.readouterr().out
    assert re.search(r"t=\d+\.\d\d s at \(5\d\d, -?\d+\) mm", out), out  # the plain behaviour
    assert "outcome      SUCCESS" in out
    summary = namespace["summary"]
    assert summary.distance_mm > 450  # type: ignore[attr-defined]
    mission = namespace["mission"]
    assert set(mission.packets) >= {43, 44}  # type: ignore[attr-defined]  # the encoders
