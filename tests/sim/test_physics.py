"""Differential drive on 15 ms steps: radius semantics, speed steps, encoders, odometry
packets, requested-velocity echo, stasis, currents and the battery."""

from __future__ import annotations

import itertools
import math

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.bits import ChargingState, motor_bits
from roomba_bt.oi.encode import Command, Radius
from roomba_bt.oi.odometry import (
    MM_PER_COUNT,
    OLD_FIRMWARE_ANGLE_FACTOR,
    WHEEL_SPEED_STEP_MM_S,
    encoder_delta,
)
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600
from roomba_bt.sim import Pose, drive_wheel_speeds
from roomba_bt.sim.state import STEP_SECONDS

from .helpers import docked_start, make

BIG = """
rooms: [[[-50, -50], [50, -50], [50, 50], [-50, 50]]]
robot: {start: {at: [0, 0], heading: 0}}
"""


def heading_change(command: bytes, seconds: float = 1.0) -> tuple[float, float, float]:
    host = make(BIG, mode="full")
    host.send(command)
    host.run(seconds)
    return host.sim.x, host.sim.y, math.degrees(host.sim.theta)


def test_positive_radius_turns_left_negative_right() -> None:
    _x, y, theta = heading_change(C.drive(200, 500).data)
    assert theta > 15 and y > 0
    _x, y, theta = heading_change(C.drive(200, -500).data)
    assert theta < -15 and y < 0


@pytest.mark.parametrize("radius", [Radius.STRAIGHT, Radius.STRAIGHT_ALT])
def test_special_radii_drive_straight(radius: Radius) -> None:
    x, y, theta = heading_change(C.drive(200, radius).data)
    assert theta == 0.0 and y == 0.0 and x > 150


def test_radius_2000_is_an_arc_not_straight() -> None:
    # [137, 0, 200, 7, 208]: a peer sends this for "straight" and drives a 2 m arc
    _x, _y, theta = heading_change(bytes([137, 0, 200, 7, 208]), 3.0)
    assert theta > 10


def test_spin_radii_turn_in_place() -> None:
    x, y, theta = heading_change(C.spin(200, clockwise=True).data)
    assert abs(x) < 1e-9 and abs(y) < 1e-9 and theta < -40
    x, y, theta = heading_change(C.spin(200, clockwise=False).data)
    assert abs(x) < 1e-9 and theta > 40


def test_drive_radius_geometry() -> None:
    left, right = drive_wheel_speeds(200, 500, 235.0)
    assert (left + right) / 2 == pytest.approx(200)
    assert (right - left) / 235.0 == pytest.approx(200 / 500)
    assert drive_wheel_speeds(-200, -1, 235.0) == (-200.0, 200.0)
    assert drive_wheel_speeds(600, 32767, 235.0) == (500.0, 500.0)


def test_drive_direct_right_faster_turns_left() -> None:
    _x, _y, theta = heading_change(C.drive_direct(300, 100).data)
    assert theta > 20


def test_drive_pwm_full_scale_is_about_500_mm_s() -> None:
    x, _y, _theta = heading_change(C.drive_pwm(255, 255).data)
    assert x == pytest.approx(500 * 67 * 0.015)  # 1 s is 67 steps of 15 ms


def test_wheel_speeds_move_in_steps_of_28_5_mm_s() -> None:
    host = make(BIG, mode="full")
    host.send(C.drive_direct(10, 10))
    host.run(1.0)
    assert host.sim.x == 0.0  # below half a step: the wheels do not turn
    host.send(C.drive_direct(100, 100))
    host.run(1.0)
    assert host.sim.x == pytest.approx(4 * WHEEL_SPEED_STEP_MM_S * 67 * 0.015)


def test_encoders_count_mm_over_pi_72_over_508_8_and_odometry_agrees() -> None:
    host = make(BIG, mode="full")
    host.stream([43, 44, 19])
    host.send(C.drive_direct(200, 200))
    frames = host.frames(2.0)
    counts = sum(encoder_delta(a[43], b[43]) for a, b in itertools.pairwise(frames))
    travelled = host.sim.x
    before_first_frame = 7 * WHEEL_SPEED_STEP_MM_S * 0.015  # 199.5 mm/s for one step
    assert counts * MM_PER_COUNT == pytest.approx(
        travelled - before_first_frame, abs=2 * MM_PER_COUNT
    )
    assert sum(f[19] for f in frames) == pytest.approx(travelled, abs=1.0)


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600, ROOMBA500], ids=lambda p: p.name)
def test_encoders_roll_over_signed_on_600_unsigned_on_500(profile) -> None:  # type: ignore[no-untyped-def]
    host = make(BIG, profile=profile, mode="full")
    host.stream([43, 44])
    host.send(C.drive_direct(-500, -500))
    frames = host.frames(30.0)  # 15 m backwards: more than 32768 counts
    values = [f[43] for f in frames]
    if profile.encoders_signed:
        assert min(values) < 0 and max(values) > 0 and max(values) <= 32767
    else:
        assert min(values) >= 0 and max(values) <= 65535
    deltas = [encoder_delta(a, b) for a, b in itertools.pairwise(values)]
    assert all(-20 <= d <= 0 for d in deltas)
    assert sum(deltas) * MM_PER_COUNT == pytest.approx(-15000 + 500 * 0.015, abs=20)


