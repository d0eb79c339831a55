"""The node parser: one YAML node -> a checked :class:`~roomba_bt.mission.plan.Node`.

A node is a mapping with one word (a word of the language table, ``subtree``, or a
behaviour) plus modifiers (``name``, ``while``, ``until``). Composites and decorators are
parsed by :mod:`roomba_bt.mission.control`, behaviour leaves by
:mod:`roomba_bt.mission.leaves`; this module dispatches, wraps guards and expands subtrees.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import replace
from pathlib import Path

import yaml

from roomba_bt.behaviours.language import MODIFIERS, WORDS, Shape
from roomba_bt.behaviours.registry import Registry
from roomba_bt.behaviours.units import STR, closest
from roomba_bt.mission.control import parse_composite, parse_decorator
from roomba_bt.mission.diagnostics import Diagnostic, SubtreeUse
from roomba_bt.mission.foreign import foreign_hint, suggestion
from roomba_bt.mission.include_path import granted_files
from roomba_bt.mission.leaves import parse_leaf, written_text
from roomba_bt.mission.own_keys import OwnKeys
from roomba_bt.mission.plan import Node
from roomba_bt.mission.shipped import library_defining
from roomba_bt.mission.source import (
    Bad,
    Loc,
    empty_name,
    kind_of,
    mapping,
    plain,
    scalar_text,
)
from roomba_bt.mission.values import (
    UNKNOWN,
    Bound,
    Context,
    SubtreeDef,
    Written,
    as_written,
    given_to,
    name_text,
    origin_of,
    parameters_used,
    resolve,
    scope_of_argument,
    unknown,
    warn_escaped,
)
from roomba_bt.mission.wording import Wording
from roomba_bt.printable import path_written
from roomba_bt.yamlsource import NOT_PLAIN_SPACES, FileTooLarge, named_character, read_text

#: How deep a tree may nest, counted in nodes from the root, subtrees expanded. A mission
#: written by hand nests a dozen or so; a file nested hundreds deep (a generator gone wrong)
#: ran the parser, the checks and the tick out of Python's stack ("internal error ...
#: RecursionError" at about 250): it is refused at this depth instead (decided).
MAX_TREE_DEPTH = 100

#: what parsing a subtree's body alone found, errors or warnings (:meth:`NodeParser._alone`)
Findings = frozenset[Diagnostic]

#: How many nodes a compile may build, subtrees expanded where they are used (decided). The
#: largest shipped mission expands to 95 (``patrol``); a subtree that uses another twice, which
#: uses another twice, ... doubles at each level: 30 levels in a 1.9 KB file hung ``validate``
#: past 1.3 GB. Counted while expanding, so the blow-up stops here, not after.
MAX_TREE_NODES = 10_000


#: why a subtree's parameter takes no ``@key`` (BT.CPP's ``{key}`` port)
_FIXED = (
    ": a subtree's parameters are fixed when the mission is compiled, before any key holds a "
    "value; read the key inside the subtree (@key): keys are the whole mission's"
)


def _without_id(items: list[tuple[str, yaml.Node, Loc, Loc]], key_loc: Loc) -> Diagnostic:
    """``subtree needs id: NAME``; at a key that stands for it when there is one (BT.CPP's
    ``ID``), saying so."""
    for key, _, kloc, _ in items:
        hint = foreign_hint(key, ["id"])
        if hint is not None:
            return kloc.at(f"subtree needs id: NAME; found {key!r}{hint}")
    return key_loc.at("subtree needs id: NAME")


def _misplaced(
    known: tuple[str, yaml.Node, Loc, Loc], misplaced: list[tuple[str, yaml.Node, Loc, Loc]]
) -> Diagnostic:
    """``- drive:`` and then ``velocity: 200 mm/s`` at the indent of ``drive:``: YAML reads
    the parameters as keys of the node, beside its word. Each was "unknown node 'velocity'
    next to 'drive'" (and ``turn`` without them "missing required parameter 'angle'"): one
    error, at the first, saying to indent them (or to write them with the word's others)."""
    word, value, _, _ = known
    keys = [m[0] for m in misplaced]
    listed = " and ".join([", ".join(keys[:-1]), keys[-1]] if len(keys) > 1 else keys)
    are, them = ("are", "them") if len(keys) > 1 else ("is", "it")
    if value is None or (isinstance(value, yaml.ScalarNode) and value.tag.endswith(":null")):
        fix = f"indent {them} under `{word}:`"
    else:
        fix = f"write {them} in its mapping, `{word}: {{...}}`"
    return misplaced[0][2].at(f"{listed} {are} {word}'s, written at the node's level: {fix}")


def _mark_used(node: Node, uses: tuple[SubtreeUse, ...]) -> None:
    """Give ``node``, in a subtree's body expanded at ``uses`` (innermost first), those uses
    in its place (and in the places of its parameters, where a key is read): the checks'
    diagnostics about it say the use beside the definition's line
    (:attr:`Diagnostic.used_in`)."""
    node.loc = node.loc.used_at(*uses)
    for option, value in node.options.items():
        if isinstance(value, Loc):  # "loc:PARAMETER", the place Node.keys_read says
            node.options[option] = value.used_at(*uses)


class _UseMarks:
    """The subtree uses a tree's nodes were expanded at, given to them (:func:`_mark_used`)
    once each: a body parsed within another body's parse is noted on its root, and its
    nodes marked when the outermost use is done, or before a check of the parse reads the
    places under a child (``held``'s, a guard's). Marking each nested use's whole body at
    once made 30 levels of subtrees O(nodes x depth): 0.46 s of CPU where parsing took 0.2."""

    def __init__(self) -> None:
        #: by id, each body root not yet marked, with the uses it was expanded at (the
        #: innermost first: a root that is also the root of the body around it has both)
        self._pending: dict[int, tuple[Node, list[SubtreeUse]]] = {}

    def add(self, body: Node, use: SubtreeUse, *, outermost: bool) -> None:
        """``body`` expanded at ``use``; ``outermost``: within no other body's parse, so
        no use is added to it any more and its nodes are marked now."""
        self._pending.setdefault(id(body), (body, []))[1].append(use)
        if outermost:  # what is left after it is of trees given up (an error in them)
            self.marked(body)

    def marked(self, root: Node) -> Node:
        """``root``'s tree with the uses noted in it given to its nodes, each walked once."""
        stack: list[tuple[Node, tuple[SubtreeUse, ...]]] = [(root, ())]
        while stack:
            node, outer = stack.pop()
            _, uses = self._pending.pop(id(node), (node, []))
            chain = (*uses, *outer)  # a body's own use first, then the bodies around it
            if chain:
                _mark_used(node, chain)
            stack.extend((child, chain) for child in node.children)
        return root


class NodeParser:
    """Parses trees (the mission's, each subtree's at each use) within one :class:`Context`."""

    def __init__(self, ctx: Context) -> None:
        self.ctx = ctx
        #: the mission's parameters: what ``${name}`` sees outside (and under) subtrees
        self.global_env: dict[str, Bound] = {}
        self._use_stack: list[str] = []
        #: nodes from the root to the one being parsed (:data:`MAX_TREE_DEPTH`)
        self._depth = 0
        self._too_deep = False
        #: nodes built so far (:data:`MAX_TREE_NODES`) and the subtree uses being expanded,
        #: innermost last: where the count goes over is reported at the use that made it
        self._count = 0
        self._uses: list[Loc] = []
        self._too_many = False
        #: each subtree's findings parsed alone (:meth:`_alone`), once a use has some
        self._alone_found: dict[tuple[str, bool], tuple[Findings, Findings]] = {}
        #: the folders the mission may include from: an unknown subtree's library is sought
        self.granted: tuple[Path, ...] = ()
        #: the uses each subtree body was expanded at, given to its nodes once
        self.uses = _UseMarks()
        #: the keys each body sees, and each use's own keys (a subtree's ``blackboard:``)
        self.own_keys = OwnKeys(ctx)

    def node(self, ynode: yaml.Node, loc: Loc, env: Mapping[str, Bound]) -> Node | None:
        """Parse one node; errors are recorded and None returned for a node that cannot be
        built (its parent goes on with the other children)."""
        if self._over_count(loc):
            return None
        if self._depth >= MAX_TREE_DEPTH:
            if not self._too_deep:  # said once: every node below it is as deep
                self._too_deep = True
                self.ctx.error(
                    loc.at(
                        f"the tree nests more than {MAX_TREE_DEPTH} nodes deep here; at most "
                        f"{MAX_TREE_DEPTH} are allowed (a file generated wrong?)"
                    )
                )
            return None
        self._depth += 1
        try:
            return self._node(ynode, loc, env)
        except Bad as bad:
            self.ctx.report(bad)
            return None
        finally:
            self._depth -= 1

    def _over_count(self, loc: Loc) -> bool:
        """Count one more node; True (said once, at the innermost subtree use, else at the
        node) once the tree has more than :data:`MAX_TREE_NODES`: nothing more is built."""
        if self._too_many:
            return True
        self._count += 1
        if self._count <= MAX_TREE_NODES:
            return False
        self._too_many = True
        where = self._uses[-1] if self._uses else loc
        cut = where.at(
            f"the tree grows past {MAX_TREE_NODES:,} nodes here (subtrees are expanded where "
            f"they are used, so a subtree using another several times multiplies it); at "
            f"most {MAX_TREE_NODES:,} are allowed (a file generated wrong?)"
        )
        self.ctx.stops.append(cut)  # listed among the first, as it explains those after
        self.ctx.error(cut)
        return True

    def _node(self, ynode: yaml.Node, loc: Loc, env: Mapping[str, Bound]) -> Node | None:
        if isinstance(ynode, yaml.ScalarNode):
            word = plain(ynode, loc)
            if not isinstance(word, str):
                raise Bad(loc.at(f"expected a node, got {kind_of(ynode)}"))
            return self._word(word, Written(None, loc, loc.child(ynode, word), env))
        if not isinstance(ynode, yaml.MappingNode):
            raise Bad(
                loc.at(f"expected a node (a mapping such as drive: {{...}}), got {kind_of(ynode)}")
            )
        items = mapping(ynode, loc, "a node")
        words = [(k, v, kl, vl) for k, v, kl, vl in items if k not in MODIFIERS]
        mods = {k: (v, kl, vl) for k, v, kl, vl in items if k in MODIFIERS}
        if not words:
            found = f"only {', '.join(mods)}" if mods else "an empty mapping"
            raise Bad(loc.at(f"a node needs a kind (such as sequence, drive, bump); found {found}"))
        kind = self._kind(words)
        stray = len(words) > 1  # unknown words beside it: reported, the node is not built
        try:
            built = None if kind is None else self._word(kind[0], Written(*kind[1:], env))
        except Bad as bad:  # an unknown word, say: its guards still checked, in the same pass
            self.ctx.report(bad)
            built = None
        if built is None:
            self._guards(mods, env)
            return None
        if "name" in mods:
            name_loc = mods["name"][2]
            written = scalar_text(mods["name"][0], name_loc, "name")
            name, uses_parameter = name_text(written, name_loc, env)
            warn_escaped(self.ctx, written, mods["name"][0], name_loc, None, "name")
            if not name.strip():  # the log said "t=1.005 INFO roomba_bt.run:  -> SUCCESS"
                self.ctx.error(name_loc.at(empty_name("name", name, built.name)))
            built.parameter_in_name = name_loc if uses_parameter else None
            if name != built.name:
                built.label, built.name = built.name, name
        for guard, gkloc, condition in self._guards(mods, env):
            built = Node("guard", gkloc, f"{guard} {condition.name}", [condition, built],
                         options={"until": guard == "until"},
                         parameter_in_name=condition.parameter_in_name)  # fmt: skip
        return None if stray else built

    def _guards(
        self, mods: Mapping[str, tuple[yaml.Node, Loc, Loc]], env: Mapping[str, Bound]
    ) -> list[tuple[str, Loc, Node]]:
        """The node's ``until`` and ``while`` conditions, each parsed and checked (made of
        conditions), with its key's place; also for a node that could not be built (an
        unknown word: a plugin not installed), whose guards were not checked at all."""
        guards = []
        for guard in ("until", "while"):
            if guard in mods:
                gnode, gkloc, gvloc = mods[guard]
                condition = self.node(gnode, gvloc, env)
                if condition is not None:
                    self._check_guard(self.uses.marked(condition), guard)
                    guards.append((guard, gkloc, condition))
        return guards

    def _kind(
        self, words: list[tuple[str, yaml.Node, Loc, Loc]]
    ) -> tuple[str, yaml.Node, Loc, Loc] | None:
        """The node's one kind among the keys that are no modifier. Beside exactly one known
        word, each unknown one (a misspelt ``untill``) is reported and the known word is still
        parsed, so that its own errors (``velocty``) come in the same pass; :class:`Bad` when
        none or several are known. None when the word's own parameters stand beside it
        (:meth:`_misplaced`): said once, the word not parsed without them."""
        if len(words) == 1:
            return words[0]
        names = [w[0] for w in words]
        known = [w for w in words if w[0] in WORDS or w[0] in self.ctx.registry]
        if len(known) != 1:
            raise Bad(
                words[1][2].at(
                    f"a node has exactly one kind; found {', '.join(names)} "
                    "(put several nodes in a sequence)"
                )
            )
        own = self._parameter_names(known[0][0])
        misplaced = [w for w in words if w[0] in own]
        if misplaced:
            self.ctx.error(_misplaced(known[0], misplaced))
        for other in words:
            if other is not known[0] and other not in misplaced:
                where = f" next to {known[0][0]!r}"
                self.ctx.error(other[2].at(self._unknown_word(other[0], other[2], where)))
        return None if misplaced else known[0]

    def _parameter_names(self, word: str) -> set[str]:
        """What ``word`` takes in its value: a behaviour's parameters, a language word's
        options (and its ``children:``, ``do:`` or ``id:``)."""
        kind = WORDS.get(word)
        if kind is None:
            decl = self.ctx.registry.get(word)
            return {p.name for p in decl.params} if decl is not None else set()
        value_keys = {Shape.CHILDREN: "children", Shape.SUBTREE: "id"}.get(kind.shape, "do")
        return {value_keys, *(p.name for p in kind.options)}

    #: at most this many broken plugins are noted beside an unknown node
    _PLUGIN_NOTES = 3

    def _unknown_word(self, word: str, at: Loc, where: str = "") -> str:
        unloaded = self.ctx.unloaded_plugins
        if unloaded:  # most likely theirs: no "did you mean" a built-in of another name
            files = ", ".join(path_written(text) for text in unloaded)
            return f"unknown node {word!r}{where} (the plugin file {files} was not loaded)"
        unread = self.ctx.unread_include_note(at)
        if unread is not None and self.ctx.registry.why_unknown(word) is None:
            return f"unknown node {word!r}{where} ({unread})"  # its plugins: were not read
        # the plugins that may have meant this word: one that declares it (a class refused
        # for its declaration: the cause, not a misspelling), else
        # those that did not import at all (any name could have been theirs); a few, not
        # every broken plugin on the machine (one line of more than 1,000 characters)
        likely, declares = self.ctx.registry.may_have_meant(word)
        message = f"unknown node {word!r}{where}"
        unspaced = _missing_space(word, self.ctx.registry)
        if unspaced is not None:  # before "no plugin package 'mode'": the likelier cause
            return f"{message}: {unspaced}"
        qualified = self.ctx.registry.why_unknown(word)  # package:name, said by its package
        if qualified is not None:
            return f"{message}: {qualified}"
        absent = self.ctx.registry.absent  # plugins the mission was made with, not here
        if absent and not declares:  # theirs, most likely: no "did you mean" a built-in
            return f"{message} (perhaps of {'; '.join(absent)})"
        if not declares:  # a misspelling, perhaps: not when a plugin is known to declare it
            meant = suggestion(word, [*WORDS, *self.ctx.registry.names(), *MODIFIERS])
            message += meant + _subtree_meant(word) + ("" if meant else _WHAT_IS_ALLOWED)
        if likely:
            failed = "; ".join(str(e) for e in likely[: self._PLUGIN_NOTES])
            more = len(likely) - self._PLUGIN_NOTES
            if more > 0:
                failed += f"; and {more} more (roomba-bt behaviours lists them)"
            message += f" (note: {failed})"
        return message

    def _check_guard(self, condition: Node, guard: str) -> None:
        for n in condition.walk():
            decl = n.declared
            if decl is not None and decl.kind == "action":
                self.ctx.error(
                    n.loc.at(f"{guard}: a guard is made of conditions; {decl.name!r} is an action")
                )

    def _word(self, word: str, at: Written) -> Node | None:
        kind = WORDS.get(word)
        if kind is None:
            decl = self.ctx.registry.get(word)
            if decl is None:
                raise Bad(at.key_loc.at(self._unknown_word(word, at.key_loc)))
            clash = self.ctx.registry.clash(word)
            if clash is not None:
                severity, why = clash
                if severity == "error":
                    raise Bad(at.key_loc.at(why))
                warning = at.key_loc.at(why).as_warning()
                self.ctx.warn(warning)
            return parse_leaf(self.ctx, decl, at)
        if kind.shape is Shape.CHILDREN:
            return parse_composite(self, kind, at)
        if kind.shape is Shape.SUBTREE:
            return self._use_subtree(at)
        return parse_decorator(self, kind, at)

    def _use_subtree(self, at: Written) -> Node | None:
        """``subtree: NAME`` or ``subtree: {id: NAME, parameter: value}``: the subtree's
        body compiled here, with its parameters bound."""
        value, key_loc, loc, env = at.value, at.key_loc, at.loc, at.env
        if value is None:
            raise Bad(key_loc.at("subtree needs a name: subtree: NAME or subtree: {id: NAME, ...}"))
        args: list[tuple[str, yaml.Node, Loc, Loc]] = []
        if isinstance(value, yaml.MappingNode):
            items = mapping(value, loc, "subtree")
            ids = [i for i in items if i[0] == "id"]
            if not ids:
                raise Bad(_without_id(items, key_loc))
            name = scalar_text(ids[0][1], ids[0][3], "subtree id")
            id_loc = ids[0][3]
            args = [i for i in items if i[0] != "id"]
        else:
            name = scalar_text(value, loc, "subtree")
            id_loc = loc
        sub = self.ctx.subtrees.get(name)
        used = parameters_used(name)
        if sub is None and used:  # not "unknown subtree '${x}'"
            if used[0] not in env:
                hint = closest(used[0], list(env))
                raise Bad(id_loc.at(f"subtree id: unknown parameter ${{{used[0]}}}{hint}"))
            raise Bad(id_loc.at(
                f"subtree id: a subtree's name is written as it is; ${{{used[0]}}} is not "
                "replaced there (name the subtree)"
            ))  # fmt: skip
        if sub is None:
            hint = _unknown_subtree_hint(self.ctx, name, id_loc, self.granted)
            raise Bad(id_loc.at(f"unknown subtree {name!r}{hint}"))
        if name in self._use_stack:
            chain = self._use_stack[self._use_stack.index(name) :]
            raise Bad(id_loc.at(f"recursive subtree: {' -> '.join([*chain, name])}"))
        sub.used = True
        if sub.written_wrongly:  # its definition's error is the one to fix
            return None
        sub_env = self._subtree_env(sub, args, key_loc, env)
        self.own_keys.hidden(sub, key_loc)
        use = SubtreeUse(key_loc.file, key_loc.line, key_loc.column, name, key_loc.path)
        body = self._body_at(sub, sub_env, use, key_loc)
        if body is None:
            return None
        if body.name == body.kind and body.kind != "leaf":
            body.name = name
        if sub.keys:
            body.own_keys = self.own_keys.at_use(sub, sub_env, use)
        self.uses.add(body, use, outermost=not self._uses)
        # show draws the use with what it was given, whatever the body
        given = ", ".join(f"{p}={written_text(n, env, lists=True)}" for p, n, _, _ in args)
        body.use = f"{name}({given})" if given else name
        body.use_loc = key_loc
        return body

    def _body_at(
        self, sub: SubtreeDef, env: Mapping[str, Bound], use: SubtreeUse, key_loc: Loc
    ) -> Node | None:
        """``sub``'s body parsed at ``use`` (at ``key_loc``) with ``env``; each error in it
        the body's own (its file alone has it) or caused by ``use`` (Diagnostic.used_at);
        each warning too, except that one in a body written in the use's file names the use
        (at the body's line: :func:`~roomba_bt.mission.diagnostics.said_at_use`)."""
        if sub.body is None:
            return None
        self._use_stack.append(sub.name)
        self._uses.append(key_loc)
        try:
            with self.ctx.collecting() as (errors, warnings), self.own_keys.seen_in(sub) as scope:
                body = self.node(sub.body, sub.body_loc, env)
                self.own_keys.checked(sub, body, scope, self.own_keys.next_number(sub))
        finally:
            self._use_stack.pop()
            self._uses.pop()
        if errors:
            own = self._alone(sub, with_mission=True)[0]
            for error in errors:
                self.ctx.error(error if error in own else error.used_at(use))
        if warnings:  # a library's own (its file alone warns of it) said once as it is
            library = sub.body_loc.file != use.file
            own = self._alone(sub, with_mission=False)[1] if library else frozenset()
            for warning in warnings:
                said = warning if warning in own else warning.used_at(use)
                self.ctx.warn(said)
        return body

    def _alone(self, sub: SubtreeDef, *, with_mission: bool) -> tuple[Findings, Findings]:
        """The errors and warnings ``sub``'s body has parsed alone, as ``validate`` of its
        file checks it (its defaults, unknown values for the parameters without one; and
        ``with_mission``, the mission's): its own, wrong at every use; one a use's body has
        beyond these the use caused (a value it gave, a key or a mission parameter it names).
        Parsed once each way, when a use first has findings in its body."""
        own = self._alone_found.get((sub.name, with_mission))
        if own is None:
            counted = self._count
            with self.ctx.collecting() as (errors, warnings):
                self._parse_alone(sub, self.global_env if with_mission else {})
            self._count = counted  # what the use's own parse counted, not twice
            own = self._alone_found[sub.name, with_mission] = frozenset(errors), frozenset(warnings)
        return own

    def _parse_alone(self, sub: SubtreeDef, mission: Mapping[str, Bound]) -> None:
        """``sub``'s body parsed without a use (:func:`_alone_env`), ``mission`` the
        parameters it sees beside its own."""
        assert sub.body is not None  # a use found something in it, or it is unused
        self._use_stack.append(sub.name)
        try:
            with self.own_keys.seen_in(sub) as scope:
                env = _alone_env(sub, mission, self.ctx.wording)
                self.own_keys.checked(sub, self.node(sub.body, sub.body_loc, env), scope, 0)
        finally:
            self._use_stack.pop()

    def _subtree_env(
        self,
        sub: SubtreeDef,
        args: list[tuple[str, yaml.Node, Loc, Loc]],
        key_loc: Loc,
        env: Mapping[str, Bound],
    ) -> dict[str, Bound]:
        """The mission's parameters, then the subtree's: given at the use or by default."""
        name = sub.name
        sub_env = dict(self.global_env)
        for pname in sub.broken:
            sub_env[pname] = Bound(STR, UNKNOWN, "?")
        for pname, pvalue, pkloc, pvloc in args:
            if pname in sub.broken:
                continue
            if pname not in sub.params:
                # one declared wrongly is still declared: it was "known: none" beside it
                declared = [*sub.params, *sorted(sub.broken)]
                self.ctx.error(
                    pkloc.at(f"subtree {name!r}: " + unknown("parameter", pname, declared))
                )
                continue
            vtype = sub.params[pname][0]
            try:
                resolved = resolve(self.ctx, pvalue, pvloc, vtype, env, f"{name}.{pname}",
                                   no_ref=_FIXED)  # fmt: skip
            except Bad as bad:
                self.ctx.report(bad)
                resolved = UNKNOWN
            sub_env[pname] = Bound(
                vtype,
                resolved,
                as_written(vtype, resolved, pvalue, env) if resolved is not UNKNOWN else "?",
                origin_of(pvalue, env) or given_to(pvalue, pvloc, name),
                scope=scope_of_argument(self.ctx, pvalue, env, self.own_keys.mission),
            )
        for warning in _shadowed(sub, self.global_env, key_loc):
            self.ctx.warn(warning)
        given = {a[0] for a in args}
        for pname, (vtype, default, _) in sub.params.items():
            if pname in given:
                continue
            if default is None:
                self.ctx.error(key_loc.at(f"subtree {name!r} needs parameter {pname!r}"))
                sub_env[pname] = Bound(vtype, UNKNOWN, "?")
            else:
                sub_env[pname] = _by_default(sub, pname, self.ctx.wording)
        return sub_env

    def check_unused_subtrees(self) -> None:
        """Check subtrees no tree uses (library files), with unknown values for parameters
        that have no default, so their errors are found before someone uses them."""
        for sub in list(self.ctx.subtrees.values()):
            if sub.used or sub.body is None:
                continue
            sub.used = True
            self._parse_alone(sub, self.global_env)


#: What an unknown node's error says is allowed when no known word is close to it (``unknown
#: node 'wander'`` alone says nothing of where the words are listed).
_WHAT_IS_ALLOWED = "; roomba-bt behaviours lists the actions and conditions there are"


def _subtree_meant(word: str) -> str:
    """A word that names a subtree of the shipped library (``dock``, ``undock``): what uses
    it, beside the "did you mean" (``dock`` is the firmware's ``seek_dock`` there, where a
    reader of ``roomba-bt run dock`` means the docking subtree that mission uses)."""
    library = library_defining(word)
    if library is None:
        return ""
    used = f"include: [{library}] and subtree: {{id: {word}}}"
    return f"; or, for the subtree the shipped missions use: {used}"


def _missing_space(word: str, registry: Registry) -> str | None:
    """What is wrong with ``mode:safe`` or ``mode safe`` (a node's word and its value
    written as one text: YAML needs ``: ``, a colon and a plain space), or None. The
    commonest beginner's mistake; ``mode:safe`` read as ``package:name`` sent students
    looking for a plugin package called ``mode``."""
    for separator in (":", " "):
        name, found, rest = word.partition(separator)
        if not found or not (name in WORDS or name in registry):
            continue
        value = rest.lstrip(NOT_PLAIN_SPACES + " ")
        if separator == " ":
            return f"write a colon and a space after the word: `{name}: {value}`"
        odd = rest[:1]
        if odd and odd in NOT_PLAIN_SPACES:  # a no-break space pasted from a web page
            return (
                f"{named_character(odd)} after the colon is no space to YAML: write a "
                f"plain space: `{name}: {value}`"
            )
        return f"{word!r} is one text to YAML: write a space after the colon: `{name}: {value}`"
    return None


def _alone_env(sub: SubtreeDef, mission: Mapping[str, Bound], wording: Wording) -> dict[str, Bound]:
    """The parameters ``sub``'s body sees when it is checked without a use: the
    ``mission``'s, then each of its own by its default, unknown without one."""
    env = dict(mission)
    for pname in sub.broken:
        env[pname] = Bound(STR, UNKNOWN, "?")
    for pname, (vtype, default, _) in sub.params.items():
        env[pname] = (
            Bound(vtype, UNKNOWN, "?") if default is None else _by_default(sub, pname, wording)
        )
    return env


def _by_default(sub: SubtreeDef, pname: str, wording: Wording) -> Bound:
    """Subtree parameter ``pname`` bound to its default: an error its value makes names
    the default's place and how a use gives another (``speed: VALUE at the use``)."""
    vtype, default, _ = sub.params[pname]
    at_use = replace(wording, give_template="{name}: {value} at the use")
    at, items = sub.default_at.get(pname, (None, ()))
    return Bound(
        vtype, default, sub.default_texts[pname], default_at=at, default_items=items,
        wording=at_use,
    )  # fmt: skip


#: at most this many subtrees are listed after ``unknown subtree`` (a renamed one)
SUBTREES_LISTED = 12


def _unknown_subtree_hint(ctx: Context, name: str, at: Loc, granted: Iterable[Path]) -> str:
    """What follows ``unknown subtree NAME``: that an include was not read (its subtrees
    are unknown, so a "did you mean" or the shipped library's name would send the user the
    wrong way), else a close name, else the shipped library file that defines it, else the
    granted files that define one of that name (an include forgotten), else the subtrees
    known (one renamed), the first :data:`SUBTREES_LISTED`."""
    note = ctx.unread_include_note(at)
    if note is not None:
        return f" ({note})"
    hint = closest(name, list(ctx.subtrees))
    library = None if hint else library_defining(name)
    if hint or library is not None:  # the shipped docking subtree, used without its include
        return hint or f" (the shipped {library} defines it: include: [{library}])"
    defining = _files_defining_once(ctx, name, granted, at.file)
    if defining:
        files = " and ".join(defining)
        return f" ({files} define{'s' if len(defining) == 1 else ''} it: include it)"
    known = sorted(ctx.subtrees)
    if not known:
        return ""
    more = len(known) - SUBTREES_LISTED
    said = ", ".join(known[:SUBTREES_LISTED]) + (f" and {more:,} more" if more > 0 else "")
    return f"; known: {said}"


#: a subtree's definition in a library's text: its name as a key, indented under subtrees:
_SUBTREES_SECTION = re.compile(r"^subtrees\s*:", re.MULTILINE)


#: the unknown subtree names a compile looks for in the granted folders' files (the errors
#: past the first hundred are not shown: a file of 100,000 unknown subtrees read the
#: folder's files for each)
HINTS_LOOKED_UP = 20


def _files_defining_once(ctx: Context, name: str, granted: Iterable[Path], using: str) -> list[str]:
    """:func:`_files_defining`, once a name and for at most :data:`HINTS_LOOKED_UP` names a
    compile (``ctx.files_defining``); none for the names past them."""
    memo = ctx.files_defining
    if name not in memo:
        memo[name] = [] if len(memo) >= HINTS_LOOKED_UP else _files_defining(name, granted, using)
    return memo[name]


def _files_defining(name: str, granted: Iterable[Path], using: str, limit: int = 3) -> list[str]:
    """Up to ``limit`` YAML files of the ``granted`` folders (:func:`granted_files`) with a
    ``subtrees:`` section that has a key ``name`` (read as text: a hint, not a compile),
    each named from the working folder as diagnostics name files, ``using`` left out."""
    key = re.compile(rf"^[ \t]+{re.escape(name)}[ \t]*:", re.MULTILINE)
    found: list[str] = []
    for path in granted_files(granted):
        if len(found) >= limit:
            break
        if path.suffix not in (".yaml", ".yml"):
            continue
        try:
            # a pipe named *.yaml in the folder hung the compile in open() (a device such as
            # /dev/zero linked there was read without end): regular files only, 1 MiB at most
            if not path.is_file():
                continue
            text = read_text(path)
        except (OSError, UnicodeDecodeError, FileTooLarge):  # a file not to read: no hint
            continue
        shown = Path(os.path.relpath(path)).as_posix()
        if shown != using and _SUBTREES_SECTION.search(text) and key.search(text):
            found.append(shown)
    return found


def _shadowed(sub: SubtreeDef, mission: Mapping[str, Bound], use: Loc) -> list[Diagnostic]:
    """A warning at ``use`` for each of ``sub``'s parameters that hides one of the
    ``mission``'s of another type (a library's ``laps: distance`` in a mission with ``laps:
    int``): ``${laps}`` in the body is the subtree's, which the mission's writer may not
    expect. One of the same type is no surprise (the subtree's wins, as documented)."""
    return [
        use.at(
            f"subtree {sub.name!r} has its own parameter {pname!r} ({vtype.describe()}), "
            f"which hides the mission's {pname!r} ({mission[pname].type.describe()}) in its "
            f"body: ${{{pname}}} there is the subtree's; rename one of them if the body "
            "should read the mission's"
        ).as_warning()
        for pname, (vtype, _, _) in sub.params.items()
        if pname in mission and mission[pname].type.name != vtype.name
    ]
