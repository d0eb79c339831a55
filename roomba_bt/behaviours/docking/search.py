"""``dock_search``: spin once, then wander toward unexplored space and follow walls until a
dock beam is seen.

The search is a state machine (:class:`SearchState`)::

    SPIN ──> TURN ──> FORWARD ──(leg done)──> TURN
               ^         │ obstacle ahead (wanting a wall)
               │         v
               ├───── FOLLOW ──(bump)──> BACK ──> UNWEDGE ──> FOLLOW
               │                          │
               └────── (bump, cliff) ─────┘

    FORWARD, FOLLOW ──(trapped: a chair's legs)──> BACK ──> RETRACE ──(clear of it)──> TURN
                                                     ^          │
                                                     └─(bump)───┘

A state's method returns the tick's status, or None after handing over to the next state,
which then acts in the same tick (every such hand-over goes down the list above:
SPIN, FOLLOW, BACK, UNWEDGE, TURN, FORWARD; and BACK to RETRACE, RETRACE to TURN).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from operator import itemgetter
from typing import Any

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.blackboard import run_board
from roomba_bt.behaviours.declare import Param, wheel_speed_param
from roomba_bt.behaviours.docking.common import (
    FROM_DOCK,
    HAZARD_IN_PACKETS,
    RUNNING,
    DockingAction,
    Hazard,
    HeadingTurn,
    IdentityEnum,
    declare_stage,
    hazard_of,
)
from roomba_bt.behaviours.docking.escape import CRUMB_MM, WAY_KEY, Crumb, Trail, Way, WayOut
from roomba_bt.behaviours.units import BOOL, DISTANCE, enum
from roomba_bt.oi.bits import BUMP_BITS, LIGHT_BUMPER_AHEAD_BITS, LIGHT_BUMPER_BITS
from roomba_bt.oi.frames import IR_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS, SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.printable import duration_said
from roomba_bt.robot.interface import Odometry, Snapshot

# The visit grid (odometry frame) and how a heading is chosen on it.
#: side of a grid cell (mm)
CELL_MM = 400.0
#: headings tried, evenly round the circle
HEADINGS = 12
#: cells scored along a heading (the next 1.6 m)
LOOKAHEAD_CELLS = 4
#: weight a cell gains per tick the robot is in it, and where a hazard was met ahead of it
TICK_VISIT_WEIGHT = 1.0
CLIFF_VISIT_WEIGHT = 400.0
HAZARD_VISIT_WEIGHT = 150.0
#: where a hazard is marked: this far ahead of the centre (mm)
HAZARD_AHEAD_MM = 250.0
#: hazards remembered (the oldest are forgotten)
HAZARDS_KEPT = 200
#: a hazard counts against a heading it lies along, up to this far ahead (mm) and this close
#: to the line (mm); its penalty fades with the distance ahead (halved at HAZARD_FADE_MM)
HAZARD_SCORE_AHEAD_MM = 900.0
HAZARD_SCORE_BESIDE_MM = 300.0
HAZARD_PENALTY = 500.0
HAZARD_FADE_MM = 300.0
#: headings closer than this (rad) to the one an obstacle was just met at are not taken
AVOID_WITHIN_RAD = 1.4
#: among equal scores, a smaller turn wins (score per radian of turn)
TURN_PENALTY_PER_RAD = 0.05

# Moving.
#: turning in place: the first full turn (wheel speeds in mm/s), then toward a chosen heading
SPIN_MM_S = 180
TURN = HeadingTurn(
    fast=160.0, slow=60.0, slow_within_rad=math.radians(20), done_rad=math.radians(4)
)
#: facing the chosen heading with something still ahead: try this much further round
BLOCKED_NUDGE_RAD = math.radians(20)
#: holding the heading on a leg: mm/s of wheel difference per radian off, and at most
STEER_MM_S_PER_RAD = 200.0
STEER_LIMIT_MM_S = 40.0
#: backing off a hazard (mm/s), for BACK_OFF_CLIFF_S after a cliff, else BACK_OFF_S
BACK_MM_S = 150
BACK_OFF_CLIFF_S = 0.8
BACK_OFF_S = 0.4
#: a leg that gets no WEDGED_MM further in WEDGED_S is wedged: a bump no bumper shows (its
#: body's side against a wall's end, beyond the bumper: the wheels stall, the odometry
#: stands still, and a leg, which ends by distance, went on until the time limit)
WEDGED_MM = 5.0
WEDGED_S = 1.0
#: an obstacle ahead is taken as a wall to follow after this much floor crossed (mm)
CROSSED_BEFORE_WALL_MM = 500.0
#: a shuttle: legs ended by a hazard that each began within SHUTTLE_MM of where the leg two
#: before began, on its heading within SHUTTLE_RAD, SHUTTLE_REPEATS in a row (two blocked
#: headings chosen in turn, a leg, a back-off and a turn each, from the same two places,
#: until the time limit); the next obstacle is then followed
SHUTTLE_MM = 30.0
SHUTTLE_RAD = math.radians(10)
SHUTTLE_REPEATS = 8

# Following a wall (light-bumper signals 0..4095).
#: speed cap while following (mm/s)
FOLLOW_MAX_MM_S = 300.0
#: the wall is kept at this signal on the side sensor (half of it on the front-side one)
WALL_SIGNAL = 500
#: mm/s of wheel difference per unit of signal error, at most this share of the speed
WALL_GAIN_MM_S = 0.12
WALL_STEER_SHARE = 0.6
#: a centre signal above this is a wall ahead: turn in place away from the wall side
WALL_AHEAD_SIGNAL = 300
FOLLOW_TURN_MM_S = 120
#: no signal: arc toward the wall side, the inner wheel at this share of the speed
CORNER_INNER_SHARE = 0.35
#: the wall counts as lost after this much path without a signal (more than the arc around
#: the end of a wall at a door)
WALL_LOST_MM = 1100.0
#: a follow ends once this many cells in a row were followed before (an island), after at
#: least FOLLOW_MIN_MM of it
OLD_CELLS_LIMIT = 4
FOLLOW_MIN_MM = 1000.0
#: a bump while following: back off, turn this far away from the wall (at UNWEDGE_MM_S),
#: follow on; after FOLLOW_BUMPS bumps on one wall it is left for a crossing of the room
UNWEDGE_TURN_RAD = math.radians(30)
UNWEDGE_MM_S = 120
FOLLOW_BUMPS = 6
#: Each share of ``speed`` a wheel is sent, which must turn it (the parameter's minimum:
#: :func:`~roomba_bt.behaviours.declare.wheel_speed_param`); the steering's slower wheel is
#: not one: a correction a still wheel makes a pivot is still made, and sooner
SPEED_SHARES = ((CORNER_INNER_SHARE, "on the inside of its arc round a wall's end"),)

# Leaving a trap the way it came in (:mod:`~roomba_bt.behaviours.docking.escape`).
#: speed on the way out (mm/s): slow, since a gap 3 cm wider than the robot is threaded by
#: odometry
RETRACE_MM_S = 100.0
#: further off the heading to the next point than this (rad), the robot stops and turns to it
REAIM_RAD = math.radians(30)

Cell = tuple[int, int]


class SearchState(IdentityEnum):
    SPIN = "spin"
    FOLLOW = "follow"
    BACK = "back"
    UNWEDGE = "unwedge"
    TURN = "turn"
    FORWARD = "forward"
    RETRACE = "retrace"


#: read on every tick of a leg as a global: a member read off its class costs about a thousand
#: machine instructions on CPython 3.11 (common.py, ``_CLIFF``)
_FORWARD = SearchState.FORWARD

#: The hazards each state stops for (backs off, or follows what is ahead): on a leg, any;
#: along a wall, all but an obstacle ahead (the wall itself); turning or backing off, none.
#: Leaving a trap, the legs beside the way are seen all along: it stops for a bump or a drop.
STOPS_FOR: dict[SearchState, frozenset[Hazard]] = {
    SearchState.FORWARD: frozenset(Hazard),
    SearchState.FOLLOW: frozenset(Hazard) - {Hazard.OBSTACLE},
    SearchState.RETRACE: frozenset(Hazard) - {Hazard.OBSTACLE},
}


class VisitGrid:
    """Where the search has been (a coarse grid in the odometry frame), where it met hazards,
    and which cells it passed while following walls; kept for the leaf's life, so a retry
    after a cliff goes on where the last attempt left off."""

    def __init__(self) -> None:
        self.visits: dict[Cell, float] = {}
        self.followed: set[Cell] = set()
        self.hazards: deque[tuple[float, float]] = deque(maxlen=HAZARDS_KEPT)

    @staticmethod
    def cell(x: float, y: float) -> Cell:
        return (math.floor(x / CELL_MM), math.floor(y / CELL_MM))

    def visit(self, x: float, y: float, weight: float) -> None:
        self.visit_cell(self.cell(x, y), weight)

    def visit_cell(self, cell: Cell, weight: float) -> None:
        self.visits[cell] = self.visits.get(cell, 0.0) + weight

    def choose_heading(self, odo: Odometry, avoid: float | None) -> float:
        """The heading toward the least visited space that does not lead straight back into
        an obstacle met before (``avoid``: the heading it was met at)."""
        best, best_score = odo.theta_rad, math.inf
        for i in range(HEADINGS):
            angle = odo.theta_rad + math.pi * 2 * i / HEADINGS
            turn = math.remainder(angle - odo.theta_rad, math.tau)
            if (
                avoid is not None
                and abs(math.remainder(angle - avoid, math.tau)) < AVOID_WITHIN_RAD
            ):
                continue
            ca, sa = math.cos(angle), math.sin(angle)
            score = 0.0
            for step in range(1, LOOKAHEAD_CELLS + 1):
                d = step * CELL_MM
                score += (
                    self.visits.get(self.cell(odo.x_mm + d * ca, odo.y_mm + d * sa), 0.0) / step
                )
            for hx, hy in self.hazards:
                dx, dy = hx - odo.x_mm, hy - odo.y_mm
                along = dx * ca + dy * sa
                if (
                    0.0 < along < HAZARD_SCORE_AHEAD_MM
                    and abs(dy * ca - dx * sa) < HAZARD_SCORE_BESIDE_MM
                ):
                    score += HAZARD_PENALTY / (1.0 + along / HAZARD_FADE_MM)
            score += TURN_PENALTY_PER_RAD * abs(turn)
            if score < best_score:
                best, best_score = angle, score
        return best


# DockSearch is over 400 lines on purpose: one stage, its states (SearchState) each a method
# of the one node, sharing the visit grid, the trail and the leg and follow marks; a class
# per state would hand those between objects on every tick (as DockApproach).
@declare_stage(
    "dock_search",
    params=(
        wheel_speed_param("speed", "200 mm/s", minimum=50, doc="forward speed while wandering",
                          shares=SPEED_SHARES),
        Param("spin_first", BOOL, default=True, doc="turn once in place before wandering"),
        Param("leg", DISTANCE, default="2 m", minimum=200,
              doc="longest straight leg before choosing a new heading"),
        Param("follow", DISTANCE, default="4 m", minimum=0,
              doc="how far it follows a wall before crossing the room"),
        Param("wall_side", enum("right", "left"), default="right", from_blackboard=False,
              doc="which side walls are kept on while following them (always the same: "
                  "a one-handed follower goes round a room and through its doors)"),
    ),
    timeout="5min",
    timeout_doc="FAILURE if no dock beam is seen by then",
    reads=(*HAZARD_IN_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS),
)  # fmt: skip
class DockSearch(DockingAction):
    """Search for the dock's beams: spin once, then wander toward unexplored space.

    SUCCESS (wheels halted) as soon as any receiver sees a dock character. Wandering drives
    straight legs toward the heading whose next 1.6 m crosses the least visited cells of a
    0.4 m grid kept in the odometry frame (headings toward obstacles met before are
    penalised). A wall met on the way is followed (docks stand against walls), always on
    the same side (``wall_side``): a one-handed follower goes round a room and, at a door,
    round the end of the wall into the next room, where alternating hands sent it back the
    way it came. It follows for up to ``follow`` or until the wall leads through cells followed
    before (an island: a bed, a table). A bump while following backs off, turns 30 deg away
    from the wall and follows on; after six bumps on one wall it crosses the room instead.
    Bumps, cliffs and virtual walls met while crossing make it back off and choose again;
    the spin happens once per leaf, not again when a retry restarts it after a cliff.
    Shuttling (eight such legs in a row, each begun where the leg two before began, on its
    heading: two blocked headings chosen in turn), it follows the next obstacle it meets.
    Trapped (30 s within a 0.5 m circle, ten hazards met there: between a chair's legs), it
    goes back to the line it came in by and on along it through the trap, or back out the way
    it came if that line is shut, by odometry (:mod:`.escape`), and searches on; the way a
    leaf before it in the run kept (``cover``, ``home_by_map``: :data:`.escape.WAY_KEY`) is
    the start of its own, so a trap it starts in has a way in.
    """

    stage = "search"
    LATE = "no dock beam seen in {}"
    #: the receivers (is a dock seen), then the hazards (:func:`hazard_of`'s order)
    WATCHED = (*IR_PACKETS, *HAZARD_IN_PACKETS)

    #: the stage's own state in slots (see :class:`~.common.DockingAction`)
    __slots__ = (
        "_avoid", "_back_until", "_bumped", "_cell", "_crumbs", "_escaping", "_follow_bumps",
        "_follow_cells", "_follow_for", "_follow_hand", "_follow_lost", "_follow_side",
        "_follow_speed", "_follow_steer", "_hazard", "_kept", "_leg", "_leg_starts", "_lit",
        "_lit_ahead", "_moved_at", "_moved_mark", "_next_crumb_at", "_old_cells", "_repeats",
        "_resume_follow", "_signals", "_speed", "_spun", "_target", "_wall_seen_at",
        "_want_wall", "_way_out", "state",
    )  # fmt: skip

    def __init__(self, name: str, params: dict[str, object] | None = None) -> None:
        super().__init__(name, params)
        self.grid = VisitGrid()
        self.trail = Trail()  # kept across starts, as the grid
        self._crumbs = self.trail.crumbs  # appended to on the tick path
        self._next_crumb_at = 0.0
        #: an attribute of each node, not a class default: CPython 3.11 does not specialise
        #: reading an attribute whose class holds an instance of a Python class (an enum
        #: member) under the same name, read on every tick (``_ACTS[self.state]``)
        self.state = SearchState.SPIN
        self._spun = False  # kept across starts: spin once a search
        self._cell = (0, 0)
        # the last hazard met: its heading, and whether a wall follow goes on after it
        self._avoid, self._resume_follow = 0.0, False
        # following a wall (:meth:`_start_follow` sets them again)
        self._wall_seen_at = None
        self._follow_lost = False
        self._follow_bumps = self._old_cells = 0
        self._follow_side = 1  # +1: the wall on the right
        # the rest is set before any tick reads it: by :meth:`start` (the parameters, the
        # heading), by :meth:`read` (the hazards)

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)  # a new run: an earlier run's way is not this one's
        py_trees.blackboard.Blackboard.storage.pop(run_board().name(WAY_KEY), None)

    def start(self) -> None:
        self.begin()
        if not self._spun:  # the first start: the way here, where a leaf before kept it
            way = py_trees.blackboard.Blackboard.storage.get(run_board().name(WAY_KEY))
            if isinstance(way, Way) and way.crumbs and not self._crumbs:
                self._crumbs.extend(way.crumbs)  # a trap it starts in: the way in is known
                self.trail.own_from = math.nextafter(way.crumbs[-1][2], math.inf)
        # spin once per search, not again on every retry after a cliff
        spin = self.value("spin_first") and not self._spun
        self._spun = True
        self.state = SearchState.SPIN if spin else SearchState.FORWARD
        self.mark_turn()
        self.mark_distance()
        self._target = self.heading()
        self._back_until = 0.0
        self._want_wall = True
        # read once a start, used on every tick
        self._speed = self.number("speed")
        self._leg = self.number("leg")
        self._follow_for = self.number("follow")
        self._follow_speed = speed = min(self._speed, FOLLOW_MAX_MM_S)
        self._follow_steer = speed * WALL_STEER_SHARE
        self._follow_hand = 1 if self.value("wall_side") == "right" else -1
        self._kept = None  # the speeds may differ from the last start's
        self.trail.restart()
        self._escaping = False
        self._moved_mark, self._moved_at = -math.inf, 0.0  # a leg's progress: none yet
        # where and on which heading the last legs began (x, y, heading), and how many in a
        # row began where the leg two before did
        self._leg_starts: deque[tuple[float, float, float]] = deque(maxlen=3)
        self._repeats = 0

    def bind(self, frame: SensorFrame) -> None:
        super().bind(frame)
        # the six light-bumper signals, read on every tick of a wall follow
        index = frame.layout.index
        for packet in LIGHT_BUMP_SIGNAL_PACKETS:
            if packet not in index:
                frame[packet]  # raises the KeyError naming the packet
        self._signals = itemgetter(*(index[packet] for packet in LIGHT_BUMP_SIGNAL_PACKETS))

    def read(self, raw: tuple[int, ...]) -> None:
        omni, left, right, bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall, light = raw
        self._done = FROM_DOCK[omni & 0xFF] or FROM_DOCK[left & 0xFF] or FROM_DOCK[right & 0xFF]
        self._hazard = hazard_of(bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall, light)
        self._bumped = bumps & BUMP_BITS != 0  # frame.any_bump
        self._lit = light & LIGHT_BUMPER_BITS != 0  # frame.light_bumper.any
        self._lit_ahead = light & LIGHT_BUMPER_AHEAD_BITS != 0  # frame.light_bumper_ahead

    def update(self) -> Status:
        """:meth:`DockingAction.update`'s checks, with the robot's cell visited and a hazard
        met marked ahead of it before the mode check: a cliff or wheel drop that dropped the
        robot to Passive is remembered, so the retry avoids it."""
        snap = self.observe()
        if self._done:
            return self.succeed()
        now = snap.time
        if now - self._t0 >= self._time_limit:
            return self.fail(self.LATE.format(duration_said(self.number("timeout"))))
        odo = snap.odometry
        # the robot's cell (VisitGrid.cell), found once a tick: visited here, and read by a
        # wall follow
        self._cell = cell = (math.floor(odo.x_mm / CELL_MM), math.floor(odo.y_mm / CELL_MM))
        visits = self.grid.visits
        visits[cell] = visits.get(cell, 0.0) + TICK_VISIT_WEIGHT
        path = odo.path_mm
        if path >= self._next_crumb_at:
            # a crumb of the way (:class:`.escape.Trail`), inline: this runs every tick
            self._next_crumb_at = path + CRUMB_MM
            self._crumbs.append((odo.x_mm, odo.y_mm, now))
        hazard = self._hazard
        if hazard is not None and hazard in STOPS_FOR.get(self.state, ()):
            self._meet(hazard, odo, now)
        if snap.mode not in DRIVING_MODES:
            return self.fail(self.fallback_message())
        act = _ACTS
        while True:
            status = act[self.state](self, snap)
            if status is not None:
                return status

    def _meet(self, hazard: Hazard, odo: Odometry, now: float) -> None:
        """A hazard met while moving on: mark it ahead on the grid; an obstacle ahead while
        wanting a wall starts following it, anything else backs off."""
        hx = odo.x_mm + HAZARD_AHEAD_MM * math.cos(odo.theta_rad)
        hy = odo.y_mm + HAZARD_AHEAD_MM * math.sin(odo.theta_rad)
        cliff = hazard is Hazard.CLIFF
        self.grid.visit(hx, hy, CLIFF_VISIT_WEIGHT if cliff else HAZARD_VISIT_WEIGHT)
        self.grid.hazards.append((hx, hy))
        if self._escaping:
            self._met_leaving(odo, now, cliff)
            return
        if self.trail.met_hazard(odo, now):
            # trapped: back off this, then out (:meth:`_back` plans the way)
            self._escaping, self._way_out = True, None
            self._back_off(odo, now, cliff)
            return
        if self.state is SearchState.FORWARD and self._shuttling():
            self._want_wall = True  # follow what is met next, out of the shuttle
        if (
            hazard is Hazard.OBSTACLE
            and self.state is SearchState.FORWARD
            and (self._want_wall or self.travelled() > CROSSED_BEFORE_WALL_MM)
        ):
            self._start_follow()  # found a wall to follow (after crossing some floor)
            return
        # a bump while following (a door jamb, a chair leg) is part of the same wall:
        # back off and follow on with the same hand
        self._resume_follow = self.state is SearchState.FOLLOW and hazard is Hazard.BUMP
        self._back_off(odo, now, cliff)

    def _shuttling(self) -> bool:
        """A leg ended by a hazard: True when :data:`SHUTTLE_REPEATS` such legs in a row
        began where the leg two before began, on its heading. Between two blocked headings
        the least visited one alternates: a leg, a back-off and a turn each, from the same
        two places, until the time limit (fresh apartment start 324: 79 legs of 36 cm from
        124 s on, every 6 s; the trap rule wants ten hazards in 30 s within a 0.5 m circle,
        and the two places were 29 cm apart). The legs before the last hazard-free one
        (a leg's whole length, a wall followed) do not count."""
        starts = self._leg_starts
        if len(starts) < 3:
            self._repeats = 0
            return False
        x, y, heading = starts[-1]
        x2, y2, heading2 = starts[0]
        again = (
            math.hypot(x - x2, y - y2) < SHUTTLE_MM
            and abs(math.remainder(heading - heading2, math.tau)) < SHUTTLE_RAD
        )
        self._repeats = self._repeats + 1 if again else 0
        if self._repeats < SHUTTLE_REPEATS:
            return False
        self._repeats = 0
        starts.clear()
        return True

    def _back_off(self, odo: Odometry, now: float, cliff: bool) -> None:
        """Back away from what was met (longer from a drop), and remember the heading it
        was met at: the next heading chosen turns well away from it."""
        self.state = SearchState.BACK
        self._back_until = now + (BACK_OFF_CLIFF_S if cliff else BACK_OFF_S)
        self._avoid = odo.theta_rad
        if cliff:
            self._want_wall = False  # a drop is no wall: wander away from it

    # states ------------------------------------------------------------------------
    def _spin(self, snap: Snapshot) -> Status | None:
        odo = snap.odometry
        if abs(odo.angle_rad - self._turn_mark) < math.tau:  # abs(self.turned())
            self.wheels(-SPIN_MM_S, SPIN_MM_S)
            return RUNNING
        self._target = self.grid.choose_heading(odo, None)
        self.state = SearchState.TURN
        return None

    def _follow(self, snap: Snapshot) -> Status | None:
        odo = snap.odometry
        travelled = abs(odo.distance_mm - self._distance_mark)  # self.travelled()
        if travelled < self._follow_for and not self._follow_lost:
            if self._cell not in self._follow_cells:
                self._note_followed(self._cell)
            if self._old_cells < OLD_CELLS_LIMIT or travelled < FOLLOW_MIN_MM:
                self._keep_wall(snap)
                return RUNNING
        self._want_wall = False  # followed far enough: cross the room
        self._target = self.grid.choose_heading(
            odo, odo.theta_rad - self._follow_side * math.pi / 2
        )
        self.state = SearchState.TURN
        return None

    def _back(self, snap: Snapshot) -> Status | None:
        if snap.time < self._back_until:
            self.wheels(-BACK_MM_S, -BACK_MM_S)
            return RUNNING
        if self._escaping:
            if self._way_out is None:
                self._way_out = WayOut(self.trail, snap.odometry)
            self.state = SearchState.RETRACE
            return None
        if self._resume_follow:
            # turn away from the wall side, then follow on with the same hand; a wall
            # that keeps bumping (a corner too tight for the robot) is given up
            self._resume_follow = False
            self._follow_bumps += 1
            if self._follow_bumps <= FOLLOW_BUMPS:
                self.state = SearchState.UNWEDGE
                self.mark_turn()
                self._wall_seen_at = None
                return None
            self._want_wall = False  # cross the room instead
        if self._want_wall and self._lit and not self._bumped:
            self._start_follow()
            return RUNNING
        self._target = self.grid.choose_heading(snap.odometry, self._avoid)
        self.state = SearchState.TURN
        return None

    def _unwedge(self, snap: Snapshot) -> Status | None:
        if abs(snap.odometry.angle_rad - self._turn_mark) < UNWEDGE_TURN_RAD:
            hand = self._follow_side
            self.wheels(-UNWEDGE_MM_S * hand, UNWEDGE_MM_S * hand)
            return RUNNING
        self.state = SearchState.FOLLOW
        return RUNNING

    def _turn(self, snap: Snapshot) -> Status | None:
        err = math.remainder(self._target - snap.odometry.theta_rad, math.tau)
        if not self.spin_to(err, TURN):
            return RUNNING
        if self._lit_ahead:
            # still blocked: aim further round, and drive the leg's step this tick
            self._target += math.copysign(BLOCKED_NUDGE_RAD, err or 1.0)
            return self._forward(snap)
        self.state = SearchState.FORWARD
        odo = snap.odometry
        self._distance_mark = self._moved_mark = odo.distance_mm  # mark_distance()
        self._moved_at = snap.time
        self._leg_starts.append((odo.x_mm, odo.y_mm, self._target))
        return None

    def _forward(self, snap: Snapshot) -> Status | None:
        """A straight leg toward unexplored space, then look for a wall again."""
        odo = snap.odometry
        if abs(odo.distance_mm - self._distance_mark) >= self._leg:  # self.travelled()
            self._want_wall = True
            self._leg_starts.clear()  # a whole leg: no shuttle
            self._target = self.grid.choose_heading(odo, None)
            self.state = SearchState.TURN
            self._distance_mark = odo.distance_mm  # self.mark_distance()
            return RUNNING
        if self.state is _FORWARD:
            if odo.distance_mm > self._moved_mark + WEDGED_MM:
                self._moved_mark, self._moved_at = odo.distance_mm, snap.time
            elif snap.time - self._moved_at > WEDGED_S:
                # wedged with no bump shown (a wall's end against the body's side, beyond
                # the bumper): the wheels stall, the odometry stands still; met as a bump
                self._meet(Hazard.BUMP, odo, snap.time)
                return None
        speed = self._speed
        err = math.remainder(self._target - odo.theta_rad, math.tau)
        # max(-STEER_LIMIT_MM_S, min(STEER_LIMIT_MM_S, ...)) as comparisons, on every
        # tick of a leg (driving.wheel_speeds says why)
        turn = STEER_MM_S_PER_RAD * err
        turn = turn if turn < STEER_LIMIT_MM_S else STEER_LIMIT_MM_S
        turn = turn if turn > -STEER_LIMIT_MM_S else -STEER_LIMIT_MM_S
        self.wheels(speed - turn, speed + turn)
        return RUNNING

    # leaving a trap ----------------------------------------------------------------
    def _met_leaving(self, odo: Odometry, now: float, cliff: bool) -> None:
        """A hazard on the way out of a trap: back off, then on by the way out left
        (:meth:`.escape.WayOut.shut`), or, given up, search on, the hazards before no longer
        counting toward another trap."""
        if self._way_out is not None and self._way_out.shut():
            self._escaping = False
            self.trail.restart()
        self._back_off(odo, now, cliff)

    def _retrace(self, snap: Snapshot) -> Status | None:
        """The way out, point by point: turn in place to face the next point, drive to it
        steering onto it; clear of the trap, the search chooses a heading away from it (its
        centre is marked as a hazard, and its cells are heavy with the ticks spent there)."""
        odo = snap.odometry
        way_out = self._way_out
        assert way_out is not None  # RETRACE follows BACK, which made it
        err = way_out.turn_to_next(odo)
        if err is not None:
            if not way_out.aimed or abs(err) > REAIM_RAD:
                way_out.aimed = self.spin_to(err, TURN)
                if not way_out.aimed:
                    return RUNNING
            turn = max(-STEER_LIMIT_MM_S, min(STEER_LIMIT_MM_S, STEER_MM_S_PER_RAD * err))
            self.wheels(RETRACE_MM_S - turn, RETRACE_MM_S + turn)
            return RUNNING
        self._escaping, self._way_out = False, None
        trap_x, trap_y = way_out.trap
        self.grid.hazards.append(way_out.trap)
        self.trail.restart()
        self._target = self.grid.choose_heading(
            odo, math.atan2(trap_y - odo.y_mm, trap_x - odo.x_mm)
        )
        self.state = SearchState.TURN
        return None

    # wall following ----------------------------------------------------------------
    def _start_follow(self) -> None:
        self.state = SearchState.FOLLOW
        self._leg_starts.clear()  # a wall followed: no shuttle
        self._wall_seen_at = None
        self._follow_lost = False
        self._follow_side = self._follow_hand
        self._follow_cells: set[Cell] = set()
        self._old_cells = 0
        self._follow_bumps = 0
        self.mark_distance()

    def _note_followed(self, cell: Cell) -> None:
        """The follow enters ``cell``, new to it. A cell followed before (not merely
        crossed) means the wall leads where it was followed already (this wall, or this
        island): :data:`OLD_CELLS_LIMIT` such cells in a row, after :data:`FOLLOW_MIN_MM`
        of the follow, end it (time to cross the room instead)."""
        self._follow_cells.add(cell)
        seen_before = cell in self.grid.followed
        self.grid.followed.add(cell)
        self._old_cells = self._old_cells + 1 if seen_before else 0

    def _keep_wall(self, snap: Snapshot) -> None:
        """Keep a wall on one side (``_follow_side``: +1 right, -1 left) at a steady
        light-bumper signal: right / front-right, or left / front-left; the centre pair for
        a wall ahead (turn away from it in place).

        Along a wall or turning from one, the speeds asked are a function of the signals
        and the bumper alone: when those are the same as at the last tick that asked them
        and the wheels still keep those speeds (no other speeds asked, no halt, no stop
        since: :meth:`wheels` would return at once), there is nothing to do. The signals
        stand still on about two ticks in five of a follow. Without a wall the arc's path
        is counted every tick: that branch is never skipped."""
        # all six signals in one call, by slot (read every tick of a follow)
        read_signals = self._signals  # read, then called: see StreamParser.take
        signals = read_signals(snap.frame.values)
        kept = self._kept
        if (
            kept is not None
            and kept[0] == signals
            and kept[1] is self._bumped
            and kept[2] is self._asked
            and self._started_motion
        ):
            return
        speed = self._follow_speed  # min(speed, FOLLOW_MAX_MM_S)
        hand = self._follow_side
        left, front_left, centre_left, centre_right, front_right, right = signals
        # max() and min() written out as their comparisons (driving.wheel_speeds says why)
        front = centre_right if centre_right > centre_left else centre_left
        side, front_side = (right, front_right) if hand > 0 else (left, front_left)
        if front > WALL_AHEAD_SIGNAL or self._bumped:
            # wall ahead: turn away from the wall side
            self.wheels(-FOLLOW_TURN_MM_S * hand, FOLLOW_TURN_MM_S * hand)
        elif side == 0 and front_side == 0:
            # lost it (an outside corner, or the end of a wall at a door): arc toward the
            # wall side; rounding a jamb takes about 0.9 m of path without a signal
            if hand > 0:
                self.wheels(speed, speed * CORNER_INNER_SHARE)
            else:
                self.wheels(speed * CORNER_INNER_SHARE, speed)
            path = snap.odometry.path_mm
            if self._wall_seen_at is None:
                self._wall_seen_at = path
            elif path - self._wall_seen_at > WALL_LOST_MM:
                self._follow_lost = True  # no wall there after all
            self._kept = None
            return
        else:
            self._wall_seen_at = None
            half = front_side // 2
            error = WALL_SIGNAL - (half if half > side else side)
            limit = self._follow_steer  # speed * WALL_STEER_SHARE
            steer = WALL_GAIN_MM_S * error
            steer = steer if steer < limit else limit
            turn = hand * (steer if steer > -limit else -limit)
            self.wheels(speed + turn, speed - turn)
        self._kept = (signals, self._bumped, self._asked)

    state: SearchState
    _wall_seen_at: float | None
    _cell: Cell
    #: leaving a trap: from the hazard that said so (then backing off) to clear of it
    _escaping: bool
    _way_out: WayOut | None
    #: the trail's crumbs, and the path (mm) at which the next is dropped
    _crumbs: deque[Crumb]
    _next_crumb_at: float
    # the readings (read)
    _hazard: Hazard | None
    _signals: Callable[[tuple[int, ...]], tuple[int, int, int, int, int, int]]
    #: what the last tick of :meth:`_keep_wall` that asked speeds read (signals, bumper)
    #: and the speeds it left asked (None: it asked none, or the arc without a wall)
    _kept: tuple[tuple[int, ...], bool, tuple[float, float] | None] | None


#: Each state's method (see the module's drawing).
_ACTS: dict[SearchState, Callable[[DockSearch, Snapshot], Status | None]] = {
    SearchState.SPIN: DockSearch._spin,
    SearchState.FOLLOW: DockSearch._follow,
    SearchState.BACK: DockSearch._back,
    SearchState.UNWEDGE: DockSearch._unwedge,
    SearchState.TURN: DockSearch._turn,
    SearchState.FORWARD: DockSearch._forward,
    SearchState.RETRACE: DockSearch._retrace,
}
