"""An example plugin: ``dirt_detect`` (a condition) and ``spot_clean`` (an action).

Neither is in roomba-bt's core library; together they show the two kinds of plugin
behaviour. ``dirt_detect`` reads the robot's dirt detector, packet 15 (one unsigned byte,
0-255: how much dirt the acoustic sensor heard under the brushes)::

    stream frame  [19][n] ... [15][level] ... [checksum]

``spot_clean`` sends Spot, one byte ``[134]``: the robot's own spot-cleaning spiral. The OI
drops to Passive (the opcode table says so: from the declaration's ``sends`` the validator
knows that a driving action after it needs a ``mode: safe`` first). It stays RUNNING while
the spiral runs (the wheels turning, as the encoders show) and succeeds once they have stood
still for ``settle``; a spiral still going after ``timeout`` fails. Time is the mission clock.
"""

from __future__ import annotations

from py_trees.common import Status

from roomba_bt.behaviours import DURATION, INT, Action, Condition, Param, declare
from roomba_bt.oi import commands
from roomba_bt.oi.frames import ENCODER_PACKETS
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.packets import PACKETS_BY_NAME, packet_ids
from roomba_bt.robot.interface import Snapshot

__all__ = ["DirtDetect", "SpotClean"]
__version__ = "0.1.0"

_DIRT = PACKETS_BY_NAME["dirt_detect"]


@declare(
    "dirt_detect",
    kind="condition",
    params=(
        Param("level", INT, default=1, minimum=1, maximum=_DIRT.maximum,
              doc="SUCCESS when the dirt detector (packet 15) reads at least this"),
    ),
    reads=packet_ids("dirt_detect"),
    primary="level",
)  # fmt: skip
class DirtDetect(Condition):
    """The dirt detector hears dirt under the brushes (packet 15 at least ``level``)."""

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame.dirt_detect >= self.number("level")


@declare(
    "spot_clean",
    kind="action",
    params=(
        Param("settle", DURATION, default="1s", minimum=0.1, maximum=10,
              doc="the spiral is over once the wheels have stood still this long"),
        Param("timeout", DURATION, default="60s", minimum=1,
              doc="FAILURE if the spiral is still going after this long"),
    ),
    reads=ENCODER_PACKETS,
    sends=opcodes("spot"),
)  # fmt: skip
class SpotClean(Action):
    """Spot-clean here (Spot 134, the robot's own spiral, in Passive) and wait until it ends."""

    def start(self) -> None:
        snap = self.snapshot
        self._started = snap.time
        self._moved = False
        self._still_since = snap.time
        self._last = (snap.odometry.distance_mm, snap.odometry.angle_rad)
        self.send(commands.spot())

    def update(self) -> Status:
        snap = self.snapshot
        now = snap.time
        here = (snap.odometry.distance_mm, snap.odometry.angle_rad)
        if here != self._last:
            self._moved, self._last, self._still_since = True, here, now
        elif self._moved and now - self._still_since >= self.number("settle") - 1e-9:
            return Status.SUCCESS
        if now - self._started >= self.number("timeout") - 1e-9:
            self.feedback_message = (
                f"the spot cycle was still running after {self.number('timeout'):g} s"
            )
            return Status.FAILURE
        return Status.RUNNING
