"""``dock_approach``: from anywhere the dock's beams are seen, onto its axis, facing it.

The approach is a state machine (:class:`ApproachState`)::

    FACE ──(in the force field, side known or guessed)──> TURN_AWAY ──> CROSS ──> FACE
      │                                                       └──(guess)──> ORBIT ──> FACE
      ├──(outside the force field)──> CLOSER ──(in it)──> FACE
      └──(no progress)──> RETREAT ──> FACE
    CLOSER, CROSS, ORBIT ──(bump, cliff)──> BACK ──> FACE
    CROSS ──(backing, held behind)──> FACE ──> RETREAT

SUCCESS in FACE, facing the dock on its axis. A state's method returns the tick's status, or
None after handing over to a later state of the list FACE, CLOSER, TURN_AWAY, RETREAT,
ORBIT, CROSS, BACK, which then acts in the same tick.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.blackboard import run_board
from roomba_bt.behaviours.declare import Param, wheel_speed_param
from roomba_bt.behaviours.docking.common import (
    HAZARD_IN_PACKETS,
    HOME_BASE,
    RUN_KEY,
    RUNNING,
    DockingAction,
    DockView,
    Hazard,
    HeadingTurn,
    IdentityEnum,
    declare_stage,
    hazard_of,
    view_of,
)
from roomba_bt.behaviours.units import ANGLE, DURATION
from roomba_bt.oi.frames import (
    CHARGING_SOURCES_PACKETS,
    HAZARD_PACKETS,
    IR_PACKETS,
    VIRTUAL_WALL_PACKETS,
)
from roomba_bt.oi.profiles import OMNI_AHEAD_MM
from roomba_bt.printable import duration_said
from roomba_bt.robot.interface import Snapshot

#: Attempts (starts of this leaf) in one docking run before the approach first backs away
#: from the dock and comes in again.
ATTEMPTS_BEFORE_RETREAT = 3
#: The last side of the axis seen counts for this long (s) when only the force field is seen.
SIDE_REMEMBERED_S = 5.0
#: CLOSER: along the beams into the force field, at this share of the speed, steering with
#: the slow wheel at CLOSER_INNER_SHARE plus CLOSER_STEER_MM_S; at most CLOSER_MAX_MM.
CLOSER_SHARE = 0.8
CLOSER_INNER_SHARE = 0.3
CLOSER_STEER_MM_S = 60
CLOSER_MAX_MM = 1500.0
#: BACK: straight back (mm/s) for BACK_S after a bump or a cliff.
BACK_MM_S = 120
BACK_S = 0.5
#: RETREAT: straight back (mm/s), out of the force field, at most RETREAT_MAX_MM.
RETREAT_MM_S = 120
RETREAT_MAX_MM = 600.0
#: ORBIT: along the edge of the force field at this share of the speed, the inner wheel at
#: ORBIT_INNER_SHARE of that; given up after ORBIT_MAX_MM (half a circle round a 1 m field).
ORBIT_SHARE = 0.8
ORBIT_INNER_SHARE = 0.2
ORBIT_MAX_MM = 3500.0
#: CROSS: given up after CROSS_MAX_MM of path, or LEFT_BEAMS_S without any beam; inside the
#: force field at FORCE_FIELD_SHARE of the speed. Centred when the centre is within
#: CENTRED_MM of the axis; toward it at CENTRE_GAIN_PER_S mm/s per mm off, at least
#: CENTRE_MIN_MM_S. Back to the near edge of the band at NEAR_EDGE_SHARE of the speed, at
#: most NEAR_EDGE_MAX_MM behind where the crossing began.
CROSS_MAX_MM = 1500.0
LEFT_BEAMS_S = 1.0
FORCE_FIELD_SHARE = 0.6
CENTRED_MM = 4.0
CENTRE_GAIN_PER_S = 1.5
CENTRE_MIN_MM_S = 30.0
NEAR_EDGE_SHARE = 0.6
NEAR_EDGE_MAX_MM = 400.0
#: A drive backwards (CROSS to the near edge or toward the axis, RETREAT) that gets no
#: BACK_STALL_MM further in BACK_STALL_S is held: something behind the robot, which no
#: sensor of a Create 2 reports (the bumper is in front). Beside the dock, against the wall
#: it stands on, the crossing's way back runs into that wall: the wheels stall, the
#: odometry stands still, and the robot backed at nothing until the stage's timeout,
#: attempt after attempt (at least 10.8 mm/s backwards, the slowest: 5 mm is half that).
BACK_STALL_S = 1.0
BACK_STALL_MM = 5.0
#: Turns in place, as shares of ``turn_speed`` (each wheel, mm/s): toward the crossing line
#: (TURN_AWAY) and, facing the dock, spinning while a receiver sees it (FACE_SEEN) and while
#: none does (FACE_SEARCH); turning to a computed heading (FACE_TURN). At 200 mm/s the robot
#: turns 1.7 rad/s: about 3 deg between two readings of the receivers (every 30 ms), inside
#: the 10 deg where both see the dock.
TURN_AWAY_SHARE = 1.0
FACE_SEEN_SHARE = 0.7
FACE_SEARCH_SHARE = 1.0
FACE_TURN = HeadingTurn(
    fast=0.6, slow=0.25, slow_within_rad=math.radians(8), done_rad=math.radians(2)
)
#: Each share of ``speed`` and ``turn_speed`` a wheel is sent, which must turn it (the
#: parameters' minimums: :func:`~roomba_bt.behaviours.declare.wheel_speed_param`)
SPEED_SHARES = (
    (CLOSER_SHARE, "moving closer along the beams"),
    (CLOSER_SHARE * CLOSER_INNER_SHARE, "on the inside of its steering toward the beams"),
    (ORBIT_SHARE, "on the outside of its orbit round the force field"),
    (ORBIT_SHARE * ORBIT_INNER_SHARE, "on the inside of its orbit round the force field"),
    (FORCE_FIELD_SHARE, "crossing toward the axis inside the force field"),
    (NEAR_EDGE_SHARE * FORCE_FIELD_SHARE, "backing to the near edge of the beams' band"),
)
TURN_SPEED_SHARES = (
    (TURN_AWAY_SHARE, "turning away from the dock"),
    (FACE_SEEN_SHARE, "turning while a receiver sees the dock"),
    (FACE_SEARCH_SHARE, "turning while no receiver sees the dock"),
    (FACE_TURN.fast, "turning to face the dock"),
    (FACE_TURN.slow, "for the last degrees of a turn to face the dock"),
)
#: seen at one heading only, then nothing for this much turn: face that heading
FRINGE_RAD = math.radians(60.0)
#: spun this far without facing: forget the heading where the dock was seen, start again
FACE_RESTART_RAD = math.radians(540.0)
#: read on a retreat's ticks as a global (``common`` says why)
_BUMP = Hazard.BUMP


def _swept_to_crossing(turned_at: float | None, turned: float) -> float | None:
    """Where (mm along the crossing line, from its start) the omni receiver would have
    been across the dock's axis as it was when the turn toward the axis had gone
    ``turned_at`` (rad) of its ``turned``: turning, it swings ``OMNI_AHEAD_MM sin(turn)``
    across, toward the axis (the dock ahead at the turn's start, the axis nearly along
    that heading); crossing, ``(s + OMNI_AHEAD_MM) sin(turned)``. None: not seen.

    Why: close to the dock the turn alone swings the omni over the axis, and the crossing
    then backed up to find the band's near edge, up to 12 cm over floor the robot had not
    driven (nothing sees behind it), and drove forward again. The edge the turn swept over
    is the one the back-up looked for."""
    if turned_at is None:
        return None
    return OMNI_AHEAD_MM * (math.sin(turned_at) / math.sin(turned) - 1.0)


class ApproachState(IdentityEnum):
    FACE = "face"
    CLOSER = "closer"
    TURN_AWAY = "turn_away"
    RETREAT = "retreat"
    ORBIT = "orbit"
    CROSS = "cross"
    BACK = "back"


# DockApproach is over 400 lines on purpose: one stage, its states (ApproachState) each a
# method of the one node, sharing the facing and crossing marks; a class per state would
# hand those between objects on every tick.
@declare_stage(
    "dock_approach",
    params=(
        wheel_speed_param("speed", "150 mm/s", minimum=30, doc="speed toward the axis",
                          shares=SPEED_SHARES),
        wheel_speed_param("turn_speed", "200 mm/s", minimum=40,
                          doc="wheel speed of the turns in place (facing the dock, turning away)",
                          shares=TURN_SPEED_SHARES),
        Param("cross_angle", ANGLE, default="80deg", minimum=20, maximum=90,
              doc="how far it turns away from the dock to move toward its axis"),
        Param("lost_after", DURATION, default="4s", minimum=0.1,
              doc="FAILURE when no beam has been seen for this long"),
    ),
    timeout="90s",
    timeout_doc="FAILURE if not facing the dock on its axis by then",
    reads=(*HAZARD_IN_PACKETS, *CHARGING_SOURCES_PACKETS),
)  # fmt: skip
class DockApproach(DockingAction):
    """Get onto the dock's axis, facing it (SUCCESS), from anywhere its beams are seen.

    Face the dock (turn toward the receiver that sees it); red only means the robot is on
    the dock's left, so the axis is on the robot's left: turn ``cross_angle`` left and move
    along that line until the centre is on the axis (the omni receiver, ahead of the centre,
    measures both edges of the band where it sees both buoys; see :meth:`_cross`); green
    only: the mirror image; then face the dock again. In the force field with no buoy, the
    side is the last one seen, or a guess: circle the dock along the field's edge that way
    until a buoy is seen, the other way after a bump. No progress (:attr:`MAX_CROSSINGS`
    turns toward the axis, or a third attempt in one docking run): back away from the dock
    out of the force field and come in again, rather than repeat the same moves until the
    time limit.
    """

    stage = "approach"
    LATE = "not on the dock's axis after {}"
    #: the receivers (the view), the home base, the hazards but the light bumper (near the
    #: dock its wall is always in sight of it: not a hazard here)
    WATCHED = (*IR_PACKETS, *CHARGING_SOURCES_PACKETS, *HAZARD_PACKETS, *VIRTUAL_WALL_PACKETS)
    #: Turns toward the axis (crossings, circles) in one approach before it backs away from
    #: the dock and starts over from the edge of the force field; three are usually enough.
    MAX_CROSSINGS = 6

    #: the stage's own state in slots (see :class:`~.common.DockingAction`)
    __slots__ = (
        "_back_until", "_band_seen", "_before_at", "_centred", "_cross_angle", "_cross_path",
        "_cross_side", "_crossings", "_face_target", "_face_turn", "_guesses", "_hazard",
        "_last_seen", "_last_side", "_last_side_time", "_lead_theta", "_lost_after", "_orbit",
        "_past_at", "_retreat", "_run", "_side_guess", "_speed", "_spin_dir", "_stall",
        "_starts", "_sweep", "_sweep_before", "_sweep_past", "_turn_speed", "_view", "state",
    )  # fmt: skip

    def __init__(self, name: str, params: dict[str, object] | None = None) -> None:
        super().__init__(name, params)
        #: an attribute of each node, not a class default: CPython 3.11 does not specialise
        #: reading an attribute whose class holds an instance of a Python class (an enum
        #: member) under the same name, read on every tick (``_ACTS[self.state]``)
        self.state = ApproachState.FACE
        # kept across starts: the docking run (RUN_KEY) the starts belong to, how many
        self._run, self._starts = None, 0
        # a turn toward the axis (:meth:`_turn_away` sets them again) and its side
        self._before_at = self._past_at = None
        self._band_seen = self._orbit = False
        self._cross_path, self._sweep, self._cross_side = 0.0, 1, 1
        self._sweep_before = self._sweep_past = None
        self._last_side_time = self._back_until = 0.0
        # a drive backwards: where (mm, signed odometry distance) and when it last got on
        self._stall = (0.0, 0.0)
        # the rest is set before any tick reads it: by :meth:`start` (the parameters, the
        # guesses, the facing), by :meth:`read` (the view, the hazard)

    def start(self) -> None:
        self.begin()
        # read once a start, used on every tick
        self._speed = self.number("speed")
        self._turn_speed = self.number("turn_speed")
        self._face_turn = FACE_TURN.scaled(self._turn_speed)
        self._cross_angle = math.radians(self.number("cross_angle"))
        self._lost_after = self.number("lost_after")
        self._last_seen = self.snapshot.time
        self._side_guess = 0
        self._last_side = 0
        self._guesses = 0
        self._crossings = 0
        self._centred = False
        run = py_trees.blackboard.Blackboard.storage.get(run_board().name(RUN_KEY))
        if run != self._run:
            self._run, self._starts = run, 0
        self._starts += 1
        # two attempts of this run already ended in a failure after or during the approach:
        # do not repeat the same moves from the same place; back away and start over
        self._retreat = self._starts >= ATTEMPTS_BEFORE_RETREAT
        view = DockView.of(self.snapshot.frame)
        self._start_facing(-1.0 if view.on_right else 1.0)

    def read(self, raw: tuple[int, ...]) -> None:
        omni, left, right, sources, bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall = raw
        self._view = view_of((omni, left, right))
        self._done = HOME_BASE[sources & 0xFF]  # frame.charging_sources.home_base
        self._hazard = hazard_of(
            bumps, cliff_l, cliff_fl, cliff_fr, cliff_r, virtual_wall, 0, obstacles=False
        )

    def step(self, snap: Snapshot) -> Status:
        now = snap.time
        view = self._view
        if view.seen:
            self._last_seen = now
            if view.side:
                self._last_side = view.side
                self._last_side_time = now
        elif now - self._last_seen >= self._lost_after:
            return self.fail(
                f"lost the dock's beams for {duration_said(self.number('lost_after'))}"
            )
        hazard = self._hazard
        act = _ACTS
        while True:
            status = act[self.state](self, snap, view, hazard)
            if status is not None:
                return status

    # states ------------------------------------------------------------------------
    def _face_state(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        """Face the dock; then done (on the axis), or on toward it: closer, or across."""
        if not self._face(snap, view):
            return RUNNING
        if self._retreat:
            return self._start_retreat()
        if view.on_axis or self._centred:
            # on the axis: the omni sees both buoys, or the last crossing measured both
            # edges of the band and stopped the centre half-way (close to the dock the
            # band at the omni is narrower than what a few degrees of heading move it)
            return self.succeed()
        if self._crossings >= self.MAX_CROSSINGS:
            return self._start_retreat()
        if not (view.omni.from_dock and view.omni.force_field):
            self.state = ApproachState.CLOSER  # along the beams, into the force field first
            self.mark_distance()
            return None
        side = view.side
        if side == 0:
            # force field only: the side last seen, if recent; else guesses that
            # alternate (+1, -1, ...) until one leads into the buoys
            now = snap.time
            if self._last_side and now - self._last_side_time < SIDE_REMEMBERED_S:
                side = self._last_side
            else:
                self._guesses += 1
                side = 1 if self._guesses % 2 else -1
                self._orbit = True  # a guess: circle the dock until a buoy is seen
            self._side_guess = side
        self._cross_side = side or 1
        self._crossings += 1
        self.state = ApproachState.TURN_AWAY
        self._sweep = 1
        self._sweep_before = self._sweep_past = None
        self._centred = False
        self.mark_turn()
        return None

    def _closer(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        """Along the beams until the omni is in the force field (or on the axis)."""
        if view.omni.from_dock and (view.omni.force_field or view.on_axis):
            self._start_facing(1.0)
            if view.on_axis and view.facing:
                return self.succeed()
            return RUNNING
        travelled = abs(snap.odometry.distance_mm - self._distance_mark)  # self.travelled()
        if hazard is not None or travelled > CLOSER_MAX_MM:
            self._start_back()
            return None
        slow = self._speed * CLOSER_SHARE
        inner = slow * CLOSER_INNER_SHARE
        if view.on_left:
            self.wheels(inner, inner + CLOSER_STEER_MM_S)
        elif view.on_right:
            self.wheels(inner + CLOSER_STEER_MM_S, inner)
        else:
            self.wheels(slow, slow)
        return RUNNING

    def _turn_away(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        """Turn ``cross_angle`` away from the dock, toward the axis; then cross (or orbit)."""
        state = self._omni_state(view)
        turned = abs(snap.odometry.angle_rad - self._turn_mark)  # abs(self.turned())
        if state is not None:
            self._sweep = state  # where the omni was last seen relative to the axis
            if state > 0:
                self._sweep_before = turned  # the last turn at which it was before the axis
            elif state < 0 and self._sweep_past is None:
                self._sweep_past = turned  # the first at which it was past it
        if turned < self._cross_angle:
            w = TURN_AWAY_SHARE * self._turn_speed * self._cross_side
            self.wheels(-w, w)
            return RUNNING
        self.state = ApproachState.ORBIT if self._orbit else ApproachState.CROSS
        self._orbit = False
        # the band's edges the omni swept over while turning, as the crossing measures them
        self._before_at = _swept_to_crossing(self._sweep_before, turned)
        self._past_at = _swept_to_crossing(self._sweep_past, turned)
        # turning swings the omni sideways: it may have swept over the axis already
        self._band_seen = self._sweep <= 0
        self._cross_path = snap.odometry.path_mm
        self._last_seen = snap.time  # turning away may hide the beams for a while
        self.mark_distance()
        self._stall = (self._distance_mark, snap.time)
        return None

    def _retreat_state(
        self, snap: Snapshot, view: DockView, hazard: Hazard | None
    ) -> Status | None:
        """Out of the force field while a buoy is still in sight, but never out of every
        beam: that would leave the search to find the dock again. A bump does not end it:
        the bumper is in front, and backing away is what frees it (facing the dock pressed
        against the wall beside it, the retreat ended on its first tick and the approach
        turned back into the same crossing). Held from behind, it ends."""
        travelled = abs(snap.odometry.distance_mm - self._distance_mark)  # self.travelled()
        if (
            (hazard is not None and hazard is not _BUMP)
            or not view.omni.from_dock
            or travelled > RETREAT_MAX_MM
            or self._held_behind(snap, backing=True)
        ):
            self._centred = False
            self._start_facing(self._spin_dir)
            self.halt()
            return RUNNING
        self.wheels(-RETREAT_MM_S, -RETREAT_MM_S)
        return RUNNING

    def _back(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        if snap.time < self._back_until:
            self.wheels(-BACK_MM_S, -BACK_MM_S)
            return RUNNING
        self._start_facing(self._spin_dir)
        self.halt()
        return RUNNING

    def _start_back(self) -> None:
        self.state = ApproachState.BACK
        self._back_until = self.snapshot.time + BACK_S

    def _start_retreat(self) -> Status:
        """No progress: back straight away from the dock (it is ahead), then come in again
        along the beams, so that the next crossing starts from the edge of the force field,
        where the band around the axis is wider, instead of repeating the same moves."""
        self._retreat = False
        self._crossings = 0
        self.state = ApproachState.RETREAT
        self.mark_distance()
        self._stall = (self._distance_mark, self.snapshot.time)
        return RUNNING

    def _held_behind(self, snap: Snapshot, *, backing: bool) -> bool:
        """Driving backwards, the odometry has not got :data:`BACK_STALL_MM` further for
        :data:`BACK_STALL_S`: something holds the robot from behind. A tick not
        ``backing`` restarts the watch."""
        at, since = self._stall
        distance = snap.odometry.distance_mm
        if not backing or distance < at - BACK_STALL_MM:
            self._stall = (distance, snap.time)
            return False
        return snap.time - since >= BACK_STALL_S

    def _leave_held_crossing(self) -> Status:
        """Backing toward the axis against something behind (the wall beside the dock): the
        next crossing from here would back into it again. Face the dock, back straight away
        from it (the wall the dock stands on is then ahead, not behind) and come in again
        along the beams."""
        self._retreat = True
        self._start_facing(-float(self._cross_side))
        self.halt()
        return RUNNING

    def _omni_state(self, view: DockView) -> int | None:
        """Where the omni receiver is relative to the axis, seen from the side the robot
        set out from (``_cross_side``): 1 before it (the near buoy alone), 0 in the band
        (both buoys), -1 past it (the far buoy alone), None when it sees no buoy."""
        omni = view.omni
        if not omni.from_dock or not (omni.red_buoy or omni.green_buoy):
            return None
        if omni.red_buoy and omni.green_buoy:
            return 0
        return 1 if (1 if omni.red_buoy else -1) == self._cross_side else -1

    def _orbit_state(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        """Circle the dock along the edge of its force field until the omni sees a buoy.

        In the force field with no buoy in sight (outside the buoys' wedges) the side of
        the axis is unknown. A straight line toward a guessed side is nearly a tangent
        there: it left the field after a few tens of degrees around the dock, the next
        guess went back the other way, and the robot shuttled between two points
        without ever reaching a buoy. Keeping the omni on the field's edge (turn away
        from the dock inside it, toward it outside) sweeps every bearing in the guessed
        direction; a bump (the wall beside the dock) or 3.5 m without a buoy (half a circle
        around a 1 m field) ends it, and the next guess circles the other way."""
        if self._omni_state(view) is not None:
            self._start_facing(-float(self._cross_side))  # a buoy: the side is known now
            self.halt()
            return RUNNING
        if hazard is not None or snap.odometry.path_mm - self._cross_path > ORBIT_MAX_MM:
            self._start_facing(-float(self._cross_side))
            if hazard is not None:
                self._start_back()
                return None
            self.halt()
            return RUNNING
        v = ORBIT_SHARE * self._speed
        # the dock is on the side opposite to the turn away (_cross_side +1: on the right);
        # the wheel on the side to turn to runs slow
        slow = ORBIT_INNER_SHARE * v
        near, far = (v, slow) if view.omni.force_field else (slow, v)
        if self._cross_side > 0:
            self.wheels(far, near)
        else:
            self.wheels(near, far)
        return RUNNING

    def _cross(self, snap: Snapshot, view: DockView, hazard: Hazard | None) -> Status | None:
        """Move along the crossing line until the centre is on the dock's axis, then face it.

        Only the omni receiver is read: it sits on the crossing line, ``OMNI_AHEAD_MM``
        ahead of the centre. Along that line (``s``, the signed odometry distance) it sees
        the near buoy alone ("before" the axis), both (the band around the axis), then the
        far buoy alone ("past"). The axis is half-way between the last "before" and the
        first "past", and the centre is there when the omni is ``OMNI_AHEAD_MM`` beyond it.
        Close to the dock the band is a few centimetres wide and the omni is often past the
        axis as soon as the robot has turned (driving a fixed distance from wherever the
        omni first saw the band overshot the axis by up to 12 cm, and the robot crossed back
        and forth without ever landing in the band). The edges the turn swept the omni over
        count as seen on this line (:func:`_swept_to_crossing`), so it drives on to the axis
        rather than back over floor it never drove (backing up, 39 of 283 crossings from fresh
        empty-room starts went back up to 12 cm); only when the turn saw no near edge
        (its side remembered from before) does it back up to find one.
        """
        s = snap.odometry.distance_mm - self._distance_mark
        self._note_band(self._omni_state(view), s)
        path = snap.odometry.path_mm - self._cross_path
        left_beams = not view.seen and snap.time - self._last_seen > LEFT_BEAMS_S
        if hazard is not None or left_beams or path > CROSS_MAX_MM:
            if view.side == 0:
                self._last_side = 0  # whatever side was believed, it did not work
            self._start_facing(-float(self._cross_side))
            if hazard is not None and self._last_wheels[0] + self._last_wheels[1] > 0:
                self._start_back()
                return None
            self.halt()
            return RUNNING
        speed = self._speed
        slow = FORCE_FIELD_SHARE if view.force_field else 1.0
        before, past = self._before_at, self._past_at
        if before is not None and past is not None:
            err = (before + past) / 2.0 + OMNI_AHEAD_MM - s
            if abs(err) < CENTRED_MM:
                self._centred = True
                self._start_facing(-float(self._cross_side))
                self.halt()
                return RUNNING
            # max(CENTRE_MIN_MM_S, min(top, wanted)) as comparisons (driving.wheel_speeds
            # says why)
            top, wanted = speed * slow, CENTRE_GAIN_PER_S * abs(err)
            wanted = wanted if wanted < top else top
            v = math.copysign(wanted if wanted > CENTRE_MIN_MM_S else CENTRE_MIN_MM_S, err)
        elif before is None and (past is not None or self._band_seen):
            if s < -NEAR_EDGE_MAX_MM:  # no near buoy behind: give up this crossing, face again
                self._start_facing(-float(self._cross_side))
                self.halt()
                return RUNNING
            # the omni is already over the axis: back to its near edge
            v = -NEAR_EDGE_SHARE * speed * slow
        else:
            v = speed * slow
        if self._held_behind(snap, backing=v < 0.0):
            return self._leave_held_crossing()
        self.wheels(v, v)
        return RUNNING

    def _note_band(self, state: int | None, s: float) -> None:
        """Where (``s``, mm along the crossing) the omni saw the band and its two edges."""
        if state == 0:
            self._band_seen = True
        elif state == 1:  # the furthest "before", the nearest "past" (max, min written out)
            before = self._before_at
            self._before_at = s if before is None or s > before else before
        elif state == -1:
            past = self._past_at
            self._past_at = s if past is None or s < past else past

    # facing the dock ---------------------------------------------------------------
    def _start_facing(self, spin_dir: float) -> None:
        self.state = ApproachState.FACE
        self._spin_dir = spin_dir
        self._lead_theta: float | None = None
        self._face_target: float | None = None
        self.mark_turn()

    def _face(self, snap: Snapshot, view: DockView) -> bool:
        """Turn to face the dock; True once facing it.

        Spinning counter-clockwise, the dock passes from the left receiver to the right one
        (clockwise: the other way round). Both at once: facing. At the edge of a beam the
        two may never see it together: then the heading half-way between the last one seen
        by the leading receiver and the first one by the trailing receiver is the dock's."""
        odo = snap.odometry
        theta = odo.theta_rad  # self.heading()
        if self._face_target is not None:
            return self._turn_to_target(view, theta, self._face_target)
        if view.facing:
            self.halt()
            return True
        left, right = view.left.from_dock, view.right.from_dock
        lead, trail = (left, right) if self._spin_dir > 0 else (right, left)
        if lead:
            self._lead_theta = theta
        if trail and not lead:
            if self._lead_theta is None:
                self._spin_dir = -self._spin_dir  # the dock is on the trailing side: go back
                self.mark_turn()
            else:
                gap = math.remainder(theta - self._lead_theta, math.tau)
                self._face_target = self._lead_theta + gap / 2.0
                return False
        if (
            self._lead_theta is not None
            and not (left or right)
            and abs(math.remainder(theta - self._lead_theta, math.tau)) > FRINGE_RAD
        ):
            # seen at one heading only (the fringe of a beam): face that way and go closer
            self._face_target = self._lead_theta
            return False
        if abs(odo.angle_rad - self._turn_mark) > FACE_RESTART_RAD:  # abs(self.turned())
            self._lead_theta = None
            self.mark_turn()
        w = (FACE_SEEN_SHARE if (left or right) else FACE_SEARCH_SHARE) * self._turn_speed
        self.wheels(-w * self._spin_dir, w * self._spin_dir)
        return False

    def _turn_to_target(self, view: DockView, theta: float, target: float) -> bool:
        """Turn in place to the computed heading ``target``; True once there (or facing
        the dock on the way)."""
        if view.facing or self.spin_to(math.remainder(target - theta, math.tau), self._face_turn):
            self.halt()
            return True
        return False

    state: ApproachState
    _before_at: float | None
    _past_at: float | None
    #: the turns (rad) toward the axis at which the omni was last before it, first past it
    _sweep_before: float | None
    _sweep_past: float | None
    _run: object
    _lead_theta: float | None
    _face_target: float | None
    _face_turn: HeadingTurn
    # the readings (read)
    _view: DockView
    _hazard: Hazard | None


#: Each state's method (see the module's drawing).
_ACTS: dict[
    ApproachState, Callable[[DockApproach, Snapshot, DockView, Hazard | None], Status | None]
] = {
    ApproachState.FACE: DockApproach._face_state,
    ApproachState.CLOSER: DockApproach._closer,
    ApproachState.TURN_AWAY: DockApproach._turn_away,
    ApproachState.RETREAT: DockApproach._retreat_state,
    ApproachState.ORBIT: DockApproach._orbit_state,
    ApproachState.CROSS: DockApproach._cross,
    ApproachState.BACK: DockApproach._back,
}
