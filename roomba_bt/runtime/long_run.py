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

The same look watches for a cycle the robot started by itself (its Clean, Spot or Dock button
pressed, its schedule) while the run has it in Passive (:class:`RobotCycleWatch`): a robot
driving itself while its mission thinks it idle. It was found at the run's end only, hours
later on an overnight patrol. When the stream carries the buttons (packet 18: a mission that
reads them), the look comes every :data:`BUTTON_LOOK_S` too, for the buttons alone: a Clean,
Spot or Dock button pressed in Passive starts the robot's own cycle (the OI spec), and the
run ends at the press. A cycle shorter than the looks need to tell it from a hand, ended by
the tree's own ``mode: safe`` (else a cycle that drove 0.61 m would go unsaid), is
judged as the run's Safe, Full or Stop is written (:meth:`RobotCycleWatch.leaving_passive`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import py_trees

from roomba_bt.behaviours.reasons import running_in
from roomba_bt.oi.bits import CYCLE_BUTTONS
from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import BATTERY_PACKETS, CHARGING_SOURCES_PACKETS, FrameLayout, SensorFrame
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import MM_PER_COUNT, encoder_delta
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.interface import UNKNOWN_CAUSE, ModeChange, Odometer, Odometry, Snapshot
from roomba_bt.robot.weak import weakly
from roomba_bt.runtime.motion_watch import MotionWatch
from roomba_bt.runtime.summary import Outcome, RunSummary

#: the run's own logger, whose warnings these are (as ``runtime/ending.py``'s)
log = logging.getLogger("roomba_bt.runtime.loop")

#: seconds of mission time between two looks at the battery and the charger
LOOK_EVERY_S = 1.0

#: The wheels' travel (mm a second, the mean of the two wheels' counts) from which a look
#: finds the robot driving since the look before: the firmware's slowest cycle move (Seek
#: Dock's last approach) is 80 mm/s, its turns on the spot 150 mm/s a wheel.
DRIVING_MM_S = 50.0
#: Looks running that must find the robot driving in Passive, with no cycle of the run's
#: that may drive, before it is taken for a cycle of its own: two whole seconds and more of
#: driving. A cycle drives on; a hand's push is over in a moment (0.2 m in half a second,
#: across one look at most, or two: it was taken for a cycle at the run's end).
CYCLE_LOOKS = 3
#: How far the robot must have rolled in Passive since it went there, at the run's end, for
#: a drive still under way to be taken for a cycle of its own (a drive's frames still on
#: their way, the wheels spinning down stay under it; a firmware cycle passes it in a third of
#: a second).
ROBOT_CYCLE_MM = 100.0
#: At the run's end, the least time since the last look over which the wheels' travel says
#: whether the robot still drives; shorter, the last look's word stands.
END_LOOK_S = 0.3
#: Seconds of mission time between two looks at the buttons (packet 18), when the stream
#: carries them: the loop looks on the first tick at or after, every fourth (60 ms). The
#: simulator shows a press for 1/6 s, as the robot does for a short push; a finger holds it
#: longer.
BUTTON_LOOK_S = 0.05
#: the buttons' packet
BUTTONS_PACKET = 18


