"""``cover``: its own map (swept strip, blocked cells, the frontier search) and the whole
behaviour on the simulator: a room swept to its edges, drops and virtual walls respected,
the same with the encoders' error on."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from functools import partial

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours import coverage_map, driving
from roomba_bt.behaviours.coverage_map import BLOCKED, CELL_MM, SWEPT, VISITED, Cover, FloorMap
from roomba_bt.behaviours.drops import DROP
from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec
from roomba_bt.evaluate.wheels import count_reversals
from roomba_bt.oi.frames import IR_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Sweep = Callable[..., EpisodeResult]
SweepSpec = Callable[..., EpisodeSpec]
Make = Callable[..., Cover]
#: ``cover`` starts in the middle of the room, at an angle to its walls
MIDDLE = (1.2, 1.0, 20)


def test_the_strip_is_swept_and_the_centre_visited() -> None:
    fmap = FloorMap()
    for k in range(11):  # 1 m along x, facing +x
        fmap.sweep(k * 100.0, 0.0, 0.0)
    here = fmap.cell(500.0, 0.0)
    assert here is not None
    assert fmap.cells[here] & (SWEPT | VISITED) == SWEPT | VISITED
    left, right = fmap.cell(500.0, 70.0), fmap.cell(500.0, -150.0)
    assert left is not None and right is not None
    assert fmap.cells[left] & SWEPT and fmap.cells[right] & SWEPT  # the side brush's side
    beyond = fmap.cell(500.0, 260.0)
    assert beyond is not None and not fmap.cells[beyond]
    assert fmap.swept == len([c for c in fmap.cells if c & SWEPT])


def test_a_blocked_cell_keeps_the_centre_out_of_its_neighbours() -> None:
    fmap = FloorMap()
    fmap.block(1000.0, 0.0)
    blocked = fmap.cell(1000.0, 0.0)
    assert blocked is not None and fmap.cells[blocked] & BLOCKED
    for dx, dy in ((CELL_MM, 0.0), (0.0, CELL_MM), (-CELL_MM, -CELL_MM)):
        cell = fmap.cell(1000.0 + dx, dy)
        assert cell is not None and not fmap.free(cell)
    far = fmap.cell(1000.0 + 2 * CELL_MM, 0.0)
    assert far is not None and fmap.free(far)
    start, end = fmap.cell(500.0, 0.0), fmap.cell(1500.0, 0.0)
    assert start is not None and end is not None
    assert not fmap.line_free(start, end)
    above = fmap.cell(1500.0, 400.0)
    assert above is not None and fmap.line_free(start, above)


def test_a_next_pass_forgets_the_sweep_and_the_walls_and_keeps_drops_beams_and_its_way() -> None:
    """The second pass maps the walls afresh (the first map's drifted ghosts closed it early)
    but never meets a known drop again for a map's sake, and the way home still leads over
    the cells it has been on to where it saw the dock."""
    fmap = FloorMap()
    for k in range(11):
        fmap.sweep(k * 100.0, 0.0, 0.0)
    fmap.block(1500.0, 0.0)
    fmap.drops.mark(0.0, 800.0, 0.0, 0.0)
    way, wall, drop = fmap.cell(500.0, 0.0), fmap.cell(1500.0, 0.0), fmap.cell(0.0, 800.0)
    assert way is not None and wall is not None and drop is not None
    fmap.beams[way] = 1000.0
    fmap.next_pass()
    assert fmap.passes == 2 and fmap.swept == 0 and not fmap.avoid
    assert fmap.cells[way] == VISITED and fmap.open_floor(way + 1)
    assert not fmap.cells[wall] and fmap.free(wall)
    assert fmap.cells[drop] & (DROP | BLOCKED) == DROP | BLOCKED and not fmap.free(drop + 1)
    assert fmap.beams == {way: 1000.0}
    assert sum(1 for n in fmap.near if n) == 9  # the drop's 3 x 3 alone
    assert fmap.floor_done() == "floor done: 0.0 m² swept by its own map (the last of 2 passes)"


def test_the_frontier_is_the_nearest_known_cell_beside_open_floor() -> None:
    fmap = FloorMap()
    for y in range(-10, 11):  # a swept square, 2 m a side, around the origin
        for x in range(-10, 11):
            cell = fmap.cell(x * CELL_MM, y * CELL_MM)
            assert cell is not None
            fmap.cells[cell] |= SWEPT
    for y in range(-12, 13):  # walls on three sides: open floor only past x = +1 m
        fmap.block(-11 * CELL_MM, y * CELL_MM)
        fmap.block(y * CELL_MM, 11 * CELL_MM + 50)
        fmap.block(y * CELL_MM, -11 * CELL_MM - 50)
    start = fmap.cell(0.0, 0.0)
    assert start is not None
    path = fmap.frontier(start)
    assert path is not None and path[0] == start
    target_x, _ = fmap.centre(path[-1])
    assert target_x > 900.0  # toward the only open side
    assert len(path) <= 12  # about 1 m: breadth-first, the nearest
    assert abs(path[1] - path[0]) in (1, 599, 600, 601)  # from the robot's own 3 x 3
    for a, b in itertools.pairwise(path[1:]):
        assert abs(a - b) in (1, 600)  # then 4-neighbours
    # swept everywhere it can reach: no frontier
    for y in range(-10, 11):
        fmap.block(11 * CELL_MM + 50, y * CELL_MM)
    assert fmap.frontier(start) is None


def _room_and_doorway(fmap: FloorMap) -> int:
    """A swept room (x -1..1 m) whose only way on is a doorway at x 1.1..1.3 m between two
    jambs 0.3 m apart (its cells all near one of them), open floor beyond; the robot's cell."""
    for y in range(-10, 11):
        for x in range(-10, 14):
            cell = fmap.cell(x * CELL_MM, y * CELL_MM)
            assert cell is not None
            if x <= 10 or y == 0:  # the doorway's row swept too, as a pass along it does
                fmap.cells[cell] |= SWEPT
    for y in range(-13, 14):  # walls around the room; the wall beyond it with its doorway
        fmap.block(-11 * CELL_MM, y * CELL_MM)
        fmap.block(y * CELL_MM, 11 * CELL_MM + 50)
        fmap.block(y * CELL_MM, -11 * CELL_MM - 50)
        if abs(y) >= 2:
            fmap.block(12 * CELL_MM, y * CELL_MM)
    fmap.block(12 * CELL_MM, CELL_MM)  # the jambs: every doorway cell is near one
    fmap.block(12 * CELL_MM, -CELL_MM)
    start = fmap.cell(0.0, 0.0)
    assert start is not None
    return start


def test_a_doorway_swept_along_its_jambs_still_leads_on() -> None:
    """Every cell of a narrow doorway is near a jamb: the search that keeps off such cells
    found no way on, and ``cover`` called a flat done with rooms behind a 0.75-0.9 m door
    left unswept (a field trial's flat: 3 of 8 runs). The search through them finds it."""
    fmap = FloorMap()
    start = _room_and_doorway(fmap)
    assert fmap.frontier(start) is None  # keeping off cells beside something
    path = fmap.frontier(start, through_near=True)
    assert path is not None and fmap.centre(path[-1])[0] > 1200.0  # through the doorway
    for cell in path:  # the robot's centre in the doorway: passable by either search
        fmap.cells[cell] |= VISITED
    assert fmap.frontier(start) is not None


def test_a_cell_the_robot_met_something_in_is_no_way_on() -> None:
    """A path through a cell beside something that the robot then bumped into was found
    again, path after path, the robot backing off and bumping at the same place until the
    search ran out of targets (a room left unswept); such a cell is avoided."""
    fmap = FloorMap()
    start = _room_and_doorway(fmap)
    path = fmap.frontier(start, through_near=True)
    assert path is not None
    doorway = next(c for c in path if fmap.centre(c)[0] > 1050.0)
    fmap.avoid.add(doorway)
    assert fmap.frontier(start, through_near=True) is None


def test_cover_sweeps_a_room_to_its_edges_and_ends(sweep: Sweep) -> None:
    result = sweep("cover: {}", MIDDLE, seed=3, timeout_s=600.0)
    assert result.outcome == "success", result.reason
    assert result.coverage is not None and result.coverage.overall >= 0.9
    assert result.coverage.longest_idle_s < 60.0
    assert result.violations == 0 and not result.fell


def test_cover_respects_a_drop_and_a_virtual_wall(sweep: Sweep) -> None:
    extra = (
        "drops: [{name: stairs, rect: [2.3, 0, 3, 1.2]}]\n"
        "virtual_walls: [{from: [0.8, 0], to: [0.8, 2.5]}]"
    )
    result = sweep("cover: {}", MIDDLE, extra, seed=3, timeout_s=600.0)
    assert result.outcome == "success", result.reason
    assert not result.fell
    assert result.coverage is not None and result.coverage.overall >= 0.85
    assert min(x for x, _ in result.trajectory) > 0.8  # never past the beam


@pytest.mark.parametrize("odometry_error", [0.0, 0.02])
def test_cover_makes_a_second_pass_when_asked_and_sweeps_no_less(
    sweep: Sweep, odometry_error: float
) -> None:
    """``passes: 2``: when its map says the floor is done it sweeps again on a map drawn
    afresh, then ends; the floor it swept is the first pass's and more. In this room (seed
    3) one pass swept 97.3 % in 165 s (97.0 % in 207 s with 2 % encoder error), two 98.1 %
    in 323 s (98.6 % in 379 s)."""
    # the one pass of test_cover_sweeps_a_room_to_its_edges_and_ends and of
    # test_cover_holds_up_with_the_encoders_error (the same episode, run once: its 600 s
    # limit is far beyond the pass's 207 s, and its success is asserted below)
    once = sweep("cover: {}", MIDDLE, seed=3, timeout_s=600.0, odometry_error=odometry_error)
    twice = sweep(
        "cover: {passes: 2}", MIDDLE, seed=3, timeout_s=900.0, odometry_error=odometry_error
    )
    assert once.outcome == twice.outcome == "success", (once.reason, twice.reason)
    assert once.coverage is not None and twice.coverage is not None
    assert twice.coverage.overall >= once.coverage.overall
    assert twice.coverage.cleaning_s > 1.5 * once.coverage.cleaning_s  # it swept again
    assert twice.coverage.longest_idle_s < 60.0
    assert twice.violations == 0 and not twice.fell


def test_the_edge_does_not_chatter_its_wheels(sweep_spec: SweepSpec) -> None:
    """Along a wall the edge flipped between a turn in place and a hard right every 15-45 ms
    (the centre light-bumper signal hovering at its one threshold): 438 wheel reversals in
    the first minute in this room, 395 of them within 0.1 s of the same wheel's previous
    one. Each reverses a real robot's wheel motor. Now a steering decision holds; what
    reverses a wheel is a manoeuvre (a bump's back-off and turn, a turn in place)."""
    result, reversals = count_reversals(sweep_spec("cover: {}", MIDDLE, seed=3, timeout_s=60.0))
    assert result.coverage is not None and result.coverage.overall >= 0.3  # it swept
    assert reversals.chatter(within_s=0.1) == 0, reversals.events
    assert reversals.per_minute < 80.0


def test_cover_holds_up_with_the_encoders_error(sweep: Sweep) -> None:
    result = sweep("cover: {}", MIDDLE, seed=3, timeout_s=600.0, odometry_error=0.02)
    assert result.coverage is not None and result.coverage.overall >= 0.85
    assert result.outcome in ("success", "timeout"), result.reason
    assert not math.isnan(result.coverage.overall)


def _frame(robot: StubRobot, counts: int, mode: OIMode = OIMode.SAFE, cliff: int = 0) -> None:
    """A frame with both encoders at ``counts`` (straight ahead), ``cliff`` on the front left."""
    values = dict.fromkeys((*driving.BLOCKED_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS), 0)
    values.update({43: counts % 65536, 44: counts % 65536, 35: int(mode), 10: cliff})
    robot.set_frame(values)


def test_cover_started_again_in_a_run_goes_on_with_its_map_and_pose(
    make: Make, robot: StubRobot
) -> None:
    """The firmware's drop to Passive at a cliff (Safe mode) fails ``cover`` at once; the
    mission's ``retry`` starts it again. It goes on with the map (it swept the floor anew, and
    ended as if done on floor it had cleaned, before session 25) and its own pose, the move
    meanwhile added, and its plan: the drive the firmware stopped meets the cliff and backs
    off, as it does in Full (a new decision drove into the same cliff, again and again). A new
    run's ``setup`` starts afresh."""
    cover = make(Cover)
    counts = 0
    _frame(robot, counts)
    for _ in range(150):  # about 1.3 m straight ahead
        counts += 20
        _frame(robot, counts)
        cover.tick_once()
    for _ in range(80):  # the firmware stopped at a drop: Passive, for more than a second
        _frame(robot, counts, OIMode.PASSIVE, cliff=1)
        cover.tick_once()
        if cover.status is not Status.RUNNING:
            break
    assert cover.status is Status.FAILURE
    swept = cover._map.swept
    before = py_trees.blackboard.Blackboard.storage[coverage_map.MAP_KEY].pose
    counts -= 100  # the robot was pushed back 14 cm meanwhile
    _frame(robot, counts, cliff=1)
    cover.tick_once()  # started again (the mission's retry), in Safe
    bearings = py_trees.blackboard.Blackboard.storage[coverage_map.MAP_KEY]
    assert cover._map is bearings.map and bearings.map.swept >= swept
    assert abs(bearings.pose.x_mm - (before.x_mm - 100 * 72.0 * math.pi / 508.8)) < 1.0
    assert cover._phase == "back"  # the drive that met the cliff backs off, as in Full
    while cover._phase == "back":  # 6 cm back, off the edge
        counts -= 8
        _frame(robot, counts)
        cover.tick_once()
    # the seek's own end, as in Full: turn the drop onto the right (75 deg left), then an
    # edge along it (a new decision drove straight at the drop again, for minutes)
    assert cover._phase == "turn" and cover._plan == [cover._edge]
    assert abs(cover._heading - (bearings.pose.theta_rad + math.radians(75.0))) < 0.02
    ahead = [bearings.map.cell(before.x_mm + d, before.y_mm) for d in range(150, 320, 10)]
    assert any(c is not None and bearings.map.cells[c] & BLOCKED for c in ahead)  # mapped
    cover.setup(robot=robot)  # the next run
    assert coverage_map.MAP_KEY not in py_trees.blackboard.Blackboard.storage


def test_cover_fails_at_once_at_the_firmwares_cliff_stop_and_waits_otherwise(
    make: Make, robot: StubRobot
) -> None:
    """At a cliff the firmware stops the wheels and drops to Passive; ``cover`` has mapped it
    and, started again, backs off it, so it fails in that tick: it waited a second each time
    (about 21 times a 20-minute apartment run, by the stairs), which nothing in the mission
    could use. Out of Safe with no cliff showing (the charger, say) it still waits the
    grace for something to bring the robot back."""
    counts = 0
    for cliff, ticks in ((1, 1), (0, round(Cover.PASSIVE_GRACE_S / 0.015) + 1)):
        cover = make(Cover)
        _frame(robot, counts)
        for _ in range(20):  # driving ahead
            counts += 20
            _frame(robot, counts)
            cover.tick_once()
        statuses = []
        for _ in range(ticks):
            _frame(robot, counts, OIMode.PASSIVE, cliff=cliff)
            cover.tick_once()
            statuses.append(cover.status)
        assert statuses[-1] is Status.FAILURE, (cliff, statuses)
        assert Status.FAILURE not in statuses[:-1], cliff
        if cliff:
            assert "left Safe/Full mode" in cover.feedback_message


def _two_parts(fmap: FloorMap, wall: int) -> int:
    """Two swept parts of one floor (x -1..0.9 m and 1.1..2 m, y -1..1 m) with a line of
    blocked cells at x 1 m between them (``wall``: the cell bits besides BLOCKED there),
    closed all round but for open floor past x 2 m; the robot's cell, in the first part."""
    for y in range(-10, 11):
        for x in range(-10, 21):
            cell = fmap.cell(x * CELL_MM + 50, y * CELL_MM + 50)
            assert cell is not None
            fmap.cells[cell] |= SWEPT | (VISITED if y == 0 and x < 10 else 0)  # its way
            fmap.swept += 1
    for y in range(-12, 13):
        fmap.block(-11 * CELL_MM + 50, y * CELL_MM + 50)
        fmap.block(y * CELL_MM + 50, 11 * CELL_MM + 50)
        fmap.block((y + 10) * CELL_MM + 50, 11 * CELL_MM + 50)
        fmap.block(y * CELL_MM + 50, -11 * CELL_MM + 50)
        fmap.block((y + 10) * CELL_MM + 50, -11 * CELL_MM + 50)
    for y in range(-10, 11):
        fmap.block(10 * CELL_MM + 50, y * CELL_MM + 50)
        cell = fmap.cell(10 * CELL_MM + 50, y * CELL_MM + 50)
        assert cell is not None
        fmap.cells[cell] |= wall
    start = fmap.cell(50.0, 50.0)
    assert start is not None
    return start


def test_a_ghost_wall_across_floor_it_drove_is_crossed_to_the_frontier_past_it() -> None:
    """With the encoders' error its map draws walls again a little off, across floor it
    drove; cut in parts so, the part it stood in had no frontier and the floor was done,
    the apartment's bedroom never entered (seed 2, 1.5 % error: 141 frontier cells left
    elsewhere on its map). A blocked cell its centre has been on is no wall: past it the
    frontier is found, over floor it knows; a wall it has not crossed, or a drop, is not
    crossed."""
    fmap = FloorMap()
    start = _two_parts(fmap, wall=VISITED)
    assert fmap.frontier(start) is None and fmap.frontier(start, through_near=True) is None
    path = fmap.frontier(start, through_near=True, through_ghosts=True)
    assert path is not None and fmap.centre(path[-1])[0] > 2000.0  # the open floor's side
    for wall in (0, VISITED | DROP):
        fmap = FloorMap()
        start = _two_parts(fmap, wall=wall)
        assert fmap.frontier(start, through_near=True, through_ghosts=True) is None, wall


def test_a_large_map_with_no_frontier_looks_past_its_ghost_walls_before_it_is_done() -> None:
    """``NoFrontier.path_out``: on a map closed on more than 6 m² (no escape across the
    unknown: a drifted room's ways out led behind its walls), the frontier across the ghost
    walls; the floor is done only when there is none."""
    fmap = FloorMap()
    start = _two_parts(fmap, wall=VISITED)
    assert fmap.swept >= coverage_map._ISLAND_CELLS
    no_frontier = coverage_map.NoFrontier()
    path = no_frontier.path_out(fmap, start)
    assert path is not None and fmap.centre(path[-1])[0] > 2000.0
    fmap = FloorMap()
    start = _two_parts(fmap, wall=0)  # a wall it never crossed: done
    assert coverage_map.NoFrontier().path_out(fmap, start) is None
    fmap = FloorMap()
    start = _two_parts(fmap, wall=VISITED)
    fmap.passes = 2  # a later pass: the cells it has been on are the first pass's, drifted
    assert coverage_map.NoFrontier().path_out(fmap, start) is None


def test_the_floor_done_says_the_floor_its_map_shows_it_found_no_way_to() -> None:
    """Nothing said a room was never reached: the run ended a success, "floor done". What
    the robot knows is its map's frontier left over: said when it is a metre or more (0
    at the end of a living-room start with exact encoders), with where the nearest of it
    is (from where it stopped, and from where it started, as an owner paces it) and why
    no way reached it. It guessed "(a door its map closed?)": a dining room's owner, whose
    floor lay past chair legs, had no door to look for."""
    fmap = FloorMap()
    _two_parts(fmap, wall=0)
    assert fmap.unreached() == 19  # the open side's, x 2 m, y -0.9..0.9 m (clear of walls)
    no_frontier = coverage_map.NoFrontier()
    start = fmap.cell(-500.0, -300.0)
    assert no_frontier.path_out(fmap, start) is None  # a wall it never crossed
    left = fmap.left_unreached(-500.0, -300.0, no_frontier.why)
    assert left == (
        "; its map shows unswept floor along 1.9 m of the floor it swept that it found no "
        "way to, the nearest 2.6 m from where it stopped (about 2.0 m ahead and 0.3 m to "
        "the right of where it started): no way over floor it swept or drove leads there"
    )
    assert fmap.floor_done(left).startswith("floor done: ")
    for y in range(-12, 13):  # closed all round: nothing to say
        fmap.block(21 * CELL_MM + 50, y * CELL_MM + 50)
    assert fmap.unreached() == 0 and fmap.left_unreached() == ""


def test_the_floor_done_after_ways_out_that_found_nothing_says_what_they_bumped() -> None:
    """Three ways out in a row that found next to no floor make the floor done; among
    chairs each bumped a leg its map did not have a few centimetres on (chairs-apart.yaml,
    seed 12: 20.7 % of the room), and the warning guessed a door. It says the tries, and
    how many bumped into something on their way."""
    fmap = FloorMap()
    start = _two_parts(fmap, wall=VISITED)  # a way out across its ghost wall, every time
    no_frontier = coverage_map.NoFrontier()
    assert no_frontier.path_out(fmap, start) is not None  # found floor: not a try that failed
    for bumped in (True, True, False):
        if bumped:
            no_frontier.bumped()
        path = no_frontier.path_out(fmap, start)
    assert path is None
    assert no_frontier.why == (
        "its last 3 ways out toward open floor found next to none, 2 of them bumping into "
        "something not on its map on the way (legs closer together than the robot's 34 cm?)"
    )


def _wheels_frame(robot: StubRobot, left: int, right: int, signals: tuple[int, ...]) -> None:
    """A frame with the encoders at ``left``, ``right`` and the light bumper's ``signals``."""
    values = dict.fromkeys((*driving.BLOCKED_PACKETS, *IR_PACKETS), 0)
    values.update(zip(LIGHT_BUMP_SIGNAL_PACKETS, signals, strict=True))
    values.update({43: left % 65536, 44: right % 65536, 35: int(OIMode.SAFE)})
    robot.set_frame(values)


def _edging(make: Make, robot: StubRobot) -> Cover:
    cover = make(Cover)
    _wheels_frame(robot, 0, 0, (0,) * 6)
    cover.tick_once()  # started: ahead to a wall
    cover._plan.clear()
    cover._edge()  # along the wall on its right, from here
    return cover


def test_an_edge_whose_wheels_are_held_ends_and_backs_off(make: Make, robot: StubRobot) -> None:
    """An edge ended by the floor it found or after ``edge_time`` (3 min): one whose wheels
    were driven and held (living room seed 22, exact encoders: its side against the plant,
    no bump) stood 180 s. Now, held for ``STALL_S``, it backs off as from a bump and the
    edge ends; one that moves goes on."""
    wall = (0, 0, 0, 0, 0, 3400)  # a wall on its right, at the edge's distance or so
    cover = _edging(make, robot)
    counts = 0
    for _ in range(round(driving.STALL_S / 0.015) + 20):  # driving along it
        counts += 15
        _wheels_frame(robot, counts, counts, wall)
        cover.tick_once()
    assert cover._phase == "edge"
    phases = []
    for _ in range(round(driving.STALL_S / 0.015) + 20):  # the wheels held where it is
        _wheels_frame(robot, counts, counts, wall)
        cover.tick_once()
        phases.append(cover._phase)
    assert phases[0] == "edge" and phases[-1] == "back", phases[-1]
    wheels = robot.flush()[-1]
    assert wheels.opcode == 145 and wheels.args[0] < 0  # backing


def test_an_edge_that_turns_a_whole_turn_in_place_ends(make: Make, robot: StubRobot) -> None:
    """Among the stairs' drops on its drifted map (apartment, seed 0, 1.5 % error), each a
    wall to an edge, the edge turned in place whichever way it faced: two edges of 180 s,
    376 s without new floor. An edge that has turned a whole turn without moving ends."""
    cover = _edging(make, robot)
    fmap = cover._map
    for k in range(12):  # a ring of drops 25 cm round it, joined into edges
        a = k * math.tau / 12
        fmap.drops.mark(250.0 * math.cos(a), 250.0 * math.sin(a), a + math.pi / 2, 100.0 * k)
    ended = []
    cover._edge_done = lambda: ended.append(robot.snapshot.time)  # type: ignore[method-assign]
    left = right = 0
    for _ in range(round(10.0 / 0.015)):
        left, right = left - 10, right + 10  # turning left in place, as its steering asks
        _wheels_frame(robot, left, right, (0,) * 6)
        cover.tick_once()
        if ended:
            break
    # a whole turn: about 740 mm a wheel, 1,660 counts, 166 ticks (2.5 s)
    assert ended and ended[0] < 4.0, ended


def test_a_leg_no_move_clear_of_the_drop_can_start_either_is_not_planned_again(
    make: Make, robot: StubRobot
) -> None:
    """A leg a known drop kept from starting turns the robot away from the drop and drives
    15 cm (session 37); where a drop, or a guess of one, ends that move before it starts
    too, the same path was planned again, leg, turn, no move, for 94 s (living room seed
    24, exact encoders, by the stairs). Now that leg's cell is not taken again; a move
    clear that went is no reason to."""
    for achieved, why, avoided in ((0.0, "drop", True), (150.0, "limit", False)):
        cover = _edging(make, robot)
        cell = cover._map.cell(400.0, 0.0)
        assert cell is not None
        decided: list[bool] = []
        cover._goto_cell = cell
        cover._kind, cover._why, cover._achieved = "clear", why, achieved
        cover._plan = [partial(decided.append, True)]  # then it decides again
        cover._ended()
        assert (cell in cover._map.avoid) is avoided and decided == [True], why


def test_a_leg_a_known_drop_keeps_from_starting_is_not_planned_again(
    make: Make, robot: StubRobot
) -> None:
    """After the move clear of the drop, the path planned again led back to the same leg,
    which the drop kept from starting again: leg, turn, 15 cm, leg, for 514 s (the
    apartment, seed 9, 1.5 % error, session 38). A leg that a known drop ends before it
    starts is not planned again; one that went some way and ended short of it is."""
    for achieved, avoided in ((0.0, True), (78.0, False)):
        cover = _edging(make, robot)
        cell = cover._map.cell(400.0, 0.0)
        assert cell is not None
        decided: list[bool] = []
        cover._goto_cell = cell
        cover._kind, cover._why, cover._achieved = "goto", "drop", achieved
        cover._plan = [partial(decided.append, True)]  # no drop near on its map: on
        cover._ended()
        assert (cell in cover._map.avoid) is avoided and decided == [True], achieved
