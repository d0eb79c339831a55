"""The tick loop: one tick per stream frame, its commands guarded and written after it.

Per batch of frames read from the connection::

    frames --(newest only; older ones are stale: dropped and counted)--> Snapshot
      Snapshot -> blackboard "/roomba/snapshot" (one write) and the RobotHandle
      root.tick_once()  (by its tick_direct when it is a lean node: tick_of)
      outbox.drain() -> mode guard -> written, right after the tick, one write a command
                        (Connection.send each; _flush)

The stream is the clock. Each frame is one 15 ms slot; the tick index advances by the number of
frames read, plus the slots the schedule says passed with no frame (frames lost in transit:
a gap is measured, not ignored; jitter makes none: :mod:`roomba_bt.runtime.schedule`).
Mission time is ``tick * 0.015`` s: the same bytes replayed at any speed, or a simulation on
the virtual clock, make the same decisions. See ``docs/runtime.md``.

No ``py_trees.trees.BehaviourTree`` here: the frames are the clock, so :class:`MissionRunner`
ticks ``root.tick_once()`` itself, once a frame, where ``BehaviourTree.tick_tock`` would tick
on a timer. Its pre- and post-tick handlers are the :class:`TickGate` (``before_tick``, which
may hold the frame's tick, and ``after_tick``: the monitor's session, which records each
tick in its feed), and its post-tick handler the observer (:data:`TickObserver`: the live
tree or the status log); py_trees visitors, when a run is given some, are run on each tick as
``BehaviourTree.tick`` runs them (:func:`visiting_tick`); the tree's ``shutdown`` is
:func:`~roomba_bt.runtime.teardown.shutdown_nodes`.
"""

from __future__ import annotations

import logging
import time
import traceback
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import replace
from functools import partial
from typing import Any, NoReturn, Protocol, cast

import py_trees

from roomba_bt.behaviours.base import UnkeptDeclaration
from roomba_bt.behaviours.blackboard import RunBoard, check_alone, claim_board, running_on
from roomba_bt.behaviours.lean import Direct
from roomba_bt.behaviours.reasons import failure_reason, running_in
from roomba_bt.mission import RUNTIME_PACKETS
from roomba_bt.oi.encode import Command
from roomba_bt.oi.errors import BandwidthError
from roomba_bt.oi.frames import BATTERY_PACKETS, SLOT_SECONDS, SensorFrame
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import check_bandwidth
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import (
    ConnectionFailed,
    LinkDown,
    ModeError,
    StreamStalled,
    TurnedAway,
)
from roomba_bt.robot.hazards import HazardConfirmation
from roomba_bt.robot.interface import (
    BaseHandle,
    ModeChange,
    Odometer,
    Snapshot,
)
from roomba_bt.robot.modes import ModeModel
from roomba_bt.robot.safety import (
    InterruptGuard,
    RunAborted,
    Terminated,
    interrupt_reason,
    interrupted_in,
)
from roomba_bt.runtime.clock import (
    StreamClock,
    ended_at,
    interrupted_at,
    mission_time_after,
)
from roomba_bt.runtime.display import TreeStatuses
from roomba_bt.runtime.ending import RetireHung, RunEnding, tree_stop_limit
from roomba_bt.runtime.long_run import MissionTimeChecks
from roomba_bt.runtime.motion_watch import MotionWatch
from roomba_bt.runtime.refusals import Refusals
from roomba_bt.runtime.schedule import DRIFT, LOST_LATE, SPREAD_DECAY
from roomba_bt.runtime.stall import StallRide
from roomba_bt.runtime.summary import (
    DEFAULT_GRACE,
    EXPECTED_FALLS,
    Outcome,
    RunSummary,
    profile_shown,
)
from roomba_bt.runtime.teardown import (
    behaviour_error,
    behaviours_interrupt,
    cut_short,
    note_late_interrupt,
    raised_in_tree,
    setup_tree,
    terminate_raised,
)
from roomba_bt.runtime.tick_guard import TickGuardLike
from roomba_bt.runtime.tick_watch import slowest_tick_named
from roomba_bt.runtime.wall_limit import WallLimit

log = logging.getLogger(__name__)

#: the actuator channels the robot stops when it falls to Passive by itself (a cliff, a wheel
#: drop): their last commands no longer stand (:meth:`MissionRunner._fallback_changed`)
FALL_STOPS = ("wheels", "motors")
_new_tuple = tuple.__new__
_Blackboard = py_trees.blackboard.Blackboard
#: the blackboard's one store (py_trees clears it, never replaces it): read off the class on
#: every tick, it was an attribute read CPython 3.11 does not specialise
_STORAGE = _Blackboard.storage
_DIRECT_TICK_ONCE = Direct.tick_once

#: Battery charge and capacity, for the run summary: streamed when the budget allows.
SUMMARY_PACKETS: tuple[int, ...] = BATTERY_PACKETS


def stream_request(mission_packets: Iterable[int], baud: int) -> tuple[int, ...]:
    """The packets to stream: what the mission reads, what the runtime needs
    (:data:`~roomba_bt.mission.RUNTIME_PACKETS`) and, if they still fit in the 15 ms budget
    at ``baud``, :data:`SUMMARY_PACKETS`. Raises :class:`~roomba_bt.oi.BandwidthError` if the
    required set does not fit (the validator reports the same before a run)."""
    required = set(mission_packets) | set(RUNTIME_PACKETS)
    check_bandwidth(sorted(required), baud)
    wanted = tuple(sorted(required | set(SUMMARY_PACKETS)))
    try:
        check_bandwidth(wanted, baud)
    except BandwidthError:
        return tuple(sorted(required))
    return wanted


class _NoSnapshotYet:
    """What :attr:`MissionRunner.snapshot` holds before the first frame: reading any of its
    fields (or indexing, or iterating it) raises the error that says why.

    A placeholder in the attribute, not a ``__getattr__`` on the runner: a class with
    ``__getattr__`` keeps CPython 3.11 from specialising *any* attribute read of its
    instances (the runner's own ``self._...`` reads in every tick's ``_advance``, ``_flush``
    and ``_loop``, the leaves' ``robot.snapshot``), each then several hundred instructions
    instead of a few dozen: about 11,000 instructions a dock or bump-and-turn tick."""

    __slots__ = ()

    def _none_yet(self, *args: object) -> NoReturn:
        raise RuntimeError("no sensor frame yet: the tree is ticked only after the first")

    __getattr__ = __getitem__ = __iter__ = __len__ = _none_yet

    def __repr__(self) -> str:
        return "<no snapshot yet>"


