"""A plugin by path: one condition, loaded by ``plugins: [./plugins/near_wall.py]``.

The walkthrough in docs/plugins.md builds this file step by step.
"""

from __future__ import annotations

from roomba_bt.behaviours import INT, Condition, Param, declare
from roomba_bt.robot.interface import Snapshot


@declare(
    "near_wall",
    kind="condition",
    params=(Param("closer_than", INT, default=300, minimum=0, maximum=4095,
                  doc="wall signal (packet 27) at or above which the wall is near"),),
    reads=(27,),
    primary="closer_than",
)  # fmt: skip
class NearWall(Condition):
    """A wall is near on the right: the wall signal (27) at or above a level."""

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame[27] >= self.number("closer_than")
