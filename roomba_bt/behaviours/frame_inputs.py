"""The ``while``/``until`` guard's memo: what decides a subtree of frame-pure conditions.

A :class:`~roomba_bt.behaviours.base.Condition` class that says ``frame_pure = True`` reads
nothing but its parameters and its declared packets of the tick's frame. A subtree made only
of such leaves under lean sequences and selectors ends a tick on the same packet values with
the same statuses, so the guard (:class:`~roomba_bt.behaviours.decorators.Guard`), which
re-ticks its condition every frame, leaves it as it is while :class:`FrameInputs` says the
values are unchanged.
"""

from __future__ import annotations

import operator
from collections.abc import Callable

import py_trees

from roomba_bt.behaviours.base import SHORT_LIFECYCLE, Condition
from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.lean import Selector, Sequence
from roomba_bt.robot.interface import RobotHandle

_DEBUG = py_trees.logging.Level.DEBUG


class FrameInputs:
    """What decides the statuses of a subtree of frame-pure conditions: the values of the
    packets its leaves read, in this tick's frame.

    Such a subtree is :class:`Condition` leaves (of ``frame_pure`` classes, without ``@key``
    parameters) under py_trees' sequences and selectors (the lean ones, exactly: no subclass
    with steps of its own). Ticked on the same values as last time, from the statuses that
    tick left, it ends with the same statuses: each leaf's status is a function of the
    values, a composite's of its children's, and its lifecycle calls (the leaves'
    ``terminate`` and ``initialise``, the composites') do nothing. So the ``while``/``until``
    guard, which re-ticks its condition every frame, may leave it as it is while
    :meth:`unchanged` holds for the values :meth:`values` gave after its last tick.

    Everything is looked up once, here and when a stream's layout is first seen: the slots
    of the packets in the frame's values (one ``itemgetter`` reads them all, one tuple
    comparison compares them), the lifecycle each class must still have, and each leaf's
    ``__dict__``, where what is patched into one node (the monitor forces a condition by
    giving it an ``update`` of its own) is found by name. (Reading a node's ``__dict__``
    makes CPython 3.11 keep a dictionary for it, which slows every later read of its
    attributes a little; these leaves are ticked only when their packets change.)
    """

    __slots__ = ("_classes", "_layout", "_nodes", "_packets", "_read", "_robot")

    def __init__(self, leaves: list[Condition]) -> None:
        #: per class, its pure check and the lifecycle of the short tick: a patch differs
        self._classes = [
            (cls, (cls._pure_check, *SHORT_LIFECYCLE))
            for cls in {type(leaf): None for leaf in leaves}
        ]
        #: the leaves' own attributes (the dictionary is the node's for good once read)
        self._nodes = [vars(leaf) for leaf in leaves]
        self._packets = tuple(
            sorted({pid for leaf in leaves for pid in leaf.declaration.packets(leaf.params)})
        )
        self._robot: RobotHandle = leaves[0].robot  # type: ignore[assignment]
        self._layout: object = None
        self._read: Callable[[tuple[int, ...]], object] | None = None

    @classmethod
    def of(cls, root: py_trees.behaviour.Behaviour) -> FrameInputs | None:
        """The inputs of the subtree at ``root``, or None when it is not made only of
        frame-pure conditions (or has no robot yet)."""
        leaves: list[Condition] = []
        if not _collect_pure(root, leaves) or not leaves:
            return None
        robot = leaves[0].robot
        if robot is None or any(leaf.robot is not robot for leaf in leaves):
            return None
        return cls(leaves)

    def values(self) -> object:
        """The values of the subtree's packets in this tick's frame (None: the frame lacks
        one of them; the subtree's own tick then says so). A layout not seen before has
        its slots looked up (the same for every frame of a stream)."""
        frame = self._robot.snapshot.frame
        layout = frame.layout
        if layout is not self._layout:
            try:
                slots = [layout.index[pid] for pid in self._packets]
            except KeyError:
                return None
            self._layout, self._read = layout, operator.itemgetter(*slots)
        assert self._read is not None
        return self._read(frame.values)

    def unchanged(self, values: object) -> bool:
        """This tick's frame has ``values`` at the slots last read, and the subtree's tick
        would still be the pure one (:meth:`usable`)."""
        frame = self._robot.snapshot.frame
        read = self._read
        # the frame's fields, not its properties (two Python calls a guard a tick)
        if frame.layout is not self._layout or read is None or read(frame.values) != values:
            return False
        return self.usable()

    def usable(self) -> bool:
        """Nothing has been patched in since (a class's lifecycle or ``check``, a node's own
        ``update`` as the monitor forces one, or ``check``), the leaves still have this robot,
        and debug logging (which a tick would write to) is off."""
        if py_trees.logging.level is _DEBUG:
            return False
        for cls, lifecycle in self._classes:
            if (
                cls.check, cls.update, cls.initialise, cls.start, cls.terminate, cls.stop
            ) != lifecycle:  # fmt: skip
                return False
        robot = self._robot
        for node in self._nodes:
            if "update" in node or "check" in node or node.get("robot") is not robot:
                return False
        return True


def _collect_pure(node: py_trees.behaviour.Behaviour, leaves: list[Condition]) -> bool:
    """Add the leaves under ``node`` to ``leaves``; False if one of the nodes is not a
    frame-pure condition nor a lean sequence or selector."""
    if type(node) in (Sequence, Selector):
        return all(_collect_pure(child, leaves) for child in node.children)
    if not isinstance(node, Condition):
        return False
    cls = type(node)
    pure = cls.frame_pure and cls._pure_check is not None and cls.check is cls._pure_check
    if not pure or any(isinstance(v, BlackboardRef) for v in node.params.values()):
        return False
    leaves.append(node)
    return True
