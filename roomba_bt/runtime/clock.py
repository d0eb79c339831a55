"""The stream as the run's clock: the tick index, mission time, and where in them a run ended.

Each frame is one 15 ms slot. :class:`StreamClock` adds up the slots each batch of frames
spans (:class:`~roomba_bt.runtime.schedule.SlotSchedule`'s rule: frames lost in transit are
slots that passed with no frame) into the run's tick index, less the slots the monitor held
the run paused: mission time is ``(tick - held_slots) * 0.015`` s. The common frame (one
slot, on time) is counted inline in ``MissionRunner._advance``, a call less a tick; the clock
takes every other batch (:meth:`StreamClock.slots_spanned`).

The functions below read a run's mission time between its ticks (a log line's stamp, a
stall's trip) and place its end for the record, from what any run shows: its last tick's
snapshot, whether the monitor holds its clock, and its link (:class:`TimedRun`).
"""

from __future__ import annotations

import logging
from typing import Protocol

from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.interface import Snapshot
from roomba_bt.runtime.schedule import NO_FRAME_YET, SlotSchedule
from roomba_bt.runtime.stall import StallRide
from roomba_bt.runtime.summary import RunSummary

#: the run's own logger, whose warnings these are (as ``runtime/stall.py``'s)
log = logging.getLogger("roomba_bt.runtime.loop")

#: a gap between frames read this long, not a stall the watchdog saw, is said (``unread_gap``)
UNREAD_GAP_SECONDS = 1.0


class StreamClock:
    """The run's tick index, as the slots its batches of frames span add up, and the slots the
    monitor held (mission time stands still meanwhile). ``ride``: the run's
    :class:`StallRide`, which says when the next gap is a stall ridden through or a blocked
    tick's, not frames nobody read; frames lost and unread gaps are counted in ``summary``."""

    __slots__ = (
        "_connection", "_ride", "_summary", "_unread_open", "held_slots", "schedule", "tick",
    )  # fmt: skip

    def __init__(self, ride: StallRide, summary: RunSummary, connection: Connection) -> None:
        self._ride = ride
        self._summary = summary
        self._connection = connection
        #: when the robot's frames are due on the link's clock: the slots a batch spans (on
        #: the simulator's steps, ``read_step``: a calm link from the start)
        stepped = getattr(connection.transport, "read_step", None) is not None
        self.schedule = SlotSchedule(stepped)
        #: the stream tick index of the last batch's newest frame (-1 before the first)
        self.tick = -1
        #: the slots that passed while the monitor held the run paused (``clock_held``)
        self.held_slots = 0
        #: the schedule's last restart was a gap nobody read (not a stall ridden through):
        #: the frames its run counts lost are the host's (``frames_lost_unread``)
        self._unread_open = False

    def slots_spanned(self, count: int, arrival: float) -> int:
        """The slots a batch of ``count`` frames spans by the schedule (the first frame:
        one); more than ``count`` when frames were lost in transit (counted). After a gap of
        a second or more, or a stall ridden through, the schedule starts again from this
        batch."""
        schedule = self.schedule
        if schedule.due == NO_FRAME_YET:
            return schedule.late_batch(count, arrival, self.tick, False)  # the first: one
        gap = schedule.gap(arrival, self.tick)
        ride = self._ride
        restart = gap >= UNREAD_GAP_SECONDS or ride.gap_explained
        unread = gap >= UNREAD_GAP_SECONDS and not ride.gap_explained
        blocked, ride.gap_explained, ride.blocked = ride.blocked, False, None
        if restart:
            self._unread_open = unread
        restart_lost = schedule.restart_lost
        slots = schedule.late_batch(count, arrival, self.tick, restart)
        if unread:
            # stamped with the batch's time, the gap's end, when it is said: the run's clock
            # (mission_time_now) still read the tick before it, and a blocked tick's gap came
            # out before the tick guard's line from inside that tick (t=1.140, then t=0.900)
            at = (self.tick + slots - self.held_slots) * SLOT_SECONDS
            unread_gap(self._summary, self._connection.name, gap, blocked, at)
        if slots > count:
            self._summary.frames_lost += slots - count
            if self._unread_open:  # the port's buffer full while nothing read it
                self._summary.frames_lost_unread += schedule.restart_lost - restart_lost
        return slots


