"""The operator's hold on a running mission: the runtime's tick gate.

Requests (from the page, from the terminal's keys, from ``--watch``) are put on a queue by any
thread and applied by the tick thread between two ticks, in :meth:`MonitorSession.before_tick`;
nothing touches the tree or the connection from another thread. Per frame::

    before_tick: apply requests -> stop? (raise StopRequested) -> reload? -> paused? (record
                 the frame, tree frozen, no tick) -> tick
    after_tick:  record the tick in the feed -> a breakpoint hit? pause -> a step done? pause

Pausing is the safe stop without ending the run: drive 0 and motors off where the mode takes
them, then Start (Passive); the stream goes on, so the page still shows the robot, but mission
time stands still (the runner's ``clock_held``; the stream's tick index goes on): a wait or a
time limit does not count the pause, and the summary's mission time leaves it out. Resuming
re-enters the mode the robot was in before the pause (Safe or Full) through the connection,
whose mode guard checks it like any other command, and the tree goes on from where it was.
"""

from __future__ import annotations

import contextlib
import logging
import math
import queue
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from py_trees.common import Status

from roomba_bt.monitor.controls import (
    BREAK_ON,
    CONTROLS,
    FORCEABLE,
    Ahead,
    ControlRefused,
    Request,
    check_request,
    find_node,
    node_path,
)
from roomba_bt.monitor.feed import IN_THE_EVENT_LOG, RunFeed
from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.printable import duration_words
from roomba_bt.runtime.display import live_names
from roomba_bt.runtime.loop import StopRequested
from roomba_bt.runtime.teardown import setup_tree

if TYPE_CHECKING:
    from roomba_bt.robot.interface import Snapshot
    from roomba_bt.runtime.loop import MissionRunner

#: the names this module held before what may be asked had a module of its own
#: (``controls.py``): ``from roomba_bt.monitor.session import ControlRefused`` still works
__all__ = [
    "BREAK_ON",
    "BY_OPERATOR",
    "FORCEABLE",
    "RELOADED_IN_A_STEP",
    "ROBOT_SLEEPS_S",
    "SLEEP_WARNING_S",
    "STEP",
    "STEPPED",
    "ControlRefused",
    "MonitorSession",
    "Request",
    "SessionState",
    "find_node",
    "node_path",
    "pause_sequence",
    "sleep_countdown",
    "sleep_warning",
]

log = logging.getLogger(__name__)

#: the resume's reason that makes it a step (the record's note says it: a replay steps too)
STEP = "one step"
#: the pause's reason after a step's tick
STEPPED = "stepped one tick"
#: the reason of a pause the operator asked for (not a breakpoint's, nor a step's end)
BY_OPERATOR = "paused by the operator"
#: the pause's reason when ``--watch`` reloads the mission while a step is under way
RELOADED_IN_A_STEP = (
    "the mission reloaded during a step: held; the new tree starts from its root at the resume"
)
#: an OI robot's sleep after this long in Passive (keep-awake's BRC pulses prevent it)
ROBOT_SLEEPS_S = 300.0
#: how long into a pause a robot that will sleep is warned of in the event log and the
#: terminal's log (the page's banner counts down from the pause's start: ``sleep_note``)
SLEEP_WARNING_S = 240.0


@dataclass
class SessionState:
    """What the page shows of the operator's controls; written by the tick thread only."""

    paused: bool = False
    pause_reason: str = ""
    #: the stream's tick the pause began at (the page says for how long); None: not paused
    paused_tick: int | None = None
    #: on a link without keep-awake, how long until the paused robot sleeps and the run
    #: ends, counted down each second of the pause from its start (``this link cannot keep
    #: the robot awake: the run ends 5 min into the pause; 4 min 18 s left``); "" otherwise.
    #: It came only at 4 minutes, in the pause's reason, and 42 s later still said "in
    #: about 60 s"
    sleep_note: str = ""
    breakpoints: dict[int, str] = field(default_factory=dict)
    forced: dict[int, str] = field(default_factory=dict)
    watching: str | None = None  # the mission file under --watch
    #: the mission's outcome (``SUCCESS``) while the run is held at its end (a breakpoint or
    #: a step on its last tick), "" otherwise: the resume then ends the run, where the
    #: page's banner said "resume goes back to the mission's mode"
    held_end: str = ""


