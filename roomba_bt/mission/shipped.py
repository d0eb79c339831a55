"""The missions shipped inside the package, and how a name reaches them.

The shipped missions are package data (``roomba_bt/missions/``, also linked from the
repository's ``missions/``), so an installed wheel has them wherever it was installed:

    roomba-bt run dock --fast                  # no file called "dock": the shipped mission
    roomba-bt run ./dock.yaml                  # a file always wins over a shipped name

A user's mission reaches the shipped library with a name that does not depend on where the
package is installed: an include starting with :data:`SHIPPED_PREFIX` is a path inside the
shipped missions' directory.

    include: [roomba-bt:lib/docking.yaml]      # the shipped docking subtree
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from roomba_bt.behaviours.units import closest
from roomba_bt.mission.values import substituted
from roomba_bt.mission.wording import COMMAND_LINE, Wording
from roomba_bt.printable import LINK_LOOP, broken_link, yaml_written

#: Where the shipped missions live: the package's data directory (a sibling of ``mission/``).
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "missions"

#: Where the simulator's shipped worlds are (:data:`roomba_bt.sim.world.WORLDS_DIR`, the
#: same folder): looked at as files, only to say that a name given for a mission is a
#: world's (:func:`a_world_s_name`); the mission layer imports no simulator
SHIPPED_WORLDS_DIR = SHIPPED_DIR.parent / "sim" / "worlds"

#: An include (or a mission argument) starting with this names a file of the shipped missions'
#: directory, e.g. ``roomba-bt:lib/docking.yaml``.
SHIPPED_PREFIX = "roomba-bt:"

#: The shipped docking library's include name (what ``dock`` and ``patrol`` include).
DOCKING_LIBRARY = f"{SHIPPED_PREFIX}lib/docking.yaml"


#: ``makerspace-bt:lib/x.yaml``: a name before a colon, as a package's (two characters at
#: least: ``C:`` starts a Windows path)
_PACKAGE_PREFIX = re.compile(r"([A-Za-z0-9][A-Za-z0-9._-]+):")


def other_package(text: str) -> str | None:
    """The package an include ``text`` names a file of, when that is not roomba-bt
    (``makerspace-bt:lib/x.yaml`` -> ``makerspace-bt``), or None: no package reaches its
    files through an include but the shipped library, and such a text was looked for as a
    file of that name in the mission's folder ("not found")."""
    match = _PACKAGE_PREFIX.match(text)
    if match is None or text.startswith(SHIPPED_PREFIX):
        return None
    return match.group(1)


@dataclass(frozen=True)
class ShippedLookup:
    """What a mission argument names: ``path`` when found, else ``problem`` (one sentence
    naming what was given and what exists)."""

    path: Path | None
    problem: str = ""


@dataclass(frozen=True)
class ShippedParameter:
    name: str
    type: str
    default: str
    doc: str


@dataclass(frozen=True)
class ShippedMission:
    """What ``roomba-bt missions`` prints of one: the description with the defaults put in."""

    name: str
    path: Path
    description: str
    parameters: tuple[ShippedParameter, ...]


def shipped_missions() -> dict[str, Path]:
    """Name (the file's stem) -> path of every shipped mission, sorted by name."""
    return {p.stem: p for p in sorted(SHIPPED_DIR.glob("*.yaml"))}


def shipped_library_files() -> tuple[str, ...]:
    """The include names of the shipped library files, e.g. ``roomba-bt:lib/docking.yaml``."""
    return tuple(
        SHIPPED_PREFIX + p.relative_to(SHIPPED_DIR).as_posix()
        for p in sorted((SHIPPED_DIR / "lib").glob("*.yaml"))
    )


def library_defining(subtree: str) -> str | None:
    """The include name of the shipped library file that defines ``subtree`` (``dock`` ->
    ``roomba-bt:lib/docking.yaml``), or None: what an unknown subtree's error suggests."""
    for name, subtrees in _library_subtrees():
        if subtree in subtrees:
            return name
    return None


@functools.lru_cache(maxsize=1)
def _library_subtrees() -> tuple[tuple[str, frozenset[str]], ...]:
    """Each shipped library file's include name with the names of its subtrees, read once
    a process: every unknown node's error asks (a mission of 100,000 unknown nodes parsed
    the library's YAML 100,000 times, for hours), and the installed files do not change."""
    found = []
    for name in shipped_library_files():
        path = shipped_file(name)
        if path is None:
            continue
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except (OSError, yaml.YAMLError):
            continue
        subtrees = data.get("subtrees") if isinstance(data, dict) else None
        if isinstance(subtrees, dict):
            found.append((name, frozenset(str(key) for key in subtrees)))
    return tuple(found)


