"""``odometry`` on a run in the simulator: ``distance`` is the path travelled, forward or back
(the summary's ``distance``); ``angle`` the net heading change (session 34's py_trees review:
odo.yaml, 10 cm forward and 10 cm back, found ``distance: 15cm`` false)."""

from __future__ import annotations

import pytest

from roomba_bt.runtime.summary import Outcome

from .simrun import RunMission

#: moves, then the condition that must hold after them (the last step of the sequence)
CASES = [
    pytest.param(
        ["drive: {velocity: 100 mm/s, distance: 10cm}",
         "drive: {velocity: -100 mm/s, distance: 10cm}"],
        "odometry: {distance: 15cm}", id="forward-and-back-is-20cm-of-path",
    ),
    pytest.param(
        ["mark: here", "drive: {velocity: 100 mm/s, distance: 10cm}",
         "drive: {velocity: -100 mm/s, distance: 10cm}"],
        "odometry: {since: here, distance: 15cm}", id="since-a-mark",
    ),
    pytest.param(
        ["turn: 90deg", "turn: -90deg"],
        "inverter: {odometry: {angle: 45deg}}", id="a-turn-back-undoes-the-turn",
    ),
    pytest.param(
        ["turn: 90deg"], "odometry: {angle: 80deg}", id="a-quarter-turn",
    ),
]  # fmt: skip


@pytest.mark.parametrize(("moves", "condition"), CASES)
def test_odometry_after_moves(run_mission: RunMission, moves: list[str], condition: str) -> None:
    steps = "".join(f"    - {step}\n" for step in ["mode: safe", *moves, condition])
    mission = "mission: odo\nblackboard:\n  here: mark\ntree:\n  sequence:\n" + steps
    run = run_mission(mission, world="apartment", timeout=30.0)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
