"""The simulated robot: OI bytes in, OI bytes out, physics and sensors on 15 ms steps.

The simulator is a robot, not a mock of one: it parses the host's bytes with the same opcode
table the encoder uses (an incomplete command waits for its data bytes), applies the spec's
mode rules (``CommandSpec.modes`` / ``leads_to``), ignores actuator commands in Passive and Off
as the robot does (and counts them in :attr:`Simulator.violations`), and answers Sensors (142),
Query List (149) and Stream (148) with bytes laid out by the packet table::

    host -> robot   [128] [131] [148][2][7][35] [145][0][100][0][100] ...
    robot -> host   [19][4][7][b7][35][b35][chk]            every 15 ms while streaming
                    [b7][b35]                               reply to [149][2][7][35]

One :meth:`Simulator.step` is one 15 ms stream slot: timeline events, wheel motion (with
collisions), sensors from the world's geometry, Safe-mode safety, battery, the passive sleep
timer, then one stream frame. The hot path is written for speed (the simulator must run far
faster than real time): sensor values live in one flat list indexed by packet id, frames are
packed by a precompiled :class:`struct.Struct`, and geometry is only recomputed when the pose
or the world changes. ``tests/sim`` checks every frame against
:meth:`roomba_bt.oi.frames.FrameLayout.stream_frame`.
"""

from __future__ import annotations

import math
import random
import struct
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from operator import itemgetter
from typing import NamedTuple

from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.ir import LighthouseBeam, dock_character, lighthouse_character
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import MM_PER_COUNT, OLD_FIRMWARE_ANGLE_FACTOR
from roomba_bt.oi.opcodes import COMMANDS, CommandSpec
from roomba_bt.oi.packets import GROUPS, VALID_PACKET_IDS, expand
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.oi.stream import byte_sum_for
from roomba_bt.sim.faults import NO_FAULTS, Faults
from roomba_bt.sim.geometry import (
    Segment,
    closest_point,
    point_in_polygon,
    wrap_angle,
)
from roomba_bt.sim.world import ROBOT_RADIUS_MM, DockSpec, Pose, TimelineEvent, World

STEP_SECONDS = 0.015
_STEP_NS = 15_000_000
_DRIVE = bytes((137,))
#: The robot's wheel speed controller moves in steps of about 28.5 mm/s.
WHEEL_SPEED_STEP_MM_S = 28.5
MAX_WHEEL_SPEED_MM_S = 500.0
PASSIVE_SLEEP_SECONDS = 300.0
BATTERY_CAPACITY_MAH = 2696.0
#: Bytes the firmware prints on Reset (7), as captured by pycreate2's author on a Create 2.
RESET_BANNER = (
    b"bl-start\r\nSTR730\r\nbootloader id: #x47186549 82ECCFFF\r\n"
    b"bootloader info rev: #xF000\r\nbootloader rev: #x0001\r\n2007-05-14-1715-L   \r\n"
    b"Roomba by iRobot!\r\nstr730\r\n2012-03-22-1549-L\r\nbattery-current-zero 252\r\n"
)

# Sensor geometry (robot frame: angle from the heading, CCW positive).
_LIGHT_BUMP_ANGLES = tuple(math.radians(a) for a in (65.0, 38.0, 12.0, -12.0, -38.0, -65.0))
_LIGHT_BUMP_DIRECTIONS = tuple((math.cos(a), math.sin(a)) for a in _LIGHT_BUMP_ANGLES)
LIGHT_BUMP_RANGE_MM = 150.0
LIGHT_BUMP_THRESHOLD = 100
_CLIFF_ANGLES = tuple(math.radians(a) for a in (60.0, 20.0, -20.0, -60.0))
CLIFF_SENSOR_RADIUS_MM = 150.0
CLIFF_FLOOR_SIGNAL = 2600
CLIFF_DROP_SIGNAL = 20
WALL_SENSOR_RANGE_MM = 120.0
WALL_SENSOR_TRIGGER_MM = 50.0
#: Bumper: contacts within this angle of the heading press both switches.
BUMP_CENTRE_ANGLE = math.radians(12.0)
BUMP_HALF_SPAN = math.radians(85.0)
CONTACT_MM = 1.5
#: IR receivers: the omni on top of the bumper, the directional ones left and right of it.
OMNI_FORWARD_MM = 130.0
RECEIVER_FORWARD_MM = 150.0
RECEIVER_SIDE_MM = 40.0
#: Field of view of the directional receivers, from the heading: left sees -5..+90 deg,
#: right -90..+5 deg, so both see the dock only when it is within 5 deg of straight ahead.
RECEIVER_INNER = math.radians(5.0)
RECEIVER_OUTER = math.radians(90.0)
#: Pushed against the dock within this angle of the contacts, its guides align the robot.
DOCK_GUIDE_ANGLE = math.radians(20.0)
_GUIDE_STEP = math.radians(1.0)
_NEAR_MARGIN_MM = 300.0
_RAY_RANGES = (LIGHT_BUMP_RANGE_MM,) * 6 + (WALL_SENSOR_RANGE_MM,)
_Line = tuple[float, float, float, float, float, float, float]


def _line(seg: Segment) -> _Line:
    """(nx, ny, n.a, tx, ty, t.a, length) of a wall segment from a to b."""
    ax, ay, bx, by = seg
    length = math.hypot(bx - ax, by - ay)
    tx, ty = ((bx - ax) / length, (by - ay) / length) if length else (1.0, 0.0)
    nx, ny = -ty, tx
    return (nx, ny, nx * ax + ny * ay, tx, ty, tx * ax + ty * ay, length)


_NEAR_RADIUS_MM = ROBOT_RADIUS_MM + LIGHT_BUMP_RANGE_MM + 40.0 + _NEAR_MARGIN_MM
_NEAR_MARGIN2 = _NEAR_MARGIN_MM**2
_REACH2 = (ROBOT_RADIUS_MM + LIGHT_BUMP_RANGE_MM + 5.0) ** 2  # walls the rays may hit
_CONTACT2 = (ROBOT_RADIUS_MM + CONTACT_MM) ** 2  # walls touching the bumper
_NEAREST2 = (_NEAR_RADIUS_MM - _NEAR_MARGIN_MM) ** 2  # the clearance the near set guarantees
_REACH = math.sqrt(_REACH2)
#: a lower bound of the clearance while no wall is within reach (the real one is larger)
_OPEN_CLEARANCE = _REACH - ROBOT_RADIUS_MM - 1.0

_DEGREES_PER_RADIAN = 180.0 / math.pi
_OLD_ANGLE_PER_RADIAN = _DEGREES_PER_RADIAN * OLD_FIRMWARE_ANGLE_FACTOR
#: The checksum byte that brings a frame's sum to 0 mod 256, for every partial sum.
_CHECKSUM_BYTE = tuple(bytes(((-total) & 0xFF,)) for total in range(256))
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_PASSIVE, _SAFE, _FULL = OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL
_CONST = 59  # values[_CONST + k] == k: constant bytes (header, ids) packed with the values
_ANALOG = (22, 23, 27, 28, 29, 30, 31, 46, 47, 48, 49, 50, 51, 54, 55, 56, 57)
_BAUD_BY_CODE = {code: rate for rate, code in BAUD_CODES.items()}


