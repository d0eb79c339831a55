"""A run tick by tick: ``for tick in stack.ticks():``, the program's loop between two ticks.

The runner ticks the tree itself, once a stream frame (``loop.py``), and its loop is the
hot path every frame takes; it is left as it is. The run goes on in a worker thread instead,
and after each tick its observer hands the :class:`Tick` to the program's loop and waits
until the loop asks for the next one: the two never run at once, so the program reads the
tree, the blackboard and the snapshot as the tick left them, and nothing moves meanwhile
on the simulator's virtual clock.

Every ending is a run's ending, with its safe stop: the run's own end (the loop then ends,
``stack.summary`` says how), a ``break`` or an exception in the loop's body (the generator
is closed: the run is stopped as ``stack.stop()`` stops it, INTERRUPTED, its safe stop
written, before the exception goes on), Ctrl-C while the loop waits for a tick (the same,
then :class:`~roomba_bt.runtime.loop.Interrupted` is raised with the summary), and
``stack.close()`` (a ``with`` block's end). On a link on the wall clock (a robot) the robot
drives on while the loop's body runs, as while a behaviour blocks: the run's tick guard
watches the body as it watches a tick (drive 0 past ``tick_limit``), SIGTERM raises
:class:`~roomba_bt.robot.safety.Terminated` in the loop while it runs, and the terminal's
stops are ignored, as ``run()`` has them (a background job's line to a ``stty tostop``
terminal stopped the process, SIGTTOU, the robot driving on).
"""

from __future__ import annotations

import contextlib
import queue
import threading
from collections.abc import Generator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import py_trees

from roomba_bt._entry import swallowed_interrupt
from roomba_bt.robot.interface import Snapshot
from roomba_bt.robot.safety import interrupt_reason, sigterm_raises, terminal_stops_ignored
from roomba_bt.runtime.loop import (
    MissionRunner,
    TickObserver,
    guarded_between_ticks,
    interrupted,
)

if TYPE_CHECKING:
    from roomba_bt.runtime.stack import RunStack

#: how the summary names the program's loop when the tick guard stopped the wheels in it
LOOP_BODY = "the program's loop over stack.ticks(), between two ticks"
#: the reason of a run whose loop ended before it (a break, an exception, close())
LOOP_LEFT = "the program's loop over stack.ticks() ended before the run did"
#: seconds the loop waits for a tick at a time: short, so a Ctrl-C is taken at once
_WAIT_S = 0.1


@dataclass(frozen=True)
class Tick:
    """One tick of a run, as :meth:`RunStack.ticks` yields it, read after the tree's tick
    (its commands written) and before the next.

    ``number``: the tree's ticks so far (1 for the first); ``snapshot``: this tick's sensor
    frame, OI mode, odometry and mission time (``snapshot.time``, also :attr:`time`;
    ``snapshot.tick``, the stream's 15 ms slot); ``status``: the root's py_trees status
    after it (RUNNING until the tree ends; the last tick yielded has its SUCCESS or
    FAILURE); ``root``: the tree, for py_trees' display and visitors
    (``py_trees.display.unicode_tree(tick.root, show_status=True)``); ``runner``: the run
    itself (:meth:`~roomba_bt.runtime.loop.MissionRunner.request_stop`, ``summary``)."""

    number: int
    snapshot: Snapshot
    status: py_trees.common.Status
    root: py_trees.behaviour.Behaviour
    runner: MissionRunner

    @property
    def time(self) -> float:
        """Mission time, in seconds (``snapshot.time``)."""
        return self.snapshot.time

    @property
    def blackboard(self) -> Mapping[str, Any]:
        """The mission's blackboard keys and their values now (``leg``, not
        ``/mission/leg``), this run's (another run's in the process are its own): a copy,
        for this tick. The keys the mission declares (``blackboard:``), each once written; a
        tree that declares none (built in Python): every key it wrote under ``/mission/``."""
        board = self.runner.blackboard
        return board.values() if board is not None else {}


class _Ended:
    """What the worker hands the loop when the run has ended: how (``raised``: the
    exception :meth:`RunStack.run` raised itself, None when it returned its summary)."""

    def __init__(self, raised: BaseException | None) -> None:
        self.raised = raised


