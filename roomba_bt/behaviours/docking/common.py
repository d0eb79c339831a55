"""What every docking stage shares: the dock as one frame sees it, the hazards it reacts to,
the wheel commands, and the notes the stages leave for ``dock_time_limit``."""

from __future__ import annotations

from collections.abc import Callable
from enum import Enum
from typing import NamedTuple, TypeVar

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.declare import Action, Param, declare
from roomba_bt.behaviours.driving import wheel_speeds
from roomba_bt.behaviours.units import DURATION
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import (
    ENCODER_PACKETS,
    HAZARD_PACKETS,
    IR_PACKETS,
    LIGHT_BUMPER_PACKETS,
    VIRTUAL_WALL_PACKETS,
    SensorFrame,
)
from roomba_bt.oi.ir import IRCharacter
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME

_new_tuple = tuple.__new__  # a named tuple without its Python-level __new__ (once a tick)

#: The stages drive with Drive Direct and halt with Drive 0: their ``sends=``.
DRIVE_SENDS = (COMMANDS_BY_NAME["drive"].opcode, COMMANDS_BY_NAME["drive_direct"].opcode)
OK, RUNNING, FAILED = Status.SUCCESS, Status.RUNNING, Status.FAILURE

#: Where the stages note which one is running, for ``dock_time_limit``'s message.
STAGE_KEY = "/roomba/docking/stage"
#: When the current docking run began (``dock_time_limit`` notes it): the approach counts
#: its attempts per run.
RUN_KEY = "/roomba/docking/run"


def note_stage(stage: str) -> None:
    py_trees.blackboard.Blackboard.storage[STAGE_KEY] = stage


def current_stage() -> str | None:
    """The docking stage that ran last (None before any)."""
    stage = py_trees.blackboard.Blackboard.storage.get(STAGE_KEY)
    return stage if isinstance(stage, str) else None


class DockView(NamedTuple):
    """What one frame says about the dock (a named tuple: one is built every tick)."""

    omni: IRCharacter
    left: IRCharacter
    right: IRCharacter

    @classmethod
    def of(cls, frame: SensorFrame) -> DockView:
        return _new_tuple(cls, (frame.ir_omni, frame.ir_left, frame.ir_right))

    @property
    def seen(self) -> bool:
        return self.omni.from_dock or self.left.from_dock or self.right.from_dock

    @property
    def on_left(self) -> bool:
        """Only the left receiver sees the dock: it is more than ~5 deg to the left."""
        return self.left.from_dock and not self.right.from_dock

    @property
    def on_right(self) -> bool:
        return self.right.from_dock and not self.left.from_dock

    @property
    def facing(self) -> bool:
        return self.left.from_dock and self.right.from_dock

    def _beams(self) -> tuple[bool, bool, bool]:
        """(red buoy, green buoy, force field) seen. The omni receiver sits on the robot's
        axis: where it is, the robot is. The side receivers are 4 cm off it and count only
        when the omni sees nothing of the dock."""
        omni, left, right = self
        if omni.from_dock:
            return omni.red_buoy, omni.green_buoy, omni.force_field
        by_left, by_right = left.from_dock, right.from_dock
        return (
            (by_left and left.red_buoy) or (by_right and right.red_buoy),
            (by_left and left.green_buoy) or (by_right and right.green_buoy),
            (by_left and left.force_field) or (by_right and right.force_field),
        )

    @property
    def red(self) -> bool:
        return self._beams()[0]

    @property
    def green(self) -> bool:
        return self._beams()[1]

    @property
    def force_field(self) -> bool:
        return self._beams()[2]

    @property
    def side(self) -> int:
        """+1 on the dock's left (red only), -1 on its right (green only), 0 on the axis or
        unknown."""
        red, green, _ = self._beams()
        if red and not green:
            return 1
        if green and not red:
            return -1
        return 0

    @property
    def on_axis(self) -> bool:
        red, green, _ = self._beams()
        return red and green


def dock_seen(frame: SensorFrame) -> bool:
    """A receiver sees a dock character: :attr:`DockView.seen` without building the view
    (the search asks on every tick, and needs nothing else of it)."""
    return frame.ir_omni.from_dock or frame.ir_left.from_dock or frame.ir_right.from_dock


class IdentityEnum(Enum):
    """Base of the docking enums: hashed by identity (members are singletons), since Enum's
    own ``__hash__`` is a Python call on every tick's table look-ups (``ACTS[self.state]``,
    ``STOPS_FOR``)."""

    __hash__ = object.__hash__


class Hazard(IdentityEnum):
    """What the search and the approach back away from, most serious first."""

    WHEEL_DROP = "wheel drop"
    #: a cliff sensor, or a virtual wall: a line not to cross, like a drop
    CLIFF = "cliff"
    BUMP = "bump"
    #: the light bumper sees something ahead (packet 45, front four sensors)
    OBSTACLE = "obstacle"


# Read on every tick as module globals: on CPython 3.11 a member read off its class
# (``Hazard.CLIFF``) costs about a thousand machine instructions (EnumType has a
# ``__getattr__`` hook), a global a few dozen.
_WHEEL_DROP, _CLIFF, _BUMP, _OBSTACLE = (
    Hazard.WHEEL_DROP, Hazard.CLIFF, Hazard.BUMP, Hazard.OBSTACLE,
)  # fmt: skip