class TracePoint(NamedTuple):
    """One point of the trajectory (every 4th step, and at each mode change). A tuple, not a
    frozen dataclass: one is made every 60 ms of robot time, and tuples are built in C."""

    time: float
    x: float
    y: float
    theta: float
    mode: OIMode


@dataclass(frozen=True, slots=True)
class SimEvent:
    """Something worth marking on a plot: a bump, a cliff, a mode change, docking..."""

    time: float
    kind: str
    detail: str
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class Violation:
    """A command the robot ignored because its mode does not accept it."""

    time: float
    opcode: int
    name: str
    mode: OIMode


class _Packer:
    """Packs a list of packet ids from the flat value list in one ``struct`` call."""

    __slots__ = (
        "byte_sum", "getter", "has_angle", "has_distance", "size", "snapshot", "struct", "sum_bias",
    )  # fmt: skip

    def __init__(
        self, ids: tuple[int, ...], profile: RobotProfile, stream: bool, noise: bool = False
    ) -> None:
        codes = [">"]
        idx: list[int] = []
        if stream:
            size = stream_payload(ids, profile)
            codes.append("BB")
            idx += [_CONST + 19, _CONST + size]
        for pid in ids:
            if stream:
                codes.append("B")
                idx.append(_CONST + pid)
            for member in expand(pid):
                codes.append(profile.packet(member).struct_code)
                idx.append(member)
        self.struct = struct.Struct("".join(codes))
        getter = itemgetter(*idx)
        self.getter: Callable[[list[int]], tuple[int, ...]] = (
            getter if len(idx) > 1 else (lambda v: (getter(v),))
        )
        members = {m for p in ids for m in expand(p)}
        self.has_distance = 19 in members
        self.has_angle = 20 in members
        #: the values need preparing before a frame: distance/angle since last read, noise
        self.snapshot = self.has_distance or self.has_angle or noise
        self.size = self.struct.size
        # The checksum byte is -(sum of the frame's bytes, less the header's 19 where the
        # profile's checksum leaves it out) & 0xFF; the sum taken as the parser takes it.
        self.byte_sum, added = byte_sum_for(self.size)
        self.sum_bias = added + (0 if profile.checksum_includes_header else 19)


def stream_payload(ids: tuple[int, ...], profile: RobotProfile) -> int:
    """The n-bytes of a stream frame of ``ids``: an id byte and the data of each packet."""
    return sum(1 + sum(profile.packet(m).size for m in expand(p)) for p in ids)


#: n-bytes is one byte: a longer stream cannot be framed
MAX_STREAM_PAYLOAD = 255


class _Builtin:
    """A built-in behaviour the firmware runs in Passive: Clean, Spot, Max, Seek Dock."""

    def __init__(self, name: str, started: float) -> None:
        self.name = name
        self.started = started
        self.phase = "forward"
        self.phase_until = 0.0
        self.turn_sign = 1.0
        self.wander_until = 0.0  # after a bounce, go straight a while before aiming again


def _count_offset(spec: CommandSpec) -> int:
    """Data bytes before the argument that counts a command's variable tail."""
    assert spec.tail is not None
    offset = 0
    for arg in spec.args:
        if arg.name == spec.tail.count_arg:
            return offset
        offset += arg.size
    raise ValueError(f"{spec.name}: no argument {spec.tail.count_arg!r}")


#: What one step of steady wheel speeds does, computed once per (left, right, dt): a plain
#: tuple (indexed on the step path, where a tuple subscript is the cheapest access)::
#:
#:     0 left   1 right   2 dt          the key: wheel speeds (mm/s) and step (s)
#:     3 dist   4 dtheta  5 dtheta / 2  travel of the centre (mm), turn (rad)
#:     6 left counts  7 right counts    encoder counts of an unhindered step
#:     8 packet 58 (stasis) of an unhindered step
_Motion = tuple[float, float, float, float, float, float, float, float, int]


def _motion_of(left: float, right: float, dt: float, half_base: float) -> _Motion:
    dl = left * dt
    dr = right * dt
    dist = (dl + dr) / 2.0
    dtheta = (dr - dl) / (2.0 * half_base)
    return (
        left, right, dt, dist, dtheta, dtheta / 2.0,
        (dist - dtheta * half_base) / MM_PER_COUNT,
        (dist + dtheta * half_base) / MM_PER_COUNT,
        1 if dist > 0.0 else 0,
    )  # fmt: skip


class _DockBeams:
    """The dock's beams and contacts as plain numbers, computed once per robot: the IR
    receivers ask for a character three times every 30 ms, so no attribute chains, no
    function calls for the angle wrap, one table lookup for the character."""

    __slots__ = (
        "angle_tolerance", "buoy2", "characters", "contact2", "facing", "field2", "green_from",
        "green_to", "reach2", "red_from", "red_to", "target_theta", "target_x", "target_y",
        "x", "y",
    )  # fmt: skip

    def __init__(self, dock: DockSpec) -> None:
        self.x, self.y, self.facing = dock.x, dock.y, dock.facing
        self.field2 = dock.force_field * dock.force_field
        self.buoy2 = dock.buoy_range * dock.buoy_range
        reach = max(dock.buoy_range, dock.force_field) + 200.0
        self.reach2 = reach * reach
        self.red_from, self.red_to = dock.red
        self.green_from, self.green_to = dock.green
        discovery = dock.family == "discovery"
        #: index: red << 2 | green << 1 | force field
        self.characters = tuple(
            dock_character(red=bool(i & 4), green=bool(i & 2), force_field=bool(i & 1),
                           discovery=discovery)
            for i in range(8)
        )  # fmt: skip
        target = dock.docked_pose
        self.target_x, self.target_y, self.target_theta = target.x, target.y, target.theta
        self.contact2 = dock.contact_tolerance**2
        self.angle_tolerance = dock.angle_tolerance

    def character(self, px: float, py: float) -> int:
        """What a receiver at (px, py) sees of a powered dock (0: nothing)."""
        dx, dy = px - self.x, py - self.y
        dist2 = dx * dx + dy * dy
        index = 1 if dist2 <= self.field2 else 0
        if dist2 <= self.buoy2:
            bearing = (math.atan2(dy, dx) - self.facing + _PI) % _TWO_PI - _PI
            if self.red_from <= bearing <= self.red_to:
                index |= 4
            if self.green_from <= bearing <= self.green_to:
                index |= 2
        return self.characters[index]


