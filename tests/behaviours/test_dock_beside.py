"""``dock_approach`` started against the wall right beside the dock, on the simulator.

In the apartment with exact encoders, ``clean`` seed 0's way home (``home_by_map``) ends
at (1.33, 0.17) m, heading 148 deg: 13 cm east of the docked pose, its body touching the
wall the dock stands on. Facing the dock from there, the approach turned 80 deg away to
cross to the axis; the omni receiver was already over it, so the crossing backed up to find
the band's near edge, straight into that wall: no bumper behind, wheels stalled, the
odometry still, and it backed at the wall until the stage's 90 s timeout, attempt after
attempt, for the mission's whole 10 minutes (0.00 m driven). Now a backing that gets
nowhere ends the crossing, the robot backs straight away from the dock (a bump pressed
against the wall no longer ends that retreat on its first tick) and comes in again along
the beams.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .sim_tree import dock_from

#: mission time (s) within which it docks from beside the dock: 18 s measured, where it
#: used to stay for the whole 600 s limit
DOCKS_WITHIN_S = 60.0


@pytest.mark.parametrize(
    ("x", "y", "heading"),
    [(1.33, 0.17, 148), (1.07, 0.17, 32)],
    ids=["east-of-the-dock-clean-seed-0", "west-of-the-dock-its-mirror"],
)
def test_a_start_against_the_wall_beside_the_dock_docks(
    tmp_path: Path, x: float, y: float, heading: int
) -> None:
    result = dock_from(tmp_path, "apartment", x, y, heading)
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
    assert result.time_s < DOCKS_WITHIN_S, result.time_s