def pause_sequence(connection: Any) -> list[Command]:
    """The safe stop's commands for the current mode, ending in Start (Passive) and keeping
    the stream: :meth:`Connection.stop_sequence` without Pause Stream, Start in place of Stop."""
    stop_name, pause = oi.stop().name, oi.pause_stream()
    out: list[Command] = []
    for command in connection.stop_sequence():
        if command.name == pause.name and command.data == pause.data:
            continue
        out.append(oi.start() if command.name == stop_name else command)
    return out


# the one place an operator's request meets the run, its check against the queued ones
# (controls.py), its application between two ticks and the state each act leaves (pause,
# resume, step, breakpoints, reload) together, under one lock; a pause's countdown to the
# robot's sleep (SleepCountdown) and the forced conditions (Forces) are parts of their own
class MonitorSession:
    """The tick gate the runner calls around each tick (see the module docstring)."""

    #: what the event log says the pause and the resume did with their commands, and where
    SENT, WHERE = "sent", ""
    #: warn of the robot's sleep in a long pause (not in a replay: the record's robot slept
    #: or not, and its link is not the run's)
    WARN_OF_SLEEP = True

    def __init__(
        self,
        feed: RunFeed,
        *,
        simulator: bool,
        allow_force: bool = False,
        paced: bool = False,
        loader: Callable[[], Any] | None = None,
        stream_packets: Iterable[int] = (),
    ) -> None:
        self.feed = feed
        self.simulator = simulator
        self.allow_force = allow_force or simulator
        self.paced = paced  # on the virtual clock: a paused run waits a frame's wall time
        self.loader = loader
        self.stream_packets = frozenset(stream_packets)
        self.state = SessionState()
        self._requests: queue.SimpleQueue[Request] = queue.SimpleQueue()
        #: held by :meth:`request` while it checks and queues, and by the tick thread while
        #: it applies requests or pauses by itself (a breakpoint, a step's end): a request is
        #: checked against the state it will meet (two pauses pressed at once both got 202,
        #: and one did nothing; a pause after a stop got 202 and was never applied)
        self._lock = threading.RLock()
        #: the pause, resume, step and stop requests queued and not applied yet, in order
        self._queued: list[str] = []
        self._wake = threading.Event()
        self._mode_before_pause: OIMode | None = None
        #: a built-in cycle (Seek Dock, Clean) driving the robot in Passive when it paused:
        #: the pause's safe stop ended it, the resume starts it again
        self._cycle_before_pause: Command | None = None
        self._steps_left: int | None = None  # ticks left before a step pauses again
        self._skip_tick = False
        self._stop: str | None = None
        self._pending_mission: Any = None
        #: a pause's countdown to the robot's sleep in Passive, where it sleeps (no keep-awake)
        self._sleep = SleepCountdown(self.state, feed)
        #: the conditions forced, as the node, the page and the summary have them
        self._forces = Forces(self.state.forced, feed)
        self.listeners: list[Callable[[str], None]] = []  # told of pauses (the terminal)
        #: who asked for the request being applied (:attr:`Request.by`), said by :meth:`_said`
        self._asker: str | None = None
        #: the pauses' stream time before the current one's (the summary's ``paused``)
        self._paused_before_s = 0.0

    # ---------------------------------------------------------------- any thread
    def request(
        self,
        action: str,
        node: int | str | None = None,
        value: str | None = None,
        by: str | None = None,
    ) -> None:
        """Queue an operator request after checking it; raises :class:`ControlRefused` or
        ValueError (bad request) without changing anything. ``node``: its index, or its name
        or path (:func:`find_node`); ``by``: who asked, for the event log."""
        infos = self.feed.infos
        if isinstance(node, str):
            node = find_node(infos, node)
        with self._lock:
            check_request(self._ahead(), infos, self.allow_force, action, node, value)
            if action in CONTROLS:
                self._queued.append(action)
            self._requests.put(Request(action, node, value, by=by))
        self._wake.set()

    def _ahead(self) -> Ahead:
        """The run's state as the requests queued will leave it (under :attr:`_lock`): what a
        new request is checked against, so that a 202 is a request the run will apply."""
        state = self.state
        now = Ahead(state.paused, self._steps_left is not None, self._stop is not None)
        now.forced = set(state.forced)
        return now.after(self._queued)

    def reload(self, mission: Any) -> None:
        """A new, valid mission to run from its root at the next safe point."""
        self._requests.put(Request("reload", payload=mission))
        self._wake.set()

    # ---------------------------------------------------------------- tick thread
    def before_tick(self, runner: MissionRunner) -> bool:
        """Apply requests; False when the tree must not tick this frame (paused)."""
        with self._lock:
            go = self._before_tick(runner)
        if not go and self.paced and self.state.paused:
            self._wake.wait(SLOT_SECONDS)
            self._wake.clear()
        return go

    def _before_tick(self, runner: MissionRunner) -> bool:
        if not self._requests.empty():
            self._apply(runner)
        if self._stop is not None:
            raise StopRequested(self._stop)
        if self._pending_mission is not None:
            self._replace_tree(runner, self._pending_mission)
            self._pending_mission = None
        if self._skip_tick:  # this frame's snapshot predates a mode change just sent
            self._skip_tick = False
            self.feed.observe(runner, ticked=False)
            return False
        if self._steps_left is not None and not self.state.paused:
            if self._steps_left == 0:
                self._pause(runner, STEPPED)
            else:
                self._steps_left -= 1
                return True
        if self.state.paused:
            self.feed.observe(runner, ticked=False)
            self._tally_pause(runner)
            if runner.has_snapshot:
                self._sleep.paused_frame(runner.snapshot)
            return False
        return True

    def between_frames(self, runner: MissionRunner) -> None:
        """The run's last read brought no frame (a stall the watchdog rides through, up to
        ``--grace``): a Stop queued acts now (the run ends as on Ctrl-C, its safe stop
        written), as the program's ``request_stop`` does; it waited for the next frame, and
        the robot's stop with it. The requests queued before it are not done: a pause, a
        step, a force act in a frame (where the record's replay does them), and the run's
        end stops the robot anyway."""
        with self._lock:
            if "stop" not in self._queued:
                return
            while self._stop is None:  # up to the stop (queued: never empty before it)
                req = self._requests.get_nowait()
                if req.action in CONTROLS:
                    self._queued.pop(0)
                if req.action == "stop":
                    self._asker = req.by
                    try:
                        self._apply_one(runner, req)
                    finally:
                        self._asker = None
            raise StopRequested(self._stop, at="after")

    def _tally_pause(self, runner: MissionRunner) -> None:
        """The summary's ``paused``: the pauses' stream time so far, this one's included (a
        run stopped while paused ends here), in the stream's ticks: what a replay counts too."""
        began = self.state.paused_tick
        if began is None or not runner.has_snapshot:
            return
        this = max(0, runner.snapshot.tick - began) * SLOT_SECONDS
        runner.summary.paused_s = self._paused_before_s + this

    def after_tick(self, runner: MissionRunner) -> None:
        if self._steps_left == 0:  # a step's tick: its pause comes with the next frame,
            runner.clock_held = True  # whose 15 ms the tree does not run (one step, one frame)
        changed = self.feed.observe(runner)
        if changed and self.state.breakpoints:
            with self._lock:  # its pause is one a request is checked against
                self._check_breakpoints(runner, changed)

    def holds(self, runner: MissionRunner) -> bool:
        """The tree's root has just ended: True while the run is held there, paused by a
        breakpoint on the last tick or by a step that was that tick, so the operator sees the
        end before the run's own; the resume (or a stop) then ends the run."""
        if self.state.forced and runner.mission.root.status is Status.SUCCESS:
            self._forces.said_in_a_success(runner)
        held = self.state.paused or self._steps_left == 0
        if held and not self.state.held_end:
            ended = runner.mission.root.status.value
            self.state.held_end = ended
            self._said(
                runner, "control", f"the mission ended: {ended}; held until resumed or stopped"
            )
        return held

    def _apply(self, runner: MissionRunner) -> None:
        while True:
            try:
                req = self._requests.get_nowait()
            except queue.Empty:
                return
            if req.action in CONTROLS and self._queued:
                self._queued.pop(0)
            self._asker = req.by
            try:
                self._apply_one(runner, req)
            finally:
                self._asker = None

    def _apply_one(self, runner: MissionRunner, req: Request) -> None:
        """One request, in the tick thread (a second pause queued behind the first, say,
        does nothing: the state is checked again here)."""
        state = self.state
        if req.action == "pause" and not state.paused:
            self._pause(runner, BY_OPERATOR)
        elif req.action == "resume" and state.paused:
            self._resume(runner, "resumed by the operator")
        elif req.action == "step" and state.paused:
            self._step(runner)
        elif req.action == "stop":
            self._stop = "stopped by the operator"
            self._said(runner, "control", "stop: the run ends (as on Ctrl-C)")
        elif req.action == "break" and req.node is not None:
            name = self.feed.infos[req.node].name
            if req.value == "none":
                state.breakpoints.pop(req.node, None)
                self._said(runner, "breakpoint", f"breakpoint on {name} cleared")
            else:
                state.breakpoints[req.node] = str(req.value)
                self._said(runner, "breakpoint", f"break when {name} {_on(req.value)}")
        elif req.action == "force" and req.node is not None:
            self._force(runner, req.node, str(req.value))
        elif req.action == "reload":
            self._pending_mission = req.payload

    def _pause(
        self, runner: MissionRunner, why: str, at: str = "before", *, noted: bool = True
    ) -> None:
        """The safe stop, the tree frozen, mission time held; ``at``: in which half of the
        frame (before or after its tick) it happened, for the record's replay."""
        if noted:
            _note(runner, {"pause": why, "at": at})
        # a step's own pause, or one that ended it first (a breakpoint on its tick, a reload
        # in it): the operator's act was the step, counted so (a breakpoint's was a pause);
        # the operator's own pause pressed during a step is both: the step, and the pause
        in_step = self._steps_left is not None
        self._steps_left = None
        connection = runner.connection
        mode = connection.mode
        self._mode_before_pause = mode if mode in (OIMode.SAFE, OIMode.FULL) else None
        cycle = connection.running_cycle if mode is OIMode.PASSIVE else None
        # on its home base the cycle has ended there (Seek Dock docked; Clean came home)
        self._cycle_before_pause = None if cycle is None or _on_home_base(runner) else cycle
        commands = pause_sequence(connection)
        connection.send_many(commands)
        runner.count_written()
        self.state.paused, self.state.pause_reason = True, why
        self.state.paused_tick = runner.snapshot.tick if runner.has_snapshot else 0
        if noted:  # a reload's pause lasts no frame: not one the summary counts
            summary = runner.summary
            if in_step:
                summary.steps += 1
            if not in_step or why == BY_OPERATOR:
                summary.pauses += 1
        runner.clock_held = True  # mission time stands still until the resume
        runner.wall_limit.hold(True)  # and --wall-limit's count: a pause is no stuck tick
        # a reload's own pause (not ``noted``) lasts no frame: no sleep to count down to
        sleeps = noted and self.WARN_OF_SLEEP and _sleeps_in_passive(connection)
        sleeps = sleeps and runner.has_snapshot
        self._sleep.begin(runner.snapshot.tick if sleeps else None)
        sent = ", ".join(c.name for c in commands) or "nothing"
        asleep = f"; {_cannot_keep_awake()} unless resumed" if sleeps else ""
        # a reload's: said as what it is. It said "pause (reload): ...; tree frozen; this link
        # cannot keep the robot awake: the run ends 5 min into the pause unless resumed", and
        # the new tree then drove at once, as a reload does (docs/monitor.md)
        said = (
            f"pause ({why}): safe stop {self.SENT} {sent}{self.WHERE}; tree frozen{asleep}"
            if noted
            else f"{why}: safe stop {self.SENT} {sent}{self.WHERE}; the old tree stops and "
            "the new one takes over at the next frame (no pause: nothing to resume)"
        )
        self._said(runner, "control", said)
        for listener in self.listeners:
            with contextlib.suppress(Exception):
                listener(why)

    def _step(self, runner: MissionRunner) -> None:
        """Resume, tick once, pause again: the next frame ticks (after the one that shows the
        mode back) and the pause comes before the one after, which mission time leaves out
        (:meth:`after_tick`): one step is one 15 ms frame of mission time, not two."""
        self._resume(runner, STEP)
        self._steps_left = 1

    def _resume(self, runner: MissionRunner, why: str) -> None:
        _note(runner, {"resume": why, "at": "before"})
        runner.wall_limit.hold(False)
        self._tally_pause(runner)
        self._paused_before_s = runner.summary.paused_s
        self.state.paused_tick = None
        self._sleep.end()  # awake again: no sleep to count to
        if self.state.held_end:  # nothing to go on with: no mode, no wheels again
            self.state.paused, self.state.pause_reason = False, ""
            self._steps_left = None
            self._said(runner, "control", f"resume ({why}): the mission ended "
                       f"({self.state.held_end}); the run ends")  # fmt: skip
            return
        mode = self._mode_before_pause
        again: list[Command] = []
        if mode in (OIMode.SAFE, OIMode.FULL):
            again.append(oi.safe() if mode is OIMode.SAFE else oi.full())
            again += _standing(runner)
        elif self._cycle_before_pause is not None:  # its leaf waits on it: started again
            again.append(self._cycle_before_pause)
        if again:
            runner.connection.send_many(again)
            runner.count_written()
        self.state.paused, self.state.pause_reason = False, ""
        runner.clock_held = False
        self._skip_tick = True  # the tree next ticks on a frame that shows the new mode
        back = f"back to {mode.label}" if mode is not None else "mode unchanged"
        resent = again[1:] if mode is not None else again
        if resent:
            back += ", " + ", ".join(c.name for c in resent) + f" {self.SENT} again"
        if again:
            back += self.WHERE
        self._said(runner, "control", f"resume ({why}): {back}; the tree goes on")

    def _said(self, runner: MissionRunner, kind: str, text: str) -> None:
        """An operator's act (or what it caused) into the page's event log, and the run's
        log on the terminal: a key pressed there (p, r, n) said nothing, and ``--display
        log`` showed no pause. At the frame it was done in (as the log and the record say):
        a request applied before this frame's tick is not the previous tick's (the feed's
        newest record), which put it 15 ms earlier on the page."""
        if self._asker is not None:
            text += f"; from {self._asker}"
        if runner.has_snapshot:
            snapshot = runner.snapshot
            self.feed.event(kind, text, snapshot.time, snapshot.tick)
        else:
            self.feed.event(kind, text)
        log.info("monitor: %s", text)

    def _force(self, runner: MissionRunner, index: int, value: str) -> None:
        """Force node ``index`` to ``value`` or release it (``none``), said and noted."""
        text = self._forces.force(runner, index, value)
        if text is not None:  # None: a second release queued, the first did it
            self._said(runner, "force", text)
            name = self.feed.infos[index].name
            _note(runner, {"force": name, "node": index, "to": value, "at": "before"})

    def _check_breakpoints(self, runner: MissionRunner, changed: tuple[int, ...]) -> None:
        """Pause after this tick when it met a breakpoint (the first of ``changed`` that did:
        :func:`breakpoint_met`), unless paused already."""
        met = (
            None
            if self.state.paused
            else breakpoint_met(self.feed, self.state.breakpoints, changed)
        )
        if met is not None:
            index, on, tick = met
            name = self.feed.infos[index].name
            self._said(runner, "breakpoint", f"breakpoint: {name} {_on(on)} at tick {tick}")
            self._pause(runner, f"breakpoint: {name} {_on(on)}", at="after")

    def _replace_tree(self, runner: MissionRunner, mission: Any) -> None:
        """Reload at a safe point: safe stop, the old tree stopped, the new one from its root."""
        was_paused = self.state.paused
        # a replay cannot go on past this point: the record has no copy of the new mission
        _note(runner, {"reload": mission.name, "at": "before"})
        if not was_paused and self._steps_left is not None:
            # a step under way: its pause to come, which the reload's own safe stop dropped
            # (the run went on unpaused, the new tree driving the robot), held now instead
            self._pause(runner, RELOADED_IN_A_STEP)
            was_paused = True
        elif not was_paused:
            self._pause(runner, "reload", noted=False)
        # the old tree stopped, then what it opened closed, each bounded as at the run's end
        runner.retire_tree(mission.name)  # (past it the run ends HUNG: RetireHung)
        runner.mission = mission
        # its name too, where a renamed one is shown: the page's header and the summary
        runner.summary.mission = self.feed.mission_name = mission.name
        setup_tree(mission.root, lambda: mission.setup(runner))  # what shutdown_nodes closes
        self._forces.release_all(runner)  # the nodes are gone: released with them
        self.state.breakpoints.clear()
        self.state.held_end = ""
        self.feed.set_tree(mission.root, live_names(mission))
        self._said(runner, "reload", f"reloaded {mission.name}: the new tree starts from its root")
        self.state.paused = was_paused
        if not was_paused:  # the reload's own pause lasts no frame: nothing to count down
            self.state.paused_tick = None
            self._sleep.end()
        runner.clock_held = was_paused
        runner.wall_limit.hold(was_paused)
        self._skip_tick = True
        # the new tree sets its own modes, from Passive: now, or when a paused run resumes
        # (which sends nothing back: neither the old tree's mode nor its wheel commands)
        self._mode_before_pause = self._cycle_before_pause = None
        if not was_paused:
            self.state.pause_reason = ""

    def check_reloadable(self, mission: Any) -> str | None:
        """Why ``mission`` cannot replace the running one, or None."""
        missing = sorted(set(mission.packets) - self.stream_packets)
        if self.stream_packets and missing:
            return (
                f"it reads packets {missing} that this run does not stream; restart the run "
                "to use it"
            )
        return None


