"""A mission as a self-contained bundle of texts, so an episode needs no shared file system.

A Dask worker on another machine has neither the mission file nor the libraries it includes
nor a world file given by path. :func:`bundle_mission` reads the mission and every file it
names in ``include:`` and ``plugins:`` (recursively, as the loader resolves them: relative to
the file naming them) into a :class:`MissionSources`: each file's text under its path
relative to the files' common folder. :meth:`MissionSources.materialise` writes them once per
process into a private temporary folder with the same layout and returns the mission's path
there, so the loader reads exactly the bytes the submitting machine read and reports the same
diagnostics. A world given by path, or one of ``ROOMBA_BT_WORLDS``'s by its name, travels the
same way (:func:`bundle_world`).

An include of the shipped library (``roomba-bt:lib/docking.yaml``) is not copied: the loader
reads it from the installed package, like the code itself, so workers must run the same
roomba-bt release as the submitting machine (they must anyway, for the same results).

The bundle is plain data (tuples of strings): small (the dock mission and its library are a
few kB), picklable, hashable; its digest names the folder, so many episodes of one bundle
share one copy.
"""

from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import yaml

from roomba_bt import yamlsource
from roomba_bt.mission.shipped import SHIPPED_PREFIX, shipped_file
from roomba_bt.sim.world import WORLDS_DIR, named_world

#: The sections of a mission (or included) file that name other files to bring along.
FILE_LISTS = ("include", "plugins")


@dataclass(frozen=True)
class MissionSources:
    """The texts of a mission and the files it names, relative to their common folder."""

    #: the mission file's path relative to the common folder (posix separators)
    main: str
    #: (relative path, text) of every file, the mission's first
    files: tuple[tuple[str, str], ...]

    @property
    def digest(self) -> str:
        h = hashlib.sha256()
        for name, text in self.files:
            h.update(name.encode() + b"\0" + text.encode() + b"\0")
        return h.hexdigest()[:16]

    def materialise(self) -> Path:
        """The mission's path in this process's copy of the bundle (written on first use)."""
        folder = _COPIES.get(self.digest)
        if folder is None:
            folder = Path(tempfile.mkdtemp(prefix=f"roomba-bt-{self.digest}-"))
            for name, text in self.files:
                target = folder / name
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_text(text, encoding="utf-8")
            _COPIES[self.digest] = folder
        return folder / self.main


_COPIES: dict[str, Path] = {}


@atexit.register
def remove_copies() -> None:
    """This process's copies of the bundles removed: at its exit, and on a local Dask
    cluster's worker as the cluster closes (a worker its nanny kills then runs no atexit)."""
    for folder in _COPIES.values():
        shutil.rmtree(folder, ignore_errors=True)
    _COPIES.clear()


def _named_files(path: Path) -> list[Path]:
    """The files ``path`` names in its include/plugins lists (unreadable ones are skipped:
    the loader reports them when the mission is checked)."""
    try:
        data = yaml.safe_load(yamlsource.read_text(path))
    except (OSError, UnicodeDecodeError, yaml.YAMLError, yamlsource.FileTooLarge):
        return []
    if not isinstance(data, dict):
        return []
    out = []
    for key in FILE_LISTS:
        entries = data.get(key)
        if isinstance(entries, list):
            out += [(path.parent / e).resolve() for e in entries
                    if isinstance(e, str) and not e.startswith(SHIPPED_PREFIX)]  # fmt: skip
    return out


def bundle_mission(path: str | Path) -> MissionSources:
    """The mission at ``path`` (a file, or a shipped mission's name as ``eval`` names it in
    its results: ``roomba-bt:dock.yaml``) and every file it names, transitively, as texts."""
    main = (shipped_file(str(path)) or Path(path)).resolve()
    seen: list[Path] = []
    pending = [main]
    while pending:
        current = pending.pop(0)
        if current in seen or not current.is_file():
            continue
        seen.append(current)
        pending += _named_files(current)
    root = Path(os.path.commonpath([p.parent for p in seen]))
    files = tuple((p.relative_to(root).as_posix(), p.read_text(encoding="utf-8")) for p in seen)
    return MissionSources(main.relative_to(root).as_posix(), files)


def bundle_world(world: str) -> tuple[str, str] | None:
    """``(file name, text)`` of a world given by path, or by its name in a folder of
    ``ROOMBA_BT_WORLDS`` (a worker on another machine has neither); None for a shipped
    world's name (every installation has those)."""
    path = Path(world)
    if not path.is_file():
        named = named_world(world)
        if named is None or named.parent == WORLDS_DIR:
            return None
        path = named
    return (path.name, path.read_text(encoding="utf-8"))