def unread_gap(
    summary: RunSummary,
    link: str,
    gap: float,
    blocked: tuple[float, str, bool, str] | None = None,
    at: float | None = None,
) -> None:
    """No frame was read for ``gap`` seconds and the watchdog did not trip: the process did
    not run (a laptop suspended, SIGSTOP, a host starved of CPU), or the watchdog is off and
    the robot was silent. Either way the robot went on with its last command, unwatched:
    counted and said (the frames that waited are dropped as stale).

    ``blocked``: the tick before the gap blocked past the tick guard's limit (``(seconds it
    had run when the guard saw it, where, halted, cycle)``): the gap is that tick's. Either
    the guard sent drive 0 in it (``halted``, :meth:`StallRide.tick_halted`), the wheels at
    rest from then on; or nothing moved (:meth:`StallRide.tick_still`: a plugin's first
    ``update`` blocking before its first drive), the robot still all along; or a built-in
    cycle could drive it (``cycle``, the guard ends none), and it went on driving: said as
    that tick's, where it said the process was suspended or starved of CPU. Said as such,
    and not counted as unread (the summary's tick guard line counts a halt): it said the
    process was suspended or starved and the robot went on with its last command, whenever
    the block came out a second or more.

    ``at``: the mission time the gap ended, the line's stamp (None: the run's clock now)."""
    stamp = None if at is None else {"mission_time": at}
    if blocked is not None:
        if blocked[3]:
            log.warning(
                "%s: no frame was read for %.2f s: a tick blocked (%s) while %s could drive "
                "it: the cycle went on driving, unwatched, until the tick returned (the tick "
                "guard does not end a built-in cycle)",
                link, gap, blocked[1], blocked[3], extra=stamp,
            )  # fmt: skip
            return
        if not blocked[2]:
            log.warning(
                "%s: no frame was read for %.2f s: a tick blocked (%s) with nothing moving: "
                "the robot stood still until it returned (the tick guard had nothing to stop)",
                link, gap, blocked[1], extra=stamp,
            )  # fmt: skip
            return
        log.warning(
            "%s: no frame was read for %.2f s: a tick blocked (%s); the tick guard had sent "
            "drive 0 once it had run %.2f s, and the wheels stood still until it returned",
            link, gap, blocked[1], blocked[0], extra=stamp,
        )  # fmt: skip
        return
    summary.unread_gaps += 1
    summary.longest_unread_s = max(summary.longest_unread_s, gap)
    log.warning(
        "%s: no frame was read for %.2f s (the process suspended or starved of CPU, or the "
        "robot silent with the watchdog off); the robot went on with its last command "
        "meanwhile", link, gap, extra=stamp,
    )  # fmt: skip


class TimedRun(Protocol):
    """What a run's mission time between ticks is read from (a ``MissionRunner``)."""

    @property
    def has_snapshot(self) -> bool: ...
    @property
    def snapshot(self) -> Snapshot: ...
    @property
    def clock_held(self) -> bool: ...
    @property
    def connection(self) -> Connection: ...


def mission_time_after(run: TimedRun, seconds: float) -> float | None:
    """The mission time ``seconds`` after the last tick's frame, for what happens between
    ticks (a stall's trip and end); None before the first tick. A clock the monitor holds
    stands still."""
    if not run.has_snapshot:
        return None
    return run.snapshot.time + (0.0 if run.clock_held else seconds)


def mission_time_now(run: TimedRun) -> float | None:
    """The mission time now on the run's clock, for a log line's stamp: the last tick's, plus
    what the link's clock (the virtual clock on the simulator and in a replay, the port's on
    a robot) has counted since that tick's frame arrived, once a slot has passed without the
    next. No tick moves the mission clock while frames stop: a stall's lines, the grace's and
    the ending's after it, read the last frame's time, and a 5 s stall showed them all at its
    start, before the watchdog's own trip. A line of the tick, or of the slot after it, keeps
    the tick's time, as the status lines have it. None before the first tick; a clock the
    monitor holds stands still (:func:`mission_time_after`)."""
    if not run.has_snapshot:
        return None
    link = run.connection.link
    since = link.transport.now() - link.arrival
    return mission_time_after(run, since if since >= SLOT_SECONDS else 0.0)


def interrupted_at(run: TimedRun, flushed: int) -> tuple[int, str] | None:
    """Where a Ctrl-C or SIGTERM came, for the end note (:func:`ended_at`): "after" the tree's
    tick on the last frame when that tick was written whole (``flushed``: the stream tick of
    the last one), else "before" it: a tick writes nothing until its flush, so an interrupt
    inside the tree's tick (or before it, in the gate) left none of it on the wire. It was
    taken as "after", and the replay ticked that frame in full and wrote a command the live
    run never sent, where the record holds the safe stop (a false difference, exit 1). An
    interrupt between two of the flush's writes is "before" too; the bytes written by then
    (``RunSummary.written_when_interrupted``, the end note's ``written``) tell the replay to
    tick that frame and write its commands up to there (``stack.RecordedEnd``)."""
    if not run.has_snapshot:
        return None
    tick = run.snapshot.tick
    return tick, "after" if tick == flushed else "before"


def ended_at(run: TimedRun, said: tuple[int, str] | None) -> tuple[int, str] | None:
    """Where the run ended, for the record's end note (``RunSummary.ended_at``): the tick of
    its last frame, and whether before the tree's tick on it (the monitor's stop, which comes
    through the gate before the tick: ``said``, from its ``StopRequested``; a Ctrl-C or
    SIGTERM inside the tick: :func:`interrupted_at`) or after (one where the run waits for
    its next frame; the tree's own end, a timeout); None before the first frame."""
    if not run.has_snapshot:
        return None
    return run.snapshot.tick, said[1] if said is not None else "after"
