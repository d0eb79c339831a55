"""Cleaning motions: a spiral over open floor, and lanes back and forth (boustrophedon).

Both steer by the odometry of the snapshot (the encoders' pose in the start frame) and stop
for hazards themselves, in the tick that shows them: a bump, a cliff or a virtual wall's beam
ends a spiral or a lane (the lane's end is where the next lane starts), a wheel drop fails.
So they also run in Full mode, where a cliff is a lane's end and not the firmware's fall back
to Passive (Safe mode's cliff safety turns the brushes off; Full mode's does not exist, so
these leaves stop before the drop: the cliff sensors look 150 mm ahead of the centre).

Lanes, seen from above (the robot's swept strip reaches 90 mm to its left and 185 mm to its
right, its side brush being on the right, so a shift toward the robot's left is shorter)::

       shift_left            <---------------------------- lane 2 (heading + 180 deg)
                                                         |
       lane 1 (heading) ---------------------------->    |  shift_right
       |                                                 v
       <---------------------------------------------- lane 0 ... (wall: bump, turn, shift)

A lane holds its line (the line through where it started, along the lane heading): the
steering corrects the heading error and the sideways drift, so lanes stay parallel by
odometry. The lanes' direction is the robot's heading when they start, turned by ``angle``:
started at the end of a stretch of wall following, they run along that wall (or across the
room), so a mission that follows a wall before each sweep re-anchors its lanes on a real wall
however far the odometry's heading has drifted since the last.
"""

from __future__ import annotations

import math

from py_trees.common import Status

from roomba_bt.behaviours.declare import WHEEL, Action, Param, declare, wheel_speeds
from roomba_bt.behaviours.units import ANGLE, DISTANCE, INT, SPEED, enum
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import (
    BUMPS_PACKETS,
    CLIFF_PACKETS,
    ENCODER_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    VIRTUAL_WALL_PACKETS,
    SensorFrame,
)
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import WHEEL_BASE_MM

_OK, _RUN, _FAIL = Status.SUCCESS, Status.RUNNING, Status.FAILURE
_HAZARDS = (*BUMPS_PACKETS, *CLIFF_PACKETS, *VIRTUAL_WALL_PACKETS)
#: a centre light-bump signal above this: something within a few centimetres, slow down
_NEAR_SIGNAL = 150
#: at a lane's end: back off this far (mm) before turning (from a bump: room to turn and move
#: over without touching; from a cliff: the cliff sensors back over the floor)
_BACK_MM = {"bump": 30.0, "cliff": 60.0}
#: turning in place: done within this angle of the target
_TURN_TOLERANCE = math.radians(2.0)
#: a lane or shift that makes no progress for this long (s) ends: something holds the robot
_STALL_S = 3.0


def _wheels(left: float, right: float) -> oi.Command:
    lo, ro = wheel_speeds(left, right)
    return oi.drive_direct(ro, lo)


def _blocked(frame: SensorFrame) -> str | None:
    """Why the robot must not go on forward (bump, cliff, virtual wall), or None."""
    if frame.any_cliff:
        return "cliff"
    if frame.any_bump:
        return "bump"
    if frame.virtual_wall:
        return "virtual wall"
    return None


def _near(frame: SensorFrame) -> bool:
    signals = frame.light_bump_signals
    return max(signals[1], signals[2], signals[3], signals[4]) >= _NEAR_SIGNAL


def _wrap(angle: float) -> float:
    return math.remainder(angle, math.tau)


def _held(action: Action) -> Status | None:
    """Why a driving leaf cannot drive this tick: a wheel drop fails it; out of Safe/Full it
    waits, and fails once stranded there after it began to move. None: it may drive."""
    snap = action.snapshot
    if snap.frame.any_wheel_drop:
        action.feedback_message = "wheel drop"
        return _FAIL
    if snap.mode not in DRIVING_MODES:
        stranded = action.stranded() if action._started_motion else None
        if stranded is not None:
            action._started_motion = False
            action.feedback_message = stranded
            return _FAIL
        return _RUN
    return None


class _Pattern(Action):
    """A cleaning pattern: each tick :func:`_held`'s guard, then the pattern's wheel speeds
    (Drive Direct); None from :meth:`wheel_speeds` ends it: the wheels halt, SUCCESS."""

    moves = True

    def update(self) -> Status:
        held = _held(self)
        if held is not None:
            return held
        wheels = self.wheel_speeds(self.snapshot.frame)
        if wheels is None:
            self.send(oi.halt())
            self._started_motion = False
            return _OK
        self.send(_wheels(*wheels))
        self._started_motion = True
        return _RUN

    def wheel_speeds(self, frame: SensorFrame) -> tuple[float, float] | None:
        """This tick's (left, right) wheel speeds, mm/s; None when the pattern is done."""
        raise NotImplementedError


