"""What the sdist and the wheel built from it must hold (called by .ci/sdist-check).

The sdist is where Debian, Fedora and conda-forge run the tests (docs/releasing.md), so it
holds every file of the tree it was built from (a clean copy of the tracked files, with the
clutter of a working tree added on purpose), except :data:`NOT_IN_SDIST`, plus what
setuptools writes (:data:`GENERATED`); nothing more, nothing less. The wheel holds the package
and its licence only.

    python .ci/sdist_contents.py TREE SDIST WHEEL CLUTTER...

CLUTTER are the paths (relative to TREE) the caller added as a working tree's leftovers: none
may be in the sdist. Exit 0 when all holds, 1 with every difference named.
"""

from __future__ import annotations

import os
import sys
import tarfile
import zipfile
from email.parser import HeaderParser
from pathlib import Path, PurePosixPath

#: tracked files the sdist leaves out on purpose: CI's own scripts and git's ignore list
NOT_IN_SDIST = (".ci/", ".gitignore")
#: what setuptools writes into an sdist beside the tree's files
GENERATED = ("PKG-INFO", "setup.cfg", "roomba_bt.egg-info/")
#: what every test run from the sdist reads: said by name when missing, before the full list
TESTS_READ = (
    "tests/conftest.py",
    "tests/golden/scenarios.py",
    "docs/architecture.md",
    "missions/dock.yaml",
    "missions/lib/docking.yaml",
    "worlds/empty-room.yaml",
    "plugins/roomba-bt-dirt/pyproject.toml",
    "bench/__init__.py",
    "Makefile",
    "LICENSE",
)


def tree_files(tree: Path) -> set[str]:
    """Every file under ``tree``, by its path from it, through linked folders (``missions/lib``
    and ``worlds`` are links, and setuptools copies what they hold)."""
    return {
        (Path(folder) / name).relative_to(tree).as_posix()
        for folder, _, files in os.walk(tree, followlinks=True)
        for name in files
    }


def sdist_problems(tree: Path, sdist: Path, clutter: list[str]) -> list[str]:
    with tarfile.open(sdist) as archive:
        members = [m for m in archive.getmembers() if not m.isdir()]
    top = PurePosixPath(members[0].name).parts[0]
    held = {PurePosixPath(m.name).relative_to(top).as_posix() for m in members}
    # a leftover is one through a linked folder too (roomba_bt/docs is docs/, by a link)
    expected = {
        f for f in tree_files(tree)
        if not f.startswith(NOT_IN_SDIST) and not any(f.endswith(f"/{c}") for c in clutter)
    } - set(clutter)  # fmt: skip
    problems = [f"the tests read {name}, and the sdist lacks it" for name in TESTS_READ
                if name not in held]  # fmt: skip
    problems += [f"a working tree's {name} is in the sdist" for name in clutter if name in held]
    problems += [f"missing from the sdist: {name}" for name in sorted(expected - held)
                 if name not in TESTS_READ]  # fmt: skip
    unexpected = held - expected - set(clutter)
    problems += [f"in the sdist, not in the tree: {name}" for name in sorted(unexpected)
                 if not name.startswith(GENERATED)]  # fmt: skip
    links = [m.name for m in members if m.issym() or m.islnk()]
    problems += [f"a link in the sdist, which a packager's copy may not keep: {name}"
                 for name in links]  # fmt: skip
    return problems


def wheel_problems(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        (metadata,) = [n for n in names if n.endswith(".dist-info/METADATA")]
        headers = HeaderParser().parsestr(archive.read(metadata).decode())
    problems = [f"in the wheel, outside the package: {name}" for name in names
                if not name.startswith(("roomba_bt/", "roomba_bt-"))]  # fmt: skip
    if not any(n.endswith(".dist-info/licenses/LICENSE") for n in names):
        problems.append("the wheel holds no .dist-info/licenses/LICENSE")
    if headers["License-Expression"] != "MIT" or headers["License-File"] != "LICENSE":
        problems.append("the wheel's METADATA lacks License-Expression: MIT, License-File: LICENSE")
    return problems


def main(argv: list[str]) -> int:
    tree, sdist, wheel, *clutter = argv
    problems = sdist_problems(Path(tree), Path(sdist), clutter) + wheel_problems(Path(wheel))
    for problem in problems:
        print(f"sdist-check: {problem}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
