"""Checked tree -> py_trees objects; and the :class:`CompiledMission` the runtime runs.

Every node is a py_trees class (``Sequence``, ``Selector``, ``Parallel``, ``Retry``,
``Inverter``, ``OneShot``, ...) or one of ours where py_trees would read the wall clock
(:mod:`roomba_bt.behaviours.decorators`), as :data:`roomba_bt.behaviours.language.WORDS`
says, so py_trees' display, visitors and idioms work on
a compiled mission unchanged.
"""

from __future__ import annotations

import copy
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any
from uuid import UUID
from weakref import WeakKeyDictionary

from py_trees.behaviour import Behaviour

from roomba_bt.behaviours.base import CheckedParams
from roomba_bt.behaviours.blackboard import declare_keys, unwrite_keys, write_key
from roomba_bt.behaviours.language import GUARD, WORDS
from roomba_bt.behaviours.registry import cut_short_in
from roomba_bt.behaviours.units import ValueType
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.plan import Node
from roomba_bt.oi.modes import OIMode
from roomba_bt.printable import ANY_CONTROL, TEXT_LIMIT, escaped, shortened
from roomba_bt.robot.interface import RobotHandle
from roomba_bt.robot.safety import code_failure, failure_said, interrupts_told_apart


class BuildError(Exception):
    """A behaviour's class raised while it was built (a plugin's ``__init__``): the node it
    was built for and the exception, said as a diagnostic at the node's place. Its
    ``sys.exit()``, a ``KeyboardInterrupt`` it raised itself and a ``BaseException`` of its
    own are said so too (:func:`~roomba_bt.robot.safety.code_failure`): they ended
    ``validate`` and ``run`` with exit 0 and no word, 130 or a traceback."""

    def __init__(self, node: Node, error: BaseException) -> None:
        self.node = node
        self.error = error
        frames = traceback.extract_tb(error.__traceback__)
        where = f" (at {frames[-1].filename}:{frames[-1].lineno})" if frames else ""
        assert node.decl is not None
        said = f"{type(error).__name__}: {error}" if isinstance(error, Exception) else None
        super().__init__(
            f"{node.decl.name}: building it raised {said or failure_said(error)}{where}"
        )

    def diagnostic(self) -> Diagnostic:
        return self.node.loc.at(str(self))


def build(node: Node) -> Behaviour:
    """The py_trees (sub)tree for a checked node: a leaf's declared class, or the class the
    language table names for the node's word. A leaf's class that raises (a plugin's bug in
    its ``__init__``) raises :class:`BuildError`, not an internal error of the compiler; a
    Ctrl-C meanwhile goes on as it came, told from a plugin's own ``raise
    KeyboardInterrupt`` (:func:`~roomba_bt.robot.safety.interrupts_told_apart`)."""
    with interrupts_told_apart():
        return _built(node)


def _built(node: Node) -> Behaviour:
    if node.kind == "leaf":
        assert node.decl is not None
        try:
            return node.decl.cls(node.name, CheckedParams(node.params))  # checked here
        except BaseException as exc:
            if not code_failure(exc):
                building = f"building {node.decl.name} ({node.loc.file}:{node.loc.line})"
                cut_short_in(exc, building, node.decl.cls)
                raise
            raise BuildError(node, exc) from exc
    children = [_built(child) for child in node.children]
    kind = GUARD if node.kind == GUARD.word else WORDS[node.kind]
    assert kind.build is not None, f"no builder for node kind {node.kind!r}"
    return kind.build(node.name, children, node.options)


