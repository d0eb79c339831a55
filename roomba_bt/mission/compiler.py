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

import gc
import itertools
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

from roomba_bt import yamlsource
from roomba_bt.behaviours.base import RobotBehaviour
from roomba_bt.behaviours.registry import Registry, default_registry
from roomba_bt.mission.build import BuildError, CompiledMission, build
from roomba_bt.mission.checks import (
    KeyCheck,
    ModeCheck,
    blind_in_full,
    check_stream,
    in_passive,
    key_ranges,
    parallel_keys,
    parallel_wheels,
    profile_commands,
    pushes_on_walls,
    restarted_branches,
    restarted_limits,
    restarted_runs,
    sensor_ranges,
    song_slots,
    waits_past_sleep,
)
from roomba_bt.mission.deadends import dead_ends
from roomba_bt.mission.diagnostics import (
    MAX_REPORTED,
    Diagnostic,
    IncludeSite,
    MissionError,
    merged_uses,
    said_at_use,
)
from roomba_bt.mission.loader import NO_PERMISSIONS, Loader, Permissions
from roomba_bt.mission.plan import Node
from roomba_bt.mission.shipped import find_mission, shipped_name
from roomba_bt.mission.source import Loc
from roomba_bt.mission.values import Context, FoundEnough
from roomba_bt.oi.modes import ALL_MODES, OIMode
from roomba_bt.oi.profiles import CREATE2, RobotProfile, profile_given
from roomba_bt.printable import MAX_FOUND, stopped_finding, stopped_warning
from roomba_bt.robot.safety import signal_interrupt

__all__ = [
    "FileValidation",
    "MissionText",
    "compile_mission",
    "load_mission",
    "load_mission_text",
    "validate_file",
    "validate_files",
]


