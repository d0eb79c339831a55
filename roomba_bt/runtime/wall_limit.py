"""A wall-clock limit on a block of code that may be stuck: ``run --wall-limit`` and an
evaluation's episode on a Dask worker (``eval --wall-limit``).

A behaviour stuck in an endless loop holds the ticking thread: on the virtual clock
(``run --fast``, an evaluation) mission time stops with it, so ``--timeout`` never fires,
and no frame is missed, so no watchdog does either. A thread cannot be ended from outside;
:class:`WallLimit` raises :class:`WallLimitReached` in it instead, between two bytecodes (the
interpreter's asynchronous exception), so a loop in Python ends where it is, the run's
safe stop still runs on the way out, and the stack it was raised on says where it was stuck
(:func:`ran_out`). A loop in C code, or a blocking call (``time.sleep``), sees it only when
it returns to Python; one that catches ``BaseException`` swallows it.

The monitor's pause holds the limit (:meth:`WallLimit.hold`): the time an operator keeps a
run paused is no behaviour stuck, and a pause longer than ``--wall-limit`` ended the run as
HUNG (exit 4, "a bug") at wherever the paused loop happened to be reading the link.
"""

from __future__ import annotations

import ctypes
import threading
import time
import traceback
from types import FrameType, TracebackType

import py_trees

from roomba_bt.printable import duration_said
from roomba_bt.robot import wording
from roomba_bt.robot.safety import RunAborted
from roomba_bt.runtime.teardown import stuck_in


class WallLimitReached(RunAborted):
    """Raised in a thread at its wall-clock limit (:class:`WallLimit`): no ``except
    Exception`` (a behaviour's, the runner's) takes it for the run's own error, nor the
    runner's ``except BaseException`` around a behaviour's code (a :class:`RunAborted`)."""


class WallLimit:
    """``with WallLimit(seconds):`` raises :class:`WallLimitReached` in the thread that
    entered it once ``seconds`` of wall-clock time have passed inside (None: no limit);
    :attr:`reached` says whether it did. Nothing is raised once the block is left: an
    exception the limit set going as the block ended is taken back."""

    def __init__(self, limit_s: float | None) -> None:
        self.limit_s = limit_s
        #: the limit ran out and its exception was set going in the thread
        self.reached = False
        self._thread = 0
        self._lock = threading.Lock()
        self._left = False
        self._timer: threading.Timer | None = None
        #: the wall-clock time the limit runs out at while it counts (``time.monotonic``)
        self._due = 0.0
        #: the seconds left when :meth:`hold` stopped the count; None: counting
        self._held_left: float | None = None

    def __enter__(self) -> WallLimit:
        if self.limit_s is not None:
            self._thread = threading.get_ident()
            self._start(self.limit_s)
        return self

    def _start(self, seconds: float) -> None:
        self._due = time.monotonic() + seconds
        self._timer = threading.Timer(seconds, self._expire)
        self._timer.daemon = True
        self._timer.start()

    def hold(self, held: bool) -> None:
        """Stop counting (``held``: the monitor's pause) or go on from where the count
        stopped; a second hold or release in a row does nothing. The time held is not the
        block's: an operator's pause is no behaviour stuck."""
        with self._lock:
            if self.limit_s is None or self._left or self.reached:
                return
            if held and self._held_left is None:
                if self._timer is not None:
                    self._timer.cancel()
                self._held_left = max(0.0, self._due - time.monotonic())
            elif not held and self._held_left is not None:
                left, self._held_left = self._held_left, None
                self._start(left)

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        with self._lock:  # no exception is set going in this thread after this
            self._left = True
            if self.reached and not isinstance(exc, WallLimitReached):
                _set_async_exc(self._thread, None)  # set going, not raised yet: taken back
                self.reached = False
        if self._timer is not None:
            self._timer.cancel()

    def said(self, exc: BaseException) -> str:
        """Where the limit found the thread, from the stack ``exc`` (its
        :class:`WallLimitReached`) unwound: :func:`ran_out`'s words, the limit named as the
        run's caller set it (``--wall-limit``, or a program's ``stack.runner.wall_limit_s``,
        which has no such option)."""
        frames = list(traceback.walk_tb(exc.__traceback__))
        return ran_out(self.limit_s or 0.0, frames, wording.current.wall_limit)[1]

    def _expire(self) -> None:
        with self._lock:
            # a timer cancelled by a hold as it fired: the count is held, not run out
            if not self._left and self._held_left is None:
                self.reached = True
                _set_async_exc(self._thread, WallLimitReached)


def _set_async_exc(thread: int, kind: type[BaseException] | None) -> None:
    """The interpreter's asynchronous exception ``kind`` raised in ``thread`` at its next
    bytecode; None takes back one set going and not raised yet."""
    ctypes.pythonapi.PyThreadState_SetAsyncExc(
        ctypes.c_ulong(thread), None if kind is None else ctypes.py_object(kind)
    )


def ran_out(
    limit_s: float,
    frames: list[tuple[FrameType, int]] | None,
    limit_named: str = wording.COMMAND_LINE.wall_limit,
) -> tuple[py_trees.behaviour.Behaviour | None, str]:
    """What a run or episode stopped at its wall-clock limit says, and the behaviour it was
    stuck in (None: outside every behaviour, or no stack): ``--wall-limit 3 s of wall-clock
    time ran out in behaviour sequence / hang (at bad.py:30)``, where :func:`stuck_in` finds
    it on ``frames`` (outermost first; None: no Python frame answered, a loop in C code).
    ``limit_named``: the limit as its caller set it (:class:`ConnectionWording.wall_limit
    <roomba_bt.robot.wording.ConnectionWording>`); an evaluation's episode keeps ``eval
    --wall-limit``'s, being judged on a worker process that does not know its caller's."""
    behaviour, where = stuck_in(frames) if frames else (None, "")
    if behaviour is None and where:  # the run's own code: a run longer than the limit
        where = (
            f"outside every behaviour ({where}): no behaviour was stuck, the run was still "
            "going; a run this long needs a longer limit"
        )
    said = f" {where}" if where else ": no Python frame answered (a loop in C code?)"
    named = limit_named.format(limit=duration_said(limit_s))
    return behaviour, f"{named} of wall-clock time ran out{said}"
