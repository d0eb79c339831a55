"""py_trees' composites, decorators and leaf tick, without their per-tick overheads.

Two costs of py_trees that a tree ticked every 15 ms pays on every tick, removed here with the
same steps in the same order:

* debug messages formatted before anyone knows whether debug logging is on (every ``stop``
  renders two ``Status`` enums through ``Enum.__format__``, every tick formats its class
  name, and every leaf and decorator rebuilds ``list(Status)`` to check what ``update``
  returned). Here they are formatted only when ``py_trees.logging.level`` is DEBUG.
* ticking through generators. py_trees' ``tick()`` yields every ticked node up through every
  ancestor's ``yield from``, so a leaf ten levels down is passed up ten times, a generator
  frame is created per node per tick, and ``tick_once()`` consumes it all only to discard
  it. :meth:`Direct.tick_once` runs the same steps as plain calls (``tick_direct``).

Each class writes its tick once. A node with children (:class:`Stepped`: the composites, the
decorators) writes it as the steps between its children's ticks: ``tick_start`` begins the
tick and names the first child to tick, ``tick_next`` reacts to the child that has just
ticked and names the next; py_trees' generator ``tick`` and ``tick_direct`` both run those
steps and differ only in how they tick a child (``yield from child.tick()``, or
``child.tick_direct()``). A py_trees parent acts when its child's ``tick`` has yielded the
child itself, which is the child's last step, so calling the child and then reading its status
is the same sequence of ``initialise``/``update``/``terminate``/``stop`` calls and the same
statuses. A leaf (:class:`DirectLeaf`) has no child: its generator is its direct tick and then
``yield self``.

``tick()`` stays py_trees' generator (for visitors and for stepping through a tree: it yields
the same nodes at the same moments); ``tick_once()`` takes the direct path. A node that is
not :class:`Direct` (a plugin's py_trees behaviour), or a subclass that overrides ``tick``
without its own ``tick_direct``, is ticked by running its generator, as ``tick_once`` always
did. The classes are py_trees' own (subclasses: ``isinstance`` checks, ``roomba-bt show``,
py_trees' display and visitors see no difference). They repeat py_trees 2.6.0's ticks, the
release pinned in ``pyproject.toml`` and checked at import (:data:`PROVEN_PY_TREES`). A test
builds random trees from the stock classes and from these and compares, on both paths, every
node's status after every tick, every node the generator yields, and the order of every leaf's
calls.
"""

from __future__ import annotations

import typing
from collections.abc import Callable
from itertools import islice
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours.reasons import failure_reason
from roomba_bt.errors import RoombaBtError
from roomba_bt.yamlsource import quoted

#: The py_trees releases whose ticks these classes are proven to repeat (by the property tests
#: in tests/behaviours/test_lean.py); ``pyproject.toml`` pins the same. A release may change a
#: composite's tick, which the classes here would then silently not follow.
PROVEN_PY_TREES = ("2.6.0",)


class UnsupportedPyTrees(ImportError, RoombaBtError):
    """The installed py_trees is not one the lean tree is proven against (roomba-bt's own
    error, worded with the release to install: the command line says it as it is)."""


def check_py_trees(installed: str | None = None) -> None:
    """Refuse a py_trees release the lean tree is not proven against (checked at import)."""
    if installed is None:
        installed = py_trees.version.__version__
    if installed not in PROVEN_PY_TREES:
        proven = ", ".join(PROVEN_PY_TREES)
        raise UnsupportedPyTrees(
            f"py_trees {installed} is installed, but roomba-bt's tree is proven against py_trees "
            f"{proven} only (roomba_bt/behaviours/lean.py repeats its composite and decorator "
            f"ticks): install it with  pip install 'py-trees=={PROVEN_PY_TREES[-1]}'"
        )


check_py_trees()

_DEBUG = py_trees.logging.Level.DEBUG
#: py_trees' logging module, whose ``level`` every node's tick reads (``py_trees.logging``
#: is one attribute read more each time, about 40 instructions, several nodes a tick)
_LOGGING = py_trees.logging
_RUNNING, _SUCCESS, _FAILURE, _INVALID = (
    Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID
)  # fmt: skip
#: the parallel policies, read as globals on every tick of a parallel
_ON_ALL, _ON_ONE, _ON_SELECTED = (
    py_trees.common.ParallelPolicy.SuccessOnAll,
    py_trees.common.ParallelPolicy.SuccessOnOne,
    py_trees.common.ParallelPolicy.SuccessOnSelected,
)
_ON_ALL_OR_ONE = (_ON_ALL, _ON_ONE)
#: py_trees' own check of a parallel's policy, which looks at SuccessOnSelected only
_VALIDATE_POLICY = py_trees.composites.Parallel.validate_policy_configuration


