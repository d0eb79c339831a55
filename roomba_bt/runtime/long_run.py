"""What the tick loop looks at now and then by mission time, not on every tick: the run's
time limit, and once a second the battery and the charger, for the summary of a long run.

An overnight patrol's summary said its battery at the end only, and each docking as "fell
to Passive by itself (charger)", with nothing of the hours it charged. The lowest battery
level seen and the time on the charger are read here from the tick's snapshot once every
:data:`LOOK_EVERY_S` of mission time (a battery's level moves by about 0.01 % a second, a
docking lasts minutes): exact to a second, the same on a replay or a run made again (it is
mission time, not the wall clock's), and nothing more on the tick path. The loop compared
its mission time with the time limit on every tick (the limit read twice off the runner); it
now compares it with the time of the next look (:attr:`MissionTimeChecks.next_at`, the time
limit when that is sooner), and calls :meth:`MissionTimeChecks.look` when it is reached: the
time limit ends the run on the same tick as before.
"""

from __future__ import annotations

import math

import py_trees

from roomba_bt.behaviours.reasons import running_in
from roomba_bt.oi.frames import BATTERY_PACKETS, CHARGING_SOURCES_PACKETS, SensorFrame
from roomba_bt.robot.interface import Snapshot
from roomba_bt.runtime.summary import RunSummary

#: seconds of mission time between two looks at the battery and the charger
LOOK_EVERY_S = 1.0


class MissionTimeChecks:
    """The run's time limit (``timeout_s``, None for none) and the looks at the charge,
    written into ``summary`` (:attr:`RunSummary.lowest_battery_percent`,
    :attr:`RunSummary.on_charger_s`)."""

    def __init__(self, summary: RunSummary, timeout_s: float | None) -> None:
        self.summary = summary
        self.timeout_s = timeout_s
        #: the mission time at which the loop calls :meth:`look` (its first tick: at once)
        self.next_at = 0.0
        #: when the last look was, and whether it found the robot on a powered charger (a
        #: second on the charger is counted from a look that found it there to the next)
        self._looked_at = 0.0
        self._on_charger = False

    def look(self, snapshot: Snapshot, root: py_trees.behaviour.Behaviour) -> bool:
        """At :attr:`next_at` or after: False when the run's time limit ran out (the summary
        says so, in the leaf running under ``root``); else the look at the tick's
        ``snapshot`` (:meth:`take`), :attr:`next_at` moved on, and True."""
        limit, mission_time = self.timeout_s, snapshot.time
        if limit is not None and mission_time >= limit:
            self.summary.timed_out(limit, running_in(root))
            return False
        self.take(mission_time, snapshot.frame)
        self.next_at = min(mission_time + LOOK_EVERY_S, math.inf if limit is None else limit)
        return True

    def take(self, mission_time: float, frame: SensorFrame) -> None:
        """The battery and the charger as ``frame`` shows them at ``mission_time``: the
        lowest level so far, and the time since the last look counted on the charger if
        that look found the robot there. A frame without the packets leaves them unknown
        (the battery's are streamed when the link's budget allows them)."""
        summary = self.summary
        if self._on_charger:
            summary.on_charger_s += mission_time - self._looked_at
        self._looked_at = mission_time
        self._on_charger = frame.carries(CHARGING_SOURCES_PACKETS) and frame.charging_sources.any
        if frame.carries(BATTERY_PACKETS):
            level = frame.battery_percent
            lowest = summary.lowest_battery_percent
            if lowest is None or level < lowest:
                summary.lowest_battery_percent = level