# --------------------------------------------------------------------------- spiral


@declare(
    "spiral",
    kind="action",
    params=(
        Param("speed", SPEED, default="300 mm/s", minimum=20, maximum=WHEEL.maximum,
              doc="speed of the robot's centre along the spiral"),
        Param("spacing", DISTANCE, default="25 cm", minimum=50, maximum=1000,
              doc="the radius grows this much a turn (the swept strip is 27.5 cm wide)"),
        Param("start_radius", DISTANCE, default="10 cm", minimum=10, maximum=2000),
        Param("max_radius", DISTANCE, default="1.2 m", minimum=50, maximum=5000,
              doc="SUCCESS once the spiral is this wide"),
    ),
    reads=(*_HAZARDS, *ENCODER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS),
    sends=opcodes("drive_direct"),
)  # fmt: skip
class Spiral(_Pattern):
    """Spiral outward, turning left, over open floor: SUCCESS when it is ``max_radius`` wide
    or something is in the way (a bump, a cliff, a virtual wall, a wall close ahead); the
    wheels halt. FAILURE on a wheel drop, or when the robot leaves Safe/Full.

    The radius grows by ``spacing`` a turn: ``r = start_radius + spacing * turned / 360 deg``,
    so the rings lie side by side; the outside of the turn is the robot's right, where the
    side brush widens the strip. Wheel speeds from Drive Direct (145)."""

    def start(self) -> None:
        self._start_angle = self.snapshot.odometry.angle_rad

    def wheel_speeds(self, frame: SensorFrame) -> tuple[float, float] | None:
        snap = self.snapshot
        turned = abs(snap.odometry.angle_rad - self._start_angle)
        radius = self.number("start_radius") + self.number("spacing") * turned / math.tau
        why = _blocked(frame) or ("wall ahead" if _near(frame) else None)
        if why is None and radius > self.number("max_radius"):
            why = "wide enough"
        if why is not None:
            self.feedback_message = why
            return None
        speed = self.number("speed")
        base = self.robot.profile.wheel_base_mm if self.robot is not None else WHEEL_BASE_MM
        half_base = base / 2.0
        return speed * (radius - half_base) / radius, speed * (radius + half_base) / radius


# --------------------------------------------------------------------------- lanes


