"""``home_by_map``: back along ``cover``'s map to where it saw the dock, before the search.

The dock search alone (``dock_search``) wanders toward unexplored space until a receiver
sees a dock character: three minutes on average in the simulator's apartment, up to seven.
The robot already knows the way: ``cover``'s
:class:`~roomba_bt.behaviours.coverage_map.Bearings` (on the blackboard under ``MAP_KEY``)
hold its own pose and a :class:`~.coverage_map.FloorMap` of the floor it has driven on,
with the cells where a receiver saw a dock's beam while it cleaned (``FloorMap.beams``;
``clean`` starts on the dock and backs off it, through its force field, so the cells where
cleaning started are among them). This leaf plans on that map with ``cover``'s own
breadth-first search (``FloorMap.search``) to the nearest of the latest such cells (seen
within :data:`RECENT_BEAMS_MM` of path of the last sighting: with the encoders' error a cell
seen early in the run is where the beams were by a pose since drifted by metres) and drives
the path's straight legs (``FloorMap.waypoints``)::

    plan:   the path from here to the nearest of the latest beam cells, over cells it has
            been on
    turn:   in place toward the next corner of the path
    drive:  along the line to it; a bump, a cliff or a virtual wall's beam: back off, keep
            out of that leg's cell (``FloorMap.avoid``, as ``cover`` does) and plan again;
            no progress for ``driving.STALL_S`` (wedged with no bump shown: a stand's side
            beyond the bumper): the same, backing off :data:`_WEDGED_BACK_MM`
    back:   as ``cover`` backs (:mod:`.reversing`): only over floor it has just driven (the
            first 6 cm, under its own body, aside), never onto a known drop; shortened,
            or none, where that floor ends (a leg begins with a turn in place)

It keeps the map and pose up to date as ``cover`` does (the same :class:`Bearings`), so what
it meets is mapped for the next plan. With no path that keeps off blocked cells (a drifted
map draws late walls across floor swept early, and can close the robot in), it plans across
them, never across a drop (:func:`path_across`), for up to :data:`ACROSS_PLANS` plans a run;
then it ends and the search starts where it is. A cliff that stops it on a leg (Safe mode)
keeps the next plans off that leg's cell.

SUCCESS in the tick any receiver sees a dock character (the dock search's own test: the
beams take over from there), after the plans across, when the path's end is reached
(the odometry may have drifted: seeing nothing there is no failure, the search starts there,
near where the beams were), or at once when no beam was seen while it cleaned (a robot put
down away from the dock: where it started says nothing of the dock; going back there first
cost a seed of the apartment its dock) or no map (no ``cover`` ran in this run: the
battery was low at once; a map of an earlier run in the same process is not this floor's,
so :meth:`HomeByMap.setup` forgets it, as ``cover``'s does). FAILURE with no path,
too many plans, ``timeout``, a wheel drop, or at once when the firmware stops at a cliff
and drops to Passive (as ``cover``: the cliff is mapped; a ``retry`` with ``mode: safe``
starts it again, and it backs off the edge and plans again).
"""

from __future__ import annotations

import heapq
import math
from typing import Any

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours import driving, reversing
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import run_board
from roomba_bt.behaviours.coverage_map import (
    BLOCKED,
    MAP_KEY,
    MAP_READS,
    NEIGHBOUR_STEPS,
    SWEPT,
    VISITED,
    Bearings,
    Cell,
    FloorMap,
    path_to,
)
from roomba_bt.behaviours.declare import Param, declare, wheel_speed_param
from roomba_bt.behaviours.drops import DROP
from roomba_bt.behaviours.units import DURATION
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.printable import duration_said
from roomba_bt.robot.interface import Odometry

__all__ = ["HOMING", "HomeByMap"]

#: plans (the first, and one after each hazard or stall) before it gives up
_PLANS = 25
#: a corner closer than this (mm) is taken as reached
_REACHED_MM = 40.0
#: the beam cells it goes back to: those seen within this much path (mm) before the last
#: sighting. The pose drifts with the path driven (the encoders' error), so a cell is where
#: the beams were by the pose of then: seen ten minutes of cleaning ago, the apartment's
#: seeds put it metres off (over the stairs, in the bedroom), the last pass a metre or so.
RECENT_BEAMS_MM = 3000.0
#: plans across blocked cells in a run (retries too): then the search starts where it is.
#: Where the map has drifted past use (the apartment's seeds 2 and 6) the plans met real
#: walls over and over and made no headway for minutes; where it led home, 8 or fewer.
ACROSS_PLANS = 10
#: the cost of a path's step into a blocked cell, and into one beside a blocked cell, when
#: no path keeps off them (:func:`path_across`); a free cell's step costs 1
_ACROSS_BLOCKED = 30
_ACROSS_NEAR = 3
#: how far (mm) it backs off a leg on which it stalled with no bump shown: a virtual wall's
#: back-off, more than a bump's, as the side it is caught by is not known
_WEDGED_BACK_MM = driving.BACK_OFF_MM["virtual wall"]