class InvalidStatus(TypeError):
    """A node's ``update`` returned something that is not a final or running py_trees
    Status (``None``: a forgotten ``return``; ``Status.INVALID``, which py_trees keeps for a
    node not ticked yet or stopped). Decided: py_trees logs an error and sets INVALID, on
    every tick, and the tree around it goes on (a sequence stays INVALID, a selector fails,
    a parallel runs on; a sequence met INVALID as "not started" and began again from its
    first child), so a run drove on until its timeout printing one line a tick; here it is
    the node's bug, raised, and the run ends as an error with its safe stop (exit 4)."""

    #: the method whose result was wrong (the run's report points at its source line)
    method = "update"

    def __init__(self, node: Behaviour, status: object) -> None:
        self.node = node
        self.status = status
        super().__init__(self.describe(node, status))

    @staticmethod
    def describe(node: Behaviour, status: object) -> str:
        name = type(node).__name__
        must = "it must return py_trees.common.Status.SUCCESS, FAILURE or RUNNING"
        if status is _INVALID:
            return (
                f"{name}.update() returned Status.INVALID, which py_trees keeps for a node that "
                f"has not run (or was stopped), not for a result: {must}"
            )
        return f"{name}.update() returned {quoted(status)}, not a Status: {must}"


def checked_status(node: Behaviour, status: object) -> Status:
    """``status`` if it is SUCCESS, FAILURE or RUNNING; otherwise (INVALID too: a parent
    sequence read it as "not started" and began again) :class:`InvalidStatus` is raised."""
    if status is _SUCCESS or status is _FAILURE or status is _RUNNING:
        return status
    raise InvalidStatus(node, status)


def check_updates(root: Behaviour) -> list[Behaviour]:
    """Every node under ``root`` whose ``update`` is no roomba-bt's or py_trees' own (a plain
    py_trees behaviour of the user's) gets an ``update`` that raises :class:`InvalidStatus`
    when the usual one returns no Status, as a roomba-bt leaf's tick does (py_trees logged
    an error every tick and the tree went on). Done once per node (a tree run again keeps
    it); a lean node checks in its own tick (:func:`tick_ended`), and a compiled mission
    holds only those and py_trees' composites: nothing there is wrapped. Returns the nodes
    given one."""
    wrapped = []
    for node in root.iterate():
        update: Any = node.update
        home = getattr(type(node).update, "__module__", None) or ""
        if isinstance(node, Direct) or getattr(update, "checks_status", False):
            continue
        if "update" not in vars(node) and home.split(".", 1)[0] in ("py_trees", "roomba_bt"):
            continue
        node.update = _checking(node, update)  # type: ignore[method-assign]
        wrapped.append(node)
    return wrapped


def _checking(node: Behaviour, update: Callable[[], object]) -> Callable[[], Status]:
    """``update`` with its result checked (:func:`checked_status`)."""

    def checked_update() -> Status:
        return checked_status(node, update())

    checked_update.checks_status = True  # type: ignore[attr-defined]
    return checked_update


def tick_generator(node: Behaviour) -> None:
    """py_trees' ``tick_once``: run the node's ``tick`` generator to its end."""
    for _ in node.tick():
        pass


class Direct:
    """Mixin: ``tick_once`` by plain calls (``tick_direct``), the same steps as ``tick``.

    A subclass that overrides ``tick`` but not ``tick_direct`` gets the generator path, so
    its own ``tick`` is what runs."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "tick" in vars(cls) and "tick_direct" not in vars(cls):
            cls.tick_direct = Direct.tick_direct  # type: ignore[method-assign]

    def tick_direct(self) -> None:
        """The calls ``tick`` makes (:class:`DirectLeaf`, :class:`Stepped`); by default the
        generator itself."""
        tick_generator(typing.cast(Behaviour, self))

    def tick_once(self) -> None:
        self.tick_direct()

    @property
    def iterator(self) -> typing.Iterator[Behaviour]:
        """py_trees' ``iterator`` (a fresh ``tick()`` generator, which py_trees' ``stop`` builds
        on every stop and nothing reads), built only when asked for: every condition stops on
        every tick, and the generator was an allocation each time."""
        return typing.cast(Behaviour, self).tick()

    @iterator.setter
    def iterator(self, value: typing.Iterator[Behaviour]) -> None:
        """py_trees' ``__init__`` assigns one; the property builds its own."""


