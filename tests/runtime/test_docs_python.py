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


WORKER = "## From Python: a run in a worker thread"


def test_the_worker_thread_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """Its ``stack`` given (a short mission on the simulator), it runs to its end: the
    worker's summary printed, the SIGTERM handler it sets put back by the test."""
    import signal

    import py_trees

    from roomba_bt.behaviours.actions import Drive, Mode
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import RunStack, TreeMission
    from roomba_bt.sim import SimLink, Simulator, load_world

    section = DOC.read_text(encoding="utf-8").split(WORKER, 1)[1].split("\n## ", 1)[0]
    [block] = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    root = py_trees.composites.Sequence("w", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("fwd", {"velocity": "200 mm/s", "distance": "0.2 m"}),
    ])  # fmt: skip
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(TreeMission(root, "worker"), link, profile=CREATE2, timeout_s=10.0)
    previous = signal.getsignal(signal.SIGTERM)
    try:
        exec(compile(block, f"{DOC}:worker", "exec"), {"stack": stack})
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert "outcome      SUCCESS" in capsys.readouterr().out
