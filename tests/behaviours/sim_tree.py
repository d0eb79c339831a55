"""One leaf on the simulator after a mode change: the set-up the tests of backing up near
the stairs share (tests/behaviours/test_homing.py and test_reversing.py), so a change to how
a tree is run on the simulator is made here once."""

from __future__ import annotations

import py_trees

from roomba_bt.behaviours.actions import Mode
from roomba_bt.behaviours.declare import RobotBehaviour
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