class MissionTimeChecks:
    """The run's time limit (``timeout_s``, None for none) and the looks at the charge,
    written into ``summary`` (:attr:`RunSummary.lowest_battery_percent`,
    :attr:`RunSummary.on_charger_s`), and at the wheels (``motion``: whether the robot does
    what it was told, runtime/motion_watch.py; None: not looked at)."""

    def __init__(
        self,
        summary: RunSummary,
        timeout_s: float | None,
        cycles: RobotCycleWatch | None = None,
        motion: MotionWatch | None = None,
    ) -> None:
        self.summary = summary
        self.timeout_s = timeout_s
        #: the watch for a cycle the robot started by itself (None: not watched)
        self.cycles = cycles
        self.motion = motion
        #: the mission time at which the loop calls :meth:`look` (its first tick: at once):
        #: the next whole look, or sooner a look at the buttons alone
        self.next_at = 0.0
        #: the mission time of the next whole look (the time limit's, the charge's...)
        self._whole_at = 0.0
        #: when the last look was, and whether it found the robot on a powered charger (a
        #: second on the charger is counted from a look that found it there to the next)
        self._looked_at = 0.0
        self._on_charger = False

    def look(self, snapshot: Snapshot, root: py_trees.behaviour.Behaviour) -> bool:
        """At :attr:`next_at` or after: False when the run's time limit ran out, the robot
        drives a cycle of its own (:class:`RobotCycleWatch`; the summary says which, in the
        leaf running under ``root``) or keeps not doing what it is told
        (:meth:`MotionWatch.look`); else the look at the tick's ``snapshot``
        (:meth:`take`), :attr:`next_at` moved on, and True."""
        limit, mission_time = self.timeout_s, snapshot.time
        if limit is not None and mission_time >= limit:
            self.summary.timed_out(limit, running_in(root))
            return False
        cycles = self.cycles
        frame = snapshot.frame
        if cycles is not None:
            pressed = cycles.pressed(frame)
            if pressed is not None:
                cycles.end_run(root, pressed)
                return False
            if mission_time < self._whole_at:  # a look at the buttons alone
                self.next_at = min(self._whole_at, mission_time + BUTTON_LOOK_S)
                return True
            if cycles.look(snapshot.odometry, mission_time):
                cycles.end_run(root)
                return False
        if self.motion is not None and not self.motion.look(snapshot):
            return False
        self.take(mission_time, frame)
        self._whole_at = min(mission_time + LOOK_EVERY_S, math.inf if limit is None else limit)
        self.next_at = self._whole_at
        if cycles is not None and cycles.watches_buttons(frame):
            self.next_at = min(self.next_at, mission_time + BUTTON_LOOK_S)
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


