"""The monitor's record of a run: each tick's statuses, sensor frame and counters, in a
bounded ring the tick thread appends to and the web server reads from.

The tick thread's part is :meth:`RunFeed.observe`, called once per tick after the tick and its
flush. It reads every node's status into a list and compares it with the last one (a C-level
list compare of enum identities); only when something flipped does it build the new status
string and the failure reasons. Then it stores one record in a preallocated ring and bumps a
counter: no lock, nothing formatted, no JSON. It never waits for a page or for the server: the
server thread reads the ring by sequence number (a slot overwritten meanwhile is seen by its
sequence number and skipped) and formats on its own time, at most ~20 times a second per
page, right after a tick (see the server's module). A page that stalls misses
updates (it is sent the newest state when it catches up); the tick never waits.

Why no lock: a lock the tick thread shares with the server is a convoy. When the server holds
it, the tick thread blocks, gives up the GIL, and gets it back only when the server thread
blocks or is made to switch (CPython's 5 ms switch interval): reaction latency p99 was
2.1 ms with the monitor against 0.55 ms without (the first version, on a quiet machine).

Memory is bounded: the ring keeps the last ``history`` ticks (default 20 000, 5 min at
66.7 Hz); a tick whose statuses did not change shares the previous tick's status string and
reasons, so the ring holds references, not copies. The event log keeps the last 2 000 events.

Statuses are one character per node, in the order ``roomba-bt show`` draws the tree::

    "SRIF"  ->  node 0 SUCCESS, node 1 RUNNING, node 2 INVALID, node 3 FAILURE
"""

from __future__ import annotations

import logging
import operator
import secrets
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import Enum
from typing import TYPE_CHECKING, Any, NamedTuple
from uuid import UUID

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.base import Condition
from roomba_bt.behaviours.blackboard import RunBoard, run_board
from roomba_bt.behaviours.language import WORDS
from roomba_bt.behaviours.reasons import failure_reason
from roomba_bt.monitor.board_text import board_text
from roomba_bt.oi.frames import (
    REQUESTED_DRIVE_PACKETS,
    REQUESTED_WHEELS_PACKETS,
    SLOT_SECONDS,
    FrameLayout,
    SensorFrame,
)
from roomba_bt.oi.modes import OIMode
from roomba_bt.printable import ANY_CONTROL, escaped
from roomba_bt.robot.interface import Odometry, Snapshot
from roomba_bt.runtime.display import node_kind
from roomba_bt.runtime.summary import LOOP_SAID, loop_said

if TYPE_CHECKING:
    from roomba_bt.runtime.loop import MissionRunner
    from roomba_bt.runtime.summary import RunSummary

STATUS_CODE: dict[Status, str] = {
    Status.SUCCESS: "S",
    Status.FAILURE: "F",
    Status.RUNNING: "R",
    Status.INVALID: "I",
}
#: A node still called by its kind's word (``sequence``, ``retry``) was not named by the
#: mission's author: its flips are not worth an event.
UNNAMED = frozenset(WORDS) | {"root"}


_STATUS = operator.attrgetter("status")
_monotonic = time.monotonic
_perf_counter = time.perf_counter
#: blackboard values that cannot change in place: kept as they are
_PLAIN = frozenset({str, int, float, bool, type(None), bytes, complex})
#: a blackboard value whose text takes longer is shown as it is now, marked so (see
#: :meth:`BoardVersions._text_at_tick`)
TEXT_BUDGET_S = 0.0002
#: ... on this many ticks in a row: one text cut short by the machine (the thread
#: descheduled, a garbage collection), not by the value, kept the cover's map as its object
#: for the rest of a run on a busy computer, every rewound tick showing the map of now
SLOW_TEXT_TICKS = 3


#: a board's entry naming its keys kept as their text at the tick (a tuple of them): plain
#: strings and a tuple, which the cyclic collector stops tracking, as it does a record (a str
#: subclass marking them would be tracked: one more tracked object a tick)
TEXT_KEYS = "\x00kept as text"
#: while paused, a live run's ring keeps a frame this many stream ticks (a second) after the
#: last one it kept: the stream goes on in a pause, and at 66.7 frames a second a 5-minute
#: pause filled the 20 000 ticks and pushed the whole run out of the page (24 m driven,
#: 0.5 m of path shown)
PAUSED_ROW_TICKS = round(1.0 / SLOT_SECONDS)
#: the packets of the wheels' requested speeds (Requested Velocity, Requested Right and Left
#: Velocity), where the stream carries them: a paused frame still reporting one is kept
_REQUESTED_SPEEDS = (*REQUESTED_DRIVE_PACKETS[:1], *REQUESTED_WHEELS_PACKETS)


