"""The steering of ``cover``'s edge: a wall on the right at a distance, from the light bumper.

Each tick the six light-bumper signals (packets 46-51, 0-4095, growing as a surface comes
closer) give the wheel speeds (mm/s)::

    a wall ahead (centre signals 48/49)   turn left in place (-150, 150): in at 900, out
                                          below 300; either decision held 0.3 s at least,
                                          but 2000 (about 3 cm ahead) turns it at once
    no wall on the right (50, 51 both 0)  curve right (speed, 0.35 speed): around an
                                          outside corner, or to find it
    otherwise                             PD on the right wall's distance (from 51):
                                          turn = 4 mm/s per mm of error + 0.15 per mm/s,
                                          (v + turn, v - turn), neither wheel backward, and
                                          no turn toward the wall while a wall ahead is in
                                          sight (centre signal 200 and up: an inside corner)

The turn in place is the one steering decision that reverses a wheel (the left one). Taken
and left on one threshold, it flips with a hard right every 15-45 ms along a wall met at a
shallow angle: the centre signal hovers at 900, one tick of turning takes it below, one
tick of the PD steering right brings it back (118 reversals a minute in the apartment, two
thirds of them within 0.1 s of the same wheel's last). The simulator has no acceleration
limit, so it costs nothing there; on a Create 2 each flip reverses a
wheel motor (gearbox strain, current spikes, a robot that shudders along the wall). A real
light bumper's signal is noisier than the simulator's and depends on the surface (the OI
spec gives strength only, 0-4095, no distance), which makes one threshold chatter more, not
less: hence hysteresis and a hold rather than a finer threshold.
"""

from __future__ import annotations

import math

from roomba_bt.behaviours.driving import WALL_AHEAD_CLOSE, WallAhead
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import BODY_RADIUS_MM, LIGHT_BUMP_RANGE_MM

__all__ = ["EdgeSteering", "signal_distance_mm"]

#: the centre signals (48/49) at which a wall ahead turns it in place, and below which the
#: turn may end
FRONT_TURN, FRONT_CLEAR = 900, 300
#: a centre signal this high turns it in place even within a hold (about 3 cm ahead)
FRONT_CLOSE = WALL_AHEAD_CLOSE
#: the shortest time (s) a decision (turn in place, or follow) holds: not a flip per tick
HOLD_S = 0.3
#: the wheels' speed (mm/s) turning in place at a wall ahead
TURN_MM_S = 150.0
#: above this centre signal it slows to 150 mm/s (the wall ahead is in sight)
FRONT_SLOW = 200
#: PD gains on the distance error (mm/s per mm, per mm/s) and the turn's share of the speed
KP, KD, TURN_SHARE = 4.0, 0.15, 0.6
#: the light bumper's ray to the right is at 65 deg: the distance across is cos(25 deg) of it
_ACROSS = 0.906


def signal_distance_mm(signal: int) -> float:
    """A light-bumper signal as the distance (mm) from the bumper along its ray (the
    simulator's model: signal = 4095 (1 - d / 150 mm) ** 2)."""
    return LIGHT_BUMP_RANGE_MM * (1.0 - math.sqrt(min(signal, 4095) / 4095.0))


class EdgeSteering:
    """Wheel speeds along a wall on the right, from the light-bumper signals (the module's
    table). Holds the state the decision needs: the turn in place at a wall ahead
    (:class:`~roomba_bt.behaviours.driving.WallAhead`) and the last distance error (the
    derivative)."""

    def __init__(self) -> None:
        self._ahead = WallAhead(FRONT_TURN, FRONT_CLEAR, HOLD_S, FRONT_CLOSE)
        self._previous: float | None = None

    def reset(self) -> None:
        """A new edge, or after a recovery: no turn under way, no derivative yet."""
        self._ahead.reset()
        self._previous = None

    def wheels(
        self, signals: tuple[int, ...], speed: float, distance_mm: float, now: float
    ) -> tuple[float, float, float | None]:
        """(left, right, error): this tick's wheel speeds, and the distance error (mm, > 0:
        too far) when it follows the wall, None when it turns or has no wall in sight."""
        front = max(signals[2], signals[3])
        if self._ahead.turning(front, now):
            self._previous = None
            return -TURN_MM_S, TURN_MM_S, None
        right = signals[5]
        if right == 0 and signals[4] == 0:
            self._previous = None
            return speed, speed * 0.35, None
        distance = _ACROSS * (BODY_RADIUS_MM + signal_distance_mm(max(right, 1)))
        error = distance - distance_mm
        derivative = 0.0 if self._previous is None else (error - self._previous) / SLOT_SECONDS
        self._previous = error
        forward = speed if front < FRONT_SLOW else min(speed, 150.0)
        limit = min(TURN_SHARE * speed, forward)  # neither wheel backward
        # a wall ahead in sight: not toward it (into the corner), only away
        right_most = limit if front < FRONT_SLOW else 0.0
        turn = max(-limit, min(right_most, KP * error + KD * derivative))
        return forward + turn, forward - turn, error