def breakpoint_met(
    feed: RunFeed, breakpoints: Mapping[int, str], changed: tuple[int, ...]
) -> tuple[int, str, int] | None:
    """The first node of ``changed`` (flipped on the feed's newest tick) whose breakpoint
    that flip meets, with what the breakpoint waited for (:data:`BREAK_ON`) and the tick;
    None. A start is RUNNING from another status, or SUCCESS or FAILURE straight from
    INVALID (a node that started and ended in one tick); before a tree's first tick (or a
    new tree's), every node was INVALID."""
    record = feed.latest()
    if record is None:
        return None
    statuses = record.statuses
    previous = feed.record(record.seq - 1)
    before_all = (
        previous.statuses if previous is not None and previous.tree == record.tree else None
    )
    for index in changed:
        on = breakpoints.get(index)
        if on is None:
            continue
        now, before = statuses[index], before_all[index] if before_all else "I"
        started = (now == "R" and before != "R") or (before == "I" and now in "SF")
        if (
            (on == "start" and started)
            or (on == "success" and now == "S")
            or (on == "failure" and now == "F")
            or (on == "end" and now in "SF")
        ):
            return index, on, record.tick
    return None


def _cannot_keep_awake() -> str:
    return (
        "this link cannot keep the robot awake: the run ends "
        f"{duration_words(ROBOT_SLEEPS_S)} into the pause"
    )