class Simulator:
    """A virtual Roomba / Create 2 in a :class:`~roomba_bt.sim.world.World`.

    ``receive(bytes)`` takes host bytes, ``step()`` advances 15 ms, ``read()`` drains what the
    robot sent. Same world, seed, faults and input bytes -> the same output bytes.
    """

    def __init__(
        self,
        world: World,
        profile: RobotProfile = CREATE2,
        seed: int = 0,
        faults: Faults | None = None,
        *,
        start: Pose | None = None,
        random_start: bool = False,
        old_firmware_angle: bool = False,
        mode: OIMode = OIMode.OFF,
    ) -> None:
        self.world = world
        self.profile = profile
        self.seed = seed
        self.faults = faults or NO_FAULTS
        self.old_firmware_angle = old_firmware_angle
        self._rng = random.Random(f"robot:{seed}")
        self._fault_rng = random.Random(f"faults:{seed}")
        pose = start or (world.sample_start(seed) if random_start else world.start)
        self.x, self.y, self.theta = pose.x, pose.y, pose.theta
        self.mode = mode
        self.asleep = False
        self.disconnected = False
        self.baud = profile.default_baud
        self.ticks = 0
        self.time = 0.0
        self._time_ns = 0
        # actuators
        self.requested_left = 0.0  # mm/s, from Drive / Drive Direct / Drive PWM
        self.requested_right = 0.0
        self.left_speed = 0.0  # actual (quantised) wheel speeds
        self.right_speed = 0.0
        self.motor_bits = 0
        self.brush_pwm = (0, 0, 0)
        self.leds: tuple[int, int, int] = (0, 0, 0)
        self.scheduling_leds: tuple[int, int] = (0, 0)
        self.digits: tuple[int, int, int, int] = (32, 32, 32, 32)
        self.songs: dict[int, tuple[tuple[int, int], ...]] = {}
        self.schedule: bytes = bytes(15)
        self.day_time: tuple[int, int, int] = (0, 0, 0)
        self._song_until = 0.0
        self._buttons_until = 0.0
        self.builtin: _Builtin | None = None
        # state
        self.battery_charge = world.battery * BATTERY_CAPACITY_MAH
        self.lifted = False
        self.fallen = False
        self.docked = False
        self.dock_powered = True
        self.blocked = False
        self._stall_steps = 0
        self._event_bump = 0
        self._left_counts = 0.0
        self._right_counts = 0.0
        self._distance_acc = 0.0
        self._angle_acc = 0.0
        self._last_activity = 0.0
        self._stream: _Packer | None = None
        self._stream_ids: tuple[int, ...] = ()
        self._stream_paused = False
        self._next_inject = self.faults.inject_every if self.faults.inject_text else math.inf
        self._inbuf = bytearray()
        self._out = bytearray()
        self._delayed: deque[tuple[float, bytes]] = deque()
        self._pending_events: list[TimelineEvent] = list(world.events)
        self._active_events: list[TimelineEvent] = []
        self._geometry_dirty = True
        self._near: tuple[Segment, ...] = ()
        self._near_at = (math.inf, math.inf)
        self._commands: dict[int, CommandSpec] = {c.opcode: c for c in profile.commands}
        self._data_sizes = {c.opcode: c.fixed_data_bytes for c in profile.commands}
        #: variable tails from the opcode table: (offset of the count byte, bytes per item)
        self._tails = {
            c.opcode: (1 + _count_offset(c), c.tail.bytes_per_item)
            for c in profile.commands
            if c.tail is not None
        }
        self._reply_packers: dict[tuple[int, ...], _Packer] = {}
        self._encoder_signed = profile.encoders_signed
        self.violations: list[Violation] = []
        self.events: list[SimEvent] = []
        self.trace: list[TracePoint] = [TracePoint(0.0, self.x, self.y, self.theta, self.mode)]
        self.ignored_bytes = 0
        self.bytes_sent = 0
        self.frames_sent = 0
        # flat value list: packets 0..58, then the constants 0..255
        self.values: list[int] = [0] * _CONST + list(range(256))
        v = self.values
        v[26] = int(BATTERY_CAPACITY_MAH)
        v[24] = 24
        v[35] = int(mode) + (1 if profile.reports_mode_plus_one else 0)
        v[40] = -32768
        v[58] = 0
        v[28] = v[29] = v[30] = v[31] = CLIFF_FLOOR_SIGNAL
        self._prev_bumps = 0
        self._prev_cliffs = 0
        self._rays_on = True
        self._ir_stale = True
        self._dock_target = world.dock.docked_pose if world.dock is not None else None
        self._beams = _DockBeams(world.dock) if world.dock is not None else None
        self._drops = world.drops
        self._lines = {seg: _line(seg) for seg in world.solid}
        #: the last Drive (137) command, whole: the same bytes again change nothing
        self._last_drive = b""
        self._drive_modes = self._commands[137].modes
        self._plain_output = not (self.faults.corrupt_rate or self.faults.latency)
        self._half_base = profile.wheel_base_mm / 2.0
        self._motion: _Motion = _motion_of(0.0, 0.0, STEP_SECONDS, self._half_base)
        self._current = 0.0
        self._clearance = 0.0
        self._free_at = (math.inf, math.inf)
        self._free2 = 0.0
        self._power_key: tuple[object, ...] | None = None
        self._disconnect_at = (
            math.inf if self.faults.disconnect_at is None else self.faults.disconnect_at
        )
        self._sense()
        self._battery(0.0)

    # ------------------------------------------------------------------ properties
    @property
    def pose(self) -> Pose:
        return Pose(self.x, self.y, self.theta)

    @property
    def streaming(self) -> bool:
        return self._stream is not None and not self._stream_paused

    @property
    def stream_ids(self) -> tuple[int, ...]:
        return self._stream_ids

    @property
    def charging(self) -> bool:
        return self.values[21] in (1, 2, 3)

    # ------------------------------------------------------------------ host -> robot
    def receive(self, data: bytes | bytearray) -> None:
        """Take bytes from the host. A command whose data bytes have not all arrived waits
        for them, as the robot does; unknown opcodes are skipped one byte at a time."""
        if self.disconnected or not data:
            return
        self._last_activity = self.time
        buf = self._inbuf
        commands = self._commands
        sizes = self._data_sizes
        tails = self._tails
        if not buf:  # the common case: exactly one whole fixed-size command
            if data == self._last_drive and not self.asleep and self.mode in self._drive_modes:
                return  # the same Drive again (a client sends one a frame): nothing changes
            spec = commands.get(data[0])
            if spec is not None and spec.tail is None and len(data) == 1 + sizes[data[0]]:
                self._execute(spec, bytes(data[1:]))
                return
        buf += data
        while buf:
            op = buf[0]
            spec = commands.get(op)
            if spec is None:
                del buf[0]
                self.ignored_bytes += 1
                continue
            need = 1 + sizes[op]
            if len(buf) < need:
                return
            tail = tails.get(op)
            if tail is not None:
                count_at, per_item = tail
                need += buf[count_at] * per_item
                if len(buf) < need:
                    return
            args = bytes(buf[1:need])
            del buf[:need]
            self._execute(spec, args)

    def _execute(self, spec: CommandSpec, args: bytes) -> None:
        op = spec.opcode
        if self.asleep or self.mode is OIMode.OFF:
            # Off (and asleep) answers nothing but Start, and Reset where it exists.
            if op != 128 and op != 7:
                if spec.is_actuator:
                    self.violations.append(Violation(self.time, op, spec.name, OIMode.OFF))
                return
        elif self.mode not in spec.modes:
            if spec.is_actuator:
                self.violations.append(Violation(self.time, op, spec.name, self.mode))
            return
        if spec.leads_to is not None:
            self._command_mode(spec)
        handler = _HANDLERS.get(op)
        if handler is not None:
            handler(self, args)

    def _command_mode(self, spec: CommandSpec) -> None:
        target = spec.leads_to
        assert target is not None
        self.asleep = False
        self.builtin = None
        self._stop_wheels()
        if target is not OIMode.SAFE and target is not OIMode.FULL:
            self.motor_bits = 0
            self.brush_pwm = (0, 0, 0)
        self._set_mode(target, spec.name)

    def _set_mode(self, mode: OIMode, cause: str) -> None:
        if mode is not self.mode:
            self.events.append(
                SimEvent(self.time, "mode", f"{self.mode.label}->{mode.label} ({cause})",
                         self.x, self.y)
            )  # fmt: skip
            self.mode = mode
            self.trace.append(TracePoint(self.time, self.x, self.y, self.theta, mode))
        # Some 600-series firmware reports mode + 1 in packet 35 (the profile says which).
        self.values[35] = int(mode) + (1 if self.profile.reports_mode_plus_one else 0)

    def _stop_wheels(self) -> None:
        self._last_drive = b""
        self.requested_left = self.requested_right = 0.0
        v = self.values
        v[39] = v[41] = v[42] = 0
        v[40] = -32768

    # command handlers ------------------------------------------------------------
    def _on_reset(self, args: bytes) -> None:
        self._stream = None
        self._stream_ids = ()
        self.songs.clear()
        self._inbuf.clear()
        self._emit(RESET_BANNER)

    def _on_start(self, args: bytes) -> None:
        return None

    def _on_stop(self, args: bytes) -> None:
        self._stream = None
        self._stream_ids = ()

    def _on_power(self, args: bytes) -> None:
        self.asleep = True
        self._stream = None
        self._stream_ids = ()
        self.events.append(SimEvent(self.time, "sleep", "power (133)", self.x, self.y))

    def _on_baud(self, args: bytes) -> None:
        self.baud = _BAUD_BY_CODE.get(args[0], self.baud)

    def _on_drive(self, args: bytes) -> None:
        command = _DRIVE + args
        if command == self._last_drive:
            return  # the same Drive again: nothing changes
        self._last_drive = command
        velocity, radius = struct.unpack(">hh", args)
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
        self._last_drive = b""
        right, left = struct.unpack(">hh", args)
        right = max(-500, min(500, right))
        left = max(-500, min(500, left))
        self.requested_left, self.requested_right = _quantise(left), _quantise(right)
        v = self.values
        v[39] = (left + right) // 2
        v[40] = -32768 if left == right else 0
        v[41] = right
        v[42] = left

    def _on_drive_pwm(self, args: bytes) -> None:
        self._last_drive = b""
        right, left = struct.unpack(">hh", args)
        scale = MAX_WHEEL_SPEED_MM_S / 255.0
        self.requested_right = _quantise(max(-255, min(255, right)) * scale)
        self.requested_left = _quantise(max(-255, min(255, left)) * scale)
        v = self.values
        v[41] = round(self.requested_right)
        v[42] = round(self.requested_left)
        v[39] = (v[41] + v[42]) // 2

    def _on_motors(self, args: bytes) -> None:
        self.motor_bits = args[0]
        self.brush_pwm = (
            127 if args[0] & 4 else 0,
            127 if args[0] & 1 else 0,
            127 if args[0] & 2 else 0,
        )

    def _on_pwm_motors(self, args: bytes) -> None:
        main, side, vacuum = struct.unpack(">bbb", args)
        self.brush_pwm = (main, side, vacuum)
        self.motor_bits = (1 if side else 0) | (2 if vacuum else 0) | (4 if main else 0)

    def _on_leds(self, args: bytes) -> None:
        self.leds = (args[0], args[1], args[2])

    def _on_scheduling_leds(self, args: bytes) -> None:
        self.scheduling_leds = (args[0], args[1])

    def _on_digits(self, args: bytes) -> None:
        self.digits = (args[0], args[1], args[2], args[3])

    def _on_song(self, args: bytes) -> None:
        number, length = args[0], args[1]
        if number > 4:
            return
        notes = args[2 : 2 + 2 * length]
        self.songs[number] = tuple((notes[i], notes[i + 1]) for i in range(0, len(notes), 2))

    def _on_play(self, args: bytes) -> None:
        song = self.songs.get(args[0])
        if song is None:
            return
        self.values[36] = args[0]
        self.values[37] = 1
        self._song_until = self.time + sum(d for _, d in song) / 64.0

    def _on_sensors(self, args: bytes) -> None:
        if args[0] in VALID_PACKET_IDS:
            self._emit(self._pack_reply((args[0],)))

    def _on_query_list(self, args: bytes) -> None:
        ids = tuple(p for p in args[1:] if p in VALID_PACKET_IDS)
        if ids:
            self._emit(self._pack_reply(ids))

    def _on_stream(self, args: bytes) -> None:
        ids = tuple(p for p in args[1:] if p in VALID_PACKET_IDS)
        payload = stream_payload(ids, self.profile)
        if payload > MAX_STREAM_PAYLOAD:
            # Neither spec says what the robot does with a list whose frame cannot be
            # framed (n-bytes is one byte); the simulator refuses it and keeps what it had.
            why = f"stream of {payload} bytes (n-bytes is one byte: at most 255)"
            self.events.append(SimEvent(self.time, "refused", why, self.x, self.y))
            return
        self._stream_ids = ids
        self._stream = _Packer(ids, self.profile, True, bool(self.faults.noise)) if ids else None
        self._stream_paused = False
        self.values[38] = min(len(ids), 108)

    def _on_pause_resume(self, args: bytes) -> None:
        self._stream_paused = args[0] == 0

    def _on_buttons(self, args: bytes) -> None:
        self.values[18] = args[0]
        self._buttons_until = self.time + 1.0 / 6.0

    def _on_schedule(self, args: bytes) -> None:
        self.schedule = bytes(args)

    def _on_day_time(self, args: bytes) -> None:
        self.day_time = (args[0], args[1], args[2])

    # ------------------------------------------------------------------ robot -> host
    def read(self) -> bytes:
        """Everything the robot has sent and the host has not read yet."""
        if self._delayed:
            now = self.time
            while self._delayed and self._delayed[0][0] <= now + 1e-9:
                self._out += self._delayed.popleft()[1]
        if not self._out:
            return b""
        data = bytes(self._out)
        self._out.clear()
        return data

    def _emit(self, data: bytes) -> None:
        if self.disconnected:
            return
        faults = self.faults
        if faults.corrupt_rate:
            rng = self._fault_rng
            rate = faults.corrupt_rate
            buf = bytearray(data)
            for i in range(len(buf)):
                if rng.random() < rate:
                    buf[i] = (buf[i] + rng.randrange(1, 256)) & 0xFF
            data = bytes(buf)
        self.bytes_sent += len(data)
        if faults.latency:
            self._delayed.append((self.time + faults.latency, data))
        else:
            self._out += data

    def _pack_reply(self, ids: tuple[int, ...]) -> bytes:
        packer = self._reply_packers.get(ids)
        if packer is None:
            packer = self._reply_packers[ids] = _Packer(ids, self.profile, False)
        return packer.struct.pack(*packer.getter(self._snapshot_values(packer)))

    def _snapshot_values(self, packer: _Packer) -> list[int]:
        """The value list to send now: distance/angle since last read, noise if asked."""
        v = self.values
        if packer.has_distance:
            d = round(self._distance_acc)
            if d:
                d = -32768 if d < -32768 else 32767 if d > 32767 else d
                self._distance_acc -= d
            v[19] = d
        if packer.has_angle:
            acc = self._angle_acc
            if self.old_firmware_angle:
                a = round(acc * _OLD_ANGLE_PER_RADIAN)
                self._angle_acc -= a / _OLD_ANGLE_PER_RADIAN
            else:
                a = round(acc * _DEGREES_PER_RADIAN)
                self._angle_acc -= a / _DEGREES_PER_RADIAN
            v[20] = -32768 if a < -32768 else 32767 if a > 32767 else a
        if self.faults.noise:
            noisy = list(v)
            rng = self._fault_rng
            sigma = self.faults.noise
            for pid in _ANALOG:
                value = round(noisy[pid] + rng.gauss(0.0, sigma))
                if pid in (23, 54, 55, 56, 57):
                    noisy[pid] = max(-32768, min(32767, value))
                elif pid == 22:
                    noisy[pid] = max(0, min(65535, value))
                else:
                    noisy[pid] = max(0, min(4095, value))
            return noisy
        return v

    # ------------------------------------------------------------------ time
    def step(self, dt: float = STEP_SECONDS) -> None:
        """Advance one 15 ms slot and send one stream frame if a stream is on."""
        self.ticks += 1
        # Whole nanoseconds, no drift: 200 steps are exactly 3.0 s (round(t, 9) costs more
        # than a third of a microsecond, the integer sum a tenth of that).
        self._time_ns += _STEP_NS if dt == STEP_SECONDS else round(dt * 1e9)
        self.time = self._time_ns / 1e9
        if self.disconnected:
            return
        faults = self.faults
        if self.time >= self._disconnect_at:
            self.disconnected = True
            self._out.clear()
            self._delayed.clear()
            self.events.append(SimEvent(self.time, "disconnect", "link lost", self.x, self.y))
            return
        if self._pending_events or self._active_events:
            self._timeline()
        if self.asleep:
            return
        v = self.values
        if v[37] or v[18]:
            if v[37] and self.time >= self._song_until:
                v[37] = 0
            if v[18] and self.time >= self._buttons_until:
                v[18] = 0
        mode = self.mode
        if self.builtin is not None and mode is _PASSIVE:
            left, right = self._builtin_wheels(self.builtin)
        elif mode is _SAFE or mode is _FULL:
            left, right = self.requested_left, self.requested_right
        else:
            left = right = 0.0
        if left or right or self.left_speed or self.right_speed:
            self._move(left, right, dt)
        if self._geometry_dirty:
            self._sense()
        if mode is _SAFE:
            if v[7] & 12 or v[9] or v[10] or v[11] or v[12] or self.docked:
                self._safety()
        elif mode is _FULL and self._drops and not self.fallen and self._over_drop(self.x, self.y):
            self._fall()
        self._battery(dt)
        if (
            mode is _PASSIVE
            and self.time - self._last_activity >= PASSIVE_SLEEP_SECONDS
            and not self.charging
            and self.builtin is None
        ):
            self.asleep = True
            self._stream = None
            self._stream_ids = ()
            self.events.append(SimEvent(self.time, "sleep", "5 min idle", self.x, self.y))
            return
        stream = self._stream
        if stream is not None and not self._stream_paused:
            if self.time >= self._next_inject:
                self._emit(faults.inject_text.encode("ascii"))
                self._next_inject += faults.inject_every
            values = self._snapshot_values(stream) if stream.snapshot else self.values
            body = stream.struct.pack(*stream.getter(values))
            frame = body + _CHECKSUM_BYTE[(stream.byte_sum(body) - stream.sum_bias) & 0xFF]
            if faults.drop_rate and self._fault_rng.random() < faults.drop_rate:
                return
            self.frames_sent += 1
            if self._plain_output:
                self.bytes_sent += len(frame)
                self._out += frame
            else:
                self._emit(frame)

    def run(self, seconds: float) -> bytes:
        """Step for ``seconds`` of simulated time; return everything sent meanwhile."""
        out = bytearray()
        for _ in range(round(seconds / STEP_SECONDS)):
            self.step()
            out += self.read()
        return bytes(out)

    # ------------------------------------------------------------------ physics
    def _move(self, left: float, right: float, dt: float) -> None:
        self.left_speed, self.right_speed = left, right
        if not left and not right:
            self.values[58] = 0
            self._stall_steps = 0
            return
        motion = self._motion
        if motion[0] != left or motion[1] != right or motion[2] != dt:
            motion = self._motion = _motion_of(left, right, dt, self._half_base)
        dist, dtheta, half_turn = motion[3], motion[4], motion[5]
        fraction = 1.0
        stuck = self.lifted or self.fallen
        x, y, theta = self.x, self.y, self.theta
        if stuck:
            fraction = 0.0
        elif dist:
            heading = theta + half_turn
            ux = dist * math.cos(heading)
            uy = dist * math.sin(heading)
            if abs(dist) >= self._clearance and self._blocked(x + ux, y + uy):
                lo, hi = 0.0, 1.0
                if self._clearance < 0.5 and self._blocked(x + ux / 64, y + uy / 64):
                    hi = 0.0  # pressed against the wall already: no room at all
                while hi - lo > 0.01:
                    mid = (lo + hi) / 2.0
                    if self._blocked(x + ux * mid, y + uy * mid):
                        hi = mid
                    else:
                        lo = mid
                fraction = lo
            self.x = x = x + ux * fraction
            self.y = y = y + uy * fraction
        v = self.values
        if fraction == 1.0:
            # free motion (the usual step): what the wheels did is the same every step
            self.blocked = False
            theta = theta + dtheta
            if theta > _PI:
                theta -= _TWO_PI
            elif theta < -_PI:
                theta += _TWO_PI
            self.theta = theta
            self._distance_acc += dist
            self._angle_acc += dtheta
            left_counts = self._left_counts = self._left_counts + motion[6]
            right_counts = self._right_counts = self._right_counts + motion[7]
            v[58] = motion[8]
            self._stall_steps = 0
            self._geometry_dirty = True
        else:
            self._move_hindered(dist, dtheta, fraction, stuck)
            left_counts, right_counts = self._left_counts, self._right_counts
        lc = int(left_counts) & 0xFFFF
        rc = int(right_counts) & 0xFFFF
        if self._encoder_signed:
            lc = lc - 0x10000 if lc > 0x7FFF else lc
            rc = rc - 0x10000 if rc > 0x7FFF else rc
        v[43] = lc
        v[44] = rc
        if not self.ticks & 3:
            self.trace.append(TracePoint(self.time, self.x, self.y, self.theta, self.mode))

    def _move_hindered(self, dist: float, dtheta: float, fraction: float, stuck: bool) -> None:
        """The rest of a step that a wall cut short, or a lifted or fallen robot's."""
        half_base = self._half_base
        blocked = self.blocked = fraction < 1.0 and dist != 0.0 and not stuck
        guided = 0.0
        if blocked and dist > 0.0 and self._dock_target is not None:
            guided = self._dock_guides()  # the body turns, the wheels slip: no encoder counts
        if stuck:
            travelled = dist
        else:
            travelled = dist * fraction
            theta = self.theta + dtheta + guided
            if theta > _PI:
                theta -= _TWO_PI
            elif theta < -_PI:
                theta += _TWO_PI
            self.theta = theta
            self._distance_acc += travelled
            self._angle_acc += dtheta
        # Encoders count wheel turns: a blocked robot's wheels stall, a lifted one's spin.
        self._left_counts = self._left_counts + (travelled - dtheta * half_base) / MM_PER_COUNT
        self._right_counts = self._right_counts + (travelled + dtheta * half_base) / MM_PER_COUNT
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

    def _near_segments(self) -> tuple[Segment, ...]:
        """The walls within reach of any sensor, kept until the robot has moved 0.3 m."""
        nx, ny = self._near_at
        dx, dy = self.x - nx, self.y - ny
        if dx * dx + dy * dy > _NEAR_MARGIN2:
            limit = _NEAR_RADIUS_MM**2
            x, y = self.x, self.y
            self._near = tuple(s for s in self.world.solid if closest_point(x, y, s)[2] < limit)
            self._near_at = (x, y)
        return self._near

    def _blocked(self, x: float, y: float) -> bool:
        r2 = ROBOT_RADIUS_MM * ROBOT_RADIUS_MM
        for seg in self._near_segments():
            d_new = closest_point(x, y, seg)[2]
            if d_new < r2 and d_new < closest_point(self.x, self.y, seg)[2] - 1e-9:
                return True
        return False

    def _over_drop(self, x: float, y: float) -> bool:
        return any(point_in_polygon(x, y, drop) for drop in self._drops)

    # ------------------------------------------------------------------ sensors
    def _sense(self) -> None:
        """Every geometric sensor, from the pose and the world (only when either changed)."""
        self._geometry_dirty = False
        v = self.values
        x, y, theta = self.x, self.y, self.theta
        close_lines: list[_Line] = []
        fx, fy = self._free_at
        dx, dy = x - fx, y - fy
        if dx * dx + dy * dy < self._free2:
            # Still in the open: no wall was within reach of a sensor plus the distance moved
            # since the walls were last measured, so none touches or shows now either.
            bumps = 0
            self._clearance = _OPEN_CLEARANCE
        else:
            bumps = self._sense_walls(x, y, theta, close_lines)
        bumps |= self._event_bump
        down = self.lifted or self.fallen
        if down:
            bumps |= 12
        v[7] = bumps
        if bumps != self._prev_bumps:
            if bumps & 3 and not self._prev_bumps & 3:
                side = {1: "right", 2: "left", 3: "both"}[bumps & 3]
                self.events.append(SimEvent(self.time, "bump", side, x, y))
            if bumps & 12 and not self._prev_bumps & 12:
                self.events.append(SimEvent(self.time, "wheel_drop", "", x, y))
            self._prev_bumps = bumps
        # light bumpers and the wall sensor (rays from the bumper against close walls)
        light_bits = 0
        if close_lines:
            ct, st = math.cos(theta), math.sin(theta)
            rays = [(ct * ca - st * sa, st * ca + ct * sa) for ca, sa in _LIGHT_BUMP_DIRECTIONS]
            # the wall sensor looks right of the heading (a ray through the centre, started
            # on the bumper: near enough to the real sensor at -60 deg, looking right)
            rays.append((st, -ct))
            # Each close wall as a line: unit normal n, unit tangent t, n.a, t.a, length. A ray
            # from the centre c in direction d meets it at c + k d, k = (n.a - n.c) / (n.d);
            # the ray starts on the bumper (k = R), the hit's place along the wall is t.(c+kd).
            hits = list(_RAY_RANGES)
            radius = ROBOT_RADIUS_MM
            for nx, ny, w, tx, ty, ta, length in close_lines:
                p = w - (nx * x + ny * y)
                q = tx * x + ty * y - ta
                i = -1
                for c, s in rays:
                    i += 1
                    dn = nx * c + ny * s
                    if dn * p <= 0.0:
                        continue  # pointing away from (or along) this wall
                    k = p / dn
                    t = k - radius
                    if t < 0.0 or t >= hits[i]:
                        continue
                    along = q + k * (tx * c + ty * s)
                    if 0.0 <= along <= length:
                        hits[i] = t
            for i in range(6):
                d = hits[i]
                if d < LIGHT_BUMP_RANGE_MM:
                    signal = int(4095 * (1.0 - d / LIGHT_BUMP_RANGE_MM) ** 2)
                    if signal >= LIGHT_BUMP_THRESHOLD:
                        light_bits |= 1 << i
                else:
                    signal = 0
                v[46 + i] = signal
            d = hits[6]
            if d < WALL_SENSOR_RANGE_MM:
                top = self.profile.wall_signal_maximum
                v[27] = int(top * (1.0 - d / WALL_SENSOR_RANGE_MM) ** 2)
                v[8] = 1 if d < WALL_SENSOR_TRIGGER_MM else 0
            else:
                v[27] = v[8] = 0
            self._rays_on = True
        elif self._rays_on:
            v[46] = v[47] = v[48] = v[49] = v[50] = v[51] = v[27] = v[8] = 0
            self._rays_on = False
        v[45] = light_bits
        # cliffs
        cliffs = 0
        if down:
            cliffs = 15
        elif self.world.drops:
            for i, a in enumerate(_CLIFF_ANGLES):
                px = x + CLIFF_SENSOR_RADIUS_MM * math.cos(theta + a)
                py = y + CLIFF_SENSOR_RADIUS_MM * math.sin(theta + a)
                if self._over_drop(px, py):
                    cliffs |= 1 << i
        if cliffs != self._prev_cliffs:
            for i in range(4):
                hit = cliffs >> i & 1
                v[9 + i] = hit
                v[28 + i] = CLIFF_DROP_SIGNAL if hit else CLIFF_FLOOR_SIGNAL
            if cliffs and not self._prev_cliffs:
                self.events.append(SimEvent(self.time, "cliff", f"{cliffs:04b}", x, y))
            self._prev_cliffs = cliffs
        if not self.ticks & 1 or self._ir_stale:
            self._sense_ir()
        # on the contacts: within the dock's tolerances of the docked pose, not lifted
        beams = self._beams
        if beams is not None:
            ex, ey = x - beams.target_x, y - beams.target_y
            docked = (
                ex * ex + ey * ey <= beams.contact2
                and abs((theta - beams.target_theta + _PI) % _TWO_PI - _PI) <= beams.angle_tolerance
                and not self.lifted
            )
            if docked != self.docked:
                self.docked = docked
                self.events.append(
                    SimEvent(self.time, "docked" if docked else "undocked", "", x, y)
                )

    def _sense_walls(self, x: float, y: float, theta: float, close_lines: list[_Line]) -> int:
        """The bumper bits from walls touching the robot; the walls close enough for the light
        bumper's rays go into ``close_lines``; how far the robot is from every wall."""
        nx, ny = self._near_at
        dx, dy = x - nx, y - ny
        near = self._near if dx * dx + dy * dy <= _NEAR_MARGIN2 else self._near_segments()
        bumps = 0
        reach2 = _REACH2
        lines = self._lines
        contact2 = _CONTACT2
        nearest2 = _NEAREST2
        for seg in near:
            ax, ay, bx, by = seg
            ex, ey = bx - ax, by - ay
            t = ((x - ax) * ex + (y - ay) * ey) / (ex * ex + ey * ey or 1.0)
            t = 0.0 if t < 0.0 else 1.0 if t > 1.0 else t
            cx, cy = ax + t * ex, ay + t * ey
            dx, dy = x - cx, y - cy
            d2 = dx * dx + dy * dy
            if d2 < nearest2:
                nearest2 = d2
            if d2 < reach2:
                close_lines.append(lines[seg])
                if d2 < contact2:
                    a = wrap_angle(math.atan2(cy - y, cx - x) - theta)
                    if -BUMP_HALF_SPAN < a < BUMP_HALF_SPAN:
                        if a > BUMP_CENTRE_ANGLE:
                            bumps |= 2
                        elif a < -BUMP_CENTRE_ANGLE:
                            bumps |= 1
                        else:
                            bumps |= 3
        nearest = math.sqrt(nearest2)
        # how far the robot can move before a wall could stop it (the _move fast path)
        self._clearance = nearest - ROBOT_RADIUS_MM - 1.0
        # how far it can move before any wall could come within reach of a sensor
        free = nearest - _REACH
        self._free_at = (x, y)
        self._free2 = free * free if free > 0.0 else 0.0
        return bumps

    def _sense_ir(self) -> None:
        """The IR receivers. A character takes tens of milliseconds to send, so they are
        updated every other step (30 ms), and at once when the world changes."""
        self._ir_stale = False
        v = self.values
        x, y, theta = self.x, self.y, self.theta
        c, s = math.cos(theta), math.sin(theta)
        omni_x, omni_y = x + OMNI_FORWARD_MM * c, y + OMNI_FORWARD_MM * s
        omni = left = right = 0
        beams = self._beams
        if beams is not None:
            dx, dy = omni_x - beams.x, omni_y - beams.y
            if dx * dx + dy * dy < beams.reach2 and self.dock_powered:
                character = beams.character
                omni = character(omni_x, omni_y)
                fx = x + RECEIVER_FORWARD_MM * c
                fy = y + RECEIVER_FORWARD_MM * s
                # Fields of view are cones from the robot's centre (the receivers sit close
                # together on the bumper); which beams each sees depends on where it is.
                bearing = (math.atan2(beams.y - y, beams.x - x) - theta + _PI) % _TWO_PI - _PI
                if -RECEIVER_INNER <= bearing <= RECEIVER_OUTER:
                    left = character(fx - RECEIVER_SIDE_MM * s, fy + RECEIVER_SIDE_MM * c)
                if -RECEIVER_OUTER <= bearing <= RECEIVER_INNER:
                    right = character(fx + RECEIVER_SIDE_MM * s, fy - RECEIVER_SIDE_MM * c)
        wall = 0
        world = self.world
        if world.virtual_walls or world.lighthouses:
            for vw in world.virtual_walls:
                if self._in_beam(omni_x, omni_y, vw.segment, vw.half_width, vw.halo):
                    wall = 162
                    break
            if not wall:
                for lh in world.lighthouses:
                    if self._in_beam(omni_x, omni_y, lh.fence_segment, lh.half_width, 0.0):
                        wall = lighthouse_character(lh.id, LighthouseBeam.FENCE)
                        break
                    ddx, ddy = omni_x - lh.x, omni_y - lh.y
                    if ddx * ddx + ddy * ddy <= lh.halo * lh.halo:
                        wall = lighthouse_character(lh.id, LighthouseBeam.FORCE_FIELD)
                        break
        v[13] = 1 if wall == 162 else 0
        if wall and (not omni or self.ticks & 2):  # both seen: they alternate
            omni = wall
        v[17] = omni
        v[52] = left
        v[53] = right

    @staticmethod
    def _in_beam(px: float, py: float, seg: Segment, half_width: float, halo: float) -> bool:
        if halo:
            dx, dy = px - seg[0], py - seg[1]
            if dx * dx + dy * dy <= halo * halo:
                return True
        return closest_point(px, py, seg)[2] <= half_width * half_width

    # ------------------------------------------------------------------ safety, battery
    def _safety(self) -> None:
        v = self.values
        cause = ""
        if v[7] & 12:
            cause = "wheel drop"
        elif (v[9] or v[10] or v[11] or v[12]) and self.left_speed + self.right_speed > 0:
            cause = "cliff while driving forward"
        elif self.docked and self.dock_powered:
            cause = "powered charger"
        if cause:
            self._stop_wheels()
            self.left_speed = self.right_speed = 0.0
            self.motor_bits = 0
            self.brush_pwm = (0, 0, 0)
            self._set_mode(OIMode.PASSIVE, f"safety: {cause}")

    def _fall(self) -> None:
        self.fallen = True
        self.left_speed = self.right_speed = 0.0
        self.events.append(SimEvent(self.time, "fell", "drove off a drop", self.x, self.y))
        self._geometry_dirty = True
        self._sense()

    def _battery(self, dt: float) -> None:
        """Charge and currents. Currents are recomputed only when what draws them changes
        (the step must stay cheap); the charge integrates every step."""
        key = (
            self.left_speed, self.right_speed, self.brush_pwm, self.docked, self.dock_powered,
            self.mode, self.blocked, self._stall_steps > 30,
        )  # fmt: skip
        if key != self._power_key:
            self._power_key = key
            self._power_changed()
        charge = self.battery_charge + self._current * dt / 3600.0
        if charge >= BATTERY_CAPACITY_MAH * 0.98 and self._current > 200.0:
            self._power_key = None  # switch to trickle charging
        if charge < 0.0:
            charge = 0.0
        elif charge > BATTERY_CAPACITY_MAH:
            charge = BATTERY_CAPACITY_MAH
        self.battery_charge = charge
        if not self.ticks & 31:
            self._update_battery_values()

    def _power_changed(self) -> None:
        v = self.values
        charging = self.docked and self.dock_powered and self.mode in (OIMode.PASSIVE, OIMode.OFF)
        if charging:
            full = self.battery_charge >= BATTERY_CAPACITY_MAH * 0.98
            current = 150.0 if full else 1500.0
            v[21] = 3 if full else 2
        else:
            wheels = abs(self.left_speed) + abs(self.right_speed)
            brushes = abs(self.brush_pwm[0]) + abs(self.brush_pwm[1]) + abs(self.brush_pwm[2])
            current = -(150.0 + 0.6 * wheels + 1.6 * brushes)
            v[21] = 0
        self._current = current
        v[34] = 2 if self.docked and self.dock_powered else 0
        stall = 600 if self.blocked else 0
        left, right = self.left_speed, self.right_speed
        v[54] = int(0.6 * left) + (stall if left > 0 else -stall if left < 0 else 0)
        v[55] = int(0.6 * right) + (stall if right > 0 else -stall if right < 0 else 0)
        v[56] = int(2.4 * abs(self.brush_pwm[0]))
        v[57] = int(0.8 * abs(self.brush_pwm[1]))
        over = 0
        if self._stall_steps > 30:
            over |= (16 if left else 0) | (8 if right else 0)
        v[14] = over
        self._update_battery_values()

    def _update_battery_values(self) -> None:
        v = self.values
        fraction = self.battery_charge / BATTERY_CAPACITY_MAH
        v[25] = int(self.battery_charge)
        v[22] = int(13200 + 3200 * fraction + (600 if self._current > 0 else 0))
        v[23] = int(self._current)

    # ------------------------------------------------------------------ timeline
    def _timeline(self) -> None:
        now = self.time
        while self._pending_events and self._pending_events[0].time <= now:
            event = self._pending_events.pop(0)
            self._active_events.append(event)
            self.events.append(SimEvent(now, event.kind, f"{event.side} start", self.x, self.y))
        still = []
        for event in self._active_events:
            if now < event.time + event.duration:
                still.append(event)
            else:
                self.events.append(SimEvent(now, event.kind, "end", self.x, self.y))
        self._active_events = still
        bump = 0
        lifted = False
        powered = True
        for event in still:
            if event.kind == "bump":
                bump |= {"right": 1, "left": 2, "both": 3}[event.side]
            elif event.kind == "lift":
                lifted = True
            elif event.kind == "charger_step":
                powered = False
        if (bump, lifted, powered) != (self._event_bump, self.lifted, self.dock_powered):
            self._event_bump, self.lifted, self.dock_powered = bump, lifted, powered
            self._geometry_dirty = True
            self._ir_stale = True

    # ------------------------------------------------------------------ built-in behaviours
    def _builtin_wheels(self, b: _Builtin) -> tuple[float, float]:
        """Wheel speeds of the firmware's own behaviours (Passive mode, 35 stays 1)."""
        now = self.time
        v = self.values
        if b.name == "seek_dock":
            return self._seek_dock(b)
        if b.name == "spot":
            elapsed = now - b.started
            if elapsed > 30.0 or v[7] & 3 or any(v[9:13]):
                self._end_builtin(b, "spot done")
                return 0.0, 0.0
            radius = 60.0 + 12.0 * elapsed
            return drive_wheel_speeds(200, int(radius), self.profile.wheel_base_mm)
        limit = 600.0 if b.name == "clean" else 3600.0
        if now - b.started > limit or self.battery_charge < 0.05 * BATTERY_CAPACITY_MAH:
            self._end_builtin(b, f"{b.name} done")
            return 0.0, 0.0
        speed = 300.0 if b.name == "clean" else 400.0
        return self._bounce(b, speed)

    def _bounce(self, b: _Builtin, speed: float) -> tuple[float, float]:
        """Forward until a bump, cliff, virtual wall or close light-bump; back up, turn a
        random amount, go on."""
        v = self.values
        now = self.time
        if b.phase == "forward":
            if v[7] & 3 or any(v[9:13]) or v[13] or v[45] & 0b001100 or self.blocked:
                b.phase, b.phase_until = "back", now + 0.3
            else:
                return speed, speed
        if b.phase == "back":
            if now < b.phase_until:
                return -150.0, -150.0
            b.phase = "turn"
            b.turn_sign = self._rng.choice((-1.0, 1.0))
            b.phase_until = now + self._rng.uniform(0.4, 1.4)
        if b.phase == "turn":
            if now < b.phase_until:
                return -150.0 * b.turn_sign, 150.0 * b.turn_sign
            b.phase = "forward"
            b.wander_until = now + self._rng.uniform(1.5, 3.0)
        return speed, speed

    def _seek_dock(self, b: _Builtin) -> tuple[float, float]:
        """Simple homing. The real firmware's algorithm is not specified, so this one uses the
        world's geometry once the dock is in sight: head for where the dock was (bouncing
        off obstacles) until the omni receiver sees a dock beam, then go to a point 0.45 m
        out on the dock's axis, turn to face the dock and drive on slowly."""
        dock = self.world.dock
        if self.docked:
            self._end_builtin(b, "docked")
            return 0.0, 0.0
        if dock is None or self.time - b.started > 600.0:
            self._end_builtin(b, "seek dock gave up")
            return 0.0, 0.0
        sees = self.values[17] and self.values[17] != 162
        target = dock.docked_pose
        fx, fy = math.cos(dock.facing), math.sin(dock.facing)
        if b.phase in ("forward", "back", "turn") and not sees:
            # search: head for where the firmware remembers the dock, bouncing off obstacles
            if (
                b.phase == "forward"
                and self.time >= b.wander_until
                and not (self.values[7] & 3 or self.blocked)
            ):
                sx, sy = target.x + 700.0 * fx, target.y + 700.0 * fy
                return _steer_to(self.x, self.y, self.theta, sx, sy, 200.0)
            return self._bounce(b, 200.0)
        ax, ay = target.x + 450.0 * fx, target.y + 450.0 * fy
        if b.phase in ("forward", "back", "turn"):
            b.phase = "approach"
        if b.phase == "approach":
            if (self.x - ax) ** 2 + (self.y - ay) ** 2 < 30.0**2:
                b.phase = "align"
            else:
                return _steer_to(self.x, self.y, self.theta, ax, ay, 200.0)
        if b.phase == "align":
            err = wrap_angle(target.theta - self.theta)
            if abs(err) < math.radians(1.5):
                b.phase = "dock"
            else:
                w = 60.0 if err > 0 else -60.0
                return -w, w
        if b.phase == "dock":
            if self.values[7] & 3:
                b.phase, b.phase_until = "retreat", self.time + 1.5
            else:
                err = wrap_angle(math.atan2(target.y - self.y, target.x - self.x) - self.theta)
                # aim at the contacts; off-axis corrections are small
                turn = max(-20.0, min(20.0, 200.0 * err))
                return 80.0 - turn, 80.0 + turn
        if b.phase == "retreat":
            if self.time < b.phase_until:
                return -100.0, -100.0
            b.phase = "approach"
        return 0.0, 0.0

    def _end_builtin(self, b: _Builtin, why: str) -> None:
        self.builtin = None
        self.events.append(SimEvent(self.time, "builtin", why, self.x, self.y))