@declare(
    "lanes",
    kind="action",
    params=(
        Param("angle", ANGLE, default="0deg", minimum=-360, maximum=360,
              doc="the lanes' direction from the robot's heading when they start (after "
                  "following a wall, 0deg: along the wall, 90deg: across the room)"),
        Param("side", enum("left", "right"), default="left",
              doc="the side the lanes advance to (left: away from a wall on the right)"),
        Param("speed", SPEED, default="300 mm/s", minimum=20, maximum=WHEEL.maximum),
        Param("turn_speed", SPEED, default="200 mm/s", minimum=20, maximum=WHEEL.maximum,
              doc="wheel speed when turning in place"),
        Param("shift_left", DISTANCE, default="15 cm", minimum=20, maximum=1000,
              doc="lane spacing when the next lane is to the robot's left"),
        Param("shift_right", DISTANCE, default="32 cm", minimum=20, maximum=1000,
              doc="lane spacing when the next lane is to the robot's right (the side "
                  "brush's side: the strip is wider there)"),
        Param("max_lane", DISTANCE, default="12 m", minimum=100, maximum=100_000,
              doc="a lane ends after this far even if nothing is in the way"),
        Param("lanes", INT, default=200, minimum=1, maximum=10_000,
              doc="SUCCESS after this many lanes"),
    ),
    reads=(*_HAZARDS, *ENCODER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS),
    sends=opcodes("drive_direct"),
)  # fmt: skip
class Lanes(_Pattern):
    """Sweep the floor in parallel lanes, back and forth (boustrophedon), by odometry.

    A lane runs until a bump or a cliff (then it backs off 3 or 6 cm), a virtual wall's beam or
    ``max_lane``; the robot turns 90 degrees toward ``side``, moves over by the spacing, turns
    90 degrees again and runs the next lane the other way. SUCCESS when a move over is
    blocked before half its length (the sweep has reached the far side) or after ``lanes``
    lanes; FAILURE on a wheel drop or when the robot leaves Safe/Full. Wheel speeds from
    Drive Direct (145)."""

    def start(self) -> None:
        heading = self.snapshot.odometry.theta_rad
        self._heading = _wrap(heading + math.radians(self.number("angle")))
        self._lanes = 0
        self._lane_heading = self._heading
        self._shift = 0.0
        self._achieved = 0.0  # how far the lane or shift a bump or cliff ended had gone
        self._back = 0.0
        self._begin_turn(self._lane_heading, "lane")  # the first lane: from where it is

    # Phases: "turn" to a heading, then a "lane" or a "shift" along a line; "back" off a
    # bump or a cliff, then what it ended.
    def _begin_turn(self, target: float, then: str) -> None:
        self._phase, self._target, self._then = "turn", target, then

    def _begin_line(self, phase: str, heading: float, then: str = "") -> None:
        odo = self.snapshot.odometry
        self._phase, self._then = phase, then
        self._line = (odo.x_mm, odo.y_mm, heading)
        self._progress = (0.0, self.snapshot.time)

    def _along_line(self) -> tuple[float, float]:
        """(distance along the current line, signed offset to its left), mm."""
        odo = self.snapshot.odometry
        x0, y0, heading = self._line
        dx, dy = odo.x_mm - x0, odo.y_mm - y0
        c, s = math.cos(heading), math.sin(heading)
        return dx * c + dy * s, -dx * s + dy * c

    def _steer(self, speed: float) -> tuple[float, float]:
        """Wheel speeds holding the current line: heading error plus sideways drift."""
        _, offset = self._along_line()
        heading = self._line[2] - math.atan(max(-1.0, min(1.0, offset / 300.0)))
        error = _wrap(heading - self.snapshot.odometry.theta_rad)
        turn = max(-0.5 * speed, min(0.5 * speed, 600.0 * error))
        return speed - turn, speed + turn

    def wheel_speeds(self, frame: SensorFrame) -> tuple[float, float] | None:
        """This tick's wheel speeds, or None when the sweep is done. A phase that ends hands
        over to the next in the same tick."""
        snap = self.snapshot
        for _ in range(4):
            phase = self._phase
            if phase == "turn":
                error = _wrap(self._target - snap.odometry.theta_rad)
                if abs(error) > _TURN_TOLERANCE:
                    w = min(self.number("turn_speed"), max(40.0, 400.0 * abs(error)))
                    return (-w, w) if error > 0 else (w, -w)
                self._begin_line(self._then, self._target)
                continue
            along, _ = self._along_line()
            if phase == "back":
                if -along < self._back and snap.time - self._progress[1] < _STALL_S:
                    return (-150.0, -150.0)
                if not self._end_of(self._then, self._achieved):
                    return None
                continue
            if along > self._progress[0] + 10.0:
                self._progress = (along, snap.time)
            why = _blocked(frame)
            stalled = snap.time - self._progress[1] >= _STALL_S
            limit = self.number("max_lane") if phase == "lane" else self._shift
            if why is None and not stalled and along < limit:
                if phase == "shift":
                    return self._steer(min(self.number("speed"), 200.0))
                return self._steer(min(self.number("speed"), 150.0) if _near(frame) else
                                   self.number("speed"))  # fmt: skip
            self._achieved = along
            if why in _BACK_MM:
                self._back = _BACK_MM[why]
                self._begin_line("back", snap.odometry.theta_rad, then=phase)
                continue
            if not self._end_of(phase, along):
                return None
        return (0.0, 0.0)

    def _end_of(self, phase: str, achieved: float) -> bool:
        """A lane or a shift has ended after ``achieved`` mm: set up what follows; False when
        the sweep is done."""
        if phase == "lane":
            self._lanes += 1
            if self._lanes >= int(self.number("lanes")):
                return False
            # toward the side the lanes advance to: the robot's left or right on this lane
            forward = abs(_wrap(self._lane_heading - self._heading)) < math.pi / 2
            to_left = (self.value("side") == "left") == forward
            self._shift = self.number("shift_left" if to_left else "shift_right")
            turn = math.pi / 2 if to_left else -math.pi / 2
            self._begin_turn(_wrap(self._lane_heading + turn), "shift")
            return True
        if achieved < 0.5 * self._shift:
            return False  # the far side: nothing more to sweep this way
        self._lane_heading = _wrap(self._lane_heading + math.pi)
        self._begin_turn(self._lane_heading, "lane")
        return True


CLEANING: tuple[type[Action], ...] = (Spiral, Lanes)
