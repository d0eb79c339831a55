"""Swept area: which floor the robot has cleaned, out of the floor it could clean.

A Roomba cleans with its main brush and vacuum (a strip across the body on the axle) and a
side brush at the front right, whose bristles reach a little past the bumper so that wall
edges get cleaned while the robot follows a wall on its right. Seen from above, in the robot's
frame (x forward, y left; mm)::

                 x (front)
             .-'''''''''-.
           /          (o)S       side brush (o): hub (60, -120), 65 mm bristles; S, its
   y <--  | L=====+=====   |       outer edge, 185 mm right of the centre (the body: 170)
          |                |     main brush (=): y -90..+90 on the axle
           \\              /      footprint: the segment L..S, swept along the path
             '-........-'

What a pass cleans is modelled as one segment across the body, swept along the true path: from
the main brush's left end ``L = (0, 90)`` to the side brush's outer edge ``S = (60, -185)`` when
both run (driving straight, that is exactly the strip the brush and the side brush's disc
cover: y -185..+90); ``(0, 90)..(0, -90)`` with the main brush (or the vacuum) alone; the side
brush's diameter ``(60, -55)..(60, -185)`` alone. The main brush or the vacuum run with motor
bits 2 and 1 of Motors (138) or a PWM of 144, the side brush with bit 0; the firmware's own
cycles (Clean, Spot, Max) run all three.

The floor is a grid of :data:`CELL_MM` squares over the world's rooms (and a margin), one byte
a cell, in rows (``index = row * columns + column``). A cell counts when its centre is covered:

* **reachable floor**, once per world and start (cached): on the floor (inside the rooms, not
  under an obstacle, not over a drop), within :data:`REACH_MM` of a place the robot's centre
  can reach from its start. Those places are found by a flood fill over cells where the body
  fits (170 mm from every wall, obstacle and the dock's plate; the cliff sensors' 130 mm from
  a drop; a virtual wall's beam is not crossed);
* **cleaned floor**: the quadrilateral between the footprint's positions at two marks. A mark
  is made when the footprint's ends have moved :data:`MARK_EVERY_MM`, not every step, and the
  quadrilateral is filled a row of cells at a time by slice assignment: coverage costs about
  three microseconds a step. It only reads the pose and the motors: the simulator's bytes are
  the same with or without it.

Coverage is cleaned / reachable, overall and per named area of the world (``areas:`` in a
world file, e.g. the apartment's living room, bedroom and kitchen); :attr:`SweptArea.curve`
samples it every :data:`SAMPLE_EVERY_S` seconds (less often past :data:`MAX_CURVE_SAMPLES`
samples, so that a run of days keeps a curve of bounded size), and
:meth:`SweptArea.longest_idle` says the longest stretch of cleaning time in which no new cell
was cleaned (a stuck robot).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

from roomba_bt.oi.bits import MOTOR_RUN_BITS
from roomba_bt.sim.geometry import Polygon, Segment, polygon_edges
from roomba_bt.sim.world import ROBOT_RADIUS_MM, Pose, World

#: Grid cell side: 2 cm, fine enough that a 90 deg corner's uncleanable triangle shows.
CELL_MM = 20.0
#: The main brush (and the vacuum's inlet behind it): a strip across the body on the axle.
MAIN_BRUSH_WIDTH_MM = 180.0
#: The side brush: its hub at the front right (x forward, y left) and its bristles' radius.
SIDE_BRUSH_HUB_MM = (60.0, -120.0)
SIDE_BRUSH_RADIUS_MM = 65.0
_HALF = MAIN_BRUSH_WIDTH_MM / 2.0
_SX, _SY = SIDE_BRUSH_HUB_MM
#: What a pass cleans, by the motor bits (side 1, vacuum 2, main 4): a segment across the
#: body in the robot's frame (ax, ay, bx, by), swept along the path; None: nothing.
FOOTPRINTS: tuple[tuple[float, float, float, float] | None, ...] = tuple(
    (0.0, _HALF, _SX, _SY - SIDE_BRUSH_RADIUS_MM) if bits & 6 and bits & 1
    else (0.0, _HALF, 0.0, -_HALF) if bits & 6
    else (_SX, _SY + SIDE_BRUSH_RADIUS_MM, _SX, _SY - SIDE_BRUSH_RADIUS_MM) if bits & 1
    else None
    for bits in range(8)
)  # fmt: skip
#: Every motor on: the firmware's Clean, Spot and Max.
ALL_BRUSHES = 7
#: How far from the centre the footprint reaches (194 mm: the side brush's outer edge).
REACH_MM = math.hypot(_SX, _SY - SIDE_BRUSH_RADIUS_MM)
#: The cliff sensors sit 150 mm from the centre, the side ones 60 deg off the heading: driving
#: along a drop's edge the centre stays 150 * sin(60 deg) = 130 mm from it.
CLIFF_KEEPOUT_MM = 130.0
#: Mark the swept floor when the footprint's ends have moved this far: two cells. The strip
#: between two marks is a quadrilateral; along an arc of 0.3 m radius it misses the arc by
#: under a millimetre.
MARK_EVERY_MM = 3 * CELL_MM
#: Sample coverage for :attr:`SweptArea.curve` this often (simulated seconds), at first.
SAMPLE_EVERY_S = 5.0
#: The most samples :attr:`SweptArea.curve` holds: one more, and every other one is dropped
#: (the first, at 0 s, and the newest kept) and the interval doubles (5 s, 10 s, 20 s, ...),
#: so the curve keeps its shape over the whole run in at most this many. 4096 at 5 s is 5.7
#: hours: no evaluation episode or report reaches it. Before, it was sampled for ever: a
#: simulator left running (``run`` keeps a coverage grid on every simulator run) grew by
#: 0.12 MB an hour of simulated time, 20 MB a week.
MAX_CURVE_SAMPLES = 4096

# Cell states of SweptArea.cells.
# 0: not reachable floor
_DIRTY = 1  # reachable, not cleaned yet
_CLEAN = 2  # reachable and cleaned
_ONES = b"\x01" * 4096
_RUN = re.compile(b"\x01+")
_CLEAN_TABLE = bytes(_CLEAN if b == _DIRTY else b for b in range(256))


# ----------------------------------------------------------------------------- the grid


@dataclass(frozen=True)
class Grid:
    """Where the cells are: ``columns`` x ``rows`` cells of ``cell`` mm from ``(x0, y0)``; the
    centre of cell (i, j) is ``(x0 + (i + 0.5) * cell, y0 + (j + 0.5) * cell)``."""

    x0: float
    y0: float
    cell: float
    columns: int
    rows: int

    @property
    def size(self) -> int:
        return self.columns * self.rows

    def index_of(self, x: float, y: float) -> int | None:
        i = math.floor((x - self.x0) / self.cell)
        j = math.floor((y - self.y0) / self.cell)
        if 0 <= i < self.columns and 0 <= j < self.rows:
            return j * self.columns + i
        return None

    def centre(self, index: int) -> tuple[float, float]:
        j, i = divmod(index, self.columns)
        return (self.x0 + (i + 0.5) * self.cell, self.y0 + (j + 0.5) * self.cell)

    # The fills below mark every cell whose centre is inside a shape, a row at a time:
    # ``spans`` yields (start, stop) index ranges, one per row.

    def convex_spans(self, points: Sequence[tuple[float, float]]) -> list[tuple[int, int]]:
        """Rows of cells inside a convex polygon (for a slightly crossed quadrilateral, a
        little more: near enough). Edge by edge, each row's leftmost and rightmost crossing."""
        inv = 1.0 / self.cell
        x0, y0 = self.x0, self.y0
        us = [(x - x0) * inv - 0.5 for x, _ in points]
        vs = [(y - y0) * inv - 0.5 for _, y in points]
        j0 = max(0, math.ceil(min(vs)))
        j1 = min(self.rows - 1, math.floor(max(vs)))
        if j1 < j0:
            return []
        lo = [math.inf] * (j1 - j0 + 1)
        hi = [-math.inf] * (j1 - j0 + 1)
        ua, va = us[-1], vs[-1]
        for ub, vb in zip(us, vs, strict=True):
            if va != vb:
                slope = (ub - ua) / (vb - va)
                first, last = (va, vb) if va < vb else (vb, va)
                for j in range(max(j0, math.ceil(first)), min(j1, math.floor(last)) + 1):
                    u = ua + (j - va) * slope
                    k = j - j0
                    if u < lo[k]:
                        lo[k] = u
                    if u > hi[k]:
                        hi[k] = u
            else:  # a horizontal edge: on its row only if the row runs through it
                if va == math.floor(va) and j0 <= va <= j1:
                    k = int(va) - j0
                    lo[k] = min(lo[k], ua, ub)
                    hi[k] = max(hi[k], ua, ub)
            ua, va = ub, vb
        columns, last_column = self.columns, self.columns - 1
        spans: list[tuple[int, int]] = []
        for k in range(j1 - j0 + 1):
            i0 = math.ceil(lo[k]) if lo[k] > 0.0 else 0
            i1 = math.floor(hi[k]) if hi[k] < last_column else last_column
            if i0 <= i1:
                start = (j0 + k) * columns
                spans.append((start + i0, start + i1 + 1))
        return spans

    def disc_spans(self, x: float, y: float, radius: float) -> list[tuple[int, int]]:
        """Rows of cells whose centre is within ``radius`` of ``(x, y)``."""
        inv = 1.0 / self.cell
        u = (x - self.x0) * inv - 0.5
        v = (y - self.y0) * inv - 0.5
        r = radius * inv
        r2 = r * r
        columns = self.columns
        spans: list[tuple[int, int]] = []
        for j in range(max(0, math.ceil(v - r)), min(self.rows - 1, math.floor(v + r)) + 1):
            half = math.sqrt(max(0.0, r2 - (j - v) * (j - v)))
            i0 = max(0, math.ceil(u - half))
            i1 = min(columns - 1, math.floor(u + half))
            if i0 <= i1:
                spans.append((j * columns + i0, j * columns + i1 + 1))
        return spans

    def polygon_spans(self, polygon: Polygon) -> list[tuple[int, int]]:
        """Rows of cells inside any polygon (even-odd rule, as the world's own test)."""
        inv = 1.0 / self.cell
        pts = [((x - self.x0) * inv - 0.5, (y - self.y0) * inv - 0.5) for x, y in polygon]
        vs = [v for _, v in pts]
        j0 = max(0, math.ceil(min(vs)))
        j1 = min(self.rows - 1, math.floor(max(vs)))
        columns = self.columns
        spans: list[tuple[int, int]] = []
        for j in range(j0, j1 + 1):
            crossings: list[float] = []
            ua, va = pts[-1]
            for ub, vb in pts:
                if (va > j) != (vb > j):
                    crossings.append(ua + (j - va) * (ub - ua) / (vb - va))
                ua, va = ub, vb
            crossings.sort()
            for a, b in zip(crossings[::2], crossings[1::2], strict=False):
                i0 = max(0, math.ceil(a))
                i1 = min(columns - 1, math.ceil(b) - 1)
                if i0 <= i1:
                    spans.append((j * columns + i0, j * columns + i1 + 1))
        return spans

    def capsule_spans(self, seg: Segment, radius: float) -> list[tuple[int, int]]:
        """Rows of cells within ``radius`` of a segment (a band and its two round ends)."""
        ax, ay, bx, by = seg
        length = math.hypot(bx - ax, by - ay)
        spans = self.disc_spans(ax, ay, radius) + self.disc_spans(bx, by, radius)
        if length > 0.0:
            nx, ny = -(by - ay) / length * radius, (bx - ax) / length * radius
            band = ((ax + nx, ay + ny), (bx + nx, by + ny), (bx - nx, by - ny), (ax - nx, ay - ny))
            spans += self.convex_spans(band)
        return spans


