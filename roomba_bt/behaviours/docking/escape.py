"""How ``dock_search`` notices it is trapped, and the way out it then drives.

A chair's four legs stand about 40 cm apart: a 34 cm robot drives in between two of them by
chance, and inside, every heading but the one it came in by meets a leg. The search's rule
(back off a bump, choose the least visited heading, drive on) then bumps about in a 37 cm
space until the time limit (a floor owner's dining room, ``tests/data/dining.yaml``: ten
minutes under chair N2). The way in is the one way out the robot knows of, and it knows it
from its odometry alone: :class:`Trail` keeps where the robot has been (a crumb every
:data:`CRUMB_MM` of path), says when the search has stayed near one point for long with many
hazards met there (:meth:`Trail.met_hazard`), and gives the crumbs back to a point clear of
the trap (:meth:`Trail.way_back`). Every crumb is a place the robot stood, so that way
touches nothing the way in did not. :func:`plan_way_out` makes of it the way the search
drives: back to the line it came in by, then on along it through the trap; the rest of the
way back is kept for when that line is shut.
"""

from __future__ import annotations

import math
from collections import deque

from roomba_bt.robot.interface import Odometry

Point = tuple[float, float]

#: a crumb of the trail every this much path (mm): fine enough for a gap 3 cm wider than the
#: robot, where the way in is the line through it
CRUMB_MM = 20.0
#: crumbs kept: the last 40 m of the way, far more than a trap's tangle and the way into it
CRUMBS_KEPT = 2000
#: trapped: within this distance (mm) of one point (a 0.5 m circle) ...
TRAPPED_RADIUS_MM = 250.0
#: ... for this long (s) ...
TRAPPED_S = 30.0
#: ... meeting this many hazards there (a wall follow along a short wall meets two or three;
#: inside a chair the search meets one every two or three seconds)
TRAPPED_HAZARDS = 10
#: the way out ends at the first crumb (going back) this far (mm) from the trap's centre: the
#: robot's diameter beyond the circle, clear of the legs that held it
CLEAR_OF_TRAP_MM = 600.0
#: two crumbs in the same or neighbouring squares of this side (mm), at most 6 cm apart, are
#: joined and the loop between them left out: the robot stood at both, and what lies between
#: two places a 34 cm disc stood 6 cm apart is at most 2.3 mm from both (no leg fits there)
JOIN_MM = 20.0
#: the line on through the trap is tried up to this far (mm) from where it left the circle
THROUGH_MM = 1200.0
#: crumbs closer than this (mm) to the straight line between two kept ones are left out: the
#: way out is driven as straight lines between the corners of the way in
STRAIGHT_WITHIN_MM = 5.0
#: a point of the way out counts as reached this close (mm), or this close and behind
REACHED_MM = 8.0
PASSED_MM = 30.0
#: hazards met on the way out (off the line through) before it is given up
WAY_BUMPS = 3


#: a crumb: where the robot was (mm, odometry frame) and when (s)
Crumb = tuple[float, float, float]
#: where a leaf that drives before the search keeps the robot's way for the run (a
#: :class:`Way` on py_trees' blackboard: ``cover`` and ``home_by_map``); the search's trail
#: begins with it, so the way into a trap the search starts in is known
WAY_KEY = "/roomba/way"


class Way:
    """The robot's way as crumbs, one every :data:`CRUMB_MM` of path (odometry frame), kept
    by a leaf that drives before the search (:data:`WAY_KEY`).

    Why: ``cover`` ended between a chair's legs (chairs-apart.yaml, seeds 0 and 2); the
    search, its trail begun there, found itself trapped, and its way out back the way it
    came led to where it started, inside: it bounced among the legs for its 10 minutes."""

    def __init__(self) -> None:
        self.crumbs: deque[Crumb] = deque(maxlen=CRUMBS_KEPT)
        self._next_at = 0.0

    def add(self, odo: Odometry, now: float) -> None:
        """A crumb where the robot is, when its path has grown by :data:`CRUMB_MM`."""
        if odo.path_mm >= self._next_at:
            self._next_at = odo.path_mm + CRUMB_MM
            self.crumbs.append((odo.x_mm, odo.y_mm, now))


