"""One evaluation episode: a mission run on the simulator's virtual clock from a seeded pose.

An episode is the same stack as ``roomba-bt run --fast``, built by the same
:class:`~roomba_bt.runtime.stack.RunStack`: the compiled mission, the robot
:class:`~roomba_bt.robot.connection.Connection` (mode model, guard, watchdog, safe stop), the
:class:`~roomba_bt.runtime.loop.MissionRunner`, and the simulator behind a
:class:`~roomba_bt.sim.SimLink`. Nothing is mocked: the mission sees the bytes a robot sends.

What is measured comes from the simulator itself, per 15 ms step (never from the mission's
own idea of what happened): the trajectory, bump onsets and how many steps the bumper stayed
in contact after each, whether the robot ended on the dock's contacts, the progress around
the world's loop (for patrols). Episodes are plain data (picklable) so that
:mod:`roomba_bt.evaluate.parallel` can run them in worker processes; the same
:class:`EpisodeSpec` gives the same :class:`EpisodeResult` in any process.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import os
import re
import socket
import threading
import time
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import FrameType
from typing import Any

from roomba_bt import yamlsource
from roomba_bt.behaviours.blackboard import (
    RunBoard,
    read_key,
    undeclared_meant,
    undeclared_writes,
)
from roomba_bt.behaviours.reasons import GUARD_STOPPED
from roomba_bt.evaluate.paths import kept_path
from roomba_bt.evaluate.sources import MissionSources, bundle_mission, bundle_world
from roomba_bt.mission import (
    NO_PERMISSIONS,
    CompiledMission,
    MissionError,
    Permissions,
    load_mission,
    reported,
)
from roomba_bt.oi.bits import BUMP_BITS
from roomba_bt.oi.frames import BUMPS_PACKETS
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import RobotProfile, get_profile
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary, falls_in_order
from roomba_bt.runtime.tick_watch import WHEN_SLOW, slowest_tick_named
from roomba_bt.runtime.wall_limit import ran_out
from roomba_bt.sim import STEP_SECONDS, Faults, SimLink, Simulator, World
from roomba_bt.sim.faults import NO_FAULTS
from roomba_bt.sim.world import (
    DOCK_BEAM_LIMIT,
    DOCK_FAMILIES,
    DOCK_LIMITS,
    DockSpec,
    parse_world,
    world_text,
)

#: Dock fields an evaluation may override (``--dock buoy_range=0.5``), with their units:
#: lengths in metres, angles in degrees, each in the range a world file allows
#: (:data:`~roomba_bt.sim.world.DOCK_LIMITS`, :data:`~roomba_bt.sim.world.DOCK_BEAM_LIMIT`).
DOCK_OVERRIDES: dict[str, str] = {
    **{key: DOCK_LIMITS[key].unit
       for key in ("buoy_range", "force_field", "contact_tolerance", "angle_tolerance")},
    "red": DOCK_BEAM_LIMIT.unit,
    "green": DOCK_BEAM_LIMIT.unit,
    "family": " or ".join(DOCK_FAMILIES),
}  # fmt: skip


class EvaluationError(ValueError):
    """Bad input to an evaluation (mission, world, override): a message for the user."""


class MissionNotCompiled(EvaluationError):
    """A mission the evaluating machine compiled that an episode's worker could not: a
    plugin installed there and not on the worker (an installed package's behaviours are
    unknown nodes there; a module a plugin file imports is missing), or another roomba-bt
    release. Every episode of the mission would fail alike: ``eval`` says it once, naming the
    mission as it was given and the worker, and stops (exit 3: the run environment failed,
    not the mission). Pickled from a worker process or a Dask worker as it is."""

    def __init__(self, mission: str, worker: str, problem: str) -> None:
        super().__init__(mission, worker, problem)
        self.mission, self.worker, self.problem = mission, worker, problem

    def __str__(self) -> str:
        return (
            f"{self.mission} was compiled here, but not on the worker {self.worker}, where "
            f"no episode of it can run:\n{self.problem}"
        )


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything that decides one episode. Same spec, same result."""

    mission: str
    world: str = "empty-room"
    seed: int = 0
    params: tuple[tuple[str, str], ...] = ()
    profile: str = "create2"
    timeout_s: float = 900.0
    random_start: bool = True
    #: start no further than this from the docked pose (m); None: the world's start region
    within_m: float | None = None
    dock: tuple[tuple[str, Any], ...] = ()
    battery: float | None = None
    #: keep every n-th trace point in the result (trajectory plots); 0: none, and the
    #: simulator keeps no trace (``eval`` without ``--plot``: a result's trajectory held
    #: about 3 MB per robot-hour, which a thousand-episode sweep kept for nothing)
    trace_every: int = 2
    #: keep the trajectory as a results record keeps it and ``eval --plot`` draws it
    #: (:func:`~roomba_bt.evaluate.paths.kept_path`: a few hundred points, not one every
    #: eighth step), made in the worker: ``eval --plot`` held every point of every episode
    #: in its parent until the end, about 100 KB an apartment dock episode
    simplify_path: bool = False
    #: what the mission file may reach (its plugin files, other include folders), as the
    #: command line granted when the mission was checked before any episode
    permissions: Permissions = NO_PERMISSIONS
    #: the mission's texts (and its includes'): set, the episode reads no file
    #: (:func:`self_contained`); None, it reads ``mission`` from this machine's disk
    sources: MissionSources | None = field(default=None, repr=False)
    #: (file name, text) of a world given by path, for the same reason
    world_file: tuple[str, str] | None = field(default=None, repr=False)
    #: start in this named area of the world (``areas:``); its coverage is the headline
    start_area: str | None = None
    #: the encoders' error (``Faults.odometry_error``, a fraction; 0: exact odometry)
    odometry_error: float = 0.0
    #: what else goes wrong (``eval``'s fault options: a bad cable, a reset...); each
    #: episode's draws come from its own ``seed``, so a sweep is repeatable episode by episode
    faults: Faults = NO_FAULTS
    #: how a TIMEOUT's reason names ``timeout_s`` (``RunSummary.time_limit``): "" as the
    #: thing it is (``the run's 900 s``), ``eval`` as its flag (``--timeout 900 s``)
    time_limit: str = ""
    #: the mission's blackboard keys whose values at the end the result keeps (``eval
    #: --key``; ``wp.distance``, a record's field), checked against its declaration first
    keys: tuple[str, ...] = ()


