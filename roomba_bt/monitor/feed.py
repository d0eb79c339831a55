"""The monitor's record of a run: each tick's statuses, snapshot and counters, in a bounded
ring the tick thread appends to and the web server reads from.

The tick thread's part is :meth:`RunFeed.observe`, called once per tick after the tick and its
flush. It reads every node's status into a list and compares it with the last one (a C-level
list compare of enum identities); only when something flipped does it build the new status
string and the failure reasons. Then one append under a lock held for that append alone. It
never waits for a page: the server thread copies what it needs under the same lock and
formats it on its own time, at most ~20 times a second per page. A page that stalls misses
updates (it is sent the newest state when it catches up); the tick never waits.

Memory is bounded: the ring keeps the last ``history`` ticks (default 20 000, 5 min at
66.7 Hz); a tick whose statuses did not change shares the previous tick's status string and
reasons, so the ring holds references, not copies. The event log keeps the last 2 000 events.

Statuses are one character per node, in the order ``roomba-bt show`` draws the tree::

    "SRIF"  ->  node 0 SUCCESS, node 1 RUNNING, node 2 INVALID, node 3 FAILURE
"""

from __future__ import annotations

import logging
import operator
import threading
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.declare import SNAPSHOT_KEY, Condition
from roomba_bt.behaviours.language import WORDS
from roomba_bt.behaviours.reasons import failure_reason
from roomba_bt.robot.interface import SLOT_SECONDS, Snapshot

if TYPE_CHECKING:
    from roomba_bt.runtime.loop import MissionRunner

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

    def as_json(self) -> dict[str, Any]:
        return {
            "i": self.index,
            "name": self.name,
            "kind": self.kind,
            "depth": self.depth,
            "parent": self.parent,
            "children": list(self.children),
            "condition": self.condition,
        }


def _kind(node: py_trees.behaviour.Behaviour) -> str:
    """The symbol ``py_trees.display`` draws before the node's name."""
    if isinstance(node, py_trees.composites.Parallel):
        return "parallel"
    if isinstance(node, py_trees.decorators.Decorator):
        return "decorator"
    if isinstance(node, py_trees.composites.Sequence):
        return "sequence_with_memory" if node.memory else "sequence_without_memory"
    if isinstance(node, py_trees.composites.Selector):
        return "selector_with_memory" if node.memory else "selector_without_memory"
    return "behaviour"


def describe_tree(
    root: py_trees.behaviour.Behaviour,
) -> tuple[list[py_trees.behaviour.Behaviour], list[NodeInfo]]:
    """The nodes in ``show``'s order (depth first, parents before children) and their info."""
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
            kind=_kind(node),
            depth=depths[i],
            parent=parents[i],
            children=tuple(children[i]),
            condition=isinstance(node, Condition),
        )
        for i, node in enumerate(nodes)
    ]
    return nodes, infos


class TickRecord(NamedTuple):
    """One tick as the monitor keeps it (fields shared with the previous tick when unchanged)."""

    seq: int  # position in the feed, counting every record ever appended
    tick: int
    time: float
    statuses: str
    changed: tuple[int, ...]
    reasons: Mapping[int, str]  # failed node -> why
    snapshot: Snapshot | None
    truth: tuple[float, float, float] | None  # the simulator's true pose (mm, mm, rad)
    sent: int  # commands written so far
    refused: int  # commands refused by the mode guard so far
    blackboard: Mapping[str, Any]
    tree: int  # tree generation (a reload starts a new one)
    ticked: bool  # False while paused: the robot is watched, the tree is frozen


class Event(NamedTuple):
    seq: int
    time: float
    kind: str  # mode, refused, warning, status, control, breakpoint, force, reload, error
    text: str