#: :attr:`MissionRunner.snapshot` before the first frame (:class:`_NoSnapshotYet`)
NO_SNAPSHOT_YET: Snapshot = cast(Snapshot, _NoSnapshotYet())


class MissionLike(Protocol):
    name: str

    @property
    def root(self) -> py_trees.behaviour.Behaviour: ...
    @property
    def packets(self) -> tuple[int, ...]: ...
    def setup(self, robot: Any) -> None: ...


TickObserver = Callable[["MissionRunner"], None]


class VisitorLike(Protocol):
    """A py_trees visitor (``py_trees.visitors.VisitorBase``, or any object with these
    three methods), run on every tick as ``py_trees.trees.BehaviourTree.tick`` runs it
    (:func:`visiting_tick`); one whose ``full`` is true visits every node after the tick,
    any other each node the tick ticked, as it is ticked."""

    def initialise(self) -> None: ...
    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None: ...
    def finalise(self) -> None: ...


class TickGate(Protocol):
    """An operator's hold on the run (the live monitor): called around every tick."""

    def before_tick(self, runner: MissionRunner) -> bool:
        """After the frame's snapshot, before the tick; False: do not tick this frame."""
        ...

    def after_tick(self, runner: MissionRunner) -> None:
        """After the tick, its flush and the observer."""
        ...

    def holds(self, runner: MissionRunner) -> bool:
        """The root has just ended: True to hold the run there (its frames go on through
        :meth:`before_tick`) until :meth:`before_tick` lets a tick through, which ends it."""
        ...


class StopRequested(Exception):
    """An operator ended the run (the monitor's stop): it ends as on Ctrl-C, exit 130.

    ``at``: in which half of the last frame it came, for the record's end note (``"before"``
    the tree's tick on it, as a gate's stop comes; ``"after"``: a stop that came with no
    frame, once the last one had ticked)."""

    def __init__(self, reason: str, at: str = "before") -> None:
        super().__init__(reason)
        self.at = at


class Interrupted(KeyboardInterrupt):
    """A Ctrl-C that ended a run, raised again by :meth:`MissionRunner.run` once the robot
    is stopped, the run's summary as :attr:`summary`. A ``KeyboardInterrupt``, as the
    interrupt it stands for (``except KeyboardInterrupt`` catches it); ``except
    roomba_bt.Interrupted as interrupt: interrupt.summary`` is typed (``interrupt.summary``
    on a bare ``KeyboardInterrupt`` failed ``mypy --strict``). Uncaught, it ends the program
    with exit status 1, not by SIGINT (130) as Ctrl-C's own does: Python does that for
    ``KeyboardInterrupt`` itself only. ``raise SystemExit(interrupt.summary.exit_code)``
    ends it as ``roomba-bt run`` does (``roomba-bt docs runtime``, a tree built by hand)."""

    summary: RunSummary

    def __init__(self, *args: object, summary: RunSummary) -> None:
        super().__init__(*args)
        self.summary = summary


class RunTerminated(Interrupted, Terminated):
    """SIGTERM, SIGHUP, Ctrl-Z or Ctrl-\\ that ended a run, raised again as Ctrl-C's is: an
    :class:`Interrupted` and a :class:`~roomba_bt.robot.safety.Terminated` (its ``signum``)."""

    def __init__(self, signum: int, *, summary: RunSummary) -> None:
        Terminated.__init__(self, signum)
        self.summary = summary


def interrupted(interrupt: KeyboardInterrupt, summary: RunSummary) -> KeyboardInterrupt:
    """What :meth:`MissionRunner.run` raises again for ``interrupt``, once the robot is
    stopped: an :class:`Interrupted` (a :class:`RunTerminated` for a signal) with the
    summary, its traceback the interrupt's. A ``KeyboardInterrupt`` subclass of the
    program's own (raised by its behaviour) is raised as it is, the summary set on it, so
    that its ``except`` still catches it."""
    kind = type(interrupt)
    again: KeyboardInterrupt
    if kind is KeyboardInterrupt:
        again = Interrupted(*interrupt.args, summary=summary)
    elif kind is Terminated:
        again = RunTerminated(cast(Terminated, interrupt).signum, summary=summary)
    else:
        interrupt.summary = summary  # type: ignore[attr-defined]
        return interrupt
    return again.with_traceback(interrupt.__traceback__)


#: what a run's reason says a signal came during whose interrupt the run never took (its
#: handler ran in a finalizer, or a plugin swallowed it, on the tick the run ended on): ``...
#: during the run (the run had ended: success)``
THE_RUN = "the run"

#: what a second run() of one runner says
RUN_TWICE = (
    "this run has ended: a RunStack (a MissionRunner) runs once; build a new RunStack for "
    "the next run (the same tree and link may be given again)"
)


class InnerGate:
    """A gate put around another, ``inner`` (the monitor's, or a replay of the operator's
    acts; None: none): it is ``inner`` but for what a subclass adds (the stop below, a
    replay's ends in :mod:`~roomba_bt.runtime.stack`)."""

    def __init__(self, inner: TickGate | None) -> None:
        self.inner = inner

    def before_tick(self, runner: MissionRunner) -> bool:
        return self.inner.before_tick(runner) if self.inner is not None else True

    def after_tick(self, runner: MissionRunner) -> None:
        if self.inner is not None:
            self.inner.after_tick(runner)

    def holds(self, runner: MissionRunner) -> bool:
        return self.inner is not None and self.inner.holds(runner)

    def between_frames(self, runner: MissionRunner) -> None:
        between_frames(self.inner, runner)


def between_frames(gate: TickGate | None, runner: MissionRunner) -> None:
    """A read brought no frame (a stall the watchdog rides through, up to ``--grace``): the
    gate's ``between_frames``, where it has one, may end the run now (raise
    :class:`StopRequested`, ``at="after"``): the program's :meth:`MissionRunner.request_stop`,
    and the monitor's Stop, which waited for the next frame, the robot's stop with it. Not a
    part of :class:`TickGate`: a gate that has nothing to do between frames needs none."""
    waiting = getattr(gate, "between_frames", None)
    if waiting is not None:
        waiting(runner)


