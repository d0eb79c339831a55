"""Structural dead ends: what a behaviour-tree reviewer checks first, from the results
each node can give (:func:`outcomes`), on the checked tree
(:class:`~roomba_bt.mission.plan.Node`).

A node that can never succeed blocks the sequence it is a step of: the steps after it can
never run (``log`` after a ``drive`` with no end, after a ``repeat`` for ever, after a
``force_failure``). One that can never fail does the same to the alternatives after it in
a fallback. A guard whose condition answers the same on its first tick either never runs
its node or always fails; a ``retry`` around a child that never fails never retries; a
``parallel`` (policy ``all``) of a condition and its inverter never succeeds. These are
warnings (errors under ``--strict``): the mission runs, and does not do what it says.

One is an error: a decorator whose :class:`Answers` say it can only fail on the tick it
starts (``first_tick``: ``held``, whose hold has lasted 0 s then) as a step of a sequence
(with memory or reactive) or a branch of a parallel, or under decorators there that pass
its FAILURE up (``timeout: {do: {held: ...}}``), where nothing ticks it again after
that failure (a ``retry`` above it, a guard's condition, an earlier alternative of a
reactive fallback would; a ``repeat`` stops at it). It fails its parent on every run,
which is never meant.

Each answer is conservative where it is not sure (an action may fail, a plugin may do
anything): it gives more results, so fewer findings, never a false one. What can end a
node from outside (a ``timeout``, a ``while:``/``until:`` guard, a reactive parent's
earlier child) is counted where it acts: a ``timeout`` may fail, an ``until:`` may
succeed, a reactive fallback succeeds when its earlier child does. An endless node at the
end of a tree (a patrol's ``repeat``) blocks nothing, and is not said.
"""

from __future__ import annotations

from dataclasses import dataclass

from roomba_bt.behaviours.language import (
    ALL,
    FAILS,
    FAILURE,
    ONE,
    RUNNING,
    SUCCEEDS,
    SUCCESS,
    Answers,
    Outcomes,
)
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.plan import Node
from roomba_bt.mission.ticks import (
    answers,
    at_once,
    combines,
    every_tick,
    goes_on,
    needs,
    reactive,
    waited_for,
)

_BOTH: Outcomes = frozenset({SUCCESS, FAILURE})


def outcomes(node: Node, first_tick: bool = False) -> Outcomes:
    """The results ``node`` can end in by itself (empty: it never ends). ``first_tick``:
    on the tick it starts, where a decorator may answer otherwise than later
    (:attr:`Answers.first_tick`: ``held`` is always FAILURE then), what a guard's condition
    answers before its node starts."""
    kind = node.kind
    if kind == "leaf":
        return _leaf_outcomes(node)
    children = node.children
    order = goes_on(node)
    if order is not None:  # a sequence, a fallback
        return _chain_outcomes(node, order, first_tick)
    if every_tick(node):  # a parallel
        return _parallel_outcomes(node)
    if kind == "guard":
        return _guard_outcomes(node, first_tick)
    decorator = answers(node)
    if decorator is None or not children:
        return _BOTH  # unbuilt: anything
    if first_tick and decorator.first_tick is not None:
        return decorator.first_tick
    return _decorated(node, decorator, outcomes(children[0], first_tick))


def _decorated(node: Node, decorator: Answers, child: Outcomes) -> Outcomes:
    """A decorator's results, by what its word declares (:class:`Answers`) of its answer
    to each of its child's: ``repeat`` without ``times`` or ``for`` never takes a success
    for its own; an answer while the child runs (``timeout``'s FAILURE) counts when the
    child may run; RUNNING (the child started again) is no result."""
    out = set(decorator.alone)
    endless = decorator.forever_without and all(
        node.options.get(option) is None for option in decorator.forever_without
    )
    for ending in child:
        answer = decorator.answer(ending)
        out |= answer - SUCCEEDS if endless and ending == SUCCESS else answer
    if not at_once(node.children[0]):
        out |= decorator.while_running
    return frozenset(out - {RUNNING})