class RobotCycleWatch:
    """A cycle the robot started by itself (its Clean, Spot or Dock button, its schedule)
    while the run has it in Passive, where nothing the run may send stops it: found by the
    once-a-second look (:meth:`look`: the robot driving in Passive, with no cycle of the
    run's that may drive, at :data:`CYCLE_LOOKS` looks running), by the look at the buttons
    when the stream carries them (:meth:`pressed`), as the run's own Safe, Full or Stop
    ends it (:meth:`leaving_passive`), and at the run's end (:meth:`at_end`).
    ``connection``'s writer is told (``CommandWriter.robot_cycle``: the safe stop then sends
    Safe first and ends it, Start alone ending no cycle: docs/protocol.md, "What ends a
    built-in cycle"), ``summary`` says it, a warning is logged. ``odometer``: the run's,
    told by the writer each time the robot goes to Passive; ``clock``: the mission time so
    many seconds after the last tick's frame (``RunEnding.clock``).

    Read off the encoders the stream always carries, at the look: what tells a cycle from a
    hand pushing the robot is that a cycle drives on. Packet 35 reads Passive in both, the
    requested velocities (39-42) are the OI's Drive commands', not a cycle's, and the wheel
    motors' currents (54, 55), which a push does not draw, are streamed only for a mission
    that reads them (asking for them would change every run's stream request); the buttons
    (18) too, which tell it at the press."""

    def __init__(
        self,
        connection: Connection,
        summary: RunSummary,
        odometer: Odometer,
        clock: Callable[[float], float | None],
    ) -> None:
        self.connection = connection
        self.summary = summary
        self.odometer = odometer
        self.clock = clock
        writer = connection.writer
        # weakly: the writer is the connection's, which its finalizer's safe stop reaches;
        # a strong hook back to this watch (which holds the connection) kept every run's
        # connection, simulator and tree alive for ever (robot/weak.py)
        writer.on_passive = weakly(self._entered_passive, None)
        writer.on_cycle_end = weakly(self.leaving_passive, None)
        #: the robot is in a Passive the run's commands or its own fall put it in (the run
        #: starts there), until a Safe, Full or Stop of the run's is written
        self._in_passive = True
        #: the last fall to Passive by itself the watch was told of (the connection's
        #: ``last_fallback``, by its tick and link time: the runtime replaces the object
        #: with a copy that has its mission time), and the fall of unknown cause that began
        #: the Passive the robot is in now (None: the run's command, or a fall with a cause)
        self._fall_seen: tuple[int, float] | None = None
        self._unknown_fall: tuple[int, float] | None = None
        #: the encoder counts (left, right) and the mission time of the last look
        self._counts: tuple[int, int] | None = None
        self._looked_at = 0.0
        #: looks running that found the robot driving in Passive by itself
        self.driving_looks = 0
        #: the last frame layout asked about and whether it carries the buttons
        self._layout: FrameLayout | None = None
        self._buttons_at: int | None = None

    def _entered_passive(self) -> None:
        """The writer's word that the robot went to Passive (a command, its own fall): the
        path it drives there is measured from here."""
        self._in_passive = True
        self.odometer.entered_passive()
        change = self.connection.last_fallback
        if change is None:
            return
        key = (change.tick, change.time)
        fresh = key != self._fall_seen
        self._fall_seen = key
        self._unknown_fall = key if fresh and change.cause == UNKNOWN_CAUSE else None

    def look(self, odometry: Odometry, mission_time: float) -> bool:
        """Whether the robot, as ``odometry`` has it at ``mission_time``, has driven in
        Passive by itself at :data:`CYCLE_LOOKS` looks running: a cycle of its own. Out of
        Passive, or with a cycle of the run's that may drive, nothing is measured (the next
        look in Passive measures from itself): most looks of a run that drives, and the
        cheapest (instruction counts: ``python -m bench.icount --against``)."""
        if not self._unbidden():
            self._counts, self.driving_looks = None, 0
            return False
        driving = self._driving(odometry, mission_time)
        self.driving_looks = self.driving_looks + 1 if driving else 0
        return self.driving_looks >= CYCLE_LOOKS

    def watches_buttons(self, frame: SensorFrame) -> bool:
        """Whether ``frame``'s stream carries the buttons (packet 18), which the loop then
        looks at every :data:`BUTTON_LOOK_S` (:meth:`pressed`)."""
        layout = frame.layout
        if layout is not self._layout:
            self._layout, self._buttons_at = layout, layout.index.get(BUTTONS_PACKET)
        return self._buttons_at is not None

    def pressed(self, frame: SensorFrame) -> str | None:
        """The button of :data:`CYCLE_BUTTONS` that ``frame`` shows pressed while the robot
        is in Passive with no cycle of the run's (it starts the robot's own cycle there),
        None for none (or no buttons in the stream)."""
        if not self.watches_buttons(frame) or not self._unbidden():
            return None
        buttons = frame.buttons
        return next((name for name in CYCLE_BUTTONS if getattr(buttons, name)), None)

    def _driving(self, odometry: Odometry, mission_time: float) -> bool:
        """Whether the wheels travelled :data:`DRIVING_MM_S` a second or more since the last
        look (the mean of the two wheels' counts, a turn on the spot's too); the look's
        counts kept for the next."""
        before, since = self._counts, self._looked_at
        left, right = odometry.left_counts, odometry.right_counts
        self._looked_at = mission_time
        if left is None or right is None:  # a stream without the encoders
            self._counts = None
            return False
        self._counts = (left, right)
        if before is None or mission_time <= since:
            return False
        turned = abs(encoder_delta(before[0], left)) + abs(encoder_delta(before[1], right))
        return turned * MM_PER_COUNT / 2.0 >= DRIVING_MM_S * (mission_time - since)

    def _unbidden(self) -> bool:
        """In Passive with no cycle of the run's that may drive: what moves the robot is its
        own doing (or a hand's)."""
        connection = self.connection
        return connection.mode is OIMode.PASSIVE and not connection.writer.builtin_may_run

    def end_run(self, root: py_trees.behaviour.Behaviour, button: str | None = None) -> None:
        """A look found a cycle of the robot's own (``button``: the one seen pressed, which
        starts it; None: the wheels drove on): the run ends here, FAILURE (exit 1), its
        reason saying so and what the tree was doing (``root``'s running leaf). Ended, not
        ridden: the tree took the robot for idle in Passive, where the run can stop no
        cycle (drive 0 is refused there; Safe ends the cycle, but would take the robot from
        under the tree); its safe stop ends it with Safe first."""
        summary = self.summary
        summary.outcome = Outcome.FAILURE
        summary.reason = (
            f"{self._said(self.odometer.driven_in_passive(), button=button)} while the tree "
            f"ran{running_in(root)}; the run ended there, its safe stop ending the cycle with "
            "Safe first (Start alone ends none)"
        )
        if button is not None:
            summary.reason += (
                "; a mission that waits for a button puts `mode: safe` first (Safe and Full "
                "start no cycle at a button)"
            )

    def leaving_passive(self, command: Command) -> None:
        """The writer's word that ``command``, which ends cycles (Safe, Full, Stop, Reset),
        is being written (the mode model already moved; the writer's cycle state not yet):
        from a Passive with no cycle of the run's, what the robot drove there by itself
        since the last look is judged now, as at the run's end (:meth:`_judged`), and said
        with the command as what ended it, so that a cycle two seconds long, ended by the
        mission's own ``mode: safe`` between two looks, is said too."""
        in_passive, self._in_passive = self._in_passive, False
        writer = self.connection.writer
        if not in_passive or writer.builtin_may_run or writer.robot_cycle is not None:
            return
        mission_time = self.clock(0.0)
        if mission_time is not None:
            spec = command.spec
            ended = f"the run's {spec.title} ({spec.opcode}) at t={mission_time:.3f} ended it"
            self._judged(self.odometer.odometry, mission_time, ended=ended)
        self._counts, self.driving_looks = None, 0

    def at_end(self, snapshot: Snapshot) -> None:
        """Before the safe stop, one look more at the last tick's ``snapshot``: a button
        that starts a cycle pressed in its frame (a tree that waited for it ends on that
        tick, before the cycle has moved the robot), else the wheels (:meth:`_judged`)."""
        if self.connection.writer.robot_cycle is not None or not self._unbidden():
            return
        button = self.pressed(snapshot.frame)
        if button is not None:
            self._said(self.odometer.driven_in_passive(), button=button)
            return
        self._judged(snapshot.odometry, snapshot.time)

    def _judged(self, odometry: Odometry, mission_time: float, ended: str = "") -> None:
        """One look more at the time since the last (if :data:`END_LOOK_S` or more; else the
        last look's word stands): driving at :data:`CYCLE_LOOKS` looks running, a cycle of
        the robot's own, said as :meth:`look`'s; driving at the last only, with over
        :data:`ROBOT_CYCLE_MM` driven in Passive since it went there, a cycle or a hand,
        which the looks had no time to tell apart: said so, and the stop sends Safe first
        all the same (harmless off the dock; Start alone would leave a cycle driving after
        the run). A push over before the last look is neither. ``ended``: what ends it, when
        not the safe stop (the tree's Safe, Full or Stop)."""
        looks = self.driving_looks
        if mission_time - self._looked_at >= END_LOOK_S:
            looks = looks + 1 if self._driving(odometry, mission_time) else 0
        driven = self.odometer.driven_in_passive()
        if looks >= CYCLE_LOOKS:
            self._said(driven, ended=ended)
        elif (looks or self._unknown_fall is not None) and driven > ROBOT_CYCLE_MM:
            # a Passive begun by a fall of no cause (a cycle command made of a lost byte
            # does it) needs no look: the run had ended a second after such a Clean, before
            # the looks saw the robot drive, and its Start left the cycle cleaning
            self._said(driven, told_apart=False, ended=ended)

    def _said(
        self,
        driven_mm: float,
        *,
        told_apart: bool = True,
        button: str | None = None,
        ended: str = "",
    ) -> str:
        """The writer told of the robot's cycle, the summary's word on it and the warning
        (``driven_mm``: its path in Passive; ``told_apart``: the looks saw it drive on, a
        cycle, not a hand; ``button``: the one seen pressed; ``ended``: what ends it, when
        not the safe stop, which the writer is then not told of); the cycle said, for a
        run's reason."""
        connection = self.connection
        writer = connection.writer
        driven = f"{driven_mm / 1000:.2f} m"
        fell = self._fall_of_no_cause()
        if button is not None:
            said = (
                f"the robot started a cycle by itself: its {button.capitalize()} button was "
                "pressed in Passive (packet 18), where it starts the robot's own cycle"
            )
        elif fell is not None:
            said = self._cycle_from_the_line(fell, driven, told_apart=told_apart, ended=ended)
        elif told_apart:
            said = (
                "the robot started a cycle by itself (its Clean, Spot or Dock button, or its "
                f"schedule): it drove {driven} in Passive with no command of the run's"
            )
        else:
            said = (
                "the robot was moving in Passive with no command of the run's as the "
                f"{'run left Passive' if ended else 'run ended'} ({driven} since it went "
                "there): a cycle it started by itself (its Clean, Spot or Dock button, or its "
                "schedule), or a hand"
            )
        if ended:
            said_end = ended
        else:
            writer.robot_cycle = said
            said_end = (
                "the safe stop ends it with Safe first"
                if writer.cycle_may_drive
                else "it was on its home base at the end (docked: no Safe, which would stop "
                "the charge)"
            )
        self.summary.robot_cycle = f"{said}; {said_end}"
        log.warning("%s: %s", connection.name, self.summary.robot_cycle)
        return said

    def _fall_of_no_cause(self) -> ModeChange | None:
        """The fall of unknown cause from Safe or Full that began the robot's Passive now,
        as the connection has it (with its mission time, once the run placed it); None
        when a command of the run's or a fall with a cause began it."""
        change = self.connection.last_fallback
        if change is None or self._unknown_fall != (change.tick, change.time):
            return None
        return change

    def _cycle_from_the_line(
        self, fell: ModeChange, driven: str, *, told_apart: bool, ended: str
    ) -> str:
        """The words for a robot driving in a Passive it fell to by itself from Safe or Full
        with no cause in its frame (no cliff, wheel drop or charger). Safe and Full ignore
        the buttons (both specs: "does not respond to button presses"), so no button started
        it: a cycle command the robot heard, which the run never wrote (its tree's Drive
        Direct at 135 mm/s, ``91 00 87 00 a5``, its opcode lost on the line: 135 is Clean).
        A wall-follow on a line losing 2 bytes in 10 000 was said "its Clean, Spot or Dock
        button, or its schedule", and its owner sent to the buttons, not the cable."""
        from roomba_bt.transport.link_kind import link_of

        at = "" if fell.mission_time is None else f" at t={fell.mission_time:.3f}"
        how = (
            f"it left {fell.previous.label} by itself{at} with no cliff, wheel drop or charger "
            f"in its frame, and {fell.previous.label} ignores the buttons"
        )
        line = (
            "a Clean (135), Spot (134), Max (136) or Seek Dock (143) made of a byte lost or "
            "changed on the line, most likely (a data byte read as an opcode: check "
            f"{link_of(self.connection.name).byte_check}: roomba-bt doctor)"
        )
        if told_apart:
            return (
                f"the robot started a cycle the run did not send: {how}, then drove {driven} "
                f"in Passive with no command of the run's: {line}"
            )
        return (
            "the robot was moving in Passive with no command of the run's as the "
            f"{'run left Passive' if ended else 'run ended'} ({driven} since {how}): {line}, "
            "or a hand"
        )


