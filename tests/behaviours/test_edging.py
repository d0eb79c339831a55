"""The edge's steering (``cover``'s wall on the right): a turn in place at a wall ahead that
holds (hysteresis and a minimum time), and a PD that never drives a wheel backward."""

from __future__ import annotations

import itertools

from roomba_bt.behaviours.edging import (
    FRONT_CLEAR,
    FRONT_CLOSE,
    FRONT_TURN,
    HOLD_S,
    TURN_MM_S,
    EdgeSteering,
    signal_distance_mm,
)

TICK = 0.015
SPEED = 300.0
DISTANCE = 180.0
#: the right signal (51) that reads about 180 mm from the wall: on target
ON_TARGET = 2675


def signals(front: int = 0, right: int = ON_TARGET) -> tuple[int, ...]:
    return (0, 0, 0, front, 0, right)


def test_a_wall_ahead_turns_it_left_in_place() -> None:
    steering = EdgeSteering()
    assert steering.wheels(signals(front=FRONT_TURN), SPEED, DISTANCE, 0.0) == (
        -TURN_MM_S, TURN_MM_S, None,
    )  # fmt: skip


def test_a_front_signal_at_the_threshold_does_not_flip_the_wheels_every_tick() -> None:
    """The centre signal of a wall met at a shallow angle, as the apartment's edges showed
    it: one tick of turning took it below 900, one tick of driving above. It flipped
    between (-150, 150) and a hard right each tick."""
    steering = EdgeSteering()
    fronts = itertools.cycle((970, 888))
    lefts = [steering.wheels(signals(next(fronts)), SPEED, DISTANCE, i * TICK)[0]
             for i in range(40)]  # fmt: skip
    assert all(left < 0 for left in lefts)  # it keeps turning: the wall is still ahead


def test_the_turn_ends_below_the_clear_level_after_the_hold() -> None:
    steering = EdgeSteering()
    steering.wheels(signals(front=FRONT_TURN), SPEED, DISTANCE, 0.0)
    left, _, _ = steering.wheels(signals(front=FRONT_CLEAR - 1), SPEED, DISTANCE, TICK)
    assert left < 0  # below the clear level, but within the hold
    left, _, _ = steering.wheels(signals(front=FRONT_CLEAR), SPEED, DISTANCE, HOLD_S)
    assert left < 0  # held long enough, but the wall ahead is still in sight
    left, right, error = steering.wheels(signals(front=FRONT_CLEAR - 1), SPEED, DISTANCE, 1.0)
    assert left >= 0 and right >= 0 and error is not None


def test_following_holds_too_unless_the_wall_ahead_is_close() -> None:
    steering = EdgeSteering()
    steering.wheels(signals(front=FRONT_TURN), SPEED, DISTANCE, 0.0)
    steering.wheels(signals(front=0), SPEED, DISTANCE, 1.0)  # the turn ends
    left, _, _ = steering.wheels(signals(front=FRONT_TURN), SPEED, DISTANCE, 1.0 + TICK)
    assert left >= 0  # a decision held: no turn again at once
    left, _, _ = steering.wheels(signals(front=FRONT_CLOSE), SPEED, DISTANCE, 1.0 + 2 * TICK)
    assert left < 0  # but a wall 3 cm ahead turns it within the hold


def test_the_pd_never_drives_a_wheel_backward() -> None:
    for front, right in itertools.product((0, 199, 200, 600), (1, 200, ON_TARGET, 4095)):
        steering = EdgeSteering()
        for i in range(3):
            left, right_wheel, _ = steering.wheels(signals(front, right), SPEED, DISTANCE, i)
            assert left >= 0 and right_wheel >= 0, (front, right, left, right_wheel)


def test_with_a_wall_ahead_in_sight_it_does_not_steer_into_the_corner() -> None:
    steering = EdgeSteering()
    far = 300  # the right wall far: the PD alone would turn right, toward it
    left, right, error = steering.wheels(signals(front=600, right=far), SPEED, DISTANCE, 0.0)
    assert error is not None and error > 0
    assert left <= right


def test_no_wall_on_the_right_curves_right() -> None:
    assert EdgeSteering().wheels(signals(right=0), SPEED, DISTANCE, 0.0) == (
        SPEED, SPEED * 0.35, None,
    )  # fmt: skip


def test_the_signal_reads_as_the_simulators_distance() -> None:
    assert signal_distance_mm(4095) == 0.0
    assert signal_distance_mm(0) == 150.0
    assert round(signal_distance_mm(1024)) == 75  # 4095 (1 - 75 / 150) ** 2