def behaviour_tick(node: Behaviour, started: bool = False) -> None:
    """py_trees' ``Behaviour.tick`` as calls: a leaf's tick (and a completed OneShot's).

    ``started``: its first half (``initialise`` unless running) is done, and a child has
    ticked since: the rest is the end of py_trees' ``Decorator.tick`` (``update``, ``stop``
    on a final status), which is that of ``Behaviour.tick``."""
    if not started:
        if _LOGGING.level is _DEBUG:
            node.logger.debug(f"{type(node).__name__}.tick()")
        if node.status is not _RUNNING:
            node.initialise()
    new_status = node.update()
    if new_status is _RUNNING:  # most ticks of a leaf: a Status, and nothing to stop
        node.status = new_status
        return
    tick_ended(node, new_status)


def tick_ended(node: Behaviour, new_status: object) -> None:
    """The end of :func:`behaviour_tick` once ``update`` returned ``new_status`` (RUNNING
    is done there): checked as a Status, the node stopped on a final one, then its status.

    For a node that calls its ``update`` from its own ``tick_direct``: CPython 3.11
    specialises an attribute read for the one class it meets at that place, and
    ``behaviour_tick`` ticks the running leaf on every tick; a decorator or a leaf ticked
    beside it there too (the retry and ``dock_time_limit`` of a docking run) made its reads
    switch class two or three times a tick."""
    if new_status is _SUCCESS or new_status is _FAILURE:
        node.stop(new_status)
    elif new_status is not _RUNNING:
        checked_status(node, new_status)  # raises: INVALID, or no Status at all
    node.status = new_status  # type: ignore[assignment]


class DirectLeaf(Direct):
    """py_trees' leaf ``tick``/``stop``, logging only when debugging. A leaf ticks no child,
    so its generator is its direct tick and then ``yield self``."""

    tick_direct = behaviour_tick  # a plain function as the method: one call less per leaf

    def tick(self) -> typing.Iterator[Behaviour]:
        node = typing.cast(Behaviour, self)
        behaviour_tick(node)
        yield node

    def stop(self, new_status: Status) -> None:
        """py_trees' stop, without formatting its debug message (two enum ``__format__``
        calls) when debug logging is off: every condition stops on every tick. (``node``
        is ``self`` typed as the Behaviour it is mixed into: an annotation, since
        ``typing.cast`` is a function call at run time.)"""
        node: Behaviour = self  # type: ignore[assignment]
        if _LOGGING.level is _DEBUG:
            change = f"{node.status}->{new_status}" if node.status != new_status else new_status
            node.logger.debug(f"{type(self).__name__}.stop({change})")
        node.terminate(new_status)
        node.status = new_status


#: what a step returns when the node's tick is over (no further child to tick)
DONE = -1


