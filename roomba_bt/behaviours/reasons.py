"""Why a tree failed, in the words a user should read first.

The runtime puts it in the run's summary when the mission ends in FAILURE, and the
``while`` guard in its message when its condition stops holding; both follow the failure down
the tree the same way.
"""

from __future__ import annotations

import re

import py_trees
from py_trees.behaviour import Behaviour

from roomba_bt.printable import ANY_CONTROL, escaped

#: decorators whose message only restates the status they flipped ("success -> failure")
_FLIPS = (
    py_trees.decorators.Inverter,
    py_trees.decorators.SuccessIsFailure,
    py_trees.decorators.FailureIsSuccess,
)


class SaysWhy:
    """A node whose message, when it failed, is the whole reason in the user's words (the
    ``while`` guard's "stopped: ... while 'clean' ran"; it has none when it failed
    otherwise): :func:`failure_reason` gives it as it is, not the leaf below it nor after
    the node's name ("while inverter: ...")."""


def failure_reason(root: Behaviour) -> str:
    """Why the mission failed, as a user should read it first. Follow the failure down from
    the root, each time into the child whose failure decided its parent's (a sequence's
    failed child; a fallback's last, after the others failed; a parallel's failed one), and
    report the deepest failed leaf on that path, or else the deepest node on it that left a
    message (a ``retry`` may have reset its child), or else the path's last node: a
    decorator that made its child's success a failure is named with its child
    (``force_failure: wait(15ms) succeeded (success is failure)``), never a leaf before it.

    Following the path matters where a tree fails in one branch and other branches hold
    failed leaves too: a patrol that gave up at a staircase is not explained by the
    low-battery check tried beside it.

    A reason is one line: the names and messages it quotes are escaped (a name holding
    ``"\\n[ok] robot stopped"`` faked a line of the summary, the log and eval's report)."""
    return escaped(_explain(root)[0], ANY_CONTROL)


def _explain(root: Behaviour) -> tuple[str, Behaviour | None, bool]:
    """:func:`failure_reason`'s text; the condition leaf that decided it by holding when the
    failure is an inverter's (else None); whether the text carries a node's own message (a
    leaf's ``feedback_message``: "no bump: forced to FAILURE by the operator")."""
    failure = py_trees.common.Status.FAILURE
    node = root
    path = [root]
    leaf: Behaviour | None = None
    with_message: Behaviour | None = None
    while True:
        if isinstance(node, SaysWhy) and node.feedback_message and node.status == failure:
            return node.feedback_message, None, True  # its message says what failed below
        failed = [child for child in node.children if child.status == failure]
        if not failed:
            break
        node = failed[-1]
        path.append(node)
        if not node.children:
            leaf = node
        elif node.feedback_message and not isinstance(node, _FLIPS):
            with_message = node
    best = leaf or with_message or node
    if best is node and isinstance(node, py_trees.decorators.Inverter):
        # an inverter fails because its condition held: that condition is the cause
        # (``while: {inverter: {cliff: any}}`` said only "inverter")
        condition = _deepest_success(node)
        if condition is not None and _is_action(condition):  # it did not hold: it ran
            return f"{node.name}: {condition.name} succeeded (inverted)", None, True
        if condition is not None:  # a name the mission gave it says what it means: kept
            said = f"{condition.name} held"
            return (said if node.name == "inverter" else f"{node.name} ({said})"), condition, False
        # a flip below it (an inverter in an inverter): said leaf by leaf, each as it ended
        # (``inverter: {inverter: {bump: any}}`` said only "inverter")
        return f"{node.name}: {_succeeded_because(node.children[0])} (inverted)", None, True
    if best is node and isinstance(node, py_trees.decorators.SuccessIsFailure):
        # a forced failure: the decorator failed the run, its child having succeeded; a
        # condition that held just before it ("back away, then fail": the patrol's cliff
        # that ended the drive before the back-off) is why it ran, and is said first. An
        # action that succeeded before it is no cause: ``[drive 100ms, force_failure:
        # {wait: 15ms}]`` blamed the drive
        child = node.children[0]
        # a leaf or a composite is said by its name ("back off succeeded"); a flip, leaf by
        # leaf ("inverter succeeded, as bump(any) did not hold")
        flip = isinstance(child, _FLIPS)
        why = _succeeded_because(child) if flip else f"{child.name} succeeded"
        said = f"{node.name}: {why} (success is failure)"
        cause = _cause_before(path)
        return (said if cause is None else f"{cause}, then {said}"), None, True
    message = "" if isinstance(best, _FLIPS) else best.feedback_message
    return (f"{best.name}: {message}" if message else best.name), None, bool(message)


