"""The run stack, assembled in one place for ``run``, ``replay``, ``eval`` and the tests.

A run is the same five parts whatever the far end is::

    link (a Transport: serial port, simulator link, recorded bytes)
      └─ RecordingTransport        with --record: every chunk in and out, timed
          └─ Connection             parser, mode model and guard, watchdog, safe stop
              └─ MissionRunner      one tick per stream frame; the behaviours' RobotHandle
                  └─ observer       live tree, status-change log, or nothing

The link is given, not made here: this layer may not import the simulator (it sits below
the CLI and the evaluation, which choose between a robot's port and the simulator), and the
link's clock (wall or virtual) is the link's business. Everything above the link is the same
code on a robot, on the simulator and in a replay.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections import deque
from collections.abc import Callable, Generator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any, Literal

from py_trees.behaviour import Behaviour

from roomba_bt.behaviours.declare import Declaration
from roomba_bt.behaviours.lean import check_updates
from roomba_bt.mission.build import blackboard_within, set_up_tree
from roomba_bt.oi.profiles import PROFILES, RobotProfile, profile_given
from roomba_bt.robot import wording
from roomba_bt.robot.connection import Connection, EndMode
from roomba_bt.robot.errors import DEFAULT_WATCHDOG, ConnectionClosed
from roomba_bt.robot.stall_asks import STREAM_AGAIN_NOTE
from roomba_bt.runtime.claimed import ClaimedFile
from roomba_bt.runtime.clock import mission_time_after
from roomba_bt.runtime.display import stamped_logs
from roomba_bt.runtime.given import check_arguments, check_given
from roomba_bt.runtime.long_run import say_waits_past_sleep
from roomba_bt.runtime.loop import (
    InnerGate,
    MissionLike,
    MissionRunner,
    StopRequested,
    TickGate,
    TickObserver,
    VisitorLike,
    stream_request,
)
from roomba_bt.runtime.recording import (
    END_IN,
    ENDED_FROM_OUTSIDE,
    MADE_BY,
    MISSION_AT,
    PLUGINS,
    RELATIVE_TO,
    RELATIVE_TO_RECORD,
    RUN_OPTIONS,
    SIMULATOR,
    SOURCES,
    WRITTEN,
    Record,
    RecordingTransport,
    ReplayTransport,
    end_note,
    ending_text,
    recorded_end_in,
    tree_ended,
)
from roomba_bt.runtime.stepping import Tick, TickStepper, replayed_loop, ticks
from roomba_bt.runtime.summary import DEFAULT_GRACE, DEFAULT_TICK_LIMIT, Outcome, RunSummary
from roomba_bt.runtime.tick_guard import (
    RecordedTickGuard,
    TickGuard,
    TickGuardLike,
    recorded_tick_guard,
    tree_notes_of,
)
from roomba_bt.transport.base import Transport
from roomba_bt.transport.serial_port import DEFAULT_BAUD

log = logging.getLogger(__name__)

#: ``RunStack(tick_limit=...)``'s default: the CLI's (``run --tick-limit``)
TickLimit = float | None | Literal["default"]

#: Seconds :meth:`RunStack.close` from another thread waits for the run it stopped to end
#: (its safe stop written) before it closes the connection anyway, a stop of its own first.
CLOSE_WAIT_S = 5.0


@dataclass
class TreeMission:
    """A tree built in Python, as a run takes it (a
    :class:`~roomba_bt.runtime.loop.MissionLike`, as a compiled mission is): ``root`` may mix
    plain py_trees behaviours with roomba-bt's leaves and decorators.

    ``packets`` are what its roomba-bt leaves declare they read (``@declare(reads=...)``,
    with their parameters), worked out when asked, so a tree changed after this was made
    is read as it is then; :func:`~roomba_bt.runtime.loop.stream_request` adds what the
    runtime needs. ``setup(robot)`` hands the robot to every node, as py_trees' idiom has
    it: a plain behaviour finds it in ``setup(robot=...)`` too (``robot.snapshot``)."""

    root: Behaviour
    name: str = "tree"

    @property
    def packets(self) -> tuple[int, ...]:
        read: set[int] = set()
        for node in self.root.iterate():
            declaration = getattr(node, "declaration", None)
            if isinstance(declaration, Declaration):
                read.update(declaration.packets(getattr(node, "params", {})))
        return tuple(sorted(read))

    def setup(self, robot: Any, **kwargs: Any) -> None:
        """Every node's ``setup(robot=...)``; and a plain behaviour whose ``update`` returns
        no Status (a forgotten ``return``) ends the run as an error, exit 4, as a roomba-bt
        leaf's does (:func:`~roomba_bt.behaviours.lean.check_updates`). A compiled mission's
        root in the tree brings its blackboard: its keys' types and ``initial:`` values are
        written first, as its own ``setup`` writes them (:func:`blackboard_within`)."""
        check_updates(self.root)
        set_up_tree(self.root, blackboard_within(self.root), robot, **kwargs)


@dataclass(frozen=True)
class Recording:
    """Where ``--record`` writes, and what its header says the run was."""

    path: str | Path
    #: the mission file, as ``replay`` will look for it
    mission: str
    #: the ``-p`` values as given (text), replayed with the same mission
    parameters: Mapping[str, str] = field(default_factory=dict)
    #: which robot: the port as given, or ``simulator WORLD``; and when the run started
    #: (ISO 8601, UTC): a record copied off the laptop names its robot and its lesson.
    #: Neither is read by a replay; a header without them (a record made before) loads.
    port: str | None = None
    started: str | None = None
    #: the run's label (``run --label``), None: none given (the header leaves it out)
    label: str | None = None
    #: the SHA-256 of each file the mission was compiled from, the mission file first
    #: (:func:`~roomba_bt.runtime.provenance.source_digests`): a replay that differs names
    #: the ones changed since. Empty: none written (a tree built in Python has no files)
    sources: Mapping[str, str] = field(default_factory=dict)
    #: each installed plugin distribution whose behaviours the tree holds, its version and
    #: its modules' digest (:func:`~roomba_bt.runtime.provenance.plugin_digests`); a replay
    #: that differs names the ones changed since. None: not written (a record that cannot
    #: tell "no plugin" from "not looked at" says nothing of them); {}: none was used
    plugins: Mapping[str, Mapping[str, str]] | None = None
    #: the mission's absolute path, for the reader, when ``mission`` is relative to the
    #: record's folder (None: left out, as ``run --reproducible`` does)
    mission_path: str | None = None
    #: the simulator's options as given (``world``, ``seed``, ...: ``recording.SIMULATOR``)
    #: and the run's (``timeout``, ``include_dirs``, ...: ``recording.RUN_OPTIONS``), what
    #: runs the mission again as recorded; None: not written (a robot's port has no simulator)
    simulator: Mapping[str, Any] | None = None
    options: Mapping[str, Any] | None = None
    #: whether the relative paths of the header (``mission``, ``sources``' names, ...) are
    #: relative to the record's folder, as ``run`` writes them (``recording.RELATIVE_TO``);
    #: False: a program's, as it gave them
    paths_from_record: bool = False
    #: ``path`` claimed already for this run (``run`` does, before it opens the robot, so a
    #: path another run writes is refused first); None: the record claims it when made
    claimed: ClaimedFile | None = field(default=None, compare=False)
    #: the file's size limit in bytes (``run --record-max``): the recording stops there, as
    #: on a full disk, and the run goes on; None: none
    max_bytes: int | None = None
    #: the run may not go on without its record (``run --require-record``): a header that
    #: cannot be written (a full disk) raises ``recording.RecordNotStarted``, nothing sent
    required: bool = False

    def header(
        self, profile: RobotProfile, baud: int, packets: Sequence[int], watchdog: float,
        grace: float, end_in: EndMode = "passive",
    ) -> dict[str, Any]:  # fmt: skip
        """The record's header: what ``replay`` runs it again with (``watchdog`` and
        ``grace``: the run's, for the replay's watchdog and ride-through; ``end_in``: how its
        stop ends, :data:`~roomba_bt.runtime.recording.END_IN`, written for Stop alone)."""
        return {
            "profile": profile.name,
            "baud": baud,
            "mission": self.mission,
            **({RELATIVE_TO: RELATIVE_TO_RECORD} if self.paths_from_record else {}),
            **({MISSION_AT: self.mission_path} if self.mission_path is not None else {}),
            "parameters": dict(self.parameters),
            "packets": list(packets),
            "watchdog": watchdog,
            "grace": grace,
            **({END_IN: "stop"} if end_in == "stop" and profile.has_command("stop") else {}),
            **({"port": self.port} if self.port is not None else {}),
            **({"started": self.started} if self.started is not None else {}),
            **({"label": self.label} if self.label is not None else {}),
            **({SOURCES: dict(self.sources)} if self.sources else {}),
            **({} if self.plugins is None else {PLUGINS: _plain(self.plugins)}),
            **({SIMULATOR: dict(self.simulator)} if self.simulator is not None else {}),
            **({RUN_OPTIONS: dict(self.options)} if self.options is not None else {}),
        }


def _plain(plugins: Mapping[str, Mapping[str, str]]) -> dict[str, dict[str, str]]:
    """``plugins`` as plain dicts, as JSON writes them."""
    return {name: dict(provenance) for name, provenance in plugins.items()}


class RunStack:
    """One mission on one link: the connection, the runner and, if asked, the record.

    ``packets`` defaults to :func:`~roomba_bt.runtime.loop.stream_request` at ``baud`` (a
    replay passes the recorded ones). Building it writes nothing to the link (a record's
    header aside); :meth:`run` does the start-up, the ticks and the safe stop.

    ``link`` is a :class:`~roomba_bt.transport.Transport` (the stack makes its connection:
    ``profile=`` needed, ``watchdog``, ``end_in``, ``baud``, ``keep_awake`` its settings), or
    a :class:`~roomba_bt.robot.connection.Connection` a program opened and drove by hand:
    the run takes it over as it was made (its profile, watchdog, ending, baud, keep-awake:
    giving them here too is a ValueError), starts it again (:meth:`Connection.start`: Start,
    the mode asked, the mission's stream) and leaves it stopped, in Passive, and open, even
    through :meth:`close` (a ``with`` block's end): who opens closes, the program drives on
    and closes it itself (``docs/runtime.md``, From Python: a connection driven by hand,
    then a mission). A closed one is refused (:class:`ConnectionClosed`).

    ``tick_limit``: seconds a tick may run while the wheels move before the tick guard sends
    drive 0 (``runtime/tick_guard.py``). ``"default"``, as ``roomba-bt run`` has it:
    :data:`~roomba_bt.runtime.summary.DEFAULT_TICK_LIMIT` on a link on the wall clock (a
    robot's port, the real-time simulator), none on the virtual clock (the robot does not
    move while the host thinks); None or 0: no guard.

    ``strict``, as ``roomba-bt run --strict``: a run whose tree succeeded but in which the
    mode guard refused a command, a command was dropped while the tree was stopped, or the
    robot fell out of Safe/Full by itself (not onto a charger) ends with exit code 7
    (:attr:`RunSummary.exit_code`; :meth:`RunSummary.raise_for_outcome` raises), its
    summary naming each count and its first instance. The outcome stays the tree's SUCCESS.

    ``visitors``: py_trees visitors (``py_trees.visitors.VisitorBase``: ``SnapshotVisitor``,
    ``DebugVisitor``, one of the program's own), run on every tick as
    ``py_trees.trees.BehaviourTree.tick`` runs them (``initialise()``, ``run(node)`` for
    each node ticked, or every node when ``full``, ``finalise()``), in the ticking thread;
    ``observer`` is the post-tick handler. With none, the tree's tick is as it was.
    """

    # Long on purpose: a signature of 15 keyword arguments (a program's one call sets up the
    # whole run), each a line; the body, the run's assembly, is about 40 lines
    def __init__(
        self,
        mission: MissionLike,
        link: Transport | Connection,
        *,
        profile: RobotProfile | str | None = None,
        baud: int | None = None,
        packets: Sequence[int] | None = None,
        watchdog: float | None = None,
        grace: float = DEFAULT_GRACE,
        end_in: EndMode | None = None,
        timeout_s: float | None = None,
        observer: TickObserver | None = None,
        input_ended: Callable[[], str | None] | None = None,
        record: Recording | None = None,
        keep_awake: bool | None = None,
        tick_limit: TickLimit = "default",
        replayed_notes: Sequence[dict[str, Any]] | None = None,
        strict: bool = False,
        visitors: Sequence[VisitorLike] = (),
    ) -> None:
        check_arguments(mission, link, timeout_s, grace, watchdog, baud, tick_limit, packets)
        check_given(observer=observer, input_ended=input_ended, strict=strict, visitors=visitors)
        made: dict[str, Any] = dict(
            watchdog=watchdog, end_in=end_in, baud=baud, keep_awake=keep_awake
        )
        connection, profile, baud, link = _given(link, profile, made)
        self.packets = tuple(
            packets if packets is not None else stream_request(mission.packets, baud)
        )
        transport: Transport = link
        if record is not None:
            watchdog_s = connection.link.watchdog if connection else _made_watchdog(made)
            ends: EndMode = connection.end_in if connection else end_in or "passive"
            header = record.header(profile, baud, self.packets, watchdog_s, grace, ends)
            # OSError: the file cannot be written (FileInUse: another run writes it;
            # RecordNotStarted: a required record's header)
            transport = RecordingTransport(
                link, record.path, header, record.claimed, record.max_bytes, record.required
            )
        self.link = link
        self.transport = transport
        #: whether the stack made its connection, and so closes it (:meth:`close`): who
        #: opens closes, and a connection the program handed over stays the program's
        self.owns_connection = connection is None
        if connection is None:
            settings = {name: value for name, value in made.items() if value is not None}
            connection = Connection(transport, profile, **{**settings, "baud": baud})
        elif record is not None:
            connection.transport = transport  # the record's tap under the taken-over link
        self.connection = connection
        # a port that fails is waited for as long as a silent stream is, for the stop alone
        connection.ending.port_return.within = grace
        self.runner = MissionRunner(
            self.connection,
            mission,
            profile=profile,
            packets=self.packets,
            timeout_s=timeout_s,
            observer=observer,
            input_ended=input_ended,
            grace=grace,
            tick_guard=_tick_guard(self.connection, link, tick_limit, replayed_notes),
        )
        if isinstance(transport, RecordingTransport):  # where it stops, said in mission time
            transport.mission_time = partial(mission_time_after, self.runner, 0.0)
        self.runner.summary.strict = strict
        if visitors:  # set only when given (a class attribute: MissionRunner.visitors)
            self.runner.visitors = tuple(visitors)
        #: the thread :meth:`run` runs in, while it runs; set when it has ended
        self._running_in: threading.Thread | None = None
        self._ended = threading.Event()
        #: the hand-over to a :meth:`ticks` loop, while one runs the stack
        self.stepper: TickStepper | None = None

    @property
    def mission(self) -> MissionLike:
        """The mission running now: the one given, until the monitor reloads another."""
        return self.runner.mission

    def run(self, *, raise_interrupts: bool = True) -> RunSummary:
        """The mission to its end; the robot is left stopped (see :meth:`MissionRunner.run`).
        With ``--record``, the record is written out before the summary is made, which says
        when a file that could not be written stopped it.

        Ctrl-C or SIGTERM: after the safe stop the interrupt is raised again, an
        :class:`~roomba_bt.runtime.loop.Interrupted` (a ``KeyboardInterrupt``) with the
        summary as its ``summary``, unless ``raise_interrupts`` is False (the CLI, the
        evaluation: the summary's outcome is then INTERRUPTED, exit 130). A stack runs once:
        a second call raises RuntimeError (build a new RunStack).

        Off the main thread (a worker thread, ``asyncio.to_thread``) no signal reaches the
        run: it says so, and the program ends it with :meth:`stop` or :meth:`close`."""
        if threading.current_thread() is not threading.main_thread():
            self._warn_off_the_main_thread(threading.current_thread())
        return self.run_here(raise_interrupts=raise_interrupts)

    def run_here(self, *, raise_interrupts: bool = True) -> RunSummary:
        """:meth:`run` in this thread, without its warning off the main thread (the worker
        of :meth:`ticks`, whose loop in the main thread takes the signals)."""
        self._running_in = threading.current_thread()
        say_waits_past_sleep(self.runner.mission, self.runner.connection)  # before it starts
        try:
            return self.runner.run(raise_interrupts=raise_interrupts)
        finally:  # an interrupt raised again too: its summary says how the record ended
            if isinstance(self.transport, RecordingTransport):
                summary = self.runner.summary
                self.transport.note(  # how it ended, for replay and the monitor's record view
                    end_note(summary.outcome.value, summary.reason, summary.mission_time_s,
                             summary.ended_at, summary.written_when_interrupted)
                )  # fmt: skip
                self.transport.flush()
                summary.record_stopped = self.transport.stopped or ""
            self._ended.set()

    def ticks(self) -> Generator[Tick, None, None]:
        """The run tick by tick: ``for tick in stack.ticks():`` runs the mission as
        :meth:`run` does, and after each tick of its tree yields a
        :class:`~roomba_bt.runtime.stepping.Tick` (the snapshot, the root's status, the
        tree, the blackboard) and waits for the loop to ask for the next: the loop's body
        runs between two ticks. The loop ends with the run, its summary then
        :attr:`summary` (``stack.summary.raise_for_outcome()``).

        Every way out of the loop ends the run with its safe stop: a ``break`` or an
        exception in the body stops it (INTERRUPTED) before the exception goes on (use
        the loop in a ``with RunStack(...) as stack:`` block, whose end closes the stack,
        so this holds even where the generator is kept alive); Ctrl-C while it waits is
        raised again as :meth:`run` raises it, the robot stopped. The run itself goes on
        in a worker thread (so the tree is ticked as :meth:`run` ticks it, frame by
        frame, at the same cost); on a robot the robot drives on while the body runs, and
        the tick guard watches the body as it watches a tick. Runs once, as :meth:`run`.
        A generator (typed so): a program that keeps it between its own steps (a gym-like
        env's ``step()``) ends the run with ``gen.close()``."""
        return ticks(self)

    @property
    def summary(self) -> RunSummary:
        """The run's summary: final once :meth:`run` has returned (or :meth:`ticks`'s loop
        ended), growing while the run goes on."""
        return self.runner.summary

    def __enter__(self) -> RunStack:
        return self

    def __exit__(self, *exc_info: object) -> None:
        """The end of a ``with`` block: :meth:`close` (a run still going, in a worker thread
        or a :meth:`ticks` loop left early, is stopped first, its safe stop written)."""
        self.close()

    def _warn_off_the_main_thread(self, thread: threading.Thread) -> None:
        """A run that drives (a link on the wall clock) in a thread Ctrl-C never reaches: a
        program that does not stop it itself leaves its robot driving after Ctrl-C (and hangs
        joining the thread). An evaluation's worker, which guards no signal, is its pool's."""
        if not self.runner.guards_signals or not getattr(self.link, "wall_clock", True):
            return
        log.warning(
            "%s: this run is in thread %r, not the main thread: Ctrl-C and SIGTERM do not reach "
            "it, and the robot would drive on after them; end it from the main thread with "
            "stack.stop() or stack.close() (in a finally:, see roomba-bt docs runtime, From "
            "Python: a run in a worker thread)",
            self.connection.name, thread.name,
        )  # fmt: skip

    def stop(self, reason: str = "stopped by the program") -> None:
        """Stop the run from another thread (a run in a worker thread, which Ctrl-C and
        SIGTERM do not reach): its tree stopped, the safe stop sent, the outcome INTERRUPTED
        with ``reason``; :meth:`run` returns it (see
        :meth:`~roomba_bt.runtime.loop.MissionRunner.request_stop`). Then join the thread,
        and :meth:`close` (which, called while the run goes on, stops it and waits itself)."""
        self.runner.request_stop(reason)
        if self.stepper is not None:  # a ticks() loop's worker may wait for its loop
            self.stepper.release()

    def close(self) -> None:
        """Close the connection the stack made (and the record); a link already gone is no
        error here: the run's summary has said what happened to it. A connection the program
        handed over (``RunStack(mission, connection)``) stays open, the program's to drive
        on or close: who opens closes (a ``with RunStack`` per episode over one connection
        had closed it after the first, and the next run blamed a pulled cable); its record,
        if any, is ended and taken from under it.

        Called from another thread while :meth:`run` goes on (a ``finally:`` in the main
        thread or an asyncio coroutine): :meth:`stop` first, and the run's end awaited (up to
        :data:`CLOSE_WAIT_S`: its own safe stop, then the close), so the robot is stopped and
        the run ends INTERRUPTED. Closing under a running run had cut the link beneath its safe
        stop: "the stop was not delivered"."""
        running_in = self._running_in
        if running_in not in (None, threading.current_thread()) and not self._ended.is_set():
            self.stop("stack.close() from another thread, while the run went on")
            if not self._ended.wait(CLOSE_WAIT_S):
                log.warning(
                    "%s: the run did not end within %.0f s of stack.close() (a tick that "
                    "blocks?): the connection is closed under it, its safe stop sent from here",
                    self.connection.name, CLOSE_WAIT_S,
                )  # fmt: skip
                self.owns_connection = True  # the robot stopped first, whoever opened it
        if self.owns_connection:
            with contextlib.suppress(Exception):
                self.connection.close()
        elif isinstance(self.transport, RecordingTransport):
            self.connection.transport = self.link  # the program's link, without the tap
            self.transport.end_record()
        board = self.runner.blackboard
        if board is not None:  # its keys: no later run in the process reads them
            board.release()


def _given(
    link: Transport | Connection, given: RobotProfile | str | None, made: Mapping[str, Any]
) -> tuple[Connection | None, RobotProfile, int, Transport]:
    """What :class:`RunStack` was given: a connection to take over (None: a link, the stack
    makes its own), the profile, the baud and the link under it. ``profile=`` is read as
    every public entry reads it (:func:`~roomba_bt.oi.profiles.profile_given`: a profile or
    its name, ``"create2"``; it was an AttributeError, 'str' object has no attribute
    'name'), but a link still needs one: None there is the TypeError below."""
    profile = None if given is None else profile_given(given, "RunStack")
    if isinstance(link, Connection):
        connection = _taken_over(link, profile, made)
        return connection, connection.profile, connection.baud, connection.transport
    if profile is None:
        raise TypeError(
            "RunStack(mission, link) needs profile=, the robot's model: "
            f"roomba_bt.PROFILES has {', '.join(PROFILES)}"
        )
    baud = made["baud"]
    return None, profile, DEFAULT_BAUD if baud is None else baud, link


def _taken_over(
    connection: Connection, profile: RobotProfile | None, made: Mapping[str, object]
) -> Connection:
    """``connection``, which a :class:`RunStack` runs as it was made: the settings given to
    the stack as well would have been silently another's (its watchdog, say). A closed one
    is refused here: its run failed at the start-up's first write, "the port is gone (the
    cable was pulled ...)", and sent the user to check a cable the program had closed."""
    if connection.ending.closed:
        raise ConnectionClosed(connection.name, "RunStack(mission, connection)")
    given = sorted(name for name, value in made.items() if value is not None)
    if given:
        raise ValueError(
            f"RunStack(mission, connection, {'=..., '.join(given)}=...): a Connection is run "
            "as it was made; give these to Connection(...) or Connection.open(...)"
        )
    if profile is not None and profile != connection.profile:
        raise ValueError(
            f"RunStack(mission, connection, profile={profile.name}): the connection speaks "
            f"to a {connection.profile.name}; leave profile= out (the connection's is used)"
        )
    return connection


def _made_watchdog(made: Mapping[str, Any]) -> float:
    """The watchdog of the connection :class:`RunStack` makes (``made``: its settings)."""
    watchdog = made["watchdog"]
    return DEFAULT_WATCHDOG if watchdog is None else float(watchdog)


def _tick_guard(
    connection: Connection,
    link: Transport,
    tick_limit: TickLimit,
    replayed_notes: Sequence[dict[str, Any]] | None,
) -> TickGuardLike | None:
    """The run's tick guard: a replay's does the record's acts again; else ``tick_limit``
    as :class:`RunStack` says (``"default"``: the CLI's on the wall clock, none on the
    virtual clock)."""
    if replayed_notes is not None:
        return recorded_tick_guard(connection, replayed_notes)
    if tick_limit == "default":
        tick_limit = DEFAULT_TICK_LIMIT if getattr(link, "wall_clock", True) else None
    return TickGuard(connection, tick_limit) if tick_limit else None


class RecordedEnd(InnerGate):
    """A replay's gate that ends the run where its record's end note says the recorded run was
    ended from outside its tree (:data:`~roomba_bt.runtime.recording.ENDED_FROM_OUTSIDE`: the
    monitor's stop, Ctrl-C, its time limit), before or after the tree's tick on that frame,
    as live; ``inner``: the monitor's replay of the operator's acts, asked first (live, a
    frame's acts were done before its stop). Without it the replay ticks the tree on past
    the run's end, and its next command, where the record holds the safe stop, is the
    replay's first difference (``expected Drive (137) 89 00 00 00 00, sent Drive Direct
    ...`` at its last bytes)."""

    def __init__(
        self,
        note: dict[str, Any],
        inner: TickGate | None,
        transport: ReplayTransport | None,
        trips: Sequence[float] = (),
    ) -> None:
        self.tick, self.half = int(note["tick"]), str(note.get("at", "after"))
        self.reason = ending_text(note)
        super().__init__(inner)
        #: the bytes the recorded run had written when its interrupt came "before" the tick
        #: was written whole (the note's ``written``; None: a record made before said none)
        written = note.get(WRITTEN)
        self.written = written if type(written) is int and transport is not None else None
        self.transport = transport
        #: whether the replay ended here (its summary then says how the recorded run did)
        self.ended = False
        #: past the end's tick, the replay waits to have written what the recorded run had
        #: when its stop came (:meth:`between_frames`): the record's end is no end yet
        self.waiting = False
        #: the note's count and the bytes the recorded run wrote before its stop, where the
        #: first is past the second (:data:`~roomba_bt.runtime.recording.MISCOUNT`), or is
        #: None where the run rode a stall past the tick (:attr:`uncounted`)
        self.miscount: tuple[int | None, int] | None = None
        #: when the recorded run's watchdog tripped (the record's notes, link time)
        self.trips = trips
        #: an "after" note with no count whose run's watchdog tripped past the end's tick: a
        #: Ctrl-C or signal in a stall, in a record made before 2e6d3655, which noted none
        #: (:data:`~roomba_bt.runtime.recording.UNCOUNTED`); set at that tick
        self.uncounted = False

    def _end(self) -> None:
        self.ended = True
        raise StopRequested(self.reason, at=self.half)

    def before_tick(self, runner: MissionRunner) -> bool:
        ticks = self.inner.before_tick(runner) if self.inner is not None else True
        tick = runner.snapshot.tick
        if tick > self.tick or (tick == self.tick and self.half == "before"):
            if tick == self.tick and self._cut_short():
                return ticks  # the tick's commands are written up to the interrupt
            self._end()
        return ticks

    def _cut_short(self) -> bool:
        """Whether the recorded run's interrupt came between two writes of this tick (it had
        written more than the replay has so far): the replay then ticks the frame and its
        transport ends the run at the first write past those bytes (or :meth:`after_tick`
        does, where the tick wrote no more). Before, the replay ended before the tick and
        missed the commands the live run had written of it: a difference, exit 1."""
        transport = self.transport
        if self.written is None or transport is None or transport.written >= self.written:
            return False
        transport.interrupt_at(self.written, self._interrupt)
        return True

    def _interrupt(self) -> None:
        """The recorded run's interrupt, where the replay's tick writes past its count; not
        once the replay has ended otherwise (:meth:`_miscounted`: its stop writes past it)."""
        if not self.ended:
            self._end()

    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        if runner.snapshot.tick >= self.tick:  # "after": the run ended with this tick...
            self.uncounted = self._stall_uncounted()
            self.waiting = self._writes_to_come()
            if not self.waiting:
                self._end()  # ...unless it wrote more before its stop (a stall's drive 0)

    def _stall_uncounted(self) -> bool:
        """Whether this "after" end with no count came in a stall the recorded run's
        watchdog rode: it tripped after this tick (the record's trip notes), so its drive 0
        came before the stop, which an older record did not count (:attr:`uncounted`)."""
        transport = self.transport
        if self.written is not None or self.half != "after" or transport is None:
            return False
        now = transport.now()
        return any(trip > now for trip in self.trips)

    def between_frames(self, runner: MissionRunner) -> None:
        """A read with no frame past the end's tick: a stop the recorded run was asked for
        between frames (the monitor's Stop in a stall, after the watchdog's drive 0) ends
        the replay here, once it has written as much. It ended the replay at the tick
        before, and the record's drive 0 was the replay's first difference (exit 1). So
        does an interrupt "before" the tick whose count is past what the tick wrote (an
        older record's miscount, :meth:`_miscounted`): it waited for ever."""
        super().between_frames(runner)
        past = runner.has_snapshot and runner.snapshot.tick >= self.tick
        if past and (self.half == "after" or self.waiting):
            self.waiting = self._writes_to_come() and not self._miscounted()
            if not self.waiting:
                self._end()

    def _miscounted(self) -> bool:
        """Whether the end note's count is past the bytes the recorded run wrote before its
        stop: the replay, between frames and waiting for them, is past the time the recorded
        run wrote its next bytes, which nothing of its run wrote here (its link writes what
        it wrote in the stall, when it did): those came after the stop, and the count is
        the known miscount of an older record (:data:`~roomba_bt.runtime.recording.
        MISCOUNT`). The replay then ends here, and its own stop is compared with the
        record's from there: the same bytes, and it is said so; others, a difference. It
        waited for bytes that came after the stop, and said the stop's drive 0 was its
        first difference, "sent nothing", exit 1. The same of a Ctrl-C "before" a tick
        whose stop was asked after (the count 5 past the tick's bytes: it waited for ever,
        "sent nothing"), and of a note with no count where the run rode a stall
        (:attr:`uncounted`: its count is where the replay has got to then)."""
        transport = self.transport
        counted = self.written is not None or self.uncounted
        if not counted or transport is None or not transport.write_passed():
            return False
        self.miscount = (self.written, transport.written)
        return True

    def _writes_to_come(self) -> bool:
        """Whether the recorded run wrote more after the end's tick, before its stop, than
        the replay has so far (the end note's ``written``: none in an older record; not
        known where it rode a stall, :attr:`uncounted`, until the replay is past its
        writes there)."""
        transport = self.transport
        if transport is None:
            return False
        if self.written is None:
            return self.uncounted
        return transport.written < self.written


class AfterTickGate(InnerGate):
    """A replay's gate that looks at the run after each tick (:meth:`after_tick`, the part a
    subclass adds) and otherwise is ``inner``: the monitor's replay of the operator's acts,
    asked first, or nothing."""

    def __init__(self, inner: TickGate | None, transport: ReplayTransport) -> None:
        super().__init__(inner)
        self.transport = transport


class WindowEnd(AfterTickGate):
    """A replay's gate that ends it once the tree has ticked at mission time ``until``
    (``--to``: a window of a long record, the rest not replayed), as if the record ended
    there (:meth:`ReplayTransport.end_here`)."""

    def __init__(self, until: float, inner: TickGate | None, transport: ReplayTransport) -> None:
        super().__init__(inner, transport)
        self.until = until

    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        if runner.snapshot.time >= self.until and not self.transport.ended_early:
            self.transport.end_here()


class LinkLostAfter(AfterTickGate):
    """A replay's gate that marks where the recorded run's link failed: once the tree has
    ticked the recorded run's last tick (its end note's, ``tick``) with the same bytes, what
    it wrote by then (:attr:`ReplayTransport.link_lost_from`). Past there the recorded run
    wrote what its link's failure had it write (the watchdog's drive 0, its queries, a wake,
    the stop, or nothing: the port gone) on a line the replay cannot be: a difference there
    is the ending's, not the tree's (``replay`` says so, exit 0)."""

    def __init__(self, tick: int, inner: TickGate | None, transport: ReplayTransport) -> None:
        super().__init__(inner, transport)
        self.tick = tick

    def before_tick(self, runner: MissionRunner) -> bool:
        """A frame the tree is not ticked in (the operator's pause, a step's end) marks the
        loss too: a run paused when its robot fell asleep, or its cable was pulled, ticked
        its tree last minutes before its end note's tick, and the replay, marking only after
        a tick, called the run's asking after the sleeping robot its first difference."""
        ticks = super().before_tick(runner)
        if not ticks:
            self._mark(runner)
        return ticks

    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        self._mark(runner)

    def _mark(self, runner: MissionRunner) -> None:
        """What the tree had written by the end note's tick, once the replay reaches it."""
        transport = self.transport
        if (
            runner.snapshot.tick >= self.tick
            and transport.link_lost_from is None
            and transport.difference is None
        ):
            transport.link_lost_from = transport.written


#: the end notes of a run whose link failed (``Outcome.CONNECTION_LOST``, ``NO_CONNECTION``),
#: or whose robot's frames were another model's (``WRONG_PROFILE``: its link's end all the same)
LINK_FAILED = tuple(
    o.value for o in (Outcome.CONNECTION_LOST, Outcome.NO_CONNECTION, Outcome.WRONG_PROFILE)
)


def link_lost_after(
    record: Record, gate: TickGate | None, transport: ReplayTransport
) -> TickGate | None:
    """``gate`` inside a :class:`LinkLostAfter` where ``record``'s run ended by its link
    failing after its tree's last tick; a run that failed before its first tick (its note
    has none: the wrong profile, no answer) marks the transport from its start, as its tree
    wrote nothing to compare. ``gate`` itself for any other ending."""
    note = record.ending
    if note is None or tree_ended(note) not in LINK_FAILED:
        return gate
    tick = note.get("tick")
    if not isinstance(tick, int):
        transport.link_lost_from = 0
        return gate
    return LinkLostAfter(tick, gate, transport)


def past_the_link_loss(
    transport: ReplayTransport,
    difference: tuple[int, str, str] | None,
    ending: Mapping[str, Any] | None,
) -> tuple[str, str] | None:
    """What a replay says of a difference (``transport.first_difference()``) that came only
    after the recorded run's link failed (after its tree's last tick:
    :attr:`ReplayTransport.link_lost_from`), two sentences, or None for any other;
    ``ending``: the record's end note. The recorded run then wrote what the failure had it
    write (the watchdog's drive 0, queries, a wake by BRC, the stop, or nothing once the
    port was gone), which a replay, with no line to fail, does not do again: "first
    difference", exit 1, read as "your mission changed" for every record of a pulled cable
    or a reset robot. ``replay`` and the monitor's view of a record both say it (the
    monitor said "replay diverged from the record", read as a broken record)."""
    lost_from = transport.link_lost_from
    if difference is None or lost_from is None or difference[0] < lost_from:
        return None
    _, expected, sent = difference
    time, tick = (ending or {}).get("time"), (ending or {}).get("tick")
    if not isinstance(tick, int):  # the start-up's bytes alone, the same up to the difference
        lost = f"before its tree's first tick; the {difference[0]} bytes up to there are the same"
    else:
        when = f" at mission time {time:.3f} s" if isinstance(time, int | float) else ""
        lost = f"{when}, after its tree's last tick; compared up to there: the tree wrote the "
        lost += f"same {lost_from} bytes"
    return (
        f"the recorded run lost its link {lost.lstrip()}",
        f"past there the replay does not fail as its link did (the record holds "
        f"{expected}, the replay's own ending sent {sent})",
    )


def recorded_end(
    record: Record, gate: TickGate | None, transport: ReplayTransport | None = None
) -> RecordedEnd | None:
    """The gate that ends ``record``'s replay where its run was ended from outside its tree,
    ``gate`` inside it; None when the record says no such end (an older record, a run that
    ended by its tree or its link: the replay ends there by itself). ``transport``: the
    replay's, which ends a tick the recorded run's interrupt cut short where it did."""
    note = record.ending
    if note is None or tree_ended(note) not in ENDED_FROM_OUTSIDE:
        return None
    if not isinstance(note.get("tick"), int) or note.get("at") not in ("before", "after"):
        return None
    return RecordedEnd(note, gate, transport, record.watchdog_trips or ())


def _window_end(until: float | None) -> str:
    """Why a replay ended at the end of its window, naming the caller's way of setting it
    (``--to``, or a program's ``until``: it was told of a flag it never gave)."""
    return f"the end of the window, mission time {until:g} s ({wording.current.replay_until})"


def _end_of(record: Record) -> str:
    """A replay's reason at the end of ``record``; for one without its run's end, where and
    why it ends: what follows it (the replay's own stop, past the record) is not the
    recorded run's, and its verdict is none (``ReplayTransport.loses_bytes``)."""
    if record.ended:
        return "end of the record"
    stopped = record.recording_stopped
    why = "its run's end is not in it" if stopped is None else f"the recording stopped ({stopped})"
    return f"end of the record: it ends at {record.last_t:.3f} s, before its run's end: {why}"


def follow_the_recorded_link(stack: RunStack, record: Record) -> None:
    """A replay's link trips its watchdog where the record's did (on the record's silence
    where the record notes no trips: made before they were noted), and asks for a silent
    stream again where the record's did, nowhere else (robot/stall_asks.py): its run's bytes
    come from those acts, which a replayed line cannot bring about by itself."""
    trips = record.watchdog_trips
    if trips is not None:
        stack.connection.link.replayed_trips = deque(trips)
    stack.connection.stall_asks.replayed = deque(
        t for t, note in record.notes if STREAM_AGAIN_NOTE in note
    )


def replay_input_ended(
    transport: ReplayTransport, record: Record, until: float | None, ends: list[RecordedEnd]
) -> Callable[[], str | None]:
    """A replay's ``input_ended`` (:func:`replay_record`): a difference, the window's end
    (``until``), or the record's; not while the replay's end (``ends``: its
    :class:`RecordedEnd`, once made) waits for the writes of a stop between frames, the
    reads going on past the record's last chunk to the watchdog's trip it noted, whose
    drive 0 came before the stop (up to the record's last time)."""

    def input_ended() -> str | None:
        if transport.difference is not None or transport.starved():
            return "first difference from the record"
        if transport.ended_early:
            return _window_end(until)
        waits = any(end.waiting for end in ends) and transport.now() <= record.last_t
        return _end_of(record) if transport.exhausted and not waits else None

    return input_ended


def replay_record(
    record: Record,
    mission: MissionLike,
    *,
    profile: RobotProfile,
    packets: Sequence[int],
    baud: int,
    name: str,
    observer: TickObserver | None = None,
    gate: TickGate | None = None,
    raise_interrupts: bool = True,
    progress: Callable[[float], None] | None = None,
    until: float | None = None,
    stamp_logs: bool = False,
) -> tuple[RunSummary, ReplayTransport]:
    """``record``'s sensor bytes through ``mission`` on the recorded clock (``replay`` and the
    monitor's recorded runs): the run ends at the record's end or at the first command that
    differs from the recorded ones; the transport holds what the tree wrote. Ctrl-C is
    raised again unless ``raise_interrupts`` is False (see :meth:`RunStack.run`).
    ``progress(fraction)``: at each tenth of the record's time replayed. ``until``: the
    mission time the replay ends at, as if the record ended there (``--to``; its
    transport's ``ended_early``). ``stamp_logs``: log lines stamped with the replay's mission
    time and the record's label, as ``run``'s (``replay``'s: its caller cannot reach the
    runner made here, and a mission's ``log`` lines had no ``t=``)."""
    transport = ReplayTransport(record, name=f"replay:{name}", progress=progress)
    header = record.header
    ends: list[RecordedEnd] = []  # the replay's end where its run was stopped, once made
    stack = RunStack(
        mission,
        transport,
        profile=profile,
        baud=baud,
        packets=packets,
        watchdog=float(header.get("watchdog", DEFAULT_WATCHDOG)),  # as the recorded run's
        grace=float(header.get("grace", DEFAULT_GRACE)),
        end_in=recorded_end_in(header, record.out_tail),
        keep_awake=False,  # no robot to keep awake (it said a robot "sleeps after 5 minutes")
        observer=observer,
        input_ended=replay_input_ended(transport, record, until, ends),
        replayed_notes=_guard_notes(record),  # the tick guard's acts
    )
    follow_the_recorded_link(stack, record)
    _watch_the_recorded_loop(stack.runner, observer)
    stack.runner.gate = _replay_gates(record, transport, gate, until, ends)
    stack.runner.on_wall_clock = False  # a record's clock: Ctrl-Z suspends, Ctrl-\ quits
    try:
        with stamped_logs(stack.runner if stamp_logs else None, record.label):
            summary = stack.run(raise_interrupts=raise_interrupts)
    finally:
        # as the recorded run's (``run``): a stop not delivered is tried once more there, and
        # its bytes are in the record; before, the replay's was left to the program's exit
        stack.close()
    end = ends[0] if ends else None
    if end is not None and end.ended and summary.outcome is Outcome.INTERRUPTED:
        summary.outcome, summary.reason = Outcome.INPUT_ENDED, f"end of the record: {end.reason}"
    if end is not None and end.miscount is not None:  # said by replay, the stop the same
        record.miscounted = end.miscount
    return summary, transport


def _guard_notes(record: Record) -> list[dict[str, Any]]:
    """The record's notes as its replay's tick guard reads them: a ``run --record``'s (its
    header's options) or 0.1.0's (no release named) held no loop over ``stack.ticks()``,
    so each of its guard's notes is the tree's (:func:`tree_notes_of`)."""
    header = record.header
    program = RUN_OPTIONS not in header and MADE_BY in header
    return tree_notes_of((note for _, note in record.notes), program_since_ticks=program)


def _watch_the_recorded_loop(runner: MissionRunner, observer: TickObserver | None) -> None:
    """Where the record's tick guard acted or saw a slow pass between two ticks (a program's
    loop over ``stack.ticks()``), the replay's observer watches that place after each tick
    (:func:`~roomba_bt.runtime.stepping.replayed_loop`), ``observer`` first."""
    guard = runner.tick_guard
    if isinstance(guard, RecordedTickGuard) and guard.between_ticks:
        runner.observer = replayed_loop(runner, observer)


def _replay_gates(
    record: Record,
    transport: ReplayTransport,
    gate: TickGate | None,
    until: float | None,
    ends: list[RecordedEnd],
) -> TickGate | None:
    """A replay's gates around ``gate`` (the monitor's replay of the operator's acts): the
    window's end (``until``), the link's loss, and the recorded end (put in ``ends``)."""
    if until is not None:
        gate = WindowEnd(until, gate, transport)
    gate = link_lost_after(record, gate, transport)
    end = recorded_end(record, gate, transport)
    ends += [end] if end is not None else []
    return end or gate
