"""``backtrack`` (roomba_bt/behaviours/actions.py): a mission's back-off goes only over the floor
the robot has just driven, read from the run's trail (roomba_bt/behaviours/reversing.py), as
``cover``'s do. ``patrol.yaml`` backed a fixed 15 cm after a cliff met a few centimetres past
its 60 deg turn in place: over floor it had never driven, beside a stair's edge."""

from __future__ import annotations

import math

import py_trees

from roomba_bt.behaviours.actions import Backtrack, Drive, Mode, Turn
from roomba_bt.behaviours.reversing import OWN_MM, RunTrail
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.interface import Odometry
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.sim import SimLink, Simulator
from roomba_bt.sim.world import Pose, parse_world

ROOM = """
name: open-room
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
"""


def _run(*leaves: py_trees.behaviour.Behaviour) -> list[tuple[float, float]]:
    """``leaves`` in a sequence after Full mode, from (2, 2) m facing east: the trace of the
    robot's true centre (mm)."""
    simulator = Simulator(parse_world(ROOM), CREATE2, 0, start=Pose(2000.0, 2000.0, 0.0))
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Mode("full", {"to": "full"}), *leaves]
    )
    stack = RunStack(TreeMission(root, "back-off"), SimLink(simulator), profile=CREATE2,
                     timeout_s=30.0)  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    return [(point.x, point.y) for point in simulator.trace]


def test_after_a_straight_drive_it_backs_the_whole_distance_over_it() -> None:
    trace = _run(
        Drive("ahead", {"velocity": 150.0, "distance": 400.0}),
        Backtrack("back", {"distance": 150.0, "speed": 150.0}),
    )
    farthest = max(x for x, _ in trace)
    assert farthest > 2380.0
    assert abs(trace[-1][0] - (farthest - 150.0)) < 15.0  # 15 cm back along its own line


def test_after_a_turn_in_place_it_backs_only_under_its_own_body() -> None:
    """Driven 40 cm east, turned 90 deg left and 2 cm north: the floor 15 cm south of it is
    floor it never drove (its east-west line lies beside, not behind). It backs 6 cm, the
    body's own (in Safe mode with a cliff showing, straight back is the one move left), and
    its centre never goes south of where the north leg began less those 6 cm."""
    trace = _run(
        Drive("ahead", {"velocity": 150.0, "distance": 400.0}),
        Turn("left", {"angle": 90.0, "speed": 100.0}),
        Drive("a little", {"velocity": 150.0, "distance": 20.0}),
        Backtrack("back", {"distance": 150.0, "speed": 150.0}),
    )
    turned_at = trace[0][1]  # the east leg's line, where it turned
    assert min(y for _, y in trace) > turned_at - OWN_MM + 20.0 - 15.0
    assert trace[-1][1] < turned_at + 20.0 - OWN_MM + 15.0  # it did back its 6 cm


def test_a_move_no_leaf_of_the_trail_saw_leaves_only_the_bodys_own() -> None:
    trail = RunTrail()
    for k in range(41):  # 40 cm straight east, fed every 10 mm
        trail.feed(Odometry(x_mm=10.0 * k, path_mm=10.0 * k))
    assert trail.backable(Odometry(x_mm=400.0, path_mm=400.0), 150.0) == 150.0
    moved = Odometry(x_mm=400.0, y_mm=300.0, path_mm=800.0)  # another leaf drove it
    assert trail.backable(moved, 150.0) == OWN_MM
    assert trail.backable(Odometry(theta_rad=math.pi), 150.0) == OWN_MM  # a new run's


def test_the_trail_fed_a_tick_at_a_time_keeps_what_each_pose_added_would() -> None:
    """``RunTrail.feed`` skips ``add`` while the path since the last pose kept is under a
    step (a path is never shorter than the line): the poses kept, and the gaps that start the
    trail again, are those of feeding every tick through ``gap`` and ``add`` (random walks,
    with turns in place, stops, a jump no feeding leaf saw and the odometry of a new run)."""
    import random

    for seed in range(20):
        rng = random.Random(seed)
        fast, slow = RunTrail(), RunTrail()
        x = y = theta = path = 0.0
        for tick in range(3000):
            roll = rng.random()
            if roll < 0.01:
                step = rng.uniform(50.0, 300.0)  # a move no feeding leaf saw
            elif roll < 0.2:
                step, theta = 0.0, theta + rng.uniform(-0.2, 0.2)  # turning in place
            else:
                step = rng.uniform(0.0, 7.5)
            x, y, path = x + step * math.cos(theta), y + step * math.sin(theta), path + step
            if rng.random() < 0.001:  # a new run's odometry
                x = y = path = 0.0
            odo = Odometry(x_mm=x, y_mm=y, theta_rad=theta, path_mm=path)
            fast.feed(odo)
            if slow.gap(odo):  # the feed before the shortcut, step by step
                slow.clear()
            slow._fed_path = odo.path_mm
            slow.add(odo)
            assert list(fast._poses) == list(slow._poses), (seed, tick)
