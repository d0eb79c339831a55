"""One leaf on the simulator after a mode change: the set-up the tests of backing up near
the stairs share (tests/behaviours/test_homing.py and test_reversing.py), so a change to how
a tree is run on the simulator is made here once; and the dock mission from one pose of a
shipped world (test_dock_beside.py, test_dock_crossing.py)."""

from __future__ import annotations

import re
from pathlib import Path

import py_trees

from roomba_bt.behaviours.actions import Mode
from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.evaluate import EpisodeResult, EpisodeSpec, run_episode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.sim import SimLink, Simulator
from roomba_bt.sim.world import Pose, parse_world


def run_after_mode(
    world: str, start: Pose, mode: str, leaf: RobotBehaviour, name: str, timeout_s: float
) -> Simulator:
    """Run ``mode`` then ``leaf`` on a Create 2 simulated in ``world`` (YAML text) from
    ``start``, seed 0, until the tree ends or ``timeout_s`` of robot time; the simulator is
    returned for its trace and whether a wheel went over a drop."""
    simulator = Simulator(parse_world(world), CREATE2, 0, start=start)
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Mode(mode, {"to": mode}), leaf]
    )
    stack = RunStack(TreeMission(root, name), SimLink(simulator), profile=CREATE2,
                     timeout_s=timeout_s)  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    return simulator


ROOT = Path(__file__).resolve().parents[2]
#: a world file's start pose, as the shipped worlds write it
_START = re.compile(r"start: \{at: \[[^\]]*\], heading: -?\d+\}")


def dock_from(
    tmp_path: Path, world: str, x: float, y: float, heading: float, *, trace_every: int = 0
) -> EpisodeResult:
    """``missions/dock.yaml`` on the shipped ``world`` (its name) with the robot put at
    (``x``, ``y``) m facing ``heading`` deg, to the mission's own 10-minute limit."""
    text = (ROOT / "roomba_bt" / "sim" / "worlds" / f"{world}.yaml").read_text()
    moved, count = _START.subn(f"start: {{at: [{x}, {y}], heading: {heading}}}", text)
    assert count == 1, f"{world}.yaml has {count} start poses where one was expected"
    path = tmp_path / f"{world}-from-{x}-{y}-{heading}.yaml"
    path.write_text(moved)
    spec = EpisodeSpec(str(ROOT / "missions" / "dock.yaml"), str(path), random_start=False,
                       timeout_s=660, trace_every=trace_every)  # fmt: skip
    return run_episode(spec)