#: How a ``while`` guard's message begins (:func:`while_stopped`): a guard, not a stage
#: (an evaluation's ``failure_stage`` must not read "stopped" as a leaf's name)
GUARD_STOPPED = "stopped: "


def while_stopped(condition: Behaviour, guarded: str, started: bool = True) -> str:
    """A ``while`` guard's message when its ``condition`` no longer holds and it stopped the
    node named ``guarded``: what happened in the words of the condition that decided it (a
    name the mission gave it, else what its leaf says its holding means), then the
    condition as written. ``while: {inverter: {wheel_drop: any}}`` around ``clean``::

        stopped: a wheel has dropped, as when the robot is lifted or a wheel goes over an
        edge, while 'clean' ran (wheel_drop(any) held)

    It said "condition no longer holds: wheel_drop(any) held", under the guard's own name
    ("while inverter"). ``started`` False: the condition failed on the guard's first tick,
    and the node never ran (``before 'drive(...)' started``; it said "while ... ran").

    A condition the mission named ``stopped: ...`` says the reason itself, and is said as it
    stands: ``stopped: cliff front left, while 'bump and turn for a while' ran``."""
    said, held, told = _explain(condition)
    said = escaped(said, ANY_CONTROL)  # one line, as failure_reason's
    when = f"while {guarded!r} ran" if started else f"before {guarded!r} started"
    if held is None and said.startswith(GUARD_STOPPED):
        # the mission named the condition by what its failing means (bump-and-turn's
        # ``{name: "stopped: cliff front left", sensor: cliff_front_left == 0}``): the reason
        # as it stands, said once; it read "stopped: stopped: cliff front left no longer
        # holds while ...", the name's words the opposite of what held
        return f"{said}, {when}"
    if held is None and told:  # its own message says what happened (the monitor's force)
        return f"{GUARD_STOPPED}{said}, {when}"
    if held is None:
        holds = "no longer holds" if started else "does not hold,"
        return f"{GUARD_STOPPED}{said} {holds} {when}"
    meaning = _meaning(held) if said == f"{held.name} held" else None
    if meaning is None:  # the mission's own name for it (or no description): as it is
        return f"{GUARD_STOPPED}{said} {when}"
    return f"{GUARD_STOPPED}{meaning}, {when} ({said})"


def _meaning(leaf: Behaviour) -> str | None:
    """What ``leaf`` holding means, as a clause: its own words where it has them for its
    parameters (``held_means()``: ``odometry`` without ``since`` counts from the run's
    start, and its description's "since a mark" was untrue there), else the first sentence
    of its behaviour's description (its declaration's doc, the class docstring), its asides
    in parentheses left out (the packets it reads): "A bumper is pressed (packet 7: ...)."
    -> "a bumper is pressed"."""
    own = getattr(leaf, "held_means", None)
    if callable(own):
        return str(own())
    declaration = getattr(type(leaf), "declaration", None)
    doc = getattr(declaration, "doc", "") or ""
    sentence = re.sub(r"\s*\([^()]*\)", "", doc.split(". ")[0]).strip().rstrip(".")
    if not sentence:
        return None
    if sentence[1:2].isupper():  # "OI mode ...": an acronym kept
        return sentence
    return sentence[0].lower() + sentence[1:]


def _deepest_success(node: Behaviour) -> Behaviour | None:
    """The leaf whose success decided ``node``'s child's: the last succeeded child, down."""
    success = py_trees.common.Status.SUCCESS
    while node.children:
        held = [c for c in node.children if c.status == success]
        if not held:
            return None
        node = held[-1]
    return node


def _succeeded_because(node: Behaviour) -> str:
    """Why ``node`` succeeded, down to the leaves that decided it, as a clause: an action
    "succeeded", a condition "held"; under an inverter, its child failed: what failed, in
    the same words (a condition "did not hold")."""
    if not node.children:
        return f"{node.name} {'succeeded' if _is_action(node) else 'held'}"
    if isinstance(node, _FLIPS) and node.children[0].status == py_trees.common.Status.FAILURE:
        return f"{node.name} succeeded, as {_failed_because(node.children[0])}"
    success = py_trees.common.Status.SUCCESS
    held = [child for child in node.children if child.status == success]
    return _succeeded_because(held[-1]) if held else f"{node.name} succeeded"


