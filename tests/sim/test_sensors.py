"""Sensors from geometry: bumpers, light bumpers, wall sensor, cliffs, wheel drops, virtual
walls and lighthouses. The robot never passes through a wall."""

from __future__ import annotations

import math
import random

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.ir import IRSource, LighthouseBeam
from roomba_bt.sim import Pose, Simulator
from roomba_bt.sim.sensing import _RAY_REACH, _RAY_TURNS, FAR_PACKETS
from roomba_bt.sim.world import ROBOT_RADIUS_MM

from .helpers import box_with_a_drop, make, pose

ROOM = """
rooms: [[[0, 0], [2, 0], [2, 2], [0, 2]]]
robot: {start: {at: [1, 1], heading: 0}}
"""


def test_the_robot_stops_on_contact_and_never_passes_through_a_wall() -> None:
    host = make(ROOM, mode="full")
    host.send(C.drive_direct(500, 500))
    host.run(5.0)
    assert host.sim.x == pytest.approx(2000.0 - ROBOT_RADIUS_MM, abs=0.5)
    assert host.sim.x <= 2000.0 - ROBOT_RADIUS_MM
    assert host.query([7]).bumps.bump_left and host.query([7]).bumps.bump_right


@pytest.mark.parametrize(
    ("heading", "left", "right"),
    [(0, True, True), (-40, True, False), (40, False, True), (180, False, False)],
)
def test_bumper_side_comes_from_the_contact_angle(heading: float, left: bool, right: bool) -> None:
    # touching the east wall; the contact is at -heading from the robot's nose
    host = make(ROOM, start=pose(2.0 - 0.1705, 1.0, heading), mode="full")
    bumps = host.query([7]).bumps
    assert (bumps.bump_left, bumps.bump_right) == (left, right)
    assert any(e.kind == "bump" for e in host.sim.events) == (left or right)


def test_driving_away_from_a_wall_is_never_blocked() -> None:
    host = make(ROOM, start=pose(2.0 - 0.1705, 1.0, 0), mode="full")
    host.send(C.drive_direct(-200, -200))
    host.run(0.5)
    assert host.sim.x < 1800.0
    assert host.query([7])[7] == 0


def test_a_bump_event_on_the_timeline_presses_the_bumper() -> None:
    host = make(ROOM + "events: [{at: 0.3, kind: bump, side: right, duration: 0.3}]\n")
    host.stream([7])
    frames = host.frames(1.0)
    assert frames[10][7] == 0 and frames[25][7] == 1 and frames[50][7] == 0


def test_light_bumpers_grow_as_the_wall_gets_closer() -> None:
    signals = []
    for gap in (0.14, 0.10, 0.05, 0.01):
        host = make(ROOM, start=pose(2.0 - 0.17 - gap, 1.0, 0))
        reply = host.query([45, 46, 47, 48, 49, 50, 51])
        signals.append(reply.light_bump_signals)
    centre = [s[2] for s in signals]
    assert centre == sorted(centre) and centre[0] < centre[-1]
    far = make(ROOM, start=pose(1.0, 1.0, 0)).query([45, 48])
    assert far[45] == 0 and far[48] == 0
    near = make(ROOM, start=pose(2.0 - 0.17 - 0.03, 1.0, 0)).query([45])
    assert near.light_bumper.center_left and near.light_bumper.center_right


def test_light_bumpers_see_the_side_the_wall_is_on() -> None:
    # wall 3 cm away on the robot's left (north wall, robot heading east)
    host = make(ROOM, start=pose(1.0, 2.0 - 0.2, 0))
    reply = host.query([45, 46, 51])
    assert reply.light_bumper.left and not reply.light_bumper.right
    assert reply[46] > 0 and reply[51] == 0


