"""How far ``cover``, ``home_by_map`` and the ``backtrack`` leaf may back up:
only over floor just driven, never onto a known drop.

Why: a Create 2 sees nothing behind it (no bumper, no cliff sensor behind the wheels), and
``cover`` backs up in four places (off a bump, a cliff or a virtual wall's beam; off one
along an edge; started again after the firmware's stop at a cliff; before the arc onto the
next lane, up to 18 cm of room for its radius). Backing blind, the arc drops a wheel down
the apartment's stairs (living room, seed 8, 1.5 % encoder error, in both one and two
passes): a lane that ends where it began, at a drop its drifted map has on the wrong side,
after a turn in place, and the arc's 18 cm back goes over the real edge behind.
``home_by_map`` keeps the same :class:`~.coverage_map.Bearings` and backs up by the same
rule (each of its legs begins with a turn in place: a beam's or a wedge's 10 cm back would
go over floor it had not driven).

What a back-off may cover now::

    the trail       the centre's poses over the last TRAIL_MM of driving, one every STEP_MM
                    (forward or back); a turn in place adds none
    a step back     of STEP_MM along the heading's opposite is floor driven when the line
                    between two poses of the trail passes within NEAR_MM of it, both facing
                    within TURN of the heading now (the wheels then go back over their own
                    tracks, give or take the tolerance, never past where the trail begins);
                    and no known drop (:meth:`~.drops.KnownDrops.behind`, not a
                    guess) under the back half of the body there or just beyond
    the back-off    the steps in a row from the robot that are both, up to what was wanted:
                    shortened, or none (turned in place since the last move: the floor
                    behind is floor it never drove); off a hazard ahead, the first OWN_MM
                    need no trail (in Safe mode a cliff showing leaves it no other move)

The missions' own back-offs (``backtrack``: ``patrol.yaml`` after a cliff or a beam,
``bump-and-turn.yaml`` after a bump) read the run's trail
(:func:`run_trail`), which the leaves that move the robot (``drive``, ``turn``, ``backtrack``,
``wall_follow``) feed on every tick they run. Why: patrol's fixed 15 cm after
a cliff met a few centimetres after its 60 deg turn in place went back over floor it had never
driven, toward the stairs' edge beside it. A move no feeding leaf saw (another leaf drove)
leaves a gap in the path the odometry counts, and the trail starts again after it
(:meth:`RunTrail.feed`): the floor behind is then not known to be driven.

What the map's cells say is not used: 10 cm cells in a frame the encoders' error drifts
from the floor (the drop drawn on the wrong side was the map's); the trail is the last metre,
where odometry is still exact enough. The cost: a comparison per tick (a pose added per
STEP_MM driven), and a few thousand when a back-off starts.
"""

from __future__ import annotations

import math
from collections import deque
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from roomba_bt.behaviours.drops import KnownDrops
    from roomba_bt.robot.interface import Odometry

import py_trees

from roomba_bt.behaviours.blackboard import TRAIL_KEY, run_board

__all__ = [
    "NEAR_MM", "OWN_MM", "STEP_MM", "TRAIL_KEY", "TRAIL_MM", "TURN", "RunTrail", "Trail",
    "run_trail",
]  # fmt: skip

#: the trail keeps a pose every this many mm of driving, and a back-off is looked at in
#: steps of this many mm
STEP_MM = 10.0
#: how much driving (mm) the trail keeps: more than the longest back-off (18 cm)
TRAIL_MM = 600.0
#: a step back is floor driven when a pose of the trail is this near (mm) ...
NEAR_MM = 30.0
#: ... and faced within this (rad) of the heading now
TURN = math.radians(15.0)

#: a back-off off a hazard ahead (a bump, a cliff, a beam) may go this far (mm) with no
#: trail, as long as no known drop is behind: the wheels stay under the body's own back
#: (117 mm out, 13 cm from the centre at most). Why: in Safe mode, with a cliff showing,
#: the firmware stops any move but straight back (a turn in place too: "a cliff while
#: turning tighter than the robot's radius"), so a robot that turned in place onto an edge
#: and may not back off is stopped again at every move; with none, 10 living-room runs
#: met the firmware's stop 715 times, not 140
OWN_MM = 60.0

_NEAR_SQ = NEAR_MM * NEAR_MM


