"""What the static checks know of how a tree is ticked (py_trees' semantics, on the checked
tree :class:`~roomba_bt.mission.plan.Node`): which nodes end on the tick they start, and which
cliff reads are ticked on every tick of a leaf with a result that can end it.

Each answer is conservative: where it is not sure, it says "no" (not at once, no cliff
watch), and the check that asks errs on the side it must (a warning given, a write not
counted). The facts it rests on:

* A sequence or fallback *with* memory resumes a RUNNING child without ticking the ones
  before it; one without (reactive) ticks them all again, from the first, every tick.
* A ``parallel`` ticks its children in order, every tick, but synchronised (``synchronise:
  true``, the default, policies ``all`` and ``selected``) not a child that has already
  succeeded: a branch that succeeded on the first tick is never ticked again while the
  others run. Not synchronised it is ticked again, and a node ticked after it finished
  starts over (py_trees initialises it again): a drive drives its distance again. Which
  options say so is the word's :class:`~roomba_bt.behaviours.language.Combines`' to name
  (:func:`needs`, :func:`waited_for`, :func:`synchronised`).
* ``oneshot`` ticks its child only until it succeeds (or completes); ``force_success`` and
  ``force_failure`` answer the same whatever the child said.
* A guard (``while:``/``until:``) ticks its condition before its child on every tick.
* ``held`` ticks its child on every tick and never returns RUNNING: it fails on the tick its
  child fails, and succeeds only once the child has succeeded for a while.

A decorator is judged by the :class:`~roomba_bt.behaviours.language.Answers` its word
declares (how its answer follows its child's), a composite by its
:class:`~roomba_bt.behaviours.language.Combines` (how its answer follows its children's:
in turn after each success or each failure, or every child on every tick), never by its
name: a new word gets the answers its declaration implies, not a default.
"""

from __future__ import annotations

from roomba_bt.behaviours.conditions import COMPARISON, OPERATORS
from roomba_bt.behaviours.declare import Comparison, Declaration
from roomba_bt.behaviours.language import (
    FAILS,
    FAILURE,
    ONE,
    RUNNING,
    SUCCEEDS,
    SUCCESS,
    WORDS,
    Answers,
    Combines,
    Outcomes,
)
from roomba_bt.mission.plan import Node
from roomba_bt.oi.frames import (
    BUMPS_PACKETS,
    CLIFF_PACKETS,
    ENCODER_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    LIGHT_BUMPER_PACKETS,
)

_NONE: Outcomes = frozenset()
_BOTH: Outcomes = frozenset({SUCCESS, FAILURE})

CLIFFS = frozenset(CLIFF_PACKETS)
#: What ends a drive at a wall or an obstacle, watched as the cliffs are: the bumpers (7),
#: the light bumper (45) and its signals (46-51), the wall signal (27), stasis (58: not
#: moving forward, as against a wall), and the encoders (43, 44: an ``odometry`` guard, a
#: distance end). Any test of one counts (``wall_signal > 5000`` too): the check warns only
#: of a drive that reads none
OBSTACLES = frozenset(
    (*BUMPS_PACKETS, *LIGHT_BUMPER_PACKETS, *LIGHT_BUMP_SIGNAL_PACKETS, *ENCODER_PACKETS, 27, 58)
)


def answers(node: Node) -> Answers | None:
    """The answers ``node``'s word declares if it is a decorator; None for a leaf, a
    composite, a guard (``while:``/``until:``) or a node that could not be built."""
    kind = WORDS.get(node.kind)
    return None if kind is None else kind.answers


def combines(node: Node) -> Combines | None:
    """How ``node``'s word declares its answer follows its children's if it is a
    composite; None for a leaf, a decorator, a guard or a node that could not be built."""
    kind = WORDS.get(node.kind)
    return None if kind is None else kind.combines


def goes_on(node: Node) -> str | None:
    """The ending of a child after which ``node`` ticks its next child, if it ticks them in
    turn: SUCCESS (a sequence), FAILURE (a fallback); None for anything else."""
    combination = combines(node)
    return None if combination is None else combination.goes_on


def every_tick(node: Node) -> bool:
    """Whether ``node`` is a composite that ticks every child on every tick (a parallel)."""
    combination = combines(node)
    return combination is not None and combination.goes_on is None