def self_contained(spec: EpisodeSpec) -> EpisodeSpec:
    """``spec`` carrying the texts it needs, so that any machine can run it (a Dask worker
    with no shared file system); the episode is the same one."""
    return Bundles()(spec)


def all_self_contained(specs: Iterable[EpisodeSpec]) -> list[EpisodeSpec]:
    """Each of ``specs`` made :func:`self_contained`, each distinct mission and world file
    read once (:class:`Bundles`)."""
    bundled = Bundles()
    return [bundled(spec) for spec in specs]


class Bundles:
    """Specs made :func:`self_contained` one at a time, as they are sent, each distinct
    mission and world file read once. An evaluation's episodes share one mission: bundling
    it again for each one parsed its YAML 48 times for 48 episodes, most of the submitting
    process's CPU on a Dask run, taken from the workers on a 2-core machine. Read once,
    every episode also carries the same bytes even if the file is saved while they are
    submitted."""

    def __init__(self) -> None:
        self._missions: dict[str, MissionSources] = {}
        self._worlds: dict[str, tuple[str, str] | None] = {}

    def __call__(self, spec: EpisodeSpec) -> EpisodeSpec:
        sources = spec.sources
        if sources is None:
            if spec.mission not in self._missions:
                self._missions[spec.mission] = bundle_mission(spec.mission)
            sources = self._missions[spec.mission]
        world_file = spec.world_file
        if world_file is None:
            if spec.world not in self._worlds:
                self._worlds[spec.world] = bundle_world(spec.world)
            world_file = self._worlds[spec.world]
        return replace(spec, sources=sources, world_file=world_file)


@dataclass(frozen=True)
class Coverage:
    """The floor cleaned in an episode (:mod:`roomba_bt.sim.coverage`), as fractions 0..1.

    ``area`` is what ``curve`` and ``final`` measure: the episode's start area, or ``""`` for
    all the reachable floor. ``curve`` samples it every 30 s of mission time from 0."""

    area: str
    final: float
    curve: tuple[tuple[float, float], ...]
    overall: float
    by_area: tuple[tuple[str, float], ...]
    #: the longest brush time without a new cell cleaned (s): a robot stuck
    longest_idle_s: float
    cleaning_s: float

    def at(self, seconds: float) -> float:
        """Coverage at ``seconds`` of mission time (the last sample at or before it)."""
        value = 0.0
        for t, c in self.curve:
            if t > seconds + 1e-6:
                break
            value = c
        return value