def stop_between_frames(runner: MissionRunner) -> None:
    """:func:`between_frames` for the run's loop: a stop it raises notes the bytes written
    by then, the stall's drive 0 among them, for the record's end note, where a replay ends
    once it has written as much (``stack.RecordedEnd.between_frames``). Out of
    :class:`MissionRunner` for its size."""
    try:
        between_frames(runner.gate, runner)
    except StopRequested:
        note_written(runner)
        raise


def note_written(runner: MissionRunner) -> None:
    """The bytes gone over the link when the run was ended from outside (a stop between
    frames, a Ctrl-C or SIGTERM), for the record's end note: the count the run's record
    keeps of its "out" side (``RecordingTransport.out_bytes``), whoever wrote them; None
    without a record. It was the link's count, translated at the end by what the link
    wrote since, which missed the bytes written past the link (``discovery.probe``'s Query
    List after a stop not confirmed): on a robot's port the note said more than was
    written, and the replay, waiting for it, called a faithful record different (exit 1).
    Read off the transport, not kept on the runner: its instance stays within CPython's
    shared attribute table (the note at the end of ``MissionRunner.__init__``)."""
    counted = getattr(runner.connection.transport, "out_bytes", None)
    runner.summary.written_when_interrupted = counted if type(counted) is int else None


class _StopGate(InnerGate):
    """What :meth:`MissionRunner.request_stop` puts before the run's gate: the next frame
    ends the run with :class:`StopRequested` (the monitor's stop, from any thread). A gate,
    so that the tick path reads nothing more than it did."""

    def __init__(self, reason: str, inner: TickGate | None) -> None:
        super().__init__(inner)
        self.reason = reason

    def before_tick(self, runner: MissionRunner) -> bool:
        raise StopRequested(self.reason)

    def between_frames(self, runner: MissionRunner) -> None:
        raise StopRequested(self.reason, at="after")  # no frame: the stop goes on anyway


