"""The mission language's own node kinds, declared once as data: the words, their options,
the shape of their value and the py_trees class each becomes.

Behaviours declare themselves with :func:`~roomba_bt.behaviours.declare.declare`; the words
of the language (composites, decorators, ``subtree``) and the modifiers are declared here,
with the same :class:`~roomba_bt.behaviours.declare.Param` for each option. Everything else
reads this table: the mission compiler (which options a word takes, their types, which are
required, ranges), the JSON Schema (``roomba-bt schema``), the tree builder, the registry's
reserved words and the documentation test. ``mode``, ``set`` and ``mark`` are behaviours
(declared with ``@declare`` in :mod:`roomba_bt.behaviours.actions`), not words of this table.

Adding a decorator is one :class:`NodeKind` in :data:`WORDS` and one class::

    NodeKind("delay", Shape.DO, lambda name, kids, o: Delay(name, kids[0], o["for"]),
             (Param("for", DURATION, required=True),), doc="RUNNING for a while, then ...",
             answers=Answers(SUCCEEDS, FAILS, alone=RUNS))

A decorator must say how its answer follows its child's (:class:`Answers`), a composite
how its answer follows its children's (:class:`Combines`): the static checks
(:mod:`roomba_bt.mission.ticks`, :mod:`roomba_bt.mission.checks`,
:mod:`roomba_bt.mission.deadends`) reason from them alone, and a word without them is
refused when its :class:`NodeKind` is made. Adding a composite is likewise one
:class:`NodeKind` and one class::

    NodeKind("race", Shape.CHILDREN, lambda name, kids, o: Race(name, kids), (_NAME,),
             doc="every child on every tick, SUCCESS with the first that succeeds",
             combines=Combines(None, needs=ONE))

It lives in the behaviours layer because the registry (which may not import the mission
layer) must know the reserved words, and because it names the node classes.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour

from roomba_bt.behaviours import decorators as ours
from roomba_bt.behaviours import lean
from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.units import BOOL, DURATION, INT, STR, UnitError, ValueType
from roomba_bt.behaviours.units import enum as enum_type
from roomba_bt.oi.frames import SLOT_SECONDS


class Shape(enum.Enum):
    """How a word's value is written."""

    #: ``word: [child, ...]`` or ``word: {children: [...], option: value, ...}``
    CHILDREN = "children"
    #: ``word: {option: value, ..., do: child}``
    DO = "do"
    #: as DO, or the child itself: ``inverter: {bump: any}``
    CHILD_OR_DO = "child or do"
    #: ``subtree: NAME`` or ``subtree: {id: NAME, parameter: value, ...}``
    SUBTREE = "subtree"
    #: not a word: ``while: condition`` or ``until: condition`` beside a node (:data:`GUARD`:
    #: its children are the condition and the node, its meaning its own, read by the checks)
    MODIFIER = "modifier"


def _text(value: object) -> str:
    if not isinstance(value, str):
        raise UnitError(f"expected a text, got {value!r}")
    return value


def _list(value: object) -> list[Any]:
    if not isinstance(value, list):
        raise UnitError(f"expected a list, got {value!r}")
    return value


#: An option taken as written (no ``${parameter}``): a node's name.
TEXT = ValueType("text", _text, json_schema=(("type", "string"),))
#: An option naming some of the node's own children (by their ``name:``). Never empty:
#: ``selected: []`` passed the compiler and py_trees refused it when the run began (exit 4).
CHILD_NAMES = ValueType(
    "child names",
    _list,
    json_schema=(("type", "array"), ("items", {"type": "string"}), ("minItems", 1)),
)
#: A list of values of the type of the blackboard key the node writes (``for_each.in``).
#: Never empty: a loop over nothing never runs its child, and succeeds having done nothing.
KEY_ITEMS = ValueType("items", _list, json_schema=(("type", "array"), ("minItems", 1)))
#: Option types the compiler reads itself rather than as a ``${parameter}``-able value.
STRUCTURAL = (TEXT, CHILD_NAMES, KEY_ITEMS)

Build = Callable[[str, Sequence[Behaviour], Mapping[str, Any]], Behaviour]

