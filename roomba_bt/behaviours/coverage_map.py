"""``cover``: clean the floor with a map of its own, kept from odometry and the bumper.

A robot without a camera still knows where it has been: the encoders' pose. ``cover`` keeps a
coarse grid (10 cm cells) in the odometry frame and marks in it, every tick:

* **swept** cells: under the strip the brushes clean (90 mm left of the centre to 185 mm
  right, where the side brush reaches past the body), while the robot drives;
* **blocked** cells: where the bumper met something, where a light-bumper ray sees a surface
  (its signal gives the distance), under a cliff sensor that sees a drop (DROP cells, joined
  along the drop's edge: :mod:`~roomba_bt.behaviours.drops`), ahead of a virtual wall's
  beam; the cells next to a blocked one are no place for the robot's centre.

It never reads anything but the snapshot (the encoders and the sensors): no true pose, no
simulator map. With the grid it decides where to go::

    start:  straight ahead to a wall, then follow the edge (wall on the right: the side brush
            cleans along it) until a metre goes by without new floor
    then:   lanes back and forth (boustrophedon) along the walls' direction, each lane ending
            at an obstacle or where the floor ahead is already swept; the next lane only
            if the floor beside this one is not swept yet
    when a region stops giving new floor: a breadth-first search over the cells it has
            been on finds the nearest swept cell next to floor it has not swept (the
            frontier); it drives there along the path and sweeps lanes from there; a
            frontier that lies along a wall gets an edge instead
    when no frontier is left: an edge from wherever it is; when two find no new floor
            either and the map closed on under 6 m², the way out to open floor past what
            it met, across cells it knows nothing of (:meth:`FloorMap.escape`: chair legs
            40 cm apart closed its map on an island of legs), and lanes there; when there
            is none, SUCCESS (the whole floor it can reach is swept), its message the floor
            it swept: ``floor done: 11.6 m² swept by its own map``
    passes: with ``passes`` above 1, a pass that ends so starts the next instead, on its
            map drawn afresh (:meth:`FloorMap.next_pass`: the drops, the cells it has been
            on and the dock's beams kept), as the first started: ahead to a wall, an edge

The cost per tick is the cells the strip and the rays touch (a few); the search runs only
when a region ends, over the cells seen so far (a few thousand).

Odometry drifts (the encoders miscount a percent or two; a straight line reads as a slow
curve). The lanes' direction is re-anchored on the walls: while it follows a straight stretch
of wall (a metre with the heading within 2 deg), the wall's heading by odometry becomes the
lanes' axis, so lanes stay parallel to the walls however the heading has drifted.

Every driving step stops for hazards in the tick that shows them (bump, cliff, virtual wall),
backs off and goes on with the next decision; and short of a drop it knows (a lane, a shift, a
path's leg, a seek, an arc), slowing near one, while its edge follows a known drop as a wall
(:mod:`~roomba_bt.behaviours.drops`: else it meets the apartment's stairs 12-30 times a run,
each a fall to Passive in Safe mode). In Safe mode the firmware stops first at a
cliff and drops to Passive (the brushes stop too); that fails ``cover`` in the tick it shows
(``Action.stranded`` with no grace: the cliff is mapped, and nothing brings the robot back
while it waits; it waited a second, 21 a run by the apartment's stairs), and the mission
re-enters Safe, turns the motors on and starts it again (missions/clean.yaml: a ``retry``).
Started again in the same run it goes on with what it knew: its map and pose are kept on the
blackboard (:data:`MAP_KEY`, dropped by each run's ``setup``), and its plan: the move the
firmware stopped meets the hazard in its first tick and reacts as in Full mode (backs off, and
the lane, edge or path goes on as it would have). A ``cover`` that another one's map is handed
to backs off, turns and makes for the nearest unswept floor. A wheel drop fails it.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from functools import partial
from typing import Any

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours import driving, reversing
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import run_board, write_key
from roomba_bt.behaviours.declare import Param, declare, wheel_speed_param
from roomba_bt.behaviours.docking.common import DockWatch
from roomba_bt.behaviours.docking.escape import WAY_KEY, Way
from roomba_bt.behaviours.driving import WHEEL
from roomba_bt.behaviours.drops import DROP, DropEdge, KnownDrops
from roomba_bt.behaviours.edging import EdgeSteering, signal_distance_mm
from roomba_bt.behaviours.units import BOOL, DISTANCE, DURATION, INT, STR
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import (
    ENCODER_PACKETS,
    IR_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    SensorFrame,
)
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import (
    BODY_RADIUS_MM,
    LIGHT_BUMP_ANGLES_DEG,
    WHEEL_BASE_MM,
)
from roomba_bt.robot.interface import Odometry

__all__ = ["COVERAGE", "MAP_KEY", "UNREACHED_SAID", "Bearings", "Cover", "FloorMap"]

_log = logging.getLogger("roomba_bt.mission")

_OK, _RUN = Status.SUCCESS, Status.RUNNING

#: the map's cell side (mm) and its extent (cells a side, centred on the start: 60 m)
CELL_MM = 100.0
_SIDE = 600
_HALF_SIDE = _SIDE // 2
#: cell bits (and DROP, 16: where a cliff sensor saw the floor end, :mod:`.drops`; ``cover``
#: treats it as any other blocked cell, ``home_by_map``'s path across blocked cells never
#: crosses it)
SWEPT, BLOCKED, VISITED, TRIED = 1, 2, 4, 8
#: a cell's four neighbours, as steps in the cell index
NEIGHBOUR_STEPS = (-_SIDE, _SIDE, -1, 1)
#: the cells within two of a cell (5 x 5), as steps in the cell index: the robot's centre
#: there would have its body (17 cm) over a drop on the map
_AROUND = tuple(row * _SIDE + col for row in range(-2, 3) for col in range(-2, 3))
#: the cell and its eight neighbours (3 x 3), as steps in the cell index: a blocked cell's
#: neighbours are no place for the robot's centre (``FloorMap.near``)
_AROUND_ONE = (-_SIDE - 1, -_SIDE, -_SIDE + 1, -1, 0, 1, _SIDE - 1, _SIDE, _SIDE + 1)
#: the strip the brushes clean, as points across the body (x forward, y left; mm): the main
#: brush 90 mm to the left, the side brush 185 mm to the right (kept a little inside both)
_STRIP = (*((0.0, y) for y in (80.0, 40.0, 0.0, -40.0, -80.0)), (40.0, -120.0), (50.0, -160.0))
#: the body's radius and the light bumper: rays from the centre at these angles, starting on
#: the bumper, 150 mm long (:func:`~roomba_bt.behaviours.edging.signal_distance_mm`)
_RADIUS_MM = BODY_RADIUS_MM
_RAY_ANGLES = tuple(math.radians(a) for a in LIGHT_BUMP_ANGLES_DEG)
#: a ray's signal from which the surface it sees is marked (about 13 cm from the bumper)
_RAY_MARK = 60
_HALF_BASE_MM = WHEEL_BASE_MM / 2.0
#: a lane that has swept nothing new for this far (mm) ends: it has reached swept floor
_NO_YIELD_MM = 400.0
#: an edge that has swept nothing new for this far (mm) ends (a loop closed, or old floor)
_EDGE_NO_YIELD_MM = 1200.0
#: a path's leg a known drop ends before this much (mm) has not started: the drop lies in
#: the look-ahead of where it stands (:meth:`Cover._clear_of_drop`)
_NO_START_MM = 20.0
#: ... and the robot drives this far (mm) straight away from the drop first: a leg along
#: the drop then clears it (a cliff sensor's look-ahead reaches 18 cm to the side)
_CLEAR_MM = 150.0
#: the frontier cells left at the end (:meth:`FloorMap.unreached`) from which ``cover``'s
#: "floor done" says them: a metre of its map's frontier
UNREACHED_SAID = 10
#: an edge whose centre has not moved turning more than this (rad) is turning in place, not
#: held (:meth:`Cover._edge_held`)
_EDGE_TURNING = math.radians(10.0)
#: a straight stretch of wall: this long (mm) with the heading within this angle re-anchors
_ANCHOR_MM, _ANCHOR_SPREAD = 1000.0, math.radians(2.0)
#: a straight wall this close to the axis (or square to it) re-anchors the heading
_SNAP = math.radians(25.0)
#: an edge that found more new cells than this was worth it: another may be
_EDGE_NEW_CELLS = 20
#: escapes in a row past what it met (:meth:`FloorMap.escape`) that found no more new cells
#: than that before the floor is done all the same: its map's outline has a gap, and the
#: floor behind it is a wall's far side
_FUTILE_ESCAPES = 2
#: a map closed on less swept floor than this (cells: 6 m²) may be an island of legs
#: rather than a room, and only then is a way out looked for; a room's map closed on more
#: is done (with the encoders' error a larger map has ghost walls across floor it swept,
#: and ways out through them led nowhere, the way home then running out of time)
_ISLAND_CELLS = 600

#: what a cell keeps into the next pass (``FloorMap.next_pass``), for each of its bytes: the
#: cells it has been on, and the drops, blocked still; not what it swept, tried or met
_NEXT_PASS_BITS = bytes(
    bits & (VISITED | DROP) | (BLOCKED if bits & DROP else 0) for bits in range(256)
)

Cell = int

#: Where ``cover`` keeps what it knows between its starts in one run: its :class:`Bearings`
#: (the map and its own pose) on py_trees' blackboard, shared by every ``cover`` of the
#: mission (one floor, one odometry frame); each run's ``setup`` drops it.
MAP_KEY = "/roomba/cover/map"
#: What a leaf that drives on the map reads (``cover``, and ``home_by_map`` along it): the
#: hazards that end a move, the encoders its pose integrates (:meth:`Bearings.integrate`),
#: the light bumper's signals and the dock's beams that :meth:`Bearings.observe` marks.
MAP_READS = (*driving.BLOCKED_PACKETS, *ENCODER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *IR_PACKETS)


def path_to(cell: Cell, start: Cell, parent: dict[Cell, Cell]) -> list[Cell]:
    """The cells from ``start`` to ``cell``, read back through a search's ``parent`` links
    (:meth:`FloorMap.search`'s breadth-first, ``home_by_map``'s cheapest path)."""
    path = [cell]
    while path[-1] != start:
        path.append(parent[path[-1]])
    path.reverse()
    return path


def _from_start(x: float, y: float) -> str:
    """Where (x, y) of the map is from where the robot started (the map's origin, its
    heading then along x), as an owner would pace it: ``1.9 m ahead and 0.6 m to the
    right of where it started`` (odometry's: a drifted map's figure is off by its drift)."""
    ahead = f"{abs(x) / 1000.0:.1f} m {'ahead' if x >= 0 else 'behind'}"
    side = f"{abs(y) / 1000.0:.1f} m to the {'left' if y >= 0 else 'right'}"
    return f"about {ahead} and {side} of where it started"


class FloorMap:
    """The robot's own grid: one byte a cell, in the odometry frame (mm), bits SWEPT, BLOCKED,
    VISITED, TRIED, DROP; ``near`` counts the blocked cells around each cell (3 x 3),
    ``drops`` keeps the drops (:class:`~roomba_bt.behaviours.drops.KnownDrops`)."""

    #: cells a side
    SIDE = _SIDE

    def __init__(self) -> None:
        self.cells = bytearray(_SIDE * _SIDE)
        self.near = bytearray(_SIDE * _SIDE)
        #: cells a path led into and the robot met something there: no path goes that way
        self.avoid: set[Cell] = set()
        #: cells newly swept (a counter: the caller compares), in this pass
        self.swept = 0
        #: the passes over the floor started (:meth:`next_pass`), this one included
        self.passes = 1
        #: cells where a receiver saw a dock's beam, each with the odometry's path (mm) when
        #: it last did: the way home leads to the nearest of the latest (``home_by_map``)
        self.beams: dict[Cell, float] = {}
        #: where the cliff sensors saw drops, and the moves' look at them
        self.drops = KnownDrops(self)

    @staticmethod
    def cell(x: float, y: float) -> Cell | None:
        col = math.floor(x / CELL_MM) + _HALF_SIDE
        row = math.floor(y / CELL_MM) + _HALF_SIDE
        if 1 <= col < _SIDE - 1 and 1 <= row < _SIDE - 1:
            return row * _SIDE + col
        return None

    @staticmethod
    def centre(cell: Cell) -> tuple[float, float]:
        row, col = divmod(cell, _SIDE)
        return ((col - _HALF_SIDE + 0.5) * CELL_MM, (row - _HALF_SIDE + 0.5) * CELL_MM)

    def sweep(self, x: float, y: float, theta: float) -> None:
        """Mark the strip under the robot at (x, y) facing theta swept, and its centre."""
        c, s = math.cos(theta), math.sin(theta)
        cells = self.cells
        for ax, ay in _STRIP:
            cell = self.cell(x + ax * c - ay * s, y + ax * s + ay * c)
            if cell is not None and not cells[cell] & SWEPT:
                cells[cell] |= SWEPT
                self.swept += 1
        cell = self.cell(x, y)
        if cell is not None:
            cells[cell] |= VISITED

    def floor_done(self, left: str = "") -> str:
        """What ``cover`` says when it is done: the floor swept, by odometry (the last pass's,
        when it made more than one: the passes sweep the same floor), then ``left``
        (:meth:`left_unreached`)."""
        swept = f"{self.swept * (CELL_MM / 1000.0) ** 2:.1f} m² swept by its own map"
        if self.passes > 1:
            swept = f"{swept} (the last of {self.passes} passes)"
        return f"floor done: {swept}{left}"

    def left_unreached(self, x: float = 0.0, y: float = 0.0, why: str = "") -> str:
        """``"; ..."``: the unswept floor its map shows beside what it swept, which no path
        on the map reached, when that borders :data:`UNREACHED_SAID` cells or more: how
        much, the nearest of it from (x, y), where it stopped, and from where it started
        (its map's origin, facing along x), and ``why`` no way reached it (what
        :class:`NoFrontier` knows of its tries); else ``""``.

        Why: the floor is done when no path on its map leads to unswept floor, which says
        nothing of a room whose door its map closed (the encoders' drift draws walls across
        floor it drove): the apartment's bedroom was never entered in one of four starts
        with 1.5 % error, the run a success whose summary said the floor was done. What the
        robot knows of it is its own map's frontier left over: at the end of a living-room
        start with exact encoders 0 cells, in the apartment with the error 27-166 before
        the search across ghost walls (:meth:`NoFrontier.path_out`), 16-159 after
        (155 where it ended at 49.6 % of the floor). It cannot say a room was missed, only
        that its map has floor it found no way to; not "(a door its map closed?)", a guess
        that would send a dining room's owner looking for a door where the floor lay past
        chair legs 1.5 m from the start."""
        left = self.unreached_cells()
        if len(left) < UNREACHED_SAID:
            return ""
        nearest = min(left, key=lambda cell: math.dist(self.centre(cell), (x, y)))
        cx, cy = self.centre(nearest)
        said = (
            f"; its map shows unswept floor along {len(left) * CELL_MM / 1000.0:.1f} m of the "
            "floor it swept that it found no way to, the nearest "
            f"{math.dist((cx, cy), (x, y)) / 1000.0:.1f} m from where it stopped "
            f"({_from_start(cx, cy)})"
        )
        return f"{said}: {why}" if why else said

    def next_pass(self) -> None:
        """Start a pass over the floor again: forget what it swept and what it met, keep the
        drops (never met twice for a map's sake), the cells it has been on (the way home
        and the searches run over them) and where it saw the dock's beams.

        Why forget what it met: with the encoders' error the first pass's map drifts from
        the floor, its walls drawn again a few centimetres over at every visit, and those
        ghost walls across floor it swept close the map early ("floor done" at 17 % of a
        living room). A pass that maps the walls afresh, in the frame the pose has drifted
        to by now, sweeps the floor the first one only thought it had; with exact encoders
        it sweeps again what the first left under a blob of blocked cells."""
        cells, near = self.cells, self.near
        cells[:] = cells.translate(_NEXT_PASS_BITS)
        near[:] = bytes(len(near))
        for cell in [cell for cell, bits in enumerate(cells) if bits & BLOCKED]:  # drops'
            for d in _AROUND_ONE:
                near[cell + d] = min(255, near[cell + d] + 1)
        self.avoid.clear()
        self.swept = 0
        self.passes += 1

    def block(self, x: float, y: float) -> None:
        """Something is at (x, y): that cell is blocked, its neighbours no place for the
        robot's centre."""
        cell = self.cell(x, y)
        if cell is None or self.cells[cell] & BLOCKED:
            return
        self.cells[cell] |= BLOCKED
        near = self.near
        for d in _AROUND_ONE:
            if near[cell + d] < 255:
                near[cell + d] += 1

    def block_ahead(self, x: float, y: float, theta: float, reach: float, spread: float) -> None:
        """Block the points ``reach`` mm from (x, y) at ``theta`` and ``theta +- spread``."""
        for a in (theta - spread, theta, theta + spread):
            self.block(x + reach * math.cos(a), y + reach * math.sin(a))

    def free(self, cell: Cell) -> bool:
        """May the robot's centre be in this cell (nothing known blocks it)?"""
        return not self.near[cell]

    def open_floor(self, cell: Cell) -> bool:
        """Floor not swept yet where the robot's centre could go: worth a visit."""
        return not self.cells[cell] & (SWEPT | BLOCKED | TRIED) and not self.near[cell]

    def frontier(
        self, start: Cell, through_near: bool = False, through_ghosts: bool = False
    ) -> list[Cell] | None:
        """The path (cells, from ``start``) over cells the robot has been on or swept, to
        the nearest one beside open floor; None when there is none. Breadth-first.
        ``through_ghosts``: across the blocked cells its centre has been on too (never a
        drop's): :meth:`search`."""
        return self.search(start, self.beside_open, through_near, through_ghosts=through_ghosts)

    def beside_open(self, cell: Cell) -> bool:
        """A cell it swept or has been on, nothing met there, not tried yet, with open
        floor beside it: the frontier."""
        cells, open_floor = self.cells, self.open_floor
        return not cells[cell] & (TRIED | BLOCKED) and any(
            open_floor(cell + d) for d in NEIGHBOUR_STEPS
        )

    def unreached(self) -> int:
        """How many frontier cells are left on the map (:meth:`unreached_cells`)."""
        return len(self.unreached_cells())

    def unreached_cells(self) -> list[Cell]:
        """The frontier cells left on the map (:meth:`beside_open`): where it knows of open
        floor beside floor it swept and found no way to (said when the floor is done)."""
        cells, beside_open = self.cells, self.beside_open
        return [
            cell
            for cell, bits in enumerate(cells)
            if bits & (SWEPT | VISITED) and _SIDE < cell < len(cells) - _SIDE and beside_open(cell)
        ]

    def escape(self, start: Cell) -> list[Cell] | None:
        """The path (cells, from ``start``) to the nearest open floor over any cell not
        blocked, floor it has not been on and cells beside what it met too, and over the
        blocked cells the robot's centre has been on (never within two cells of a drop). None when
        blocked cells close it in: its map has found the room's outline. A gap in a wall's
        line on the map (a corner the edge cut) lets it out too: :class:`NoFrontier` stops
        after one such escape that found nothing.

        Chair and table legs (3 cm, 40 cm apart: the robot passes between them) come out
        as blobs of blocked cells with no free cell between them on a 10 cm grid (a thin
        leg reflects little: the light bumper reads it farther off than it is, so the rays
        smear it over the cells round it), drawn over the robot's own way in; ``frontier``
        then finds no way out, and the map closed on an island of legs (a dining room:
        "floor done" at 7-21 %). Open floor past them is not done floor, and a blocked cell
        the robot's centre has been on cannot be solid (a drifted map's ghost, or a leg
        smeared): the escape crosses it."""
        return self.search(start, self.open_floor, through_unknown=True)

    def search(
        self,
        start: Cell,
        goal: Callable[[Cell], bool],
        through_near: bool = False,
        through_unknown: bool = False,
        through_ghosts: bool = False,
    ) -> list[Cell] | None:
        """The path (cells, from ``start``) to the nearest cell other than ``start`` that
        ``goal`` takes, over the cells the robot has been on, or swept away from anything
        (or near it too: ``through_near``, a narrow doorway; or any cell not blocked:
        ``through_unknown``, :meth:`escape`: any cell not blocked, and a blocked one the
        robot's centre has been on, never a cell within two of a drop; or ``through_ghosts``,
        the swept cells and those it has been on, blocked or not, never a drop's: a ghost
        wall its drifted map drew across floor it crossed), never other blocked ones nor
        :attr:`avoid`; None when none is reached. Breadth-first: ``frontier`` and
        ``home_by_map`` plan with it."""
        cells, near, avoid = self.cells, self.near, self.avoid
        parent: dict[Cell, Cell] = {start: start}
        queue = deque((start,))
        # the robot may stand next to something it just met: its own neighbourhood is free
        for d in (-_SIDE - 1, -_SIDE, -_SIDE + 1, -1, 1, _SIDE - 1, _SIDE, _SIDE + 1):
            beside = start + d
            bits = cells[beside]
            if bits & (SWEPT | VISITED) and not bits & BLOCKED and beside not in avoid:
                parent[beside] = start
                queue.append(beside)
        while queue:
            cell = queue.popleft()
            if cell != start and goal(cell):
                return path_to(cell, start, parent)
            for d in NEIGHBOUR_STEPS:
                nxt = cell + d
                bits = cells[nxt]
                if through_unknown:  # a blocked cell its centre has been on is a ghost
                    passable = (
                        not bits & BLOCKED or bool(bits & VISITED and not bits & DROP)
                    ) and not any(cells[nxt + a] & DROP for a in _AROUND)
                elif through_ghosts:  # known floor only, a ghost wall crossed
                    passable = bool(bits & (SWEPT | VISITED)) and (
                        not bits & BLOCKED or bool(bits & VISITED and not bits & DROP)
                    )
                else:
                    passable = not bits & BLOCKED and bool(
                        bits & VISITED or (bits & SWEPT and (through_near or not near[nxt]))
                    )
                if passable and nxt not in parent and nxt not in avoid:
                    parent[nxt] = cell
                    queue.append(nxt)
        return None

    def line_free(self, a: Cell, b: Cell) -> bool:
        """Can the centre go straight from cell a to cell b (every cell on the way free)?"""
        (ax, ay), (bx, by) = self.centre(a), self.centre(b)
        steps = max(1, int(math.hypot(bx - ax, by - ay) / (CELL_MM / 2.0)))
        for k in range(steps + 1):
            cell = self.cell(ax + (bx - ax) * k / steps, ay + (by - ay) * k / steps)
            if cell is None or self.near[cell]:
                return False
        return True

    def waypoints(self, path: list[Cell]) -> list[Cell]:
        """The path's corners: the farthest cell reachable in a straight line, and on."""
        points: list[Cell] = []
        i = 0
        while i < len(path) - 1:
            j = len(path) - 1
            while j > i + 1 and not self.line_free(path[i], path[j]):
                j -= 1
            points.append(path[j])
            i = j
        return points

    def open_along(self, x: float, y: float, heading: float, length: float) -> int:
        """Open-floor cells on the line from (x, y) along ``heading`` for ``length`` mm,
        up to the first blocked one."""
        count = 0
        c, s = math.cos(heading), math.sin(heading)
        seen: set[Cell] = set()
        for k in range(1, int(length / (CELL_MM / 2.0)) + 1):
            d = k * CELL_MM / 2.0
            cell = self.cell(x + d * c, y + d * s)
            if cell is None or self.cells[cell] & BLOCKED:
                break
            if cell not in seen and self.open_floor(cell):
                seen.add(cell)
                count += 1
        return count


