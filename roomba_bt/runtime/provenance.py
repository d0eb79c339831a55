"""What made a record: the roomba-bt release that ran it, and the files its mission was
compiled from, each by its digest.

A record's header names both (``roomba_bt_version``; ``sources``: the SHA-256 of the mission
file and of each file it included or imported, the mission's first). A record replays
byte for byte only against the files it was made with: when a shipped library changed in a
new release (``roomba-bt:lib/undock.yaml`` came to end in Safe), an owner's old records
differed on replay, and nothing said why, so they hunted for a change in their own mission.
A replay that differs now names each file whose digest is no longer the recorded one.

A file of the shipped missions' folder is named as an include names it
(``roomba-bt:lib/undock.yaml``, ``roomba-bt:dock.yaml``), so the name holds wherever the
package is installed; any other file by its absolute path (the header's ``mission`` is too).
A record made before has neither field: its replay says nothing of them.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from roomba_bt import __version__
from roomba_bt.mission.shipped import SHIPPED_DIR, SHIPPED_PREFIX
from roomba_bt.runtime.recording import MADE_BY, SOURCES


def source_name(path: Path) -> str:
    """``roomba-bt:lib/undock.yaml`` for a shipped file (the same in every installation),
    else the file's absolute path."""
    resolved = path.resolve()
    if resolved.is_relative_to(SHIPPED_DIR):
        return SHIPPED_PREFIX + resolved.relative_to(SHIPPED_DIR).as_posix()
    return str(resolved)


def source_digests(files: Iterable[Path]) -> dict[str, str]:
    """Each file's SHA-256 by :func:`source_name`, in the order given (a compiled mission's
    ``files``: the mission file first). A file gone since it was compiled is left out: there
    is nothing to compare a replay's with."""
    digests: dict[str, str] = {}
    for path in files:
        try:
            digests[source_name(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError:
            continue
    return digests


def changed_sources(header: Mapping[str, Any], files: Iterable[Path]) -> list[str]:
    """What a replay against ``files`` (the mission it compiled) says of the record's
    ``header``: each file the recorded run's mission was compiled from too, whose digest
    changed since (``roomba-bt:lib/undock.yaml changed since this record was made (roomba-bt
    0.2.0 -> 0.3.0): a difference may come from it``). Files are matched by name; a file
    the record does not name (a record made before: none) is not said."""
    recorded = header.get(SOURCES)
    if not isinstance(recorded, Mapping):
        return []
    made_by = header.get(MADE_BY)
    changed = []
    for name, digest in source_digests(files).items():
        was = recorded.get(name)
        if was is None or was == digest:
            continue
        releases = ""
        if name.startswith(SHIPPED_PREFIX) and made_by != __version__:  # a new release's file
            releases = f" (roomba-bt {made_by or 'unknown'} -> {__version__})"
        changed.append(
            f"{name} changed since this record was made{releases}: a difference may come from it"
        )
    return changed