class TickStepper:
    """The hand-over between the run's worker thread and the program's loop: the run's
    observer puts each :class:`Tick` and waits for :meth:`next_tick`'s next call."""

    def __init__(self, stack: RunStack, inner: TickObserver | None) -> None:
        self.stack = stack
        self.inner = inner
        self._handed: queue.Queue[Tick | _Ended] = queue.Queue()
        self._go_on = threading.Semaphore(0)
        #: the loop is gone (or the run was stopped): the observer hands nothing more
        self.released = False
        self._wait = guarded_between_ticks(stack.runner, self._go_on.acquire, LOOP_BODY)

    def observe(self, runner: MissionRunner) -> None:
        """The run's observer, in its worker thread after each tick: the program's own
        observer first, then the tick handed to the loop, and a wait until it asks again."""
        if self.inner is not None:
            self.inner(runner)
        if self.released:
            return
        root = runner.mission.root
        self._handed.put(Tick(runner.summary.ticks, runner.snapshot, root.status, root, runner))
        self._wait()

    def work(self) -> None:
        """The worker thread: the run, then its end handed to the loop."""
        raised: BaseException | None = None
        try:
            self.stack.run_here(raise_interrupts=False)
        except BaseException as exc:  # the loop raises it: a run that could not run
            raised = exc
        finally:
            self.released = True
            self._handed.put(_Ended(raised))

    def next_tick(self, first: bool) -> Tick | _Ended:
        """The next tick (or the run's end), the worker let go on first unless ``first``."""
        if not first:
            self._go_on.release()
        while True:
            with contextlib.suppress(queue.Empty):
                return self._handed.get(timeout=_WAIT_S)

    def release(self) -> None:
        """The worker no longer waits for the loop (``stack.stop()``, ``close()``)."""
        self.released = True
        self._go_on.release()


def ticks(stack: RunStack) -> Generator[Tick, None, None]:
    """:meth:`RunStack.ticks`: the run in a worker thread, each tick yielded; the run
    stopped, its safe stop written, on every way out of the loop."""
    stepper = TickStepper(stack, stack.runner.observer)
    stack.runner.observer = stepper.observe
    stack.stepper = stepper
    worker = threading.Thread(
        target=stepper.work, name=f"roomba-bt run of {stack.mission.name}", daemon=True
    )
    interrupt: KeyboardInterrupt | None = None
    ended: _Ended | None = None
    # the run's own guard is the worker's, which can set no handler: the terminal's stops are
    # ignored here, as run() has them on the wall clock
    swallowed_interrupt()  # one kept before this run is not this run's
    with sigterm_raises(), terminal_stops_ignored(stack.runner.on_wall_clock):
        worker.start()
        try:
            first = True
            while True:
                handed = stepper.next_tick(first)
                first = False
                if isinstance(handed, _Ended):
                    ended = handed
                    break
                yield handed
                # a SIGTERM raised in the loop's body that never left it (Python dropped it
                # in a finalizer, or the body's own ``except BaseException`` took it): the
                # loop went on, the robot driving, and systemd's one SIGTERM was lost
                dropped = swallowed_interrupt()
                if dropped is not None:
                    raise dropped.with_traceback(None)
        except KeyboardInterrupt as exc:  # Ctrl-C, or Terminated, while the loop waited
            interrupt = exc
            stack.stop(interrupt_reason(exc))
        finally:
            if ended is None:  # a break, an exception, close(), Ctrl-C: the run stops
                stack.stop(LOOP_LEFT)
            late = _join(worker)
    if ended is not None and ended.raised is not None:
        raise ended.raised
    interrupt = interrupt or late
    if interrupt is not None:
        raise interrupted(interrupt, stack.summary) from None


def replayed_loop(runner: MissionRunner, inner: TickObserver | None) -> TickObserver:
    """The observer a replay gives ``runner`` where its recorded run was a program's loop over
    ``stack.ticks()`` whose tick guard acted or saw a pass past its limit there: after each
    tick, ``inner`` (the replay's own observer), then the loop's place watched as the
    stepper watches it live (:data:`LOOP_BODY`), its recorded acts done there (the drive 0
    after the tick's flush, the wheels given back with the next tick's) and counted as the
    loop's (``loop_slow``, ``loop_halts``). The replay did them inside the tree's tick: a
    slow tick of the tree's, its wheels given back a tick early (a difference, exit 1)."""
    watched = guarded_between_ticks(runner, lambda: None, LOOP_BODY)

    def observe(runner: MissionRunner) -> None:
        if inner is not None:
            inner(runner)
        watched()

    return observe


def _join(worker: threading.Thread) -> KeyboardInterrupt | None:
    """The worker's end awaited, its run's safe stop written, whatever comes meanwhile: a
    Ctrl-C (or SIGTERM) then is kept and returned, to be raised once the robot is stopped
    (as a run's own stop keeps one that comes during it)."""
    late: KeyboardInterrupt | None = None
    while worker.is_alive():
        try:
            worker.join(_WAIT_S)
        except KeyboardInterrupt as exc:
            late = late or exc
    return late
