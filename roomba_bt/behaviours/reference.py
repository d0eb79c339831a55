"""A behaviour's entry in docs/missions.md's reference, made from its declaration.

``roomba-bt behaviours --markdown NAME`` prints it for a contributor to paste, and
tests/mission/test_docs.py holds the page to the same function: one definition of what an
entry says, so the command and the check cannot drift apart (the entries were typed by hand
and matched to the test's own copy of these rules, one failure at a time).
"""

from __future__ import annotations

import re

from roomba_bt.behaviours.declare import Declaration, Param
from roomba_bt.printable import yaml_written

#: the parameter table's head, as every entry on the page has it
TABLE_HEAD = (
    "| parameter | type | range | default | meaning |",
    "|---|---|---|---|---|",
)


#: a reST role: ``:class:`~pkg.Name```, ``:py:func:`f```, ``:ref:`title <target>```
_ROLE = re.compile(r":(?:[\w-]+:)?[\w-]+:`([^`]+)`")
#: a reST hyperlink, ```text <https://...>`_`` or ```name`_``
_LINK = re.compile(r"`([^`<]+?)\s*(?:<([^`>]+)>)?`__?")
#: reST's inline literal, ````text````
_LITERAL = re.compile(r"``(.+?)``")
#: reST's strong and emphasis, ``**text**`` and ``*text*``: a star that opens one is
#: followed by a character that is no space (``ASCII 32..126 but * + @`` keeps its stars)
_STRESSED = re.compile(r"(?<![\w*])\*\*?(\S(?:[^*]*?\S)?)\*\*?(?![\w*])")


def _role_said(content: str) -> str:
    """What a role shows: its title where it gives one (``title <target>``), else its
    target's last name where it starts with ``~`` (Sphinx's rule), else its target."""
    titled = re.fullmatch(r"(.+?)\s*<[^>]+>", content)
    if titled is not None:
        return titled.group(1)
    target = content.lstrip("!")
    return target[1:].rsplit(".", 1)[-1] if target.startswith("~") else target


def inline_text(text: str) -> str:
    """``text`` (a docstring's first paragraph, a parameter's ``doc``) with its reST inline
    markup as a terminal and Markdown both read it: a literal (````key````) and a role
    (``:class:`~pkg.Name```) as code in single backquotes (`` `key` ``, `` `Name` ``), a
    link as its text and address, strong and emphasis as their words, and a paragraph's
    closing ``::`` as one colon. ``roomba-bt behaviours`` printed a plugin's docstring as
    written: ``sends its own :class:`Safe` first``, ````own_mode````. No reST parser (a
    dependency, and a docstring is no document): what a docstring's first paragraph holds."""
    text = _ROLE.sub(lambda m: f"`{_role_said(m.group(1))}`", text)
    text = _LITERAL.sub(r"`\1`", text)
    text = _LINK.sub(lambda m: m.group(1) + (f" ({m.group(2)})" if m.group(2) else ""), text)
    text = _STRESSED.sub(r"\1", text)
    return text[:-1] if text.endswith("::") else text


def entry_text(decl: Declaration) -> str:
    """The entry's first line after the name: the declaration's text on one line, its reST
    inline markup written as Markdown reads it (:func:`inline_text`)."""
    return " ".join(inline_text(decl.doc).split())


def param_span(param: Param) -> str:
    """The range column: ``lo..hi``, either end left open; empty for an unbounded one."""
    if param.minimum is None and param.maximum is None:
        return ""
    low = "" if param.minimum is None else f"{param.minimum:g}"
    high = "" if param.maximum is None else f"{param.maximum:g}"
    return f"{low}..{high}"


def param_default(param: Param) -> str:
    """The default column: **required**, the default as code, or empty (optional, none)."""
    if param.required:
        return "**required**"
    return "" if param.default is None else f"`{yaml_written(param.default)}`"


def param_row(param: Param) -> tuple[str, str, str, str, str]:
    """A parameter table row's columns: name, type, range, default, meaning."""
    return (
        f"`{param.name}`",
        param.type.describe(),
        param_span(param),
        param_default(param),
        inline_text(param.doc),
    )


def markdown_entry(decl: Declaration) -> str:
    """The whole entry: ``**`name`**: text`` with Markdown's line break (two spaces), then
    the parameter table (none for a behaviour without parameters). The page may say more
    after the text; the packets, commands and modes line is written by hand beside it."""
    lines = [f"**`{decl.name}`**: {entry_text(decl)}  "]
    if decl.params:
        lines += ["", *TABLE_HEAD]
        lines += ["| " + " | ".join(param_row(p)) + " |" for p in decl.params]
    return "\n".join(lines) + "\n"
