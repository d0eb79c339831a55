"""The Python example of docs/runtime.md ("From Python: a tree built by hand") runs as
written: a hand-built tree of a plain py_trees behaviour and roomba-bt leaves, on the
simulator, to SUCCESS."""

from __future__ import annotations

import ast
import json
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from waits import HANG_S, line  # tests/waits.py: a hang's bound, a line within it

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


def test_every_python_example_s_simulator_keeps_no_trajectory() -> None:
    """The default Simulator keeps its whole trajectory (12.7 MB an hour of simulated
    driving), and each Python example here built it so: one copied into a soak of hours
    grew 12 MB an hour, which its user measured as a leak (soak, finding 3). The pycon
    example (help(roomba_bt)'s, a dock of a minute) is not a ``python`` block."""
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.DOTALL)
    built = [
        node
        for block in blocks
        for node in ast.walk(ast.parse(block))
        if isinstance(node, ast.Call) and ast.unparse(node.func).endswith("Simulator")
    ]
    assert len(built) >= 3
    for call in built:
        trace = [k.value for k in call.keywords if k.arg == "trace"]
        assert [ast.unparse(v) for v in trace] == ["False"], ast.unparse(call)


BY_HAND = "## From Python: a connection driven by hand, then a mission"


def test_the_connection_driven_by_hand_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """Driven by hand, handed to a RunStack for a mission, taken back: the robot moved by
    hand, the mission succeeded on the same connection, and the program started it again."""
    section = DOC.read_text(encoding="utf-8").split(BY_HAND, 1)[1].split("\n## ", 1)[0]
    [block] = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    namespace: dict[str, object] = {"__name__": "docs_example"}
    exec(compile(block, f"{DOC}:by-hand", "exec"), namespace)
    out = capsys.readouterr().out
    counts = re.search(r"by hand: (\d+) encoder counts", out)
    assert counts is not None and int(counts[1]) > 50, out  # it drove before the mission
    assert "outcome      SUCCESS" in out and "after the mission: Passive" in out, out
    stack, robot = namespace["stack"], namespace["robot"]
    assert stack.connection is robot  # type: ignore[attr-defined]  # taken over, not copied
    simulator = namespace["simulator"]
    assert simulator.mode.label == "Passive"  # type: ignore[attr-defined]
    assert (simulator.requested_left, simulator.requested_right) == (0, 0)  # type: ignore[attr-defined]


WORKER = "## From Python: a run in a worker thread"


def test_the_worker_thread_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """Its two blocks run as written, one after the other (the ``stack`` the first makes:
    the recipe's alone stopped with a NameError, session 37's stranger), to the worker's
    summary printed; the SIGTERM handler it sets is put back by the test. The two sections
    after it point at this ``stack``."""
    import signal

    text = DOC.read_text(encoding="utf-8")
    section = text.split(WORKER, 1)[1].split("\n## ", 1)[0]
    made, recipe = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    namespace: dict[str, object] = {"__name__": "docs_example"}
    previous = signal.getsignal(signal.SIGTERM)
    try:
        exec(compile(made, f"{DOC}:worker-stack", "exec"), namespace)
        exec(compile(recipe, f"{DOC}:worker", "exec"), namespace)
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert "outcome      SUCCESS" in capsys.readouterr().out
    for later in ("## From Python: runs side by side", ASYNCIO):
        after = text.split(later, 1)[1].split("\n## ", 1)[0]
        assert 'made as in "a run in a worker thread"' in " ".join(after.split()), later


ASYNCIO = "## From Python: asyncio"

#: The recipe in a program of its own (``asyncio.run`` wants a main thread without a loop,
#: and Ctrl-C is a signal to the process): its ``stack`` given, a mission that drives on the
#: real-time simulator (``wall``: until Ctrl-C, "driving" said once it drives) or one that
#: ends on the virtual clock; how it ended printed last, as JSON.
RECIPE_HOST = """
import json, re, sys
import py_trees
from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, load_world

doc, section, kind = sys.argv[1:]
text = open(doc, encoding="utf-8").read().split(section, 1)[1].split("\\n## ", 1)[0]
[recipe] = re.findall(r"```python\\n(.*?)```", text, flags=re.DOTALL)
wall = kind == "wall"
drive = {"velocity": "150 mm/s"} if wall else {"velocity": "200 mm/s", "distance": "0.2 m"}
root = py_trees.composites.Sequence("a", memory=True, children=[
    Mode("safe", {"to": "safe"}), Drive("fwd", drive),
])
simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
link = RealtimeSimLink(simulator) if wall else SimLink(simulator)

def driving(runner):
    if runner.snapshot.tick == 20:
        print("driving", flush=True)

stack = RunStack(TreeMission(root, "async"), link, profile=CREATE2, timeout_s=60.0,
                 observer=driving if wall else None)
ended = "returned"
try:
    exec(compile(recipe, doc + ":asyncio", "exec"), {"stack": stack})
except KeyboardInterrupt:
    ended = "KeyboardInterrupt"
summary = stack.runner.summary
print(json.dumps({
    "ended": ended, "outcome": summary.outcome.value, "delivered": summary.stop_delivered,
    "mode": simulator.mode.label,
    "wheels": [simulator.requested_left, simulator.requested_right],
}), flush=True)
"""