class RunFeed:
    """Everything the page shows, appended by the tick thread, read by the server thread."""

    def __init__(
        self,
        *,
        history: int | None = 20_000,
        source: str = "simulator",
        truth: Callable[[], tuple[float, float, float]] | None = None,
        world: Mapping[str, Any] | None = None,
        mission_name: str = "",
    ) -> None:
        self.lock = threading.Lock()
        self.records: deque[TickRecord] = deque(maxlen=history)
        self.events: deque[Event] = deque(maxlen=2000)
        self.source = source  # simulator, robot or record
        self.truth = truth
        self.world = world
        self.mission_name = mission_name
        self.trees: dict[int, list[NodeInfo]] = {}
        self.generation = -1
        self.finished: str | None = None  # the run's outcome once it ended
        self.truth_start: tuple[float, float, float] | None = None  # where odometry's 0 is
        self._seq = 0
        self._event_seq = 0
        self._nodes: list[py_trees.behaviour.Behaviour] = []
        self._last: list[Status] = []
        self._statuses = ""
        self._reasons: Mapping[int, str] = {}
        self._blackboard: Mapping[str, Any] = {}
        self._mode: object = None
        self._refused_seen = 0
        self._unnamed: frozenset[int] = frozenset()

    # ---------------------------------------------------------------- tree
    @property
    def nodes(self) -> list[py_trees.behaviour.Behaviour]:
        return self._nodes

    @property
    def infos(self) -> list[NodeInfo]:
        return self.trees.get(self.generation, [])

    def set_tree(self, root: py_trees.behaviour.Behaviour) -> int:
        """A (new) tree to watch; returns its generation."""
        nodes, infos = describe_tree(root)
        with self.lock:
            self.generation += 1
            self.trees[self.generation] = infos
            self._nodes = nodes
            self._last = [node.status for node in nodes]
            self._statuses = "".join(STATUS_CODE[s] for s in self._last)
            self._reasons = {}
            self._unnamed = frozenset(i.index for i in infos if i.name in UNNAMED)
        return self.generation

    # ---------------------------------------------------------------- tick thread
    def observe(self, runner: MissionRunner, ticked: bool = True) -> tuple[int, ...]:
        """Record this tick; returns the indices of the nodes whose status flipped."""
        statuses = list(map(_STATUS, self._nodes))
        changed: tuple[int, ...] = ()
        if statuses != self._last:
            changed = self._flipped(statuses, runner)
        snapshot = runner.snapshot if runner.has_snapshot else None
        summary = runner.summary
        if snapshot is not None and snapshot.mode is not self._mode:
            if self._mode is not None:
                self.event("mode", f"OI mode {snapshot.mode.label}", snapshot.time)
            self._mode = snapshot.mode
        if summary.refused_commands != self._refused_seen:
            self._refused(runner, snapshot)
        storage = py_trees.blackboard.Blackboard.storage
        if len(storage) > 1 or SNAPSHOT_KEY not in storage:
            board = {k: v for k, v in storage.items() if k != SNAPSHOT_KEY}
            if board != self._blackboard:
                self._blackboard = board
        truth = self.truth() if self.truth is not None else None
        if truth is not None and self.truth_start is None:
            self.truth_start = truth
        tick = snapshot.tick if snapshot is not None else 0
        record = TickRecord(
            self._seq,
            tick,
            tick * SLOT_SECONDS,
            self._statuses,
            changed,
            self._reasons,
            snapshot,
            truth,
            summary.commands_written,
            summary.refused_commands,
            self._blackboard,
            self.generation,
            ticked,
        )
        with self.lock:
            self.records.append(record)
            self._seq += 1
        return changed

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
                reasons[i] = failure_reason(node) if node.children else node.feedback_message
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

    # ---------------------------------------------------------------- any thread
    def event(self, kind: str, text: str, time: float | None = None) -> None:
        """Append to the event log (mission time; the newest tick's when ``time`` is None)."""
        with self.lock:
            if time is None:
                time = self.records[-1].time if self.records else 0.0
            self.events.append(Event(self._event_seq, time, kind, text))
            self._event_seq += 1

    def since(self, seq: int) -> tuple[list[TickRecord], list[Event]]:
        """Records with ``seq`` or later (all that the ring still holds) and the events."""
        with self.lock:
            records = self.records
            if not records:
                return [], list(self.events)
            first = records[0].seq
            start = max(seq - first, 0)
            return [records[i] for i in range(start, len(records))], list(self.events)

    def latest(self) -> TickRecord | None:
        with self.lock:
            return self.records[-1] if self.records else None

    def window(self) -> tuple[TickRecord | None, TickRecord | None]:
        """The oldest and newest records the ring holds."""
        with self.lock:
            if not self.records:
                return None, None
            return self.records[0], self.records[-1]

    def at(self, tick: int) -> tuple[TickRecord | None, list[TickRecord]]:
        """The last record at or before ``tick`` (or the oldest, when ``tick`` is before the
        ring) and, for rates, ``[the record a second before it, the one just before it]``."""
        with self.lock:
            records = self.records
            if not records:
                return None, []
            lo, hi = 0, len(records) - 1
            if records[lo].tick > tick:
                return records[lo], []
            while lo < hi:  # last index with records[i].tick <= tick
                mid = (lo + hi + 1) // 2
                if records[mid].tick <= tick:
                    lo = mid
                else:
                    hi = mid - 1
            back = max(lo - round(1.0 / SLOT_SECONDS), 0)
            return records[lo], [records[back], records[max(lo - 1, 0)]]

    def path(self, upto_seq: int, limit: int = 1500) -> list[TickRecord]:
        """Records up to ``upto_seq``, thinned to at most ``limit``, for drawing the path."""
        with self.lock:
            records = self.records
            if not records:
                return []
            end = min(upto_seq - records[0].seq + 1, len(records))
            stride = max(1, end // limit)
            return [records[i] for i in range(0, end, stride)]


class EventLogHandler(logging.Handler):
    """Warnings of the roomba_bt loggers into the feed's event log."""

    def __init__(self, feed: RunFeed) -> None:
        super().__init__(logging.WARNING)
        self.feed = feed

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.feed.event("warning", record.getMessage())
        except Exception:  # a log line must never break the run
            self.handleError(record)
