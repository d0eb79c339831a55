"""The firmware's own behaviours, which run in Passive: Spot (134), Clean (135), Max (136) and
Seek Dock (143). The robot stays in Passive (packet 35 says 1) while one runs; a cycle ends by
itself (its time is up, the battery is low, the dock is reached) or when a mode command that
ends cycles comes (Safe, Full, Power, Stop, Reset: not Start, docs/protocol.md). A Clean, Spot
or Dock button pushed in Passive (Buttons, 165) starts the cycle of its command
(:data:`BUTTON_CYCLES`).

The real firmware's algorithms are not specified; these behave the way a client sees them:

* Spot: an outward spiral at 200 mm/s for 30 s, ended early by a bump or a cliff;
* Clean (10 min, 300 mm/s) and Max (60 min, 400 mm/s): forward until a bump, cliff, virtual
  wall, close light bump or stall, back up 0.3 s, turn a random 0.4-1.4 s, go on;
* Seek Dock: search without a map (straight runs, bounces, wall-following spells) until a
  receiver sees a dock beam, then a point 0.45 m out on the dock's axis, turn to face it,
  drive on slowly.

Components, not a layer: each cycle is an object with its own state (phase and timers), asked
for wheel speeds once a step while it runs. Nothing here is on the step path otherwise.
"""

from __future__ import annotations

import math
import random
from abc import ABC, abstractmethod

from roomba_bt.oi.bits import BUMP_BITS, Buttons
from roomba_bt.oi.ir import IR_CHARACTERS
from roomba_bt.sim.geometry import wrap_angle
from roomba_bt.sim.motion import drive_wheel_speeds
from roomba_bt.sim.power import BATTERY_CAPACITY_MAH, Power
from roomba_bt.sim.world import Pose

Wheels = tuple[float, float]
#: Seek Dock's own limit: it stops searching after 10 minutes.
SEEK_DOCK_LIMIT_S = 600.0
#: Seek Dock's search: the cleaning speed straight, slower along a wall.
_SEARCH_SPEED = 300.0
_FOLLOW_SPEED = 250.0
#: light-bumper signals (0-4095) of the wall following: something ahead within about 9 cm;
#: a wall on the right at all; the right rays' set point (about 5 cm from the wall)
_FOLLOW_AHEAD = 600
_FOLLOW_SEEN = 150
_FOLLOW_SET = 2000
#: which IR characters a home base sends (either family), by code
_FROM_DOCK = tuple(IR_CHARACTERS[code].from_dock for code in range(256))
_STOP: Wheels = (0.0, 0.0)
#: packet 45: the centre left and centre right light bumps (a wall straight ahead)
_LIGHT_BUMPS_CENTRE = 0b001100


class BuiltinCycle(ABC):
    """A built-in behaviour the firmware runs in Passive. :meth:`wheels` gives the wheel
    speeds for this step; once the cycle is over, :attr:`ended` says why."""

    def __init__(self, name: str, started: float, rng: random.Random) -> None:
        self.name = name
        self.started = started
        self.rng = rng  # the robot's: the draws follow one another across cycles
        self.phase = "forward"
        self.phase_until = 0.0
        self.turn_sign = 1.0
        self.ended: str | None = None

    @abstractmethod
    def wheels(self, robot: Power) -> Wheels:
        """The wheel speeds (left, right, mm/s) for this step."""

    def _end(self, why: str) -> Wheels:
        self.ended = why
        return _STOP

    def _bounce(self, robot: Power, speed: float) -> Wheels:
        """Forward until a bump, cliff, virtual wall or close light-bump; back up, turn a
        random amount, go on."""
        now = robot.time
        if self.phase == "forward":
            if _in_the_way(robot):
                self.phase, self.phase_until = "back", now + 0.3
            else:
                return speed, speed
        if self.phase == "back":
            if now < self.phase_until:
                return -150.0, -150.0
            self._start_turn(now)
        if self.phase == "turn":
            turning = self._turning(now)
            if turning is not None:
                return turning
            # a draw that once timed Seek Dock's wander before aiming at the dock; kept so
            # that Clean and Max follow the same random sequence (and recordings) as before
            self.rng.uniform(1.5, 3.0)
        return speed, speed

    def _start_turn(self, now: float) -> None:
        """Turn on the spot a random way for a random 0.4-1.4 s (two draws, in this order)."""
        self.phase = "turn"
        self.turn_sign = self.rng.choice((-1.0, 1.0))
        self.phase_until = now + self.rng.uniform(0.4, 1.4)

    def _turning(self, now: float) -> Wheels | None:
        """The turn's wheels, or None once it is over (the phase is then "forward")."""
        if now < self.phase_until:
            return -150.0 * self.turn_sign, 150.0 * self.turn_sign
        self.phase = "forward"
        return None