#: What :func:`hazard_in` reads: packets 7 and 9-12 (bumps, wheel drops, cliffs), 13 (a
#: virtual wall) and 45 (the light bumper), for the ``reads`` of a stage that calls it.
HAZARD_IN_PACKETS = (*HAZARD_PACKETS, *VIRTUAL_WALL_PACKETS, *LIGHT_BUMPER_PACKETS)


def hazard_in(frame: SensorFrame, *, obstacles: bool = True) -> Hazard | None:
    """The most serious hazard the frame shows, or None; with ``obstacles=False`` the light
    bumper is not read (nothing ahead counts). Read every tick: the union ``any_hazard``
    first, so a clear frame costs one accessor for packets 7 and 9-12, not three."""
    if frame.any_hazard:
        if frame.any_wheel_drop:
            return _WHEEL_DROP
        if frame.any_cliff:
            return _CLIFF
        return _BUMP
    if frame.virtual_wall:
        return _CLIFF
    if obstacles and frame.light_bumper_ahead:
        return _OBSTACLE
    return None


class DockingAction(Action):
    """Shared helpers: wheel commands, stage notes and messages, odometry marks."""

    moves = True
    stage = ""

    def wheels(self, left: float, right: float) -> None:
        """Drive Direct (mm/s), sent only when the wheel speeds change (the robot keeps
        them), clamped to the command's range. Asked the same speeds as last time with the
        wheels still turning (no halt since), it has nothing to do: most ticks of a spin or
        a straight leg ask the same (rounding and clamping them again was most of its cost)."""
        if self._started_motion and self._asked == (left, right):
            return
        lo, ro = wheel_speeds(left, right)
        if (lo, ro) != self._last_wheels or not self._started_motion:
            self.send(oi.drive_direct(ro, lo))
        self._last_wheels = (lo, ro)
        self._asked = (left, right)
        self._started_motion = True

    def spin_toward(self, err: float, speed: float) -> None:
        """Turn in place at ``speed`` (mm/s on each wheel) toward the side of ``err``
        (radians, counter-clockwise positive)."""
        self.wheels(-speed if err > 0 else speed, speed if err > 0 else -speed)

    def halt(self) -> None:
        if self._started_motion and not self.not_driving():
            self.send(oi.halt())
        self._started_motion = False
        self._last_wheels = (0, 0)
        self._asked = None

    _last_wheels = (0, 0)
    #: the speeds (mm/s) that set ``_last_wheels``, None after a halt
    _asked: tuple[float, float] | None = None

    def fail(self, message: str) -> Status:
        self.halt()
        self.feedback_message = f"{self.stage}: {message}"
        return FAILED

    def succeed(self) -> Status:
        self.halt()
        return OK

    def begin(self) -> None:
        note_stage(self.stage)
        self._t0 = self.snapshot.time
        # read once a start (the parameters are resolved before it), compared every tick
        self._time_limit = self.number("timeout") - 1e-9

    def timed_out(self, now: float) -> bool:
        """The ``timeout`` parameter (s) has passed since the stage began (``now``: the
        snapshot's time)."""
        return now - self._t0 >= self._time_limit

    def not_driving(self) -> bool:
        return self.snapshot.mode not in DRIVING_MODES

    def fallback_message(self) -> str:
        change = self.snapshot.last_fallback
        cause = f" ({change.cause})" if change is not None else ""
        return f"the robot left Safe/Full mode{cause}"

    def heading(self) -> float:
        return self.snapshot.odometry.theta_rad

    def turned(self) -> float:
        """Signed rotation since :meth:`mark_turn`, radians."""
        return self.snapshot.odometry.angle_rad - self._turn_mark

    def mark_turn(self) -> None:
        self._turn_mark = self.snapshot.odometry.angle_rad

    def travelled(self) -> float:
        """How far (mm, either way) the signed odometry distance is from :meth:`mark_distance`."""
        return abs(self.snapshot.odometry.distance_mm - self._distance_mark)

    def mark_distance(self) -> None:
        self._distance_mark = self.snapshot.odometry.distance_mm

    _turn_mark = 0.0
    _distance_mark = 0.0
    _t0 = 0.0
    _time_limit = 0.0


Stage = TypeVar("Stage", bound=type[DockingAction])


def declare_stage(
    name: str,
    *,
    timeout: str,
    timeout_doc: str,
    params: tuple[Param, ...] = (),
    reads: tuple[int, ...] = (),
) -> Callable[[Stage], Stage]:
    """``@declare`` for a driving stage, with what :class:`DockingAction` itself uses said
    once: the ``timeout`` parameter :meth:`~DockingAction.timed_out` reads (after the
    stage's own ``params``), the receivers' IR characters (:class:`DockView`) before and the
    encoders (the odometry marks) after the packets in ``reads``, and Drive Direct and Drive
    0 sent (:meth:`~DockingAction.wheels`, :meth:`~DockingAction.halt`)."""
    limit = Param("timeout", DURATION, default=timeout, minimum=1, doc=timeout_doc)
    return declare(
        name,
        kind="action",
        params=(*params, limit),
        reads=(*IR_PACKETS, *reads, *ENCODER_PACKETS),
        sends=DRIVE_SENDS,
    )
