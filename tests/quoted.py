"""The lines a page of the docs quotes as a command prints them: ``roomba-bt CMD: ...`` in
backquotes. :func:`quotes` finds them, :func:`assert_quoted` holds one to what the command
printed (tests/test_docs_run.py runs the cheap ones' commands; a test that already makes a
harder one, a hung episode or a lost Dask worker, holds the page to its own output).

A quote may leave a part out as ``...``: it stands for any text there (``no such folder;
...``); the rest is compared to the character, the Markdown's line breaks aside."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: a quoted line of a command's: ``roomba-bt run: ...``, ``roomba-bt eval: warning: ...``
QUOTE = re.compile(r"`(roomba-bt [\w-]+: [^`]+)`")


def quotes(doc: str) -> list[str]:
    """Every such quote of the page ``doc`` (a path from the repository's root), in order,
    its line breaks made spaces."""
    text = " ".join((ROOT / doc).read_text(encoding="utf-8").split())
    return QUOTE.findall(text)


#: a number of a quote that gives an example's numbers (``3 episode(s)``, ``seeds 17, 18``)
NUMBER = re.compile(r"\d+(?:\.\d+)?")


def pattern(quote: str, numbers: bool = False) -> re.Pattern[str]:
    """The quote as a pattern of the whole line: ``...`` for any text, with ``numbers`` each
    number for any number, the rest as written."""

    def literal(part: str) -> str:
        if not numbers:
            return re.escape(part)
        return NUMBER.pattern.join(re.escape(piece) for piece in NUMBER.split(part))

    return re.compile(".*".join(literal(part) for part in quote.split("...")))


def assert_quoted(
    doc: str, start: str, printed: str, numbers: bool = False, names: dict[str, str] | None = None
) -> None:
    """Each quote of ``doc`` that begins ``start`` (one, or the same said again) is one of
    the lines ``printed`` (a command's stderr), whitespace runs made one space. With
    ``numbers``, the quote's numbers are an example's (the test makes 4 episodes hang where
    the page says 3) and stand for any number: its words are compared; ``names``, the
    test's paths (a ``tmp_path``'s) each replaced by the page's name of it."""
    quoted = [q for q in quotes(doc) if q.startswith(start)]
    assert quoted, f"{doc} quotes no line that begins {start!r}"
    for name, page_name in (names or {}).items():
        printed = printed.replace(name, page_name)
    lines = [" ".join(line.split()) for line in printed.splitlines()]
    for quote in quoted:
        assert any(pattern(quote, numbers).fullmatch(line) for line in lines), (
            f"{doc} quotes\n{quote}\nwhich the command did not print; it printed:\n{printed}"
        )