def _fill(mask: bytearray, spans: list[tuple[int, int]], value: int) -> None:
    for a, b in spans:
        mask[a:b] = bytes((value,)) * (b - a)


def _and(a: bytes | bytearray, b: bytes | bytearray) -> bytearray:
    """Cell-wise AND of two 0/1 masks (one big-integer AND, in C)."""
    n = len(a)
    return bytearray(
        (int.from_bytes(a, "little") & int.from_bytes(b, "little")).to_bytes(n, "little")
    )


# ----------------------------------------------------------------------------- the floor


@dataclass(frozen=True)
class FloorModel:
    """A world's floor on a grid: ``floor`` (1 where a cell's centre is floor), ``free`` (1
    where the robot's centre fits), ``area_of`` (1 + the index of the named area holding the
    cell, 0 for none) and the area names."""

    grid: Grid
    floor: bytes
    free: bytes
    area_of: bytes
    area_names: tuple[str, ...]


@lru_cache(maxsize=8)
def floor_model(world: World, cell: float = CELL_MM) -> FloorModel:
    """The world's floor, free space and areas (cached: a world is read once per process)."""
    xs = [x for room in world.rooms for x, _ in room]
    ys = [y for room in world.rooms for _, y in room]
    margin = (math.ceil(REACH_MM / cell) + 1) * cell  # see _dilate
    x0, y0 = min(xs) - margin, min(ys) - margin
    columns = math.ceil((max(xs) + margin - x0) / cell)
    grid = Grid(x0, y0, cell, columns, math.ceil((max(ys) + margin - y0) / cell))
    rooms = bytearray(grid.size)
    for room in world.rooms:  # rooms may not overlap; even-odd within each
        _fill(rooms, grid.polygon_spans(room), 1)
    floor = bytearray(rooms)
    for shape in (*world.obstacles, *world.drops):
        _fill(floor, grid.polygon_spans(shape), 0)
    free = bytearray(floor)
    for seg in world.solid:
        _fill(free, grid.capsule_spans(seg, ROBOT_RADIUS_MM), 0)
    for drop in world.drops:
        for edge in polygon_edges(drop):
            _fill(free, grid.capsule_spans(edge, CLIFF_KEEPOUT_MM), 0)
    for vw in world.virtual_walls:
        _fill(free, grid.capsule_spans(vw.segment, vw.half_width), 0)
        if vw.halo:
            _fill(free, grid.disc_spans(vw.ax, vw.ay, vw.halo), 0)
    for lh in world.lighthouses:
        _fill(free, grid.capsule_spans(lh.fence_segment, lh.half_width), 0)
    area_of = bytearray(grid.size)
    for k, area in reversed(list(enumerate(world.areas))):  # the first named wins
        _fill(area_of, grid.polygon_spans(area.polygon), k + 1)
    return FloorModel(
        grid,
        bytes(floor),
        bytes(free),
        bytes(area_of),
        tuple(a.name for a in world.areas),
    )


