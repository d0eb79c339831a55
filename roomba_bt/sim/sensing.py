"""Sensing: what the robot's sensors report, from its pose and the world's geometry.

The bumper (packet 7), the cliff sensors (9-12, 28-31), the wall sensor (8, 27), the light
bumper's six rays (45, 46-51), the IR receivers (13, 17, 52, 53) and the dock's contacts
(34, via :attr:`docked`)::

    packet           sensor                 computed from
    7                bumper, wheel drops    walls within 1.5 mm of the body; lifted, fallen
    8, 27            wall sensor            a ray to the right, walls within 120 mm
    9-12, 28-31      cliff sensors          4 points 150 mm out at +60 +20 -20 -60 deg, drops
    45, 46-51        light bumper           6 rays at +65 +38 +12 -12 -38 -65 deg, 150 mm
    13, 17, 52, 53   IR receivers           dock beams, virtual walls, lighthouses (30 ms)

A layer of the simulator (see state.py): :meth:`Sensing._sense` runs on most steps, so it
reads the pose and writes the value list through ``self`` directly, and geometry is measured
again only when the pose or the world changed (``_geometry_dirty``), walls only once the robot
may have moved far enough for what they show to change (``_walls_at``, ``_walls_same2``: no
wall touching, the same walls within the rays' reach).

The far sensors (the light bumper, the wall sensor and the IR receivers: 8, 13, 17, 27,
45-53) change nothing on the robot itself; they are only read. When nothing reads them every
step (no stream of them, no built-in cycle driving), :meth:`Sensing._sense` keeps what they
were due to be measured from (the pose, the close walls, the step) and
:meth:`Sensing._settle_far` measures them from it when they are read: before a reply, and
when a stream of them or a built-in cycle starts (both read them every step). The same
values, measured once instead of every step; a bump-and-turn mission streams none of them.
"""

from __future__ import annotations

import math
from math import trunc

from roomba_bt.oi.bits import BUMP_BITS, WHEEL_DROP_BITS
from roomba_bt.oi.ir import LighthouseBeam, dock_character, lighthouse_character
from roomba_bt.oi.profiles import (
    CLIFF_SENSOR_ANGLES_DEG,
    CLIFF_SENSOR_RADIUS_MM,
    LIGHT_BUMP_ANGLES_DEG,
    LIGHT_BUMP_RANGE_MM,
    OMNI_AHEAD_MM,
)
from roomba_bt.sim.geometry import Segment, closest_point, point_in_polygon, wrap_angle
from roomba_bt.sim.state import RobotState
from roomba_bt.sim.world import ROBOT_RADIUS_MM, DockSpec

# Sensor geometry (robot frame: angle from the heading, CCW positive).
_LIGHT_BUMP_ANGLES = tuple(math.radians(a) for a in LIGHT_BUMP_ANGLES_DEG)
_LIGHT_BUMP_DIRECTIONS = tuple((math.cos(a), math.sin(a)) for a in _LIGHT_BUMP_ANGLES)
_LIGHT_BUMP_RAYS = tuple((i, ca, sa) for i, (ca, sa) in enumerate(_LIGHT_BUMP_DIRECTIONS))
LIGHT_BUMP_THRESHOLD = 100
_CLIFF_ANGLES = tuple(math.radians(a) for a in CLIFF_SENSOR_ANGLES_DEG)
CLIFF_FLOOR_SIGNAL = 2600
CLIFF_DROP_SIGNAL = 20
WALL_SENSOR_RANGE_MM = 120.0
WALL_SENSOR_TRIGGER_MM = 50.0
#: half a drive wheel's tyre width (mm): a wheel falls once its inner edge has left the floor
WHEEL_HALF_WIDTH_MM = 10.0

#: Bumper: contacts within this angle of the heading press both switches.
BUMP_CENTRE_ANGLE = math.radians(12.0)
BUMP_HALF_SPAN = math.radians(85.0)
CONTACT_MM = 1.5
#: IR receivers: the omni on top of the bumper, the directional ones left and right of it.
OMNI_FORWARD_MM = OMNI_AHEAD_MM
RECEIVER_FORWARD_MM = 150.0
RECEIVER_SIDE_MM = 40.0
#: Field of view of the directional receivers, from the heading: left sees -5..+90 deg,
#: right -90..+5 deg, so both see the dock only when it is within 5 deg of straight ahead.
RECEIVER_INNER = math.radians(5.0)
RECEIVER_OUTER = math.radians(90.0)
#: The virtual wall's character on the omni receiver (it also sets packet 13).
VIRTUAL_WALL_CHARACTER = 162
#: the far sensors' packets: wall (8, 27), virtual wall (13), IR (17, 52, 53), light bumper
FAR_PACKETS = frozenset((8, 13, 17, 27, 45, 46, 47, 48, 49, 50, 51, 52, 53))
#: The far sensors in three groups, each measured every step only while something reads it
#: (bits of the ``far`` argument of :meth:`Sensing._sense`): a dock mission streams the light
#: bumper and the IR receivers but not the wall sensor, whose ray is then owed.
FAR_LIGHT = 1  # the light bumper, 45-51
FAR_WALL = 2  # the wall sensor, 8 and 27
FAR_IR = 4  # the virtual wall and IR receivers, 13, 17, 52, 53
FAR_ALL = FAR_LIGHT | FAR_WALL | FAR_IR
_FAR_RAYS = FAR_LIGHT | FAR_WALL
_FAR_GROUPS = (
    (FAR_LIGHT, frozenset(range(45, 52))),
    (FAR_WALL, frozenset((8, 27))),
    (FAR_IR, frozenset((13, 17, 52, 53))),
)