def test_distance_and_angle_are_since_last_read() -> None:
    host = make(BIG, mode="full")
    host.send(C.spin(100, clockwise=False))
    host.run(2.0)
    angle = host.query([20])[20]
    assert angle == pytest.approx(math.degrees(host.sim.theta), abs=1)
    assert host.query([20])[20] == 0  # read: reset
    host.send(C.drive_direct(200, 200))
    host.run(1.0)
    assert host.query([19])[19] == pytest.approx(199.5 - 2 * 0.0, abs=4)
    assert host.query([19])[19] == 0


def test_old_firmware_angle_is_scaled_by_0_324056() -> None:
    host = make(BIG, mode="full", old_firmware_angle=True)
    host.send(C.spin(100, clockwise=False))
    host.run(2.0)
    degrees = math.degrees(host.sim.theta)
    raw = host.query([20])[20]
    assert raw == pytest.approx(degrees * OLD_FIRMWARE_ANGLE_FACTOR, abs=1)


def test_requested_velocities_are_echoed_in_39_to_42() -> None:
    host = make(BIG, mode="full")
    host.send(C.drive(-200, 500))
    reply = host.query([39, 40, 41, 42])
    assert reply[39] == -200 and reply[40] == 500
    assert reply[41] < reply[42] < 0  # backwards, turning: the right wheel is faster
    host.send(C.drive(100, Radius.STRAIGHT))
    assert host.query([40])[40] == -32768
    host.send(C.drive_direct(150, -50))
    reply = host.query([39, 41, 42])
    assert (reply[41], reply[42], reply[39]) == (150, -50, 50)


def test_stasis_shows_forward_progress_only_when_moving_freely() -> None:
    text = """
rooms: [[[0, 0], [1, 0], [1, 1], [0, 1]]]
robot: {start: {at: [0.5, 0.5], heading: 0}}
"""
    host = make(text, mode="full")
    assert host.query([58])[58] == 0
    host.send(C.drive_direct(200, 200))
    host.run(0.3)
    assert host.query([58])[58] == 1
    host.run(3.0)  # pushed against the wall
    assert host.query([58, 7])[58] == 0


def test_currents_wheels_brushes_and_overcurrent_when_stalled() -> None:
    text = """
rooms: [[[0, 0], [1, 0], [1, 1], [0, 1]]]
robot: {start: {at: [0.5, 0.5], heading: 0}}
"""
    host = make(text, mode="full")
    idle = host.query([23, 54, 55, 56, 57])
    assert idle[54] == idle[55] == idle[56] == idle[57] == 0
    host.send(C.drive_direct(200, 200), C.motors(motor_bits(main_brush=True, side_brush=True)))
    host.run(0.2)
    moving = host.query([23, 54, 55, 56, 57, 14])
    assert moving[54] > 0 and moving[55] > 0 and moving[56] > 0 and moving[57] > 0
    assert moving[23] < idle[23] < 0
    host.run(3.0)
    stalled = host.query([54, 14])
    assert stalled[54] > moving[54]
    assert stalled.overcurrents.left_wheel and stalled.overcurrents.right_wheel


@pytest.mark.parametrize(
    "command",
    [C.pwm_motors(127, 0, 0), C.pwm_motors(0, -127, 0), C.pwm_motors(51, -38, 64),
     C.pwm_motors(0, 0, 127), C.motors(motor_bits(main_brush=True, vacuum=True))],
    ids=["main brush", "side brush reversed", "gentle", "vacuum", "motors: main and vacuum"],
)  # fmt: skip
def test_the_battery_gives_what_each_motor_draws_in_proportion_to_its_duty_cycle(
    command: Command,
) -> None:
    """PWM Motors (144): the brushes' currents (56, 57) follow the duty cycle, whichever way
    a brush turns, and the battery (23) gives the robot's 150 mA, them and the vacuum's
    (in no packet). Until 0.2.0 it gave 1.6 mA a step of each motor: the main brush alone at
    full power drew 304 mA by packet 56 from a battery that gave it 203."""
    host = make(BIG, mode="full")
    idle = host.query([23])[23]
    host.send(command)
    host.run(0.1)
    now = host.query([23, 54, 55, 56, 57])
    main, side, vacuum = host.sim.brush_pwm
    assert (now[56], now[57]) == (math.trunc(2.4 * abs(main)), math.trunc(0.8 * abs(side)))
    assert now[54] == now[55] == 0  # the wheels stand
    assert idle == -150
    assert now[23] == math.trunc(-(150 + 2.4 * abs(main) + 0.8 * abs(side) + 1.6 * vacuum))
    assert -now[23] >= 150 + now[56] + now[57]


