"""What of a text may reach a terminal or a log line as it is: the control characters a
stranger's file can carry, the invisible ones that reorder or hide what is shown, and
:func:`escaped` to show them as ``\\x1b`` or ``\\u202e``; a path quoted as it was written
(:func:`path_written`, one backslash where the file has one); and a duration as a person reads it
(:func:`duration_said`: ``1 d``, not ``86400 s``), the one spelling of every layer's messages;
a long name or value cut with its length said (:func:`shortened`, :func:`name_shown`); and a
long list of errors cut after its first hundred, how many more said (:func:`listed`); a
value as a mission writes it (:func:`yaml_written`: ``true``, not Python's ``True``).

Standard library only and importing nothing of ours, so that every layer may use it, the
protocol's included, and the command line's parser can say a name without loading YAML
(:mod:`roomba_bt.yamlsource` refuses :data:`CONTROL` characters in a file; this module only
shows them)."""

from __future__ import annotations

import errno
import math
import os
import re
import stat

__all__ = [
    "ANY_CONTROL", "CONTROL", "INVISIBLE", "MAX_FOUND", "MAX_LISTED", "NAME_LIMIT", "TEXT_LIMIT",
    "UNPRINTABLE", "duration_said", "duration_words", "encodes", "escaped", "listed",
    "more_listed", "name_shown", "shortened", "stopped_finding", "stopped_warning",
    "yaml_written",
]  # fmt: skip

#: Characters no text of a data file may hold (C0 but tab and newline, DEL, C1): a file
#: travels between strangers, and its texts reach the terminal (``show``, the live tree, the
#: log, error lines), where ``"\e[2J"`` clears the screen and ``"\e]0;...\a"`` retitles it
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")
#: Characters a terminal does not show but that change what it shows ("Trojan Source"): the
#: bidi embeddings, overrides and isolates (U+202A-U+202E, U+2066-U+2069), the marks (U+061C,
#: U+200E, U+200F), and the zero-width characters (U+200B-U+200D, U+2060, U+FEFF). A file may
#: hold them (a name in Arabic needs them), so they are escaped where printed, never refused:
#: ``gentle<U+202E> s/mm 005`` rendered as "gentle 500 mm/s" in the live tree and the log
INVISIBLE_CHARACTERS = "\u061c\u200b-\u200f\u202a-\u202e\u2060\u2066-\u2069\ufeff"
INVISIBLE = re.compile(f"[{INVISIBLE_CHARACTERS}]")
#: what is escaped in printed text that may span lines (an error line's message, a log
#: record): :data:`CONTROL` and :data:`INVISIBLE`
UNPRINTABLE = re.compile(f"[\x00-\x08\x0b-\x1f\x7f-\x9f{INVISIBLE_CHARACTERS}]")
#: every control and invisible character, tab and newline too: what must stay on one line (a
#: node's name in the live tree, the log and a run's summary, where "\n[ok] robot stopped"
#: would fake a line; a file name in ``validate``'s lines)
ANY_CONTROL = re.compile(f"[\x00-\x1f\x7f-\x9f{INVISIBLE_CHARACTERS}]")


def escaped(text: str, which: re.Pattern[str] = UNPRINTABLE) -> str:
    """``text`` with each character ``which`` matches written as ``\\x1b`` (``\\u202e`` past
    U+00FF): an error line, a node's name or a mission's text is printed to a terminal, where a
    raw ``ESC [2J`` would clear the screen and a raw U+202E reverse what follows
    (:data:`ANY_CONTROL`: a newline too, for what is one line)."""
    if which.search(text) is None:
        return text
    return which.sub(_escape, text)


def _escape(found: re.Match[str]) -> str:
    code = ord(found.group())
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"


#: How much of a name a stranger wrote (a mission's, a node's) one line shows: a name is a
#: few words, and a 200 KB ``mission:`` name was printed whole by ``show``, the live tree and
#: the run's summary (200 KB on the terminal, once each)
NAME_LIMIT = 80
#: How much of a text a stranger wrote (a mission's ``description:``, a ``log`` message, a
#: run's label read from a record) one line shows: a sentence or a short paragraph, six
#: lines of a terminal at most. A 10 MB description was printed whole by ``show``
TEXT_LIMIT = 500


def shortened(text: str, limit: int = NAME_LIMIT, length: int | None = None) -> str:
    """``text`` cut to ``limit`` characters, as a compiler cuts a long name it quotes: an
    ellipsis and the whole length said (``length``, when ``text`` is a quoting of a longer
    value: its own), ``NNNN... (200,000 characters)``; a text that fits is as it is."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text) if length is None else length:,} characters)"


#: How many errors a command lists of one file (decided: a compiler's convention), a
#: mission's (``mission.diagnostics.MAX_REPORTED``) and a world's alike. A stranger's file of
#: 1 MiB can hold 350,000 errors (an alias, a duplicate key, repeated), and a world of 20,000
#: bad obstacles printed 20,000 lines: the first hundred say what is wrong, the rest would
#: only scroll them away
MAX_LISTED = 100


#: How many errors a file's check finds before it stops (decided), a mission's tree being cut
#: at as many nodes (``mission.nodes.MAX_TREE_NODES``, "a file generated wrong?"): a world of
#: 150,000 bad points built 150,000 problems (6 s, 350 MB) to list the first hundred.
MAX_FOUND = 10_000


def stopped_finding(limit: int = MAX_FOUND) -> str:
    """What a check stopped at :data:`MAX_FOUND` says, at the place it stopped (the last of
    its ``limit`` errors), worded as the mission's tree cut at as many nodes."""
    return (
        f"checking stopped here, at {limit:,} errors (at most {limit:,} are said): the rest of "
        "the file is not checked (a file generated wrong?)"
    )