class Stepped(Direct):
    """A node with children, its tick written once as the steps between its children's ticks.

    ``tick_start()`` begins the tick and returns the index of the first child to tick (or
    :data:`DONE`); ``tick_next(index)``, called once the child at ``index`` has ticked, reads
    its status and returns the index of the next child to tick (or DONE). py_trees' generator
    ``tick`` and the direct ``tick_direct`` both run these steps, and differ only in how they
    tick a child: ``yield from child.tick()`` (every node ticked below is yielded up, as
    py_trees does; a visitor sees each as soon as it has ticked), or ``child.tick_direct()``.
    """

    children: list[Behaviour]
    #: the child a resumed tick (:meth:`Sequence.tick_direct`, :meth:`Selector.tick_direct`,
    #: :meth:`DecoratorTick.tick_direct`) last found to be :class:`Direct`, and its
    #: ``tick_direct``: the same child on the next tick is ticked so without asking
    #: ``isinstance`` again (about 170 instructions a node, four nodes on every tick of a
    #: docking run; a node's class does not change). Before any: :data:`_NO_CHILD`.
    _direct_child: tuple[object, Callable[[], None]]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """A subclass that rewrites a step (``tick_start``/``tick_next``) without its own
        ``tick_direct`` is ticked by the steps themselves (:meth:`Stepped.tick_direct`): the
        shortcut a lean class writes beside its steps (the resumed tick of a running
        sequence, of a decorator) repeats the class's steps, not the subclass's."""
        super().__init_subclass__(**kwargs)
        own = vars(cls)
        if "tick_direct" not in own and ("tick_start" in own or "tick_next" in own):
            cls.tick_direct = Stepped.tick_direct  # type: ignore[method-assign]

    def tick_start(self) -> int:
        raise NotImplementedError

    def tick_next(self, index: int) -> int:
        raise NotImplementedError

    def tick(self) -> typing.Iterator[Behaviour]:
        index = self.tick_start()
        children = self.children
        while index != DONE:
            yield from children[index].tick()
            index = self.tick_next(index)
        yield typing.cast(Behaviour, self)

    def tick_direct(self) -> None:
        self.tick_steps(self.tick_start())

    def tick_steps(self, index: int) -> None:
        """The steps from the child at ``index`` on, each child ticked by its direct path
        when it has one: the whole tick from ``tick_start``'s child (:meth:`tick_direct`), or
        the rest of it where a shortcut has ticked a child and called ``tick_next``."""
        children = self.children
        while index != DONE:
            child = children[index]
            if isinstance(child, Direct):  # by its direct path when it has one
                child.tick_direct()
            else:
                tick_generator(child)
            index = self.tick_next(index)


#: :attr:`Stepped._direct_child` before a resumed tick has found one (no child is None)
_NO_CHILD: tuple[object, Callable[[], None]] = (None, lambda: None)
Stepped._direct_child = _NO_CHILD


def composite_stop(node: py_trees.composites.Composite, new_status: Status) -> None:
    """py_trees 2.6's ``Composite.stop`` (without building the ``iterator`` nothing reads):
    on INVALID the current child is lost and every child not INVALID stopped; then
    ``terminate`` and the status."""
    if new_status is _INVALID:
        node.current_child = None
        for child in node.children:
            if child.status is not _INVALID:
                child.stop(new_status)
    node.terminate(new_status)
    node.status = new_status


class _CompositeStop:
    """``Sequence.stop`` / ``Selector.stop``: the debug line, then ``Composite.stop``."""

    def stop(self, new_status: Status = Status.INVALID) -> None:
        node: py_trees.composites.Composite = self  # type: ignore[assignment]
        if _LOGGING.level is _DEBUG:
            node.logger.debug(f"{type(self).__name__}.stop()[{node.status}->{new_status}]")
        composite_stop(node, new_status)


class Sequence(Stepped, _CompositeStop, py_trees.composites.Sequence):
    """py_trees 2.6's ``Sequence.tick``, step for step."""

    def tick_direct(self) -> None:
        """A running sequence with memory resumes its current child: ``tick_start`` only
        finds that child's index then, and when the child is still running, ``tick_next``
        only sets the sequence's status to RUNNING. A mission's root and its attempts are
        such sequences on almost every tick, one child running for seconds; the steps
        (two calls and their reads) are run only when the child has ended."""
        child = self.current_child
        if (
            child is None
            or self.status is not _RUNNING
            or not self.memory
            or _LOGGING.level is _DEBUG
        ):
            Stepped.tick_direct(self)
            return
        known = self._direct_child  # Stepped._direct_child
        if known[0] is child:
            known[1]()
        elif isinstance(child, Direct):
            self._direct_child = (child, child.tick_direct)
            child.tick_direct()
        else:
            tick_generator(child)
        if child.status is _RUNNING:
            self.status = _RUNNING
            return
        self.tick_steps(self.tick_next(self.children.index(child)))

    def tick_start(self) -> int:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.tick()")
        children = self.children
        index = 0
        if self.status is not _RUNNING:
            self.current_child = children[0] if children else None
            for child in children:
                if child.status is not _INVALID:
                    child.stop(_INVALID)
            self.initialise()
        elif self.memory and self.current_child is not None:
            index = children.index(self.current_child)
        else:
            self.current_child = children[0] if children else None
        if not children:
            self.current_child = None
            self.stop(_SUCCESS)
            return DONE
        return index

    def tick_next(self, index: int) -> int:
        children = self.children
        status = children[index].status
        if status is not _SUCCESS:
            if not self.memory:  # invalidate the rest: kill dangling runners
                for later in islice(children, index + 1, None):
                    if later.status is not _INVALID:
                        later.stop(_INVALID)
            if status is not _RUNNING:
                self.stop(status)
            else:
                self.status = status
            return DONE
        if index + 1 < len(children):
            self.current_child = children[index + 1]
            return index + 1
        self.stop(_SUCCESS)
        return DONE


