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
evaluation (thousands of episodes, benchmarked per tick) does not start one
(:attr:`MissionRunner.names_slow_ticks <roomba_bt.runtime.loop.MissionRunner.names_slow_ticks>`:
``roomba-bt run`` sets it).

What it can name: a tick that ran for two looks or more (about 50 ms); a shorter slowest
tick, or one whose looks found no behaviour (the runtime's own code, the port), stays
unnamed, and one that ran much shorter than the longest iteration seen is not called that
(:meth:`SlowTickWatch.culprit`).
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator

from roomba_bt.runtime.summary import RunSummary
from roomba_bt.runtime.teardown import behaviour_at

#: seconds between two looks at the ticking thread
LOOK_EVERY_S = 0.025


class SlowTickWatch:
    """Looks at one run's ticking thread from a thread of its own (the module docstring)."""

    def __init__(self, summary: RunSummary, look_every_s: float = LOOK_EVERY_S) -> None:
        self.summary = summary
        self.look_every_s = look_every_s
        #: the longest iteration found inside a behaviour: seconds it had run by the last
        #: look that found it there, and where that look found it
        self.longest_s = 0.0
        self.where = ""
        self._owner = threading.get_ident()  # the thread that ticks: the one that made it
        self._done = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, name="roomba-bt slow tick watch", daemon=True
        )

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        """Stop looking (at once: the thread waits on an event)."""
        self._done.set()
        self._thread.join()

    def culprit(self) -> str:
        """Where the slowest tick was, or "" when the watch cannot tell: the longest iteration
        it found inside a behaviour must have run, by its looks, for at least the slowest
        tick's time less three looks (a look comes up to one late at each end, and a look
        may itself be late); an iteration
        that ran that long is the slowest tick, or one as slow."""
        slowest = self.summary.max_tick_s
        if not self.where or self.longest_s < slowest - 3 * self.look_every_s:
            return ""
        return self.where

    def _watch(self) -> None:
        summary, clock, frames = self.summary, time.monotonic, sys._current_frames
        seen = -1  # the tick count at the last look
        last = 0.0  # when that look was
        inside: float | None = None  # since when (a look's time) the iteration is in a behaviour
        while not self._done.wait(self.look_every_s):
            now, ticks = clock(), summary.ticks
            if ticks != seen:  # a new iteration since the last look: a short one, so far
                seen, last, inside = ticks, now, None
                continue
            where = behaviour_at(frames().get(self._owner))
            if not where:  # the runtime's own code or wait (a poll, a pause): no tick's
                inside = None
            else:
                inside = last if inside is None else inside  # it was running at the last look
                if now - inside > self.longest_s:
                    self.longest_s, self.where = now - inside, where
            last = now


@contextlib.contextmanager
def slowest_tick_named(summary: RunSummary, watch: bool) -> Iterator[None]:
    """The run's ticks, watched when ``watch`` (:class:`SlowTickWatch`, from the calling
    thread, which ticks); when they end, however they end, ``summary.slowest_in`` says where
    the slowest tick was if the watch could tell."""
    if not watch:
        yield
        return
    watcher = SlowTickWatch(summary)
    watcher.start()
    try:
        yield
    finally:
        watcher.close()
        summary.slowest_in = watcher.culprit()
