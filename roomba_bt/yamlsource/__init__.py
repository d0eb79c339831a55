"""YAML with positions: the one reader for every YAML file roomba-bt reads (missions, worlds).

It composes nodes and never lets a tag build a Python object (``!!python/object`` and any
custom tag are refused, not executed); every value keeps its line and column so an error
can point at it; a key written twice in one mapping is an error, never a silent overwrite.
It imports nothing of roomba-bt, so every layer, the simulator included, may use it.

Missions walk the composed nodes (:func:`compose`, :func:`position`, :func:`is_plain`,
:func:`pairs`, :func:`scalar`); worlds take plain data with a position for every path
(:func:`to_data`)::

    data, marks = to_data(compose("rooms: [[0, 0]]\\n"), refuse="the tag {tag!r} ...")
    marks[("rooms", 0)] == (1, 9)       # 1-based line and column
    marks[("rooms", KEY)] == (1, 1)     # where the key itself is written
"""

from __future__ import annotations

import os
import re
import sys
import unicodedata
from collections.abc import Iterator
from pathlib import Path
from typing import Any, NoReturn

import yaml

from roomba_bt.printable import CONTROL, repr_written, shortened

#: libyaml's parser where installed (much faster on large missions), else PyYAML's own
FAST_LOADER: type[Any] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
#: PyYAML's own parser: its syntax messages do not depend on libyaml being installed
PURE_LOADER: type[Any] = yaml.SafeLoader

CORE = "tag:yaml.org,2002:"
#: a text's tag, the one every mapping key has
STR = CORE + "str"
_PLAIN_SCALARS = frozenset(CORE + t for t in ("str", "int", "float", "bool", "null"))
#: scalars YAML resolves implicitly that a mission takes as text
TEXT_SCALARS = frozenset(CORE + t for t in ("timestamp", "binary"))
_PLAIN_COLLECTIONS = frozenset({CORE + "seq", CORE + "map"})
#: ``marks[(*path, key, KEY)]``: where a mapping key itself is written
KEY = "<key>"

_CONSTRUCTOR = yaml.constructor.SafeConstructor()

PathKey = tuple[str | int, ...]
Marks = dict[PathKey, tuple[int, int]]


#: how much of a value a diagnostic quotes: a stranger's file may hold a page in one scalar
#: (a world given ``/etc/passwd`` quoted all of it, on one line)
QUOTE_LIMIT = 60


def quoted(value: object, limit: int = QUOTE_LIMIT) -> str:
    """``repr(value)`` for a diagnostic, each backslash as written (a Windows path
    ``'C:\\missions\\a.yaml'`` was said with each one doubled) and a long one cut, its
    length said:
    ``'root:x:0:0:root:/root:/bin/bash daemon:x:1:1:daemon:/usr/sb... (1,234 characters)``."""
    text = repr_written(value)
    return shortened(text, limit, len(str(value)))


def tab_hint(text: str, line: int, column: int) -> str:
    """What to add to PyYAML's syntax error at (``line``, ``column``), 1-based, when the
    character there is a tab ("found character that cannot start any token" says nothing
    of it): an editor's tab in a stranger's file is the commonest such error."""
    lines = text.splitlines()
    inside = 0 < line <= len(lines) and 0 < column <= len(lines[line - 1])
    if inside and lines[line - 1][column - 1] == "\t":
        return " (a tab: YAML indents with spaces)"
    return ""


#: quotes a word processor or a chat app writes for ' and ": YAML reads them as text
TYPOGRAPHIC_QUOTES = "\u2018\u2019\u201a\u201b\u201c\u201d\u201e\u201f"
#: one opening a value, where YAML's quote would be: at the line's start or after ``:``, ``-``,
#: ``[``, ``{`` or ``,`` (one inside a text, ``"he said “hi”"``, is no cause of an error)
_TYPOGRAPHIC_QUOTE = re.compile(f"(?:^|[-:[{{,])[ \\t]*([{TYPOGRAPHIC_QUOTES}])")
#: spaces that are not U+0020 (a no-break space, a narrow one, an ideographic one): YAML
#: reads them as text, so one at the start of a line indents nothing
NOT_PLAIN_SPACES = "\u00a0\u1680" + "".join(map(chr, range(0x2000, 0x200B))) + "\u202f\u205f\u3000"
_SPACE_INDENT = re.compile(f"^[ \t]*([{NOT_PLAIN_SPACES}])", re.MULTILINE)
#: such a space right after a colon: ``mission:\xa0name`` is one text, no key and value
_SPACE_AFTER_COLON = re.compile(f":([{NOT_PLAIN_SPACES}])")


def named_character(char: str) -> str:
    """``'\\xa0' (U+00A0 NO-BREAK SPACE)``: a character a diagnostic names because it looks
    like another one."""
    name = unicodedata.name(char, "")
    return f"{char!r} (U+{ord(char):04X}{' ' + name if name else ''})"


def lookalike_cause(text: str, line: int, column: int) -> tuple[int, int, str] | None:
    """Where and what the cause of PyYAML's syntax error at (``line``, ``column``), 1-based,
    is when it is a character that looks like YAML's own: a typographic quote on that line
    (YAML reads ``“${speed}”`` as text, and its ``{`` is the error: "did not find expected
    ','"), a space that is not a plain one indenting that line or the one before (a
    no-break space indents nothing: "could not find expected ':'" a line later) or following
    a colon there (``mission:\xa0x`` runs on as a text: "mapping values are not allowed" a
    line later). None
    otherwise: PyYAML's sentence is all there is to say."""
    lines = text.split("\n")
    if 0 < line <= len(lines):
        quote = _TYPOGRAPHIC_QUOTE.search(lines[line - 1])
        if quote is not None:
            return line, quote.start(1) + 1, typographic_quote(quote.group(1))
    for number in (line, line - 1):
        indent = _SPACE_INDENT.match(lines[number - 1]) if 0 < number <= len(lines) else None
        if indent is not None:
            return number, indent.start(1) + 1, space_indent(indent.group(1))
    for number in (line, line - 1):  # "mission:\xa0x" is a text running on to the next key
        after = _SPACE_AFTER_COLON.search(lines[number - 1]) if 0 < number <= len(lines) else None
        if after is not None:
            return number, after.start(1) + 1, space_after_colon(after.group(1))
    return None


