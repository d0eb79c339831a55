"""What every docking stage shares: the dock as one frame sees it, the hazards it reacts to,
the wheel commands, and the notes the stages leave for ``dock_time_limit``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from enum import Enum
from operator import itemgetter
from typing import NamedTuple, TypeVar

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import run_board
from roomba_bt.behaviours.declare import Declaration, Param, declare
from roomba_bt.behaviours.driving import left_driving_message, wheel_speeds
from roomba_bt.behaviours.units import DURATION
from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import (
    BUMP_BITS,
    CHARGING_SOURCES_BY_BYTE,
    LIGHT_BUMPER_AHEAD_BITS,
    WHEEL_DROP_BITS,
)
from roomba_bt.oi.frames import (
    ENCODER_PACKETS,
    HAZARD_PACKETS,
    IR_PACKETS,
    LIGHT_BUMPER_PACKETS,
    VIRTUAL_WALL_PACKETS,
    FrameLayout,
    SensorFrame,
)
from roomba_bt.oi.ir import IR_CHARACTERS, IRCharacter
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME
from roomba_bt.oi.packets import PACKETS
from roomba_bt.printable import duration_said
from roomba_bt.robot.interface import Snapshot

#: The stages drive with Drive Direct and halt with Drive 0: their ``sends=``.
DRIVE_SENDS = (COMMANDS_BY_NAME["drive"].opcode, COMMANDS_BY_NAME["drive_direct"].opcode)
OK, RUNNING, FAILED = Status.SUCCESS, Status.RUNNING, Status.FAILURE

#: Where the stages note which one is running, for ``dock_time_limit``'s message.
STAGE_KEY = "/roomba/docking/stage"
#: When the current docking run began (``dock_time_limit`` notes it, a :class:`DockingRun`):
#: the approach counts its attempts per run.
RUN_KEY = "/roomba/docking/run"


class DockingRun(NamedTuple):
    """One docking run: which ``dock_time_limit`` began it, and when. Compared whole (two
    limits in one tree begin two runs); shown on the monitor's blackboard by its start and
    limit, not by the node's ``id()`` (a number that told the reader nothing)."""

    owner: int  # id() of the dock_time_limit node
    started: float  # mission time, s
    limit: str = ""  # the node's name: dock_time_limit(300 s)

    def __repr__(self) -> str:
        by = f" ({self.limit})" if self.limit else ""
        return f"<docking run since t={self.started:.2f} s{by}>"


#: Set (True) once a stage past the search began in this docking run: a receiver saw the
#: dock's beams (the search succeeds at the first one), for ``dock_time_limit``'s message.
PAST_SEARCH_KEY = "/roomba/docking/past_search"


def note_stage(stage: str) -> None:
    """Keep ``stage`` as this run's docking stage (the run's own name for
    :data:`STAGE_KEY`: :func:`~roomba_bt.behaviours.blackboard.run_board`), and note a
    stage past the search (:data:`PAST_SEARCH_KEY`)."""
    storage, board = py_trees.blackboard.Blackboard.storage, run_board()
    storage[board.name(STAGE_KEY)] = stage
    if stage != "search":
        storage[board.name(PAST_SEARCH_KEY)] = True


def past_search() -> bool:
    """Did a stage past the search begin in this docking run (a beam was seen)?"""
    return py_trees.blackboard.Blackboard.storage.get(run_board().name(PAST_SEARCH_KEY)) is True


def current_stage() -> str | None:
    """The docking stage that ran last in this run (None before any)."""
    stage = py_trees.blackboard.Blackboard.storage.get(run_board().name(STAGE_KEY))
    return stage if isinstance(stage, str) else None