def _display(path: Path) -> str:
    """How a diagnostic names a file: a shipped file by its shipped name
    (``roomba-bt:lib/docking.yaml``, as an include writes it and a record holds it:
    ``validate dock`` named it by its site-packages path, a different line on every
    machine, and so did a folder above the venv, ``~`` over ``~/roomba/venv``, as the path
    from there); else by its path from the working folder; else as given."""
    resolved = path.resolve()
    shipped = shipped_name(resolved)
    if shipped is not None:
        return shipped
    try:
        return str(resolved.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def compile_mission(
    path: str | Path,
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile | str | None = CREATE2,
    baud: int | None = None,
    registry: Registry | None = None,
    require_tree: bool = True,
    permissions: Permissions = NO_PERMISSIONS,
    text: MissionText | None = None,
) -> tuple[CompiledMission | None, list[Diagnostic]]:
    """Compile and check; ``(mission or None, diagnostics)``. Never raises for bad input (a
    ``profile=`` that names no model is a bad argument: :func:`profile_given`).
    ``permissions`` (none by default) says whether the file's plugin files may be imported
    and where else it may include from. ``text``: the mission's YAML as given, read in
    place of the file at ``path`` (which then only places its includes and names it)."""
    model = profile_given(profile, "compile_mission")
    mission, diagnostics, _ = _compile(
        Path(path), params, model, baud, registry, require_tree, permissions, text
    )
    return mission, diagnostics


@dataclass(frozen=True)
class MissionText:
    """A mission given as text (:func:`load_mission_text`): its YAML, and the name its
    diagnostics say (``name:3:7: ...``) for the path it stands at, in the folder its includes
    and plugin files are found from."""

    yaml: str
    name: str
    path: Path

    def display(self, path: Path) -> str:
        """How a diagnostic names ``path``: this text by its name, another file as usual."""
        return self.name if path == self.path else _display(path)


@contextmanager
def _no_cycle_collection() -> Iterator[None]:
    """Python's cycle collector paused while a file is compiled, unless something paused it
    already: a compile makes an object for every YAML node, place and finding, none of them
    garbage in a cycle (refcounts free what it drops), and each full collection walked them
    all again. A file of 68,000 unknown parameters spent 1.0 s of its 2.5 s CPU in ten full
    collections. Collected as usual after it: the cycles others made meanwhile too."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def _compile(
    path: Path,
    params: Mapping[str, str] | None,
    profile: RobotProfile,
    baud: int | None,
    registry: Registry | None,
    require_tree: bool,
    permissions: Permissions,
    text: MissionText | None = None,
) -> tuple[CompiledMission | None, list[Diagnostic], Loader | None]:
    """The mission, its diagnostics, and the loader that read its files (what it included;
    None when the compiler itself failed, which is said as a diagnostic)."""
    display = _display if text is None else text.display
    try:
        ctx = Context(registry=registry or default_registry(), wording=permissions.wording)
        loader = Loader(ctx, display, permissions)
        with _no_cycle_collection():
            mission, diagnostics = _checked(
                loader, ctx, path, params, profile, baud, require_tree, text
            )
        if not diagnostics and (mission is None or not mission.warnings):
            return mission, diagnostics, loader  # a clean compile (run's) resolves no more
        chains = _IncludeChains(display(path), loader.include_sites)
        if mission is None:
            return None, [chains.of(d) for d in diagnostics], loader
        mission.warnings = tuple(chains.of(d) for d in mission.warnings)
        return mission, diagnostics, loader
    except Exception as exc:  # a compiler bug must still not be a traceback at a user
        if signal_interrupt(exc) is not None:
            raise  # a SIGTERM Python wrapped as a plugin's class was made: the CLI's 130
        message = f"internal error while compiling ({type(exc).__name__}: {exc}); please report it"
        return None, [Diagnostic(display(path), 1, 1, message)], None


class _IncludeChains:
    """Each diagnostic in an included file given the include chain that reached it
    (:attr:`Diagnostic.included_from`), so that the mission that failed is named beside the
    library's line."""

    def __init__(self, top: str, sites: dict[str, Loc]) -> None:
        self.top = top
        self.sites = sites

    def of(self, diagnostic: Diagnostic) -> Diagnostic:
        chain: list[IncludeSite] = []
        file = diagnostic.file
        # each file is entered once (an include cycle is refused), so the walk ends at the top
        # file; bounded by the number of files all the same
        while file != self.top and file in self.sites and len(chain) <= len(self.sites):
            site = self.sites[file]
            chain.append(IncludeSite(site.file, site.line, site.column))
            file = site.file
        if not chain:
            return diagnostic
        return replace(diagnostic, included_from=tuple(chain))


def _checked(
    loader: Loader,
    ctx: Context,
    path: Path,
    params: Mapping[str, str] | None,
    profile: RobotProfile,
    baud: int | None,
    require_tree: bool,
    text: MissionText | None = None,
) -> tuple[CompiledMission | None, list[Diagnostic]]:
    """The mission file (or ``text``) read, checked and built: the compiler's stages in
    order. A library (no tree) that reads without error has its warnings as its diagnostics:
    ``validate lib.yaml`` said a lone ``$$`` of it only where a mission included it."""
    try:
        parsed = loader.compile_file(path, dict(params or {}), require_tree=require_tree, text=text)
    except FoundEnough:
        return None, _stopped(ctx.diagnostics, ctx.stops)
    if parsed is None or parsed.tree is None:
        return None, _unbuilt(ctx)
    tree = parsed.tree
    modes = ModeCheck(ctx.wording)
    modes.run(tree)
    keys = KeyCheck()
    keys.run(tree, frozenset(k for k, d in ctx.keys.items() if d.has_initial))
    packets, sends, needed = _what_leaves_use(tree)
    unavailable, ignored = profile_commands(tree, profile, ctx.wording)
    diagnostics = ctx.diagnostics + modes.errors + keys.errors + key_ranges(tree, ctx.keys)
    diagnostics += restarted_limits(tree) + restarted_branches(tree) + unavailable
    # judged once the rest is right: a held whose child is refused is said once, there
    dead_errors, dead_warnings = dead_ends(tree) if not diagnostics else ([], [])
    diagnostics += dead_errors
    problem = check_stream(tuple(sorted(packets)), baud or profile.default_baud, profile)
    if problem is not None:
        assert parsed.tree_loc is not None
        diagnostics.append(parsed.tree_loc.at(problem))
    if diagnostics:
        return None, _pinned(_said(diagnostics), ctx.stops)
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
        # as written (``time_limit=2min``, not ``120 s``), as the nodes' names say them
        parameters_shown={name: bound.text for name, bound in parsed.params.items()},
        source=path,
        files=tuple(dict.fromkeys(loader.files)),
        blackboard_initial={k: d.initial for k, d in ctx.keys.items() if d.has_initial},
        blackboard_keys={k: d.type for k, d in ctx.keys.items()},
        sends=frozenset(sends),
        plan=tree,
        warnings=_kept(ctx.warnings, _tree_warnings(tree, modes, profile, ignored), dead_warnings),
        waits_past_sleep=waits_past_sleep(tree, modes, profile),
    )
    return mission, []