@declare(
    "home_by_map",
    kind="action",
    params=(
        wheel_speed_param("speed", "300 mm/s", minimum=50, doc="driving speed along the path"),
        wheel_speed_param("turn_speed", "200 mm/s", minimum=20,
                          doc="wheel speed when turning in place"),
        Param("timeout", DURATION, default="3min", minimum=5,
              doc="give up (FAILURE) after this long"),
    ),
    reads=MAP_READS,
    sends=opcodes("drive_direct", "drive"),
)  # fmt: skip
class HomeByMap(Action):
    """Drive back along ``cover``'s map (its own breadth-first search, around what it
    mapped; across blocked cells, never a drop, where none keeps off them) to the nearest of
    the places a receiver saw a dock beam last while it cleaned: SUCCESS when a dock beam is
    seen, the path's end is reached, after a few plans across the map led nowhere, or none
    was seen while it cleaned (or no ``cover`` ran in this run: nothing to go by); FAILURE
    with no way there, after
    ``timeout``, on a wheel drop, or when the
    robot leaves Safe/Full (started again, it plans again from where it is). A leg met by a
    bump, a cliff or a virtual wall, or on which it makes no progress for 3 s (wedged with
    no bump shown: a cabinet's side beyond the bumper), is backed off and kept out of the
    next plans; it backs up as ``cover`` does, only over floor it has just driven (its first
    6 cm under its own body aside) and never toward a drop on its map, less or not at all
    where the floor behind is not such floor (a leg begins with a turn in place). Drive
    Direct (145)."""

    moves = True

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)  # a new run: an earlier run's map (the process's) is not its
        py_trees.blackboard.Blackboard.storage.pop(run_board().name(MAP_KEY), None)
        self._across = 0  # plans across blocked cells, this run (a retry goes on counting)

    def start(self) -> None:
        snap = self.snapshot
        kept = py_trees.blackboard.Blackboard.storage.get(run_board().name(MAP_KEY))
        self._bearings = kept if isinstance(kept, Bearings) else None
        if self._bearings is not None:
            self._bearings.resume(snap.odometry)
        self._until = snap.time + float(self.value("timeout"))
        self._plans = 0
        self._corners: list[Cell] = []
        self._phase, self._since, self._heading = "plan", snap.time, 0.0
        self._line: driving.Line = (0.0, 0.0, 0.0)
        self._limit, self._back_to, self._cell = 0.0, 0.0, 0
        self._progress = (0.0, snap.time)
        # started again where the firmware stopped at a hazard: off it first
        why = driving.blocked(snap.frame)
        if why in driving.BACK_OFF_MM and self._bearings is not None:
            self._back(driving.BACK_OFF_MM[why])

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        bearings = self._bearings
        if bearings is None:
            # the battery low before cover ran: nothing known, the search starts here (a
            # FAILURE was retried by clean.yaml's retry, and said "gave up after 5 attempts")
            self.feedback_message = "no map of cover's to go by: nothing to go back to"
            return Status.SUCCESS
        bearings.integrate(snap.odometry, snap.time)
        bearings.observe(frame)  # what it meets is on the map for the next plan
        if bearings.sees_dock:  # this frame's, as observe read it
            return self._arrived("a dock beam seen")
        waiting = driving.held(self, 0.0 if frame.any_cliff else None)
        if waiting is not None:
            if waiting is Status.FAILURE and self._phase == "drive":
                # the firmware stopped it on this leg (a cliff): no path that way again,
                # or each retry drove the same leg to the same edge (the stairs)
                bearings.map.avoid.add(self._cell)
            return waiting
        if snap.time >= self._until:
            self.feedback_message = f"not back within {duration_said(float(self.value('timeout')))}"
            return Status.FAILURE
        for _ in range(6):
            step = self._step(frame)
            if isinstance(step, Status):
                return step
            if step is not None:
                self.send(driving.drive_wheels(*step))
                return Status.RUNNING
        self.send(driving.drive_wheels(0.0, 0.0))
        return Status.RUNNING

    def _arrived(self, why: str) -> Status:
        self.send(oi.halt())
        self.feedback_message = why
        return Status.SUCCESS

    def _step(self, frame: SensorFrame) -> tuple[float, float] | Status | None:
        """This tick's wheel speeds, or the end; None: the phase changed, look again."""
        phase = self._phase
        if phase == "plan":
            return self._plan()
        if phase == "turn":
            return self._turning()
        if phase == "back":
            return self._backing()
        return self._driving(frame)

    def _plan(self) -> Status | None:
        bearings = self._bearings
        assert bearings is not None
        fmap, pose = bearings.map, bearings.pose
        beams = fmap.beams
        if not beams:  # a robot started on the dock sees it backing off: this one did not
            return self._arrived("no dock beam seen while cleaning: the search starts here")
        here = fmap.cell(pose.x_mm, pose.y_mm)
        if here is None:
            self.feedback_message = "off the map"
            return Status.FAILURE
        goal = latest_beams(beams)
        if here in goal:
            return self._arrived("where the dock's beams were seen")
        self._plans += 1
        path = fmap.search(here, goal.__contains__) or fmap.search(
            here, goal.__contains__, through_near=True
        )
        if path is None:  # the map closes it in: drifted, most likely (path_across says)
            if self._across >= ACROSS_PLANS:
                return self._arrived("its map has led nowhere (drifted): the search starts here")
            self._across += 1
            path = path_across(fmap, here, goal)
        if path is None or self._plans > _PLANS:
            self.feedback_message = "no way on the map to where the dock's beams were seen"
            return Status.FAILURE
        self._corners = fmap.waypoints(path)
        return self._leg()

    def _leg(self) -> Status | None:
        """Toward the path's next corner (turn, then drive); the last one reached: home."""
        bearings = self._bearings
        assert bearings is not None
        while self._corners:
            self._cell = cell = self._corners.pop(0)
            x, y = bearings.map.centre(cell)
            pose = bearings.pose
            dx, dy = x - pose.x_mm, y - pose.y_mm
            distance = math.hypot(dx, dy)
            if distance >= _REACHED_MM:
                heading = math.atan2(dy, dx)
                self._phase, self._heading, self._limit = "turn", heading, distance
                self._since = self.snapshot.time
                return None
        return self._arrived("at the end of its path, no beam seen")

    def _turning(self) -> tuple[float, float] | None:
        pose = self._pose
        error = driving.wrap(self._heading - pose.theta_rad)
        now = self.snapshot.time
        wheels = driving.turning_to(error, self._since, now, self.number("turn_speed"))
        if wheels is None:
            self._phase, self._progress = "drive", (0.0, now)
            self._line = (pose.x_mm, pose.y_mm, self._heading)
        return wheels

    def _driving(self, frame: SensorFrame) -> tuple[float, float] | Status | None:
        pose, now = self._pose, self.snapshot.time
        along, _ = driving.along_line(self._line, pose.x_mm, pose.y_mm)
        if along > self._progress[0] + driving.PROGRESS_MM:
            self._progress = (along, now)
        why = driving.blocked(frame)
        if why is not None:  # no path through that cell again (as cover's paths)
            assert self._bearings is not None
            self._bearings.map.avoid.add(self._cell)
            self._back(driving.BACK_OFF_MM[why])
            return None
        if now - self._progress[1] >= driving.STALL_S:
            # wedged with no bump shown (a stand's side beyond the bumper, a sofa's lip): as
            # after a bump, no path through that cell again, and back off before the next
            # plan turns away; planning at once pushed the same way again, plan after plan
            assert self._bearings is not None
            self._bearings.map.avoid.add(self._cell)
            self._back(_WEDGED_BACK_MM)
            return None
        if along >= self._limit:
            return self._leg()
        assert self._bearings is not None
        drops = self._bearings.map.drops
        if drops.ahead(pose, pose.theta_rad, guessed=False):  # known: not met again
            self._bearings.map.avoid.add(self._cell)  # (cover's legs end there too)
            self._phase = "plan"
            return None
        speed = self.number("speed")
        if driving.near_ahead(frame):
            speed = min(speed, 150.0)
        speed = drops.speed(pose, pose.theta_rad, speed)
        return driving.steer_along(self._line, pose.x_mm, pose.y_mm, pose.theta_rad, speed)

    def _back(self, distance: float) -> None:
        """Back up ``distance`` mm, or as much of it as runs over floor it has just driven
        (the first :data:`~.reversing.OWN_MM` aside: under its own body) with no known drop
        behind, as ``cover`` does (:mod:`.reversing`: it sees nothing behind it). Every
        back-off here is off something ahead (a hazard, or a leg it is wedged on), and a
        leg starts after a turn in place: backed blind, a beam's or a wedge's 10 cm could
        go over floor it had not driven, and any back-off toward a drop on its map (a
        wheel down the stairs in ``tests/behaviours/test_homing.py``)."""
        assert self._bearings is not None
        allowed = self._bearings.reversible(distance, reversing.OWN_MM)
        self._phase, self._back_to = "back", self._pose.distance_mm - allowed
        self._since = self.snapshot.time

    def _backing(self) -> tuple[float, float] | None:
        if driving.backing_to(
            self._pose.distance_mm, self._back_to, self._since, self.snapshot.time
        ):
            return (-driving.BACK_MM_S, -driving.BACK_MM_S)
        self._phase = "plan"
        return None

    @property
    def _pose(self) -> Odometry:
        assert self._bearings is not None
        return self._bearings.pose


