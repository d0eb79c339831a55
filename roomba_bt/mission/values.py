"""Values in a mission: ``${parameter}`` substitution (``$$`` is one literal ``$``, as in
Python's ``string.Template``), ``@key`` references, units and ranges, and what one
compilation shares (:class:`Context`).

Every value a mission writes goes through :func:`resolve`: the loader for parameter
defaults and initial blackboard values, the node parser for options and behaviour
parameters.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import yaml

from roomba_bt.behaviours.actions import NOTES
from roomba_bt.behaviours.blackboard import BLACKBOARD_REF, BlackboardRef
from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.registry import Registry
from roomba_bt.behaviours.units import (
    MARK,
    STR,
    VALUE_TYPES,
    BareNumber,
    ItemErrors,
    UnitError,
    ValueType,
    closest,
    compatible,
    convert,
    enum_misfits,
    percent_sign_kept,
    shown,
    with_article,
)
from roomba_bt.mission.diagnostics import Diagnostic, Later
from roomba_bt.mission.foreign import port_remapping, suggestion
from roomba_bt.mission.plan import KeyDecl, is_own_key
from roomba_bt.mission.source import Bad, Loc, mapping, plain, scalar_text, sequence
from roomba_bt.mission.wording import PYTHON, Wording
from roomba_bt.printable import MAX_FOUND, path_written
from roomba_bt.yamlsource import quoted, yaml12_number_problem

_FULL_SUBSTITUTION = re.compile(r"^\s*(-?)\$\{([A-Za-z_][A-Za-z0-9_]*)\}\s*$")
#: What a text's ``$`` may start, read left to right, by Python's ``string.Template`` rule
#: (which users know): ``$$``, one literal ``$`` anywhere (so ``$${x}`` is the text ``${x}``,
#: and ``$$${x}`` a ``$`` and then x's value: a price); ``${name}``, a parameter (group 1);
#: or a ``${`` that starts neither, unterminated or not a name (group 1 None): an error in
#: a value. A ``$`` before anything else is itself. (0.1.0 read ``$${x}`` as a ``$`` and
#: x's value: :func:`escaped_parameters` warns where a mission may mean that.)
_PLACEHOLDER = re.compile(r"\$\$|\$\{(?:([A-Za-z_][A-Za-z0-9_]*)\})?")
_DOLLAR = "$$"
#: a parameter's ``{name}`` right after a ``$$``: the text ``${name}``
_BRACED_NAME = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")
#: said with every error about a ``${``: the text may have meant one literally
ESCAPE_HINT = 'a literal "${" is written "$${"'


def substituted(text: str, text_of: Callable[[str], str | None]) -> str:
    """``text`` with each ``$$`` as ``$`` and each ``${name}`` as ``text_of(name)`` (kept
    as written where that is None: a description or a name shown names an unknown
    parameter as it was written); a ``${`` that starts no parameter is kept as it is
    (:func:`_substitute` refuses it first where a value is resolved)."""

    def replaced(match: re.Match[str]) -> str:
        whole, name = match.group(0), match.group(1)
        if whole == _DOLLAR:
            return "$"
        value = None if name is None else text_of(name)
        return whole if value is None else value

    return _PLACEHOLDER.sub(replaced, text)


def parameters_used(text: str) -> list[str]:
    """The names of the parameters ``text`` uses, read as :func:`substituted` reads it: the
    ``x`` of ``$$${x}``, not that of ``$${x}`` (the text ``${x}``)."""
    return [m.group(1) for m in _PLACEHOLDER.finditer(text) if m.group(1) is not None]


def escaped_parameters(text: str, names: Collection[str]) -> list[tuple[int, str]]:
    """Each ``$${name}`` in ``text`` whose name is one of ``names`` (the parameters in
    scope): its place and the name. The text ``${name}`` now, it was a ``$`` and the value
    in 0.1.0, and such a mission validates and runs with another text than its author's:
    what :func:`escape_warning` says."""
    found = []
    for match in _PLACEHOLDER.finditer(text):
        if match.group(0) == _DOLLAR:
            braced = _BRACED_NAME.match(text, match.end())
            if braced is not None and braced.group(1) in names:
                found.append((match.start(), braced.group(1)))
    return found


def escape_warning(where: Loc, what: str, name: str) -> Diagnostic:
    """The warning of a ``$${name}`` naming a parameter (:func:`escaped_parameters`), with
    both answers: the spelling of a ``$`` and the value, and ``literal:`` for the text. The
    file to say it in is named: a warning a mission's use causes in a library's subtree is
    said at the use, in the mission, and ``literal:`` belongs at the top of the library."""
    return where.at(
        f'{what}: "$${{{name}}}" is the text "${{{name}}}"; a "$" before the value is written '
        f'"$$${{{name}}}" (in 0.1.0, "$${{{name}}}" was a "$" and then the value); if the '
        f"text is meant, say so at the top of {where.file}: literal: [{name}]"
    ).as_warning()


def read_literal(ctx: Context, node: yaml.Node, loc: Loc) -> None:
    """A file's ``literal: [laps]``: in that file, ``$${laps}`` is meant as the text
    ``${laps}``, and :func:`escape_warning` is not said of it. ``$${`` is the only way to
    write a literal ``${``, so without this a mission that means the text warned on every
    run and could never pass ``--strict``. By name, not for the whole file: another
    ``$${name}`` there, written for 0.1.0, is still said."""
    names: dict[str, Loc] = {}
    try:
        entries = sequence(node, loc, "literal")
    except Bad as bad:
        ctx.report(bad)
        return
    for item, iloc in entries:
        try:
            name = scalar_text(item, iloc, "literal")
        except Bad as bad:
            ctx.report(bad)
            continue
        if _BRACED_NAME.fullmatch(f"{{{name}}}") is None:
            ctx.error(
                iloc.at(
                    f"literal: {name!r} is no parameter name (an ASCII letter or _, then "
                    "ASCII letters, digits or _): list the names of ${name} meant as text"
                )
            )
            continue
        names.setdefault(name, iloc)
    ctx.literal[loc.file] = names


def check_literal_names(ctx: Context, mission_parameters: Collection[str]) -> None:
    """Each file's ``literal:`` names against the parameters its texts can name: the
    mission's and those of the subtrees the file defines. Any other name was taken without
    a word, and a misspelt ``literal: [lpas]`` left ``$${laps}`` warned of with no hint
    why. Not for a file with a subtree refused as written: its parameters are unknown."""
    defined_in: dict[str, set[str]] = {}
    unknown_in: set[str] = set()
    for sub in ctx.subtrees.values():
        defined_in.setdefault(sub.loc.file, set()).update(sub.params, sub.broken)
        if sub.written_wrongly:
            unknown_in.add(sub.loc.file)
    for file, names in ctx.literal.items():
        if file in unknown_in:
            continue
        allowed = sorted({*mission_parameters, *defined_in.get(file, ())})
        said = (
            f"{', '.join(allowed)} (the mission's parameters and those of the subtrees this "
            "file defines)"
            if allowed
            else "none: neither the mission nor a subtree this file defines has a parameter"
        )
        for name, at in names.items():
            if name not in allowed:
                ctx.error(
                    at.at(
                        f"literal: found {name!r}, no parameter in scope in this file"
                        f"{closest(name, allowed)}; allowed: {said}"
                    )
                )


#: Two dollars alone (no ``$`` before or after them) and before anything but a ``{``: one
#: ``$`` now, two in 0.1.0, where no ``$`` was special outside ``${name}``. A 0.1.0 author
#: meant the two they saw; one written for 0.2.0 never needs them, a lone ``$`` before
#: anything else being itself. A longer run (``$$$$``: two now) or ``$$${x}`` (a ``$`` and
#: the value) is the only spelling of what it says now, so it is not warned of: a warning
#: with no way to avoid it would be said on every run of a mission that is right.
_LONE_DOUBLED = re.compile(r"(?<!\$)\$\$(?![$\{])")


def doubled_dollars(text: str) -> list[int]:
    """Where in ``text`` each ``$$`` is that read ``$$`` in 0.1.0 and reads ``$`` now,
    with nothing a 0.2.0 author needs it for (:data:`_LONE_DOUBLED`)."""
    return [match.start() for match in _LONE_DOUBLED.finditer(text)]


def doubled_warning(where: Loc, what: str, text: str, offset: int) -> Diagnostic:
    """The warning of a ``$$`` at ``offset`` of ``text`` (:func:`doubled_dollars`): what
    was found, with the character after it, what it reads now, and both spellings."""
    after = text[offset + 2 : offset + 3]
    return where.at(
        f'{what}: "$${after}" reads "${after}" since 0.2.0 ("$$" is one "$", as in Python\'s '
        f'string.Template); in 0.1.0 it read "$${after}": write "${after}" for one "$", or '
        f'"$$$${after}" to keep two'
    ).as_warning()


def warn_escaped(
    ctx: Context,
    text: str,
    node: yaml.Node,
    loc: Loc,
    names: Collection[str] | None,
    what: str,
) -> None:
    """Add to ``ctx.warnings`` what changed meaning in ``text`` (``node``'s, at ``loc``)
    since 0.1.0: an :func:`escape_warning` for each ``$${name}`` naming one of ``names``
    (None: a ``name:``, which 0.1.0 showed as written, substituting nothing) and a
    :func:`doubled_warning` for each lone ``$$``; each at its own column where the text is
    written on one line as it reads; once, however often the text is resolved (a subtree
    used twice)."""

    def at(offset: int) -> Loc:
        return _character_at(node, loc, text, offset)

    said = [
        (offset, doubled_warning(at(offset), what, text, offset))
        for offset in doubled_dollars(text)
    ]
    meant = ctx.literal.get(loc.file, {})
    said += [
        (offset, escape_warning(at(offset), what, name))
        for offset, name in escaped_parameters(text, names or ())
        if name not in meant
    ]
    for _, warning in sorted(said, key=lambda each: each[0]):
        ctx.warn(warning)


def _character_at(node: yaml.Node, loc: Loc, text: str, offset: int) -> Loc:
    """Where character ``offset`` of ``text``, the value of ``node`` (at ``loc``), is in the
    file: exact when the scalar is written on one line, plain or quoted, with no escape or
    folding (its length in the file is the text's, plus its quotes); else where it starts."""
    if isinstance(node, yaml.ScalarNode) and node.start_mark.line == node.end_mark.line:
        quotes = 1 if node.style in ('"', "'") else 0
        if node.end_mark.column - node.start_mark.column == len(text) + 2 * quotes:
            return Loc(loc.file, loc.line, loc.column + quotes + offset, loc.path)
    return loc


def _stray_opening(text: str) -> int | None:
    """Where in ``text`` the first ``${`` is that is neither a parameter nor after a
    ``$$``."""
    for match in _PLACEHOLDER.finditer(text):
        if match.group(0) != _DOLLAR and match.group(1) is None:
            return match.start()
    return None


def unknown(
    what: str, name: str, known: list[str], owner: str | None = None, hint: str | None = None
) -> str:
    """``unknown parameter 'velocty' (did you mean 'velocity'?); known: ...``; ``owner``:
    the word whose option or parameter it is, for the hints of
    :func:`~roomba_bt.mission.foreign.suggestion` (a modifier inside a value, BT.CPP's
    ``num_attempts``), which names of the mission's own (keys, fields) never get; ``hint``:
    the caller's own, where it knows better than a spelling's likeness."""
    listing = ", ".join(known) if known else "none"
    if hint is None:
        hint = closest(name, known) if owner is None else suggestion(name, known, owner)
    return f"unknown {what} {name!r}{hint}; known: {listing}"


class UnknownNames:
    """:func:`unknown`'s messages for names of one place (a leaf's parameters, a word's
    options), each with its "did you mean" left for when it is shown
    (:class:`~roomba_bt.mission.diagnostics.Later`; give both to ``Loc.at``): a file may
    hold thousands of them. The list of known names is said once for them all (a leaf of
    68,000 unknown parameters joined it 68,000 times)."""

    def __init__(self, what: str, known: list[str], owner: str | None = None) -> None:
        self.what, self.known, self.owner = what, known, owner
        self._listing = f"; known: {', '.join(known) if known else 'none'}"

    def __call__(self, name: str) -> tuple[str, Later]:
        said = f"unknown {self.what} {name!r}"
        return said + self._listing, Later(said, partial(self._part, name))

    def _part(self, name: str) -> str:
        if self.owner is None:
            return closest(name, self.known)
        return suggestion(name, self.known, self.owner)


class _Unknown:
    """The value of a subtree parameter with no default, when an unused subtree is checked."""

    def __repr__(self) -> str:
        return "<unknown>"


UNKNOWN: Any = _Unknown()


@dataclass(frozen=True, slots=True)
class Bound:
    """A parameter in scope: its type, canonical value and the text it was written as; and
    where its value was set when that was not beside its use (``origin``, said with an
    error at the use: "time_limit=0s, set on the command line")."""

    type: ValueType
    value: Any
    text: str
    origin: str = ""
    #: where the default is written, for a mission parameter that has its default (none
    #: given with -p): an error its value makes at a use names the parameter and that place,
    #: and how to give another (:func:`said_default`); not ``origin``, which a subtree's
    #: argument passes on in place of the use that gave it
    default_at: Loc | None = None
    #: of a list parameter bound to its default: where each item of the default is written,
    #: where a ``for_each`` item out of its readers' range is said (not at the ``in:``)
    default_items: tuple[Loc, ...] = ()
    #: how the caller gives a parameter another value (said with ``default_at``)
    wording: Wording = PYTHON
    #: the blackboard keys seen where a subtree argument's value was written (the body
    #: that gives it, or the mission): a key name passed down is that body's key, not one
    #: the body it reaches sees (:func:`key_written_in`); None: the body it is used in
    scope: KeyScope | None = None


@dataclass(eq=False)
class KeyScope:
    """The blackboard keys one subtree body sees by the names it writes while it is parsed:
    the mission's (``outside``), its own hiding them (``own``). A key name passed into a
    body it uses (``measure: {out: here}``, read there as ``key: "${out}"``) is looked up
    here, where it was written, as BT.CPP's SubTree remaps a port to the caller's key
    (docs/missions.md, A subtree's own keys). Compared by identity: one per body parsed."""

    subtree: str  # "" for the mission's
    keys: Mapping[str, KeyDecl]
    own: frozenset[str]
    outside: Mapping[str, KeyDecl]
    #: the body this one is used in (None: the mission's tree)
    parent: KeyScope | None = None


#: a node's mark for a key name written in the mission's tree, not the body it is in
MISSION_SCOPE = "mission"

#: a whole ``${name}``, or ``${name}.field``: a key name a parameter passes
_PASSED_KEY = re.compile(r"^\s*\$\{([A-Za-z_][A-Za-z0-9_]*)\}(\.[A-Za-z_][A-Za-z0-9_]*)?\s*$")


def key_written_in(
    ctx: Context, node: yaml.Node | None, env: Mapping[str, Bound]
) -> tuple[Mapping[str, KeyDecl], KeyScope | str | None]:
    """The keys a key name written as ``node`` is looked up in, and the scope it names a
    key of when that is not the body being parsed (the mark the use that renames its keys
    reads: :func:`roomba_bt.mission.own_keys.renamed`), else None. A name that is a text
    parameter's value alone (``"${out}"``, ``"${out}.x"``) is one of the keys seen where
    that value was written (:attr:`Bound.scope`), as is ``"@${out}"``'s; any other is
    this body's."""
    here = ctx.scope
    text = getattr(node, "value", None)
    text = text.strip().removeprefix("@") if isinstance(text, str) else None
    passed = _PASSED_KEY.match(text) if text is not None else None
    bound = None if passed is None else env.get(passed.group(1))
    if here is None or bound is None or bound.type is not STR or bound.scope in (None, here):
        return ctx.keys, None
    if not bound.scope.subtree:  # the mission's tree wrote it: its keys, none of a body's
        return here.outside, MISSION_SCOPE
    return bound.scope.keys, bound.scope


def scope_of_argument(
    ctx: Context, node: yaml.Node, env: Mapping[str, Bound], outside: KeyScope
) -> KeyScope:
    """Where a subtree argument's value was written, for a key name it may be: the body
    (or the mission's tree, ``outside``) that gives it, or, passed on as a whole
    ``${name}``, where that parameter's value was written (a default, or a mission
    parameter: the body passing it on)."""
    here = ctx.scope or outside
    text = getattr(node, "value", None)
    passed = _FULL_SUBSTITUTION.match(text) if isinstance(text, str) else None
    bound = None if passed is None else env.get(passed.group(2))
    return bound.scope if bound is not None and bound.scope is not None else here


def unseen_own_key(ctx: Context, key: str) -> str:
    """After "unknown blackboard key 'here'" in a subtree's body: that a body it is used in
    declares one of its own of that name, which its subtrees do not see, and how to pass it
    (a text parameter); "" when none does."""
    name = key.partition(".")[0]
    scope = ctx.scope.parent if ctx.scope is not None else None
    while scope is not None and name not in scope.own:
        scope = scope.parent
    if scope is None or ctx.scope is None:
        return ""
    sub = ctx.scope.subtree
    return (
        f" (subtree {scope.subtree}'s own key {name!r} is not seen in the subtrees it uses: "
        f"pass its name down as a text parameter, parameters: {{out: {{type: str}}}} in "
        f"{sub}, subtree: {{id: {sub}, out: {name}}} at the use, and name the key "
        f'"${{out}}" in {sub})'
    )


@dataclass(frozen=True, slots=True)
class Written:
    """A word as the file writes it: its value, where the word and the value are, and the
    parameters in scope there."""

    value: yaml.Node | None
    key_loc: Loc
    loc: Loc
    env: Mapping[str, Bound]


@dataclass(slots=True)
class SubtreeDef:
    name: str
    loc: Loc
    params: dict[str, tuple[ValueType, Any, Loc]]  # name -> (type, default or None, loc)
    body: yaml.Node | None
    body_loc: Loc
    used: bool = False
    #: parameters declared wrongly (reported there): unknown values at every use
    broken: frozenset[str] = frozenset()
    #: the definition itself was refused (reported there): its uses compile to nothing and
    #: say nothing more, its parameters being unknown
    written_wrongly: bool = False
    #: each default as the library writes it (``10min``), the text a use that gives none
    #: names its nodes with
    default_texts: Mapping[str, str] = field(default_factory=dict)
    #: where each default is written: an error its value makes in the body names it
    #: (:func:`said_default`), as a mission parameter's; and where each item of a list's
    #: default is (:attr:`Bound.default_items`)
    default_at: Mapping[str, tuple[Loc, tuple[Loc, ...]]] = field(default_factory=dict)
    #: its own ``blackboard:``, by the names its body writes: keys of each use's own,
    #: renamed at each use (``NodeParser``: ``go#1/here``), hiding the mission's there
    keys: Mapping[str, KeyDecl] = field(default_factory=dict)
    #: the ``initial:`` of each of its own keys that uses one of its parameters, with its
    #: place: resolved at each use, with the values that use gives
    initials: Mapping[str, tuple[yaml.Node, Loc]] = field(default_factory=dict)


class FoundEnough(Exception):
    """A compilation found :data:`~roomba_bt.printable.MAX_FOUND` errors: no more are looked
    for (a file of 100,000 duplicate keys listed 100,000, as a world of as many problems
    did); the compiler says where it stopped."""


@dataclass
class Context:
    """Everything one compilation shares."""

    registry: Registry
    diagnostics: list[Diagnostic] = field(default_factory=list)
    #: how the messages say what the caller grants and sets (``Permissions.wording``)
    wording: Wording = PYTHON
    keys: dict[str, KeyDecl] = field(default_factory=dict)
    #: the keys of the subtree body being parsed by the names it writes, with those of the
    #: bodies it is used in (:class:`KeyScope`); None: the mission's tree
    scope: KeyScope | None = None
    subtrees: dict[str, SubtreeDef] = field(default_factory=dict)
    #: plugin files named but not loaded (no --allow-plugin-files, or not found): an unknown
    #: word may be one of theirs
    unloaded_plugins: list[str] = field(default_factory=list)
    #: includes refused or not read (each its text and place): a subtree, key or node not
    #: found may be one of theirs, and its error says so (:meth:`unread_include_note`)
    unread_includes: list[tuple[str, Loc]] = field(default_factory=list)
    #: what compiles but is likely a mistake, found while parsing (a plugin's behaviour of a
    #: built-in's name): the compiled mission's warnings, with the whole-tree checks' own
    warnings: list[Diagnostic] = field(default_factory=list)
    #: each file's ``literal:`` names, by the file as its places name it: the ``$${name}``
    #: written there that mean the text ``${name}``, not warned of (:func:`read_literal`)
    #: each name with where it is written, for :func:`check_literal_names`
    literal: dict[str, dict[str, Loc]] = field(default_factory=dict)
    #: where a check stopped before the file's end (the tree cut at ``MAX_TREE_NODES``): a
    #: command lists it among the first it lists, wherever it sorts (``compiler._pinned``)
    stops: list[Diagnostic] = field(default_factory=list)
    #: ``diagnostics`` as a set: an error is reported once, and looking it up in the list
    #: made N errors cost N**2/2 comparisons (20,000 aliases took 40 s to validate)
    _reported: set[Diagnostic] = field(default_factory=set, init=False, repr=False)
    #: ``warnings`` as a set, for the same reason: 16,000 YAML 1.1 numbers (``1_0``, four
    #: bytes each) took 44 s to validate, and a file of 1 MiB holds 260,000
    _warned: set[Diagnostic] = field(default_factory=set, init=False, repr=False)
    #: the files that define each unknown subtree's name, by the name (``nodes``'s hint,
    #: which reads the granted folders' files): looked up once a name, and for at most
    #: ``HINTS_LOOKED_UP`` names a compile (100,000 unknown subtrees read the folder's
    #: files 100,000 times)
    files_defining: dict[str, list[str]] = field(default_factory=dict, init=False, repr=False)

    def error(self, diagnostic: Diagnostic) -> None:
        """One more error; :class:`FoundEnough` at :data:`~roomba_bt.printable.MAX_FOUND`."""
        reported = self._reported
        before = len(reported)
        reported.add(diagnostic)  # one hash a diagnostic, not two (in, then add)
        if len(reported) != before:
            self.diagnostics.append(diagnostic)
            if len(self.diagnostics) >= MAX_FOUND:
                raise FoundEnough

    def warn(self, diagnostic: Diagnostic) -> None:
        """One more warning, kept once; past :data:`~roomba_bt.printable.MAX_FOUND` of them
        none is kept (the check goes on for errors): the compiler keeps as many as it says
        (:func:`~roomba_bt.mission.compiler._kept`), and says where they stopped."""
        warned = self._warned
        if len(warned) > MAX_FOUND:
            return
        before = len(warned)
        warned.add(diagnostic)
        if len(warned) != before:
            self.warnings.append(diagnostic)

    def said(self, diagnostics: list[Diagnostic]) -> None:
        """What reading a file said: its errors, and its warnings once each (a file
        included twice is read twice)."""
        for diagnostic in diagnostics:
            if diagnostic.severity != "warning":
                self.error(diagnostic)
            else:
                self.warn(diagnostic)

    #: at most this many unread includes are named in one note
    _UNREAD_NAMED = 2

    def unknown_key(self, key: str, at: Loc, keys: Mapping[str, KeyDecl] | None = None) -> str:
        """``unknown blackboard key 'legs' ...``: after a failed include, that it may be
        one of the include's; else that a body this one is used in has its own of that
        name (:func:`unseen_own_key`); else a close name and the keys known (``keys``, where
        the name was written: ``ctx.keys`` unless a parameter passed it)."""
        note = self.unread_include_note(at)
        if note is not None:
            return f"unknown blackboard key {key!r} ({note})"
        unseen = unseen_own_key(self, key) if keys is None else ""
        if unseen:
            return f"unknown blackboard key {key!r}{unseen}"
        # a use's own keys (``go#1/here``) are no name a file writes: not offered
        known = [k for k in (self.keys if keys is None else keys) if not is_own_key(k)]
        # none at all: what is allowed is a key declared, said (it was "known: none" alone)
        hint = (
            None
            if known
            else (
                f" (declare it with its type under blackboard:, {{{key}: TYPE}}, a type such as "
                "distance, int or mark)"
            )
        )
        return unknown("blackboard key", key, known, hint=hint)

    def unread_include_note(self, at: Loc) -> str | None:
        """What an unknown name at ``at`` follows from when an include was not read, instead
        of a "did you mean" that sends the user the wrong way (``unknown subtree 'undock'
        (did you mean 'dock'?)`` when a refused library defined ``undock``); None when every
        include was read."""
        unread = self.unread_includes
        if not unread:
            return None
        if len(unread) == 1:
            text, loc = unread[0]
            return (
                f"the include of {path_written(text)} at {_line_of(loc, at)} failed, and may have "
                "defined it"
            )
        named = [
            f"{path_written(text)} ({_line_of(loc, at)})"
            for text, loc in unread[: self._UNREAD_NAMED]
        ]
        more = len(unread) - len(named)
        listed = ", ".join(named) + (f" and {more} more" if more else "")
        return f"the includes of {listed} failed, and may have defined it"

    @contextmanager
    def collecting(self) -> Iterator[tuple[list[Diagnostic], list[Diagnostic]]]:
        """The errors and the warnings said within the ``with``, collected apart (into the
        two lists it gives), not said: a subtree's body parsed at a use, whose findings the
        use may have caused (:meth:`NodeParser.node`'s caller decides where each is said)."""
        said, reported, warned = self.diagnostics, self._reported, self.warnings
        warned_set = self._warned
        self.diagnostics, self._reported, self.warnings, self._warned = [], set(), [], set()
        try:
            yield self.diagnostics, self.warnings
        finally:
            self.diagnostics, self._reported, self.warnings = said, reported, warned
            self._warned = warned_set

    def report(self, bad: Bad) -> None:
        """A :class:`Bad`'s diagnostic and those raised with it (each key of a mapping that
        is no name, on its own line)."""
        for diagnostic in (bad.diagnostic, *bad.more):
            self.error(diagnostic)


def _line_of(loc: Loc, at: Loc) -> str:
    """Where ``loc`` is, said from ``at``: ``line 5`` in the same file, else ``file:5``."""
    return f"line {loc.line}" if loc.file == at.file else f"{loc.file}:{loc.line}"


def parse_type_name(
    node: yaml.Node, loc: Loc, *, allow_mark: bool = False, also: tuple[str, ...] = ()
) -> ValueType:
    """The value type ``node`` names; ``also``: names the caller handles itself (a
    parameter's ``enum``), listed among the known ones when the name is not known."""
    text = scalar_text(node, loc, "type")
    vtype = VALUE_TYPES.get(text)
    if vtype is None or (vtype is MARK and not allow_mark):
        names = [n for n in VALUE_TYPES if allow_mark or n != "mark"] + list(also)
        if text in PARAMETER_ONLY_TYPES:  # "unknown" would send one to look for a typo
            raise Bad(loc.at(
                f"{text!r} is a parameter type, not a key type: {PARAMETER_ONLY_TYPES[text]}; "
                f"key types: {', '.join(names)}"
            ))  # fmt: skip
        raise Bad(
            loc.at(f"unknown type {text!r}{closest(text, names)}; known types: {', '.join(names)}")
        )
    return vtype


#: the types a parameter is declared with by a name alone: the value types but ``mark`` (only
#: the ``mark`` action writes one), and a song's ``notes``
PARAMETER_TYPES: dict[str, ValueType] = {
    **{name: vtype for name, vtype in VALUE_TYPES.items() if vtype is not MARK},
    "notes": NOTES,
}
#: every word a parameter's ``type:`` may be: ``enum`` with its ``choices:``, ``list`` with
#: its ``items:`` (:func:`roomba_bt.mission.loader.param_decl`)
PARAMETER_TYPE_NAMES: tuple[str, ...] = (*PARAMETER_TYPES, "enum", "list")
#: the parameter types a blackboard key (or a record's field) cannot be, and what to write
#: instead: each is more than one value, or words only a parameter declares
PARAMETER_ONLY_TYPES: dict[str, str] = {
    "list": "a key holds one value: declare a parameter {type: list, items: TYPE} and give "
    "it to for_each.in, whose key holds each item in turn",
    "notes": "a key holds one value: declare a parameter {type: notes} and give it to song.notes",
    "enum": "its choices are declared on a parameter {type: enum, choices: [...]}; a key "
    "holds a word as str",
}
#: the option a parameter's type is declared with beside ``type:``: the type that reads it
#: (and needs it), and what that type is; validate (the loader's ``_declared_type``) and the
#: JSON Schema (schema.py) both read it, so they refuse the same declarations
PARAMETER_TYPE_OPTIONS: dict[str, tuple[str, str]] = {
    "choices": ("enum", "a closed set of words"),
    "items": ("list", "a list of values of one type"),
}
#: what a list parameter's ``items:`` may be: one value each (a song is a list already)
LIST_ITEM_TYPES: dict[str, ValueType] = {
    name: vtype for name, vtype in PARAMETER_TYPES.items() if vtype is not NOTES
}


def record_type(fields: dict[str, ValueType]) -> ValueType:
    """A mapping with typed fields: a waypoint ``{distance: 1 m, turn: 90deg}``."""

    def parse(value: object) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise UnitError(f"expected a mapping with {', '.join(fields)}")
        unknown = [k for k in value if k not in fields]
        if unknown:
            raise UnitError(
                f"unknown field {unknown[0]!r}{closest(str(unknown[0]), list(fields))}; "
                f"fields: {', '.join(fields)}"
            )
        missing = [k for k in fields if k not in value]
        if missing:
            raise UnitError(f"missing field {missing[0]!r}; fields: {', '.join(fields)}")
        out = {}
        for k, t in fields.items():
            try:
                out[k] = t.parse(value[k])
            except UnitError as exc:
                raise UnitError(f"field {k}: {exc}") from None
        return out

    return ValueType(
        "record", parse, json_schema=(("type", "object"),), fields=tuple(fields.items())
    )


def record_fields(vtype: ValueType) -> dict[str, ValueType] | None:
    return dict(vtype.fields) if vtype.name == "record" else None


def _negate(value: Any) -> Any:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return -value
    raise UnitError("only a number can be negated")


def resolve(
    ctx: Context,
    node: yaml.Node,
    loc: Loc,
    vtype: ValueType,
    env: Mapping[str, Bound],
    what: str,
    *,
    param: Param | None = None,
    allow_ref: bool = False,
    no_ref: str = "",
    keys: Mapping[str, KeyDecl] | None = None,
) -> Any:
    """One value of type ``vtype``: ``${param}`` substituted, ``@key`` resolved to a
    :class:`BlackboardRef` (where allowed), units parsed, range checked. Raises :class:`Bad`.
    ``no_ref``: why a blackboard value is not allowed here, said when one is written.
    ``keys``: those an ``@key`` names one of, where not ``ctx.keys`` (a key name passed
    down, :func:`key_written_in`)."""
    fields = record_fields(vtype)
    if fields is not None and isinstance(node, yaml.MappingNode):
        return _record(ctx, node, loc, fields, env, what)
    if vtype.item is not None and isinstance(node, yaml.SequenceNode):
        return _items(ctx, node, loc, vtype.item, env, what)
    raw = plain(node, loc)
    passed_on: str | None = None  # a text parameter's value: where it was set, if said
    if isinstance(raw, str):
        full = _FULL_SUBSTITUTION.match(raw)
        if full is not None:
            negative, pname = full.groups()
            bound = env.get(pname)
            if bound is None:
                hint = _not_a_parameter(ctx, pname, env, allow_ref, no_ref)
                raise Bad(loc.at(_unknown_parameter(what, pname, hint, loc)))
            if bound.value is UNKNOWN:
                return UNKNOWN
            if compatible(bound.type, vtype):
                return _filled(pname, bound, negative, vtype, (loc, what, param))
            if bound.type.name != "str" or vtype.item is not None or vtype is NOTES:
                raise Bad(loc.at(f"{what}: {_misfit(pname, bound.type, vtype, what)}"))
            raw = ("-" if negative else "") + str(bound.value)
            passed_on = _where_set(pname, bound, loc)
        elif "$" in raw:  # a parameter, a stray "${", or "$$" (one "$")
            warn_escaped(ctx, raw, node, loc, env, what)
            raw = _substitute(raw, loc, env, what)
            if raw is UNKNOWN:
                return UNKNOWN
        if raw.startswith("@") or (port_remapping(raw) and vtype.name not in ("str", "any")):
            return _reference(ctx, raw, loc, vtype, what, (allow_ref, no_ref), keys)
    if passed_on is not None:
        return _text_parameter_read(raw, vtype, (loc, what, param, node), passed_on)
    parsed = _parsed(vtype, raw, loc, what, param, node)
    return _check_range(parsed, loc, what, param, written=raw if isinstance(raw, str) else "")


def _filled(
    pname: str,
    bound: Bound,
    negative: str,
    vtype: ValueType,
    at: tuple[Loc, str, Param | None],
) -> Any:
    """The value of parameter ``pname`` (``bound``, of a type that fills ``vtype``) at a
    whole ``${pname}`` (``-${pname}`` when ``negative``) at ``at`` (where, the slot's name
    and its parameter): converted, negated, its range checked, an error naming where the
    value was set or its default."""
    loc, what, param = at
    value = convert(bound.type, vtype, bound.value)
    if negative:
        try:
            value = _negate(value)
        except UnitError as exc:
            raise Bad(loc.at(f"{what}: {exc}")) from None
    origin = f" (${{{pname}}} is {bound.origin})" if bound.origin else ""
    if not origin and param is not None and param.check_range(value) is not None:
        origin = said_default(pname, bound, loc, _in_range(pname, bound, param, negative))
    return _check_range(value, loc, what, param, origin)


def _where_set(pname: str, bound: Bound, loc: Loc) -> str:
    """Where a text parameter's value was set, said with an error the slot it fills finds
    in it (read by the slot's type there, not where it was set: ``-p color=blue`` is
    "(${color} is color=blue, set on the command line)"); "" where that is the use."""
    if bound.origin:
        return f" (${{{pname}}} is {bound.origin})"
    return said_default(pname, bound, loc)


def _text_parameter_read(
    raw: Any, vtype: ValueType, at: tuple[Loc, str, Param | None, yaml.Node], passed_on: str
) -> Any:
    """A text parameter's value ``raw`` read by the slot of ``vtype`` at ``at`` (where, its
    name, its parameter and the node that names the parameter): its error ends with where
    the value was set (``passed_on``)."""
    loc, what, param, node = at
    raw = _text_read(raw, vtype)
    try:
        parsed = _parsed(vtype, raw, loc, what, param, node)
        return _check_range(parsed, loc, what, param, written=raw if isinstance(raw, str) else "")
    except Bad as bad:
        if not passed_on:
            raise
        said = bad.diagnostic
        raise Bad(replace(said, message=said.message + passed_on), bad.more) from None


#: a whole number written as a text: what a text parameter may hold for a slot of numbers
_INTEGER_TEXT = re.compile(r"\s*[-+]?[0-9]+\s*")


def _text_read(text: str, vtype: ValueType) -> object:
    """A text parameter's value as a slot of ``vtype`` reads it: a whole number as the
    number when the slot takes integers (``-p color=200`` for ``leds.power_color``, whose
    refusal of the text promised "a number 0..255"), as the number written in the file
    would be; anything else the text."""
    takes_integers = vtype.name in ("int", "float") or "int" in vtype.takes
    return int(text) if takes_integers and _INTEGER_TEXT.fullmatch(text) else text


def _list_declared(target: ValueType) -> str:
    """How a parameter that fills a list slot of ``target`` type is declared, or why none
    can (a record's items: write the list there)."""
    if target is NOTES:
        return "declare the parameter {type: notes}"
    item = target.item
    assert item is not None  # a list's slot, or NOTES
    fields = record_fields(item)
    if fields is not None:  # waypoints: the key's record, field by field
        said = ", ".join(f"{name}: {ftype.name}" for name, ftype in fields.items())
        return f"declare the parameter {{type: list, items: {{fields: {{{said}}}}}}}"
    if LIST_ITEM_TYPES.get(item.name) is not item:
        return f"no list parameter holds items of {item.describe()}: write the list here"
    return f"declare the parameter {{type: list, items: {item.name}}}"


def _type_said(vtype: ValueType) -> str:
    """A type as a misfit says it: a record (a list's items too) with its fields, since two
    records are told apart by them alone (``list of record {distance: distance, turn:
    angle}``: waypoints with a speed do not fill a key without one)."""
    if vtype.item is not None:
        return f"list of {_type_said(vtype.item)}"
    fields = record_fields(vtype)
    if fields is None:
        return vtype.describe()
    return f"record {{{', '.join(f'{name}: {ftype.name}' for name, ftype in fields.items())}}}"


def _misfit(pname: str, source: ValueType, target: ValueType, what: str) -> str:
    """Why parameter ``pname`` of type ``source`` cannot fill ``what`` (of type ``target``):
    the types, and for an enum the words the slot does not read, with why the first is not."""
    said = f"parameter ${{{pname}}} is {with_article(_type_said(source))}, but {what}"
    if source is STR and (target.item is not None or target is NOTES):
        return f"{said} takes a list, never read from a text: {_list_declared(target)}"
    misfits = enum_misfits(source, target) if source.choices else []
    if not misfits:
        return f"{said} needs {_type_said(target)}"
    words = ", ".join(repr(word) for word, _ in misfits)
    return (
        f"{said} does not take {words} ({misfits[0][1]}): an enum fills a slot when each of "
        "its choices is a value the slot takes"
    )


def number_as_text_problem(node: yaml.Node | None, number: float) -> str | None:
    """What is wrong with a plain number written where a text is meant when the text it
    makes shows other digits than the file (``1.10`` is the float 1.1, ``0x1F`` 31, ``1.5e3``
    1500.0), or None (``3``, ``2.5``). Refused, as ``0200`` and ``1:30`` are (decided: never
    a number other than the digits shown): a version ``1.10`` was logged as ``1.1``."""
    written = str(getattr(node, "value", ""))
    if not written or str(number) == written:
        return None
    if isinstance(node, yaml.ScalarNode) and yaml12_number_problem(node) is not None:
        return None  # 1_000, 0b11: warned of already (a text to YAML 1.2, decided)
    return (
        f"{quoted(written)} is read by YAML as the number {number}, not as written: quote it "
        f'where a text is meant ("{written}")'
    )


def _item_locs(node: yaml.Node, loc: Loc, raw: object) -> list[Loc] | None:
    """Where each item of a list value is, when ``raw`` is the list the file wrote there
    (not one a parameter gave): what an item's error is said at."""
    if isinstance(node, yaml.SequenceNode) and isinstance(raw, list):
        return [loc.child(item, f"[{i}]") for i, item in enumerate(node.value)]
    return None


def _not_a_parameter(
    ctx: Context, name: str, env: Mapping[str, Bound], allowed: bool, no_ref: str
) -> str:
    """What follows "unknown parameter ${x}": that x is a blackboard key (BT.CPP's script
    ``${key}``) and how a key is read here, else difflib's guess among the parameters."""
    if name in ctx.keys:
        return f": {name!r} is a blackboard key, and {_reference_here(ctx, name, allowed)}{no_ref}"
    return closest(name, list(env))


def _reference_here(ctx: Context, key: str | None, allowed: bool) -> str:
    """How a blackboard value of ``key`` is written, or that none is allowed here."""
    if not allowed:
        return "a blackboard value (@key) is not allowed here"
    declared = "" if key in ctx.keys else f" (no key {key!r} is declared)"
    return f'a blackboard value is written "@{key}" here{declared}'


def _parsed(
    vtype: ValueType,
    raw: object,
    loc: Loc,
    what: str,
    param: Param | None,
    node: yaml.Node | None = None,
) -> Any:
    """``raw`` in ``vtype``'s unit; a bare number's hint names the unit that puts it in the
    parameter's range (``max_radius: 1`` is ``1m``, not ``1mm``). Items of a list that do
    not parse are each said at their own place in ``node`` (the value as written), all of
    them."""
    if vtype is STR and isinstance(raw, int | float) and not isinstance(raw, bool):
        other_digits = number_as_text_problem(node, raw)
        if other_digits is not None:
            raise Bad(loc.at(f"{what}: {other_digits}"))
    try:
        return vtype.parse(raw)
    except BareNumber as exc:
        if param is not None:
            exc.within(param.minimum, param.maximum)
        raise Bad(loc.at(f"{what}: {exc}")) from None
    except ItemErrors as exc:
        items = None if node is None else _item_locs(node, loc, raw)
        if items is None or len(items) != exc.count:
            raise Bad(loc.at(f"{what}: {exc}")) from None
        first, *more = (
            items[i].at(f"{what}: {exc.said(i, problem)}") for i, problem in exc.problems
        )
        raise Bad(first, tuple(more)) from None
    except UnitError as exc:
        raise Bad(loc.at(f"{what}: {exc}")) from None


def _record(
    ctx: Context,
    node: yaml.Node,
    loc: Loc,
    fields: dict[str, ValueType],
    env: Mapping[str, Bound],
    what: str,
) -> dict[str, Any]:
    """A record written as a mapping: every field, each resolved with its own type."""
    given = {k: (v, vl) for k, v, _, vl in mapping(node, loc, what)}
    unknown_fields = [k for k in given if k not in fields]
    if unknown_fields:
        name = unknown_fields[0]
        raise Bad(loc.at(f"{what}: " + unknown("field", name, list(fields))))
    missing = [k for k in fields if k not in given]
    if missing:
        raise Bad(loc.at(f"{what}: missing field {missing[0]!r}; fields: {', '.join(fields)}"))
    return {
        k: resolve(ctx, given[k][0], given[k][1], t, env, f"{what}.{k}") for k, t in fields.items()
    }


def _items(
    ctx: Context,
    node: yaml.SequenceNode,
    loc: Loc,
    item: ValueType,
    env: Mapping[str, Bound],
    what: str,
) -> Any:
    """A list written as a list, for a list parameter: each item resolved with the item
    type (so an item may be a ``${parameter}``), every bad one said at its own place."""
    values, bad = [], []
    for index, each in enumerate(node.value):
        try:
            values.append(resolve(ctx, each, loc.child(each, f"[{index}]"), item, env, what))
        except Bad as problem:
            bad += [problem.diagnostic, *problem.more]
    if bad:
        raise Bad(bad[0], tuple(bad[1:]))
    return UNKNOWN if any(value is UNKNOWN for value in values) else tuple(values)


def _substitute(raw: str, loc: Loc, env: Mapping[str, Bound], what: str) -> Any:
    """``"${a} mm/s"``: each parameter replaced by its text, each ``$$`` by ``$``; UNKNOWN
    if a parameter's value is unknown. A ``${`` that starts no parameter (``"${speed"``,
    ``"${ x }"``) is an error: it was passed on as text, so a typo in a use went unseen."""
    names = _parameters_used(raw, loc, env, what)
    if any(env[name].value is UNKNOWN for name in names):
        return UNKNOWN
    return substituted(raw, lambda name: env[name].text)


def name_text(raw: str, loc: Loc, env: Mapping[str, Bound]) -> tuple[str, bool]:
    """A node's ``name:`` with each ``${parameter}`` replaced by its text and each ``$${`` by
    ``${``, and whether it used a parameter (its name then changes with the value: nothing
    may pick the node by it, :func:`roomba_bt.mission.control.parse_composite`'s
    ``selected:``). ``name: "turn ${side}"`` ended a run ``FAILURE (turn ${side})``: a
    subtree used twice could not name its two uses apart. Unknown or stray ``${`` are
    errors, as in a log line; a value unknown (an unused subtree checked) is kept as
    written."""
    names = _parameters_used(raw, loc, env, "name")

    def text_of(name: str) -> str | None:
        bound = env[name]
        return None if bound.value is UNKNOWN else bound.text

    return substituted(raw, text_of), bool(names)


def _unknown_parameter(what: str, name: str, hint: str, loc: Loc) -> str:
    """``drive.velocity: unknown parameter ${cruise}``, with ``hint``; in a subtree's body,
    how it gets a mission's parameter that only some missions declare (a library's body read
    ``${cruise}`` of the missions that have one, and failed in the others)."""
    if not hint and loc.path.startswith("subtrees."):
        hint = (
            f" (a subtree's body sees its own parameters and those of the mission compiled, "
            f"which has no {name}: declare {name} in the subtree's parameters, and let each "
            f'use give it, {name}: "${{{name}}}" to pass a mission\'s on)'
        )
    return f"{what}: unknown parameter ${{{name}}}{hint}; {ESCAPE_HINT}"


def _parameters_used(raw: str, loc: Loc, env: Mapping[str, Bound], what: str) -> list[str]:
    """The parameters ``raw`` uses, each in ``env``; :class:`Bad` at the first ``${`` that
    starts none, or names an unknown one, saying how a literal one is written."""
    stray = _stray_opening(raw)
    if stray is not None:
        raise Bad(
            loc.at(
                f'{what}: "${{" at character {stray + 1} of {raw!r} starts no parameter (a '
                f"parameter is ${{name}}: an ASCII letter or _, then ASCII letters, digits or _, "
                f"then }}); "
                f"{ESCAPE_HINT}"
            )
        )
    names = parameters_used(raw)
    for name in names:
        if name not in env:
            hint = closest(name, list(env))
            raise Bad(loc.at(_unknown_parameter(what, name, hint, loc)))
    return names


def _check_range(
    value: Any, loc: Loc, what: str, param: Param | None, origin: str = "", written: str = ""
) -> Any:
    if param is not None:
        problem = param.check_range(value, written)
        if problem is not None:
            owner = what.rsplit(".", 1)[0] if "." in what else what
            raise Bad(loc.at(f"{owner}: {problem}{origin}"))
    return value


def said_default(name: str, bound: Bound, said_at: Loc, give: str = "") -> str:
    """`` (${creep} is 10 mm/s, the default of parameter creep at 7:26: give -p
    creep=15mm/s, or another default there)``, after an error that a mission parameter's
    default makes at a use (said at ``said_at``: the value was not written there); "" when
    the value was not its default. ``give``: a ``name=value`` that would do, if known."""
    if bound.default_at is None or bound.origin:
        return ""
    return (
        f" ({_default_of(name, bound, said_at)}: "
        f"give {bound.wording.give(give or name + '=VALUE')}, or another default there)"
    )


def said_defaults(
    written: Iterable[yaml.Node], env: Mapping[str, Bound], said_at: Loc, problem: str = ""
) -> str:
    """Each of ``written`` that is a whole ``${name}`` with its default, as
    :func:`said_default` says one, in one parenthesis. ``problem``: an error of a leaf as a
    whole (``drive at 10 mm/s never covers its distance``), which does not say which
    parameter made it: only the defaults whose value it names, so that one about which
    parameters are given (``velocity or left/right, not both``) names none."""
    said: dict[str, str] = {}
    wording = PYTHON
    for node in written:
        if isinstance(node, yaml.ScalarNode) and isinstance(node.value, str):
            full = _FULL_SUBSTITUTION.match(node.value)
            bound = None if full is None else env.get(full.group(2))
            if (
                full is not None
                and bound is not None
                and bound.default_at
                and not bound.origin
                and (not problem or _names_value(problem, bound))
            ):
                said[full.group(2)] = _default_of(full.group(2), bound, said_at)
                wording = bound.wording  # the caller's, as every default's
    if not said:
        return ""
    give = f"{next(iter(said))}=VALUE" if len(said) == 1 else "NAME=VALUE"
    return f" ({'; '.join(said.values())}: give {wording.give(give)}, or another default there)"


def _names_value(problem: str, bound: Bound) -> bool:
    """Whether ``problem`` says ``bound``'s value, as written or as a mission writes it
    (``10 mm/s``), as a whole word (not the ``0`` of ``500``)."""
    for text in {bound.text, shown(bound.type, bound.value)}:
        if re.search(rf"(?<![\w.]){re.escape(text)}(?![\w.])", problem):
            return True
    return False


def _default_of(name: str, bound: Bound, said_at: Loc) -> str:
    """``${creep} is 10 mm/s, the default of parameter creep at 7:26`` (with its file when
    that is not the one of ``said_at``)."""
    at = bound.default_at
    assert at is not None
    return (
        f"${{{name}}} is {bound.text}, the default of parameter {name} at {at.said_from(said_at)}"
    )


def _in_range(name: str, bound: Bound, param: Param, negative: str) -> str:
    """``creep=15mm/s``: the end of ``param``'s range nearest the parameter's value, as -p
    takes it (the canonical unit, no space); "" where the use converts or negates it."""
    value = bound.value
    same = bound.type.name == param.type.name or bound.type.name in param.type.takes
    if negative or not same or not isinstance(value, int | float):
        return ""
    low, high = param.minimum, param.maximum
    nearest = low if low is not None and value < low else high
    if nearest is None:
        return ""
    return f"{name}={nearest:g}{param.type.unit}"


def whole_parameter(node: yaml.Node, env: Mapping[str, Bound]) -> tuple[str, Bound] | None:
    """The parameter ``node`` is, when it is a whole ``${name}`` (or ``-${name}``) of one
    in ``env``, and its binding; else None."""
    if isinstance(node, yaml.ScalarNode) and isinstance(node.value, str):
        full = _FULL_SUBSTITUTION.match(node.value)
        if full is not None:
            bound = env.get(full.group(2))
            if bound is not None:
                return full.group(2), bound
    return None


def origin_of(node: yaml.Node, env: Mapping[str, Bound]) -> str:
    """Where the value of ``node`` was set, when it is a whole ``${name}`` whose parameter
    was set elsewhere (a subtree's argument passing the mission's on: the error at its use
    in a library names the command line)."""
    whole = whole_parameter(node, env)
    return "" if whole is None else whole[1].origin


def said_origin(node: yaml.Node, env: Mapping[str, Bound]) -> str:
    """`` (${speed} is 900 mm/s, given at m.yaml:15:31 to subtree go)``: where the value of
    ``node`` was set (:func:`origin_of`), said after an error at its use; or ""."""
    origin = origin_of(node, env)
    return f" ({str(node.value).strip()} is {origin})" if origin else ""


def given_to(node: yaml.Node, loc: Loc, subtree: str) -> str:
    """A subtree argument's origin (:attr:`Bound.origin`): the value as the use writes it,
    and where, so that an error its value makes in the subtree's body names the use too."""
    text = str(node.value).strip() if isinstance(node, yaml.ScalarNode) else "{...}"
    return f"{text}, given at {loc.file}:{loc.line}:{loc.column} to subtree {subtree}"


def _reference(
    ctx: Context,
    raw: str,
    loc: Loc,
    vtype: ValueType,
    what: str,
    allowed: tuple[bool, str],
    keys: Mapping[str, KeyDecl] | None = None,
) -> BlackboardRef:
    """``@key`` (or ``@key.field``) checked against the key's declaration; ``allowed``:
    whether a blackboard value may be written here, and if not, why. BT.CPP's ``{key}``
    is said to be written ``@key``."""
    allow_ref, no_ref = allowed
    port = port_remapping(raw)
    if port is not None:
        said = _reference_here(ctx, port, allow_ref)
        raise Bad(loc.at(f"{what}: {raw!r} is BehaviorTree.CPP's port remapping; {said}{no_ref}"))
    if not allow_ref:
        raise Bad(loc.at(f"{what}: {_reference_here(ctx, None, False)}{no_ref}"))
    match = BLACKBOARD_REF.match(raw)
    if match is None:
        raise Bad(loc.at(f"{what}: {raw!r} is not a blackboard reference (@key or @key.field)"))
    key, fname = match.groups()
    decl = (ctx.keys if keys is None else keys).get(key)
    if decl is None:
        note = ctx.unread_include_note(loc)
        hint = f" ({note})" if note is not None else ""
        if keys is None:  # written here, not passed down: a caller's own, not seen here?
            hint = hint or unseen_own_key(ctx, key)
        hint = hint or closest(key, list(ctx.keys if keys is None else keys))
        raise Bad(loc.at(f"{what}: unknown blackboard key {key!r}{hint}"))  # no list: @key
    ktype = decl.type
    if fname is not None:
        fields = record_fields(ktype)
        if fields is None or fname not in fields:
            known = ", ".join(fields) if fields else "none: it is not a record"
            raise Bad(
                loc.at(f"{what}: blackboard key {key!r} has no field {fname!r} (fields: {known})")
            )
        ktype = fields[fname]
    if not compatible(ktype, vtype, as_stored=True):
        raise Bad(
            loc.at(
                f"{what}: blackboard key {str(BlackboardRef(key, fname))[1:]!r} holds "
                f"{ktype.describe()}, but {what} needs {vtype.describe()}"
            )
        )
    return BlackboardRef(key, fname)


def as_written(vtype: ValueType, value: Any, node: yaml.Node, env: Mapping[str, Bound]) -> str:
    """``value`` as ``node`` writes it, each ``${parameter}`` as that parameter's own text:
    a subtree's ``time_limit: "${time_limit}"`` passes on the ``2min`` its user wrote, where
    the canonical ``120 s`` named the node ``dock_time_limit(120 s)`` in ``show``, the live
    tree and the failure. :func:`shown` where the node is no scalar, the value is a text
    (its ``$$`` already one ``$``), or the written text does not read back as ``value``
    (``40`` for an int: YAML's number, which a text is not)."""

    def text_of(name: str) -> str | None:
        bound = env.get(name)
        return None if bound is None or bound.value is UNKNOWN else bound.text

    if isinstance(node, yaml.SequenceNode) and all(
        isinstance(item, yaml.ScalarNode) for item in node.value
    ):  # a list argument (a list parameter's, a song's): its items as written
        items = (substituted(str(item.value), text_of).strip() for item in node.value)
        return f"[{', '.join(items)}]"
    if vtype is STR or not isinstance(node, yaml.ScalarNode):
        return shown(vtype, value)
    text = substituted(str(node.value), text_of).strip()
    if vtype.item is not None or vtype is NOTES:  # a whole ${list}: the list as given
        return text
    try:
        reads_back = vtype.parse(text) == value
    except ValueError:  # UnitError: the written text is no value of this type alone
        reads_back = False
    return percent_sign_kept(vtype, text) if reads_back else shown(vtype, value)
