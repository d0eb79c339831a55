"""Diagnostics: every error a mission has, at once, each with its place in the file.

``str(diagnostic)`` is the format compilers and editors understand::

    square.yaml:12:18: drive: velocity 600 mm/s is out of range: allowed -500..500 mm/s
                       [tree.sequence[2].drive.velocity]   (on the same line)

A diagnostic in a file the mission includes carries the include chain that reached it
(``included_from``), said on the same line as a C compiler says it::

    lib/escapes.yaml:12:52: drive.distance: unknown distance unit 'parsecs' ... [subtrees...]
        (included from lib/safe_drive.yaml:3:11, from delivery/to-kitchen.yaml:5:11)
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace

from roomba_bt.errors import RoombaBtError
from roomba_bt.printable import ANY_CONTROL, MAX_LISTED, UNPRINTABLE, escaped, more_listed


@dataclass(frozen=True, slots=True, order=True)
class Place:
    """A place in a mission file a diagnostic names beside its own: file, 1-based line and
    column, said ``file:line:column``."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{escaped(self.file, ANY_CONTROL)}:{self.line}:{self.column}"


@dataclass(frozen=True, slots=True, order=True)
class IncludeSite(Place):
    """Where an ``include:`` entry named a file: the including file, 1-based line and column
    of the entry."""


@dataclass(frozen=True, slots=True, order=True)
class SubtreeUse(Place):
    """Where a ``subtree:`` was used (its ``subtree`` key), and the subtree's name: a
    diagnostic about a node of its body says the use beside the definition's line, which
    alone did not say which use of the subtree it meant. ``path``: the YAML path of the
    place (the use's ``subtree`` key, or the node in the body), which a diagnostic said at
    the use takes as its own; not compared, as the place says the same."""

    name: str
    path: str = field(default="", compare=False)


@dataclass(slots=True)
class Later:
    """A part of a diagnostic's message worked out only when the diagnostic is shown: the
    "did you mean" of an unknown name (difflib, tens of microseconds a name). A file of
    68,000 unknown parameters spent 5 s of its 15 on suggestions for errors past the 100
    printed. ``after``: the text of the message the part follows (``unknown parameter
    'x'``); ``part``: the part (`` (did you mean 'y'?)``), or "" for none. Never changed
    once made, but not ``frozen``, as :class:`Diagnostic`: one is made with each of those
    errors."""

    after: str
    part: Callable[[], str]

    def filled(self, message: str) -> str:
        """``message`` with the part after the first ``after`` in it."""
        return message.replace(self.after, self.after + self.part(), 1)


#: the uses of subtrees that expanded a node: one use of its own subtree, then the use of
#: the subtree that use is in, and so on out to the tree (innermost first)
UseChain = tuple[SubtreeUse, ...]


