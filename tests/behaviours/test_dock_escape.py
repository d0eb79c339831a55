"""The dock search's trap detection and way out (:mod:`roomba_bt.behaviours.docking.escape`),
on made-up trails: the whole search in the dining room is pinned in
``tests/missions/test_shipped.py::test_dock_from_under_a_table_ringed_by_chairs``."""

from __future__ import annotations

import math

from roomba_bt.behaviours.docking.escape import (
    CRUMB_MM,
    THROUGH_MM,
    TRAPPED_HAZARDS,
    TRAPPED_S,
    Point,
    Trail,
    plan_way_out,
    straightened,
)
from roomba_bt.robot.interface import Odometry


def walk(trail: Trail, points: list[Point], start_s: float = 0.0) -> Odometry:
    """Drop a crumb at each point, one a second, as the search's ticks would; the odometry
    at the last point."""
    odo = Odometry()
    for second, (x, y) in enumerate(points):
        odo = Odometry(x_mm=x, y_mm=y, path_mm=odo.path_mm + CRUMB_MM)
        trail.drop(odo, start_s + second)
    return odo


def test_a_long_stay_with_many_hazards_is_a_trap_and_a_short_or_quiet_one_is_not() -> None:
    trail = Trail()
    trail.restart(Odometry(), 0.0)
    walk(trail, [(10.0 * (i % 5), 0.0) for i in range(40)])  # to and fro within 5 cm
    assert not any(trail.met_hazard(now=TRAPPED_S - 1.0) for _ in range(TRAPPED_HAZARDS))
    assert trail.met_hazard(now=TRAPPED_S)
    quiet = Trail()
    quiet.restart(Odometry(), 0.0)
    assert not quiet.met_hazard(now=TRAPPED_S * 10)  # one hazard in a long stay: no trap


def test_leaving_the_circle_starts_a_new_stay() -> None:
    trail = Trail()
    trail.restart(Odometry(), 0.0)
    for _ in range(TRAPPED_HAZARDS):
        trail.met_hazard(now=1.0)
    walk(trail, [(0.0, 100.0 * i) for i in range(5)], start_s=TRAPPED_S)  # 40 cm away
    assert trail.anchor == (0.0, 300.0)  # the first crumb past the circle's 25 cm
    assert not trail.met_hazard(now=2 * TRAPPED_S)  # the hazards of the last stay are gone


def test_the_way_back_leaves_out_the_loops_and_ends_clear_of_the_trap() -> None:
    """In along y from 1 m away, a loop about the trap's centre, then the way back: straight
    down the line it came in by."""
    trail = Trail()
    way_in = [(0.0, -1000.0 + CRUMB_MM * i) for i in range(51)]
    loop = [(100.0 * math.sin(a / 10), 100.0 * (1 - math.cos(a / 10))) for a in range(63)]
    odo = walk(trail, way_in + loop)
    trail.restart(Odometry(), 0.0)  # the trap's centre at the origin
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
