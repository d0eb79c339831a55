"""The plan: the compiler's intermediate tree, what the YAML said, checked, with its place in
the file (kept as :attr:`CompiledMission.plan <roomba_bt.mission.build.CompiledMission.plan>`,
which builds the tree again for the next episode).

The parser builds it, the static checks (:mod:`roomba_bt.mission.checks`) walk it, and the
builder turns it into py_trees objects. Keeping it apart from py_trees means a mission is
fully checked before a single behaviour object exists.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.declare import Declaration
from roomba_bt.behaviours.units import ValueType
from roomba_bt.mission.source import Loc


@dataclass(eq=False)
class Node:
    """One node of the checked tree.

    A node that could not be built (its errors reported) stays in its place as an
    ``unbuilt`` node, so that the checks of the whole tree judge what was written around it
    in the same pass (a limit under a reactive fallback is still not its last child when a
    sibling after it is misspelt). It has no ``decl``, and of its parameters only the
    declared keys it writes (a ``set`` whose value alone was wrong): the checks that read a
    behaviour's parameters pass it by. ``partial`` is the behaviour it names when
    only its parameters were wrong: what it sends is known, so where it is reached is still
    judged (:mod:`roomba_bt.mission.checks`)."""

    kind: str  # "leaf", a word of behaviours.language.WORDS, "guard" or "unbuilt"
    loc: Loc
    name: str
    children: list[Node] = field(default_factory=list)
    decl: Declaration | None = None
    params: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    partial: Declaration | None = None
    #: what the node is, as its name says it without ``name:`` (``drive(velocity=500 mm/s,
    #: duration=10s)``), when ``name:`` replaced that; "" otherwise
    label: str = ""
    #: a composite's or decorator's options as the file writes them (``after=10min``),
    #: for ``show`` to say what the node does whatever its name; "" when none is written
    options_written: str = ""
    #: where the ``${parameter}`` is written that the name was made with (``name: "turn
    #: ${side}"``, a leaf's ``bump(${side})``, a guard's condition's): the name changes with
    #: the value, so ``selected:`` cannot pick the node by it; None: the name is fixed
    parameter_in_name: Loc | None = None
    #: the subtree use this node is the body of, with the arguments the use writes
    #: (``bump_recovery(angle=45deg)``), for ``show`` to draw every use one way; "" otherwise
    use: str = ""
    #: where that use is written (its ``subtree`` key): a key its body reads before it is
    #: written, passed down by the body it is used in, is said there (that body's line,
    #: :class:`~roomba_bt.mission.checks.KeyCheck`); None otherwise
    use_loc: Loc | None = None
    #: the names the use's own blackboard keys have (``go#1/here``: a subtree's own
    #: ``blackboard:``, :mod:`roomba_bt.mission.own_keys`), for ``show`` to say; () otherwise
    own_keys: tuple[str, ...] = ()

    @property
    def declared(self) -> Declaration | None:
        """The behaviour this node names, built (``decl``) or not (``partial``)."""
        return self.decl or self.partial

    def walk(self) -> Iterator[Node]:
        yield self
        for child in self.children:
            yield from child.walk()

    def keys_read(self) -> list[tuple[str, Loc]]:
        """Blackboard keys this leaf reads (``@key`` values and key-naming parameters; a
        record's field, ``check: {key: wp.distance}``, reads the key ``wp``)."""
        out: list[tuple[str, Loc]] = []
        if self.decl is None:
            return out
        for pname in self.decl.reads_keys:
            value = self.params.get(pname)
            if isinstance(value, str):
                key = value.partition(".")[0]
                out.append((key, self.options.get(f"loc:{pname}", self.loc)))
        for pname, value in self.params.items():
            if isinstance(value, BlackboardRef):
                out.append((value.key, self.options.get(f"loc:{pname}", self.loc)))
        return out

    def keys_written(self) -> list[str]:
        if self.decl is None:
            return []
        return [
            str(self.params[p])
            for p in self.decl.writes_keys
            if isinstance(self.params.get(p), str)
        ]


@dataclass(frozen=True, slots=True)
class KeyDecl:
    """A declared blackboard key."""

    name: str
    type: ValueType
    loc: Loc
    initial: Any = None
    has_initial: bool = False
    doc: str = ""
    #: where the initial value is written (the range check of its readers says it there)
    initial_loc: Loc | None = None


#: what separates a subtree's name from the number of its use in the name of a use's own
#: key (:func:`own_key_name`): no key a file declares has it (keys are snake_case), so no
#: use's key meets a mission's
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
