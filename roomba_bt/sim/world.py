"""Worlds: the floor the simulated robot drives on, read from YAML and validated.

A world file is written in metres and degrees (people measure rooms that way); everything is
converted once, on load, to the simulator's millimetres and radians. The schema, with every
default, is in ``docs/simulator.md``; in short::

    name: empty-room
    rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]   # floor polygons; their edges are walls
    walls: [[1.0, 0.0, 1.0, 1.2]]                # extra wall segments (x0, y0, x1, y1)
    obstacles: [{name: sofa, rect: [0.2, 2.0, 2.0, 2.8]}]   # or {polygon: [[x, y], ...]}
    drops: [{name: stairs, rect: [3.0, 0.0, 4.0, 1.0]}]      # cliff zones
    dirt: [{name: crumbs, rect: [1.0, 1.0, 1.5, 1.5], level: 40}]  # packet 15 over it
    virtual_walls: [{from: [2, 0], to: [2, 3], halo: 0.3}]
    lighthouses: [{id: 1, at: [2, 1.5], heading: 90, fence: 2.0, halo: 0.4}]
    dock: {at: [2, 0], facing: 90, red: [-5, 25], green: [-25, 5], buoy_range: 1.0,
           force_field: 0.6, contact_tolerance: 0.075, angle_tolerance: 6, family: drive-on}
    robot: {start: {at: [2, 1], heading: -90}, battery: 0.8,
            start_region: {near_dock: 1.5}}          # or {rect: [...], heading: [lo, hi]}
    events: [{at: 5.0, kind: bump, side: left, duration: 0.2}]
    areas: [{name: living-room, rect: [0, 0, 4, 1.5]}]   # named parts of the floor (no walls)

Every problem is reported at once, each as ``file:line:col: field: found ...; allowed ...``,
with the line and column of the offending YAML node (the shared reader,
:mod:`roomba_bt.yamlsource`, keeps the position of every node). Loading never shows a
traceback to a user: it raises :class:`WorldError`, which the CLI prints.
"""

from __future__ import annotations

import contextlib
import difflib
import math
import os
import pathlib
import random
import re
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from typing import Any

import yaml

from roomba_bt import yamlsource
from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.bits import BUTTON_NAMES, OVERCURRENT_BITS, PRESS_SECONDS
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import BODY_RADIUS_MM
from roomba_bt.printable import MAX_FOUND, MAX_LISTED, broken_link, listed, stopped_finding
from roomba_bt.sim.geometry import (
    Point,
    Polygon,
    Segment,
    distance_sq_to_segment,
    point_in_polygon,
    polygon_edges,
    segments_meet,
    wrap_angle,
)

#: Radius of the round Roomba / Create 2 body (oi.profiles.BODY_RADIUS_MM).
ROBOT_RADIUS_MM = BODY_RADIUS_MM
#: How far into a wall a pose may reach and still count as touching it (mm): a robot whose
#: bumper rests on a wall fits there (the docked pose is one, 170 mm from the plate), and
#: the docked pose of a dock facing at an angle lands that much off by rounding.
TOUCHING_MM = 1e-6

#: The shipped worlds: package data (``roomba_bt/sim/worlds/``, also linked as ``worlds/`` at
#: the top of the source tree).
WORLDS_DIR = pathlib.Path(__file__).resolve().parent / "worlds"

#: Folders of the user's own worlds, separated as in ``PYTHONPATH``, whose worlds a name
#: finds before the shipped ones (:func:`world_folders`).
WORLDS_VARIABLE = "ROOMBA_BT_WORLDS"

EVENT_KINDS = ("bump", "lift", "charger_step", "press", "overcurrent", "plug")
SIDES = ("left", "right", "both")
DOCK_FAMILIES = ("drive-on", "discovery")


@dataclass(frozen=True, slots=True)
class Limit:
    """The range a number of a world may take, as written (``lo..hi`` in ``unit``), and the
    factor to the model's unit (metres -> mm, degrees -> radians)."""

    lo: float
    hi: float
    unit: str
    scale: float = 1.0

    def allowed(self) -> str:
        """``a number in 0.2..5 m``: what a message says may stand there."""
        return f"a number in {self.lo:g}..{self.hi:g} {self.unit}"

    def holds(self, value: float) -> bool:
        return self.lo <= value <= self.hi  # NaN holds nowhere


#: The dock's numbers, in a world file's ``dock:`` and in ``eval --dock FIELD=VALUE`` alike.
DOCK_LIMITS: dict[str, Limit] = {
    "buoy_range": Limit(0.2, 5.0, "m", 1000.0),
    "force_field": Limit(0.1, 2.0, "m", 1000.0),
    "contact_tolerance": Limit(0.01, 0.3, "m", 1000.0),
    "plate_width": Limit(0.1, 1.0, "m", 1000.0),
    "angle_tolerance": Limit(1.0, 45.0, "deg", math.pi / 180.0),
}
#: Each end of a dock beam's ``[from, to]`` (``red``, ``green``), from the dock's facing.
DOCK_BEAM_LIMIT = Limit(-90.0, 90.0, "deg", math.pi / 180.0)


# ----------------------------------------------------------------------------- the model


@dataclass(frozen=True, slots=True)
class Pose:
    """A robot pose: ``x``, ``y`` in mm, ``theta`` in radians (CCW from +x)."""

    x: float
    y: float
    theta: float


@dataclass(frozen=True, slots=True)
class DockSpec:
    """The charging dock and its IR beams (defaults: ``GUIDE.md`` section 5).

    ``x, y`` is the middle of the dock's back plate, where the robot's bumper touches it and
    where the beams come from; ``facing`` points from the dock into the room. Beam angles are
    measured from ``facing``, positive toward the dock's own left (counter-clockwise)::

                    red   -5 .. +25 deg   (dock's left)
        dock  ===>  both  -5 .. +5  deg   on the axis
                    green -25 .. +5 deg   (dock's right)
    """

    x: float
    y: float
    facing: float
    red: tuple[float, float] = (math.radians(-5.0), math.radians(25.0))
    green: tuple[float, float] = (math.radians(-25.0), math.radians(5.0))
    buoy_range: float = 1000.0
    force_field: float = 600.0
    contact_tolerance: float = 75.0
    angle_tolerance: float = math.radians(6.0)
    family: str = "drive-on"
    plate_width: float = 300.0

    @property
    def docked_pose(self) -> Pose:
        """Where the robot's centre is when its bumper rests on the plate, facing the dock."""
        return Pose(
            self.x + ROBOT_RADIUS_MM * math.cos(self.facing),
            self.y + ROBOT_RADIUS_MM * math.sin(self.facing),
            wrap_angle(self.facing + math.pi),
        )

    @property
    def plate(self) -> Segment:
        half = self.plate_width / 2.0
        px, py = -math.sin(self.facing) * half, math.cos(self.facing) * half
        return (self.x - px, self.y - py, self.x + px, self.y + py)


@dataclass(frozen=True, slots=True)
class VirtualWallSpec:
    """A virtual wall: an IR beam from its emitter ``(ax, ay)`` to ``(bx, by)``; the robot's
    omni receiver sees it within ``half_width`` of the beam or ``halo`` of the emitter."""

    ax: float
    ay: float
    bx: float
    by: float
    half_width: float = 60.0
    halo: float = 0.0

    @property
    def segment(self) -> Segment:
        return (self.ax, self.ay, self.bx, self.by)


@dataclass(frozen=True, slots=True)
class LighthouseSpec:
    """A virtual-wall lighthouse: a fence beam along ``heading`` and a force-field halo."""

    id: int
    x: float
    y: float
    heading: float
    fence: float = 2000.0
    halo: float = 400.0
    half_width: float = 60.0

    @property
    def fence_segment(self) -> Segment:
        return (
            self.x,
            self.y,
            self.x + self.fence * math.cos(self.heading),
            self.y + self.fence * math.sin(self.heading),
        )


