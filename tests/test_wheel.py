"""The wheel as its readers meet it: the package index shows README.md as its long description,
and ``roomba-bt docs PAGE --path`` gives a wheel's user a page to open in a Markdown viewer.

The wheel is built here as ``pip wheel`` builds it (``.ci/wheel-check`` does the same), from a
copy of the files it is made of, so that the build writes nothing into the checkout: the
links of README.md pointed into a repository (``docs/robot.md``, ``CONTRIBUTING.md``), dead
on the index's page, as the package names no public repository; and the pages' pictures,
which the wheel leaves out on purpose (pyproject.toml: 1.2 MB beside its 1.6), were bare
titles in a viewer of ``roomba-bt docs PAGE --path`` (session 39's stranger).
"""

from __future__ import annotations

import posixpath
import re
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from email.parser import Parser
from pathlib import Path, PurePosixPath

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: what the wheel is made of (pyproject.toml's package and its readme and licence)
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "MANIFEST.in")
#: how a wheel's user or an index reader gets the source distribution, where the files a
#: wheel leaves out are (the words of ``roomba-bt docs``'s own message)
SDIST = "pip download --no-deps --no-binary :all: roomba-bt"
#: a Markdown link or picture: ``[text](target)``, ``![alt](target)``
LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\]]*\])*)\]\(([^)\s]+)\)")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Iterator[zipfile.ZipFile]:
    """The wheel built from a copy of the package's files (``roomba_bt/docs``, a link to the
    repository's ``docs/``, copied as the files it links, as the sdist holds them)."""
    tree = tmp_path_factory.mktemp("tree")
    for name in SOURCES:
        shutil.copy2(ROOT / name, tree / name)
    shutil.copytree(
        ROOT / "roomba_bt", tree / "roomba_bt", ignore=shutil.ignore_patterns("__pycache__")
    )
    dist = tmp_path_factory.mktemp("dist")
    done = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet",
         "--disable-pip-version-check", "--wheel-dir", str(dist), str(tree)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    offline = r"(?i)no matching distribution|could not find a version|network is unreachable"
    if done.returncode != 0 and re.search(offline, done.stderr):
        # pip fetches the build backend, setuptools>=77, from an index: none here (offline)
        pytest.skip(
            "needs setuptools>=77 from a package index to build the wheel: pip "
            f"install 'setuptools>=77' where one is reachable ({done.stderr[-500:]})"
        )
    assert done.returncode == 0, f"pip wheel failed:\n{done.stdout}{done.stderr}"
    [built] = dist.glob("roomba_bt-*.whl")
    archive = zipfile.ZipFile(built)
    yield archive
    archive.close()


def long_description(wheel: zipfile.ZipFile) -> str:
    [metadata] = [n for n in wheel.namelist() if n.endswith(".dist-info/METADATA")]
    message = Parser().parsestr(wheel.read(metadata).decode("utf-8"))
    assert message["Description-Content-Type"] == "text/markdown"
    return str(message.get_payload())


def shipped_pages(wheel: zipfile.ZipFile) -> dict[str, str]:
    """The pages ``roomba-bt docs`` lists, by name, as the wheel holds them."""
    return {
        PurePosixPath(n).stem: wheel.read(n).decode("utf-8")
        for n in wheel.namelist()
        if re.fullmatch(r"roomba_bt/docs/[\w-]+\.md", n)
    }


def test_the_long_description_is_the_readme(wheel: zipfile.ZipFile) -> None:
    assert long_description(wheel).strip() == (ROOT / "README.md").read_text("utf-8").strip()


