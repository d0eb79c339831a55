"""A subtree's own blackboard keys: each use's copy, named apart, and what it hides.

A subtree definition may declare ``blackboard:`` of its own (docs/missions.md, Subtrees). Its
body is parsed at each use with those keys under the names it writes (``here``), hiding a
mission key of that name (:meth:`OwnKeys.seen_in`); once parsed, every reference to them in
that body is renamed to the use's own name (:meth:`OwnKeys.at_use`: ``go#1/here``,
``go#2/here``, :func:`~roomba_bt.mission.plan.own_key_name`), which is then declared like a
mission key. So every check that follows keys (their types, the ranges of their readers,
``initial:``, parallel writers) and the run itself (the keys under ``/mission/``, written at
start, removed when the run is closed) see each use's keys as keys of their own, with
nothing of their own to learn. Renaming the plan, not resolving names at run time, keeps
the tick path as it was: a behaviour reads ``/mission/go#1/here`` as it reads
``/mission/leg``.

Read before written is judged in the body alone (:meth:`OwnKeys.checked`): nothing outside
it reads or writes its own keys, so the body decides it whole, and the error is the
subtree's own, found by ``validate`` of its library alone and said once, not at every use.

The bodies of the subtrees a body uses are not renamed with it: a body's own keys are its
alone (lexical scope), so a library's subtree used inside another cannot have its keys taken
by the caller's (each is renamed at its own use, before).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import replace

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.language import WORDS
from roomba_bt.mission.checks import KeyCheck
from roomba_bt.mission.diagnostics import SubtreeUse
from roomba_bt.mission.plan import KeyDecl, Node, own_key_name
from roomba_bt.mission.source import Bad, Loc
from roomba_bt.mission.values import UNKNOWN, Bound, Context, SubtreeDef, resolve


class OwnKeys:
    """The keys each body being parsed sees, and each use's own keys named and declared."""

    def __init__(self, ctx: Context) -> None:
        self.ctx = ctx
        #: the keys outside every subtree body being parsed (the mission's, and each use's
        #: own once renamed), which a body sees beneath its own; None: no body is parsed
        self._outside: dict[str, KeyDecl] | None = None
        #: the uses of each subtree with keys of its own so far, which number them
        self._uses: dict[str, int] = {}

    @property
    def outside(self) -> dict[str, KeyDecl]:
        """The keys outside every body: where a use's own are declared, once renamed."""
        return self.ctx.keys if self._outside is None else self._outside

    @contextmanager
    def seen_in(self, sub: SubtreeDef) -> Iterator[None]:
        """The keys ``sub``'s body sees while it is parsed (``ctx.keys``): those outside
        every body (the mission's), then its own by the names it writes, hiding a mission
        key of the same name; not the own keys of a body it is used in."""
        before, outside = self.ctx.keys, self._outside
        base = self.outside
        self._outside = base
        self.ctx.keys = {**base, **sub.keys} if sub.keys else base
        try:
            yield
        finally:
            self.ctx.keys, self._outside = before, outside

    def hidden(self, sub: SubtreeDef, use: Loc) -> None:
        """A warning at ``use`` for each of ``sub``'s own keys that hides a mission key of
        another type (as a parameter that hides one, docs/missions.md, Subtrees): ``@here``
        in the body is the use's own, which the mission's writer may not expect. One of the
        same type is taken as meant."""
        outside = self.outside
        for key, decl in sub.keys.items():
            if key not in outside or outside[key].type.describe() == decl.type.describe():
                continue
            warning = use.at(
                f"subtree {sub.name!r} has its own blackboard key {key!r} "
                f"({decl.type.describe()}), which hides the mission's {key!r} "
                f"({outside[key].type.describe()}) in its body: {key} there is each use's "
                "own; rename one of them if the body should read the mission's"
            ).as_warning()
            if warning not in self.ctx.warnings:
                self.ctx.warnings.append(warning)

    def checked(self, sub: SubtreeDef, body: Node | None) -> None:
        """Each of ``sub``'s own keys read in ``body`` (parsed, not yet renamed) before
        anything there writes it on some path, reported as an error of the body: its own
        keys are read and written nowhere else (a body it uses does not see them), and
        their ``initial:`` values are written before the run."""
        if body is None or not sub.keys:
            return
        check = KeyCheck(shown=lambda key: f"{key!r} (subtree {sub.name}'s own)")
        written = frozenset(key for key, decl in sub.keys.items() if decl.has_initial)
        check.run(body, written, judged=frozenset(sub.keys))
        for error in check.errors:
            self.ctx.error(error)

    def at_use(
        self, sub: SubtreeDef, body: Node, env: Mapping[str, Bound], use: SubtreeUse
    ) -> tuple[str, ...]:
        """``sub``'s own keys at this use, parsed into ``body``: each given the use's name,
        renamed so in the body and declared beside the mission's, where the checks and the
        run find them; an initial value that uses the subtree's parameters is the one
        ``env``, the use's, gives (and a finding about it names the use)."""
        number = self._uses[sub.name] = self._uses.get(sub.name, 0) + 1
        names = {key: own_key_name(sub.name, number, key) for key in sub.keys}
        outside = self.outside
        for key, full in names.items():
            decl = replace(sub.keys[key], name=full)
            if key in sub.initials:
                inode, iloc = sub.initials[key]
                try:
                    value = resolve(
                        self.ctx, inode, iloc, decl.type, env, f"initial value of {key}"
                    )
                except Bad as bad:
                    self.ctx.report(bad)
                    value = UNKNOWN
                decl = replace(decl, initial=value, initial_loc=iloc.used_at(use))
            outside[full] = decl
        renamed(body, names)
        return tuple(names.values())


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