def _component(free: bytes, grid: Grid, start: int) -> bytearray:
    """The cells 4-connected to ``start`` through free cells: runs of free cells per row,
    joined where runs of neighbouring rows overlap (a few thousand runs, not 10^5 cells)."""
    columns = grid.columns
    runs: list[list[tuple[int, int]]] = []
    for j in range(grid.rows):
        row = free[j * columns : (j + 1) * columns]
        runs.append([(m.start(), m.end()) for m in _RUN.finditer(row)])
    j0, i0 = divmod(start, columns)
    first = next(r for r in runs[j0] if r[0] <= i0 < r[1])
    seen = {(j0, first)}
    stack = [(j0, first)]
    region = bytearray(grid.size)
    while stack:
        j, (a, b) = stack.pop()
        region[j * columns + a : j * columns + b] = _ONES[: b - a]
        for nj in (j - 1, j + 1):
            if 0 <= nj < grid.rows:
                for run in runs[nj]:
                    if run[0] < b and a < run[1] and (nj, run) not in seen:
                        seen.add((nj, run))
                        stack.append((nj, run))
    return region


def _dilate(region: bytes | bytearray, grid: Grid, radius: float) -> bytes:
    """Every cell whose centre is within ``radius`` of a region cell's centre. The grid as one
    big integer, a byte a cell: a row of the disc is the region widened by some cells (shifts by
    8 bits) and moved some rows (shifts by a row's bits). The grid's margin (wider than the
    radius) keeps a widened row from wrapping into the next."""
    n = len(region)
    whole = int.from_bytes(region, "little")
    row_bits = 8 * grid.columns
    r = radius / grid.cell
    widened = [whole]  # widened[w]: the region widened by w cells each way
    out = 0
    for dj in range(-math.floor(r), math.floor(r) + 1):
        w = math.floor(math.sqrt(r * r - dj * dj))
        while len(widened) <= w:
            last = widened[-1]
            widened.append(last | (last << 8) | (last >> 8))
        out |= widened[w] << (dj * row_bits) if dj >= 0 else widened[w] >> (-dj * row_bits)
    return (out & ((1 << (8 * n)) - 1)).to_bytes(n, "little")


