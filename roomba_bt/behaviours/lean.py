"""py_trees' composites and decorators, without the per-tick costs of debug logging.

py_trees formats its debug messages before it knows whether debug logging is on: every
``stop`` renders two ``Status`` enums through ``Enum.__format__``, and every decorator tick
rebuilds ``list(Status)`` to check the status its ``update`` returned. A mission ticks every
15 ms and conditions stop on every tick, so on the virtual clock those formatted-and-dropped
strings were a large share of the tree's time.

The classes here are py_trees' own (subclasses: ``isinstance`` checks, ``roomba-bt show``,
py_trees' display and visitors see no difference) with ``stop`` (and, for decorators that do
not define their own, ``tick``) replaced by the same steps in the same order, logging only
when ``py_trees.logging.level`` is DEBUG. A test runs the same trees with the stock classes
and with these and compares every node's status after every tick.
"""

from __future__ import annotations

import typing

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

_DEBUG = py_trees.logging.Level.DEBUG
_STATUSES = frozenset(Status)


def debugging() -> bool:
    """True when py_trees debug logging is on (its ``Logger.debug`` would print)."""
    return py_trees.logging.level is _DEBUG


def checked_status(node: Behaviour, status: object) -> Status:
    """``status`` if it is a Status; otherwise INVALID, logged as py_trees does."""
    try:
        if status in _STATUSES:
            return status
    except TypeError:  # unhashable: not a Status either
        pass
    node.logger.error(
        f"A behaviour returned an invalid status, setting to INVALID [{status}][{node.name}]"
    )
    return Status.INVALID


class _CompositeStop:
    """``Sequence.stop`` / ``Selector.stop``: the debug line, then ``Composite.stop``."""

    def stop(self, new_status: Status = Status.INVALID) -> None:
        node = typing.cast(py_trees.composites.Composite, self)
        if debugging():
            node.logger.debug(f"{type(self).__name__}.stop()[{node.status}->{new_status}]")
        py_trees.composites.Composite.stop(node, new_status)


class Sequence(_CompositeStop, py_trees.composites.Sequence):
    pass


class Selector(_CompositeStop, py_trees.composites.Selector):
    pass


class Parallel(py_trees.composites.Parallel):
    def stop(self, new_status: Status = Status.INVALID) -> None:
        if debugging():
            self.logger.debug(f"{type(self).__name__}.stop()[{self.status}->{new_status}]")
        for child in self.children:
            if child.status == Status.RUNNING:
                child.stop(Status.INVALID)
        py_trees.composites.Composite.stop(self, new_status)


class DecoratorStop:
    """``Decorator.stop``, step for step, logging only when debugging."""

    def stop(self, new_status: Status) -> None:
        node = typing.cast(py_trees.decorators.Decorator, self)
        if debugging():
            node.logger.debug(f"{type(self).__name__}.stop({new_status})")
        node.terminate(new_status)
        if new_status == Status.INVALID:
            node.decorated.stop(new_status)
        if node.decorated.status == Status.RUNNING:
            node.decorated.stop(Status.INVALID)
        node.status = new_status


class DecoratorTick(DecoratorStop):
    """``Decorator.tick`` too (for decorators that do not define their own)."""

    def tick(self) -> typing.Iterator[Behaviour]:
        node = typing.cast(py_trees.decorators.Decorator, self)
        if debugging():
            node.logger.debug(f"{type(self).__name__}.tick()")
        if node.status != Status.RUNNING:
            node.initialise()
        yield from node.decorated.tick()
        new_status = checked_status(node, node.update())
        if new_status != Status.RUNNING:
            node.stop(new_status)
        node.status = new_status
        yield node


class Retry(DecoratorTick, py_trees.decorators.Retry):
    pass


class Inverter(DecoratorTick, py_trees.decorators.Inverter):
    pass


class FailureIsSuccess(DecoratorTick, py_trees.decorators.FailureIsSuccess):
    pass


class SuccessIsFailure(DecoratorTick, py_trees.decorators.SuccessIsFailure):
    pass


class OneShot(DecoratorStop, py_trees.decorators.OneShot):
    """OneShot keeps its own ``tick`` (it bounces after completion); only ``stop`` is lean."""
