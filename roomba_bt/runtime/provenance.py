"""What made a record: the roomba-bt release that ran it, the files its mission was compiled
from, and the installed plugins its behaviours came from, each by its digest.

A record's header names them (``roomba_bt_version``; ``sources``: the SHA-256 of the mission
file and of each file it included or imported, the mission's first; ``plugins``: each
installed plugin distribution that provides a behaviour of the mission's tree, its version
and the SHA-256 of its modules' files). A record replays byte for byte only against what it
was made with: when a shipped library changed in a new release (``roomba-bt:lib/undock.yaml``
came to end in Safe), an owner's old records differed on replay, and nothing said why, so
they hunted for a change in their own mission; a plugin upgraded (or edited in an editable
install) did the same with no digest to say so. A replay that differs names each file and
plugin that is no longer the recorded one, and one whose bytes are the same says in one
line that the record was made with other files (:func:`drift_line`).

A file of the shipped missions' folder is named as an include names it
(``roomba-bt:lib/undock.yaml``, ``roomba-bt:dock.yaml``), so the name holds wherever the
package is installed; any other file by its absolute path. The header's ``mission`` is named
the same way (:func:`source_name`): a record of ``roomba-bt run dock`` replays on any machine.
A record made before has none of the fields: its replay says nothing of them.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from py_trees.behaviour import Behaviour

from roomba_bt import __version__
from roomba_bt.behaviours.declare import Declaration
from roomba_bt.behaviours.registry import ENTRY_POINT_GROUP, group_entry_points
from roomba_bt.mission import shipped
from roomba_bt.runtime.recording import (
    MADE_BY,
    PLUGINS,
    SOURCES,
    header_text,
    recorded_path,
)

#: a plugin's provenance: its distribution's version and its modules' digest
VERSION, DIGEST = "version", "sha256"


def source_name(path: Path, folder: Path | None = None) -> str:
    """``roomba-bt:lib/undock.yaml`` for a shipped file (the same in every installation);
    else, given the record's ``folder``, the file's path relative to it (``../missions/x.yaml``)
    when the two lie under a common folder below the file system's root (:func:`near`), the
    same in every checkout of a repository that holds both; else the file's absolute path."""
    resolved = path.resolve()
    name = shipped.shipped_name(resolved)
    if name is not None:
        return name
    if folder is not None and near(resolved, folder.resolve()):
        return Path(os.path.relpath(resolved, folder.resolve())).as_posix()
    return str(resolved)


def near(path: Path, folder: Path) -> bool:
    """Whether ``path`` and ``folder`` (both absolute) share a folder below the file system's
    root: a mission and the record of it in one repository (``repo/missions/x.yaml``,
    ``repo/records/x.jsonl``) do, and a checkout moved or cloned elsewhere keeps the path
    from one to the other. Only ``/`` in common (``/home/me/x.yaml``, ``/mnt/usb/r.jsonl``):
    the absolute path is the better guess, for the record is likely to move alone."""
    common = Path(os.path.commonpath([path, folder]))
    return common != Path(common.anchor)


def source_digests(files: Iterable[Path], folder: Path | None = None) -> dict[str, str]:
    """Each file's SHA-256 by :func:`source_name` (relative to ``folder``, the record's, where
    near it), in the order given (a compiled mission's ``files``: the mission file first). A
    file gone since it was compiled is left out: there is nothing to compare a replay's with."""
    digests: dict[str, str] = {}
    for path in files:
        digest = file_digest(path)
        if digest is not None:
            digests[source_name(path, folder)] = digest
    return digests