def _fixed(value: object) -> bool:
    """An enum member, or a tuple of plain values (``/roomba/docking/run``): it cannot change."""
    if isinstance(value, Enum):
        return True
    return isinstance(value, tuple) and all(type(item) in _PLAIN for item in value)


_TUPLE_NEW: Any = tuple.__new__


@dataclass(frozen=True)
class NodeInfo:
    """One node as the page draws it: ``show``'s line, its place, and what may be done to it."""

    index: int
    name: str
    kind: str  # py_trees' display symbol key: sequence_with_memory, decorator, behaviour, ...
    depth: int
    parent: int | None
    children: tuple[int, ...]
    condition: bool  # may be forced to SUCCESS/FAILURE
    #: the name the page draws, ``show``'s for a node no ``name:`` renamed (``retry(times=40)``;
    #: :func:`~roomba_bt.runtime.display.live_names`); :attr:`name`, the node's own, is
    #: what the events, the API and a breakpoint's words say
    label: str = ""

    def as_json(self) -> dict[str, Any]:
        return {
            "i": self.index,
            "name": self.name,
            "label": self.label or self.name,
            "kind": self.kind,
            "depth": self.depth,
            "parent": self.parent,
            "children": list(self.children),
            "condition": self.condition,
        }


def describe_tree(
    root: py_trees.behaviour.Behaviour, names: Mapping[UUID, str] | None = None
) -> tuple[list[py_trees.behaviour.Behaviour], list[NodeInfo]]:
    """The nodes in ``show``'s order (depth first, parents before children) and their info;
    ``names``: each node's name as the page draws it, by its id (its labels)."""
    nodes: list[py_trees.behaviour.Behaviour] = []
    parents: list[int | None] = []
    depths: list[int] = []
    stack: list[tuple[py_trees.behaviour.Behaviour, int | None, int]] = [(root, None, 0)]
    while stack:
        node, parent, depth = stack.pop()
        nodes.append(node)
        parents.append(parent)
        depths.append(depth)
        here = len(nodes) - 1
        stack.extend((child, here, depth + 1) for child in reversed(node.children))
    children: dict[int, list[int]] = {i: [] for i in range(len(nodes))}
    for i, parent in enumerate(parents):
        if parent is not None:
            children[parent].append(i)
    infos = [
        NodeInfo(
            index=i,
            name=node.name.replace("\n", " "),
            kind=node_kind(node),
            depth=depths[i],
            parent=parents[i],
            children=tuple(children[i]),
            condition=isinstance(node, Condition),
            label=(names or {}).get(node.id, node.name).replace("\n", " "),
        )
        for i, node in enumerate(nodes)
    ]
    return nodes, infos


class TickRecord(NamedTuple):
    """One tick as the monitor keeps it (fields shared with the previous tick when unchanged).

    Only numbers, strings and tuples of them (and dicts of those: the reasons): nothing the
    cyclic garbage collector must follow, so it stops tracking a record at its first
    collection. A record holding the tick's :class:`Snapshot` (frame, layout, mode, profile:
    objects it tracks) kept four tracked objects a tick alive; 20 000 ticks of them made its
    collections frequent and long, in whichever thread allocated next, the tick thread most
    likely (one bench run: reaction latency p99 0.93 ms against 0.41 ms without it). The
    snapshot is rebuilt on the server's side: :meth:`RunFeed.snapshot`.
    """

    seq: int  # position in the feed, counting every record ever appended
    tick: int
    time: float
    statuses: str
    changed: tuple[int, ...]
    reasons: Mapping[int, str]  # failed node -> why
    frame: tuple[int, ...] | None  # the sensor frame's raw values (None before the first)
    layout: int  # the frame's layout: RunFeed.layouts[layout]
    mode: int  # the OI mode (OIMode's value)
    odometry: Odometry | None
    frames_lost: int
    truth: tuple[float, float, float] | None  # the simulator's true pose (mm, mm, rad)
    sent: int  # commands written so far
    refused: int  # commands refused by the mode guard so far
    board: int  # the blackboard's version: RunFeed.boards[board]
    tree: int  # tree generation (a reload starts a new one)
    ticked: bool  # False while paused: the robot is watched, the tree is frozen
    #: the bytes of the motors' last command (Motors (138) or PWM Motors (144): what the
    #: run last wrote to the brushes and vacuum, the tree or a halt's motors off, and the
    #: robot still obeys), None before any; the command's own bytes object, so a tick that
    #: changed nothing shares it
    motors: bytes | None = None


class Event(NamedTuple):
    seq: int
    time: float
    kind: str  # mode, refused, warning, status, control, breakpoint, force, reload, error
    text: str
    #: the stream's tick it came at (the newest record's): the page's timeline is in ticks,
    #: and mission time stands still during a pause (its events all had one time)
    tick: int = 0