class Bearings:
    """Where ``cover`` is and what it has met, kept apart from what it decides: its own pose
    (the odometry's increments since the start, the heading re-anchored on straight walls:
    the module's last paragraph but one) and, each tick, what the sensors show marked in its
    :class:`FloorMap`. Reads only the snapshot's odometry and frame."""

    def __init__(self, fmap: FloorMap, odo: Odometry) -> None:
        self.map = fmap
        #: its own pose: the odometry's increments, the heading re-anchored on walls
        self.pose = odo
        #: the odometry as the last tick saw it
        self._odo = odo
        #: the lanes' axis (rad, mod 90 deg), from the walls; None before the first one
        self.axis: float | None = None
        #: (path mm, heading) along the straight stretch of wall followed now
        self._straight: list[tuple[float, float]] = []
        #: re-anchorings of the heading on a wall (for tests and the curious)
        self.anchored = 0
        #: a receiver saw a dock character in the frame :meth:`observe` last took (the
        #: beams' cells are kept on the map; ``home_by_map`` ends on it)
        self.sees_dock = False
        self._dock = DockWatch()
        #: where its centre has just been: how far it may back up (:mod:`.reversing`)
        self.trail = reversing.Trail()
        #: its way in the odometry's frame, for the dock search after it (:data:`WAY_KEY`)
        self.way = Way()

    def integrate(self, odo: Odometry, now: float) -> Odometry:
        """Its pose after this tick: the odometry's travel and turn since the last, from
        its own (re-anchored) pose; a crumb of its :attr:`way` at ``now``."""
        self.way.add(odo, now)
        pose, last = self.pose, self._odo
        distance, angle = odo.distance_mm - last.distance_mm, odo.angle_rad - last.angle_rad
        self._odo = odo
        mid = pose.theta_rad + angle / 2.0
        self.pose = pose = odo._replace(
            x_mm=pose.x_mm + distance * math.cos(mid),
            y_mm=pose.y_mm + distance * math.sin(mid),
            theta_rad=pose.theta_rad + angle,
        )
        self.trail.add(pose)
        return pose

    @staticmethod
    def of_run(odo: Odometry) -> tuple[Bearings, bool]:
        """The run's bearings kept under :data:`MAP_KEY`, resumed at ``odo`` (True), or new
        ones from ``odo``, kept there (False)."""
        storage, name = py_trees.blackboard.Blackboard.storage, run_board().name(MAP_KEY)
        kept = storage.get(name)
        if isinstance(kept, Bearings):
            kept.resume(odo)
            return kept, True
        bearings = storage[name] = Bearings(FloorMap(), odo)
        storage[run_board().name(WAY_KEY)] = bearings.way
        return bearings, False

    def resume(self, odo: Odometry) -> None:
        """``cover`` starts again in the same run (after the firmware's drop to Passive at a
        cliff, say): the robot's move since the last tick it saw is the odometry's, turned
        into its own frame (whose heading walls may have re-anchored), as one rigid move."""
        pose, last = self.pose, self._odo
        turn = pose.theta_rad - last.theta_rad
        dx, dy = odo.x_mm - last.x_mm, odo.y_mm - last.y_mm
        c, s = math.cos(turn), math.sin(turn)
        self.pose = odo._replace(
            x_mm=pose.x_mm + dx * c - dy * s,
            y_mm=pose.y_mm + dx * s + dy * c,
            theta_rad=odo.theta_rad + turn,
        )
        self._odo = odo
        self._straight.clear()

    def __repr__(self) -> str:  # the monitor's blackboard shows it
        pose = self.pose
        # the heading as the odometry's panel gives it, -179..180 (it said "900 deg": the
        # turns summed), never "-0"
        heading = round(math.degrees(pose.theta_rad)) % 360
        heading = heading - 360 if heading > 180 else heading
        return (
            f"<cover's map: {self.map.swept} cells swept, at x {pose.x_mm:.0f} mm "
            f"y {pose.y_mm:.0f} mm, {heading} deg>"
        )

    def observe(self, frame: SensorFrame) -> None:
        """Mark what this tick shows from the pose: the strip swept (while the wheels
        turn), surfaces, the cell if a receiver sees the dock (:attr:`sees_dock`)."""
        pose = self.pose
        x, y, theta = pose.x_mm, pose.y_mm, pose.theta_rad
        fmap = self.map
        fmap.sweep(x, y, theta)
        self.sees_dock = seen = self._dock.view(frame).seen
        if seen:
            cell = fmap.cell(x, y)
            if cell is not None:
                fmap.beams[cell] = pose.path_mm
        signals = frame.light_bump_signals
        for angle, signal in zip(_RAY_ANGLES, signals, strict=True):
            if signal >= _RAY_MARK:
                reach = _RADIUS_MM + signal_distance_mm(signal) + 20.0
                a = theta + angle
                fmap.block(x + reach * math.cos(a), y + reach * math.sin(a))
        if frame.any_bump:
            bumps = frame.bumps  # one side alone: the contact is off to that side
            spread = (
                0.0 if bumps.bump_left == bumps.bump_right else (0.6 if bumps.bump_left else -0.6)
            )
            fmap.block_ahead(x, y, theta + spread, _RADIUS_MM + 30.0, 0.35)
        if frame.any_cliff:  # under the sensors that see it, joined along its edge
            fmap.drops.met(frame, pose)
        if frame.virtual_wall:
            fmap.block_ahead(x, y, theta, _RADIUS_MM + 80.0, 0.5)

    def reversible(self, wanted: float, own: float = 0.0) -> float:
        """How far (mm, up to ``wanted``) it may back up from its pose: over floor it has
        just driven (the first ``own`` mm aside), no known drop behind
        (:meth:`.reversing.Trail.reversible`)."""
        return self.trail.reversible(self.pose, wanted, self.map.drops, own)

    def blocked_ahead(self, heading: float) -> bool:
        """The map has something just ahead of the bumper along ``heading``."""
        odo = self.pose
        reach = _RADIUS_MM + 40.0
        x, y = odo.x_mm + reach * math.cos(heading), odo.y_mm + reach * math.sin(heading)
        cell = self.map.cell(x, y)
        return cell is not None and bool(self.map.cells[cell] & BLOCKED)

    def off_wall(self) -> None:
        """No straight stretch of wall now (a corner, a recovery, a new edge)."""
        self._straight.clear()

    def anchor(self, path: float, heading: float, steady: bool) -> None:
        """Along a straight stretch of wall, its heading re-anchors the lanes' axis."""
        straight = self._straight
        if not steady:
            straight.clear()
            return
        straight.append((path, heading))
        while straight and path - straight[0][0] > _ANCHOR_MM:
            headings = [h for _, h in straight]
            mean = math.atan2(
                sum(math.sin(h) for h in headings), sum(math.cos(h) for h in headings)
            )
            if max(abs(driving.wrap(h - mean)) for h in headings) <= _ANCHOR_SPREAD:
                self._reanchor(mean)
                straight.clear()
                return
            straight.pop(0)

    def _reanchor(self, wall: float) -> None:
        """A straight wall runs along ``wall`` (rad) by its pose. The first one sets the
        lanes' axis; walls meet at right angles, so a later one off the axis by less than
        :data:`_SNAP` says how far its heading has drifted: taken off the pose."""
        axis = self.axis
        if axis is None:
            self.axis = wall
            return
        quarter = math.pi / 2
        error = driving.wrap(wall - axis - quarter * round(driving.wrap(wall - axis) / quarter))
        if abs(error) < _SNAP:
            self.pose = self.pose._replace(theta_rad=self.pose.theta_rad - error)
            self.trail.turned(-error)
            self.anchored += 1