def file_digest(path: Path) -> str | None:
    """The SHA-256 of the file at ``path``, None when it cannot be read."""
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def plugin_digests(root: Behaviour) -> dict[str, dict[str, str]]:
    """Each installed plugin distribution that provides a behaviour of the tree ``root``:
    ``{"roomba-bt-dirt": {"version": "0.1.0", "sha256": ...}}``, by name. The digest is of
    the ``.py`` files of its top-level packages that hold those behaviours, read where Python
    imported them from (an editable install's source tree too, whose distribution lists no
    module file). A plugin installed but unused by the mission is left out: it cannot change
    the run. A plugin file a mission names (``plugins: [./x.py]``) is a source file instead."""
    used = {
        type(node).__module__.partition(".")[0]
        for node in root.iterate()
        if isinstance(getattr(node, "declaration", None), Declaration)
    }
    used.discard("roomba_bt")  # the built-ins: the release says them
    if not used:  # no entry point read (a scan of the installed distributions)
        return {}
    packages: dict[str, dict[str, str]] = {}  # distribution -> its packages used -> version
    for ep in group_entry_points(ENTRY_POINT_GROUP):
        top = ep.module.partition(".")[0]
        if top in used and ep.dist is not None:
            packages.setdefault(ep.dist.name, {})[top] = ep.dist.version
    return {
        name: {VERSION: next(iter(tops.values())), DIGEST: _package_digest(sorted(tops))}
        for name, tops in sorted(packages.items())
    }


def _package_digest(tops: list[str]) -> str:
    """SHA-256 over each ``.py`` file of the imported packages (or modules) ``tops``: its
    package and path within it, then its bytes' digest, in path order; a file that cannot
    be read counts as empty."""
    total = hashlib.sha256()
    for top in tops:
        module = sys.modules.get(top)
        places = list(getattr(module, "__path__", ()) or ())
        file = getattr(module, "__file__", None)
        if not places and file:  # a single-module plugin
            files = [(Path(file).name, Path(file))]
        else:
            files = sorted(
                (path.relative_to(place).as_posix(), path)
                for place in map(Path, places)
                for path in place.rglob("*.py")
                if "__pycache__" not in path.parts
            )
        for relative, path in files:
            try:
                data = path.read_bytes()
            except OSError:
                data = b""
            total.update(f"{top}/{relative}\0{hashlib.sha256(data).hexdigest()}\n".encode())
    return total.hexdigest()


def changed_sources(
    header: Mapping[str, Any], files: Iterable[Path], record: Path | None = None
) -> list[str]:
    """What a replay against ``files`` (the mission it compiled, its file first) says of the
    record's ``header`` (the record at ``record``): each file the recorded run's mission was
    compiled from too, whose digest changed since (``roomba-bt:lib/undock.yaml changed since
    this record was made (roomba-bt 0.2.0 -> 0.3.0): a difference may come from it``). A file
    the record does not name (a record made before: none) is not said.

    Files are matched by where they lie from their mission (:func:`_by_place`): the mission
    file with the recorded one, ``../common/lib/escapes.yaml`` beside the recorded mission
    with the one beside the replay's, whatever folder either checkout is in, and with
    ``--mission``. They were matched by absolute path, and a record replayed in another
    checkout (CI's) named no change at all."""
    recorded = header.get(SOURCES)
    if not isinstance(recorded, Mapping) or not recorded:
        return []
    files = list(files)
    was = _by_place(
        [(name, recorded_path(name, header, record)) for name in recorded], recorded.values()
    )
    was_at = {str(where): (name, digest) for name, where, digest in was.values() if where}
    now = _by_place([(source_name(path), path.resolve()) for path in files], None)
    made_by = header.get(MADE_BY)
    changed = []
    for place, (name, where, digest) in now.items():
        before = was.get(place, (None, None, None))[2] or was_at.get(str(where), (None, None))[1]
        if before is None or before == digest:
            continue
        recorded_as = Path(was[""][0]).name if place == "" and "" in was else None
        if recorded_as is not None and recorded_as != Path(name).name:  # replay --mission
            changed.append(
                f"{_shown(name)} is not the recorded mission {recorded_as}: a difference may "
                "come from it"
            )
            continue
        releases = ""
        if name.startswith(shipped.SHIPPED_PREFIX) and made_by != __version__:  # a release's
            releases = f" (roomba-bt {made_by or 'unknown'} -> {__version__})"
        changed.append(
            f"{_shown(name)} changed since this record was made{releases}: a difference may "
            "come from it"
        )
    return [header_text(line) for line in changed]


