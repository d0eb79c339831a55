"""A behaviour's entry in docs/missions.md's reference, made from its declaration.

``roomba-bt behaviours --markdown NAME`` prints it for a contributor to paste, and
tests/mission/test_docs.py holds the page to the same function: one definition of what an
entry says, so the command and the check cannot drift apart (the entries were typed by hand
and matched to the test's own copy of these rules, one failure at a time).
"""

from __future__ import annotations

from roomba_bt.behaviours.declare import Declaration, Param

#: the parameter table's head, as every entry on the page has it
TABLE_HEAD = (
    "| parameter | type | range | default | meaning |",
    "|---|---|---|---|---|",
)


def entry_text(decl: Declaration) -> str:
    """The entry's first line after the name: the declaration's text on one line, with the
    reST double backquotes of a docstring written as Markdown's single ones."""
    return " ".join(decl.doc.replace("``", "`").split())


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
    return "" if param.default is None else f"`{param.default}`"


def param_row(param: Param) -> tuple[str, str, str, str, str]:
    """A parameter table row's columns: name, type, range, default, meaning."""
    return (
        f"`{param.name}`",
        param.type.describe(),
        param_span(param),
        param_default(param),
        param.doc,
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
