"""``wall_follow``: keep a wall on the right at a steady light-bumper signal.

The right light-bumper signal (packet 51) grows as the wall comes closer (0-4095). A PD
controller turns the error ``target - signal`` into a difference of wheel speeds::

    error  = target - signal              (> 0: too far from the wall)
    turn   = kp * error + kd * d(error)/dt   (mm/s, clamped to +-speed)
    left   = speed + turn                 (too far: the left wheel speeds up,
    right  = speed - turn                  the robot steers right, toward the wall)

and sends them as Drive Direct (145) ``[145][right hi][right lo][left hi][left lo]``. An
obstacle ahead (the centre signals 48 / 49 above ``front_threshold``) turns it left in
place, so it follows an inside corner. By default that turn is decided afresh every tick,
as it always was (the golden recordings hold it): along a wall met at a shallow angle the
signal hovers at the threshold and the left wheel reverses every 15-45 ms (49 reversals a
minute in the empty room, nearly all within 0.1 s of the last; ``bench/wheel_reversals.py``).
``front_clear: 300, turn_hold: 0.3s`` make it a decision that holds, as ``cover``'s edge
does (:class:`~roomba_bt.behaviours.driving.WallAhead`). A bump (packet 7) that the light
bumper did not see coming (a gap narrower than the robot, a chair leg) backs it off 5 cm
and turns it left by ``bump_turn`` before the controller takes over again: without that,
it pushed into the wedge for as long as the mission ran. Time is the mission clock
(``snapshot.time``); the behaviour never blocks and halts the wheels when it ends or is
preempted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from py_trees.common import Status

from roomba_bt.behaviours import driving, reversing
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.declare import Param, declare, wheel_speed_param
from roomba_bt.behaviours.driving import wheel_speeds
from roomba_bt.behaviours.units import ANGLE, DURATION, FLOAT, INT
from roomba_bt.oi import commands
from roomba_bt.oi.frames import BUMPS_PACKETS, LIGHT_BUMP_SIGNAL_PACKETS
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.packets import PACKETS

__all__ = ["WALL_FOLLOWING", "WallFollow"]

#: the light-bumper signals it reads: centre left, centre right, front right, right
_SIGNALS = LIGHT_BUMP_SIGNAL_PACKETS[2:]
_SIGNAL_MAX = PACKETS[_SIGNALS[-1]].maximum
#: after a bump: back off this far (mm), giving up after this long (s) if something is behind
_BACK_MM, _BACK_S = 50.0, 1.0
#: and the turn gives up after this long (s): a robot held in place must not spin forever
_TURN_S = 4.0


_FRONT_THRESHOLD = Param(
    "front_threshold", INT, default=800, minimum=1, maximum=_SIGNAL_MAX,
    doc="centre signal (48/49) above which it turns away from a wall ahead",
)  # fmt: skip


def _hysteresis_in_order(params: Mapping[str, Any]) -> list[str]:
    """``front_clear`` above ``front_threshold`` is a hysteresis upside down: the turn away
    from a wall ahead would end at a signal above the one that starts it (it was taken as
    ``front_threshold`` without a word). Values read from the blackboard pass."""
    enter = params.get("front_threshold", _FRONT_THRESHOLD.default)
    leave = params.get("front_clear")
    if not isinstance(enter, int | float) or not isinstance(leave, int | float):
        return []
    if leave > enter:
        return [
            f"front_clear {leave:g} is above front_threshold {enter:g}"
            f"{'' if 'front_threshold' in params else ' (its default)'}: the turn away from a "
            "wall ahead starts above front_threshold and ends below front_clear, so "
            f"front_clear must be at most front_threshold (1..{enter:g}; 300 suits the "
            "default 800)"
        ]
    return []


@declare(
    "wall_follow",
    kind="action",
    params=(
        wheel_speed_param("speed", "150 mm/s", minimum=20, doc="forward wheel speed"),
        Param("target", INT, default=600, minimum=1, maximum=_SIGNAL_MAX,
              doc="right light-bumper signal (51) to hold"),
        Param("kp", FLOAT, default=0.15, minimum=0, maximum=10,
              doc="mm/s of wheel-speed difference per unit of signal error"),
        Param("kd", FLOAT, default=0.01, minimum=0, maximum=10,
              doc="mm/s per unit of signal error change per second"),
        _FRONT_THRESHOLD,
        Param("front_clear", INT, minimum=1, maximum=_SIGNAL_MAX,
              doc="centre signal below which that turn ends (hysteresis; 300 suits it); "
                  "default: front_threshold; above front_threshold it is refused (the "
                  "hysteresis upside down)"),
        Param("turn_hold", DURATION, default="0s", minimum=0, maximum=5,
              doc="the shortest time that turn, or the following after it, holds (0.3s "
                  "suits it); 0: decided afresh every tick"),
        Param("bump_turn", ANGLE, default="45deg", minimum=0, maximum=180,
              doc="on a bump: back off 5 cm, then turn left (away from the wall) this far"),
        Param("duration", DURATION, minimum=0, doc="SUCCESS after this long; default: never"),
    ),
    reads=(*BUMPS_PACKETS, *_SIGNALS),
    sends=opcodes("drive_direct", "drive"),
    may_succeed=lambda params: "duration" in params,  # else RUNNING until ended
    constraints=_hysteresis_in_order,
)  # fmt: skip
class WallFollow(Action):
    """Follow a wall on the right at a steady light-bumper signal (PD on wheel speeds).

    It does not look for a wall: started with none on its right it turns right at full
    correction and circles in open floor. Put it beside one first, as
    ``missions/wall-follow.yaml`` does: ``drive`` until the light bumper or the bumper sees a
    wall, then ``turn: 75deg`` (left) to have it on the right. RUNNING until ``duration``
    (SUCCESS) or until a guard or a higher branch preempts it; the wheels are halted in both
    cases.
    """

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        reversing.forget_run_trail()  # a new run: no floor driven yet

    def start(self) -> None:
        #: the run's trail, fed every tick it drives: what ``backtrack`` may back over
        self._trail = reversing.run_trail()
        self._start_time = self.snapshot.time
        self._previous_error: float | None = None
        self._previous_time = self._start_time
        self._recovery: tuple[str, float, float] | None = None  # phase, odometry mark, time
        enter = round(self.number("front_threshold"))
        leave = self.value("front_clear")
        self._ahead = driving.WallAhead(
            enter,
            enter if leave is None else min(enter, int(leave)),
            self.number("turn_hold"),
            max(enter, driving.WALL_AHEAD_CLOSE),
        )

    def recovery_speeds(self, bumped: bool) -> tuple[int, int] | None:
        """(left, right) while getting away from a bump (back off, then turn left), or
        None when the controller drives."""
        snap = self.snapshot
        odo = snap.odometry
        speed = round(self.number("speed"))
        if bumped and self._recovery is None:
            self._recovery = ("back", odo.distance_mm, snap.time)
        if self._recovery is None:
            return None
        phase, mark, since = self._recovery
        if phase == "back":
            if mark - odo.distance_mm < _BACK_MM and snap.time - since < _BACK_S:
                return -speed, -speed
            self._recovery = phase, mark, since = ("turn", odo.angle_rad, snap.time)
        turned = odo.angle_rad - mark
        if turned < math.radians(self.number("bump_turn")) and snap.time - since < _TURN_S:
            return -speed, speed
        self._recovery = None
        self._previous_error = None  # the controller starts afresh
        self._ahead.reset()
        return None

    def wheel_speeds(self, signal: int, front: int, now: float) -> tuple[int, int]:
        """(left, right) in mm/s for this tick's signals: the controller, testable alone."""
        speed = self.number("speed")
        if self._ahead.turning(front, now):
            self._previous_error = None
            return -round(speed), round(speed)  # wall ahead: spin left in place
        error = self.number("target") - signal
        derivative = 0.0
        dt = now - self._previous_time
        if self._previous_error is not None and dt > 0:
            derivative = (error - self._previous_error) / dt
        self._previous_error, self._previous_time = error, now
        turn = self.number("kp") * error + self.number("kd") * derivative
        turn = max(-speed, min(speed, turn))
        return wheel_speeds(speed + turn, speed - turn)

    def update(self) -> Status:
        snap = self.snapshot
        self._trail.feed(snap.odometry)
        duration = self.value("duration")
        if duration is not None and snap.time - self._start_time >= float(duration) - 1e-9:
            self.send(commands.halt())
            return Status.SUCCESS
        if snap.mode not in DRIVING_MODES:
            return self.wait_for_driving_mode()
        self.stranded()  # back in Safe/Full: the wait is over
        frame = snap.frame
        recovering = self.recovery_speeds(frame.any_bump)
        if recovering is not None:
            left, right = recovering
        else:
            front = max(frame.light_bump_center_left_signal, frame.light_bump_center_right_signal)
            left, right = self.wheel_speeds(frame.light_bump_right_signal, front, snap.time)
        self.send(commands.drive_direct(right, left))
        return Status.RUNNING


WALL_FOLLOWING: tuple[type[Action], ...] = (WallFollow,)