@dataclass(slots=True, order=True, unsafe_hash=True)
class Diagnostic:
    """One error (or, ``severity="warning"``, something that compiles but is likely a
    mistake): file, 1-based line and column, the message, and the YAML path.

    Never changed once made (:func:`dataclasses.replace` makes another), but not
    ``frozen``: a frozen dataclass's ``__init__`` sets each of its eleven fields through
    ``object.__setattr__``, four to six times the cost of a plain one, and a file of 68,000
    unknown parameters makes a diagnostic for each and another at each ``replace``; equal,
    ordered and hashed by its fields as before (:class:`~roomba_bt.mission.source.Loc`
    does the same).

    ``included_from``: when ``file`` is not the file that was compiled but one it includes,
    the include entries that reached it, innermost first: the last is in the compiled file.
    Without it an error in a shared library was printed once per mission under the
    library's name alone, and nothing said which missions it broke. Empty for the compiled
    file's own diagnostics.

    ``began_at``: of a YAML syntax error, the 1-based line and column where the structure it
    broke began (the ``{`` left open, the block a line falls out of), said in the message too;
    empty otherwise.

    ``used_in``: of a diagnostic about a node of a subtree's body (said at its definition),
    each use of the subtree it was found at (:data:`UseChain`); one found the same at
    several uses is said once, naming them all (:func:`merged_uses`). Empty otherwise.

    ``in_subtree``: of a diagnostic said at the use that caused it (:func:`said_at_use`),
    where in the subtree's body it was found: the place in the body (and the subtree's
    name, and the body's YAML path), then each use of a subtree between that body and the
    use said (the place, and the subtree it is in), innermost first. Empty otherwise. Its
    ``used_in`` is then each use in the mission it was found at, one a chain: its own line
    first, then the others (:func:`merged_uses`)."""

    file: str
    line: int
    column: int
    message: str
    yaml_path: str = ""
    severity: str = "error"
    included_from: tuple[IncludeSite, ...] = ()
    began_at: tuple[int, ...] = ()
    used_in: tuple[UseChain, ...] = ()
    in_subtree: tuple[SubtreeUse, ...] = ()
    #: a part of the message still to be worked out (:class:`Later`): ``message`` lacks it
    #: until :meth:`shown` fills it in, which a compilation does for the first
    #: :data:`MAX_REPORTED` of a file's diagnostics, those a command prints; ``str()`` fills
    #: it for any other. Not compared: the part follows from the message.
    later: Later | None = field(default=None, compare=False, repr=False)

    def shown(self) -> Diagnostic:
        """This diagnostic with its message whole (:attr:`later` filled in)."""
        if self.later is None:
            return self
        return replace(self, message=self.later.filled(self.message), later=None)

    def __str__(self) -> str:
        if self.later is not None:
            return str(self.shown())
        where = (
            f" [{escaped(shortened_path(self.yaml_path), ANY_CONTROL)}]" if self.yaml_path else ""
        )
        kind = "warning: " if self.severity == "warning" else ""
        # the file's name on one line: a newline in it faked a line of ``validate *.yaml``
        file = escaped(self.file, ANY_CONTROL)
        text = f"{self.line}:{self.column}: {kind}{self.message}"
        return f"{file}:{escaped(text, UNPRINTABLE)}{self.uses_said()}{where}{self.chain_said()}"

    def uses_said(self) -> str:
        """``used_in`` as the line says it: `` (in subtree turn, used at m.yaml:12:5 and at
        m.yaml:20:5)``; a use within another subtree names that one's use too (`` (in
        subtree turn, used at m.yaml:4:9 in subtree square at m.yaml:12:5)``); "" for a
        diagnostic outside subtrees. At most :data:`USES_SAID` uses, then how many more.
        One said at its use (``in_subtree``) names the subtree's line and path instead: `` (in
        subtree leg, lib.yaml:30:19 [subtrees.leg.tree.drive])``, and the other uses found
        the same, if any (``, used here and at m.yaml:8:7``)."""
        if self.in_subtree:
            return _inside_said(self.in_subtree, self.used_in)
        if not self.used_in:
            return ""
        said = " and at ".join(_chain_said(chain) for chain in self.used_in[:USES_SAID])
        more = len(self.used_in) - USES_SAID
        if more > 0:
            said += f" and {more:,} more"  # as _inside_said says it
        name = escaped(self.used_in[0][0].name, UNPRINTABLE)
        return f" (in subtree {name}, used at {said})"

    def used_at(self, use: SubtreeUse) -> Diagnostic:
        """This diagnostic, found in a subtree's body, as caused by its use at ``use`` (a
        value it gave; outside the uses it has, as :meth:`Loc.used_at`)."""
        chains = tuple((*chain, use) for chain in self.used_in) or ((use,),)
        return replace(self, used_in=chains)

    def chain_said(self) -> str:
        """``included_from`` as the line says it: `` (included from a.yaml:3:11, from
        m.yaml:5:11)``, or "" for a diagnostic of the compiled file itself."""
        if not self.included_from:
            return ""
        return " (included from " + ", from ".join(map(str, self.included_from)) + ")"

    @property
    def checked_file(self) -> str:
        """The file that was compiled when this was found: the outermost include's file, or
        ``file`` itself."""
        return self.included_from[-1].file if self.included_from else self.file

    def located(self) -> Diagnostic:
        """The diagnostic without its include chain: the same error reached from two
        missions is one place to fix (``validate`` prints it once)."""
        return replace(self, included_from=()) if self.included_from else self

    def as_warning(self) -> Diagnostic:
        return replace(self, severity="warning")


