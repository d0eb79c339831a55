"""``roomba-bt show LIB.yaml``: a library of subtrees listed (each with its ``doc:`` and its
parameters), or one of them drawn with ``--subtree NAME``.

A library has no tree of its own, and ``show`` refused it ("a library ... not run"): a
maintainer had no way to see what a library offers but to read its YAML, and the ``doc:``
fields written for each subtree appeared nowhere.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import yaml

from roomba_bt.mission.compiler import MissionText
from roomba_bt.mission.shipped import REQUIRED, LibrarySubtree, parameter_line
from roomba_bt.printable import ANY_CONTROL, escaped
from roomba_bt.runtime.summary import ExitCode


def print_subtrees(subtrees: list[LibrarySubtree], indent: str = "") -> None:
    """Each subtree by name and ``doc:``, its parameters under it (type, default, doc)."""
    for subtree in subtrees:
        doc = f"  {subtree.doc}" if subtree.doc else ""
        print(escaped(f"{indent}{subtree.name}{doc}", ANY_CONTROL))
        for param in subtree.parameters:
            print(escaped(f"{indent}    {parameter_line(param)}", ANY_CONTROL))
        for key in subtree.keys:  # each use's own (docs/missions.md, Subtrees)
            print(escaped(f"{indent}    own key {key}", ANY_CONTROL))


def library_listed(file: str, subtrees: list[LibrarySubtree], description: str) -> int:
    """``show LIB.yaml``: what the library holds, and how to draw or use one."""
    header = f"{file}: {description.strip()}".rstrip(": ")
    print(escaped(header, ANY_CONTROL))
    count = f"{len(subtrees)} subtree{'s' if len(subtrees) != 1 else ''}"
    print(f"a library of {count}, to be included (draw one: roomba-bt show {file} --subtree NAME)")
    print()
    print_subtrees(subtrees)
    return ExitCode.OK


def subtree_mission(
    file: str,
    found: Path,
    subtrees: list[LibrarySubtree],
    name: str,
    given: dict[str, str],
    *,
    safe_first: bool = False,
) -> MissionText | str:
    """A mission whose tree is one use of the library's subtree ``name``, each ``-p`` given
    as its argument (the defaults for the rest), to be compiled and drawn as any mission;
    else why not (an unknown subtree, an unknown or missing argument), one line.
    ``safe_first``: after a ``mode: safe`` step, as a mission reaches a subtree whose body
    drives without entering a mode itself (alone, each drive in it is an error, "reached in
    Passive mode", that no use of it has)."""
    from roomba_bt.behaviours.units import closest

    chosen = {subtree.name: subtree for subtree in subtrees}.get(name)
    if chosen is None:
        known = [subtree.name for subtree in subtrees]
        return f"{file} defines no subtree {name!r}{closest(name, known)}; it defines: " + (
            ", ".join(known) or "none"
        )
    params = {param.name: param for param in chosen.parameters}
    for pname in given:
        if pname not in params:
            return f"subtree {name!r} has no parameter {pname!r}{closest(pname, list(params))}" + (
                f"; its parameters: {', '.join(params) or 'none'}"
            )
    missing = [p for p in chosen.parameters if p.default == REQUIRED and p.name not in given]
    if missing:
        wanted = " ".join(f"-p {p.name}=VALUE" for p in missing)
        kinds = ", ".join(f"{p.name} ({p.type})" for p in missing)
        return f"subtree {name!r} needs a value for {kinds} (no default): give {wanted}"
    use = {"id": name, **{pname: _argument(value) for pname, value in given.items()}}
    steps = [{"mode": "safe"}] if safe_first else []
    tree = {"sequence": [*steps, {"subtree": use}]}
    text = (
        f"mission: {json.dumps(name)}\n"
        f"description: {json.dumps(chosen.doc)}\n"
        f"include: [{json.dumps(found.name)}]\n"
        f"tree: {json.dumps(tree, default=str)}\n"
    )
    # beside the library, so that its includes are found from where it stands
    return MissionText(text, f"{file} --subtree {name}", found.with_name(f"{found.name}#{name}"))


def _argument(value: str) -> object:
    """A ``-p`` value as the use's argument: read as YAML (``[1m, 2m]`` a list, ``3`` a
    number), as a mission file writes it; text that does not read is passed as text."""
    try:
        return yaml.safe_load(value)
    except yaml.YAMLError:
        return value


def refused(message: str) -> int:
    """``roomba-bt show: MESSAGE`` on stderr, exit 2."""
    print(f"roomba-bt show: {escaped(message, ANY_CONTROL)}", file=sys.stderr)
    return ExitCode.INVALID