#: PyYAML's ``context`` of a syntax error, as a diagnostic names the structure it began
_STRUCTURES = {
    "while parsing a block mapping": "the mapping that starts at",
    "while parsing a block collection": "the list that starts at",
    "while parsing a flow mapping": "the { opened at",
    "while parsing a flow sequence": "the [ opened at",
}


def syntax_context(exc: yaml.MarkedYAMLError, text: str) -> tuple[str, tuple[int, int]] | None:
    """What to add to a syntax error's problem about where the structure it broke began, and
    that place (1-based line and column), or None when PyYAML gives no such place. PyYAML
    says it ("while parsing a flow mapping ... in line 3, column 10"); the problem's own place
    alone is often a line that looks fine: the ``tree:`` after a ``{`` left open, a list
    item one space out of line. For a block, the line that broke and the nearest line above
    it of its kind (a list item, a key) are compared: their indentation is the usual cause."""
    context, mark = exc.context, exc.context_mark
    problem_mark = exc.problem_mark
    if not context or mark is None or problem_mark is None:
        return None
    began = (mark.line + 1, mark.column + 1)
    structure = _STRUCTURES.get(context)
    if structure is None:  # "while scanning a quoted scalar": PyYAML's own words
        if not context.startswith("while "):  # "expected a single document": said already
            return None
        return f"{context} at {began[0]}:{began[1]}", began
    said = f"in {structure} {began[0]}:{began[1]}"
    if structure.startswith("the {") or structure.startswith("the ["):
        closing = "}" if "{" in structure else "]"
        return f"{said}: is its {closing} missing?", began
    hint = indentation_hint(text.split("\n"), problem_mark.line + 1, began[0])
    return (f"{said}; {hint}" if hint else said), began


def indentation_hint(lines: list[str], line: int, first: int) -> str:
    """``line 6 is indented 3 spaces, the list item on line 5 above it 4: ...``: the line
    that broke against the nearest line above it (down to ``first``) of its kind, a list
    item or a key; "" when they line up or there is none."""
    if not 0 < line <= len(lines):
        return ""
    broke = lines[line - 1]
    stripped = broke.lstrip(" ")
    item = stripped.startswith("-")
    for number in range(line - 1, max(first, 1) - 1, -1):
        above = lines[number - 1]
        content = above.lstrip(" ")
        if not content or content.startswith("#") or content.startswith("-") != item:
            continue
        indent, other = len(broke) - len(stripped), len(above) - len(content)
        if indent == other:
            return ""
        kind = "list item" if item else "key"
        return (
            f"line {line} is indented {indent} spaces, the {kind} on line {number} above it "
            f"{other}: the entries of one list or mapping start in the same column"
        )
    return ""


def space_after_colon(char: str) -> str:
    """What is wrong with a space that is not a plain one after a key's colon."""
    return (
        f"{named_character(char)} after ':' is no space to YAML, so the key, the colon and "
        "the value are one text: write a plain space after the colon"
    )


def typographic_quote(char: str) -> str:
    """What is wrong with a typographic quote used as YAML's."""
    return f"{named_character(char)} is a typographic quote, not a YAML quote: write \" or '"


def space_indent(char: str) -> str:
    """What is wrong with a space that is not a plain one indenting a line."""
    return (
        f"{named_character(char)} indents this line: YAML indents with plain spaces only "
        "(write a space)"
    )


def undecodable_position(exc: UnicodeDecodeError) -> tuple[int, int]:
    """1-based line and column (in bytes) of the first byte that is not UTF-8."""
    data = bytes(exc.object)
    line_start = data.rfind(b"\n", 0, exc.start) + 1
    return data.count(b"\n", 0, exc.start) + 1, exc.start - line_start + 1


#: The most of a YAML file roomba-bt reads (decided): a mission or a world is a few KB, a long
#: waypoint list a few hundred; a generated 3 MB mission took 8 s and 500 MB to validate, so a
#: larger file is refused before it is read, not composed until the machine runs out of memory.
MAX_FILE_BYTES = 1 << 20


class FileTooLarge(Exception):
    """A YAML file over :data:`MAX_FILE_BYTES`; ``size`` in bytes."""

    def __init__(self, size: int) -> None:
        self.size = size
        super().__init__(
            f"{size:,} bytes; at most {MAX_FILE_BYTES:,} are read (a mission or a world is a "
            "few KB: a file generated wrong?)"
        )


def read_text(path: Path) -> str:
    """A YAML file's text; :class:`FileTooLarge` before reading one over the limit, else what
    ``Path.read_text`` raises (``OSError``, ``UnicodeDecodeError``)."""
    with path.open("rb") as file:
        size = os.fstat(file.fileno()).st_size
        if size > MAX_FILE_BYTES:
            raise FileTooLarge(size)
        data = file.read(MAX_FILE_BYTES + 1)
    if len(data) > MAX_FILE_BYTES:  # grew since, or a size the file system does not give
        raise FileTooLarge(len(data))
    if data[:4] in UTF32_MARKS:  # before UTF-16's: its little-endian mark begins with FF FE
        raise UnicodeDecodeError("utf-8", data, 0, 1, UTF32)
    if looks_utf16(data):  # Notepad's "Unicode": "byte 0xff" or "U+0000" said nothing of it
        raise UnicodeDecodeError("utf-8", data, 0, 1, UTF16)
    for signature, what in DOCUMENT_SIGNATURES:  # a word processor's file, named as one
        if data.startswith(signature):
            raise UnicodeDecodeError("utf-8", data, 0, 1, what)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        if b"\0" in data:  # a program, an image, an archive: no text holds a NUL
            raise UnicodeDecodeError(exc.encoding, data, 0, 1, BINARY) from None  # the whole
        raise UnicodeDecodeError(
            exc.encoding, data, exc.start, exc.end, f"{exc.reason}{legacy_encoding(data, exc)}"
        ) from None
    # as Path.read_text: universal newlines (a CRLF file's columns as a LF file's)
    return text.replace("\r\n", "\n").replace("\r", "\n")


