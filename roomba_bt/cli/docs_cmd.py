"""``roomba-bt docs``: roomba-bt's documentation as installed with it, its pages listed or one
printed.

Messages (a shipped mission's parameters, a run started in a worker thread) sent their reader
to "roomba-bt's repository: docs/evaluation.md", with no address to it: a wheel's user has
no repository, and the package names no project URL. The pages ship in the package
(``roomba_bt/docs``: the repository's ``docs/`` folder, by a link, as ``missions/`` and
``worlds/`` link into the package the other way), and a message names the command that
prints one, ``roomba-bt docs evaluation``, which works wherever roomba-bt is installed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from roomba_bt.cli.arguments import add_command
from roomba_bt.runtime.summary import ExitCode

#: Where the pages are installed (in a checkout, a link to the repository's ``docs/``).
DOCS_DIR = Path(__file__).resolve().parent.parent / "docs"


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "docs",
        docs_command,
        """list roomba-bt's documentation, or print a page of it

        List the pages of roomba-bt's documentation installed with it, each with its title,
        and the folder they are in. With PAGE, print that page (Markdown; roomba-bt docs
        evaluation | less); with --path, its file's path instead (for an editor or a
        Markdown viewer). The messages that send you to a page name it so: roomba-bt docs
        evaluation, "What a patrol's lap is".
        """,
    )
    parser.add_argument(
        "page", nargs="?", metavar="PAGE", help="print this page (missions, runtime, ...)"
    )
    parser.add_argument(
        "--path", action="store_true", help="print the page's path (or the folder's) instead"
    )


def pages() -> dict[str, Path]:
    """The installed pages by name (``evaluation`` for ``evaluation.md``), in name order."""
    if not DOCS_DIR.is_dir():
        return {}
    return {path.stem: path for path in sorted(DOCS_DIR.glob("*.md"))}


def title(path: Path) -> str:
    """A page's first heading (``# Evaluation`` -> ``Evaluation``), or "" if it has none."""
    with path.open(encoding="utf-8") as text:
        for line in text:
            if line.startswith("# "):
                return line[2:].strip()
    return ""


def docs_command(args: argparse.Namespace) -> int:
    from roomba_bt.behaviours.units import closest
    from roomba_bt.printable import ANY_CONTROL, escaped

    found = pages()
    if not found:
        print(f"roomba-bt docs: no pages in {DOCS_DIR}: this installation holds none (a "
              "package built without them); they are the docs/ folder of roomba-bt's source "
              "distribution (pip download --no-deps --no-binary :all: roomba-bt)",
              file=sys.stderr)  # fmt: skip
        return ExitCode.INVALID
    if args.page is None:
        if args.path:
            print(DOCS_DIR)
            return ExitCode.OK
        width = max(len(name) for name in found)
        for name, page in found.items():
            print(f"{name:<{width}}  {title(page)}")
        print(f"\n{len(found)} pages in {DOCS_DIR}; roomba-bt docs PAGE prints one")
        return ExitCode.OK
    # docs/evaluation.md, evaluation.md and evaluation name one page, as the messages say it
    name = args.page.replace("\\", "/").rsplit("/", 1)[-1].removesuffix(".md")
    path = found.get(name) or found.get(name.lower())
    if path is None:
        shown = escaped(args.page, ANY_CONTROL)
        print(f"roomba-bt docs: no page {shown!r}{closest(name, list(found))}; there are: "
              f"{', '.join(found)}", file=sys.stderr)  # fmt: skip
        return ExitCode.INVALID
    if args.path:
        print(path)
    else:
        sys.stdout.write(path.read_text(encoding="utf-8"))
    return ExitCode.OK