def _nearest_free(free: bytes, grid: Grid, x: float, y: float) -> int | None:
    """The free cell nearest ``(x, y)`` within 10 cells (a start pose close to a wall may sit
    in a cell whose centre is a little too close). Each episode's start looks: a span is one
    row, so the centre's row term is taken once a row (:meth:`Grid.centre`'s arithmetic)."""
    best: tuple[float, int] | None = None
    x0, y0, cell, columns = grid.x0, grid.y0, grid.cell, grid.columns
    for a, b in grid.disc_spans(x, y, 10 * cell):
        j = a // columns
        row, dy2 = j * columns, (y0 + (j + 0.5) * cell - y) ** 2
        for k in range(a, b):
            if free[k]:
                d = (x0 + (k - row + 0.5) * cell - x) ** 2 + dy2
                if best is None or d < best[0]:
                    best = (d, k)
    return None if best is None else best[1]


#: per floor model: (its connected regions, the reachable floor of each)
_REACHABLE_CACHE: dict[int, tuple[FloorModel, list[tuple[bytes, bytes]]]] = {}


def reachable_floor(world: World, start: Pose, cell: float = CELL_MM) -> bytes:
    """1 where a cell's centre is floor a brush can reach from ``start``, else 0 (cached per
    world and connected region: most starts of an evaluation share one)."""
    model = floor_model(world, cell)
    grid = model.grid
    root = _nearest_free(model.free, grid, start.x, start.y)
    if root is None:
        return bytes(grid.size)
    cached = _REACHABLE_CACHE.get(id(model))
    if cached is None or cached[0] is not model:
        cached = _REACHABLE_CACHE[id(model)] = (model, [])
    for known, floor in cached[1]:
        if known[root]:
            return floor
    component = bytes(_component(model.free, grid, root))
    reach = _dilate(component, grid, REACH_MM)  # the brushes reach past the edge
    reachable = bytes(_and(reach, model.floor))
    cached[1].append((component, reachable))
    return reachable


