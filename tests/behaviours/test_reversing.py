"""How far ``cover`` backs up (roomba_bt/behaviours/reversing.py): only over floor it has just
driven, never onto a known drop; and the arc onto the next lane, which backed 18 cm blind
onto the stairs (living room, seed 8, 1.5 % encoder error), looks first."""

from __future__ import annotations

import math

from roomba_bt.behaviours import driving
from roomba_bt.behaviours.coverage_map import SWEPT, VISITED, Cover, FloorMap
from roomba_bt.behaviours.reversing import OWN_MM, Trail
from roomba_bt.robot.interface import Odometry
from roomba_bt.sim.world import Pose

from .sim_tree import run_after_mode


def _driven(trail: Trail, heading: float, length: float) -> Odometry:
    """``trail`` after a straight drive of ``length`` mm from the origin along ``heading``:
    the pose at its end."""
    pose = Odometry(theta_rad=heading)
    for k in range(int(length // 5) + 1):
        d = 5.0 * k
        pose = pose._replace(x_mm=d * math.cos(heading), y_mm=d * math.sin(heading))
        trail.add(pose)
    return pose


def test_it_backs_over_the_line_it_drove_and_no_further() -> None:
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 300.0)
    assert trail.reversible(pose, 180.0, fmap.drops) == 180.0
    assert trail.reversible(pose, 500.0, fmap.drops) == 300.0  # the line began there


def test_after_a_turn_in_place_the_floor_behind_is_floor_it_never_drove() -> None:
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 300.0)
    turned = pose._replace(theta_rad=math.pi / 2)  # a turn in place adds no pose
    assert trail.reversible(turned, 180.0, fmap.drops) == 0.0
    assert trail.reversible(pose._replace(theta_rad=math.radians(10.0)), 60.0, fmap.drops) == 60.0
    assert trail.reversible(Odometry(), 30.0, fmap.drops) == 0.0  # nothing driven yet


def test_off_a_hazard_it_backs_under_its_own_body_unless_a_drop_is_known_there() -> None:
    """In Safe mode a cliff showing stops every move but straight back: a back-off off a
    hazard may go OWN_MM with no trail (the wheels stay under the body), never toward a
    known drop."""
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 300.0)._replace(theta_rad=math.pi / 2)  # turned in place
    assert trail.reversible(pose, 180.0, fmap.drops, own=OWN_MM) == OWN_MM
    assert trail.reversible(pose, 30.0, fmap.drops, own=OWN_MM) == 30.0
    fmap.drops.mark(pose.x_mm, pose.y_mm - 180.0, 0.0, 0.0)  # 18 cm behind it now
    assert trail.reversible(pose, 60.0, fmap.drops, own=OWN_MM) == 0.0


def test_a_drop_beside_it_keeps_no_back_off_from_starting() -> None:
    """Along an edge that follows a drop (on the right, 24 cm from the centre), backing
    straight keeps the body off it: the look behind is the body's back half."""
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 300.0)
    fmap.drops.mark(0.0, -240.0, 0.0, 0.0)
    fmap.drops.mark(400.0, -240.0, 0.0, 400.0)
    assert trail.reversible(pose, 60.0, fmap.drops) == 60.0


def test_never_onto_a_known_drop_even_over_floor_it_drove() -> None:
    """With the encoders' error a drop may lie on the map over floor the trail has: the drop
    wins."""
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 400.0)
    fmap.drops.mark(100.0, 0.0, 0.0, 0.0)  # 30 cm behind the centre, on the line driven
    allowed = trail.reversible(pose, 180.0, fmap.drops)
    assert allowed < 180.0
    # the body and the margin stay short of it: 300 - 170 (the body) - 20 (the margin)
    assert allowed <= 300.0 - 170.0 - 20.0 + 10.0


def test_a_heading_re_anchored_on_a_wall_turns_the_trail_with_it() -> None:
    fmap = FloorMap()
    trail = Trail()
    pose = _driven(trail, 0.0, 300.0)
    trail.turned(-0.3)
    assert trail.reversible(pose._replace(theta_rad=-0.3), 60.0, fmap.drops) == 60.0
    assert trail.reversible(pose, 60.0, fmap.drops) == 0.0