def _leaf_outcomes(node: Node) -> Outcomes:
    """A leaf: SUCCESS unless its declaration says it cannot with these parameters
    (``may_succeed``), FAILURE unless it says it never fails (``never_fails``)."""
    decl = node.decl
    if decl is None:
        return _BOTH
    succeeds = decl.may_succeed is None or decl.may_succeed(node.params)
    return frozenset(
        ({SUCCESS} if succeeds else set()) | (set() if decl.never_fails else {FAILURE})
    )


def _chain_outcomes(node: Node, go_on: str, first_tick: bool) -> Outcomes:
    """A sequence goes on after a success, a fallback after a failure (``go_on``): it ends
    the other way at the first child that can, and its own way if every child can go on."""
    out: set[str] = set()
    for child in node.children:
        results = outcomes(child, first_tick)
        out |= results - {go_on}
        if go_on not in results:
            return frozenset(out)
    return frozenset(out | {go_on})


def _parallel_outcomes(node: Node) -> Outcomes:
    """A failed branch fails the parallel; it succeeds when one branch (``one``), the
    ``selected`` ones or all of them can."""
    results = [outcomes(child) for child in node.children]
    if _contradicts(node.children):
        return frozenset({FAILURE})
    failure = {FAILURE} if any(FAILURE in r for r in results) else set()
    policy = needs(node)
    if policy == ONE:
        succeeds = any(SUCCESS in r for r in results)
    else:
        succeeds = all(SUCCESS in results[i] for i in waited_for(node))
    success = {SUCCESS} if succeeds else set()
    return frozenset(failure | success)


def _contradicts(branches: list[Node]) -> bool:
    """Whether the branches all end on the tick they start and one inverts another
    (``[bump: any, inverter: {bump: any}]``: a decorator whose :class:`Answers` say it
    answers the opposite of its child, on that tick): on that tick one of them fails."""
    if not all(at_once(branch) for branch in branches):
        return False
    said = {(branch.kind, branch.name) for branch in branches}
    return any(
        _inverts(branch) and (branch.children[0].kind, branch.children[0].name) in said
        for branch in branches
    )


def _inverts(node: Node) -> bool:
    """Whether ``node``'s word answers the opposite of its child, on the tick its child
    answers (:attr:`Answers.inverts`: ``inverter``)."""
    decorator = answers(node)
    return decorator is not None and decorator.inverts


def _guard_outcomes(node: Node, first_tick: bool) -> Outcomes:
    """``while:`` fails when its condition does, ``until:`` succeeds when its condition
    does; a condition that stops it on its first tick leaves its node never started."""
    condition, guarded = node.children
    stop = SUCCESS if node.options["until"] else FAILURE
    if outcomes(condition, first_tick=True) == {stop} and at_once(condition):
        return frozenset({stop})
    stops = {stop} if stop in outcomes(condition) else set()
    return outcomes(guarded, first_tick) | stops


def _why(results: Outcomes) -> str:
    """How a node that blocks what follows it ends, if it does."""
    if not results:
        return (
            "never ends (nothing ends it: no distance, duration or count, no until:, no "
            "timeout, no reactive parent whose earlier child ends it)"
        )
    return "never succeeds (it can only fail)" if results == {FAILURE} else "never fails"


def _line(node: Node) -> str:
    return f"line {node.loc.line}"


def _guarded(node: Node) -> Node:
    """The node a ``while:``/``until:`` runs (through a guard of a guard), else ``node``:
    what a warning names, where the guard's own name (``until force_success``, at the
    guard's line) read as another node than the ``drive`` written above it."""
    while node.kind == "guard":
        node = node.children[1]
    return node


def _described(node: Node) -> str:
    """``drive(...) (line 5, while held)``: a node by the one it runs, with its guard."""
    inner = _guarded(node)
    guard = f", {node.name}" if inner is not node else ""
    return f"{inner.name} ({_line(inner)}{guard})"