# ----------------------------------------------------------------------------- sweeping


class SweptArea:
    """The floor cleaned by one robot, updated from its true pose every step.

    ``update(time, x, y, theta, motors)`` is called once per simulator step with the pose
    and which brushes run; coverage is read with :meth:`coverage`, :meth:`coverage_by_area`,
    :attr:`curve` and :meth:`longest_idle`. With no brush running and before
    :attr:`idle_until`, an update would only note the step's time: the simulator sets
    :attr:`last_time` itself then instead of calling (a call a step saved while a robot
    drives with its brushes off, as docking does).
    """

    def __init__(self, world: World, start: Pose, cell: float = CELL_MM) -> None:
        model = floor_model(world, cell)
        self.grid = model.grid
        self.area_names = model.area_names
        self._area_of = model.area_of
        reachable = reachable_floor(world, start, cell)
        #: one byte a cell: 0 not reachable floor, 1 reachable, 2 reachable and cleaned
        self.cells = bytearray(reachable)
        # the reachable cells' area numbers (reachable is 0/1 a byte: times 0xFF, a byte mask),
        # counted in C: a loop over the cells was most of an evaluation episode's set-up
        size = len(reachable)
        mask = int.from_bytes(reachable, "big") * 0xFF
        kept = (int.from_bytes(model.area_of, "big") & mask).to_bytes(size, "big")
        counts = [0] + [kept.count(k + 1) for k in range(len(self.area_names))]
        counts[0] = reachable.count(1) - sum(counts)
        #: reachable cells per area (index 0: outside every named area)
        self.reachable_cells = tuple(counts)
        self.reachable_total = sum(counts)
        #: cleaned cells per area, as reachable_cells
        self.cleaned_cells = [0] * len(counts)
        self.cleaned_total = 0
        #: (time s, cleaned cells per area) every :attr:`sample_every` seconds, from time 0
        self.curve: list[tuple[float, tuple[int, ...]]] = [(0.0, tuple(self.cleaned_cells))]
        #: the curve's interval: SAMPLE_EVERY_S, doubled each time it is thinned
        self.sample_every = SAMPLE_EVERY_S
        self._next_sample = SAMPLE_EVERY_S
        self._mark: tuple[float, float, float] | None = None  # pose of the last mark
        self._footprint: tuple[float, float, float, float] | None = None
        #: the time of the last update (``update``'s, or the simulator's on an idle step)
        self.last_time = 0.0
        #: until then an update with no brush running changes nothing but last_time: no mark
        #: to drop, no sample due
        self.idle_until = SAMPLE_EVERY_S
        self.cleaning_time = 0.0
        self._last_new = 0.0  # cleaning time of the last new cell
        self._longest_idle = 0.0

    # ------------------------------------------------------------------ per step
    def update(self, time: float, x: float, y: float, theta: float, motors: int) -> None:
        """The robot is at ``(x, y, theta)`` at ``time`` with ``motors`` on (the bits of
        Motors, 138: side brush 1, vacuum 2, main brush 4)."""
        footprint = FOOTPRINTS[motors & MOTOR_RUN_BITS]
        if footprint is not None:
            self.cleaning_time += time - self.last_time
            mark = self._mark
            if mark is None or footprint is not self._footprint:
                self._mark = (x, y, theta)
                self._footprint = footprint
                self._sweep(footprint, x, y, theta, x, y, theta)
            else:
                mx, my, mtheta = mark
                turn = abs(theta - mtheta)
                if turn > math.pi:
                    turn = 2.0 * math.pi - turn
                if abs(x - mx) + abs(y - my) + turn * REACH_MM >= MARK_EVERY_MM:
                    self._mark = (x, y, theta)
                    self._sweep(footprint, mx, my, mtheta, x, y, theta)
        elif self._mark is not None:
            self._mark = None
        self.last_time = time
        if time >= self._next_sample:
            self.curve.append((time, tuple(self.cleaned_cells)))
            self._next_sample += self.sample_every
            if len(self.curve) > MAX_CURVE_SAMPLES:
                self._thin_curve()
        self.idle_until = self._next_sample if self._mark is None else -math.inf

    def _thin_curve(self) -> None:
        """Keep every other sample of the curve (its first and, an odd count, its newest)
        and sample half as often from here: the samples stay evenly spaced from 0 s, sample
        ``k`` due at ``k * sample_every`` s."""
        del self.curve[1::2]
        self.sample_every *= 2.0
        self._next_sample = len(self.curve) * self.sample_every

    def finish(self, time: float, x: float, y: float, theta: float) -> None:
        """Sweep what moved since the last mark (at the end of a run, or before reading)."""
        mark = self._mark
        if mark is not None and self._footprint is not None and mark != (x, y, theta):
            self._mark = (x, y, theta)
            self._sweep(self._footprint, *mark, x, y, theta)

    def _sweep(
        self, footprint: tuple[float, float, float, float], x0: float, y0: float, t0: float,
        x1: float, y1: float, t1: float,
    ) -> None:  # fmt: skip
        ax, ay, bx, by = footprint
        c0, s0, c1, s1 = math.cos(t0), math.sin(t0), math.cos(t1), math.sin(t1)
        quad = (
            (x0 + ax * c0 - ay * s0, y0 + ax * s0 + ay * c0),
            (x0 + bx * c0 - by * s0, y0 + bx * s0 + by * c0),
            (x1 + bx * c1 - by * s1, y1 + bx * s1 + by * c1),
            (x1 + ax * c1 - ay * s1, y1 + ax * s1 + ay * c1),
        )
        cells = self.cells
        new = 0
        for a, b in self.grid.convex_spans(quad):
            row = cells[a:b]
            if _DIRTY in row:
                area_of, counts = self._area_of, self.cleaned_cells
                for k in range(a, b):
                    if cells[k] == _DIRTY:
                        counts[area_of[k]] += 1
                        new += 1
                cells[a:b] = row.translate(_CLEAN_TABLE)
        if new:
            self.cleaned_total += new
            idle = self.cleaning_time - self._last_new
            if idle > self._longest_idle:
                self._longest_idle = idle
            self._last_new = self.cleaning_time

    # ------------------------------------------------------------------ results
    def coverage(self) -> float:
        """Cleaned / reachable floor, 0..1 (0 when nothing is reachable)."""
        return self.cleaned_total / self.reachable_total if self.reachable_total else 0.0

    def coverage_by_area(self) -> dict[str, float]:
        """Per named area of the world (in the world's order; areas with no reachable floor
        left out)."""
        return {
            name: self.cleaned_cells[k + 1] / self.reachable_cells[k + 1]
            for k, name in enumerate(self.area_names)
            if self.reachable_cells[k + 1]
        }

    def area_m2(self, cells: int) -> float:
        return cells * self.grid.cell * self.grid.cell / 1e6

    def longest_idle(self) -> float:
        """The longest stretch of cleaning time (s, brushes on) without a new cell cleaned,
        including the one still going on."""
        return max(self._longest_idle, self.cleaning_time - self._last_new)
