"""``cover``'s known drops: where its cliff sensors saw the floor end, kept on its map, and how
it keeps off them afterwards.

Why it matters: in Safe mode (``clean.yaml``'s default) a cliff seen while the robot drives
forward makes the firmware stop the wheels and the brushes and drop to Passive, each time
with the front caster over the edge; ``cover`` fails in that tick and the mission's retry
starts it again (docs/routines.md). Marking only three cells 23 cm ahead of the body at a
cliff and taking them for a bump is not enough: the edge, with no wall on its right along
a staircase (the light bumper sees no surface over a drop), curves right into the drop
again every 20 cm (back 6 cm, 60 deg left, a 24 cm curve to the right, cliff), and again on
every later edge along it; lanes and paths meet it wherever those few cells are not: 12 to
30 falls in a 15-minute clean of the apartment, the first 16 within 90 s of one start.

What it does::

    a cliff sensor sees a drop      a point where the sensor is (packets 9-12, the profile's
                                    CLIFF_SENSOR_ANGLES_DEG, 150 mm out, + 20 mm), its cell
                                    DROP and blocked; it is joined by a straight line to
                                    each drop met within JOIN_MM (or JOIN_ALONG_MM, along
                                    one stretch of driving, facing the same way): one edge,
                                    its cells DROP too; a line of GUESS_FROM_MM or more is
                                    guessed to go on for GUESS_MM (a guess: no cell blocked)
    an edge along a known drop      the light bumper's rays are also read on the lines (in
                                    mm, not cells): a ray reaching one gives the signal a
                                    wall WALL_MM nearer would (:meth:`KnownDrops.signals`),
                                    so the edge follows the drop without touching it; after
                                    a cliff it turns left only until the drop is on its
                                    right and none ahead (:meth:`DropEdge.along`, 15 deg at
                                    least, 60 at most), and within SEARCH_MM of a drop on its
                                    right it drives at SLOW_MM_S
    a lane, a shift, a path's leg,  ends where a line (or a guess; a path's leg: a known one
    a seek, an arc between lanes    only, and its path goes on) is within MARGIN_MM beyond a
                                    cliff sensor or between two; slows to SLOW_MM_S within
                                    SLOW_MM of one

A part of a drop not met yet is met as before (the first edge along the apartment's stairs
meets them every 35 cm instead of every 20); a part met is not met again while odometry
holds (with the encoders' error the map drifts from the floor, and the lines with it).

The cost: a byte read per tick away from a known drop (:attr:`KnownDrops.zone` counts the
cells with a line within ZONE_CELLS of each cell); near one, a few dozen lines a tick.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from roomba_bt.behaviours.edging import FRONT_CLEAR
from roomba_bt.oi.profiles import (
    BODY_RADIUS_MM,
    CLIFF_SENSOR_ANGLES_DEG,
    CLIFF_SENSOR_RADIUS_MM,
    LIGHT_BUMP_ANGLES_DEG,
    LIGHT_BUMP_RANGE_MM,
)

if TYPE_CHECKING:
    from roomba_bt.behaviours.coverage_map import FloorMap
    from roomba_bt.oi.frames import SensorFrame
    from roomba_bt.robot.interface import Odometry

__all__ = ["DROP", "DropEdge", "KnownDrops"]

#: the map's cell bit of a drop (its cells are BLOCKED too)
DROP = 16
#: a drop is marked this far (mm) beyond the sensor that saw it: the floor ended before it
MARK_BEYOND_MM = 20.0
#: two drops met this close (mm) are one straight edge (lanes meet it 15-32 cm apart,
#: minutes apart); and farther, up to JOIN_ALONG_MM, when met within JOIN_PATH_MM of driving
#: facing within JOIN_TURN of the same way (an edge's search meets a drop every metre or so;
#: a robot that turned a corner of the drop between the two would cut the floor's corner off)
JOIN_MM, JOIN_PATH_MM, JOIN_ALONG_MM = 400.0, 3000.0, 1500.0
JOIN_TURN = math.radians(45.0)
#: two drops joined at least this far apart (mm), met facing the same way (lanes toward the
#: drop, one after the other), say where the edge goes on: this far (mm) beyond the newer
#: is a guess (:attr:`KnownDrops.guessed`) that ends moves (the next lane) but blocks no path
GUESS_FROM_MM, GUESS_MM = 150.0, 300.0
#: a straight move ends where the map has a drop this far (mm) beyond a cliff sensor
MARGIN_MM = 50.0
#: ... and slows to SLOW_MM_S (mm/s) where it has one this far beyond
SLOW_MM, SLOW_MM_S = 150.0, 150.0
#: an edge sees a known drop as a wall this much (mm) nearer: it follows it this much
#: farther out than a wall (the side cliff sensor 130 mm to the right of the centre, 90 mm
#: inside the drop's line at the edge's distance; the side brush reaches 35 mm short of it)
WALL_MM = 60.0
#: a point met is a disc this wide (mm, radius) to a ray
POINT_MM = 30.0
#: past a drop's known end, the edge goes on at SLOW_MM_S for this far (mm)
SEARCH_MM = 1500.0
#: the least turn (rad) off a drop met along an edge (:meth:`DropEdge.along`)
ALONG_TURN = math.radians(15.0)
#: the zone: how many cells around a DROP cell a driving robot looks at the map for it
ZONE_CELLS = 4
#: an edge's cells are found every this many mm along it
_RAY_STEP_MM = 15.0
#: the light bumper's rays end this far (mm) from the centre
_RAY_END_MM = BODY_RADIUS_MM + LIGHT_BUMP_RANGE_MM + WALL_MM
_DARK = (0, 0, 0, 0, 0, 0)
#: points recorded closer than this (mm) to the last are the same drop (a cliff shows for
#: several ticks: the robot stops, in Passive, and backs off)
_SAME_MM = 40.0

_CLIFF_ANGLES = tuple(math.radians(a) for a in CLIFF_SENSOR_ANGLES_DEG)
#: where a move looks for a known drop: the cliff sensors' angles and between them
_AHEAD_ANGLES = tuple(math.radians(a) for a in (60.0, 40.0, 20.0, 0.0, -20.0, -40.0, -60.0))
_RAY_ANGLES = tuple(math.radians(a) for a in LIGHT_BUMP_ANGLES_DEG)
#: where a back-off looks for a known drop (:meth:`KnownDrops.behind`), from the heading's
#: opposite: the body's back half, its wheels (90 deg) included
_BEHIND_ANGLES = tuple(math.radians(a) for a in (90.0, 60.0, 30.0, 0.0, -30.0, -60.0, -90.0))
#: ... as far as the body reaches and this much (mm) beyond
BEHIND_MARGIN_MM = 20.0


class KnownDrops:
    """The drops on a :class:`~roomba_bt.behaviours.coverage_map.FloorMap`, kept with it: the
    points where the cliff sensors saw them and the straight lines joining them (exact, in
    mm, for the moves that keep off them: the module's table), and their cells, DROP and
    blocked (for the plans)."""

    def __init__(self, fmap: FloorMap) -> None:
        self._map = fmap
        side = fmap.SIDE
        #: how many cells with a known drop (or a guessed one) lie within ZONE_CELLS of each
        #: cell (0: none near)
        self.zone = bytearray(side * side)
        self._zone_steps = tuple(
            row * side + col
            for row in range(-ZONE_CELLS, ZONE_CELLS + 1)
            for col in range(-ZONE_CELLS, ZONE_CELLS + 1)
        )
        #: the drops met: (x, y, heading, the odometry's path), for the joining
        self._met: list[tuple[float, float, float, float]] = []
        #: the known edges (x0, y0, x1, y1, guessed): a point met is one of length 0; guessed,
        #: where a straight edge would go on (GUESS_MM), for the moves only
        self.edges: list[tuple[float, float, float, float, bool]] = []
        #: the edges through each cell (indices into :attr:`edges`)
        self._edges_in: dict[int, list[int]] = {}
        #: DROP cells marked (a count, for tests and the curious)
        self.cells = 0
        #: the odometry's path (mm) when a cliff sensor last saw a drop
        self.last_met = -math.inf

    def met(self, frame: SensorFrame, pose: Odometry) -> None:
        """This tick's cliff sensors from ``pose``: each that sees a drop marks it there."""
        sensors = (frame.cliff_left, frame.cliff_front_left, frame.cliff_front_right,
                   frame.cliff_right)  # fmt: skip
        x, y, theta = pose.x_mm, pose.y_mm, pose.theta_rad
        reach = CLIFF_SENSOR_RADIUS_MM + MARK_BEYOND_MM
        self.last_met = pose.path_mm
        for angle, seen in zip(_CLIFF_ANGLES, sensors, strict=True):
            if seen:
                a = theta + angle
                self.mark(x + reach * math.cos(a), y + reach * math.sin(a), theta, pose.path_mm)

    def mark(self, x: float, y: float, heading: float, path_mm: float) -> None:
        """A drop at (x, y), met facing ``heading`` after ``path_mm`` of driving: a point, and
        the straight line to each drop met before on the same edge (JOIN_MM's rule), with
        the guess of where it goes on (GUESS_MM's)."""
        met = self._met
        if any(abs(x - mx) < _SAME_MM and abs(y - my) < _SAME_MM for mx, my, _, _ in met):
            return  # the same drop, a tick later
        self._add(x, y, x, y, False)
        for mx, my, m_heading, m_path in met:
            length = math.hypot(x - mx, y - my)
            same_way = abs(math.remainder(heading - m_heading, math.tau)) < JOIN_TURN
            along = same_way and path_mm - m_path <= JOIN_PATH_MM and length <= JOIN_ALONG_MM
            if length > JOIN_MM and not along:
                continue
            self._add(mx, my, x, y, False)
            if length >= GUESS_FROM_MM:
                ahead = GUESS_MM / length
                self._add(x, y, x + (x - mx) * ahead, y + (y - my) * ahead, True)
        met.append((x, y, heading, path_mm))

    def _add(self, x0: float, y0: float, x1: float, y1: float, guessed: bool) -> None:
        """An edge: indexed by the cells it crosses; a known one's cells DROP and blocked."""
        index = len(self.edges)
        self.edges.append((x0, y0, x1, y1, guessed))
        fmap, edges_in = self._map, self._edges_in
        steps = int(math.hypot(x1 - x0, y1 - y0) / _RAY_STEP_MM) + 1
        for k in range(steps + 1):
            x, y = x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps
            cell = fmap.cell(x, y)
            if cell is None:
                continue
            here = edges_in.setdefault(cell, [])
            if here and here[-1] == index:
                continue
            if not here:
                self._zone(cell)
            here.append(index)
            if not guessed and not fmap.cells[cell] & DROP:
                fmap.block(x, y)
                fmap.cells[cell] |= DROP
                self.cells += 1

    def _zone(self, cell: int) -> None:
        """One more cell with a drop near each cell within ZONE_CELLS of ``cell``."""
        zone = self.zone
        for step in self._zone_steps:
            near = cell + step
            if 0 <= near < len(zone) and zone[near] < 255:
                zone[near] += 1

    def near(self, pose: Odometry) -> bool:
        """Is a known drop within ZONE_CELLS of the robot's cell (a byte read)?"""
        cell = self._map.cell(pose.x_mm, pose.y_mm)
        return cell is not None and self.zone[cell] > 0

    def _edges_near(self, pose: Odometry, guessed: bool) -> list[tuple[float, float, float, float]]:
        """The edges through the cells within ZONE_CELLS of the robot's (``guessed`` ones
        too, or not)."""
        cell = self._map.cell(pose.x_mm, pose.y_mm)
        if cell is None or not self.zone[cell]:
            return []
        edges_in, edges = self._edges_in, self.edges
        found: set[int] = set()
        for step in self._zone_steps:
            found.update(edges_in.get(cell + step, ()))
        return [edges[i][:4] for i in sorted(found) if guessed or not edges[i][4]]

    def ahead(
        self, pose: Odometry, heading: float, margin: float = MARGIN_MM, guessed: bool = True
    ) -> bool:
        """Is a known drop (or a ``guessed`` one) within ``margin`` mm beyond a cliff sensor,
        or between two, of the robot at ``pose`` facing ``heading``?"""
        edges = self._edges_near(pose, guessed)
        reach = CLIFF_SENSOR_RADIUS_MM + margin
        x, y = pose.x_mm, pose.y_mm
        return bool(edges) and any(
            _ray(edges, x, y, heading + a, reach) < reach for a in _AHEAD_ANGLES
        )

    def away(self, pose: Odometry) -> float | None:
        """The heading straight away from the nearest known drop (not a guess) near the
        robot at ``pose``, None when none is near: where ``cover`` turns and drives to when a
        known drop keeps its next leg from starting (:meth:`.coverage_map.Cover._ended`)."""
        best: tuple[float, float, float] | None = None
        x, y = pose.x_mm, pose.y_mm
        for x0, y0, x1, y1 in self._edges_near(pose, guessed=False):
            dx, dy = x1 - x0, y1 - y0
            length_sq = dx * dx + dy * dy
            t = 0.0 if length_sq == 0.0 else ((x - x0) * dx + (y - y0) * dy) / length_sq
            t = min(1.0, max(0.0, t))
            px, py = x0 + t * dx, y0 + t * dy
            d_sq = (x - px) ** 2 + (y - py) ** 2
            if best is None or d_sq < best[0]:
                best = (d_sq, px, py)
        if best is None or best[0] == 0.0:
            return None
        return math.atan2(y - best[2], x - best[1])

    def behind(self, pose: Odometry) -> bool:
        """Is a known drop (not a guess: where an edge would go on is no drop met) under the
        back half of the body at ``pose``, or within BEHIND_MARGIN_MM of it: where a
        back-off must not go (it has no sensor behind;
        :mod:`~roomba_bt.behaviours.reversing`). Looked for along its back half's rays, to
        the sides (the wheels) too: a drop beside the body is clear of a straight back."""
        edges = self._edges_near(pose, guessed=False)
        reach = BODY_RADIUS_MM + BEHIND_MARGIN_MM
        x, y, back = pose.x_mm, pose.y_mm, pose.theta_rad + math.pi
        return bool(edges) and any(
            _ray(edges, x, y, back + a, reach) < reach for a in _BEHIND_ANGLES
        )

    def speed(self, pose: Odometry, heading: float, speed: float) -> float:
        """``speed``, or SLOW_MM_S near a known drop ahead (SLOW_MM beyond a sensor)."""
        if speed > SLOW_MM_S and self.ahead(pose, heading, SLOW_MM):
            return SLOW_MM_S
        return speed

    def signals(self, pose: Odometry) -> tuple[int, ...]:
        """The light bumper's six signals that the known drops would give as walls WALL_MM
        nearer: a ray reaching one d mm from the bumper gives 4095 (1 - d / 150) ** 2
        (:func:`~roomba_bt.behaviours.edging.signal_distance_mm`'s model), else 0."""
        edges = self._edges_near(pose, guessed=True)
        if not edges:
            return _DARK
        x, y, theta = pose.x_mm, pose.y_mm, pose.theta_rad
        seen = []
        for angle in _RAY_ANGLES:
            d = _ray(edges, x, y, theta + angle, _RAY_END_MM) - BODY_RADIUS_MM - WALL_MM
            seen.append(
                0 if d >= LIGHT_BUMP_RANGE_MM
                else round(4095.0 * (1.0 - max(d, 0.0) / LIGHT_BUMP_RANGE_MM) ** 2)
            )  # fmt: skip
        return tuple(seen)


def _ray(
    edges: list[tuple[float, float, float, float]], x: float, y: float, angle: float, end: float
) -> float:
    """How far (mm) from (x, y) along ``angle`` the first of ``edges`` is (a point one as a
    disc of POINT_MM), up to ``end`` (``end``: none before)."""
    c, s = math.cos(angle), math.sin(angle)
    nearest = end
    for x0, y0, x1, y1 in edges:
        dx, dy = x1 - x0, y1 - y0
        # the disc around the start point
        ox, oy = x0 - x, y0 - y
        along = ox * c + oy * s
        across = ox * s - oy * c
        if 0.0 < along < nearest and abs(across) < POINT_MM:
            nearest = min(nearest, max(0.0, along - math.sqrt(POINT_MM**2 - across**2)))
        denominator = c * dy - s * dx
        if abs(denominator) < 1e-9:
            continue
        # x + t c = x0 + u dx, y + t s = y0 + u dy
        t = (ox * dy - oy * dx) / denominator
        u = (ox * s - oy * c) / denominator
        if 0.0 <= u <= 1.0 and 0.0 <= t < nearest:
            nearest = t
    return nearest


class DropEdge:
    """What ``cover``'s edge adds for drops: the light bumper's signals with the known drops
    seen as walls, and after a drop on its right, a wider, slower search for it (the
    module's table). One per edge."""

    def __init__(self, drops: KnownDrops) -> None:
        self._drops = drops
        #: the odometry's path (mm) when a known drop was last on its right
        self._last = -math.inf

    def along(self, pose: Odometry, turned: float) -> bool:
        """Turning left off a drop just met: has it turned enough (ALONG_TURN at least) to
        have the drop on its right and nothing of it ahead (on the map)? A fixed 60 deg
        left it heading 40 deg away from a drop met at 20, to curve back for a metre."""
        if turned < ALONG_TURN:
            return False
        known = self._drops.signals(pose)
        return max(known[1:5]) < FRONT_CLEAR and max(known[4:6]) > 0

    def view(
        self, frame: SensorFrame, pose: Odometry, speed: float
    ) -> tuple[tuple[int, ...], float]:
        """(the light bumper's signals, the speed) for this tick of an edge at ``pose``."""
        signals: tuple[int, ...] = frame.light_bump_signals
        drops = self._drops
        if drops.near(pose):
            known = drops.signals(pose)
            if known[4] or known[5]:
                self._last = pose.path_mm
            signals = tuple(map(max, signals, known))
        if pose.path_mm - max(self._last, drops.last_met) > SEARCH_MM:
            return signals, speed
        return signals, min(speed, SLOW_MM_S)