def stopped_warning(limit: int = MAX_FOUND) -> str:
    """What a mission's check says in place of its warnings past :data:`MAX_FOUND`, at the
    place it stopped keeping them: it goes on for errors (a warning never stops a mission
    that compiles), but a file of 1 MiB held 260,000 warnings, each one more to sort."""
    return (
        f"warnings stopped here, at {limit:,} (at most {limit:,} are said): the rest of the "
        "file is checked for errors only (a file generated wrong?)"
    )


def more_listed(count: int, noun: str = "errors", limit: int = MAX_LISTED) -> str:
    """The line that ends a list cut after its first ``limit``: ``... and 19,900 more errors
    (the first 100 are listed)``."""
    return f"... and {count:,} more {noun} (the first {limit} are listed)"


def listed(lines: list[str], limit: int = MAX_LISTED) -> list[str]:
    """``lines`` (errors, one a line), the first ``limit`` of them and :func:`more_listed`."""
    if len(lines) <= limit:
        return lines
    return [*lines[:limit], more_listed(len(lines) - limit, limit=limit)]


def name_shown(name: str, limit: int = NAME_LIMIT) -> str:
    """A name (or, with :data:`TEXT_LIMIT`, a text) on one line of the terminal:
    :func:`shortened`, then :func:`escaped` with :data:`ANY_CONTROL` (cut first, so an
    escape is never cut in half)."""
    return escaped(shortened(name, limit), ANY_CONTROL)


def path_written(text: str) -> str:
    """A path a stranger wrote, quoted in a message: ``repr``'s quotes and escapes, but each
    backslash as the file writes it. ``'lib\\moves.yaml'``, doubled, sent a student searching
    the file for two, and a Windows path ``'C:\\lab\\x.py'`` read as no path they wrote."""
    return repr_written(text)


#: what :func:`broken_link` says of a link that leads back to itself
LINK_LOOP = "a symbolic link loop (it leads back to itself)"


def broken_link(link: os.PathLike[str]) -> str:
    """What a symbolic link that leads to no file is, a mission's or a world's: a loop
    (:data:`LINK_LOOP`), or a link to nothing (a world's said "no such file")."""
    try:
        os.stat(link)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return LINK_LOOP
    return f"a broken symbolic link (to {os.readlink(link)!r}, which does not exist)"


def special_file(path: os.PathLike[str]) -> str | None:
    """What ``path`` is when it is neither a regular file nor a folder (a named pipe, a
    device, a socket, a broken link or a link loop), None otherwise (one of those, or
    nothing there): "there is no such directory" was said of a pipe that is there."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return broken_link(path) if os.path.islink(path) else None
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return None


def repr_written(value: object) -> str:
    """``repr(value)`` with each backslash as it was written (:func:`path_written`): a
    value a message quotes, a text or a list of them; its control characters stay escaped
    (``'\\x1b'``), which a terminal would obey."""
    return repr(value).replace("\\\\", "\\")


def yaml_written(value: object) -> str:
    """``value`` (a default, an initial value) as a mission file writes it: ``true``,
    ``false`` and ``null``, not Python's ``True``, ``False`` and ``None``, which
    ``roomba-bt behaviours``, its generated docs and ``missions`` printed (a mission that
    wrote ``True`` got it as YAML 1.1 reads it, a user who wrote ``None`` a text); ``.inf``
    and ``.nan``; a list or a mapping in YAML's flow style, its items alike."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return ".nan" if math.isnan(value) else ("-.inf" if value < 0 else ".inf")
    if isinstance(value, list | tuple):
        return "[" + ", ".join(map(yaml_written, value)) + "]"
    if isinstance(value, dict):
        pairs = (f"{yaml_written(key)}: {yaml_written(item)}" for key, item in value.items())
        return "{" + ", ".join(pairs) + "}"
    return str(value)


def encodes(stream: object, text: str) -> bool:
    """Whether ``stream``'s encoding can write ``text`` (``✓``, ``m²``): False on an ASCII
    or Latin-1 stdout (``PYTHONIOENCODING=ascii``, ``LC_ALL=POSIX`` with ``PYTHONUTF8=0``),
    where the caller says it in ASCII (``[ok]``, ``m2``) rather than as ``\u2713``. A stream
    without an encoding (a ``StringIO``) takes any text."""
    encoding = getattr(stream, "encoding", None)
    if not encoding:
        return True
    try:
        text.encode(encoding)
    except (UnicodeError, LookupError):
        return False
    return True


#: the units :func:`duration_words` says a duration in, largest first, in seconds (the
#: mission language's own spelling: ``1 h 30 min`` reads back as a duration)
_DURATION_WORDS = (("d", 86400), ("h", 3600), ("min", 60), ("s", 1))


def duration_words(seconds: float) -> str:
    """A duration as a person says a long one, to the second: ``4 h 12 min 3 s``, ``12 h``,
    ``45 s``, ``1 d 2 h`` (units that are 0 left out)."""
    left = round(seconds)
    parts = []
    for unit, size in _DURATION_WORDS:
        count, left = divmod(left, size)
        if count:
            parts.append(f"{count} {unit}")
    return " ".join(parts) or "0 s"


def duration_said(seconds: float) -> str:
    """A duration a message names (a time limit, a wait): ``45 s`` or ``0.25 s`` under a
    minute, in words from a minute on when it is whole seconds (``1 d``, ``1 h 30 min``,
    :func:`duration_words`), else as it is (``90.5 s``). ``--timeout 1d`` ran out as
    ``--timeout 86400 s``, and a reader had to divide to know it was the day they gave."""
    if seconds < 60 or seconds != int(seconds):
        return f"{seconds:g} s"
    return duration_words(seconds)