def reactive(node: Node) -> bool:
    """Whether ``node`` ticks its children in turn without memory: from the first, on
    every tick (``reactive_sequence``, ``reactive_fallback``), as its ``memory`` option
    says (defaulted by its word)."""
    kind = WORDS.get(node.kind)
    if kind is None or kind.combines is None or kind.combines.goes_on is None:
        return False
    memory = kind.option("memory")
    return not node.options.get("memory", memory is None or memory.default)


def needs(node: Node) -> str:
    """Which of its children's successes a composite that ticks every child on every tick
    waits for (``ALL``, ``ONE``, ``SELECTED``): as the option its word's :class:`Combines`
    names says (a parallel's ``policy``), else its word's."""
    combination = combines(node)
    assert combination is not None, f"{node.kind} is not a composite"
    return combination.waits(node.options)


def waited_for(node: Node) -> list[int]:
    """The places of the children whose successes a composite that ticks every child on
    every tick waits for: every child, or those the option its word's :class:`Combines`
    names picks (a parallel's ``selected``, under ``policy: selected``)."""
    combination = combines(node)
    assert combination is not None, f"{node.kind} is not a composite"
    return combination.waited_for(node.options, len(node.children))


def synchronised(node: Node) -> bool:
    """Whether a composite that ticks every child on every tick leaves a child that has
    succeeded unticked while the others run (a parallel's ``synchronise``, as its word's
    :class:`Combines` says where to read it)."""
    combination = combines(node)
    assert combination is not None, f"{node.kind} is not a composite"
    return combination.synchronised(node.options)


def at_once(node: Node) -> bool:
    """Whether ``node`` ends (SUCCESS or FAILURE) on every tick it starts: a condition, a
    leaf declared ``at_once`` (``stop``, ``set``, ``log``), and what is built of them alone."""
    kind = node.kind
    if kind == "leaf":
        decl = node.decl
        return decl is not None and (decl.kind == "condition" or decl.at_once)
    decorator = answers(node)
    if decorator is None:  # a composite or guard; an unbuilt node (no children) is not known
        return kind != "unbuilt" and all(at_once(child) for child in node.children)
    if RUNNING in decorator.on_success | decorator.on_failure | decorator.alone:
        return False  # it runs on (retry, repeat, for_each, delay)
    # never RUNNING itself (held), or RUNNING only while its child is
    return RUNNING not in decorator.while_running or at_once(node.children[0])


def succeeds_at_once(node: Node) -> bool:
    """Whether ``node`` returns SUCCESS on the tick it starts, every time (what it writes
    is written by the end of that tick): a leaf declared ``at_once``, a sequence or parallel
    of such, a ``force_success`` of what ends at once."""
    kind = node.kind
    if kind == "leaf":
        return node.decl is not None and node.decl.at_once
    order = goes_on(node)
    if order == FAILURE:  # a fallback: as its first child
        return succeeds_at_once(node.children[0])
    if order == SUCCESS or every_tick(node):  # a sequence, a parallel: every child
        return all(succeeds_at_once(child) for child in node.children)
    decorator = answers(node)
    if decorator is None or decorator.alone or decorator.restarts_on:
        return False  # a guard, an unbuilt node; one that may answer before its child
    if decorator.on_success | decorator.on_failure == SUCCEEDS:  # force_success
        return at_once(node.children[0])
    return decorator.on_success == SUCCEEDS and succeeds_at_once(node.children[0])