class Trail:
    """The robot's recent way (odometry frame), and whether it is trapped in a small space.

    The search appends a crumb to :attr:`crumbs` each time its path has grown by
    :data:`CRUMB_MM` (inline, on the tick path: one comparison a tick, an append every few);
    all the rest is worked out when a hazard is met (:meth:`met_hazard`), a few times a
    minute. The trap's centre is the middle of the crumbs of the stay that trapped it."""

    def __init__(self) -> None:
        self.crumbs: deque[Crumb] = deque(maxlen=CRUMBS_KEPT)
        #: when the last :data:`TRAPPED_HAZARDS` hazards were met (s)
        self._hazards: deque[float] = deque(maxlen=TRAPPED_HAZARDS)
        self.centre: Point = (0.0, 0.0)
        #: when its own crumbs begin: those before (a way kept before the search, :class:`Way`)
        #: lead out of a trap but make no stay in one
        self.own_from = -math.inf

    def restart(self) -> None:
        """A new count (a search started, or a way out driven): the hazards met before no
        longer count toward a trap."""
        self._hazards.clear()

    def met_hazard(self, odo: Odometry, now: float) -> bool:
        """Note a hazard met: True (the trap's centre noted) when
        :data:`TRAPPED_HAZARDS` were met in the last :data:`TRAPPED_S` and the robot was
        within :data:`TRAPPED_RADIUS_MM` of here all that time (time to leave)."""
        hazards = self._hazards
        hazards.append(now)
        since = now - TRAPPED_S
        if len(hazards) < TRAPPED_HAZARDS or hazards[0] < since:
            return False
        x, y = odo.x_mm, odo.y_mm
        stay: list[Crumb] = []
        for crumb in reversed(self.crumbs):
            crumb_x, crumb_y, then = crumb
            if (
                then < self.own_from
                or (crumb_x - x) ** 2 + (crumb_y - y) ** 2 > TRAPPED_RADIUS_MM**2
            ):
                return False
            stay.append(crumb)
            if then <= since:
                # the middle of where it moved: a chair's middle, whichever leg it is at
                self.centre = (
                    sum(crumb[0] for crumb in stay) / len(stay),
                    sum(crumb[1] for crumb in stay) / len(stay),
                )
                return True
        return False  # the trail is younger than a stay

    def way_back(self, odo: Odometry) -> list[Point]:
        """The crumbs back to the first one :data:`CLEAR_OF_TRAP_MM` from the trap's centre
        (or the oldest kept), loops left out and straight runs reduced to their ends, in the
        order driven: the robot's place first, the point clear of the trap last."""
        crumbs = [(x, y) for x, y, _ in self.crumbs]
        crumbs.append((odo.x_mm, odo.y_mm))
        # the earliest crumb in each square: going back, a loop since then is left out
        earliest: dict[tuple[int, int], int] = {}
        for index, point in enumerate(crumbs):
            earliest.setdefault(_square(point), index)
        ax, ay = self.centre
        way: list[Point] = []
        index = len(crumbs) - 1
        while index >= 0:
            sx, sy = _square(crumbs[index])
            index = min(
                earliest.get((sx + dx, sy + dy), index) for dx in (-1, 0, 1) for dy in (-1, 0, 1)
            )
            x, y = crumbs[index]
            way.append((x, y))
            if math.hypot(x - ax, y - ay) >= CLEAR_OF_TRAP_MM:
                break
            index -= 1
        return straightened(way)


