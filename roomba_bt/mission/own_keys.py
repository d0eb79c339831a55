"""A subtree's own blackboard keys: each use's copy, named apart, and what it hides.

A subtree definition may declare ``blackboard:`` of its own (docs/missions.md, Subtrees). Its
body is parsed at each use with those keys under the names it writes (``here``), hiding a
mission key of that name; once parsed, every reference to them in that body is renamed to
the use's own name (:func:`own_key_name`: ``go#1/here``, ``go#2/here``), which is then
declared like a mission key. So every check that follows keys (read before written, the
ranges of their readers, ``initial:``, parallel writers) and the run itself (the keys under
``/mission/``, written at start, removed when the run is closed) see each use's keys as keys
of their own, with nothing of their own to learn. Renaming the plan, not resolving names at
run time, keeps the tick path as it was: a behaviour reads ``/mission/go#1/here`` as it
reads ``/mission/leg``.

The bodies of the subtrees a body uses are not renamed with it: a body's own keys are its
alone (lexical scope), so a library's subtree used inside another cannot have its keys taken
by the caller's (each is renamed at its own use, before).
"""

from __future__ import annotations

from collections.abc import Mapping

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.language import WORDS
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.plan import KeyDecl, Node
from roomba_bt.mission.source import Loc

#: what separates the subtree's name from the number of its use in an own key's name: no
#: key a file declares has it (keys are snake_case), so no name of a use meets a mission's
USE_MARK = "#"


def own_key_name(subtree: str, use: int, key: str) -> str:
    """The name key ``key`` of ``subtree``'s own blackboard has at its ``use``-th use in the
    compiled tree (1 first, in the file's order, subtrees expanded): ``go#2/here``, that
    is ``/mission/go#2/here`` on py_trees' blackboard. A number, not the use's line: a use
    in a library's subtree has the library's line at every use of that subtree."""
    return f"{subtree}{USE_MARK}{use}/{key}"


def is_own_key(name: str) -> bool:
    """Whether ``name`` is a use's own key (:func:`own_key_name`), not one a file wrote."""
    return USE_MARK in name


def said_key(name: str) -> str:
    """A key as a message names it: ``'leg'``, and a use's own by the name its body writes,
    ``'here' (subtree go's own)``: the use itself is named beside the finding (in subtree
    go, used at ...), and the same finding at every use of a library's subtree is one."""
    if not is_own_key(name):
        return repr(name)
    subtree, _, rest = name.partition(USE_MARK)
    return f"{rest.partition('/')[2]!r} (subtree {subtree}'s own)"


def written_ref(ref: BlackboardRef) -> str:
    """``@here`` for a use's own key ``go#1/here``, as its body writes it; ``@leg`` else."""
    if not is_own_key(ref.key):
        return str(ref)
    return str(BlackboardRef(ref.key.partition("/")[2], ref.field))


def renamed(body: Node, names: Mapping[str, str]) -> None:
    """Each reference to a key of ``names`` in ``body`` renamed as it says: ``@here``,
    ``set: {key: here}``, ``check: {key: here.x}``, ``for_each.key``, a plugin's key
    parameter. The bodies of subtrees used in it (a node with ``use``) are left as they
    are: they were parsed, and their own keys renamed, where they are used."""
    stack = [body]
    while stack:
        node = stack.pop()
        _rename_node(node, names)
        stack.extend(child for child in node.children if not child.use)


def _rename_node(node: Node, names: Mapping[str, str]) -> None:
    declared = node.declared
    key_params = (
        set(declared.writes_keys) | set(declared.reads_keys) if declared is not None else set()
    )
    for pname, value in node.params.items():
        if isinstance(value, BlackboardRef) and value.key in names:
            node.params[pname] = BlackboardRef(names[value.key], value.field)
        elif isinstance(value, str) and pname in key_params:
            key, dot, field = value.partition(".")
            if key in names:
                node.params[pname] = names[key] + dot + field
    word = WORDS.get(node.kind)
    if word is not None and word.writes_key is not None:
        written = node.options.get(word.writes_key)
        if isinstance(written, str) and written in names:
            node.options[word.writes_key] = names[written]


def hidden_keys(
    subtree: str, own: Mapping[str, KeyDecl], outside: Mapping[str, KeyDecl], use: Loc
) -> list[Diagnostic]:
    """A warning at ``use`` for each of the subtree's own keys that hides a mission key of
    another type (as a parameter that hides one, docs/missions.md, Subtrees): ``@here`` in
    the body is the use's own, which the mission's writer may not expect. One of the same
    type is taken as meant."""
    return [
        use.at(
            f"subtree {subtree!r} has its own blackboard key {key!r} "
            f"({decl.type.describe()}), which hides the mission's {key!r} "
            f"({outside[key].type.describe()}) in its body: {key} there is each use's own; "
            "rename one of them if the body should read the mission's"
        ).as_warning()
        for key, decl in own.items()
        if key in outside and outside[key].type.describe() != decl.type.describe()
    ]
