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
from collections.abc import Mapping
from typing import Any

from py_trees.common import Status

from roomba_bt.behaviours import driving
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.declare import Param, declare, wheel_speed_param
from roomba_bt.behaviours.units import ANGLE, DISTANCE, INT, enum
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import ENCODER_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS, SensorFrame
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import WHEEL_BASE_MM

_OK, _RUN = Status.SUCCESS, Status.RUNNING
#: at a lane's end: back off this far (mm) before turning (from a bump: room to turn and move
#: over without touching; from a cliff: the cliff sensors back over the floor), and never
#: further than the lane or shift it drove: a robot sees nothing behind it, and the floor
#: behind a line begun after a turn in place is floor it has not driven (``cover`` keeps a
#: trail for it: :mod:`.reversing`)
_BACK_MM = {"bump": 30.0, "cliff": 60.0}
#: turning in place: done within this angle of the target
#: a lane or shift that makes no progress for this long (s) ends: something holds the robot
_STALL_S = 3.0


class _Pattern(Action):
    """A cleaning pattern: each tick the driving leaves' guard (:func:`.driving.held`), then
    the pattern's wheel speeds (Drive Direct); None from :meth:`wheel_speeds` ends it: the
    wheels halt, SUCCESS."""

    moves = True

    def update(self) -> Status:
        waiting = driving.held(self)
        if waiting is not None:
            return waiting
        wheels = self.wheel_speeds(self.snapshot.frame)
        if wheels is None:
            self.send(oi.halt())
            self._started_motion = False
            return _OK
        self.send(driving.drive_wheels(*wheels))
        self._started_motion = True
        return _RUN

    def wheel_speeds(self, frame: SensorFrame) -> tuple[float, float] | None:
        """This tick's (left, right) wheel speeds, mm/s; None when the pattern is done."""
        raise NotImplementedError


# --------------------------------------------------------------------------- spiral


_START_RADIUS = Param(
    "start_radius",
    DISTANCE,
    default="10 cm",
    minimum=10,
    maximum=2000,
    doc="less than max_radius (a spiral that starts at its widest is refused)",
)
_MAX_RADIUS = Param("max_radius", DISTANCE, default="1.2 m", minimum=50, maximum=5000,
                    doc="SUCCESS once the spiral is this wide")  # fmt: skip


def _spiral_grows(params: Mapping[str, Any]) -> list[str]:
    """A spiral that starts at or beyond its ``max_radius`` is over before it moves (it
    succeeded on its first tick, nothing driven). Values read from the blackboard pass."""
    start = params.get("start_radius", DISTANCE.parse(_START_RADIUS.default))
    widest = params.get("max_radius", DISTANCE.parse(_MAX_RADIUS.default))
    if not isinstance(start, int | float) or not isinstance(widest, int | float):
        return []
    if start >= widest:
        return [
            f"start_radius {start:g} mm is not below max_radius {widest:g} mm"
            f"{'' if 'max_radius' in params else ' (its default)'}: the spiral would be over "
            "before it moved; start_radius must be less than max_radius"
        ]
    return []