def _by_place(
    files: list[tuple[str, Path | None]], digests: Iterable[str] | None
) -> dict[str, tuple[str, Path | None, str | None]]:
    """Each file ``(name, where)`` (a mission's, its own first) by its place from the mission:
    ``""`` for the mission itself, a shipped file's name, else its path relative to the
    mission's folder (its name where it cannot be found: a relative name of a record made
    before); its name, where it is and its digest (``digests``, in the same order; None: the
    file's, read now)."""
    places: dict[str, tuple[str, Path | None, str | None]] = {}
    digest_of = iter(digests) if digests is not None else None
    home = files[0][1].parent if files and files[0][1] is not None else None
    for index, (name, where) in enumerate(files):
        if digest_of is not None:
            digest = next(digest_of, None)
        else:
            digest = file_digest(where) if where is not None else None
        if index == 0:
            place = ""
        elif name.startswith(shipped.SHIPPED_PREFIX) or where is None or home is None:
            place = name
        else:
            place = Path(os.path.relpath(where, home)).as_posix()
        places[place] = (name, where, digest)
    return places


def _shown(name: str) -> str:
    """A file's name as a replay says it: relative to the working folder when it lies in it
    (``missions/common/lib/escapes.yaml``, as the user typed it), else as it is."""
    path = Path(name)
    if path.is_absolute():
        with contextlib.suppress(ValueError):
            return path.relative_to(Path.cwd()).as_posix()
    return name


def changed_plugins(header: Mapping[str, Any], root: Behaviour) -> list[str]:
    """Each plugin distribution whose behaviours the recorded run or the replay's tree
    ``root`` used, that is not now what it was (``plugin roomba-bt-dirt changed since this
    record was made (0.1.0 -> 0.2.0): a difference may come from it``): another version, the
    same version with other code (an editable install, a rebuild), gone from the tree
    (uninstalled, or its behaviours now from elsewhere), or new to it. A record made before
    plugins were recorded says nothing."""
    recorded = header.get(PLUGINS)
    if not isinstance(recorded, Mapping):
        return []
    now = plugin_digests(root)
    changed = []
    for name in sorted(set(recorded) | set(now)):
        was: Mapping[str, str] | None = recorded.get(name)
        is_ = now.get(name)
        if was == is_:
            continue
        if was is None and is_ is not None:
            what = (f"plugin {name} {is_[VERSION]} provides behaviours of this replay and "
                    "provided none of the recorded run's")  # fmt: skip
        elif was is not None and is_ is None:
            what = (f"plugin {name} {was[VERSION]} provided behaviours of the recorded run and "
                    "provides none of this replay's (uninstalled, or they come from elsewhere "
                    "now)")  # fmt: skip
        elif was is not None and is_ is not None and was[VERSION] != is_[VERSION]:
            what = (f"plugin {name} changed since this record was made ({was[VERSION]} -> "
                    f"{is_[VERSION]})")  # fmt: skip
        else:
            what = (f"plugin {name} {(is_ or {}).get(VERSION)}'s code changed since this record "
                    "was made (the same version: an editable install, or a rebuild)")  # fmt: skip
        changed.append(f"{what}: a difference may come from it")
    return [header_text(line) for line in changed]


@dataclass(frozen=True)
class AbsentPlugin:
    """A plugin distribution a record's run used (its header's ``plugins``) that is not
    installed here as it was: ``installed`` is the version here, None when there is none."""

    name: str
    version: str
    installed: str | None

    @property
    def short(self) -> str:
        """``plugin roomba-bt-lab 0.1.0, not installed`` (``0.2.0 installed`` for another
        version): an unknown node's note, where a "did you mean" would send the user to a
        built-in the plugin's behaviour is not."""
        here = "not installed" if self.installed is None else f"{self.installed} installed"
        return f"plugin {self.name} {self.version}, {here}"

    def said(self) -> str:
        """What a replay or the monitor says first when the recorded mission does not
        compile: ``this record was made with plugin roomba-bt-lab 0.1.0, which is not
        installed (pip install roomba-bt-lab==0.1.0)``."""
        here = (
            "which is not installed" if self.installed is None
            else f"and {self.installed} is installed"
        )  # fmt: skip
        return (
            f"this record was made with plugin {self.name} {self.version}, {here} "
            f"(pip install {self.name}=={self.version})"
        )


