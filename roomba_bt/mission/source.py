"""Mission YAML with positions: :class:`Loc` (file, line, column, YAML path) for every value,
and the checked accessors the loader and the parser read a file with.

Composing, tags, positions and duplicate keys are the shared reader's
(:mod:`roomba_bt.yamlsource`): only the YAML core types are built (str, int, float, bool,
null, lists, mappings); a tag that would build a Python object (``!!python/object``) or any
custom tag is an error, never executed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from roomba_bt import yamlsource
from roomba_bt.mission.diagnostics import Diagnostic, Later, SubtreeUse, UseChain
from roomba_bt.printable import MAX_FOUND, path_written

_CORE = yamlsource.CORE


@dataclass(slots=True, unsafe_hash=True)
class Loc:
    """Where a value is: file, 1-based line and column, YAML path. Never changed once made,
    but not ``frozen``: a frozen dataclass's ``__init__`` sets each field through
    ``object.__setattr__``, 7,300 instructions a Loc instead of 2,200, and compiling a
    mission makes one for every key and value (about 300 for ``dock.yaml``); equal and
    hashed by its fields as before."""

    file: str
    line: int
    column: int
    path: str
    #: of a place in a subtree's body, as the tree uses it: the use that expanded it (and
    #: the uses of the subtrees that one is in), said by its diagnostics; not compared: it
    #: is the same place in the file
    used_in: UseChain = field(default=(), compare=False)

    def at(self, message: str, later: Later | None = None) -> Diagnostic:
        """A diagnostic here; ``later``, a part of ``message`` worked out when it is shown
        (:class:`~roomba_bt.mission.diagnostics.Later`)."""
        used_in = (self.used_in,) if self.used_in else ()
        return Diagnostic(
            self.file, self.line, self.column, message, self.path, used_in=used_in, later=later
        )

    def said_from(self, said_at: Loc) -> str:
        """This place named in a message said at ``said_at``: ``12:5``, with its file when
        that is another (a library's line named from the mission's, or the other way)."""
        at = f"{self.line}:{self.column}"
        return at if self.file == said_at.file else f"{self.file}:{at}"

    def used_at(self, *uses: SubtreeUse) -> Loc:
        """This place as the subtree use ``uses`` expand it, innermost first (outside the
        ones it has: those of a subtree used within the subtree a use names)."""
        return Loc(self.file, self.line, self.column, self.path, (*self.used_in, *uses))

    def child(self, node: yaml.Node, segment: str) -> Loc:
        return loc_of(node, self.file, join(self.path, segment))


def join(path: str, segment: str) -> str:
    if not path:
        return segment
    return f"{path}{segment}" if segment.startswith("[") else f"{path}.{segment}"


def loc_of(node: yaml.Node, file: str, path: str) -> Loc:
    """Where ``node`` starts (:func:`yamlsource.position`, read here without the call and
    the tuple: a compile makes a Loc for every key and value)."""
    mark = node.start_mark
    return Loc(file, mark.line + 1, mark.column + 1, path)


#: what a mission file that exists and cannot be read is said to want, after what the system
#: said of it, as an include or a plugin file says it ("cannot read mission file: Permission
#: denied" named neither the file nor what would do)
MISSION_WANTED = "wanted: a mission file (YAML text) this user may read"
#: how such a file's diagnostic begins (its path follows)
UNREADABLE_MISSION = "cannot read mission file"
#: what ``validate``, which takes a mission or a world, says of a file it cannot read: it
#: cannot tell which the file is, and "cannot read mission file 'w.yaml': ...; wanted: a
#: mission file" was said of a world
UNREADABLE_FILE = "cannot read file"
EITHER_WANTED = "wanted: a mission or a world file (YAML text) this user may read"


def compose(
    path: Path, display: str, include: tuple[str, Loc] | None = None
) -> tuple[yaml.Node | None, list[Diagnostic]]:
    """The document's root node, or the syntax error as a diagnostic. ``include``: the text
    and place of the include naming the file, where a file that cannot be opened is
    reported."""
    try:
        text = yamlsource.read_text(path)
    except yamlsource.FileTooLarge as exc:
        return None, [Diagnostic(display, 1, 1, f"mission file of {exc}")]
    except OSError as exc:
        why = exc.strerror or exc
        if include is not None:
            name, where = include
            return None, [where.at(f"cannot read included file {path_written(name)}: {why}")]
        said = f"{UNREADABLE_MISSION} {path_written(display)}: {why}; {MISSION_WANTED}"
        return None, [Diagnostic(display, 1, 1, said)]
    except UnicodeDecodeError as exc:
        line, column = yamlsource.undecodable_position(exc)
        byte = bytes(exc.object)[exc.start]
        whole = exc.reason in yamlsource.WHOLE_REASONS
        said = exc.reason if whole else f"byte 0x{byte:02x} at offset {exc.start:,} ({exc.reason})"
        return None, [Diagnostic(display, line, column, f"mission file is not UTF-8 text: {said}")]
    return compose_text(text, display)


#: what a mission file with no YAML in it (nothing, or only comments) is said to be where a
#: mission is expected (``run``, an include); ``validate``, which takes a world too, says it
#: as neither (:data:`EMPTY_FILE`)
EMPTY_MISSION = "the mission file is empty"
#: what ``validate`` says of such a file: it cannot tell a mission meant from a world
EMPTY_FILE = (
    "an empty file (no YAML in it, at most comments): neither a mission nor a world; expected "
    "a mission (at least tree:, or a library's subtrees:) or a world (at least rooms:, the "
    "floor's polygons in metres; roomba-bt worlds empty-room prints a whole one)"
)


def compose_text(text: str, display: str) -> tuple[yaml.Node | None, list[Diagnostic]]:
    try:
        node = yamlsource.compose(text)
    except yamlsource.Refused as exc:
        refused = []
        for each in exc.every()[:MAX_FOUND]:  # the compile stops at as many
            line, column = yamlsource.error_position(each) or (1, 1)
            refused.append(Diagnostic(display, line, column, str(each.problem)))
        return None, refused
    except yaml.MarkedYAMLError as exc:
        line, column = yamlsource.error_position(exc) or (1, 1)
        problem = exc.problem or exc.context or "invalid YAML"
        if problem == "but found another document":  # the composer's sentence, cut in two
            problem = "a mission file holds one YAML document; a second one (---) starts here"
        tab = yamlsource.tab_hint(text, line, column)
        problem += tab
        cause = None if tab else yamlsource.lookalike_cause(text, line, column)
        began: tuple[int, ...] = ()
        if cause is not None:  # the character that looks like YAML's own, at its place
            problem = f"{cause[2]} ({problem} at {line}:{column})"
            line, column = cause[0], cause[1]
        elif not tab and (context := yamlsource.syntax_context(exc, text)) is not None:
            began = context[1]
            misplaced = misplaced_key(text.split("\n"), line, began[0], problem)
            if misplaced is not None:  # the language's words for what YAML calls syntax
                return None, [Diagnostic(display, line, misplaced[0], misplaced[1], began_at=began)]
            problem = f"{problem} ({context[0]})"
        elif not tab and (misplaced := misplaced_key(text.split("\n"), line, 1, problem)):
            return None, [Diagnostic(display, line, misplaced[0], misplaced[1])]
        said = f"YAML syntax error: {problem}"
        return None, [Diagnostic(display, line, column, said, began_at=began)]
    except yaml.YAMLError as exc:
        return None, [Diagnostic(display, 1, 1, f"YAML error: {exc}")]
    if node is None:
        return None, [Diagnostic(display, 1, 1, EMPTY_MISSION)]
    return node, [*duplicate_keys(node, display), *yaml12_text_numbers(node, display)]


#: a line's key: ``until:``, ``velocity: 100 mm/s``
_KEY = re.compile(r"([A-Za-z_][A-Za-z0-9_-]*)[ \t]*:(?:[ \t]|$)")


def misplaced_key(lines: list[str], line: int, first: int, problem: str) -> tuple[int, str] | None:
    """A node's modifier or option indented under no node, said in the mission language's
    words: the column of the key and the message, or None when line ``line`` (1-based; where
    YAML's syntax error ``problem`` is) holds no key, or no list item's node stands above it
    (down to line ``first``, where the broken structure began) with the key in its block.
    YAML says only "did not find expected key", "... expected '-' indicator" or "mapping
    values are not allowed in this context" of an ``until:`` one column out of line; the
    nodes the key most likely belongs to are the list items above it (``- drive: ...``, and
    the ones that hold it): a modifier (:data:`~roomba_bt.behaviours.language.MODIFIERS`)
    goes beside its node's word, in its column, an option in the column of the node's other
    options."""
    from roomba_bt.behaviours.language import MODIFIERS
    from roomba_bt.mission.loader import TOP_LEVEL  # imported here: the loader imports this

    if not 0 < line <= len(lines):
        return None
    broke = lines[line - 1]
    stripped = broke.lstrip(" ")
    match = _KEY.match(stripped)
    if match is None or match.group(1) in TOP_LEVEL:  # a section: not a node's
        return None
    key, column = match.group(1), len(broke) - len(stripped) + 1
    nodes, options = _nodes_above(lines, line, first)
    if not nodes:
        return None
    (at, word, word_column), outer = nodes[0], nodes[1:]
    if column == word_column or (options is not None and column == options[2]):
        return None  # in line with them: the cause is elsewhere
    found = f"{key}: in column {column} is in no node's mapping (YAML: {problem})"
    node = f"the node above, {word} (line {at})"
    others = "".join(f", {w}'s (line {n}) column {c}" for n, w, c in outer)
    if key in MODIFIERS and outer:
        return column, (
            f"{found}: {key} is a modifier, written beside its node's word in the same "
            f"column: {word}'s (line {at}) is column {word_column}{others}; write {key}: in "
            "the column of the node it belongs to"
        )
    if key in MODIFIERS:
        return column, (
            f"{found}: {key} is a modifier, written beside its node's word in the same "
            f"column: {node}, has its word in column {word_column}; write {key}: there, "
            f"indented {word_column - 1} spaces"
        )
    modifiers = ", ".join(MODIFIERS)
    if options is not None:
        return column, (
            f"{found}: {node}, has its options in column {options[2]} ({options[1]}, line "
            f"{options[0]}) and its modifiers ({modifiers}) beside its word, in column "
            f"{word_column}: write {key}: in the column of the ones it belongs with"
        )
    return column, (
        f"{found}: {node}, takes its options in its value ({word}: {{...}}) and its "
        f"modifiers ({modifiers}) beside its word, in column {word_column}: write {key}: "
        f"in its value, or in column {word_column} if it is a modifier"
    )


#: a list item that is a node: ``- drive: {...}``, ``- stop``
_ITEM = re.compile(r"- +([A-Za-z_][A-Za-z0-9_-]*)[ \t]*(?::(?:[ \t]|$)|$)")


def _nodes_above(
    lines: list[str], line: int, first: int
) -> tuple[list[tuple[int, str, int]], tuple[int, str, int] | None]:
    """The list items' nodes above line ``line`` (down to ``first``) whose blocks hold the
    lines between, innermost first, each as its line, word and the word's column; and the
    innermost one's option key nearest to ``line`` (line, key, column) where its options are
    a block under it, else None."""
    nodes: list[tuple[int, str, int]] = []
    options: tuple[int, str, int] | None = None
    least: int | None = None  # the least indentation of the lines passed
    for number in range(line - 1, max(first, 1) - 1, -1):
        text = lines[number - 1]
        content = text.lstrip(" ")
        if not content or content.startswith("#"):
            continue
        indent = len(text) - len(content)
        if least is not None and indent >= least:
            continue  # inside a block passed already, or beside a line of it
        item = _ITEM.match(content)
        if item is not None:
            word_column = indent + item.start(1) + 1
            if not nodes and options is not None and options[2] <= word_column:
                options = None  # not under the word: another mapping's
            nodes.append((number, item.group(1), word_column))
        elif not nodes and options is None and (key := _KEY.match(content)) is not None:
            options = (number, key.group(1), indent + 1)
        least = indent
    return nodes, options


def duplicate_keys(root: yaml.Node, display: str) -> list[Diagnostic]:
    """Every key written twice in a mapping of the file, each at its second place
    (:func:`yamlsource.every_duplicate_key`): :func:`mapping` leaves the second one out and
    the parser goes on to the file's other errors."""
    found: list[Diagnostic] = []
    for dup in yamlsource.every_duplicate_key(root)[:MAX_FOUND]:  # the compile stops at as many
        path = ""
        for part in dup.path or ():
            path = join(path, f"[{part}]" if isinstance(part, int) else part)
        first = yamlsource.position(dup.first)[0]
        where = loc_of(dup.node, display, path)
        found.append(where.at(f"duplicate key {_key_shown(dup.node)} (first at line {first})"))
    return found


def yaml12_text_numbers(root: yaml.Node, display: str) -> list[Diagnostic]:
    """A warning at each number an editor reads otherwise (``1_000``, ``0b11``: texts to
    YAML 1.2; :func:`yamlsource.yaml12_text_numbers`)."""
    found = []
    for node, parts, problem in yamlsource.yaml12_text_numbers(root):
        path = ""
        for part in parts:
            path = join(path, f"[{part}]" if isinstance(part, int) else part)
        found.append(loc_of(node, display, path).at(problem).as_warning())
    return found


def _key_shown(node: yaml.Node) -> str:
    """A key as a diagnostic names it: a text quoted, another value as written, said to
    be no name (``1``, ``true`` and ``1.0`` are three different keys)."""
    if isinstance(node, yaml.ScalarNode) and node.tag == yamlsource.STR:
        return repr(node.value)
    return f"{kind_of(node)} (not a name)"


class Bad(Exception):
    """A value that cannot be used; carries its diagnostic."""

    def __init__(self, diagnostic: Diagnostic, more: tuple[Diagnostic, ...] = ()) -> None:
        super().__init__(str(diagnostic))
        self.diagnostic = diagnostic
        #: others found with it, reported with it (``Context.report``)
        self.more = more


def check_tag(node: yaml.Node, loc: Loc) -> None:
    if not yamlsource.is_plain(node):
        tag = node.tag or ""
        raise Bad(loc.at(f"YAML tag {tag!r} is not allowed: missions use plain values only"))


def plain(node: yaml.Node, loc: Loc) -> Any:
    """The node as plain Python data (scalars, lists, dicts), tags checked."""
    check_tag(node, loc)
    if isinstance(node, yaml.ScalarNode):
        if node.tag in yamlsource.TEXT_SCALARS:
            return str(node.value)
        try:
            return yamlsource.scalar(node)
        except yamlsource.Refused as exc:  # an integer too long to read
            raise Bad(loc.at(str(exc.problem))) from None
    if isinstance(node, yaml.SequenceNode):
        return [plain(item, loc.child(item, f"[{i}]")) for i, item in enumerate(node.value)]
    out: dict[Any, Any] = {}
    for key, value in node.value:
        out[plain(key, loc.child(key, str(key.value)))] = plain(
            value, loc.child(value, str(key.value))
        )
    return out


def mapping(node: yaml.Node, loc: Loc, what: str) -> list[tuple[str, yaml.Node, Loc, Loc]]:
    """``(key, value node, key loc, value loc)`` of a mapping; a non-text key is an error. A
    key written again is left out, the first one standing: :func:`compose_text` reported
    every duplicate already (:func:`duplicate_keys`)."""
    items, not_names = named_entries(node, loc, what)
    if not_names is not None:
        raise not_names
    return items


def named_entries(
    node: yaml.Node, loc: Loc, what: str
) -> tuple[list[tuple[str, yaml.Node, Loc, Loc]], Bad | None]:
    """:func:`mapping`'s entries whose keys are names, and the error of those that are not
    (None when all are): for a section whose other entries stand on their own (a parameter
    named ``off:`` made every other parameter of the mission "unknown" at each use)."""
    check_tag(node, loc)
    if not isinstance(node, yaml.MappingNode):
        raise Bad(loc.at(f"{what} must be a mapping (key: value), got {kind_of(node)}"))
    out = []
    not_names = []
    file, path = loc.file, loc.path
    for _, key_node, value_node in yamlsource.pairs(node, skip_duplicates=True):  # once
        if not _is_name(key_node):
            said = f"keys of {what} must be names, got {_key_kind(key_node)}"
            not_names.append(loc_of(key_node, file, path).at(said))
            continue
        key = str(key_node.value)
        key_loc = loc_of(key_node, file, join(path, key))
        out.append((key, value_node, key_loc, loc_of(value_node, file, key_loc.path)))
    # each on its own line: `1:`, `true:`, `1.0:` are three keys, three errors
    bad = Bad(not_names[0], tuple(not_names[1:])) if not_names else None
    return out, bad


def _is_name(key_node: yaml.Node) -> bool:
    return isinstance(key_node, yaml.ScalarNode) and key_node.tag == yamlsource.STR


def written_keys(node: yaml.Node) -> list[str]:
    """The keys of a mapping as written, names or not (``off`` for a key YAML 1.1 read as a
    boolean): the names a user meant, so that their uses are not reported again."""
    if not isinstance(node, yaml.MappingNode):
        return []
    return [str(k.value) for _, k, _ in yamlsource.pairs(node, skip_duplicates=True)
            if isinstance(k, yaml.ScalarNode)]  # fmt: skip


def _key_kind(key_node: yaml.Node) -> str:
    """What a key that is no name is; ``on:`` says to quote it, as an enum's ``yes`` does
    (``vacuum: {on: true}``, the long form of a documented parameter, gave no hint)."""
    written = str(key_node.value)
    if key_node.tag == _CORE + "bool" and written.lower() not in ("true", "false"):
        read = str(yamlsource.scalar(key_node)).lower()
        return f"'{written}', read as the boolean {read} (YAML 1.1): quote it, '{written}'"
    if key_node.tag == _CORE + "merge":  # said "merge <<": what to write instead, too
        return (
            f"'{written}', a YAML merge key: a mission file copies no mapping into another "
            "(aliases, *name, are refused too); write the keys out"
        )
    return kind_of(key_node)


def sequence(node: yaml.Node, loc: Loc, what: str) -> list[tuple[yaml.Node, Loc]]:
    check_tag(node, loc)
    if not isinstance(node, yaml.SequenceNode):
        raise Bad(loc.at(f"{what} must be a list, got {kind_of(node)}"))
    return [(item, loc.child(item, f"[{i}]")) for i, item in enumerate(node.value)]


def empty_name(what: str, written: str, instead: str) -> str:
    """The error of a ``mission:`` or ``name:`` with no name in it (``""``, ``"  "``): the
    summary, the log and the trees showed nothing where the name goes (``mission      ``,
    ``roomba_bt.run:  -> SUCCESS``), and two such nodes could not be told apart."""
    found = "an empty text" if not written else f"only spaces ({written!r})"
    return (
        f"{what}: found {found}, no name; allowed: a name (not spaces alone), or no "
        f"{what.rpartition('.')[2]}: at all, and it is named {instead!r}"
    )


def scalar_text(node: yaml.Node, loc: Loc, what: str) -> str:
    value = plain(node, loc)
    if not isinstance(value, str):
        raise Bad(loc.at(f"{what} must be a text, got {kind_of(node)}"))
    return value


def kind_of(node: yaml.Node) -> str:
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if isinstance(node, yaml.SequenceNode):
        return "a list"
    tag = (node.tag or "").removeprefix(_CORE)
    if tag == "null":
        return "nothing (null)"
    if tag == "str":
        return f"the text {node.value!r}"
    if tag == "bool":
        return f"a boolean ({node.value})"
    return f"{tag} {node.value}"