class MissionRunner(BaseHandle):
    """Runs one compiled mission on one connection; is the behaviours' ``RobotHandle``."""

    def __init__(
        self,
        connection: Connection,
        mission: MissionLike,
        *,
        profile: RobotProfile,
        packets: Sequence[int],
        timeout_s: float | None = None,
        observer: TickObserver | None = None,
        poll_timeout: float = 0.05,
        input_ended: Callable[[], str | None] | None = None,
        gate: TickGate | None = None,
        grace: float = DEFAULT_GRACE,
        hold_interrupts: bool = False,
        tick_guard: TickGuardLike | None = None,
    ) -> None:
        super().__init__(profile)
        self.connection = connection
        self.summary = RunSummary(mission.name, profile=profile_shown(profile))
        self.mission = mission
        self.packets = tuple(packets)
        self.timeout_s = timeout_s
        self.observer = observer
        self.poll_timeout = poll_timeout
        self.input_ended = input_ended
        self.gate = gate
        #: True while the monitor holds the run paused: frames still come and make snapshots
        #: (the page shows the robot) and the tick index (the stream's) goes on, but mission
        #: time stands still: a wait, a time limit or the run's timeout does not count the pause
        self.clock_held = False
        #: the watchdog's trips, ridden through for ``grace`` seconds (0: a trip ends the run;
        #: said apart while the monitor holds the run paused), and the tick guard's drive 0
        clock, held = partial(mission_time_after, self), partial(getattr, self, "clock_held")
        self._ride = StallRide(connection, self._outbox, self.summary, grace, clock, held)
        #: the stream's slots added up: the tick index, the slots the monitor held
        self._clock = StreamClock(self._ride, self.summary, connection)
        self._odometer = Odometer(profile.wheel_base_mm)
        #: the run's end: its tree stopped, the wheels first (also the monitor's reload)
        self._ending = RunEnding(connection, self._outbox, self.summary, clock, self._odometer)
        #: Ctrl-C and SIGTERM stay ignored after :meth:`run` returns, until
        #: :meth:`release_interrupts` (the CLI: its summary is still to be printed); else the
        #: previous handlers come back when it returns
        self.hold_interrupts = hold_interrupts
        if tick_guard is not None:  # set only when given: see the class attribute
            self.tick_guard = tick_guard
        self._guard: InterruptGuard | None = None
        self.snapshot = NO_SNAPSHOT_YET
        self.refusals = Refusals(self.summary)
        #: this run's part of py_trees' blackboard, claimed when it starts (None before):
        #: ``runner.blackboard.values()``, its mission's keys; ``.read("leg")``, one of them
        self.blackboard: RunBoard | None = None
        #: hazards shown to the tree once two frames agree, or the robot's own reaction does
        self._hazards = HazardConfirmation()
        self._fallback_seen: object = None
        #: the connection's mode model and link, read on every tick (one hop, not a chain of
        #: properties)
        self._modes = connection.modes
        self._link = connection.link
        # No more attributes than these 28 (a subclass may add its own): CPython 3.11 keeps
        # an instance's attributes in a compact table shared by its class only up to 30
        # names; past that the instance gets a dictionary of its own, and then no method call
        # on it (``self._advance(...)``, ``self._flush()`` every tick) is specialised.

    # ---------------------------------------------------------------- RobotHandle
    #: this tick's snapshot: an attribute set by each tick (the leaves read it several times
    #: a tick; a property was a call each time); before the first frame,
    #: :data:`NO_SNAPSHOT_YET`, whose every use says that there is none yet
    snapshot: Snapshot

    #: what stops the wheels when a tick runs too long (:mod:`roomba_bt.runtime.tick_guard`;
    #: None: no guard, as on the virtual clock). A class attribute the instance sets only
    #: when given, so the evaluation's runners keep one attribute fewer (see the note at the
    #: end of ``__init__``)
    tick_guard: TickGuardLike | None = None
    #: Ctrl-Z and Ctrl-\ end the run with its safe stop (a suspended run cannot stop its
    #: robot; one quit at once leaves it driving); an evaluation and ``run --fast`` set it
    #: False: on the virtual clock nothing drives meanwhile, and both keep their usual
    #: meaning. A class attribute for the same reason as ``tick_guard``
    on_wall_clock: bool = True
    #: False: the run installs no signal handler (an evaluation's pool worker: Ctrl-C is
    #: its parent's, which ends the workers)
    guards_signals: bool = True
    names_slow_ticks: bool = False  #: the slowest tick's behaviour named (runtime/tick_watch.py)
    tree_as_left: TreeStatuses | None = None  #: the tree as the run left it (tree_left)
    #: wall-clock seconds after which the run ends as an ERROR saying where it was stuck
    #: (``run --wall-limit``: runtime/wall_limit.py); None: none. Set as ``tick_guard`` is
    wall_limit_s: float | None = None
    #: py_trees visitors run on every tick (``RunStack(visitors=...)``; :func:`visiting_tick`);
    #: none: the tree is ticked directly (:func:`tick_of`), its tick's cost unchanged
    visitors: tuple[VisitorLike, ...] = ()
    #: the writer's count of commands when the start-up was done (see :meth:`count_written`)
    _sent_at_start: int | None = None

    @property
    def last_sent(self) -> Mapping[str, Command]:
        """The last command written on each channel ("wheels", "motors", ...) that still
        stands: what a stall's ride-through and a resume after the monitor's pause send
        again. The outbox keeps it (:attr:`Outbox.standing
        <roomba_bt.robot.interface.Outbox.standing>`, beside what the tree asked for)."""
        return self._outbox.standing

    @property
    def ride(self) -> StallRide:
        """The run's ride through a watchdog trip or a tick guard's halt."""
        return self._ride

    @property
    def has_snapshot(self) -> bool:
        return self.snapshot is not NO_SNAPSHOT_YET

    # ---------------------------------------------------------------- running
    def run(self, *, raise_interrupts: bool = True) -> RunSummary:
        """The mission to its end; on every ending the tree stopped and the safe stop sent.
        A Ctrl-C or SIGTERM is then raised again, the summary as its ``summary`` (a program's
        next mission must not drive after its operator's Ctrl-C), unless ``raise_interrupts``
        is False: the CLI and the evaluation read Outcome.INTERRUPTED (exit 130). One that
        came during the tree's stop, the safe stop or a ``shutdown()`` is raised too, once they are
        done (:func:`~roomba_bt.runtime.teardown.note_late_interrupt` says it).

        One run per runner (decided): a second raises RuntimeError (its summary, counters
        and clock would have added up the two)."""
        if self._guard is not None:
            raise RuntimeError(RUN_TWICE)
        summary = self.summary
        wall_start = time.perf_counter()
        root = self.mission.root
        guard = self._guard = InterruptGuard(
            hold=self.hold_interrupts,
            wall_clock=self.on_wall_clock,
            enabled=self.guards_signals,
            raises=raise_interrupts,
        )
        tick_guard = self.tick_guard
        interrupt: KeyboardInterrupt | None = None
        raised_in: py_trees.behaviour.Behaviour | None = None  # its terminate raised: said
        limit = self.wall_limit = WallLimit(self.wall_limit_s)  # the monitor's pause holds it
        # this thread's while it runs: its keys are no other run's in the process
        board = self.blackboard = claim_board()
        with guard, running_on(board):
            try:
                with limit:
                    self.connection.start(OIMode.PASSIVE, self.packets)
                    self._sent_at_start = self.connection.writer.sent
                    setup_tree(self.mission.root, lambda: self.mission.setup(self))
                    check_alone(board, root)  # a py_trees client's keys: the process's
                    virtual = not getattr(self.connection.transport, "wall_clock", True)
                    summary.virtual_clock = virtual or not self.on_wall_clock
                    if summary.virtual_clock:  # py_trees' Timeout would never fire
                        warn_of_wall_clock_timeouts(root)
                    if tick_guard is not None:
                        tick_guard.start()
                    with slowest_tick_named(summary, self.names_slow_ticks):
                        self._loop(root, summary)
            except RunAborted as exc:
                if not limit.reached:  # raised into the run from outside: on, after the stop
                    raise
                summary.outcome, summary.reason = Outcome.HUNG, limit.said(exc)
            except BaseException as exc:  # Ctrl-C; a stop, a lost link, a bug, sys.exit()
                interrupt, raised_in = run_ended_by(exc, self)
            finally:
                if tick_guard is not None:
                    tick_guard.close()  # it writes nothing more: the safe stop is ours
                guard.stopping()  # a further Ctrl-C or SIGTERM waits for the safe stop
                self._finish(summary, wall_start, raised_in)
        interrupt = ending_interrupt(interrupt, guard, summary)  # a late one: not lost
        if interrupt is not None and raise_interrupts:  # the robot is stopped: now the caller
            raise interrupted(interrupt, summary) from None
        return summary

    def request_stop(self, reason: str = "stopped by the program") -> None:
        """End the run as the monitor's stop does: at the next frame (or empty read) the tree
        is stopped, the safe stop sent and the nodes shut down; the outcome is INTERRUPTED,
        ``reason`` its reason, and nothing is raised. Safe from any thread: the way to stop
        a run in a worker thread, which signals never reach (``docs/runtime.md``)."""
        self.gate = _StopGate(reason, self.gate)

    def release_interrupts(self) -> None:
        """Ctrl-C and SIGTERM as they were before :meth:`run` (after a held run's summary)."""
        if self._guard is not None:
            self._guard.release()

    def retire_tree(self, mission: str) -> None:
        """The monitor's reload to ``mission`` (its name): the tree stopped and shut down, each
        bounded as at the run's end (``RunEnding.retire_tree``; ``RetireHung`` past it)."""
        self._ending.retire_tree(self.mission.root, mission, tree_stop_limit(self.wall_limit_s))

    def _finish(
        self, summary: RunSummary, wall_start: float, raised_in: py_trees.behaviour.Behaviour | None
    ) -> None:
        run_over(self)  # where it ended, for the record's end note; the stalls not yet said
        guard, limit = cast(InterruptGuard, self._guard), tree_stop_limit(self.wall_limit_s)
        self.tree_as_left = tree_left(self, summary.exception)  # before the stop: INVALID
        first = self._ending.end_tree(self.mission.root, self.tick_guard, guard, raised_in, limit)
        self.count_written()  # the safe stop's are said apart
        set_up = self._sent_at_start is not None  # what its setup() opened, closed
        last = self.snapshot if self.has_snapshot else None
        self._ending.safe_stop(guard, first, self.mission.root if set_up else None, last)
        self._ending.sum_up(time.perf_counter() - wall_start, last, self._hazards.unconfirmed)

    # Long on purpose: every frame's path, written out in one loop (a call less a frame),
    # and the try around it that places a Ctrl-C in its frame (interrupted_at)
    def _loop(self, root: py_trees.behaviour.Behaviour, summary: RunSummary) -> None:
        success, failure = py_trees.common.Status.SUCCESS, py_trees.common.Status.FAILURE
        perf = time.perf_counter
        ride = self._ride
        tick = guarded_tick(self, root)
        poll, poll_timeout = self.connection.poll_frames, self.poll_timeout
        clock = self._clock
        writer = self.connection.writer
        held = False  # the root ended and the gate holds the run there (the monitor)
        untick: int | None = None  # the gate held the tree: the tick it last ticked on
        flushed = -1  # the stream tick of the last tree tick written whole
        motion = MotionWatch(self.connection, summary)  # the wheels doing what they were told
        checks = MissionTimeChecks(summary, self.timeout_s, self._ending.cycles, motion)
        kept = cast(InterruptGuard, self._guard).kept  # a signal's, dropped: raised again
        started = perf()  # each tick's start (an interrupt's before the first: none cut short)
        try:
            while True:
                try:
                    batch = poll(poll_timeout)
                except StreamStalled as stalled:
                    batch = ride.tripped(stalled)
                if ride.stall is not None:
                    ride.carry_on(batch)
                if kept:  # before the tick, or with no frame: the tree ticks no more after it
                    raise kept[0].with_traceback(None)
                if not batch:
                    if writer.silenced_by is not None:  # sent past the tick (a thread's)
                        return silenced(root, summary, writer.silenced_by)
                    if self.gate is not None:  # a stop asked for acts without a frame
                        stop_between_frames(self)
                    if self.input_ended is not None and (why := self.input_ended()):
                        summary.outcome, summary.reason = Outcome.INPUT_ENDED, why
                        return
                    continue
                started = perf()
                mission_time, untick = self._advance(batch, untick), None
                gate = self.gate
                if gate is not None:
                    if not gate.before_tick(self):  # a pause's frame, a step's, one a mode
                        untick = self.snapshot.previous_tick  # change made stale: no gap
                        continue
                    if self.mission.root is not root:  # a reload replaced it
                        root = self.mission.root
                        tick = guarded_tick(self, root)
                    elif held:  # the operator let the ended mission go: the run ends
                        tree_ended(root, summary)
                        return
                    held = False
                tick()
                self._flush()
                flushed = clock.tick
                if writer.silenced_by is not None:  # Reset or Stop: no frame will come
                    return silenced(root, summary, writer.silenced_by)
                elapsed = perf() - started
                summary.ticks += 1
                if elapsed > SLOT_SECONDS:
                    summary.overruns += 1
                if elapsed > summary.max_tick_s:
                    summary.max_tick_s = elapsed
                if self.observer is not None:
                    self.observer(self)
                if gate is not None:
                    gate.after_tick(self)
                status = root.status
                if status is success or status is failure:
                    if gate is not None and gate.holds(self):
                        held = True
                        continue
                    tree_ended(root, summary)
                    return
                if mission_time >= checks.next_at and not checks.look(self.snapshot, root):
                    return  # the time limit, the robot's own cycle, or no obeying (long_run.py)
        except (KeyboardInterrupt, RunAborted) as exc:  # Ctrl-C, SIGTERM, --wall-limit...:
            if not behaviours_interrupt(exc):  # in which half of its frame (a behaviour's own
                summary.ended_at = interrupted_at(self, flushed)  # interrupt: its error)
                note_written(self)  # a flush cut short ("before"), a stall's drive 0 ("after")
                if summary.ended_at is not None and summary.ended_at[1] == "before":
                    summary.cut_short = cut_short(exc, perf() - started)
            raise

    def _advance(self, batch: Sequence[SensorFrame], untick: int | None = None) -> float:
        """Newest frame of the batch -> the tick's snapshot; stale frames and gaps counted.
        The frames of a batch came in one read, at the link's ``arrival``. Returns the
        snapshot's mission time, for the loop's timeout (a named tuple's field read is a
        generic attribute read in CPython 3.11, about 170 instructions). ``untick``: the
        tick the tree last ticked on, when the gate held it since (else the frame before).
        The common frame (the only one of its batch, one slot after the one before) takes
        the first branch of each test: no stale frame to confirm hazards with, no fall to
        Passive new since the last, no slot lost (the schedule's slow path)."""
        count = len(batch)
        if count > 1:
            self._stale(batch)
        frame = batch[-1]
        arrival = self._link.arrival
        modes = self._modes
        # SlotSchedule.slots' common case, inline: one frame, early or less than LOST_LATE
        # late: one slot; the schedule follows it (up to DRIFT), its lateness kept (spread)
        clock = self._clock
        schedule = clock.schedule
        due = schedule.due + SLOT_SECONDS
        late = arrival - due
        if count == 1 and late < LOST_LATE:
            schedule.due = arrival if late < DRIFT else due + DRIFT
            spread = schedule.spread
            schedule.spread = late if late > spread else spread - SPREAD_DECAY
            slots = 1
        else:
            slots = clock.slots_spanned(count, arrival)
        tick = clock.tick = clock.tick + slots
        if self.clock_held:
            clock.held_slots += slots
        mission_time = (tick - clock.held_slots) * SLOT_SECONDS
        fallback = modes.last_fallback  # after the clock: a fall is placed in mission time
        if fallback is self._fallback_seen:
            frame = self._hazards.frame(frame)
        else:
            frame, fallback = self._fallback_changed(frame, fallback, mission_time)
        # tuple.__new__: the named tuple's own __new__ is a Python call that binds each
        # field (with keywords, several times the cost of the rest of this method)
        snapshot: Snapshot = _new_tuple(Snapshot, (
            frame,
            tick,
            mission_time,
            modes.mode,
            self._odometer.frame(frame),
            fallback,
            self._profile,
            self.summary.frames_lost,
            self.connection.writer.builtin_may_run,
            tick - slots if untick is None else untick,
        ))  # fmt: skip
        self.snapshot = snapshot
        if (board := self.blackboard) is not None:
            if _Blackboard.activity_stream is None:
                # the client's own key, registered for writing: its permission checks and
                # name parsing cost more than the rest of this method
                _STORAGE[board.snapshot_key] = snapshot
            else:  # someone is watching the blackboard's activity: tell it
                board.write_snapshot(snapshot)
        return mission_time

    def _fallback_changed(
        self, frame: SensorFrame, fallback: ModeChange | None, mission_time: float
    ) -> tuple[SensorFrame, ModeChange | None]:
        """A fall to Passive by itself new since the last frame (or its end), placed in mission
        time (:func:`placed`): the hazards see the frame afresh, the commands of
        :data:`FALL_STOPS` no longer stand (a stall's ride-through and the monitor's resume do
        not send them again), the first fall is noted for ``--strict`` (:func:`noted_fall`)."""
        self._fallback_seen = fallback = placed(self._modes, fallback, mission_time)
        if fallback is not None:
            self._outbox.robot_stopped(FALL_STOPS)
        frame = self._hazards.frame(frame, True)
        noted_fall(self.summary, fallback, mission_time, self.mission.root)
        return frame, fallback

    def _stale(self, batch: Sequence[SensorFrame]) -> None:
        """The frames of a batch before its newest: dropped (counted), their hazards seen."""
        confirm = self._hazards.frame
        for older in batch[:-1]:
            confirm(older)
        self.summary.stale_frames_dropped += len(batch) - 1

    def _flush(self) -> None:
        if self._hazards.pending or self.connection.writer.forward_held:
            self._bump_reflex()
        if not self._outbox.queued:
            return
        outbox = self._outbox
        for command in outbox.drain():
            try:
                self.connection.send(command)
                outbox.written(command)
            except ModeError as exc:  # counted, said with when and who sent it
                when = self.snapshot.time if self.has_snapshot else None
                sender = outbox.sender_of(command)
                self.refusals.note(command, exc, sender, when, self._link.arrival)

    def count_written(self) -> int:
        """``summary.commands_written`` brought up to date (at the end, by the monitor's feed):
        every command since the start-up, the bump reflex's and watchdog's drive 0 too."""
        start = self._sent_at_start
        written = 0 if start is None else self.connection.writer.sent - start
        self.summary.commands_written = written
        return written

    def _bump_reflex(self) -> None:
        """While a bump onset waits for its confirming frame, forward motion is held at 0
        (robot/hazards.py); confirmed or cleared, the forward command held goes out again
        unless this tick queued another wheel command (the tree's reaction)."""
        connection = self.connection
        if self._hazards.bump_pending:
            connection.hold_forward()
        elif connection.forward_held:
            held = connection.release_forward()
            if held is not None and all(c.spec.channel != "wheels" for c in self._outbox):
                self._outbox.send(held, self)