def _in_the_way(robot: Power) -> bool:
    """A bump, a cliff, a virtual wall or something close dead ahead: what ends a straight run
    of the firmware's bounce."""
    v = robot.values
    return bool(
        v[7] & BUMP_BITS or any(v[9:13]) or v[13] or v[45] & _LIGHT_BUMPS_CENTRE or robot.blocked
    )


class Spot(BuiltinCycle):
    """An outward spiral for 30 s, until a bump or a cliff."""

    def wheels(self, robot: Power) -> Wheels:
        elapsed = robot.time - self.started
        v = robot.values
        if elapsed > 30.0 or v[7] & BUMP_BITS or any(v[9:13]):
            return self._end("spot done")
        radius = 60.0 + 12.0 * elapsed
        return drive_wheel_speeds(200, int(radius), robot.profile.wheel_base_mm)


class Clean(BuiltinCycle):
    """Bounce around the room: Clean for 10 min at 300 mm/s, Max for 60 min at 400 mm/s;
    either ends early below 5 % of the battery."""

    def __init__(self, name: str, started: float, rng: random.Random) -> None:
        super().__init__(name, started, rng)
        self.limit = 600.0 if name == "clean" else 3600.0
        self.speed = 300.0 if name == "clean" else 400.0

    def wheels(self, robot: Power) -> Wheels:
        if (
            robot.time - self.started > self.limit
            or robot.battery_charge < 0.05 * BATTERY_CAPACITY_MAH
        ):
            return self._end(f"{self.name} done")
        return self._bounce(robot, self.speed)


