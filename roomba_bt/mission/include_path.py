"""Include folders granted once for every command: ``ROOMBA_BT_INCLUDE_PATH`` and a project
file's ``include-dirs`` under ``[tool.roomba-bt]`` in ``pyproject.toml``.

A team keeps its library beside its missions (``missions/common/lib``), and a mission in a
sibling folder includes it (``../common/lib/safe_drive.yaml``). Granted only by
``--include-dir``, that folder had to be named on every ``validate``, ``run``, ``eval``,
``replay``, ``show`` and ``monitor``, in CI, in pre-commit and in each developer's shell; one
forgotten and the mission did not compile. Here the same grant is written once.

An include folder is a permission (:class:`~roomba_bt.mission.loader.Permissions`: a mission
file is data and reads nothing outside its own folder tree and the shipped library unless
the user allows it), so where it may come from follows who is trusted:

- ``ROOMBA_BT_INCLUDE_PATH`` is the user's own, like ``--include-dir``: folders separated as
  in ``PYTHONPATH`` (``os.pathsep``), relative ones read from the current directory.
- A project file is found next to the mission, and may have come with it (an emailed folder,
  a cloned repository). It may only widen a mission's reach to folders inside the project
  file's own folder tree, symbolic links followed (files that came with it, never
  ``~/.ssh`` or ``..``), and it is read only when the user running roomba-bt (or root) owns
  it, as git reads a repository's configuration (a ``/tmp/pyproject.toml`` another user left
  grants nothing). It never grants plugin files: ``--allow-plugin-files`` stays the command
  line's.

Entries that grant nothing are returned as warnings, never as errors: the include they were
meant for is then refused at its line, which says where it looked and how to allow it.
Standard library only; the project file is found by :mod:`roomba_bt.project`.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from roomba_bt.printable import path_written
from roomba_bt.project import PROFILE_KEY, PROJECT_FILE, PROJECT_TABLE, find_project_file, why

__all__ = [  # the project file's names too, where the loader's messages take them
    "DOCUMENTED_AT",
    "INCLUDE_DIRS_KEY",
    "INCLUDE_PATH_VARIABLE",
    "PROJECT_FILE",
    "PROJECT_TABLE",
    "IncludeGrant",
    "configured_include_dirs",
    "granted_files",
]

#: The environment variable of include folders, ``os.pathsep``-separated (``:``, ``;`` on
#: Windows), as ``PYTHONPATH`` is.
INCLUDE_PATH_VARIABLE = "ROOMBA_BT_INCLUDE_PATH"

#: Its key: ``[tool.roomba-bt]`` ``include-dirs = ["missions/common"]``.
INCLUDE_DIRS_KEY = "include-dirs"

#: The other keys the table may hold, read elsewhere: the robot's model (cli/profile_choice.py).
OTHER_KEYS = (PROFILE_KEY,)

#: Where a user reads about it, said in every message that names these settings: the help
#: an installed user has (it said docs/missions.md, which the wheel does not ship).
DOCUMENTED_AT = "roomba-bt run --help, --include-dir"


@dataclass(frozen=True, slots=True)
class IncludeGrant:
    """The include folders configured for one mission, resolved, and why any entry grants
    nothing (``warnings``, each a whole sentence naming where the entry is written)."""

    folders: tuple[Path, ...] = ()
    warnings: tuple[str, ...] = ()
    #: the project file read (None: none found, or it was not read)
    project_file: Path | None = None


def configured_include_dirs(
    mission: str | Path | None, environ: Mapping[str, str] | None = None
) -> IncludeGrant:
    """The folders ``ROOMBA_BT_INCLUDE_PATH`` (from ``environ``, the process's environment
    by default) and the project file above ``mission`` grant to it: what the command line
    adds to its ``--include-dir`` folders. ``mission`` None: the environment's only."""
    env = os.environ if environ is None else environ
    folders, warnings = _from_environment(env.get(INCLUDE_PATH_VARIABLE, ""))
    project_file = None
    if mission is not None:
        found = find_project_file(Path(mission))
        if isinstance(found, str):
            warnings.append(found)
        elif found is not None:
            project_file, table = found
            granted, refused = _from_project_file(project_file, table)
            folders += granted
            warnings += refused
    unique = tuple(dict.fromkeys(folders))
    return IncludeGrant(unique, tuple(warnings), project_file)