def _steer_to(
    x: float, y: float, theta: float, tx: float, ty: float, speed: float
) -> tuple[float, float]:
    err = wrap_angle(math.atan2(ty - y, tx - x) - theta)
    if abs(err) > math.radians(20.0):
        w = 120.0 if err > 0 else -120.0
        return -w, w
    turn = 2.0 * speed * err
    return speed - turn, speed + turn


def _quantise(speed: float) -> float:
    q = round(speed / WHEEL_SPEED_STEP_MM_S) * WHEEL_SPEED_STEP_MM_S
    return max(-MAX_WHEEL_SPEED_MM_S, min(MAX_WHEEL_SPEED_MM_S, q))


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


def _builtin_handler(name: str) -> Callable[[Simulator, bytes], None]:
    def start(sim: Simulator, args: bytes) -> None:
        sim.builtin = _Builtin(name, sim.time)
        sim.events.append(SimEvent(sim.time, "builtin", name, sim.x, sim.y))

    return start


_HANDLERS: dict[int, Callable[[Simulator, bytes], None]] = {
    7: Simulator._on_reset,
    128: Simulator._on_start,
    129: Simulator._on_baud,
    133: Simulator._on_power,
    134: _builtin_handler("spot"),
    135: _builtin_handler("clean"),
    136: _builtin_handler("max"),
    137: Simulator._on_drive,
    138: Simulator._on_motors,
    139: Simulator._on_leds,
    140: Simulator._on_song,
    141: Simulator._on_play,
    142: Simulator._on_sensors,
    143: _builtin_handler("seek_dock"),
    144: Simulator._on_pwm_motors,
    145: Simulator._on_drive_direct,
    146: Simulator._on_drive_pwm,
    148: Simulator._on_stream,
    149: Simulator._on_query_list,
    150: Simulator._on_pause_resume,
    162: Simulator._on_scheduling_leds,
    163: Simulator._on_digits,
    164: Simulator._on_digits,
    165: Simulator._on_buttons,
    167: Simulator._on_schedule,
    168: Simulator._on_day_time,
    173: Simulator._on_stop,
}

assert set(_HANDLERS) <= set(COMMANDS), "a handler for an opcode the table does not have"
assert all(g in VALID_PACKET_IDS for g in GROUPS)