class Selector(Stepped, _CompositeStop, py_trees.composites.Selector):
    """py_trees 2.6's ``Selector.tick``, step for step."""

    def tick_direct(self) -> None:
        """A running selector with memory resumes its current child, as a sequence does
        (:meth:`Sequence.tick_direct`): ``tick_start`` stops the children before it (none
        is left to stop but on its first resumed tick) and names it; when it is still
        running, ``tick_next`` keeps it current (it was: nothing was interrupted) and sets
        the selector's status to RUNNING.

        Written out again, not shared with the sequence's: CPython specializes a code
        object's attribute reads for the one class it sees, and one function ticking both
        classes measured 2,900 more instructions a dock tick (``bench.tick_replay --icount``);
        this is the hottest path of the tree."""
        child = self.current_child
        if (
            child is None
            or self.status is not _RUNNING
            or not self.memory
            or _LOGGING.level is _DEBUG
        ):
            Stepped.tick_direct(self)
            return
        children = self.children
        for earlier in children:  # the children before it (its index is needed only after)
            if earlier is child:
                break
            if earlier.status is not _INVALID:
                earlier.stop(_INVALID)
        known = self._direct_child  # Stepped._direct_child
        if known[0] is child:
            known[1]()
        elif isinstance(child, Direct):
            self._direct_child = (child, child.tick_direct)
            child.tick_direct()
        else:
            tick_generator(child)
        if child.status is _RUNNING and self.current_child is child:
            self.status = _RUNNING
            return
        self.tick_steps(self.tick_next(children.index(child)))

    def tick_start(self) -> int:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.tick()")
        children = self.children
        if self.status is not _RUNNING:
            self.current_child = children[0] if children else None
            self.initialise()
        if not children:
            self.current_child = None
            self.stop(_FAILURE)
            return DONE
        if not self.memory:
            return 0
        assert self.current_child is not None
        index = children.index(self.current_child)
        for child in islice(children, None, index):
            if child.status is not _INVALID:
                child.stop(_INVALID)
        return index

    def tick_next(self, index: int) -> int:
        children = self.children
        child = children[index]
        status = child.status
        if status is _RUNNING or status is _SUCCESS:
            # the current child is still the one this tick started from (py_trees' previous)
            previous = self.current_child
            self.current_child = child
            if previous is None or previous != child:
                # it interrupted: invalidate everything at a lower priority
                passed = False
                for other in children:
                    if passed and other.status is not _INVALID:
                        other.stop(_INVALID)
                    if other == child:
                        passed = True
            if status is _SUCCESS:
                self.stop(status)
            else:
                self.status = status
            return DONE
        if index + 1 < len(children):
            return index + 1
        self.stop(_FAILURE)
        self.current_child = children[-1]
        return DONE


