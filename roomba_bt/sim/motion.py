"""Motion: the wheels. Drive commands to wheel speeds, a step's travel, collisions with walls,
the dock's guides, and a fall off a drop in Full mode.

Drive (137) sets a velocity and a radius, Drive Direct (145) and Drive PWM (146) each wheel;
the speed controller steps every wheel speed to multiples of about 28.5 mm/s (at most 500).
What the robot asked for is reported in packets 39-42 (velocity, radius, right, left)::

    [137][vel hi][vel lo][rad hi][rad lo]     velocity mm/s, radius mm (0x8000: straight)
    [145][right hi][right lo][left hi][left lo]
    [146][right pwm hi][lo][left pwm hi][lo]  -255..255 of full speed

A step moves the centre by the mean of the wheels' travel along the mean heading; a step that
would bring the body into a wall is cut short by bisection (the wheels stall, packet 58
stasis drops, the encoders stop counting). Encoder counts (43, 44), distance and angle (19,
20, via the accumulators) follow what the wheels did.

A layer of the simulator (see state.py): :meth:`Motion._move` runs on every step the wheels
turn, so the pose and speeds are attributes of the robot itself, and a steady motion's
travel is computed once per (left, right, dt) (:func:`_motion_of`).
"""

from __future__ import annotations

import math
import struct
from math import trunc

from roomba_bt.oi.odometry import MM_PER_COUNT, WHEEL_SPEED_STEP_MM_S
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME
from roomba_bt.sim.geometry import closest_point, wrap_angle
from roomba_bt.sim.sensing import Sensing
from roomba_bt.sim.state import EXACT_ODOMETRY, STEP_SECONDS, OdometryError, TracePoint
from roomba_bt.sim.world import ROBOT_RADIUS_MM

MAX_WHEEL_SPEED_MM_S = 500.0
#: Pushed against the dock within this angle of the contacts, its guides align the robot.
DOCK_GUIDE_ANGLE = math.radians(20.0)
_GUIDE_STEP = math.radians(1.0)
#: each wheel command's opcode byte, from the table: what ``_last_drive`` starts with
_DRIVE, _DRIVE_DIRECT, _DRIVE_PWM = (
    bytes((COMMANDS_BY_NAME[name].opcode,)) for name in ("drive", "drive_direct", "drive_pwm")
)
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_new_tuple = tuple.__new__

#: What one step of steady wheel speeds does, computed once per (left, right, dt): a plain
#: tuple (indexed on the step path, where a tuple subscript is the cheapest access)::
#:
#:     0 left   1 right   2 dt          the key: wheel speeds (mm/s) and step (s)
#:     3 dist   4 dtheta  5 dtheta / 2  travel of the centre (mm), turn (rad)
#:     6 left counts  7 right counts    encoder counts of an unhindered step
#:     8 packet 58 (stasis) of an unhindered step
#:     9 measured dist  10 measured dtheta   what the encoders say (packets 19, 20): the
#:                                          travel and turn unless Faults.odometry_error
#:    11 |dist|         the travel's length, against the clearance (no abs() a step)
_Motion = tuple[float, float, float, float, float, float, float, float, int, float, float, float]


def _motion_of(
    left: float, right: float, dt: float, half_base: float, error: OdometryError = EXACT_ODOMETRY
) -> _Motion:
    dl = left * dt
    dr = right * dt
    dist = (dl + dr) / 2.0
    dtheta = (dr - dl) / (2.0 * half_base)
    measured_dist, measured_dtheta = (
        (dist, dtheta) if error is EXACT_ODOMETRY else _measured(dist, dtheta, dt, half_base, error)
    )
    return (
        left, right, dt, dist, dtheta, dtheta / 2.0,
        (measured_dist - measured_dtheta * half_base) / MM_PER_COUNT,
        (measured_dist + measured_dtheta * half_base) / MM_PER_COUNT,
        1 if dist > 0.0 else 0, measured_dist, measured_dtheta, abs(dist),
    )  # fmt: skip


def _measured(
    dist: float, dtheta: float, dt: float, half_base: float, error: OdometryError
) -> tuple[float, float]:
    """(travel, turn) as the encoders count them for a true ``dist`` (mm) and ``dtheta``
    (rad) over ``dt`` s of turning wheels: each wheel's scale, then the drift."""
    if error is EXACT_ODOMETRY:
        return dist, dtheta
    drift = error.drift * dt * half_base
    left = (dist - dtheta * half_base) * error.left_scale - drift
    right = (dist + dtheta * half_base) * error.right_scale + drift
    return (left + right) / 2.0, (right - left) / (2.0 * half_base)