class Ending(NamedTuple):
    """What the run's end left the robot in, which no tick shows: the safe stop comes after
    the last tick, with the stream paused, so no frame after it is read. The page's robot
    panel showed that last tick (Safe, the wheels at their last speed, the brushes on) under
    "the run ended"; it shows this in its place once the run has ended."""

    #: the summary's ``final mode`` (``Passive``, or ``unknown: last seen in Safe, the stop
    #: was not delivered``)
    mode: str
    #: the stop is known to have arrived (:attr:`RunSummary.left_stopped`): drive 0, motors
    #: off; False: what the robot does is not known, and the panel says so
    stopped: bool
    #: the summary's ``safe stop`` (``sent drive, motors, pause_resume_stream, start``)
    safe_stop: str
    #: how the run ended (``interrupted: stopped by the operator``)
    outcome: str
    #: a stop not known to have arrived, as the final mode says it (``the stop was not
    #: delivered``, ``the stop unconfirmed``: :meth:`RunSummary.stop_said`)
    stop_said: str = "the stop was not delivered"
    #: the connection's words of a stop not known delivered, its advice left out (what the
    #: robot was last seen doing, why the stop did not reach it), or ""
    robot: str = ""
    #: what to do about the robot that stop left (the summary's ``stop_advice``), or ""
    advice: str = ""

    @classmethod
    def of(cls, summary: RunSummary) -> Ending:
        reason = f": {summary.reason}" if summary.reason else ""
        advice = summary.stop_advice
        return cls(
            mode=summary.final_mode_text(),
            stopped=summary.left_stopped,
            safe_stop=summary.safe_stop,
            outcome=f"{summary.outcome.value}{reason}",
            stop_said=summary.stop_said(),
            robot=summary.stop_report.removesuffix(f": {advice}" if advice else ""),
            advice=advice,
        )

    def banner(self) -> str:
        """What the page's banner says after "the run ended: ": how it ended, then the final
        mode and the safe stop as the summary says them; a stop the connection said not
        delivered in three lines, each said once: what happened, where the robot was left,
        what to do. That banner was the summary's words run together: the final mode (``last
        seen in Safe, the stop was not delivered``), the safe stop's headline (``NOT
        DELIVERED``) and its report (``last seen in Safe ...; the stop was not delivered:
        ...``) over five lines of a laptop's window, the advice at their end."""
        if self.stopped or not self.robot:
            return f"{self.outcome} (final mode {self.mode}; safe stop {self.safe_stop})"
        lines = [self.outcome, f"the robot: {self.robot}"]
        return "\n".join([*lines, self.advice] if self.advice else lines)

    def as_json(self) -> dict[str, Any]:
        return self._asdict()


class Ring:
    """The last ``size`` records by sequence number (all of them when ``size`` is None).

    One writer (the tick thread) and any number of readers, without a lock: the writer stores
    the record in its slot, then publishes ``count``; a reader asks for sequence numbers below
    ``count`` and gets None for a slot the writer has reused since (its record's ``seq``
    differs). Each store and load is one bytecode under the GIL, so nothing is seen torn.
    """

    def __init__(self, size: int | None) -> None:
        if size is not None and size < 1:
            raise ValueError(f"history {size}: allowed 1 or more ticks (or None: all)")
        self.size = size
        self._slots: list[TickRecord | None] = [None] * size if size is not None else []
        self.count = 0  # records ever appended
        #: when the newest record was appended (time.monotonic, the server loop's clock): the
        #: end of the newest tick, from which the server's pump knows when the next ones end
        self.ended = 0.0

    def append(self, record: TickRecord) -> None:
        """Tick thread only; ``record.seq`` must be ``count``."""
        if self.size is None:
            self._slots.append(record)
        else:
            self._slots[record.seq % self.size] = record
        self.count = record.seq + 1
        self.ended = _monotonic()

    @property
    def first(self) -> int:
        """The oldest sequence number still held (a reader may still find it overwritten)."""
        return 0 if self.size is None else max(self.count - self.size, 0)

    def get(self, seq: int) -> TickRecord | None:
        if not 0 <= seq < self.count:
            return None
        record = self._slots[seq if self.size is None else seq % self.size]
        return record if record is not None and record.seq == seq else None

    def since(self, seq: int) -> list[TickRecord]:
        """Records ``seq`` .. newest that are still held, oldest first."""
        count = self.count
        start = max(seq, self.first)
        if self.size is None:
            return self._slots[start:count]  # type: ignore[return-value]
        out = [self.get(s) for s in range(start, count)]
        return [r for r in out if r is not None]

    def newest(self) -> TickRecord | None:
        return self.get(self.count - 1)

    def oldest(self) -> TickRecord | None:
        """The oldest record still held (one the writer is about to reuse is skipped)."""
        count, first = self.count, self.first
        for seq in range(first, min(first + 8, count)):
            record = self.get(seq)
            if record is not None:
                return record
        return self.newest()


