"""``dock_approach``'s crossing to the axis, close to the dock: no back-up over floor the
robot never drove.

Fresh empty-room start 1100 (``roomba-bt eval dock --within 1.5 --seed 1100 --runs 1``):
(2.093, 0.787) m, heading 68 deg, 9 cm east of the axis (x 2.0 m). The robot faces the
dock, drives in along the beams to (2.080, 0.717) and turns 80 deg west toward the axis. The
turn swings the omni receiver, 13 cm ahead of the centre, over the band where both buoys
are seen, so the crossing used to back up 11 cm east (centre at x 2.192 m) to find the
band's near edge, and then drive 19 cm west again. Behind a Create 2 nothing sees a drop or
a wall, and that floor is beside the line it came in by, not on it. The near edge is the one
the turn swept the omni over: the crossing now takes it from the turn and drives on west.
"""

from __future__ import annotations

import math
from pathlib import Path

from .sim_tree import dock_from

START = (2.093, 0.787, 68)
#: how far east (m) of where it came to a stop facing the dock the centre may go: the
#: odometry's own few millimetres, far less than the 11 cm back-up
EAST_SLACK_M = 0.01


def test_the_crossing_takes_the_near_edge_from_its_turn_and_never_backs_away(
    tmp_path: Path,
) -> None:
    x, y, heading = START
    result = dock_from(tmp_path, "empty-room", x, y, heading, trace_every=1)
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
    # it came in along the beams (south) before it turned toward the axis: from there on
    # its centre only goes west
    east = max(px for px, _ in result.trajectory)
    assert east <= x + EAST_SLACK_M, f"backed up to x {east:.3f} m, east of {x} m"
    # and it crossed: the docked pose is on the axis
    assert math.isclose(result.end[0], 2.0, abs_tol=0.03), result.end