#: ``far`` (0-7) split once: (its ray groups, light bumper, wall sensor, IR receivers), for
#: :meth:`Sensing._sense` to read by one look-up: an ``&`` of ints is not specialised in
#: CPython 3.11 (about 120 instructions each, four a step)
_FAR_SPLIT = tuple(
    (far & _FAR_RAYS, bool(far & FAR_LIGHT), bool(far & FAR_WALL), bool(far & FAR_IR))
    for far in range(FAR_ALL + 1)
)


def far_groups(packets: frozenset[int] | set[int]) -> int:
    """The far sensor groups (FAR_LIGHT, FAR_WALL, FAR_IR bits) among ``packets``."""
    return sum(group for group, members in _FAR_GROUPS if not members.isdisjoint(packets))


_NEAR_MARGIN_MM = 300.0
_LIGHT_RANGES = (LIGHT_BUMP_RANGE_MM,) * 6
#: the farthest any ray reaches from the robot's centre, and 1 mm more
_RAY_REACH = ROBOT_RADIUS_MM + max(LIGHT_BUMP_RANGE_MM, WALL_SENSOR_RANGE_MM) + 1.0
_Line = tuple[float, float, float, float, float, float, float, float, float]
#: A wall as the sensing pass reads it, computed once per world: a, b - a, |b - a|^2 (1 for
#: a point), its line (:func:`_line`) and the segment itself
_Wall = tuple[float, float, float, float, float, _Line, Segment]
#: a ray that may meet a wall: n.d (> 0), its index, t.d (see :func:`_facing_walls`)
_Facing = tuple[float, int, float]
#: a close wall's line (:data:`_Line`), then the rays that may meet it from its normal's
#: side and from the other side
_FacingWall = tuple[
    float, float, float, float, float, float, float, float, float,
    tuple[_Facing, ...], tuple[_Facing, ...],
]  # fmt: skip
_DARK = (0,) * 6  # the six light bumper signals with no wall in sight
#: packet 7's bump bits of each side of the bumper (the timeline's ``bump`` events say sides)
BUMP_SIDE_BITS = {"right": 1, "left": 2, "both": 3}
_BUMP_SIDES = {bits: side for side, bits in BUMP_SIDE_BITS.items()}


def _line(seg: Segment) -> _Line:
    """(nx, ny, n.a, tx, ty, t.a, length, angle of n, angle of -n) of a wall segment from a
    to b (angles from the x axis, -pi..pi)."""
    ax, ay, bx, by = seg
    length = math.hypot(bx - ax, by - ay)
    tx, ty = ((bx - ax) / length, (by - ay) / length) if length else (1.0, 0.0)
    nx, ny = -ty, tx
    return (
        nx, ny, nx * ax + ny * ay, tx, ty, tx * ax + ty * ay, length,
        math.atan2(ny, nx), math.atan2(-ny, -nx),
    )  # fmt: skip


def _wall(seg: Segment) -> _Wall:
    ax, ay, bx, by = seg
    ex, ey = bx - ax, by - ay
    return (ax, ay, ex, ey, ex * ex + ey * ey or 1.0, _line(seg), seg)


#: each ray as a rotation of the heading: its index, cos and sin. The wall sensor's, by
#: -90 deg, gives (sin, -cos) of the heading as :meth:`Sensing._sense_wall` takes it: the same
#: numbers, x + 0.0 and x * -1.0 being exact (but for a heading of -0.0, whose sine -0.0
#: comes out +0.0: a zero either way, the rays meet the same walls at the same places)
_RAY_TURNS = (*_LIGHT_BUMP_RAYS, (6, 0.0, -1.0))
#: the light bumper's rays sorted by their angle from the heading, repeated a turn below
#: and a turn above (:meth:`Sensing._sense_rays` turning): the rays whose angle is within a
#: window about any bearing in -pi..pi (the window less than a turn wide) are one slice of
#: them. (The rays lie within -65..65 deg and a window reaches 90 deg and a margin either
#: side of its bearing: a copy a turn away falls in one only at right angles to the wall's
#: normal, where n.d is 0 but for rounding. Kept so that the slice holds every ray the full
#: loop would test, rounding and all.)
_ARC = sorted(
    (math.atan2(sa, ca) + turn, (i, ca, sa))
    for turn in (-2.0 * math.pi, 0.0, 2.0 * math.pi)
    for i, ca, sa in _LIGHT_BUMP_RAYS
)
_ARC_ANGLES = tuple(angle for angle, _ in _ARC)
_ARC_RAYS = tuple(ray for _, ray in _ARC)
#: The slice for a window, by look-up, not bisection (two bisect calls cost about 3,200
#: instructions, the look-ups a quarter of that): angles from _ARC_LOW (below every window)
#: cut into buckets _ARC_BUCKET wide; for bucket k, the first ray at or above the bottom of
#: bucket k - 1 (_ARC_FROM) and the end of those at or below the top of bucket k + 1
#: (_ARC_TO). The bucket a window's end falls in, worked out in floating point, is off by one
#: at most: the slice holds every ray of the window and maybe one beyond it (under 8 deg
#: beyond, a copy a turn away never), which n.d > least, the exact test, passes over.
_ARC_LOW = -5.0  # windows reach from -pi - pi/2 to pi + pi/2
_ARC_BUCKET = math.radians(4.0)
_ARC_PER_RADIAN = 1.0 / _ARC_BUCKET