class PausedMotion:
    """Whether each frame of a pause shows the robot moving (its encoders moved since the
    pause's last frame, or it reports a wheel speed requested) or is the first still one
    after that: news a thinned pause keeps (:meth:`RunFeed.observe`). The frames a pause
    comes in carry the speed from before the stop; the page showed PAUSED, Passive and the
    wheels turning for a second, until the next frame a second kept."""

    def __init__(self) -> None:
        self._counts: tuple[int | None, int | None] | None = None
        self._moving = True

    def before_the_pause(self, snapshot: Snapshot | None) -> None:
        """A ticked frame (the last before a pause, when one comes): the pause's first frame
        is compared with its counts. Compared with nothing, it was judged still, and in a
        run in Passive (a built-in cycle's: no requested speed, no mode change at the pause)
        the first still frame after it was left out."""
        if snapshot is not None:
            odometry = snapshot.odometry
            self._counts = (odometry.left_counts, odometry.right_counts)
        self._moving = True

    def seen(self, snapshot: Snapshot) -> bool:
        odometry = snapshot.odometry
        counts = (odometry.left_counts, odometry.right_counts)
        before, self._counts = self._counts, counts
        frame = snapshot.frame
        moving = (before is not None and counts != before) or any(
            frame.get(packet) for packet in _REQUESTED_SPEEDS
        )
        was, self._moving = self._moving, moving
        return moving or was


class BoardVersions:
    """The run's blackboard as the page shows it at each tick: a new version, by number,
    each time a key changed (a record names its tick's: :attr:`TickRecord.board`), with the
    keys whose text is too slow to take every tick kept as their object. Versions that no
    record in the ring refers to any more are dropped from time to time. The tick thread
    writes (:meth:`watch`, every tick); the server's thread reads :attr:`versions`."""

    def __init__(self, oldest: Callable[[], TickRecord | None]) -> None:
        """``oldest``: the oldest record the feed's ring holds now, read when old versions
        are dropped."""
        self._oldest = oldest
        self._current: Mapping[str, Any] = {}
        #: the blackboard's contents by version, a new version when they changed; versions no
        #: record in the ring refers to any more are dropped from time to time
        self.versions: dict[int, Mapping[str, Any]] = {0: self._current}
        self.version = 0  # the newest
        self._limit = 64
        #: keys whose value's text was too slow to take every tick: kept as the object
        self.live_keys: set[str] = set()
        #: keys whose text went over its budget on the last ticks: on how many in a row
        self._slow_texts: dict[str, int] = {}

    def watch(self, run: RunBoard) -> int:
        """A new version of the blackboard when a key changed (the snapshot's mirror and the
        keys' declared types are not keys): ``run``'s keys, by the names a user knows
        (:meth:`RunBoard.shown <roomba_bt.behaviours.blackboard.RunBoard.shown>`).

        A value that may change in place (the cover's map: one object, changed every tick)
        is kept as its text at this tick (its key listed under :data:`TEXT_KEYS`): kept as
        the object, a rewound tick showed its text of the moment the page asked (the whole
        run's map at tick 100), and no new version was made when it changed. Numbers,
        strings, enums and tuples of them are kept as they are (they cannot change). Returns
        the newest version, the one this tick's record names."""
        storage = py_trees.blackboard.Blackboard.storage
        if len(storage) > 1 or run.snapshot_key not in storage:
            board = run.shown()
            texts: tuple[str, ...] = ()
            for key, value in board.items():
                if type(value) not in _PLAIN and not _fixed(value):
                    text = self._text_at_tick(key, value)
                    if text is not None:
                        board[key] = text
                        texts += (key,)
            if texts:
                board[TEXT_KEYS] = texts
            if board != self._current:
                self._new(board)
        return self.version

    def _text_at_tick(self, key: str, value: Any) -> str | None:
        """``value``'s text now, or None (kept as the object) for a key whose text took over
        :data:`TEXT_BUDGET_S` on :data:`SLOW_TEXT_TICKS` ticks in a row (the page marks it as
        current, not at the tick shown): a plugin's object with a slow ``repr`` does not
        slow every tick, and a quick one the machine held up once is still kept as text."""
        if key in self.live_keys:
            return None
        began = _perf_counter()
        text = board_text(value)
        if _perf_counter() - began > TEXT_BUDGET_S:
            self._slow_text(key)
        elif self._slow_texts:  # a quick one again: the row is broken
            self._slow_texts.pop(key, None)
        return text

    def _slow_text(self, key: str) -> None:
        """``key``'s text went over its budget this tick: kept as the object from now on if
        it did on :data:`SLOW_TEXT_TICKS` ticks in a row."""
        slow = self._slow_texts.get(key, 0) + 1
        if slow < SLOW_TEXT_TICKS:
            self._slow_texts[key] = slow
        else:
            self._slow_texts.pop(key, None)
            self.live_keys.add(key)

    def _new(self, board: Mapping[str, Any]) -> None:
        self._current = board
        self.version += 1
        boards = self.versions
        boards[self.version] = board
        if len(boards) > self._limit:  # drop what no record in the ring refers to
            oldest = self._oldest()
            keep = oldest.board if oldest is not None else self.version
            for version in [v for v in boards if v < keep]:
                del boards[version]
            self._limit = max(64, 2 * len(boards))