@dataclass
class CompiledMission:
    """A checked mission, compiled onto py_trees, ready for ``setup(robot)`` and ticking."""

    name: str
    description: str
    root: Behaviour
    packets: tuple[int, ...]
    modes_needed: frozenset[OIMode]
    parameters: Mapping[str, Any]
    source: Path
    #: the mission file and every file it includes (what ``run --watch`` watches)
    files: tuple[Path, ...] = ()
    blackboard_initial: Mapping[str, Any] = field(default_factory=dict)
    #: each declared key's type: what ``write_key`` takes for it during a run
    blackboard_keys: Mapping[str, ValueType] = field(default_factory=dict)
    #: each parameter's value as a mission writes it, with its unit (``side: 50 cm``)
    parameters_shown: Mapping[str, str] = field(default_factory=dict)
    #: the opcodes its leaves may send (their ``sends=``)
    sends: frozenset[int] = frozenset()
    #: the checked tree ``root`` was built from (:meth:`rebuilt`); None: not kept
    plan: Node | None = field(default=None, repr=False, compare=False)
    #: what compiles but is likely a mistake (``Diagnostic.severity == "warning"``)
    warnings: tuple[Diagnostic, ...] = ()
    #: the ``wait`` leaves longer than the 5 minutes a robot sleeps after in Passive that may
    #: run there (``file:line:column: wait(10min)``): said when the run starts on a port
    #: whose keep-awake cannot pulse (:func:`~roomba_bt.mission.checks.waits_past_sleep`)
    waits_past_sleep: tuple[str, ...] = ()

    def rebuilt(self) -> CompiledMission:
        """The same mission with a tree of its own: new behaviours, in their initial state,
        built again from the checked plan (an evaluation's next episode, without compiling
        the same text again). The blackboard's initial values are copied too: a run may
        change a mutable one in place."""
        if self.plan is None:
            raise ValueError(f"mission {self.name!r} kept no plan to build a tree from")
        return replace(
            self,
            root=build(self.plan),
            blackboard_initial=copy.deepcopy(dict(self.blackboard_initial)),
        )

    def reviewed(self) -> Behaviour:
        """A tree to review the mission by (``show``, its ``--dot`` and ``--svg``): ``root``
        built again with each node ``name:`` renamed said by what it is first, the name after
        (``drive(velocity=500 mm/s, duration=10s) named 'gentle'``). A name replaced the
        label whole, and ``drive(velocity=50 mm/s, distance=10cm)`` could name a drive at
        500 mm/s; the live tree, the log and the outcome keep the name."""
        if self.plan is None:
            return self.root
        return build(_as_reviewed(self.plan))

    def reviewed_names(self) -> dict[UUID, str]:
        """Each live node's name as ``show`` draws it (:meth:`reviewed`), by the live node's
        id: ``run`` draws its tree before and after the run in ``show``'s words
        (``timeout(after=2s)``) with the live nodes' statuses, where the tree after the run
        said ``timeout`` under one that said ``timeout(after=2s)``. The log and the record
        keep the live names. Below a node whose drawn twin has other children, the live
        names stand."""
        names: dict[UUID, str] = {}
        pairs = [(self.root, self.reviewed())]
        while pairs:
            live, drawn = pairs.pop()
            names[live.id] = drawn.name
            if len(live.children) == len(drawn.children):
                pairs.extend(zip(live.children, drawn.children, strict=True))
        return names

    def __post_init__(self) -> None:
        # the root remembers the blackboard its mission declares: a tree built in Python
        # around it (a TreeMission) writes the initial values too (missions_in)
        _BLACKBOARD_OF_ROOT[self.root] = MissionBlackboard(
            self.name, self.blackboard_keys, self.blackboard_initial
        )

    def setup(self, robot: RobotHandle, **kwargs: Any) -> None:
        """Hand the robot to every node (py_trees idiom: hardware arrives in ``setup``) and
        write the blackboard's initial values. Call again before each run."""
        blackboard = MissionBlackboard(self.name, self.blackboard_keys, self.blackboard_initial)
        set_up_tree(self.root, blackboard, robot, **kwargs)


@dataclass(frozen=True)
class MissionBlackboard:
    """The blackboard a compiled mission declares (``blackboard:``): each key's type and
    the initial values, which its ``setup`` writes before a run. Kept for its root, so that
    a tree that holds the root as a subtree writes them too (:func:`blackboard_within`):
    wrapped in a py_trees ``Sequence`` with other behaviours, a mission whose ``initial:``
    values were never written ended its run with ``UnwrittenKey``."""

    mission: str
    keys: Mapping[str, ValueType]
    initial: Mapping[str, Any]


#: each compiled mission's root -> the blackboard its mission declares. Weak: a root no
#: longer held leaves (the entry does not hold the root: a mission's blackboard does not)
_BLACKBOARD_OF_ROOT: WeakKeyDictionary[Behaviour, MissionBlackboard] = WeakKeyDictionary()


def set_up_tree(
    root: Behaviour, blackboard: MissionBlackboard | None, robot: RobotHandle, **kwargs: Any
) -> None:
    """A run's set-up of ``root``, for a compiled mission and a tree built around one alike:
    ``blackboard``'s keys declared, those without an initial value unwritten (a value the
    run before in this process left is not this run's) and the initial values written
    first (None: no mission declares one), so that a node's ``setup`` may read them, then
    the robot handed to every node."""
    if blackboard is not None:
        declare_keys(blackboard.keys)
        unwrite_keys(key for key in blackboard.keys if key not in blackboard.initial)
        for key, value in blackboard.initial.items():
            write_key(key, value)
    for node in root.iterate():
        node.setup(robot=robot, **kwargs)