def _arc_slices(buckets: int) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(_ARC_FROM, _ARC_TO) for ``buckets`` buckets: one walk up the angles (a bisection
    per bucket would cost 2 M instructions at import)."""
    first: list[int] = []
    end: list[int] = []
    below = above = 0  # the angles below a bucket's bottom, at or below its top
    count = len(_ARC_ANGLES)
    for k in range(buckets):
        bottom = _ARC_LOW + (k - 1) * _ARC_BUCKET
        top = _ARC_LOW + (k + 2) * _ARC_BUCKET
        while below < count and _ARC_ANGLES[below] < bottom:
            below += 1
        while above < count and _ARC_ANGLES[above] <= top:
            above += 1
        first.append(below)
        end.append(above)
    return tuple(first), tuple(end)


_ARC_FROM, _ARC_TO = _arc_slices(trunc(-2.0 * _ARC_LOW * _ARC_PER_RADIAN) + 2)
#: far more than rounding makes n.d or a bearing off by (a few 1e-16)
_ANGLE_MARGIN = 1e-9
#: ``least`` (n.d a ray needs to reach a wall) this far above 1: no ray's n.d, 1 at most with
#: rounding, is above it
_LEAST_TOP = 1.0 + _ANGLE_MARGIN
#: a ray reaches a wall only if its angle from the wall's normal is below acos(least);
#: pi/2 - least is above that (acos x = pi/2 - asin x, asin x >= x for x >= 0), with margins
_HALF_TOP = math.pi / 2.0 + 3 * _ANGLE_MARGIN


def _facing_walls(theta: float, close_lines: tuple[_Line, ...]) -> tuple[_FacingWall, ...]:
    """The close walls as the light bumper's rays see them at a heading ``theta``: each
    wall's line, then the rays that may meet it from either side of it, as (n.d, ray, t.d),
    sorted by n.d from the largest down and only those with n.d > 0 (from the far side, n
    turned over: -n.d, exactly the same number negated). The same for every step at one
    heading and the same close walls: driving straight, n.d and t.d are not worked out again
    every step, the rays pointing away from a wall are not looked at, and a wall no ray
    points at is passed over with one comparison. The rays' directions (the heading turned
    by each ray's angle) are worked out in the loop, as :meth:`Sensing._sense_rays` does
    turning: no tuple of them built (by a generator, a call per ray) for one use or two."""
    ct, st = math.cos(theta), math.sin(theta)
    facing: list[_FacingWall] = []
    for line in close_lines:
        nx, ny, _, tx, ty, _, _, _, _ = line
        front: list[_Facing] = []
        back: list[_Facing] = []
        for i, ca, sa in _LIGHT_BUMP_RAYS:
            c = ct * ca - st * sa
            s = st * ca + ct * sa
            dn = nx * c + ny * s
            if dn > 0.0:
                front.append((dn, i, tx * c + ty * s))
            elif dn < 0.0:
                back.append((-dn, i, tx * c + ty * s))
        front.sort(reverse=True)
        back.sort(reverse=True)
        facing.append((*line, tuple(front), tuple(back)))
    return tuple(facing)


#: the walls kept near (a wall beyond the near radius less its margin is that far away at
#: least: the 120 mm beyond the rays' reach let the robot move that far before measuring again)
_NEAR_RADIUS_MM = ROBOT_RADIUS_MM + LIGHT_BUMP_RANGE_MM + 120.0 + _NEAR_MARGIN_MM
_NEAR_MARGIN2 = _NEAR_MARGIN_MM**2
_REACH2 = (ROBOT_RADIUS_MM + LIGHT_BUMP_RANGE_MM + 5.0) ** 2  # walls the rays may hit
_CONTACT2 = (ROBOT_RADIUS_MM + CONTACT_MM) ** 2  # walls touching the bumper
_NEAREST2 = (_NEAR_RADIUS_MM - _NEAR_MARGIN_MM) ** 2  # the clearance the near set guarantees
_REACH = math.sqrt(_REACH2)
#: no wall measured closer than this (from the centre) touches the bumper on a move shorter
#: than the difference, less 10 mm: the clearance stays above a step's travel (7.5 mm at
#: 500 mm/s), so the _move fast path does not look for walls in the way
_QUIET_CONTACT = math.sqrt(_CONTACT2) + 10.0
#: what rounding could take off a distance measured (far more than it can)
_SAME_MARGIN = 0.01
_PI = math.pi
_TWO_PI = 2.0 * math.pi


class _DockBeams:
    """The dock's beams and contacts as plain numbers, computed once per robot: the IR
    receivers ask for a character three times every 30 ms, so no attribute chains, no
    function calls for the angle wrap, one table lookup for the character."""

    __slots__ = (
        "angle_tolerance", "buoy2", "characters", "contact", "contact2", "facing", "field2",
        "green_from", "green_to", "reach", "reach2", "red_from", "red_to", "target_theta",
        "target_x", "target_y", "x", "y",
    )  # fmt: skip

    def __init__(self, dock: DockSpec) -> None:
        self.x, self.y, self.facing = dock.x, dock.y, dock.facing
        self.field2 = dock.force_field * dock.force_field
        self.buoy2 = dock.buoy_range * dock.buoy_range
        reach = max(dock.buoy_range, dock.force_field) + 200.0
        self.reach = reach
        self.reach2 = reach * reach
        self.red_from, self.red_to = dock.red
        self.green_from, self.green_to = dock.green
        discovery = dock.family == "discovery"
        #: index: red << 2 | green << 1 | force field
        self.characters = tuple(
            dock_character(red=bool(i & 4), green=bool(i & 2), force_field=bool(i & 1),
                           discovery=discovery)
            for i in range(8)
        )  # fmt: skip
        target = dock.docked_pose
        self.target_x, self.target_y, self.target_theta = target.x, target.y, target.theta
        self.contact = dock.contact_tolerance
        self.contact2 = dock.contact_tolerance**2
        self.angle_tolerance = dock.angle_tolerance

    def character(self, px: float, py: float) -> int:
        """What a receiver at (px, py) sees of a powered dock (0: nothing)."""
        dx, dy = px - self.x, py - self.y
        dist2 = dx * dx + dy * dy
        index = 1 if dist2 <= self.field2 else 0
        if dist2 <= self.buoy2:
            bearing = (math.atan2(dy, dx) - self.facing + _PI) % _TWO_PI - _PI
            if self.red_from <= bearing <= self.red_to:
                index |= 4
            if self.green_from <= bearing <= self.green_to:
                index |= 2
        return self.characters[index]


# Over 400 lines on purpose: the simulator's "sensing (incl. IR)" layer, every packet a frame
# carries measured from one pose; its parts share the close walls found once per circle
# (`_near`) and the order `_sense` measures them in. A class per sensor would be one more
# link in the layers' chain (state.py) and split state that the parts read together.
class Sensing(RobotState):
    """The sensors' packets in :attr:`values`, measured again when the pose or world changed."""

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_beams", "_body_bits", "_clearance", "_dirt", "_drops", "_facing", "_facing_lines",
        "_facing_theta", "_geometry_dirty", "_ground_varies", "_ir_beamless", "_ir_quiet2",
        "_ir_quiet_at", "_ir_stale", "_near", "_near_at", "_owed_ir", "_prev_bumps",
        "_prev_cliffs", "_rays_on", "_rays_read", "_rays_theta", "_safety_due", "_walls",
        "_walls_at", "_walls_clear", "_walls_lines", "_walls_same2",
    )  # fmt: skip

    def _init_sensing(self) -> None:
        world = self.world
        v = self.values
        v[28] = v[29] = v[30] = v[31] = CLIFF_FLOOR_SIGNAL
        self._geometry_dirty = True
        self._near: tuple[_Wall, ...] = ()
        self._near_at = (math.inf, math.inf)
        self._walls = tuple(_wall(seg) for seg in world.solid)
        #: the heading the rays were last measured at (the same again: driving straight)
        self._rays_theta = math.nan
        #: the close walls as the rays see them at a heading (:func:`_facing_walls`), and the
        #: heading and walls they are for (worked out again when either changes)
        self._facing: tuple[_FacingWall, ...] = ()
        self._facing_theta = math.nan
        self._facing_lines: tuple[_Line, ...] = ()
        self._drops = world.drops
        self._dirt = world.dirt
        self._beams = _DockBeams(world.dock) if world.dock is not None else None
        #: packet 7's bits the walls do not set (the timeline's bump, wheel drops), and
        #: whether the cliffs and dirt can be anything but clear (:meth:`_body_changed`)
        self._body_bits = 0
        self._ground_varies = False
        self._body_changed()
        self._prev_bumps = 0
        self._prev_cliffs = 0
        #: a wheel drop, a cliff or the dock's contacts: what Safe mode's own rules act on
        #: (``OIProtocol._safety``), kept as they change instead of read from five packets
        #: every step
        self._safety_due = False
        self._rays_on = True
        self._ir_stale = True
        #: no virtual wall nor lighthouse: away from the dock, the IR receivers see nothing;
        #: where they were last measured so, and how far (squared) the robot may move from
        #: there with them still beyond the dock's beams (:meth:`_ir_quiet_circle`)
        self._ir_beamless = not (world.virtual_walls or world.lighthouses)
        self._ir_quiet_at = (math.inf, math.inf)
        self._ir_quiet2 = 0.0
        #: the far sensors owed (see the module's docstring). The rays: the groups of them
        #: (FAR_LIGHT, FAR_WALL) the last :meth:`_sense` measured, the others owed from its
        #: pose and close walls, which stay the robot's own until the next step moves it (and
        #: senses again): a number, not a tuple a step. The IR receivers' are due every other
        #: step: the arguments of :meth:`_sense_ir` as they were due, or None
        self._rays_read = _FAR_RAYS
        self._owed_ir: tuple[float, float, float, int, bool] | None = None
        #: how far the robot can move before a wall could stop it (motion's fast path): exact
        #: where the walls were measured, elsewhere a bound below it (``_walls_clear``)
        self._clearance = 0.0
        #: where walls were last measured, and the squared distance the robot may move from
        #: there before what they show could change (:meth:`_sense_walls`): no wall touches
        #: the bumper, and the same walls are within reach of the rays (``_walls_lines``)
        self._walls_at = (math.inf, math.inf)
        self._walls_same2 = 0.0
        self._walls_lines: tuple[_Line, ...] = ()
        #: the clearance anywhere within that circle: where the walls were measured, less the
        #: circle's radius (a bound set once per circle, instead of the distance moved, a
        #: square root, taken off every step)
        self._walls_clear = 0.0

    # Few calls (the rays only near a wall): it runs on every step the robot moves, and a call
    # costs about a tenth of a microsecond, 3 % of a whole step.
    def _sense(self, far: int = FAR_ALL) -> None:
        """Every geometric sensor, from the pose and the world (only when either changed);
        the far sensors of the groups in ``far`` (FAR_LIGHT, FAR_WALL, FAR_IR: something reads
        them every step) now, the others owed."""
        self._geometry_dirty = False
        v = self.values
        x, y, theta = self.x, self.y, self.theta
        wx, wy = self._walls_at
        dx, dy = x - wx, y - wy
        moved2 = dx * dx + dy * dy
        if moved2 < self._walls_same2:
            # Within the circle where the walls were measured: none touches the bumper, the
            # same ones are within the rays' reach, the dock's contacts are out of reach (the
            # walls are not looked at again, the contacts not tested): packet 7 holds only
            # the bits the walls do not set.
            bumps = self._body_bits
            self._clearance = self._walls_clear
            contacts = False
        else:
            bumps = self._sense_walls(x, y, theta) | self._body_bits
            contacts = self._beams is not None
        v[7] = bumps
        if bumps != self._prev_bumps:
            self._bumps_changed(bumps)
        close_lines = self._walls_lines
        rays, light, wall, ir = _FAR_SPLIT[far]
        # measured now: what was owed is out of date (a fall measures at once)
        self._rays_read = rays
        if rays:
            if close_lines:
                if light:
                    v[45] = self._sense_rays(x, y, theta, close_lines)
                if wall:
                    self._sense_wall(x, y, theta, close_lines)
            elif self._rays_on:  # no wall in reach: every ray dark, none owed
                v[45] = v[46] = v[47] = v[48] = v[49] = v[50] = v[51] = v[27] = v[8] = 0
                self._rays_on = False
        if self._ground_varies or self._prev_cliffs:  # else no cliff, no dirt, as before
            self._sense_ground(x, y, theta)
        if not self.ticks & 1 or self._ir_stale:
            if ir:
                qx, qy = self._ir_quiet_at
                dx, dy = x - qx, y - qy
                if dx * dx + dy * dy >= self._ir_quiet2:  # else beyond every beam's reach
                    self._sense_ir(x, y, theta, self.ticks, self.dock_powered)
                self._owed_ir = None
            else:
                self._owed_ir = (x, y, theta, self.ticks, self.dock_powered)
            self._ir_stale = False
        if contacts:
            self._sense_contacts(x, y, theta)

    def _sense_ground(self, x: float, y: float, theta: float) -> None:
        """The cliff sensors (9-12, 28-31) and the dirt detector (15)."""
        down = self.lifted or self.fallen
        cliffs = 15 if down else self._cliffs_over_drops(x, y, theta) if self._drops else 0
        if self._dirt:
            self.values[15] = 0 if down else self.world.dirt_at(x, y)
        if cliffs != self._prev_cliffs:
            self._cliffs_changed(cliffs)

    def _body_changed(self) -> None:
        """The timeline pressed the bumper, lifted the robot, or it fell: the bits of packet 7
        that are not the walls' (``_body_bits``), and whether the ground must be looked at."""
        down = self.lifted or self.fallen
        self._body_bits = self._event_bump | (WHEEL_DROP_BITS if down else 0)
        self._ground_varies = bool(down or self._drops or self._dirt)

    def _sense_contacts(self, x: float, y: float, theta: float) -> None:
        """On the dock's contacts: within its tolerances of the docked pose, not lifted."""
        beams = self._beams
        assert beams is not None
        ex, ey = x - beams.target_x, y - beams.target_y
        docked = (
            ex * ex + ey * ey <= beams.contact2
            and abs((theta - beams.target_theta + _PI) % _TWO_PI - _PI) <= beams.angle_tolerance
            and not self.lifted
        )
        if docked != self.docked:
            self.docked = docked
            self._power_due = True  # the contacts may charge (power.py)
            self.event("docked" if docked else "undocked", "")
            self._check_safety()

    def _settle_far(self) -> None:
        """Measure the far sensors owed, from the pose and step they were due at: before a
        reply and whenever something starts to read them every step (a stream of them, a
        built-in cycle), after which :meth:`_sense` measures them as they are due."""
        owed = _FAR_RAYS & ~self._rays_read
        if owed:
            self._rays_read = _FAR_RAYS
            close_lines = self._walls_lines
            if close_lines:
                x, y, theta = self.x, self.y, self.theta
                if owed & FAR_LIGHT:
                    self.values[45] = self._sense_rays(x, y, theta, close_lines)
                if owed & FAR_WALL:
                    self._sense_wall(x, y, theta, close_lines)
            elif self._rays_on:
                v = self.values
                v[45] = v[46] = v[47] = v[48] = v[49] = v[50] = v[51] = v[27] = v[8] = 0
                self._rays_on = False
        ir = self._owed_ir
        if ir is not None:
            self._owed_ir = None
            self._sense_ir(*ir)

    # Over 60 lines on purpose: both ray loops (turning, straight) inline with no call a ray,
    # on the step's path whenever the light bumper is streamed near a wall.
    def _sense_rays(self, x: float, y: float, theta: float, close_lines: tuple[_Line, ...]) -> int:
        """The light bumper (packets 46-51): six rays from the bumper against the walls close
        enough to show; returns packet 45's bits. A ray's signal is worked out where it hits
        (a ray meets a second wall only closer: its signal, stronger, replaces the first)."""
        v = self.values
        v[46:52] = _DARK
        hits = list(_LIGHT_RANGES)  # the nearest hit of each ray so far
        bits = 0
        radius = ROBOT_RADIUS_MM
        # A ray from the centre c in direction d meets a wall's line at c + k d,
        # k = (n.a - n.c) / (n.d); the ray starts on the bumper (k = R), the hit's place along
        # the wall is t.(c + kd). A ray meets the wall within its range only if
        # n.d > p / (R + range): the others are passed over at once (with a margin; the
        # exact test decides the rest).
        if theta != self._rays_theta:
            # Turning: the rays that may meet each wall at this heading, once; the rays'
            # directions as _facing_walls works them out, in the loop (no tuple of them
            # made for one use). A ray meets the wall's line in range only if n.d > least, i.e.
            # if its angle from the normal is below acos(least) (< half): only the rays
            # within half of the normal's bearing are looked at, the others (four of six,
            # usually) passed over by a slice of the rays sorted by angle (_ARC).
            self._rays_theta = theta
            ct, st = math.cos(theta), math.sin(theta)
            for nx, ny, w, tx, ty, ta, length, ahead, behind in close_lines:
                p = w - (nx * x + ny * y)
                if p < 0.0:  # the normal turned towards the wall (negation is exact: same k)
                    nx, ny, p = -nx, -ny, -p
                    bearing = behind - theta
                else:
                    bearing = ahead - theta  # the normal's angle from the heading
                least = p / _RAY_REACH
                if least >= _LEAST_TOP:
                    continue  # beyond every ray's reach
                while bearing > _PI:
                    bearing -= _TWO_PI
                while bearing < -_PI:
                    bearing += _TWO_PI
                half = _HALF_TOP - least
                first = _ARC_FROM[trunc((bearing - half - _ARC_LOW) * _ARC_PER_RADIAN)]
                end = _ARC_TO[trunc((bearing + half - _ARC_LOW) * _ARC_PER_RADIAN)]
                q = tx * x + ty * y - ta
                for i, ca, sa in _ARC_RAYS[first:end]:
                    c = ct * ca - st * sa
                    s = st * ca + ct * sa
                    dn = nx * c + ny * s
                    if dn <= least:
                        continue  # pointing away from (or along) this wall, or out of range
                    k = p / dn
                    t = k - radius
                    if t < 0.0 or t >= hits[i]:
                        continue
                    along = q + k * (tx * c + ty * s)
                    if 0.0 <= along <= length:
                        hits[i] = t
                        signal = v[46 + i] = trunc(4095 * (1.0 - t / LIGHT_BUMP_RANGE_MM) ** 2)
                        if signal >= LIGHT_BUMP_THRESHOLD:
                            bits |= 1 << i
                        else:
                            bits &= ~(1 << i)
        else:
            # The heading of the last step (driving straight, or standing): the rays that can
            # meet each wall, worked out once for this heading and these walls.
            facing = self._facing
            if theta != self._facing_theta or close_lines is not self._facing_lines:
                facing = self._facing = _facing_walls(theta, close_lines)
                self._facing_theta = theta
                self._facing_lines = close_lines
            for nx, ny, w, tx, ty, ta, length, _, _, front, back in facing:
                p = w - (nx * x + ny * y)
                if p < 0.0:  # on the other side of the wall's line: the rays seen from there
                    p = -p
                    front = back
                least = p / _RAY_REACH
                if not front or front[0][0] <= least:
                    continue  # no ray reaches this wall
                q = tx * x + ty * y - ta
                for dn, i, td in front:
                    if dn <= least:
                        break  # nor any after it: n.d only gets smaller
                    k = p / dn
                    t = k - radius
                    if t < 0.0 or t >= hits[i]:
                        continue
                    along = q + k * td
                    if 0.0 <= along <= length:
                        hits[i] = t
                        signal = v[46 + i] = trunc(4095 * (1.0 - t / LIGHT_BUMP_RANGE_MM) ** 2)
                        if signal >= LIGHT_BUMP_THRESHOLD:
                            bits |= 1 << i
                        else:
                            bits &= ~(1 << i)
        self._rays_on = True
        return bits

    def _sense_wall(self, x: float, y: float, theta: float, close_lines: tuple[_Line, ...]) -> None:
        """The wall sensor (packets 8, 27): a ray right of the heading (through the centre,
        started on the bumper: near enough to the real sensor at -60 deg, looking right)
        against the close walls, with the light bumper's arithmetic (:meth:`_sense_rays`)."""
        c, s = math.sin(theta), -math.cos(theta)
        hit = WALL_SENSOR_RANGE_MM
        for nx, ny, w, tx, ty, ta, length, _, _ in close_lines:
            p = w - (nx * x + ny * y)
            if p < 0.0:
                nx, ny, p = -nx, -ny, -p
            dn = nx * c + ny * s
            if dn <= p / _RAY_REACH:
                continue
            k = p / dn
            t = k - ROBOT_RADIUS_MM
            if t < 0.0 or t >= hit:
                continue
            q = tx * x + ty * y - ta
            along = q + k * (tx * c + ty * s)
            if 0.0 <= along <= length:
                hit = t
        v = self.values
        if hit < WALL_SENSOR_RANGE_MM:
            top = self.profile.wall_signal_maximum
            v[27] = trunc(top * (1.0 - hit / WALL_SENSOR_RANGE_MM) ** 2)
            v[8] = 1 if hit < WALL_SENSOR_TRIGGER_MM else 0
        else:
            v[27] = v[8] = 0
        self._rays_on = True

    def _bumps_changed(self, bumps: int) -> None:
        """Packet 7 changed: mark a new bump and a new wheel drop."""
        if bumps & BUMP_BITS and not self._prev_bumps & BUMP_BITS:
            self.event("bump", _BUMP_SIDES[bumps & BUMP_BITS])
        if bumps & WHEEL_DROP_BITS and not self._prev_bumps & WHEEL_DROP_BITS:
            self.event("wheel_drop", "")
        self._prev_bumps = bumps
        self._check_safety()

    def _check_safety(self) -> None:
        """A wheel drop, a cliff, the dock's contacts or the wall charger's plug changed
        (packet 7, 9-12, 34)."""
        self._safety_due = bool(
            self._prev_bumps & WHEEL_DROP_BITS
            or self._prev_cliffs
            or self.docked
            or self.plugged_in
        )

    def _cliffs_over_drops(self, x: float, y: float, theta: float) -> int:
        """Bits of the cliff sensors over a drop (left 1, front left 2, front right 4, right 8)."""
        cliffs = 0
        for i, a in enumerate(_CLIFF_ANGLES):
            px = x + CLIFF_SENSOR_RADIUS_MM * math.cos(theta + a)
            py = y + CLIFF_SENSOR_RADIUS_MM * math.sin(theta + a)
            if self._over_drop(px, py):
                cliffs |= 1 << i
        return cliffs

    def _cliffs_changed(self, cliffs: int) -> None:
        """The cliff bits (9-12) and signals (28-31); a new cliff is marked."""
        v = self.values
        for i in range(4):
            hit = cliffs >> i & 1
            v[9 + i] = hit
            v[28 + i] = CLIFF_DROP_SIGNAL if hit else CLIFF_FLOOR_SIGNAL
        if cliffs and not self._prev_cliffs:
            self.event("cliff", f"{cliffs:04b}")
        self._prev_cliffs = cliffs
        self._check_safety()

    # Over 60 lines on purpose: one pass over the near walls gives the bumps, the rays' walls
    # and the clearances that let the next steps skip this pass; split, it would walk twice.
    def _sense_walls(self, x: float, y: float, theta: float) -> int:
        """The bumper bits from walls touching the robot at (``x``, ``y``, ``theta``); the
        walls close enough for the light bumper's rays (``_walls_lines``); how far the robot
        is from every wall (``_clearance``), and how far it may move from here before either
        could change (``_walls_same2``: :meth:`_sense` measures them again only beyond it)."""
        nx, ny = self._near_at
        dx, dy = x - nx, y - ny
        near = self._near if dx * dx + dy * dy <= _NEAR_MARGIN2 else self._near_segments()
        bumps = 0
        reach2 = _REACH2
        contact2 = _CONTACT2
        # the walls beyond the near set are farther than it guarantees
        nearest2 = outside2 = _NEAREST2
        inside2 = 0.0
        close_lines: list[_Line] = []
        for ax, ay, ex, ey, length2, line, _ in near:
            t = ((x - ax) * ex + (y - ay) * ey) / length2
            t = 0.0 if t < 0.0 else 1.0 if t > 1.0 else t
            cx, cy = ax + t * ex, ay + t * ey
            dx, dy = x - cx, y - cy
            d2 = dx * dx + dy * dy
            if d2 < nearest2:
                nearest2 = d2
            if d2 < reach2:
                close_lines.append(line)
                if d2 > inside2:
                    inside2 = d2
                if d2 < contact2:
                    a = wrap_angle(math.atan2(cy - y, cx - x) - theta)
                    if -BUMP_HALF_SPAN < a < BUMP_HALF_SPAN:
                        if a > BUMP_CENTRE_ANGLE:
                            bumps |= 2
                        elif a < -BUMP_CENTRE_ANGLE:
                            bumps |= 1
                        else:
                            bumps |= 3
            elif d2 < outside2:
                outside2 = d2
        nearest = math.sqrt(nearest2)
        # how far the robot can move before a wall could stop it (the _move fast path)
        clearance = self._clearance = nearest - ROBOT_RADIUS_MM - 1.0
        self._walls_at = (x, y)
        self._walls_lines = tuple(close_lines)
        # A point's distance to a wall changes by at most the distance the point moves: no
        # wall comes within _QUIET_CONTACT, none enters or leaves the rays' reach, closer.
        # (The least of the three by comparisons, as min() takes it: min() parses keywords,
        # about 1,500 instructions a call.)
        same = nearest - _QUIET_CONTACT
        entering = math.sqrt(outside2) - _REACH
        if entering < same:
            same = entering
        leaving = _REACH - math.sqrt(inside2)
        if leaving < same:
            same = leaving
        beams = self._beams
        if beams is not None:  # nor come onto the dock's contacts
            ex, ey = x - beams.target_x, y - beams.target_y
            contacts = math.sqrt(ex * ex + ey * ey) - beams.contact
            if contacts < same:
                same = contacts
        same -= _SAME_MARGIN
        if same > 0.0:
            self._walls_same2 = same * same
            # the clearance anywhere within the circle: 10.5 mm at least (see _QUIET_CONTACT),
            # more than a step's travel, which is all the _move fast path asks of it
            self._walls_clear = clearance - same
        else:
            self._walls_same2 = 0.0
        return bumps

    def _exact_clearance(self) -> float:
        """The clearance at the pose now (``_clearance`` may be a bound below it)."""
        self._sense_walls(self.x, self.y, self.theta)
        return self._clearance

    def _near_segments(self) -> tuple[_Wall, ...]:
        """The walls within reach of any sensor, kept until the robot has moved 0.3 m."""
        nx, ny = self._near_at
        dx, dy = self.x - nx, self.y - ny
        if dx * dx + dy * dy > _NEAR_MARGIN2:
            limit = _NEAR_RADIUS_MM**2
            x, y = self.x, self.y
            self._near = tuple(w for w in self._walls if closest_point(x, y, w[6])[2] < limit)
            self._near_at = (x, y)
        return self._near

    def _over_drop(self, x: float, y: float) -> bool:
        return any(point_in_polygon(x, y, drop) for drop in self._drops)

    def _wheel_over_drop(self) -> bool:
        """Is a drive wheel's whole tyre over a drop (its inner edge, half the wheel base less
        :data:`WHEEL_HALF_WIDTH_MM` either side of the centre, on the axle)? A tyre partly over
        an edge still rests on the floor. The robot rests on its two wheels and the front caster: a
        wheel past the edge tips it over, whatever the mode and whichever way it moved. The
        centre need not be over it: a robot driving along an edge falls when its outer wheel
        leaves the floor."""
        half_base = self.profile.wheel_base_mm / 2.0 - WHEEL_HALF_WIDTH_MM
        x, y, theta = self.x, self.y, self.theta
        across_x, across_y = -half_base * math.sin(theta), half_base * math.cos(theta)
        return self._over_drop(x + across_x, y + across_y) or self._over_drop(
            x - across_x, y - across_y
        )

    def _sense_ir(self, x: float, y: float, theta: float, ticks: int, powered: bool) -> None:
        """The IR receivers at the pose (``x``, ``y``, ``theta``) of step ``ticks``, the
        dock ``powered`` or not. A character takes tens of milliseconds to send, so they are
        updated every other step (30 ms), and at once when the world changes. Not called
        within the quiet circle (:meth:`_ir_quiet_circle`): nothing seen there, as where it
        was measured (:meth:`_sense` tests the circle before the call; a measure owed is taken
        wherever the robot is)."""
        v = self.values
        c, s = math.cos(theta), math.sin(theta)
        omni_x, omni_y = x + OMNI_FORWARD_MM * c, y + OMNI_FORWARD_MM * s
        omni = left = right = 0
        near = False  # the omni receiver within the beams' reach
        beams = self._beams
        if beams is not None:
            dx, dy = omni_x - beams.x, omni_y - beams.y
            near = dx * dx + dy * dy < beams.reach2
            if near and powered:
                character = beams.character
                omni = character(omni_x, omni_y)
                fx = x + RECEIVER_FORWARD_MM * c
                fy = y + RECEIVER_FORWARD_MM * s
                # Fields of view are cones from the robot's centre (the receivers sit close
                # together on the bumper); which beams each sees depends on where it is.
                bearing = (math.atan2(beams.y - y, beams.x - x) - theta + _PI) % _TWO_PI - _PI
                if -RECEIVER_INNER <= bearing <= RECEIVER_OUTER:
                    left = character(fx - RECEIVER_SIDE_MM * s, fy + RECEIVER_SIDE_MM * c)
                if -RECEIVER_OUTER <= bearing <= RECEIVER_INNER:
                    right = character(fx + RECEIVER_SIDE_MM * s, fy - RECEIVER_SIDE_MM * c)
        wall = 0
        world = self.world
        if world.virtual_walls or world.lighthouses:
            for vw in world.virtual_walls:
                if self._in_beam(omni_x, omni_y, vw.segment, vw.half_width, vw.halo):
                    wall = VIRTUAL_WALL_CHARACTER
                    break
            if not wall:
                for lh in world.lighthouses:
                    if self._in_beam(omni_x, omni_y, lh.fence_segment, lh.half_width, 0.0):
                        wall = lighthouse_character(lh.id, LighthouseBeam.FENCE)
                        break
                    ddx, ddy = omni_x - lh.x, omni_y - lh.y
                    if ddx * ddx + ddy * ddy <= lh.halo * lh.halo:
                        wall = lighthouse_character(lh.id, LighthouseBeam.FORCE_FIELD)
                        break
        v[13] = 1 if wall == VIRTUAL_WALL_CHARACTER else 0
        if wall and (not omni or ticks & 2):  # both seen: they alternate
            omni = wall
        v[17] = omni
        v[52] = left
        v[53] = right
        if self._ir_beamless:
            if near:  # the centre within OMNI_FORWARD_MM more: no quiet circle (0)
                self._ir_quiet2 = 0.0
            else:
                self._ir_quiet_circle(x, y)

    def _ir_quiet_circle(self, x: float, y: float) -> None:
        """How far the robot may move from (``x``, ``y``) with every IR receiver beyond the
        dock's beams (a world with no virtual wall nor lighthouse): :meth:`_sense_ir` need not
        look again within it. The receivers see a beam only while the omni receiver is within
        the beams' reach, and it is OMNI_FORWARD_MM from the centre: its distance to the dock
        changes no more than the robot moves."""
        beams = self._beams
        if beams is None:
            quiet = math.inf
        else:
            dx, dy = x - beams.x, y - beams.y
            quiet = math.sqrt(dx * dx + dy * dy) - OMNI_FORWARD_MM - beams.reach - _SAME_MARGIN
        self._ir_quiet_at = (x, y)
        self._ir_quiet2 = quiet * quiet if quiet > 0.0 else 0.0

    @staticmethod
    def _in_beam(px: float, py: float, seg: Segment, half_width: float, halo: float) -> bool:
        if halo:
            dx, dy = px - seg[0], py - seg[1]
            if dx * dx + dy * dy <= halo * halo:
                return True
        return closest_point(px, py, seg)[2] <= half_width * half_width