class Parallel(Stepped, py_trees.composites.Parallel):
    """py_trees 2.6's ``Parallel.tick``, step for step."""

    def __init__(
        self,
        name: str,
        policy: py_trees.common.ParallelPolicy.Base,
        children: typing.Sequence[Behaviour] | None = None,
    ) -> None:
        super().__init__(name, policy, children)
        #: whether the node's class checks its policy as py_trees' does (which has nothing to
        #: say of SuccessOnAll and SuccessOnOne): found once, as the class cannot change
        #: under its node, for :meth:`tick_direct`, where ``type(self).<method>`` (a read off
        #: the class, which CPython 3.11 does not specialise) was a few hundred instructions
        #: on every tick
        self._stock_policy_check = type(self).validate_policy_configuration is _VALIDATE_POLICY
        #: the policy object :meth:`tick_direct` last found to be py_trees' SuccessOnAll or
        #: SuccessOnOne, its check py_trees' own (None: none yet): the same object on the next
        #: tick is not asked its type again (a policy is seldom replaced, never changed)
        self._lean_policy: py_trees.common.ParallelPolicy.Base | None = None

    def stop(self, new_status: Status = Status.INVALID) -> None:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.stop()[{self.status}->{new_status}]")
        for child in self.children:
            if child.status == _RUNNING:
                child.stop(_INVALID)
        composite_stop(self, new_status)

    def tick_direct(self) -> None:
        """The steps in one call: every child not yet succeeded (when synchronised) ticked
        in turn, then :meth:`_conclude`; a parallel is ticked on every tick of a mission
        that has one, and its children are never skipped. The steps themselves when there
        is more to do first (debug logging, a policy other than py_trees' SuccessOnAll and
        SuccessOnOne, a policy check of its own, no children).

        With every child still running after its tick, :meth:`_conclude` would find neither
        a failure nor a success: the parallel runs on, its current child the last one
        (both policies). That is most ticks of a docking run (the time limit beside the
        attempt), and it is decided here without the call and its pass over the policies."""
        policy = self.policy
        if policy is not self._lean_policy:
            kind = type(policy)
            if (kind is not _ON_ONE and kind is not _ON_ALL) or not self._stock_policy_check:
                Stepped.tick_direct(self)
                return
            self._lean_policy = policy
        if _LOGGING.level is _DEBUG or not self.children:
            Stepped.tick_direct(self)
            return
        children = self.children
        if self.status is not _RUNNING:
            for child in children:
                if child.status is not _INVALID:
                    child.stop(_INVALID)
            self.current_child = None
            self.initialise()
        synchronise = policy.synchronise
        for child in children:
            if synchronise and child.status is _SUCCESS:
                continue
            if isinstance(child, Direct):
                child.tick_direct()
            else:
                tick_generator(child)
        for child in children:
            if child.status is not _RUNNING:
                self._conclude()
                return
        self.current_child = children[-1]
        self.status = _RUNNING

    def tick_start(self) -> int:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.tick()")
        if isinstance(self.policy, _ON_SELECTED) or (
            type(self).validate_policy_configuration is not _VALIDATE_POLICY
        ):  # py_trees validates on every tick; its check has nothing to say of the others
            self.validate_policy_configuration()
        children = self.children
        if self.status is not _RUNNING:
            for child in children:
                if child.status is not _INVALID:
                    child.stop(_INVALID)
            self.current_child = None
            self.initialise()
        if not children:
            self.current_child = None
            self.stop(_SUCCESS)
            return DONE
        return self.tick_next(-1)

    def tick_next(self, index: int) -> int:
        """The next child to tick (one that has not succeeded, when synchronised); after
        the last, the parallel's own status."""
        children = self.children
        following = index + 1
        if self.policy.synchronise:
            while following < len(children) and children[following].status is _SUCCESS:
                following += 1
        if following < len(children):
            return following
        self._conclude()
        return DONE

    def _conclude(self) -> None:
        """py_trees' ending of the tick, from one pass over the children's statuses: the
        first that failed (the parallel fails, naming it), else the last that succeeded
        (SuccessOnOne's ``reversed`` search) and whether all did (SuccessOnAll)."""
        children = self.children
        policy = self.policy
        succeeded = None
        all_succeeded = True
        for child in children:
            status = child.status
            if status is _FAILURE:
                self.current_child = child
                self.stop(_FAILURE)
                self.status = _FAILURE
                return
            if status is _SUCCESS:
                succeeded = child
            else:
                all_succeeded = False
        new_status = _RUNNING
        current = children[-1]
        if succeeded is None and isinstance(policy, _ON_ALL_OR_ONE):
            pass  # neither policy is met while nothing has succeeded: RUNNING
        elif isinstance(policy, _ON_ALL):
            if all_succeeded:
                new_status = _SUCCESS
        elif isinstance(policy, _ON_ONE):
            if succeeded is not None:
                new_status = _SUCCESS
                current = succeeded
        elif isinstance(policy, _ON_SELECTED):
            if all(c.status is _SUCCESS for c in policy.children):
                new_status = _SUCCESS
                current = policy.children[-1]
        else:
            raise RuntimeError(
                f"this parallel has been configured with an unrecognised policy [{type(policy)}]"
            )
        self.current_child = current
        if new_status is not _RUNNING:
            self.stop(new_status)
        self.status = new_status