def test_battery_drains_faster_while_moving() -> None:
    still = make(BIG, mode="full")
    moving = make(BIG, mode="full")
    moving.send(C.drive_direct(400, 400))
    still.run(60.0)
    moving.run(60.0)
    start = still.sim.world.battery * 2696
    assert start - moving.sim.battery_charge > start - still.sim.battery_charge > 0
    assert moving.query([25])[25] < still.query([25])[25]


def test_a_new_speed_at_the_same_heading_moves_the_robot_at_that_speed() -> None:
    # A straight drive's travel a step is kept while the heading and the speeds stay
    # (motion.py, _move): a new speed at the same heading must move the robot at it.
    host = make(BIG, start=Pose(0.0, 0.0, math.radians(30.0)), mode="full")
    host.send(C.drive_direct(200, 200))
    host.run(0.3)
    x, y = host.sim.x, host.sim.y
    host.send(C.drive_direct(400, 400))
    host.run(0.3)
    speed = math.hypot(host.sim.x - x, host.sim.y - y) / 0.3
    assert speed == pytest.approx(round(400 / WHEEL_SPEED_STEP_MM_S) * WHEEL_SPEED_STEP_MM_S)
    assert host.sim.theta == math.radians(30.0)


#: a powered dock to charge on (fast, then trickle from 98 %), its charger stepped on, a
#: wall and the dock to stall against, a drop to fall off in Full mode, a lift and a bump
POWER_WORLD = """
rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]
dock: {at: [2, 0], facing: 90}
drops: [{rect: [3.6, 0, 4, 3]}]
robot: {start: {at: [2, 1.2], heading: -90}, battery: 0.9799}
events:
  - {at: 1.5, kind: charger_step, duration: 0.6}
  - {at: 9.0, kind: lift, duration: 0.4}
  - {at: 10.0, kind: bump, side: left, duration: 0.3}
"""

#: (steps, commands sent before them): on the dock in Passive, Safe (the powered charger
#: drops it to Passive), Full: off the dock, brushes, arcs, a spin, into the dock and
#: stalled there, away, a stop, then off the drop
POWER_SCRIPT: list[tuple[int, list[Command]]] = [
    (190, []),
    (20, [C.safe()]),
    (30, [C.full()]),
    (70, [C.drive_direct(-200, -200)]),
    (40, [C.motors(7)]),
    (30, [C.pwm_motors(50, -30, 100)]),
    (60, [C.drive(200, 500)]),
    (50, [C.spin(150, True)]),
    (60, [C.drive_direct(300, 280)]),
    (150, [C.drive_direct(150, 150)]),
    (120, [C.drive_direct(60, 250)]),
    (40, [C.drive_direct(150, 150)]),
    (30, [C.motors_off(), C.drive_direct(0, 0)]),
    (190, [C.drive_pwm(-60, 60)]),
    (500, [C.drive_direct(400, 400)]),
]


def test_the_battery_step_run_only_when_due_gives_what_one_run_every_step_gives() -> None:
    # The battery's step runs only when something the currents depend on changed, every
    # 32nd step and while charging fast; the other steps' charge is owed and taken later
    # (power.py). A robot whose battery step runs every step (as if everything changed)
    # must report the same packets every step and the same charge; and between steps,
    # unless a change is due, the currents are those of the robot's state now (no place
    # that changes what draws them forgets to say so).
    due = make(POWER_WORLD, start=docked_start(), mode="passive")
    every = make(POWER_WORLD, start=docked_start(), mode="passive")
    states = set()
    n = 0
    for steps, commands in POWER_SCRIPT:
        due.send(*commands)
        every.send(*commands)
        for _ in range(steps):
            n += 1
            dt = 0.03 if n % 37 == 0 and n < 190 else STEP_SECONDS  # a longer step now and then
            every.sim._power_due = True
            every.sim.step(dt)
            due.sim.step(dt)
            sim = due.sim
            assert sim.values == every.sim.values, n
            assert (
                sim._power_due or sim._power_key is None or (sim._power_inputs() == sim._power_key)
            ), n
            if n % 50 == 0:
                assert sim.battery_charge == every.sim.battery_charge, n
            states.add((sim.values[21], sim.values[14] != 0, sim.docked, sim.lifted, sim.mode))
    assert due.sim.battery_charge == every.sim.battery_charge
    assert due.sim.fallen
    charging = {state[0] for state in states}
    assert {ChargingState.FULL_CHARGING, ChargingState.TRICKLE_CHARGING, 0} <= charging
    assert any(state[1] for state in states)  # stalled long enough for an overcurrent
    assert {True, False} <= {state[2] for state in states} and any(s[3] for s in states)
