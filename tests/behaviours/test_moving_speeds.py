"""Every speed a behaviour must move the robot at turns a wheel: the speed controller steps
wheel speeds by about 28.5 mm/s (600 spec, Drive 137), and a wheel asked for less than half a
step stands still. ``turn`` took 1 mm/s and ``dock_drive_on.slow`` 10 mm/s; both leaves then
waited for ever for wheels that never turned (a --timeout or the dock's time limit ended the
run)."""

from __future__ import annotations

import pytest

from roomba_bt.behaviours.declare import moving_minimum, wheel_speed_param
from roomba_bt.behaviours.registry import default_registry
from roomba_bt.oi.odometry import SLOWEST_MOVING_SPEED_MM_S, WHEEL_SPEED_STEP_MM_S, speed_steps
from roomba_bt.sim.motion import _quantise


def test_the_slowest_moving_speed_is_the_first_the_speed_controller_does_not_round_to_0() -> None:
    assert WHEEL_SPEED_STEP_MM_S == 28.5  # the spec's "steps of about 28.5 mm/s"
    assert speed_steps(SLOWEST_MOVING_SPEED_MM_S - 1) == 0
    assert speed_steps(SLOWEST_MOVING_SPEED_MM_S) == 1
    # the simulator models the same controller with the same constant
    assert _quantise(SLOWEST_MOVING_SPEED_MM_S - 1) == 0
    assert _quantise(SLOWEST_MOVING_SPEED_MM_S) == WHEEL_SPEED_STEP_MM_S


@pytest.mark.parametrize("name", ["turn", "dock_drive_on"])
def test_no_speed_a_moving_leaf_allows_stands_still(name: str) -> None:
    declaration = default_registry().get(name)
    assert declaration is not None
    speeds = [p for p in declaration.params if p.type.name == "speed"]
    assert speeds
    for param in speeds:
        assert param.minimum is not None
        assert speed_steps(param.minimum) != 0, f"{name}.{param.name}"


def test_dock_drive_on_moves_at_the_share_it_searches_with() -> None:
    from roomba_bt.behaviours.docking.drive_on import SEARCH_SHARE

    declaration = default_registry().get("dock_drive_on")
    assert declaration is not None
    slow = next(p for p in declaration.params if p.name == "slow")
    assert slow.minimum == moving_minimum(SEARCH_SHARE) == 30
    assert speed_steps(slow.minimum * SEARCH_SHARE) != 0


def test_a_wheel_speed_parameter_that_would_stand_still_is_a_declaration_error() -> None:
    with pytest.raises(ValueError, match="does not move a wheel"):
        wheel_speed_param("slow", "60 mm/s", minimum=10)