def test_wall_sensor_sees_a_wall_close_on_the_right() -> None:
    host = make(ROOM, start=pose(1.0, 0.19, 0))  # south wall 2 cm from the right side
    reply = host.query([8, 27])
    assert reply.wall and reply.wall_signal > 0
    host = make(ROOM, start=pose(1.0, 2.0 - 0.19, 0))  # wall on the left: not the wall sensor
    assert host.query([8, 27])[27] == 0


RAY_PACKETS = [8, 27, 45, 46, 47, 48, 49, 50, 51]


@pytest.mark.parametrize(
    "wheels", [(100, -100), (150, 150), (160, 60)], ids=["spin", "straight", "arc"]
)
def test_the_rays_of_a_moving_robot_are_those_of_a_robot_placed_where_it_is(
    wheels: tuple[int, int],
) -> None:
    # the rays' directions are kept while the heading stays the same (sensing.py): spinning,
    # driving straight along a wall and arcing into a corner, every step's light bumper and
    # wall sensor read what a robot built at that pose reads
    host = make(ROOM, start=pose(2.0 - 0.25, 0.22, 60), mode="full")
    host.send(C.drive_direct(*wheels))
    seen = set()
    for _ in range(40):
        host.sim.step()
        moving = host.query(RAY_PACKETS)
        placed = make(ROOM, start=host.sim.pose, mode="full").query(RAY_PACKETS)
        assert [moving[p] for p in RAY_PACKETS] == [placed[p] for p in RAY_PACKETS]
        seen.add(tuple(moving[p] for p in RAY_PACKETS))
    assert len(seen) > 10  # the signals changed as the robot moved


DOCK_ROOM = """
rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]
dock: {at: [1.5, 0], facing: 90}
virtual_walls: [{from: [0.3, 1.2], to: [0.3, 2.8]}]
robot: {start: {at: [1.5, 0.22], heading: 0}}
events: [{at: 3.0, kind: charger_step, duration: 1.0}]
"""


def test_far_sensors_not_streamed_read_as_if_measured_every_step() -> None:
    # Not streamed, the light bumper, wall sensor and IR receivers are measured when read,
    # from the pose and step they were due at (sensing.py): a robot streaming only its
    # bumper answers every query, on odd and even steps, as one streaming them all; and a
    # stream of them started later sends the same frames from its first. The robot circles
    # the room 0.22 m from its walls, past the dock, its beams and a virtual wall, and back.
    far = sorted(FAR_PACKETS)
    lazy, eager = make(DOCK_ROOM, mode="full"), make(DOCK_ROOM, mode="full")
    lazy.stream([7])
    eager.stream([7, *far])
    for host in (lazy, eager):
        host.send(C.drive(400, 1280))
    seen = set()
    for step in range(1400):  # even: the first frame below is on an odd step, without IR
        for host in (lazy, eager):
            host.sim.step()
            host.sim.read()
        # every odd step (often the IR receivers owed since the step before) and every
        # third even one; none in the last 100 steps, back into the dock's beams
        if step < 1300 and (step % 2 == 0 or step % 6 == 1):
            owed = lazy.query(far)
            measured = eager.query(far)
            assert [owed[p] for p in far] == [measured[p] for p in far], step
            seen.add(tuple(owed[p] for p in far))
    assert len(seen) > 30 and len({values[far.index(17)] for values in seen}) > 2
    for host in (lazy, eager):
        host.stream(far)
    assert lazy.frames(0.3) == eager.frames(0.3)