class NoFrontier:
    """What ``cover`` does once no frontier is left: an edge again, unless two edges in a
    row found nothing new (:data:`_EDGE_NEW_CELLS`); then the way out past what it met
    (:meth:`FloorMap.escape`), after which the edges start over (the robot is out among the
    room's walls); then another pass (``passes``: :meth:`next_pass`), or done. An escape that found
    next to nothing by the next one (a leg's far side, floor behind a wall its map has a
    gap in) counts, and after
    :data:`_FUTILE_ESCAPES` of them in a row the floor is done all the same."""

    def __init__(self) -> None:
        self._start_over()

    def _start_over(self) -> None:
        """A pass begins: no edge, no escape yet."""
        self._idle_edges = 0  # edges in a row that followed no frontier
        self._swept = -1 - _EDGE_NEW_CELLS  # the map's swept count when the last one started
        self._futile = 0  # escapes in a row that found next to no floor
        self._bumps = 0  # bumps on the way of the last escape
        self._row: list[int] = []  # the bumps of each escape in that row
        #: why it found no way out, said with the floor its map left (:meth:`path_out`)
        self.why = ""

    def edge_again(self, edge_found: int) -> bool:
        """Is another edge worth it, the last one having found ``edge_found`` new cells?"""
        if edge_found > _EDGE_NEW_CELLS:
            self._idle_edges = 0
        if self._idle_edges >= 2:
            return False
        self._idle_edges += 1
        return True

    def path_out(self, fmap: FloorMap, here: Cell | None) -> list[Cell] | None:
        """The path out from ``here``, or None: the floor is done. On a map closed on less
        than :data:`_ISLAND_CELLS`, the way out to open floor past what it met
        (:meth:`FloorMap.escape`); on a larger one, the nearest frontier across the ghost
        walls on its map (:meth:`FloorMap.frontier`, ``through_ghosts``).

        Why the second: with the encoders' error each visit draws a wall a few centimetres
        off, across floor it drove, and those cells cut its map in parts; from where it
        stood the frontier search would find none, though its map had open floor beside 141
        cells elsewhere, and the floor be done: the apartment, seed 2 with 1.5 % error,
        would end at 852 s with the bedroom never entered. Over floor it swept or
        drove, crossing only blocked cells its centre has been on, never a drop's; in the
        first pass only (a later pass's cells it has been on are an earlier pass's, in a
        frame drifted since)."""
        if here is None:
            return None
        if fmap.swept - self._swept <= _EDGE_NEW_CELLS:
            self._futile += 1
            self._row.append(self._bumps)
        else:
            self._futile, self._row = 0, []
        if self._futile > _FUTILE_ESCAPES:
            self.why = self._futile_said()
            return None
        path = self._way_out(fmap, here)
        if path is not None:
            self._swept = fmap.swept
            self._idle_edges = 0  # out among the walls there: edges are worth it again
            self._bumps = 0
        elif fmap.swept < _ISLAND_CELLS:
            self.why = "what it met closes it off on its map (no gap it fits through)"
        elif fmap.passes == 1:
            self.why = "no way over floor it swept or drove leads there"
        else:
            self.why = "a later pass does not cross the walls its map drew"
        return path

    def _futile_said(self) -> str:
        """The tries that made the floor done: how many, and what they bumped into."""
        tries = len(self._row)
        said = f"its last {tries} ways out toward open floor found next to none"
        bumped = sum(1 for bumps in self._row if bumps)
        if bumped:
            which = "each" if bumped == tries else f"{bumped} of them"
            said += (
                f", {which} bumping into something not on its map on the way (legs closer "
                f"together than the robot's {2 * _RADIUS_MM / 10:.0f} cm?)"
            )
        return said

    def bumped(self) -> None:
        """A leg of the last way out bumped into something its map did not have when the
        way was planned (the leg's cell is avoided, and the next decision made): said with
        the floor left when such tries end it (:meth:`_futile_said`).

        Why: among chairs each way out to the open floor past their legs bumped a leg (a
        3 cm leg the light bumper misses) a few centimetres into its first leg; the floor
        was done after three, and the owner read "(a door its map closed?)" in a dining
        room with no door (chairs-apart.yaml, seed 12: 20.7 % of the room)."""
        self._bumps += 1

    @staticmethod
    def _way_out(fmap: FloorMap, here: Cell) -> list[Cell] | None:
        """:meth:`path_out`'s search: past what it met on a small map, across the ghost
        walls on a larger one."""
        if fmap.swept >= _ISLAND_CELLS:
            if fmap.passes > 1:  # the cells it has been on are an earlier pass's, drifted
                return None  # (a box's second pass, 2 % error, stood 169 s on such ways)
            return fmap.frontier(here, through_near=True, through_ghosts=True)
        return fmap.escape(here)

    def next_pass(self, fmap: FloorMap, passes: float) -> bool:
        """The floor is done by its map: a pass again on the map drawn afresh
        (:meth:`FloorMap.next_pass`), from a clean slate here too (True), unless ``passes``
        have been made (False: done)."""
        if fmap.passes >= passes:
            return False
        fmap.next_pass()
        self._start_over()
        return True