class SeekDock(BuiltinCycle):
    """Seek Dock as the OI specifications describe it, with no map of the home.

    The Roomba 500 OI: "This command directs Roomba to drive onto the dock the next time it
    encounters the docking beams"; the Create 2: "This command sends Roomba to the dock". The
    firmware knows nothing of where the dock is until a receiver picks up one of its beams, so
    until then this cycle searches as the cleaning cycles move, never reading the dock's pose
    (nor the world's): straight runs at the cleaning speed; at an obstacle it backs up, then
    either turns a random amount or follows the wall on its right (the right light bumper
    rays, round a wall's end as into a doorway) for a random 6-20 s spell. The draws come
    from the robot's seeded generator. Once any receiver (omni 17, left 52, right 53) has
    seen a dock character it homes: to a point 0.45 m out on the dock's axis, turn to face the
    dock, drive on slowly (a stand-in for the firmware's beam following, which is not
    specified; it keeps homing if the beam is lost again). Gives up after 10 min."""

    def __init__(self, name: str, started: float, rng: random.Random) -> None:
        super().__init__(name, started, rng)
        self.homing = False
        self.follow_until = 0.0  # the wall-following spell's end (0: running straight)
        self.wall_lost_at = 0.0

    def wheels(self, robot: Power) -> Wheels:
        if robot.docked:
            return self._end("docked")
        if robot.time - self.started > SEEK_DOCK_LIMIT_S:
            return self._end("seek dock gave up")
        v = robot.values
        if not self.homing:
            if not (_FROM_DOCK[v[17]] or _FROM_DOCK[v[52]] or _FROM_DOCK[v[53]]):
                return self._search(robot)
            self.homing = True
            self.phase = "approach"
        dock = robot.world.dock
        if dock is None:  # a beam seen once but no dock any more: nothing to home on
            return _STOP
        target = dock.docked_pose
        fx, fy = math.cos(dock.facing), math.sin(dock.facing)
        return self._home(robot, target, target.x + 450.0 * fx, target.y + 450.0 * fy)

    def _search(self, robot: Power) -> Wheels:
        """No beam seen yet: the cleaning cycles' moves from the robot's own sensors only."""
        v = robot.values
        now = robot.time
        if self.phase == "follow":
            if now >= self.follow_until or v[9] or v[10] or v[11] or v[12] or v[13]:
                self.follow_until = 0.0
                self.phase, self.phase_until = "back", now + 0.3
            elif v[7] & BUMP_BITS or robot.blocked:
                self.phase, self.phase_until = "follow_back", now + 0.55
            else:
                return self._follow(robot)
        if self.phase == "follow_back":  # a bump while following: back off, turn left a little
            if now < self.phase_until - 0.35:
                return -150.0, -150.0
            if now < self.phase_until:
                return -150.0, 150.0
            self.phase = "follow"
            return self._follow(robot)
        if self.phase == "forward":
            if _in_the_way(robot):
                self.phase, self.phase_until = "back", now + 0.3
                # a wall (not a drop, not a beam): follow it for a spell, or turn away
                if not (v[9] or v[10] or v[11] or v[12] or v[13]) and self.rng.random() < 0.5:
                    self.phase_until = now + 0.15
                    self.follow_until = now + self.rng.uniform(6.0, 20.0)
            else:
                return _SEARCH_SPEED, _SEARCH_SPEED
        if self.phase == "back":
            if now < self.phase_until:
                return -150.0, -150.0
            if self.follow_until:
                self.phase = "follow"
                self.wall_lost_at = now
                return self._follow(robot)
            self._start_turn(now)
        if self.phase == "turn":
            turning = self._turning(now)
            if turning is not None:
                return turning
        return _SEARCH_SPEED, _SEARCH_SPEED

    def _follow(self, robot: Power) -> Wheels:
        """Wall on the right: turn left while something is close ahead, keep the right rays'
        signal near a set point (about 5 cm from the wall), arc right round a wall's end;
        3 s without a wall ends the spell."""
        v = robot.values
        now = robot.time
        if max(v[47], v[48], v[49]) > _FOLLOW_AHEAD:
            self.wall_lost_at = now
            return -150.0, 150.0
        side = v[51] + v[50] // 2
        if side > _FOLLOW_SEEN:
            self.wall_lost_at = now
            err = max(-1.0, min(1.0, (side - _FOLLOW_SET) / _FOLLOW_SET))
            return _FOLLOW_SPEED - 60.0 * err, _FOLLOW_SPEED + 60.0 * err
        if now - self.wall_lost_at > 3.0:
            self.phase, self.follow_until = "forward", 0.0
            return _SEARCH_SPEED, _SEARCH_SPEED
        return _FOLLOW_SPEED, 0.35 * _FOLLOW_SPEED

    def _home(self, robot: Power, target: Pose, ax: float, ay: float) -> Wheels:
        """In sight of the dock: to (ax, ay) on its axis, turn to face the docked pose
        ``target``, drive on; back off and try again after a bump."""
        if self.phase == "approach":
            if (robot.x - ax) ** 2 + (robot.y - ay) ** 2 < 30.0**2:
                self.phase = "align"
            else:
                return _steer_to(robot, ax, ay, 200.0)
        if self.phase == "align":
            err = wrap_angle(target.theta - robot.theta)
            if abs(err) < math.radians(1.5):
                self.phase = "dock"
            else:
                w = 60.0 if err > 0 else -60.0
                return -w, w
        if self.phase == "dock":
            if robot.values[7] & BUMP_BITS:
                self.phase, self.phase_until = "retreat", robot.time + 1.5
            else:
                err = wrap_angle(math.atan2(target.y - robot.y, target.x - robot.x) - robot.theta)
                # aim at the contacts; off-axis corrections are small
                turn = max(-20.0, min(20.0, 200.0 * err))
                return 80.0 - turn, 80.0 + turn
        if self.phase == "retreat":
            if robot.time < self.phase_until:
                return -100.0, -100.0
            self.phase = "approach"
        return _STOP


def _steer_to(robot: Power, tx: float, ty: float, speed: float) -> Wheels:
    """Turn on the spot towards (tx, ty) while more than 20 deg off, else arc towards it."""
    err = wrap_angle(math.atan2(ty - robot.y, tx - robot.x) - robot.theta)
    if abs(err) > math.radians(20.0):
        w = 120.0 if err > 0 else -120.0
        return -w, w
    turn = 2.0 * speed * err
    return speed - turn, speed + turn


#: the cycle each command starts, by the name it is marked with in the events
CYCLES: dict[str, type[BuiltinCycle]] = {
    "spot": Spot,
    "clean": Clean,
    "max": Clean,
    "seek_dock": SeekDock,
}

#: The buttons that start a cycle (packet 18's flags, as :class:`~roomba_bt.oi.bits.Buttons`
#: names them, in bit order) and the command each is: the 600 / Create 2 spec says Clean
#: (135) "is the same as pressing Roomba's Clean button", Spot (134) and Seek Dock (143) the
#: same of theirs. Max has no button; the scheduling buttons start nothing. Several pushed
#: at once: the first here (neither spec says; decided).
BUTTON_CYCLES: tuple[tuple[int, str], ...] = (
    (1 << Buttons.flag_names().index("clean"), "clean"),
    (1 << Buttons.flag_names().index("spot"), "spot"),
    (1 << Buttons.flag_names().index("dock"), "seek_dock"),
)