def test_the_wall_sensor_not_streamed_beside_the_light_bumper_reads_as_if_measured() -> None:
    # The far sensors are owed by group (sensing.py): a stream of the light bumper alone
    # (a dock mission's) measures its rays every step and owes the wall sensor's, measured
    # when asked for. Arcing along and into the walls, every query of the wall sensor (and
    # the light bumper's frames) must be what a robot streaming both reads.
    light = [45, 46, 47, 48, 49, 50, 51]
    lazy, eager = make(ROOM, mode="full"), make(ROOM, mode="full")
    lazy.stream([7, *light])
    eager.stream([7, 8, 27, *light])
    for host in (lazy, eager):
        host.send(C.drive(300, 900))
    seen = set()
    for step in range(900):
        for host in (lazy, eager):
            host.sim.step()
            host.sim.read()
        assert [lazy.sim.values[p] for p in light] == [eager.sim.values[p] for p in light]
        if step % 3 == 0:
            owed, measured = lazy.query([8, 27]), eager.query([8, 27])
            assert (owed[8], owed[27]) == (measured[8], measured[27]), step
            seen.add((owed[8], owed[27]))
    assert len(seen) > 20  # the wall sensor saw the walls come and go


def test_a_builtin_cycle_reads_far_sensors_measured_as_it_starts() -> None:
    # the light bumper owed while nothing streamed it is measured when Clean starts: its
    # first step sees the wall ahead (and backs off) as a robot streaming it does
    lazy, eager = make(ROOM), make(ROOM)
    lazy.stream([7])
    eager.stream([7, 45, 46, 47, 48, 49, 50, 51])
    for host in (lazy, eager):
        host.send(C.drive_direct(200, 200))
        host.run(3.6)  # 0.11 m from the east wall: the light bumper sees it
        host.send(C.clean())
        host.run(0.3)
    assert eager.sim.x < 2000.0 - 170.0 - 110.0 - 30.0  # backed off at once
    assert lazy.sim.pose == eager.sim.pose


CLIFFS = box_with_a_drop(2.0, start=(1, 1))


@pytest.mark.parametrize(
    ("heading", "expected"),
    [(0, (0, 1, 1, 0)), (90, (0, 0, 0, 1)), (-90, (1, 0, 0, 0)), (180, (0, 0, 0, 0))],
)
def test_cliff_sensors_see_the_drop_they_are_over(
    heading: float, expected: tuple[int, int, int, int]
) -> None:
    # the drop begins at x = 2 m, 0.1 m from the robot's centre; the cliff sensors sit
    # 0.15 m from the centre at 60 and 20 deg left and right of the heading
    host = make(CLIFFS, start=pose(1.9, 2.0, heading), mode="full")
    reply = host.query([9, 10, 11, 12, 28, 29, 30, 31])
    assert (reply[9], reply[10], reply[11], reply[12]) == expected
    for flag, signal in zip(expected, reply.cliff_signals, strict=True):
        assert (signal < 100) == bool(flag)


def test_lifting_the_robot_drops_both_wheels_and_all_cliffs_and_stops_it() -> None:
    text = ROOM + "events: [{at: 0.3, kind: lift, duration: 1.0}]\n"
    host = make(text, mode="full")
    host.send(C.drive_direct(100, 100))
    host.run(0.6)
    x = host.sim.x
    reply = host.query([7, 9, 10, 11, 12, 43])
    assert reply.bumps.wheel_drop_left and reply.bumps.wheel_drop_right and reply.any_cliff
    host.run(0.3)
    assert host.sim.x == x
    assert host.query([43])[43] > reply[43]  # the wheels spin in the air
    host.run(1.0)
    assert host.query([7])[7] == 0


VIRTUAL = """
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
virtual_walls: [{from: [2, 0.5], to: [2, 3.5], halo: 0.3}]
lighthouses: [{id: 3, at: [0.5, 3.5], heading: 0, fence: 1.0, halo: 0.3}]
robot: {start: {at: [1, 1], heading: 0}}
"""


def test_virtual_wall_beam_gives_packet_13_and_character_162() -> None:
    # the omni receiver is 0.13 m ahead of the centre
    inside = make(VIRTUAL, start=pose(2.0 - 0.13, 2.0, 0)).query([13, 17])
    assert inside.virtual_wall and inside.ir_omni.source is IRSource.VIRTUAL_WALL
    outside = make(VIRTUAL, start=pose(1.5, 2.0, 0)).query([13, 17])
    assert not outside.virtual_wall and outside[17] == 0
    halo = make(VIRTUAL, start=pose(2.2 - 0.13, 0.3, 0)).query([13])
    assert halo.virtual_wall