class RunFeed:
    """Everything the page shows, appended by the tick thread, read by the server thread.
    ``packed_from``: None, the last ``history`` ticks are kept (a live run's; a pause's
    frames at one a second: :meth:`_thins`); a mission time, every tick from then on, packed
    (a recorded run's, from 0 or ``monitor RECORD --from``; its events are every tick's)."""

    # long on purpose: every attribute the feed holds, each said where it is set
    def __init__(
        self,
        *,
        history: int | None = 20_000,
        source: str = "simulator",
        truth: Callable[[], tuple[float, float, float]] | None = None,
        world: Mapping[str, Any] | None = None,
        mission_name: str = "",
        packed_from: float | None = None,
        robot: str = "",
        started: datetime | None = None,
        label: str = "",
        thin_pauses: bool = True,
    ) -> None:
        #: the run's identity, sent in the page's first message and checked with each
        #: control: a page left open after its run was killed reconnected to the next run
        #: served on that port (another robot, perhaps) and its controls drove that one. A new
        #: random id each feed; ``robot``: its port, or ``simulator WORLD``; ``started``, UTC
        #: (None for a record made before its header held it: unknown, not the monitor's);
        #: ``label``: ``run --label`` (``robot 3``), which the page's title and header lead with
        self.run_id = secrets.token_urlsafe(12)
        self.robot, self.label = robot, label
        self.started = started if started or source == "record" else datetime.now(UTC)
        #: the frames' layouts (one per stream: a record names its layout by index)
        self.layouts: list[FrameLayout] = []
        if packed_from is not None:  # every tick from then, packed (a record's: history.py)
            from roomba_bt.monitor.history import PackedRing

            self.ring: Ring = PackedRing(self.layouts, packed_from)
        else:
            self.ring = Ring(history)
        self.events: deque[Event] = deque(maxlen=2000)
        #: a live run's ring thins its paused frames (:meth:`observe`); a record's keeps all
        #: (its pauses are in its file already), as does ``thin_pauses=False`` (a test that
        #: compares a live run's every frame with its replay's)
        self.thin_pauses = thin_pauses and source != "record"
        #: the stream's tick of the last paused frame kept (None: not paused)
        self._paused_kept: int | None = None
        self._motion = PausedMotion()  # whether a paused frame shows the robot moving
        self.source = source  # simulator, robot or record
        self.truth, self.world = truth, world
        self.mission_name = mission_name
        self.trees: dict[int, list[NodeInfo]] = {}
        self.generation = -1
        self.finished: str | None = None  # the run's outcome once it ended
        self.ending: Ending | None = None  # what its safe stop left (:meth:`end`)
        #: why the robot panel's last tick is all there is of the robot at the end: a
        #: record without its run's end (a killed run's), which the panel's title says, as
        #: the banner does; None: the run's end is known, or its panel says why not itself
        self.no_end: str | None = None
        self.truth_start: tuple[float, float, float] | None = None  # where odometry's 0 is
        #: writers of the event log (the tick thread, a logging thread, the file watcher)
        #: take it so that the log's order is its sequence numbers'; readers never do
        self._event_lock = threading.Lock()
        self._event_seq = 0
        self._nodes: list[py_trees.behaviour.Behaviour] = []
        self._last: list[Status] = []
        self._statuses = ""
        self._reasons: Mapping[int, str] = {}
        #: the blackboard's versions, which each record names (its ring read when old
        #: versions are dropped: a test gives the feed a smaller ring after it is made)
        self._boards = BoardVersions(lambda: self.ring.oldest())
        self._layout: FrameLayout | None = None
        self._mode: object = None
        self._refused_seen = 0
        self._guard_seen, self._guard_counts = 0, (0, 0, 0, 0)  # tick_guard_said's
        self._unnamed: frozenset[int] = frozenset()

    @property
    def boards(self) -> dict[int, Mapping[str, Any]]:
        """The blackboard's contents by version (:attr:`BoardVersions.versions`)."""
        return self._boards.versions

    @property
    def live_keys(self) -> set[str]:
        """The keys kept as their object (:attr:`BoardVersions.live_keys`)."""
        return self._boards.live_keys

    # ---------------------------------------------------------------- tree
    @property
    def nodes(self) -> list[py_trees.behaviour.Behaviour]:
        return self._nodes

    @property
    def infos(self) -> list[NodeInfo]:
        return self.trees.get(self.generation, [])

    def set_tree(
        self, root: py_trees.behaviour.Behaviour, names: Mapping[UUID, str] | None = None
    ) -> int:
        """A (new) tree to watch (before the run, or from the tick thread); its generation.
        ``names``: its nodes' names as the page draws them
        (:func:`~roomba_bt.runtime.display.live_names`)."""
        nodes, infos = describe_tree(root, names)
        self.trees[self.generation + 1] = infos
        self._nodes = nodes
        self._last = [node.status for node in nodes]
        self._statuses = "".join(STATUS_CODE[s] for s in self._last)
        self._reasons = {}
        self._unnamed = frozenset(i.index for i in infos if i.name in UNNAMED)
        self.generation += 1  # published last: a reader finds the tree's infos in place
        return self.generation

    # ---------------------------------------------------------------- tick thread
    # long on purpose: once per tick, on the tick thread: one pass with no call it need not
    # make (each check a compare; the record built in place)
    def observe(self, runner: MissionRunner, ticked: bool = True) -> tuple[int, ...]:
        """Record this tick; returns the indices of the nodes whose status flipped."""
        statuses = list(map(_STATUS, self._nodes))
        changed: tuple[int, ...] = ()
        if statuses != self._last:
            changed = self._flipped(statuses, runner)
        snapshot = runner.snapshot if runner.has_snapshot else None
        summary = runner.summary
        mode_changed = False
        if snapshot is not None and snapshot.mode is not self._mode:
            mode_changed = True
            if self._mode is not None:
                self.event("mode", f"OI mode {snapshot.mode.label}", snapshot.time)
            self._mode = snapshot.mode
        if summary.refused_commands != self._refused_seen:
            self._refused(runner, snapshot)
        if summary.tick_halts + summary.tick_stills + summary.tick_cycles + summary.loop_slow != (
            self._guard_seen
        ):
            self._tick_guard_saw(summary, snapshot)
        board = self._boards.watch(runner.blackboard or run_board())
        if not ticked and self.thin_pauses and snapshot is not None:
            if self._thins(snapshot.tick, changed or mode_changed or self._motion.seen(snapshot)):
                return changed
        else:
            self._paused_kept = None
            self._motion.before_the_pause(snapshot)
        truth = self.truth() if self.truth is not None else None
        if truth is not None and self.truth_start is None:
            self.truth_start = truth
        ring = self.ring
        # what the robot obeys: the last Motors written, the tree's or a batch's (a halt's
        # motors off), while the channel stands (a fall to Passive stopped them)
        motors = runner.connection.writer.last_motors if "motors" in runner.last_sent else None
        motor_bytes = motors.data if motors is not None else None
        if snapshot is not None:
            frame = snapshot.frame
            if frame.layout is not self._layout:
                self._layout = frame.layout
                self.layouts.append(frame.layout)
            record: TickRecord = _TUPLE_NEW(  # TickRecord(...) without its __new__'s frame
                TickRecord,
                (
                    ring.count,
                    snapshot.tick,
                    snapshot.time,
                    self._statuses,
                    changed,
                    self._reasons,
                    frame.values,
                    len(self.layouts) - 1,
                    int(snapshot.mode),
                    snapshot.odometry,
                    snapshot.frames_lost,
                    truth,
                    runner.count_written(),
                    summary.refused_commands,
                    board,
                    self.generation,
                    ticked,
                    motor_bytes,
                ),
            )
        else:
            record = TickRecord(ring.count, 0, 0.0, self._statuses, changed, self._reasons,
                                None, -1, 0, None, 0, truth, runner.count_written(),
                                summary.refused_commands, board, self.generation,
                                ticked, motor_bytes)  # fmt: skip
        ring.append(record)
        return changed

    def _thins(self, tick: int, news: object) -> bool:
        """Whether this paused frame is left out of the ring: kept are the pause's first
        frame, one a second after it (:data:`PAUSED_ROW_TICKS`) and any that brings news (a
        status flipped, the mode changed). The page's timeline, path and robot panel then
        show a pause at a frame a second, and a long pause no longer uses up the ticks the
        ring holds of the run (a lunch's pause erased the morning from the page)."""
        kept = self._paused_kept
        if kept is not None and not news and tick - kept < PAUSED_ROW_TICKS:
            return True
        self._paused_kept = tick
        return False

    def _flipped(self, statuses: list[Status], runner: MissionRunner) -> tuple[int, ...]:
        last = self._last
        changed = tuple(
            i for i, (a, b) in enumerate(zip(statuses, last, strict=True)) if a is not b
        )
        self._last = statuses
        self._statuses = "".join(STATUS_CODE[s] for s in statuses)
        reasons = dict(self._reasons)
        snapshot = runner.snapshot if runner.has_snapshot else None
        now = snapshot.time if snapshot is not None else 0.0
        for i in changed:
            status = statuses[i]
            node = self._nodes[i]
            if status is Status.FAILURE:
                # a leaf's own message, escaped as failure_reason's text is: one line on the
                # page and in the event log (a plugin's "\\n[ok] ..." faked an event)
                reasons[i] = (
                    failure_reason(node)
                    if node.children
                    else escaped(node.feedback_message, ANY_CONTROL)
                )
            else:
                reasons.pop(i, None)
            if i not in self._unnamed and status is not Status.INVALID:
                why = f": {reasons[i]}" if status is Status.FAILURE and reasons.get(i) else ""
                self.event("status", f"{node.name} -> {status.value}{why}", now)
        self._reasons = reasons
        return changed

    def _refused(self, runner: MissionRunner, snapshot: Snapshot | None) -> None:
        count = runner.summary.refused_commands - self._refused_seen
        self._refused_seen = runner.summary.refused_commands
        last = runner.refusals[-1] if runner.refusals else "by the mode guard"
        more = f" (+{count - 1} more)" if count > 1 else ""
        self.event("refused", f"{last}{more}", snapshot.time if snapshot else 0.0)

    def _tick_guard_saw(self, summary: RunSummary, snapshot: Snapshot | None) -> None:
        """Its events since the feed last looked (:func:`tick_guard_said`), at the tick's time;
        their sum is what ``observe`` compares a tick (one compare where it had three)."""
        time = snapshot.time if snapshot is not None else None
        for text in tick_guard_said(summary, self._guard_counts):
            self.event("note", f"tick guard: {text}", time)
        counts = (summary.tick_halts, summary.tick_stills, summary.tick_cycles, summary.loop_slow)
        self._guard_counts, self._guard_seen = counts, sum(counts)

    # ---------------------------------------------------------------- any thread
    def end(self, finished: str, ending: Ending | None, no_end: str | None = None) -> None:
        """The run is over: ``finished`` is what the page's banner says, ``ending`` what the
        robot was left in (the robot panel's last state; None: not known, a record's view
        that diverged or was cut short), ``no_end`` why a record's view has no end to show
        (:attr:`no_end`). ``ending`` and ``no_end`` are published first: a server that sees
        ``finished`` change sends the robot panel they give."""
        self.ending = ending
        self.no_end = no_end
        self.finished = finished

    def event(
        self, kind: str, text: str, time: float | None = None, tick: int | None = None
    ) -> None:
        """Append to the event log (mission time, to the ms: ``21.69``, not the sum of
        15 ms steps ``21.689999999999998``; the newest tick's when ``time`` or ``tick`` is
        None)."""
        newest = self.ring.newest()
        if tick is None:
            tick = newest.tick if newest is not None else 0
        if time is None:
            time = newest.time if newest is not None else 0.0
        with self._event_lock:
            self.events.append(Event(self._event_seq, round(time, 3), kind, text, tick))
            self._event_seq += 1

    def events_after(self, seq: int) -> list[Event]:
        """The events after sequence number ``seq`` still in the log, oldest first."""
        events = list(self.events)  # one C-level copy: no append can interleave
        start = len(events)
        while start > 0 and events[start - 1].seq > seq:
            start -= 1
        return events[start:]

    def since(self, seq: int) -> tuple[list[TickRecord], list[Event]]:
        """Records with ``seq`` or later (all that the ring still holds) and the events."""
        return self.ring.since(seq), list(self.events)

    def latest(self) -> TickRecord | None:
        return self.ring.newest()

    def snapshot(self, record: TickRecord) -> Snapshot | None:
        """The tick's snapshot as the runtime made it (frame, mode, odometry; not the profile
        or the last fallback, which the page does not show)."""
        if record.frame is None:
            return None
        return Snapshot(
            frame=SensorFrame(self.layouts[record.layout], record.frame),
            tick=record.tick,
            time=record.time,
            mode=OIMode(record.mode),
            odometry=record.odometry or Odometry(),
            frames_lost=record.frames_lost,
        )

    def blackboard(self, record: TickRecord) -> Mapping[str, Any]:
        """The mission's blackboard keys at that tick ({} once its version was dropped)."""
        return self._boards.versions.get(record.board, {})

    def record(self, seq: int) -> TickRecord | None:
        """The record with sequence number ``seq``, if the ring still holds it."""
        return self.ring.get(seq)

    def window(self) -> tuple[TickRecord | None, TickRecord | None]:
        """The oldest and newest records the ring holds."""
        newest = self.ring.newest()
        if newest is None:
            return None, None
        return self.ring.oldest(), newest

    def at(self, tick: int) -> tuple[TickRecord | None, list[TickRecord]]:
        """The last record at or before ``tick`` (or the oldest, when ``tick`` is before the
        ring) and, for rates, ``[the record a second before it, the one just before it]``."""
        oldest, newest = self.window()
        if oldest is None or newest is None:
            return None, []
        if oldest.tick > tick:
            return oldest, []
        ring = self.ring
        lo = self._last_at_or_before(tick, oldest.seq, newest.seq)
        found = ring.get(lo) or newest
        # a second of the stream before it, by tick: a pause keeps a frame a second, so the
        # record 67 back was a minute back in a long pause, or before it, and the page's
        # "commands / refused per s" said the driving's rate for as long as the pause lasted
        second = round(1.0 / SLOT_SECONDS)
        start = max(lo - second, oldest.seq)  # ticks rise by 1 at least: it is past here
        back = ring.get(start) or found
        if back.tick < found.tick - second:  # a gap (a pause's frames thinned): look for it
            back = ring.get(self._last_at_or_before(found.tick - second, start, lo)) or found
        return found, [back, ring.get(max(lo - 1, oldest.seq)) or found]

    def _last_at_or_before(self, tick: int, lo: int, hi: int) -> int:
        """The last sequence number in ``lo..hi`` whose record's tick is at most ``tick``
        (``lo`` when none is)."""
        ring = self.ring
        while lo < hi:
            mid = (lo + hi + 1) // 2
            record = ring.get(mid)
            # None: reused by the writer meanwhile, so it was older still
            if record is None or record.tick <= tick:
                lo = mid
            else:
                hi = mid - 1
        return lo

    def path(self, upto_seq: int, limit: int = 1500) -> list[TickRecord]:
        """Records up to ``upto_seq``, thinned to at most ``limit``, for drawing the path."""
        ring = self.ring
        first = ring.first
        end = min(upto_seq + 1, ring.count)
        stride = max(1, (end - first) // limit)
        out = [ring.get(seq) for seq in range(first, end, stride)]
        return [r for r in out if r is not None]


#: ``log.warning(..., extra=IN_THE_EVENT_LOG)``: a warning the monitor put in its event log
#: itself (its own words, without the logger's prefix), said in the terminal's log too; the
#: :class:`EventLogHandler` leaves it out, or the page's log showed it twice
IN_THE_EVENT_LOG = {"in_the_event_log": True}


def tick_guard_said(summary: RunSummary, seen: tuple[int, int, int, int]) -> list[str]:
    """The tick guard's events since ``seen`` (its halts, still ticks, ticks in a cycle and a
    program's slow loop passes as the feed last counted them): a halt, and a tick past the
    limit in which it sent nothing, with nothing moving or while a built-in cycle could
    drive the robot (the guard ends none), as a halt is (those were a log warning only, and
    only when the gap they left came out a second or more); each with where the last was
    and how many so far; a pass of a program's loop over ``stack.ticks()`` past the limit,
    as the loop's (it was said as a tick's)."""
    said = []
    if summary.tick_halts != seen[0]:
        said.append(
            f"drive 0 while a tick ran over its limit, in {summary.tick_halt_last} "
            f"({summary.tick_halts} so far)"
        )
    if summary.tick_stills != seen[1]:
        said.append(
            f"a tick ran over its limit with nothing moving, in {summary.tick_still_last} "
            f"(nothing to stop; {summary.tick_stills} so far)"
        )
    if summary.tick_cycles != seen[2]:
        said.append(
            f"a tick ran over its limit while a built-in cycle could drive the robot, in "
            f"{summary.tick_cycle_last} (the cycle went on: the guard ends none; "
            f"{summary.tick_cycles} so far)"
        )
    if summary.loop_slow != seen[3]:  # a program's loop over stack.ticks(), not a tick
        said.append(f"{LOOP_SAID} ran over the tick limit: {loop_said(summary)}")
    return said


class EventLogHandler(logging.Handler):
    """Warnings of the roomba_bt loggers into the feed's event log (but those already there:
    :data:`IN_THE_EVENT_LOG`)."""

    def __init__(self, feed: RunFeed) -> None:
        super().__init__(logging.WARNING)
        self.feed = feed

    def emit(self, record: logging.LogRecord) -> None:
        if getattr(record, "in_the_event_log", False):
            return
        try:
            self.feed.event("warning", record.getMessage())
        except Exception:  # a log line must never break the run
            self.handleError(record)