def guarded_between_ticks(
    runner: MissionRunner, work: Callable[[], object], where: str
) -> Callable[[], object]:
    """``work``, done between two ticks in the ticking thread, watched as a tick is by the
    run's tick guard (none: ``work`` itself): past the limit with the wheels moving, drive
    0, said as a tick's halt is, ``where``, the wheels' last command sent again once it
    returns; counted as the loop's own, not the tree's ticks' (the summary's ``loop_slow``,
    ``loop_halts``). ``RunStack.ticks()`` has the program's loop body watched so: the robot
    drives on while it runs, as while a behaviour blocks."""
    tick_guard = runner.tick_guard
    if tick_guard is None:
        return work
    ride = runner.ride

    def slow(seconds: float, _where: str, halted: bool, cycle: str) -> None:
        if halted:
            ride.tick_halted(tick_guard, seconds, where, loop=True)
        else:
            ride.tick_still(seconds, where, cycle, loop=True)

    return tick_guard.guarded(work, slow, lambda: runner.snapshot.tick, where)


def tree_ended(root: py_trees.behaviour.Behaviour, summary: RunSummary) -> None:
    """The run's outcome by its tree's: SUCCESS, or FAILURE and why."""
    if root.status is py_trees.common.Status.SUCCESS:
        summary.outcome = Outcome.SUCCESS
    else:
        summary.outcome = Outcome.FAILURE
        summary.reason = failure_reason(root)


