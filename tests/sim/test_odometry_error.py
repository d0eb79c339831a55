"""The encoders' error (``Faults.odometry_error``): off by default (the counts are exact), on
it scales each wheel's counts and drifts the heading, seeded; the true pose never changes."""

from __future__ import annotations

import itertools
import math

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.odometry import MM_PER_COUNT, encoder_delta
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.interface import Odometry
from roomba_bt.sim import Faults
from roomba_bt.sim.state import EXACT_ODOMETRY, OdometryError

from .helpers import make

BIG = """
rooms: [[[-50, -50], [50, -50], [50, 50], [-50, 50]]]
robot: {start: {at: [0, 0], heading: 0}}
"""


def _drive(faults: Faults | None, seed: int, *commands: tuple[bytes, float]) -> tuple:  # type: ignore[type-arg]
    """Drive the commands (bytes, seconds) streaming the encoders: (true pose, odometry,
    sum of packet 19, sum of packet 20)."""
    host = make(BIG, mode="full", faults=faults, seed=seed)
    host.stream([43, 44, 19, 20])
    frames = []
    for command, seconds in commands:
        host.send(command)
        frames += host.frames(seconds)
    odometry = Odometry()
    for frame in frames:
        odometry = odometry.advance(frame[43], frame[44], CREATE2.wheel_base_mm)
    sim = host.sim
    return (
        (sim.x, sim.y, sim.theta),
        odometry,
        sum(f[19] for f in frames),
        sum(f[20] for f in frames),
    )


def test_off_by_default_and_at_zero_the_counts_are_exact() -> None:
    assert Faults().odometry_error == 0.0
    assert OdometryError.draw(0.0, 7) is EXACT_ODOMETRY
    plan = ((C.drive_direct(200, 200).data, 2.0), (C.drive_direct(150, -150).data, 1.0))
    assert _drive(None, 3, *plan) == _drive(Faults(odometry_error=0.0), 3, *plan)


def test_seeded_and_within_the_fraction() -> None:
    a, b = OdometryError.draw(0.015, 1), OdometryError.draw(0.015, 1)
    assert a == b
    assert OdometryError.draw(0.015, 2) != a
    for seed in range(50):
        e = OdometryError.draw(0.015, seed)
        assert abs(e.left_scale - 1.0) <= 0.015 * 1.1 and abs(e.right_scale - 1.0) <= 0.015 * 1.1
        assert abs(e.drift) <= math.radians(0.015)


def test_on_the_true_path_is_the_same_and_the_counts_are_not() -> None:
    plan = ((C.drive_direct(300, 300).data, 4.0), (C.drive_direct(150, -150).data, 2.0))
    exact_pose, exact_odo, exact_19, _ = _drive(None, 5, *plan)
    pose, odo, distance, _ = _drive(Faults(odometry_error=0.02), 5, *plan)
    assert pose == exact_pose  # the robot moved the same
    error = OdometryError.draw(0.02, 5)
    scale = (error.left_scale + error.right_scale) / 2.0
    assert distance == pytest.approx(exact_19 * scale, abs=3.0)  # packet 19 carries it
    assert odo.distance_mm == pytest.approx(exact_odo.distance_mm * scale, abs=2 * MM_PER_COUNT)
    assert odo != exact_odo


def test_a_straight_line_reads_as_a_curve_and_the_heading_drifts() -> None:
    # 60 s straight: the differential and the drift turn the odometry's heading
    _, odo, _, _ = _drive(Faults(odometry_error=0.02), 11, (C.drive_direct(200, 200).data, 60.0))
    error = OdometryError.draw(0.02, 11)
    half_base = CREATE2.wheel_base_mm / 2.0
    travelled = 200.0 * 60.0
    expected = (
        travelled * (error.right_scale - error.left_scale) / (2 * half_base) + error.drift * 60.0
    )
    assert odo.theta_rad == pytest.approx(expected, abs=math.radians(0.5))
    assert abs(odo.theta_rad) > math.radians(0.5)


def test_blocked_wheels_count_with_the_same_error() -> None:
    wall = """
rooms: [[[0, 0], [2, 0], [2, 2], [0, 2]]]
robot: {start: {at: [1.5, 1], heading: 0}}
"""
    host = make(wall, mode="full", faults=Faults(odometry_error=0.02), seed=4)
    host.stream([43, 44])
    host.send(C.drive_direct(200, 200))
    frames = host.frames(4.0)  # 0.33 m to the wall, then pushing against it
    counts = sum(encoder_delta(a[43], b[43]) for a, b in itertools.pairwise(frames))
    error = OdometryError.draw(0.02, 4)
    travelled = host.sim.x - 1500.0
    assert counts * MM_PER_COUNT == pytest.approx(travelled * error.left_scale, abs=8.0)