def blackboard_within(root: Behaviour) -> MissionBlackboard | None:
    """The blackboard of every compiled mission whose root is ``root`` or in its tree, in
    one (None: no compiled mission's root is there), its keys' types and initial values
    to write before a run. A key two of them declare with different types, or with
    different initial values, is a ValueError naming both: the blackboard is one."""
    found = [_BLACKBOARD_OF_ROOT.get(node) for node in root.iterate()]
    missions = [each for each in found if each is not None]
    if not missions:
        return None
    keys: dict[str, ValueType] = {}
    initial: dict[str, Any] = {}
    declared_by: dict[str, str] = {}
    for each in missions:
        for key, vtype in each.keys.items():
            other = declared_by.setdefault(key, each.mission)
            if key in keys and (keys[key] != vtype or _differs(initial, each.initial, key)):
                raise ValueError(
                    f"blackboard key {key!r} is declared by missions {other!r} and "
                    f"{each.mission!r}, differently (its type or its initial value): one "
                    "tree has one blackboard; rename the key in one of them"
                )
            keys[key] = vtype
        initial.update(each.initial)
    return MissionBlackboard(", ".join(each.mission for each in missions), keys, initial)


def _differs(initial: Mapping[str, Any], other: Mapping[str, Any], key: str) -> bool:
    return (key in initial) != (key in other) or initial.get(key) != other.get(key)


def _use_said(node: Node, what: str) -> str:
    """The body of a subtree use as ``show`` draws it: the use with the arguments it wrote,
    then what the body's root is when it says more than its symbol does (a decorator's
    options, a leaf, a name the library gave it). A use was drawn as the subtree's name
    alone (``{-} bump_recovery``), or as ``retry(times=3) named 'drive_leg'`` where the
    root is a decorator: two looks, neither with the arguments."""
    said = f"subtree {shortened(node.use, TEXT_LIMIT)}"  # the arguments a text, as a description
    if node.own_keys:  # where its own keys are on the blackboard: /mission/go#1/here
        said = f"{said} [own keys: {', '.join(node.own_keys)}]"
    if node.options_written or node.kind in ("leaf", GUARD.word):
        said = f"{said}: {what}"
    # a name the library or the use gave it (a leaf's own name and a guard's are what)
    named = (node.kind == "leaf" and bool(node.label)) or node.kind not in ("leaf", GUARD.word)
    if named and node.name not in (node.kind, node.use.split("(", 1)[0]):
        said = f"{said} named {shortened(node.name)!r}"
    return said


def _condition_said(condition: Node) -> str:
    """What a guard's condition tests, as ``show`` names the guard: an ``inverter`` the
    mission did not name as ``not`` what it inverts (``while not bump(any)``; it drew
    ``while inverter``, what it tests only in the rows under it)."""
    if condition.kind == "inverter" and condition.name == "inverter" and condition.children:
        return f"not {_condition_said(condition.children[0])}"
    return shortened(condition.name)


def _as_reviewed(node: Node) -> Node:
    """``node`` and its children, each renamed by ``name:`` named by what it is first (a long
    name cut, :func:`shortened`)."""
    named = shortened(node.name)
    what = node.label or named
    if node.options_written:  # a composite or decorator: its options, as a leaf's
        what = f"{node.kind}({node.options_written})"
        renamed = node.name != node.kind  # by name:, or as a subtree's body
        name = f"{what} named {named!r}" if renamed else what
    else:
        name = f"{what} named {named!r}" if node.label else named
    if node.use:  # one look for every use: ``subtree drive_leg(dist=1m): retry(times=3)``
        name = _use_said(node, what)
    name = escaped(name, ANY_CONTROL)  # one line of show's tree: a -p text may hold "\n"
    children = [_as_reviewed(child) for child in node.children]
    if node.kind == GUARD.word:  # drawn as the composite it ticks as (Guard.drawn_as)
        word = "reactive_fallback" if node.options["until"] else "reactive_sequence"
        tests = _condition_said(node.children[0])  # "while not bump(any)", not "while inverter"
        name = escaped(f"{'until' if node.options['until'] else 'while'} {tests}", ANY_CONTROL)
        return replace(node, kind=word, name=name, children=children, options={"memory": False})
    return replace(node, name=name, children=children)