def _unbuilt(ctx: Context) -> list[Diagnostic]:
    """What a mission whose file did not read says (its errors), or a library (no tree: its
    warnings, which a mission's use of it would say)."""
    if ctx.diagnostics:
        return _pinned(_said(ctx.diagnostics), ctx.stops)
    return list(_kept(ctx.warnings))


def _said(*found: Iterable[Diagnostic]) -> tuple[Diagnostic, ...]:
    """Diagnostics as ``validate`` says them: in the order of the file (by check, a warning
    on line 8 came before one on line 5); one in a library's subtree that a use caused at
    that use (:func:`said_at_use`); a finding at several uses of a subtree written in their
    own file once, naming each (:func:`merged_uses`)."""
    every = itertools.chain.from_iterable(found)
    said = sorted(merged_uses(itertools.chain.from_iterable(map(said_at_use, every))))
    # the messages a command prints whole; those past them keep their "did you mean" for
    # str() to work out (Diagnostic.later): thousands of them cost seconds
    return (*(d.shown() for d in said[:MAX_REPORTED]), *said[MAX_REPORTED:])


def _stopped(found: list[Diagnostic], stops: list[Diagnostic]) -> list[Diagnostic]:
    """The errors of a check stopped at :data:`~roomba_bt.printable.MAX_FOUND` (``found``,
    in the order found) as ``validate`` says them, as a world's are: all but the last in the
    file's order, and in the last one's place the note that the check stopped there, listed
    among the first :data:`MAX_REPORTED` (after them a command says only how many more
    there are: the note sorted at the file's end was never seen), as is ``stops``' note of
    a tree cut short."""
    last = found[-1]
    note = Diagnostic(last.file, last.line, last.column, stopped_finding())
    return _pinned((*_said(found[:-1]), note), [*stops, note])


def _kept(*found: Iterable[Diagnostic]) -> tuple[Diagnostic, ...]:
    """A mission's warnings as ``validate`` says them (:func:`_said`), at most
    :data:`~roomba_bt.printable.MAX_FOUND`: past them, the first so many found less one, and
    in the place of the last the note that no more are said (``Context.warn`` keeps no
    more), listed among the first :data:`MAX_REPORTED`, as the errors' stop is."""
    every = list(itertools.chain.from_iterable(found))
    if len(every) <= MAX_FOUND:
        return _said(every)
    last = every[MAX_FOUND - 1]
    note = Diagnostic(last.file, last.line, last.column, stopped_warning(), severity="warning")
    return tuple(_pinned((*_said(every[: MAX_FOUND - 1]), note), [note]))