def test_lighthouse_fence_and_force_field_characters() -> None:
    fence = make(VIRTUAL, start=pose(1.2 - 0.13, 3.5, 0)).query([13, 17])
    assert fence.ir_omni.lighthouse_id == 3
    assert fence.ir_omni.lighthouse_beam is LighthouseBeam.FENCE
    assert not fence.virtual_wall  # packet 13 is the virtual wall's, not the lighthouse's
    halo = make(VIRTUAL, start=pose(0.5, 3.1, 90)).query([17])
    assert halo.ir_omni.lighthouse_beam is LighthouseBeam.FORCE_FIELD


@pytest.mark.parametrize(
    ("room", "start"),
    [
        (ROOM + "dock: {at: [1, 0], facing: 90}\n", (0.6, 0.5, 20)),
        (  # a large room: in and out of the dock's beams
            "rooms: [[[0, 0], [5, 0], [5, 5], [0, 5]]]\n"
            "robot: {start: {at: [1, 1], heading: 0}}\n"
            "dock: {at: [2.5, 0], facing: 90}\n",
            (1.0, 3.0, -60),
        ),
    ],
)
@pytest.mark.parametrize("wheels", [(300, 300), (200, 120), (-150, 150), (480, 350)])
def test_a_moving_robot_reports_what_a_robot_placed_at_its_pose_measures(
    room: str, start: tuple[float, float, float], wheels: tuple[int, int]
) -> None:
    # The walls are measured again only once the robot may have moved far enough for what
    # they show to change, the IR receivers only once it may have come within the dock's
    # beams (sensing.py): every step, the sensors must be those a robot built at that pose
    # measures from scratch (the IR's, every other step, when they are measured). Driving
    # about a room with a dock, along and into walls, in and out of the light bumper's reach.
    host = make(room, start=pose(*start), mode="full")
    sim = host.sim
    host.send(C.drive_direct(*wheels))
    near = (7, 8, 27, 45, 46, 47, 48, 49, 50, 51)
    ir = (13, 17, 52, 53)
    for _ in range(900):
        sim.step()
        sim._settle_far()  # as a reply of them would
        fresh = Simulator(sim.world, start=Pose(sim.x, sim.y, sim.theta))
        assert [sim.values[p] for p in near] == [fresh.values[p] for p in near]
        if not sim.ticks & 1:
            assert [sim.values[p] for p in ir] == [fresh.values[p] for p in ir]
        assert sim.docked == fresh.docked
        assert sim._clearance <= fresh._clearance


#: posts on both sides of a straight path: walls come within the rays' reach and leave it
#: while the heading stays the same
POSTS = """
rooms: [[[0, 0], [6, 0], [6, 2], [0, 2]]]
obstacles:
  - {rect: [1.0, 0.05, 1.1, 0.25]}
  - {rect: [1.6, 0.66, 1.75, 0.85]}
  - {rect: [2.3, 0.1, 2.6, 0.24]}
  - {polygon: [[3.1, 0.64], [3.4, 0.7], [3.2, 0.9]]}
"""


@pytest.mark.parametrize("wheels", [(300, 300), (500, 500), (-200, -200)])
def test_driving_straight_past_walls_the_rays_see_what_a_robot_placed_there_sees(
    wheels: tuple[int, int],
) -> None:
    # Driving straight, the rays' table of which may meet each close wall is kept from one
    # step to the next (sensing.py, _facing_walls): it must be made again when other walls
    # come within reach at the same heading, and give every step what a robot built at
    # that pose measures from scratch.
    start = pose(0.4, 0.45, 0) if wheels[0] > 0 else pose(3.9, 0.45, 0)
    host = make(POSTS, start=start, mode="full")
    sim = host.sim
    host.send(C.drive_direct(*wheels))
    near = (7, 8, 27, 45, 46, 47, 48, 49, 50, 51)
    seen = set()
    for _ in range(700):
        sim.step()
        sim._settle_far()
        fresh = Simulator(sim.world, start=Pose(sim.x, sim.y, sim.theta))
        measured = [sim.values[p] for p in near]
        assert measured == [fresh.values[p] for p in near]
        seen.add(tuple(measured))
    assert sim.theta == 0.0  # straight all the way
    assert len(seen) > 50  # the posts came into the rays' view and went