@dataclass(frozen=True, slots=True)
class EpisodeResult:
    """What happened in one episode, measured on the simulator.

    An evaluation keeps every result of its sweep until its report (the statistics, ``--out``
    in the seeds' order), so a result is kept small: its fields in slots (a dataclass's
    ``__dict__`` of 38 entries was a kilobyte an episode), and the words one result repeats
    of another (its mission, world, outcome, reason, worker...) shared, not copied, when it
    arrives from a worker process (:meth:`__reduce__`). A result took 2.6 KB in the sweep's
    parent, now under 1 KB (a sweep's parent, its specs included: 3.0 KB an episode, 300 MB
    at 100 000 episodes, now 1.3 KB)."""

    seed: int
    outcome: str  # "success", "failure", "timeout", "error", ...
    reason: str
    time_s: float
    wall_s: float
    ticks: int
    start: tuple[float, float, float]  # x, y (m), heading (deg)
    end: tuple[float, float, float]
    bumps: int
    #: longest run of steps the bumper stayed pressed right after a bump onset, per onset
    contact_steps: tuple[int, ...]
    docked: bool
    charging: bool
    cliffs: int
    fell: bool
    violations: int
    #: full turns around the world's centre (signed; patrols) and the longest time (s)
    #: with less than 0.3 m of progress around it
    loops: float
    longest_stall_s: float
    #: the longest time (s) off the dock with no new floor cleaned and no move of
    #: TRAPPED_RADIUS_MM (:attr:`_MeasuredSimulator.longest_trapped`): brushes on or off
    longest_trapped_s: float = 0.0
    trajectory: tuple[tuple[float, float], ...] = field(repr=False, default=())
    #: per bump onset, steps from the bump frame to the first wheel request that no longer
    #: drives forward (a drive 0 or the reaction) and to the first that backs out (-1: none
    #: within a second); 0 is a command written in the bump frame's own tick
    reaction_steps: tuple[tuple[int, int], ...] = field(repr=False, default=())
    #: what ran: the mission (as given), the world's name, the parameters
    mission: str = ""
    world: str = ""
    params: tuple[tuple[str, str], ...] = ()
    #: the leaf (or node) the failure reason names, "" when none
    stage: str = ""
    distance_m: float = 0.0
    commands_sent: int = 0
    commands_refused: int = 0
    #: the robot's own falls to Passive by cause, the commonest first (``(("cliff", 4),)``):
    #: the run summary's ``falls`` (a cliff or wheel drop in Safe, the charger), each one the
    #: firmware stopping the wheels under the tree; not ``fell``, the simulated robot going
    #: over a drop. A tuple of pairs, as ``params``: hashable, and pickled to a worker's
    #: parent or from a Dask worker as it is
    falls: tuple[tuple[str, int], ...] = ()
    #: where it ran (host:pid, or the Dask worker's address); not part of the episode
    worker: str = field(default="", compare=False)
    coverage: Coverage | None = field(repr=False, default=None)
    #: CPU seconds of the thread that ran the episode (``time.thread_time``: compiling the
    #: mission, building the world, the run), where ``wall_s`` is the run's wall-clock time,
    #: which also counts the time waiting for a core; not part of the episode
    cpu_s: float = field(default=0.0, compare=False)
    #: the spec's ``keys`` and their values at the end, in its order (None: never written;
    #: :func:`final_values`), as ``params``: pairs, hashable and picklable
    keys: tuple[tuple[str, Any], ...] = ()
    #: each key a behaviour wrote that the mission does not declare, with who wrote it first
    #: and where (:func:`~roomba_bt.behaviours.blackboard.undeclared_writes`): the warning a
    #: run says, which an episode's silenced log does not; the summary says it once
    undeclared: tuple[tuple[str, str], ...] = ()
    #: of those keys, each that may be a misspelling of a declared key, with that key
    #: (``(("dirt_levl", "dirt_level"),)``: :func:`~roomba_bt.behaviours.blackboard.
    #: undeclared_meant`): the summary's warning says `` (did you mean 'dirt_level'?)`` as
    #: ``run``'s does (it said none: the records held no declared key to suggest)
    undeclared_like: tuple[tuple[str, str], ...] = ()
    #: each action of the user's own code whose commands the mode guard refused, with its
    #: class and where (:attr:`~roomba_bt.runtime.summary.RunSummary.refused_actions`): what
    #: ``run`` tells its author on stderr, which the summary says once for the episodes
    refused_actions: tuple[tuple[str, str], ...] = ()
    #: the mission's last words (the run summary's ``mission said`` line, "" for none): which
    #: way it ended, so a patrol's "laps done" and its "docked on a low battery", both a
    #: SUCCESS, are told apart in a sweep's records and report
    said: str = ""
    #: the robot model the episode's mission ran as (``EpisodeSpec.profile``): a results
    #: file read back (``eval --from``, ``--resume``) names it; "" in files written before
    profile: str = ""
    #: the behaviour the episode's slowest tick was in, where a behaviour held the ticks on
    #: the wall clock (the run summary's ``slowest ... ms in sleepy (Sleepy.update at
    #: x.py:11)``: runtime/tick_watch.py, :data:`~roomba_bt.runtime.tick_watch.WHEN_SLOW`),
    #: and that tick's host seconds; "" and 0 for an episode at its usual pace. The
    #: evaluation's report says it once; measured on the host, not part of the episode: a
    #: results file's ``slowest_tick_in`` and ``slowest_tick`` (left empty by
    #: ``--reproducible``), so that ``eval --from`` and ``--resume`` say it again
    slowest_in: str = field(default="", compare=False)
    slowest_tick_s: float = field(default=0.0, compare=False)
    #: the robot's 15 ms sensor frames the run never read (the run summary's ``frames ...
    #: lost``): what the line's faults (``--byte-drop-rate``, ``--stream-gap-at``...) cost the
    #: tree, which the report said nowhere
    frames_lost: int = 0

    @property
    def succeeded(self) -> bool:
        return self.outcome == "success"

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickled (to a worker's parent, from a Dask worker) as its values, unpickled by
        :func:`_arrived`: each text its own copy, unpickled, held the same words once per
        episode."""
        return _arrived, tuple(getattr(self, f.name) for f in fields(self))

    def sharing_words(self) -> EpisodeResult:
        """This result with its texts shared as an unpickled one's are (:func:`_arrived`):
        one read back from a results file (``--resume``, ``--from``) is made of its line's
        own strings, 1.5 KB a record, kept until the report."""
        return _arrived(*(getattr(self, f.name) for f in fields(self)))


def _trajectory(
    spec: EpisodeSpec, trace: Sequence[Any], simulator: Simulator
) -> tuple[tuple[float, float], ...]:
    """The trace's points (m) and the last pose, as ``spec`` asks (none, all, or as drawn)."""
    if spec.trace_every <= 0:
        return ()
    points = (
        *((p.x / 1000.0, p.y / 1000.0) for p in trace),
        (simulator.x / 1000.0, simulator.y / 1000.0),
    )
    return kept_path(points) if spec.simplify_path else points


def _arrived(*values: Any) -> EpisodeResult:
    """An :class:`EpisodeResult` unpickled, its texts shared with the results before it
    (:func:`_one_copy`) and its pairs of texts too (``params``, ``falls``' causes)."""
    return EpisodeResult(*(_shared(value) for value in values))


def _shared(value: Any) -> Any:
    if type(value) is str:
        return _one_copy(value)
    if type(value) is tuple and value and all(type(item) is tuple for item in value):
        return tuple(tuple(_shared(part) for part in item) for item in value)
    return value


@functools.lru_cache(maxsize=4096)
def _one_copy(text: str) -> str:
    """The first of the texts equal to ``text`` among the last 4 096 different ones met: a
    sweep's repeated words (its mission, world, outcomes, reasons, worker) held once. Not
    ``sys.intern``, whose strings the first 3.12 releases and the free-threaded build keep
    for the process's life (CPython gh-113993): a text met once (an error's message, a key's
    value) would stay after its sweep, in a program that runs many."""
    return text


class _MeasuredSimulator(Simulator):
    """A simulator that also records, per step, what the evaluation measures.

    Its work is on every step of every episode, so it does only what changed: the bearing
    around the world's centre is taken again only when the robot moved (standing still, the
    loop angle cannot change nor the progress mark move), and the longest stall is kept as
    the time of the last step without progress, folded in when the mark moves (the stall
    grows with time between two marks: its largest value is its last)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.contact_steps: list[int] = []
        self._in_contact = 0  # the bump bits of the last step (0: not pressed)
        self._centre_x, self._centre_y = centre = _world_centre(self.world)
        self._loop_angle = 0.0
        self._last_bearing = math.atan2(self.y - centre[1], self.x - centre[0])
        self._last_x, self._last_y = self.x, self.y
        # the progress mark: the loop angle and the time it was set (two attributes, not a
        # pair: the angle is read on every step that moves)
        self._mark_angle = self._mark_time = 0.0
        #: the longest stall before the progress mark, and the time of the last step since
        #: the mark without progress (None: none yet)
        self._longest_before_mark = 0.0
        self._stalled_at: float | None = None
        self._radius = max(1.0, math.hypot(self.x - centre[0], self.y - centre[1]))
        # the trap measure: where and when the robot last made progress (new floor cleaned,
        # or a move of TRAPPED_RADIUS_MM), the floor cleaned then, the longest stretch off
        # the dock without progress before it, and the last step off the dock since
        self._anchor_x, self._anchor_y, self._anchor_time = self.x, self.y, 0.0
        self._anchor_cleaned = 0
        self._longest_before_anchor = 0.0
        self._off_dock_at = 0.0
        self.reaction_steps: list[tuple[int, int]] = []
        self._since_onset: int | None = None  # steps since the last onset, while awaited
        self._stopped_after = -1

    def step(self, dt: float = STEP_SECONDS) -> None:
        # Simulator.step named, not super().step: super() builds an object every step
        if self._since_onset is not None:
            self._watch_reaction(self._since_onset)
        _simulator_step(self, dt)
        pressed = self.values[_BUMPS_PACKET] & BUMP_BITS
        if pressed:
            if not self._in_contact:
                self.contact_steps.append(0)
                self._since_onset, self._stopped_after = 0, -1
            else:
                self.contact_steps[-1] += 1
        self._in_contact = pressed
        x, y = self.x, self.y
        if self.docked:  # on the dock's contacts: where a robot is meant to wait
            self._progress(x, y)
        else:
            self._off_dock_at = self.time
        if x != self._last_x or y != self._last_y:  # moved (no tuple built to compare)
            self._last_x, self._last_y = x, y
            dx, dy = x - self._anchor_x, y - self._anchor_y
            swept = self.swept
            if dx * dx + dy * dy >= _TRAPPED_RADIUS_SQ or (
                swept is not None and swept.cleaned_total != self._anchor_cleaned
            ):
                self._progress(x, y)
            bearing = _atan2(y - self._centre_y, x - self._centre_x)
            loop_angle = self._loop_angle = self._loop_angle + _remainder(
                bearing - self._last_bearing, _TAU
            )
            self._last_bearing = bearing
            if abs(loop_angle - self._mark_angle) * self._radius >= 300.0:
                self._longest_before_mark = self.longest_stall
                self._mark_angle, self._mark_time = loop_angle, self.time
                self._stalled_at = None
                return
        self._stalled_at = self.time

    @property
    def longest_stall(self) -> float:
        """The longest time (s) with less than 0.3 m of progress around the world's centre."""
        stalled_at = self._stalled_at
        if stalled_at is None:
            return self._longest_before_mark
        return max(self._longest_before_mark, stalled_at - self._mark_time)

    def _progress(self, x: float, y: float) -> None:
        """The robot made progress at ``(x, y)`` (or stands on the dock): the stretch without
        progress before it is folded in, and a new one starts here."""
        self._longest_before_anchor = self.longest_trapped
        self._anchor_x, self._anchor_y, self._anchor_time = x, y, self.time
        swept = self.swept
        self._anchor_cleaned = swept.cleaned_total if swept is not None else 0

    @property
    def longest_trapped(self) -> float:
        """The longest time (s) off the dock in which the robot cleaned no new floor and
        went no further than :data:`TRAPPED_RADIUS_MM` from where it was: brushes on or
        off, so it also counts a robot trapped on its way home or in the dock search."""
        return max(self._longest_before_anchor, self._off_dock_at - self._anchor_time)

    def _watch_reaction(self, waited: int) -> None:
        """The wheels as requested before the step, ``waited`` steps after a bump frame."""
        mean = self.requested_left + self.requested_right
        if self._stopped_after < 0 and mean <= 0.0:
            self._stopped_after = waited
        if mean < 0.0 or waited >= 66:
            self.reaction_steps.append((self._stopped_after, waited if mean < 0.0 else -1))
            self._since_onset = None
        else:
            self._since_onset = waited + 1

    @property
    def loops(self) -> float:
        return self._loop_angle / math.tau


_simulator_step = Simulator.step
#: a robot that goes no further than this (mm) from where it was, cleaning no new floor,
#: makes no progress: trapped under chairs or wedged, it moves about within a chair's
#: footprint; driving home or searching for the dock, it gets further than this
TRAPPED_RADIUS_MM = 500.0
_TRAPPED_RADIUS_SQ = TRAPPED_RADIUS_MM * TRAPPED_RADIUS_MM
#: read on every step that moves, as globals (a module attribute is one read more)
_atan2, _remainder, _TAU = math.atan2, math.remainder, math.tau
#: the bumper's packet (7) in the simulator's values, read every step for the contacts
(_BUMPS_PACKET,) = BUMPS_PACKETS


def _world_centre(world: World) -> tuple[float, float]:
    xs = [x for room in world.rooms for x, _ in room]
    ys = [y for room in world.rooms for _, y in room]
    return ((min(xs) + max(xs)) / 2.0, (min(ys) + max(ys)) / 2.0)


def build_world(spec: EpisodeSpec) -> World:
    """The spec's world with its dock and battery overrides applied."""
    try:
        if spec.world_file is not None:
            source, text = spec.world_file
        else:
            text, source = world_text(spec.world)
        world = _parsed_world(text, source)
    except Exception as exc:  # WorldError: every problem, already worded for the user
        # its cause kept: eval --json lists each problem at its file, line and column
        raise EvaluationError(str(exc)) from exc
    if spec.dock:
        if world.dock is None:
            raise EvaluationError(f"--dock: world {world.name!r} has no dock")
        world = replace(world, dock=_override_dock(world.dock, dict(spec.dock)))
    if spec.battery is not None:
        world = replace(world, battery=spec.battery)
    return world


@functools.lru_cache(maxsize=16)
def _parsed_world(text: str, source: str) -> World:
    """A world's text parsed once per process: the episodes of an evaluation all read the
    same world, and parsing its YAML again was most of an episode's set-up. A
    :class:`World` is frozen: the episodes share it (their overrides make new ones)."""
    return parse_world(text, source)


def _override_dock(dock: DockSpec, overrides: dict[str, Any]) -> DockSpec:
    values: dict[str, Any] = {}
    for key, value in overrides.items():
        if key not in DOCK_OVERRIDES:
            raise EvaluationError(
                f"--dock {key}: unknown dock field; allowed: {', '.join(DOCK_OVERRIDES)}"
            )
        if key == "family":
            if value not in DOCK_FAMILIES:
                raise EvaluationError(f"--dock family={value}: allowed: {', '.join(DOCK_FAMILIES)}")
            values[key] = value
        elif key in ("red", "green"):
            lo, hi = value
            scale = DOCK_BEAM_LIMIT.scale
            values[key] = (float(lo) * scale, float(hi) * scale)
        else:
            values[key] = float(value) * DOCK_LIMITS[key].scale
    return replace(dock, **values)


def start_pose(world: World, spec: EpisodeSpec) -> Any:
    """The seeded start pose: the world's start region, or within ``within_m`` of the dock."""
    if not spec.random_start:
        return world.start
    from roomba_bt.sim.world import StartRegion

    if spec.start_area is not None:
        if world.area(spec.start_area) is None:
            names = ", ".join(a.name for a in world.areas) or "none"
            raise EvaluationError(
                f"--start-area {spec.start_area}: world {world.name!r} has no such area; "
                f"allowed: {names}"
            )
        world = replace(world, start_region=StartRegion(area=spec.start_area))
    elif spec.within_m is not None:
        if world.dock is None:
            raise EvaluationError(f"--within: world {world.name!r} has no dock")
        world = replace(world, start_region=StartRegion(near_dock=spec.within_m * 1000.0))
    try:
        return world.sample_start(spec.seed)
    except Exception as exc:
        given = f"--within {spec.within_m:g} m: " if spec.within_m is not None else ""
        raise EvaluationError(f"{given}{exc}") from None


def run_episode(
    spec: EpisodeSpec, simulator: type[_MeasuredSimulator] | None = None
) -> EpisodeResult:
    """Run one episode to its end (success, failure, or the spec's timeout). The robot
    layer's log lines (stream started, mode fell back, a stop a robot that switched itself
    off could not confirm) are silenced: the result's outcome and reason say what happened,
    and a thousand episodes' lines would scroll over the progress bar. ``simulator``: a
    subclass that measures more (:mod:`roomba_bt.evaluate.wheels`), for a caller that keeps
    its instance; the episode is the same."""
    started = _cpu_clock()
    with _robot_log_silenced():
        result = _run_episode(spec, simulator or _MeasuredSimulator)
    return tidied(replace(result, cpu_s=_cpu_clock() - started))


class _Silenced:
    """How many episodes of the process are running (:func:`_robot_log_silenced`), and the
    ``roomba_bt`` logger's level before the first of them."""

    lock = threading.Lock()
    running = 0
    level = logging.NOTSET


@contextlib.contextmanager
def _robot_log_silenced() -> Iterator[None]:
    """The ``roomba_bt`` logger at CRITICAL while any episode of the process runs, its level
    before the first put back after the last. Each episode saving and restoring it alone,
    two in threads left it CRITICAL for the rest of the process (the second saved the first's
    CRITICAL, and put it back last)."""
    logger = logging.getLogger("roomba_bt")
    with _Silenced.lock:
        if _Silenced.running == 0:
            _Silenced.level = logger.level
            logger.setLevel(logging.CRITICAL)
        _Silenced.running += 1
    try:
        yield
    finally:
        with _Silenced.lock:
            _Silenced.running -= 1
            if _Silenced.running == 0:
                logger.setLevel(_Silenced.level)


#: Significant digits kept of an episode's measured numbers (``stats.tidy``'s, for ``--json``):
#: a sum of 15 ms ticks is 27.885 s, not 27.884999999999998 (binary noise in the 16th digit),
#: in ``--out``'s records too, which still read back exactly (the rounded value is the value).
DIGITS = 10


def _tidy(value: Any) -> Any:
    if isinstance(value, float):
        return float(f"{value:.{DIGITS}g}") if math.isfinite(value) else value
    if isinstance(value, tuple):
        return tuple(_tidy(v) for v in value)
    return value


def tidied(result: EpisodeResult) -> EpisodeResult:
    """``result`` with every measured float cut to :data:`DIGITS` significant digits (the
    trajectory, for plots only, as it is)."""
    changes = {f.name: _tidy(getattr(result, f.name)) for f in fields(result)
               if f.name not in ("trajectory", "coverage")}  # fmt: skip
    coverage = result.coverage
    if coverage is not None:
        changes["coverage"] = replace(
            coverage, **{f.name: _tidy(getattr(coverage, f.name)) for f in fields(coverage)}
        )
    return replace(result, **changes)


#: The CPU seconds of the calling thread: an episode's, in whichever process or Dask
#: worker thread runs it (``time.process_time`` would add the worker's other threads).
_cpu_clock = time.thread_time


#: Missions compiled in this process, by what decides the compiled mission (the file, the
#: parameters, the profile, the permissions), with the text of every file it read: the
#: next episode of an evaluation builds its tree again from the checked plan
#: (:meth:`CompiledMission.rebuilt`) instead of compiling the same texts again.
_COMPILED: dict[
    tuple[object, ...], tuple[CompiledMission, tuple[tuple[Path, str | None], ...]]
] = {}
_COMPILED_KEPT = 16


def _mission(
    path: Path, params: tuple[tuple[str, str], ...], profile: RobotProfile, granted: Permissions
) -> CompiledMission:
    """The compiled mission for an episode, a tree of its own: compiled once per process
    while the texts of its files stay the same (each is read again and compared). The one
    kept is never run, each episode its own :meth:`~CompiledMission.rebuilt` tree: a run's
    leaves hold its robot handle, and the kept tree, run by the first episode, held that
    episode's connection and simulator for as long as the worker lived."""
    key = (path.resolve(), params, profile.name, granted)
    cached = _COMPILED.get(key)
    if cached is not None:
        mission, texts = cached
        if all(_text_of(file) == text for file, text in texts):
            return mission.rebuilt()
    mission = load_mission(path, dict(params), profile=profile, permissions=granted)
    if len(_COMPILED) >= _COMPILED_KEPT:
        del _COMPILED[next(iter(_COMPILED))]  # the oldest
    _COMPILED[key] = (mission, tuple((file, _text_of(file)) for file in mission.files))
    return mission.rebuilt()


def _text_of(path: Path) -> str | None:
    """A mission's file as it is now (None: unreadable or grown past the limit, which never
    matches a text)."""
    try:
        return yamlsource.read_text(path)
    except (OSError, UnicodeDecodeError, yamlsource.FileTooLarge):
        return None


#: Set in a local pool's worker processes (:func:`roomba_bt.evaluate.parallel.run_episodes`).
IN_POOL_WORKER = False


def _run_episode(spec: EpisodeSpec, measured: type[_MeasuredSimulator]) -> EpisodeResult:
    profile = get_profile(spec.profile)
    path = spec.sources.materialise() if spec.sources is not None else spec.mission
    granted = spec.permissions
    if spec.sources is not None:  # the bundle holds what the submitter's check allowed
        folder = Path(path).parents[len(Path(spec.sources.main).parts) - 1]
        granted = replace(granted, include_dirs=(*granted.include_dirs, folder))
    try:
        mission = _mission(Path(path), spec.params, profile, granted)
    except MissionError as exc:  # the evaluation compiled it before any episode: not here
        raise _not_compiled(spec, exc) from None
    world = build_world(spec)
    pose = start_pose(world, spec)
    faults = replace(spec.faults, odometry_error=spec.odometry_error)
    simulator = measured(
        world, profile, spec.seed, faults, start=pose, coverage=bool(mission.sends & BRUSHES),
        trace=spec.trace_every > 0, cycle_commands_pause=True,  # as the OI spec says
    )  # fmt: skip
    stack = RunStack(mission, SimLink(simulator), profile=profile, timeout_s=spec.timeout_s)
    stack.runner.summary.time_limit = spec.time_limit
    stack.runner.on_wall_clock = False  # Ctrl-Z suspends an evaluation, Ctrl-\ quits it
    if IN_POOL_WORKER:  # Ctrl-C is the parent's: it ends the pool, a worker just ends
        stack.runner.guards_signals = False
    # Ctrl-C or a signal stops the evaluation, not just this episode: raised again once the
    # robot is stopped, with the signal it stands for (its Interruption says which). A
    # behaviour that waits on the wall clock is named as run names it, by a watch that
    # sleeps while the episode runs at its usual pace (off the tick path: the loop is run's)
    with slowest_tick_named(stack.runner.summary, WHEN_SLOW):
        summary = stack.run()
    if summary.outcome is Outcome.INTERRUPTED:  # a stop asked of the run itself: the same
        raise KeyboardInterrupt(summary.reason)
    stage = failure_stage(summary.reason)
    board = stack.runner.blackboard
    result = _measured(spec, world, pose, simulator, summary, summary.outcome.value, stage, board)
    if board is not None:  # its keys removed: the next episode in the process starts clean
        board.release()
    return result


def _not_compiled(spec: EpisodeSpec, exc: MissionError) -> MissionNotCompiled:
    """What the worker's compiler said of the episode's mission, each file named as the
    evaluation gave it: the bundle's copy (``/tmp/roomba-bt-.../lab.py``) is no file the
    user knows."""
    said = _named_as_given(spec, "\n".join(reported(exc.diagnostics)))
    return MissionNotCompiled(spec.mission, f"{socket.gethostname()}:{os.getpid()}", said)


def _named_as_given(spec: EpisodeSpec, said: str) -> str:
    """``said`` with each file of the bundle's copy (``/tmp/roomba-bt-.../lab.py``, on a
    worker) named by its path as the evaluation was given it (``lab.py``), the file the user
    knows; as it is where the episode read the files themselves."""
    if spec.sources is None:
        return said
    depth = len(Path(spec.sources.main).parts) - 1  # folders from the bundle's root
    copy = spec.sources.materialise().parents[depth]
    given = os.path.normpath(os.path.join(Path(spec.mission).parent, *[".."] * depth))
    return said.replace(f"{copy}{os.sep}", "" if given == "." else f"{given}{os.sep}")


def _pairs_as_given(
    spec: EpisodeSpec, pairs: Iterable[tuple[str, str]]
) -> tuple[tuple[str, str], ...]:
    """Each ``(name, where)`` with its file named as the evaluation was given it
    (:func:`_named_as_given`): an undeclared key's writer, a refused action's class."""
    return tuple((name, _named_as_given(spec, where)) for name, where in pairs)


def _measured(
    spec: EpisodeSpec,
    world: World,
    pose: Any,
    simulator: _MeasuredSimulator,
    summary: RunSummary,
    outcome: str,
    stage: str,
    board: RunBoard | None,
) -> EpisodeResult:
    """The result of an episode that ran (to its end, or until its wall-clock limit): its
    summary's words and counts, what its simulator measured, and the keys asked for as
    its run's blackboard (``board``) holds them."""
    trace = simulator.trace[:: max(1, spec.trace_every)]
    events = simulator.events
    return EpisodeResult(
        seed=spec.seed,
        outcome=outcome,
        reason=summary.reason,
        time_s=summary.mission_time_s,
        wall_s=summary.wall_time_s,
        ticks=summary.ticks,
        start=(pose.x / 1000.0, pose.y / 1000.0, math.degrees(pose.theta)),
        end=(simulator.x / 1000.0, simulator.y / 1000.0, math.degrees(simulator.theta)),
        bumps=sum(1 for e in events if e.kind == "bump"),
        contact_steps=tuple(simulator.contact_steps),
        reaction_steps=tuple(simulator.reaction_steps),
        docked=simulator.docked,
        charging=simulator.charging,
        cliffs=sum(1 for e in events if e.kind == "cliff"),
        fell=simulator.fallen,
        violations=len(simulator.violations),
        loops=simulator.loops,
        longest_stall_s=simulator.longest_stall,
        longest_trapped_s=simulator.longest_trapped,
        trajectory=_trajectory(spec, trace, simulator),
        mission=spec.mission,
        world=world.name,
        params=spec.params,
        stage=stage,
        distance_m=summary.distance_mm / 1000.0,
        commands_sent=summary.commands_written,
        commands_refused=summary.refused_commands,
        falls=falls_in_order(summary.falls),
        worker=f"{socket.gethostname()}:{os.getpid()}",
        coverage=_coverage(simulator, spec.start_area or ""),
        keys=final_values(spec.keys, board),
        undeclared=_pairs_as_given(spec, undeclared_writes(board)),
        undeclared_like=undeclared_meant(board),
        refused_actions=_pairs_as_given(spec, summary.refused_actions),
        said=summary.said,
        profile=spec.profile,
        slowest_in=_named_as_given(spec, summary.slowest_in),
        slowest_tick_s=summary.max_tick_s if summary.slowest_in else 0.0,
        frames_lost=summary.frames_lost,
    )


def final_values(
    names: Sequence[str], board: RunBoard | None = None
) -> tuple[tuple[str, Any], ...]:
    """Each of ``names`` with its value on ``board`` (the episode's run's blackboard; None:
    this thread's run's) now, at the episode's end (None: never written; a record's field
    read as ``check`` reads it). The declared types are
    numbers, bools and text; anything else a plugin wrote is kept as its text, so that a
    result stays plain data (pickled from a worker, written as JSON)."""
    values = []
    for name in names:
        value = board.read(name) if board is not None else read_key(name)
        if not (value is None or isinstance(value, bool | int | float | str)):
            value = str(value)
        values.append((name, value))
    return tuple(values)


#: The outcome of an episode stopped at its wall-clock limit (``eval --wall-limit``): stuck
#: (a behaviour's endless loop, most often), not a way the mission ended; ``run
#: --wall-limit``'s outcome, the same word (:attr:`Outcome.HUNG`).
HUNG = Outcome.HUNG.value

#: ``--wall-limit``'s default: this, plus a tenth of the episode's --timeout. Episodes run
#: 200-900x real time (docs/performance.md), so one still running at a tenth of its mission
#: time, after a minute for its set-up and a busy machine, is stuck.
WALL_LIMIT_GRACE_S = 60.0
WALL_LIMIT_SPEED = 10.0


def default_wall_limit(timeout_s: float) -> float:
    """The wall-clock seconds an episode of ``timeout_s`` mission time gets by default."""
    return WALL_LIMIT_GRACE_S + timeout_s / WALL_LIMIT_SPEED


def hung_result(
    spec: EpisodeSpec, limit_s: float, frames: list[tuple[FrameType, int]] | None
) -> EpisodeResult:
    """The record of an episode stopped at its wall-clock limit: where it was stuck, from the
    stack it was on (``frames``, outermost first; None: none could be read, a loop in C code),
    the behaviour (its path in the tree, file:line, the stage) and what the episode had
    measured by then (the locals of its :func:`_run_episode`); all zero when it was stuck
    before its run began (compiling the mission: a plugin's import)."""
    behaviour, reason = ran_out(limit_s, frames)
    stage = behaviour.name.split("(", 1)[0] if behaviour is not None else ""
    run = next((f.f_locals for f, _ in frames or () if f.f_code is _run_episode.__code__), {})
    stack = run.get("stack")
    cpu_s = _cpu_so_far(frames)
    if not isinstance(stack, RunStack):
        zero = (0.0, 0.0, 0.0)
        return EpisodeResult(
            spec.seed, HUNG, reason, 0.0, limit_s, 0, zero, zero, 0, (), False, False, 0,
            False, 0, 0.0, 0.0, mission=spec.mission, world=spec.world, params=spec.params,
            stage=stage, profile=spec.profile, cpu_s=cpu_s,
        )  # fmt: skip
    runner = stack.runner
    runner.count_written()
    # the falls so far: the runner copies them into its summary only at the run's end
    falls = stack.connection.falls
    summary = replace(runner.summary, reason=reason, wall_time_s=limit_s, falls=falls)
    summary.take_last(runner.snapshot if runner.has_snapshot else None)
    measured = _measured(
        spec, run["world"], run["pose"], run["simulator"], summary, HUNG, stage, runner.blackboard
    )
    return tidied(replace(measured, cpu_s=cpu_s))


def _cpu_so_far(frames: list[tuple[FrameType, int]] | None) -> float:
    """The CPU time the stuck episode's thread has spent since :func:`run_episode` began
    (its ``started``, read from its frame): a HUNG result is made in that thread (the
    local worker's SIGUSR1 handler, Dask's exception in it). It recorded none, and the
    summary's speed counted its mission time over the others' CPU time; 0.0 when no
    Python frame answered (a loop in C code)."""
    code = run_episode.__code__
    started = next((f.f_locals.get("started") for f, _ in frames or () if f.f_code is code), None)
    return max(0.0, _cpu_clock() - started) if isinstance(started, float) else 0.0


#: The outcome of an episode whose worker process died while running it, and again when it
#: ran alone (a behaviour calling ``os._exit``, a crash in C code, the OOM killer): a bug, as a
#: HUNG one is, recorded so that the sweep goes on without it.
DIED = "died"


def died_result(spec: EpisodeSpec, how: str, worker: str = "") -> EpisodeResult:
    """The record of an episode whose worker died running it: ``how`` it died (its exit
    status, or what Dask says) as the reason; nothing measured (the process that measured
    it is gone), as a HUNG episode stuck before its run began."""
    zero = (0.0, 0.0, 0.0)
    return EpisodeResult(
        spec.seed, DIED, f"the worker running it died: {how}", 0.0, 0.0, 0, zero, zero, 0, (),
        False, False, 0, False, 0, 0.0, 0.0, mission=spec.mission, world=spec.world,
        params=spec.params, worker=worker, profile=spec.profile,
    )  # fmt: skip


#: What runs the brushes (Motors, PWM Motors, the firmware's Clean, Spot and Max): a mission
#: whose leaves send none of these never cleans, and its simulator keeps no coverage grid
#: (building one was a fifth of an episode's set-up, and it was updated on every step).
BRUSHES = frozenset(opcodes("motors", "pwm_motors", "clean", "spot", "max"))

#: how often an episode's coverage curve is sampled (s)
COVERAGE_SAMPLE_S = 30.0


def _coverage(simulator: Simulator, area: str) -> Coverage | None:
    """The episode's coverage, or None if the brushes never ran."""
    swept = simulator.swept
    if swept is None or not swept.cleaning_time:
        return None
    swept.finish(simulator.time, simulator.x, simulator.y, simulator.theta)
    index = swept.area_names.index(area) + 1 if area in swept.area_names else None
    total = swept.reachable_cells[index] if index is not None else swept.reachable_total
    curve: list[tuple[float, float]] = []
    for t, cells in swept.curve:
        if not curve or t >= curve[-1][0] + COVERAGE_SAMPLE_S - 1e-6:
            cleaned = cells[index] if index is not None else sum(cells)
            curve.append((round(t, 3), cleaned / total if total else 0.0))
    by_area = swept.coverage_by_area()
    final = by_area.get(area, 0.0) if index is not None else swept.coverage()
    end = round(simulator.time, 3)
    if curve and curve[-1][0] < end:  # the last sample: an episode that ended between two
        curve.append((end, final))  # read its sample before the end at any later time
    return Coverage(
        area=area,
        final=final,
        curve=tuple(curve),
        overall=swept.coverage(),
        by_area=tuple(by_area.items()),
        longest_idle_s=swept.longest_idle(),
        cleaning_s=swept.cleaning_time,
    )


_STAGE = re.compile(r"^([a-z_][a-z0-9_]*)(?:\(|: |$)")
_RUNNING_STAGE = re.compile(r"\(stage ([^)]+) was running\)|ran out in ([a-z_][a-z0-9_]*)$")
#: ``behaviour sequence / boom(x=1) raised RuntimeError: ...`` (runtime/teardown.py)
_RAISED_IN = re.compile(r"^behaviour (.+?) raised ")


def failure_stage(reason: str) -> str:
    """The stage a failure reason names: the one it says was running (``... (stage search
    was running)`` -> ``search``; a --timeout or a ``timeout`` decorator that ``... ran out
    in dock_approach`` -> ``dock_approach``), the behaviour that raised (``behaviour
    sequence / boom(x=1) raised ...`` -> ``boom``), else the leaf it starts with
    (``find_dock(...): lost the beam`` -> ``find_dock``, ``charging`` -> ``charging``); ""
    when it names none."""
    running = _RUNNING_STAGE.search(reason)
    if running:
        return running.group(1) or running.group(2)
    if reason.startswith(GUARD_STOPPED):  # a while guard that stopped before a leaf ran
        return ""
    raised = _RAISED_IN.match(reason)
    if raised:
        return raised.group(1).rsplit(" / ", 1)[-1].split("(", 1)[0]
    match = _STAGE.match(reason)
    return match.group(1) if match else ""


def mission_name(path: str) -> str:
    return Path(path).stem