def never_succeeds(node: Node) -> bool:
    """Whether ``node`` can only end in FAILURE (stays RUNNING until then): a ``repeat``
    without ``times`` or ``for``, a ``force_failure``, a leaf that says it cannot succeed
    with its parameters (a ``drive`` with no end, ``dock_time_limit``: ``may_succeed``), a
    sequence with such a child, a ``while:`` or ``timeout`` around one."""
    kind = node.kind
    if kind == "leaf":
        decl = node.decl
        return (
            decl is not None and decl.may_succeed is not None and not decl.may_succeed(node.params)
        )
    order = goes_on(node)
    if order == SUCCESS:  # a sequence
        return any(never_succeeds(child) for child in node.children)
    if order == FAILURE:  # a fallback
        return all(never_succeeds(child) for child in node.children)
    if kind == "guard":
        return not node.options["until"] and never_succeeds(node.children[1])
    decorator = answers(node)
    if decorator is None:
        return False  # a composite that may succeed; an unbuilt node
    given = (node.options.get(option) is not None for option in decorator.forever_without)
    if decorator.forever_without and not any(given):
        return True  # repeat without times or for
    own = decorator.on_success | decorator.on_failure | decorator.while_running | decorator.alone
    if SUCCESS not in own:
        return True  # force_failure
    # one that ends as its child does, on the tick it does (timeout); conservative, as the
    # module is: a delay, retry, held or oneshot of such a child is not said to never succeed
    mirrors = (decorator.on_success, decorator.on_failure) == (SUCCEEDS, FAILS)
    return (
        mirrors
        and not decorator.alone
        and not decorator.replays
        and never_succeeds(node.children[0])
    )


def runs_again(node: Node) -> bool:
    """Whether ticking ``node`` again after it succeeded starts something over: an action
    leaf (a drive drives its distance again, a ``log`` logs again, a ``mark`` moves its
    mark), or a node that may be RUNNING again (a ``wait``'s clock, a ``repeat``'s count, a
    ``delay``). Not a ``oneshot`` (once done it answers as the first time without ticking
    its child) nor what only reads (conditions, and composites and ``held`` of them); not
    a node that could not be built (its own errors are said)."""
    kind = node.kind
    decorator = answers(node)
    if kind == "unbuilt" or (decorator is not None and decorator.replays):
        return False
    if kind == "leaf":
        return node.decl is not None and node.decl.kind == "action"
    return not at_once(node) or any(runs_again(child) for child in node.children)


def reads_cliffs(node: Node, packets: frozenset[int] = CLIFFS) -> bool:
    """Whether a leaf of ``node``'s subtree reads a cliff sensor (packets 9-12), or one of
    ``packets`` (the watch's sensors: :data:`OBSTACLES` for a wall)."""
    return any(
        n.decl is not None and not packets.isdisjoint(n.decl.packets(n.params)) for n in node.walk()
    )


def packet_tests(node: Node) -> list[tuple[str, str, Comparison]]:
    """A leaf's packet tests: (the parameter, how to name it, the test); the ``sensor:``
    test written, or those its declaration says its answer is (``compares``)."""
    decl = node.decl
    if decl is None:
        return []
    found = [
        (param.name, f"{decl.name}.{param.name}", test)
        for param in decl.params
        if param.type is COMPARISON and isinstance(test := node.params.get(param.name), tuple)
    ]
    if decl.compares is not None:
        found += [
            (name, f"{decl.name}: {node.params.get(name, _default(decl, name))}", test)
            for name, test in decl.compares(node.params)
        ]
    return found


def _default(decl: Declaration, name: str) -> object:
    param = decl.param(name)
    return None if param is None else param.default


def _leaf_cliff_ends(node: Node, packets: frozenset[int]) -> Outcomes:
    """What a cliff seen by a leaf's cliff sensors makes it answer: SUCCESS for ``cliff``
    (its tests say a drop is 1), FAILURE for ``sensor: cliff_left == 0``; either where its
    tests do not say (``cover``, a plugin, a test of a signal strength)."""
    if not reads_cliffs(node, packets):
        return _NONE
    if packets is not CLIFFS:  # 1 is no hazard there (stasis 0 is stuck): either result
        return _BOTH
    tests = [test for _, _, test in packet_tests(node) if test[0] in packets]
    if not tests:
        return _BOTH
    out: set[str] = set()
    for _, op, number in tests:
        seen, clear = OPERATORS[op](1, number), OPERATORS[op](0, number)
        out |= {SUCCESS} if seen and not clear else {FAILURE} if clear and not seen else _BOTH
    return frozenset(out)