SUCCESS, FAILURE, RUNNING = "success", "failure", "running"
#: some of a node's answers (SUCCESS, FAILURE, RUNNING)
Outcomes = frozenset[str]
SUCCEEDS: Outcomes = frozenset({SUCCESS})
FAILS: Outcomes = frozenset({FAILURE})
RUNS: Outcomes = frozenset({RUNNING})


@dataclass(frozen=True, slots=True)
class Answers:
    """How a decorator's answer follows its child's, on the tick the child gives it: the
    facts the static checks read (which nodes end on the tick they start, which modes and
    blackboard keys hold after them, which cliff reads end them), so that a new decorator
    is judged by what it declares, never by a default for a word they do not know.

    RUNNING in the answer to a child that ended means the decorator starts it again
    (``repeat`` after a success, ``retry`` after a failure)."""

    #: what it answers on a tick its child succeeds
    on_success: Outcomes
    #: what it answers on a tick its child fails
    on_failure: Outcomes
    #: what it answers on a tick its child is RUNNING: RUNNING, FAILURE too when its own
    #: clock can end the child (``timeout``), or FAILURE alone (``held`` is never RUNNING)
    while_running: Outcomes = RUNS
    #: what it may answer on a tick it does not tick its child: RUNNING while a ``delay``
    #: waits, SUCCESS for a ``for_each`` of no items
    alone: Outcomes = frozenset()
    #: once ended, it gives that answer again without ticking its child (``oneshot``)
    replays: bool = False
    #: its own clock or count can end it in FAILURE, and starts afresh when the node is
    #: started again (``timeout``, ``retry``)
    limit: bool = False
    #: options without any of which it starts its child again after every success, for
    #: ever: it can only fail (``repeat``'s ``times`` and ``for``)
    forever_without: tuple[str, ...] = ()
    #: what it answers on the tick it starts, whatever its child says, where that is not
    #: what it answers later (``held``: FAILURE); None: the same from its first tick. A
    #: guard's condition is judged by it, and a step of a sequence ticked once that can
    #: only fail on its first tick is an error (:mod:`roomba_bt.mission.deadends`)
    first_tick: Outcomes | None = None
    #: why it answers :attr:`first_tick`, as validate says it (``its hold has lasted 0 s``)
    first_tick_why: str = ""

    def __post_init__(self) -> None:
        """A first-tick answer without its why would be said in validate's error as ``()``."""
        if self.first_tick is not None and not self.first_tick_why:
            raise TypeError("Answers(first_tick=...) needs first_tick_why: why it answers so")

    @property
    def restarts_on(self) -> Outcomes:
        """The child's endings after which it ticks the child again."""
        return frozenset(
            ending
            for ending, answer in ((SUCCESS, self.on_success), (FAILURE, self.on_failure))
            if RUNNING in answer
        )

    def answer(self, ending: str) -> Outcomes:
        """What it answers on a tick its child ended in ``ending`` (SUCCESS or FAILURE)."""
        return self.on_success if ending == SUCCESS else self.on_failure

    @property
    def inverts(self) -> bool:
        """Whether it answers the opposite of its child on every tick its child ends, and
        only then (``inverter``): a branch beside its child fails on a tick they both end."""
        return (
            (self.on_success, self.on_failure) == (FAILS, SUCCEEDS)
            and not self.alone
            and not self.replays
            and self.first_tick is None
        )


#: what a composite that ticks every child on every tick needs to succeed: every child's
#: success, any one's, or the chosen ones' (the children its :attr:`Combines.chosen` option
#: names, by their places: :func:`places_option`)
ALL, ONE, SELECTED = "all", "one", "selected"


def places_option(option: str) -> str:
    """The option the compiler leaves the places of the children an option of child names
    picks in (``selected`` -> ``selected_at``, :mod:`roomba_bt.mission.control`): the
    builder and the checks read them by place, since ``show`` renames the nodes it reviews."""
    return f"{option}_at"