def silenced(root: py_trees.behaviour.Behaviour, summary: RunSummary, command: Command) -> None:
    """The tree sent Reset (7) or Stop (173): the run ends at once, as its own ending. The OI
    is off and streams no more frames, and the frames are the run's clock: its ticks, its
    ``--timeout``, every timeout in the tree; the watchdog is off too, since silence is what
    Stop asks for. Waiting for the tree to go on would wait for ever (a Start after it brings
    Passive back, but not the stream, and a Reset reboots the robot). Decided: end here, not
    ask for the stream again: the spec's word for Stop is "when you are finished working with
    the robot", and a tree that went on would have had its clock stop at the Stop whatever
    came after. A tree that ended on that tick (the leaf last, as the validator asks) has its
    outcome; one still running FAILED, and why says so. The safe stop sends nothing from Off:
    the robot stopped its wheels and motors there (or Start, should the tree have sent one
    after it in the same tick)."""
    spec = command.spec
    status = root.status
    if status is py_trees.common.Status.SUCCESS or status is py_trees.common.Status.FAILURE:
        tree_ended(root, summary)
        return
    summary.outcome = Outcome.FAILURE
    summary.reason = (
        f"the tree sent {spec.title} ({spec.opcode}) while it still ran{running_in(root)}: the OI "
        "is off and streams no more sensor frames, the run's clock, so the run ended there (a "
        "leaf that sends Reset or Stop must be the last the tree runs)"
    )


def placed(modes: ModeModel, change: ModeChange | None, mission_time: float) -> ModeChange | None:
    """``change``, the mode model's last fall, with the mission time of the tick that first
    showed it (:attr:`ModeChange.mission_time`, which the leaves' messages say: "in Passive
    since t=0.960"); the model keeps the placed change, so the next frame finds it seen. None,
    a change already placed, or one no longer the model's last, is returned as it is."""
    if change is None or change.mission_time is not None or modes.last_fallback is not change:
        return change
    modes.last_fallback = change = replace(change, mission_time=mission_time)
    return change