class DockView:
    """What the three receivers' IR characters say about the dock.

    Every reading is worked out when the view is built, and a view is built once per
    distinct (omni, left, right) triple of bytes (:func:`view_of`): the stages read several
    of them on every tick, and a tick's view is then one dictionary look-up and plain
    attribute reads, not a tuple and a dozen property calls."""

    __slots__ = (
        "facing", "force_field", "green", "left", "omni", "on_axis", "on_left", "on_right", "red",
        "right", "seen", "side",
    )  # fmt: skip

    def __init__(self, omni: IRCharacter, left: IRCharacter, right: IRCharacter) -> None:
        self.omni, self.left, self.right = omni, left, right
        by_left, by_right = left.from_dock, right.from_dock
        self.seen: bool = omni.from_dock or by_left or by_right
        #: only the left receiver sees the dock: it is more than ~5 deg to the left
        self.on_left: bool = by_left and not by_right
        self.on_right: bool = by_right and not by_left
        self.facing: bool = by_left and by_right
        # The beams seen (red buoy, green buoy, force field). The omni receiver sits on the
        # robot's axis: where it is, the robot is. The side receivers are 4 cm off it and
        # count only when the omni sees nothing of the dock.
        if omni.from_dock:
            red, green, force_field = omni.red_buoy, omni.green_buoy, omni.force_field
        else:
            red = (by_left and left.red_buoy) or (by_right and right.red_buoy)
            green = (by_left and left.green_buoy) or (by_right and right.green_buoy)
            force_field = (by_left and left.force_field) or (by_right and right.force_field)
        self.red: bool = red
        self.green: bool = green
        self.force_field: bool = force_field
        #: +1 on the dock's left (red only), -1 on its right (green only), 0 on the axis or
        #: unknown
        self.side: int = 1 if red and not green else -1 if green and not red else 0
        self.on_axis: bool = red and green

    @classmethod
    def of(cls, frame: SensorFrame) -> DockView:
        return view_of(tuple(frame[packet] for packet in IR_PACKETS))


#: The views built so far, by (omni, left, right) byte (:func:`view_of`).
_VIEWS: dict[tuple[int, ...], DockView] = {}
#: More distinct triples than a run meets (a few dozen): the views are built afresh.
_VIEWS_KEPT = 4096


def view_of(codes: tuple[int, ...]) -> DockView:
    """The :class:`DockView` of the receivers' bytes (``codes``: packets 17, 52 and 53, the
    order of ``IR_PACKETS``), built on the first meeting and kept."""
    view = _VIEWS.get(codes)
    if view is None:
        if len(_VIEWS) >= _VIEWS_KEPT:
            _VIEWS.clear()
        omni, left, right = codes
        view = _VIEWS[codes] = DockView(
            IR_CHARACTERS[omni & 0xFF], IR_CHARACTERS[left & 0xFF], IR_CHARACTERS[right & 0xFF]
        )
    return view


class DockWatch:
    """The tick's :class:`DockView`, for a leaf that looks for the dock on every tick and is
    no docking stage (``cover``'s map keeps where the beams were seen; ``home_by_map`` ends
    when one is): the receivers' bytes read by one ``itemgetter`` bound to the frame's
    layout, bound again only when the layout changes (a new stream), where
    :meth:`DockView.of` looks each packet up and builds a tuple (about 600 ns against 100)."""

    __slots__ = ("_codes", "_layout")

    def __init__(self) -> None:
        self._layout: FrameLayout | None = None  # nothing bound yet: the first view binds

    #: the receivers' bytes (packets 17, 52, 53) from a frame's values, in ``_layout``
    _codes: Callable[[tuple[int, ...]], tuple[int, ...]]

    def view(self, frame: SensorFrame) -> DockView:
        """The frame's view; a frame without the receivers' packets raises the ``KeyError``
        naming the first missing one (the leaf's declared reads carry them)."""
        if frame.layout is not self._layout:
            index = frame.layout.index
            for packet in IR_PACKETS:
                if packet not in index:
                    frame[packet]  # raises the KeyError naming the packet
            self._codes = itemgetter(*(index[packet] for packet in IR_PACKETS))
            self._layout = frame.layout
        return view_of(self._codes(frame.values))


