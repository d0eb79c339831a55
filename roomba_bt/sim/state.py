"""What every part of the simulated robot reads: its world, pose, mode, clock, sensor values and
the records of a run (events, trajectory, ignored commands).

The simulator is built in layers, one module per seam, each a class that adds its own state
and methods on top of the ones below it::

    RobotState   (state.py)     world, pose, mode, clock, the flat sensor value list, records
    Sensing      (sensing.py)   bumper, cliffs, wall sensor, light bumper, IR receivers, dock
    Motion       (motion.py)    wheels, Drive commands, collisions, dock guides, falls
    Power        (power.py)     battery, currents, charging on the dock's contacts
    StreamOutput (replies.py)   replies, stream frames, faults on the robot -> host bytes
    OIProtocol   (protocol.py)  command parsing and dispatch, mode rules, Safe-mode safety
    Simulator    (robot.py)     the facade: constructor, one 15 ms step, the timeline

Layers, not components: the step path reads the pose, the speeds and the value list about a
hundred times a step, and ``self.x`` on one object is one lookup where ``self.motion.x`` is two.
Each layer declares the attributes it adds in ``__slots__``: the robot has over a hundred, too
many for CPython's shared-key instance dict, and with a dict of its own every method called on
``self`` is looked up in it and the type, every step (slots: 3.7k of 58.7k instructions a dock
step; a subclass, as the evaluation's, may still add a dict).
The parts that are not on every step's path are objects with their own state: the built-in
cycles (cycles.py) and the world's timeline (timeline.py).

A float becomes a packet's whole number by ``math.trunc``, not ``int``: the same number (both
cut towards zero), and where ``int(x)`` is a call of the type (about 760 instructions in
CPython 3.11), ``trunc(x)`` is a call of a builtin function (about 280).
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import NamedTuple

from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.sim.faults import NO_FAULTS, Faults
from roomba_bt.sim.world import Pose, World

#: One simulator step is one stream slot (the protocol's 15 ms,
#: :data:`~roomba_bt.oi.frames.SLOT_SECONDS`).
STEP_SECONDS = SLOT_SECONDS


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


@dataclass(frozen=True, slots=True)
class OdometryError:
    """How far the encoders' counts are from what the wheels did (``Faults.odometry_error``).

    A real robot's odometry drifts: the wheels' effective diameters differ from the nominal
    (wear, load, carpet), and the two differ a little from each other, so distances come out
    a percent or two off and a straight line reads as a slow curve; slip adds a slow heading
    drift. The simulator's pose stays the truth; only the counts (packets 43, 44) and the
    distance and angle (19, 20) carry the error. Drawn once per seed, with ``f`` the fault's
    fraction::

        common        ~ U(-f, f)          both wheels: distances and turns off by it
        differential  ~ U(-f/10, f/10)    left 1 + common - differential, right 1 + common
                                          + differential: a straight line reads as a curve
        drift         ~ U(-f, f) deg/s    heading drift while the wheels turn (f = 0.015:
                                          up to 0.9 deg per minute of driving)
    """

    left_scale: float = 1.0
    right_scale: float = 1.0
    #: rad/s added to the measured turn while the wheels turn
    drift: float = 0.0

    @classmethod
    def draw(cls, fraction: float, seed: int) -> OdometryError:
        """The seed's error for a fault of ``fraction`` (none for 0: the exact encoders)."""
        if not fraction:
            return EXACT_ODOMETRY
        rng = random.Random(f"odometry:{seed}")  # its own draws: other faults unchanged
        common = fraction * rng.uniform(-1.0, 1.0)
        differential = fraction / 10.0 * rng.uniform(-1.0, 1.0)
        drift = math.radians(fraction) * rng.uniform(-1.0, 1.0)
        return cls(1.0 + common - differential, 1.0 + common + differential, drift)


EXACT_ODOMETRY = OdometryError()


class RobotState:
    """The state every layer reads: set once here, changed by the layer that owns each part.

    ``values`` is the robot's sensor state as the OI reports it, one flat list indexed by
    packet id (0..58), packed into replies and stream frames by replies.py::

        values[7]   bumps and wheel drops      values[35]        OI mode (packet 35)
        values[19]  distance since last read   values[46..51]    light bump signals

    The far sensors' packets (light bumper, wall sensor, IR receivers: sensing.py) are
    measured when read unless a stream of them or a built-in cycle reads them every step:
    ask for them with a reply (Query List) rather than read them here.
    """

    __slots__ = (
        "_event_bump", "_event_overcurrents", "_fault_rng", "_power_due", "_time_ns", "asleep",
        "disconnected", "dock_powered", "docked", "events", "fallen", "faults", "lifted", "mode",
        "odometry_error", "old_firmware_angle", "plugged_in", "profile", "seed", "theta",
        "ticks", "time", "trace", "values", "violations", "world", "x", "y",
    )  # fmt: skip

    #: whether ``trace`` grows (the Simulator's ``trace`` argument)
    keeps_trace: bool = True

    def __init__(
        self,
        world: World,
        profile: RobotProfile,
        seed: int,
        faults: Faults | None,
        start: Pose | None,
        random_start: bool,
        old_firmware_angle: bool,
        mode: OIMode,
    ) -> None:
        self.world = world
        self.profile = profile
        self.seed = seed
        self.faults = faults or NO_FAULTS
        self.old_firmware_angle = old_firmware_angle
        self._fault_rng = random.Random(f"faults:{seed}")
        self.odometry_error = OdometryError.draw(self.faults.odometry_error, seed)
        pose = start or (world.sample_start(seed) if random_start else world.start)
        self.x, self.y, self.theta = pose.x, pose.y, pose.theta
        self.mode = mode
        self.asleep = False
        self.disconnected = False
        self.ticks = 0
        self.time = 0.0
        self._time_ns = 0.0  # the clock in whole nanoseconds: no drift (robot.py's step)
        #: the timeline's effects on the body (timeline.py): held down, lifted, charger off,
        #: a motor's overcurrent (packet 14's bits), the wall charger's plug in its socket
        self._event_bump = 0
        self._event_overcurrents = 0
        self.lifted = False
        self.fallen = False
        self.docked = False
        self.dock_powered = True
        self.plugged_in = False
        #: something the battery's currents depend on may have changed (power.py): set by
        #: every layer that changes one of them
        self._power_due = True
        self.values: list[int] = [0] * (max(PACKETS) + 1)  # indexed by packet id, 0..58
        self.values[35] = int(mode) + (1 if profile.reports_mode_plus_one else 0)
        self.events: list[SimEvent] = []
        self.trace: list[TracePoint] = [TracePoint(0.0, self.x, self.y, self.theta, self.mode)]
        self.violations: list[Violation] = []

    @property
    def pose(self) -> Pose:
        return Pose(self.x, self.y, self.theta)

    def event(self, kind: str, detail: str) -> None:
        """Mark ``kind`` at the robot's place now (events are rare: not for the hot path)."""
        self.events.append(SimEvent(self.time, kind, detail, self.x, self.y))