@dataclass(frozen=True, slots=True)
class TimelineEvent:
    """Something the world does to the robot at ``time`` seconds, for ``duration`` seconds.

    ``bump``: the bumper is pressed (``side``); ``lift``: the robot is picked up (both wheel
    drops, cliffs, no traction); ``charger_step``: someone steps on the charger, which loses
    power for the duration; ``plug``: the wall charger's plug is put in the robot's socket
    (the internal charger, packet 34 bit 0) and pulled out after the duration; ``press``: a
    finger presses ``button`` (packet 18's name) for the spec's 1/6 s, which in Passive
    starts the robot's own cycle for Clean, Spot or Dock;
    ``overcurrent``: ``motor`` (packet 14's name: a brush wound with hair, a wheel jammed)
    shows an overcurrent for the duration."""

    time: float
    kind: str
    duration: float
    side: str = "both"
    button: str = ""
    motor: str = ""


#: How far from the docked pose a start region may reach (m): the evaluation's ``--within``
#: too (farther, the region lies almost all outside any room and no free pose is found).
NEAR_DOCK_RANGE_M = (0.05, 20.0)


@dataclass(frozen=True, slots=True)
class StartRegion:
    """Random start poses for evaluation: within ``near_dock`` mm of the docked pose, in
    ``rect`` (x0, y0, x1, y1 mm) or in the named ``area``; heading anywhere or in ``heading``
    (radians, lo..hi)."""

    near_dock: float | None = None
    rect: tuple[float, float, float, float] | None = None
    heading: tuple[float, float] | None = None
    area: str | None = None


@dataclass(frozen=True, slots=True)
class AreaSpec:
    """A named part of the floor (a room of an open-plan flat, say): for reports such as the
    coverage per room, and start regions. Not a wall: the robot drives across its edges."""

    name: str
    polygon: Polygon


@dataclass(frozen=True, slots=True)
class DirtSpec:
    """A dirty patch of floor: over it, the robot's dirt detector (packet 15) reads ``level``."""

    area: Polygon
    level: int


@dataclass(frozen=True)
class World:
    """A validated world, in millimetres and radians."""

    name: str
    rooms: tuple[Polygon, ...]
    start: Pose
    walls: tuple[Segment, ...] = ()
    obstacles: tuple[Polygon, ...] = ()
    drops: tuple[Polygon, ...] = ()
    #: dirty patches and the dirt-detect level (packet 15, 0-255) the robot reads over each
    dirt: tuple[DirtSpec, ...] = ()
    virtual_walls: tuple[VirtualWallSpec, ...] = ()
    lighthouses: tuple[LighthouseSpec, ...] = ()
    dock: DockSpec | None = None
    start_region: StartRegion | None = None
    events: tuple[TimelineEvent, ...] = ()
    battery: float = 0.8
    areas: tuple[AreaSpec, ...] = ()
    source: str = "<world>"
    description: str = ""
    #: what loads but is likely a mistake, at its place in the file (a given start whose
    #: body reaches over a drop): ``validate`` and ``run --world`` say them
    warnings: tuple[WorldProblem, ...] = field(default=(), compare=False)
    solid: tuple[Segment, ...] = field(init=False)

    def __post_init__(self) -> None:
        solid: list[Segment] = []
        for room in self.rooms:
            solid += polygon_edges(room)
        solid += self.walls
        for obstacle in self.obstacles:
            solid += polygon_edges(obstacle)
        if self.dock is not None:
            solid.append(self.dock.plate)
        object.__setattr__(self, "solid", tuple(solid))

    # ------------------------------------------------------------------ queries
    def on_floor(self, x: float, y: float) -> bool:
        """Inside a room and not inside an obstacle."""
        if not any(point_in_polygon(x, y, room) for room in self.rooms):
            return False
        return not any(point_in_polygon(x, y, ob) for ob in self.obstacles)

    def over_drop(self, x: float, y: float) -> bool:
        return any(point_in_polygon(x, y, drop) for drop in self.drops)

    def dirt_at(self, x: float, y: float) -> int:
        """The dirt-detect level (packet 15) at a point: the highest patch under it, else 0."""
        return max((d.level for d in self.dirt if point_in_polygon(x, y, d.area)), default=0)

    def pose_is_free(self, pose: Pose, clearance: float = ROBOT_RADIUS_MM) -> bool:
        """The robot fits here: on the floor, no wall within its radius (touching one fits:
        :data:`TOUCHING_MM`), not over a drop. So the docked pose, the bumper on the plate,
        is a start pose (without the touching allowance 0.17 m from a wall would be refused
        and 0.171 m taken)."""
        if not self.on_floor(pose.x, pose.y) or self.over_drop(pose.x, pose.y):
            return False
        limit = (clearance - TOUCHING_MM) ** 2
        return all(distance_sq_to_segment(pose.x, pose.y, s) > limit for s in self.solid)

    def body_clear_of_drops(self, pose: Pose, clearance: float = ROBOT_RADIUS_MM) -> bool:
        """No part of the body, ``clearance`` around the centre, over a drop: the cliff sensors
        (0.15 m out) and the wheels' tyres are inside it, so a robot put here neither falls
        (a tyre past the edge) nor reads a cliff on its first frame. :meth:`pose_is_free`
        asks only the centre, which a given start needs (a test may put one at an edge)."""
        if self.over_drop(pose.x, pose.y):
            return False
        limit = clearance**2
        return all(
            distance_sq_to_segment(pose.x, pose.y, edge) >= limit
            for drop in self.drops
            for edge in polygon_edges(drop)
        )

    def nearest_drop(self, pose: Pose) -> tuple[int, float]:
        """The drop whose edge is nearest the pose's centre: its index in ``drops`` and the
        distance (mm; infinite with no drop), which tells how far a body reaches over it."""
        return min(
            (
                (i, math.sqrt(min(distance_sq_to_segment(pose.x, pose.y, e) for e in edges)))
                for i, drop in enumerate(self.drops)
                if (edges := polygon_edges(drop))
            ),
            key=lambda found: found[1],
            default=(-1, math.inf),
        )

    def area(self, name: str) -> AreaSpec | None:
        """The named area, or None."""
        return next((a for a in self.areas if a.name == name), None)

    def sample_start(self, seed: int) -> Pose:
        """A free pose drawn from the start region (or the start pose if there is none),
        the same for the same seed: the body with 20 mm to spare clear of every wall,
        obstacle and drop (a body over the apartment's stairs fell at 0.1 s, a failure that
        was not the mission's)."""
        region = self.start_region
        if region is None:
            return self.start
        rng = random.Random(f"start:{seed}")
        area = self.area(region.area) if region.area is not None else None
        for _ in range(10_000):
            if region.near_dock is not None and self.dock is not None:
                centre = self.dock.docked_pose
                r = region.near_dock * math.sqrt(rng.random())
                a = rng.uniform(-math.pi, math.pi)
                x, y = centre.x + r * math.cos(a), centre.y + r * math.sin(a)
            elif region.rect is not None:
                x0, y0, x1, y1 = region.rect
                x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
            elif area is not None:
                x = rng.uniform(min(p[0] for p in area.polygon), max(p[0] for p in area.polygon))
                y = rng.uniform(min(p[1] for p in area.polygon), max(p[1] for p in area.polygon))
                if not point_in_polygon(x, y, area.polygon):
                    continue
            else:
                return self.start
            lo, hi = region.heading if region.heading is not None else (-math.pi, math.pi)
            pose = Pose(x, y, wrap_angle(rng.uniform(lo, hi)))
            room = ROBOT_RADIUS_MM + 20.0
            if self.pose_is_free(pose, room) and self.body_clear_of_drops(pose, room):
                return pose
        raise WorldError(
            [WorldProblem(self.source, 0, 0, "robot.start_region", "no free pose", "a region "
                          "with room for the robot (340 mm across)")]
        )  # fmt: skip


# ----------------------------------------------------------------------------- errors


@dataclass(frozen=True, slots=True)
class WorldProblem:
    """One problem of a world file: ``field`` (dotted path) found ``found``, ``allowed`` says
    what may stand there. Without ``allowed``, ``found`` is a whole sentence (YAML's own
    syntax message after ``field`` "YAML syntax error", or an alias or tag refused), worded
    as a mission file's are."""

    source: str
    line: int
    column: int
    field: str
    found: str
    allowed: str

    def __str__(self) -> str:
        where = f"{self.source}:{self.line}:{self.column}" if self.line else self.source
        return f"{where}: {self.message}"

    @property
    def message(self) -> str:
        """The problem without its place: what ``eval --json`` lists beside the file, line
        and column, as a mission's diagnostic has them."""
        if not self.allowed:  # a sentence of its own: YAML's syntax error, a refused tag
            field = f"{self.field}: " if self.field else ""
            return f"{field}{self.found}"
        return f"{self.field}: found {self.found}; allowed: {self.allowed}"