class DecoratorTick(Stepped, py_trees.decorators.Decorator):
    """py_trees' ``Decorator.tick`` in its two steps (``initialise`` unless running; after
    the child, ``update`` and ``stop`` on a final status) and its ``stop``, logging only when
    debugging. A decorator with its own tick overrides a step."""

    def tick_start(self) -> int:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.tick()")
        if self.status is not _RUNNING:
            self.initialise()
        return 0

    def tick_next(self, index: int) -> int:
        behaviour_tick(self, started=True)
        return DONE

    def tick_direct(self) -> None:
        """The two steps in one call (``initialise`` unless running, the child's tick, the
        rest of the decorator's own tick: ``update``, and :func:`tick_ended` unless it says
        RUNNING). A decorator that rewrites a step is ticked by its steps
        (:meth:`Stepped.__init_subclass__`)."""
        if _LOGGING.level is _DEBUG:
            Stepped.tick_direct(self)
            return
        if self.status is not _RUNNING:
            self.initialise()
        child = self.children[0]
        known = self._direct_child  # Stepped._direct_child
        if known[0] is child:
            known[1]()
        elif isinstance(child, Direct):
            self._direct_child = (child, child.tick_direct)
            child.tick_direct()
        else:
            tick_generator(child)
        new_status = self.update()
        if new_status is _RUNNING:
            self.status = new_status
            return
        tick_ended(self, new_status)

    def stop(self, new_status: Status) -> None:
        if _LOGGING.level is _DEBUG:
            self.logger.debug(f"{type(self).__name__}.stop({new_status})")
        self.terminate(new_status)
        if new_status == _INVALID:
            self.decorated.stop(new_status)
        if self.decorated.status == _RUNNING:
            self.decorated.stop(_INVALID)
        self.status = new_status


class Retry(DecoratorTick, py_trees.decorators.Retry):
    """py_trees' retry, whose giving up names the last attempt's failure: ``gave up after 30
    failed attempts; the last: drive(...): cliff front right`` (the child is reset between
    attempts, so by the end its leaves no longer say why).

    Its ``update`` is py_trees 2.6's ``Retry.update`` (the same counts, statuses and
    messages) without rebuilding the message on every tick: py_trees formats ``running
    [status: 0 failure from 40]`` each time its child runs, which is every tick of a docking
    attempt, and reads three ``Status`` members off the Enum class to do it."""

    last_failure: str = ""
    #: what the message last written by :meth:`_say` says, and that message itself
    _said: tuple[str, int, int] | None = None
    _said_text: str | None = None

    def update(self) -> Status:
        child = self.decorated.status
        if child is _FAILURE:
            self.last_failure = failure_reason(self)
            self.failures += 1
            if self.failures < self.num_failures:
                return self._say("attempt failed", _RUNNING)
            # py_trees: "final failure [status: 3 failure from 3]"
            attempts = "attempt" if self.failures == 1 else "attempts"
            last = f"; the last: {self.last_failure}" if self.last_failure else ""
            self.feedback_message = f"gave up after {self.failures} failed {attempts}{last}"
            return _FAILURE
        if child is _RUNNING:
            # every tick of a docking attempt: the message shown says so already (the test
            # of _say, without its call)
            said = ("running", self.failures, self.num_failures)
            if said == self._said and self.feedback_message is self._said_text:
                return _RUNNING
            return self._say("running", _RUNNING)
        return self._say("succeeded", _SUCCESS)  # py_trees' else: SUCCESS (or INVALID)

    def _say(self, word: str, status: Status) -> Status:
        """py_trees' message ``{word} [status: {failures} failure from {num_failures}]``,
        formatted only when it differs from the one already shown (set by this method and
        not replaced since); then ``status``."""
        said = (word, self.failures, self.num_failures)
        if said != self._said or self.feedback_message is not self._said_text:
            text = f"{word} [status: {self.failures} failure from {self.num_failures}]"
            self.feedback_message = self._said_text = text
            self._said = said
        return status


class Inverter(DecoratorTick, py_trees.decorators.Inverter):
    pass


class FailureIsSuccess(DecoratorTick, py_trees.decorators.FailureIsSuccess):
    pass


class SuccessIsFailure(DecoratorTick, py_trees.decorators.SuccessIsFailure):
    pass


class OneShot(DecoratorTick, py_trees.decorators.OneShot):
    """py_trees' ``OneShot.tick`` (which the steps replace: they come first in the MRO): once
    completed it bounces, ticked as a leaf (its ``update`` returns the final status) without
    ticking its child."""

    def tick_start(self) -> int:
        if self.final_status:
            behaviour_tick(self)
            return DONE
        return super().tick_start()