def _quantise(speed: float) -> float:
    q = round(speed / WHEEL_SPEED_STEP_MM_S) * WHEEL_SPEED_STEP_MM_S
    # a condition, not max(min()): each of those parses its keywords (~900 instructions)
    top = MAX_WHEEL_SPEED_MM_S
    return -top if q < -top else top if q > top else q


class _Quantised(dict[int, float]):
    """:func:`_quantise` of the Drive Direct (145) speeds asked so far (-500..500 mm/s): a
    docking client sends one every few steps, and a look-up costs a tenth of the call (kept
    as they are asked for: a table of all 1001 would cost 3 M instructions at import)."""

    def __missing__(self, speed: int) -> float:
        quantised = self[speed] = _quantise(speed)
        return quantised


_QUANTISED = _Quantised()
#: two big-endian signed 16-bit arguments: Drive's, Drive Direct's and Drive PWM's
_unpack_two = struct.Struct(">hh").unpack


def drive_wheel_speeds(velocity: float, radius: int, wheel_base_mm: float) -> tuple[float, float]:
    """(left, right) wheel speeds in mm/s for Drive (137).

    Radius semantics from the spec: positive turns left (counter-clockwise), ``-32768``
    (0x8000) and ``32767`` (0x7FFF) drive straight, ``-1`` spins clockwise and ``1``
    counter-clockwise in place. Radii outside -2000..2000 are treated as straight (the
    spec's range), and radius 0 as straight too. Each wheel is limited to 500 mm/s."""
    velocity = float(max(-500.0, min(500.0, velocity)))
    if radius in (-32768, 32767, 0) or not -2000 <= radius <= 2000:
        return float(velocity), float(velocity)
    if radius == -1:
        return float(velocity), float(-velocity)
    if radius == 1:
        return float(-velocity), float(velocity)
    half = wheel_base_mm / 2.0
    left = velocity * (radius - half) / radius
    right = velocity * (radius + half) / radius
    top = max(abs(left), abs(right))
    if top > MAX_WHEEL_SPEED_MM_S:
        left *= MAX_WHEEL_SPEED_MM_S / top
        right *= MAX_WHEEL_SPEED_MM_S / top
    return left, right


