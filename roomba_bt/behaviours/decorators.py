"""Decorators that count mission time, and the ``while``/``until`` guard.

py_trees' ``Timeout`` reads the wall clock; a mission's time is ``snapshot.time`` (15 ms
stream slots), so that a replay, a simulation on a virtual clock and the live run make the
same decisions. These decorators receive the robot in ``setup(robot=...)`` like the leaves.
"""

from __future__ import annotations

import typing
from collections.abc import Sequence
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours.declare import write_key
from roomba_bt.behaviours.lean import (
    DecoratorStop,
    DecoratorTick,
    Direct,
    behaviour_tick_direct,
    tick_child,
)
from roomba_bt.behaviours.reasons import failure_reason
from roomba_bt.robot.interface import RobotHandle


class _MissionClock:
    """Mixin: ``now()`` is the mission time of the current snapshot."""

    robot: RobotHandle | None = None
    name: str

    def setup(self, **kwargs: Any) -> None:
        robot = kwargs.get("robot")
        if robot is not None:
            self.robot = robot

    def now(self) -> float:
        if self.robot is None:
            raise RuntimeError(f"{self.name!r} was ticked before setup(robot=...)")
        return self.robot.snapshot.time


class Timeout(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """FAILURE (and the child stopped) if the child is still RUNNING after ``duration``
    seconds of mission time; otherwise the child's status."""

    def __init__(self, name: str, child: Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = duration
        self._started = 0.0

    def initialise(self) -> None:
        self._started = self.now()

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is Status.RUNNING and self.now() - self._started >= self.duration - 1e-9:
            self.feedback_message = f"timed out after {self.duration:g} s"
            return Status.FAILURE
        return status


class Delay(_MissionClock, Direct, DecoratorStop, py_trees.decorators.Decorator):
    """RUNNING for ``duration`` seconds of mission time, then ticks the child (BT.CPP's
    ``Delay``)."""

    def __init__(self, name: str, child: Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = duration
        self._started = 0.0

    def initialise(self) -> None:
        self._started = self.now()

    def tick(self) -> typing.Iterator[Behaviour]:
        if self.status is not Status.RUNNING:
            self.initialise()
        if self.now() - self._started < self.duration - 1e-9:
            self.status = Status.RUNNING
            yield self
            return
        yield from self.decorated.tick()
        new_status: Status = self.decorated.status
        if new_status is not Status.RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def tick_direct(self) -> None:
        if self.status is not Status.RUNNING:
            self.initialise()
        if self.now() - self._started < self.duration - 1e-9:
            self.status = Status.RUNNING
            return
        tick_child(self.decorated)
        new_status: Status = self.decorated.status
        if new_status is not Status.RUNNING:
            self.stop(new_status)
        self.status = new_status

    def update(self) -> Status:
        return self.decorated.status


class Repeat(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """Restart the child on each SUCCESS: ``times`` times, for ``duration`` seconds of mission
    time, or forever (neither given). FAILURE as soon as the child fails."""

    def __init__(
        self, name: str, child: Behaviour, times: int | None = None, duration: float | None = None
    ) -> None:
        super().__init__(name=name, child=child)
        self.times = times
        self.duration = duration
        self.count = 0
        self._started = 0.0

    def initialise(self) -> None:
        self.count = 0
        if self.duration is not None:
            self._started = self.now()

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is not Status.SUCCESS:
            return status
        self.count += 1
        if self.times is not None and self.count >= self.times:
            return Status.SUCCESS
        if self.duration is not None and self.now() - self._started >= self.duration - 1e-9:
            return Status.SUCCESS
        self.feedback_message = f"{self.count} done"
        return Status.RUNNING


class ForEach(Direct, DecoratorStop, py_trees.decorators.Decorator):
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
            write_key(self.key, self.items[0])

    def tick(self) -> typing.Iterator[Behaviour]:
        if not self.items:
            self.status = Status.SUCCESS
            yield self
            return
        yield from super().tick()

    def tick_direct(self) -> None:
        if not self.items:
            self.status = Status.SUCCESS
            return
        behaviour_tick_direct(self, self.decorated)

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is not Status.SUCCESS:
            return status
        self.index += 1
        if self.index >= len(self.items):
            return Status.SUCCESS
        write_key(self.key, self.items[self.index])
        self.feedback_message = f"item {self.index + 1} of {len(self.items)}"
        return Status.RUNNING


class Guard(Direct, py_trees.composites.Composite):
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

    def tick(self) -> typing.Iterator[Behaviour]:
        if self.status is not Status.RUNNING:
            self.initialise()
        yield from self.condition.tick()
        holds = self.condition.status is Status.SUCCESS
        if holds == self.until:
            new_status = Status.SUCCESS if self.until else Status.FAILURE
            if self.child.status is Status.RUNNING:
                self.child.stop(Status.INVALID)
            self.feedback_message = self._why()
            self.stop(new_status)
            yield self
            return
        self.current_child = self.child
        yield from self.child.tick()
        status: Status = self.child.status
        if status is not Status.RUNNING:
            self.stop(status)
        self.status = status
        yield self

    def tick_direct(self) -> None:
        """``tick`` as calls (see :mod:`roomba_bt.behaviours.lean`)."""
        if self.status is not Status.RUNNING:
            self.initialise()
        tick_child(self.condition)
        holds = self.condition.status is Status.SUCCESS
        if holds == self.until:
            new_status = Status.SUCCESS if self.until else Status.FAILURE
            if self.child.status is Status.RUNNING:
                self.child.stop(Status.INVALID)
            self.feedback_message = self._why()
            self.stop(new_status)
            return
        self.current_child = self.child
        tick_child(self.child)
        status: Status = self.child.status
        if status is not Status.RUNNING:
            self.stop(status)
        self.status = status

    def _why(self) -> str:
        """The guard's message, read before its children are reset: for ``while``, which
        part of the condition failed (``condition no longer holds: oi_mode(safe)``)."""
        if self.until:
            return "condition met"
        return f"condition no longer holds: {failure_reason(self.condition)}"

    def stop(self, new_status: Status = Status.INVALID) -> None:
        if self.child.status is Status.RUNNING:
            self.child.stop(Status.INVALID)
        super().stop(new_status)