class WorldError(ValueError, RoombaBtError):
    """A world that cannot be loaded; ``problems`` lists every one found, in the file's
    order (those without a place last); its message, the first hundred
    (:func:`~roomba_bt.printable.listed`: 20,000 bad obstacles were 20,000 lines). A check
    stops at :data:`~roomba_bt.printable.MAX_FOUND` problems: the last kept is then the note
    that says so, at the place of the last found, listed as the hundredth (after it, only
    how many more are said)."""

    def __init__(self, problems: list[WorldProblem]) -> None:
        ordered = sorted(problems, key=lambda p: (not p.line, p.line, p.column))
        if len(ordered) >= MAX_FOUND:
            last = ordered[MAX_FOUND - 1]
            note = WorldProblem(last.source, last.line, last.column, "", stopped_finding(), "")
            ordered = ordered[: MAX_FOUND - 1]
            ordered.insert(MAX_LISTED - 1, note)
        self.problems = ordered
        super().__init__("\n".join(listed([str(p) for p in self.problems])))


class _Stopped(Exception):
    """A world's check found :data:`~roomba_bt.printable.MAX_FOUND` problems: no more are
    looked for (:class:`WorldError` says so)."""


# ----------------------------------------------------------------------------- loading

PathKey = yamlsource.PathKey


_KEY = yamlsource.KEY  # marks[(*path, key, _KEY)]: where a mapping key itself is written


def _dotted(path: PathKey) -> str:
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else part
    return out or "(document)"


def _show(value: object) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return yamlsource.quoted(value)