#: the uses of a subtree a diagnostic names (:meth:`Diagnostic.uses_said`): a subtree used
#: in a loop of a generated file is not listed a hundred times on one line
USES_SAID = 5


def _chain_said(chain: UseChain) -> str:
    """``m.yaml:4:9 in subtree square at m.yaml:12:5``: one use of a subtree, with the uses
    of the subtrees it is in."""
    outer = "".join(f" in subtree {escaped(use.name, UNPRINTABLE)} at {use}" for use in chain[1:])
    return f"{chain[0]}{outer}"


def _inside_said(inside: tuple[SubtreeUse, ...], uses: tuple[UseChain, ...]) -> str:
    """`` (in subtree turn, lib.yaml:12:11 [subtrees.turn.tree.drive], used at lib.yaml:32:35
    in subtree leg, used here and at m.yaml:9:7)``: where in a subtree's body a diagnostic
    said at its use was found, and the other ``uses`` in the mission that found the same (at
    most :data:`USES_SAID` uses in all, then how many more)."""
    first, *between = inside
    body = f"{first} [{escaped(shortened_path(first.path), ANY_CONTROL)}]" if first.path else first
    said = "".join(
        f", used at {use} in subtree {escaped(use.name, UNPRINTABLE)}" for use in between
    )
    others = " and at ".join(_chain_said(chain) for chain in uses[1:USES_SAID])
    more = len(uses) - USES_SAID
    also = f", used here and at {others}" if others else ""
    if more > 0:
        also += f" and {more:,} more"
    return f" (in subtree {escaped(first.name, UNPRINTABLE)}, {body}{said}{also})"


def said_at_use(diagnostic: Diagnostic) -> list[Diagnostic]:
    """``diagnostic`` said at the use that caused it, one for each use it was found at, when
    that use is in another file than the subtree's body (a library's): the mission that
    uses the library wrongly is the file to fix, the one counted and annotated, and its line
    is the use (``missions/x.yaml:17:19: ... (in subtree leg, lib.yaml:30:19 [subtrees.leg.
    tree.drive])``), its YAML path the use's. The use that caused it is the outermost one it
    names: a value given there, or the place in the tree that the mission's checks (modes,
    keys) follow the body from. One found in a body written in the file of its use stays at
    the body's line, naming the use."""
    if not diagnostic.used_in:
        return [diagnostic]
    said = []
    for chain in diagnostic.used_in:
        use = chain[-1]
        if use.file == diagnostic.file:
            said.append(replace(diagnostic, used_in=(chain,)))
            continue
        body = SubtreeUse(
            diagnostic.file, diagnostic.line, diagnostic.column, chain[0].name,
            diagnostic.yaml_path,
        )  # fmt: skip
        between = tuple(
            SubtreeUse(inner.file, inner.line, inner.column, outer.name, inner.path)
            for inner, outer in itertools.pairwise(chain)  # the use in the next
        )
        said.append(
            replace(
                diagnostic, file=use.file, line=use.line, column=use.column, yaml_path=use.path,
                used_in=((use,),), in_subtree=(body, *between), included_from=(),
            )
        )  # fmt: skip
    return said


