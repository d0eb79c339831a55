"""``roomba-bt monitor RECORD.jsonl``: a recorded run, replayed into a feed for the page.

The record's sensor bytes go through the same parser, mode model and tree as ``replay`` does
(:class:`~roomba_bt.runtime.recording.ReplayTransport`), and every tick is kept, packed
(:mod:`roomba_bt.monitor.history`), so the page's timeline covers the whole run. A record
holds no simulator truth: the path is the odometry, drawn in the world a simulator run's
record names (:func:`recorded_world`) from where the robot started in it.

The operator's acts are in the record as notes, each with the tick it was done at and in which
half of that frame (before or after the tick): pause, resume, a condition forced. The replay
does each at the same place through the same session as the live run (:class:`ReplayedActs`),
so the bytes it writes stay the recorded ones and a pause shows as it happened: the stream's
ticks go on, the tree is frozen and mission time stands still until the resume. A reload
(``run --watch``) ends the replay there: the record has no copy of the new mission. Notes
without a tick (records made before they had one) are only shown as events. ``roomba-bt
replay`` does the acts through the same session (:func:`operator_replay`), without a page.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, Self

from roomba_bt.monitor.feed import Ending, RunFeed
from roomba_bt.monitor.session import STEP, MonitorSession
from roomba_bt.printable import escaped
from roomba_bt.runtime.display import live_names
from roomba_bt.runtime.loop import StopRequested
from roomba_bt.runtime.recording import (
    ENDED,
    RECORD_STOPPED,
    SIMULATOR,
    STILL_WRITTEN,
    Record,
    ReplayTransport,
    ending_text,
    header_text,
    held_to_record,
    record_holder,
    recorded_path,
)
from roomba_bt.runtime.stack import past_the_link_loss, replay_record
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.runtime.tick_guard import CYCLE_NOTE, STILL_NOTE

if TYPE_CHECKING:
    from roomba_bt.runtime.loop import MissionRunner
    from roomba_bt.sim.world import World


def replay_into_feed(
    record: Record,
    mission: Any,
    profile: Any,
    packets: tuple[int, ...],
    baud: int,
    name: str,
    progress: Callable[[float], None] | None = None,
    diverged_at: Callable[[str], None] | None = None,
    window: tuple[float, float | None] = (0.0, None),
) -> tuple[RunFeed, RunSummary]:
    """Replay ``record`` through ``mission``; the feed holds every tick, packed
    (``monitor/history.py``). ``progress(fraction)``: at each tenth of the record replayed;
    ``diverged_at(text)``: where the replay diverged from the record, if it did (the command
    line says it on stderr, as ``replay`` does). ``window``: the mission time from which
    ticks are kept, and the one the replay ends at (None: the record's end; ``--from``,
    ``--to``); the ticks before it are replayed all the same (the tree's state there is
    the recorded run's only so), and their events kept."""
    keep_from, until = window
    feed = RunFeed(
        source="record", mission_name=mission.name, packed_from=keep_from,
        robot=record.header.get("port") or "", started=recorded_start(record),
        label=record.label,
    )  # fmt: skip
    feed.set_tree(mission.root, live_names(mission))
    with MissionWordsOnThePage(feed), ActsOnThePage():  # the page says them; stderr: trouble
        summary, transport, lost = replay_judged(
            record, mission, profile=profile, packets=packets, baud=baud, name=name,
            gate=ReplayedActs(feed, recorded_acts(record)),  # it records each tick in the feed
            raise_interrupts=False,  # Ctrl-C: the monitor shows the summary, as `replay` does
            progress=progress, until=until,
        )  # fmt: skip
    for t, note in record.notes:
        # the tick guard's: shown as the run had it (the end note: below, with the end)
        if not isinstance(note.get("tick"), int) and ENDED not in note:
            feed.event("force" if "force" in note else "note", _note_text(note), t)
    # a Ctrl-C or SIGTERM while the record was read cut the replay short: its safe stop is
    # no difference from the record (the command ends there: monitor_cmd)
    cut_short = summary.outcome is Outcome.INTERRUPTED
    difference = diverged(summary, transport) if lost is None and not cut_short else None
    if difference is not None and diverged_at is not None:
        diverged_at(difference)
    finished = how_the_replay_ended(record, summary, difference, feed, transport.ended_early, lost)
    # what the recorded run's safe stop left the robot in: the replay wrote the same stop
    # (checked against the record), where the record holds the run's end and no difference
    # (nor a link lost: the recorded run's stop went into its failed link, the replay's not)
    told = difference is None and lost is None and not record.being_written
    told = told and record.recording_stopped is None and not transport.ended_early
    whole = told and record.ending is not None
    # the robot panel's title says a killed run's last tick is all the record has, as the
    # banner does (it said "its last tick before the run ended", an end the record lacks)
    unended = told and record.ending is None and record.end_said() is not None
    feed.end(finished, Ending.of(summary) if whole else None, NO_END if unended else None)
    return feed, summary


def replay_judged(
    record: Record, mission: Any, *, name: str, **replayed: Any
) -> tuple[RunSummary, ReplayTransport, tuple[str, str] | None]:
    """``record`` replayed (:func:`~roomba_bt.runtime.stack.replay_record`, given
    ``replayed``), with what ``replay`` and ``monitor RECORD`` both say of its end: ``lost``,
    the two sentences of :func:`~roomba_bt.runtime.stack.past_the_link_loss` where the
    recorded run lost its link (None for any other ending). There the replay's own stop is
    no robot's: its reports are dropped (:class:`ReplayStopReports`) and the summary says
    how the recorded run ended (:func:`recorded_loss_said`). ``replay`` printed ``ERROR ...
    the stop was written but is unconfirmed`` and ``outcome CONNECTION LOST (the safe stop
    did not reach the robot ...)`` of a replay that reaches no robot, where the monitor
    already said neither: one rule for both. So is the replay's start: its connection's INFO
    lines only at ``-v`` (:class:`QuietReplayStart`)."""
    # the replay's start (its banner, a mode change by itself) is said only at -v: the
    # record's summary and page say it, and stderr is for what went wrong
    with ReplayStopReports(f"replay:{name}") as stop_reports, QuietReplayStart(f"replay:{name}"):
        summary, transport = replay_record(record, mission, name=name, **replayed)
    # a difference past where the recorded run's link failed is none (replay's own words)
    lost = past_the_link_loss(transport, transport.first_difference(), record.ending)
    if lost is None:  # any other ending: the replay's stop is said as before
        stop_reports.say()
    elif record.ending is not None:
        recorded_loss_said(summary, record.ending)
    return summary, transport, lost


#: the summary's ``safe stop`` line of a replay whose recorded run lost its link
NO_STOP_REPLAYED = (
    "not replayed: the recorded run's stop went into its failed link, and the record holds "
    "nothing past there (the replay's own stop reached no robot)"
)


def recorded_loss_said(summary: RunSummary, ending: dict[str, Any]) -> None:
    """The summary of a replay whose recorded run lost its link (``ending``: the record's end
    note) says that run's ending, in its outcome and reason, and that its stop is not in
    the record; the final mode is the recorded run's last seen, its stop not delivered.
    It said the replay's own: "CONNECTION LOST (the safe stop did not reach the robot (the
    run had ended: input ended: end of the record))", "NOT DELIVERED: ... written but is
    unconfirmed"."""
    ended, reason = ending.get(ENDED), ending.get("reason")
    outcomes = {outcome.value: outcome for outcome in Outcome}
    summary.outcome = outcomes.get(str(ended), summary.outcome)
    summary.reason = f"the recorded run's: {reason}" if isinstance(reason, str) and reason else ""
    summary.safe_stop = NO_STOP_REPLAYED
    summary.stop_delivered = False


class _OnLogger(logging.Filter):
    """A filter on the logger :attr:`LOGGER` for as long as a ``with`` block runs."""

    LOGGER = "roomba_bt"

    def __enter__(self) -> Self:
        logging.getLogger(self.LOGGER).addFilter(self)
        return self

    def __exit__(self, kind: object, *_: object) -> None:
        logging.getLogger(self.LOGGER).removeFilter(self)


def _said_at_v() -> bool:
    """Whether ``-v`` (or a program's DEBUG logging) asks for every line."""
    return logging.getLogger().isEnabledFor(logging.DEBUG)


class QuietReplayStart(_OnLogger):
    """The replay's connection's INFO lines (``replay:FILE: iRobot Create 2 in Passive,
    streaming [...]``, a mode change by itself) kept off stderr while a record is replayed
    (``replay``, ``monitor RECORD``: :func:`replay_judged`): the summary, the page and its
    banner say them, and a user replaying a record wants a quiet terminal unless something
    is wrong (docs/monitor.md and docs/runtime.md say what stderr shows), not the banner
    for every record. A warning or worse is said as before,
    and so is everything at ``-v``."""

    LOGGER = "roomba_bt.robot.connection"

    def __init__(self, link: str) -> None:
        super().__init__()
        self.prefix = f"{link}: "

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING or _said_at_v():
            return True
        return not record.getMessage().startswith(self.prefix)


class MissionWordsOnThePage(_OnLogger):
    """The mission's log (``roomba_bt.mission``: its ``log`` leaves, its behaviours'
    warnings) into the record's page while ``monitor RECORD`` replays it, not onto stderr:
    it printed every ``log`` line of the recorded run there, without its time, before the
    page's URL. A warning or worse goes into the page's event log, as a live run's page has
    it (:class:`~roomba_bt.monitor.feed.EventLogHandler`); a ``log`` at ``info`` is on the
    page as its leaf's status change (``log(text) -> SUCCESS``). At ``-v`` each is said on
    stderr too. ``replay`` says them on stderr as the run did: it has no page."""

    LOGGER = "roomba_bt.mission"

    def __init__(self, feed: RunFeed) -> None:
        super().__init__()
        self.feed = feed

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING:
            self.feed.event("warning", record.getMessage())
        return _said_at_v()


class ActsOnThePage(_OnLogger):
    """The replayed operator acts' log lines (``monitor: pause (paused by the operator):
    safe stop replayed drive, ...``) kept off stderr while ``monitor RECORD`` replays a
    record: the page's event log has each at its tick, and stderr is for what went wrong (a
    record with a pause and three steps printed nine INFO lines before the page's URL). A
    warning is said as before, and every line at ``-v``. ``replay`` says them: it has no
    page."""

    LOGGER = "roomba_bt.monitor.session"

    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= logging.WARNING or _said_at_v()


class ReplayStopReports(_OnLogger):
    """The replay's own safe stop's reports (``robot/ending.py``'s log, naming the replay's
    link, ``link``), held back while a record is replayed (:func:`replay_judged`: the page's
    and ``replay``'s): :meth:`say` lets them out, and a replay that leaves without it drops
    them. A record whose run lost its
    link holds nothing past there, so the replay's stop, written to no robot, is always
    "written but unconfirmed": ``monitor RECORD`` printed that ERROR on stderr, of a robot
    "last seen spinning", under a view that said in its own words that the recorded run
    lost its link (its banner, its event log: what each side wrote past there), and whose
    recorded run's stop had gone into a failed port, not been "unconfirmed". A replay
    that ends in any other way says them as before (:meth:`say`); one left by an exception
    too."""

    LOGGER = "roomba_bt.robot.ending"

    def __init__(self, link: str) -> None:
        super().__init__()
        self.prefix = f"{link}: "
        self.held: list[logging.LogRecord] = []

    def filter(self, record: logging.LogRecord) -> bool:
        if record.getMessage().startswith(self.prefix):
            self.held.append(record)
            return False
        return True

    def __exit__(self, kind: object, *_: object) -> None:
        super().__exit__(kind)
        if kind is not None:
            self.say()

    def say(self) -> None:
        """Log what was held, as it would have been logged."""
        logger = logging.getLogger(self.LOGGER)
        held, self.held = self.held, []
        for record in held:
            logger.handle(record)


#: the world the page draws for a record and where its robot started there (mm, mm, rad:
#: the odometry's 0), or why it draws none (a text for stderr)
DrawnWorld = tuple[dict[str, Any], tuple[float, float, float]]


def recorded_world(
    record: Record, mission: Path, chosen: World | None = None
) -> DrawnWorld | str | None:
    """The world a simulator run's record names (its header's ``simulator.world``: a world's
    name, shipped or of ``ROOMBA_BT_WORLDS``'s, or a file's path from the record's folder,
    found as ``replay`` finds the mission's), drawn as the live page draws it, with the pose
    the robot started at (its seed's, under ``random_start``): the recorded page drew the
    bare odometry, in its own frame, with no rooms, furniture or dock. ``chosen``: the world
    the user gave instead (``monitor --world``), drawn whatever the record names, a robot's
    record too. None for a robot's record; a text saying why when the world named cannot be
    read (the page then draws the odometry alone).

    A world file is read only inside the folder that holds the record and its ``mission``
    (the file replayed), as the record's include folders are, or in a folder of the user's
    worlds (:func:`~roomba_bt.sim.world.world_folders`): a record from someone else named
    ``/etc/shadow`` as its world, and the world's errors quoted its lines."""
    from roomba_bt.monitor.views import world_drawing
    from roomba_bt.sim.world import WorldError, load_world

    options = record.header.get(SIMULATOR)
    options = options if isinstance(options, dict) else {}
    if chosen is None:
        name = options.get("world")
        if not isinstance(name, str):
            return None
        shown = header_text(name)
        try:
            where = _recorded_world_file(name, record, mission)
            if not isinstance(where, str):
                where = _same_world(where, options.get("world_sha256")) or where
            if isinstance(where, str):
                return f"its world {shown}{where}; the page draws the odometry alone"
            chosen = load_world(where)
        except WorldError as exc:
            return f"its world {shown}: {escaped(str(exc))}; the page draws the odometry alone"
    seed = options.get("seed")
    start = (
        chosen.sample_start(seed)
        if options.get("random_start") and isinstance(seed, int)
        else chosen.start
    )
    return world_drawing(chosen), (start.x, start.y, start.theta)


#: how a world the record names and the monitor does not read can be drawn all the same
OWN_WORLD = "monitor --world FILE_OR_NAME draws the one you give"


def _recorded_world_file(name: str, record: Record, mission: Path) -> Path | str:
    """The file of the world ``name`` a record's header names, or why none is read (a text
    following ``its world NAME``): a path beside the record, held to the folder holding the
    record and its ``mission`` or to one of the user's world folders (a record made before
    worlds were named wrote a ``ROOMBA_BT_WORLDS`` world's path); a name, found where
    ``run --world`` finds one."""
    from roomba_bt.sim.world import named_world, world_folders

    where = recorded_path(name, record.header, record.path)
    if where is not None and (where.is_file() or "/" in name):
        holder = record_holder(record.path, mission)
        yours = where.suffix == ".yaml" and any(
            where.resolve().parent == folder.resolve() for folder in world_folders()
        )
        if yours or held_to_record(where, holder):
            return where
        return (
            " is outside the folder that holds the record and its mission "
            f"({header_text(str(holder))}): a record names only worlds there, in your world "
            f"folders or by name; not read ({OWN_WORLD})"
        )
    # a world's name (``apartment``), as ``run --world`` took it: a shipped world or the
    # user's own (ROOMBA_BT_WORLDS); never a file from the current folder
    found = named_world(name)
    if found is None:
        return f": no such world beside the record, nor a world of that name ({OWN_WORLD})"
    return found


def _same_world(found: Path, recorded: object) -> str | None:
    """Why the world file ``found`` is not the one the run used (a text following ``its
    world NAME``), or None when it is, or when the record holds no digest to tell (one made
    before its header held ``world_sha256``). A world found by its name, or where the record
    says, may be another of that name (a ``ROOMBA_BT_WORLDS`` world that takes a shipped
    one's name, another machine's) or the file edited since; drawn, the page showed the
    recorded robot driving through walls that were not there. Not drawn: a
    ``monitor --world`` given is drawn, the user's own choice."""
    from roomba_bt.runtime.provenance import file_digest

    if not isinstance(recorded, str):
        return None
    now = file_digest(found)
    if now is None or now == recorded:  # unreadable: load_world says why
        return None
    return (
        f" ({header_text(str(found))}) is not the file the run used: its SHA-256 is "
        f"{now[:12]}..., the record's {header_text(recorded[:12])}... (edited since, or another "
        f"world of that name); not drawn ({OWN_WORLD})"
    )


def recorded_start(record: Record) -> datetime | None:
    """When the recorded run started (its header's ``started``), for the page's header; None
    for a record made before it was written, or one whose text is no ISO 8601 time."""
    text = record.header.get("started")
    try:
        return datetime.fromisoformat(text) if isinstance(text, str) else None
    except ValueError:
        return None


def recorded_acts(record: Record) -> list[dict[str, Any]]:
    """The operator's acts ``record`` notes with the tick they were done at (pause, resume, a
    step, a force, a reload), in the order they were done; the tick guard's (its acts and
    the still ticks it saw) are replayed by the runner's own guard, and the end note by the
    replay's end."""
    return [
        note
        for _, note in record.notes
        if isinstance(note.get("tick"), int)
        and "tick_guard" not in note
        and STILL_NOTE not in note
        and CYCLE_NOTE not in note
        and ENDED not in note
    ]


#: the ticks a replay without a page keeps in its feed (:func:`operator_replay`)
OPERATOR_REPLAY_HISTORY = 2


def operator_replay(record: Record, mission: Any) -> ReplayedActs | None:
    """The gate that does ``record``'s operator acts again where the live run did them, for
    ``replay``, which has no page (its feed keeps the last two ticks: a breakpoint's pause
    is in the record as a pause, so none is looked for); None for a record without them.
    Before, ``replay`` did none: a paused run's record differed at its first pause, and the
    replay pointed to ``roomba-bt monitor RECORD``, which did them. A session of the
    monitor's, so it lives here; ``replay`` (the command line) is above both."""
    acts = recorded_acts(record)
    if not acts:
        return None
    feed = RunFeed(source="record", mission_name=mission.name, history=OPERATOR_REPLAY_HISTORY)
    feed.set_tree(mission.root)
    return ReplayedActs(feed, acts)


#: the robot panel's word for a record without its run's end (:meth:`Record.end_said
#: <roomba_bt.runtime.recording.Record.end_said>` is the banner's): ``Robot: its last
#: recorded tick (no end recorded: the run was killed, or writing its record failed)``
NO_END = "no end recorded: the run was killed, or writing its record failed"


def how_the_replay_ended(
    record: Record,
    summary: RunSummary,
    difference: str | None,
    feed: RunFeed,
    ended_early: bool = False,
    lost: tuple[str, str] | None = None,
) -> str:
    """What the record view says of the end (its banner, and the event log): where the
    replay diverged from the record, if it did (``difference``: where, what was expected,
    what was sent; the timeline ends there, as ``replay`` says it: it said only "input
    ended"), else that the recorded run lost its link there (``lost``:
    :func:`~roomba_bt.runtime.stack.past_the_link_loss`, as ``replay`` says it: it said
    "replay diverged ... expected nothing, sent Drive (137)"), else where its window ended
    (``ended_early``: ``--to``), else how the recorded run ended (its end note: "the
    recorded run was stopped by the operator at t=44.17 s"),
    else that the record ends without its run's end (as ``replay`` says it:
    :meth:`Record.end_said <roomba_bt.runtime.recording.Record.end_said>`), else the
    replay's outcome."""
    ticks = f"recorded run, {summary.ticks} ticks"
    if difference is not None:
        feed.event("warning", difference)
        return f"{difference} ({ticks})"
    if lost is not None:
        if record.ending is not None:
            feed.event("control", ending_text(record.ending))
        for said in lost:
            feed.event("control", said)
        return f"{lost[0]} ({ticks})"
    if ended_early:
        text = (
            f"shown up to t={summary.mission_time_s:.2f} s of mission time (--to); the "
            f"record goes on to t={record.last_t:.2f} s"
        )
        feed.event("control", text)
        return f"{text} ({ticks})"
    stopped = record.recording_stopped
    if stopped is not None:  # the run went on: how it ended is not in the record
        text = f"the recording stopped at t={record.last_t:.2f} s ({stopped}); the run went on"
        return f"{text} ({ticks})"
    if record.being_written:  # its end is where the run had got to when it was read
        text = f"{STILL_WRITTEN}: shown up to t={record.last_t:.2f} s"
        feed.event("warning", text)
        return f"{text} ({ticks})"
    ending = record.ending
    if ending is not None:
        text = ending_text(ending)
        feed.event("control", text)
        return f"{text} ({ticks})"
    unended = record.end_said()  # replay's words: it said "input ended" of a killed run
    if unended is not None:
        feed.event("warning", unended)
        return f"{unended} ({ticks})"
    return f"{summary.outcome.value} ({ticks})"


def diverged(summary: RunSummary, transport: ReplayTransport) -> str | None:
    """``replay diverged from the record at t=75.36 s: expected Motors (138) 8a 07, sent
    nothing; the timeline ends there``, or None when the replay wrote what the record holds
    (up to where it ends)."""
    difference = transport.first_difference()
    if difference is None:
        return None
    _, expected, sent = difference
    return (
        f"replay diverged from the record at t={summary.mission_time_s:.2f} s: expected "
        f"{expected}, sent {sent}; the timeline ends there"
    )


def _note_text(note: dict[str, Any]) -> str:
    if RECORD_STOPPED in note:
        return f"the recording stopped ({note[RECORD_STOPPED]}): the record ends here"
    if "watchdog" in note and isinstance(note["watchdog"], int | float):  # a trip, replayed
        return f"watchdog: no valid sensor frame for {note['watchdog'] * 1000:.0f} ms"
    if "baud" in note:  # the port's rate changed (the record's own note)
        cut = f", cut short by {note['cut_short']}" if "cut_short" in note else ""
        return f"the port set to {note['baud']} baud{cut}"
    if "force" in note:
        to = note.get("to")
        return f"{note['force']} forced to {to}" if to != "none" else f"{note['force']} released"
    return ", ".join(f"{k}={v}" for k, v in note.items())


class ReplayedActs(MonitorSession):
    """The live run's session, its requests taken from the record's notes instead of a page:
    each act is done in the frame (and the half of it) it was done in live. Its commands go
    to the record's check, never to a robot: the event log says "replayed", not "sent"."""

    SENT, WHERE = "replayed", " (the record's: checked against it, sent to no robot)"
    WARN_OF_SLEEP = False  # the run's own warning is not in the record; no robot sleeps here

    def __init__(self, feed: RunFeed, acts: list[dict[str, Any]]) -> None:
        super().__init__(feed, simulator=False, allow_force=True)
        self._acts = deque(acts)  # in the record's order, which is the order they were done

    def before_tick(self, runner: MissionRunner) -> bool:
        self._replay(runner, "before")
        return super().before_tick(runner)

    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        self._replay(runner, "after")

    def _replay(self, runner: MissionRunner, half: str) -> None:
        acts, tick = self._acts, runner.snapshot.tick
        while acts and (
            acts[0]["tick"] < tick or (acts[0]["tick"] == tick and acts[0].get("at") == half)
        ):
            act = acts.popleft()
            if "pause" in act and not self.state.paused:
                self._pause(runner, str(act["pause"]), half)
            elif "resume" in act and self.state.paused:
                if act["resume"] == STEP:  # a step, as live: the clock held after its tick
                    self._step(runner)
                else:
                    self._resume(runner, str(act["resume"]))
            elif "force" in act and isinstance(act.get("node"), int):
                if 0 <= act["node"] < len(self.feed.nodes) and act.get("to") in (
                    "success", "failure", "none",
                ):  # fmt: skip
                    self._force(runner, act["node"], str(act["to"]))
            elif "reload" in act:
                self.feed.event("reload", f"the run reloaded its mission ({act['reload']}) here: "
                                "the record has no copy of it, so the replay ends")  # fmt: skip
                raise StopRequested("the recorded run reloaded its mission here")