def shipped_file(text: str) -> Path | None:
    """The file a ``roomba-bt:PATH`` name designates, or None if ``text`` is no such name or
    the file does not exist (a name may not climb out of the shipped directory)."""
    if not text.startswith(SHIPPED_PREFIX):
        return None
    relative = text[len(SHIPPED_PREFIX) :]
    target = (SHIPPED_DIR / relative).resolve()
    return target if in_shipped_library(target) else None


def shipped_name(resolved: Path) -> str | None:
    """The name a file of the shipped directory goes by in every installation
    (``roomba-bt:lib/docking.yaml``, what an include writes and a record holds), or None for
    another file. ``resolved``: an absolute path without links, as ``Path.resolve`` gives."""
    if not resolved.is_relative_to(SHIPPED_DIR):
        return None
    return SHIPPED_PREFIX + resolved.relative_to(SHIPPED_DIR).as_posix()


def mission_label(name: str) -> str:
    """How a report labels the mission ``name`` (a results record's, :func:`shipped_name`'s
    for a shipped one): a shipped mission by the name ``roomba-bt missions`` lists and
    ``run`` takes (``dock`` for ``roomba-bt:dock.yaml``), any other name as it is. ``eval``
    said ``variant dock`` and ``eval --from`` of its results ``variant roomba-bt:dock.yaml``."""
    relative = name.removeprefix(SHIPPED_PREFIX)
    if relative == name or "/" in relative or not relative.endswith(".yaml"):
        return name
    return relative.removesuffix(".yaml") if (SHIPPED_DIR / relative).is_file() else name


def in_shipped_library(target: Path) -> bool:
    """``target`` (a resolved path) is a file of the shipped directory: what a
    ``roomba-bt:PATH`` name may designate."""
    return target.is_relative_to(SHIPPED_DIR) and target.is_file()


def find_mission(text: str, wording: Wording = COMMAND_LINE) -> ShippedLookup:
    """A mission argument as the command line takes it: an existing file; else a shipped
    mission's name (``dock``, ``dock.yaml`` or ``roomba-bt:dock.yaml``) or a shipped file's
    path in the shipped directory (``lib/docking.yaml``, as ``roomba-bt missions`` takes it).
    ``wording``: the caller's (``load_mission`` gives its own: no command to list them)."""
    if not text.strip():  # Path("") is the current folder: "a directory" said nothing useful
        lists = f" ({wording.lists_missions.removeprefix('; ')})" if wording.lists_missions else ""
        return ShippedLookup(None, f"{text!r}: an empty path; give a mission file or a shipped "
                             f"mission's name{lists}")  # fmt: skip
    if text == "-":
        return ShippedLookup(None, "reading a mission from standard input is not supported: "
                             "give a file")  # fmt: skip
    given = Path(text)
    try:
        return _find_mission(text, given, wording)
    except OSError as exc:  # a folder on the way the user cannot enter: stat() itself fails
        return ShippedLookup(None, f"cannot read {text}: {exc.strerror or exc}")


def _find_mission(text: str, given: Path, wording: Wording) -> ShippedLookup:
    if given.is_file():
        return ShippedLookup(given)
    named = shipped_file(text)
    if named is not None:
        return ShippedLookup(named)
    shipped = shipped_missions()
    stem = text[: -len(".yaml")] if text.endswith(".yaml") else text
    if "/" not in text and stem in shipped:
        return ShippedLookup(shipped[stem])
    # a shipped library file by its path in the shipped directory, as `roomba-bt missions
    # lib/docking.yaml` prints it (validate said "no such mission file" to the same words)
    library = shipped_file(f"{SHIPPED_PREFIX}{stem}.yaml")
    if library is not None and not given.is_absolute():
        return ShippedLookup(library)
    names = ", ".join(shipped) or "none"
    if given.is_dir():
        return ShippedLookup(None, f"{text}: a directory, not a mission file (a .yaml file)")
    if given.exists():  # a device, a pipe: nothing a mission is read from
        return ShippedLookup(None, f"{text}: not a regular file; a mission is a .yaml file")
    if given.is_symlink():
        return ShippedLookup(None, f"{text}: {_broken_link(given)}")
    base = Path(stem).name
    here = Path(f"{text}.yaml")
    if "/" not in text and not text.endswith(".yaml") and here.is_file():
        hint = f"; did you mean ./{here}?"
    elif base in shipped:  # missions/dock.yaml from a checkout's docs, in an empty folder
        hint = f"; the shipped mission {base!r} is named alone: {base}"
    else:
        hint = closest(base, list(shipped))
    return ShippedLookup(
        None,
        f"{text}: no such mission file, and no shipped mission of that name "
        f"(shipped: {names}{wording.lists_missions}){hint}{a_world_s_name(text, wording)}",
    )


