"""A watchdog trip, ridden through: the run's read of the stream when frames stop coming.

The connection's watchdog sends drive 0 (and motors off, if a brush or the vacuum runs) when
no valid frame came for its time and raises :class:`~roomba_bt.robot.errors.StreamStalled`
once. A noisy cable or a loaded machine makes such gaps; the run waits up to its grace
(``--grace``, 2 s) for valid frames. Frames coming back let the tree go on where it was, the
wheels and the motors given their last commands again; none within
the grace ends the run with the cause the connection finds (a garbled line, a robot asleep,
reset or switched off: :meth:`~roomba_bt.robot.connection.Connection.check_stall`).

The tick guard's drive 0 (a tick that blocked: :mod:`roomba_bt.runtime.tick_guard`) is ridden
through the same way (:meth:`StallRide.tick_halted`): counted, the frames it left unread not
taken for a gap nobody read, the wheels and the motors given their last commands again. A
tick the guard saw past its limit with nothing moving, or while a built-in cycle may have
driven the robot (:meth:`StallRide.tick_still`), sent nothing and gets nothing back, but
the frames it left unread are its own too.

A loaded machine (a pty simulator beside a busy build, a paused run on a shared laptop) makes
a late frame every few seconds, and each was two warnings: 21 of them in 5 minutes of a pause,
which nobody can act on. The first stall is said in full, trip and return; those ridden
through in the minute after it are counted, and said as one line when a minute has gone by
(:class:`LateFrames`: how many, the longest, how many sent drive 0). A stall that lasts half
its grace is said at once all the same (a real one: a cable, a robot asleep), and one that
ends the run says why as ever.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

from roomba_bt.oi.encode import Command, turns_wheels
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.printable import duration_words
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import StreamStalled
from roomba_bt.robot.hazards import sets_going
from roomba_bt.robot.interface import Outbox
from roomba_bt.runtime.schedule import LOST_LATE
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.runtime.tick_guard import TickGuardLike

log = logging.getLogger("roomba_bt.runtime.loop")

#: What frames back after a stall say of a run the monitor holds paused: nothing goes on
#: until the operator resumes (the wheels and motors were stopped by the pause itself)
PAUSED_GOES_ON = "the run stays paused (the mission goes on at the resume)"

#: After a stall is said, the link's seconds in which the next ones ridden through are counted
#: and summed up in one line rather than each said (:class:`LateFrames`)
QUIET_S = 60.0


class LateFrames:
    """The stalls ridden through since the last one said: how many, the longest gap and how
    many sent drive 0, summed up in one line once :data:`QUIET_S` has gone by."""

    def __init__(self) -> None:
        self.count = 0
        self.longest = 0.0
        #: the mission time the longest began at (its last valid frame's; None: before the
        #: first tick)
        self.longest_at: float | None = None
        self.halts = 0

    def add(self, gap: float, halted: bool, began_at: float | None) -> None:
        self.count += 1
        if gap > self.longest:
            self.longest, self.longest_at = gap, began_at
        self.halts += halted

    def said(self, name: str, since: float, goes_on: str, when: str = "once a minute") -> str:
        """The line: ``frames were late 21 more times in the last 5 min 2 s (longest 421
        ms, from t=12.345), each back within the grace: ...``; ``when``: when such a line is
        said (once a minute; at the run's end, the stalls counted since the last)."""
        sent = (
            f"drive 0 sent in {self.halts} (the robot stopped until the frames came back)"
            if self.halts
            else "the robot was not driving (nothing sent)"
        )
        at = "" if self.longest_at is None else f", from t={self.longest_at:.3f}"
        return (
            f"{name}: frames were late {self.count} more "
            f"{'time' if self.count == 1 else 'times'} in the last {duration_words(since)} "
            f"(longest {self.longest * 1000:.0f} ms{at}), each back within the grace: {sent}; "
            f"{goes_on} (a busy computer or link; said {when}, the summary's stalls line "
            "counts them all)"
        )


class StallRide:
    """The run's reads, each trip counted in ``summary`` and ridden through for ``grace``
    seconds (0: the trip ends the run); once frames are back the tree's last wheel command
    goes into ``outbox`` again (the watchdog's drive 0 had replaced it). ``clock`` is the mission
    time so many seconds after the last valid frame (None before the first): no tick moves
    the mission clock during a stall, so the trip and the frames' return are stamped with
    their own times, not both with the last frame's. ``paused``: whether the monitor holds
    the run paused (the runner's ``clock_held``): frames back then leave it paused, and the
    log says so (it said "the mission goes on" of a run nobody had resumed)."""

    def __init__(
        self,
        connection: Connection,
        outbox: Outbox,
        summary: RunSummary,
        grace: float,
        clock: Callable[[float], float | None],
        paused: Callable[[], bool] = lambda: False,
    ) -> None:
        self.connection = connection
        self.paused = paused
        self.outbox = outbox
        self.summary = summary
        self.grace = grace
        self._clock = clock
        #: while a stall is ridden through: (bytes read when it began, drive 0 sent, the
        #: last valid frame's time)
        self.stall: tuple[int, bool, float] | None = None
        #: the next batch's gap is a stall ridden through, not a gap nobody read (read once
        #: by the run's clock, :meth:`StreamClock.slots_spanned
        #: <roomba_bt.runtime.clock.StreamClock.slots_spanned>`)
        self.gap_explained = False
        #: the tick before the next batch blocked past the tick guard's limit (how long it had
        #: run when the guard saw it, where, whether the guard stopped the wheels or the
        #: motors in it, and the built-in cycle that may have driven the robot meanwhile, ""
        #: if nothing moved): the next batch's gap is that tick's (set by :meth:`tick_halted`
        #: and :meth:`tick_still`, read once as ``gap_explained``)
        self.blocked: tuple[float, str, bool, str] | None = None
        #: once frames are back, while the frames that waited are read (the stall's
        #: backlog, over several reads): when the last of its batches came (None: not back)
        self._backlog_read_at: float | None = None
        #: the link's time the last stall was said (None: none yet), the stalls ridden
        #: through since, counted and not said, and whether the one ridden now is such a one
        #: (its trip not said: said late if it lasts half the grace)
        self._said_at: float | None = None
        self._late = LateFrames()
        #: the link's time the tally began (the line before it was said)
        self._late_since = 0.0
        self._quiet = False
        self._tripped: StreamStalled | None = None

    def tripped(self, stalled: StreamStalled) -> Sequence[SensorFrame]:
        """The watchdog tripped (drive 0 sent): the ride begins, no frames this read; or,
        without a grace, the trip ends the run, as does one whose frames are another
        model's (``mismatch``): that diagnosis is certain at the trip (the robot streams all
        along, every frame refused by the profile alone), and the run waited the whole grace
        for frames that could not come."""
        if self.grace <= 0:
            raise stalled
        self.summary.stalls += 1
        self.summary.stall_halts += stalled.halted
        if stalled.mismatch is not None:
            raise stalled
        link = self.connection.link
        self.stall = (link.bytes_read, stalled.halted, link.silent_since)
        self._backlog_read_at = None
        at = link.silent_since + stalled.silent_for
        said_at = self._said_at  # a minute gone with stalls counted: said at this one's end
        self._quiet = said_at is not None and (at - said_at < QUIET_S or self._late.count > 0)
        self._tripped = stalled
        if not self._quiet:
            self._say_trip(stalled, stalled.silent_for, at)
        else:  # each one still, with -v: an operator tracing the link wants them all
            log.debug(
                "%s; waiting up to %g s for valid frames (counted: said once a minute)",
                stalled, self.grace, extra={"mission_time": self._clock(stalled.silent_for)},
            )  # fmt: skip
        return ()

    def _say_trip(self, stalled: StreamStalled, silent_for: float, at: float) -> None:
        """The trip's warning, at the trip, or ``silent_for`` into a stall whose trip was
        counted rather than said (:attr:`_quiet`) once it has lasted half the grace."""
        still = (
            f"; still none {silent_for * 1000:.0f} ms after the last (half the grace)"
            if silent_for > stalled.silent_for
            else ""
        )
        log.warning(
            "%s%s%s; waiting up to %g s for valid frames", stalled,
            ", and motors off" if self._motors_off() is not None else "", still, self.grace,
            extra={"mission_time": self._clock(silent_for)},
        )  # fmt: skip
        self._said_at = at
        self._quiet = False

    def carry_on(self, batch: Sequence[SensorFrame]) -> None:
        """During a ride, after a read: frames back end the wait; none raise the stall's
        cause once the grace is over. The wheels and the motors get their commands back once
        the frames that waited are read (:meth:`_backlog_read`). (The run's loop reads the
        stream itself, and calls this only while :attr:`stall` is set: a call a frame less
        on the tick path.)"""
        stall = self.stall
        assert stall is not None
        read_at = self._backlog_read_at
        if read_at is not None:
            self._backlog_read(batch, read_at)
        elif batch:
            self._back(stall[2], stall[1])
        else:
            if self._quiet and self._tripped is not None:
                now = self.connection.link.transport.now()
                if now - stall[2] >= self.grace / 2:
                    self._say_trip(self._tripped, now - stall[2], now)
            self.connection.check_stall(stall[0], self.grace, stall[1])

    def _back(self, silent_since: float, halted: bool) -> None:
        """Valid frames came back within the grace: the tree goes on, on the frames that
        waited first (a stall's backlog, read over several reads: a network bridge's). A
        stall whose trip was not said is counted, and the count said once :data:`QUIET_S`
        has gone by since the last line (:class:`LateFrames`)."""
        self.gap_explained = True
        self.summary.stalls_ridden += 1
        connection = self.connection
        back_at = connection.link.silent_since
        gap = back_at - silent_since
        goes_on = PAUSED_GOES_ON if self.paused() else "the mission goes on"
        self._backlog_read_at = connection.link.arrival
        said_at = self._said_at
        if self._quiet and said_at is not None:
            late = self._late
            if not late.count:
                self._late_since = said_at
            late.add(gap, halted, self._clock(0.0))
            log.debug(
                "%s: valid frames are back after %.0f ms (counted: said once a minute)",
                connection.name, gap * 1000, extra={"mission_time": self._clock(gap)},
            )  # fmt: skip
            if back_at - said_at >= QUIET_S:
                line = late.said(connection.name, back_at - self._late_since, goes_on)
                log.warning("%s", line, extra={"mission_time": self._clock(gap)})
                self._late = LateFrames()
                self._said_at = back_at
            return
        log.warning(
            "%s: valid frames are back after %.0f ms; %s%s", connection.name, gap * 1000,
            goes_on, "; stalls in the next minute are counted, and said once a minute",
            extra={"mission_time": self._clock(gap)},
        )  # fmt: skip

    def run_ended(self, lost: bool) -> None:
        """At the run's end: the stalls counted and not yet said (a run that ended within a
        minute of the last line said none of them, and the summary's stalls line has their
        count, not the longest), then a stall still open, how long and from where, unless
        its silence ended the run (``lost``: the run's reason says it)."""
        late, stall = self._late, self.stall
        if not late.count and stall is None:
            return
        name = self.connection.name
        now = self.connection.link.transport.now()
        if late.count:
            went_on = "the mission went on"
            line = late.said(name, now - self._late_since, went_on, "at the run's end")
            log.warning("%s", line, extra={"mission_time": self._clock(0.0)})
            self._late = LateFrames()
        if stall is not None and self._backlog_read_at is None and not lost:
            log.warning(
                "%s: the run ended in a stall: no valid frame for its last %.0f ms (since "
                "t=%.3f)%s", name, (now - stall[2]) * 1000, self._clock(0.0) or 0.0,
                "; the watchdog had sent drive 0" if stall[1] else "",
                extra={"mission_time": self._clock(now - stall[2])},
            )  # fmt: skip

    def _backlog_read(self, batch: Sequence[SensorFrame], read_at: float) -> None:
        """While the stall's backlog is read: once a batch comes spaced as the stream is (half
        a slot or more after the one before) or none comes, the frames that waited are
        read, and the wheels and the motors (which the watchdog turned off with the wheels)
        get their last commands again unless the tree sent others meanwhile. Given back at
        the first batch, a turn the backlog's later frames showed done went to the robot
        once before the tree's next command, the robot on its way back to a stale
        command."""
        arrival = self.connection.link.arrival
        if batch and arrival - read_at < LOST_LATE:
            self._backlog_read_at = arrival
            return
        self.stall = self._backlog_read_at = None
        self._given_back(self._motors_off())

    def tick_halted(
        self, tick_guard: TickGuardLike | None, seconds: float, where: str,
        tree_running: bool = True, loop: bool = False,
    ) -> None:  # fmt: skip
        """The tick guard stopped the wheels (and the motors) during the tick that just
        returned: counted, said, and, as after a watchdog stall, the last wheel command goes
        out again unless this tick queued another, and so does the last Motors command the
        guard turned off (the mission goes on where it was); not once the tick ended the
        tree (``tree_running`` False): the run's end follows, and the brushes went on again
        for a moment before its motors off. ``loop``: it was a pass of a program's loop over
        ``stack.ticks()``, between two ticks (:meth:`loop_counted`), not the tree's tick."""
        summary = self.summary
        motors_off = self._motors_off()
        if not self.loop_counted(loop, True):
            summary.tick_halts += 1
            summary.tick_halt_last = where or "unknown"
            summary.tick_halt_first = summary.tick_halt_first or summary.tick_halt_last
            summary.tick_halts_motors += motors_off is not None
        log.warning(
            "%s ran over %g s (%s): the tick guard sent drive 0%s",
            "the program's loop body" if loop else "a tick",
            tick_guard.limit_s if tick_guard else 0.0, where or "where: unknown",
            " and motors off" if motors_off is not None else "",
        )  # fmt: skip
        self.blocked = (seconds, where or "unknown", True, "")  # the frames it left unread
        if tree_running:
            self._given_back(motors_off)

    def loop_counted(self, loop: bool, halted: bool) -> bool:
        """Count a pass of a program's loop over ``stack.ticks()`` (``loop``) that ran past
        the tick guard's limit, ``halted`` or not, as the loop's own (the summary's
        ``loop_slow``, ``loop_halts``): the program's time between two ticks, not the
        tree's. It was counted and said as a slow tick ("while the tree was busy"); True if
        it was the loop's."""
        if loop:
            self.summary.loop_slow += 1
            self.summary.loop_halts += halted
        return loop

    def tick_still(self, seconds: float, where: str, cycle: str = "", loop: bool = False) -> None:
        """The tick that just returned ran past the tick guard's limit with nothing moving, or
        while ``cycle`` (a built-in cycle, as :func:`~roomba_bt.runtime.tick_guard.cycle_said`
        says it) may have driven the robot, which the guard does not end (``seconds``: how
        long it had run when the guard saw it; ``where``: the behaviour and its line):
        nothing was sent, nothing is given back; counted (the summary's tick guard line, the
        monitor's timeline), and the frames it left unread are its own (:attr:`blocked`), not
        a process that did not run. ``loop``: a pass of a program's loop over
        ``stack.ticks()`` (:meth:`loop_counted`)."""
        summary = self.summary
        where = where or "where: unknown"
        if self.loop_counted(loop, False):
            pass
        elif cycle:
            summary.tick_cycles += 1
            summary.tick_cycle_last = where
            summary.tick_cycle_first = summary.tick_cycle_first or where
        else:
            summary.tick_stills += 1
            summary.tick_still_last = where
            summary.tick_still_first = summary.tick_still_first or where
        self.blocked = (seconds, where, False, cycle)

    def _given_back(self, turned_off: Command | None) -> None:
        """After the runtime's own stop (the watchdog's, the tick guard's): the last wheel
        command again (:meth:`_wheels_again`), and ``turned_off``, the Motors command that
        stop turned off (:meth:`_motors_off`), unless the tick queued another: the mission
        goes on as it had the robot."""
        self._wheels_again()
        if turned_off is not None and all(c.spec.channel != "motors" for c in self.outbox):
            self.outbox.send(turned_off, self)

    def _motors_off(self) -> Command | None:
        """The tree's last Motors command (the outbox's record) if the runtime's stop (the
        watchdog's, the tick guard's) turned it off (the writer's last is no longer it) and
        it runs a brush or the vacuum in a mode the robot obeys it in: sent again unless the
        tick queued another Motors command, as the wheels' is (a drive 0 alone leaves the
        motors running: nothing to give back)."""
        motors = self.outbox.standing.get("motors")
        if (
            motors is not None
            and sets_going(motors)
            and self.connection.writer.last_motors != motors
            and self.connection.mode in DRIVING_MODES
        ):
            return motors
        return None

    def _wheels_again(self) -> None:
        """After a drive 0 the runtime sent on its own (the watchdog's, the tick guard's): the
        last wheel command the tree wrote goes out again, if it turns a wheel and the robot
        obeys it, unless this tick queued another wheel command (the tree's newer word). A
        fall to Passive by itself (``MissionRunner._advance``) forgets that command: the
        robot stopped. The outbox's record, not the writer's (``CommandWriter.last_wheels``,
        which the tick guard reads): the writer's holds the drive 0 this gives the wheels
        their command back after. The two agree but for the runtime's own drive 0s; both
        forget a fall."""
        outbox = self.outbox
        wheels = outbox.standing.get("wheels")
        if (
            wheels is not None
            and turns_wheels(wheels)
            and self.connection.writer.last_wheels != wheels  # the tree's own since: it stands
            and self.connection.mode in DRIVING_MODES
            and all(c.spec.channel != "wheels" for c in outbox)
        ):
            outbox.send(wheels, self)