class _Checker:
    """Collects every problem of one world file."""

    def __init__(self, source: str, marks: dict[PathKey, tuple[int, int]]) -> None:
        self.source = source
        self.marks = marks
        self.problems: list[WorldProblem] = []
        self.warnings: list[WorldProblem] = []

    def error(self, path: PathKey, found: str, allowed: str, at: PathKey | None = None) -> None:
        self.add(self._placed(path, found, allowed, at))

    def add(self, problem: WorldProblem) -> None:
        """One more problem; :class:`_Stopped` at :data:`~roomba_bt.printable.MAX_FOUND`."""
        self.problems.append(problem)
        if len(self.problems) >= MAX_FOUND:
            raise _Stopped

    def warn(self, path: PathKey, found: str, allowed: str) -> None:
        """Something that loads but is likely a mistake, said at its place as an error is."""
        self.warnings.append(self._placed(path, found, allowed))

    def _placed(
        self, path: PathKey, found: str, allowed: str, at: PathKey | None = None
    ) -> WorldProblem:
        probe = at if at is not None and at in self.marks else path
        while probe not in self.marks and probe:
            probe = probe[:-1]
        line, col = self.marks.get(probe, (0, 0))
        return WorldProblem(self.source, line, col, _dotted(path), found, allowed)

    def mapping(
        self, value: object, path: PathKey, keys: tuple[str, ...], required: tuple[str, ...] = ()
    ) -> dict[str, Any] | None:
        if not isinstance(value, dict):
            self.error(path, _show(value), f"a mapping with keys {', '.join(keys)}")
            return None
        for key in value:
            if key not in keys:
                close = difflib.get_close_matches(str(key), keys, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                self.error(
                    (*path, str(key)),
                    f"unknown key {key!r}",
                    f"{', '.join(keys)}{hint}",
                    at=(*path, str(key), _KEY),
                )
        for key in required:
            if key not in value:
                self.error(path, f"no {key!r}", f"a mapping with {key!r}")
        return value

    def record(
        self, value: object, path: PathKey, keys: tuple[str, ...], required: tuple[str, ...]
    ) -> dict[str, Any] | None:
        """A :meth:`mapping` that is only of use with all its ``required`` keys: None (and
        the problems reported) without one of them."""
        spec = self.mapping(value, path, keys, required)
        if spec is None or any(key not in spec for key in required):
            return None
        return spec

    def records(
        self, value: object, section: str, keys: tuple[str, ...], required: tuple[str, ...]
    ) -> Iterator[tuple[PathKey, dict[str, Any]]]:
        """Each :meth:`record` of the list ``section`` holds, with its path; the ones that are
        none are reported and left out."""
        for i, item in enumerate(self.items(value, (section,))):
            path: PathKey = (section, i)
            spec = self.record(item, path, keys, required)
            if spec is not None:
                yield path, spec

    def number(self, value: object, path: PathKey, lo: float, hi: float, unit: str) -> float | None:
        limit = Limit(lo, hi, unit)
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.error(path, _show(value), limit.allowed())
            return None
        if not limit.holds(value):
            self.error(path, _show(value), limit.allowed())
            return None
        return float(value)

    def choice(self, value: object, path: PathKey, choices: tuple[str, ...]) -> str | None:
        if not isinstance(value, str) or value not in choices:
            close = difflib.get_close_matches(str(value), choices, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            self.error(path, _show(value), f"one of {', '.join(choices)}{hint}")
            return None
        return value

    def numbers(
        self, value: object, path: PathKey, count: int, limits: tuple[float, float, str], what: str
    ) -> tuple[float, ...] | None:
        """A list of ``count`` numbers, each within ``limits`` (lo, hi, unit); every bad one
        is reported. ``what`` says what the whole list should be."""
        if not isinstance(value, list) or len(value) != count:
            self.error(path, _show(value), what)
            return None
        nums = [self.number(v, (*path, i), *limits) for i, v in enumerate(value)]
        if any(n is None for n in nums):
            return None
        return tuple(n or 0.0 for n in nums)

    def point(self, value: object, path: PathKey) -> Point | None:
        """``[x, y]`` in metres -> mm."""
        xy = self.numbers(value, path, 2, _METRES, "a point [x, y] in metres")
        if xy is None:
            return None
        return (xy[0] * 1000.0, xy[1] * 1000.0)

    def polygon(self, value: object, path: PathKey) -> Polygon | None:
        if not isinstance(value, list) or len(value) < 3:
            self.error(path, _show(value), "a polygon: a list of at least 3 points [x, y] (m)")
            return None
        points = [self.point(p, (*path, i)) for i, p in enumerate(value)]
        if any(p is None for p in points):
            return None
        poly = tuple(p for p in points if p is not None)
        repeated = _repeated_corner(poly)
        if repeated is not None:
            i, what = repeated
            self.error((*path, i), f"[{poly[i][0] / 1000:g}, {poly[i][1] / 1000:g}] again, "
                       f"{what}",
                       "each corner once, in order around the polygon")  # fmt: skip
            return None
        if _collinear(poly):  # its sides lie over each other: "cross" said nothing of a line
            self.error(path, "a polygon of zero area (its corners all on one line)",
                       "a polygon enclosing some floor")  # fmt: skip
            return None
        crossing = _first_crossing(poly)
        if abs(_area(poly)) < 1.0 and crossing is None:  # a bowtie's halves cancel: it crosses
            self.error(path, "a polygon of zero area", "a polygon enclosing some floor")
            return None
        if crossing is not None:
            sides = " and ".join(_side(poly, i) for i in crossing)
            self.error(
                path,
                f"a polygon whose sides cross ({sides})",
                "a polygon whose points go once around it, in order (its sides meet only at "
                "its corners)",
            )
            return None
        return poly

    def rect(self, value: object, path: PathKey) -> tuple[float, float, float, float] | None:
        nums = self.numbers(value, path, 4, _METRES, "a rectangle [x0, y0, x1, y1] in metres")
        if nums is None:
            return None
        x0, y0, x1, y1 = (n * 1000.0 for n in nums)
        if x1 <= x0 or y1 <= y0:
            a, b, c, d = nums
            which = " and ".join(
                f"{lo} {n:g} not below {hi} {m:g}"
                for lo, n, hi, m in (("x0", a, "x1", c), ("y0", b, "y1", d))
                if m <= n
            )  # it said only "a list of 4"
            self.error(path, f"[{a:g}, {b:g}, {c:g}, {d:g}]: {which}", "x0 < x1 and y0 < y1")
            return None
        return (x0, y0, x1, y1)

    def shape(self, value: object, path: PathKey, extra: tuple[str, ...] = ()) -> Polygon | None:
        """``{rect: [...]}`` or ``{polygon: [...]}``, with an optional ``name`` (and the
        ``extra`` keys the caller reads itself)."""
        spec = self.mapping(value, path, ("name", "rect", "polygon", *extra))
        if spec is None:
            return None
        if ("rect" in spec) == ("polygon" in spec):
            self.error(path, "neither or both of rect/polygon", "exactly one of rect, polygon")
            return None
        if "rect" in spec:
            r = self.rect(spec["rect"], (*path, "rect"))
            if r is None:
                return None
            x0, y0, x1, y1 = r
            return ((x0, y0), (x1, y0), (x1, y1), (x0, y1))
        return self.polygon(spec["polygon"], (*path, "polygon"))

    def items(self, value: object, path: PathKey) -> list[Any]:
        """A list of the world's (rooms, obstacles, walls...), none read past
        :data:`MAX_LIST_ITEMS` (one error for the list, not one per item)."""
        if value is None:
            return []
        if not isinstance(value, list):
            self.error(path, _show(value), "a list")
            return []
        if len(value) > MAX_LIST_ITEMS:
            allowed = f"at most {MAX_LIST_ITEMS:,} (a whole furnished home needs a few hundred)"
            self.error(path, f"{len(value):,} items", allowed)
            return []
        return value


def _first_crossing(poly: Polygon) -> tuple[int, int] | None:
    """The first two sides of ``poly`` that meet other than at the corner they share (side
    ``i`` from point ``i`` to ``i + 1``; the first: the least ``(i, j)``), or None for a
    simple polygon. A world's polygon is drawn by hand: points out of order make a bow tie,
    whose floor and walls are not what its author meant (which side of a crossed side is
    inside?).

    Only sides that share a cell of a grid (cells about a side long) are tested against each
    other: every pair was tested, and a floor plan of 10,000 points (200 KB) took 37 s to
    load; a side meets another only where their boxes overlap, in a cell both are in."""
    n = len(poly)
    if n < 4:
        return None
    sides = [(poly[i], poly[(i + 1) % n]) for i in range(n)]
    xs = [x for x, _ in poly]
    ys = [y for _, y in poly]
    extent = max(max(xs) - min(xs), max(ys) - min(ys), 1e-9)
    cell = max(extent / max(1.0, n**0.5), sum(math.dist(a, b) for a, b in sides) / n, 1e-9)
    cells: dict[tuple[int, int], list[int]] = {}
    for i, (a, b) in enumerate(sides):
        for cx in range(int((min(a[0], b[0])) // cell), int((max(a[0], b[0])) // cell) + 1):
            for cy in range(int((min(a[1], b[1])) // cell), int((max(a[1], b[1])) // cell) + 1):
                cells.setdefault((cx, cy), []).append(i)
    crossings: list[tuple[int, int]] = []
    tested: set[tuple[int, int]] = set()
    for members in cells.values():
        for k, first in enumerate(members):
            for second in members[k + 1 :]:
                pair = (first, second) if first < second else (second, first)
                if pair in tested or pair[1] == pair[0] + 1 or pair == (0, n - 1):
                    continue  # tested in another cell, or neighbours (they share a corner)
                tested.add(pair)
                if segments_meet(*sides[pair[0]], *sides[pair[1]]):
                    crossings.append(pair)
    return min(crossings) if crossings else None


def _repeated_corner(poly: Polygon) -> tuple[int, str] | None:
    """The first corner of ``poly`` that repeats the one before it, and what it repeats
    (None: none does). The last corner repeating the first is a polygon closed by hand,
    which closes by itself: said so. Such a side of no length was said as "sides cross"."""
    n = len(poly)
    for i in range(1, n):
        if poly[i] == poly[i - 1]:
            return i, f"the corner before it ([{i - 1}])"
    if poly[0] == poly[-1]:
        return n - 1, "the first corner ([0]): a polygon closes by itself, leave the last out"
    return None


def _collinear(poly: Polygon) -> bool:
    """Every corner of ``poly`` on the line through its first two (within a square
    millimetre of area): a polygon of no floor, whose sides overlap."""
    (ax, ay), (bx, by) = poly[0], poly[1]
    return all(abs((bx - ax) * (y - ay) - (by - ay) * (x - ax)) < 2.0 for x, y in poly[2:])


def _side(poly: Polygon, i: int) -> str:
    """Side ``i`` of ``poly`` as the file writes it: ``[x, y]-[x, y]`` in metres."""
    a, b = poly[i], poly[(i + 1) % len(poly)]
    return f"[{a[0] / 1000:g}, {a[1] / 1000:g}]-[{b[0] / 1000:g}, {b[1] / 1000:g}]"


def _area(poly: Polygon) -> float:
    return 0.5 * sum(
        poly[i][0] * poly[(i + 1) % len(poly)][1] - poly[(i + 1) % len(poly)][0] * poly[i][1]
        for i in range(len(poly))
    )


#: How many items one list of a world file (``rooms``, ``obstacles``, ``walls``, ``drops``,
#: ``dirt``, ``events``...) may hold (decided). A furnished home is a few hundred shapes (the
#: shipped dining room's chair legs are 30); each obstacle costs the floor map three capsule
#: fills, so a generated file of 12,000 took 13 s to load (the work is linear in the count,
#: nothing to index: the cost is the count). A polygon's points are not items: a floor plan
#: of 10,000 points is read.
MAX_LIST_ITEMS = 1000
#: Coordinates in a world file: metres, within a kilometre of the origin.
_METRES = (-1000.0, 1000.0, "m")
_TOP_KEYS = (
    "name", "description", "rooms", "walls", "obstacles", "drops", "dirt", "virtual_walls",
    "lighthouses", "dock", "robot", "events", "areas",
)  # fmt: skip
_DOCK_KEYS = (
    "at", "facing", "red", "green", "buoy_range", "force_field", "contact_tolerance",
    "angle_tolerance", "family", "plate_width",
)  # fmt: skip


def _angle_range(c: _Checker, value: object, path: PathKey) -> tuple[float, float] | None:
    beam = DOCK_BEAM_LIMIT
    pair = c.numbers(value, path, 2, (beam.lo, beam.hi, beam.unit),
                     f"[from, to] in degrees, {beam.lo:g}..{beam.hi:g}, from < to")  # fmt: skip
    if pair is None:
        return None
    lo, hi = pair
    if lo >= hi:
        c.error(path, _show(value), "[from, to] with from < to")
        return None
    return (lo * beam.scale, hi * beam.scale)


def _dock(c: _Checker, value: object) -> DockSpec | None:
    path: PathKey = ("dock",)
    spec = c.record(value, path, _DOCK_KEYS, ("at", "facing"))
    if spec is None:
        return None
    at = c.point(spec["at"], (*path, "at"))
    facing = c.number(spec["facing"], (*path, "facing"), -360, 360, "deg")
    kwargs: dict[str, Any] = {}
    for key in ("red", "green"):
        if key in spec:
            kwargs[key] = _angle_range(c, spec[key], (*path, key))
    for key, limit in DOCK_LIMITS.items():
        if key in spec:
            n = c.number(spec[key], (*path, key), limit.lo, limit.hi, limit.unit)
            kwargs[key] = None if n is None else n * limit.scale
    if "family" in spec:
        kwargs["family"] = c.choice(spec["family"], (*path, "family"), DOCK_FAMILIES)
    if at is None or facing is None or any(v is None for v in kwargs.values()):
        return None
    return DockSpec(at[0], at[1], math.radians(facing), **kwargs)


def _pose(c: _Checker, value: object, path: PathKey) -> Pose | None:
    spec = c.record(value, path, ("at", "heading"), ("at",))
    if spec is None:
        return None
    at = c.point(spec["at"], (*path, "at"))
    heading = c.number(spec.get("heading", 0), (*path, "heading"), -360, 360, "deg")
    if at is None or heading is None:
        return None
    return Pose(at[0], at[1], wrap_angle(math.radians(heading)))


def _start_region(c: _Checker, value: object, path: PathKey) -> StartRegion | None:
    spec = c.mapping(value, path, ("near_dock", "rect", "area", "heading"))
    if spec is None:
        return None
    given = [key for key in ("near_dock", "rect", "area") if key in spec]
    if len(given) != 1:
        c.error(path, f"{' and '.join(given) or 'none'} of near_dock/rect/area",
                "exactly one of near_dock, rect, area")  # fmt: skip
        return None
    near: float | None = None
    rect: tuple[float, float, float, float] | None = None
    heading: tuple[float, float] | None = None
    area: str | None = None
    if "near_dock" in spec:
        n = c.number(spec["near_dock"], (*path, "near_dock"), *NEAR_DOCK_RANGE_M, "m")
        if n is None:
            return None
        near = n * 1000.0
    elif "area" in spec:
        if not isinstance(spec["area"], str):
            c.error((*path, "area"), _show(spec["area"]), "the name of one of the world's areas")
            return None
        area = spec["area"]
    else:
        rect = c.rect(spec["rect"], (*path, "rect"))
        if rect is None:
            return None
    if "heading" in spec and spec["heading"] != "any":
        pair = c.numbers(spec["heading"], (*path, "heading"), 2, (-360, 360, "deg"),
                         "'any' or [from, to] in degrees")  # fmt: skip
        if pair is None:
            return None
        heading = (math.radians(pair[0]), math.radians(pair[1]))
    return StartRegion(near, rect, heading, area)


def _event(c: _Checker, value: object, path: PathKey) -> TimelineEvent | None:
    keys = ("at", "kind", "side", "duration", "button", "motor")
    spec = c.record(value, path, keys, ("at", "kind"))
    if spec is None:
        return None
    at = c.number(spec["at"], (*path, "at"), 0, 1e6, "s")
    kind = c.choice(spec["kind"], (*path, "kind"), EVENT_KINDS)
    if kind == "press":
        return _press(c, spec, path, at)
    for key, own_kind in (("button", "press"), ("motor", "overcurrent")):
        if key in spec and kind != own_kind:
            c.error((*path, key), f"a {key} for a {kind}", f"{key} only with kind: {own_kind}")
    motor: str | None = ""
    if kind == "overcurrent":
        motors = tuple(OVERCURRENT_BITS)
        if "motor" not in spec:
            c.error(path, "no 'motor'", f"kind: overcurrent with a motor: {', '.join(motors)}")
            return None
        motor = c.choice(spec["motor"], (*path, "motor"), motors)
    duration = c.number(spec.get("duration", 0.5), (*path, "duration"), SLOT_SECONDS, 1e6, "s")
    side = c.choice(spec.get("side", "both"), (*path, "side"), SIDES)
    if at is None or kind is None or duration is None or side is None or motor is None:
        return None
    return TimelineEvent(at, kind, duration, side, motor=motor)


def _press(
    c: _Checker, spec: dict[str, Any], path: PathKey, at: float | None
) -> TimelineEvent | None:
    """A ``press`` event: a button and a time. It lasts the spec's 1/6 s, as a press by
    Buttons (165) does, so a ``duration`` (or a bumper ``side``) is refused rather than
    ignored: the robot's packet 18 shows a press that long whatever the finger did."""
    only = "at, kind: press, button (a press lasts the spec's 1/6 s)"
    for key in ("duration", "side"):
        if key in spec:
            c.error((*path, key), f"a {key} for a press", only)
    if "button" not in spec:
        c.error(path, "no 'button'", f"kind: press with a button: {', '.join(BUTTON_NAMES)}")
        return None
    button = c.choice(spec["button"], (*path, "button"), BUTTON_NAMES)
    if at is None or button is None:
        return None
    return TimelineEvent(at, "press", PRESS_SECONDS, button=button)


def _areas(c: _Checker, value: object) -> tuple[AreaSpec, ...]:
    """``areas: [{name: kitchen, rect: [...]}, {name: hall, polygon: [...]}]``: named, each
    name once."""
    areas: list[AreaSpec] = []
    for i, a in enumerate(c.items(value, ("areas",))):
        path: PathKey = ("areas", i)
        shape = c.shape(a, path)
        name = a.get("name") if isinstance(a, dict) else None
        if isinstance(a, dict) and not isinstance(name, str):
            c.error((*path, "name"), _show(name), "a name for the area (a string)")
            continue
        if name in {x.name for x in areas}:
            c.error((*path, "name"), repr(name), "each area's name once")
            continue
        if shape is not None and isinstance(name, str):
            areas.append(AreaSpec(name, shape))
    return tuple(areas)


_REFUSED_TAG = "the tag {tag!r} is not allowed in a world"
#: What an empty world file (nothing, or only comments) is said to be, and what it needs.
_EMPTY = (
    "an empty file (no YAML in it, at most comments)",
    "a world: at least rooms, a list of floor polygons in metres, e.g. "
    "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]] (roomba-bt worlds empty-room prints a whole one)",
)


def _compose_world(text: str) -> yaml.Node | None:
    """The world's root node by libyaml's parser where installed (the apartment in 2.5 ms
    instead of 22 ms: every simulated run and evaluation worker reads its world once); a text
    it refuses is read again by PyYAML's own, so the syntax message a user sees is the same
    whether libyaml is installed or not."""
    try:
        return yamlsource.compose(text)
    except yaml.YAMLError:
        return yamlsource.compose(text, yamlsource.PURE_LOADER)


def parse_world(text: str, source: str = "<world>") -> World:
    """Validate a world given as YAML text; :class:`WorldError` lists every problem."""
    try:
        root = _compose_world(text)
        if root is None:  # it said "roomba-bt: FILE: (document): found nothing", no place
            raise WorldError([WorldProblem(source, 1, 1, "(document)", *_EMPTY)])
        if not yamlsource.holds_some_of(root, _TOP_KEYS):
            line, col = yamlsource.position(root)
            found = yamlsource.not_a_file_of("this file", "world", _TOP_KEYS)
            raise WorldError([WorldProblem(source, line, col, "", found, "")])
        duplicates = yamlsource.every_duplicate_key(root)
        data, marks = yamlsource.to_data(root, _REFUSED_TAG, skip_duplicates=True)
    except yamlsource.Refused as exc:  # each alias, tag or control character, at once
        every = exc.every()[:MAX_FOUND]
        raise WorldError([_yaml_problem(each, text, source) for each in every]) from None
    except yaml.YAMLError as exc:
        raise WorldError([_yaml_problem(exc, text, source)]) from None
    c = _Checker(source, marks)
    try:
        for dup in duplicates:  # every one, and then the world's other problems
            line, col = yamlsource.position(dup.node)
            first = yamlsource.position(dup.first)[0]
            c.add(WorldProblem(source, line, col, _dotted(dup.path or ()),
                               f"the key {str(dup.key)!r} again (first at line {first})",
                               "each key once"))  # fmt: skip
        return _build_world(c, data, source)
    except _Stopped:
        raise WorldError(c.problems) from None


def _yaml_problem(exc: yaml.YAMLError, text: str, source: str) -> WorldProblem:
    """A YAML error or a refusal worded as a mission's (mission/source.py): PyYAML's
    sentence after the position."""
    line, col = yamlsource.error_position(exc) or (0, 0)
    problem = getattr(exc, "problem", None) or getattr(exc, "context", None) or str(exc)
    refused = isinstance(exc, yamlsource.Refused)
    # a refusal (an alias, a tag) is no syntax error: no tab to name, and the hint, which
    # splits the whole text, made a file of 100,000 aliases take hours (as a mission's does)
    tab = "" if refused else yamlsource.tab_hint(text, line, col)
    problem = str(problem) + tab
    kind = "" if refused else "YAML syntax error"
    cause = None if refused or tab else yamlsource.lookalike_cause(text, line, col)
    if cause is not None:  # a typographic quote, a no-break space: named at its place
        problem = f"{cause[2]} ({problem} at {line}:{col})"
        line, col = cause[0], cause[1]
    return WorldProblem(source, line, col, kind, problem, "")


def _build_world(c: _Checker, data: object, source: str) -> World:
    """The whole world file, checked part by part in the file's order; every problem is
    collected before :class:`WorldError` is raised."""
    top = c.mapping(data, (), _TOP_KEYS, ("rooms",))
    if top is None:
        raise WorldError(c.problems)
    name = _text(c, top, "name", pathlib.Path(source).stem)
    description = _text(c, top, "description", "")
    rooms = [_room(c, r, ("rooms", i)) for i, r in enumerate(c.items(top.get("rooms"), ("rooms",)))]
    if top.get("rooms") == []:
        c.error(("rooms",), "no room", "at least one room polygon")
    walls = _walls(c, top.get("walls"))
    obstacles = [
        c.shape(o, ("obstacles", i))
        for i, o in enumerate(c.items(top.get("obstacles"), ("obstacles",)))
    ]
    drops = [c.shape(o, ("drops", i)) for i, o in enumerate(c.items(top.get("drops"), ("drops",)))]
    dirt = _dirt(c, top.get("dirt"))
    vwalls = _virtual_walls(c, top.get("virtual_walls"))
    lighthouses = _lighthouses(c, top.get("lighthouses"))
    dock = _dock(c, top["dock"]) if "dock" in top else None
    start, region, battery = _robot(c, top)
    events = [
        e for i, v in enumerate(c.items(top.get("events"), ("events",)))
        if (e := _event(c, v, ("events", i))) is not None
    ]  # fmt: skip
    areas = _areas(c, top.get("areas"))
    names = [a.name for a in areas]
    if region is not None and region.area is not None and region.area not in names:
        allowed = f"one of the world's areas ({', '.join(names) or 'none'})"
        c.error(("robot", "start_region", "area"), repr(region.area), allowed)
    # Where the rooms stand, what else is wrong is checked for its place too (every problem
    # at once: a shape outside every room was said only once the rest was mended); a check
    # that leans on a part in error is left for the next reading (no error of its own).
    broken = {_leans_on(p.field) for p in c.problems}
    room_polys = tuple(r for r in rooms if r is not None)
    if c.problems and ("rooms" in broken or "(document)" in broken or not room_polys):
        raise WorldError(c.problems)
    world = World(
        name=name,
        rooms=room_polys,
        start=start if start is not None else _default_start(dock, room_polys),
        walls=walls,
        obstacles=tuple(o for o in obstacles if o is not None),
        drops=tuple(d for d in drops if d is not None),
        dirt=dirt,
        virtual_walls=vwalls,
        lighthouses=lighthouses,
        dock=dock,
        start_region=region,
        events=tuple(sorted(events, key=lambda e: e.time)),
        battery=battery,
        source=source,
        description=description,
        areas=areas,
    )
    _check_placement(c, world, start is not None, broken)
    if c.problems:
        raise WorldError(c.problems)
    return replace(world, warnings=tuple(c.warnings)) if c.warnings else world


def _leans_on(field: str) -> str:
    """The part of the world a problem at ``field`` leaves in doubt: its top-level key, but
    ``robot.battery`` alone for the charge (the start does not lean on it: a world with a
    start off the floor and ``battery: 1.5`` said the battery only, and the start once
    that was mended)."""
    top = re.split(r"[.\[]", field, maxsplit=1)[0]
    return "robot.battery" if field.startswith("robot.battery") else top


def _room(c: _Checker, value: object, path: PathKey) -> Polygon | None:
    """A room: a polygon ``[[x, y], ...]``, or written as the other shapes are,
    ``{rect: [...]}`` / ``{polygon: [...]}`` (a stranger's world wrote a room as a rect); one
    too wide for a room is said (:func:`_check_room_span`)."""
    room = c.shape(value, path) if isinstance(value, dict) else c.polygon(value, path)
    if room is not None:
        _check_room_span(c, room, path)
    return room


#: The widest room a world may hold (m): a home's room is a few metres across, and one of
#: hundreds is a room written in centimetres (``rect: [0, 0, 500, 400]``), which otherwise
#: loads as a 500 m hall that every obstacle written in metres fits into. 150, not less: a
#: test's open floor of 100 x 100 m (no wall in reach) is meant, and a room under 1.5 m
#: written in centimetres is rare.
ROOM_SPAN_M = 150.0


def _check_room_span(c: _Checker, room: Polygon, path: PathKey) -> None:
    """The room at most :data:`ROOM_SPAN_M` across; a wider one is asked whether it was
    written in centimetres (the shapes outside every room are asked the same, but a room in
    centimetres holds them all)."""
    width = (max(x for x, _ in room) - min(x for x, _ in room)) / 1000.0
    depth = (max(y for _, y in room) - min(y for _, y in room)) / 1000.0
    if max(width, depth) > ROOM_SPAN_M:
        c.error(
            path,
            f"a room {width:g} x {depth:g} m across (did you write centimetres? "
            f"{width:g} cm is {width / 100:g} m)",
            f"a room at most {ROOM_SPAN_M:g} m across, in metres",
        )


def _overlaps(shape: Polygon, rooms: tuple[Polygon, ...]) -> bool:
    """Whether ``shape`` has some part inside a room: a corner of one inside the other, or
    two sides that meet."""
    for room in rooms:
        if any(point_in_polygon(x, y, room) for x, y in shape):
            return True
        if any(point_in_polygon(x, y, shape) for x, y in room):
            return True
        if any(segments_meet(a, b, p, q) for a, b in _sides(shape) for p, q in _sides(room)):
            return True
    return False


def _sides(poly: Polygon) -> list[tuple[Point, Point]]:
    return [(poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))]


def _check_inside_rooms(c: _Checker, world: World) -> None:
    """Obstacles, drops, dirt and areas lie (at least partly) on a room's floor: one wholly
    outside does nothing in the simulator, and is a slip (centimetres written for metres, a
    sign lost); a drop may stick out of a room (stairs drawn past the wall) and is fine."""
    kinds: tuple[tuple[str, tuple[Polygon, ...]], ...] = (
        ("obstacles", world.obstacles),
        ("drops", world.drops),
        ("dirt", tuple(d.area for d in world.dirt)),
        ("areas", tuple(a.polygon for a in world.areas)),
    )
    for key, shapes in kinds:
        for i, shape in enumerate(shapes):
            if not _overlaps(shape, world.rooms):
                xs, ys = [p[0] / 1000 for p in shape], [p[1] / 1000 for p in shape]
                c.error(
                    (key, i),
                    f"a shape wholly outside every room (x {min(xs):g}..{max(xs):g}, "
                    f"y {min(ys):g}..{max(ys):g} m)",
                    "a shape on a room's floor, in metres",
                )


def _text(c: _Checker, top: dict[str, Any], key: str, default: str) -> str:
    """A top-level string (``name``, ``description``); a non-string is reported."""
    value = top.get(key, default)
    if isinstance(value, str):
        return value
    c.error((key,), _show(value), "a string")
    return str(value) if key == "name" else default


def _walls(c: _Checker, value: object) -> tuple[Segment, ...]:
    """``walls: [[x0, y0, x1, y1], ...]`` in metres -> segments in mm."""
    walls: list[Segment] = []
    for i, w in enumerate(c.items(value, ("walls",))):
        r = c.numbers(w, ("walls", i), 4, _METRES, "a segment [x0, y0, x1, y1] in metres")
        if r is None:
            continue
        x0, y0, x1, y1 = (n * 1000.0 for n in r)
        if not _no_length(c, ("walls", i), (x0, y0), (x1, y1), "wall"):
            walls.append((x0, y0, x1, y1))
    return tuple(walls)


def _no_length(c: _Checker, path: PathKey, a: Point, b: Point, what: str) -> bool:
    """Whether the segment from ``a`` to ``b`` (mm) has no length, said at ``path``: a wall
    of no length stops nothing and a virtual wall of none shows no beam, yet both loaded
    without a word."""
    if a != b:
        return False
    at = f"[{a[0] / 1000:g}, {a[1] / 1000:g}]"
    c.error(path, f"a {what} of no length (both ends at {at})",
            f"a {what} whose two ends differ")  # fmt: skip
    return True


def _dirt(c: _Checker, value: object) -> tuple[DirtSpec, ...]:
    """``dirt: [{rect: [...], level: 1..255}, ...]``: patches the dirt detector sees."""
    dirt: list[DirtSpec] = []
    for i, patch in enumerate(c.items(value, ("dirt",))):
        area = c.shape(patch, ("dirt", i), extra=("level",))
        if not isinstance(patch, dict):
            continue
        dirt_level = patch.get("level")
        if type(dirt_level) is not int or not 1 <= dirt_level <= 255:
            c.error(("dirt", i, "level"), _show(dirt_level), "an integer dirt-detect level 1..255")
        elif area is not None:
            dirt.append(DirtSpec(area, dirt_level))
    return tuple(dirt)


def _virtual_walls(c: _Checker, value: object) -> tuple[VirtualWallSpec, ...]:
    """``virtual_walls: [{from: [x, y], to: [x, y], width: m, halo: m}, ...]``."""
    vwalls: list[VirtualWallSpec] = []
    keys = ("name", "from", "to", "halo", "width")
    for path, spec in c.records(value, "virtual_walls", keys, ("from", "to")):
        a = c.point(spec["from"], (*path, "from"))
        b = c.point(spec["to"], (*path, "to"))
        halo = c.number(spec.get("halo", 0.0), (*path, "halo"), 0.0, 2.0, "m")
        width = c.number(spec.get("width", 0.12), (*path, "width"), 0.02, 1.0, "m")
        if a and b and _no_length(c, (*path, "to"), a, b, "virtual wall"):
            continue
        if a and b and halo is not None and width is not None:
            vwalls.append(VirtualWallSpec(a[0], a[1], b[0], b[1], width * 500.0, halo * 1000.0))
    return tuple(vwalls)


def _lighthouses(c: _Checker, value: object) -> tuple[LighthouseSpec, ...]:
    """``lighthouses: [{id: 1..10, at: [x, y], heading: deg, fence: m, halo: m}, ...]``."""
    lighthouses: list[LighthouseSpec] = []
    keys = ("id", "at", "heading", "fence", "halo")
    for path, spec in c.records(value, "lighthouses", keys, ("id", "at")):
        lid = spec["id"]
        if isinstance(lid, bool) or not isinstance(lid, int) or not 1 <= lid <= 10:
            c.error((*path, "id"), _show(lid), "an integer lighthouse id 1..10")
            continue
        at = c.point(spec["at"], (*path, "at"))
        heading = c.number(spec.get("heading", 0), (*path, "heading"), -360, 360, "deg")
        fence = c.number(spec.get("fence", 2.0), (*path, "fence"), 0.1, 10.0, "m")
        halo = c.number(spec.get("halo", 0.4), (*path, "halo"), 0.0, 2.0, "m")
        if at and heading is not None and fence is not None and halo is not None:
            lighthouses.append(
                LighthouseSpec(lid, at[0], at[1], math.radians(heading), fence * 1000.0,
                               halo * 1000.0)
            )  # fmt: skip
    return tuple(lighthouses)


def _robot(c: _Checker, top: dict[str, Any]) -> tuple[Pose | None, StartRegion | None, float]:
    """``robot: {start | start_region, battery}``: the start pose or region and the charge."""
    start: Pose | None = None
    region: StartRegion | None = None
    battery = 0.8
    if "robot" not in top:
        return start, region, battery
    robot = c.mapping(top["robot"], ("robot",), ("start", "start_region", "battery"))
    if robot is None:
        return start, region, battery
    if "start" in robot:
        start = _pose(c, robot["start"], ("robot", "start"))
    if "start_region" in robot:
        region = _start_region(c, robot["start_region"], ("robot", "start_region"))
        if region is not None and region.near_dock is not None and "dock" not in top:
            c.error(("robot", "start_region", "near_dock"), "no dock in this world",
                    "near_dock only in a world with a dock")  # fmt: skip
    if "battery" in robot:
        given = robot["battery"]
        level: float | None = None
        percent = _percent(given)
        if percent is not None and 0.0 <= percent <= 1.0:  # 80%, as --battery takes it
            level = percent
        else:
            level = c.number(given, ("robot", "battery"), 0.0, 1.0, "(or a percent, 0%..100%)")
        if level == 0.0:  # as --battery 0: the robot would answer nothing, a lost connection
            c.error(("robot", "battery"), f"{_show(given)}: an empty battery switches the "
                    "simulated robot off, and it would answer nothing",
                    "a charge above 0, up to 1 (0.05, 5%)")  # fmt: skip
            level = None
        battery = 0.8 if level is None else level
    return start, region, battery


def _percent(value: object) -> float | None:
    """``"80%"`` -> 0.8; None for anything else."""
    if isinstance(value, str) and value.strip().endswith("%"):
        with contextlib.suppress(ValueError):
            number = float(value.strip()[:-1]) / 100.0
            return number if math.isfinite(number) else None
    return None


def _default_start(dock: DockSpec | None, rooms: tuple[Polygon, ...]) -> Pose:
    """No start pose given: 0.8 m out from the docked pose, else the first room's middle."""
    if dock is not None:
        d = dock.docked_pose
        return Pose(
            d.x + 800.0 * math.cos(dock.facing), d.y + 800.0 * math.sin(dock.facing), d.theta
        )
    xs = [p[0] for p in rooms[0]]
    ys = [p[1] for p in rooms[0]]
    return Pose(sum(xs) / len(xs), sum(ys) / len(ys), 0.0)


def _faces_floor(world: World, dock: DockSpec) -> bool:
    """The floor just in front of the dock's plate (10 mm out along ``facing``)."""
    return world.on_floor(dock.x + 10 * math.cos(dock.facing), dock.y + 10 * math.sin(dock.facing))


def _docks_well(world: World, dock: DockSpec) -> bool:
    """The dock faces the floor and a docked robot fits in front of it, not over a drop."""
    docked = dock.docked_pose
    return _faces_floor(world, dock) and world.pose_is_free(docked)


def _facings_that_dock(world: World, dock: DockSpec) -> list[str]:
    """The facings of the four walls' directions (0, 90, 180, -90 deg) at which the same
    dock, at the same point, would face the floor with room for the docked robot: what
    the message offers when ``facing`` is the mistake. The plate is part of the world's
    walls, so each is judged in a world with the plate turned."""
    fitting = []
    for degrees in (0, 90, 180, -90):
        turned = replace(dock, facing=math.radians(degrees))
        if _docks_well(replace(world, dock=turned), turned):
            fitting.append(f"{degrees}")
    return fitting


def _check_dock(c: _Checker, world: World, dock: DockSpec) -> None:
    """The dock faces the floor and its docked robot fits there, as a start pose must: a
    docked pose inside a wall validated and the dock mission then failed after 10 minutes.
    When another facing at the same point would do, the mistake is said at ``facing``
    (with the facings that fit), else at ``at``."""
    docked = dock.docked_pose
    if _docks_well(world, dock):
        return
    facings = _facings_that_dock(world, dock)
    said = f"facing {math.degrees(dock.facing):g}"
    into_room = (
        f"a facing (deg) that turns the dock's front into the room: {' or '.join(facings)} here"
        if facings
        else "a point inside a room, against a wall, facing into the room"
    )
    field = "facing" if facings else "at"
    if not _faces_floor(world, dock):
        found = f"a dock {said}, out of the room" if facings else "a dock off the floor"
        c.error(("dock", field), found, into_room)
    elif world.over_drop(docked.x, docked.y):
        c.error(("dock", "at"), "a dock whose docked robot stands over a drop",
                "floor in front of the dock (a docked robot's centre is 0.17 m out)")  # fmt: skip
    else:
        c.error(
            ("dock", field),
            f"a dock ({said}) whose docked robot, at ({docked.x / 1000:.2f}, "
            f"{docked.y / 1000:.2f}) m, does not fit there (0.17 m from the plate, it reaches "
            "into a wall or an obstacle or off the floor)",
            into_room,
        )


def _check_placement(
    c: _Checker, world: World, start_given: bool, broken: set[str] | frozenset[str] = frozenset()
) -> None:
    """The dock stands on the floor, the robot fits where it starts and its start region
    has room for it. A start not given is said to be the default one, where it comes from
    (a dock off the floor puts it off the floor too: that is said once, at the dock).
    ``broken``: the parts already in error (:func:`_leans_on`); the start is not judged
    beside a robot, dock or areas in error (it leans on them), but it is beside a battery
    in error."""
    _check_inside_rooms(c, world)
    dock = world.dock
    dock_off = dock is not None and not _faces_floor(world, dock)
    if dock is not None:
        _check_dock(c, world, dock)
    if broken & {"robot", "dock", "areas"}:
        return
    if not world.pose_is_free(world.start) and not (dock_off and not start_given):
        where = f"({world.start.x / 1000:.2f}, {world.start.y / 1000:.2f}) m"
        fits = (
            "a pose on the floor at least 0.17 m from every wall and obstacle (touching one "
            "fits: the docked pose), not over a drop"
        )
        if start_given:
            c.error(("robot", "start"), f"a start pose {where} where the robot does not fit",
                    fits)  # fmt: skip
        else:
            origin = "0.8 m out from the dock" if dock is not None else "the first room's middle"
            c.error(
                ("dock",) if dock is not None else ("rooms",),
                f"no robot.start, and the default start pose {where} ({origin}) is where the "
                "robot does not fit",
                f"a robot.start {{at: [x, y], heading: degrees}} at {fits}",
            )
    elif start_given:
        _warn_if_over_a_drop(c, world)
    if world.start_region is not None:
        try:
            world.sample_start(0)
        except WorldError:
            c.error(("robot", "start_region"), "a region with no free pose for the robot",
                    "a region on the floor with room for the robot (340 mm across)")  # fmt: skip


def _warn_if_over_a_drop(c: _Checker, world: World) -> None:
    """A given start whose centre is clear of the drops but whose body is not (a tyre or a
    cliff sensor past the edge: the robot falls, or reads a cliff on its first frame) is
    warned of, by how much; a drawn start keeps the body 20 mm off. A warning, not an error:
    a test may put the robot at an edge on purpose."""
    index, distance = world.nearest_drop(world.start)
    if distance >= ROBOT_RADIUS_MM:
        return
    where = f"({world.start.x / 1000:.3f}, {world.start.y / 1000:.3f}) m"
    c.warn(("robot", "start"), f"a start pose {where} whose body reaches "
           f"{(ROBOT_RADIUS_MM - distance) / 1000:.3f} m over drops[{index}] (its edge "
           f"{distance / 1000:.3f} m from the centre, the body's radius "
           f"{ROBOT_RADIUS_MM / 1000:.3f} m): the robot may fall or read a cliff at once",
           f"a start with the whole body off every drop ({(ROBOT_RADIUS_MM + 20) / 1000:.2f} m "
           "from its edge, as a drawn start keeps it), or this on purpose (a test at an "
           "edge)")  # fmt: skip


def shipped_worlds() -> tuple[str, ...]:
    """Names of the worlds shipped in ``worlds/``."""
    return tuple(sorted(p.stem for p in WORLDS_DIR.glob("*.yaml")))


def world_folders() -> tuple[pathlib.Path, ...]:
    """Where a world's name is looked for, in order: each folder ``ROOMBA_BT_WORLDS`` names
    (the user's own worlds; separated by ``:``, ``;`` on Windows; an empty entry skipped),
    then the shipped worlds' folder, so a world of one's own may take a shipped world's
    name. Read when a name is looked up, not at import. :class:`WorldError` naming the
    variable and the folder when one is missing or unreadable: the variable once replaced
    the shipped folder, and a wrong one left no world at all, its error ending in "one of"
    and nothing, and ``roomba-bt worlds`` listing nothing with exit 0."""
    folders = []
    for entry in os.environ.get(WORLDS_VARIABLE, "").split(os.pathsep):
        if not entry.strip():
            continue
        problem = _not_a_readable_folder(pathlib.Path(entry))
        if problem is not None:
            raise WorldError([WorldProblem(
                WORLDS_VARIABLE, 0, 0, "",
                f"{entry!r}: {problem}; it names folders of your own worlds, looked in before "
                f"the shipped ones: give existing folders, or unset it", "",
            )])  # fmt: skip
        folders.append(pathlib.Path(entry))
    return (*folders, WORLDS_DIR)


def _not_a_readable_folder(folder: pathlib.Path) -> str | None:
    """Why ``folder`` holds no worlds one can read (None: it is a folder that can be)."""
    try:
        with os.scandir(folder):
            return None
    except FileNotFoundError:
        return "no such folder"
    except NotADirectoryError:
        return "a file, not a folder"
    except OSError as exc:
        return f"an unreadable folder ({exc.strerror or exc})"


def world_files() -> dict[str, pathlib.Path]:
    """Every world a name finds, name -> file, sorted by name: a name in two folders is the
    first folder's (:func:`world_folders`)."""
    found: dict[str, pathlib.Path] = {}
    for folder in world_folders():
        for path in sorted(folder.glob("*.yaml")):
            found.setdefault(path.stem, path)
    return dict(sorted(found.items()))


def named_world(name: str) -> pathlib.Path | None:
    """The file a world's name finds in :func:`world_folders` (None: none)."""
    if "/" in name:
        return None
    for folder in world_folders():
        path = folder / f"{name}.yaml"
        if path.is_file():
            return path
    return None


def load_world(path_or_name: str | pathlib.Path) -> World:
    """A world file by path, or a world by name (``"empty-room"``): a shipped one, or one of
    the user's in ``ROOMBA_BT_WORLDS``'s folders (:func:`world_folders`)."""
    return parse_world(*world_text(path_or_name))


def _no_such_world(path: pathlib.Path, given: str) -> WorldProblem:
    """What ``given`` is instead of a world file or a world's name, with the names there are
    and the closest of them."""
    own = len(world_folders()) > 1
    found = (
        "a directory"
        if path.is_dir()
        else "a device or a pipe, not a file"
        if path.exists()
        else broken_link(path)
        if path.is_symlink()
        else f"no such file or world in {WORLDS_VARIABLE}'s folders or the shipped ones"
        if own
        else "no such file or shipped world"
    )
    names = list(world_files())
    close = difflib.get_close_matches(given, names, n=1)
    if close and not path.exists():
        found += f" (did you mean {close[0]!r}?)"
    return WorldProblem(given, 0, 0, "world", found, f"a YAML file or one of {', '.join(names)}")


def world_text(path_or_name: str | pathlib.Path) -> tuple[str, str]:
    """The text of a shipped world by name or of a world file by path, and its source (the
    file's path) for :func:`parse_world`; :class:`WorldError` if there is none to read."""
    path = pathlib.Path(path_or_name)
    try:
        is_file = path.is_file()
    except OSError as exc:  # a folder on the way the user cannot enter: stat() itself fails
        raise _unreadable(path, exc) from None
    if not is_file:
        named = named_world(path_or_name) if isinstance(path_or_name, str) else None
        if named is None:
            raise WorldError([_no_such_world(path, str(path_or_name))])
        path = named
    try:
        text = yamlsource.read_text(path)
    except yamlsource.FileTooLarge as exc:
        raise WorldError(
            [WorldProblem(str(path), 0, 0, "world", f"a file of {exc}", "a YAML file up to 1 MiB")]
        ) from None
    except UnicodeDecodeError as exc:
        line, col = yamlsource.undecodable_position(exc)
        byte = bytes(exc.object)[exc.start]
        # UTF-16 text (Notepad's "Unicode"), a Word file: said as a mission's is ("byte 0xff")
        whole = exc.reason in yamlsource.WHOLE_REASONS
        found = (  # the legacy encoding it reads as, if any, as a mission's says it
            exc.reason.removeprefix("this is ")
            if whole
            else f"byte 0x{byte:02x}, not UTF-8 text ({exc.reason})"
        )
        raise WorldError(
            [WorldProblem(str(path), line, col, "world", found, "a UTF-8 YAML file")]
        ) from None
    except OSError as exc:
        raise _unreadable(path, exc) from None
    return text, str(path)


#: what a world file that is there and cannot be read is said to want, after what the system
#: said of it, as a mission file (``MISSION_WANTED``) or a plugin file says it: it was
#: "found an unreadable file ([Errno 13] Permission denied: 'w.yaml')", Python's words
WORLD_FILE_WANTED = "wanted: a world file (YAML text) this user may read"


def _unreadable(path: pathlib.Path, exc: OSError) -> WorldError:
    """The world file ``path`` the system would not read (``chmod 000``, a folder on the way
    the user cannot enter, a read that fails): what the system said, and what is wanted."""
    said = f"cannot be read: {exc.strerror or exc}; {WORLD_FILE_WANTED}"
    return WorldError([WorldProblem(str(path), 0, 0, "world", said, "")])