def a_world_s_name(text: str, wording: Wording) -> str:
    """What a name given for a mission is when it is a shipped world's (``validate
    empty-room``, ``load_mission("empty-room")``): how to see that world and run a mission
    in it, in the caller's words; else nothing. The error listed the shipped missions alone,
    as if the name were a typo of one. A path (a ``/`` in it) is a file of the user's."""
    name = text.removesuffix(".yaml")
    if "/" in text or not any(p.stem == name for p in SHIPPED_WORLDS_DIR.glob("*.yaml")):
        return ""
    return f"; {name} is a shipped world, not a mission: " + wording.on_world_name.format(name=name)


def _broken_link(link: Path) -> str:
    """What a symbolic link that leads to no file is: a loop, or a link to nothing."""
    said = broken_link(link)
    return f"{said}, not a mission file" if said == LINK_LOOP else said


def _with_defaults(text: str, params: tuple[ShippedParameter, ...]) -> str:
    """``text`` with its parameters' defaults, as :func:`~roomba_bt.mission.values.substituted`
    reads a mission's (``$$`` one literal ``$``)."""
    defaults = {p.name: p.default for p in params}
    return substituted(text, defaults.get)


def describe_shipped() -> list[ShippedMission]:
    """Each shipped mission's name, description and parameter declarations, read as plain
    data (the files are checked by the tests; listing them compiles nothing)."""
    out = []
    for name, path in shipped_missions().items():
        data: Any = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        params = _declared(data.get("parameters") or {})
        description = _with_defaults(str(data.get("description", "")), params)
        out.append(ShippedMission(name, path, description, params))
    return out


@dataclass(frozen=True)
class LibrarySubtree:
    """What ``roomba-bt missions`` and ``roomba-bt show LIB.yaml`` print of a library's
    subtree: the ``doc:`` its writer gave it appeared nowhere a user looks."""

    name: str
    doc: str
    parameters: tuple[ShippedParameter, ...]
    #: its own blackboard keys (``blackboard:`` in the subtree, each use's own), each as
    #: listed: ``here: mark``, ``n: int, initial 0``
    keys: tuple[str, ...] = ()


def describe_library(text: str) -> tuple[str, list[LibrarySubtree]]:
    """A library file's ``description:`` and each subtree its YAML ``text`` defines (not
    those it includes), in the file's order, read as plain data: the caller has compiled
    the file first (its errors said, never a traceback here)."""
    data: Any = yaml.safe_load(text) or {}
    return str(data.get("description") or ""), [
        LibrarySubtree(
            name,
            str(body.get("doc", "")),
            _declared(body.get("parameters") or {}),
            _own_keys(body.get("blackboard") or {}),
        )
        for name, body in (data.get("subtrees") or {}).items()
    ]


def _own_keys(declared: dict[str, Any]) -> tuple[str, ...]:
    """A subtree's ``blackboard:`` as listed: ``here: mark``, ``n: int, initial 0``, a
    record as ``wp: record``, its ``doc:`` after two spaces."""
    out = []
    for key, decl in declared.items():
        if not isinstance(decl, dict):
            out.append(f"{key}: {decl}")
            continue
        line = f"{key}: {'record' if 'fields' in decl else decl.get('type', '')}"
        if "initial" in decl:
            line += f", initial {yaml_written(decl['initial'])}"
        out.append(line + (f"  {decl['doc']}" if decl.get("doc") else ""))
    return tuple(out)


def _declared(declared: dict[str, Any]) -> tuple[ShippedParameter, ...]:
    """A ``parameters:`` section's declarations as listed: a list parameter's type is said
    with its items' (``list of distance``); one with no default is ``required``."""
    return tuple(
        ShippedParameter(
            pname,
            str(decl.get("type", "")) + (f" of {decl['items']}" if "items" in decl else ""),
            yaml_written(decl["default"]) if "default" in decl else REQUIRED,
            str(decl.get("doc", "")),
        )
        for pname, decl in declared.items()
    )


#: a parameter's ``default`` when it has none: given at every use (or with ``-p``)
REQUIRED = "required"


def parameter_line(param: ShippedParameter) -> str:
    """One parameter as ``missions`` and ``show`` list it: ``laps: int, default 2  doc``."""
    default = param.default if param.default == REQUIRED else f"default {param.default}"
    doc = f"  {param.doc}" if param.doc else ""
    return f"{param.name}: {param.type}, {default}{doc}"
