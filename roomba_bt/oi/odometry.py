"""Odometry from the wheel encoders (packets 43 / 44).

Encoders are preferred to Distance (19) and Angle (20): those are wrong before firmware 3.3.0
/ 3.4.1 (Appendix B). Encoder counts roll over at 2**16, and the 600 spec calls them signed
while the 500 spec calls them unsigned; a delta taken modulo 2**16 and mapped into
-32768..32767 is right for both and across the rollover::

    65530 -> 5      is +11   (a well-known driver gets +12)
    5     -> 65530  is -11   (it gets +65526)

The encoders are square-wave, not quadrature: the robot counts in the commanded direction.
"""

from __future__ import annotations

import math

from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import COUNTS_PER_REVOLUTION, WHEEL_BASE_MM, WHEEL_DIAMETER_MM

MM_PER_COUNT = math.pi * WHEEL_DIAMETER_MM / COUNTS_PER_REVOLUTION
#: Top wheel speed in the spec (Drive, Drive Direct: -500..500 mm/s).
TOP_WHEEL_SPEED_MM_S = 500
#: "Roomba's speed controller can only control the velocity of the wheels in steps of about
#: 28.5 mm/s" (600 spec, Drive 137 and Drive Direct 145): a wheel asked for a speed turns at
#: the nearest step (the simulator models it so, docs/simulator.md).
WHEEL_SPEED_STEP_MM_S = 28.5
#: The slowest whole mm/s that moves a wheel: below half a step (14.25 mm/s) the controller's
#: nearest step is 0 and the wheel stands still, so a leaf waiting for it to travel waits for
#: ever. The minimum of every speed parameter that must produce motion (15 mm/s).
SLOWEST_MOVING_SPEED_MM_S = math.floor(WHEEL_SPEED_STEP_MM_S / 2) + 1


def speed_steps(speed_mm_s: float) -> int:
    """How many of the speed controller's steps a wheel asked for ``speed_mm_s`` (whole mm/s,
    as sent) turns at: 0 is a wheel that stands still, the sign its direction."""
    return round(speed_mm_s / WHEEL_SPEED_STEP_MM_S)


#: Most counts a wheel can turn between two stream frames (15 ms): 7.5 mm is 16.9 counts at
#: top speed; half again for the robot's own timing of the frames. A larger step between two
#: consecutive frames is a corrupted frame, not a motion.
MAX_COUNTS_PER_SLOT = math.ceil(1.5 * TOP_WHEEL_SPEED_MM_S * SLOT_SECONDS / MM_PER_COUNT)
#: Angle (20) on firmware 3.4.0 and earlier must be divided by this to give degrees.
OLD_FIRMWARE_ANGLE_FACTOR = 0.324056


def encoder_delta(previous: int, current: int) -> int:
    """Counts moved from ``previous`` to ``current``, modulo 2**16, in -32768..32767."""
    return ((current - previous + 0x8000) & 0xFFFF) - 0x8000


def counts_to_mm(counts: float) -> float:
    """``counts * pi * 72.0 / 508.8`` (600 spec, packet 43)."""
    return counts * MM_PER_COUNT


def mm_to_counts(mm: float) -> float:
    return mm / MM_PER_COUNT


def arc_from_wheels(
    left_mm: float, right_mm: float, wheel_base_mm: float = WHEEL_BASE_MM
) -> tuple[float, float]:
    """(distance travelled by the centre in mm, heading change in radians, CCW positive)."""
    return (left_mm + right_mm) / 2.0, (right_mm - left_mm) / wheel_base_mm


def corrected_old_angle(raw_angle: int) -> float:
    """Degrees from Angle (20) on firmware 3.4.0 and earlier."""
    return raw_angle / OLD_FIRMWARE_ANGLE_FACTOR