#: the reason of the :class:`UnicodeDecodeError` :func:`read_text` raises for UTF-16 text
UTF16 = "this is UTF-16 text: save it as UTF-8"
#: and for UTF-32 text, which starts with its byte-order mark (it was called UTF-16)
UTF32 = "this is UTF-32 text: save it as UTF-8"
UTF32_MARKS = (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")
#: how files that are no text start, and the reason :func:`read_text` gives for each (a
#: teacher's class handed in TextEdit's RTF and Word's .docx as missions: "byte 0x8e" and a
#: YAML syntax error in line 2 said nothing of what the file was)
DOCUMENT_SIGNATURES: tuple[tuple[bytes, str], ...] = (
    (b"{\\rtf", "this is an RTF document (TextEdit's default): save it as plain text, UTF-8"),
    (b"PK\x03\x04", "this is a ZIP archive, such as a Word (.docx) or OpenDocument file: "
     "save it as plain text, UTF-8"),
    (b"%PDF-", "this is a PDF document: a mission is a plain text file, UTF-8"),
    (b"\x89PNG", "this is a PNG image: a mission is a plain text file, UTF-8"),
)  # fmt: skip
#: and for a file that is not UTF-8 and holds a NUL byte, which no text does (UTF-16's aside,
#: told apart before): a program or an image given as a world was "byte 0xd0, not UTF-8
#: text", and as a mission "it reads as 'Ð' in Windows-1252 ...: save the file as UTF-8"
BINARY = "this is a binary file (it holds NUL bytes), not text: YAML is plain text, UTF-8"
#: the reasons that say the whole of what is wrong (no byte of a text to show)
WHOLE_REASONS = frozenset({UTF16, UTF32, BINARY, *(what for _, what in DOCUMENT_SIGNATURES)})


def legacy_encoding(data: bytes, exc: UnicodeDecodeError) -> str:
    """What follows the reason a byte is not UTF-8 when the file reads as Windows-1252 (which
    Latin-1 files also read as): the character the byte is there, and to save it as UTF-8;
    "" otherwise."""
    try:
        char = data[exc.start : exc.start + 1].decode("cp1252")
        data.decode("cp1252")
    except UnicodeDecodeError:
        return ""
    return (
        f"; it reads as {char!r} in Windows-1252 or Latin-1, an older encoding: save the file "
        "as UTF-8"
    )


def looks_utf16(data: bytes) -> bool:
    """``data`` starts as UTF-16 does: its byte-order mark (FF FE, FE FF), or ASCII with a NUL
    beside each character (no BOM). UTF-8 never holds FF or FE, and a YAML file no NUL."""
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return True
    head = data[:2]
    return len(head) == 2 and head.count(0) == 1 and max(head) < 0x80


class Refused(yaml.MarkedYAMLError):
    """Something a data file may not hold, found before anything is composed: an alias, an
    explicit tag, a character the YAML reader refuses. ``problem`` says what,
    ``problem_mark`` where."""

    #: the refusals found after this one, in the file's order: every one is reported at once
    more: tuple[Refused, ...] = ()

    def every(self) -> list[Refused]:
        """This refusal and the others found with it."""
        return [self, *self.more]


def compose(text: str, loader: type[Any] = FAST_LOADER) -> yaml.Node | None:
    """The document's root node (None for an empty document); raises :class:`yaml.YAMLError`
    (see :func:`error_position`) for a syntax error, :class:`Refused` for an alias, an
    explicit tag, a character YAML does not allow (:func:`unprintable`) or lists and mappings
    nested deeper than :data:`MAX_NESTING`. A fresh loader reads each text: nothing is kept
    between calls.

    An alias is written with ``*`` and a tag with ``!``: a text with neither holds none, and
    its event pass (:func:`refuse_aliases_and_tags`, a sixth of compiling a mission) is left
    out unless composing fails, when it runs first as always, so that the error raised is the
    same one (a syntax error after the first document is the event pass's, not the
    composer's "expected a single document")."""
    if _HIDDEN_BREAK.search(text) is not None:
        refuse_hidden_breaks(text)
    if text.find(BOM, 1) > 0:
        refuse_inner_boms(text)
    try:
        root = _compose(text, loader)
    except yaml.reader.ReaderError as exc:
        raise unprintable(text, exc) from None
    if root is not None:
        refuse_deep_nodes(root)
        if _SPACE_INDENT.search(text) is not None:
            refuse_space_indented_keys(root)
        if _DIGIT_COMMA_DIGIT.search(text) is not None:
            refuse_decimal_commas(root, text)
        if "\\" in text:  # a control character gets into a text only as a "\e" escape
            refuse_control_characters(root)
    return root


def refuse_space_indented_keys(root: yaml.Node) -> None:
    """Raise :class:`Refused` at each key (in the file's order) that starts a line with a
    space that is not a plain one: ``\\xa0\\xa0sequence:`` pasted from a chat is the key
    ``'\\xa0\\xa0sequence'`` one level out, and the file's errors were an empty ``tree:``
    and an unknown top-level key. No key of a mission or a world starts with a space."""
    found: list[tuple[int, Refused]] = []
    for mapping in _mappings(root):
        for key, _ in mapping.value:
            plain_key = key.__class__ is yaml.ScalarNode and not key.style
            indent = _SPACE_INDENT.match(key.value) if plain_key else None
            if indent is not None and key.start_mark.column == 0:
                refused = Refused(
                    problem=space_indent(indent.group(1)), problem_mark=key.start_mark
                )
                found.append((key.start_mark.index, refused))
    if found:
        raise_every([refused for _, refused in sorted(found, key=lambda each: each[0])])


_DIGIT_COMMA_DIGIT = re.compile("[0-9],[0-9]")


def refuse_decimal_commas(root: yaml.Node, text: str) -> None:
    """Raise :class:`Refused` at each number of a flow mapping followed at once by a comma and
    a key of digits (``{distance: 1,5 m}``): a decimal comma, which YAML reads as the end of
    the value, and the file's errors were a bare ``1`` and an unknown parameter ``'5 m'``.
    No key of a mission or a world starts with a digit."""
    found: list[tuple[int, Refused]] = []
    for mapping in _mappings(root):
        if not mapping.flow_style:
            continue
        for (_, value), (key, _) in zip(mapping.value, mapping.value[1:], strict=False):
            end = value.end_mark.index
            if (
                value.tag in _NUMBER_TAGS
                and key.__class__ is yaml.ScalarNode
                and not key.style
                and key.value[:1].isdigit()
                and key.start_mark.index == end + 1
                and text[end : end + 1] == ","
            ):
                written = f"{value.value},{key.value}"
                problem = (
                    f"{quoted(written)} holds a decimal comma, which ends the value here: write "
                    f"{value.value}.{key.value}"
                )
                found.append((end, Refused(problem=problem, problem_mark=value.start_mark)))
    if found:
        raise_every([refused for _, refused in sorted(found, key=lambda each: each[0])])


def _mappings(root: yaml.Node) -> Iterator[yaml.MappingNode]:
    """Every mapping of the document (a walk with a stack of its own: any depth)."""
    pending = [root]
    while pending:
        node = pending.pop()
        if node.__class__ is yaml.MappingNode:
            yield node
            pending.extend(item for pair in node.value for item in pair)
        elif node.__class__ is yaml.SequenceNode:
            pending.extend(node.value)


def _compose(text: str, loader: type[Any]) -> yaml.Node | None:
    try:
        if "*" in text or "!" in text:
            refuse_aliases_and_tags(text, loader)
            root = yaml.compose(text, Loader=loader)
        else:
            try:
                root = yaml.compose(text, Loader=loader)
            except yaml.YAMLError:
                refuse_aliases_and_tags(text, loader)
                raise
    except RecursionError:  # PyYAML's own composer recurses: deeper than Python's stack
        refuse_deep_events(text, loader)
        raise
    except yaml.MarkedYAMLError as exc:
        if exc.problem == _LIBYAML_TOO_DEEP:  # libyaml's own bound, 1000: the documented message
            refuse_deep_events(text, PURE_LOADER)
        raise
    return root


#: libyaml's scanner's problem past 1,000 levels (``while increasing flow level``, or block
#: level), which named no bound the docs give. libyaml scans ahead for a key and gives no
#: event of a line that goes that deep, so PyYAML's own parser (no bound of its own, no
#: recursion) reads the events for :func:`refuse_deep_events`, which names the documented
#: bound at the collection that goes over it; on this error only, so its pace costs nothing
_LIBYAML_TOO_DEEP = "exceeded maximum nesting depth"


def reader_offset(text: str, exc: yaml.reader.ReaderError) -> int | None:
    """Index in ``text`` of the character a :class:`yaml.reader.ReaderError` refused.

    PyYAML's reader gives ``position`` in characters, libyaml's in bytes of the UTF-8
    encoding: the two differ after any non-ASCII character. Both report the first character
    they refuse, so the smaller of the two readings that holds that character is it."""
    char = chr(exc.character)
    position: int = exc.position
    in_bytes = len(text.encode("utf-8")[:position].decode("utf-8", "ignore"))
    for index in sorted({in_bytes, position}):
        if 0 <= index < len(text) and text[index] == char:
            return index
    found = text.find(char)
    return found if found >= 0 else None


def character_name(char: str) -> str:
    """``U+001B``: how a diagnostic names a character that cannot be shown as itself."""
    return f"U+{ord(char):04X}"


def unprintable(text: str, exc: yaml.reader.ReaderError) -> Refused:
    """A character the YAML reader refuses (a NUL, a BEL in a comment, a raw ESC), as a
    :class:`Refused` at its own line and column: PyYAML says "position 52" of "<unicode
    string>" on a second line, and a mark of 1:1."""
    index = reader_offset(text, exc)
    char = chr(exc.character)
    kind = "control character" if char < " " or "\x7f" <= char <= "\x9f" else "character"
    problem = (
        f"{kind} {character_name(char)} is not allowed in a YAML file: it may hold printable "
        "characters, tabs and line breaks only"
    )
    if index is None:
        return Refused(problem=problem)
    line = text.count("\n", 0, index)
    column = index - (text.rfind("\n", 0, index) + 1)
    return Refused(problem=problem, problem_mark=yaml.Mark("<text>", index, line, column, None, 0))


#: Characters YAML reads as a line break and an editor does not show as one: NEL (U+0085, a
#: C1 control), the line separator U+2028 and the paragraph separator U+2029. PyYAML and
#: libyaml accept them raw, so every line after one was numbered one off what the editor
#: shows (a NEL in a comment was a syntax error on the wrong line); refused raw, at their own
#: line:col, as every other control character (decided: not read as breaks)
_HIDDEN_BREAK = re.compile("[\x85\u2028\u2029]")
_BREAK_NAMES = {"\u2028": "line separator", "\u2029": "paragraph separator"}


#: the byte-order mark: YAML skips one at the file's start, and reads one anywhere else as text
BOM = "\ufeff"


def refuse_inner_boms(text: str) -> None:
    """Raise :class:`Refused` at each byte-order mark after the file's start (the first, the
    others in its ``more``): two files pasted together leave one, invisible in an editor,
    and the error was "did not find expected key" a line later."""
    found = []
    index = text.find(BOM, 1)
    while index > 0:
        line = text.count("\n", 0, index)
        column = index - (text.rfind("\n", 0, index) + 1)
        problem = (
            f"{named_character(BOM)}, a byte-order mark, is allowed only at the start of the "
            "file (two files pasted together?): delete it (most editors do not show it)"
        )
        mark = yaml.Mark("<text>", index, line, column, None, 0)
        found.append(Refused(problem=problem, problem_mark=mark))
        index = text.find(BOM, index + 1)
    raise_every(found)


def refuse_hidden_breaks(text: str) -> None:
    """Raise :class:`Refused` at each :data:`_HIDDEN_BREAK` character of ``text`` (the first,
    the others in its ``more``), lines counted as an editor counts them (newlines only)."""
    found = []
    for match in _HIDDEN_BREAK.finditer(text):
        index = match.start()
        char = match.group()
        line = text.count("\n", 0, index)
        column = index - (text.rfind("\n", 0, index) + 1)
        if char in _BREAK_NAMES:
            problem = (
                f"{_BREAK_NAMES[char]} {character_name(char)} is not allowed: editors do not "
                "show it as a line break, YAML reads one (write a newline, or a space)"
            )
        else:
            problem = (
                f"control character {character_name(char)} (NEL) is not allowed in a YAML "
                "file: it may hold printable characters, tabs and line breaks only"
            )
        mark = yaml.Mark("<text>", index, line, column, None, 0)
        found.append(Refused(problem=problem, problem_mark=mark))
    raise_every(found)


def refuse_control_characters(root: yaml.Node) -> None:
    """Raise :class:`Refused` at the first key or value (in the file's order) holding a
    :data:`CONTROL` character, the others in its ``more``. The reader refuses such characters
    written raw; a double-quoted text still makes them from escapes (``"\\e"``, ``"\\x1b"``,
    ``"\\u001b"``, ``"\\a"``, ``"\\r"``): the text is refused at its own line and column,
    the character named."""
    found: list[Refused] = []
    pending: list[tuple[yaml.Node, str]] = [(root, "value")]
    while pending:
        node, role = pending.pop()
        if node.__class__ is yaml.ScalarNode:
            control = CONTROL.search(node.value)
            if control is not None:
                found.append(Refused(problem=_control_problem(control.group(), role),
                                     problem_mark=node.start_mark))  # fmt: skip
        elif node.__class__ is yaml.MappingNode:
            for key, value in reversed(node.value):
                pending += ((value, "value"), (key, "key"))
        else:
            pending.extend((item, "value") for item in reversed(node.value))
    if found:
        raise_every(found)


def _control_problem(char: str, role: str) -> str:
    return (
        f"control character {character_name(char)} (an escape such as \\e, \\x1b or \\a in "
        f"quotes) is not allowed in a {role}: a text may hold printable characters, tabs and "
        "line breaks only"
    )


#: How deep lists and mappings may nest in a file roomba-bt reads (decided). A mission tree
#: nests two a level (``sequence: [...]``) and may be 100 nodes deep; a world, four. Deeper
#: nesting ran the readers out of Python's stack (a world nested 990 deep was a traceback;
#: PyYAML's own composer fails at about 600, libyaml refuses 1000).
MAX_NESTING = 300


def _too_deep(mark: Any) -> Refused:
    return Refused(
        problem=f"lists and mappings nested more than {MAX_NESTING} deep here: at most "
        f"{MAX_NESTING} are allowed (a file generated wrong?)",
        problem_mark=mark,
    )


def refuse_deep_nodes(root: yaml.Node) -> None:
    """Raise :class:`Refused` at the first collection (in the file's order) nested deeper
    than :data:`MAX_NESTING`; a walk with a stack of its own, so any depth is measured. Only
    collections are visited (scalars, most of a file, cannot nest)."""
    scalar = yaml.ScalarNode
    pending: list[tuple[yaml.Node, int]] = [] if root.__class__ is scalar else [(root, 1)]
    while pending:
        node, depth = pending.pop()
        if depth > MAX_NESTING:
            raise _too_deep(node.start_mark)
        if node.__class__ is yaml.MappingNode:
            children = [item for pair in node.value for item in pair]
        else:
            children = node.value
        depth += 1
        for child in reversed(children):
            if child.__class__ is not scalar:
                pending.append((child, depth))


def refuse_deep_events(text: str, loader: type[Any] = FAST_LOADER) -> None:
    """:func:`refuse_deep_nodes` on the event stream (nothing composed): for a text too deep
    for the composer to build."""
    depth = 0
    for event in yaml.parse(text, Loader=loader):
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_NESTING:
                raise _too_deep(event.start_mark)
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1


def refuse_aliases_and_tags(text: str, loader: type[Any] = FAST_LOADER) -> None:
    """Read the event stream (linear in the text, nothing built) and raise :class:`Refused` at
    the first alias, explicit tag or :data:`CONTROL` character in a text, every other one
    found in :attr:`Refused.more` (a stranger fixing the first must not meet the next):

    * ``*name``: aliases nested a few levels expand a small file exponentially (6 levels in
      857 bytes took 18 s to validate, 7 more than 15 s); no mission or world needs them;
    * ``!!int 1s``, ``!!float``, ``!!bool``, ``!!python/...``, ``!custom``: a tag decides
      what is built (an int from "1s" fails deep inside; a Python object is code). Values
      are written plain, and the schema's own rules type them.

    A syntax error past a refusal ends the pass with the refusals found before it (the
    error is the parser's to report once they are gone)."""
    found: list[Refused] = []
    try:
        if "\\" in text:  # a control character gets into a text only as a "\e" escape
            _refuse_with_controls(text, loader, found)
        else:  # the pass as fast as it was before it looked for control characters
            for event in yaml.parse(text, Loader=loader):
                if event.__class__ is yaml.AliasEvent or (
                    getattr(event, "tag", None) is not None and isinstance(event, yaml.NodeEvent)
                ):
                    found.append(_refused_event(event))
    except yaml.YAMLError:
        if not found:
            raise
    if found:
        raise_every(found)


def _refuse_with_controls(text: str, loader: type[Any], found: list[Refused]) -> None:
    """:func:`refuse_aliases_and_tags`'s pass that also refuses a :data:`CONTROL` character in
    a text, saying whether the text is a key or a value (which it follows for each mapping)."""
    # per open collection: nodes read so far in a mapping (even: a key comes next), -1 in a list
    open_: list[int] = []
    for event in yaml.parse(text, Loader=loader):
        if isinstance(event, yaml.CollectionEndEvent):
            open_.pop()
            continue
        if not isinstance(event, yaml.NodeEvent):
            continue
        role = "key" if open_ and open_[-1] >= 0 and open_[-1] % 2 == 0 else "value"
        if open_ and open_[-1] >= 0:
            open_[-1] += 1
        if isinstance(event, yaml.CollectionStartEvent):
            open_.append(0 if isinstance(event, yaml.MappingStartEvent) else -1)
        if isinstance(event, yaml.AliasEvent) or getattr(event, "tag", None) is not None:
            found.append(_refused_event(event))
        elif isinstance(event, yaml.ScalarEvent):
            control = CONTROL.search(event.value)
            if control is not None:
                mark: Any = event.start_mark
                found.append(Refused(problem=_control_problem(control.group(), role),
                                     problem_mark=mark))  # fmt: skip


def _refused_event(event: yaml.Event) -> Refused:
    """The refusal of an alias or a tagged node."""
    mark: Any = event.start_mark
    if isinstance(event, yaml.AliasEvent):
        return Refused(
            problem=f"alias *{event.anchor} is not allowed: write the value out "
            "(aliases can expand a small file without bound)",
            problem_mark=mark,
        )
    tag: str = getattr(event, "tag", "")
    shown = "!!" + tag[len(CORE) :] if tag.startswith(CORE) else tag
    return Refused(
        problem=f"explicit tag {shown} is not allowed: write the plain value (1s, 2, true, text)",
        problem_mark=mark,
    )


def raise_every(found: list[Refused]) -> NoReturn:
    """Raise the first of ``found`` (in the file's order) with the others in its ``more``."""
    first = found[0]
    first.more = tuple(found[1:])
    raise first


def position(node: yaml.Node) -> tuple[int, int]:
    """1-based line and column where ``node`` starts."""
    mark = node.start_mark
    return mark.line + 1, mark.column + 1


def holds_some_of(root: yaml.Node | None, words: tuple[str, ...]) -> bool:
    """Whether ``root`` is a mapping with at least one of ``words`` as a key: a file of the
    kind they are the top-level keys of (a mission, a world). Anything else is not one, and
    its content is never quoted back in an error (:func:`not_a_file_of`): a path a stranger
    chose (a record's world, an include) may name ``~/.pgpass`` or ``/etc/shadow``, whose
    lines an "unknown key" error would print."""
    return isinstance(root, yaml.MappingNode) and any(
        isinstance(key, yaml.ScalarNode) and key.value in words for key, _ in root.value
    )


def not_a_file_of(what: str, kind: str, words: tuple[str, ...]) -> str:
    """What a file that :func:`holds_some_of` none of ``words`` is said to be (``what``: the
    file as the message names it; ``kind``: "mission", "world"), quoting none of it."""
    return f"{what} is not a {kind} file: expected a mapping with some of {', '.join(words)}"


def error_position(exc: yaml.YAMLError) -> tuple[int, int] | None:
    """1-based line and column of a YAML error (of the problem, else of its context)."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    return (mark.line + 1, mark.column + 1) if mark is not None else None


def is_plain(node: yaml.Node) -> bool:
    """A core-schema value (str, int, float, bool, null, timestamp, binary, list, mapping):
    nothing a tag could turn into a Python object."""
    tag = node.tag or ""
    if isinstance(node, yaml.ScalarNode):
        return tag in _PLAIN_SCALARS or tag in TEXT_SCALARS
    return isinstance(node, _COLLECTIONS) and tag in _PLAIN_COLLECTIONS


#: (a tuple: ``A | B`` written in a call builds a new union object each time)
_COLLECTIONS = (yaml.SequenceNode, yaml.MappingNode)


def scalar(node: yaml.Node) -> Any:
    """A node as Python data by the safe constructor (``3`` -> 3, ``true`` -> True,
    ``2s`` -> "2s"); a tag it has no constructor for raises
    :class:`yaml.constructor.ConstructorError`. A text is its value, as the constructor
    would return it, without the constructor's dispatch and caches (most scalars of a
    mission are texts). An integer too long for Python to read (over 4,300 digits) raises
    :class:`Refused` at its place: it was a ValueError far from it, "internal error" at 1:1
    of a mission and a traceback for a world."""
    if node.tag == STR and isinstance(node, yaml.ScalarNode):
        return node.value
    if node.tag in _NUMBER_TAGS and isinstance(node, yaml.ScalarNode):
        problem = yaml11_number_problem(str(node.value))
        if problem is not None:
            raise Refused(problem=problem, problem_mark=node.start_mark)
    try:
        return _CONSTRUCTOR.construct_object(node, deep=True)
    except ValueError:
        if node.tag != CORE + "int":
            raise
        raise _too_many_digits(node) from None
    finally:  # its caches would keep every node alive and remember a failed one
        _CONSTRUCTOR.constructed_objects.clear()
        _CONSTRUCTOR.recursive_objects.clear()


_NUMBER_TAGS = frozenset({CORE + "int", CORE + "float"})
#: YAML 1.1 numbers that do not mean what they say to a reader: a leading zero is octal
#: (``0200`` is 128) and ``a:b`` is base 60 (``1:30`` is 90, ``1:30.5`` is 90.5); PyYAML's
#: own patterns for them (``0:30`` is not an integer to it: a text)
_OCTAL = re.compile(r"[-+]?0[0-7_]+")
_BASE_60 = re.compile(
    r"[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\.[0-9_]*"
)
#: longer than this, YAML's reading is not worked out for a message (base 60 grows a number
#: quadratically in its length: a generated ``1:59:59:...`` of a megabyte)
_READING_LIMIT = 40


def yaml11_number_problem(text: str, *, in_a_file: bool = True) -> str | None:
    """What is wrong with ``text`` as a plain scalar, or None: an octal (``0200``) or base-60
    (``1:30``) number, which YAML 1.1 reads as a number other than the digits written (decided:
    refused everywhere, a text slot too, never taken silently as 128 or 90; ``0`` is fine).
    ``in_a_file``: say to quote it for a text (a ``-p`` value is a text unless typed a number)."""
    text = text.strip()
    octal = _OCTAL.fullmatch(text) is not None
    if not octal and _BASE_60.fullmatch(text) is None:
        return None
    reading = _yaml11_reading(text, "int" if octal or "." not in text else "float")
    if octal:
        digits = text.replace("_", "").lstrip("+")
        sign = "-" if digits.startswith("-") else ""
        decimal = sign + (digits.lstrip("-").lstrip("0") or "0")
        what = f"the octal number {reading} (a leading zero)" if reading else "an octal number"
        advice = f"write {decimal}"
        if reading and reading != decimal:
            advice += f" (or {reading} if octal was meant)"
    else:
        what = f"the base-60 number {reading} (a ':')" if reading else "a base-60 number"
        advice = f"write {reading}" if reading else "write the number in decimal"
    quote = "; quote it where a text is meant" if in_a_file else ""
    return f"{quoted(text)} is read by YAML 1.1 as {what}, not as written: {advice}{quote}"


#: a number PyYAML reads that a YAML 1.2 reader takes as a text: ``_`` between digits, binary
_YAML12_TEXT = re.compile(r"[-+]?0b[01_]+|.*_.*")


def yaml12_text_numbers(root: yaml.Node) -> list[tuple[yaml.ScalarNode, PathKey, str]]:
    """Every number of the document (a value, in the order written) that PyYAML reads as a
    number and YAML 1.2's core schema as a text: ``1_000`` (1000 here, the text "1_000" to
    an editor's YAML extension, yaml-language-server; ruamel, check-jsonschema's reader, takes
    both spellings as numbers), ``0b11``; with its path and what to say
    (:func:`yaml12_number_problem`). Octal and base 60 are refused already (:func:`scalar`)."""
    found: list[tuple[yaml.ScalarNode, PathKey, str]] = []
    pending: list[tuple[yaml.Node, PathKey]] = [(root, ())]
    while pending:
        node, path = pending.pop()
        if node.__class__ is yaml.ScalarNode:
            problem = yaml12_number_problem(node) if node.tag in _NUMBER_TAGS else None
            if problem is not None:
                found.append((node, path, problem))
        elif node.__class__ is yaml.SequenceNode:
            pending += ((item, (*path, i)) for i, item in enumerate(node.value))
        elif node.__class__ is yaml.MappingNode:
            pending += ((value, (*path, str(key.value))) for key, value in node.value)
    found.sort(key=lambda each: position(each[0]))
    return found


def yaml12_number_problem(node: yaml.ScalarNode) -> str | None:
    """What a number node written in a YAML 1.1 spelling that YAML 1.2 reads as a text says,
    or None. A warning, not an error: roomba-bt reads it as the number it shows, but an editor
    validating against the JSON Schema, or another program reading the file, sees a text."""
    text = str(node.value)
    if _YAML12_TEXT.fullmatch(text) is None or yaml11_number_problem(text) is not None:
        return None
    reading = _yaml11_reading(text, "int" if node.tag == CORE + "int" else "float")
    if not reading:
        return None
    return (
        f"{quoted(text)} is the number {reading} to roomba-bt (YAML 1.1), but the text "
        f"{quoted(text)} to YAML 1.2 (an editor's YAML extension reads it so): write "
        f"{reading}, or quote it where the text is meant"
    )


def _yaml11_reading(text: str, kind: str) -> str:
    """What PyYAML makes of ``text`` as a ``kind`` ("int", "float"), for a message; "" when
    too long to work out."""
    if len(text) > _READING_LIMIT:
        return ""
    try:
        return str(_CONSTRUCTOR.construct_object(yaml.ScalarNode(CORE + kind, text)))
    except ValueError:
        return ""
    finally:
        _CONSTRUCTOR.constructed_objects.clear()


def _too_many_digits(node: yaml.Node) -> Refused:
    return Refused(problem=too_many_digits(str(node.value)), problem_mark=node.start_mark)


def too_many_digits(text: str) -> str:
    """What is wrong with ``text``, an integer too long for Python to read."""
    digits = sum(c.isdigit() for c in text)
    return (
        f"an integer of {digits:,} digits is too large a number: at most "
        f"{sys.get_int_max_str_digits():,} digits are read (a file generated wrong?)"
    )


class DuplicateKey(Exception):
    """A key written twice in one mapping."""

    def __init__(self, key: Any, node: yaml.Node, first: yaml.Node) -> None:
        super().__init__(f"duplicate key {key!r}")
        self.key = key
        self.node = node
        self.first = first
        #: the key's path, when read by :func:`to_data`
        self.path: PathKey | None = None


def pairs(
    node: yaml.MappingNode, *, skip_duplicates: bool = False
) -> Iterator[tuple[Any, yaml.Node, yaml.Node]]:
    """``(key, key node, value node)`` in written order; raises :class:`DuplicateKey` when a
    key comes again (keys compared by type and value, :func:`_same`: ``1``, ``true`` and
    ``1.0`` are three keys, ``1`` and ``0x1`` one), or with ``skip_duplicates`` leaves it
    out (the first one stands): for a caller that reported every duplicate beforehand
    (:func:`duplicate_keys`) and goes on to the other errors."""
    seen: dict[Any, yaml.Node] = {}
    for key_node, value_node in node.value:
        key = _key(key_node)
        same = _same(key)
        if same in seen:
            if skip_duplicates:
                continue
            raise DuplicateKey(key, key_node, seen[same])
        seen[same] = key_node
        yield key, key_node, value_node


def duplicate_keys(node: yaml.MappingNode) -> list[DuplicateKey]:
    """Every key of ``node`` written again after its first time (compared as :func:`pairs`
    compares them), in written order."""
    seen: dict[Any, yaml.Node] = {}
    found = []
    for key_node, _ in node.value:
        key = _key(key_node)
        same = _same(key)
        if same in seen:
            found.append(DuplicateKey(key, key_node, seen[same]))
        else:
            seen[same] = key_node
    return found


def every_duplicate_key(root: yaml.Node) -> list[DuplicateKey]:
    """Every key written twice in a mapping of the document, each at its second place with
    its :attr:`~DuplicateKey.path`: found before anything is read, so that a reader that then
    leaves them out (``skip_duplicates``) goes on to the file's other errors (a duplicate
    ``tree:`` or ``rooms:`` hid every error inside the first one)."""
    found: list[DuplicateKey] = []
    pending: list[tuple[yaml.Node, PathKey]] = [(root, ())]
    while pending:
        node, path = pending.pop()
        # a scalar holds no mapping: not walked (a file of 68,000 values made a path for each)
        if isinstance(node, yaml.SequenceNode):
            pending += ((item, (*path, i)) for i, item in enumerate(node.value)
                        if item.__class__ is not yaml.ScalarNode)  # fmt: skip
        elif isinstance(node, yaml.MappingNode):
            texts = {k.value for k, _ in node.value if k.tag == STR}
            if len(texts) != len(node.value):  # not all texts, all different (most mappings)
                for dup in duplicate_keys(node):
                    dup.path = (*path, str(dup.key))
                    found.append(dup)
            for key_node, value in node.value:
                if value.__class__ is not yaml.ScalarNode and isinstance(key_node, yaml.ScalarNode):
                    pending.append((value, (*path, str(key_node.value))))
    found.sort(key=lambda dup: position(dup.node))
    return found


def _same(key: Any) -> Any:
    """What two keys must share to be one: a text itself, another value with its type
    (Python's ``1 == True == 1.0`` made ``true:`` a duplicate of ``1:``)."""
    return key if key.__class__ is str else (key.__class__, key)


def _key(key_node: yaml.Node) -> Any:
    """A mapping key as :func:`pairs` compares it: a text as itself, another plain scalar as
    its value, anything else as its text (a tagged key stays a node, for the caller to
    refuse)."""
    if key_node.tag == STR:
        return key_node.value
    try:
        key = scalar(key_node) if is_plain(key_node) else key_node
    except Refused:  # too long a number: a key by its text (no mission or world key is one)
        return str(key_node.value)
    return key if isinstance(key, str | int | float | bool) else str(key)


def to_data(node: yaml.Node, refuse: str, *, skip_duplicates: bool = False) -> tuple[Any, Marks]:
    """The document as plain Python data, and the position of every value by its path
    (``("rooms", 0, 1)``) and of every key (``(..., key, KEY)``). A list or mapping with a
    tag raises :class:`yaml.constructor.ConstructorError` with ``refuse.format(tag=...)``;
    merge keys (``<<: *base``) are merged. A duplicate key raises :class:`DuplicateKey`,
    or with ``skip_duplicates`` is left out (see :func:`every_duplicate_key`)."""
    marks: Marks = {}
    return _data(node, (), marks, refuse, skip_duplicates), marks


def _data(node: yaml.Node, path: PathKey, marks: Marks, refuse: str, skip: bool) -> Any:
    marks[path] = position(node)
    if isinstance(node, yaml.MappingNode | yaml.SequenceNode) and not is_plain(node):
        raise yaml.constructor.ConstructorError(
            None, None, refuse.format(tag=node.tag), node.start_mark
        )
    if isinstance(node, yaml.MappingNode):
        _CONSTRUCTOR.flatten_mapping(node)
        out: dict[Any, Any] = {}
        try:
            for key, key_node, value_node in pairs(node, skip_duplicates=skip):
                if not is_plain(key_node):
                    scalar(key_node)  # raises: no safe constructor for its tag
                if key in out:  # 1, true and 1.0: three keys, one to a dict: keep each
                    key = str(key_node.value)
                marks[(*path, str(key), KEY)] = position(key_node)
                out[key] = _data(value_node, (*path, str(key)), marks, refuse, skip)
        except DuplicateKey as dup:
            if dup.path is None:
                dup.path = (*path, str(dup.key))
            raise
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_data(item, (*path, i), marks, refuse, skip) for i, item in enumerate(node.value)]
    return scalar(node)