@dataclass(frozen=True, slots=True)
class Combines:
    """How a composite's answer follows its children's: the facts the static checks read
    (:mod:`roomba_bt.mission.ticks`, :mod:`roomba_bt.mission.checks`,
    :mod:`roomba_bt.mission.deadends`), so that a new composite is judged by what it
    declares, never by a list of words, nor by the names of a word's options: the options
    that change how it combines (a parallel's ``policy``, ``selected`` and ``synchronise``)
    are named here, and the checks ask :meth:`waits`, :meth:`waited_for` and
    :meth:`synchronised` of a node's options rather than read them by name.

    Whether one that ticks its children in turn remembers a RUNNING child is its ``memory``
    option (each declares one; a reactive word defaults it to false and refuses true): read
    per node, as written. One that ticks every child on every tick has nothing to resume."""

    #: the ending of a child after which it ticks the next, in turn: SUCCESS for a sequence
    #: (it fails at the first failure, and succeeds when every child has succeeded),
    #: FAILURE for a fallback (it succeeds at the first success); None: it ticks every
    #: child on every tick (a parallel: any failure fails it; :attr:`needs` says which
    #: successes it waits for)
    goes_on: str | None
    #: (every child on every tick) which successes it waits for (:data:`ALL`, :data:`ONE`,
    #: :data:`SELECTED`) when the node has no :attr:`policy` option saying so
    needs: str = ALL
    #: the option whose value (:data:`ALL`, :data:`ONE`, :data:`SELECTED`) says which
    #: successes the node waits for, where a node may say so (``parallel``'s ``policy``)
    policy: str | None = None
    #: the option of child names whose successes :data:`SELECTED` waits for
    #: (``parallel``'s ``selected``); without it, or not given, every child's
    chosen: str | None = None
    #: whether a child that has succeeded is left unticked while the others run (py_trees'
    #: synchronise), when the node has no :attr:`synchronise` option saying so; without it
    #: a success is ticked again, and a node ticked after it finished starts over
    synchronised_by_default: bool = True
    #: the option (a boolean) that says per node whether it is synchronised
    #: (``parallel``'s ``synchronise``)
    synchronise: str | None = None

    @property
    def stops(self) -> str | None:
        """The ending of a child that ends the composite in turn (FAILURE for a sequence,
        SUCCESS for a fallback); None for one that ticks every child on every tick."""
        if self.goes_on is None:
            return None
        return FAILURE if self.goes_on == SUCCESS else SUCCESS

    @property
    def options(self) -> tuple[str, ...]:
        """The options it names, which its word must declare (:class:`NodeKind` checks)."""
        named = (self.policy, self.chosen, self.synchronise)
        return tuple(option for option in named if option is not None)

    def waits(self, options: Mapping[str, Any]) -> str:
        """Which successes a node with ``options`` waits for: :data:`ALL`, :data:`ONE` or
        :data:`SELECTED`, as its :attr:`policy` option says, else :attr:`needs`."""
        if self.policy is None:
            return self.needs
        return str(options.get(self.policy, self.needs))

    def waited_for(self, options: Mapping[str, Any], count: int) -> list[int]:
        """The places of the children whose successes a node with ``options`` and ``count``
        children waits for: every child's but under :data:`SELECTED`, where it is those its
        :attr:`chosen` option picks (all of them when it names none)."""
        if self.waits(options) == SELECTED and self.chosen is not None:
            return list(options.get(places_option(self.chosen), range(count)))
        return list(range(count))

    def synchronised(self, options: Mapping[str, Any]) -> bool:
        """Whether a node with ``options`` leaves a child that has succeeded unticked while
        the others run (its :attr:`synchronise` option, else the word's default)."""
        if self.synchronise is None:
            return self.synchronised_by_default
        return bool(options.get(self.synchronise, self.synchronised_by_default))


#: ``sequence`` and its kin: children in turn, each after the previous one's success
IN_TURN_ALL = Combines(SUCCESS)
#: ``fallback`` and its kin: children in turn, each after the previous one's failure
IN_TURN_FIRST = Combines(FAILURE)
#: ``parallel``: every child on every tick, waiting for the successes its options say
EVERY_TICK = Combines(None, policy="policy", chosen="selected", synchronise="synchronise")