def absent_plugins(header: Mapping[str, Any]) -> list[AbsentPlugin]:
    """Each plugin distribution the record's header names that is not installed here, or
    not at the recorded version (its code is :func:`changed_plugins`' to compare, once the
    mission compiles); none for a record made before plugins were recorded."""
    recorded = header.get(PLUGINS)
    if not isinstance(recorded, Mapping):
        return []
    absent = []
    for name, was in sorted(recorded.items()):
        version = was.get(VERSION) if isinstance(was, Mapping) else None
        if not isinstance(name, str) or not isinstance(version, str):
            continue
        try:
            installed: str | None = metadata.version(name)
        except metadata.PackageNotFoundError:
            installed = None
        if installed != version:
            absent.append(AbsentPlugin(name, version, installed))
    return absent


def changed_since(
    header: Mapping[str, Any], files: Iterable[Path], root: Behaviour, record: Path | None = None
) -> list[str]:
    """Every file (:func:`changed_sources`) and plugin (:func:`changed_plugins`) of the
    record's (at ``record``) that the replay's mission (its ``files``, its tree ``root``) has
    otherwise."""
    return [*changed_sources(header, files, record), *changed_plugins(header, root)]


#: the CHANGELOG's section for a 0.1.0 set-up (records, missions and plugins of 0.1.0)
UPGRADING = "Upgrading from 0.1.0"


def made_by_said(header: Mapping[str, Any]) -> str:
    """The release that made the record, as a replay says it: ``roomba-bt 0.2.0``, or for a
    header that names none (``roomba_bt_version`` is written since 0.2.0) what that tells."""
    made_by = header.get(MADE_BY)
    if isinstance(made_by, str):
        return f"roomba-bt {header_text(made_by)}"
    return "roomba-bt 0.1.0 or earlier, as the record names no release"


def drift_line(
    header: Mapping[str, Any], sources: list[str], plugins: list[str], *, same_bytes: bool
) -> str | None:
    """One line saying that the replay ran on other code than the record was made with
    (``recorded with roomba-bt 0.2.0 (this is 0.3.0); 1 of its 3 source files and 1 plugin
    differ now``), or None when nothing differs; ``sources`` and ``plugins``: what
    :func:`changed_sources` and :func:`changed_plugins` said. ``same_bytes``: the replay
    wrote the recorded bytes, and a release alone is not said then (the bytes are the news:
    an older record that still replays is the common case, and a line on every one would be
    noise); when they differ it is, for a runtime that changed may be the cause where no
    file did. A record made before ``roomba_bt_version`` was written (by 0.1.0) is said as
    such when its bytes differ, with where its changes are listed: its replay said only the
    opcode of the first difference, and the upgrader had to work out the cause from it."""
    made_by = header.get(MADE_BY)
    if not isinstance(made_by, str):
        if same_bytes:
            return None
        return (
            f"recorded by {made_by_said(header)}; this is {__version__}: what replays "
            f'differently is in the CHANGELOG, "{UPGRADING}"'
        )
    release = made_by != __version__
    if not sources and not plugins and (same_bytes or not release):
        return None
    said = []
    if sources:
        recorded = header.get(SOURCES)
        total = len(recorded) if isinstance(recorded, Mapping) else len(sources)
        said.append(f"{len(sources)} of its {total} source file{'s' * (total != 1)}")
    if plugins:
        said.append(f"{len(plugins)} plugin{'s' * (len(plugins) != 1)}")
    which = f"this is {__version__}" if release else "this release too"
    line = f"recorded with roomba-bt {made_by} ({which})"
    if said:
        verb = "differs" if len(sources) + len(plugins) == 1 else "differ"
        line += f"; {' and '.join(said)} {verb} now"
    return header_text(line)
