"""Falls off a drop and Safe mode's cliff stop, as the specs' "Safe Mode" describes them.

A robot falls when a drive wheel leaves the floor, in any mode; Safe mode stops it at a cliff
only while it moves forward or turns tighter than its own radius (docs/simulator.md, "Falls").
"""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.bits import WHEEL_DROP_BITS
from roomba_bt.oi.encode import Command
from roomba_bt.oi.modes import OIMode
from roomba_bt.sim import Pose, SimEvent, Simulator, load_world
from roomba_bt.sim.world import ROBOT_RADIUS_MM

from .helpers import Host, box_with_a_drop, make, pose

#: the floor a drop east of x = 2 m (stairs), as in the protocol engineer's cliffworld
STAIRS_AT_2_M = box_with_a_drop(2.0, start=(1, 2))


def _mode_causes(events: list[SimEvent]) -> list[str]:
    """The mode changes' details, oldest first: the last says why the robot is in Passive."""
    return [e.detail for e in events if e.kind == "mode"]


@pytest.mark.parametrize(
    ("start", "command"),
    [
        (pose(1.7, 2, 180), C.drive_straight(-150)),  # straight back toward the stairs
        (pose(1.86, 2, 90), C.drive(-100, -300)),  # back on an arc wider than the robot
    ],
    ids=["straight-back", "wide-backward-arc"],
)
def test_reversing_in_safe_mode_falls_off_the_drop_and_the_wheel_drop_gives_passive(
    start: Pose, command: Command
) -> None:
    """No cliff sensor leads when the robot backs straight or on a wide arc, so the firmware
    does not stop it: the wheels go over the edge, it falls, and its wheel drop gives Passive
    (before, it backed 1.2 m into the drop in Safe and the drive ended SUCCESS)."""
    host = make(STAIRS_AT_2_M, start=start)
    host.send(command)
    host.run(8.0)
    sim = host.sim
    assert sim.fallen
    assert sim.mode is OIMode.PASSIVE
    assert host.query([7])[7] & WHEEL_DROP_BITS == WHEEL_DROP_BITS
    assert sim.left_speed == sim.right_speed == 0.0
    assert _mode_causes(sim.events)[-1] == "Safe->Passive (safety: wheel drop)"
    assert sim.x < 2100.0  # it fell at the edge, not a metre on


def test_a_wheel_over_the_drop_falls_in_full_mode_with_the_centre_still_on_the_floor() -> None:
    """Driving along the edge, the outer wheel leaves the floor first: the robot falls there,
    its centre short of the drop (before, only the centre over a drop made it fall)."""
    host = make(STAIRS_AT_2_M, start=pose(1.85, 1, 80), mode="full")
    host.send(C.drive_straight(200))
    host.run(8.0)
    sim = host.sim
    assert sim.fallen and sim.mode is OIMode.FULL
    fell = next(e for e in sim.events if e.kind == "fell")
    assert fell.x < 2000.0
    assert host.query([7])[7] & WHEEL_DROP_BITS == WHEEL_DROP_BITS


@pytest.mark.parametrize(("over_mm", "falls"), [(5.0, False), (15.0, True)])
def test_a_wheel_falls_once_its_whole_tyre_is_past_the_edge(over_mm: float, falls: bool) -> None:
    """A tyre partly over an edge still rests on the floor (the apartment's stairs' corner
    tipped a cleaning robot with one wheel's axle point 1 cm past it): it falls once its
    inner edge, ``WHEEL_HALF_WIDTH_MM`` inside the axle's end, has left the floor."""
    axle_end_x = 2.0 + over_mm / 1000.0  # the right wheel's contact point, heading north
    host = make(STAIRS_AT_2_M, start=pose(axle_end_x - 0.1175, 1, 90), mode="full")
    host.send(C.drive_straight(100))
    host.run(2.0)
    assert host.sim.fallen is falls


