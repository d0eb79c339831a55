"""``roomba-bt docs``: the user's pages installed with the package. Messages sent a wheel's
user to "roomba-bt's repository: docs/evaluation.md", with no address (the package names no
project URL); they name ``roomba-bt docs PAGE`` now, which prints the page wherever
roomba-bt is installed (``roomba_bt/docs``: the repository's ``docs/``, shipped in the
wheel)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.cli.docs_cmd import DOCS_DIR, pages

PACKAGE = Path(__file__).resolve().parents[2] / "roomba_bt"
#: modules whose texts name a page by its path on purpose: the tools that write the
#: repository's pages themselves (``make routines``, ``make coverage``, the modes page)
WRITERS = ("evaluate/report.py", "evaluate/coverage_report.py", "robot/docgen.py")


def test_docs_lists_every_page_with_its_title_and_prints_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["docs"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^evaluation +Evaluating missions", out, re.M), out
    assert f"{len(pages())} pages in {DOCS_DIR}" in out
    assert {"missions", "runtime", "evaluation", "routines", "plugins"} <= set(pages())
    for given in ("evaluation", "evaluation.md", "docs/evaluation.md"):
        assert main(["docs", given]) == 0
        assert capsys.readouterr().out == (DOCS_DIR / "evaluation.md").read_text(encoding="utf-8")
    assert main(["docs", "runtime", "--path"]) == 0
    assert capsys.readouterr().out == f"{DOCS_DIR / 'runtime.md'}\n"


def test_an_unknown_page_is_refused_with_the_pages_there_are(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["docs", "evaluaton"]) == 2
    err = capsys.readouterr().err
    assert "roomba-bt docs: no page 'evaluaton' (did you mean 'evaluation'?); there are: " in err


def _texts(path: Path) -> list[tuple[int, str]]:
    """Every string of ``path`` a user may read: its constants but its docstrings."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
        and node.body
        and isinstance(node.body[0], ast.Expr)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str)
        and id(node) not in docstrings
    ]  # fmt: skip


@pytest.mark.parametrize(
    "path",
    sorted(p for p in PACKAGE.rglob("*.py") if p.relative_to(PACKAGE).as_posix() not in WRITERS),
    ids=lambda p: p.relative_to(PACKAGE).as_posix(),
)
def test_a_message_names_a_page_as_the_command_that_prints_it(path: Path) -> None:
    """No message, help text or mission's word names a page by a path a wheel does not
    hold (``docs/runtime.md``) or a repository it gives no address of; each ``roomba-bt
    docs PAGE`` a message names is an installed page."""
    for line, text in _texts(path):
        assert not re.search(r"docs/[\w-]+\.md|roomba-bt's repository", text), (line, text)
        for page in re.findall(r"roomba-bt docs ([\w-]+)", text):
            assert page in pages() or page == "PAGE", (line, text)
