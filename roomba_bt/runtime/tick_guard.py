"""The tick guard: the wheels stop when a tick takes too long.

A tick does not block (``docs/runtime.md``), but a behaviour can: a plugin that waits on the
network, a file, ``time.sleep``; a debugger. Meanwhile the robot drives on with its last
Drive: the Open Interface has no command timeout, and the stream watchdog does not trip
(frames keep arriving; nobody reads them). So a thread watches the tick::

    main thread   ─ port ─┤ tick ............................... ├─ port ─ flush ─
    guard         ·········│····· limit ─► drive 0 (if wheels move)│···············
                           release lock                   take lock back

The main thread holds :attr:`TickGuard.lock` whenever it is not inside a tick, so the guard
can write only while the tree is busy and never between the main thread's own bytes (a
command is never cut by another). Once a tick has run for ``limit_s`` with the wheels
commanded to move in Safe or Full, the guard sends drive 0 (the watchdog's action:
:meth:`~roomba_bt.robot.connection.Connection.halt`), once per tick. When the tick returns,
the runner counts it and, as after a watchdog stall, sends the last wheel command again
unless the tick queued another: the mission goes on where it was.

Only a run on the wall clock has one (a robot's port, the real-time simulator); on the
virtual clock and in a replay the robot does not move while the host thinks.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from collections.abc import Callable
from types import FrameType

import py_trees

from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.hazards import turns_a_wheel
from roomba_bt.runtime.summary import DEFAULT_TICK_LIMIT

log = logging.getLogger(__name__)


class TickGuard:
    """Watches one run's ticks from a thread of its own (see the module docstring)."""

    def __init__(
        self,
        connection: Connection,
        limit_s: float = DEFAULT_TICK_LIMIT,
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not limit_s > 0.0:
            raise ValueError(f"tick limit must be above 0 s, got {limit_s!r}")
        self.connection = connection
        self.limit_s = limit_s
        self.clock = clock
        #: held by the main thread except inside a tick
        self.lock = threading.Lock()
        #: when the running tick began (``clock``), None between ticks
        self._entered: float | None = None
        self._ticks = 0
        #: the tick whose wheels the guard stopped, how long it had run then, and where it
        #: was (:meth:`_where`)
        self._halted: tuple[int, float, str] | None = None
        self._owner = 0  # the thread that ticks
        self._done = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, name="roomba-bt tick guard", daemon=True
        )

    def start(self) -> None:
        """Take the lock for the main thread (the caller) and start watching."""
        self.lock.acquire()
        self._owner = threading.get_ident()
        self._thread.start()

    def close(self) -> None:
        """Stop watching; after this the guard writes nothing. The main thread may hold the
        lock or not (a tick that raised gave it back through :meth:`guarded`)."""
        self._done.set()
        if self._thread.is_alive():
            self._thread.join()

    def guarded(
        self, tick: Callable[[], object], halted: Callable[[float, str], None]
    ) -> Callable[[], None]:
        """``tick`` with the lock released around it; ``halted(seconds, where)`` is called in
        the main thread, lock held, after a tick during which the guard stopped the wheels,
        whether it returned or raised (``seconds``: how long that tick had run by then;
        ``where``: :meth:`_where`)."""
        lock = self.lock
        clock = self.clock

        def guarded_tick() -> None:
            self._ticks += 1
            self._entered = clock()
            lock.release()
            try:
                tick()
            finally:  # also when the tick raised or was interrupted: the halt is counted
                lock.acquire()
                self._entered = None
                stopped = self._halted
                if stopped is not None and stopped[0] == self._ticks:
                    halted(stopped[1], stopped[2])

        return guarded_tick

    def _watch(self) -> None:
        period = self.limit_s / 5.0
        while not self._done.wait(period):
            entered, tick = self._entered, self._ticks
            if entered is None or (self._halted is not None and self._halted[0] == tick):
                continue
            ran = self.clock() - entered
            if ran < self.limit_s or not self.lock.acquire(timeout=period):
                continue
            try:  # lock held: the main thread is inside a tick; is it still that one?
                if self._entered is not None and self._ticks == tick and self._moving():
                    self._halted = (tick, ran, self._where())
                    self.connection.halt()
            except Exception as exc:  # the port gone, say: the main thread meets it next
                log.warning("the tick guard could not send drive 0: %s", exc)
            finally:
                self.lock.release()

    def _moving(self) -> bool:
        """The last wheel command drives, in a mode where the robot obeys it."""
        wheels = self.connection.writer.last_wheels
        return (
            wheels is not None and turns_a_wheel(wheels) and self.connection.mode in DRIVING_MODES
        )

    def _where(self) -> str:
        """Where the ticking thread is: the innermost frame of a py_trees behaviour's method
        (``self``), named, at its line (the call that blocks, in the behaviour's own code);
        else the innermost frame's line; "" if the thread is gone."""
        frame: FrameType | None = sys._current_frames().get(self._owner)
        innermost = frame
        while frame is not None:
            owner = frame.f_locals.get("self")
            if isinstance(owner, py_trees.behaviour.Behaviour):
                code = frame.f_code
                return (
                    f"{owner.name} ({type(owner).__name__}.{code.co_name} at "
                    f"{code.co_filename}:{frame.f_lineno})"
                )
            frame = frame.f_back
        if innermost is None:
            return ""
        return f"at {innermost.f_code.co_filename}:{innermost.f_lineno}"