def _pinned(said: Sequence[Diagnostic], stops: Sequence[Diagnostic]) -> list[Diagnostic]:
    """``said`` with each diagnostic that says where a check stopped (``stops``, by their
    text) among the first :data:`MAX_REPORTED`, the last of them, where it sorts past them:
    it explains the rest, and a command lists only those (the tree cut at 10,000 nodes was
    said after a hundred errors of the nodes before it, and never seen)."""
    notes = {stop.message for stop in stops}
    late = [d for d in said[MAX_REPORTED:] if d.message in notes]
    if not late:
        return list(said)
    kept = [d for d in said if d.message not in notes or d not in late]
    at = MAX_REPORTED - len(late)
    return [*kept[:at], *(d.shown() for d in late), *kept[at:]]


def _tree_warnings(
    tree: Node, modes: ModeCheck, profile: RobotProfile, ignored: list[Diagnostic]
) -> tuple[Diagnostic, ...]:
    """The checks of a tree that compiled whose findings are warnings (a mission that runs,
    and may not do what its writer meant); ``ignored``:
    the commands the profile's firmware ignores (:func:`profile_commands`)."""
    return (
        *blind_in_full(tree, modes),
        *pushes_on_walls(tree, modes),
        *in_passive(tree, modes),
        *parallel_wheels(tree),
        *parallel_keys(tree),
        *restarted_runs(tree),
        *ignored,
        *sensor_ranges(tree, profile),
        *song_slots(tree),
    )


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
    profile: RobotProfile | str | None = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
    behaviours: Iterable[type[RobotBehaviour]] = (),
) -> CompiledMission:
    """Compile the mission at ``path`` with ``params`` (``-p name=value`` strings); raises
    :class:`MissionError` carrying every diagnostic. ``path`` is read as ``roomba-bt run``
    reads its argument (:func:`~roomba_bt.mission.shipped.find_mission`): a file, else a
    shipped mission's name (``"dock"``, ``"roomba-bt:dock.yaml"``). ``behaviours``: classes
    the program declares itself (``@declare``), which the YAML may name beside the
    built-ins (:meth:`Registry.with_behaviours`: a name a built-in has is a
    :class:`~roomba_bt.behaviours.declare.DeclarationError`). YAML text itself is
    :func:`load_mission_text`'s. Neither a file nor a shipped name, and the diagnostic says
    so as the command line does, a shipped mission's name it may have meant with it
    (``"dok"``: did you mean 'dock'?). ``profile``: the model it is compiled for, ``CREATE2``
    unless given, never ``ROOMBA_BT_PROFILE`` or the project file's (the command line's;
    ``roomba_bt.configured_profile(path)`` reads them for a program that wants them)."""
    # text, not a name: said so, not escaped back; a file whose name holds a newline is a
    # file (roomba-bt run refused one that validate and show read)
    if isinstance(path, str) and "\n" in path and not os.path.isfile(path):
        raise MissionError([Diagnostic(
            "load_mission", 1, 1,
            "load_mission takes a mission file's path or a shipped mission's name, and this "
            "is several lines of text: compile YAML text with load_mission_text(text, "
            "name=..., base_dir=...)",
        )])  # fmt: skip
    lookup = find_mission(str(path), permissions.wording)
    if lookup.path is None and lookup.problem is not None:
        shown = _display(Path(path))
        problem = lookup.problem.removeprefix(f"{path}: ")  # the diagnostic names the file
        raise MissionError([Diagnostic(shown, 1, 1, problem)])
    found = lookup.path or path
    mission, diagnostics = compile_mission(
        found, params, profile=profile_given(profile, "load_mission"), baud=baud,
        permissions=permissions,
        registry=_with_behaviours(registry, behaviours),
    )  # fmt: skip
    if mission is None:
        raise MissionError(diagnostics)
    return mission