@dataclass(frozen=True, slots=True)
class NodeKind:
    """One word of the language: its value's shape, options, and the class it builds."""

    word: str
    shape: Shape
    #: ``(name, children, options) -> py_trees node``; None for ``subtree`` (its body is
    #: compiled in its place)
    build: Build | None
    options: tuple[Param, ...] = ()
    doc: str = ""
    #: options of which at most one may be given (``repeat``: ``times`` or ``for``)
    exclusive: tuple[str, ...] = ()
    #: the option naming the blackboard key this node writes (``for_each.key``)
    writes_key: str | None = None
    #: ``(option, other, value)``: the option is required when ``other`` is ``value``
    required_if: tuple[tuple[str, str, str], ...] = ()
    #: ``(option, other, value)``: the option may be given only when ``other`` is ``value``
    #: (``parallel``'s ``selected:``, read by no other policy)
    only_if: tuple[tuple[str, str, str], ...] = ()
    #: ``(option, value, why)``: a value the word refuses, and why (``reactive_sequence``
    #: with ``memory: true`` is a ``sequence``)
    refused: tuple[tuple[str, object, str], ...] = ()
    #: the child is ticked as a condition, on every tick, and its RUNNING never waited for
    #: (``held``): the compiler refuses an action under it, or a node that may be RUNNING
    #: (the word would halt it and start it again on every tick)
    condition_child: bool = False
    #: a decorator's answers by its child's (:class:`Answers`): required of every decorator
    answers: Answers | None = None
    #: a composite's answer by its children's (:class:`Combines`): required of every
    #: composite (a word whose value is its children)
    combines: Combines | None = None

    def __post_init__(self) -> None:
        """A decorator without :class:`Answers` would be judged by no check (or wrongly by
        a default): refused here, when the table is built, not found in a wrong ``validate``."""
        decorates = self.shape in (Shape.DO, Shape.CHILD_OR_DO)
        if decorates and self.answers is None:
            raise TypeError(
                f"NodeKind {self.word!r} is a decorator ({self.shape.value}) and needs "
                "answers=Answers(...): how its answer follows its child's (see Answers)"
            )
        if not decorates and self.answers is not None:
            raise TypeError(
                f"NodeKind {self.word!r} takes no answers=: only a decorator (one child "
                "under do:) has them"
            )
        composes = self.shape is Shape.CHILDREN
        if composes and self.combines is None:
            raise TypeError(
                f"NodeKind {self.word!r} is a composite and needs combines=Combines(...): "
                "how its answer follows its children's (see Combines)"
            )
        if self.combines is not None and self.combines.goes_on and not self.option("memory"):
            raise TypeError(
                f"NodeKind {self.word!r} ticks its children in turn and needs a memory "
                "option: whether it resumes a RUNNING child (true) or ticks them all from "
                "the first on every tick (false, a reactive word)"
            )
        if not composes and self.combines is not None:
            raise TypeError(
                f"NodeKind {self.word!r} takes no combines=: only a composite (children:) has it"
            )
        if self.combines is not None:
            self._combines_options(self.combines)

    def _combines_options(self, combines: Combines) -> None:
        """An option :class:`Combines` names that the word does not declare (or declares with
        another type) would never be read: the checks would judge every node by the default."""
        wanted = {combines.policy: None, combines.chosen: CHILD_NAMES,
                  combines.synchronise: BOOL}  # fmt: skip
        for name, kind in wanted.items():
            if name is None:
                continue
            param = self.option(name)
            if param is None or (kind is not None and param.type is not kind):
                said = "an option" if kind is None else f"a {kind.name} option"
                raise TypeError(
                    f"NodeKind {self.word!r}: its Combines name {name!r}, which must be "
                    f"{said} of the word"
                )

    def option(self, name: str) -> Param | None:
        for p in self.options:
            if p.name == name:
                return p
        return None

    @property
    def defaults(self) -> dict[str, Any]:
        """Options with a default, parsed: what a node has when they are not written."""
        return {p.name: p.type.parse(p.default) for p in self.options if p.default is not None}


# ----------------------------------------------------------------------------- composites