def _failed_because(node: Behaviour) -> str:
    """Why ``node`` failed, as :func:`_succeeded_because` says a success: a condition "did
    not hold", an action "failed" (with its message), a flip's child succeeded."""
    if not node.children:
        if not _is_action(node):
            return f"{node.name} did not hold"
        return f"{node.name} failed" + (
            f" ({node.feedback_message})" if node.feedback_message else ""
        )
    if isinstance(node, _FLIPS) and node.children[0].status == py_trees.common.Status.SUCCESS:
        return f"{node.name} failed, as {_succeeded_because(node.children[0])}"
    failure = py_trees.common.Status.FAILURE
    failed = [child for child in node.children if child.status == failure]
    return _failed_because(failed[-1]) if failed else f"{node.name} failed"


def _cause_before(path: list[Behaviour]) -> str | None:
    """Why the forced failure at the end of ``path`` ran, as a clause, or None:

    * where the path left a fallback just after a ``while`` guard that failed
      (``fallback[drive while not bump, force_failure(recover)]``, a library's bump
      recovery), the guard's own message: the condition that stopped the drive ("stopped: a
      bumper is pressed, while 'drive(...)' ran (bump(any) held)"); the reason said only
      "force_failure: recover succeeded", never that the bumper stopped the drive;
    * where it left a sequence, the condition that ended the step before: in ``[drive until
      cliff, fallback[inverter(cliff), force_failure(back off)]]`` "cliff(any) held" (the
      leaf that succeeded last under the step just before); None when that leaf is an
      action (a ``log`` before the ``force_failure`` is no reason for it)."""
    success = py_trees.common.Status.SUCCESS
    for parent, child in zip(reversed(path[:-1]), reversed(path[1:]), strict=True):
        index = parent.children.index(child)
        if isinstance(parent, py_trees.composites.Selector) and index > 0:
            tried = parent.children[index - 1]  # failed: a fallback goes on only then
            if isinstance(tried, SaysWhy) and tried.feedback_message:
                return tried.feedback_message  # escaped with the rest by the callers
        if not isinstance(parent, py_trees.composites.Sequence):
            continue
        if index == 0:
            return None
        node = parent.children[index - 1]
        while node.children:
            held = [c for c in node.children if c.status == success]
            if not held:
                break
            node = held[-1]
        condition = node.status == success and not node.children and not _is_action(node)
        return f"{node.name} held" if condition else None
    return None


def _is_action(leaf: Behaviour) -> bool:
    """Whether ``leaf`` is a declared action (a drive, a ``log``): its success is something
    done, not a condition that held. A leaf declared nowhere (a py_trees behaviour a Python
    tree holds) is taken as a condition."""
    declaration = getattr(type(leaf), "declaration", None)
    return getattr(declaration, "kind", None) == "action"


#: The leaves that only count time beside the work of a parallel (a ``wait`` is ``clean
#: for the duration``'s timer, ``dock_time_limit`` the docking's bound): RUNNING until their
#: time is up, so never where a robot was when a limit ran out while another leaf ran.
TIMERS = frozenset({"wait", "dock_time_limit"})


def running_in(root: Behaviour) -> str:
    """`` in dock_approach`` when a time limit runs out under ``root`` (the run's --timeout,
    a ``timeout`` decorator's): the leaf still running (the stage it was in, without its
    parameters, so equal stages group together), or "". A timer (:data:`TIMERS`) running
    beside another leaf is a parallel's (``clean for the duration``: the ``wait`` and
    ``cover``; a docking: ``dock_time_limit`` and its stage): the other is what the robot
    was doing, and is named. Before, every --timeout of the dock mission ran out "in
    dock_time_limit", and an evaluation's failures said no stage."""
    running = [
        node
        for node in root.iterate()
        if node.status is py_trees.common.Status.RUNNING and not node.children
    ]
    doing = [
        n for n in running if getattr(getattr(n, "declaration", None), "name", "") not in TIMERS
    ]
    doing = doing or running
    return " in " + escaped(doing[0].name.split("(", 1)[0], ANY_CONTROL) if doing else ""