def sleep_countdown(ticks_left: int) -> str:
    """The paused banner's countdown (:attr:`SessionState.sleep_note`) for a robot that
    sleeps in ``ticks_left`` stream ticks, in whole seconds rounded up ("0 s left" only once
    it is due): a new text once a second, which the page is sent as it changes."""
    left = duration_words(math.ceil(max(0, ticks_left) * SLOT_SECONDS))
    return f"{_cannot_keep_awake()}; {left} left"


def sleep_warning(paused_s: float, left_s: float) -> str:
    """The event log's and the terminal's warning :data:`SLEEP_WARNING_S` into the pause."""
    return (
        f"paused {duration_words(paused_s)} without keep-awake: the robot sleeps after "
        f"{duration_words(ROBOT_SLEEPS_S)} paused in Passive (in {duration_words(left_s)}; "
        "the run then ends, connection lost); resume or stop"
    )


class SleepCountdown:
    """A pause's countdown to the robot's sleep: an OI robot sleeps after
    :data:`ROBOT_SLEEPS_S` in Passive, and the run then ends (CONNECTION LOST, "the robot
    fell asleep"), on a link that cannot keep it awake (:func:`_sleeps_in_passive`). From
    the pause's tick, the page's banner counts down (:attr:`SessionState.sleep_note`, a
    new text once a second) and, :data:`SLEEP_WARNING_S` into the pause, the event log and
    the terminal's log, which have no countdown, warn once. The tick thread's alone."""

    def __init__(self, state: SessionState, feed: RunFeed) -> None:
        self._state = state
        self._feed = feed
        #: the stream's tick at which the paused robot is warned of (None: not paused,
        #: warned already, or it does not sleep)
        self._warn_tick: int | None = None
        #: the stream's tick at which it sleeps (None: not paused, or it does not sleep)
        self._sleep_tick: int | None = None

    def begin(self, tick: int | None) -> None:
        """A pause from the stream's ``tick`` in which the robot sleeps; None: one in which
        it does not (keep-awake, a replay, a reload's pause that lasts no frame)."""
        if tick is None:
            self._warn_tick = self._sleep_tick = None
            return
        self._warn_tick = tick + round(SLEEP_WARNING_S / SLOT_SECONDS)
        self._sleep_tick = tick + round(ROBOT_SLEEPS_S / SLOT_SECONDS)
        self._state.sleep_note = sleep_countdown(round(ROBOT_SLEEPS_S / SLOT_SECONDS))

    def end(self) -> None:
        """The pause is over (or lasted no frame): nothing to count down to."""
        self._warn_tick = self._sleep_tick = None
        self._state.sleep_note = ""

    def paused_frame(self, snapshot: Snapshot) -> None:
        """A frame of the pause: the banner's countdown, and the warning once it is due."""
        tick = snapshot.tick
        if self._sleep_tick is not None:
            self._state.sleep_note = sleep_countdown(self._sleep_tick - tick)
        if self._warn_tick is None or tick < self._warn_tick:
            return
        self._warn_tick = None
        left = (self._sleep_tick - tick) * SLOT_SECONDS if self._sleep_tick is not None else 0.0
        paused = (tick - (self._state.paused_tick or 0)) * SLOT_SECONDS
        text = sleep_warning(paused, left)
        self._feed.event("warning", text, snapshot.time, tick)
        log.warning("monitor: %s", text, extra=IN_THE_EVENT_LOG)  # in the terminal's log too


