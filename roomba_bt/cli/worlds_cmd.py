"""``roomba-bt worlds``: the simulator's shipped worlds, listed or printed as shipped (a
wheel's user found them only by opening the package's folder)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import add_command
from roomba_bt.printable import ANY_CONTROL, TEXT_LIMIT, escaped, listed, name_shown
from roomba_bt.runtime.summary import ExitCode

if TYPE_CHECKING:
    from collections.abc import Sequence

    from roomba_bt.mission import Diagnostic
    from roomba_bt.sim.world import WorldError, WorldProblem


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "worlds",
        worlds_command,
        """list the shipped simulator worlds, or print one

        List the worlds shipped with roomba-bt (give one to run, sim or eval: --world
        apartment), each with its description, size, areas and dock, and your own from the
        folders ROOMBA_BT_WORLDS names (separated by ':'; they come before the shipped
        ones). With NAME, print that world's file, its comments included: a start for a
        world of your own (roomba-bt worlds empty-room > my-room.yaml).
        """,
    )
    parser.add_argument("name", nargs="?", metavar="NAME", help="print this world's file")


def worlds_command(args: argparse.Namespace) -> int:
    from roomba_bt.behaviours.units import closest
    from roomba_bt.sim.world import WORLDS_VARIABLE, WorldError, shipped_worlds, world_files

    try:
        files = world_files()
    except WorldError as exc:
        print(world_error_text(exc, "worlds"), file=sys.stderr)
        return ExitCode.INVALID
    names = tuple(files)
    if args.name is not None:
        name = args.name.removesuffix(".yaml")
        if name not in names and Path(args.name).is_file():  # a world of one's own
            shown = escaped(args.name, ANY_CONTROL)
            print(f"roomba-bt worlds: {shown} is a file, not a shipped world's name: check it "
                  f"with roomba-bt validate {shown}; run a mission in it with --world {shown}",
                  file=sys.stderr)  # fmt: skip
            return ExitCode.INVALID
        if name not in names:
            hint = closest(name, list(names))
            which = "shipped" if names == shipped_worlds() else f"{WORLDS_VARIABLE}'s or shipped"
            print(f"roomba-bt worlds: no {which} world {args.name!r}{hint}; there are: "
                  f"{', '.join(names)}", file=sys.stderr)  # fmt: skip
            return ExitCode.INVALID
        sys.stdout.write(files[name].read_text(encoding="utf-8"))
        return ExitCode.OK
    return _list_worlds(files)


def _list_worlds(files: dict[str, Path]) -> int:
    """Each world's name, description, size, dock and areas; one of the user's says its
    file, and one that does not load its problems on stderr (exit 2 after the others)."""
    from roomba_bt.sim.world import WORLDS_DIR, WorldError, load_world

    code = ExitCode.OK
    for name, path in files.items():
        try:
            world = load_world(path)
        except WorldError as exc:
            print(world_error_text(exc, "worlds"), file=sys.stderr)
            code = ExitCode.INVALID
            continue
        xs = [x for room in world.rooms for x, _ in room]
        ys = [y for room in world.rooms for _, y in room]
        size = f"{(max(xs) - min(xs)) / 1000:g} x {(max(ys) - min(ys)) / 1000:g} m"
        # a world of your own is a stranger's file: its texts are cut as a line shows them
        areas = name_shown(", ".join(a.name for a in world.areas), TEXT_LIMIT) or "none"
        dock = "a dock" if world.dock is not None else "no dock"
        print(f"{name_shown(name)}  {name_shown(world.description, TEXT_LIMIT)}")
        print(f"    {size}, {dock}; areas: {areas}")
        if path.parent != WORLDS_DIR:
            print(f"    your own: {escaped(str(path), ANY_CONTROL)}")
    return code


def world_diagnostics(path: str) -> list[Diagnostic] | None:
    """Every problem of the world file ``path`` as ``validate`` reports a mission's (each at
    file:line:col), and for a world that loads its warnings (a given start whose body
    reaches over a drop); none for a good world; None when the file is no world (a mapping
    with ``rooms:`` and no ``tree:``, as the mission loader tells one). A world's checks
    were reached only by running a mission in it, whose first line began ``roomba-bt: ``
    and broke a ``^file:line:col`` matcher."""
    if not is_world_file(Path(path)):
        return None
    from roomba_bt.sim.world import WorldError, parse_world, world_text

    try:
        world = parse_world(*world_text(Path(path)))
    except WorldError as exc:
        return [_as_diagnostic(problem) for problem in exc.problems]
    return [_as_diagnostic(problem, "warning") for problem in world.warnings]


def is_world_file(path: Path) -> bool:
    """``path`` holds a world: a top-level mapping with ``rooms:`` and no ``tree:``. A text
    YAML cannot read counts by its unindented lines, so that a world with a syntax error is
    reported as a world's, not as "not a mission file"."""
    import yaml

    from roomba_bt import yamlsource
    from roomba_bt.mission.loader import are_world_keys

    try:
        text = yamlsource.read_text(path)
    except (OSError, UnicodeDecodeError, yamlsource.FileTooLarge):
        return False  # the mission's check says why it cannot be read
    if "rooms" not in text:  # every mission, at no cost
        return False
    try:
        root = yamlsource.compose(text)
    except yaml.YAMLError:
        keys = {line.split(":", 1)[0] for line in text.splitlines() if line[:1].isalpha()}
    else:
        if not isinstance(root, yaml.MappingNode):
            return False
        keys = {key.value for key, _ in root.value if isinstance(key, yaml.ScalarNode)}
    return are_world_keys(keys)


def world_warnings_text(warnings: Sequence[WorldProblem]) -> list[str]:
    """A loaded world's warnings as ``run --world`` says them on stderr: each
    ``file:line:col: warning: robot.start: ...``, as ``validate`` says it."""
    return [str(_as_diagnostic(problem, "warning")) for problem in warnings]


def _as_diagnostic(problem: WorldProblem, severity: str = "error") -> Diagnostic:
    """A world's problem (or warning) as a mission's diagnostic: the same line,
    ``file:line:col: field: ...``; one without a place (none is found reading a file that
    exists) at 1:1."""
    from roomba_bt.mission import Diagnostic

    where = f"{problem.source}:{problem.line}:{problem.column}" if problem.line else problem.source
    message = str(problem).removeprefix(where).removeprefix(": ")
    return Diagnostic(problem.source, problem.line or 1, problem.column or 1, message,
                      severity=severity)  # fmt: skip


def world_error_text(exc: WorldError, command: str) -> str:
    """A world's problems as ``run``, ``sensors``, ``monitor`` and ``worlds`` (``command``)
    print them on stderr: a problem at a place as its own ``file:line:col: ...`` line, as
    ``validate`` prints it (the first line began ``roomba-bt: `` and broke a
    ``^file:line:col`` matcher), one without a place (no such file, unreadable) after
    ``roomba-bt COMMAND: ``, as the command's other errors and ``eval``'s world errors begin
    (it said ``roomba-bt: ``); the first hundred, then how many more (:func:`listed`)."""
    prefix = f"roomba-bt {command}: "
    return "\n".join(listed([str(p) if p.line else f"{prefix}{p}" for p in exc.problems]))
