"""``dock_drive_on`` (final alignment): along the axis onto the charging contacts.

Two states (:class:`DriveOnState`): DRIVE in along the axis until the bumper touches the
dock's plate, then WIGGLE in place to seat the contacts. SUCCESS as soon as packet 34 shows
the home base, in either.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from py_trees.common import Status

from roomba_bt.behaviours.declare import Param, moving_minimum, wheel_speed_param
from roomba_bt.behaviours.docking.common import (
    HOME_BASE,
    RUNNING,
    DockingAction,
    DockView,
    IdentityEnum,
    declare_stage,
    view_of,
)
from roomba_bt.behaviours.units import ANGLE
from roomba_bt.oi.bits import BUMP_BITS
from roomba_bt.oi.frames import BUMPS_PACKETS, CHARGING_SOURCES_PACKETS, IR_PACKETS
from roomba_bt.robot.interface import Snapshot

#: FAILURE once no receiver has seen the dock for this long (s).
LOST_BEAMS_S = 1.5
#: One receiver alone sees the dock: the near wheel at STEER_SHARE of the speed, the far one
#: STEER_MM_S faster; neither: both at SEARCH_SHARE.
STEER_SHARE = 0.3
STEER_MM_S = 50
SEARCH_SHARE = 0.5
#: Facing the dock with one buoy only: this share of the speed moves from wheel to wheel
#: toward the axis.
NUDGE_SHARE = 0.15
#: WIGGLE: each turn ends within WIGGLE_DONE_RAD of its goal, at WIGGLE_MM_S, with
#: WIGGLE_PUSH_MM_S forward on both wheels to keep the bumper on the plate.
WIGGLE_DONE_RAD = math.radians(1.0)
WIGGLE_MM_S = 30.0
WIGGLE_PUSH_MM_S = 8.0
#: Each share of ``speed`` (and of ``slow``, in the force field) a wheel is sent, which must
#: turn it (the parameters' minimums: :func:`~roomba_bt.behaviours.declare.wheel_speed_param`)
SPEED_SHARES = (
    (STEER_SHARE, "on the near side, steering toward the receiver that sees the dock"),
    (SEARCH_SHARE, "driving on while neither receiver sees the dock"),
    (1.0 - NUDGE_SHARE, "on the slower side of its nudge toward the axis"),
)


class DriveOnState(IdentityEnum):
    DRIVE = "drive"
    WIGGLE = "wiggle"


@declare_stage(
    "dock_drive_on",
    params=(
        wheel_speed_param("speed", "120 mm/s", minimum=moving_minimum(), shares=SPEED_SHARES,
                          doc="speed along the axis outside the force field"),
        wheel_speed_param("slow", "60 mm/s", minimum=moving_minimum(), shares=SPEED_SHARES,
                          doc="speed inside the force field"),
        Param("wiggle", ANGLE, default="12deg", minimum=0, maximum=45,
              doc="how far it turns each way on contact to seat the charging contacts"),
    ),
    timeout="45s",
    timeout_doc="FAILURE if the home base is not reached by then",
    reads=(*BUMPS_PACKETS, *CHARGING_SOURCES_PACKETS),
)  # fmt: skip
class DockDriveOn(DockingAction):
    """Final alignment: drive onto the contacts along the axis (SUCCESS: packet 34 shows
    the home base).

    Steers to keep both directional receivers on the dock (one alone: turn toward it), nudges
    toward the axis when only one buoy is seen, slows down in the force field. On contact
    without the home-base bit it wiggles in place (``wiggle`` each way) to seat the
    contacts; FAILURE if that does not make contact, so a recovery can back off and retry.
    """

    stage = "final alignment"
    LATE = "did not reach the contacts in {}"
    #: the receivers (the view), the home base, the bumper
    WATCHED = (*IR_PACKETS, *CHARGING_SOURCES_PACKETS, *BUMPS_PACKETS)

    #: the stage's own state in slots (see :class:`~.common.DockingAction`)
    __slots__ = (
        "_bumped", "_last_seen", "_slow", "_speed", "_view", "_wiggle_rad", "_wiggle_step", "state",
    )  # fmt: skip

    def __init__(self, name: str, params: dict[str, object] | None = None) -> None:
        super().__init__(name, params)
        #: an attribute of each node, not a class default: CPython 3.11 does not specialise
        #: reading an attribute whose class holds an instance of a Python class (an enum
        #: member) under the same name, read on every tick (``_ACTS[self.state]``)
        self.state = DriveOnState.DRIVE
        self._wiggle_step = 0
        # the rest is set before any tick reads it: by :meth:`start` (the parameters, the
        # last beam seen), by :meth:`read` (the view, the bumper)

    def start(self) -> None:
        self.begin()
        # read once a start, used on every tick
        self._speed = self.number("speed")
        self._slow = self.number("slow")
        self._wiggle_rad = math.radians(self.number("wiggle"))
        self.state = DriveOnState.DRIVE
        self._last_seen = self.snapshot.time
        self.mark_turn()

    def read(self, raw: tuple[int, ...]) -> None:
        omni, left, right, sources, bumps = raw
        self._view = view_of((omni, left, right))
        self._done = HOME_BASE[sources & 0xFF]  # frame.charging_sources.home_base
        self._bumped = bumps & BUMP_BITS != 0  # frame.any_bump

    def step(self, snap: Snapshot) -> Status:
        now = snap.time
        view = self._view
        if view.seen:
            self._last_seen = now
        elif now - self._last_seen > LOST_BEAMS_S:
            return self.fail("lost the dock's beams")
        act = _ACTS
        while True:
            status = act[self.state](self, snap, view)
            if status is not None:
                return status

    # states ------------------------------------------------------------------------
    def _drive_state(self, snap: Snapshot, view: DockView) -> Status | None:
        """In along the axis until the bumper touches the plate; then wiggle."""
        if not self._bumped:  # frame.any_bump
            return self._drive(view)
        if not (view.red or view.green):
            # the plate is in the buoys' beams: outside them, it is something else
            return self.fail("bumped into something that is not the dock")
        self.state = DriveOnState.WIGGLE
        self._wiggle_step = 0
        self.mark_turn()
        return None

    def _drive(self, view: DockView) -> Status:
        """In along the axis, slow in the force field, steering toward the receiver that
        sees the dock, nudging toward the axis when one buoy is seen."""
        speed = self._slow if view.force_field else self._speed
        if view.on_left:
            self.wheels(speed * STEER_SHARE, speed * STEER_SHARE + STEER_MM_S)
        elif view.on_right:
            self.wheels(speed * STEER_SHARE + STEER_MM_S, speed * STEER_SHARE)
        elif not view.facing:
            self.wheels(speed * SEARCH_SHARE, speed * SEARCH_SHARE)
        else:
            nudge = NUDGE_SHARE * speed * view.side  # red only: axis on the left
            self.wheels(speed - nudge, speed + nudge)
        return RUNNING

    def _wiggle(self, snap: Snapshot, view: DockView) -> Status | None:
        """In place: +wiggle, back through 0 to -wiggle, back to 0; FAILURE after that."""
        w = self._wiggle_rad
        targets = (w, -w, 0.0)
        if self._wiggle_step >= len(targets):
            return self.fail("touched the dock but the contacts did not engage")
        goal = targets[self._wiggle_step]
        err = goal - (snap.odometry.angle_rad - self._turn_mark)  # self.turned()
        if abs(err) < WIGGLE_DONE_RAD:
            self._wiggle_step += 1
            self.halt()
            return RUNNING
        spin = WIGGLE_MM_S if err > 0 else -WIGGLE_MM_S
        self.wheels(-spin + WIGGLE_PUSH_MM_S, spin + WIGGLE_PUSH_MM_S)
        return RUNNING

    state: DriveOnState
    # the readings (read)
    _view: DockView


#: Each state's method.
_ACTS: dict[DriveOnState, Callable[[DockDriveOn, Snapshot, DockView], Status | None]] = {
    DriveOnState.DRIVE: DockDriveOn._drive_state,
    DriveOnState.WIGGLE: DockDriveOn._wiggle,
}
