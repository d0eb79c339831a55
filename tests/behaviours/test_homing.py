"""``home_by_map``: back along ``cover``'s map to where a dock beam was seen or to the start,
on the simulator (around an obstacle, with and without the encoders' error) and on a stub
robot (a beam seen on the way ends it, in that tick)."""

from __future__ import annotations

import math
from collections.abc import Callable

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours import coverage_map, driving
from roomba_bt.behaviours.coverage_map import Cover
from roomba_bt.behaviours.homing import HomeByMap
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import IR_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

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


def _frame(robot: StubRobot, counts: int, ir: int = 0) -> None:
    """Both encoders at ``counts`` (straight ahead); ``ir`` on the omni receiver."""
    values = dict.fromkeys((*driving.BLOCKED_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS), 0)
    values.update({43: counts % 65536, 44: counts % 65536, 35: int(OIMode.SAFE), 17: ir})
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
