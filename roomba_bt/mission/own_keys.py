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
subtree's own, found by ``validate`` of its library alone and said once, not at every use;
a read in a subtree the body passes a key down to is said at the body's use of it
(:func:`passed_down`), the line of the body to fix.

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
from roomba_bt.mission.values import UNKNOWN, Bound, Context, KeyScope, SubtreeDef, resolve


class OwnKeys:
    """The keys each body being parsed sees, and each use's own keys named and declared."""

    def __init__(self, ctx: Context) -> None:
        self.ctx = ctx
        #: the keys outside every subtree body being parsed (the mission's, and each use's
        #: own once renamed), which a body sees beneath its own; None: no body is parsed
        self._outside: dict[str, KeyDecl] | None = None
        #: the uses of each subtree with keys of its own so far, which number them
        self._uses: dict[str, int] = {}
        self._mission: KeyScope | None = None

    @property
    def outside(self) -> dict[str, KeyDecl]:
        """The keys outside every body: where a use's own are declared, once renamed."""
        return self.ctx.keys if self._outside is None else self._outside

    @property
    def mission(self) -> KeyScope:
        """The mission's tree as a scope: where a key name a use there gives is looked up."""
        if self._mission is None:
            self._mission = KeyScope("", self.outside, frozenset(), self.outside)
        return self._mission

    def next_number(self, sub: SubtreeDef) -> int:
        """The number ``sub``'s use being parsed will have (:meth:`at_use` takes it): known
        before its body is, since no body uses its own subtree (recursion is refused)."""
        return self._uses.get(sub.name, 0) + 1

    @contextmanager
    def seen_in(self, sub: SubtreeDef) -> Iterator[KeyScope]:
        """The keys ``sub``'s body sees while it is parsed (``ctx.keys``, ``ctx.scope``):
        those outside every body (the mission's), then its own by the names it writes,
        hiding a mission key of the same name; not the own keys of a body it is used in,
        except by a name passed down as a parameter (:func:`~roomba_bt.mission.values.
        key_written_in`)."""
        before, outside, scope = self.ctx.keys, self._outside, self.ctx.scope
        base = self.outside
        self._outside = base
        self.ctx.keys = {**base, **sub.keys} if sub.keys else base
        parent = scope or self.mission
        self.ctx.scope = KeyScope(sub.name, self.ctx.keys, frozenset(sub.keys), base, parent)
        try:
            yield self.ctx.scope
        finally:
            self.ctx.keys, self._outside, self.ctx.scope = before, outside, scope

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
            self.ctx.warn(warning)

    def checked(self, sub: SubtreeDef, body: Node | None, scope: KeyScope, number: int) -> None:
        """``sub``'s own keys in ``body`` (parsed in ``scope``) given the names of its
        ``number``-th use (0: parsed alone, no use), there and where a body it uses was
        given one by name; then each read there before anything writes it on some path,
        reported as an error of the body: its own keys are read and written nowhere else,
        and their ``initial:`` values are written before the run. Said by the names the
        body writes (``'here' (subtree leg's own)``), alike at every use."""
        if body is None or not sub.keys:
            return
        names = {key: own_key_name(sub.name, number, key) for key in sub.keys}
        renamed(body, names, scope)
        check = KeyCheck(passed_down(body))
        written = frozenset(names[key] for key, decl in sub.keys.items() if decl.has_initial)
        check.run(body, written, judged=frozenset(names.values()))
        for error in check.errors:  # a read in a body it uses: said at that use, in this one
            self.ctx.error(replace(error, used_in=()))  # alone, not at one: the body's own

    def at_use(self, sub: SubtreeDef, env: Mapping[str, Bound], use: SubtreeUse) -> tuple[str, ...]:
        """``sub``'s own keys at this use (its body renamed by :meth:`checked`), each
        declared by the use's name beside the mission's, where the checks and the run find
        them; an initial value that uses the subtree's parameters is the one ``env``, the
        use's, gives (and a finding about it names the use)."""
        number = self._uses[sub.name] = self.next_number(sub)
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
        return tuple(names.values())


def passed_down(body: Node) -> dict[int, Node]:
    """Each leaf in the bodies of the subtrees ``body`` uses, by id, with the use in
    ``body`` it is reached through (the root of the body expanded there, which names its
    use: :attr:`Node.use_loc`). ``body``'s own root names none yet: its use is named after
    it is checked."""
    found: dict[int, Node] = {}
    stack: list[tuple[Node, Node | None]] = [(body, None)]
    while stack:
        node, use = stack.pop()
        use = use or (node if node.use_loc is not None else None)
        if use is not None and node.kind == "leaf":
            found[id(node)] = use
        stack.extend((child, use) for child in node.children)
    return found


def renamed(body: Node, names: Mapping[str, str], scope: KeyScope) -> None:
    """Each reference to a key of ``names`` in ``body`` (parsed in ``scope``) renamed as it
    says: ``@here``, ``set: {key: here}``, ``check: {key: here.x}``, ``for_each.key``, a
    plugin's key parameter. In the bodies of subtrees used in it (a node with ``use``:
    parsed, and their own keys renamed, where they are used) only the names given them by
    a parameter from this body (marked with ``scope``); here, none marked with another's
    (a name the mission's tree, or a body this one is used in, gave it)."""
    stack = [(body, False)]
    while stack:
        node, nested = stack.pop()
        _rename_node(node, names, scope, nested)
        stack.extend((child, nested or bool(child.use)) for child in node.children)


def _rename_node(node: Node, names: Mapping[str, str], scope: KeyScope, nested: bool) -> None:
    """``node``'s key references renamed by ``names``, each written in ``scope``: marked
    so (the node's ``scope:PARAMETER`` option), or unmarked (its body wrote the name) in
    a node of that body, not ``nested`` in a body it uses."""

    def ours(mark: object) -> bool:
        return mark is scope or (mark is None and not nested)

    declared = node.declared
    key_params = (
        set(declared.writes_keys) | set(declared.reads_keys) if declared is not None else set()
    )
    for pname, value in node.params.items():
        if not ours(node.options.get(f"scope:{pname}")):
            continue
        if isinstance(value, BlackboardRef) and value.key in names:
            node.params[pname] = BlackboardRef(names[value.key], value.field)
        elif isinstance(value, str) and pname in key_params:
            key, dot, field = value.partition(".")
            if key in names:
                node.params[pname] = names[key] + dot + field
    word = WORDS.get(node.kind)
    if word is not None and word.writes_key is not None:
        written = node.options.get(word.writes_key)
        ours_too = ours(node.options.get(f"scope:{word.writes_key}"))
        if ours_too and isinstance(written, str) and written in names:
            node.options[word.writes_key] = names[written]
