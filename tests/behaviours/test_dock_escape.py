"""The dock search's trap detection and way out (:mod:`roomba_bt.behaviours.docking.escape`),
on made-up trails: the whole search in the dining room is pinned in
``tests/missions/test_shipped.py::test_dock_from_under_a_table_ringed_by_chairs``."""

from __future__ import annotations

import math

import pytest

from roomba_bt.behaviours.docking.escape import (
    CLEAR_OF_TRAP_MM,
    CRUMB_MM,
    THROUGH_MM,
    TRAPPED_HAZARDS,
    TRAPPED_S,
    WAY_BUMPS,
    Point,
    Trail,
    WayOut,
    plan_way_out,
    straightened,
)
from roomba_bt.robot.interface import Odometry


def walk(trail: Trail, points: list[Point], start_s: float = 0.0) -> Odometry:
    """A crumb at each point, one a second, as the search's ticks leave them; the odometry
    at the last point."""
    for second, (x, y) in enumerate(points):
        trail.crumbs.append((x, y, start_s + second))
    x, y = points[-1]
    return Odometry(x_mm=x, y_mm=y)


def hazards(trail: Trail, odo: Odometry, times: list[float]) -> list[bool]:
    return [trail.met_hazard(odo, now) for now in times]


def test_a_long_stay_with_many_hazards_is_a_trap() -> None:
    trail = Trail()
    odo = walk(trail, [(10.0 * (i % 5), 0.0) for i in range(40)])  # to and fro within 5 cm
    found = hazards(trail, odo, [39.0 - i for i in range(TRAPPED_HAZARDS, 0, -1)] + [39.0])
    assert found == [False] * (TRAPPED_HAZARDS - 1) + [True, True]
    assert 15.0 < trail.centre[0] < 25.0 and trail.centre[1] == 0.0  # the stay's middle


def test_few_hazards_a_short_stay_or_a_restart_is_no_trap() -> None:
    trail = Trail()
    odo = walk(trail, [(10.0 * (i % 5), 0.0) for i in range(40)])
    spread = [39.0 - 4.0 * i for i in range(TRAPPED_HAZARDS, 0, -1)]  # over 40 s
    assert not any(hazards(trail, odo, spread))  # ten, but not within TRAPPED_S
    young = Trail()
    odo = walk(young, [(0.0, 0.0)] * int(TRAPPED_S - 5))  # the trail is younger than a stay
    assert not any(hazards(young, odo, [TRAPPED_S - 6.0] * (TRAPPED_HAZARDS + 1)))
    restarted = Trail()
    odo = walk(restarted, [(0.0, 0.0)] * 40)
    hazards(restarted, odo, [39.0] * (TRAPPED_HAZARDS - 1))
    restarted.restart()
    assert not restarted.met_hazard(odo, 39.0)


def test_the_way_kept_before_the_search_leads_out_but_makes_no_stay() -> None:
    """The search's trail begins with the way ``cover`` drove (``escape.Way``): crumbs from
    minutes of cleaning, the odometry centimetres off since. Counted as a stay, they made
    it trapped 20 s into the search, and each way back along them met a leg
    (chairs-apart.yaml, seed 5: not home in the search's 10 minutes). Only its own crumbs
    make a stay; the way kept before still leads out."""
    trail = Trail()
    odo = walk(trail, [(10.0 * (i % 5), 0.0) for i in range(40)])  # cover's, then its own
    trail.own_from = 30.0
    assert not any(hazards(trail, odo, [39.0] * (TRAPPED_HAZARDS + 1)))  # its own: 9 s
    walk(trail, [(10.0 * (i % 5), 0.0) for i in range(31)], start_s=40.0)
    assert hazards(trail, odo, [70.0] * TRAPPED_HAZARDS)[-1]  # 31 s of its own: a stay


def test_a_stay_is_within_the_circle_all_the_time() -> None:
    """Ten hazards within 30 s, but ten seconds ago the robot was 40 cm away: no trap."""
    trail = Trail()
    points = [(0.0, 0.0)] * 20 + [(400.0, 0.0)] + [(0.0, 0.0)] * 10
    odo = walk(trail, points, start_s=0.0)
    assert not any(hazards(trail, odo, [30.0] * TRAPPED_HAZARDS))


def test_the_way_back_leaves_out_the_loops_and_ends_clear_of_the_trap() -> None:
    """In along y from 1 m away, a loop about the trap's centre, then the way back: straight
    down the line it came in by."""
    trail = Trail()
    way_in = [(0.0, -1000.0 + CRUMB_MM * i) for i in range(51)]
    loop = [(100.0 * math.sin(a / 10), 100.0 * (1 - math.cos(a / 10))) for a in range(63)]
    odo = walk(trail, way_in + loop)
    assert trail.centre == (0.0, 0.0)  # the trap's centre at the origin
    back = trail.way_back(odo)
    assert math.dist(back[0], (odo.x_mm, odo.y_mm)) < 60.0  # where it is, or a crumb by it
    assert all(abs(x) < 1e-6 for x, _ in back)  # the loop is left out
    assert back[-1][1] <= -600.0  # clear of the trap
    assert len(back) <= 3  # the straight line kept as its ends


def test_the_way_out_goes_on_through_the_trap_and_the_way_back_is_kept_for_a_shut_line() -> None:
    back = [(0.0, 0.0), (0.0, -100.0), (0.0, -400.0), (-300.0, -700.0)]
    way, retreat = plan_way_out(back, (0.0, 0.0))
    assert way[-2:] == [(0.0, -100.0), (0.0, 0.0)]  # back to the line it came in by first
    assert way[0] == (0.0, THROUGH_MM - 400.0)  # then on along it, through the trap
    assert retreat == [(-300.0, -700.0), (0.0, -400.0)]  # else out the way it came in


def test_straightened_keeps_the_corners() -> None:
    line = [(float(x), 0.0) for x in range(0, 101, 10)] + [(100.0, float(y)) for y in (10, 20)]
    assert straightened(line) == [(0.0, 0.0), (100.0, 0.0), (100.0, 20.0)]


def test_the_way_out_turns_to_its_points_and_a_shut_line_through_sends_it_back() -> None:
    """In along y to the trap's centre, then 10 cm to the side: back to the line, then on
    along it; a bump on the line through takes the way back out instead; clear of the trap
    there is nothing more to do."""
    trail = Trail()
    walk(trail, [(0.0, -1000.0 + CRUMB_MM * i) for i in range(51)] + [(100.0, 0.0)])
    trail.centre = (0.0, 0.0)
    beside = Odometry(x_mm=100.0, theta_rad=math.pi / 2)  # facing +y
    way_out = WayOut(trail, beside)
    assert way_out.turn_to_next(beside) == pytest.approx(math.pi / 2, abs=0.3)  # to -x
    on_the_line = Odometry(theta_rad=math.pi / 2)
    assert way_out.turn_to_next(on_the_line) == pytest.approx(0.0)  # on along +y: through
    assert not way_out.shut()  # the line through is shut: the way back instead
    assert abs(way_out.turn_to_next(on_the_line) or 0.0) == pytest.approx(math.pi)
    assert way_out.turn_to_next(Odometry(y_mm=-CLEAR_OF_TRAP_MM - 1.0)) is None
    assert [way_out.shut() for _ in range(WAY_BUMPS + 1)] == [False] * WAY_BUMPS + [True]