def _sleeps_in_passive(connection: Any) -> bool:
    """Whether the robot falls asleep in a long pause: a robot that sleeps after 5 minutes in
    Passive, on a link without keep-awake (off, ``--no-keep-awake``, or a pty or plain socket
    that has no line to pulse)."""
    if not getattr(connection.profile, "sleeps_in_passive", False):
        return False
    wake = getattr(connection, "wake", None)
    return wake is None or wake.unavailable is not None


class Forces:
    """The conditions the operator forced: each node's ``update`` replaced by one that
    answers the status chosen (an instance attribute, found before the class's ``update``,
    removed to release it), the page's list of them (:attr:`SessionState.forced`, ``forced``
    here), and the summary's entry of each (``forced``), with the ticks it was forced and
    released at. The tick thread's alone."""

    def __init__(self, forced: dict[int, str], feed: RunFeed) -> None:
        self._forced = forced
        self._feed = feed
        #: each forced node's entry in the summary's ``forced``, until it is released
        self._entries: dict[int, int] = {}

    def force(self, runner: MissionRunner, index: int, value: str) -> str | None:
        """Force node ``index`` to ``value`` (``success``, ``failure``; ``none`` releases
        it); what the event log says of it, or None: a release of a node not forced (two
        releases queued: the first did it)."""
        node = self._feed.nodes[index]
        name = self._feed.infos[index].name
        if value == "none":
            if index not in self._forced:
                return None
            node.__dict__.pop("update", None)
            node.feedback_message = ""
            self._forced.pop(index, None)
            text = f"{name} no longer forced"
        else:
            status = FORCEABLE[value]
            said = f"forced to {status.value} by the operator"

            def forced() -> Status:
                # said where the result is read: a mission failed by it says so in its
                # summary (it read as the sensor's own failure)
                node.feedback_message = said
                return status

            node.__dict__["update"] = forced
            self._forced[index] = value
            text = f"{name} forced to {status.value}"
        self._summarise(runner, index, f"{name} to {value.upper()}" if value != "none" else "")
        return text

    def release_all(self, runner: MissionRunner) -> None:
        """The tree is replaced (a reload): its nodes gone, their forces with them, each
        said released in the summary."""
        for index in list(self._entries):
            self._summarise(runner, index, "")
        self._forced.clear()

    def said_in_a_success(self, runner: MissionRunner) -> None:
        """A mission that ends in SUCCESS with a condition forced (still returning what the
        operator chose): its summary says so, as a failure's reason does ("battery(below=15%):
        forced to SUCCESS by the operator"); it read as the mission's own success."""
        nodes, infos = self._feed.nodes, self._feed.infos
        forced = [
            f"{infos[i].name}: forced to {FORCEABLE[v].value} by the operator"
            for i, v in sorted(self._forced.items())
            if nodes[i].status is FORCEABLE[v]
        ]
        if forced:
            runner.summary.reason = "; ".join(forced)

    def _summarise(self, runner: MissionRunner, index: int, forced: str) -> None:
        """Every force into the summary (``forced``: "NAME to SUCCESS", or "" for a
        release), with its ticks: it named only one still forced at the end, and a SUCCESS
        forced and released before it went unsaid, though the run may have turned on it."""
        entries = runner.summary.forced
        at = (
            f"tick {runner.snapshot.tick} (t={runner.snapshot.time:.3f} s)"
            if runner.has_snapshot
            else "the start"
        )
        was = self._entries.pop(index, None)
        if was is not None:
            entries[was] += f", {'released' if not forced else 'until'} at {at}"
        if forced:
            self._entries[index] = len(entries)
            entries.append(f"{forced} at {at}")