def dead_ends(root: Node) -> tuple[list[Diagnostic], list[Diagnostic]]:
    """Errors and warnings (see the module docstring), each said once for a subtree used
    twice."""
    errors: list[Diagnostic] = []
    warnings: list[Diagnostic] = []
    # each node with the endings after which something above ticks it again (the root: none)
    pending: list[tuple[Node, Outcomes]] = [(root, frozenset())]
    while pending:
        node, again = pending.pop()
        children_again = [_child_again(node, again, index) for index in range(len(node.children))]
        errors += _failing_first_steps(node, children_again)
        warnings += _blocked_children(node) + _guard_answers(node) + _futile_retry(node)
        warnings += _parallel_never_succeeds(node)
        pending.extend(reversed(list(zip(node.children, children_again, strict=True))))
    return list(dict.fromkeys(errors)), list(dict.fromkeys(warnings))


def _child_again(node: Node, again: Outcomes, index: int) -> Outcomes:
    """The endings of ``node``'s child at ``index`` after which something ticks it again,
    so that a ``held`` there may count a hold (:func:`_failing_first_steps`); ``again``:
    ``node``'s own. A decorator ticks its child again after an ending it answers with
    RUNNING (``retry`` after a failure; ``repeat`` only after a success, so a failure
    under it ends the loop), or passes it up as an answer ticked again above. A failed
    step fails its sequence, a failed branch its parallel (whatever the policy), the last
    alternative its fallback: each is ticked again when its parent is. A guard reads its
    condition on every tick its node runs, a reactive fallback its earlier alternatives.
    A success that something else follows (a step before the last, a branch) is counted
    as ticked again: not sure, so fewer findings, never a false one."""
    decorator = answers(node)
    if decorator is not None:
        return frozenset(
            ending
            for ending in _BOTH
            if RUNNING in decorator.answer(ending) or decorator.answer(ending) & again
        )
    last = index == len(node.children) - 1
    order = goes_on(node)
    if order == SUCCESS:  # a sequence
        return (again & FAILS) | (again & SUCCEEDS if last else SUCCEEDS)
    if order == FAILURE:  # a fallback
        return (again & SUCCEEDS) | (FAILS if reactive(node) and not last else again & FAILS)
    if every_tick(node):  # a parallel
        return (again & FAILS) | SUCCEEDS
    if node.kind == "guard" and index == 1:
        return again  # the guarded node's ending is the guard's
    return _BOTH  # a guard's condition; a node not known


@dataclass(frozen=True, slots=True)
class _FirstFailure:
    """A node that can only fail on the tick it starts (:func:`_fails_first`)."""

    #: the node whose word says so (``held``)
    node: Node
    #: its word's answers (their ``first_tick_why`` is said)
    answers: Answers
    #: the decorators between the step and it that pass that failure up, the step first
    through: tuple[Node, ...]


def _fails_first(node: Node) -> _FirstFailure | None:
    """Whether ``node`` can only fail on the tick it starts: its word's answers say so
    (``held``: :attr:`Answers.first_tick`), or it is a decorator that passes such a
    child's failure up on that tick (``timeout: {do: {held: ...}}``): one that ticks its
    child on its first tick (nothing answered ``alone``) and answers a failure with FAILURE
    alone (``timeout``, ``repeat``, ``oneshot``; not ``retry``, which starts its child
    again, nor ``inverter`` or ``force_success``, which answer otherwise)."""
    through: list[Node] = []
    while (decorator := answers(node)) is not None and node.children:
        if decorator.first_tick == FAILS:
            return _FirstFailure(node, decorator, tuple(through))
        passes_failure_up = decorator.on_failure == FAILS and decorator.first_tick is None
        if decorator.alone or not passes_failure_up:
            return None
        through.append(node)
        node = node.children[0]
    return None


def _failing_first_steps(node: Node, children_again: list[Outcomes]) -> list[Diagnostic]:
    """A step of a sequence (with memory or reactive) or a branch of a parallel that can
    only fail on the tick it starts (:func:`_fails_first`), and that nothing ticks again
    after that failure (:func:`_child_again`): its failure fails its parent on every run.
    Said at the node whose word fails (``held``), naming the decorators that pass it up."""
    if goes_on(node) == SUCCESS:  # a sequence
        role = "step"
    elif every_tick(node):  # a parallel
        role = "branch"
    else:
        return []
    errors: list[Diagnostic] = []
    for child, again in zip(node.children, children_again, strict=True):
        found = _fails_first(child)
        if found is None or FAILURE in again:
            continue
        failing, why = found.node, found.answers.first_tick_why
        errors.append(
            failing.loc.at(
                f"{failing.kind} is FAILURE on the tick it starts ({why})"
                f"{_passed_up(found.through)}, and as a {role} of this "
                f"{node.kind} ({node.loc.line}:{node.loc.column}) it is ticked once: the "
                f"{node.kind} fails here on every run; use it where it is ticked on every "
                f"tick: until: {{{failing.kind}: ...}} around a node, or the first child of "
                "a reactive_fallback"
            )
        )
    return errors


