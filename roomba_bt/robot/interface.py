"""What a behaviour sees of the robot during one tick, and how it asks for commands.

This is the contract between the behaviours (above) and the runtime (which fills it once per
stream frame). A behaviour never touches the port:

* it reads :attr:`RobotHandle.snapshot`: one immutable :class:`Snapshot` per tick (the sensor
  frame, the mission clock counted in 15 ms stream slots, the reconciled OI mode and the
  odometry integrated from the wheel encoders);
* it hands commands to :attr:`RobotHandle.outbox`. After the tick the runtime checks each one
  against the mode model and writes it, one write a command (``MissionRunner._flush``): per
  actuator channel the last one wins, and mode changes keep their order relative to the
  actuator commands that follow them.

Time in a mission is ``snapshot.time`` (``tick * 0.015`` s), never ``time.time()``, so a replay
or a simulation on a virtual clock makes the same decisions as the live run.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple, Protocol

from roomba_bt._lazy import moved_names
from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import CHARGING_SOURCES_PACKETS, FrameLayout, SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.odometry import MM_PER_COUNT
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME, Delivery, Effect
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.robot.hazards import sets_going

# the 15 ms slot is the protocol's (oi.frames); plugins that took it from here, beside what
# a behaviour sees, still find it, with a DeprecationWarning until 0.3.0
if not TYPE_CHECKING:  # to a type checker the old name is gone, and a typo no Any (PEP 562)
    __getattr__ = moved_names(__name__, {"SLOT_SECONDS": "roomba_bt.oi.frames"})

_new_tuple = tuple.__new__


class Odometry(NamedTuple):
    """Pose and path integrated from the encoders since the run started.

    ``x_mm``/``y_mm``/``theta_rad`` are in the start frame (x forward, theta CCW positive);
    ``distance_mm`` is the signed path length of the centre, ``angle_rad`` the signed total
    rotation (not wrapped), both cumulative so that "since a mark" is a subtraction.
    """

    x_mm: float = 0.0
    y_mm: float = 0.0
    theta_rad: float = 0.0
    distance_mm: float = 0.0
    angle_rad: float = 0.0
    left_counts: int | None = None
    right_counts: int | None = None
    path_mm: float = 0.0  # unsigned path length: "distance driven"

    def advance(self, left_counts: int, right_counts: int, wheel_base_mm: float) -> Odometry:
        """The odometry after a frame carrying these raw encoder counts
        (:func:`advanced_fields` of its fields; the same object while the counts stand)."""
        moved = advanced_fields(self, left_counts, right_counts, wheel_base_mm)
        return self if moved is self else _new_tuple(Odometry, moved)


#: An :class:`Odometry`'s fields in a plain tuple, in its order.
OdometryFields = tuple[float, float, float, float, float, int | None, int | None, float]


def advanced_fields(
    fields: OdometryFields, left_counts: int, right_counts: int, wheel_base_mm: float
) -> OdometryFields:
    """:meth:`Odometry.advance` on the fields of an odometry (an :class:`Odometry`, or its
    fields in a plain tuple): ``fields`` itself while the counts stand (most frames of a
    docked or waiting robot), else the new fields in a plain tuple.

    The :class:`Odometer` keeps the plain tuple it built its odometry from and passes that:
    CPython 3.11 unpacks an exact tuple in one step, a named tuple's items through an
    iterator (about 500 instructions more, on every tick of a moving robot). The
    arithmetic of :func:`~roomba_bt.oi.odometry.encoder_delta`,
    :func:`~roomba_bt.oi.odometry.counts_to_mm` and
    :func:`~roomba_bt.oi.odometry.arc_from_wheels` is written out here, the same operations
    in the same order (the same floats): three calls a tick cost more than the arithmetic
    (tests/robot/test_odometry.py checks it against them)."""
    x, y, theta, distance, angle, previous_left, previous_right, path = fields
    if left_counts == previous_left and right_counts == previous_right:
        return fields
    if previous_left is None or previous_right is None:
        return (x, y, theta, distance, angle, left_counts, right_counts, path)
    left = (((left_counts - previous_left + 0x8000) & 0xFFFF) - 0x8000) * MM_PER_COUNT
    right = (((right_counts - previous_right + 0x8000) & 0xFFFF) - 0x8000) * MM_PER_COUNT
    if left == 0.0 and right == 0.0:
        return (x, y, theta, distance, angle, left_counts, right_counts, path)
    dist = (left + right) / 2.0
    dtheta = (right - left) / wheel_base_mm
    mid = theta + dtheta / 2.0
    return (
        x + dist * math.cos(mid),
        y + dist * math.sin(mid),
        theta + dtheta,
        distance + dist,
        angle + dtheta,
        left_counts,
        right_counts,
        path + abs(dist),
    )


class Odometer:
    """The odometry of one run's stream, integrated frame by frame (the runtime's, once a
    tick): :attr:`odometry` is the newest :class:`Odometry`.

    What is the same for every frame of a stream is found once per layout, not per frame:
    where the encoder counts sit in the frame's values (two indexes: read so, and compared
    one by one with the counts before, they cost half what an ``itemgetter``'s call and a
    tuple's comparison did). A frame whose counts are those of the frame before (a robot
    standing still: docked, waiting) leaves the odometry as it is, the same object, with no
    call; a frame without the encoder packets too."""

    __slots__ = (
        "_counted_left", "_counted_right", "_fields", "_layout", "_left_slot", "_right_slot",
        "_wheel_base_mm", "odometry", "passive_from_mm",
    )  # fmt: skip

    def __init__(self, wheel_base_mm: float) -> None:
        self.odometry = Odometry()
        #: what :attr:`odometry` was built from (after the first frame, its fields in a
        #: plain tuple)
        self._fields: OdometryFields = self.odometry
        self._wheel_base_mm = wheel_base_mm
        self._layout: FrameLayout | None = None
        #: where the frame's left and right encoder counts sit in its values (-1: its layout
        #: has none)
        self._left_slot = self._right_slot = -1
        #: the counts :attr:`odometry` was last advanced to (None: none yet)
        self._counted_left: int | None = None
        self._counted_right: int | None = None
        #: the path (mm) when the robot last went to Passive (the run's start, a command
        #: written, a fall by itself: the writer's ``on_passive`` calls
        #: :meth:`entered_passive`): what it drives in Passive by itself is measured from
        #: there (:meth:`driven_in_passive`), once, at the run's end
        self.passive_from_mm = 0.0

    def entered_passive(self) -> None:
        """The robot went to Passive now: its path in Passive is measured from here."""
        self.passive_from_mm = self.odometry.path_mm

    def driven_in_passive(self) -> float:
        """The path (mm) since the robot last went to Passive (:meth:`entered_passive`)."""
        return self.odometry.path_mm - self.passive_from_mm

    def frame(self, frame: SensorFrame) -> Odometry:
        """The odometry after ``frame`` (:meth:`Odometry.advance` on its encoder counts)."""
        layout = frame.layout
        if layout is not self._layout:
            self._layout = layout
            slots = layout.encoder_slots
            self._left_slot, self._right_slot = (-1, -1) if slots is None else slots
        odometry = self.odometry
        left_slot = self._left_slot
        if left_slot < 0:
            return odometry
        values = frame.values
        left_counts = values[left_slot]
        right_counts = values[self._right_slot]
        # the odometry's own left_counts and right_counts, kept as read: a named tuple's
        # items are read through the generic protocol, twice the cost of one comparison
        if left_counts == self._counted_left and right_counts == self._counted_right:
            return odometry
        self._counted_left, self._counted_right = left_counts, right_counts
        fields = advanced_fields(self._fields, left_counts, right_counts, self._wheel_base_mm)
        if fields is self._fields:
            return odometry
        self._fields = fields
        odometry = self.odometry = _new_tuple(Odometry, fields)
        return odometry


#: A fall's cause when its frame and the frames before show none (no cliff, wheel drop or
#: charger: ``robot/modes.infer_cause``): said with the cable beside it where bytes to the
#: robot were seen lost (``Connection.cable_suspected``).
UNKNOWN_CAUSE = "unknown"


@dataclass(frozen=True, slots=True)
class ModeChange:
    """A mode change the robot made by itself (seen in packet 35), with its likely cause."""

    previous: OIMode
    current: OIMode
    tick: int
    time: float
    cause: str  # "cliff", "wheel drop", "charger", "unknown", ...
    wall_time: float = 0.0  # time.time() when seen, for messages only
    #: when the robot entered ``previous`` (link clock: the command that put it there), if
    #: known; tells a fall right at the Safe command from one met later
    entered: float | None = None
    #: when the run first saw it, in mission time (``Snapshot.time``; the runtime places it
    #: so, the tick it shows): what a leaf's message says, "in Passive since t=1.005" (the
    #: link's clock, ``time``, is no time a mission counts). None: not seen in a run
    mission_time: float | None = None

    @property
    def fall(self) -> bool:
        """A fall from Safe or Full to Passive (a cliff, a wheel drop, the charger in Safe),
        not a resync to what packet 35 reports."""
        return self.current is OIMode.PASSIVE and self.previous in DRIVING_MODES

    @property
    def refused_on_charger(self) -> bool:
        """Safe entered on a powered charger: the firmware dropped it to Passive at once
        (within :data:`CHARGER_REFUSAL_S` of the Safe command), the charger named as the
        cause. The robot started on its dock; a mission that met the charger later (driven
        onto the contacts) is another case, and its messages say nothing of undocking."""
        return (
            self.previous is OIMode.SAFE
            and self.current is OIMode.PASSIVE
            and "charger" in self.cause.split(" and ")  # the dock's, not a plug's
            and self.entered is not None
            and self.time - self.entered <= CHARGER_REFUSAL_S
        )


#: How soon after the Safe command a fall with the charger as its cause counts as the
#: charger refusing Safe (s): the firmware drops at once, the next frames or two show it
CHARGER_REFUSAL_S = 1.0


class Snapshot(NamedTuple):
    """Everything a tick may read, immutable. One blackboard key holds it.

    A named tuple rather than a frozen dataclass: it is built once per 15 ms frame on the
    tick path, and a tuple is built several times faster."""

    frame: SensorFrame
    tick: int
    time: float
    mode: OIMode
    odometry: Odometry = Odometry()
    last_fallback: ModeChange | None = None
    profile: RobotProfile = DEFAULT_PROFILE
    frames_lost: int = 0
    #: a Clean/Spot/Max/Seek Dock cycle may be driving the robot: one was written and no
    #: command that ends it since (the session writer's ``builtin_may_run``); its leaf ends
    #: it when it is halted (:meth:`Outbox.end_cycle`)
    cycle_may_run: bool = False
    #: the ``tick`` of the last snapshot the tree ticked on (the tree's previous tick: ``tick``
    #: less the slots this frame's arrival spans, lost or stale frames being no tick of the
    #: tree; or, after the monitor held the tree on frames, a pause's or a step's, the tick
    #: before them: a pause is no gap, and mission time stood still meanwhile); None when
    #: not known (a snapshot made by hand: take ``tick - 1``). A node that keeps
    #: state across ticks (the ``held`` decorator) compares it with the ``tick`` it last
    #: saw: another one means the tree ticked without it in between
    previous_tick: int | None = None


#: What ends a built-in cycle that may still drive the robot, and leaves it stopped in the
#: Passive the cycle had it in: Safe (131) ends the cycle and makes the actuators take
#: commands, drive 0 ``[137][0][0][0][0]`` and motors off ``[138][0]`` (Clean, Spot and Max
#: run the brushes and the vacuum), Start (128) back to Passive. On a powered home base
#: Safe drops to Passive at once: harmless, and Start leaves the model where the robot is.
CYCLE_END: tuple[Command, ...] = (oi.safe(), oi.halt(), oi.motors_off(), oi.start())
_SEEK_DOCK = COMMANDS_BY_NAME["seek_dock"]
_STATE = Delivery.STATE
_SONG = COMMANDS_BY_NAME["song"]


def docked_by_seek_dock(cycle: Command | None, frame: SensorFrame | None) -> bool:
    """Whether the built-in cycle written last (``cycle``: the last wheel command) is a Seek
    Dock that has ended on its home base: ``frame`` carries packet 34 and shows the home
    base's power. The firmware's Seek Dock stops on the contacts, and the robot charges there
    in Passive: nothing drives, so nothing needs ending (no Safe, which on a powered dock
    stops the charge and drops back to Passive). Any other cycle on the home base may be
    about to drive off it (a Clean sent on the dock) and is ended all the same. The one rule
    of the tree's cycle leaves (``behaviours.driving.cycle_may_run``) and of the safe stop
    (:mod:`~roomba_bt.robot.ending`)."""
    return cycle is not None and cycle.spec is _SEEK_DOCK and on_home_base(frame)


def on_home_base(frame: SensorFrame | None) -> bool:
    """Whether ``frame`` carries packet 34 and it shows the home base's power."""
    return (
        frame is not None
        and all(pid in frame for pid in CHARGING_SOURCES_PACKETS)
        and frame.charging_sources.home_base
    )


