"""Every speed a behaviour must move the robot at turns a wheel: the speed controller steps
wheel speeds by about 28.5 mm/s (600 spec, Drive 137), and a wheel asked for less than half a
step stands still. ``turn`` took 1 mm/s and ``dock_drive_on.slow`` 10 mm/s; both leaves then
waited for ever for wheels that never turned (a --timeout or the dock's time limit ended the
run)."""

from __future__ import annotations

from pathlib import Path

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


#: Every leaf that sends a wheel a fixed share of a speed parameter, that share's module's
#: name for it, and the parameters it scales
SHARED = [
    ("dock_drive_on", "roomba_bt.behaviours.docking.drive_on", ("speed", "slow")),
    ("dock_approach", "roomba_bt.behaviours.docking.approach", ("speed",)),
    ("dock_search", "roomba_bt.behaviours.docking.search", ("speed",)),
]


@pytest.mark.parametrize(("name", "module", "params"), SHARED)
def test_every_share_of_a_speed_a_leaf_sends_turns_a_wheel_at_its_minimum(
    name: str, module: str, params: tuple[str, ...]
) -> None:
    """``dock_approach`` took ``speed: 30 mm/s`` and backed to the beams' band at 36% of it
    (10.8 mm/s, a wheel that stands still), orbited on a 4.8 mm/s inner wheel, and turned
    its last degrees to the dock at 25% of ``turn_speed: 40 mm/s``; ``dock_drive_on`` steered
    on 30% of ``slow: 30 mm/s``. Each share is declared beside the parameter, and its
    minimum turns every one."""
    import importlib

    shares = importlib.import_module(module).SPEED_SHARES
    declaration = default_registry().get(name)
    assert declaration is not None
    for param in (p for p in declaration.params if p.name in params):
        assert param.minimum is not None
        for share, when in shares:
            assert speed_steps(round(param.minimum * share)) != 0, (name, param.name, when)


def test_dock_approach_turns_its_last_degrees_at_its_minimum_turn_speed() -> None:
    from roomba_bt.behaviours.docking.approach import FACE_TURN, TURN_SPEED_SHARES

    declaration = default_registry().get("dock_approach")
    assert declaration is not None
    turn_speed = next(p for p in declaration.params if p.name == "turn_speed")
    assert (FACE_TURN.slow, "for the last degrees of a turn to face the dock") in TURN_SPEED_SHARES
    assert turn_speed.minimum == moving_minimum(FACE_TURN.slow) == 60
    assert speed_steps(round(turn_speed.minimum * FACE_TURN.slow)) != 0


def _errors(tmp_path: Path, leaf: str) -> list[str]:
    """The diagnostics of a mission that enters Safe and runs ``leaf``."""
    from roomba_bt.mission import compile_mission

    path = tmp_path / "m.yaml"
    path.write_text(f"mission: m\ntree: {{sequence: [{{mode: safe}}, {{{leaf}}}]}}\n")
    _, diagnostics = compile_mission(path)
    return [d.message for d in diagnostics]


@pytest.mark.parametrize(
    ("leaf", "said"),
    [
        ("dock_approach: {speed: 50 mm/s}",
         "dock_approach: speed 50 mm/s is out of range: allowed 94..500 mm/s (it sends a wheel "
         "16% of speed on the inside of its orbit round the force field: below 94 mm/s that is "
         "less than 15 mm/s, and the wheel stands still"),
        ("dock_approach: {turn_speed: 50 mm/s}",
         "dock_approach: turn_speed 50 mm/s is out of range: allowed 60..500 mm/s (it sends a "
         "wheel 25% of turn_speed for the last degrees of a turn to face the dock: below 60 mm/s"),
        ("dock_drive_on: {slow: 40 mm/s}",
         "dock_drive_on: slow 40 mm/s is out of range: allowed 50..500 mm/s (it sends a wheel "
         "30% of slow on the near side, steering toward the receiver that sees the dock"),
    ],
)  # fmt: skip
def test_a_speed_whose_share_stands_still_is_refused_naming_the_share(
    tmp_path: Path, leaf: str, said: str
) -> None:
    (error,) = _errors(tmp_path, leaf)
    assert said in error, error


@pytest.mark.parametrize(
    ("leaf", "note"),
    [
        ("dock_search: {speed: 10 mm/s}", False),  # 50 mm/s for another reason
        ("dock_search: {speed: 20 mm/s}", False),
        ("cover: {speed: 10 mm/s}", False),
        ("turn: {angle: 90deg, speed: 10 mm/s}", True),  # the floor itself
        ("wall_follow: {speed: 10 mm/s}", False),  # 20 mm/s for another reason
    ],
)  # fmt: skip
def test_the_stands_still_note_is_said_only_where_the_minimum_is_the_floor(
    tmp_path: Path, leaf: str, note: bool
) -> None:
    """``dock_search: {speed: 10 mm/s}`` was refused with "a wheel asked for less than 15
    mm/s stands still" though its minimum, 50 mm/s, is not that floor (20 mm/s, refused
    alike, said nothing of it)."""
    (error,) = _errors(tmp_path, leaf)
    assert "is out of range" in error, error
    assert ("stands still" in error) is note, error


def test_a_wheel_speed_parameter_that_would_stand_still_is_a_declaration_error() -> None:
    with pytest.raises(ValueError, match="does not move a wheel"):
        wheel_speed_param("slow", "60 mm/s", minimum=10)


#: The fastest wheel speed a Create 2 was measured standing still at (mm/s, either sign:
#: ktibow.github.io/blog/roombamotors, "anything from -10 to 10 mm/s will result in no
#: movement"); docs/protocol.md, "wheel speed steps".
MEASURED_STANDING_STILL_MM_S = 10


def test_every_speed_the_language_accepts_moves_the_measured_robot() -> None:
    """validate's error for a slower speed is no guess: the measured robot stands still
    there too, so a mission refused would have hung on it; the minimum is not lowered
    to the measured 11, which the simulator's nearest step stands still at."""
    assert SLOWEST_MOVING_SPEED_MM_S > MEASURED_STANDING_STILL_MM_S
    assert speed_steps(MEASURED_STANDING_STILL_MM_S + 1) == 0  # why the minimum stays 15
