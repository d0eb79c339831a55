"""What the driving leaves share: the wheel command, the hazards that end a move, the wait
for Safe/Full, and the geometry of their moves, each said once.

The cleaning patterns (``spiral``, ``lanes``), ``cover``, ``wall_follow`` and the docking
stages all drive with Drive Direct (145), wheel speeds clamped to what it takes::

    [145][right hi][right lo][left hi][left lo]      (signed 16-bit mm/s, -500..500)

and steer by the odometry of the snapshot. Their moves, as (left, right) wheel speeds (mm/s):

* turning in place toward the side of a heading error: ``(-w, w)`` to the left (counter-
  clockwise, error > 0), ``(w, -w)`` to the right (:func:`spin_toward`, :func:`turn_toward`);
* holding a straight line through a point (:func:`steer_along`): the heading error plus the
  sideways drift, so a lane stays on its line and lanes stay parallel::

        offset (mm, + to the line's left) -> aim atan(offset / 300 mm) back toward the line
        turn = 600 mm/s per rad of error, at most half the speed; (speed - turn, speed + turn)

* an arc of a radius around a point on one side (:func:`arc_wheels`): both wheels at the
  centre's speed scaled by their own radius, ``radius -+ half the wheel base``;
* the map-driven leaves' (``cover``, ``home_by_map``) turn in place (:func:`turning_to`) and
  back-off from what :func:`blocked` names (:func:`backing_to`): ``(-250, -250)`` for
  :data:`BACK_OFF_MM` (a bump 30 mm, a cliff 60, a virtual wall's beam 100), at most
  :data:`BACK_GIVE_UP_S`; and their straight drives' stall: no :data:`PROGRESS_MM` along the
  line for :data:`STALL_S`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from py_trees.common import Status

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import (
    BUMPS_PACKETS,
    CLIFF_PACKETS,
    VIRTUAL_WALL_PACKETS,
    SensorFrame,
)
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME
from roomba_bt.robot.interface import (
    ModeChange,
    RobotHandle,
    Snapshot,
    docked_by_seek_dock,
    on_home_base,
)

if TYPE_CHECKING:  # the leaves' base imports this module: their class for annotations only
    from roomba_bt.behaviours.base import Action

__all__ = [
    "CHARGER_ADVICE",
    "WHEEL",
    "cycle_may_run",
    "left_driving_message",
    "needs_mode_message",
    "on_home_base",
    "BACK_GIVE_UP_S",
    "BACK_MM_S",
    "BACK_OFF_MM",
    "BLOCKED_PACKETS",
    "NEAR_SIGNAL",
    "PROGRESS_MM",
    "STALL_S",
    "TURN_GIVE_UP_S",
    "TURN_TOLERANCE",
    "Line",
    "WALL_AHEAD_CLOSE",
    "WallAhead",
    "along_line",
    "arc_wheels",
    "backing_to",
    "blocked",
    "drive_wheels",
    "held",
    "near_ahead",
    "spin_toward",
    "steer_along",
    "turn_toward",
    "turning_to",
    "wheel_speeds",
    "wrap",
]

#: One wheel's speed as Drive Direct takes it, mm/s (-500..500, from the opcode table): the
#: bound of every wheel-speed parameter and of what a driving action sends.
WHEEL = COMMANDS_BY_NAME["drive_direct"].args[0]


#: What to do when Safe was refused on a powered charger: the user's two ways out, the
#: second by the name the shipped missions use (missions/lib/undock.yaml)
CHARGER_ADVICE = (
    "Safe mode on a powered dock drops to Passive at once: start the robot off the dock, or "
    "begin the mission with the `undock` subtree (`subtree: {id: undock}`, from "
    "`include: [roomba-bt:lib/undock.yaml]`), which backs off the dock in Full first, as "
    "missions/clean.yaml does"
)


def left_driving_message(change: ModeChange | None, waited: str = "") -> str:
    """The failure message of a leaf whose robot left Safe/Full by itself: the cause, and,
    when the cause is the charger refusing a Safe just sent (the robot started on its
    dock), what to do about it; the bare "(charger)" left an owner guessing."""
    cause = f" ({change.cause})" if change is not None else ""
    message = f"the robot left Safe/Full mode{cause}{waited}"
    if change is not None and change.refused_on_charger:
        message += f"; {CHARGER_ADVICE}"
    return message


def needs_mode_message(what: str, needs: frozenset[OIMode], snap: Snapshot) -> str:
    """The failure message of a leaf (``what``: its behaviour's name) that would send a command
    only ``needs`` take while the robot, as ``snap`` has it, is in another mode: the mode,
    since when and why when its fall by itself put it there (the run places the fall in
    mission time), and the fix; on a powered charger that refused Safe, what to do there. A
    ``turn`` that waited instead, started after a wheel drop had dropped the robot to
    Passive, would send nothing and wait for ever, its run ending at ``--timeout`` with "ran
    out in turn", no word of Passive: failing lets a ``retry`` or a fallback put the
    robot back in Safe and go on."""
    change = snap.last_fallback
    why = ""
    if change is not None and change.current is snap.mode:  # the fall put it there
        since = change.mission_time
        why = f"{'' if since is None else f' since t={since:.3f}'} ({change.cause})"
    wanted = " or ".join(mode.label for mode in sorted(needs))
    message = (
        f"the robot is in {snap.mode.label}{why}: {what} needs {wanted}; put `mode: safe` "
        "before it, e.g. in a retry"
    )
    if change is not None and change.refused_on_charger:
        message += f"; {CHARGER_ADVICE}"
    return message


def cycle_may_run(robot: RobotHandle) -> bool:
    """Whether a built-in cycle may still be driving the robot: one was written and nothing
    has ended it since (:attr:`Snapshot.cycle_may_run
    <roomba_bt.robot.interface.Snapshot.cycle_may_run>`), the robot is in Passive, and it is
    not a Seek Dock on its home base (docked: that cycle ended there). Any other cycle on the
    home base may be about to drive off it (Clean sent on the dock); ending it there is
    harmless, as Safe on a powered dock drops to Passive at once."""
    snap = robot.snapshot
    if not snap.cycle_may_run or snap.mode is not OIMode.PASSIVE:
        return False
    return not docked_by_seek_dock(robot.outbox.last_on("wheels"), snap.frame)


#: a centre light-bump signal (packets 47-50) at or above this: something within a few
#: centimetres ahead, slow down
NEAR_SIGNAL = 150
#: holding a line: an offset of this much (mm) aims 45 deg back toward it; the turn is this
#: many mm/s of wheel difference per radian of heading error, at most this share of the speed
LINE_OFFSET_MM = 300.0
LINE_TURN_MM_S_PER_RAD = 600.0
LINE_TURN_SHARE = 0.5

#: a centre light-bump signal this high (a wall about 3 cm ahead) turns a :class:`WallAhead`
#: in place even within its hold
WALL_AHEAD_CLOSE = 2000

#: What :func:`blocked` and :func:`held` read: packets 7 (bumps, wheel drops), 9-12 (cliffs)
#: and 13 (a virtual wall), for the ``reads`` of a leaf that calls them.
BLOCKED_PACKETS = (*BUMPS_PACKETS, *CLIFF_PACKETS, *VIRTUAL_WALL_PACKETS)

#: A straight line: a point on it (x, y, mm) and its heading (rad), in the odometry frame.
Line = tuple[float, float, float]


def wheel_speeds(left: float, right: float) -> tuple[int, int]:
    """``left``, ``right`` (mm/s) rounded and clamped to what Drive Direct takes.

    ``max(-limit, min(limit, speed))`` written out as the same comparisons (the same
    result, NaN included): CPython 3.11's ``min`` and ``max`` parse keyword arguments on
    every call, about 1,200 instructions each, and a driving stage asks new speeds on one
    tick in four."""
    limit = WHEEL.maximum
    low = -limit
    lo, ro = round(left), round(right)
    lo = lo if lo < limit else limit
    ro = ro if ro < limit else limit
    return (lo if lo > low else low), (ro if ro > low else low)


def drive_wheels(left: float, right: float) -> oi.Command:
    """Drive Direct with ``left``, ``right`` (mm/s) rounded and clamped (right goes first on
    the wire)."""
    lo, ro = wheel_speeds(left, right)
    return oi.drive_direct(ro, lo)


def wrap(angle: float) -> float:
    """``angle`` (rad) brought into -pi..pi."""
    return math.remainder(angle, math.tau)


def blocked(frame: SensorFrame) -> str | None:
    """Why the robot must not go on forward (cliff, bump, virtual wall), or None."""
    if frame.any_cliff:
        return "cliff"
    if frame.any_bump:
        return "bump"
    if frame.virtual_wall:
        return "virtual wall"
    return None


def near_ahead(frame: SensorFrame) -> bool:
    """One of the four centre light-bump signals is at :data:`NEAR_SIGNAL` or above."""
    signals = frame.light_bump_signals
    return max(signals[1], signals[2], signals[3], signals[4]) >= NEAR_SIGNAL


def held(action: Action, grace: float | None = None) -> Status | None:
    """Why a driving leaf cannot drive this tick: a wheel drop fails it; out of Safe/Full it
    waits, and fails once stranded there after it began to move (after ``grace`` s, the
    action's :attr:`~.Action.PASSIVE_GRACE_S` unless given), or at once when its wheels were
    not turning (:meth:`~.Action.wait_for_driving_mode`). None: it may drive (back in
    Safe/Full, the wait is over: the next time out of them has its own grace)."""
    snap = action.snapshot
    if snap.frame.any_wheel_drop:
        action.feedback_message = "wheel drop"
        return Status.FAILURE
    if snap.mode not in DRIVING_MODES:
        return action.wait_for_driving_mode(grace)
    action.stranded()  # in Safe/Full: clears the time it left them, returns None
    return None


def spin_toward(error: float, speed: float) -> tuple[float, float]:
    """Turn in place at ``speed`` (each wheel, mm/s) toward the side of ``error`` (rad,
    counter-clockwise positive): left when it is positive, else right."""
    return (-speed, speed) if error > 0 else (speed, -speed)


def turn_toward(error: float, top: float, least: float, gain: float) -> tuple[float, float]:
    """Turn in place toward the side of ``error`` (rad), each wheel at ``gain`` mm/s per
    radian of it, between ``least`` (the last degrees still turn) and ``top``."""
    return spin_toward(error, min(top, max(least, gain * abs(error))))


#: a turn in place toward a heading is done within this (rad)
TURN_TOLERANCE = math.radians(2.0)
#: a turn in place toward a heading gives up after this long (s): a wheel held by something
TURN_GIVE_UP_S = 6.0
#: backing off ends after this long (s) whatever the odometry says (a wheel slipping)
BACK_GIVE_UP_S = 1.5
#: the wheels' speed (mm/s) backing off a hazard
BACK_MM_S = 250.0
#: how far (mm) a map-driven leaf (``cover``, ``home_by_map``) backs off each hazard
#: :func:`blocked` names before it goes on: a bump, room to turn without touching it again; a
#: cliff, the cliff sensors back over the floor; a virtual wall's beam, out of it. One table
#: for both: the way home meets what cleaning met, and reacts alike. A plain dict, not a
#: read-only mapping: mypy narrows ``why`` (``str | None``) to ``str`` by ``why in`` a dict
BACK_OFF_MM = {"bump": 30.0, "cliff": 60.0, "virtual wall": 100.0}
#: a straight drive along a line (``cover``'s lanes, shifts and paths, ``home_by_map``'s
#: legs) has made progress when it is this much (mm) further along the line than when it last
#: did; with none for :data:`STALL_S` (s) it is stalled (a wheel held, a bumper pressed on
#: something the sensors do not report) and ends, for a new decision from where it is
PROGRESS_MM = 10.0
STALL_S = 3.0


def turning_to(error: float, started: float, now: float, top: float) -> tuple[float, float] | None:
    """A map-driven turn in place (``cover``'s, ``home_by_map``'s) this tick: the wheel speeds
    toward the side of ``error`` (rad), or None when it faces the heading or has turned for
    :data:`TURN_GIVE_UP_S` since ``started``."""
    if abs(error) <= TURN_TOLERANCE or now - started > TURN_GIVE_UP_S:
        return None
    return turn_toward(error, top, 60.0, 500.0)


def backing_to(distance_mm: float, back_to: float, started: float, now: float) -> bool:
    """Whether a back-off goes on this tick: the odometry's path length still above
    ``back_to`` (mm), and less than :data:`BACK_GIVE_UP_S` since ``started``."""
    return distance_mm > back_to and now - started < BACK_GIVE_UP_S


def along_line(line: Line, x: float, y: float) -> tuple[float, float]:
    """Where (x, y) is from ``line``: (distance along it, signed offset to its left), mm."""
    x0, y0, heading = line
    dx, dy = x - x0, y - y0
    c, s = math.cos(heading), math.sin(heading)
    return dx * c + dy * s, -dx * s + dy * c


def steer_along(line: Line, x: float, y: float, theta: float, speed: float) -> tuple[float, float]:
    """Wheel speeds holding ``line`` from the pose (x, y, theta): heading error plus
    sideways drift (the module's drawing)."""
    _, offset = along_line(line, x, y)
    heading = line[2] - math.atan(max(-1.0, min(1.0, offset / LINE_OFFSET_MM)))
    error = wrap(heading - theta)
    limit = LINE_TURN_SHARE * speed
    turn = max(-limit, min(limit, LINE_TURN_MM_S_PER_RAD * error))
    return speed - turn, speed + turn


def arc_wheels(speed: float, radius: float, half_base: float) -> tuple[float, float]:
    """(inner, outer) wheel speeds (mm/s) of an arc of ``radius`` (mm, of the centre's
    path) at ``speed`` along it: each wheel on its own radius, ``radius -+ half_base``."""
    return speed * (radius - half_base) / radius, speed * (radius + half_base) / radius


class WallAhead:
    """Whether to turn in place at a wall ahead, as a decision that holds: in at ``enter``
    (a centre light-bumper signal), out once it is below ``leave``, and neither change
    sooner than ``hold_s`` after the last one, unless the signal reaches ``close`` (a wall
    a few centimetres ahead turns it at once). One threshold and no hold (``leave`` =
    ``enter``, ``hold_s`` = 0) is a decision taken afresh every tick: along a wall met at a
    shallow angle the signal hovers at the threshold, and the wheels flip every tick or two
    between the turn and driving on (a wheel motor reversed each time, on a real robot)."""

    def __init__(self, enter: int, leave: int, hold_s: float, close: int) -> None:
        self.enter, self.leave, self.hold_s, self.close = enter, leave, hold_s, close
        self._decision = (False, -math.inf)  # turning, since when (s)

    def reset(self) -> None:
        """No turn under way, and no hold: the next tick decides afresh."""
        self._decision = (False, -math.inf)

    def turning(self, front: int, now: float) -> bool:
        """This tick's decision for the centre signal ``front`` at ``now`` (s)."""
        turning, since = self._decision
        held = now - since < self.hold_s - 1e-9
        if turning:
            change = front < self.leave and not held
        else:
            change = front >= self.close or (front >= self.enter and not held)
        if change:
            self._decision = (not turning, now)
        return turning != change