def _every_ray_against_every_wall(sim: Simulator) -> list[int]:
    """Packets 8, 27 and 45-51 as the turning robot measured them before the rays were
    chosen by angle (sensing.py): every ray against every close wall, with the same
    arithmetic, so the same bits."""
    x, y, theta = sim.x, sim.y, sim.theta
    ct, st = math.cos(theta), math.sin(theta)
    hits = [150.0] * 6 + [120.0]
    lit = set()
    for nx, ny, w, tx, ty, ta, length, _, _ in sim._walls_lines:
        p = w - (nx * x + ny * y)
        q = tx * x + ty * y - ta
        if p < 0.0:
            nx, ny, p = -nx, -ny, -p
        least = p / _RAY_REACH
        for i, ca, sa in _RAY_TURNS:
            c = ct * ca - st * sa
            s = st * ca + ct * sa
            dn = nx * c + ny * s
            if dn <= least:
                continue
            k = p / dn
            t = k - ROBOT_RADIUS_MM
            if 0.0 <= t < hits[i] and 0.0 <= q + k * (tx * c + ty * s) <= length:
                hits[i] = t
                lit.add(i)
    signals = [int(4095 * (1.0 - hits[i] / 150.0) ** 2) if i in lit else 0 for i in range(6)]
    bits = sum(1 << i for i, signal in enumerate(signals) if signal >= 100)
    wall = 0
    if 6 in lit:
        wall = int(sim.profile.wall_signal_maximum * (1.0 - hits[6] / 120.0) ** 2)
    return [1 if 6 in lit and hits[6] < 50.0 else 0, wall, bits, *signals]


#: walls at every angle, thin ones seen from both sides, corners: the rays meet them at
#: grazing angles and head on
ANGLES = """
rooms: [[[0, 0], [3, 0], [3.4, 1.2], [2.2, 2.6], [0.3, 2.2]]]
obstacles:
  - {polygon: [[1.0, 0.8], [1.4, 0.7], [1.2, 1.1]]}
  - {polygon: [[2.0, 1.0], [2.02, 1.5], [2.01, 1.0]]}
  - {rect: [0.6, 1.5, 0.9, 1.55]}
"""


def test_turning_rays_chosen_by_angle_are_those_every_ray_against_every_wall_gives() -> None:
    # Turning, the rays looked at for each close wall are those within an angle of its
    # normal (sensing.py, _ARC): at thousands of poses near walls, at every heading (and
    # about the -pi/pi seam), the light bumper and wall sensor read what every ray against
    # every close wall reads.
    rng = random.Random(18)
    sim = make(ANGLES, mode="full").sim
    seen = set()
    for n in range(6000):
        theta = math.pi - rng.random() * 1e-3 if n % 10 == 0 else rng.uniform(-math.pi, math.pi)
        sim.x, sim.y = rng.uniform(0.0, 3400.0), rng.uniform(0.0, 2600.0)
        sim.theta = -theta if n % 20 == 0 else theta
        sim._walls_same2 = 0.0  # the walls measured again here
        sim._rays_theta = math.nan  # turning
        sim._sense()
        measured = [sim.values[p] for p in RAY_PACKETS]
        assert measured == _every_ray_against_every_wall(sim), (sim.x, sim.y, sim.theta)
        seen.add(tuple(measured))
    assert len(seen) > 2000  # the rays met walls in every way