def noted_fall(
    summary: RunSummary,
    change: ModeChange | None,
    mission_time: float,
    root: py_trees.behaviour.Behaviour,
) -> None:
    """The robot's first fall out of Safe/Full by itself onto a hazard (a cliff, a wheel
    drop; a charger's is a dock run's end: :data:`EXPECTED_FALLS`), placed for ``--strict``:
    when, why, and the leaf that was driving (the tree has not ticked on this frame yet)."""
    if summary.first_fall or change is None or not change.fall or change.cause in EXPECTED_FALLS:
        return
    summary.first_fall = f"t={mission_time:.3f}{running_in(root)}: {change.cause}"


def ending_interrupt(
    interrupt: KeyboardInterrupt | None, guard: InterruptGuard, summary: RunSummary
) -> KeyboardInterrupt | None:
    """The interrupt :meth:`MissionRunner.run` raises once the robot is stopped: the signal's
    that ended the run (``interrupt``), else one whose interrupt the run never took (Python
    dropped it, or a plugin swallowed it, on the tick the run ended on: ``during`` the run),
    else one that came during the stop (:attr:`InterruptGuard.late`), the run's reason then
    saying it (:func:`~roomba_bt.runtime.teardown.note_late_interrupt`). The guard's kept
    interrupt is taken in any case: the run is over."""
    kept = guard.take()
    if interrupt is not None:
        return interrupt
    if kept is not None:
        note_late_interrupt(summary, kept, THE_RUN)
        return kept
    late = guard.late_interrupt()
    if late is not None:
        note_late_interrupt(summary, late, guard.late_during)
    return late


def run_over(runner: MissionRunner) -> None:
    """The run's end, before anything is stopped: where it ended, for the record's end note
    (``RunSummary.ended_at``), and its ride's stalls not yet said (:meth:`StallRide.run_ended
    <roomba_bt.runtime.stall.StallRide.run_ended>`; one whose silence ended the run is its
    reason). A function, not a method: the class's size."""
    summary = runner.summary
    summary.ended_at = ended_at(runner, summary.ended_at)
    runner.ride.run_ended(summary.outcome in (Outcome.CONNECTION_LOST, Outcome.NO_CONNECTION))


def run_ended_by(
    exc: BaseException, runner: MissionRunner
) -> tuple[KeyboardInterrupt | None, py_trees.behaviour.Behaviour | None]:
    """The run's outcome and reason when ``exc`` ended it (:meth:`MissionRunner.run`): an
    interrupt (Ctrl-C, or :class:`Terminated`: SIGTERM, SIGHUP, ...), returned to be raised
    once the robot is stopped; else what :func:`ended_by` says, a behaviour's own ``raise
    KeyboardInterrupt`` too (:func:`behaviours_interrupt`), the node whose ``terminate``
    raised it returned (its ``terminate`` is not called again)."""
    summary = runner.summary
    if isinstance(exc, KeyboardInterrupt) and not behaviours_interrupt(exc):
        why = interrupt_reason(exc)
        cut_in = summary.cut_short or (f"while {said}" if (said := interrupted_in(exc)) else "")
        cut = f" {cut_in}" if cut_in else ""  # a tick (cut_short), or a plugin's setup()
        summary.outcome, summary.reason = Outcome.INTERRUPTED, why + cut
        return exc, None
    # answered: a frame came; wrote: a command since the start-up (a wrong profile's 2 or 8)
    ended_by(exc, summary, answered=runner.has_snapshot, wrote=runner.count_written() > 0)
    summary.ended_at = (-1, getattr(exc, "at", "after"))  # a stop's: before the tick
    return None, terminate_raised(exc)


#: what the reason of a run the link ended before its stream's first frame adds: the robot
#: answered the start-up, but with no frame the tree never ticked, so nothing of the mission
#: was sent and a retry is as safe as after a robot that never answered (exit 3, ``NO
#: CONNECTION``; decided: a service's ``RestartPreventExitStatus=8`` kept a run whose stream
#: request a noisy cable lost from being tried again, though nothing had moved)
NOT_STARTED = (
    "the mission did not start: no sensor frame came after the robot answered the start-up, "
    "so nothing of the mission was sent"
)


def ended_by(exc: BaseException, summary: RunSummary, *, answered: bool, wrote: bool) -> None:
    """The outcome and reason of a run that ``exc`` ended (Ctrl-C aside): the operator's
    stop, the link (its own errors, :class:`LinkDown` and :class:`ConnectionFailed`;
    ``answered``: the robot had streamed, so it was not merely never there; a bridge that
    closed before a byte, :class:`TurnedAway`, with none answered: not started; a link lost
    before the stream's first frame: not started either, :data:`NOT_STARTED`; frames of
    another model than the profile's before the run ``wrote`` a command since its start-up:
    a wrong setting, exit 2, nothing moved), or an
    exception in a behaviour, an ``OSError`` too, or its ``sys.exit()``, a
    ``KeyboardInterrupt`` it raised itself (no signal came), a ``BaseException`` of its own
    (its path, method and file:line, the traceback: not ours to exit, as at a plugin's
    import; they went on through the CLI, which exited 0, 130 or 1 with no summary), each
    after the safe stop."""
    if isinstance(exc, StopRequested):
        summary.outcome, summary.reason = Outcome.INTERRUPTED, str(exc)
    elif isinstance(exc, RetireHung):  # the reload's old tree never stopped: as the end's
        summary.outcome, summary.reason = Outcome.HUNG, str(exc)
    elif isinstance(exc, ConnectionFailed) or (isinstance(exc, TurnedAway) and not answered):
        # a bridge that turned the run away before any robot answered: never started
        summary.outcome = Outcome.CONNECTION_LOST if answered else Outcome.NO_CONNECTION
        summary.reason, summary.link_error = str(exc), exc
    elif isinstance(exc, LinkDown):
        wrong = exc.mismatch is not None and not wrote  # before a command of the mission
        summary.reason, summary.headline, summary.link_error = str(exc), exc.headline, exc
        if wrong:
            summary.outcome = Outcome.WRONG_PROFILE
        elif not answered:  # no frame: no tick, nothing of the mission sent (decided: 3)
            summary.outcome = Outcome.NO_CONNECTION
            summary.reason += f"; {NOT_STARTED}"
        else:
            summary.outcome = Outcome.CONNECTION_LOST
    else:  # a bug in a behaviour must still end in a safe stop. An OSError is one too: the
        # link turns its own I/O errors into LinkDown (PortLost) and ConnectionFailed where
        # it reads and writes (robot/link.py), so a bare one came from a behaviour's code
        # (a plugin's log file, a socket of its own), not from the robot's port
        summary.outcome, summary.reason = Outcome.ERROR, behaviour_error(exc)
        summary.traceback = "".join(traceback.format_exception(exc))
        summary.exception = exc  # the program's own exception object: RunFailed's cause