class Trail:
    """Where the robot's centre has just been (the module's table): the poses of the last
    :data:`TRAIL_MM` of driving, in ``cover``'s own frame, and how far back it may go."""

    def __init__(self) -> None:
        self._poses: deque[tuple[float, float, float]] = deque(maxlen=int(TRAIL_MM / STEP_MM) + 1)

    def add(self, pose: Odometry) -> bool:
        """The pose after this tick: kept (True) when it is :data:`STEP_MM` from the last
        kept."""
        poses = self._poses
        x, y = pose.x_mm, pose.y_mm
        if poses:
            last = poses[-1]
            dx, dy = x - last[0], y - last[1]
            if dx * dx + dy * dy < STEP_MM * STEP_MM:
                return False
        poses.append((x, y, pose.theta_rad))
        return True

    def turned(self, by: float) -> None:
        """The pose's heading was turned ``by`` (rad) where it stands (re-anchored on a
        wall): the trail's headings with it, so that the floor behind is judged as before."""
        turned = [(x, y, theta + by) for x, y, theta in self._poses]
        self._poses.clear()
        self._poses.extend(turned)

    def clear(self) -> None:
        """Forget the trail: nothing behind is known to be driven."""
        self._poses.clear()

    def reversible(
        self, pose: Odometry, wanted: float, drops: KnownDrops | None, own: float = 0.0
    ) -> float:
        """How far (mm, up to ``wanted``) the robot at ``pose`` may back up straight: the
        steps in a row over floor it has driven with no known drop behind (the module's
        table); 0 when the first is not. The first ``own`` mm need no trail (a hazard's
        back-off: :data:`OWN_MM`), only no known drop (``drops`` None: none known)."""
        if wanted <= 0.0:
            return 0.0
        heading = pose.theta_rad
        back = heading + math.pi
        c, s = math.cos(back), math.sin(back)
        steps = math.ceil(wanted / STEP_MM)
        for k in range(1, steps + 1):
            d = min(wanted, k * STEP_MM)
            x, y = pose.x_mm + d * c, pose.y_mm + d * s
            if d > own and not self._driven(x, y, heading):
                return (k - 1) * STEP_MM
            if drops is not None and drops.behind(pose._replace(x_mm=x, y_mm=y)):
                return (k - 1) * STEP_MM
        return wanted

    def _driven(self, x: float, y: float, heading: float) -> bool:
        """Has the centre driven past (x, y), within :data:`NEAR_MM` of it, between two poses
        of the trail facing within :data:`TURN` of ``heading``?"""
        poses = self._poses
        for k in range(1, len(poses)):
            ax, ay, a_theta = poses[k - 1]
            bx, by, b_theta = poses[k]
            dx, dy = bx - ax, by - ay
            length_sq = dx * dx + dy * dy
            t = ((x - ax) * dx + (y - ay) * dy) / length_sq  # kept poses are STEP_MM apart
            if not 0.0 <= t <= 1.0:
                continue
            ox, oy = ax + t * dx - x, ay + t * dy - y
            if ox * ox + oy * oy > _NEAR_SQ:
                continue
            if (
                abs(math.remainder(a_theta - heading, math.tau)) <= TURN
                and abs(math.remainder(b_theta - heading, math.tau)) <= TURN
            ):
                return True
        return False


#: path (mm) the odometry may grow between two feeds of the run's trail: more is a move no
#: feeding leaf saw (about 7 mm a 15 ms tick at 500 mm/s; a lost frame or two)
GAP_MM = 40.0


class RunTrail(Trail):
    """The run's trail in the raw odometry's frame, fed by ``drive``, ``turn``, ``backtrack``
    and ``wall_follow`` on the ticks they run (the module's doc): what a mission's
    ``backtrack`` may back over."""

    def __init__(self) -> None:
        super().__init__()
        self._fed_path: float | None = None
        #: the path (mm) at the last pose kept (:meth:`Trail.add`), -inf when none is
        self._kept_path = -math.inf

    def feed(self, odo: Odometry) -> None:
        """The odometry this tick, from a leaf that moves the robot: a move since the last
        feed that no feeding leaf saw (more than :data:`GAP_MM` of path) starts it again.

        Called on every tick a ``drive`` or ``wall_follow`` runs: on most, the centre has
        gone less than :data:`STEP_MM` of path since the last pose kept, so it is no
        :data:`STEP_MM` away from it either (a path is never shorter than the line) and
        ``add`` would keep nothing: that is settled by one subtraction, without ``add``'s
        distance (a call and a pose read cost 6,000 instructions a bump-and-turn tick)."""
        path = odo.path_mm
        fed = self._fed_path
        self._fed_path = path
        if fed is None or not 0.0 <= path - fed <= GAP_MM:  # self.gap(odo), inline
            self.clear()
        elif path - self._kept_path < STEP_MM:
            return
        if self.add(odo):
            self._kept_path = path

    def clear(self) -> None:
        super().clear()
        self._kept_path = -math.inf

    def gap(self, odo: Odometry) -> bool:
        """Has the robot moved since the last feed (a leaf that feeds none drove it)?"""
        fed = self._fed_path  # (a path shorter than fed: another run's odometry)
        return fed is None or not 0.0 <= odo.path_mm - fed <= GAP_MM

    def backable(self, odo: Odometry, wanted: float, own: float = OWN_MM) -> float:
        """How far (mm, up to ``wanted``) the robot at ``odo`` may back up: over the floor
        its trail shows it just drove, the first ``own`` mm (under its own body) aside."""
        if self.gap(odo):
            return min(wanted, own)
        return self.reversible(odo, wanted, None, own)


def run_trail() -> RunTrail:
    """The run's :class:`RunTrail` (made on first use; each run has its own board)."""
    storage, name = py_trees.blackboard.Blackboard.storage, run_board().name(TRAIL_KEY)
    trail = storage.get(name)
    if not isinstance(trail, RunTrail):
        trail = storage[name] = RunTrail()
    return trail


def forget_run_trail() -> None:
    """A new run's set-up: no trail of an earlier run's (a board kept in the process)."""
    py_trees.blackboard.Blackboard.storage.pop(run_board().name(TRAIL_KEY), None)
