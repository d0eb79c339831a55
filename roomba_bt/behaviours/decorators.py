"""Decorators that count mission time, and the ``while``/``until`` guard.

py_trees' ``Timeout`` reads the wall clock; a mission's time is ``snapshot.time`` (15 ms
stream slots), so that a replay, a simulation on a virtual clock and the live run make the
same decisions. These decorators receive the robot in ``setup(robot=...)`` like the leaves.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any, Literal

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours.blackboard import write_key
from roomba_bt.behaviours.declare import ParamError
from roomba_bt.behaviours.frame_inputs import FrameInputs
from roomba_bt.behaviours.lean import (
    DONE,
    DecoratorTick,
    Direct,
    Stepped,
    composite_stop,
    tick_generator,
)
from roomba_bt.behaviours.reasons import SaysWhy, running_in, while_stopped
from roomba_bt.behaviours.units import DURATION, UnitError
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.printable import duration_said
from roomba_bt.robot.interface import RobotHandle

#: the statuses as module constants: ``Status.RUNNING`` goes through the Enum metaclass's
#: ``__getattr__`` hook on every read (several times a global's cost), and guards and
#: repeats read them on every tick
_RUNNING, _SUCCESS, _FAILURE, _INVALID = (
    Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID
)  # fmt: skip


class _MissionClock:
    """Mixin: ``now()`` is the mission time of the current snapshot; ``lasted(duration)``
    whether that much of it has passed since ``start_clock()``."""

    robot: RobotHandle | None = None
    name: str
    _started = 0.0

    def setup(self, **kwargs: Any) -> None:
        robot = kwargs.get("robot")
        if robot is not None:
            self.robot = robot

    def now(self) -> float:
        if self.robot is None:
            raise RuntimeError(f"{self.name!r} was ticked before setup(robot=...)")
        return self.robot.snapshot.time

    def start_clock(self) -> None:
        self._started = self.now()

    def lasted(self, duration: float) -> bool:
        """``duration`` seconds have passed since ``start_clock`` (1 ns of slack: sums of
        15 ms slots are not exact in floating point)."""
        return self.now() - self._started >= duration - 1e-9


def _seconds(decorator: str, name: str, what: str, value: object, minimum: float) -> float:
    """A decorator's time as built from Python, checked as the compiler checks a mission's:
    a finite number of seconds (not a bool) or a text with its unit (``"5 s"``), at least
    ``minimum``. Raises :class:`ParamError` (the leaves' error) naming the decorator, the
    node and what was found: a negative, NaN or missing time ran ('timed out after -5 s',
    a Timeout that never fired) or failed at the first tick."""
    where = f"{decorator} {name!r}: {what}"
    if isinstance(value, str):
        try:
            value = DURATION.parse(value)
        except UnitError as exc:
            raise ParamError(f"{where}: {exc}") from None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParamError(
            f"{where}: expected seconds (a number, or a text with its unit such as '5 s'), "
            f"got {value!r} ({type(value).__name__})"
        )
    if not math.isfinite(value) or value < minimum:
        shown = f"at least {minimum:g} s (one 15 ms tick)" if minimum else "at least 0 s"
        raise ParamError(f"{where}: {value!r} s is out of range: {shown}")
    return float(value)


class _Lasting(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """A decorator that lasts ``duration`` seconds of mission time from its first tick."""

    #: the shortest ``duration`` (the language's: ``timeout.after`` one tick, ``delay.for`` 0)
    shortest = SLOT_SECONDS

    def __init__(self, name: str, child: Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = _seconds(type(self).__name__, name, "duration", duration, self.shortest)

    def initialise(self) -> None:
        self.start_clock()


class Timeout(_Lasting):
    """FAILURE (and the child stopped) if the child is still RUNNING after ``duration``
    seconds of mission time; otherwise the child's status. Its message names the tree's
    limit and the leaf it stopped (``the tree's 8 s limit ran out in dock_approach``): "timed
    out after 8 s" read, in an evaluation's failures, like the run's own --timeout."""

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is _RUNNING and self.lasted(self.duration):
            where = running_in(self.decorated)
            self.feedback_message = (
                f"the tree's {duration_said(self.duration)} limit ran out{where}"
            )
            return _FAILURE
        return status


class Delay(_Lasting):
    """RUNNING for ``duration`` seconds of mission time, then ticks the child (BT.CPP's
    ``Delay``)."""

    shortest = 0.0

    def tick_start(self) -> int:
        """Waiting: RUNNING without ticking the child; then a decorator's tick."""
        first = super().tick_start()
        if not self.lasted(self.duration):
            self.status = _RUNNING
            return DONE
        return first

    def update(self) -> Status:
        return self.decorated.status


class Repeat(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """Restart the child on each SUCCESS: ``times`` times, for ``duration`` seconds of mission
    time, or forever (neither given). FAILURE as soon as the child fails."""

    def __init__(
        self, name: str, child: Behaviour, times: int | None = None, duration: float | None = None
    ) -> None:
        super().__init__(name=name, child=child)
        if times is not None and (isinstance(times, bool) or not isinstance(times, int)
                                  or times < 1):  # fmt: skip
            raise ParamError(
                f"Repeat {name!r}: times: expected a whole number of at least 1 (None: no "
                f"count), got {times!r}"
            )
        self.times = times
        self.duration = (
            None if duration is None
            else _seconds("Repeat", name, "duration", duration, SLOT_SECONDS)
        )  # fmt: skip
        self.count = 0

    def initialise(self) -> None:
        self.count = 0
        if self.duration is not None:
            self.start_clock()

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is not _SUCCESS:
            return status
        self.count += 1
        self.feedback_message = f"{self.count} done"  # the last too: the tree shown at the end
        if self.times is not None and self.count >= self.times:
            return _SUCCESS
        if self.duration is not None and self.lasted(self.duration):
            return _SUCCESS
        return _RUNNING


class Held(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """A debounce: SUCCESS once the child has returned SUCCESS on every tick for ``duration``
    seconds of mission time, FAILURE otherwise; never RUNNING, so that it reads as a
    condition (an ``until:`` that stops a drive only after the battery has stayed low for
    3 s, where one low reading would have).

    The hold starts on the first tick the child succeeds and counts from that tick's time
    (SUCCESS on the first tick at least ``duration`` later, as ``timeout`` counts). It
    starts again when the child says anything else, and when the node was not ticked on the
    tree's previous tick (a guard that held an hour ago, ticked again, must not count its
    old hold: ``Snapshot.previous_tick``; frames lost on the way are no tick missed, nor
    are the frames of a monitor's pause, when mission time stands still too: a hold goes on
    after the resume, and counts one frame a single step): so also after a halt, a run's
    end, a branch left, once it is ticked again.

    Decided: a stop alone (``stop(INVALID)``, ``terminate``) does not restart it. py_trees
    stops every child of a composite that starts afresh, and a sequence or fallback of
    conditions (``until: {sequence: [held, ...]}``) starts afresh on every tick: a reset
    there never let the hold last past one tick. A node stopped and ticked again on the
    next tick has seen its child succeed on every tick, which is what it counts; one
    stopped and left is caught by the gap. (Its own SUCCESS or FAILURE ends every tick,
    and py_trees' ``initialise`` follows on the next: neither is a restart either.)"""

    def __init__(self, name: str, child: Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = _seconds("Held", name, "duration", duration, SLOT_SECONDS)
        #: the duration as its messages say it (``2 min``: ``120 s`` was no text the mission
        #: held), made once rather than at every tick
        self._duration_said = duration_said(self.duration)
        #: the mission time the child's run of successes began (None: not succeeding)
        self.since: float | None = None
        #: ``snapshot.tick`` of this node's last tick (None: never ticked)
        self._last_tick: int | None = None

    def update(self) -> Status:
        if self.robot is None:
            raise RuntimeError(f"{self.name!r} was ticked before setup(robot=...)")
        snapshot = self.robot.snapshot
        tick, previous = snapshot.tick, snapshot.previous_tick
        if previous is None:
            previous = tick - 1
        if self._last_tick != previous:  # the tree ticked without this node: a gap
            self.since = None
        self._last_tick = tick
        if self.decorated.status is not _SUCCESS:
            self.since = None
            self.feedback_message = ""  # the child's own failure says why
            return _FAILURE
        now = snapshot.time
        if self.since is None:
            self.since = now
        held = now - self.since
        if held >= self.duration - 1e-9:  # 1 ns of slack, as _MissionClock.lasted
            self.feedback_message = f"held for {self._duration_said}"
            return _SUCCESS
        self.feedback_message = f"held {held:.3g} s of {self._duration_said} so far"
        return _FAILURE


class ForEach(DecoratorTick, py_trees.decorators.Decorator):
    """Run the child once per item, writing the item to a blackboard key first (waypoints).

    SUCCESS when every item succeeded; FAILURE when the child fails for one of them.
    """

    def __init__(self, name: str, child: Behaviour, key: str, items: Sequence[Any]) -> None:
        super().__init__(name=name, child=child)
        self.key = key
        self.items = tuple(items)
        self.index = 0

    def initialise(self) -> None:
        self.index = 0
        if self.items:
            write_key(self.key, self.items[0], self.name)

    def tick_start(self) -> int:
        """No items: SUCCESS at once, the child never ticked."""
        if not self.items:
            self.status = _SUCCESS
            return DONE
        return super().tick_start()

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is not _SUCCESS:
            return status
        self.index += 1
        if self.index >= len(self.items):
            return _SUCCESS
        write_key(self.key, self.items[self.index], self.name)
        self.feedback_message = f"item {self.index + 1} of {len(self.items)}"
        return _RUNNING


class Guard(SaysWhy, Stepped, py_trees.composites.Composite):
    """``while:`` / ``until:`` on any node: the condition subtree is ticked before the child
    on every tick (BT.CPP's ``_while``, py_trees' EternalGuard, with a subtree as condition).

    * ``while`` (``until=False``): the child runs while the condition succeeds; when it does
      not, the child is stopped (a drive halts) and the guard returns FAILURE.
    * ``until`` (``until=True``): the child runs until the condition succeeds; then the child
      is stopped and the guard returns SUCCESS (also if the condition holds at the start).

    The two children are shown by ``roomba-bt show``: the condition first.
    """

    def __init__(self, name: str, condition: Behaviour, child: Behaviour, until: bool) -> None:
        super().__init__(name=name, children=[condition, child])
        self.condition = condition
        self.child = child
        self.until = until
        #: the condition's inputs (False: it has others than the frame; None: not looked at)
        self._inputs: FrameInputs | Literal[False] | None = None
        #: the condition's status after its last tick, and the inputs' values it had then
        self._seen: tuple[Status, object] | None = None

    @property
    def drawn_as(self) -> str:
        """The py_trees composite it ticks as, by its symbol's key in
        ``py_trees.display.unicode_symbols``: a ``while`` guard is a sequence without memory
        of [condition, node] (``[-]``: FAILURE and the node halted when the condition fails),
        an ``until`` guard a selector without memory (``[o]``: SUCCESS and the node halted
        when it holds). py_trees' displays draw every composite they do not know as a leaf
        (``-->``), which a node with children is not."""
        return "selector_without_memory" if self.until else "sequence_without_memory"

    def initialise(self) -> None:
        """No message from a run before (:class:`SaysWhy`: one only when the condition
        ended this run)."""
        self.feedback_message = ""

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' generator (:class:`Stepped`): ticks the condition, which is then no
        longer what :meth:`tick_direct` last saw."""
        self._seen = None
        yield from super().tick()

    def tick_direct(self) -> None:
        """The steps of :meth:`Stepped.tick_direct` in one call (``tick_start``; the
        condition; :meth:`tick_next`'s reading of it; the child; ``tick_next``'s reading of
        the child, written out here for the guard that goes on running, which it does on
        almost every tick), without the condition's tick when it would change nothing: a
        condition subtree of frame-pure leaves ticked last time on the same values of its
        packets ends this tick with the statuses it has (:class:`FrameInputs`). A cliff or
        bump guard is re-ticked on every frame, and the cliff and bump sensors change on
        few of them."""
        if self.status is not _RUNNING:
            self.initialise()
        children = self.children
        condition = children[0]
        seen, inputs = self._seen, self._inputs
        if (
            seen is None
            or condition.status is not seen[0]
            or not inputs
            or not inputs.unchanged(seen[1])
        ):
            if isinstance(condition, Direct):
                condition.tick_direct()
            else:
                tick_generator(condition)
            self._remember(condition)
        if (self.condition.status is _SUCCESS) == self.until:
            self.tick_next(0)  # the guard ends here
            return
        self.current_child = self.child
        child = children[1]
        if isinstance(child, Direct):
            child.tick_direct()
        else:
            tick_generator(child)
        status: Status = self.child.status
        if status is not _RUNNING:
            self.stop(status)
        self.status = status

    def _remember(self, condition: Behaviour) -> None:
        """After the condition's tick: its status and its inputs' values, for the next;
        nothing when that tick was not the pure one (a node forced, a check patched in)."""
        inputs = self._inputs
        if inputs is None:
            inputs = self._inputs = FrameInputs.of(condition) or False
        status = condition.status
        if inputs and (status is _SUCCESS or status is _FAILURE) and inputs.usable():
            values = inputs.values()
            self._seen = (status, values) if values is not None else None
        else:
            self._seen = None

    def tick_start(self) -> int:
        """The condition first (child 0)."""
        if self.status is not _RUNNING:
            self.initialise()
        return 0

    def tick_next(self, index: int) -> int:
        """After the condition: stop here, or tick the child (child 1); after the child: its
        status."""
        if index == 0:
            holds = self.condition.status is _SUCCESS
            if holds == self.until:
                new_status = _SUCCESS if self.until else _FAILURE
                self.feedback_message = self._why()  # before the child's stop: its stage
                if self.child.status is _RUNNING:
                    self.child.stop(_INVALID)
                self.stop(new_status)
                return DONE
            self.current_child = self.child
            return 1
        status: Status = self.child.status
        if status is not _RUNNING:
            self.stop(status)
        self.status = status
        return DONE

    def _why(self) -> str:
        """The guard's message, read before its children are reset: for ``while``, what
        stopped which node, in the words of the part of the condition that decided it
        (:func:`~roomba_bt.behaviours.reasons.while_stopped`), and the leaf it stopped
        (``(stage drive was running)``: an evaluation's stage)."""
        if self.until:
            return "condition met"
        stage = running_in(self.child).removeprefix(" in ")
        running = f" (stage {stage} was running)" if stage else ""
        guarded = self.child
        while isinstance(guarded, Guard):  # an until: inside: the name is on what it wraps
            guarded = guarded.child
        # read before the child's stop: RUNNING once it ran; anything else, the condition
        # failed on this run's first tick and the child was never ticked
        started = self.child.status is _RUNNING
        return while_stopped(self.condition, guarded.name, started) + running

    def stop(self, new_status: Status = _INVALID) -> None:
        if self.child.status is _RUNNING:
            self.child.stop(_INVALID)
        composite_stop(self, new_status)