def tree_left(runner: MissionRunner, exc: BaseException | None) -> TreeStatuses:
    """Each node's last status and message as the run left its tree, before the stop marks
    every node INVALID (``run``'s tree after the run: it showed every node ``[-]`` after a
    behaviour's exception, even a ``mode(safe)`` that had succeeded); ``exc``, the run's
    exception (``summary.exception``: a behaviour's error). When it came out of a behaviour
    in a tick (or the tree's set-up, after the first frame), that behaviour says what it
    raised, and the observer is called once more, so that the status log prints the lines
    of that tick (``pre -> SUCCESS``; the log stopped at the tick before) and the live tree
    shows it; an observer that raises then is logged, not let replace the behaviour's
    error. A class attribute set at the end, as ``tick_guard``: see ``__init__``'s note."""
    raiser = raised_in_tree(exc) if exc is not None and runner.has_snapshot else None
    if raiser is not None and runner.observer is not None:
        try:
            runner.observer(runner)
        except Exception:  # the behaviour's error is the run's; this one only logged
            log.debug("the observer raised after a behaviour's exception", exc_info=True)
    left = TreeStatuses()
    if raiser is None:
        left.take(runner.mission.root)
        return left
    what = type(exc).__name__
    if isinstance(exc, UnkeptDeclaration) and exc.refusal:  # it returned, and was refused
        what = f"{what} ({exc.refusal})"
    left.take(runner.mission.root, (raiser, what))
    return left


def guarded_tick(runner: MissionRunner, root: py_trees.behaviour.Behaviour) -> Callable[[], object]:
    """What ``runner``'s loop calls to tick ``root`` once: its tick (:func:`tick_of`; with
    the run's visitors, :func:`visiting_tick`), through the run's tick guard when it has
    one (started by :meth:`MissionRunner.run`): a tick it halts is ridden through
    (:meth:`StallRide.tick_halted <roomba_bt.runtime.stall.StallRide.tick_halted>`), the
    stream tick the tree ticks on kept for the guard's record."""
    visitors = runner.visitors
    tick = visiting_tick(root, visitors) if visitors else tick_of(root)
    tick_guard = runner.tick_guard
    if tick_guard is None:
        return tick
    ride = runner.ride

    def slow(seconds: float, where: str, halted: bool, cycle: str) -> None:
        if not halted:  # nothing sent: nothing to give back, only the gap to say
            ride.tick_still(seconds, where, cycle)
            return
        # a tick that ended the tree gets nothing of it sent again: the run's end follows
        going = root.status is py_trees.common.Status.RUNNING
        ride.tick_halted(tick_guard, seconds, where, tree_running=going)

    return tick_guard.guarded(tick, slow, lambda: runner.snapshot.tick)


def visiting_tick(
    root: py_trees.behaviour.Behaviour, visitors: Sequence[VisitorLike]
) -> Callable[[], None]:
    """``root``'s tick with py_trees visitors, as ``py_trees.trees.BehaviourTree.tick`` runs
    them: each one's ``initialise()``; the tree ticked by its generator, ``root.tick()``,
    each node it yields (each node ticked, when its tick ends: the same nodes at the same
    moments as the lean nodes' direct tick, ``behaviours/lean.py``) visited by every visitor
    that is not ``full``; then every node of the tree by the ``full`` ones; each one's
    ``finalise()``. Which visitors are ``full`` is read once, when the run starts. A run
    without visitors ticks by :func:`tick_of` instead: nothing of this is on its path."""
    ticked = tuple(v for v in visitors if not getattr(v, "full", False))
    full = tuple(v for v in visitors if getattr(v, "full", False))

    def tick() -> None:
        for visitor in visitors:
            visitor.initialise()
        for node in root.tick():
            for visitor in ticked:
                node.visit(visitor)
        if full:
            for node in root.iterate():
                for visitor in full:
                    node.visit(visitor)
        for visitor in visitors:
            visitor.finalise()

    return tick


def tick_of(root: py_trees.behaviour.Behaviour) -> Callable[[], None]:
    """What ticks ``root`` once: its ``tick_once``, which for a lean node
    (:class:`~roomba_bt.behaviours.lean.Direct`) only calls ``tick_direct``: that method
    itself then, one call less on every tick. A class with a ``tick_once`` of its own keeps
    it."""
    if getattr(type(root), "tick_once", None) is _DIRECT_TICK_ONCE:
        return cast(Direct, root).tick_direct
    return root.tick_once


def warn_of_wall_clock_timeouts(root: py_trees.behaviour.Behaviour) -> list[str]:
    """On a clock that is not the wall clock (the simulator's :class:`SimLink`, ``--fast``,
    a replay, an evaluation), py_trees' own ``Timeout`` decorator still reads
    ``time.monotonic()``: 5 s of mission time pass in a hundredth of that, and it never
    fires. One warning at the start of the run names each such node and the decorator that
    counts mission time; returns their names. (Ours is
    :class:`roomba_bt.behaviours.decorators.Timeout`, no subclass of py_trees'.)"""
    names = [n.name for n in root.iterate() if isinstance(n, py_trees.decorators.Timeout)]
    if names:
        log.warning(
            "py_trees.decorators.Timeout %s reads the wall clock, and this run is on a "
            "virtual clock (the simulator's, a replay's): it would not fire at its mission "
            "time. Use roomba_bt.behaviours.decorators.Timeout (timeout: in a mission's "
            "YAML), which counts mission time",
            ", ".join(repr(name) for name in names),
        )
    return names