def test_every_link_of_the_index_page_leads_somewhere_a_reader_can_go(
    wheel: zipfile.ZipFile,
) -> None:
    """The index shows the long description with its links as written, and the package names
    no repository (no Project-URL): a relative link there leads nowhere. Each relative link
    to a page says, as its text, the command that prints the page from the installed wheel
    (``roomba-bt docs robot``), which holds it; a link to another file of the repository's
    says, after it, the command that downloads the source distribution, which holds it."""
    text = long_description(wheel)
    pages = shipped_pages(wheel)
    links = LINK.findall(text)
    assert len(links) > 10, "README.md lost its links to the pages"
    lost = []
    for match in LINK.finditer(text):
        picture, label, target = match.groups()
        if re.match(r"https?://", target):
            continue
        path = target.split("#", 1)[0]
        page = re.fullmatch(r"docs/([\w-]+)\.md", path)
        if page and not picture:
            if page[1] not in pages:
                lost.append(f"{target}: a page the wheel does not hold")
            elif label != f"`roomba-bt docs {page[1]}`":
                lost.append(f"[{label}]({target}): its text is not `roomba-bt docs {page[1]}`")
            continue
        after = " ".join(text[match.end() : match.end() + 400].split())
        if not (ROOT / path).is_file() or SDIST not in after:
            lost.append(f"{match[0]}: not followed by where it is ({SDIST})")
    assert not lost, "links of the index page that lead nowhere:\n" + "\n".join(lost)


def test_the_pages_pictures_say_what_they_show_and_where_they_are(
    wheel: zipfile.ZipFile,
) -> None:
    """A picture the wheel leaves out shows, in a Markdown viewer, as its alternative text:
    that text says what the picture shows (a sentence, not a file's title) and where the
    picture is, its path in the source distribution, which the page says how to fetch."""
    held = set(wheel.namelist())
    pictures = 0
    bare = []
    for name, page in shipped_pages(wheel).items():
        for match in LINK.finditer(page):
            picture, alt, target = match.groups()
            if not picture or re.match(r"https?://", target):
                continue
            pictures += 1
            if f"roomba_bt/docs/{target}" in held:
                continue
            alt = " ".join(alt.split())
            source = f"docs/{target}"
            if len(alt.split()) < 12 or source not in alt or "source distribution" not in alt:
                bare.append(f"{name}.md: ![{alt}]({target})")
            elif SDIST not in " ".join(page.split()):
                bare.append(f"{name}.md: says nowhere how to fetch the source ({SDIST})")
    assert pictures >= 7, "the pages lost their pictures"
    assert not bare, "pictures the wheel leaves out and the page does not explain:\n" + "\n".join(
        bare
    )


def test_every_link_of_a_shipped_page_leads_to_a_file_of_the_wheel(
    wheel: zipfile.ZipFile,
) -> None:
    """The pages link one another, which the wheel holds beside them; docs/ci.md linked
    ``../CONTRIBUTING.md``, which it does not: such a link says, after it, the command that
    downloads the source distribution, which holds it."""
    held = set(wheel.namelist())
    lost = []
    for name, page in shipped_pages(wheel).items():
        for match in LINK.finditer(page):
            picture, _, target = match.groups()
            if picture or re.match(r"https?://|#", target):
                continue
            path = posixpath.normpath(f"roomba_bt/docs/{target.split('#', 1)[0]}")
            after = " ".join(page[match.end() : match.end() + 400].split())
            if path not in held and SDIST not in after:
                lost.append(f"{name}.md: {match[0]}")
    assert not lost, "links of the installed pages to files the wheel lacks:\n" + "\n".join(lost)


def test_every_picture_of_the_docs_is_shown_by_a_page() -> None:
    """``docs/images/monitor-node-menu.png`` was made by ``make monitor-screenshots`` and
    shipped in the source distribution, and no page showed it: a picture no page shows is
    checked against nothing (its tree's labels had gone stale). Each is shown by a page of
    ``docs/`` or README.md, or deleted. Read from the files: no wheel needed."""
    shown = set()
    for page in (ROOT / "README.md", *(ROOT / "docs").glob("*.md")):
        folder = page.parent.relative_to(ROOT).as_posix()
        for match in LINK.finditer(page.read_text(encoding="utf-8")):
            if match[1] and not re.match(r"https?://", match[3]):
                shown.add(posixpath.normpath(posixpath.join(folder, match[3])))
    pictures = {p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").rglob("*.png")}
    assert "docs/images/monitor-dock-approach.png" in pictures  # the pictures are found
    assert not pictures - shown, f"pictures no page shows: {sorted(pictures - shown)}"