#: By byte of packet 17, 52 or 53: a character sent by a home base.
FROM_DOCK: tuple[bool, ...] = tuple(character.from_dock for character in IR_CHARACTERS)
#: By byte of packet 34: the home base powers the robot.
HOME_BASE: tuple[bool, ...] = tuple(sources.home_base for sources in CHARGING_SOURCES_BY_BYTE)


@dataclass(frozen=True, slots=True)
class HeadingTurn:
    """How a stage turns in place to a heading: ``fast`` (mm/s on each wheel), ``slow``
    once within ``slow_within_rad`` of it, there within ``done_rad``. The search and the
    approach each turn with their own (:meth:`DockingAction.spin_to`)."""

    fast: float
    slow: float
    slow_within_rad: float
    done_rad: float

    def scaled(self, speed: float) -> HeadingTurn:
        """The same turn with ``fast`` and ``slow`` given as shares of ``speed``."""
        return replace(self, fast=self.fast * speed, slow=self.slow * speed)


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
#: virtual wall) and 45 (the light bumper), for the ``reads`` of a stage that calls it, and
#: the order of :func:`hazard_of`'s arguments.
HAZARD_IN_PACKETS = (*HAZARD_PACKETS, *VIRTUAL_WALL_PACKETS, *LIGHT_BUMPER_PACKETS)
assert HAZARD_IN_PACKETS == (7, 9, 10, 11, 12, 13, 45)


def hazard_of(
    bumps: int,
    cliff_left: int,
    cliff_front_left: int,
    cliff_front_right: int,
    cliff_right: int,
    virtual_wall: int,
    light_bumper: int,
    obstacles: bool = True,
) -> Hazard | None:
    """The most serious hazard the raw values of :data:`HAZARD_IN_PACKETS` show, or None;
    with ``obstacles=False`` the light bumper is not read (nothing ahead counts). The bits
    the frame's readings test: ``any_hazard`` (packets 7 and 9-12), ``any_wheel_drop``,
    ``any_cliff``, ``virtual_wall``, ``light_bumper_ahead``."""
    if (
        bumps & (BUMP_BITS | WHEEL_DROP_BITS)
        or cliff_left
        or cliff_front_left
        or cliff_front_right
        or cliff_right
    ):
        if bumps & WHEEL_DROP_BITS:
            return _WHEEL_DROP
        if cliff_left or cliff_front_left or cliff_front_right or cliff_right:
            return _CLIFF
        return _BUMP
    if virtual_wall & 0xFF:
        return _CLIFF
    if obstacles and light_bumper & LIGHT_BUMPER_AHEAD_BITS:
        return _OBSTACLE
    return None


def hazard_in(frame: SensorFrame, *, obstacles: bool = True) -> Hazard | None:
    """The most serious hazard the frame shows, or None (:func:`hazard_of` of its values);
    with ``obstacles=False`` the light bumper is not read (nothing ahead counts)."""
    bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall, light = (
        frame[packet] for packet in HAZARD_IN_PACKETS
    )
    return hazard_of(
        bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall, light, obstacles=obstacles
    )


#: The Drive Direct commands encoded so far, by (right, left) mm/s (:func:`drive_direct`).
_DRIVE_DIRECT: dict[tuple[int, int], oi.Command] = {}
#: More distinct speed pairs than a run sends (a few hundred): encoded afresh.
_DRIVE_DIRECT_KEPT = 4096


def drive_direct(right: int, left: int) -> oi.Command:
    """:func:`~roomba_bt.oi.encode.drive_direct`, each pair of speeds encoded once and the
    (immutable) command kept: a wall follow sends a few hundred distinct pairs, a thousand
    times, and checking and packing the same bytes again was most of a sending tick."""
    command = _DRIVE_DIRECT.get((right, left))
    if command is None:
        if len(_DRIVE_DIRECT) >= _DRIVE_DIRECT_KEPT:
            _DRIVE_DIRECT.clear()
        command = _DRIVE_DIRECT[right, left] = oi.drive_direct(right, left)
    return command


