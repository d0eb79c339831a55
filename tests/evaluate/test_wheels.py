"""Wheel reversals counted from the wheel speeds a mission asked for."""

from __future__ import annotations

from roomba_bt.evaluate.wheels import WheelReversals


def test_a_sign_change_of_either_wheel_is_a_reversal_a_stop_between_too() -> None:
    seen = WheelReversals()
    for t, left, right in [(0.0, 100, 100), (0.015, -150, 150), (0.03, 0, 0), (0.045, 200, 200),
                           (0.06, 200, -10), (1.06, -200, -200), (2.06, -200, -200)]:  # fmt: skip
        seen.see(t, left, right)
    assert [t for t, _ in seen.events] == [0.015, 0.045, 0.06, 1.06]
    assert seen.events[1] == (0.045, 0.03)  # the left wheel again, 30 ms after its first
    assert seen.shortest_s == 0.03
    assert seen.chatter() == 1  # within 0.15 s of the same wheel's previous reversal
    assert seen.per_minute == 60.0 * 4 / 2.06


def test_a_wheel_that_only_stops_never_reverses() -> None:
    seen = WheelReversals()
    for t, speed in enumerate((100, 0, 100, 0, 50)):
        seen.see(float(t), speed, speed)
    assert seen.events == [] and seen.shortest_s is None and seen.per_minute == 0.0
