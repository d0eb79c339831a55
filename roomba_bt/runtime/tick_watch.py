"""The slow tick's culprit: which behaviour the run's slowest tick was in.

The summary's ticks line says how slow the slowest tick was (``slowest 503.89 ms``); on the
wall clock the tick guard names a tick that blocks while the wheels move
(runtime/tick_guard.py), but on the virtual clock (``run --fast``, where plugin authors
test) there is no guard, and a ``time.sleep`` in an ``update()`` went unnamed. So a thread
looks at the ticking thread every :data:`LOOK_EVERY_S` seconds, as the tick guard does, and
keeps where it found the longest stretch of one iteration of the loop inside a behaviour
(:func:`~roomba_bt.runtime.teardown.behaviour_at`: ``sleepy (Sleepy.update at x.py:98)``).

Off the tick path on purpose: the loop's code is the same; the watch reads the summary's
tick count, which the loop keeps anyway, and a count unchanged from one look to the next is
an iteration still running (only then does it look where: a fast run's ticks pass unseen).
The ticking thread pays only the GIL hand-over of a thread that wakes 40 times a second. An
evaluation (thousands of episodes, benchmarked per tick) starts one that sleeps
(:data:`DORMANT_LOOK_S`): it wakes twice a second, reads the tick count, and looks closely
only once the episode's mission time went slower than the wall clock over a wake's
interval (an episode runs hundreds of times faster than a robot: one that does not has a
behaviour waiting on the wall clock, a ``time.sleep``, I/O). A plugin that slept in its
``update`` under ``eval`` was said only by ``--wall-limit``'s HUNG; an episode at its
usual pace never wakes the watch, and a short one ends before its first look
(:attr:`MissionRunner.names_slow_ticks <roomba_bt.runtime.loop.MissionRunner.names_slow_ticks>`:
``roomba-bt run`` sets it True, an evaluation's episode :data:`WHEN_SLOW`).

What it can name: a tick that ran for two looks or more (about 50 ms); a shorter slowest
tick, or one whose looks found no behaviour (the runtime's own code, the port), stays
unnamed, and one that ran much shorter than the longest iteration seen is not called that
(:meth:`SlowTickWatch.culprit`).

A tick is also slow when the process did not run: on a loaded host (a soak's ``--fast`` runs
beside other work, load 6 to 8 on 2 cores) the ticking thread waits for a CPU, and the look
finds it wherever it was stopped, a line of ``wall_follow`` that computes in a millisecond
("slowest 126.74 ms in wall_follow ... wall.py:192"). So the watch also reads the ticking
thread's time on a CPU and its time waiting for one (Linux's
``/proc/self/task/TID/schedstat``, :class:`SchedStat`: a microsecond's read of a file kept
open, at each look that finds a new tick count, in the watch's own thread: nothing on the
tick path). When the slowest tick so far ended between two such looks, and over that window
the thread had a CPU for less than half the time and waited for one for half of it or more,
the slowest tick was the host's, not a behaviour's: the summary says ``the host was busy
(3.10 ms of CPU in 100.20 ms, 95.00 ms of it waiting for a CPU)`` and names no behaviour. A
behaviour that blocks (``time.sleep``, I/O, a lock) has no CPU either but waits for none,
and is named as before; where the times cannot be read (not Linux), every slow tick is
named as before.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator

from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.runtime.teardown import behaviour_at

log = logging.getLogger(__name__)

#: seconds between two looks at the ticking thread
LOOK_EVERY_S = 0.025
#: wall seconds of a run on the virtual clock after which, if its mission time is still
#: behind its wall time and its ticks are found in a behaviour, it is said once
#: (:meth:`SlowTickWatch.slower_than_real_time`): a run that long, slower than a robot
#: would go, looks hung to its author
FAST_BUT_SLOW_AFTER_S = 2.0

#: ``MissionRunner.names_slow_ticks`` of an evaluation's episode: a watch that looks closely
#: only once the run goes slower than the wall clock (:data:`DORMANT_LOOK_S`)
WHEN_SLOW = "when slow"
#: seconds between two reads of the tick count by a watch that waits for the run to go slower
#: than the wall clock (:attr:`SlowTickWatch.dormant_s`): two wakes a second cost an episode
#: nothing it measures, and a run that slow takes seconds
DORMANT_LOOK_S = 0.5

#: a thread's seconds on a CPU and waiting for one, so far (:class:`SchedStat`); None: not
#: known here
ThreadTimes = Callable[[], tuple[float, float] | None]


class SchedStat:
    """The thread ``native_id``'s seconds on a CPU and waiting on a run queue for one, from
    Linux's ``/proc/self/task/TID/schedstat`` ("on-CPU ns, waiting ns, timeslices"), read
    by :meth:`read` (about a microsecond: the file is kept open and read again from its
    start); None where there is no such file (another system, a kernel without scheduler
    statistics)."""

    def __init__(self, native_id: int) -> None:
        try:
            self._fd: int | None = os.open(f"/proc/self/task/{native_id}/schedstat", os.O_RDONLY)
        except OSError:
            self._fd = None

    def read(self) -> tuple[float, float] | None:
        if self._fd is None:
            return None
        try:
            on_cpu, waiting = os.pread(self._fd, 64, 0).split()[:2]
            return int(on_cpu) / 1e9, int(waiting) / 1e9
        except (OSError, ValueError):
            return None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


class SlowTickWatch:
    """Looks at one run's ticking thread from a thread of its own (the module docstring).
    ``clock`` and ``times`` (the ticking thread's :data:`ThreadTimes`) are the wall clock's
    and the kernel's (:class:`SchedStat`), given for a test. ``dormant_s``: first only read
    the tick count every that many seconds, until the run goes slower than the wall clock
    (:meth:`wakes`); None: look every ``look_every_s`` from the start."""

    def __init__(
        self,
        summary: RunSummary,
        look_every_s: float = LOOK_EVERY_S,
        *,
        clock: Callable[[], float] = time.monotonic,
        times: ThreadTimes | None = None,
        dormant_s: float | None = None,
    ) -> None:
        self.summary = summary
        self.look_every_s = look_every_s
        self.clock = clock
        self.dormant_s = dormant_s
        #: the dormant watch's last read (its time and the tick count; first, the watch's
        #: making, before the ticks begin), and the time of the read before the last one that
        #: found the count changed: the tick running when it wakes began after that
        #: (:meth:`wakes`)
        self._dormant_read = (clock(), summary.ticks)
        self._began_after = self._dormant_read[0]
        #: the kernel's reader of the ticking thread's times (the one that makes the watch),
        #: closed by :meth:`close`; None when a test gives ``times``
        self._schedstat: SchedStat | None = None
        if times is None:
            self._schedstat = SchedStat(threading.get_native_id())
            times = self._schedstat.read
        self.times = times
        #: the longest iteration found inside a behaviour: seconds it had run by the last
        #: look that found it there, and where that look found it
        self.longest_s = 0.0
        self.where = ""
        #: how much longer than :attr:`longest_s` that iteration may have run, by the gaps
        #: between the looks around it: the one before its first look inside, and the one
        #: after its last (0: not measured; :meth:`culprit` allows three looks at least)
        self.longest_unseen_s = 0.0
        #: the slowest tick that had ended at a look (the summary's ``max_tick_s`` then), and
        #: its thread's time on a CPU, in how long, and how much of it waiting for a CPU when
        #: the host kept the thread from running (:meth:`_host_busy`), else ""
        self.slowest_judged = 0.0
        self.host_busy = ""
        self._owner = threading.get_ident()  # the thread that ticks: the one that made it
        self._seen = -1  # the tick count at the last look
        self._last = clock()  # when that look was (made: the ticks begin after it)
        self._inside: float | None = None  # since when (a look's time) it is in a behaviour
        self._gap = 0.0  # seconds from the look before the last to the last
        self._inside_gap = 0.0  # the gap before that stretch's first look inside
        #: the gap before the longest iteration's first look inside, while it is the one the
        #: looks find there (None: the longest has been left, its unseen time measured)
        self._longest_gap: float | None = None
        #: the last look that found a new tick count, and the thread's times then: the ticks
        #: that end before the next such look ran after it
        self._window: tuple[float, tuple[float, float] | None] | None = None
        #: wall seconds the looks found the ticks inside a behaviour (a pause, the runtime's
        #: own waits not counted), and whether a run on the virtual clock slower than real
        #: time was said (:meth:`slower_than_real_time`)
        self.held_s = 0.0
        self.slow_said = False
        self._done = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, name="roomba-bt slow tick watch", daemon=True
        )

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        """Stop looking (at once: the thread waits on an event); the ticks since the last
        look have ended too (:meth:`_ticks_ended`)."""
        self._done.set()
        if self._thread.ident is not None:  # started (a test looks by hand)
            self._thread.join()
        now = self.clock()
        self._left(now)
        self._ticks_ended(now)
        if self._schedstat is not None:
            self._schedstat.close()

    def culprit(self) -> str:
        """Where the slowest tick was, or "" when the watch cannot tell, or the host kept
        the thread from running then (:meth:`host_kept_it`): the longest iteration it found
        inside a behaviour must have run, by its looks, for at least the slowest tick's time
        less what the looks could not see of it: the gaps between the looks at each end (it
        began after the look before its first look inside, and ended before the look after
        its last) and a look more (the runtime's own code in the tick); three looks at the
        least, looks on time. An iteration that ran that long is the slowest tick, or one as
        slow. The gaps are measured, not taken as a look each: on a loaded host the watch's
        own thread waits for a CPU, its looks come late, and a fixed three looks of slack
        could leave a tick blocked for half a second unnamed (what its looks did not see of
        it was 46-74 ms of the 75 allowed with two busy loops beside the run)."""
        slowest = self.summary.max_tick_s
        unseen = max(3 * self.look_every_s, self.longest_unseen_s + self.look_every_s)
        if not self.where or self.longest_s < slowest - unseen:
            return ""
        return "" if self.host_kept_it() else self.where

    def host_kept_it(self) -> str:
        """:attr:`host_busy`, when it was said of the run's slowest tick; else ""."""
        return self.host_busy if self.slowest_judged == self.summary.max_tick_s else ""

    def _watch(self) -> None:
        frames = sys._current_frames
        if self.dormant_s is not None:
            while not self._done.wait(self.dormant_s):
                if self.wakes(self.summary.ticks):
                    break
            else:
                return  # the run ended at its usual pace: nothing looked at
        while not self._done.wait(self.look_every_s):
            self.look(self.summary.ticks, lambda: behaviour_at(frames().get(self._owner)))

    def wakes(self, ticks: int) -> bool:
        """A dormant watch's read of the loop's tick count ``ticks``: True (it looks every
        ``look_every_s`` from now on) when the mission time the ticks added since the last
        read is less than the wall time since it. The looks go on from this read as if it
        were one of theirs: the tick running now began after the read before the one that
        last found the count changed, and that stretch is counted as unseen, so a long tick
        under way when the watch wakes is still judged by :meth:`culprit`'s rule."""
        now = self.clock()
        (then, before), self._dormant_read = self._dormant_read, (now, ticks)
        if ticks != before:
            self._began_after = then
        if (ticks - before) * SLOT_SECONDS >= now - then:
            return False
        self._seen, self._last, self._gap = ticks, now, now - self._began_after
        # The thread's times from here are the window the tick under way is judged by when
        # it ends (:meth:`_ticks_ended`); with none, it was judged at the next such look by
        # the few ms after it (an episode's last ticks, waiting for a CPU: "the host was
        # busy", and a plugin's 2 s sleep went unnamed in 2 episodes of 3)
        self._window = (now, self.times())
        return True

    def look(self, ticks: int, where_now: Callable[[], str]) -> None:
        """One look, the loop's tick count ``ticks`` read: the same as at the last look is
        an iteration still running, and the thread is looked into (``where_now``: the
        behaviour it is in, "" for none); another, ticks that ended (:meth:`_ticks_ended`)."""
        now = self.clock()
        if ticks != self._seen:  # a new iteration since the last look: a short one, so far
            self._left(now)
            self._ticks_ended(now)
            self._seen, self._inside = ticks, None
            self._gap, self._last = now - self._last, now
            return
        where = where_now()
        if not where:  # the runtime's own code or wait (a poll, a pause): no tick's
            self._left(now)
            self._inside = None
        else:
            if self._inside is None:  # its first look inside: it began after the look before
                self._inside, self._inside_gap = self._last, self._gap
            if now - self._inside > self.longest_s:
                self.longest_s, self.where = now - self._inside, where
                self._longest_gap = self._inside_gap  # this iteration is the longest
            self.held_s += now - self._last
            if not self.slow_said and self.summary.virtual_clock:
                self.slower_than_real_time(ticks, where)
        self._gap, self._last = now - self._last, now

    def slower_than_real_time(self, ticks: int, where: str) -> None:
        """On the virtual clock (``run --fast``), once: a run whose ticks the looks have found
        inside behaviours for :data:`FAST_BUT_SLOW_AFTER_S` of wall time or more
        (:attr:`held_s`: a monitor's pause is not counted), its mission time, ``ticks``
        frames, behind that; ``where``: the behaviour the tick is in now. A plugin's
        ``time.sleep(1)`` a tick made a 2 s ``timeout`` take some 130 s, mission time moving
        15 ms a tick: a first run looked hung, and nothing was said until the summary. The
        watch's own look, off the tick path: the loop's cost is the same."""
        held, mission = self.held_s, ticks * SLOT_SECONDS
        if held < FAST_BUT_SLOW_AFTER_S or mission >= held:
            return
        self.slow_said = True
        log.warning(
            "run --fast: behaviours have held the ticks %.1f s of wall time for %.2f s of "
            "mission time (%.0fx slower than a robot), now %s: --fast ticks the tree as fast "
            "as it allows and mission time is the frames ticked (%g ms each), so a behaviour "
            "that waits on the wall clock (time.sleep, I/O) slows the whole run, and a limit "
            "in mission time takes that much longer; the run is not hung",
            held, mission, held / max(mission, SLOT_SECONDS), where, SLOT_SECONDS * 1000,
        )  # fmt: skip

    def _left(self, now: float) -> None:
        """The iteration the looks found inside a behaviour is there no longer at ``now``
        (it ended, or is in the runtime's code): if it is the longest, how long it may have
        run unseen (:attr:`longest_unseen_s`): the gap before its first look inside and the
        one after its last."""
        if self._longest_gap is not None:
            self.longest_unseen_s = self._longest_gap + (now - self._last)
            self._longest_gap = None

    def _ticks_ended(self, now: float) -> None:
        """Ticks ended since the window began (the last look that found a new tick count):
        if the slowest so far is among them (the loop raised ``max_tick_s``), what the
        thread's times over the window say of it (:meth:`_host_busy`). The times are read
        at every such look (the window's start must be read before a tick turns out slow:
        on a loaded host the looks themselves come late, the slowest tick seen by none),
        and after the ticks ended (a wait for a CPU is counted once the thread has one)."""
        times = self.times()
        slowest = self.summary.max_tick_s
        if self._window is not None and slowest > self.slowest_judged:
            began, before = self._window
            self.slowest_judged = slowest
            self.host_busy = self._host_busy(now - began, before, times)
        self._window = (now, times)

    def _host_busy(
        self, window: float, before: tuple[float, float] | None, after: tuple[float, float] | None
    ) -> str:
        """``3.10 ms of CPU in 100.20 ms, 95.00 ms of it waiting for a CPU`` when, over the
        ``window`` s (the times ``before`` and ``after``), the thread had a CPU for less
        than half the time and waited for one for half of it or more; "" otherwise, or when
        not known."""
        if before is None or after is None or window <= 0:
            return ""
        on_cpu, waiting = after[0] - before[0], after[1] - before[1]
        # The kernel adds a wait to the thread's figure when the thread gets its CPU: one that
        # began before the window is counted in it, so the figures can span more than the
        # looks' window (a watcher's report: 29.96 ms waiting "in 25.13 ms"): the time said
        # is the longer of the two, never less than what it holds.
        window = max(window, on_cpu + waiting)
        if on_cpu >= window / 2 or waiting < window / 2:
            return ""
        return (
            f"{on_cpu * 1000:.2f} ms of CPU in {window * 1000:.2f} ms, {waiting * 1000:.2f} ms "
            "of it waiting for a CPU"
        )


@contextlib.contextmanager
def slowest_tick_named(summary: RunSummary, watch: bool | str) -> Iterator[None]:
    """The run's ticks, watched when ``watch`` (:class:`SlowTickWatch`, from the calling
    thread, which ticks; :data:`WHEN_SLOW`: dormant until the run goes slower than the wall
    clock); when they end, however they end, ``summary.slowest_in`` says where the slowest
    tick was if the watch could tell, or ``summary.slowest_host_busy`` that the host kept
    the ticking thread from running then."""
    if not watch:
        yield
        return
    watcher = SlowTickWatch(summary, dormant_s=DORMANT_LOOK_S if watch == WHEN_SLOW else None)
    watcher.start()
    try:
        yield
    finally:
        watcher.close()
        summary.slowest_in = watcher.culprit()
        summary.slowest_host_busy = watcher.host_kept_it()
