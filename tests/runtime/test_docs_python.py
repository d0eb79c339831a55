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


ASYNCIO = "## From Python: asyncio"


def _asyncio_recipe() -> str:
    section = DOC.read_text(encoding="utf-8").split(ASYNCIO, 1)[1].split("\n## ", 1)[0]
    [block] = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    return str(block)


def test_the_asyncio_recipe_runs(capsys: pytest.CaptureFixture[str]) -> None:
    import py_trees

    from roomba_bt.behaviours.actions import Drive, Mode
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import RunStack, TreeMission
    from roomba_bt.sim import SimLink, Simulator, load_world

    root = py_trees.composites.Sequence("a", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("fwd", {"velocity": "200 mm/s", "distance": "0.2 m"}),
    ])  # fmt: skip
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(TreeMission(root, "async"), link, profile=CREATE2, timeout_s=10.0)
    exec(compile(_asyncio_recipe(), f"{DOC}:asyncio", "exec"), {"stack": stack})
    assert "outcome      SUCCESS" in capsys.readouterr().out


def test_the_asyncio_recipe_stops_the_robot_on_ctrl_c() -> None:
    """Ctrl-C while the robot drives (in real time): ``asyncio.run`` cancels the coroutine, its
    ``finally`` closes the stack, and the run ends INTERRUPTED with its safe stop delivered
    (without it the mission drove on to its end, and the program waited for it)."""
    import os
    import signal
    import threading

    import py_trees

    from roomba_bt.behaviours.actions import Drive, Mode
    from roomba_bt.oi.modes import OIMode
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.loop import MissionRunner
    from roomba_bt.runtime.stack import RunStack, TreeMission
    from roomba_bt.runtime.summary import Outcome
    from roomba_bt.sim import RealtimeSimLink, Simulator, load_world

    assert threading.current_thread() is threading.main_thread()  # where Ctrl-C lands
    pressed = threading.Event()

    def ctrl_c_while_driving(runner: MissionRunner) -> None:
        if runner.snapshot.tick >= 20 and not pressed.is_set():
            pressed.set()
            os.kill(os.getpid(), signal.SIGINT)

    root = py_trees.composites.Sequence("a", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("fwd", {"velocity": "150 mm/s"}),
    ])  # fmt: skip
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
    stack = RunStack(
        TreeMission(root, "async"), RealtimeSimLink(simulator), profile=CREATE2,
        timeout_s=60.0, observer=ctrl_c_while_driving,
    )  # fmt: skip
    with pytest.raises(KeyboardInterrupt):
        exec(compile(_asyncio_recipe(), f"{DOC}:asyncio", "exec"), {"stack": stack})
    assert pressed.is_set()
    summary = stack.runner.summary
    assert summary.outcome is Outcome.INTERRUPTED, summary
    assert summary.stop_delivered, summary.safe_stop
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