class Motion(Sensing):
    """Wheel speeds asked for and done, the pose's change, odometry, collisions."""

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_angle_acc", "_distance_acc", "_dock_target", "_encoder_low", "_half_base",
        "_last_drive", "_left_counts", "_motion", "_right_counts", "_stall_steps", "_steady",
        "_travel", "_travel_heading", "_travel_motion", "blocked", "left_speed", "requested_left",
        "requested_right", "right_speed",
    )  # fmt: skip

    def _init_motion(self) -> None:
        self.requested_left = 0.0  # mm/s, from Drive / Drive Direct / Drive PWM
        self.requested_right = 0.0
        self.left_speed = 0.0  # actual (quantised) wheel speeds
        self.right_speed = 0.0
        self.blocked = False
        self._stall_steps = 0
        #: the last step moved freely at the speeds now (:meth:`_move`): packet 58 and the
        #: stall count stay as that step left them, not set again every step
        self._steady = False
        self._left_counts = 0.0
        self._right_counts = 0.0
        #: travel and turn not yet reported in packets 19 and 20 (replies.py reads them)
        self._distance_acc = 0.0
        self._angle_acc = 0.0
        #: the wheel command in force (Drive, Drive Direct or Drive PWM), whole: the same
        #: bytes again change nothing (protocol.py hears them without executing them)
        self._last_drive = b""
        self._half_base = self.profile.wheel_base_mm / 2.0
        self._motion: _Motion = _motion_of(0.0, 0.0, STEP_SECONDS, self._half_base)
        #: a free step's travel of the centre (mm, x and y), and the heading and motion it is
        #: for (:meth:`_move`: driving straight, the same each step)
        self._travel = (0.0, 0.0)
        self._travel_heading = math.nan
        self._travel_motion = self._motion
        self._encoder_low = -0x8000 if self.profile.encoders_signed else 0
        dock = self.world.dock
        self._dock_target = dock.docked_pose if dock is not None else None
        self.values[40] = -32768
        self.values[58] = 0

    def _stop_wheels(self) -> None:
        self._last_drive = b""
        self.requested_left = self.requested_right = 0.0
        v = self.values
        v[39] = v[41] = v[42] = 0
        v[40] = -32768

    def _on_drive(self, args: bytes) -> None:
        self._last_drive = _DRIVE + args
        velocity, radius = _unpack_two(args)
        # The speed controller steps the commanded velocity; the radius sets the wheel ratio.
        speed = _quantise(velocity)
        left, right = drive_wheel_speeds(speed, radius, self.profile.wheel_base_mm)
        self.requested_left, self.requested_right = left, right
        v = self.values
        v[39] = max(-500, min(500, velocity))
        v[40] = radius
        asked_left, asked_right = drive_wheel_speeds(velocity, radius, self._half_base * 2.0)
        v[41] = round(asked_right)
        v[42] = round(asked_left)

    def _on_drive_direct(self, args: bytes) -> None:
        self._last_drive = _DRIVE_DIRECT + args
        right, left = _unpack_two(args)
        right = -500 if right < -500 else 500 if right > 500 else right
        left = -500 if left < -500 else 500 if left > 500 else left
        self.requested_left, self.requested_right = _QUANTISED[left], _QUANTISED[right]
        v = self.values
        v[39] = (left + right) // 2
        v[40] = -32768 if left == right else 0
        v[41] = right
        v[42] = left

    def _on_drive_pwm(self, args: bytes) -> None:
        self._last_drive = _DRIVE_PWM + args
        right, left = _unpack_two(args)
        scale = MAX_WHEEL_SPEED_MM_S / 255.0
        self.requested_right = _quantise(max(-255, min(255, right)) * scale)
        self.requested_left = _quantise(max(-255, min(255, left)) * scale)
        v = self.values
        v[41] = round(self.requested_right)
        v[42] = round(self.requested_left)
        v[39] = (v[41] + v[42]) // 2

    # Over 60 lines on purpose: the usual step runs inline, no call (_turn's work too): it
    # runs on every step the wheels turn; a wall in the way, a lift or a fall calls out.
    def _move(self, left: float, right: float, dt: float) -> None:
        """Turn the wheels at ``left``, ``right`` mm/s for ``dt`` seconds."""
        motion = self._motion
        if left != self.left_speed or right != self.right_speed or dt != motion[2]:
            # New speeds (or step). Speeds that stay are those of the last move (only a stop
            # sets others: 0), and the motion kept is theirs: nothing to check on a step.
            self._power_due = True  # the wheels draw other currents (power.py)
            self._steady = False
            self.left_speed, self.right_speed = left, right
            if not left and not right:
                self.values[58] = 0
                self._stall_steps = 0
                return
            if motion[0] != left or motion[1] != right or motion[2] != dt:
                motion = self._motion = _motion_of(
                    left, right, dt, self._half_base, self.odometry_error
                )
        dist, dtheta = motion[3], motion[4]
        fraction = 1.0
        stuck = self.lifted or self.fallen
        if stuck:
            fraction = 0.0
        elif dist:
            x, y = self.x, self.y
            heading = self.theta + motion[5]
            if heading != self._travel_heading or motion is not self._travel_motion or not heading:
                # a new heading or speed: the centre's travel along it (a straight drive keeps
                # both, and the same step's travel from one step to the next; a zero heading
                # is worked out every time, its sign being the one thing equality misses)
                self._travel = (dist * math.cos(heading), dist * math.sin(heading))
                self._travel_heading = heading
                self._travel_motion = motion
            ux, uy = self._travel
            if motion[11] >= self._clearance and self._blocked(x + ux, y + uy):
                fraction = self._reach(x, y, ux, uy)
                ux *= fraction
                uy *= fraction
            self.x = x + ux
            self.y = y + uy
        v = self.values
        if fraction == 1.0:
            # free motion (the usual step): what the wheels did is the same every step (the
            # heading and the counts as _turn does them, inline: this runs every step)
            if not self._steady:
                # the first free step at these speeds or after a hindered one: packet 58, the
                # stall count and the blocked flag as free steps leave them, the same after
                self._steady = True
                v[58] = motion[8]
                self._stall_steps = 0
                if self.blocked:
                    self.blocked = False
                    self._power_due = True
            theta = self.theta + dtheta
            if theta > _PI:
                theta -= _TWO_PI
            elif theta < -_PI:
                theta += _TWO_PI
            self.theta = theta
            self._distance_acc += motion[9]
            self._angle_acc += motion[10]
            left_counts = self._left_counts = self._left_counts + motion[6]
            right_counts = self._right_counts = self._right_counts + motion[7]
            self._geometry_dirty = True
        else:
            self._move_hindered(dist, dtheta, fraction, stuck, dt)
            left_counts, right_counts = self._left_counts, self._right_counts
        # 16 bits, signed or not: the count itself while within low..low + 0xFFFF (low -0x8000
        # when signed, else 0), else (n - low) & 0xFFFF + low: comparisons, not three new
        # integers a wheel (trunc, not int: state.py)
        low = self._encoder_low
        high = low + 0xFFFF
        n = trunc(left_counts)
        v[43] = n if low <= n <= high else (n - low & 0xFFFF) + low
        n = trunc(right_counts)
        v[44] = n if low <= n <= high else (n - low & 0xFFFF) + low
        if not self.ticks & 3 and self.keeps_trace:
            # built as the tuple it is: the NamedTuple's __new__ is a Python call
            point = (self.time, self.x, self.y, self.theta, self.mode)
            self.trace.append(_new_tuple(TracePoint, point))

    def _reach(self, x: float, y: float, ux: float, uy: float) -> float:
        """A wall is in the way of the move (ux, uy) from (x, y): how far along it the body
        gets, to 1 % (bisection)."""
        lo, hi = 0.0, 1.0
        if (
            self._clearance < 0.5  # a bound below the clearance: is the clearance itself?
            and self._exact_clearance() < 0.5
            and self._blocked(x + ux / 64, y + uy / 64)
        ):
            hi = 0.0  # pressed against the wall already: no room at all
        while hi - lo > 0.01:
            mid = (lo + hi) / 2.0
            if self._blocked(x + ux * mid, y + uy * mid):
                hi = mid
            else:
                lo = mid
        return lo

    def _turn(self, theta: float, travelled: float, dtheta: float) -> None:
        """The body now faces ``theta`` (wrapped into -pi..pi here); the encoders count
        ``travelled`` mm and ``dtheta`` rad: what packets 19 and 20 add up."""
        if theta > _PI:
            theta -= _TWO_PI
        elif theta < -_PI:
            theta += _TWO_PI
        self.theta = theta
        self._distance_acc += travelled
        self._angle_acc += dtheta

    def _move_hindered(
        self, dist: float, dtheta: float, fraction: float, stuck: bool, dt: float
    ) -> None:
        """The rest of a step that a wall cut short, or a lifted or fallen robot's."""
        half_base = self._half_base
        self._power_due = True  # a stall draws more current
        self._steady = False  # packet 58 and the stall count set here
        blocked = self.blocked = fraction < 1.0 and dist != 0.0 and not stuck
        guided = 0.0
        if blocked and dist > 0.0 and self._dock_target is not None:
            guided = self._dock_guides()  # the body turns, the wheels slip: no encoder counts
        travelled = dist if stuck else dist * fraction
        counted, turned = _measured(travelled, dtheta, dt, half_base, self.odometry_error)
        if not stuck:
            self._turn(self.theta + dtheta + guided, counted, turned)
        # Encoders count wheel turns: a blocked robot's wheels stall, a lifted one's spin.
        self._left_counts = self._left_counts + (counted - turned * half_base) / MM_PER_COUNT
        self._right_counts = self._right_counts + (counted + turned * half_base) / MM_PER_COUNT
        self.values[58] = 1 if dist > 0.0 and fraction > 0.5 and not stuck else 0
        self._stall_steps = self._stall_steps + 1 if blocked else 0
        if fraction or dtheta or guided:
            self._geometry_dirty = True

    def _dock_guides(self) -> float:
        """The dock's guides: pushed forward against the dock close to the contacts, the
        robot slides onto them (up to 2 mm and 1 deg a step); returns the extra rotation."""
        target = self._dock_target
        dock = self.world.dock
        assert target is not None and dock is not None
        ex, ey = target.x - self.x, target.y - self.y
        err = wrap_angle(target.theta - self.theta)
        if ex * ex + ey * ey > (dock.contact_tolerance + 25.0) ** 2 or abs(err) > DOCK_GUIDE_ANGLE:
            return 0.0
        off = math.hypot(ex, ey)
        if off > 0.0:
            step = min(off, 2.0)
            self.x += ex / off * step
            self.y += ey / off * step
        self._geometry_dirty = True
        return max(-_GUIDE_STEP, min(_GUIDE_STEP, err))

    def _blocked(self, x: float, y: float) -> bool:
        """Would the body at (x, y) overlap a wall it does not overlap now?"""
        r2 = ROBOT_RADIUS_MM * ROBOT_RADIUS_MM
        for wall in self._near_segments():
            seg = wall[6]
            d_new = closest_point(x, y, seg)[2]
            if d_new < r2 and d_new < closest_point(self.x, self.y, seg)[2] - 1e-9:
                return True
        return False

    def _fall(self) -> None:
        """A drive wheel off a drop (:meth:`_wheel_over_drop`), in any mode: wheel drops, all
        cliffs, stuck. Safe mode's own rules then see the wheel drop and give Passive."""
        self.fallen = True
        self._body_changed()
        self.left_speed = self.right_speed = 0.0
        self._power_due = True
        self.event("fell", "drove off a drop")
        self._geometry_dirty = True
        self._sense()
