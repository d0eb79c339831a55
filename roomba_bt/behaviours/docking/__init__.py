"""Docking from the home base's IR beams, in the stages of Nav2's docking server.

The home base sends IR characters (decoded by :mod:`roomba_bt.oi.ir`, both dock families:
160-173 and 240-254) in three beams::

                 red buoy  (dock's left,  about -5 .. +25 deg of its axis)
      dock ==>   both      (on the axis, about +-5 deg)      up to about 1 m
                 green buoy(dock's right, about -25 .. +5 deg)
                 force field: all around, about 0.6 m

The robot has three receivers: the omni (packet 17) on top of the bumper, and the left (52)
and right (53) directional ones, which see the dock only when it is within about 5 deg of the
other side of the heading: both of them see it when the robot faces the dock. So the robot
reads two things from every frame: *where the dock is* relative to its heading (left receiver
only: turn left; right only: turn right; both: facing it) and *which side of the dock's axis
it is on* (red only: the dock's left; green only: its right; both: on the axis).

The stages, each a leaf whose failure message names the stage (``search: ...``,
``approach: ...``, ``final alignment: ...``, ``wait for charge: ...``):

``dock_search``
    spin once in place, then wander toward the least visited space (a coarse visit grid in
    the odometry frame), backing away from bumps, cliffs and light-bumper obstacles, until a
    dock character is seen; trapped in a small space (between a chair's legs), it leaves
    along the line it came in by (:mod:`.escape`).
``dock_approach``
    face the dock; if off its axis, turn toward the axis and move until the centre is on it
    (the omni receiver finds both edges of the band where it sees both buoys), then face the
    dock again; with no buoy in sight, circle the dock until one is seen. SUCCESS facing
    the dock on its axis.
``dock_drive_on``
    drive in along the axis, slower inside the force field, steering to keep both the left
    and right receivers on the dock; on contact without charge, wiggle in place to seat the
    contacts. SUCCESS when packet 34 shows the home base.
``dock_wait_charge``
    SUCCESS when packet 34's home-base bit and a charging state in packet 21 are both seen.
``dock_time_limit``
    RUNNING until the time limit, then FAILURE naming the stage that was running: put it in
    a ``parallel`` (policy ``one``) beside the stages.

None of them sends Seek Dock (143). They drive with Drive Direct (145)
``[145][right hi][right lo][left hi][left lo]`` and halt ``[137][0][0][0][0]`` when they end.

Each moving stage is a state machine with an enum of its states and one method per state
(:mod:`.search`, :mod:`.approach`, :mod:`.drive_on`); :mod:`.common` holds what they share
(the dock as one frame sees it, the hazards, the wheel commands), :mod:`.charge` the two
stages that do not move.
"""

from __future__ import annotations

from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.docking.approach import ApproachState, DockApproach
from roomba_bt.behaviours.docking.charge import DockTimeLimit, DockWaitCharge
from roomba_bt.behaviours.docking.common import (
    RUN_KEY,
    STAGE_KEY,
    DockingAction,
    DockView,
    Hazard,
    current_stage,
    hazard_in,
)
from roomba_bt.behaviours.docking.drive_on import DockDriveOn, DriveOnState
from roomba_bt.behaviours.docking.search import DockSearch, SearchState, VisitGrid
from roomba_bt.oi.profiles import OMNI_AHEAD_MM

DOCKING: tuple[type[Action], ...] = (
    DockSearch, DockApproach, DockDriveOn, DockWaitCharge, DockTimeLimit,
)  # fmt: skip

__all__ = [
    "DOCKING",
    "OMNI_AHEAD_MM",
    "RUN_KEY",
    "STAGE_KEY",
    "ApproachState",
    "DockApproach",
    "DockDriveOn",
    "DockSearch",
    "DockTimeLimit",
    "DockView",
    "DockWaitCharge",
    "DockingAction",
    "DriveOnState",
    "Hazard",
    "SearchState",
    "VisitGrid",
    "current_stage",
    "hazard_in",
]
