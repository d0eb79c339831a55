"""``home_by_map``: back along ``cover``'s map to where a dock beam was seen or to the start,
on the simulator (around an obstacle, with and without the encoders' error) and on a stub
robot (a beam seen on the way ends it, in that tick)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours import coverage_map, driving
from roomba_bt.behaviours.coverage_map import (
    SWEPT,
    VISITED,
    Bearings,
    Cell,
    Cover,
    FloorMap,
)
from roomba_bt.behaviours.drops import DROP
from roomba_bt.behaviours.homing import ACROSS_PLANS, HomeByMap, path_across
from roomba_bt.behaviours.reversing import OWN_MM
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import IR_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import MM_PER_COUNT
from roomba_bt.oi.stream import SLOT_SECONDS
from roomba_bt.robot.interface import Odometry
from roomba_bt.robot.testing import StubRobot
from roomba_bt.sim.world import Pose

from .sim_tree import run_after_mode

Sweep = Callable[..., EpisodeResult]
Make = Callable[..., object]

#: a minute of ``cover``, the brushes off, then the way home (the sweep's leaf, flow style)
CLEAN_THEN_HOME = (
    "sequence: {children: [{parallel: {policy: one, children: [{wait: 60s}, {cover: {}}]}},"
    " {motors: {}}, {home_by_map: {}}]}"
)
#: a box in the room's middle, and a dock on the south wall whose beams reach 0.5 m
DOCKED_ROOM = (
    "obstacles: [{name: pillar, rect: [1.3, 0.9, 1.7, 1.5]}]\n"
    "dock: {at: [0.6, 0.0], facing: 90, buoy_range: 0.5, force_field: 0.3}"
)
#: as ``clean`` leaves the dock: 0.4 m off it, facing away
START = (0.6, 0.4, 90)
#: a dock character (the red buoy) on the omni receiver
RED_BUOY = 168


def _farthest(result: EpisodeResult) -> float:
    x0, y0, _ = result.start
    return max(math.dist((x, y), (x0, y0)) for x, y in result.trajectory)


def test_the_way_home_leads_back_to_the_beams_around_what_cover_mapped(sweep: Sweep) -> None:
    """A minute of ``cover`` takes it across the room; the way home ends within the dock's
    beams (0.5 m), where the dock search takes over."""
    result = sweep(CLEAN_THEN_HOME, START, DOCKED_ROOM, seed=1, timeout_s=400.0)
    assert result.outcome == "success", result.reason
    assert _farthest(result) > 1.5  # it had gone across the room
    assert math.dist(result.end[:2], (0.6, 0.0)) < 0.7  # 1.2 m when cover's minute ends
    assert not result.fell and result.violations == 0


def test_the_way_home_with_the_encoders_error_still_ends(sweep: Sweep) -> None:
    """The pose drifts: it ends in a beam, or where its map says it saw one (SUCCESS, for
    the dock search to take over)."""
    result = sweep(
        CLEAN_THEN_HOME, START, DOCKED_ROOM, seed=1, timeout_s=400.0, odometry_error=0.015
    )
    assert result.outcome == "success", result.reason
    assert math.dist(result.end[:2], (0.6, 0.0)) < 0.7  # 0.9 m when cover's minute ends


def _frame(
    robot: StubRobot, counts: int, ir: int = 0, cliff: bool = False, mode: OIMode = OIMode.SAFE
) -> None:
    """Both encoders at ``counts`` (straight ahead); ``ir`` on the omni receiver; ``cliff``
    on the front-left cliff sensor."""
    values = dict.fromkeys((*driving.BLOCKED_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS), 0)
    values.update({43: counts % 65536, 44: counts % 65536, 35: int(mode), 17: ir, 10: int(cliff)})
    robot.set_frame(values)


def test_a_beam_seen_on_the_way_ends_it_and_the_way_leads_where_one_was_seen(
    make: Make, robot: StubRobot
) -> None:
    """``cover`` drives 1.3 m and sees a dock's beam on the way (its map keeps the cells);
    the way home plans to the nearest of them, not to the start, and ends in the tick a
    receiver sees a beam again."""
    home = make(HomeByMap)  # set up with the tree, before cover's first tick
    cover = make(Cover)
    counts = 0
    _frame(robot, counts)
    for tick in range(150):
        counts += 20
        _frame(robot, counts, RED_BUOY if 40 <= tick < 50 else 0)
        cover.tick_once()
    bearings = py_trees.blackboard.Blackboard.storage[coverage_map.MAP_KEY]
    beams = bearings.map.beams
    assert beams and all(300.0 < bearings.map.centre(c)[0] < 700.0 for c in beams)
    cover.stop(Status.INVALID)
    assert isinstance(home, HomeByMap)
    robot.flush()
    home.tick_once()
    assert home.status is Status.RUNNING
    assert home._corners == [] and home._cell in beams  # one straight leg, to a beam cell
    assert abs(driving.wrap(home._heading - math.pi)) < 0.1  # back the way it came
    for _ in range(5):
        _frame(robot, counts)
        home.tick_once()
    assert home.status is Status.RUNNING
    _frame(robot, counts, RED_BUOY)
    robot.flush()
    home.tick_once()
    assert home.status is Status.SUCCESS
    assert home.feedback_message == "a dock beam seen"
    assert oi.halt() in robot.flush()


def _cover_straight_ahead(make: Make, robot: StubRobot) -> None:
    """``cover`` set up and ticked 100 frames straight ahead (no beam seen), then halted: its
    map on the blackboard, as a run leaves it."""
    cover = make(Cover)
    counts = 0
    for _ in range(100):
        counts += 20
        _frame(robot, counts)
        cover.tick_once()
    cover.stop(Status.INVALID)


def test_without_cover_s_map_or_a_beam_seen_it_ends_at_once(make: Make, robot: StubRobot) -> None:
    """No map (the battery low before cover ran) and a map without a beam seen (a robot put
    down away from the dock): nothing to go back to, SUCCESS at once, and the search starts
    where it is (going back to where it was put down first cost a seed of the apartment its
    dock; a FAILURE with no map was retried by clean.yaml five times, "gave up")."""
    home = make(HomeByMap)
    assert isinstance(home, HomeByMap)
    _frame(robot, 0)
    home.tick_once()
    assert home.status is Status.SUCCESS
    assert "no map" in home.feedback_message
    home = make(HomeByMap)  # a tree's nodes are all set up before its first tick
    _cover_straight_ahead(make, robot)
    home.tick_once()
    assert home.status is Status.SUCCESS
    assert "no dock beam seen" in home.feedback_message


def test_a_map_an_earlier_run_left_is_not_gone_by(make: Make, robot: StubRobot) -> None:
    """The blackboard is the process's: a second run (a program's second RunStack, an
    evaluation in one process) of a mission without ``cover`` drove on the first run's map
    (2.27 m in a corridor on the apartment's). Set up for a new run, it forgets it."""
    _cover_straight_ahead(make, robot)
    home = make(HomeByMap)
    home.tick_once()
    assert home.status is Status.SUCCESS
    assert "no map" in home.feedback_message


class _Wheels:
    """The stub robot's encoders turned by what the leaves send: each frame moves each wheel
    at the last Drive Direct's speed for one 15 ms slot (Drive 0 stops them; ``held``: a
    wheel held by something, nothing moves), so a leaf drives, turns and backs off by its
    own commands."""

    def __init__(self, robot: StubRobot) -> None:
        self.robot = robot
        self.speeds = (0, 0)  # left, right (mm/s)
        self._counts = [0.0, 0.0]

    def sent(self) -> tuple[int, int]:
        """The wheel speeds the last tick left (left, right)."""
        for command in self.robot.flush():
            if command.opcode == 145:
                right, left = command.args
                self.speeds = (left, right)
            elif command.opcode == 137:
                self.speeds = (0, 0)
        return self.speeds

    def frame(self, *, held: bool = False, ir: int = 0, hazard: int = 0) -> None:
        """The next frame: the wheels moved one slot; ``hazard`` a packet that shows 1."""
        if not held:
            for i, speed in enumerate(self.sent()):
                self._counts[i] += speed * SLOT_SECONDS / MM_PER_COUNT
        packets = (*driving.BLOCKED_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS)
        values = dict.fromkeys(packets, 0)
        left, right = (round(counts) % 65536 for counts in self._counts)
        values.update({43: left, 44: right, 35: int(OIMode.SAFE), 17: ir})
        if hazard:
            values[hazard] = 1
        self.robot.set_frame(values)


#: a packet that shows each hazard :func:`driving.blocked` names: the right bumper, the front
#: left cliff sensor, a virtual wall's beam
HAZARDS = {"bump": 7, "cliff": 10, "virtual wall": 13}


def _cover_then_homing(make: Make, wheels: _Wheels) -> tuple[Cover, HomeByMap]:
    """``cover`` 150 frames straight ahead on its own commands, a beam seen on the way, then
    ``home_by_map`` ticked until it drives back along its path."""
    home = make(HomeByMap)
    cover = make(Cover)
    for tick in range(150):
        wheels.frame(ir=RED_BUOY if 40 <= tick < 50 else 0)
        cover.tick_once()
    cover.stop(Status.INVALID)
    assert isinstance(home, HomeByMap)
    for _ in range(400):  # plan, turn about (some 2 s), drive
        wheels.frame()
        home.tick_once()
        if home._phase == "drive" and wheels.speeds[0] > 0:
            return cover, home
    raise AssertionError(f"home_by_map never drove its path: {home._phase}")


def _backs_off(
    leaf: Cover | HomeByMap, wheels: _Wheels, hazard: int, under_way: int = 10
) -> tuple[float, set]:
    """``leaf`` driving straight meets ``hazard`` (one frame) after ``under_way`` frames:
    how far (mm) it then backed off, and the wheel speeds it backed at."""
    for _ in range(under_way):  # well under way
        wheels.frame()
        leaf.tick_once()
    assert min(wheels.sent()) > 0
    wheels.frame(hazard=hazard)
    leaf.tick_once()
    met = wheels.robot.snapshot.odometry.distance_mm
    speeds = set()
    while max(wheels.sent()) < 0:  # both wheels backward
        speeds.add(wheels.speeds)
        wheels.frame()
        leaf.tick_once()
    return met - wheels.robot.snapshot.odometry.distance_mm, speeds


@pytest.mark.parametrize("why", sorted(HAZARDS))
def test_the_way_home_backs_off_a_hazard_as_cover_does(
    make: Make, robot: StubRobot, why: str
) -> None:
    """The way home meets what cleaning met and reacts alike: both back off each hazard the
    same distance at the same speed (``driving.BACK_OFF_MM``, ``driving.BACK_MM_S``; homing
    read cover's private table, and a change to one was not a change to the other)."""
    wheels = _Wheels(robot)
    cover = make(Cover)
    assert isinstance(cover, Cover)
    # cover backs off over floor it has driven (behaviours/reversing.py): 30 frames of its
    # seek, some 13 cm, are more than the longest back-off (a beam's 10 cm)
    cleaning = _backs_off(cover, wheels, HAZARDS[why], under_way=30)
    py_trees.blackboard.Blackboard.storage.clear()
    _, home = _cover_then_homing(make, wheels)
    homing = _backs_off(home, wheels, HAZARDS[why], under_way=30)  # so does the way home
    # one frame's move backing off, and the encoders' count
    step = driving.BACK_MM_S * SLOT_SECONDS + MM_PER_COUNT
    for backed, speeds in (cleaning, homing):
        assert driving.BACK_OFF_MM[why] <= backed < driving.BACK_OFF_MM[why] + step
        assert speeds == {(-driving.BACK_MM_S, -driving.BACK_MM_S)}

    assert abs(cleaning[0] - homing[0]) < step


def test_the_way_home_backs_off_no_bump_toward_a_drop_on_its_map(
    make: Make, robot: StubRobot
) -> None:
    """A drop ``cover`` met lies 18 cm behind the way home's centre, across its line (over
    floor it drove: with the encoders' error a drop may sit on the map there): a bump ahead
    then backs it off not at all, where it backed its 3 cm blind."""
    wheels = _Wheels(robot)
    _, home = _cover_then_homing(make, wheels)
    for _ in range(30):
        wheels.frame()
        home.tick_once()
    assert home._bearings is not None
    pose = home._pose
    back = pose.theta_rad + math.pi
    x, y = pose.x_mm + 180.0 * math.cos(back), pose.y_mm + 180.0 * math.sin(back)
    across = (-150.0 * math.sin(back), 150.0 * math.cos(back))
    home._bearings.map.drops.mark(x - across[0], y - across[1], back, 0.0)
    home._bearings.map.drops.mark(x + across[0], y + across[1], back, 1.0)
    backed, _ = _backs_off(home, wheels, HAZARDS["bump"], under_way=1)
    assert backed < 1.0, backed


def _held_until(leaf: Cover | HomeByMap, wheels: _Wheels, gave_up: Callable[[], bool]) -> float:
    """How long (s) ``leaf`` drives on with its wheels held until ``gave_up()``."""
    start = wheels.robot.snapshot.time
    while not gave_up():
        wheels.frame(held=True)
        leaf.tick_once()
        assert wheels.robot.snapshot.time - start < 2 * driving.STALL_S
    return wheels.robot.snapshot.time - start


def test_the_way_home_gives_a_held_leg_up_as_cover_gives_up_a_held_line(
    make: Make, robot: StubRobot
) -> None:
    """A wheel held on a straight drive: both leaves give it up after the same time with no
    progress along the line (``driving.STALL_S``; cover's own, read by homing): cover ends
    the line (``stalled``), the way home backs off it and keeps its cell out of the next
    plans, as after a bump (it planned the same push again at once, plan after plan: a TV
    stand's side pushed for 6.5 minutes)."""
    wheels = _Wheels(robot)
    _, home = _cover_then_homing(make, wheels)
    homing = _held_until(home, wheels, lambda: home._phase == "back")
    assert home._bearings is not None and home._cell in home._bearings.map.avoid
    cover = make(Cover)  # a new run: ahead from a standstill, the wheels held from the start
    assert isinstance(cover, Cover)
    cleaning = _held_until(cover, wheels, lambda: getattr(cover, "_why", None) == "stalled")
    for after in (homing, cleaning):
        assert abs(after - driving.STALL_S) <= 2 * SLOT_SECONDS, (homing, cleaning)


def _cell(fmap: FloorMap, x: float, y: float) -> Cell:
    cell = fmap.cell(x, y)
    assert cell is not None
    return cell


def _strip_map(
    beams: dict[tuple[float, float], float], across_at: float | None = None, also: int = 0
) -> FloorMap:
    """``cover``'s map as a run leaves it on the blackboard, the robot at its origin facing
    +x: a strip 0.3 m wide swept from x -2 m to +2 m; the beams seen at these points (mm),
    each with the path (mm) driven when last seen there; and at x ``across_at`` a line of
    blocked cells across the strip (with the bits ``also``: DROP, a drop's)."""
    fmap = FloorMap()
    for x in range(-2000, 2000, 100):
        for y in (-100, 0, 100):
            fmap.cells[_cell(fmap, x + 50.0, y + 50.0)] |= SWEPT | VISITED
    for (x, y), path in beams.items():
        fmap.beams[_cell(fmap, x, y)] = path
    if across_at is not None:
        for y in (-100, 0, 100):
            fmap.block(across_at + 50.0, y + 50.0)
            fmap.cells[_cell(fmap, across_at + 50.0, y + 50.0)] |= also
    py_trees.blackboard.Blackboard.storage[coverage_map.MAP_KEY] = Bearings(fmap, Odometry())
    return fmap


def _plan_once(
    make: Make, robot: StubRobot, beams: dict[tuple[float, float], float], **across: Any
) -> tuple[HomeByMap, FloorMap]:
    """A ``home_by_map`` set up (which forgets any earlier map), then :func:`_strip_map`'s
    map (``across``: its line of blocked cells), then one tick."""
    home = make(HomeByMap)
    assert isinstance(home, HomeByMap)
    fmap = _strip_map(beams, **across)
    _frame(robot, 0)
    home.tick_once()
    return home, fmap


def _goal(home: HomeByMap) -> Cell:
    """The cell its plan ends in (the last corner, or the leg on now when it is the last)."""
    return home._corners[-1] if home._corners else home._cell


def test_the_way_home_leads_to_the_beams_seen_last_not_the_nearest(
    make: Make, robot: StubRobot
) -> None:
    """With the encoders' error a beam cell is where the beams were by the pose of when it
    was seen: one seen early in the run is metres off by now (the apartment put such cells
    over the stairs and in the bedroom, 1.5 % error). The way home leads to those seen last
    (within RECENT_BEAMS_MM of path of the last sighting), here 1.55 m ahead, not to the
    nearest, 0.45 m behind but seen 19 m of path before."""
    home, fmap = _plan_once(make, robot, {(-450.0, 50.0): 1000.0, (1550.0, 50.0): 20000.0})
    assert home.status is Status.RUNNING
    assert _goal(home) == _cell(fmap, 1550.0, 50.0)
    assert abs(driving.wrap(home._heading)) < 0.1  # ahead, not back


def test_a_map_that_closes_the_robot_in_is_crossed_but_never_a_drop(
    make: Make, robot: StubRobot
) -> None:
    """With the encoders' error a wall met late in the run is drawn across floor swept early
    (seeds of the apartment found the robot's part of the map closed all round, and the way
    home failed at once: "no way", the search from the bedroom or the kitchen). With no path
    that keeps off blocked cells it plans across them; never across a drop's cells (the
    stairs: each meeting stops the robot in Safe mode)."""
    beam = {(1550.0, 50.0): 5000.0}
    home, fmap = _plan_once(make, robot, beam, across_at=500.0)
    assert home.status is Status.RUNNING
    assert _goal(home) == _cell(fmap, 1550.0, 50.0)
    home, fmap = _plan_once(make, robot, beam, across_at=500.0, also=DROP)
    assert home.status is Status.FAILURE
    assert home.feedback_message == "no way on the map to where the dock's beams were seen"


def test_plans_across_the_map_are_given_up_after_a_few_in_a_run(
    make: Make, robot: StubRobot
) -> None:
    """Where the map has drifted past use, plans across it met real walls over and over for
    minutes (two seeds of the apartment lost their dock so): after ACROSS_PLANS in a run,
    counted over the retries that start it again, it ends and the search starts there."""
    home, _ = _plan_once(make, robot, {(1550.0, 50.0): 5000.0}, across_at=500.0)
    for _ in range(ACROSS_PLANS - 1):
        assert home.status is Status.RUNNING
        home.stop(Status.FAILURE)  # as clean.yaml's retry after a cliff: started again
        home.tick_once()
    assert home.status is Status.RUNNING
    home.stop(Status.FAILURE)
    home.tick_once()
    assert home.status is Status.SUCCESS
    assert "led nowhere" in home.feedback_message


def test_a_cliff_on_a_leg_keeps_the_next_plans_off_it(make: Make, robot: StubRobot) -> None:
    """The firmware stops the robot at a cliff (Safe to Passive) and the leaf fails at once;
    the leg's cell is avoided from then on, and the drop is on the map as one: the retries
    of the apartment's seed 19 drove the same leg to the stairs' edge five times in 6 s."""
    home, fmap = _plan_once(make, robot, {(1550.0, 50.0): 5000.0})
    leg = home._cell
    for counts in range(20, 200, 20):  # along the leg
        _frame(robot, counts)
        home.tick_once()
    assert home.status is Status.RUNNING and home._phase == "drive"
    _frame(robot, 200, cliff=True, mode=OIMode.PASSIVE)
    home.tick_once()
    assert home.status is Status.FAILURE
    assert leg in fmap.avoid
    assert any(bits & DROP for bits in fmap.cells)


def test_a_path_across_the_map_keeps_a_cell_off_a_known_drop() -> None:
    """A landing beside the stairs (their edge met every 25 cm along y = -20 mm) and a ghost
    wall across it: the path across blocked cells ran along the edge, the robot's centre
    70 mm from it and a cliff sensor over it (session 27's review); it keeps a cell off."""
    fmap = FloorMap()
    for x in range(0, 3000, 100):
        for y in range(0, 600, 100):
            fmap.cells[_cell(fmap, x + 50.0, y + 50.0)] |= SWEPT
    for i, x in enumerate(range(0, 3001, 250)):
        fmap.drops.mark(float(x), -20.0, -math.pi / 2, i * 50.0)
    for y in range(100, 600, 100):
        fmap.block(1550.0, y + 50.0)  # the ghost wall, the landing's first row left open
    path = path_across(fmap, _cell(fmap, 250.0, 350.0), {_cell(fmap, 2750.0, 350.0)})
    assert path is not None
    around = (-601, -600, -599, -1, 0, 1, 599, 600, 601)
    assert not [c for c in path if any(fmap.cells[c + d] & DROP for d in around)]


def test_a_leg_toward_a_known_drop_ends_short_of_it(make: Make, robot: StubRobot) -> None:
    """A drop ``cover`` met (its map's line) ahead on a leg: the leg ends before a cliff
    sensor reaches it and the next plans keep off that leg's cell, as ``cover``'s legs do
    (session 27's review: the way home drove on along a known edge until the firmware's
    stop, a fall to Passive and one of the mission's retries)."""
    home, fmap = _plan_once(make, robot, {(1550.0, 50.0): 5000.0})
    leg = home._cell
    for counts in range(20, 100, 20):  # along the leg, about 4 cm
        _frame(robot, counts)
        home.tick_once()
    assert home.status is Status.RUNNING and home._phase == "drive"
    x = home._pose.x_mm
    for i, y in enumerate((-300.0, -150.0, 0.0, 150.0, 300.0)):  # across the leg, 0.2 m ahead
        fmap.drops.mark(x + 200.0, y, math.pi / 2, 100.0 * i)
    robot.flush()
    _frame(robot, 100)
    home.tick_once()
    assert leg in fmap.avoid
    assert home._phase != "drive"
    assert not [c for c in robot.flush() if c.spec.name == "drive_direct" and max(c.args) > 0]


#: A 3 m x 2.5 m room whose south 60 cm are stairs, a virtual wall's beam across it at 0.81 m
STAIRS_BEHIND_A_BEAM = """
name: stairs-behind-a-beam
rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]
drops: [{name: stairs, rect: [0, 0, 3, 0.6]}]
virtual_walls: [{from: [0, 0.81], to: [3, 0.81]}]
"""


class _LegIntoABeam(HomeByMap):
    """``home_by_map`` as a leg north begins: it has just turned in place (it has driven
    nothing facing this way), its omni receiver into a virtual wall's beam, the stairs
    behind it; where the dock's beams were seen is 1 m ahead."""

    def start(self) -> None:
        odo = self.snapshot.odometry
        bearings = Bearings(FloorMap(), odo)
        heading = odo.theta_rad
        goal = bearings.map.cell(
            odo.x_mm + 1000.0 * math.cos(heading), odo.y_mm + 1000.0 * math.sin(heading)
        )
        assert goal is not None
        bearings.map.beams[goal] = 0.0
        storage = py_trees.blackboard.Blackboard.storage
        storage[coverage_map.run_board().name(coverage_map.MAP_KEY)] = bearings
        super().start()
        self._phase, self._cell, self._limit = "drive", goal, 1000.0
        self._line = (odo.x_mm, odo.y_mm, odo.theta_rad)


def test_the_way_home_does_not_back_blind_off_a_beam_onto_the_stairs() -> None:
    """Its wheels 8 cm from the stairs' edge behind it, a leg that meets a virtual wall's
    beam at once backed off it 10 cm blind (a Create 2 has no sensor behind the wheels):
    a wheel went down the stairs. Now it backs as ``cover`` does (behaviours/reversing.py):
    no floor driven behind it, so no more than under its own body (6 cm): no wheel drop."""
    start = Pose(1500.0, 600.0 + 80.0, math.pi / 2)
    home = _LegIntoABeam("home_by_map", {})
    simulator = run_after_mode(STAIRS_BEHIND_A_BEAM, start, "safe", home, "leg-into-a-beam", 10.0)
    assert not simulator.fallen
    lowest = min(point.y for point in simulator.trace)
    assert 600.0 + 10.0 < lowest < start.y - OWN_MM + 10.0, lowest  # it backed: its own 6 cm