def merged_uses(diagnostics: Iterable[Diagnostic]) -> list[Diagnostic]:
    """``diagnostics`` with those that differ only by the subtree use they were found at
    made one, naming every use (in the order found): a subtree used twice gave the same
    warning twice at its definition's line. One said at its use in the mission
    (:func:`said_at_use`) is made one with those said at the other uses in the same file
    with the same text, from the same place in the body: a library's subtree used a hundred
    times gave a hundred lines. It is said at its first use (the mission's line, the one
    counted and annotated), naming the others. One whose message differs with the use (a
    parameter's value said) stays one a use."""
    #: each finding (the diagnostic without its uses): the one said, and every use found
    found: dict[Diagnostic, tuple[Diagnostic, list[UseChain]]] = {}
    for diagnostic in diagnostics:
        if not diagnostic.used_in:  # most: one look-up, no replace() (a 68,000-error file)
            found.setdefault(diagnostic, (diagnostic, []))
            continue
        same = replace(diagnostic, used_in=())
        if diagnostic.in_subtree:  # the finding, wherever in the mission's file it was caused
            same = replace(same, line=0, column=0, yaml_path="")
        said, chains = found.setdefault(same, (diagnostic, []))
        chains.extend(chain for chain in diagnostic.used_in if chain not in chains)
        if _place(diagnostic) < _place(said):
            found[same] = diagnostic, chains
    merged = []
    for said, chains in found.values():
        if said.in_subtree:  # its own use first, the others in the file's order
            own = said.used_in[0][-1]
            chains = sorted(chains, key=lambda chain: (chain[-1] != own, chain[-1]))
        merged.append(replace(said, used_in=tuple(chains)) if chains else said)
    return merged


def _place(diagnostic: Diagnostic) -> tuple[int, int]:
    return diagnostic.line, diagnostic.column


#: a YAML path longer than this is shown by its ends (:func:`shortened_path`)
PATH_SHOWN = 100


def shortened_path(path: str, ends: int = 3) -> str:
    """``path`` as an error line shows it: whole, or when longer than :data:`PATH_SHOWN`, its
    first and last ``ends`` steps and how many lie between (a tree nested a hundred deep gave
    a path of 1,200 characters)::

        tree.sequence[0].sequence[0] ... (94 more) ... sequence[0].sequence[0].mode
    """
    steps = path.split(".")
    if len(path) <= PATH_SHOWN or len(steps) <= 2 * ends:
        return path
    hidden = len(steps) - 2 * ends
    return f"{'.'.join(steps[:ends])} ... ({hidden} more) ... {'.'.join(steps[-ends:])}"


#: How many diagnostics a command prints of one file (decided): a compiler's convention, the
#: one a world's errors keep too (:data:`~roomba_bt.printable.MAX_LISTED`).
MAX_REPORTED = MAX_LISTED


def reported(diagnostics: Iterable[Diagnostic], limit: int = MAX_REPORTED) -> list[str]:
    """The lines a command prints for ``diagnostics``: the first ``limit``, then how many
    more there are (``... and 19,900 more errors (the first 100 are listed)``)."""
    every = list(diagnostics)
    lines = [str(d) for d in every[:limit]]
    hidden = every[limit:]
    if hidden:
        errors = sum(d.severity == "error" for d in hidden)
        noun = ("errors" if errors == len(hidden) else
                "warnings" if not errors else "errors and warnings")  # fmt: skip
        lines.append(more_listed(len(hidden), noun, limit))
    return lines


class MissionError(RoombaBtError):
    """A mission that cannot be compiled; ``diagnostics`` holds every error found (its
    message, the first :data:`MAX_REPORTED`)."""

    def __init__(self, diagnostics: Iterable[Diagnostic]) -> None:
        self.diagnostics: list[Diagnostic] = list(diagnostics)
        count = len(self.diagnostics)
        head = f"{count:,} error{'s' if count != 1 else ''} in mission"
        super().__init__("\n".join([head, *reported(self.diagnostics)]))
