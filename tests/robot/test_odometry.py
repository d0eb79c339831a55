"""Odometry.advance writes out the odometry helpers' arithmetic (a tick-path saving): it must
give exactly the floats the helpers give, wrap-around and standing still included. The
runtime's Odometer reads the counts from the stream's frames and gives what advance gives."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt.oi.frames import SensorFrame, layout_for
from roomba_bt.oi.odometry import WHEEL_BASE_MM, arc_from_wheels, counts_to_mm, encoder_delta
from roomba_bt.oi.profiles import DEFAULT_PROFILE
from roomba_bt.robot.interface import Odometer, Odometry

COUNTS = st.integers(min_value=0, max_value=0xFFFF)
STEP = st.integers(min_value=-40, max_value=40)


def by_the_helpers(odometry: Odometry, left_counts: int, right_counts: int) -> Odometry:
    """One step as the helpers of roomba_bt.oi.odometry compute it."""
    assert odometry.left_counts is not None and odometry.right_counts is not None
    left = counts_to_mm(encoder_delta(odometry.left_counts, left_counts))
    right = counts_to_mm(encoder_delta(odometry.right_counts, right_counts))
    if left == 0.0 and right == 0.0:
        return odometry._replace(left_counts=left_counts, right_counts=right_counts)
    dist, dtheta = arc_from_wheels(left, right, WHEEL_BASE_MM)
    mid = odometry.theta_rad + dtheta / 2.0
    return Odometry(
        odometry.x_mm + dist * math.cos(mid),
        odometry.y_mm + dist * math.sin(mid),
        odometry.theta_rad + dtheta,
        odometry.distance_mm + dist,
        odometry.angle_rad + dtheta,
        left_counts,
        right_counts,
        odometry.path_mm + abs(dist),
    )


@settings(max_examples=200, deadline=None)
@given(COUNTS, COUNTS, st.lists(st.tuples(STEP, STEP), min_size=1, max_size=30))
def test_advance_is_the_helpers_arithmetic(
    left0: int, right0: int, steps: list[tuple[int, int]]
) -> None:
    odometry = expected = Odometry().advance(left0, right0, WHEEL_BASE_MM)
    left, right = left0, right0
    for dl, dr in steps:
        left, right = (left + dl) & 0xFFFF, (right + dr) & 0xFFFF
        odometry = odometry.advance(left, right, WHEEL_BASE_MM)
        expected = by_the_helpers(expected, left, right)
        assert odometry == expected  # exact floats, not approximately


def test_the_first_frame_only_anchors_and_standing_still_keeps_the_same_object() -> None:
    first = Odometry().advance(65530, 3, WHEEL_BASE_MM)
    assert first == Odometry(left_counts=65530, right_counts=3)
    assert first.advance(65530, 3, WHEEL_BASE_MM) is first
    moved = first.advance(4, 3, WHEEL_BASE_MM)  # the left wheel wrapped forward 10 counts
    assert moved.distance_mm == counts_to_mm(10) / 2.0
    assert moved.angle_rad < 0.0  # left wheel ahead: clockwise


@settings(max_examples=100, deadline=None)
@given(COUNTS, COUNTS, st.lists(st.tuples(STEP, STEP), min_size=1, max_size=30))
def test_the_odometer_of_a_stream_is_advance_frame_by_frame(
    left0: int, right0: int, steps: list[tuple[int, int]]
) -> None:
    """The runtime's Odometer, reading the counts from stream frames (with other packets
    around them), gives the odometry Odometry.advance gives for the same counts, and keeps
    the same object while the counts stay the same."""
    layout = layout_for((7, 43, 35, 44), DEFAULT_PROFILE)
    odometer = Odometer(WHEEL_BASE_MM)
    expected = Odometry()
    left, right = left0, right0
    for dl, dr in [(0, 0), *steps]:
        left, right = (left + dl) & 0xFFFF, (right + dr) & 0xFFFF
        before = odometer.odometry
        got = odometer.frame(SensorFrame(layout, (1, left, 2, right)))
        expected = expected.advance(left, right, WHEEL_BASE_MM)
        assert got == expected and odometer.odometry is got
        if (left, right) == (before.left_counts, before.right_counts):
            assert got is before


def test_the_odometer_leaves_the_odometry_as_it_is_without_encoder_packets() -> None:
    odometer = Odometer(WHEEL_BASE_MM)
    with_counts = layout_for((43, 44), DEFAULT_PROFILE)
    odometer.frame(SensorFrame(with_counts, (10, 20)))
    moved = odometer.frame(SensorFrame(with_counts, (30, 20)))
    bumps_only = SensorFrame(layout_for((7,), DEFAULT_PROFILE), (1,))
    assert odometer.frame(bumps_only) is moved
    assert odometer.frame(SensorFrame(with_counts, (30, 20))) is moved  # the layout back
