"""The compiler: a mission file to a checked :class:`~roomba_bt.mission.build.CompiledMission`.

The pipeline, each stage in its own module::

    Loader.compile_file     loader.py: the YAML read, includes and plugins, parameters
                            substituted, each node parsed (nodes.py) into the plan
                            (plan.py: Node), every problem a Diagnostic at file:line:col
    ModeCheck, KeyCheck     checks.py: the OI mode each node runs in, each @key written
    key_ranges, ...         before it is read; the ranges, the profile's commands, the
    check_stream            stream's bandwidth at the baud
    build                   build.py: the plan to py_trees objects
    CompiledMission         the tree, the packets to stream, the modes needed, the warnings

:func:`compile_mission` never raises for bad input; :func:`load_mission` raises
:class:`~roomba_bt.mission.diagnostics.MissionError` with every diagnostic at once;
:func:`validate_files` returns them, warnings too.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from roomba_bt import yamlsource
from roomba_bt.behaviours.registry import Registry, default_registry
from roomba_bt.mission.build import BuildError, CompiledMission, build
from roomba_bt.mission.checks import (
    KeyCheck,
    ModeCheck,
    blind_in_full,
    check_stream,
    key_ranges,
    parallel_wheels,
    profile_commands,
    restarted_branches,
    restarted_limits,
    restarted_runs,
    sensor_ranges,
)
from roomba_bt.mission.diagnostics import Diagnostic, MissionError
from roomba_bt.mission.loader import NO_PERMISSIONS, Loader, Permissions
from roomba_bt.mission.plan import Node
from roomba_bt.mission.shipped import find_mission
from roomba_bt.mission.values import Context, shown
from roomba_bt.oi.modes import ALL_MODES, OIMode
from roomba_bt.oi.profiles import CREATE2, RobotProfile

__all__ = ["compile_mission", "load_mission", "validate_files"]


def _display(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def compile_mission(
    path: str | Path,
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile = CREATE2,
    baud: int | None = None,
    registry: Registry | None = None,
    require_tree: bool = True,
    permissions: Permissions = NO_PERMISSIONS,
) -> tuple[CompiledMission | None, list[Diagnostic]]:
    """Compile and check; ``(mission or None, diagnostics)``. Never raises for bad input.
    ``permissions`` (none by default) says whether the file's plugin files may be imported
    and where else it may include from."""
    path = Path(path)
    try:
        return _compile(path, params, profile, baud, registry, require_tree, permissions)
    except Exception as exc:  # a compiler bug must still not be a traceback at a user
        message = f"internal error while compiling ({type(exc).__name__}: {exc}); please report it"
        return None, [Diagnostic(_display(path), 1, 1, message)]


def _compile(
    path: Path,
    params: Mapping[str, str] | None,
    profile: RobotProfile,
    baud: int | None,
    registry: Registry | None,
    require_tree: bool,
    permissions: Permissions,
) -> tuple[CompiledMission | None, list[Diagnostic]]:
    ctx = Context(registry=registry or default_registry())
    loader = Loader(ctx, _display, permissions)
    parsed = loader.compile_file(path, dict(params or {}), require_tree=require_tree)
    if parsed is None or parsed.tree is None:
        return None, sorted(ctx.diagnostics)
    tree = parsed.tree
    modes = ModeCheck()
    modes.run(tree)
    keys = KeyCheck()
    keys.run(tree, frozenset(k for k, d in ctx.keys.items() if d.has_initial))
    packets, sends, needed = _what_leaves_use(tree)
    unavailable, ignored = profile_commands(tree, profile)
    diagnostics = ctx.diagnostics + modes.errors + keys.errors + key_ranges(tree, ctx.keys)
    diagnostics += restarted_limits(tree) + restarted_branches(tree) + unavailable
    problem = check_stream(tuple(sorted(packets)), baud or profile.default_baud, profile)
    if problem is not None:
        assert parsed.tree_loc is not None
        diagnostics.append(parsed.tree_loc.at(problem))
    if diagnostics:
        return None, sorted(set(diagnostics))
    try:
        root = build(tree)
    except BuildError as failed:
        return None, [failed.diagnostic()]
    mission = CompiledMission(
        name=parsed.name,
        description=parsed.description,
        root=root,
        packets=tuple(sorted(packets)),
        modes_needed=frozenset(needed),
        parameters={name: bound.value for name, bound in parsed.params.items()},
        parameters_shown={
            name: shown(bound.type, bound.value) for name, bound in parsed.params.items()
        },
        source=path,
        files=tuple(dict.fromkeys(loader.files)),
        blackboard_initial={k: d.initial for k, d in ctx.keys.items() if d.has_initial},
        blackboard_keys={k: d.type for k, d in ctx.keys.items()},
        sends=frozenset(sends),
        plan=tree,
        warnings=(
            *ctx.warnings,
            *blind_in_full(tree, modes),
            *parallel_wheels(tree),
            *restarted_runs(tree),
            *ignored,
            *sensor_ranges(tree, profile),
        ),
    )
    return mission, []


def _what_leaves_use(tree: Node) -> tuple[set[int], set[int], set[OIMode]]:
    """The packets the leaves read, the opcodes they send and the modes they need."""
    packets: set[int] = set()
    sends: set[int] = set()
    needed: set[OIMode] = set()
    for node in tree.walk():
        if node.decl is not None:
            packets.update(node.decl.packets(node.params))
            sends.update(node.decl.sends)
            if node.decl.modes != ALL_MODES and node.decl.is_actuator:
                needed.update(node.decl.modes)
            after = node.decl.mode_after(node.params)
            if after is not None:
                needed.add(after)
    return packets, sends, needed


def load_mission(
    path: str | Path,
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
) -> CompiledMission:
    """Compile the mission at ``path`` with ``params`` (``-p name=value`` strings); raises
    :class:`MissionError` carrying every diagnostic. ``path`` is read as ``roomba-bt run``
    reads its argument (:func:`~roomba_bt.mission.shipped.find_mission`): a file, else a
    shipped mission's name (``"dock"``, ``"roomba-bt:dock.yaml"``)."""
    found = find_mission(str(path)).path or path
    mission, diagnostics = compile_mission(
        found, params, profile=profile, baud=baud, registry=registry, permissions=permissions
    )
    if mission is None:
        raise MissionError(diagnostics)
    return mission


def validate_files(
    paths: Iterable[str | Path],
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
) -> list[Diagnostic]:
    """Every diagnostic of every file, errors and warnings (``severity``). A file without
    ``tree:`` is checked as a library of subtrees (what ``include`` brings in)."""
    out: list[Diagnostic] = []
    for path in paths:
        path = Path(path)
        require_tree = _has_tree(path)
        mission, diagnostics = compile_mission(
            path, params, profile=profile, baud=baud, registry=registry,
            require_tree=require_tree, permissions=permissions,
        )  # fmt: skip
        out.extend(diagnostics)
        if mission is not None:
            out.extend(mission.warnings)
    return out


def _has_tree(path: Path) -> bool:
    """A library file (no top-level ``tree:`` and some ``subtrees:``) needs no tree. Read as
    the compiler reads it, the size checked first: a 4 GB file took 8 GB of memory here
    before the compiler refused it. A file that cannot be read is left to the compiler to
    say so."""
    try:
        text = yamlsource.read_text(path)
    except (OSError, UnicodeDecodeError, yamlsource.FileTooLarge):
        return True
    lines = [line for line in text.splitlines() if line and not line[0].isspace()]
    has_subtrees = any(line.startswith("subtrees:") for line in lines)
    return not has_subtrees or any(line.startswith("tree:") for line in lines)
