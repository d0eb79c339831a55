"""``cover``'s known drops (roomba_bt/behaviours/drops.py): marked where the cliff sensors saw
them, joined along an edge, seen by the edge as a wall, and the end of a move toward one."""

from __future__ import annotations

import math

from roomba_bt.behaviours import driving
from roomba_bt.behaviours.coverage_map import BLOCKED, Bearings, FloorMap
from roomba_bt.behaviours.drops import DROP, GUESS_MM, KnownDrops
from roomba_bt.oi.frames import IR_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS, SensorFrame, layout_for
from roomba_bt.oi.profiles import CLIFF_SENSOR_RADIUS_MM
from roomba_bt.robot.interface import Odometry

#: cliff packets: left, front left, front right, right
LEFT, FRONT_LEFT, FRONT_RIGHT, RIGHT = 9, 10, 11, 12


def _frame(**cliffs: int) -> SensorFrame:
    """A frame of the packets ``cover`` reads, with the cliff packets given (by name)."""
    by_name = {"left": LEFT, "front_left": FRONT_LEFT, "front_right": FRONT_RIGHT,
               "right": RIGHT}  # fmt: skip
    values = dict.fromkeys((*driving.BLOCKED_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS), 0)
    values.update({by_name[name]: value for name, value in cliffs.items()})
    layout = layout_for(tuple(sorted(values)), with_ids=False)
    return layout.decode(layout.pack(values))


def _bits(fmap: FloorMap, x: float, y: float) -> int:
    cell = fmap.cell(x, y)
    assert cell is not None
    return fmap.cells[cell]


def test_a_cliff_is_marked_under_the_sensor_that_saw_it_not_across_the_front() -> None:
    """The right cliff sensor alone sees a drop (a staircase's edge met at a glancing angle):
    the cell under it is a drop, blocked. The floor ahead and to the left is not: until
    session 27 every cliff blocked three cells 23 cm ahead of the body, 29 deg either way,
    whichever sensor saw it."""
    fmap = FloorMap()
    bearings = Bearings(fmap, Odometry())
    bearings.observe(_frame(right=1))
    reach = CLIFF_SENSOR_RADIUS_MM + 20.0
    under = (reach * math.cos(math.radians(-60.0)), reach * math.sin(math.radians(-60.0)))
    assert _bits(fmap, *under) & (DROP | BLOCKED) == DROP | BLOCKED
    ahead_left = (230.0 * math.cos(0.5), 230.0 * math.sin(0.5))
    assert not _bits(fmap, *ahead_left) & BLOCKED  # floor: the old mark blocked it
    assert fmap.drops.cells == 1


def test_drops_met_along_one_edge_are_joined_and_guessed_on() -> None:
    """Two drops 30 cm apart are one straight edge: the cells between are drops too; where
    it would go on (GUESS_MM) ends a lane toward it but blocks no path."""
    fmap = FloorMap()
    drops = fmap.drops
    drops.mark(1000.0, 0.0, math.pi / 2, 0.0)
    drops.mark(1000.0, 300.0, math.pi / 2, 800.0)
    for y in range(0, 301, 50):
        assert _bits(fmap, 1000.0, float(y)) & DROP, y
    beyond = 300.0 + GUESS_MM - 60.0
    assert not _bits(fmap, 1000.0, beyond) & BLOCKED  # a guess: no path is kept off it
    facing = Odometry(x_mm=1000.0 - 160.0, y_mm=beyond, theta_rad=0.0)
    assert drops.ahead(facing, 0.0)  # but a lane toward it ends there
    assert not drops.ahead(facing, 0.0, guessed=False)
    far = Odometry(x_mm=1000.0 - 160.0, y_mm=300.0 + GUESS_MM + 300.0, theta_rad=0.0)
    assert not drops.ahead(far, 0.0)


def test_drops_far_apart_or_met_facing_other_ways_are_not_joined() -> None:
    """A robot that turned a corner between two drops would cut the floor's corner off:
    drops farther apart than JOIN_MM are joined only when met facing the same way along one
    stretch of driving."""
    fmap = FloorMap()
    drops = fmap.drops
    drops.mark(0.0, 0.0, 0.0, 0.0)
    drops.mark(700.0, 700.0, math.pi / 2, 1000.0)  # 1 m away, a quarter turn later
    assert not _bits(fmap, 350.0, 350.0) & DROP
    drops.mark(0.0, 1000.0, 0.0, 1500.0)  # 1 m from the first, the same way, 1.5 m on
    assert _bits(fmap, 0.0, 500.0) & DROP


def test_an_edge_sees_a_known_drop_on_its_right_as_a_wall() -> None:
    """Over a drop the light bumper sees nothing: the edge curved right into the staircase
    every 20 cm. The map's drop gives the right rays the signal a wall would, WALL_MM
    nearer; nothing is seen once it is out of the rays' reach."""
    fmap = FloorMap()
    drops: KnownDrops = fmap.drops
    drops.mark(0.0, -250.0, 0.0, 0.0)
    drops.mark(600.0, -250.0, 0.0, 500.0)  # a drop's edge 25 cm to the right, along x
    beside = drops.signals(Odometry(x_mm=300.0, y_mm=0.0, theta_rad=0.0))
    assert beside[5] > 0  # the right ray
    assert beside[:4] == (0, 0, 0, 0)  # nothing ahead or left
    away = drops.signals(Odometry(x_mm=300.0, y_mm=400.0, theta_rad=0.0))
    assert away == (0, 0, 0, 0, 0, 0)
    facing = drops.signals(Odometry(x_mm=300.0, y_mm=0.0, theta_rad=-math.pi / 2))
    assert facing[2] > 0 and facing[3] > 0  # head-on: ahead