def _standing(runner: MissionRunner) -> list[Command]:
    """The actuators' commands as the tree left them (its actions sent theirs once), to
    send again on a resume: not Play or Buttons (they would play or press again). A wheel
    or motor command from before the robot's own fall to Passive is not among them: the
    run forgets it at the fall (runtime/loop.py ``FALL_STOPS``; a resume sent the forward
    drive that took the robot over the edge)."""
    return [c for c in runner.last_sent.values() if c.spec.sets_state]


def _on_home_base(runner: MissionRunner) -> bool:
    """Whether the run's last frame shows the robot on its home base (packet 34)."""
    if not runner.has_snapshot:
        return False
    try:
        return bool(runner.snapshot.frame.charging_sources.home_base)
    except (AttributeError, LookupError):  # a stream without packet 34
        return False


def _note(runner: MissionRunner, act: dict[str, Any]) -> None:
    """Mark an operator's act in the record (``run --record``), with the tick it was done at,
    so that a replay does it at the same place (:mod:`roomba_bt.monitor.recorded`)."""
    note = getattr(runner.connection.transport, "note", None)
    if callable(note):
        note({**act, "tick": runner.snapshot.tick if runner.has_snapshot else 0})


def _on(value: object) -> str:
    return {"start": "starts", "success": "ends in SUCCESS", "failure": "ends in FAILURE",
            "end": "ends"}.get(str(value), str(value))  # fmt: skip