#: A 3 m x 2.5 m room whose south 60 cm are stairs.
STAIRS_BEHIND = """
name: stairs-behind
rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]
drops: [{name: stairs, rect: [0, 0, 3, 0.6]}]
"""


class _LaneAtADrop(Cover):
    """``cover`` where seed 8 fell: it has just turned in place (it has driven nothing
    facing this way) and its lane ends where it begins, at a drop its drifted map holds 20
    cm ahead; the next lane is to its right, 32 cm over (an arc of 16 cm radius)."""

    def start(self) -> None:
        super().start()
        pose = self._pose
        heading = pose.theta_rad
        ahead = (pose.x_mm + 200.0 * math.cos(heading), pose.y_mm + 200.0 * math.sin(heading))
        self._map.drops.mark(*ahead, heading, 0.0)
        self._plan.clear()
        self._advance = driving.wrap(heading - math.pi / 2)
        self._lane(heading)


def test_the_arc_onto_the_next_lane_does_not_back_blind_onto_the_stairs() -> None:
    """Facing away from the stairs, its wheels 15 cm from their edge (the back of its body
    over it, as a robot that backed off a wall may stand at a step), a lane that ends at
    once leaves the arc no room ahead. It backed 18 cm to make it, blind (a Create 2 has no
    sensor behind the wheels): a wheel dropped down the stairs. Now the floor behind is
    floor it has not driven, so it turns in place, moves over and turns: no wheel drop, and
    it goes on."""
    start = Pose(1500.0, 600.0 + 150.0, math.pi / 2)
    cover = _LaneAtADrop("cover", {})
    simulator = run_after_mode(STAIRS_BEHIND, start, "full", cover, "lane-at-a-drop", 20.0)
    assert not simulator.fallen
    lowest = min(point.y for point in simulator.trace)
    assert lowest > 600.0 + 100.0, lowest  # its wheels never neared the edge
    assert max(point.x for point in simulator.trace) > start.x + 250.0  # over to its right


class _PathAlongADrop(Cover):
    """``cover`` where living room seed 2 (1.5 % encoder error) stood 164 s: 15 cm from a
    drop on its map (its right), the floor it has swept a strip along the drop, unswept
    floor only at the strip's far end, 1 m ahead. Every leg of the path there runs along
    the drop, inside a cliff sensor's look-ahead of it (17 cm to the side)."""

    def start(self) -> None:
        super().start()
        fmap = self._map
        for k, x in enumerate(range(-300, 2400, 300)):  # the drop: one straight line
            fmap.drops.mark(float(x), -150.0, 0.0, 300.0 * k)
        for x in range(-250, 1000, 50):  # the strip it swept and drove (10 cm cells)
            for y in range(-50, 500, 50):
                cell = fmap.cell(float(x), float(y))
                assert cell is not None
                fmap.cells[cell] |= SWEPT | VISITED
            fmap.block(float(x), 550.0)  # a wall along its left
        for y in range(-50, 500, 50):
            fmap.block(-350.0, float(y))
        self._plan.clear()
        self._decide()
        self.unstarted = 0

    def _ended(self) -> None:
        if self._why == "drop" and self._achieved < 20.0:
            self.unstarted += 1  # a line a known drop ended before it began
        super()._ended()


def test_a_path_along_a_known_drop_first_gets_clear_of_it() -> None:
    """With back-offs only over floor just driven (session 36) the robot is left nearer a
    drop: every leg of the path along it ended in the tick it began, the next leg too, and
    the same floor was planned again (about 2,400 moves of no length in 164 s). Now it turns
    straight away from the drop, drives 15 cm and plans again: it is along the strip to the
    unswept floor within seconds, its wheels never near the real edge."""
    start = Pose(400.0, 600.0 + 190.0, 0.0)  # the real edge 19 cm to its right, the map's 15
    cover = _PathAlongADrop("cover", {})
    simulator = run_after_mode(STAIRS_BEHIND, start, "full", cover, "path-along-a-drop", 15.0)
    assert not simulator.fallen
    assert min(point.y for point in simulator.trace) > 600.0 + 150.0
    assert max(point.x for point in simulator.trace) > start.x + 900.0  # at the unswept floor
    assert cover.unstarted == 1, cover.unstarted  # the first leg; then clear of the drop