@declare(
    "spiral",
    kind="action",
    params=(
        wheel_speed_param("speed", "300 mm/s", minimum=20,
                          doc="speed of the robot's centre along the spiral"),
        Param("spacing", DISTANCE, default="25 cm", minimum=50, maximum=1000,
              doc="the radius grows this much a turn (the swept strip is 27.5 cm wide)"),
        _START_RADIUS,
        _MAX_RADIUS,
    ),
    reads=(*driving.BLOCKED_PACKETS, *ENCODER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS),
    sends=opcodes("drive_direct", "drive"),
    constraints=_spiral_grows,
)  # fmt: skip
class Spiral(_Pattern):
    """Spiral outward, turning left, over open floor (the radius grows by ``spacing`` a turn,
    so the rings lie side by side): SUCCESS when it is ``max_radius`` wide
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
        why = driving.blocked(frame) or ("wall ahead" if driving.near_ahead(frame) else None)
        if why is None and radius > self.number("max_radius"):
            why = "wide enough"
        if why is not None:
            self.feedback_message = why
            return None
        speed = self.number("speed")
        base = self.robot.profile.wheel_base_mm if self.robot is not None else WHEEL_BASE_MM
        return driving.arc_wheels(speed, radius, base / 2.0)


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
        wheel_speed_param("speed", "300 mm/s", minimum=20),
        wheel_speed_param("turn_speed", "200 mm/s", minimum=20,
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
    reads=(*driving.BLOCKED_PACKETS, *ENCODER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS),
    sends=opcodes("drive_direct", "drive"),
)  # fmt: skip
class Lanes(_Pattern):
    """Sweep the floor in parallel lanes, back and forth (boustrophedon), by odometry.

    A lane runs until a bump or a cliff (then it backs off 3 or 6 cm, at most as far as it
    drove along it), a virtual wall's beam or
    ``max_lane``; the robot turns 90 degrees toward ``side``, moves over by the spacing, turns
    90 degrees again and runs the next lane the other way. SUCCESS when a move over is
    blocked before half its length (the sweep has reached the far side) or after ``lanes``
    lanes; FAILURE on a wheel drop or when the robot leaves Safe/Full. Wheel speeds from
    Drive Direct (145)."""

    def start(self) -> None:
        heading = self.snapshot.odometry.theta_rad
        self._heading = driving.wrap(heading + math.radians(self.number("angle")))
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
        self._line: driving.Line = (odo.x_mm, odo.y_mm, heading)
        self._progress = (0.0, self.snapshot.time)

    def _along_line(self) -> tuple[float, float]:
        """(distance along the current line, signed offset to its left), mm."""
        odo = self.snapshot.odometry
        return driving.along_line(self._line, odo.x_mm, odo.y_mm)

    def _steer(self, speed: float) -> tuple[float, float]:
        """Wheel speeds holding the current line."""
        odo = self.snapshot.odometry
        return driving.steer_along(self._line, odo.x_mm, odo.y_mm, odo.theta_rad, speed)

    def wheel_speeds(self, frame: SensorFrame) -> tuple[float, float] | None:
        """This tick's wheel speeds, or None when the sweep is done. A phase that ends hands
        over to the next in the same tick."""
        snap = self.snapshot
        for _ in range(4):
            phase = self._phase
            if phase == "turn":
                error = driving.wrap(self._target - snap.odometry.theta_rad)
                if abs(error) > driving.TURN_TOLERANCE:
                    return driving.turn_toward(error, self.number("turn_speed"), 40.0, 400.0)
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
            why = driving.blocked(frame)
            stalled = snap.time - self._progress[1] >= _STALL_S
            limit = self.number("max_lane") if phase == "lane" else self._shift
            if why is None and not stalled and along < limit:
                if phase == "shift":
                    return self._steer(min(self.number("speed"), 200.0))
                speed = self.number("speed")
                return self._steer(min(speed, 150.0) if driving.near_ahead(frame) else speed)
            self._achieved = along
            if why in _BACK_MM:  # no further than the line it drove: it sees nothing behind
                self._back = min(_BACK_MM[why], max(along, 0.0))
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
            forward = abs(driving.wrap(self._lane_heading - self._heading)) < math.pi / 2
            to_left = (self.value("side") == "left") == forward
            self._shift = self.number("shift_left" if to_left else "shift_right")
            turn = math.pi / 2 if to_left else -math.pi / 2
            self._begin_turn(driving.wrap(self._lane_heading + turn), "shift")
            return True
        if achieved < 0.5 * self._shift:
            return False  # the far side: nothing more to sweep this way
        self._lane_heading = driving.wrap(self._lane_heading + math.pi)
        self._begin_turn(self._lane_heading, "lane")
        return True


CLEANING: tuple[type[Action], ...] = (Spiral, Lanes)
