"""The project file: the nearest ``pyproject.toml`` with a ``[tool.roomba-bt]`` table, read
only when it is the user's own.

Settings written once for a project, instead of on every command: its include folders
(``include-dirs``, :mod:`roomba_bt.mission.include_path`, which says what they may grant)
and its robot's model (``profile``, :mod:`roomba_bt.cli.profile_choice`). A project file is
found next to a mission, or above the current directory for a command that reads no mission,
and may have come with what it sits beside (an emailed folder, a cloned repository), so it
is read only when the user running roomba-bt (or root) owns it, as git reads a repository's
configuration: a ``/tmp/pyproject.toml`` another user left is not read.

Below every layer, standard library only (``tomllib``): ``sensors``, ``sim`` and ``doctor``
read the project's profile without loading the mission compiler.
"""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

#: The project file looked for in the starting folder and each folder above it.
PROJECT_FILE = "pyproject.toml"

#: Its table: ``[tool.roomba-bt]``.
PROJECT_TABLE = "roomba-bt"

#: The table's key of the robot's model: ``profile = "roomba500"`` (``include-dirs``, the
#: other, is the mission layer's own).
PROFILE_KEY = "profile"

#: A project file larger than this is not read (as a mission file, yamlsource.read_text):
#: one that came with a stranger's mission is not parsed whatever its size.
MAX_PROJECT_FILE = 1 << 20


def find_project_file(start: Path) -> tuple[Path, object] | str | None:
    """The nearest ``pyproject.toml`` with a ``[tool.roomba-bt]`` table in the folder of
    ``start`` (a file: a mission, or ``cwd / pyproject.toml``) or a folder above it, with
    the table; a warning when the nearest such file cannot be used (unreadable, not TOML,
    owned by another user: the search stops there, so that a broken project file is said
    rather than passed over for one further up); None when there is none. A
    ``pyproject.toml`` without the table (a plugin package's own) is passed over."""
    try:
        first = start.resolve().parent
    except (OSError, RuntimeError):  # a link loop: the loader says so at the mission
        return None
    for folder in (first, *first.parents):
        candidate = folder / PROJECT_FILE
        try:
            if not candidate.is_file():
                continue
            size = candidate.stat().st_size
            if size > MAX_PROJECT_FILE:
                return f"{candidate}: a file of {size:,} bytes, over 1 MiB; not read"
            text = candidate.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            return f"{candidate}: cannot read it ({why(exc)}); its settings not read"
        if PROJECT_TABLE not in text:  # parsed only when it may hold the table
            continue
        try:
            tool = tomllib.loads(text).get("tool")
        except tomllib.TOMLDecodeError as exc:
            return f"{candidate}: not valid TOML ({exc}); its settings not read"
        table = tool.get(PROJECT_TABLE) if isinstance(tool, dict) else None
        if table is None:
            continue
        owner = _foreign_owner(candidate)
        if owner is not None:
            return (
                f"{candidate}: not read, owned by another user ({owner}): a project file "
                "is read only when it is yours (or root's), as git reads a repository's "
                "configuration"
            )
        return candidate, table
    return None


def key_line(project_file: Path, key: str) -> int:
    """The line (1-based) where ``key`` is set in the file's ``[tool.roomba-bt]`` table, for
    a message that names it (``tomllib`` keeps no positions); 0 when it is not found so (a
    dotted or inline-table spelling)."""
    try:
        lines = project_file.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return 0
    setting = re.compile(rf"\s*[\"']?{re.escape(key)}[\"']?\s*=")
    table = re.compile(rf"\s*\[\s*tool\s*\.\s*[\"']?{re.escape(PROJECT_TABLE)}[\"']?\s*\]")
    in_table = False
    for number, line in enumerate(lines, 1):
        if line.lstrip().startswith("["):
            in_table = table.match(line) is not None
        elif in_table and setting.match(line):
            return number
    return 0


def _foreign_owner(path: Path) -> str | None:
    """Who owns ``path`` when it is neither the user running this nor root; None where the
    system has no owners (Windows)."""
    getuid = getattr(os, "getuid", None)
    if getuid is None:
        return None
    owner = path.stat().st_uid
    return None if owner in (getuid(), 0) else f"uid {owner}"


def why(exc: BaseException) -> str:
    """An OS error's reason alone (``Permission denied``), else the error's text."""
    return str(getattr(exc, "strerror", None) or exc)