def cliff_ends(node: Node, packets: frozenset[int] = CLIFFS) -> Outcomes:
    """The results a cliff makes ``node`` give, read on *every* tick ``node`` is ticked;
    empty where a tick may pass without a cliff read that counts (``oneshot``, a check
    after a ``wait`` in a sequence) or whose result nothing passes on (``force_success``)."""
    kind = node.kind
    if kind == "leaf":
        return _leaf_cliff_ends(node, packets)
    if kind == "guard":
        ends = SUCCESS if node.options["until"] else FAILURE
        by_condition = {ends} if ends in cliff_ends(node.children[0], packets) else set()
        return frozenset(by_condition) | cliff_ends(node.children[1], packets)
    combination = combines(node)
    if combination is not None:
        if combination.stops is not None:
            return _chain_ends(node, combination.stops, packets)
        return frozenset().union(*(branch_ends(node, child, packets) for child in node.children))
    decorator = answers(node)
    if decorator is None or decorator.alone or decorator.replays:
        return _NONE  # unbuilt; a decorator that may answer without its child's cliff read
    return _passed_on(decorator, cliff_ends(node.children[0], packets))


def _passed_on(decorator: Answers, child_ends: Outcomes) -> Outcomes:
    """What a decorator answers to the cliff results ``child_ends`` of its child: each that
    it answers one way (not a ``repeat``'s success, which may start the child again, nor a
    ``held`` one, which succeeds only in time), and whose other result it may answer
    otherwise (``force_success`` answers SUCCESS whatever its child said: nothing passes
    on)."""
    out: set[str] = set()
    for ending in child_ends:
        answer = decorator.answer(ending)
        other = decorator.answer(FAILURE if ending == SUCCESS else SUCCESS)
        if len(answer) == 1 and RUNNING not in answer and other != answer:
            out |= answer
    return frozenset(out)


def _chain_ends(node: Node, stops: str, packets: frozenset[int]) -> Outcomes:
    """A sequence (``stops`` FAILURE) or fallback (SUCCESS): a child whose cliff result
    ``stops`` it, reached on every tick (every child before it ends at once) and, with
    memory, not skipped for a later child still running (every child after it ends at
    once); a chain of one child answers as that child."""
    children = node.children
    if len(children) == 1:
        return cliff_ends(children[0], packets)
    again = reactive(node)
    for index, child in enumerate(children):
        if stops in cliff_ends(child, packets) and (
            again or all(at_once(later) for later in children[index + 1 :])
        ):
            return frozenset({stops})
        if not at_once(child):
            break
    return _NONE


def branch_ends(parallel: Node, branch: Node, packets: frozenset[int] = CLIFFS) -> Outcomes:
    """What a cliff read in ``branch`` ends ``parallel`` with, if the branch is ticked on
    every tick the parallel runs: a failure always ends it, a success with ``policy:
    one``. Synchronised (:func:`synchronised`; policies ``all`` and ``selected``) a branch
    that succeeded is not ticked again, so it counts only if it never succeeds."""
    one = needs(parallel) == ONE
    ticked = one or not synchronised(parallel) or never_succeeds(branch)
    if not ticked:
        return _NONE
    return cliff_ends(branch, packets) & (_BOTH if one else {FAILURE})


def watched_children(
    node: Node, watched: bool, packets: frozenset[int] = CLIFFS
) -> list[tuple[Node, bool]]:
    """Each child of ``node`` and whether a cliff is read on every tick it runs, with a
    result that ends it: the condition of a ``while`` (a failure) or ``until`` (a
    success) around it; an earlier child of a reactive sequence (a failure) or reactive
    fallback (a success), ticked again every tick; another branch of a parallel ticked on
    every tick (:func:`branch_ends`). A sequence or fallback with memory ticks an earlier
    child once, not while the later one runs: no watch."""
    children = node.children
    if watched:
        return [(child, True) for child in children]
    kind = node.kind
    if kind == "guard":  # children: the condition, the guarded node
        stop = SUCCESS if node.options["until"] else FAILURE
        return [(children[0], False), (children[1], stop in cliff_ends(children[0], packets))]
    if every_tick(node):
        watch = [bool(branch_ends(node, child, packets)) for child in children]
        return [(c, any(w for j, w in enumerate(watch) if j != i)) for i, c in enumerate(children)]
    if reactive(node):
        stops = FAILURE if goes_on(node) == SUCCESS else SUCCESS
        out, before = [], False
        for child in children:
            out.append((child, before))
            before = before or stops in cliff_ends(child, packets)
        return out
    return [(child, False) for child in children]