def load_mission_text(
    text: str,
    params: Mapping[str, str] | None = None,
    *,
    name: str = "<string>",
    base_dir: str | Path | None = None,
    profile: RobotProfile | str | None = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
    behaviours: Iterable[type[RobotBehaviour]] = (),
) -> CompiledMission:
    """Compile a mission written as YAML ``text`` (a string in a test, a notebook cell, a
    generated mission), as :func:`load_mission` compiles a file: raises
    :class:`MissionError` carrying every diagnostic, each at ``name:line:column``.
    ``base_dir`` (the current folder by default) is the folder the text stands in: its
    ``include:`` and ``plugins:`` paths are found from there, and may reach that folder's
    tree (and the shipped library, and ``permissions.include_dirs``), as a file's may reach
    its own folder's. ``name`` also names the mission when it has no ``mission:``."""
    if not isinstance(text, str):
        raise TypeError(
            f"load_mission_text(text) takes the mission's YAML as a str, not "
            f"{type(text).__name__} (a file: load_mission(path))"
        )
    if not isinstance(name, str) or not name:
        raise TypeError(f"load_mission_text(name=...) takes a non-empty str, not {name!r}")
    folder = Path.cwd() if base_dir is None else Path(base_dir)
    if not folder.is_dir():
        raise ValueError(f"load_mission_text(base_dir={str(base_dir)!r}): no such folder")
    stands_at = folder.resolve() / (Path(name).name or "mission")
    given = MissionText(text, name, stands_at)
    model = profile_given(profile, "load_mission_text")
    mission, diagnostics = compile_mission(
        stands_at, params, profile=model, baud=baud, permissions=permissions,
        registry=_with_behaviours(registry, behaviours), text=given,
    )  # fmt: skip
    if mission is None:
        raise MissionError(diagnostics)
    return mission


def _with_behaviours(
    registry: Registry | None, behaviours: Iterable[type[RobotBehaviour]]
) -> Registry | None:
    """``registry`` (the default one when None) with the program's own ``behaviours``."""
    if isinstance(behaviours, tuple | list) and not behaviours:
        return registry
    return (registry or default_registry()).with_behaviours(behaviours)


@dataclass(frozen=True)
class FileValidation:
    """What :func:`validate_file` found in one file: its diagnostics, errors and warnings,
    and ``includes``, every file it includes, directly or through others, named as the
    diagnostics name them, in the order first reached: a CI job reads which missions a
    changed library reaches from it (``validate --format json``, docs/ci.md); and
    ``parameters``, the names the file declares (which of ``validate -p``'s values a file of
    a batch takes)."""

    diagnostics: list[Diagnostic]
    includes: tuple[str, ...]
    parameters: tuple[str, ...] = ()


def validate_file(
    path: str | Path,
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile | str | None = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
) -> FileValidation:
    """Every diagnostic of the file, and the files it includes. A file without ``tree:`` is
    checked as a library of subtrees (what ``include`` brings in). A diagnostic in a file it
    includes names the include chain that reached it (``included_from``; ``checked_file``
    is then ``path``)."""
    path = Path(path)
    model = profile_given(profile, "validate_file")
    mission, diagnostics, loader = _compile(
        path, params, model, baud, registry, _has_tree(path), permissions
    )
    warnings = mission.warnings if mission is not None else ()
    if loader is None:
        return FileValidation([*diagnostics, *warnings], ())
    return FileValidation([*diagnostics, *warnings], tuple(loader.include_sites), loader.parameters)


def validate_files(
    paths: Iterable[str | Path],
    params: Mapping[str, str] | None = None,
    *,
    profile: RobotProfile | str | None = CREATE2,
    baud: int = 115200,
    registry: Registry | None = None,
    permissions: Permissions = NO_PERMISSIONS,
) -> list[Diagnostic]:
    """Every diagnostic of every file (:func:`validate_file`'s): an error in a library
    shared by several of ``paths`` comes once for each of them."""
    model = profile_given(profile, "validate_files")
    return [
        diagnostic
        for path in paths
        for diagnostic in validate_file(
            path, params, profile=model, baud=baud, registry=registry, permissions=permissions
        ).diagnostics
    ]


def is_library(path: Path) -> bool:
    """Whether the file at ``path`` is a library of subtrees (``subtrees:``, no ``tree:``):
    ``show`` lists its subtrees, or draws one, instead of a tree."""
    return not _has_tree(path)


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