class DockingAction(Action):
    """Shared helpers: wheel commands, stage notes and messages, odometry marks, and the
    frame's readings taken once a tick by slot.

    Each stage names the packets its readings come from (:attr:`WATCHED`). Their slots in a
    frame's layout are found once (:meth:`bind`: every frame of a stream has the same
    layout), their values are read every tick in one call, and the readings (the dock seen,
    the hazard, ...) are worked out again (:meth:`read`) only when one of those values
    changed: most ticks see the same receivers and the same bumpers as the tick before.
    ``update`` does it in its first line, :meth:`observe`.
    """

    moves = True
    stage = ""
    #: the packets :meth:`read` takes the values of, in its order (two at least)
    WATCHED: tuple[int, ...] = ()
    #: what the stage did not do within its ``timeout`` (``{}``: the limit as a message says
    #: a duration, ``2 min``: :func:`~roomba_bt.printable.duration_said`)
    LATE = "not done in {}"
    #: The stages' state in slots, set in ``__init__`` (the class keeps no defaults of
    #: these names): a node's own attributes past the 30 that CPython 3.11 keeps in its
    #: class's shared table give it a dictionary of its own, and then no method call on it
    #: (``self.observe()``, ``self.wheels(...)``, the parent's ``child.tick_direct()``: each
    #: tick) is specialised. py_trees' and the leaf base classes' attributes stay in the
    #: instance's own table, now under that limit; each stage adds its slots.
    __slots__ = (
        "_asked", "_distance_mark", "_done", "_last_wheels", "_layout", "_raw", "_t0",
        "_time_limit", "_turn_mark", "_watched",
    )  # fmt: skip

    def __init__(self, name: str, params: dict[str, object] | None = None) -> None:
        super().__init__(name, params)
        #: the stage's goal reached, as :meth:`read` last found it
        self._done = False
        self._layout = self._raw = None  # nothing bound nor read yet (:meth:`observe`)
        self._last_wheels, self._asked = (0, 0), None  # as after a :meth:`halt`
        self._turn_mark = self._distance_mark = self._t0 = self._time_limit = 0.0

    @classmethod
    def declaration_problem(cls, declaration: Declaration) -> str | None:
        """Each packet of :attr:`WATCHED` among the declared reads: the stream carries only
        what the tree declares, and a stage watching a packet it did not declare would raise
        ``KeyError`` at its first tick (a plugin's subclass adding one to ``WATCHED``)."""
        if callable(declaration.reads):
            return None
        missing = [packet for packet in cls.WATCHED if packet not in declaration.reads]
        if not missing:
            return None
        named = ", ".join(f"{packet} ({PACKETS[packet].name})" for packet in missing)
        return (
            f"{cls.__name__}.WATCHED has packets its declaration does not read: {named}; "
            "add them to the declaration's reads"
        )

    def bind(self, frame: SensorFrame) -> None:
        """Find the slots of :attr:`WATCHED` in the frame's layout; a packet the frame lacks
        raises its ``KeyError`` here (the stream carries what the stage declares)."""
        index = frame.layout.index
        for packet in self.WATCHED:
            if packet not in index:
                frame[packet]  # raises the KeyError naming the packet
        self._watched = itemgetter(*(index[packet] for packet in self.WATCHED))
        self._layout = frame.layout

    def observe(self) -> Snapshot:
        """The tick's snapshot, its readings worked out again (:meth:`read`) only when a value
        of :attr:`WATCHED` changed: every stage's ``update`` starts with it."""
        robot = self.robot
        snap = robot.snapshot if robot is not None else self.snapshot
        frame = snap.frame
        if frame.layout is not self._layout:
            self.bind(frame)
        watched = self._watched  # read, then called: see StreamParser.take
        raw = watched(frame.values)
        if raw != self._raw:
            self._raw = raw
            self.read(raw)
        return snap

    def update(self) -> Status:
        """A driving stage's tick, its checks in one order: the readings (:meth:`observe`);
        the stage's goal reached (``_done``, set by :meth:`read`): SUCCESS; its ``timeout``
        up: FAILURE saying what was not done (:attr:`LATE`); the robot out of Safe/Full:
        FAILURE; else the stage's own :meth:`step`. (The search keeps its own: it marks a
        hazard met on its map before the mode check.)"""
        snap = self.observe()
        if self._done:
            return self.succeed()
        if snap.time - self._t0 >= self._time_limit:
            return self.fail(self.LATE.format(duration_said(self.number("timeout"))))
        if snap.mode not in DRIVING_MODES:
            return self.fail(self.fallback_message())
        return self.step(snap)

    def step(self, snap: Snapshot) -> Status:
        """The stage's own tick, once the checks of :meth:`update` passed."""
        raise NotImplementedError

    def read(self, raw: tuple[int, ...]) -> None:
        """Work the readings out from the values of :attr:`WATCHED` (``raw``): they stand
        until one of those values changes."""
        raise NotImplementedError

    _layout: FrameLayout | None
    _watched: Callable[[tuple[int, ...]], tuple[int, ...]]
    #: the values the readings were worked out from (None: none yet)
    _raw: tuple[int, ...] | None

    def wheels(self, left: float, right: float) -> None:
        """Drive Direct (mm/s), sent only when the wheel speeds change (the robot keeps
        them), clamped to the command's range. Asked the same speeds as last time with the
        wheels still turning (no halt since), it has nothing to do: most ticks of a spin or
        a straight leg ask the same (rounding and clamping them again was most of its cost)."""
        if self._started_motion and self._asked == (left, right):
            return
        lo, ro = wheel_speeds(left, right)
        if (lo, ro) != self._last_wheels or not self._started_motion:
            self.send(drive_direct(ro, lo))
        self._last_wheels = (lo, ro)
        self._asked = (left, right)
        self._started_motion = True

    def spin_toward(self, err: float, speed: float) -> None:
        """Turn in place at ``speed`` (mm/s on each wheel) toward the side of ``err``
        (radians, counter-clockwise positive)."""
        self.wheels(-speed if err > 0 else speed, speed if err > 0 else -speed)

    def spin_to(self, err: float, turn: HeadingTurn) -> bool:
        """Turning to a heading ``err`` radians away (counter-clockwise positive): True,
        sending nothing, once within ``turn.done_rad``; else a spin toward it, fast or slow."""
        if abs(err) < turn.done_rad:
            return True
        self.spin_toward(err, turn.fast if abs(err) > turn.slow_within_rad else turn.slow)
        return False

    def halt(self) -> None:
        if self._started_motion and not self.not_driving():
            self.send(oi.halt())
        self._started_motion = False
        self._last_wheels = (0, 0)
        self._asked = None

    #: the speeds (mm/s) that set ``_last_wheels``, None after a halt
    _asked: tuple[float, float] | None

    def fail(self, message: str) -> Status:
        self.halt()
        self.feedback_message = f"{self.stage}: {message}"
        return FAILED

    def succeed(self) -> Status:
        self.halt()
        return OK

    def begin(self) -> None:
        """Note the stage and when it began. Its ``timeout`` parameter (s) is read once a
        start (the parameters are resolved before it): each tick's ``update`` compares
        ``now - _t0 >= _time_limit``."""
        note_stage(self.stage)
        self._t0 = self.snapshot.time
        self._time_limit = self.number("timeout") - 1e-9

    def not_driving(self) -> bool:
        return self.snapshot.mode not in DRIVING_MODES

    def fallback_message(self) -> str:
        """Why the stage fails out of Safe/Full: the robot left them while its wheels
        turned; else it would start (or go on from a stop) where the guard refuses its
        wheel commands, said with the mode, the fall and the fix (:meth:`refused_motion`)."""
        if self._started_motion:
            return left_driving_message(self.snapshot.last_fallback)
        return self.refused_motion()

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
    once: the ``timeout`` parameter :meth:`~DockingAction.begin` reads (after the
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
