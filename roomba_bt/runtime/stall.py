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
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

from roomba_bt.oi.encode import Command, turns_wheels
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES
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
        log.warning(
            "%s%s; waiting up to %g s for valid frames", stalled,
            ", and motors off" if self._motors_off() is not None else "", self.grace,
            extra={"mission_time": self._clock(stalled.silent_for)},
        )  # fmt: skip
        return ()

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
            self._back(stall[2])
        else:
            self.connection.check_stall(stall[0], self.grace, stall[1])

    def _back(self, silent_since: float) -> None:
        """Valid frames came back within the grace: the tree goes on, on the frames that
        waited first (a stall's backlog, read over several reads: a network bridge's)."""
        self.gap_explained = True
        self.summary.stalls_ridden += 1
        connection = self.connection
        gap = connection.link.silent_since - silent_since
        goes_on = PAUSED_GOES_ON if self.paused() else "the mission goes on"
        log.warning(
            "%s: valid frames are back after %.0f ms; %s", connection.name, gap * 1000,
            goes_on, extra={"mission_time": self._clock(gap)},
        )  # fmt: skip
        self._backlog_read_at = connection.link.arrival

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