def _host_the_recipe(kind: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", RECIPE_HOST, str(DOC), ASYNCIO, kind],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


def _ctrl_c_once_driving(host: subprocess.Popen[str], what: str) -> tuple[str, str]:
    """Ctrl-C to ``host`` once it says "driving"; its stdout and stderr at its end."""
    assert host.stdout is not None
    try:
        said = line(host.stdout, what)
        assert said == "driving\n", said
        host.send_signal(signal.SIGINT)
        return host.communicate(timeout=HANG_S)
    finally:
        host.kill()


def test_the_asyncio_recipe_runs() -> None:
    out, err = _host_the_recipe("virtual").communicate(timeout=HANG_S)
    assert "outcome      SUCCESS" in out, err
    assert json.loads(out.splitlines()[-1])["ended"] == "returned"


def test_the_asyncio_recipe_stops_the_robot_on_ctrl_c() -> None:
    """Ctrl-C while the robot drives (in real time): ``asyncio.run`` cancels the coroutine, its
    ``finally`` closes the stack, and the run ends INTERRUPTED with its safe stop delivered
    (without it the mission drove on to its end, and the program waited for it)."""
    out, err = _ctrl_c_once_driving(_host_the_recipe("wall"), "the recipe's robot driving")
    assert json.loads(out.splitlines()[-1]) == {
        "ended": "KeyboardInterrupt",
        "outcome": "interrupted",
        "delivered": True,
        "mode": "Passive",
        "wheels": [0, 0],
    }, err
    assert "not the main thread: Ctrl-C and SIGTERM do not reach it" in err


TICKS = "## From Python: a run tick by tick"


def test_the_tick_by_tick_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """The loop sees the run to its end: the blackboard's key written, SUCCESS, the robot
    left in Passive."""
    section = DOC.read_text(encoding="utf-8").split(TICKS, 1)[1].split("\n## ", 1)[0]
    [block] = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    namespace: dict[str, object] = {"__name__": "docs_example"}
    exec(compile(block, f"{DOC}:ticks", "exec"), namespace)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("t=1.48 s RUNNING Safe {'legs': 0}"), out
    assert out[-2].endswith("SUCCESS Passive {'legs': 1}") and out[-1] == "Outcome.SUCCESS", out
    simulator = namespace["simulator"]
    assert simulator.mode.label == "Passive"  # type: ignore[attr-defined]


#: A run on the real-time simulator until Ctrl-C ("driving" said once it drives), the
#: interrupt left uncaught (``bare``) or ended as the hand-built tree's example ends it.
INTERRUPTED_HOST = """
import sys
import py_trees
import roomba_bt
from roomba_bt.behaviours.actions import Drive, Mode

root = py_trees.composites.Sequence("a", memory=True, children=[
    Mode("safe", {"to": "safe"}), Drive("fwd", {"velocity": "150 mm/s"}),
])
simulator = roomba_bt.Simulator(roomba_bt.load_world("empty-room"), roomba_bt.CREATE2, seed=0)

def driving(runner):
    if runner.snapshot.tick == 20:
        print("driving", flush=True)

stack = roomba_bt.RunStack(roomba_bt.TreeMission(root, "ctrl-c"),
                           roomba_bt.RealtimeSimLink(simulator), profile=roomba_bt.CREATE2,
                           timeout_s=60.0, observer=driving)
if sys.argv[1] == "bare":
    stack.run()
try:
    stack.run()
except roomba_bt.Interrupted as interrupt:
    raise SystemExit(interrupt.summary.exit_code) from None
"""


@pytest.mark.parametrize(("how", "status"), [("bare", 1), ("as the example", 130)])
def test_an_interrupted_run_ends_the_program_with_the_status_the_page_says(
    how: str, status: int
) -> None:
    """An uncaught ``roomba_bt.Interrupted`` ends the program with status 1, not by SIGINT
    as Ctrl-C's own ``KeyboardInterrupt`` does (Python does that for the class itself
    only): the page said it ended the program "as Ctrl-C does". Its example's ending
    exits 130, as ``roomba-bt run`` does."""
    assert "raise SystemExit(interrupt.summary.exit_code) from None" in _example()
    host = subprocess.Popen(
        [sys.executable, "-c", INTERRUPTED_HOST, how.split()[0]],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    _, err = _ctrl_c_once_driving(host, "the run's robot driving")
    assert host.returncode == status, err
    assert ("roomba_bt.runtime.loop.Interrupted" in err) is (how == "bare"), err
