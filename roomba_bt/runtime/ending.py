"""The run's ending: its tree stopped, the wheels first, and the safe stop, each said.

``MissionRunner._finish`` ends every run in :mod:`~roomba_bt.runtime.teardown`'s order:
drive 0 and motors off while a node still runs (:meth:`RunEnding.wheels_first`), the tree's
stop with nothing set going meanwhile (:meth:`RunEnding.stop_tree`; the monitor's reload
retires a tree with it too), then the safe stop (:func:`stop_robot`, the connection's
:class:`~roomba_bt.robot.ending.SafeStop`) and the nodes' ``shutdown()``
(:meth:`RunEnding.safe_stop`), and the summary's word on each (:meth:`RunEnding.sum_up`).
The monitor's reload retires its old tree with the same bounded stop and shutdown
(:meth:`RunEnding.retire_tree`): one that does not end ends the run, HUNG, as the run's own
end says it.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from types import FrameType

import py_trees

from roomba_bt.behaviours.actions import last_said
from roomba_bt.behaviours.blackboard import run_board, running_on, undeclared_hinted
from roomba_bt.oi.encode import Command
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.printable import duration_said
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS, SafeStop
from roomba_bt.robot.hazards import sets_going
from roomba_bt.robot.interface import Odometer, Outbox, Snapshot
from roomba_bt.robot.safety import SAFE_STOP_UNDER_WAY, InterruptGuard
from roomba_bt.runtime.long_run import RobotCycleWatch
from roomba_bt.runtime.summary import ASLEEP_STOPPED, SEEN_STOPPED_FIRST, RunSummary
from roomba_bt.runtime.teardown import (
    behaviour_at,
    behaviour_in,
    during,
    note_stop_abandoned,
    note_stop_failures,
    note_undelivered_stop,
    shutdown_nodes,
    stop_nodes,
    tree_running,
    where_in,
)
from roomba_bt.runtime.tick_guard import TickGuardLike

#: the run's own logger, whose warnings these are (as ``runtime/stall.py``'s)
log = logging.getLogger("roomba_bt.runtime.loop")

#: what the summary's safe stop adds when the robot streamed on after the stop and took it
#: only when written again after zeros (``SafeStop.taken_again``)
TAKEN_AGAIN_IN_SUMMARY = (
    " (not taken at first: a lost byte may have started a long command; sent {zeros} zeros "
    "and the stop again, heard at write {times})"
)
#: what a Ctrl-C says while the run's tree is stopped (each running node's ``terminate()``),
#: after what the wheels do meanwhile, and how long the run's end waits for it
STOPPING_THE_TREE = (
    "the run is ending: {wheels}; its tree is being stopped (each running behaviour's "
    "terminate(), for at most {limit}), the safe stop after it"
)
#: How long the run's end waits for its tree's stop: unbounded, a plugin's ``terminate()``
#: that never returns would hold the run's end for ever, the robot left in Safe with its
#: stream going, no summary printed and no signal ending the process (each held for the stop
#: to end). Past this the end goes on without it: the safe stop, the
#: summary (HUNG, the terminate and its line named), the exit code. A few seconds: a
#: terminate that closes a file or a socket has ample time, an operator's Ctrl-C meanwhile
#: waits no longer; ``run --wall-limit`` below it caps it (:func:`tree_stop_limit`).
TREE_STOP_LIMIT_S = 5.0
#: ... and while the nodes' ``shutdown()`` runs, waited for as long at most (the same
#: bound: a ``shutdown()`` that never returns would hang the process as a ``terminate()``
#: would, after the safe stop but before the summary and the exit code)
SHUTTING_DOWN = "the robot is stopped; the behaviours' shutdown() is under way"
#: how a HUNG run's reason begins when a ``terminate()`` or a ``shutdown()`` never returned
#: (``eval``'s closing line words a HUNG episode from it: ``cli/eval_report.py``)
STOP_NOT_ENDED = "the tree's stop did not end within"
SHUTDOWN_NOT_ENDED = "the behaviours' shutdown() did not end within"
#: what the run's reason says a late signal came during (``Ctrl-C during the tree's stop, in
#: slow (Slow.terminate at plugin.py:12)``; the safe stop's is ``THE_SAFE_STOP``)
THE_TREES_STOP, THE_SHUTDOWN = "the tree's stop", "the behaviours' shutdown()"
#: what a HUNG run's reason says after its method and line when the monitor's reload waited
#: for the old tree's stop or shutdown in vain (:meth:`RunEnding.retire_tree`)
RELOAD_GIVEN_UP = "the reload of {mission} was given up and the run ended ({left})"


class RetireHung(Exception):
    """The monitor's reload waited for its old tree's stop or its nodes' ``shutdown()`` past
    the bound of a run's end (:meth:`RunEnding.retire_tree`): the run ends on it, HUNG (exit
    4), its reason (``str()``) naming the method and its line, as the run's end says one it
    waited for in vain. An ``Exception`` raised by the runtime (the monitor's gate), never in
    a behaviour's code: no behaviour's ``except`` sees it. ``at``: it came before the tick,
    as the monitor's stop does (the record's end note)."""

    at = "before"


@dataclass(frozen=True, eq=False)
class RunEnding:
    """How a run stops its tree on ``connection``: the wheels first, nothing the behaviours
    write meanwhile sets the robot going (counted in ``summary``), what they queued in
    ``outbox`` dropped. The runner's parts, held as it made them (frozen: one run, one
    ending; ``eq=False``: each ending is its own, compared by identity)."""

    connection: Connection
    outbox: Outbox
    summary: RunSummary
    #: the mission time so many seconds after the last tick's frame (None before the
    #: first), to place what was not written
    clock: Callable[[float], float | None]
    #: the run's odometry, told by the writer each time the robot goes to Passive: what it
    #: drives there by itself may be a cycle it started (:attr:`cycles`)
    odometer: Odometer
    #: the watch for a cycle the robot started by itself (the loop's once-a-second look),
    #: looked at once more before the safe stop (:meth:`safe_stop`)
    cycles: RobotCycleWatch = field(init=False)
    #: what the tree's stop left for the shutdown: its bound, and the node whose
    #: ``terminate()`` was abandoned (:meth:`end_tree`, :meth:`safe_stop`)
    left: _StopLeft = field(init=False)

    def __post_init__(self) -> None:
        watch = RobotCycleWatch(self.connection, self.summary, self.odometer, self.clock)
        object.__setattr__(self, "cycles", watch)  # frozen: set once, as it is made
        object.__setattr__(self, "left", _StopLeft())

    def end_tree(
        self,
        root: py_trees.behaviour.Behaviour,
        tick_guard: TickGuardLike | None,
        guard: InterruptGuard,
        raised_in: py_trees.behaviour.Behaviour | None,
        limit_s: float = TREE_STOP_LIMIT_S,
    ) -> bool:
        """The tree's stop at the run's end (:meth:`stop_tree`, its failures in the
        summary), drive 0 and motors off before it if the wheels move (:meth:`wheels_first`:
        True if they were sent), and a warning if it blocked (:meth:`_said_slow_stop`). The
        stop runs in a thread of its own, waited for ``limit_s`` at most
        (:data:`TREE_STOP_LIMIT_S`): past it the run's end goes on without it
        (:meth:`_abandoned`), in this thread, which is not stuck."""
        # the mission's last words, whatever ended it (the summary's "mission said")
        self.summary.said = last_said(root) or ""
        self.left.limit_s = limit_s  # the shutdown's bound too
        stopper = self.left.reloading if self.left.reloading_root is root else None
        if stopper is not None and self.left.given_up:  # the run ended on it: said already
            return False  # (the guard says the safe stop is under way: it is next)
        if stopper is None:  # else the reload's, interrupted: waited for, not run twice
            stopper = _Bounded(
                THE_TREES_STOP, "roomba-bt tree stop", lambda: self.stop_tree(root, raised_in)
            )
        first = self.wheels_first(root, tick_guard, guard, stopper, limit_s)
        began = time.monotonic()
        failures = stopper.within(limit_s)
        if failures is None:  # a terminate that has not returned: the end goes on without it
            self._abandoned(stopper, limit_s, late=guard.late is not None)
            return first
        note_stop_failures(self.summary, failures)
        self._said_slow_stop(tick_guard, time.monotonic() - began, first)
        return first

    def _abandoned(self, stopper: _Bounded, limit_s: float, late: bool) -> None:
        """The tree's stop ran past ``limit_s`` (:class:`_Bounded`): said in the summary
        (:meth:`_stop_given_up`'s words), and warned. ``late``: a signal came meanwhile,
        whose interrupt the run's reason says (:func:`note_stop_abandoned`)."""
        said = self._stop_given_up(stopper, limit_s, "the run's end went on without it ({})")
        log.warning("%s", said)
        note_stop_abandoned(self.summary, said, interrupted=late)

    def _stop_given_up(self, stopper: _Bounded, limit_s: float, then: str) -> str:
        """What a tree's stop that ran past ``limit_s`` says, naming the method it is stuck
        in and its line (``term_hang (TermHang.terminate at plugin.py:17)``, as the tick guard
        names a blocked ``update``), ``then`` what was done instead (``{}``: the safe stop and
        the summary). What its nodes queued is dropped, and the writer still holds what would
        set the robot going (its thread may write yet). The node stuck there is not shut down
        (:attr:`left`, :meth:`safe_stop`): its ``shutdown()`` would meet the state its
        ``terminate()`` holds, and wait on it as well."""
        self.left.stuck = stopper.behaviour()
        self.outbox.clear()
        where = stopper.where() or "a behaviour's terminate()"
        skipped = "; its shutdown() not called" if self.left.stuck is not None else ""
        left = then.format(f"the safe stop, the summary{skipped}")
        return f"{STOP_NOT_ENDED} {duration_said(limit_s)}: {where} had not returned; {left}"

    def retire_tree(
        self, root: py_trees.behaviour.Behaviour, mission: str, limit_s: float = TREE_STOP_LIMIT_S
    ) -> None:
        """The monitor's reload, once its pause has stopped the robot: the old tree at
        ``root`` stopped (:meth:`stop_tree`), then its nodes' ``shutdown()``, each in a
        thread of its own waited for ``limit_s`` at most, as at the run's end
        (:class:`_Bounded`): one that never returned hung the reload, and the run, for ever,
        the robot paused in Passive and no signal but a kill ending it. Past the bound the
        reload of ``mission`` (its name) is given up and :class:`RetireHung` raised, its words
        those of the run's end (the method and its line); the run's end then neither stops
        the tree again nor shuts down the node stuck in its ``terminate()`` (:attr:`left`).
        A signal while the stop is waited for ends the run, whose end waits for this same
        stop (:meth:`end_tree`), never a second one beside it. The failures of a
        ``terminate()`` or ``shutdown()`` are logged, as a reload always did."""
        stopper = _Bounded(THE_TREES_STOP, "roomba-bt tree stop", lambda: self.stop_tree(root))
        self.left.reloading, self.left.reloading_root = stopper, root
        then = RELOAD_GIVEN_UP.format(mission=mission, left="{}")
        if stopper.within(limit_s) is None:
            self.left.given_up = True
            raise RetireHung(self._stop_given_up(stopper, limit_s, then))
        self.left.reloading = self.left.reloading_root = None
        shutdown = _Bounded(THE_SHUTDOWN, "roomba-bt shutdown", lambda: shutdown_nodes(root)[1])
        if shutdown.within(limit_s) is None:
            said = then.format("the safe stop, the summary")
            raise RetireHung(self._shutdown_given_up(shutdown, limit_s, said))

    def _shutdown_given_up(self, shutdown: _Bounded, limit_s: float, then: str) -> str:
        """What the nodes' ``shutdown()`` that ran past ``limit_s`` says, naming the method
        it is stuck in and its line; ``then``: what was done instead."""
        where = shutdown.where() or "a behaviour's shutdown()"
        return f"{SHUTDOWN_NOT_ENDED} {duration_said(limit_s)}: {where} had not returned; {then}"

    def safe_stop(
        self,
        guard: InterruptGuard,
        first: bool,
        set_up: py_trees.behaviour.Behaviour | None,
        last: Snapshot | None = None,
    ) -> None:
        """After the tree's stop: the safe stop (:func:`stop_robot`; ``first``: drive 0 and
        motors off went out before the tree's stop), a cycle the robot still drives by
        itself at ``last`` (the last tick's snapshot; None: none came) ended by it with Safe
        first (:meth:`RobotCycleWatch.at_end`), then each node's ``shutdown()`` of the tree
        at ``set_up`` (None: its ``setup()`` never ran, nothing to close), but the one whose
        ``terminate()`` the tree's stop left running (:attr:`left`), in a thread of its own
        waited for as long as the tree's stop at most (:meth:`_shut_down`). ``guard`` is told
        what the run does meanwhile, for a Ctrl-C then."""
        guard.stopping(SAFE_STOP_UNDER_WAY)
        if last is not None:
            self.cycles.at_end(last)
        stop_robot(self.connection, self.summary, first)
        if set_up is not None:
            self._shut_down(set_up, guard)

    def _shut_down(self, set_up: py_trees.behaviour.Behaviour, guard: InterruptGuard) -> None:
        """Each node's ``shutdown()`` (:func:`shutdown_nodes`; an exception there logged, no
        more; a ``sys.exit()`` there the run's error) in a daemon thread, waited for the
        tree's stop's bound at most: past it the run's end goes on to the summary and the
        exit code without it, said as the tree's stop's is (HUNG, the method and its line);
        one that never returned hung the process after the safe stop."""
        stuck = self.left.stuck
        shutdown = _Bounded(
            THE_SHUTDOWN, "roomba-bt shutdown", lambda: shutdown_nodes(set_up, stuck)[1]
        )
        guard.stopping(SHUTTING_DOWN, shutdown.during)
        limit_s = self.left.limit_s
        exits = shutdown.within(limit_s)
        if exits is not None:
            note_stop_failures(self.summary, exits)
            return
        then = "the run's end went on without it (the summary)"
        said = self._shutdown_given_up(shutdown, limit_s, then)
        log.warning("%s", said)
        note_stop_abandoned(self.summary, said, interrupted=guard.late is not None)

    def sum_up(self, wall_time_s: float, last: Snapshot | None, unconfirmed: int) -> None:
        """The summary's last figures, once the robot is stopped: the run's wall time, the
        last snapshot's (None: none came), the mode the robot was left in (and whether the
        stream showed it: packet 35), whether it ever answered, the hazard onsets never
        confirmed, the parser's counters, the falls and the undeclared keys written (the
        tree's ``terminate()`` calls too: this is after its stop)."""
        summary, connection = self.summary, self.connection
        summary.undeclared_keys = undeclared_hinted(run_board())
        summary.wall_time_s = wall_time_s
        summary.take_last(last)
        summary.final_mode = mode_of(connection)
        link = getattr(connection, "link", None)
        streamed = getattr(link, "stream_ids", None)  # none asked for: nothing to say
        summary.mode_streamed = not streamed or OI_MODE_PACKET in streamed
        heard = getattr(connection, "robot_answered", None)  # a reply or a frame, not noise
        summary.robot_answered = getattr(link, "bytes_read", 1) > 0 if heard is None else heard
        summary.unconfirmed_hazards = unconfirmed
        summary.take_counters(getattr(connection, "counters", None))
        summary.falls = dict(getattr(connection, "falls", {}))
        suspected = getattr(connection, "cable_suspected", None)
        summary.falls_cable = suspected() if callable(suspected) else ""

    def wheels_first(
        self,
        root: py_trees.behaviour.Behaviour,
        tick_guard: TickGuardLike | None,
        guard: InterruptGuard,
        stopper: _Bounded | None = None,
        limit_s: float = TREE_STOP_LIMIT_S,
    ) -> bool:
        """Before the tree's stop, whose ``terminate()`` calls may block (a plugin's
        ``time.sleep``): drive 0 and motors off, the first half of the safe stop, through the
        run's tick guard (a run on the wall clock; a replay's, as its record says), when a
        node still runs and the wheels move or the tree's last Motors runs a brush or the
        vacuum. True if they were sent. ``guard`` is told what the run does meanwhile, for a
        Ctrl-C then, and where the stop (``stopper``'s thread) is when it comes."""
        motors = self.outbox.standing.get("motors")
        first = (
            tick_guard is not None
            and tree_running(root)
            and tick_guard.halt_before_stop(motors is not None and sets_going(motors))
        )
        wheels = (
            "drive 0 and motors off were sent"
            if first
            else f"the robot keeps its last wheel command ({self.connection.activity()})"
        )
        doing = STOPPING_THE_TREE.format(wheels=wheels, limit=duration_said(limit_s))
        # the stop's own thread's frame, not this one's, which waits for it
        guard.stopping(doing, during(THE_TREES_STOP) if stopper is None else stopper.during)
        return first

    def _said_slow_stop(
        self, tick_guard: TickGuardLike | None, seconds: float, first: bool
    ) -> None:
        """A tree's stop that took longer than a tick may (a ``terminate()`` that blocked):
        warned, with what the wheels did meanwhile (``first``: drive 0 went out before it)."""
        limit = tick_guard.limit_s if tick_guard is not None else None
        if not limit or seconds <= limit:
            return
        activity = self.connection.activity()
        wheels = (
            "drive 0 and motors off had been sent before it"
            if first
            else f"the robot kept its last wheel command ({activity}) meanwhile"
        )
        log.warning(
            "stopping the tree took %.2f s (a behaviour's terminate() blocked); %s", seconds, wheels
        )

    def stop_tree(
        self,
        root: py_trees.behaviour.Behaviour,
        raised_in: py_trees.behaviour.Behaviour | None = None,
    ) -> list[str]:
        """Stop the running tree at ``root`` (each running node's ``terminate``, every node
        even when one raises: :func:`~roomba_bt.runtime.teardown.stop_nodes`) and drop what
        its leaves queued on the way out: the safe stop that comes with it (the run's end, a
        reload from the monitor) supersedes their halts, which Passive would refuse anyway;
        one that would have set the robot going is said (:meth:`_dropped_in_stop`).
        Meanwhile nothing written sets the robot going (:meth:`CommandWriter.hold_motion
        <roomba_bt.robot.writer.CommandWriter.hold_motion>`, :meth:`_held_in_stop`): a
        plugin's terminate that wrote a drive straight to the connection and then blocked
        drove the robot until the safe stop. Its commands no longer stand: nothing sends them
        again (a resume, the watchdog's recovery). Returns what each ``terminate`` that
        raised says (each logged as a warning); ``raised_in``: the node whose ``terminate``
        raised in the tick that ended the run, already said, is stopped without calling it
        again."""
        writer = self.connection.writer
        outbox = self.outbox
        # what a tick that raised had queued is dropped too, but was not sent by the stop
        before = [(id(command), id(sender)) for command, sender in outbox.queued_by()]
        writer.hold_motion(self._held_in_stop)
        try:
            failures = stop_nodes(root, raised_in)
        finally:
            writer.hold_motion(None)
        for command, sender in outbox.queued_by():
            if sets_going(command) and (id(command), id(sender)) not in before:
                self._dropped_in_stop(command, sender)
        outbox.clear()  # what stood too
        return failures

    def _held_in_stop(self, command: Command) -> None:
        """A command written while the tree was stopped that would have set the robot going:
        not written (:meth:`stop_tree`); said and counted (:meth:`_not_written`), with the
        behaviour that wrote it and where (the frame that called the writer: a bound method
        adds none)."""
        self._not_written(where_in(sys._getframe(1)) or "a behaviour", "sent", command)

    def _dropped_in_stop(self, command: Command, sender: object) -> None:
        """A command queued (``send``) while the tree was stopped that would have set the
        robot going: dropped with the outbox (:meth:`stop_tree`); said, with the behaviour
        that queued it and its ``terminate`` (the method that runs then; the line of the
        ``send`` itself is not kept). It was dropped silently, though docs/runtime.md said
        otherwise."""
        who = "the runtime"
        if isinstance(sender, py_trees.behaviour.Behaviour):
            cls = type(sender)
            code = getattr(cls.terminate, "__code__", None)
            where = f" at {code.co_filename}:{code.co_firstlineno}" if code is not None else ""
            who = f"{sender.name} ({cls.__name__}.terminate{where})"
        self._not_written(who, "queued", command)

    def _not_written(self, who: str, how: str, command: Command) -> None:
        """A command that would have set the robot going while the tree was stopped, not
        written (:meth:`_held_in_stop`, :meth:`_dropped_in_stop`): logged, counted, the first
        kept for the summary and ``--strict`` (``t=1.005 sticky (Sticky.terminate at x.py:31)
        queued Drive (137) 89 01 2c 80 00``)."""
        what = f"{command.spec.title} ({command.opcode}) {command.data.hex(' ')}"
        log.warning(
            "%s %s %s while the tree was being stopped: not written (the tree's stop sets "
            "nothing going: it would run on, unwatched, until the safe stop)", who, how, what,
        )  # fmt: skip
        summary = self.summary
        summary.dropped_in_stop += 1
        if not summary.first_dropped:
            now = self.clock(0.0)  # the last tick's time
            when = f"t={now:.3f} " if now is not None else ""
            summary.first_dropped = f"{when}{who} {how} {what}"


@dataclass
class _StopLeft:
    """What a run's tree's stop leaves for its shutdown (:attr:`RunEnding.left`): the bound
    it was waited for, and the node whose ``terminate()`` had not returned (None: none)."""

    limit_s: float = TREE_STOP_LIMIT_S
    stuck: py_trees.behaviour.Behaviour | None = None
    #: the monitor's reload's stop of its old tree (at ``reloading_root``) while it has not
    #: ended (:meth:`RunEnding.retire_tree`): the run's end waits for it, never a second
    reloading: _Bounded | None = None
    reloading_root: py_trees.behaviour.Behaviour | None = None
    #: ... and it was given up: the run ended on it, said (:class:`RetireHung`)
    given_up: bool = False


class _Bounded:
    """A part of a run's end that calls the behaviours' code, the tree's stop
    (:meth:`RunEnding.stop_tree`) or the nodes' ``shutdown()`` (``work``: what each that
    failed says), in a daemon thread of its own, lent the run's blackboard (a ``terminate()``
    reads and writes keys as it would in the run's thread), so that the thread that waits
    for it is never stuck in a plugin's method that does not return: it goes on to the safe
    stop and the summary, and the process exits with the thread still in it (a daemon
    thread: nothing waits for it at the interpreter's exit; decided over ``os._exit``, which
    would skip the record's and the streams' own closing, and over an exception raised in
    the stuck thread, which a ``threading.Event().wait()`` in C never sees). ``phase``: what
    a signal meanwhile came during (:data:`THE_TREES_STOP`, :data:`THE_SHUTDOWN`)."""

    def __init__(self, phase: str, name: str, work: Callable[[], list[str]]) -> None:
        self.phase, self.work = phase, work
        self.board = run_board()  # the run's, read in the run's thread
        self.failures: list[str] = []
        #: what the thread raised that was not a behaviour's failure (a signal's interrupt
        #: raised in it is not: signals go to the main thread), raised again in the waiter
        self.raised: BaseException | None = None
        self.done = threading.Event()
        #: where this thread signalled its own process (:meth:`_called`), "" if it did not
        self.signalled = ""
        self.began = 0.0  #: when it started (``time.monotonic()``): :meth:`within`
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        sys.setprofile(self._called)  # this thread's alone, for as long as it runs
        try:
            with running_on(self.board, ends_run=False):
                self.failures = self.work()
        except BaseException as exc:  # carried to the waiting thread, raised there
            self.raised = exc
        finally:
            sys.setprofile(None)
            self.done.set()

    def _called(self, frame: FrameType, event: str, arg: object) -> None:
        """A signal this thread sends its own process (``os.kill(os.getpid(), ...)`` in a
        terminate): where it was sent from, kept (:attr:`signalled`). Its handler runs in the
        main thread, and this one may have run on, or ended, by then."""
        if event == "c_call" and arg in _SIGNALLING and not self.signalled:
            self.signalled = behaviour_at(frame)

    def within(self, limit_s: float) -> list[str] | None:
        """Start the work and wait for it until ``limit_s`` after its start at most: what
        each behaviour that failed says, or None if it has not ended by then. Started
        already (a reload's stop that a signal interrupted: :meth:`RunEnding.end_tree`),
        what is left of that bound. A signal's handler runs in this (the main) thread
        meanwhile: the guard holds it (:class:`InterruptGuard`)."""
        if self.thread.ident is None:
            self.began = time.monotonic()
            self.thread.start()
        if not self.done.wait(max(0.0, self.began + limit_s - time.monotonic())):
            return None
        if self.raised is not None:
            raise self.raised
        return self.failures

    def _frame(self) -> FrameType | None:
        ident = self.thread.ident
        return None if ident is None else sys._current_frames().get(ident)

    def where(self) -> str:
        """The behaviour's method the thread is in now, at its line (:func:`behaviour_at`)."""
        return behaviour_at(self._frame())

    def behaviour(self) -> py_trees.behaviour.Behaviour | None:
        """The behaviour whose method the thread is in now (:func:`behaviour_in`)."""
        return behaviour_in(self._frame())

    def during(self, _frame: FrameType | None) -> str:
        """What a signal that came meanwhile came during (``InterruptGuard.stopping``'s
        ``during``, given the main thread's frame, which only waits): the phase, in the
        behaviour's method this thread is in, or sent the signal from."""
        where = self.signalled or self.where()
        return f"{self.phase}, in {where}" if where else self.phase


def threads_left() -> int:
    """How many threads a run's end left stuck in a behaviour's ``terminate()`` or
    ``shutdown()`` still live in this process (:class:`_Bounded`'s, past their bound): each
    holds its run's tree, connection and simulator until the process exits (``eval --jobs 1``
    caps them: ``evaluate/parallel.py``)."""
    names = {"roomba-bt tree stop", "roomba-bt shutdown"}
    return sum(1 for t in threading.enumerate() if t.name in names and t.is_alive())


#: the calls by which a thread signals its own process (:meth:`_Bounded._called`)
_SIGNALLING = tuple(
    call
    for call in (os.kill, getattr(signal, "pthread_kill", None), signal.raise_signal)
    if call is not None
)


def tree_stop_limit(wall_limit_s: float | None) -> float:
    """How long a run's end waits for its tree's stop: :data:`TREE_STOP_LIMIT_S`, or less
    under a shorter ``run --wall-limit`` (the run was given no more than that in all)."""
    if wall_limit_s is None or wall_limit_s <= 0.0:
        return TREE_STOP_LIMIT_S
    return min(TREE_STOP_LIMIT_S, wall_limit_s)


def stop_robot(connection: Connection, summary: RunSummary, first: bool = False) -> None:
    """The safe stop, and the summary's word on it: what was sent, or why it was not
    delivered (the connection's report); ``first``: drive 0 and motors off went out before
    the tree's stop (:meth:`RunEnding.wheels_first`), said before it."""
    try:
        sequence = [c.name for c in connection.stop_sequence()]
        if connection.safe_stop():
            before = "drive 0, motors off before the tree's stop, then " if first else ""
            back = getattr(getattr(connection, "ending", None), "port_return", None)
            reopened = back.said if back is not None else ""
            through = f" ({reopened})" if reopened else ""
            again = getattr(getattr(connection, "ending", None), "taken_again", 0)
            if again:  # the robot took it only after zeros: a lost byte's long command
                through += TAKEN_AGAIN_IN_SUMMARY.format(
                    zeros=len(STOP_RESYNC_ZEROS), times=again + 1
                )
            found_at = getattr(getattr(connection, "ending", None), "found_at", "")
            if found_at:  # heard only at another rate: a Baud made of lost bytes
                through += f" ({found_at})"
            summary.safe_stop = (
                before + "sent " + ", ".join(sequence) + through
                if sequence
                else "nothing to stop: the robot was never started"
                if connection.mode is OIMode.OFF and connection.writer.sent == 0
                else off_by_the_tree(connection.writer.silenced_by)
                if connection.mode is OIMode.OFF and connection.writer.silenced_by is not None
                else "nothing to send"
            )
            return
        report = getattr(connection, "stop_report", None)
        ending = getattr(connection, "ending", None)
        said = undelivered_said(connection)
        summary.safe_stop = said + (report or "the stop sequence could not be written")
        summary.stop_delivered = False
        summary.set_nothing_going = getattr(ending, "nothing_set_going", False)
        summary.stop_report = report or ""
        summary.stop_advice = getattr(ending, "stop_advice", "") if report else ""
        summary.asleep_stopped = getattr(ending, "asleep_stopped", False)
        summary.seen_stopped = getattr(ending, "seen_still", False)
        note_undelivered_stop(summary)
    except KeyboardInterrupt:
        summary.safe_stop = "interrupted during the safe stop"
    except Exception as exc:
        summary.safe_stop = f"FAILED: {type(exc).__name__}: {exc}"


def undelivered_said(connection: object) -> str:
    """The first words of what is said of a stop not known delivered, the summary's ``safe
    stop`` line's and the command line's after an internal error alike (the connection's
    ``stop_report`` follows them): ``NOT DELIVERED:``, in capitals, only for a robot that
    may be moving. A robot the run set nothing going for (one that never left Passive nor
    had a wheel command: an alarm to a hobbyist) is said calmly; so is one whose reset was
    read (its OI is Off, its wheels stopped, whatever the stop did: the report says it) and
    one seen stopped that then fell asleep (a long pause: asleep, it does not move), and
    one whose frames, sent after every command written, showed it stopped, whatever kept
    the stop from it then (a cable pulled while the monitor held the run paused: the
    pause's own stop seen taken; ``robot.ending.seen_stopped``). One function for both
    lines, so that the command line and the summary never word one stop differently."""
    ending = getattr(connection, "ending", None)
    if getattr(ending, "nothing_set_going", False):
        return "nothing this run set going; "
    if getattr(ending, "reset_seen", False):
        return ""
    if getattr(ending, "asleep_stopped", False):
        return f"{ASLEEP_STOPPED}; "
    if getattr(ending, "seen_still", False):
        return f"{SEEN_STOPPED_FIRST}; "
    return "NOT DELIVERED: "


def off_by_the_tree(command: Command | None) -> str:
    """The safe stop's word when the tree's own Reset or Stop left the robot in Off: nothing
    to send, the robot is stopped there (its wheels and motors stop as the OI turns off)."""
    name = "Reset or Stop" if command is None else f"{command.spec.title} ({command.spec.opcode})"
    return f"nothing to send: the tree's {name} left the robot in Off, stopped"


def mode_of(connection: object) -> OIMode | None:
    """The OI mode ``connection``'s model holds, if it has one; after a stop that did not
    reach the robot, the mode it was last seen in (a stop written but unconfirmed moved the
    model to Passive: ``last seen in Passive`` was said of a robot last seen in Safe)."""
    ending = getattr(connection, "ending", None)
    if isinstance(ending, SafeStop) and ending.safe_stopped is False:
        return ending.last_seen
    mode = getattr(connection, "mode", None)
    return mode if isinstance(mode, OIMode) else None