# Cover is long on purpose (about 400 lines): it is one leaf's phase machine (seek, edge,
# lanes, arcs, paths, back-offs) over one state; what it knows and decides apart from its
# phases already lives in FloorMap, Bearings, NoFrontier and the drops' DropEdge.
@declare(
    "cover",
    kind="action",
    params=(
        wheel_speed_param("speed", "300 mm/s", minimum=50, doc="driving speed on lanes and edges"),
        wheel_speed_param("turn_speed", "300 mm/s", minimum=20,
                          doc="wheel speed when turning in place"),
        Param("shift_left", DISTANCE, default="15 cm", minimum=50, maximum=500,
              doc="lane spacing when the next lane is to the robot's left (the strip "
                  "reaches 9 cm to the left of the centre)"),
        Param("shift_right", DISTANCE, default="32 cm", minimum=50, maximum=500,
              doc="lane spacing when the next lane is to the robot's right (the side "
                  "brush's side: 18.5 cm)"),
        Param("edge_distance", DISTANCE, default="18 cm", minimum=150, maximum=400,
              doc="the centre's distance from a wall followed on the right (the side brush "
                  "reaches 18.5 cm)"),
        Param("edge_time", DURATION, default="3min", minimum=5,
              doc="an edge ends after this long even if it still finds new floor"),
        Param("passes", INT, default=1, minimum=1,
              doc="passes over the floor: when its map says the floor is done, another "
                  "on a map of the walls drawn afresh (the encoders' drift closes the "
                  "first early)"),
        Param("unreached", STR, from_blackboard=False,
              doc="a bool key written when the floor is done: true when its map still "
                  "shows unswept floor it found no way to (its message says how much, "
                  "where, and what stopped its ways there), "
                  "for the mission to say so"),
    ),
    reads=MAP_READS,
    writes_keys={"unreached": BOOL},
    sends=opcodes("drive_direct", "drive"),
)  # fmt: skip
class Cover(Action):
    """Cover the floor with a map of its own (odometry and bumps, 10 cm cells): an edge,
    lanes where the floor is open, the nearest unswept floor next (a breadth-first search
    on its map), edges where the frontier is a wall; ``passes`` over the floor. SUCCESS
    when nothing reachable is left unswept (its message: the floor it swept); FAILURE on a
    wheel drop or when the robot leaves Safe/Full (started again, it goes on with its map).
    Drive Direct (145)."""

    moves = True

    #: a drop to Passive ended it: started again, its phase meets the hazard (as in Full)
    _interrupted = False
    #: how much (mm) of the last back-off the floor behind did not allow (:meth:`_back`)
    _short = 0.0
    _progress: tuple[float, float] = (0.0, 0.0)  # along a line (mm), when it last grew

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)  # a new run: its floor is not known yet
        storage = py_trees.blackboard.Blackboard.storage
        storage.pop(run_board().name(MAP_KEY), None)
        storage.pop(run_board().name(WAY_KEY), None)
        self._interrupted = False

    def start(self) -> None:
        """The first start in a run: ahead to a wall, an edge. A later one goes on with
        :data:`MAP_KEY`'s map and pose; after a drop to Passive, with its plan too (else
        off the hazard it meets, a turn, and the nearest unswept floor)."""
        bearings, kept = Bearings.of_run(odo := self.snapshot.odometry)
        self._bearings, self._map = bearings, bearings.map
        if kept and self._interrupted:
            self._interrupted = False
            self._since = now = self.snapshot.time  # its timers skip the time in Passive
            self._progress = (self._progress[0], now)
            return
        self._plan: list[Callable[[], None]] = []
        self._edge_found = 0  # new cells the last edge found
        self._way_out = False  # the path driven now is a way out (NoFrontier.path_out)
        self._no_frontier = NoFrontier()
        self._line: driving.Line = (odo.x_mm, odo.y_mm, odo.theta_rad)
        self._phase = ""
        why = driving.blocked(self.snapshot.frame) if kept else None
        if not kept:
            self._seek(then_edge=True)
        elif why in driving.BACK_OFF_MM:  # ahead again, it met the same hazard again
            self._plan.extend((self._onto_right, self._decide))
            self._back(driving.BACK_OFF_MM[why])
        else:
            self._decide()

    # ------------------------------------------------------------------ the tick

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        bearings = self._bearings
        bearings.integrate(snap.odometry, snap.time)
        bearings.observe(frame)  # a cliff is mapped in the tick it shows, in Passive too
        waiting = driving.held(self, 0.0 if frame.any_cliff else None)  # module doc: Safe
        if waiting is not None:
            self._interrupted = waiting is Status.FAILURE and not frame.any_wheel_drop
            return waiting
        for _ in range(6):
            if self._phase == "done":
                self.send(oi.halt())
                self._started_motion = False
                fmap = self._map
                pose = self._pose
                left = fmap.left_unreached(pose.x_mm, pose.y_mm, self._no_frontier.why)
                self.feedback_message = fmap.floor_done(left)
                if left:  # floor left on its map: the run's log says it, as a warning
                    _log.warning("%s: %s", self.name, self.feedback_message)
                self._said_unreached(bool(left))
                return _OK
            wheels = self._step(frame)
            if wheels is not None:
                self.send(driving.drive_wheels(*wheels))
                self._started_motion = True
                return _RUN
        self.send(driving.drive_wheels(0.0, 0.0))
        return _RUN

    def _said_unreached(self, left: bool) -> None:
        """Write ``left`` (its map shows floor it found no way to) to the ``unreached`` key,
        where one is given.

        Why: the warning and this leaf's message were all that said it, and the run
        summary's ``mission said`` line, the mission's last ``log``, read "cleaning stopped:
        the floor is done" over a bedroom never entered; with the key the mission's own
        ``log`` says it (missions/clean.yaml)."""
        key = self.value("unreached")
        if key is not None:
            write_key(str(key), left, self.name)

    @property
    def _pose(self) -> Odometry:
        """Its own pose, as :class:`Bearings` keeps it."""
        return self._bearings.pose

    def _step(self, frame: SensorFrame) -> tuple[float, float] | None:
        """This tick's wheel speeds in the current phase; None: the phase ended (the next
        one is set up), look again."""
        phase = self._phase
        if phase == "turn":
            return self._turning()
        if phase == "edge":
            return self._edging(frame)
        if phase == "back":
            return self._backing()
        if phase == "uturn":
            return self._uturning(frame)
        return self._driving(frame)

    def _next(self) -> None:
        """The phase ended: the plan's next step, or a new decision."""
        if self._plan:
            self._plan.pop(0)()
        else:
            self._decide()

    # ------------------------------------------------------------------ phases

    def _turn_to(self, heading: float) -> None:
        self._phase, self._heading = "turn", heading
        self._since = self.snapshot.time

    def _turning(self) -> tuple[float, float] | None:
        error = driving.wrap(self._heading - self._pose.theta_rad)
        now = self.snapshot.time
        wheels = driving.turning_to(error, self._since, now, self.number("turn_speed"))
        if wheels is None:
            self._next()
        return wheels

    def _back(self, distance: float) -> None:
        """Back up ``distance`` mm, or as much of it as runs over floor it has just driven
        (the first :data:`~.reversing.OWN_MM` aside: under its own body) with no known drop
        behind (:mod:`.reversing`: it sees nothing behind it); what it could not is
        :attr:`_short`."""
        odo = self._pose
        allowed = self._bearings.reversible(distance, reversing.OWN_MM)
        self._short = distance - allowed
        self._phase, self._back_to = "back", odo.distance_mm - allowed
        self._since = self.snapshot.time

    def _backing(self) -> tuple[float, float] | None:
        if driving.backing_to(
            self._pose.distance_mm, self._back_to, self._since, self.snapshot.time
        ):
            return (-driving.BACK_MM_S, -driving.BACK_MM_S)
        self._next()
        return None

    def _drive(
        self, kind: str, heading: float, limit: float, through: tuple[float, float] | None = None
    ) -> None:
        """Drive a straight line along ``heading`` (through a point, or from here): a lane,
        a shift, a leg of a path (``goto``), or ``seek`` (ahead to the first obstacle)."""
        odo = self._pose
        self._phase, self._kind, self._limit = "drive", kind, limit
        x, y = through if through is not None else (odo.x_mm, odo.y_mm)
        self._line = (x, y, heading)
        self._progress = (0.0, self.snapshot.time)
        self._yield = (self._map.swept, 0.0)  # swept counter, distance when it last grew
        self._achieved = 0.0

    def _driving(self, frame: SensorFrame) -> tuple[float, float] | None:
        snap = self.snapshot
        pose = self._pose
        along, _ = driving.along_line(self._line, pose.x_mm, pose.y_mm)
        if along > self._progress[0] + driving.PROGRESS_MM:
            self._progress = (along, snap.time)
        if self._map.swept != self._yield[0]:
            self._yield = (self._map.swept, along)
        why = driving.blocked(frame)
        kind = self._kind
        if why is None:
            if snap.time - self._progress[1] >= driving.STALL_S:
                why = "stalled"
            elif along >= self._limit:
                why = "limit"
            elif kind == "lane" and along - self._yield[1] > _NO_YIELD_MM:
                why = "swept"
            elif kind in ("lane", "shift") and self._bearings.blocked_ahead(self._line[2]):
                why = "map"
            elif self._map.drops.ahead(pose, pose.theta_rad, guessed=kind != "goto"):
                why = "drop"  # known: not met again (drops.py)
        if why is None:
            speed = self.number("speed")
            if kind == "shift" or kind == "goto":
                speed = min(speed, 250.0)
            if driving.near_ahead(frame):
                speed = min(speed, 150.0)
            speed = self._map.drops.speed(pose, pose.theta_rad, speed)
            return driving.steer_along(self._line, pose.x_mm, pose.y_mm, pose.theta_rad, speed)
        self._achieved = along
        self._why = why
        if why in driving.BACK_OFF_MM:
            self._plan.insert(0, self._ended)
            self._back(driving.BACK_OFF_MM[why])
        else:
            self._ended()
        return None

    def _ended(self) -> None:
        """A straight line ended (``self._why``, after ``self._achieved`` mm)."""
        kind = self._kind
        if kind == "lane":
            self._lane_ended()
        elif kind == "shift":
            if self._achieved < 0.5 * self._limit:
                self._plan.clear()
                self._decide()
            else:
                self._lane(driving.wrap(self._lane_heading + math.pi))
        elif kind == "goto":
            if self._why == "drop" and self._achieved < _NO_START_MM:
                # a known drop kept the leg from starting: that way is not planned again
                # (after the move clear the same path would lead back to it, 514 s: apartment
                # seed 9, 1.5 % error), and away from the drop first
                self._map.avoid.add(self._goto_cell)
                if self._clear_of_drop():
                    return
            if self._why not in ("limit", "drop"):  # blocked on the way: decide again
                # from here (a known drop: this leg ends short of it, the path goes on)
                if self._why in driving.BACK_OFF_MM:  # met something: no path that way again
                    self._map.avoid.add(self._goto_cell)  # (it bumped into it, path after path)
                self._plan.clear()
                if self._why == "bump" and self._way_out:
                    self._no_frontier.bumped()
                self._decide()
            else:
                self._next()
        elif kind == "clear":
            if self._why == "drop" and self._achieved < _NO_START_MM:
                # away from the drop was no way either: that leg's way is not taken again
                self._map.avoid.add(self._goto_cell)
            self._next()
        else:  # seek
            self._next()

    def _clear_of_drop(self) -> bool:
        """Turn straight away from the known drop that kept a leg of the path from starting
        and drive :data:`_CLEAR_MM` that way (forward: its cliff sensors look ahead), then
        decide again; False when no drop is near (the path goes on as before).

        Why: a back-off goes only over floor just driven (:mod:`.reversing`), so the robot
        is left closer to a drop than a blind back-off leaves it (15 cm from the apartment's
        stairs); every leg of the path to unswept floor that runs along the drop then ends
        in its first tick (the drop within a cliff sensor's look-ahead), the path's next leg
        too, and the same path is planned again: living room seed 2 with 1.5 % encoder
        error would stand 164 s without new floor, 656 s in.

        A move clear that a drop ends before it starts too (a drop, or a guess of one, the
        other way as well) puts the leg's cell in :attr:`FloorMap.avoid`: else the path is
        planned again through it, leg, turn, no move, for 94 s (living room seed 24, exact
        encoders, by the stairs)."""
        away = self._map.drops.away(self._pose)
        if away is None:
            return False
        self._plan.clear()
        self._plan.extend((lambda: self._drive("clear", away, _CLEAR_MM), self._decide))
        self._turn_to(away)
        return True

    # ------------------------------------------------------------------ edges

    def _edge(self) -> None:
        """Follow the wall on the right until it gives no new floor for a while."""
        snap = self.snapshot
        self._phase = "edge"
        self._edge_start = (snap.time, self._map.swept)
        self._edge_yield = (self._map.swept, self._pose.path_mm)
        self._edge_recovery: tuple[str, float, float, str] | None = None
        self._steering = EdgeSteering()
        self._drop_edge = DropEdge(self._map.drops)
        self._bearings.off_wall()
        odo = self._pose
        self._edge_mark = (odo.x_mm, odo.y_mm, odo.angle_rad, odo.angle_rad, snap.time)

    def _edging(self, frame: SensorFrame) -> tuple[float, float] | None:
        snap = self.snapshot
        odo = self._pose
        if self._map.swept != self._edge_yield[0]:
            self._edge_yield = (self._map.swept, odo.path_mm)
        if odo.path_mm - self._edge_yield[1] > _EDGE_NO_YIELD_MM or snap.time - self._edge_start[
            0
        ] > float(self.value("edge_time")):
            self._edge_done()
            self._next()
            return None
        held = self._edge_held(odo, snap.time)
        if held is not None:  # nowhere to go on from here: the edge ends
            self._edge_done()
            if held == "stalled":  # off what holds it first, as off a bump
                self._back(driving.BACK_OFF_MM["bump"])
            else:
                self._next()
            return None
        speed = self.number("speed")
        recovery = self._edge_recovery
        why = driving.blocked(frame)
        if why is not None and (recovery is None or recovery[0] == "turn"):
            # a bump, a drop or a beam: back off, turn left, go on along it
            recovery = self._edge_recovery = ("back", odo.distance_mm, snap.time, why)
            self._edge_back = self._bearings.reversible(driving.BACK_OFF_MM[why], reversing.OWN_MM)
            self._bearings.off_wall()
        if recovery is not None:
            phase, mark, since, cause = recovery
            if phase == "back":
                if mark - odo.distance_mm < self._edge_back and snap.time - since < 1.5:
                    return (-150.0, -150.0)
                recovery = self._edge_recovery = ("turn", odo.angle_rad, snap.time, cause)
                phase, mark, since, cause = recovery
            turn = math.radians(35.0 if cause == "bump" else 60.0)
            turned = odo.angle_rad - mark
            if cause == "cliff" and self._drop_edge.along(odo, turned):
                turned = turn  # along the drop it just mapped: the steering takes it on
            if turned < turn and snap.time - since < 3.0:
                return (-150.0, 150.0)
            self._edge_recovery = None
            self._steering.reset()
        signals, speed = self._drop_edge.view(frame, odo, speed)  # known drops as walls
        left, right, error = self._steering.wheels(
            signals, speed, self.number("edge_distance"), snap.time
        )
        if error is None:  # turning at a wall ahead, or no wall on the right
            self._bearings.off_wall()
        else:
            self._bearings.anchor(odo.path_mm, odo.theta_rad, abs(error) < 15.0)
        return left, right

    def _edge_held(self, odo: Odometry, now: float) -> str | None:
        """Has the edge stopped getting anywhere? ``"stalled"``: its centre has moved less
        than :data:`~.driving.PROGRESS_MM` and turned less than :data:`_EDGE_TURNING` for
        :data:`~.driving.STALL_S`; ``"closed in"``: it has turned a whole turn in place (a
        wall ahead whichever way it faces); else None.

        Why: an edge ends by the floor it finds (:data:`_EDGE_NO_YIELD_MM` of path) or after
        ``edge_time``, and neither comes to a robot that does not move. Living room seed 22
        (exact encoders) would stand 180 s with its side against the plant, the wheels
        driven and held, no bump; the apartment, seed 0 with 1.5 % error, would turn in place
        for two edges of 180 s each among the stairs' drops on its map, each a wall to the
        edge whichever way it faced (376 s without new floor)."""
        x, y, angle, turned, since = self._edge_mark
        if math.hypot(odo.x_mm - x, odo.y_mm - y) > driving.PROGRESS_MM:
            self._edge_mark = (odo.x_mm, odo.y_mm, odo.angle_rad, odo.angle_rad, now)
            return None
        if abs(odo.angle_rad - angle) >= math.tau:
            return "closed in"
        if abs(odo.angle_rad - turned) > _EDGE_TURNING:  # turning in place: not held
            self._edge_mark = (x, y, angle, odo.angle_rad, now)
            return None
        return "stalled" if now - since >= driving.STALL_S else None

    def _edge_done(self) -> None:
        """An edge ends: how much new floor it found decides whether another is worth it."""
        self._edge_found = self._map.swept - self._edge_start[1]

    # ------------------------------------------------------------------ lanes

    def _lanes(self) -> None:
        """Start sweeping lanes from here: along the axis, the way with most open floor."""
        odo = self._pose
        axis = self._bearings.axis
        if axis is None:
            axis = odo.theta_rad
        x, y = odo.x_mm, odo.y_mm
        options = [driving.wrap(axis + k * math.pi / 2) for k in range(4)]
        score = {h: self._map.open_along(x, y, h, 1500.0) for h in options}
        heading = max(options, key=lambda h: (score[h], -abs(driving.wrap(h - odo.theta_rad))))
        left = driving.wrap(heading + math.pi / 2)
        right = driving.wrap(heading - math.pi / 2)
        # advance to the side with more open floor (looked at beside the first lane)
        self._advance = left if self._side_open(left) >= self._side_open(right) else right
        self._lane(heading)

    def _side_open(self, direction: float) -> int:
        odo = self._pose
        total = 0
        for k in (1, 2, 3):
            d = k * 250.0
            x = odo.x_mm + d * math.cos(direction)
            y = odo.y_mm + d * math.sin(direction)
            for h in (direction + math.pi / 2, direction - math.pi / 2):
                total += self._map.open_along(x, y, h, 1000.0)
        return total

    def _uturn(
        self, heading: float, shift: float, side: float, through: tuple[float, float]
    ) -> None:
        """Half a turn on an arc of ``shift`` wide toward ``side`` (+1 left, -1 right) onto
        the next lane, along ``heading`` through ``through``: a turn in place, a move over and
        another turn took three times as long. An arc needs its radius clear ahead: backed
        up to it when the floor behind is floor just driven (:mod:`.reversing`), else back
        as far as that floor goes (the turn's room from what ended the lane: a turn in
        place with a cliff showing is the firmware's stop in Safe mode), the turn in place,
        the move over and the turn (its blind back onto the stairs dropped a wheel: a lane
        that ended where it began, after a turn in place)."""
        radius = shift / 2.0
        room = radius + 20.0 - driving.BACK_OFF_MM.get(self._why, 0.0) + self._short
        if self._why in ("swept", "limit", "stalled"):
            room = 0.0
        allowed = self._bearings.reversible(room) if room > 0.0 else 0.0
        if allowed < room:  # back what it may (the turn's room from the edge), then over
            self._lane_heading = driving.wrap(heading + math.pi)  # the shift's end turns it
            self._plan[:0] = (
                lambda: self._turn_to(self._advance),
                lambda: self._drive("shift", self._advance, shift),
            )
            self._back(allowed)
            return
        self._lane_heading = heading

        def arc() -> None:
            self._phase, self._arc = "uturn", (radius, side, self._pose.angle_rad)
            self._since = self.snapshot.time

        self._plan.insert(0, lambda: self._drive("lane", heading, 12_000.0, through))
        if room > 0.0:
            self._plan.insert(0, arc)
            self._back(room)
        else:
            arc()

    def _uturning(self, frame: SensorFrame) -> tuple[float, float] | None:
        radius, side, start = self._arc
        turned = side * (self._pose.angle_rad - start)
        why = driving.blocked(frame)
        if why is None and self._map.drops.ahead(self._pose, self._pose.theta_rad):
            why = "drop"  # a known drop in the arc's way: not met again
        if why is not None or self.snapshot.time - self._since > 6.0:
            self._plan.clear()  # something beside the lane: decide again from here
            self._why = why or "stalled"
            if why in driving.BACK_OFF_MM:
                self._plan.append(self._decide)
                self._back(driving.BACK_OFF_MM[why])
            else:
                self._decide()
            return None
        if turned >= math.pi - driving.TURN_TOLERANCE:
            self._next()
            return None
        outer = radius + _HALF_BASE_MM
        speed = min(self.number("speed"), WHEEL.maximum * radius / outer, 250.0)
        inner_wheel, outer_wheel = driving.arc_wheels(speed, radius, _HALF_BASE_MM)
        return (inner_wheel, outer_wheel) if side > 0 else (outer_wheel, inner_wheel)

    def _lane(self, heading: float) -> None:
        self._lane_heading = heading
        self._plan.insert(0, lambda: self._drive("lane", heading, 12_000.0))
        self._turn_to(heading)

    def _lane_ended(self) -> None:
        heading = self._lane_heading
        advance = self._advance
        to_left = driving.wrap(advance - heading) > 0
        shift = self.number("shift_left" if to_left else "shift_right")
        odo = self._pose
        x = odo.x_mm + shift * math.cos(advance)
        y = odo.y_mm + shift * math.sin(advance)
        back = driving.wrap(heading + math.pi)
        if self._map.open_along(x, y, back, 1500.0) < 2:
            self._plan.clear()
            self._decide()  # nothing beside this lane: the region is done
            return
        self._uturn(back, shift, 1.0 if to_left else -1.0, (x, y))

    # ------------------------------------------------------------------ decisions

    def _seek(self, then_edge: bool) -> None:
        """Straight ahead to the first obstacle; then turn it onto the right and edge."""
        heading = self._pose.theta_rad
        if then_edge:
            self._plan.extend((self._onto_right, self._edge))
        self._drive("seek", heading, 8_000.0)

    def _onto_right(self) -> None:
        self._turn_to(driving.wrap(self._pose.theta_rad + math.radians(75.0)))

    def _decide(self) -> None:
        """Where next: the nearest frontier, or an edge, or done."""
        odo = self._pose
        here = self._map.cell(odo.x_mm, odo.y_mm)
        self._way_out = False
        path = None
        if here is not None:
            path = self._map.frontier(here) or self._map.frontier(here, through_near=True)
        if path is None:
            edge_found, self._edge_found = self._edge_found, 0
            if self._no_frontier.edge_again(edge_found):
                self._seek(then_edge=True)
                return
            path = self._no_frontier.path_out(self._map, here)
            if path is None:
                if self._no_frontier.next_pass(self._map, self.number("passes")):
                    self._seek(then_edge=True)  # as the first pass started
                else:
                    self._phase = "done"
                return
            self._way_out = True
        target = path[-1]
        waypoints = self._map.waypoints(path)
        self._map.cells[target] |= TRIED  # once reached, its lanes decide; never again
        for cell in waypoints:
            self._plan.append(partial(self._go, cell))
        self._plan.append(self._lanes)
        self._next()

    def _go(self, cell: Cell) -> None:
        self._goto_cell = cell
        odo = self._pose
        x, y = self._map.centre(cell)
        dx, dy = x - odo.x_mm, y - odo.y_mm
        distance = math.hypot(dx, dy)
        if distance < 40.0:
            self._next()
            return
        heading = math.atan2(dy, dx)
        self._plan.insert(0, lambda: self._drive("goto", heading, distance))
        self._turn_to(heading)


COVERAGE: tuple[type[Action], ...] = (Cover,)