def _from_environment(value: str) -> tuple[list[Path], list[str]]:
    """The folders of ``ROOMBA_BT_INCLUDE_PATH``; an empty entry is skipped (``a::b``, a
    trailing separator), as ``PYTHONPATH``'s are."""
    folders: list[Path] = []
    warnings: list[str] = []
    for entry in value.split(os.pathsep):
        if not entry.strip():
            continue
        folder = Path(entry)
        problem = _not_a_folder(folder, entry)
        if problem is not None:
            warnings.append(f"{INCLUDE_PATH_VARIABLE}: {problem}; not granted")
            continue
        folders.append(folder.resolve())
    return folders, warnings


def _from_project_file(project_file: Path, table: object) -> tuple[list[Path], list[str]]:
    """The folders ``include-dirs`` names, relative to the project file's folder, each
    inside that folder's tree (symbolic links followed): a project file that came with a
    mission grants nothing beyond what came with it."""
    where = f"{project_file}: [tool.{PROJECT_TABLE}]"
    if not isinstance(table, dict):
        return [], [f"{where} is not a table; write it as [tool.{PROJECT_TABLE}]"]
    known = (INCLUDE_DIRS_KEY, *OTHER_KEYS)
    warnings = [
        f"{where}: unknown key {key!r}; known: {', '.join(known)}"
        for key in table
        if key not in known
    ]
    entries = table.get(INCLUDE_DIRS_KEY, [])
    if not isinstance(entries, list) or not all(isinstance(e, str) for e in entries):
        warnings.append(
            f"{where} {INCLUDE_DIRS_KEY}: a list of folders is expected "
            f'({INCLUDE_DIRS_KEY} = ["missions/common"]); not granted'
        )
        return [], warnings
    root = project_file.parent.resolve()
    folders: list[Path] = []
    for entry in entries:
        folder = project_file.parent / entry
        problem = _not_a_folder(folder, entry)
        if problem is None:
            folder = folder.resolve()
            if not folder.is_relative_to(root):
                problem = (
                    f"{path_written(entry)} is outside this file's folder ({folder}): a project "
                    "file grants only folders inside its own folder tree; give it with "
                    f"--include-dir or {INCLUDE_PATH_VARIABLE}"
                )
        if problem is not None:
            warnings.append(f"{where} {INCLUDE_DIRS_KEY}: {problem}; not granted")
            continue
        folders.append(folder)
    return folders, warnings


def _not_a_folder(folder: Path, entry: str) -> str | None:
    """Why ``folder`` (written ``entry``) is no folder to grant, or None."""
    try:
        if folder.is_dir():
            folder.resolve()
            return None
        if folder.is_file():
            return (
                f"{path_written(entry)} is a file, not a folder: give its folder ({folder.parent})"
            )
    except (OSError, RuntimeError) as exc:  # a link loop, a folder the user cannot enter
        return f"{path_written(entry)} cannot be read ({why(exc)})"
    return f"{path_written(entry)} is no folder (looked for {folder.absolute()})"


#: at most this many files of the granted folders are looked at for a hint (an included
#: file moved, a subtree's library not included): a home folder granted whole is not walked
#: to its end
FILES_LOOKED_AT = 5_000


def granted_files(roots: Iterable[Path], limit: int = FILES_LOOKED_AT) -> Iterator[Path]:
    """The files of ``roots`` (the folders a mission may include from), in name order,
    hidden folders left out, at most ``limit``: where an error's hint looks for the file a
    mission may have meant."""
    seen = 0
    for root in roots:
        for folder, folders, files in os.walk(root):
            folders[:] = sorted(f for f in folders if not f.startswith("."))
            for name in sorted(files):
                seen += 1
                if seen > limit:
                    return
                yield Path(folder) / name