#: the outbox's key of a cycle's end asked for (no channel's, no opcode's), and who asked
#: when nobody did (a sender may be None)
_CYCLE_END_KEY = object()
_NOBODY = object()


class Outbox:
    """Commands produced during one tick, flushed by the runtime after it.

    The opcode table says which commands are states and which are events
    (:class:`~roomba_bt.oi.opcodes.Delivery`, one field of each row, read here and nowhere
    else): of the states (Drive, Motors, LEDs, the stream...) the last on each channel
    (``CommandSpec.channel``, e.g. ``"wheels"``) in a tick wins; the events (Play, Buttons,
    Song definitions, mode changes, queries) are all kept, in order. Two Plays in one tick
    are both written, back to back: Play is no state of a "speaker", whose last would drop
    the first, so ``play: 0`` then ``play: 1`` plays both songs. The
    order of the flush is the order in which each surviving command was first queued in
    this tick, so a ``safe`` queued before a ``drive`` is written before it; but a state
    that sets something going, queued again after a mode command (``halt``, ``safe``, then
    the next leaf's ``drive``), moves after it, as the mode command would otherwise undo it
    (:meth:`_mode_change_after`).

    A behaviour that ends stops what it set moving with :meth:`send_stop`, which yields to a
    command another behaviour queued on that channel in this tick. A fallback that switches
    to a higher-priority branch ticks the new branch first and stops the old one after it:
    the old one's halt must not replace the new one's first Drive (it did, and the robot
    stood still while the new branch believed it was turning).

    It is also the one record of each channel's last command, kept two ways because they
    differ: :meth:`last_on`, what the tree last asked for (its leaves read it), and
    :attr:`standing`, what the runtime last wrote and the robot still obeys (what the
    runtime sends again after its own drive 0, and the monitor's resume). After a tick they
    are the same command unless the mode guard refused it (asked for, not written: the
    earlier one stands), the robot fell to Passive by itself since (:meth:`robot_stopped`:
    asked for, no longer standing), or a cycle was ended in the tick it was queued (neither
    asked for nor written; the command before it may stand). Both are kept here, so the
    runner keeps no copy of its own that could differ.
    """

    __slots__ = (
        "_ender", "_last", "_queue", "_senders", "_songs", "_standing", "queued", "standing",
    )  # fmt: skip

    def __init__(self) -> None:
        self._queue: dict[object, Command] = {}
        self._senders: dict[object, object] = {}
        self._last: dict[object, Command] = {}
        #: the queue itself, read-only: true while a command waits (the runtime asks after
        #: every tick, and most ticks queue nothing: a dict's truth is no call, ``len`` is)
        self.queued: Mapping[object, Command] = self._queue
        #: who asked, this tick, for the end of a built-in cycle (:meth:`end_cycle`)
        self._ender: object = _NOBODY
        self._standing: dict[str, Command] = {}
        #: the last command written on each channel ("wheels", "motors", ...) that the robot
        #: still obeys, read-only (:meth:`written`, :meth:`robot_stopped`)
        self.standing: Mapping[str, Command] = self._standing
        #: how long the song last written to each slot plays (s): what ``play`` waits for
        #: when the stream never shows a song that short (:meth:`song_seconds`)
        self._songs: dict[int, float] = {}

    def send(self, command: Command, sender: object = None) -> None:
        """Queue ``command`` for this tick's flush: a state replaces the one queued on its
        channel, an event is added after the rest under a key of its own (an ``object()``:
        not ``(opcode, len(queue))``, which can meet a key again after :meth:`end_cycle`
        deleted one). An event's ``sender`` is kept as its channel's (a
        refusal of either of two Plays names the later one's sender)."""
        spec = command.spec
        channel = spec.channel
        key: object = channel if spec.delivery is _STATE else object()
        queue = self._queue
        if key in queue and sets_going(command) and self._mode_change_after(key):
            del queue[key]  # its place is after the mode command: at the end
        queue[key] = command
        if channel is not None:
            self._senders[channel] = sender
            self._last[channel] = command

    def _mode_change_after(self, key: object) -> bool:
        """Is a mode command (Safe, Full, Start...: its row's ``leads_to``) queued after the
        command under ``key``? A state that sets something going and replaces one queued
        before a mode command is written after that command, not in the old one's place: a
        plugin that ends with ``halt``, ``safe`` and SUCCESS, and the next leaf's first Drive
        in the same tick, would write Drive then Safe, and the Safe would stop the wheels the
        Drive had just set going (a 2 s drive would go 4 cm). A stop keeps the
        earlier place: a leaf's halt after its Stop (173) is refused in Off, so the halt goes
        first. Only on a replacement, a few commands at most: most ticks queue nothing."""
        after = False
        for queued_key, queued in self._queue.items():
            if after and queued.spec.leads_to is not None:
                return True
            after = after or queued_key == key
        return False

    def queued_by(self) -> list[tuple[Command, object]]:
        """Each command queued on a channel (the wheels, the motors...) with who queued it:
        what the runtime says of those it drops (a tree's stop at the run's end)."""
        senders = self._senders
        return [(command, senders[key]) for key, command in self._queue.items() if key in senders]

    def send_stop(self, command: Command, sender: object) -> None:
        """Queue ``command`` (a halt) from ``sender``, which is ending, unless another sender
        already queued a command on its channel in this tick."""
        channel = command.spec.channel
        if channel is not None and channel in self._queue:
            other = self._senders.get(channel)
            if other is not None and other is not sender:
                return
        self.send(command, sender)

    def end_cycle(self, sender: object, *, running: bool = True) -> None:
        """End a built-in cycle (Clean, Spot, Max, Seek Dock): ``sender``, the leaf that
        started it, is halted or failed. Its own cycle command still queued (started and
        halted in one tick: a parallel's other branch ended it) is not written at all;
        ``running``: a cycle written before may still drive the robot in Passive, where
        drive 0 is refused. Then :data:`CYCLE_END` is written before this tick's other
        commands (a higher branch's ``mode: safe`` then still leaves the robot in Safe),
        a cycle this tick starts too (a repeat's ``clean`` sent again, ``mode: passive``
        then ``seek_dock``) included: the 600 / Create 2 OI spec says Clean, Spot, Max and
        Seek Dock each "will pause a cleaning cycle if one is already in progress", so the
        old cycle is ended first and the new command starts a cycle instead of pausing one."""
        queue = self._queue
        wheels = queue.get("wheels")
        if (
            wheels is not None
            and wheels.spec.effect is Effect.BUILTIN_CYCLE
            and self._senders.get("wheels") is sender
        ):
            del queue["wheels"]  # never written: no channel's last command either
            del self._last["wheels"], self._senders["wheels"]
        if running and self._ender is _NOBODY:
            self._ender = sender
            queue[_CYCLE_END_KEY] = CYCLE_END[0]  # ``queued`` is true: the flush comes

    def end_queued_cycle(self, sender: object) -> None:
        """Before ``sender`` queues a built-in cycle command (Clean, Spot, Max, Seek Dock):
        one another leaf queued in this tick (``[spot, seek_dock: {wait: false}]``, both
        ending on the tick they start) is written where it was asked for, then ended by
        :data:`CYCLE_END`, and ``sender``'s comes after. One command per channel would
        have kept only the second, while the first leaf showed SUCCESS for a Spot never
        sent; written back to back, the second would pause the first's cycle (600 / Create
        2 spec) instead of starting its own. Each keeps its place in the flush's order;
        the end's commands on other channels are the tree's last on them (as
        :meth:`drain`'s end of a cycle)."""
        queue = self._queue
        queued = queue.get("wheels")
        if (
            queued is None
            or queued.spec.effect is not Effect.BUILTIN_CYCLE
            or self._senders.get("wheels") is sender
        ):
            return
        # written in this order, each under a key of its own (no channel's: the wheels'
        # is the new cycle's, queued next)
        replaced = {object(): command for command in (queued, *CYCLE_END)}
        items = list(queue.items())
        at = next(i for i, (key, _) in enumerate(items) if key == "wheels")
        queue.clear()
        queue.update(items[:at])
        queue.update(replaced)
        queue.update(items[at + 1 :])
        for command in CYCLE_END:
            channel = command.spec.channel
            if channel is not None and channel != "wheels" and channel not in queue:
                self._senders[channel] = sender
                self._last[channel] = command

    def drain(self) -> list[Command]:
        """The commands to write, in order; empties the outbox. Who sent each channel's
        last command is kept until that channel is sent on again (:meth:`sender_of`: a
        refusal names it); :meth:`send_stop` looks at it only while its channel is queued."""
        queue = self._queue
        ender = self._ender
        if ender is not _NOBODY:
            del queue[_CYCLE_END_KEY]
            self._ender = _NOBODY
        out = list(queue.values())
        queue.clear()
        if ender is not _NOBODY:
            later = {c.spec.channel for c in out}  # written after the end: theirs stand
            for command in CYCLE_END:
                channel = command.spec.channel
                if channel is not None and channel not in later:
                    self._senders[channel] = ender
                    self._last[channel] = command
            out[:0] = CYCLE_END
        return out

    def sender_of(self, command: Command) -> object:
        """The behaviour that queued ``command`` (a channel's last one), or None."""
        channel = command.spec.channel
        return self._senders.get(channel) if channel is not None else None

    def last_on(self, channel: str) -> Command | None:
        """The last command queued on ``channel`` (``"motors"``) in this run, None before
        any: what a leaf that leaves Safe or Full stops first (``mode: passive``)."""
        return self._last.get(channel)

    def written(self, command: Command) -> None:
        """The runtime wrote ``command`` (drained, and the mode guard let it through): the
        robot obeys it now, until the next one on its channel."""
        channel = command.spec.channel
        if channel is not None:
            self._standing[channel] = command
        elif command.spec is _SONG:  # the robot holds it until it is switched off
            self._songs[command.args[0]] = oi.song_seconds(command)

    def song_seconds(self, slot: int) -> float | None:
        """How long the song this run last wrote to ``slot`` (Song 140) plays, in seconds;
        None when it wrote none there (the slot may hold an earlier program's song, or
        none: the robot keeps its songs until it is switched off)."""
        return self._songs.get(slot)

    def robot_stopped(self, channels: Iterable[str]) -> None:
        """The robot stopped these channels by itself (a fall to Passive stops the wheels and
        the motors): their last commands no longer stand. What the tree asked for
        (:meth:`last_on`) is unchanged."""
        for channel in channels:
            self._standing.pop(channel, None)

    def pending(self) -> list[Command]:
        return list(self._queue.values())

    def __len__(self) -> int:
        return len(self._queue)

    def __iter__(self) -> Iterator[Command]:
        return iter(list(self._queue.values()))

    def clear(self) -> None:
        """Nothing queued, asked for or standing: the tree was stopped (its commands no
        longer stand: nothing sends them again)."""
        self._queue.clear()
        self._ender = _NOBODY
        self._senders.clear()
        self._last.clear()
        self._standing.clear()


class BaseHandle:
    """The part every :class:`RobotHandle` holds alike: the robot's profile and the outbox the
    behaviours queue into. The runtime's runner and the tests' stub add the snapshot, each
    from its own frames."""

    def __init__(self, profile: RobotProfile) -> None:
        self._profile = profile
        self._outbox = Outbox()

    @property
    def outbox(self) -> Outbox:
        return self._outbox

    @property
    def profile(self) -> RobotProfile:
        return self._profile


class RobotHandle(Protocol):
    """What ``tree.setup(robot=handle)`` hands to every behaviour."""

    @property
    def snapshot(self) -> Snapshot: ...

    @property
    def outbox(self) -> Outbox: ...

    @property
    def profile(self) -> RobotProfile: ...