def test_driving_forward_in_safe_mode_the_cliff_sensors_stop_it_before_a_wheel_falls() -> None:
    host = make(STAIRS_AT_2_M, start=pose(1.5, 2, 0))
    host.send(C.drive_straight(200))
    host.run(5.0)
    assert host.sim.mode is OIMode.PASSIVE and not host.sim.fallen
    causes = _mode_causes(host.sim.events)
    assert causes[-1] == "Safe->Passive (safety: cliff while driving forward)"


@pytest.mark.parametrize(
    "command",
    [C.spin(100, clockwise=True), C.drive_direct(-100, 100), C.drive(-100, 100)],
    ids=["spin-clockwise", "drive-direct-in-place", "tight-backward-arc"],
)
def test_turning_tighter_than_the_robot_at_an_edge_in_safe_mode_drops_to_passive(
    command: Command,
) -> None:
    """The spec's "moving backward with a small turning radius, less than one robot radius":
    a turn in place (radius 0) or a tight backward arc that brings a cliff sensor over the
    edge stops the robot in Passive, on the floor (before, only forward motion did)."""
    host = make(STAIRS_AT_2_M, start=pose(1.86, 2, 90))  # the right cliff sensor 10 mm short
    host.run(0.1)
    assert host.sim.mode is OIMode.SAFE
    host.send(command)
    host.run(4.0)
    assert host.sim.mode is OIMode.PASSIVE and not host.sim.fallen
    assert _mode_causes(host.sim.events)[-1] == (
        "Safe->Passive (safety: cliff while turning tighter than the robot's radius)"
    )


#: :data:`STAIRS_AT_2_M` with a start region across the stairs' edge: drawn by the centre
#: alone, a third of its starts stood with a wheel or a cliff sensor over the drop
STAIRS_EDGE_REGION = (
    "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\n"
    "drops: [{rect: [2.0, 0, 4, 4]}]\n"
    "robot: {start: {at: [1, 2], heading: 0}, "
    "start_region: {rect: [1.4, 0.5, 2.3, 3.5], heading: any}}\n"
)


def test_drawn_starts_keep_the_whole_body_off_a_drop() -> None:
    """A drawn start is refused while any part of the body (with its 20 mm to spare) is over
    a drop, not only its centre: its wheels and cliff sensors are on the floor, so it stands
    there without falling and reads no cliff on its first frame."""
    robot_reach_mm = ROBOT_RADIUS_MM + 20.0
    nearest_mm = []
    for seed in range(60):
        host = make(STAIRS_EDGE_REGION, start=None, mode="full", seed=seed, random_start=True)
        sim = host.sim
        nearest_mm.append(2000.0 - sim.x)
        assert sim.world.body_clear_of_drops(Pose(sim.x, sim.y, sim.theta), robot_reach_mm)
        host.run(1.0)
        assert not sim.fallen
        cliffs = host.query([9, 10, 11, 12])
        assert [cliffs[packet] for packet in (9, 10, 11, 12)] == [0, 0, 0, 0]
    assert min(nearest_mm) >= robot_reach_mm
    assert min(nearest_mm) < robot_reach_mm + 60.0  # the region up to the edge is still used


#: apartment seeds whose start, drawn by the centre alone, put the body over the stairs (an
#: eval sweep's seed 1203 fell at 0.1 s, 8 mm from their edge; 173, 315, 456 and 482 too)
OVER_THE_STAIRS_SEEDS = (143, 173, 315, 456, 482, 1203)


@pytest.mark.parametrize("seed", OVER_THE_STAIRS_SEEDS)
def test_apartment_starts_that_overhung_the_stairs_are_drawn_again(seed: int) -> None:
    world = load_world("apartment")
    sim = Simulator(world, seed=seed, random_start=True)
    start = Pose(sim.x, sim.y, sim.theta)
    assert start == world.sample_start(seed)
    assert world.body_clear_of_drops(start, ROBOT_RADIUS_MM)
    Host(sim).run(1.0)
    assert not sim.fallen
