"""Docking from the home base's IR beams, in the stages of Nav2's docking server.

The home base sends IR characters (decoded by :mod:`roomba_bt.oi.ir`, both dock families:
160-173 and 240-254) in three beams::

                 red buoy  (dock's left,  about -5 .. +25 deg of its axis)
      dock ==>   both      (on the axis, about +-5 deg)      up to about 1 m
                 green buoy(dock's right, about -25 .. +5 deg)
                 force field: all around, about 0.6 m

The robot has three receivers: the omni (packet 17) on top of the bumper, and the left (52)
and right (53) directional ones, which see the dock only when it is within about 5 deg of the
other side of the heading: both of them see it when the robot faces the dock. So the robot
reads two things from every frame: *where the dock is* relative to its heading (left receiver
only: turn left; right only: turn right; both: facing it) and *which side of the dock's axis
it is on* (red only: the dock's left; green only: its right; both: on the axis).

The stages, each a leaf whose failure message names the stage (``search: ...``,
``approach: ...``, ``final alignment: ...``, ``wait for charge: ...``):

``dock_search``
    spin once in place, then wander toward the least visited space (a coarse visit grid in
    the odometry frame), backing away from bumps, cliffs and light-bumper obstacles, until a
    dock character is seen.
``dock_approach``
    face the dock; if off its axis, turn toward the axis and move until the centre is on it
    (the omni receiver finds both edges of the band where it sees both buoys), then face the
    dock again; with no buoy in sight, circle the dock until one is seen. SUCCESS facing
    the dock on its axis.
``dock_drive_on``
    drive in along the axis, slower inside the force field, steering to keep both the left
    and right receivers on the dock; on contact without charge, wiggle in place to seat the
    contacts. SUCCESS when packet 34 shows the home base.
``dock_wait_charge``
    SUCCESS when packet 34's home-base bit and a charging state in packet 21 are both seen.
``dock_time_limit``
    RUNNING until the time limit, then FAILURE naming the stage that was running: put it in
    a ``parallel`` (policy ``one``) beside the stages.

None of them sends Seek Dock (143). They drive with Drive Direct (145)
``[145][right hi][right lo][left hi][left lo]`` and halt ``[137][0][0][0][0]`` when they end.
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.declare import Action, Param, declare
from roomba_bt.behaviours.units import ANGLE, BOOL, DISTANCE, DURATION, SPEED, enum
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.ir import IR_CHARACTERS, IRCharacter
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME

_WHEEL = COMMANDS_BY_NAME["drive_direct"].args[0]
_OK, _RUN, _FAIL = Status.SUCCESS, Status.RUNNING, Status.FAILURE

#: Where the stages note which one is running, for ``dock_time_limit``'s message.
STAGE_KEY = "/roomba/docking/stage"
#: When the current docking run began (``dock_time_limit`` notes it): the approach counts
#: its attempts per run.
RUN_KEY = "/roomba/docking/run"
#: Turns toward the axis (crossings, circles) in one approach before it backs away from the
#: dock and starts over from the edge of the force field; three are usually enough.
_MAX_CROSSINGS = 6

IR_PACKETS = (17, 52, 53)
HAZARD_PACKETS = (7, 9, 10, 11, 12, 13, 45)
ODOMETRY_PACKETS = (43, 44)
#: How far the omni receiver is ahead of the wheels' axle (Roomba / Create 2: about 13 cm).
OMNI_AHEAD_MM = 130.0
#: Light-bumper bits 1..4 (front-left, centre-left, centre-right, front-right): something ahead.
_LIGHT_AHEAD = 0b011110


def _note_stage(stage: str) -> None:
    py_trees.blackboard.Blackboard.storage[STAGE_KEY] = stage


def current_stage() -> str | None:
    """The docking stage that ran last (None before any)."""
    stage = py_trees.blackboard.Blackboard.storage.get(STAGE_KEY)
    return stage if isinstance(stage, str) else None


class DockView(NamedTuple):
    """What one frame says about the dock (a named tuple: one is built every tick)."""

    omni: IRCharacter
    left: IRCharacter
    right: IRCharacter

    @classmethod
    def of(cls, frame: SensorFrame) -> DockView:
        return cls(
            IR_CHARACTERS[frame[17] & 0xFF],
            IR_CHARACTERS[frame[52] & 0xFF],
            IR_CHARACTERS[frame[53] & 0xFF],
        )

    @property
    def seen(self) -> bool:
        return self.omni.from_dock or self.left.from_dock or self.right.from_dock

    @property
    def on_left(self) -> bool:
        """Only the left receiver sees the dock: it is more than ~5 deg to the left."""
        return self.left.from_dock and not self.right.from_dock

    @property
    def on_right(self) -> bool:
        return self.right.from_dock and not self.left.from_dock

    @property
    def facing(self) -> bool:
        return self.left.from_dock and self.right.from_dock

    def _beams(self) -> tuple[bool, bool, bool]:
        """(red buoy, green buoy, force field) seen. The omni receiver sits on the robot's
        axis: where it is, the robot is. The side receivers are 4 cm off it and count only
        when the omni sees nothing of the dock."""
        omni, left, right = self
        if omni.from_dock:
            return omni.red_buoy, omni.green_buoy, omni.force_field
        by_left, by_right = left.from_dock, right.from_dock
        return (
            (by_left and left.red_buoy) or (by_right and right.red_buoy),
            (by_left and left.green_buoy) or (by_right and right.green_buoy),
            (by_left and left.force_field) or (by_right and right.force_field),
        )

    @property
    def red(self) -> bool:
        return self._beams()[0]

    @property
    def green(self) -> bool:
        return self._beams()[1]

    @property
    def force_field(self) -> bool:
        return self._beams()[2]

    @property
    def side(self) -> int:
        """+1 on the dock's left (red only), -1 on its right (green only), 0 on the axis or
        unknown."""
        red, green = self.red, self.green
        if red and not green:
            return 1
        if green and not red:
            return -1
        return 0

    @property
    def on_axis(self) -> bool:
        return self.red and self.green


class _DockingAction(Action):
    """Shared helpers: wheel commands, hazards, stage notes and messages."""

    moves = True
    stage = ""

    def wheels(self, left: float, right: float) -> None:
        """Drive Direct, sent only when the wheel speeds change (the robot keeps them)."""
        limit = _WHEEL.maximum
        lo = max(-limit, min(limit, round(left)))
        ro = max(-limit, min(limit, round(right)))
        if (lo, ro) != self._last_wheels or not self._started_motion:
            self.send(oi.drive_direct(ro, lo))
        self._last_wheels = (lo, ro)
        self._started_motion = True

    def halt(self) -> None:
        if self._started_motion and not self.not_driving():
            self.send(oi.halt())
        self._started_motion = False
        self._last_wheels = (0, 0)

    _last_wheels = (0, 0)

    def fail(self, message: str) -> Status:
        self.halt()
        self.feedback_message = f"{self.stage}: {message}"
        return _FAIL

    def succeed(self) -> Status:
        self.halt()
        return _OK

    def begin(self) -> None:
        _note_stage(self.stage)
        self._t0 = self.snapshot.time

    def elapsed(self) -> float:
        return self.snapshot.time - self._t0

    def not_driving(self) -> bool:
        return self.snapshot.mode not in DRIVING_MODES

    def fallback_message(self) -> str:
        change = self.snapshot.last_fallback
        cause = f" ({change.cause})" if change is not None else ""
        return f"the robot left Safe/Full mode{cause}"

    def heading(self) -> float:
        return self.snapshot.odometry.theta_rad

    def turned(self) -> float:
        """Signed rotation since :meth:`mark_turn`, radians."""
        return self.snapshot.odometry.angle_rad - self._turn_mark

    def mark_turn(self) -> None:
        self._turn_mark = self.snapshot.odometry.angle_rad

    def travelled(self) -> float:
        return abs(self.snapshot.odometry.distance_mm - self._distance_mark)

    def mark_distance(self) -> None:
        self._distance_mark = self.snapshot.odometry.distance_mm

    _turn_mark = 0.0
    _distance_mark = 0.0
    _t0 = 0.0


def _hazard(frame: SensorFrame) -> str | None:
    if frame[7] & 12:
        return "wheel drop"
    if frame[9] or frame[10] or frame[11] or frame[12]:
        return "cliff"
    if frame[7] & 3:
        return "bump"
    if frame[13]:
        return "cliff"  # a virtual wall: a line not to cross, like a drop
    if frame[45] & _LIGHT_AHEAD:
        return "obstacle"
    return None


# --------------------------------------------------------------------------- search

_CELL_MM = 400.0
_DIRECTIONS = 12
#: wall following: the wall counts as lost after this much path without a signal (more
#: than the arc around the end of a wall at a door)
_WALL_LOST_MM = 1100.0
#: a bump while following: back off, turn this far away from the wall, follow on; after
#: this many bumps on one wall it is left for a crossing of the room
_UNWEDGE_TURN = math.radians(30)
_FOLLOW_BUMPS = 6


@declare(
    "dock_search",
    kind="action",
    params=(
        Param("speed", SPEED, default="200 mm/s", minimum=50, maximum=_WHEEL.maximum,
              doc="forward speed while wandering"),
        Param("spin_first", BOOL, default=True, doc="turn once in place before wandering"),
        Param("leg", DISTANCE, default="2 m", minimum=200,
              doc="longest straight leg before choosing a new heading"),
        Param("follow", DISTANCE, default="4 m", minimum=0,
              doc="how far it follows a wall before crossing the room"),
        Param("wall_side", enum("right", "left"), default="right", from_blackboard=False,
              doc="which side walls are kept on while following them (always the same: "
                  "a one-handed follower goes round a room and through its doors)"),
        Param("timeout", DURATION, default="5min", minimum=1,
              doc="FAILURE if no dock beam is seen by then"),
    ),
    reads=(*IR_PACKETS, *HAZARD_PACKETS, 46, 47, 48, 49, 50, 51, *ODOMETRY_PACKETS),
    sends=(137, 145),
)  # fmt: skip
class DockSearch(_DockingAction):
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
    """

    stage = "search"

    def __init__(self, name: str, params: dict[str, object] | None = None) -> None:
        super().__init__(name, params)
        self._visits: dict[tuple[int, int], float] = {}
        self._followed: set[tuple[int, int]] = set()  # cells passed while following walls
        self._hazards: deque[tuple[float, float]] = deque(maxlen=200)

    def start(self) -> None:
        self.begin()
        # spin once per search, not again on every retry after a cliff
        spin = self.value("spin_first") and not self._spun
        self._spun = True
        self._phase = "spin" if spin else "forward"
        self.mark_turn()
        self.mark_distance()
        self._target = self.heading()
        self._back_until = 0.0
        self._want_wall = True

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return (math.floor(x / _CELL_MM), math.floor(y / _CELL_MM))

    def _visit(self, x: float, y: float, weight: float) -> None:
        cell = self._cell(x, y)
        self._visits[cell] = self._visits.get(cell, 0.0) + weight

    def _choose_heading(self, avoid: float | None) -> float:
        """The heading toward the least visited space that does not lead straight back into
        an obstacle met before (``avoid``: the heading it was met at)."""
        odo = self.snapshot.odometry
        best, best_score = odo.theta_rad, math.inf
        for i in range(_DIRECTIONS):
            angle = odo.theta_rad + math.pi * 2 * i / _DIRECTIONS
            turn = math.remainder(angle - odo.theta_rad, math.tau)
            if avoid is not None and abs(math.remainder(angle - avoid, math.tau)) < 1.4:
                continue
            ca, sa = math.cos(angle), math.sin(angle)
            score = 0.0
            for step in range(1, 5):
                d = step * _CELL_MM
                score += (
                    self._visits.get(self._cell(odo.x_mm + d * ca, odo.y_mm + d * sa), 0.0) / step
                )
            for hx, hy in self._hazards:
                dx, dy = hx - odo.x_mm, hy - odo.y_mm
                along = dx * ca + dy * sa
                if 0.0 < along < 900.0 and abs(dy * ca - dx * sa) < 300.0:
                    score += 500.0 / (1.0 + along / 300.0)
            score += 0.05 * abs(turn)  # prefer small turns among equals
            if score < best_score:
                best, best_score = angle, score
        return best

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        if DockView.of(frame).seen:
            return self.succeed()
        if self.elapsed() >= self.number("timeout") - 1e-9:
            return self.fail(f"no dock beam seen in {self.number('timeout'):g} s")
        odo = snap.odometry
        self._visit(odo.x_mm, odo.y_mm, 1.0)
        hazard = _hazard(frame)
        moving_on = self._phase in ("forward", "follow")
        if hazard is not None and moving_on and not (self._phase == "follow" and
                                                      hazard == "obstacle"):  # fmt: skip
            ahead = 250.0
            hx = odo.x_mm + ahead * math.cos(odo.theta_rad)
            hy = odo.y_mm + ahead * math.sin(odo.theta_rad)
            self._visit(hx, hy, 400.0 if hazard == "cliff" else 150.0)
            self._hazards.append((hx, hy))
            if (
                hazard == "obstacle"
                and self._phase == "forward"
                and (self._want_wall or self.travelled() > 500.0)
            ):
                self._start_follow()  # found a wall to follow (after crossing some floor)
            else:
                # a bump while following (a door jamb, a chair leg) is part of the same wall:
                # back off and follow on with the same hand
                self._resume_follow = self._phase == "follow" and hazard == "bump"
                self._phase = "back"
                self._back_until = snap.time + (0.8 if hazard == "cliff" else 0.4)
                self._avoid = odo.theta_rad
                if hazard == "cliff":
                    self._want_wall = False  # a drop is no wall: wander away from it
        if self.not_driving():
            # a cliff or wheel drop in Safe mode: remembered above, so the retry avoids it
            return self.fail(self.fallback_message())
        if self._phase == "spin":
            if abs(self.turned()) < math.tau:
                self.wheels(-180, 180)
                return _RUN
            self._target = self._choose_heading(None)
            self._phase = "turn"
        if self._phase == "follow":
            if (
                self.travelled() < self.number("follow")
                and not self._follow_lost
                and self._follow_is_new()
            ):
                self._follow(frame)
                return _RUN
            self._want_wall = False  # followed far enough: cross the room
            self._target = self._choose_heading(odo.theta_rad - self._follow_side * math.pi / 2)
            self._phase = "turn"
        if self._phase == "back":
            if snap.time < self._back_until:
                self.wheels(-150, -150)
                return _RUN
            if self._resume_follow:
                # turn away from the wall side, then follow on with the same hand; a wall
                # that keeps bumping (a corner too tight for the robot) is given up
                self._resume_follow = False
                self._follow_bumps += 1
                if self._follow_bumps <= _FOLLOW_BUMPS:
                    self._phase = "unwedge"
                    self.mark_turn()
                    self._wall_seen_at = None
                else:
                    self._want_wall = False  # cross the room instead
            if self._phase == "back":
                if self._want_wall and frame[45] and not frame[7] & 3:
                    self._start_follow()
                    return _RUN
                self._target = self._choose_heading(self._avoid)
                self._phase = "turn"
        if self._phase == "unwedge":
            if abs(self.turned()) < _UNWEDGE_TURN:
                hand = self._follow_side
                self.wheels(-120 * hand, 120 * hand)
                return _RUN
            self._phase = "follow"
            return _RUN
        if self._phase == "turn":
            err = math.remainder(self._target - odo.theta_rad, math.tau)
            if abs(err) < math.radians(4) and frame[45] & _LIGHT_AHEAD:
                self._target += math.copysign(math.radians(20), err or 1.0)  # still blocked
            elif abs(err) < math.radians(4):
                self._phase = "forward"
                self.mark_distance()
            else:
                w = 160.0 if abs(err) > math.radians(20) else 60.0
                self.wheels(-w if err > 0 else w, w if err > 0 else -w)
                return _RUN
        # forward: a straight leg toward unexplored space, then look for a wall again
        if self.travelled() >= self.number("leg"):
            self._want_wall = True
            self._target = self._choose_heading(None)
            self._phase = "turn"
            self.mark_distance()
            return _RUN
        speed = self.number("speed")
        err = math.remainder(self._target - odo.theta_rad, math.tau)
        turn = max(-40.0, min(40.0, 200.0 * err))
        self.wheels(speed - turn, speed + turn)
        return _RUN

    def _start_follow(self) -> None:
        self._phase = "follow"
        self._wall_seen_at = None
        self._follow_lost = False
        self._follow_side = 1 if self.value("wall_side") == "right" else -1
        self._follow_cells: set[tuple[int, int]] = set()
        self._old_cells = 0
        self._follow_bumps = 0
        self.mark_distance()

    _wall_seen_at: float | None = None
    _follow_lost = False
    _resume_follow = False
    _follow_bumps = 0
    _follow_side = 1  # +1: the wall on the right
    _old_cells = 0

    def _follow_is_new(self) -> bool:
        """False once the wall leads through cells visited before this follow (it has been
        followed already): time to cross the room instead."""
        odo = self.snapshot.odometry
        cell = self._cell(odo.x_mm, odo.y_mm)
        if cell not in self._follow_cells:
            self._follow_cells.add(cell)
            # followed before (not merely crossed): this wall, or this island, is done
            seen_before = cell in self._followed
            self._followed.add(cell)
            self._old_cells = self._old_cells + 1 if seen_before else 0
        return self._old_cells < 4 or self.travelled() < 1000.0

    def _follow(self, frame: SensorFrame) -> None:
        """Keep a wall on one side (``_follow_side``: +1 right, -1 left) at a steady
        light-bumper signal: right 51 / front-right 50, left 46 / front-left 47, centre
        48-49 for a wall ahead (turn away from it in place)."""
        speed = min(self.number("speed"), 300.0)
        hand = self._follow_side
        front = max(frame[48], frame[49])
        side, front_side = (frame[51], frame[50]) if hand > 0 else (frame[46], frame[47])
        if front > 300 or frame[7] & 3:
            self.wheels(-120 * hand, 120 * hand)  # wall ahead: turn away from the wall side
        elif side == 0 and front_side == 0:
            # lost it (an outside corner, or the end of a wall at a door): arc toward the
            # wall side; rounding a jamb takes about 0.9 m of path without a signal
            if hand > 0:
                self.wheels(speed, speed * 0.35)
            else:
                self.wheels(speed * 0.35, speed)
            path = self.snapshot.odometry.path_mm
            if self._wall_seen_at is None:
                self._wall_seen_at = path
            elif path - self._wall_seen_at > _WALL_LOST_MM:
                self._follow_lost = True  # no wall there after all
        else:
            self._wall_seen_at = None
            error = 500 - max(side, front_side // 2)
            turn = hand * max(-speed * 0.6, min(speed * 0.6, 0.12 * error))
            self.wheels(speed + turn, speed - turn)

    _spun = False
    _want_wall = True
    _avoid = 0.0
    _phase = "spin"
    _target = 0.0
    _back_until = 0.0


# --------------------------------------------------------------------------- approach


@declare(
    "dock_approach",
    kind="action",
    params=(
        Param("speed", SPEED, default="150 mm/s", minimum=30, maximum=_WHEEL.maximum,
              doc="speed toward the axis"),
        Param("cross_angle", ANGLE, default="80deg", minimum=20, maximum=90,
              doc="how far it turns away from the dock to move toward its axis"),
        Param("lost_after", DURATION, default="4s", minimum=0.1,
              doc="FAILURE when no beam has been seen for this long"),
        Param("timeout", DURATION, default="90s", minimum=1,
              doc="FAILURE if not facing the dock on its axis by then"),
    ),
    reads=(*IR_PACKETS, *HAZARD_PACKETS, 34, *ODOMETRY_PACKETS),
    sends=(137, 145),
)  # fmt: skip
class DockApproach(_DockingAction):
    """Get onto the dock's axis, facing it (SUCCESS), from anywhere its beams are seen.

    Face the dock (turn toward the receiver that sees it); red only means the robot is on
    the dock's left, so the axis is on the robot's left: turn ``cross_angle`` left and move
    along that line until the centre is on the axis (the omni receiver, ahead of the centre,
    measures both edges of the band where it sees both buoys; see :meth:`_cross`); green
    only: the mirror image; then face the dock again. In the force field with no buoy, the
    side is the last one seen, or a guess: circle the dock along the field's edge that way
    until a buoy is seen, the other way after a bump. No progress (``_MAX_CROSSINGS`` turns
    toward the axis, or a third attempt in one docking run): back away from the dock out of
    the force field and come in again, rather than repeat the same moves until the time
    limit.
    """

    stage = "approach"

    def start(self) -> None:
        self.begin()
        self._last_seen = self.snapshot.time
        self._side_guess = 0
        self._last_side = 0
        self._guesses = 0
        self._crossings = 0
        self._centred = False
        run = py_trees.blackboard.Blackboard.storage.get(RUN_KEY)
        if run != self._run:
            self._run, self._starts = run, 0
        self._starts += 1
        # two attempts of this run already ended in a failure after or during the approach:
        # do not repeat the same moves from the same place; back away and start over
        self._retreat = self._starts >= 3
        view = DockView.of(self.snapshot.frame)
        self._start_facing(-1.0 if view.on_right else 1.0)

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        view = DockView.of(frame)
        if frame.charging_sources.home_base:
            return self.succeed()
        if self.elapsed() >= self.number("timeout") - 1e-9:
            return self.fail(f"not on the dock's axis after {self.number('timeout'):g} s")
        if self.not_driving():
            return self.fail(self.fallback_message())
        if view.seen:
            self._last_seen = snap.time
            if view.side:
                self._last_side = view.side
                self._last_side_time = snap.time
        elif snap.time - self._last_seen >= self.number("lost_after"):
            return self.fail(f"lost the dock's beams for {self.number('lost_after'):g} s")
        speed = self.number("speed")
        hazard = _hazard(frame)
        if hazard == "obstacle":
            hazard = None  # near the dock its wall is always in sight of the light bumper
        if self._phase == "face":
            if not self._face(view):
                return _RUN
            if self._retreat:
                return self._start_retreat()
            side = view.side
            if view.on_axis or self._centred:
                # on the axis: the omni sees both buoys, or the last crossing measured both
                # edges of the band and stopped the centre half-way (close to the dock the
                # band at the omni is narrower than what a few degrees of heading move it)
                return self.succeed()
            if self._crossings >= _MAX_CROSSINGS:
                return self._start_retreat()
            if not (view.omni.from_dock and view.omni.force_field):
                self._phase = "closer"  # along the beams, into the force field first
                self.mark_distance()
            elif side == 0:
                # force field only: the side last seen, if recent; else guesses that
                # alternate (+1, -1, ...) until one leads into the buoys
                if self._last_side and snap.time - self._last_side_time < 5.0:
                    side = self._last_side
                else:
                    self._guesses += 1
                    side = 1 if self._guesses % 2 else -1
                    self._orbit = True  # a guess: circle the dock until a buoy is seen
                self._side_guess = side
            if self._phase == "face":
                self._cross_side = side or 1
                self._crossings += 1
                self._phase = "turn_away"
                self._sweep = 1
                self._centred = False
                self.mark_turn()
        if self._phase == "closer":
            if view.omni.from_dock and (view.omni.force_field or view.on_axis):
                self._start_facing(1.0)
                if view.on_axis and view.facing:
                    return self.succeed()
                return _RUN
            if hazard is not None or self.travelled() > 1500.0:
                self._phase = "back"
                self._back_until = snap.time + 0.5
            else:
                slow = speed * 0.8
                if view.on_left:
                    self.wheels(slow * 0.3, slow * 0.3 + 60)
                elif view.on_right:
                    self.wheels(slow * 0.3 + 60, slow * 0.3)
                else:
                    self.wheels(slow, slow)
                return _RUN
        if self._phase == "turn_away":
            goal = math.radians(self.number("cross_angle"))
            state = self._omni_state(view)
            if state is not None:
                self._sweep = state  # where the omni was last seen relative to the axis
            if abs(self.turned()) >= goal:
                self._phase = "orbit" if self._orbit else "cross"
                self._orbit = False
                self._before_at = self._past_at = None
                # turning swings the omni sideways: it may have swept over the axis already
                self._band_seen = self._sweep <= 0
                self._cross_path = snap.odometry.path_mm
                self._last_seen = snap.time  # turning away may hide the beams for a while
                self.mark_distance()
            else:
                w = 90.0 * self._cross_side
                self.wheels(-w, w)
                return _RUN
        if self._phase == "retreat":
            # out of the force field while a buoy is still in sight, but never out of
            # every beam: that would leave the search to find the dock again
            if hazard is not None or not view.omni.from_dock or self.travelled() > 600.0:
                self._centred = False
                self._start_facing(self._spin_dir)
                self.halt()
                return _RUN
            self.wheels(-120, -120)
            return _RUN
        if self._phase == "orbit":
            status = self._circle(view, hazard, speed)
            if status is not None:
                return status
        if self._phase == "cross":
            status = self._cross(view, hazard, speed)
            if status is not None:
                return status
        if self._phase == "back":
            if snap.time < self._back_until:
                self.wheels(-120, -120)
                return _RUN
            self._start_facing(self._spin_dir)
            self.halt()
        return _RUN

    def _start_retreat(self) -> Status:
        """No progress: back straight away from the dock (it is ahead), then come in again
        along the beams, so that the next crossing starts from the edge of the force field,
        where the band around the axis is wider, instead of repeating the same moves."""
        self._retreat = False
        self._crossings = 0
        self._phase = "retreat"
        self.mark_distance()
        return _RUN

    def _omni_state(self, view: DockView) -> int | None:
        """Where the omni receiver is relative to the axis, seen from the side the robot
        set out from (``_cross_side``): 1 before it (the near buoy alone), 0 in the band
        (both buoys), -1 past it (the far buoy alone), None when it sees no buoy."""
        omni = view.omni
        if not omni.from_dock or not (omni.red_buoy or omni.green_buoy):
            return None
        if omni.red_buoy and omni.green_buoy:
            return 0
        return 1 if (1 if omni.red_buoy else -1) == self._cross_side else -1

    def _circle(self, view: DockView, hazard: str | None, speed: float) -> Status | None:
        """Circle the dock along the edge of its force field until the omni sees a buoy.

        In the force field with no buoy in sight (outside the buoys' wedges) the side of
        the axis is unknown. A straight line toward a guessed side is nearly a tangent
        there: it left the field after a few tens of degrees around the dock, the next
        guess went back the other way, and the robot shuttled between two points
        without ever reaching a buoy. Keeping the omni on the field's edge (turn away
        from the dock inside it, toward it outside) sweeps every bearing in the guessed
        direction; a bump (the wall beside the dock) or 3.5 m without a buoy (half a circle
        around a 1 m field) ends it, and the next guess circles the other way. None: go on
        this tick."""
        snap = self.snapshot
        if self._omni_state(view) is not None:
            self._start_facing(-float(self._cross_side))  # a buoy: the side is known now
            self.halt()
            return _RUN
        if hazard is not None or snap.odometry.path_mm - self._cross_path > 3500.0:
            self._start_facing(-float(self._cross_side))
            if hazard is not None:
                self._phase = "back"
                self._back_until = snap.time + 0.5
                return None
            self.halt()
            return _RUN
        v = 0.8 * speed
        # the dock is on the side opposite to the turn away (_cross_side +1: on the right);
        # the wheel on the side to turn to runs slow
        near, far = (v, 0.2 * v) if view.omni.force_field else (0.2 * v, v)
        if self._cross_side > 0:
            self.wheels(far, near)
        else:
            self.wheels(near, far)
        return _RUN

    def _cross(self, view: DockView, hazard: str | None, speed: float) -> Status | None:
        """Move along the crossing line until the centre is on the dock's axis, then face it.

        Only the omni receiver is read: it sits on the crossing line, ``OMNI_AHEAD_MM``
        ahead of the centre. Along that line (``s``, the signed odometry distance) it sees
        the near buoy alone ("before" the axis), both (the band around the axis), then the
        far buoy alone ("past"). The axis is half-way between the last "before" and the
        first "past", and the centre is there when the omni is ``OMNI_AHEAD_MM`` beyond it.
        Close to the dock the band is a few centimetres wide and the omni is often past the
        axis as soon as the robot has turned: then it backs up to find the near edge
        instead of driving on (driving a fixed distance from wherever the omni first saw
        the band overshot the axis by up to 12 cm, and the robot crossed back and forth
        without ever landing in the band). None: go on with the next phase this tick.
        """
        snap = self.snapshot
        s = snap.odometry.distance_mm - self._distance_mark
        state = self._omni_state(view)
        if state == 0:
            self._band_seen = True
        elif state == 1:
            self._before_at = s if self._before_at is None else max(self._before_at, s)
        elif state == -1:
            self._past_at = s if self._past_at is None else min(self._past_at, s)
        path = snap.odometry.path_mm - self._cross_path
        left_field = not view.seen and snap.time - self._last_seen > 1.0
        if hazard is not None or left_field or path > 1500.0:
            if view.side == 0:
                self._last_side = 0  # whatever side was believed, it did not work
            self._start_facing(-float(self._cross_side))
            if hazard is not None and self._last_wheels[0] + self._last_wheels[1] > 0:
                self._phase = "back"
                self._back_until = snap.time + 0.5
                return None
            self.halt()
            return _RUN
        slow = 0.6 if view.force_field else 1.0
        before, past = self._before_at, self._past_at
        if before is not None and past is not None:
            err = (before + past) / 2.0 + OMNI_AHEAD_MM - s
            if abs(err) < 4.0:
                self._centred = True
                self._start_facing(-float(self._cross_side))
                self.halt()
                return _RUN
            v = math.copysign(max(30.0, min(speed * slow, 1.5 * abs(err))), err)
        elif before is None and (past is not None or self._band_seen):
            if s < -400.0:  # no near buoy behind: give up this crossing, face again
                self._start_facing(-float(self._cross_side))
                self.halt()
                return _RUN
            v = -0.6 * speed * slow  # the omni is already over the axis: back to its near edge
        else:
            v = speed * slow
        self.wheels(v, v)
        return _RUN

    def _start_facing(self, spin_dir: float) -> None:
        self._phase = "face"
        self._spin_dir = spin_dir
        self._lead_theta: float | None = None
        self._face_target: float | None = None
        self.mark_turn()

    def _face(self, view: DockView) -> bool:
        """Turn to face the dock; True once facing it.

        Spinning counter-clockwise, the dock passes from the left receiver to the right one
        (clockwise: the other way round). Both at once: facing. At the edge of a beam the
        two may never see it together: then the heading half-way between the last one seen
        by the leading receiver and the first one by the trailing receiver is the dock's."""
        theta = self.heading()
        if self._face_target is not None:
            err = math.remainder(self._face_target - theta, math.tau)
            if abs(err) < math.radians(2.0) or view.facing:
                self.halt()
                return True
            w = 60.0 if abs(err) > math.radians(8.0) else 35.0
            self.wheels(-w if err > 0 else w, w if err > 0 else -w)
            return False
        if view.facing:
            self.halt()
            return True
        left, right = view.left.from_dock, view.right.from_dock
        lead, trail = (left, right) if self._spin_dir > 0 else (right, left)
        if lead:
            self._lead_theta = theta
        if trail and not lead:
            if self._lead_theta is None:
                self._spin_dir = -self._spin_dir  # the dock is on the trailing side: go back
                self.mark_turn()
            else:
                gap = math.remainder(theta - self._lead_theta, math.tau)
                self._face_target = self._lead_theta + gap / 2.0
                return False
        if (
            self._lead_theta is not None
            and not (left or right)
            and abs(math.remainder(theta - self._lead_theta, math.tau)) > math.radians(60.0)
        ):
            # seen at one heading only (the fringe of a beam): face that way and go closer
            self._face_target = self._lead_theta
            return False
        if abs(self.turned()) > math.radians(540.0):
            self._lead_theta = None
            self.mark_turn()
        w = 70.0 if (left or right) else 110.0
        self.wheels(-w * self._spin_dir, w * self._spin_dir)
        return False

    _crossings = 0
    _before_at: float | None = None
    _past_at: float | None = None
    _band_seen = False
    _cross_path = 0.0
    _orbit = False
    _sweep = 1
    _centred = False
    _retreat = False
    _run: object = None
    _starts = 0
    _lead_theta: float | None = None
    _face_target: float | None = None
    _phase = "face"
    _cross_side = 1
    _side_guess = 0
    _last_side = 0
    _last_side_time = 0.0
    _guesses = 0
    _spin_dir = 1.0
    _last_seen = 0.0
    _back_until = 0.0


# --------------------------------------------------------------------------- final alignment


@declare(
    "dock_drive_on",
    kind="action",
    params=(
        Param("speed", SPEED, default="120 mm/s", minimum=20, maximum=_WHEEL.maximum,
              doc="speed along the axis outside the force field"),
        Param("slow", SPEED, default="60 mm/s", minimum=10, maximum=_WHEEL.maximum,
              doc="speed inside the force field"),
        Param("wiggle", ANGLE, default="12deg", minimum=0, maximum=45,
              doc="how far it turns each way on contact to seat the charging contacts"),
        Param("timeout", DURATION, default="45s", minimum=1,
              doc="FAILURE if the home base is not reached by then"),
    ),
    reads=(*IR_PACKETS, 7, 34, *ODOMETRY_PACKETS),
    sends=(137, 145),
)  # fmt: skip
class DockDriveOn(_DockingAction):
    """Final alignment: drive onto the contacts along the axis (SUCCESS: packet 34 shows
    the home base).

    Steers to keep both directional receivers on the dock (one alone: turn toward it), nudges
    toward the axis when only one buoy is seen, slows down in the force field. On contact
    without the home-base bit it wiggles in place (``wiggle`` each way) to seat the
    contacts; FAILURE if that does not make contact, so a recovery can back off and retry.
    """

    stage = "final alignment"

    def start(self) -> None:
        self.begin()
        self._phase = "drive"
        self._last_seen = self.snapshot.time
        self.mark_turn()

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        if frame.charging_sources.home_base:
            return self.succeed()
        if self.elapsed() >= self.number("timeout") - 1e-9:
            return self.fail(f"did not reach the contacts in {self.number('timeout'):g} s")
        if self.not_driving():
            return self.fail(self.fallback_message())
        view = DockView.of(frame)
        if view.seen:
            self._last_seen = snap.time
        elif snap.time - self._last_seen > 1.5:
            return self.fail("lost the dock's beams")
        bumped = bool(frame[7] & 3)
        if self._phase == "drive":
            if bumped:
                if not (view.red or view.green):
                    # the plate is in the buoys' beams: outside them, it is something else
                    return self.fail("bumped into something that is not the dock")
                self._phase = "wiggle"
                self._wiggle_step = 0
                self.mark_turn()
            else:
                speed = self.number("slow") if view.force_field else self.number("speed")
                if view.on_left:
                    self.wheels(speed * 0.3, speed * 0.3 + 50)
                elif view.on_right:
                    self.wheels(speed * 0.3 + 50, speed * 0.3)
                elif not view.facing:
                    self.wheels(speed * 0.5, speed * 0.5)
                else:
                    nudge = 0.15 * speed * view.side  # red only: axis on the left
                    self.wheels(speed - nudge, speed + nudge)
                return _RUN
        # wiggle in place: +w, back through 0 to -w, back to 0
        w = math.radians(self.number("wiggle"))
        targets = (w, -w, 0.0)
        if self._wiggle_step >= len(targets):
            return self.fail("touched the dock but the contacts did not engage")
        goal = targets[self._wiggle_step]
        err = goal - self.turned()
        if abs(err) < math.radians(1.0):
            self._wiggle_step += 1
            self.halt()
            return _RUN
        spin = 30.0 if err > 0 else -30.0
        self.wheels(-spin + 8.0, spin + 8.0)  # keep a little forward push on the plate
        return _RUN

    _phase = "drive"
    _wiggle_step = 0
    _last_seen = 0.0


# --------------------------------------------------------------------------- wait for charge


@declare(
    "dock_wait_charge",
    kind="action",
    params=(
        Param("timeout", DURATION, default="10s", minimum=0.1,
              doc="FAILURE if charging is not confirmed by then"),
    ),
    reads=(21, 34),
)  # fmt: skip
class DockWaitCharge(Action):
    """SUCCESS when charging is confirmed: packet 34's home-base bit AND a charging state
    (reconditioning, full, trickle) in packet 21. The robot charges only in Passive: put a
    ``mode: passive`` before this leaf."""

    stage = "wait for charge"

    def start(self) -> None:
        _note_stage(self.stage)
        self._t0 = self.snapshot.time

    def update(self) -> Status:
        frame = self.snapshot.frame
        home = frame.charging_sources.home_base
        if home and frame.charging_state.is_charging:
            return _OK
        if self.snapshot.time - self._t0 >= self.number("timeout") - 1e-9:
            why = "charging state stays" if home else "the home base is not powering the robot;"
            state = frame.charging_state.name.lower().replace("_", " ")
            self.feedback_message = (
                f"{self.stage}: {why} {state} after {self.number('timeout'):g} s"
                if home
                else f"{self.stage}: {why} charging state {state}"
            )
            return _FAIL
        return _RUN

    _t0 = 0.0


# --------------------------------------------------------------------------- time limit


@declare(
    "dock_time_limit",
    kind="action",
    params=(Param("limit", DURATION, required=True, minimum=1,
                  doc="give up after this much mission time"),),
    primary="limit",
)  # fmt: skip
class DockTimeLimit(Action):
    """RUNNING until ``limit`` has passed, then FAILURE: ``gave up after 300 s in stage
    approach``. Run it in a ``parallel`` (policy ``one``) beside the docking stages."""

    def start(self) -> None:
        self._t0 = self.snapshot.time
        storage = py_trees.blackboard.Blackboard.storage
        storage.pop(STAGE_KEY, None)  # a new docking run
        storage[RUN_KEY] = (id(self), self._t0)

    def update(self) -> Status:
        if self.snapshot.time - self._t0 >= self.number("limit") - 1e-9:
            stage = current_stage() or "search"
            self.feedback_message = (
                f"{stage}: gave up after the time limit of {self.number('limit'):g} s "
                f"(stage {stage} was running)"
            )
            return _FAIL
        return _RUN

    _t0 = 0.0


DOCKING: tuple[type[Action], ...] = (
    DockSearch, DockApproach, DockDriveOn, DockWaitCharge, DockTimeLimit,
)  # fmt: skip