def latest_beams(beams: dict[Cell, float]) -> set[Cell]:
    """The beam cells seen within :data:`RECENT_BEAMS_MM` of path before the last sighting
    (``beams``: each cell's path when last seen): the ones the pose has drifted least from
    since. With exact encoders every beam cell is where the beams are; not the nearest of
    all, which with the encoders' error is often one seen early in the run, by a pose since
    drifted by metres."""
    last = max(beams.values())
    return {cell for cell, seen in beams.items() if seen >= last - RECENT_BEAMS_MM}


def path_across(fmap: FloorMap, start: Cell, goal: set[Cell]) -> list[Cell] | None:
    """The cheapest path over the cells the robot has been on or swept to a ``goal`` cell,
    through blocked cells too at a cost (:data:`_ACROSS_BLOCKED`, :data:`_ACROSS_NEAR`), never
    through a drop (``DROP``) or a cell beside one, nor :attr:`FloorMap.avoid`: for when no
    path keeps off them.
    With the encoders' error, what ``cover`` met late in the run is drawn across floor it
    swept early (the same wall, a metre off), and the apartment's seeds found the robot's
    part of the map closed all round; a blocked cell on the way is then most likely such a
    ghost, and a real one is met, avoided and planned round (:meth:`HomeByMap._driving`).
    A drop is never crossed: the stairs' edge, met again, stops the robot (Safe mode) and
    costs one of the mission's retries. None: no such path."""
    cells, near, avoid = fmap.cells, fmap.near, fmap.avoid
    parent: dict[Cell, Cell] = {start: start}
    cost: dict[Cell, int] = {start: 0}
    queue = [(0, start)]
    while queue:
        spent, cell = heapq.heappop(queue)
        if spent > cost[cell]:
            continue  # reached more cheaply since it was queued
        if cell in goal:
            return path_to(cell, start, parent)
        for step in NEIGHBOUR_STEPS:
            nxt = cell + step
            bits = cells[nxt]
            if not bits & (SWEPT | VISITED) or nxt in avoid or _beside_drop(cells, nxt):
                continue
            price = _ACROSS_BLOCKED if bits & BLOCKED else _ACROSS_NEAR if near[nxt] else 1
            if spent + price < cost.get(nxt, spent + price + 1):
                cost[nxt], parent[nxt] = spent + price, cell
                heapq.heappush(queue, (spent + price, nxt))
    return None


#: a cell and its eight neighbours, as steps in the cell index (:func:`_beside_drop`)
_AROUND = tuple(
    row + col for row in (-NEIGHBOUR_STEPS[1], 0, NEIGHBOUR_STEPS[1]) for col in (-1, 0, 1)
)


def _beside_drop(cells: Any, cell: Cell) -> bool:
    """Is ``cell``, or a cell beside it, a drop's? A path across blocked cells keeps the
    robot's centre a cell off a known drop (a centre beside one puts a cliff sensor over it:
    a path along the apartment stairs' edge would pass 70 mm from it)."""
    return any(cells[cell + d] & DROP for d in _AROUND)


HOMING: tuple[type[Action], ...] = (HomeByMap,)