def say_waits_past_sleep(mission: object, connection: Connection) -> None:
    """Name, when the run starts, each ``wait`` of ``mission`` that may run in Passive
    longer than the 5 minutes the robot sleeps after there
    (:attr:`~roomba_bt.mission.build.CompiledMission.waits_past_sleep`), when keep-awake
    cannot keep it awake on this connection: off, no modem line, or (known at its first
    pulse) a port that cannot drive the lines. Without it, ``patrol -p charge_for=10min``
    on a pty docks, sleeps 5 minutes into the charge wait and ends "the robot fell asleep"
    (exit 8), with only keep-awake's own line at the start ("Passive sleeps after 5 min"),
    which names no wait."""
    waits: tuple[str, ...] = getattr(mission, "waits_past_sleep", ())
    if not waits:
        return
    from roomba_bt.robot import wording
    from roomba_bt.transport.link_kind import link_of

    pulse_fix = link_of(connection.name).pulse_fix
    if not connection.keep_awake:
        caller = wording.current
        _say_waits(waits, f"keep-awake is off ({caller.keep_awake_off})", caller.keep_awake_on)
    elif connection.wake is None:
        _say_waits(waits, "this link has no modem line to pulse BRC on", pulse_fix)
    else:
        connection.wake.on_unavailable = lambda why: _say_waits(
            waits, f"keep-awake cannot pulse BRC here ({why})", pulse_fix
        )


def _say_waits(waits: tuple[str, ...], why: str, fix: str) -> None:
    for wait in waits:
        log.warning(
            "%s may run in Passive (as on the dock, charging) longer than the 5 minutes the "
            "robot sleeps after there with nothing from us, and %s: it cannot finish (the "
            "robot falls asleep 5 minutes into it and the run ends, exit 8); %s, or wait "
            "5 minutes or less",
            wait, why, fix,
        )  # fmt: skip