def plan_way_out(way_back: list[Point], trap: Point) -> tuple[list[Point], list[Point]]:
    """The way out of the trap centred on ``trap``, and the way back should it be blocked,
    each with the next point last (popped as each is reached).

    The way out goes back to the straight line the robot came into the trap's circle by, and
    on along it, :data:`THROUGH_MM` from where it crossed the circle: a chair's far gap lies
    on that line when the robot came in square to the chair, and beyond it is open floor,
    where the way back may lead only into a table's cage of chairs (``tests/data/dining.yaml``:
    under the table every way out is through a chair). The way back is the rest of
    ``way_back``, from where that line crossed the circle."""
    tx, ty = trap
    outside = [
        index
        for index, (x, y) in enumerate(way_back)
        if (x - tx) ** 2 + (y - ty) ** 2 > TRAPPED_RADIUS_MM**2
    ]
    if not outside or outside[0] == 0:
        return way_back[::-1], []
    crossed = outside[0]
    (ox, oy), (ix, iy) = way_back[crossed], way_back[crossed - 1]
    length = math.hypot(ix - ox, iy - oy)
    through = (ox + (ix - ox) / length * THROUGH_MM, oy + (iy - oy) / length * THROUGH_MM)
    return [through, *way_back[crossed - 1 :: -1]], way_back[: crossed - 1 : -1]


def _square(point: Point) -> tuple[int, int]:
    return (math.floor(point[0] / JOIN_MM), math.floor(point[1] / JOIN_MM))


def straightened(way: list[Point]) -> list[Point]:
    """``way`` with the points within :data:`STRAIGHT_WITHIN_MM` of the line between their
    neighbours left out (Douglas-Peucker, with a stack rather than recursion: a straight
    leg of the trail is hundreds of crumbs); the first and last are always kept."""
    if len(way) < 3:
        return list(way)
    keep = [False] * len(way)
    keep[0] = keep[-1] = True
    spans = [(0, len(way) - 1)]
    while spans:
        first, last = spans.pop()
        (x0, y0), (x1, y1) = way[first], way[last]
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        farthest, far_index = 0.0, first
        for index in range(first + 1, last):
            px, py = way[index]
            if length:
                off = abs(dx * (py - y0) - dy * (px - x0)) / length
            else:
                off = math.hypot(px - x0, py - y0)
            if off > farthest:
                farthest, far_index = off, index
        if farthest > STRAIGHT_WITHIN_MM:
            keep[far_index] = True
            spans += [(first, far_index), (far_index, last)]
    return [point for point, kept in zip(way, keep, strict=True) if kept]


class WayOut:
    """The way out of one trap (:func:`plan_way_out`), driven point by point by the search:
    which point is next, and what a hazard met on the way means."""

    def __init__(self, trail: Trail, odo: Odometry) -> None:
        self.trap = trail.centre
        self.way, self.retreat = plan_way_out(trail.way_back(odo), self.trap)
        #: facing the next point (the search turns in place until it is)
        self.aimed = False
        self._hazards = 0

    def turn_to_next(self, odo: Odometry) -> float | None:
        """How far (rad, counter-clockwise positive) the robot is to turn to face the next
        point, the points reached (or just passed) dropped; None once clear of the trap
        (:data:`CLEAR_OF_TRAP_MM` from its centre) or at the way's end."""
        way = self.way
        trap_x, trap_y = self.trap
        while way and math.hypot(odo.x_mm - trap_x, odo.y_mm - trap_y) < CLEAR_OF_TRAP_MM:
            x, y = way[-1]
            dx, dy = x - odo.x_mm, y - odo.y_mm
            distance = math.hypot(dx, dy)
            err = math.remainder(math.atan2(dy, dx) - odo.theta_rad, math.tau)
            if distance >= REACHED_MM and (distance >= PASSED_MM or abs(err) <= math.pi / 2):
                return err
            way.pop()
            self.aimed = False
        return None

    def shut(self) -> bool:
        """A hazard met on the way: on the line through the trap, that way is shut and the
        way back out is taken instead; elsewhere the way goes on, and after
        :data:`WAY_BUMPS` such the way out is given up (True: odometry drift, or something
        moved)."""
        self.aimed = False
        if len(self.way) == 1 and self.retreat:
            self.way, self.retreat = self.retreat, []
            return False
        self._hazards += 1
        return self._hazards > WAY_BUMPS