def _passed_up(through: tuple[Node, ...]) -> str:
    """``, passed up by repeat (4:17) and oneshot (4:7)``: the decorators between a step
    and the node whose first failure it is, from the inside out; "" when there are none."""
    if not through:
        return ""
    said = [f"{outer.kind} ({outer.loc.line}:{outer.loc.column})" for outer in reversed(through)]
    return ", passed up by " + " and ".join(said)


def _blocked_children(node: Node) -> list[Diagnostic]:
    """The first child of a sequence after a step that never succeeds, of a fallback after
    an alternative that never fails: it can never run."""
    go_on = goes_on(node)
    if go_on is None:  # not a sequence nor a fallback
        return []
    for child, after in zip(node.children, node.children[1:], strict=False):
        if _fails_first(child) is not None:
            continue  # said by _failing_first_steps, or ticked again by a loop above
        results = outcomes(child)
        if go_on in results:
            continue
        if go_on == SUCCESS:
            what, needs = "step", "succeeds"
            fix = "give it an end that succeeds (a distance or duration, until:)"
        else:
            what, needs = "alternative", "fails"
            fix = "let it fail (no force_success around it)"
        blocked = _guarded(after)
        return [
            blocked.loc.at(
                f"{blocked.name} can never run: the {what} before it, {_described(child)}, "
                f"{_why(results)}, and the {node.kind} goes on only when it {needs}; {fix}, "
                "or remove what follows it"
            ).as_warning()
        ]
    return []


def _guard_answers(node: Node) -> list[Diagnostic]:
    """A ``while:``/``until:`` whose condition ends the guard on its first tick, every
    time: its node never starts."""
    if node.kind != "guard":
        return []
    condition, guarded = node.children
    until = node.options["until"]
    stop = SUCCESS if until else FAILURE
    if not at_once(condition) or outcomes(condition, first_tick=True) != {stop}:
        return []
    word, answer, result = ("until", "true", "SUCCESS") if until else ("while", "false", "FAILURE")
    return [
        guarded.loc.at(
            f"{guarded.name} never runs: its {word}: condition {condition.name} is always "
            f"{answer} on its first tick, so the guard ends in {result} before it starts; "
            "guard it with a condition that can change (a sensor, bump, odometry)"
        ).as_warning()
    ]


def _futile_retry(node: Node) -> list[Diagnostic]:
    """A ``retry`` around a child that never fails: it never retries."""
    if node.kind != "retry" or FAILURE in outcomes(node.children[0]):
        return []
    child = node.children[0]
    return [
        node.loc.at(
            f"retry never retries: {_described(child)} never fails, and retry "
            "starts it again only after a failure; remove the retry, or retry what can fail"
        ).as_warning()
    ]


def _parallel_never_succeeds(node: Node) -> list[Diagnostic]:
    """A ``parallel`` waiting for every branch (policy ``all``) whose branches contradict
    each other (:func:`_contradicts`). Not one with a branch that only fails (``[drive,
    inverter: {cliff: any}]`` drives until the cliff is seen, and fails then, as meant):
    a step after it is said by :func:`_blocked_children`."""
    if not every_tick(node) or needs(node) != ALL or not _contradicts(node.children):
        return []
    combination = combines(node)
    policy = None if combination is None else combination.policy
    said = "" if policy is None else f" ({policy}: {ALL})"
    return [
        node.loc.at(
            f"the {node.kind} can never succeed: it waits for every branch{said}, its "
            "branches are all read on the tick it starts, and one is the inverter of another, "
            "so one of them fails on that tick; use a fallback to take either answer, or "
            "remove one of them"
        ).as_warning()
    ]
