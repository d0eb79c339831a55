"""How a run ended, the exit code that says so, and the figures printed at the end of every
run."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum, IntEnum
from typing import TYPE_CHECKING

from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.frames import BATTERY_PACKETS, SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.printable import (
    ANY_CONTROL,
    duration_said,
    duration_words,
    escaped,
    shortened,
)
from roomba_bt.robot.interface import UNKNOWN_CAUSE

if TYPE_CHECKING:
    from roomba_bt.robot.interface import Snapshot

#: Seconds a run waits, after the watchdog stopped the wheels, for valid frames to come back
#: before it ends as a lost connection, exit 8 (``run --grace``).
DEFAULT_GRACE = 2.0
#: The summary's ``safe stop`` first words for a stop written to a robot asleep whose frames
#: had shown it stopped before it slept (a long pause on a link without keep-awake): it does
#: not move, and "NOT DELIVERED:" in capitals is kept for a robot that may (the exit code is
#: the lost connection's all the same: the run ended on the sleep)
ASLEEP_STOPPED = "asleep and stopped"
#: ... and for any other stop not known delivered (the port gone, the robot silent, the port
#: failed while the stop was listened after) to a robot whose frames, sent after every
#: command written, showed it stopped (its requested wheel speeds at 0 / packet 35 reading
#: Passive, no brush nor the vacuum left running, no built-in cycle): nothing was written
#: since that could set it going (not "NOT DELIVERED:": the capitals are for a robot that
#: may be moving)
SEEN_STOPPED_FIRST = "seen stopped"
#: What ``final mode`` adds after a mode the run's stream never showed: packet 35 not in it
#: (a program's own packet list), the mode is only what the run wrote, the mode model's
#: (without it, the mode reads as if the robot had shown it)
MODEL_ONLY = " (not in the stream: the run's own model)"

#: ``run --tick-limit`` default, seconds (runtime/tick_guard.py): 17 stream slots; at
#: 500 mm/s, 12.5 cm driven blind
DEFAULT_TICK_LIMIT = 0.25


class ExitCode(IntEnum):
    """Exit codes of every ``roomba-bt`` command, the one table (``docs/runtime.md``, "Exit
    codes"): each command exits with one of these, and no two mean different things; a
    command's ``--help`` lists those it uses. ``run``'s are its outcomes'; 5 and 6 are
    ``doctor``'s alone (0.1.0 had them in a table of its own, ``DoctorExit``)."""

    OK = 0  # mission succeeded / command did what was asked
    MISSION_FAILED = 1  # the tree ended in FAILURE (or the timeout ran out)
    #: invalid mission, world or command-line usage; for ``run``, also a profile that the
    #: robot's frames show wrong before anything of the mission was written
    #: (``Outcome.WRONG_PROFILE``): a setting, which fails the same way again
    INVALID = 2
    #: could not start: the port could not be opened, the robot did not answer the
    #: start-up, or its stream's first frame never came (``Outcome.NO_CONNECTION``: the tree
    #: never ticked); no command of the mission was sent, so trying
    #: again is safe (systemd's ``Restart=on-failure``, docs/unattended.md). ``sensors``,
    #: ``sim`` and ``eval`` exit 3 for their own connection's failure
    CONNECTION = 3
    #: the link was lost after the run had started (``Outcome.CONNECTION_LOST``): the port
    #: gone, the stream lost, the robot reset or asleep, commands not heard; also a run whose
    #: tree ended well but whose stop did not reach the robot (``note_undelivered_stop``).
    #: The robot may have moved, and the summary's "safe stop" line says whether the stop
    #: reached it: a person should look before it runs again (``RestartPreventExitStatus=``).
    #: Exit 3 said it too before 0.2.0, which a service could not tell from "not started"
    LINK_LOST = 8
    #: a behaviour raised an exception (a bug in it or its plugin), its own ``sys.exit()``,
    #: ``KeyboardInterrupt`` or ``BaseException`` too (``robot/safety.py``: ``code_failure``)
    BEHAVIOUR_ERROR = 4
    #: ``run --strict``: the tree ended in SUCCESS, but the run did what a mission that works
    #: does not (:meth:`RunSummary.strict_findings`: a command the mode guard refused, one
    #: dropped while the tree was stopped, a fall out of Safe/Full by itself). 7, not 5: 5
    #: and 6 are ``roomba-bt doctor``'s (nothing answered; a later step failed). Also
    #: ``validate --strict``: every file valid, but warnings failed one (docs/ci.md)
    STRICT = 7
    #: ``doctor``: nothing answered at any OI rate, even after a BRC pulse (or none could be
    #: given), or the port echoes every byte (docs/doctor.md)
    NO_ANSWER = 5
    #: ``doctor``: the robot answered, but a later step failed (no stream, the link lost, a
    #: reply that makes no sense)
    UNHEALTHY = 6
    #: roomba-bt itself raised (a bug in the runner, the display, the monitor, the record),
    #: not a behaviour: said in one line, the traceback with ``-v``, after the run's port was
    #: closed. 70 is sysexits.h's EX_SOFTWARE ("internal software error"): Python's own exit
    #: for an uncaught exception, 1, read as "the mission failed"
    INTERNAL_ERROR = 70
    INTERRUPTED = 130  # Ctrl-C or SIGTERM, after the safe stop


#: Exit 70 as each command's ``--help`` lists it among its exit codes (every command ends
#: there on roomba-bt's own bug: :func:`roomba_bt.cli._internal_error`), from the table above.
INTERNAL_ERROR_SAID = f"{int(ExitCode.INTERNAL_ERROR)} internal error (a bug in roomba-bt)"


def profile_shown(profile: RobotProfile) -> str:
    """How a summary names the robot profile: ``roomba500 (Roomba 500 series)``, or "" for
    the default (create2), which goes unsaid so that the usual summary reads as it did."""
    return "" if profile.name == DEFAULT_PROFILE.name else f"{profile.name} ({profile.title})"


#: what a SUCCESS at the run's planned length says (``run --duration``): a record's replay
#: ends there as at a time limit (``recording.tree_ended``)
PLANNED_END = "the planned end"


class Outcome(Enum):
    SUCCESS = "success"
    FAILURE = "failure"
    TIMEOUT = "timeout"
    INTERRUPTED = "interrupted"
    CONNECTION_LOST = "connection lost"
    #: the robot never answered the start-up (it was never connected, so nothing was lost),
    #: or the link failed before its stream's first frame (no tick: the mission never
    #: started; 0.1.0 said CONNECTION_LOST, both exit 3)
    NO_CONNECTION = "no connection"
    #: the robot's frames show another model than the profile's (the robot layer's
    #: ``mismatch``) before the run wrote anything of the mission: nothing moved, and a
    #: retry fails the same way until the setting is fixed, so exit 2, a mistake in the
    #: command line, not exit 8, "the link was lost after the run started: a person looks
    #: first". Found after a command of the mission, it stays CONNECTION_LOST
    WRONG_PROFILE = "wrong profile"
    ERROR = "error"
    #: the run ran past its wall-clock limit (``run --wall-limit``, an ``eval`` episode's):
    #: stuck, most often in a behaviour's endless loop. No exception in the tree (nothing
    #: raised: the limit ended it from outside), and a bug all the same, so exit 4 as ERROR
    HUNG = "hung"
    #: the run's input ended before the tree did: a replayed record's end, or its first
    #: difference from what the tree wrote (``replay`` says which, and exits by the bytes)
    INPUT_ENDED = "input ended"

    @property
    def exit_code(self) -> ExitCode:
        """The documented ``roomba-bt run`` exit code (see ``docs/runtime.md``)."""
        return _EXIT[self]


_EXIT = {
    Outcome.SUCCESS: ExitCode.OK,
    Outcome.FAILURE: ExitCode.MISSION_FAILED,
    Outcome.TIMEOUT: ExitCode.MISSION_FAILED,
    Outcome.INTERRUPTED: ExitCode.INTERRUPTED,
    Outcome.CONNECTION_LOST: ExitCode.LINK_LOST,
    Outcome.NO_CONNECTION: ExitCode.CONNECTION,
    Outcome.WRONG_PROFILE: ExitCode.INVALID,
    Outcome.ERROR: ExitCode.BEHAVIOUR_ERROR,
    Outcome.HUNG: ExitCode.BEHAVIOUR_ERROR,
    Outcome.INPUT_ENDED: ExitCode.MISSION_FAILED,
}


class RunFailed(RoombaBtError):
    """A run that did not succeed, raised by :meth:`RunSummary.raise_for_outcome` (as
    requests' ``raise_for_status``): for a program that would rather have an exception than
    read the outcome. ``outcome``, ``reason`` and ``exit_code`` (what ``roomba-bt run`` would
    exit with) say how it ended; ``summary`` is the whole report. The robot was stopped
    before it was raised: the run had ended. A run that a behaviour's or an observer's
    exception ended has that exception as ``__cause__`` (and as :attr:`exception`), so
    Python shows its traceback under this one and a program can test its class; a run the
    link ended, the link's (:attr:`link_error`: ``NoAnswer``, ``PortLost``, ...)."""

    def __init__(self, summary: RunSummary) -> None:
        self.summary = summary
        self.outcome = summary.outcome
        self.reason = summary.reason
        self.exit_code = ExitCode(summary.exit_code)
        #: the exception that ended the run as ERROR (also ``__cause__`` when raised by
        #: :meth:`RunSummary.raise_for_outcome`); None for any other ending
        self.exception = summary.exception
        #: the link's exception that ended the run (a ``ConnectionFailed`` or a
        #: ``LinkDown``; also ``__cause__``); None for any other ending
        self.link_error = summary.link_error
        #: what failed ``--strict`` (``RunStack(..., strict=True)``) in a run whose tree
        #: succeeded; empty for any other failure
        self.findings = tuple(summary.strict_findings()) if summary.failed_strict else ()
        if self.findings:
            reason = f" but failed {summary.strict_named}: {'; '.join(self.findings)}"
        else:
            reason = f": {summary.reason}" if summary.reason else ""
        message = (
            f"mission {summary.mission} ended {summary.outcome.value.upper()}{reason} "
            f"(exit code {int(self.exit_code)})"
        )
        super().__init__(escaped(message, ANY_CONTROL))  # on one line, as the summary's


def falls_in_order(falls: Mapping[str, int]) -> tuple[tuple[str, int], ...]:
    """The falls by cause, the commonest first (then by name): the order a summary says
    them in, and one order for equal counts whichever process counted them."""
    return tuple(sorted(falls.items(), key=lambda item: (-item[1], item[0])))


def falls_said(falls: Mapping[str, int]) -> str:
    """The robot's own falls to Passive by cause, in the words of the run summary's
    ``falls`` line: ``the robot fell to Passive by itself 21 times (cliff 20, wheel drop
    1)``. One wording for a run and for an evaluation's many episodes summed
    (:class:`roomba_bt.evaluate.stats.Summary`), so a user reads the same line in both; a
    summary without falls says none, but prints no ``falls`` line at all."""
    causes = falls_in_order(falls)
    if not causes:
        return "the robot never fell to Passive by itself"
    total = sum(times for _, times in causes)
    said = (
        causes[0][0]
        if len(causes) == 1
        else ", ".join(f"{cause} {times}" for cause, times in causes)
    )
    times = "once" if total == 1 else f"{total} times"
    return f"the robot fell to Passive by itself {times} ({said})"


#: the falls to Passive by themselves that are a mission's expected end, not a hazard met: on
#: a powered charger the OI drops Safe to Passive (a dock run ends so), logged as information
#: and never failing ``--strict``; a cliff, a wheel drop or an unknown cause does
EXPECTED_FALLS = frozenset({"charger"})


def hazard_falls(falls: Mapping[str, int]) -> dict[str, int]:
    """The falls of ``falls`` by cause that are not :data:`EXPECTED_FALLS` (``cliff and
    charger`` is a cliff met on the dock: it counts)."""
    return {cause: times for cause, times in falls.items() if cause not in EXPECTED_FALLS}


def times_said(count: int, what: str) -> str:
    """``1 command``, ``313 commands``."""
    return f"{count} {what}" if count == 1 else f"{count} {what}s"


#: what the author of an action of their own whose commands were refused does about it
#: (``run``'s stderr and ``eval``'s summary say it)
YOUR_ACTION_FIX = (
    "an action that drives checks self.snapshot.mode each tick and, out of Safe/Full, returns "
    "self.wait_for_driving_mode() (roomba-bt docs plugins, When the robot leaves Safe/Full "
    "under your action)"
)


def undeclared_said(key: str, where: str, hint: str = "", episodes: str = "") -> str:
    """The words of a write to an undeclared key, as ``run``'s summary and ``eval``'s say
    it: ``write_key('dirt_levl') by 'probe' at lab.py:10: blackboard key 'dirt_levl' is not
    declared by the mission (did you mean 'dirt_level'?); declare it ...``; ``episodes``:
    eval's ``, in 3 of 20 episodes``. One text, so the two commands say it alike."""
    return (
        f"write_key({key!r}){where}: blackboard key {key!r} is not declared by the mission"
        f"{hint}{episodes}; declare it under blackboard: ({key}: {{type: ...}}), or name a "
        "declared key in a parameter listed in writes_keys"
    )


def first_said(instance: str) -> str:
    """`` (the first: t=3.330 blind_drive: ...)`` after a count; "" when the first is not
    known (a summary a program made itself)."""
    return f" (the first: {instance})" if instance else ""


def long_duration_said(seconds: float) -> str:
    """`` (4 h 12 min 3 s)`` after a number of seconds of a minute or more, for the
    summary's duration line (``43200.00 s`` alone had the reader divide by 3600 after a
    night); "" for a shorter one, whose seconds say it (``3.00 s``)."""
    return f" ({duration_words(seconds)})" if seconds >= 60 else ""


#: the share of the robot's frames lost from which the summary calls the link poor
POOR_LINK = 0.05
#: the frames a run must span (3 s) before the summary judges its link
LINK_VERDICT_SLOTS = 200


@dataclass
class RunSummary:
    """The end-of-run report; every field is measured, none is assumed.

    Long on purpose: two thirds of it are its fields, each with the comment a script's
    author reads (``--json`` and the Python API give them by these names); the text of the
    report is in the short methods below them."""

    mission: str
    outcome: Outcome = Outcome.ERROR
    reason: str = ""
    #: the reason's short first line, where a long one is repeated (the command line's
    #: stderr line under the summary: a wrong profile's fix, its detail said once, here in
    #: :attr:`reason`); "" says the reason whole there too
    headline: str = ""
    mission_time_s: float = 0.0
    wall_time_s: float = 0.0
    ticks: int = 0
    overruns: int = 0
    #: the run's ticks came on a virtual clock (``--fast``, a replay): a tick that took the
    #: host longer than the slot made no tick late, and the ticks line says so
    virtual_clock: bool = False
    stale_frames_dropped: int = 0
    frames_lost: int = 0
    checksum_failures: int = 0
    implausible_frames: int = 0
    skipped_bytes: int = 0
    #: hazard onsets (bump, wheel drop, cliff) the next frame did not confirm: never shown to
    #: the tree (robot/hazards.py); a corrupted frame would have stopped an action for each
    unconfirmed_hazards: int = 0
    refused_commands: int = 0
    #: times the watchdog tripped (drive 0) and the run waited for valid frames; how many
    #: of those the frames came back from within the grace
    stalls: int = 0
    stalls_ridden: int = 0
    #: of the stalls, those whose drive 0 was sent (the wheels turning; the others found
    #: them at rest, and nothing was sent)
    stall_halts: int = 0
    #: gaps of a second or more with no frame read and no watchdog trip (the process
    #: suspended or starved: runtime/clock.py ``unread_gap``), and the longest
    unread_gaps: int = 0
    longest_unread_s: float = 0.0
    #: of :attr:`frames_lost`, those lost in such gaps: the robot streamed on while nothing
    #: read the port, and its buffer, full, dropped them (the host's, not the line's: a
    #: laptop's 45 s suspended said the link poor, 73 % of the frames lost)
    frames_lost_unread: int = 0
    #: ticks that ran over ``--tick-limit`` with the wheels moving, each stopped by the tick
    #: guard (runtime/tick_guard.py); where the first and the last were (the behaviour, its
    #: line)
    tick_halts: int = 0
    #: of :attr:`tick_halts`, those whose drive 0 went out with motors off (a brush or the
    #: vacuum ran): the summary says what was sent
    tick_halts_motors: int = 0
    tick_halt_first: str = ""
    tick_halt_last: str = ""
    #: ticks that ran over ``--tick-limit`` in which the guard sent nothing, with where the
    #: first and the last of each kind were: with nothing moving (``tick_still*``: the robot
    #: at rest, nothing to stop; a log warning only before, when its gap came out a second
    #: or more), or while a built-in cycle (Clean, Spot, Seek Dock) may have driven the
    #: robot in Passive (``tick_cycle*``: the guard ends no cycle; it went on driving)
    tick_stills: int = 0
    tick_still_first: str = ""
    tick_still_last: str = ""
    tick_cycles: int = 0
    tick_cycle_first: str = ""
    tick_cycle_last: str = ""
    #: passes of a program's loop over ``stack.ticks()`` (its body, between two ticks: the
    #: program's own time, not the tree's) that ran over ``--tick-limit``, and of those the
    #: ones the guard stopped the robot in; none of them is among the ticks' counts above
    #: (counted there, they would be said as the tree's "slow tick(s)")
    loop_slow: int = 0
    loop_halts: int = 0
    commands_written: int = 0
    #: times the robot's wheels did not do what the command standing asked for a second (its
    #: encoders), put right by zeros and the command again (runtime/motion_watch.py); of
    #: those, the times the wheels then obeyed (bytes from us had been lost) and the times
    #: they still did not (a robot wedged, or the line lost that too; the others the run
    #: ended or the tree went on from before the next look); the first finding, when and
    #: what (``t=6.390 the wheels stood still for a second under Drive (137) velocity 200,
    #: radius 32768``)
    unheard: int = 0
    unheard_obeyed: int = 0
    unheard_stalled: int = 0
    unheard_first: str = ""
    #: the first command the mode guard refused: when, the behaviour that sent it, and why
    #: (``t=3.330 blind_drive: drive needs Safe or Full; the robot is in Passive since
    #: t=3.330, after a cliff``)
    first_refusal: str = ""
    #: commands that would have set the robot going, sent while the tree was being stopped
    #: (the run's end, the monitor's reload): not written (runtime/ending.py
    #: ``RunEnding.stop_tree``); the first, with its behaviour and when
    dropped_in_stop: int = 0
    first_dropped: str = ""
    #: the robot's first fall out of Safe/Full by itself that was not its expected end
    #: (:data:`EXPECTED_FALLS`): when, why and the leaf that was running
    #: (``t=3.330 in blind_drive: cliff``)
    first_fall: str = ""
    #: why a fall of unknown cause may be the cable's, where the run found bytes to the
    #: robot lost and put right (``Connection.cable_suspected``); "" without that evidence
    falls_cable: str = ""
    #: ``run --strict`` (``RunStack(..., strict=True)``): a run whose tree succeeded exits
    #: :attr:`ExitCode.STRICT` when :meth:`strict_findings` found anything
    strict: bool = False
    #: each blackboard key a behaviour wrote that the mission does not declare, who wrote it
    #: first and where, and the declared key it may be a misspelling of
    #: (``("dirt_levl", " by 'probe' at lab.py:10", " (did you mean 'dirt_level'?)")``):
    #: warned of during the run, said again by the summary (a log line scrolled away, and the
    #: run succeeded), counted by :meth:`strict_findings`
    undeclared_keys: tuple[tuple[str, str, str], ...] = ()
    #: the actions of the user's own code (a plugin's, a program's) whose commands the mode
    #: guard refused, each once, with its class and where it is defined
    #: (``("passive_drive", "PassiveDrive (lab.py:7)")``): told the fix
    #: (``runtime/refusals.py``: ``run``'s stderr, ``eval``'s summary)
    refused_actions: tuple[tuple[str, str], ...] = ()
    distance_mm: float = 0.0
    #: a cycle the robot started by itself (a button, its schedule): it drove in Passive
    #: with no command of the run's, and how the stop ended it (runtime/ending.py
    #: ``RunEnding.robot_cycle``); "" if none was seen
    robot_cycle: str = ""
    final_mode: OIMode | None = None
    #: the run's stream carried the OI mode (packet 35): False, the final mode is the run's
    #: own model of what it wrote, never checked against the robot (:data:`MODEL_ONLY`)
    mode_streamed: bool = True
    battery_percent: float | None = None
    #: the lowest battery level seen, looked at once a second of mission time
    #: (runtime/long_run.py) and at the end; None when the stream did not carry it
    lowest_battery_percent: float | None = None
    #: seconds of mission time the robot spent on a powered charger (packet 34), to the
    #: second (runtime/long_run.py): an overnight patrol's hours of charging
    on_charger_s: float = 0.0
    safe_stop: str = "not attempted"
    #: False when the stop could not reach the robot: the final mode is then only the last
    #: one seen, and says so
    stop_delivered: bool = True
    #: the connection's words of a stop not known delivered (what the robot was last seen
    #: doing, why the stop did not reach it, :attr:`stop_advice`), or "": :attr:`safe_stop`
    #: is them after its headline (``NOT DELIVERED:``, ``seen stopped;``)
    stop_report: str = ""
    #: what to do about the robot that stop left (the port gone: pick it up or press its
    #: Clean or power button; then doctor): the tail of :attr:`stop_report`, or ""
    stop_advice: str = ""
    #: False when no robot answered (no valid frame, no reply; noise is none): its mode is
    #: then not known at all
    robot_answered: bool = True
    #: the stop not known delivered met a robot the run set nothing going for (none
    #: answered, or one seen only in Passive with its wheels never commanded)
    set_nothing_going: bool = False
    #: the stop not known delivered was written to a robot asleep, its frames having shown it
    #: stopped before it slept (a long pause on a link without keep-awake): said
    #: :data:`ASLEEP_STOPPED`, not ``NOT DELIVERED``
    asleep_stopped: bool = False
    #: the stop not known delivered met a robot its frames had shown stopped after every
    #: command written (asleep or not): said :data:`SEEN_STOPPED_FIRST` (or
    #: :data:`ASLEEP_STOPPED`), not ``NOT DELIVERED``
    seen_stopped: bool = False
    max_tick_s: float = 0.0
    #: where the slowest tick was, when a watch could tell (runtime/tick_watch.py: ``run``'s,
    #: on either clock): ``sleepy (Sleepy.update at x.py:98)``; "" otherwise
    slowest_in: str = ""
    #: the slowest tick was the host's: its thread's time on a CPU and waiting for one
    #: (runtime/tick_watch.py: ``3.10 ms of CPU in 100.20 ms, 95.00 ms of it waiting for a
    #: CPU``), said instead of a behaviour it did not spend its time in; "" otherwise
    slowest_host_busy: str = ""
    #: the tick a Ctrl-C or a signal ended the run in, when it had run past its slot in a
    #: behaviour (runtime/teardown.py ``cut_short``: ``in a tick that had run 19.66 s, in
    #: behaviour sequence / hang (at bad.py:30)``), which the reason says; "" otherwise
    cut_short: str = ""
    #: the exception's traceback when a behaviour raised one (printed under ``-v``)
    traceback: str = ""
    #: the exception itself that ended the run as ERROR (a behaviour's, a plugin's, the
    #: observer's: the program's own code), kept so that a Python caller can catch or
    #: inspect it: :class:`RunFailed` is raised from it (its ``__cause__``), so
    #: ``except RunFailed as failed: raise failed.__cause__`` or ``isinstance`` reach the
    #: caller's own class; None for every other ending. Not shown, not compared: the
    #: summary's text and the CLI say it through :attr:`reason` and :attr:`traceback`
    exception: BaseException | None = field(default=None, repr=False, compare=False)
    #: the link's own exception that ended the run (a :class:`~roomba_bt.robot.errors.
    #: ConnectionFailed`: :class:`~roomba_bt.robot.errors.NoAnswer`, the robot not
    #: answering at the start; a :class:`~roomba_bt.robot.errors.LinkDown`: the port gone,
    #: the stream stopped), :class:`RunFailed`'s cause, so a program tests its class as a
    #: ``Connection.start()`` caller does; None for every other ending (lost bytes the
    #: motion watch gave up on, a safe stop not delivered: no exception said them)
    link_error: BaseException | None = field(default=None, repr=False, compare=False)
    #: ``--record``: why and when the record stopped before the run's end ("" if it did not)
    record_stopped: str = ""
    #: the message of the mission's ``log`` leaf said last (info or above; "" for none), the
    #: ``mission said`` line under the outcome: which way a mission ended, in its own words
    #: (a patrol that docked on a low battery before any lap read as "SUCCESS" alone)
    said: str = ""
    #: whether :meth:`lines` says the wall-clock measurements (the wall time, the ticks over
    #: the slot and the slowest): other on every run of the same mission; ``run
    #: --reproducible`` leaves them out, so the summary of a run made again is the same
    timings: bool = True
    #: the robot profile, said when it is not the default (``roomba500 (Roomba 500 series)``;
    #: "" for the default, whose summary reads as it always did)
    profile: str = ""
    #: the robot's own falls to Passive (a cliff, a wheel drop, the charger in Safe), by
    #: cause: each stopped the wheels and the tree's drive (``Connection.falls``)
    falls: dict[str, int] = field(default_factory=dict)
    #: every condition the operator forced from the monitor (what, to what, from which tick,
    #: until which), released before the end too: the run may have turned on one
    forced: list[str] = field(default_factory=list)
    #: the operator's pauses from the monitor (a breakpoint's too) and their stream time,
    #: which mission time leaves out; steps (a resume, one tick, a pause) counted apart
    paused_s: float = 0.0
    pauses: int = 0
    steps: int = 0
    #: how a TIMEOUT's reason names the run's time limit: "" says it as the thing it is
    #: (``the run's 90 s``: a Python caller's ``timeout_s=90``); the command line names its
    #: flag (``--timeout 90 s``), or says whose limit it was when no user gave one (``run
    #: --fast``'s own: ``--fast's own limit of 7200 s``)
    time_limit: str = ""
    #: the time limit is the run's planned length (``run --duration``, a shift), not a
    #: guard: reaching it is SUCCESS (:meth:`timed_out`)
    planned_end: bool = False
    #: how the summary and :class:`RunFailed` name the strict check (``RunStack(...,
    #: strict=True)``); the command line names its flag, ``--strict``
    strict_named: str = "the strict check"
    #: where the run's end came: the stream tick of its last frame and whether the tree had
    #: ticked on it (``"after"``) or not (``"before"``: the monitor's stop comes before the
    #: tick); the record's end note holds it, and a replay ends an interrupted run there
    #: (None: before the first frame)
    ended_at: tuple[int, str] | None = None
    #: the bytes gone over the link (the record's "out" side: whoever wrote them) when the
    #: run was ended from outside in its tick loop (None: it was not, or no record counts
    #: them: ``loop.note_written``). A Ctrl-C or SIGTERM "before" the tree's tick
    #: was written whole (``ended_at``) came inside the tick (none of it written) or between
    #: two of its flush's writes (part of it): the replay writes the tick up to there. A
    #: stop asked for between frames (the monitor's, ``request_stop``), or a Ctrl-C there,
    #: in a stall: the watchdog's drive 0 among them, and the replay ends once it has
    #: written as much (``stack.RecordedEnd.between_frames``). The record's end note holds it
    #: (``written``)
    written_when_interrupted: int | None = None
    #: which robot ran it: its port as given, or ``simulator WORLD`` (``run`` sets it: two
    #: runs' summaries in one terminal, of one mission, could not be told apart); "" says
    #: nothing (a replay, an evaluation's episode)
    robot: str = ""
    #: when the run started, local ISO 8601 (``run`` sets it: a cron job's runs in one log
    #: file told apart); "" says nothing (a Python program's run, ``--reproducible``)
    started: str = ""
    #: the run's label (``run --label``: ``robot 3``), said on the summary's first line:
    #: several robots run from one laptop, one mission each, the summaries alike; "" for none
    label: str = ""

    @property
    def exit_code(self) -> int:
        """The outcome's exit code; :attr:`ExitCode.STRICT` for a SUCCESS that failed
        ``--strict`` (:attr:`failed_strict`)."""
        return ExitCode.STRICT if self.failed_strict else self.outcome.exit_code

    @property
    def failed_strict(self) -> bool:
        """A run under ``--strict`` whose tree succeeded, with something
        :meth:`strict_findings` names: the SUCCESS hid a mission that did not do what it
        says (a leaf that drove on, refused, after a cliff dropped the robot to Passive)."""
        return self.strict and self.outcome is Outcome.SUCCESS and bool(self.strict_findings())

    def strict_findings(self) -> list[str]:
        """What ``--strict`` fails a successful run for, each with its count and its first
        instance: commands the mode guard refused, commands dropped while the tree was
        stopped, the robot's falls out of Safe/Full by itself (other than onto a
        charger: :data:`EXPECTED_FALLS`), blackboard keys written that the mission does not
        declare (a plugin's misspelt key: the mission's own fault, as a refused command is,
        which the run only warned of). Empty for a clean run. A poor link (lost frames, checksum
        failures, stalls ridden through) is left out on purpose: it is the cable's, not the
        mission's, and the summary's ``link`` and ``stalls`` lines say it."""
        found = []
        if self.refused_commands:
            refused = times_said(self.refused_commands, "command")
            found.append(f"the mode guard refused {refused}{first_said(self.first_refusal)}")
        if self.dropped_in_stop:
            dropped = times_said(self.dropped_in_stop, "command")
            found.append(
                f"{dropped} dropped while the tree was stopped{first_said(self.first_dropped)}"
            )
        falls = hazard_falls(self.falls)
        if falls:
            found.append(f"{falls_said(falls)}{first_said(self.first_fall)}")
        if self.undeclared_keys:
            key, where, hint = self.undeclared_keys[0]
            keys = times_said(len(self.undeclared_keys), "blackboard key")
            found.append(
                f"{keys} written that the mission does not declare (the first: "
                f"write_key({key!r}){where}{hint})"
            )
        return found

    def raise_for_outcome(self) -> RunSummary:
        """This summary, if the run succeeded (and passed ``--strict``, when the run was
        strict); else :class:`RunFailed` carrying it (its outcome, reason and exit code):
        ``stack.run().raise_for_outcome()``."""
        if self.exit_code != ExitCode.OK:  # from the caller's own exception, or the link's
            raise RunFailed(self) from self.exception or self.link_error
        return self

    def take_last(self, snapshot: Snapshot | None) -> None:
        """Mission time, distance and charge as the last snapshot had them (None: the run
        ended before its first frame, and they stay unknown)."""
        if snapshot is None:
            return
        self.mission_time_s = snapshot.time
        self.distance_mm = snapshot.odometry.path_mm
        if snapshot.frame.carries(BATTERY_PACKETS):
            self.battery_percent = level = snapshot.frame.battery_percent
            lowest = self.lowest_battery_percent
            self.lowest_battery_percent = level if lowest is None else min(lowest, level)

    def take_counters(self, counters: object) -> None:
        """What the stream parser refused or skipped (its ``counters``; None: a link without)."""
        if counters is not None:
            self.checksum_failures = int(getattr(counters, "checksum_failures", 0))
            self.skipped_bytes = int(getattr(counters, "skipped_bytes", 0))
            self.implausible_frames = int(getattr(counters, "implausible_frames", 0))

    def timed_out(self, limit_s: float, where: str) -> None:
        """The run's time limit of ``limit_s`` s ran out (``where``: `` in drive``, the leaf
        running). The reason keeps its end, ``... of mission time ran out in drive``, which
        :func:`~roomba_bt.evaluate.episode.failure_stage` reads. A planned end
        (:attr:`planned_end`: ``run --duration``) is SUCCESS, its reason saying so
        (:data:`PLANNED_END`)."""
        limit = self.time_limit or f"the run's {duration_said(limit_s)}"
        if self.planned_end:
            self.outcome = Outcome.SUCCESS
            self.reason = f"{limit} of mission time reached{where} ({PLANNED_END})"
            return
        self.outcome = Outcome.TIMEOUT
        self.reason = f"{limit} of mission time ran out{where}"

    @property
    def left_stopped(self) -> bool:
        """Whether the run's end is known to have left the robot stopped: its safe stop was
        written and heard (or there was nothing to stop), so its wheels are at 0 and its
        motors off in :attr:`final_mode`; False when the stop was not delivered, was cut
        short or failed, or the robot never answered (what it does is then unknown)."""
        unfinished = ("not attempted", "interrupted", "FAILED")
        return (
            self.stop_delivered
            and self.robot_answered
            and not self.safe_stop.startswith(unfinished)
        )

    def stop_said(self) -> str:
        """A stop not known to have arrived, as the final mode says it: "the stop
        unconfirmed" where it was written to a robot seen still that the run had set nothing
        going, or asleep; "the stop was not delivered" otherwise (the monitor's robot panel
        said that of every one, of a stop written to a robot asleep too)."""
        if self.set_nothing_going or self.asleep_stopped:
            return "the stop unconfirmed"
        return "the stop was not delivered"

    def final_mode_text(self) -> str:
        """The summary's ``final mode``: the mode after the safe stop, or why it is unknown;
        one the stream never showed (no packet 35) said as the run's own model's."""
        mode = self.final_mode.label if self.final_mode is not None else "unknown"
        if self.final_mode is not None and not self.mode_streamed:
            mode += MODEL_ONLY
        if not self.robot_answered:
            return "unknown: no robot answered"
        if not self.stop_delivered and self.set_nothing_going:
            return f"unknown: last seen in {mode}, the run set nothing going, {self.stop_said()}"
        if not self.stop_delivered and self.asleep_stopped:
            return f"unknown: asleep, last seen stopped in {mode}; {self.stop_said()}"
        if not self.stop_delivered and self.seen_stopped:
            return f"unknown: last seen stopped in {mode}, the stop was not delivered"
        if not self.stop_delivered:
            return f"unknown: last seen in {mode}, the stop was not delivered"
        return mode

    def lines(self) -> list[str]:
        """The summary's lines, each one line: what a mission's author wrote (its name, a
        node's in the reason) is escaped (``"\\n[ok] robot stopped"`` faked a line)."""
        mode = self.final_mode_text()
        reason = f" ({self.reason})" if self.reason else ""
        lines = [
            *([f"label        {shortened(self.label)}"] if self.label else []),
            f"mission      {shortened(self.mission)}",
            *([f"profile      {self.profile}"] if self.profile else []),
            *([f"robot        {self.robot}"] if self.robot else []),
            *([f"started      {self.started}"] if self.started else []),
            f"outcome      {self.outcome.value.upper()}{reason}",
            *([f"mission said {self.said}"] if self.said else []),
            *([f"forced       by the operator: {'; '.join(self.forced)}"] if self.forced else []),
            f"duration     {self.mission_time_s:.2f} s mission time"
            f"{long_duration_said(self.mission_time_s)}{_wall_said(self)}",
            *([f"paused       {self.paused_text()}"] if self.pauses or self.steps else []),
            f"ticks        {self.ticks}{_tick_times_said(self)}",
            f"frames       {self.stale_frames_dropped} stale dropped, {self.frames_lost} lost, "
            f"{self.checksum_failures} checksum failures, "
            f"{self.implausible_frames} out of range, {self.skipped_bytes} bytes skipped, "
            f"{self.unconfirmed_hazards} unconfirmed hazards",
            *([f"stalls       {self.stall_text()}"] if self.stalls else []),
            *([f"falls        {self.falls_text()}"] if hazard_falls(self.falls) else []),
            *([f"charger      {charger}"] if (charger := self.charger_text()) else []),
            *([f"link         {link}"] if (link := _link_verdict(self)) else []),
            *(
                [
                    f"unread       {self.unread_gaps} gap(s) with no frame read, the longest "
                    f"{self.longest_unread_s:.2f} s: the robot went on with its last command"
                    f"{_unread_lost_said(self)}"
                ]
                if self.unread_gaps
                else []
            ),
            *([f"tick guard   {guarded}"] if (guarded := self.tick_guard_text()) else []),
            *([f"unheard      {_unheard_said(self)}"] if self.unheard else []),
            f"commands     {self.commands_written} written, "
            f"{self.refused_commands} refused by the mode guard{_dropped_said(self)}",
            f"distance     {self.distance_mm / 1000:.2f} m",
            *([f"robot cycle  {self.robot_cycle}"] if self.robot_cycle else []),
            f"final mode   {mode}",
            f"battery      {self.battery_text()}",
            f"safe stop    {self.safe_stop}",
            *([f"record       {self.record_stopped}"] if self.record_stopped else []),
            *[f"warning      {undeclared_said(*written)}" for written in self.undeclared_keys],
            *self.verdict_lines(),
        ]
        return [escaped(line, ANY_CONTROL) for line in lines]

    def verdict_lines(self) -> list[str]:
        """``--strict``'s verdict, said on every strict run (``strict       FAILED (exit 7):
        the mode guard refused 313 commands (the first: ...)``, or ``passed``); without it, a
        warning when the mode guard refused commands: the run's outcome does not show them,
        and a leaf that drove on after a fall to Passive ended SUCCESS, exit 0."""
        if self.strict:
            findings = self.strict_findings()
            if not findings:
                docked = " but onto the charger" if self.falls else ""  # the others would fail
                return [
                    "strict       passed: no command refused or dropped, no fall to Passive "
                    f"by itself{docked}, no undeclared blackboard key written"
                ]
            if self.outcome is Outcome.SUCCESS:
                return [f"strict       FAILED (exit {int(ExitCode.STRICT)}): {'; '.join(findings)}"]
            return [f"strict       also: {'; '.join(findings)}"]  # the outcome fails it anyway
        if not self.refused_commands:
            return []
        refused = times_said(self.refused_commands, "command")
        strict = (
            f": {self.strict_named} fails such a run (exit {int(ExitCode.STRICT)})"
            if self.outcome is Outcome.SUCCESS
            else ""
        )
        return [
            f"warning      the mode guard refused {refused} the tree sent"
            f"{first_said(self.first_refusal)}{strict}"
        ]

    def __str__(self) -> str:
        return "\n".join(self.lines())

    def paused_text(self) -> str:
        """The pauses, in the duration line's units: ``6.15 s in 2 pauses, 3 steps, left out
        of mission time`` (a user subtracted the wall time from the mission time to know)."""
        parts = [f"{self.pauses} pause{'' if self.pauses == 1 else 's'}"] if self.pauses else []
        if self.steps:
            parts.append(f"{self.steps} step{'' if self.steps == 1 else 's'}")
        return f"{self.paused_s:.2f} s in {', '.join(parts)}, left out of mission time"

    def tick_guard_text(self) -> str:
        """The ticks the tick guard saw past its limit: those it stopped the robot in, then
        those with nothing moving (``1 slow tick(s) with nothing moving (nothing to stop);
        the first in sleepy (Sleepy.update at ...)``), then a program's loop over
        ``stack.ticks()`` past the limit between two ticks, said as its own; "" when it saw
        none."""
        parts = []
        if self.tick_halts:
            parts.append(
                f"{self.tick_halts} slow tick(s): {self.tick_halts_said()} while the tree was "
                f"busy; the first in {self.tick_halt_first}"
            )
        if self.tick_stills:
            parts.append(
                f"{self.tick_stills} slow tick(s) with nothing moving (nothing to stop); the "
                f"first in {self.tick_still_first}"
            )
        if self.tick_cycles:
            parts.append(
                f"{self.tick_cycles} slow tick(s) while a built-in cycle could drive the robot "
                f"(it went on: the guard ends no cycle); the first in {self.tick_cycle_first}"
            )
        if self.loop_slow:
            parts.append(f"{self.loop_slow} slow pass(es) of {LOOP_SAID}: {loop_said(self)}")
        return "; and ".join(parts)

    def tick_halts_said(self) -> str:
        """What the tick guard sent in its halts: ``drive 0 and motors off sent``, ``drive 0
        sent``, or both counted (it said ``drive 0 sent`` of a halt whose motors off went
        out in the same write)."""
        motors, halts = self.tick_halts_motors, self.tick_halts
        if motors <= 0:
            return "drive 0 sent"
        if motors >= halts:
            return "drive 0 and motors off sent"
        return f"drive 0 sent, with motors off in {motors} of them"

    def stall_text(self) -> str:
        """The watchdog's trips: how many sent drive 0 (a trip with the wheels at rest, on
        the dock say, sends nothing) and how many the frames came back from."""
        halts = (
            "watchdog drive 0"
            if self.stall_halts == self.stalls
            else f"watchdog drive 0 in {self.stall_halts}, the wheels at rest in the others"
        )
        return f"{self.stalls} ({halts}), {self.stalls_ridden} ridden through"

    def falls_text(self) -> str:
        """The robot's own falls to Passive, the commonest cause first: ``the robot fell to
        Passive by itself 21 times (cliff 20, wheel drop 1)`` (:func:`falls_said`). Those
        onto the charger (:data:`EXPECTED_FALLS`) are not among them: each is a docking,
        which the ``charger`` line counts (:meth:`charger_text`); a patrol that docked ten
        times read as ten faults."""
        falls = hazard_falls(self.falls)
        cable = f"; {self.falls_cable}" if self.falls_cable and UNKNOWN_CAUSE in falls else ""
        return f"{falls_said(falls)}{cable}"

    def charger_text(self) -> str:
        """The ``charger`` line: the dockings (the OI's own drop from Safe or Full to
        Passive on a powered charger's contacts: how docking ends) and the time on the
        charger, when a second or more (``docked 2 times, on it 2 h 41 min in all``); ""
        for a run that met no charger."""
        docked = self.falls.get("charger", 0)
        parts = [f"docked {'once' if docked == 1 else f'{docked} times'}"] if docked else []
        if self.on_charger_s >= 1:
            parts.append(f"on it {duration_words(self.on_charger_s)} in all")
        return ", ".join(parts)

    def battery_text(self) -> str:
        """``46%``, then the lowest level seen when it was lower: ``46%, the lowest 18%``
        (a night's patrol ended charged, its low point unsaid); ``n/a`` unknown."""
        final, lowest = self.battery_percent, self.lowest_battery_percent
        if final is None:
            return "n/a"
        if lowest is None or round(lowest) >= round(final):
            return f"{final:.0f}%"
        return f"{final:.0f}%, the lowest {lowest:.0f}%"


# How the summary's lines word a measure (RunSummary.lines): out of the class, which
# holds what was measured.


#: how the tick guard line names a program's loop over ``stack.ticks()``, its slow passes
LOOP_SAID = (
    "the program's loop over stack.ticks(), between two ticks (the program's own time, not "
    "the tree's)"
)


def loop_said(summary: RunSummary) -> str:
    """What the tick guard did in the slow passes of a program's loop over ``stack.ticks()``:
    stopped the robot in some, sent nothing in the others."""
    said = []
    if summary.loop_halts:
        said.append(f"stopped the robot in {summary.loop_halts}")
    if summary.loop_slow > summary.loop_halts:
        said.append(
            f"sent nothing in {summary.loop_slow - summary.loop_halts} (nothing moving, or a "
            "built-in cycle, which it does not end)"
        )
    return "the tick guard " + ", ".join(said)


def _unheard_said(summary: RunSummary) -> str:
    """The robot not doing what it was told (runtime/motion_watch.py), in the summary's
    words: ``the robot did not do what it was told 2 times (the first t=6.390 the wheels
    stood still ...): bytes from the computer to the robot were lost 2 times (it obeyed
    the command sent again); check the cable and its adapter (roomba-bt doctor)``."""
    first = f" (the first {summary.unheard_first})" if summary.unheard_first else ""
    said = [f"the robot did not do what it was told {_times(summary.unheard)}{first}"]
    if summary.unheard_obeyed:
        said.append(
            f"bytes from the computer to the robot were lost {_times(summary.unheard_obeyed)} "
            "(it obeyed the command sent again)"
        )
    if summary.unheard_stalled:
        said.append(
            f"{_times(summary.unheard_stalled)} the command sent again did not help either "
            "(the robot wedged with no bump shown or its wheels stalled, or the line lost "
            "that too)"
        )
    if summary.unheard > summary.unheard_obeyed + summary.unheard_stalled:
        said.append(
            "the command was sent again, and the run ended before it could be judged: "
            "bytes from the computer to the robot may have been lost"
        )
    line = summary.unheard > summary.unheard_stalled
    return "; ".join(said) + (f"; {_check_the_line(summary)} (roomba-bt doctor)" if line else "")


def _check_the_line(summary: RunSummary) -> str:
    """What to check of the run's line, in its kind's words (a cable, a Wi-Fi bridge)."""
    # imported here: validate and show load this module, and the transport package pyserial
    from roomba_bt.transport.link_kind import link_of

    return link_of(summary.robot).check


def _times(count: int) -> str:
    """``once``, ``2 times``."""
    return "once" if count == 1 else f"{count} times"


def _wall_said(summary: RunSummary) -> str:
    """``, 0.04 s wall`` for the duration line; "" without :attr:`RunSummary.timings`."""
    if not summary.timings:
        return ""
    return f", {summary.wall_time_s:.2f} s wall{long_duration_said(summary.wall_time_s)}"


def _tick_times_said(summary: RunSummary) -> str:
    """`` (0 overruns > 15 ms, slowest 1.98 ms)`` for the ticks line; "" without
    :attr:`RunSummary.timings`."""
    if not summary.timings:
        return ""
    slowest = f"slowest {summary.max_tick_s * 1000:.2f} ms{_slowest_said(summary)}"
    if summary.virtual_clock:  # it waits for each tick: "2010 overruns" there was noise
        return (
            f" ({summary.overruns} over 15 ms of host time, none late on the virtual clock; "
            f"{slowest})"
        )
    return f" ({summary.overruns} overruns > 15 ms, {slowest})"


def _dropped_said(summary: RunSummary) -> str:
    """``, 2 dropped while the tree was stopped`` for the commands line; "" for none."""
    if not summary.dropped_in_stop:
        return ""
    return f", {summary.dropped_in_stop} dropped while the tree was stopped"


def _slowest_said(summary: RunSummary) -> str:
    """`` in sleepy (Sleepy.update at x.py:98)``: the slowest tick's behaviour, for the ticks
    line, when it ran over the 15 ms slot (a run's ordinary slowest tick is not news) and
    the watch named it, or ``: the host was busy (...)`` when the host kept the ticking
    thread from running (:attr:`RunSummary.slowest_host_busy`); else ""."""
    if summary.max_tick_s <= SLOT_SECONDS:
        return ""
    if summary.slowest_host_busy:
        return f": the host was busy ({summary.slowest_host_busy})"
    return f" in {summary.slowest_in}" if summary.slowest_in else ""


def _link_verdict(summary: RunSummary, late: str = "the tree saw the robot late") -> str:
    """A line that lost :data:`POOR_LINK` or more of the robot's frames, over a run long
    enough to tell (:data:`LINK_VERDICT_SLOTS`), said as such: the run may end well on
    it, ``late`` (the tree seeing the robot late; ``sensors``' tables). "" for a line that
    did not."""
    lost = summary.frames_lost - summary.frames_lost_unread  # the line's, not the host's
    sent = summary.ticks + summary.stale_frames_dropped + lost
    if sent < LINK_VERDICT_SLOTS or lost < POOR_LINK * sent:
        return ""
    return (
        f"poor: {100 * lost / sent:.0f} % of the robot's frames lost "
        f"({lost} of {sent}), {summary.checksum_failures} checksum failures: "
        f"{late}; {_check_the_line(summary)} (roomba-bt doctor)"
    )


def _unread_lost_said(summary: RunSummary) -> str:
    """``; 2309 of the frames lost were lost in them (...)`` for the unread line: the frames
    the port's buffer dropped while nothing read it, which the link line leaves out; ""
    for none."""
    lost = summary.frames_lost_unread
    if not lost:
        return ""
    return (
        f"; {lost} of the frames lost were lost in them (the port's buffer full while nothing "
        "read it: the computer's, not the line's)"
    )


def link_lines(summary: RunSummary, late: str) -> list[str]:
    """What a command that reads the stream without a tree (``roomba-bt sensors``) says of
    its line, as a run's summary does: its ``frames`` line, less what only a tree has (stale
    frames, unconfirmed hazards), and its ``link`` line (``late``: what the loss made of
    the command's output); none for a line that lost and garbled nothing (``ticks``: the
    frames read)."""
    if not (summary.frames_lost or summary.checksum_failures or summary.skipped_bytes
            or summary.implausible_frames):  # fmt: skip
        return []
    frames = (
        f"frames       {summary.ticks} read, {summary.frames_lost} lost, "
        f"{summary.checksum_failures} checksum failures, {summary.implausible_frames} out of "
        f"range, {summary.skipped_bytes} bytes skipped"
    )
    link = _link_verdict(summary, late)
    return [frames, *([f"link         {link}"] if link else [])]
