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
Standard library only (``tomllib``).
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

#: The environment variable of include folders, ``os.pathsep``-separated (``:``, ``;`` on
#: Windows), as ``PYTHONPATH`` is.
INCLUDE_PATH_VARIABLE = "ROOMBA_BT_INCLUDE_PATH"

#: The project file looked for in the mission's folder and each folder above it.
PROJECT_FILE = "pyproject.toml"

#: Its table and key: ``[tool.roomba-bt]`` ``include-dirs = ["missions/common"]``.
PROJECT_TABLE = "roomba-bt"
INCLUDE_DIRS_KEY = "include-dirs"

#: A project file larger than this is not read (as a mission file, yamlsource.read_text):
#: one that came with a stranger's mission is not parsed whatever its size.
MAX_PROJECT_FILE = 1 << 20

#: Where a user reads about it, said in every message that names these settings.
DOCUMENTED_AT = "docs/missions.md, Include folders"


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


def find_project_file(mission: Path) -> tuple[Path, object] | str | None:
    """The nearest ``pyproject.toml`` with a ``[tool.roomba-bt]`` table in the mission's
    folder or a folder above it, with the table; a warning when the nearest such file
    cannot be used (unreadable, not TOML, owned by another user: the search stops there, so
    that a broken project file is said rather than passed over for one further up); None
    when there is none. A ``pyproject.toml`` without the table (a plugin package's own) is
    passed over."""
    try:
        start = mission.resolve().parent
    except (OSError, RuntimeError):  # a link loop: the loader says so at the mission
        return None
    for folder in (start, *start.parents):
        candidate = folder / PROJECT_FILE
        try:
            if not candidate.is_file():
                continue
            size = candidate.stat().st_size
            if size > MAX_PROJECT_FILE:
                return f"{candidate}: a file of {size:,} bytes, over 1 MiB; not read"
            text = candidate.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            return f"{candidate}: cannot read it ({_why(exc)}); its include-dirs not read"
        if PROJECT_TABLE not in text:  # parsed only when it may hold the table
            continue
        try:
            tool = tomllib.loads(text).get("tool")
        except tomllib.TOMLDecodeError as exc:
            return f"{candidate}: not valid TOML ({exc}); its include-dirs not read"
        table = tool.get(PROJECT_TABLE) if isinstance(tool, dict) else None
        if table is None:
            continue
        owner = _foreign_owner(candidate)
        if owner is not None:
            return (
                f"{candidate}: not read, owned by another user ({owner}): a project file "
                "grants include folders only when it is yours (or root's), as git reads a "
                "repository's configuration"
            )
        return candidate, table
    return None


def _from_project_file(project_file: Path, table: object) -> tuple[list[Path], list[str]]:
    """The folders ``include-dirs`` names, relative to the project file's folder, each
    inside that folder's tree (symbolic links followed): a project file that came with a
    mission grants nothing beyond what came with it."""
    where = f"{project_file}: [tool.{PROJECT_TABLE}]"
    if not isinstance(table, dict):
        return [], [f"{where} is not a table; write it as [tool.{PROJECT_TABLE}]"]
    warnings = [
        f"{where}: unknown key {key!r}; known: {INCLUDE_DIRS_KEY}"
        for key in table
        if key != INCLUDE_DIRS_KEY
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
                    f"{entry!r} is outside this file's folder ({folder}): a project file "
                    "grants only folders inside its own folder tree; give it with "
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
            return f"{entry!r} is a file, not a folder: give its folder ({folder.parent})"
    except (OSError, RuntimeError) as exc:  # a link loop, a folder the user cannot enter
        return f"{entry!r} cannot be read ({_why(exc)})"
    return f"{entry!r} is no folder (looked for {folder.absolute()})"


def _foreign_owner(path: Path) -> str | None:
    """Who owns ``path`` when it is neither the user running this nor root; None where the
    system has no owners (Windows)."""
    getuid = getattr(os, "getuid", None)
    if getuid is None:
        return None
    owner = path.stat().st_uid
    return None if owner in (getuid(), 0) else f"uid {owner}"


def _why(exc: BaseException) -> str:
    return str(getattr(exc, "strerror", None) or exc)
