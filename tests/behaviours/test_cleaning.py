"""The cleaning motions on the simulator: lanes sweep a room, a spiral grows, hazards stop them;
and on a stub robot, the wait out of Safe/Full they share."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from py_trees.common import Status

from roomba_bt.behaviours.cleaning import Lanes, Spiral
from roomba_bt.behaviours.coverage_map import Cover
from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.robot.testing import StubRobot

Sweep = Callable[..., EpisodeResult]
Make = Callable[..., RobotBehaviour]
#: the lanes start in a corner of the room, facing along its long side
CORNER = (0.25, 0.2, 0)


def test_lanes_from_a_corner_sweep_the_room(sweep: Sweep) -> None:
    result = sweep("lanes: {speed: 300 mm/s}", CORNER)
    assert result.outcome == "success", result.reason
    assert result.coverage is not None
    assert result.coverage.overall >= 0.9
    assert result.violations == 0


def test_lanes_end_at_a_drop_and_never_fall_in_full_mode(sweep: Sweep) -> None:
    drop = "drops: [{name: stairs, rect: [2.2, 0, 3, 2.5]}]"
    result = sweep("lanes: {speed: 300 mm/s}", CORNER, drop)
    assert result.outcome == "success", result.reason
    assert result.cliffs > 0 and not result.fell
    assert result.coverage is not None and result.coverage.overall >= 0.85


def test_lanes_do_not_cross_a_virtual_wall(sweep: Sweep) -> None:
    beam = "virtual_walls: [{from: [1.8, 0], to: [1.8, 2.5]}]"
    result = sweep("lanes: {speed: 300 mm/s}", CORNER, beam)
    assert result.outcome == "success", result.reason
    assert max(x for x, _ in result.trajectory) < 1.8


def test_a_wheel_drop_fails_the_lanes(sweep: Sweep) -> None:
    lift = "events: [{at: 5, kind: lift, duration: 2}]"
    result = sweep("lanes: {speed: 300 mm/s}", CORNER, lift)
    assert result.outcome == "failure"
    assert "wheel drop" in result.reason


@pytest.mark.parametrize("radius_m", [0.5, 0.8])
def test_the_spiral_grows_to_its_radius_in_open_floor(sweep: Sweep, radius_m: float) -> None:
    result = sweep(f"spiral: {{max_radius: {radius_m} m}}", (1.5, 1.25, 0))
    assert result.outcome == "success", result.reason
    # the spiral's centre starts 10 cm to the robot's left and drifts as the rings grow
    reach = max(math.hypot(x - 1.5, y - 1.25) for x, y in result.trajectory)
    assert radius_m <= reach <= radius_m + 0.3
    assert result.bumps == 0


def test_the_spiral_stops_at_a_wall(sweep: Sweep) -> None:
    result = sweep("spiral: {max_radius: 3 m}", CORNER)
    assert result.outcome == "success", result.reason
    assert result.time_s < 120


def tick(
    node: RobotBehaviour, robot: StubRobot, values: dict[int, int], mode: int, ticks: int = 1
) -> Status:
    """One tick of ``node`` on a frame of ``values`` in OI mode ``mode`` (packet 35)."""
    robot.set_frame({**values, 35: mode}, ticks=ticks)
    node.tick_once()
    return node.status


@pytest.mark.parametrize("leaf", [Spiral, Lanes, Cover])
def test_back_in_safe_the_grace_out_of_it_starts_again(
    robot: StubRobot, make: Make, leaf: type[RobotBehaviour]
) -> None:
    """A second out of Safe/Full fails a driving leaf; once the robot is back, the next time
    it leaves counts its own second (a fall to Passive long after the first one does not
    fail it at once, as :meth:`~roomba_bt.behaviours.declare.Action.stranded` says)."""
    node = make(leaf)
    still = {pid: 0 for pid in leaf.declaration.packets(node.params)}
    assert tick(node, robot, still, 2) is Status.RUNNING  # Safe: it drives
    assert tick(node, robot, still, 1) is Status.RUNNING  # Passive: it waits
    assert tick(node, robot, still, 2, ticks=200) is Status.RUNNING  # 3 s later, Safe again
    statuses = [tick(node, robot, still, 1) for _ in range(68)]  # Passive again
    assert statuses[:-1] == [Status.RUNNING] * 67  # a second of grace, again
    assert statuses[-1] is Status.FAILURE
    assert node.feedback_message.startswith("the robot left Safe/Full mode")


@pytest.mark.parametrize("leaf", [Spiral, Lanes, Cover])
def test_a_leaf_started_again_after_a_failure_says_nothing_of_it(
    robot: StubRobot, make: Make, leaf: type[RobotBehaviour]
) -> None:
    """A retry starts it again: the last attempt's failure is not its message any more (the
    tree at the end of a clean showed ``cover [✓] -- the robot left Safe/Full mode (cliff)
    ...``, from an attempt long before; halted by the time being up, the same)."""
    node = make(leaf)
    still = {pid: 0 for pid in leaf.declaration.packets(node.params)}
    assert tick(node, robot, still, 2) is Status.RUNNING
    assert tick(node, robot, still, 1) is Status.RUNNING  # Passive: its second begins
    assert tick(node, robot, still, 1, ticks=68) is Status.FAILURE
    assert node.feedback_message.startswith("the robot left Safe/Full mode")
    assert tick(node, robot, still, 2) is Status.RUNNING  # the retry: Safe, started again
    assert node.feedback_message == ""
