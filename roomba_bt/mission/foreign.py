"""BehaviorTree.CPP's words, as data: what someone porting a tree writes out of habit, and
the word roomba-bt has for it, or, when it has none, what to write instead.

The suggester (:func:`suggestion`) reads the table for an unknown node word, an unknown
option of a composite or decorator and an unknown parameter of a behaviour: a word found
here gets its note instead of difflib's "did you mean" (which offered ``spot`` for
``script`` and ``force_success`` for ``_successIf``). Words are matched without case or
underscores (``RetryUntilSuccessful``, ``retry_until_successful``). ``{key}``, BT.CPP's
port remapping, is a value, not a word: :func:`port_remapping` finds it.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from roomba_bt.behaviours.language import MODIFIERS
from roomba_bt.behaviours.units import closest


@dataclass(frozen=True, slots=True)
class Foreign:
    """What a foreign word is here."""

    #: the words it may be here: the first one known where it is written is named; none
    #: when roomba-bt has no counterpart
    ours: tuple[str, ...]
    #: how to write it here, or (no counterpart) what to write instead
    note: str


_RETRY_TIMES = "times: N (at least 1)"
_COUNTS = (
    "policy: all, one or selected (the children selected: [NAME, ...] names); there are no "
    "counts, and any failure fails"
)
_IN_A_UNIT = "a time with its unit, such as 2s or 500ms"
_NO_SCRIPT = (
    "there are no scripts: set: {key: KEY, value: VALUE} writes a key, check: {key: KEY, "
    "op: '>', value: VALUE} compares one"
)
_AFTER = (
    "there are no scripts: put what should follow the node after it in a sequence "
    "(sequence: [NODE, {set: {key: KEY, value: VALUE}}])"
)
_MEMORY = (
    "roomba-bt's sequence has memory: it resumes a RUNNING child without ticking the ones "
    "before it again; after a failure it starts again from the first child"
)

#: BehaviorTree.CPP (v3 and v4) word -> what it is here (decided: the words a port of the
#: BT.CPP samples met; those whose word is ours in snake_case need no entry, difflib finds
#: them)
BTCPP: dict[str, Foreign] = {
    "RetryUntilSuccessful": Foreign(("retry",), "retry: {times: N, do: NODE}, times at least 1"),
    "KeepRunningUntilFailure": Foreign(
        ("repeat",), "repeat: {do: NODE} without times re-runs it after each success until it fails"
    ),
    "RunOnce": Foreign(
        ("oneshot",),
        "oneshot: NODE runs it until it succeeds, then returns SUCCESS without running it "
        "again; oneshot: {policy: on_completion, do: NODE} until it ends either way, as "
        "RunOnce does",
    ),
    "Sleep": Foreign(("wait",), "wait: 500ms"),
    "SequenceWithMemory": Foreign(("sequence",), _MEMORY),
    "SequenceStar": Foreign(("sequence",), _MEMORY),
    "SetBlackboard": Foreign(("set",), "set: {key: KEY, value: VALUE}"),
    "SubTreePlus": Foreign(("subtree",), "subtree: {id: NAME, parameter: value}"),
    "ID": Foreign(("id",), "subtree: {id: NAME}"),
    "num_attempts": Foreign(("times",), _RETRY_TIMES),
    "num_cycles": Foreign(("times",), _RETRY_TIMES),
    "msec": Foreign(("after", "for", "duration"), _IN_A_UNIT),
    "delay_msec": Foreign(("for",), _IN_A_UNIT),
    "success_count": Foreign(("policy",), _COUNTS),
    "failure_count": Foreign(("policy",), _COUNTS),
    "success_threshold": Foreign(("policy",), _COUNTS),
    "failure_threshold": Foreign(("policy",), _COUNTS),
    "ParallelAll": Foreign(
        ("parallel",),
        "parallel: [NODE, NODE] (policy: all, the default) succeeds when every child has; "
        "any failure fails it",
    ),
    "max_failures": Foreign(("policy",), _COUNTS),
    "_while": Foreign(("while",), "while: CONDITION, written beside the node's word"),
    "_successIf": Foreign(
        ("until",),
        "until: CONDITION, written beside the node's word, ends it with SUCCESS when "
        "the condition holds, checked on every tick, not only before it starts",
    ),
    "_skipIf": Foreign(
        (), "fallback: [CONDITION, NODE] does not run NODE (and succeeds) when CONDITION holds"
    ),
    "_failureIf": Foreign(
        (),
        "sequence: [{inverter: CONDITION}, NODE] fails without running NODE when CONDITION holds",
    ),
    "_post": Foreign((), _AFTER),
    "_onSuccess": Foreign((), _AFTER),
    "_onFailure": Foreign(
        (),
        "there are no scripts: what should run when the node fails goes after it in a "
        "fallback (fallback: [NODE, {set: {key: KEY, value: VALUE}}])",
    ),
    "_onHalted": Foreign((), "nothing runs when a node is halted but the node's own stop"),
    "Script": Foreign((), _NO_SCRIPT),
    "ScriptCondition": Foreign((), _NO_SCRIPT),
    "IfThenElse": Foreign(
        (), "fallback: [{sequence: [IF, THEN]}, ELSE] (ELSE runs when THEN fails too)"
    ),
    "WhileDoElse": Foreign(
        (),
        "reactive_fallback: [{reactive_sequence: [IF, THEN]}, ELSE] (ELSE runs when THEN "
        "fails too)",
    ),
    "Precondition": Foreign((), "sequence: [CONDITION, NODE], or while: CONDITION beside NODE"),
    "AlwaysSuccess": Foreign((), "wait: 0s succeeds at once"),
    "AlwaysFailure": Foreign((), "force_failure: {wait: 0s} fails at once"),
}


def _folded(word: str) -> str:
    return word.replace("_", "").lower()


_BY_FOLDED: dict[str, tuple[str, Foreign]] = {_folded(w): (w, f) for w, f in BTCPP.items()}


def foreign_hint(word: str, known: Sequence[str]) -> str | None:
    """`` (BehaviorTree.CPP's Sleep is 'wait' here: wait: 500ms)``, or with no counterpart
    what to write instead; None for a word the table does not hold, or whose counterparts
    are none of ``known`` (the words that may be written where ``word`` is)."""
    found = _BY_FOLDED.get(_folded(word))
    if found is None:
        return None
    theirs, entry = found
    if not entry.ours:
        return f" (BehaviorTree.CPP's {theirs} has no counterpart here: {entry.note})"
    ours = next((w for w in entry.ours if w in known), None)
    if ours is None:
        return None
    return f" (BehaviorTree.CPP's {theirs} is {ours!r} here: {entry.note})"


def suggestion(word: str, known: Sequence[str], owner: str | None = None) -> str:
    """What follows "unknown node 'x'" or (``owner``: the word whose value holds it)
    "unknown option 'x'": a modifier written inside a word's value, a BT.CPP word
    (:data:`BTCPP`), else difflib's "did you mean"."""
    if owner is not None and word in MODIFIERS and word not in known:
        return (
            f" ({word} is a modifier: write it beside the word, in the node's own mapping "
            f"({{{owner}: ..., {word}: ...}}), not inside {owner}'s value)"
        )
    return foreign_hint(word, known) or closest(word, known)


_PORT = re.compile(r"^\{\s*([A-Za-z_][A-Za-z0-9_]*)\s*\}$")


def port_remapping(text: str) -> str | None:
    """The key of ``{key}``, BT.CPP's port remapping, written as a value; else None."""
    match = _PORT.match(text)
    return match.group(1) if match else None