def _sequence(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    return lean.Sequence(name, bool(o["memory"]), list(kids))


def _selector(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    return lean.Selector(name, bool(o["memory"]), list(kids))


def _parallel(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    policy: py_trees.common.ParallelPolicy.Base
    synchronise = EVERY_TICK.synchronised(o)
    waits = EVERY_TICK.waits(o)
    if waits == ONE:
        policy = py_trees.common.ParallelPolicy.SuccessOnOne()
    elif waits == SELECTED:
        chosen = [kids[i] for i in EVERY_TICK.waited_for(o, len(kids))]  # by place
        policy = py_trees.common.ParallelPolicy.SuccessOnSelected(chosen, synchronise)
    else:
        policy = py_trees.common.ParallelPolicy.SuccessOnAll(synchronise)
    return lean.Parallel(name, policy, list(kids))


_NAME = Param("name", TEXT, doc="the node's name (same as the name modifier)")


#: why a reactive composite takes no ``memory: true``
_NO_MEMORY = (
    "a {word} ticks every child from the first on every tick: it has no memory "
    "(write {memory} for one that resumes its RUNNING child)"
)


#: a sequence's build and meaning, a fallback's: one pair, so that no word of the table
#: builds one and is judged as the other
_SEQUENCE: tuple[Build, Combines] = (_sequence, IN_TURN_ALL)
_SELECTOR: tuple[Build, Combines] = (_selector, IN_TURN_FIRST)


def _composite(word: str, chain: tuple[Build, Combines], memory: bool, doc: str) -> NodeKind:
    build, combines = chain
    remembers = Param("memory", BOOL, default=memory, doc="resume a RUNNING child")
    why = _NO_MEMORY.format(word=word, memory=word.removeprefix("reactive_"))
    refused = () if memory else (("memory", True, why),)
    return NodeKind(
        word, Shape.CHILDREN, build, (remembers, _NAME), doc, refused=refused, combines=combines
    )


_PARALLEL = NodeKind(
    "parallel",
    Shape.CHILDREN,
    _parallel,
    (
        Param("memory", BOOL, default=False,
              doc="false only: a parallel ticks every child on every tick (it has no memory)"),
        _NAME,
        Param(
            "policy",
            enum_type(ALL, ONE, SELECTED),
            default=ALL,
            doc="SUCCESS when all children succeed, any one does, or the selected ones do",
        ),
        Param(
            "synchronise", BOOL, default=True, doc="do not re-tick children that already succeeded"
        ),
        Param("selected", CHILD_NAMES, doc="child names, for policy: selected"),
    ),
    "py_trees Parallel: ticks every child each tick (with synchronise, not one that succeeded)",
    required_if=(("selected", "policy", "selected"),),
    only_if=(("selected", "policy", "selected"),),
    refused=(("memory", True, "a parallel ticks every child on every tick: it has no memory "
              "to resume (memory: true was ignored; its children's own memory is theirs)"),),
    combines=EVERY_TICK,
)  # fmt: skip

# ----------------------------------------------------------------------------- decorators


def _oneshot(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    policy = (
        py_trees.common.OneShotPolicy.ON_COMPLETION
        if o.get("policy") == "on_completion"
        else py_trees.common.OneShotPolicy.ON_SUCCESSFUL_COMPLETION
    )
    return lean.OneShot(name, kids[0], policy)


_KINDS: tuple[NodeKind, ...] = (
    _composite("sequence", _SEQUENCE, True, "py_trees Sequence: children in order"),
    _composite("reactive_sequence", _SEQUENCE, False,
               "py_trees Sequence without memory: re-ticks every child from the first"),
    _composite("fallback", _SELECTOR, True, "py_trees Selector: children until one succeeds"),
    _composite("selector", _SELECTOR, True, "py_trees Selector (same as fallback)"),
    _composite("reactive_fallback", _SELECTOR, False,
               "py_trees Selector without memory: a higher child preempts a running one"),
    _composite("reactive_selector", _SELECTOR, False,
               "py_trees Selector without memory (same as reactive_fallback)"),
    _PARALLEL,
    NodeKind("inverter", Shape.CHILD_OR_DO, lambda n, k, o: lean.Inverter(n, k[0]),
             doc="SUCCESS <-> FAILURE", answers=Answers(FAILS, SUCCEEDS)),
    NodeKind("force_success", Shape.CHILD_OR_DO, lambda n, k, o: lean.FailureIsSuccess(n, k[0]),
             doc="FAILURE becomes SUCCESS", answers=Answers(SUCCEEDS, SUCCEEDS)),
    NodeKind("force_failure", Shape.CHILD_OR_DO, lambda n, k, o: lean.SuccessIsFailure(n, k[0]),
             doc="SUCCESS becomes FAILURE", answers=Answers(FAILS, FAILS)),
    NodeKind("retry", Shape.DO, lambda n, k, o: lean.Retry(n, k[0], int(o["times"])),
             (Param("times", INT, required=True, minimum=1, doc="attempts in all"),),
             doc="re-run the child after a failure",
             answers=Answers(SUCCEEDS, RUNS | FAILS, limit=True)),
    # A negative time is refused everywhere. repeat.for and timeout.after are at least one
    # tick of the mission clock: less repeats nothing (the child runs once) or fails any
    # child still running after its first tick. delay.for may be 0 (no delay, as wait: 0s:
    # a parameter may switch it off).
    NodeKind("repeat", Shape.DO,
             lambda n, k, o: ours.Repeat(n, k[0], o.get("times"), o.get("for")),
             (Param("times", INT, minimum=1, doc="successes in all"),
              Param("for", DURATION, minimum=SLOT_SECONDS, doc="mission time to repeat for")),
             doc="re-run the child after each success (forever without times or for)",
             exclusive=("times", "for"),
             answers=Answers(RUNS | SUCCEEDS, FAILS, forever_without=("times", "for"))),
    NodeKind("timeout", Shape.DO, lambda n, k, o: ours.Timeout(n, k[0], float(o["after"])),
             (Param("after", DURATION, required=True, minimum=SLOT_SECONDS,
                    doc="mission time"),),
             doc="FAILURE, and the child stopped, if it still runs after a while",
             answers=Answers(SUCCEEDS, FAILS, while_running=RUNS | FAILS, limit=True)),
    NodeKind("delay", Shape.DO, lambda n, k, o: ours.Delay(n, k[0], float(o["for"])),
             (Param("for", DURATION, required=True, minimum=0, doc="mission time"),),
             doc="RUNNING for a while, then ticks the child",
             answers=Answers(SUCCEEDS, FAILS, alone=RUNS)),
    # held.for is at least one tick, as repeat.for: a hold of less is no debounce (the child
    # holding on one tick would do).
    NodeKind("held", Shape.DO, lambda n, k, o: ours.Held(n, k[0], float(o["for"])),
             (Param("for", DURATION, required=True, minimum=SLOT_SECONDS,
                    doc="mission time the child must hold"),),
             doc="SUCCESS once the child has succeeded on every tick for a while, else "
                 "FAILURE (never RUNNING: a debounced condition)",
             condition_child=True,
             answers=Answers(SUCCEEDS | FAILS, FAILS, while_running=FAILS, first_tick=FAILS,
                             first_tick_why="its hold has lasted 0 s")),
    NodeKind("oneshot", Shape.CHILD_OR_DO, _oneshot,
             (Param("policy", enum_type("on_success", "on_completion"),
                    doc="on_success (the default) or on_completion"),),
             doc="runs the child until it succeeds (or completes), then returns that result",
             answers=Answers(SUCCEEDS, FAILS, replays=True)),
    NodeKind("for_each", Shape.DO,
             lambda n, k, o: ours.ForEach(n, k[0], str(o["key"]), o.get("items", ())),
             (Param("key", STR, required=True, doc="a declared blackboard key"),
              Param("in", KEY_ITEMS, required=True, doc="values of the key's type")),
             doc="for each item: write it to the key and run the child", writes_key="key",
             answers=Answers(RUNS | SUCCEEDS, FAILS, alone=SUCCEEDS)),
    NodeKind("subtree", Shape.SUBTREE, None,
             (Param("id", TEXT, required=True, doc="the subtree's name"),),
             doc="use a subtree by name"),
)  # fmt: skip

#: Every word of the language, in the order the documentation lists them.
WORDS: dict[str, NodeKind] = {kind.word: kind for kind in _KINDS}

#: The node ``while:`` and ``until:`` become (not a word: written as a modifier).
GUARD = NodeKind(
    "guard",
    Shape.MODIFIER,
    lambda n, k, o: ours.Guard(n, k[0], k[1], until=bool(o["until"])),
    (Param("until", BOOL, required=True),),
    doc="run the node while (or until) a condition succeeds",
)

#: Keys any node may carry beside its word, with what they mean.
MODIFIERS: dict[str, str] = {
    "name": "the node's name in displays",
    "while": "run while this condition succeeds, else FAILURE",
    "until": "run until this condition succeeds, then SUCCESS",
}

#: Words a behaviour may not take: the language's, the modifiers, and the file sections a
#: node could be mistaken for.
RESERVED: frozenset[str] = frozenset({*WORDS, *MODIFIERS, "include", "tree"})
