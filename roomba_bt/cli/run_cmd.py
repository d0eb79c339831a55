"""``roomba-bt run`` and ``roomba-bt replay``."""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from roomba_bt.cli import raise_lost_interrupt
from roomba_bt.cli.arguments import (
    LABEL_LENGTH,
    MIN_WATCHDOG,
    add_battery_option,
    add_command,
    add_display_option,
    add_far_end_options,
    add_fault_options,
    add_odometry_error_option,
    add_param_option,
    add_permission_options,
    add_strict_option,
    add_wall_limit_option,
    add_window_options,
    baud_warning,
    fault_options_set,
    faults_given,
    limit_seconds,
    mission_file,
    parse_params,
    parse_timeout,
    parse_window,
    permissions,
    plot_file,
    record_file,
    record_size_limit,
    run_label,
    seconds,
    watchdog_seconds,
)
from roomba_bt.cli.monitor_cmd import LiveMonitor, MonitorOptions, chosen_token
from roomba_bt.cli.monitor_cmd import add_run_arguments as add_monitor_arguments
from roomba_bt.cli.profile_choice import (
    AUTO_PROFILE,
    chosen_profile,
    mission_near,
    profile_line,
    profile_setting,
)
from roomba_bt.cli.record_header import (
    add_reproducible_option,
    epoch_problem,
    replayed_include_dirs,
)
from roomba_bt.installation import optional_import_failure
from roomba_bt.oi.errors import BandwidthError
from roomba_bt.oi.profiles import RobotProfile, get_profile
from roomba_bt.printable import ANY_CONTROL, duration_said, encodes, escaped
from roomba_bt.robot.errors import DEFAULT_WATCHDOG, TurnedAway
from roomba_bt.robot.safety import answer_given, terminal_stops_ignored, terminal_stops_kept
from roomba_bt.runtime.summary import (
    DEFAULT_GRACE,
    DEFAULT_TICK_LIMIT,
    INTERNAL_ERROR_SAID,
    ExitCode,
    Outcome,
    RunSummary,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from roomba_bt.mission import Diagnostic, Permissions
    from roomba_bt.runtime.claimed import ClaimedFile
    from roomba_bt.runtime.loop import TickObserver
    from roomba_bt.runtime.provenance import AbsentPlugin
    from roomba_bt.runtime.recording import Record, ReplayTransport
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import Simulator
    from roomba_bt.transport import Transport

#: the mode guard's refusals printed after the summary; a line says how many more there were
SHOWN_REFUSALS = 5
#: ``--fast``'s time limit when no ``--timeout`` is given, s of mission time (2 h: a battery
#: of cleaning). On the virtual clock a mission that never ends ran until the simulated
#: battery was flat (hours, then "connection lost"), or for ever on the charger.
FAST_TIMEOUT_S = 7200.0


def register(sub: Any) -> None:
    _add_run_parser(sub)
    _add_replay_parser(sub)


def _add_run_parser(sub: Any) -> None:
    run = add_command(
        sub,
        "run",
        run_command,
        f"""run a mission on a robot (--port) or the simulator

        Run MISSION. Without --port it runs on the built-in simulator (real time; --fast on the
        virtual clock). Exit codes: 0 succeeded, 1 failed or timed out, 2 invalid mission or usage
        (or a --profile the robot's frames show wrong before anything of the mission was sent),
        3 not started: the port could not be opened, the robot did not answer or its stream
        never came (nothing of the mission sent: safe to retry), 4 a behaviour raised an
        exception (sys.exit() too) or the run hung past --wall-limit, 7
        succeeded but failed --strict (or, with --strict, not started: the mission has
        warnings), 8 the link was lost after the run started (the robot may have moved: the
        summary's safe stop line says whether the stop reached it), {INTERNAL_ERROR_SAID},
        130 interrupted (Ctrl-C, a signal).
        """,
    )
    run.add_argument("mission", help="mission YAML file, or a shipped mission's name (dock)")
    add_far_end_options(
        run,
        port_help="serial device or URL (socket://host:port, rfc2217://, loop://)",
        world_help="simulator world: a shipped name or a YAML path",
    )
    run.add_argument("--seed", type=int, default=0, help="simulator seed (default 0)")
    add_battery_option(run, "simulator only: ")
    run.add_argument(
        "--random-start", action="store_true", help="start in the world's start region"
    )
    add_odometry_error_option(run, "simulator only: ")
    add_fault_options(
        run, "simulator only (refused with --port): what goes wrong on the line and in the "
        "robot, drawn from --seed; with --fast, an hour of a bad cable in seconds",
    )  # fmt: skip
    add_param_option(run, "set a mission parameter, e.g. -p speed=250mm/s (repeatable)")
    _add_limit_options(run)
    _add_record_options(run)
    run.add_argument(
        "--plot",
        metavar="FILE",
        type=plot_file,
        help="simulator only: plot the trajectory (.png, .pdf, .svg: the suffix is the format)",
    )
    add_permission_options(run)
    run.add_argument("--fast", action="store_true", help="simulator on the virtual clock")
    add_reproducible_option(run)
    _add_strict_option(run)
    _add_session_options(run)
    add_display_option(run, live=True)
    run.add_argument(
        "--heartbeat", metavar="DURATION", default="10min",
        help="with --display log: a line of battery, distance, mode and ticks every this "
        "much mission time (--fast too); none: no such line (default 10min)",
    )  # fmt: skip
    _add_label_option(run)
    add_monitor_arguments(run)


def _add_limit_options(run: argparse.ArgumentParser) -> None:
    """The run's two limits: ``--timeout`` of mission time, which a tree that returns
    reaches, and ``--wall-limit`` of wall-clock time, for one stuck in a tick (mission time
    stands still with it on the virtual clock)."""
    run.add_argument(
        "--timeout",
        help="give up after this much mission time, e.g. 90s, 5min, 1h30min or 1d (default: "
        f"none; with --fast and no --monitor/--watch {FAST_TIMEOUT_S / 3600:g}h, else a mission "
        "that never ends would run until the simulated battery is flat, or for ever on the dock)",
    )
    run.add_argument(
        "--duration",
        help="a planned shift: stop after this much mission time (8h) and call it SUCCESS, "
        "exit 0, where --timeout calls it TIMEOUT, exit 1 (not both; the tree ending sooner "
        "ends the run as it says)",
    )
    add_wall_limit_option(
        run, "for the run",
        "after the safe stop, HUNG, exit 4; the way to end a --fast run stuck where --timeout's "
        "mission time stands still (default: none)",
    )  # fmt: skip


def _add_record_options(run: argparse.ArgumentParser) -> None:
    """``--record`` and its size limit, ``--record-max`` (a night's record on a small disk)."""
    run.add_argument(
        "--record",
        metavar="FILE",
        type=record_file,
        help="write every byte in and out, timestamped (a FILE ending in .gz: compressed)",
    )
    run.add_argument(
        "--record-max", metavar="SIZE", type=record_size_limit,
        help="stop the --record file at this size on disk (500MB, 2GB); the run goes on, and "
        "its summary says the mission time of the cut (default: no limit)",
    )  # fmt: skip
    run.add_argument(
        "--require-record", action="store_true",
        help="refuse to start (exit 2, nothing sent) when the --record file's header cannot be "
        "written (a full disk); default: the run goes on without its record, said so",
    )  # fmt: skip


def _add_label_option(run: argparse.ArgumentParser) -> None:
    """``--label``: which run this is, to its people (several robots from one laptop)."""
    run.add_argument(
        "--label", type=run_label, metavar="TEXT",
        help="a label for this run, to tell several apart (robot 3): shown in the live tree "
        "and each log line, the summary, the monitor's URL line, page and tab, and the record "
        f"(1 to {LABEL_LENGTH} printable characters)",
    )  # fmt: skip


def _add_strict_option(run: argparse.ArgumentParser) -> None:
    """``--strict``: what the run did fails it too, beside compile-time warnings."""
    add_strict_option(
        run,
        "(nor reloaded by --watch); one that succeeded exits 7 if the mode guard refused any "
        "command, a command was dropped while the tree was stopped, or the robot fell out of "
        "Safe/Full by itself (a cliff, a wheel drop; not onto a charger), or a behaviour wrote "
        "a blackboard key the mission does not declare: the summary's strict "
        "line names each count and its first instance",
    )


def _add_session_options(run: argparse.ArgumentParser) -> None:
    """How the connection ends, watches the stream and keeps the robot awake."""
    run.add_argument(
        "--end-in", choices=("passive", "stop"), default="passive",
        help="leave the robot in Passive (Start) or, where the profile has it, Stop (173)",
    )  # fmt: skip
    run.add_argument(
        "--watchdog", type=watchdog_seconds, default=DEFAULT_WATCHDOG, metavar="SECONDS",
        help="stop the wheels (drive 0) when no valid sensor frame came for this long "
        f"(default {DEFAULT_WATCHDOG:g}; {MIN_WATCHDOG:g} or more: it cannot be turned off)",
    )  # fmt: skip
    run.add_argument(
        "--grace", type=seconds, default=DEFAULT_GRACE, metavar="SECONDS",
        help="after the watchdog stopped the wheels, wait this long for valid frames before "
        f"ending as a lost connection (default {DEFAULT_GRACE:g}; 0: end at once)",
    )  # fmt: skip
    run.add_argument(
        "--tick-limit", type=seconds, default=DEFAULT_TICK_LIMIT, metavar="SECONDS",
        help="stop the wheels (drive 0) when a tick runs this long, e.g. a behaviour that "
        "blocks; the mission then goes on (default "
        f"{DEFAULT_TICK_LIMIT:g}; 0: no guard; --fast has none: nothing moves while it thinks)",
    )  # fmt: skip
    run.add_argument(
        "--no-keep-awake",
        dest="keep_awake",
        action="store_false",
        help="do not pulse BRC (RTS/DTR) once a minute; a robot left in Passive then sleeps "
        "after 5 minutes",
    )


def _add_replay_parser(sub: Any) -> None:
    replay = add_command(
        sub,
        "replay",
        replay_command,
        f"""play a --record file back through the tree

        Feed the recorded sensor bytes back through the same parser and tree and compare the
        commands the tree writes with the recorded ones; the monitor's pauses, steps and
        forced conditions in the record are done again where they were done. Exit codes: 0
        the same bytes, 1 at the first difference (its mission time and both commands are
        printed), 2 invalid record or mission, or a mission reading packets the record lacks,
        {INTERNAL_ERROR_SAID}.
        """,
    )
    replay.add_argument("record", help="a file written by run --record")
    replay.add_argument("--mission", help="mission to replay against (default: the recorded one)")
    add_param_option(replay)
    add_permission_options(replay)
    add_window_options(replay, start=False)
    add_display_option(replay, live=False)


def _error(message: str, command: str) -> int:
    """``roomba-bt run: MESSAGE`` (``replay``, ``monitor``) on stderr, exit 2: the command
    named as ``show``, ``validate`` and ``eval`` name theirs (``run DIR`` said "roomba-bt:")."""
    print(f"roomba-bt {command}: {message}", file=sys.stderr)
    return ExitCode.INVALID


def load(
    path: str,
    params: dict[str, str],
    profile: RobotProfile,
    baud: int = 115200,
    granted: Permissions | None = None,
    absent: Sequence[AbsentPlugin] = (),
    failed: list[Diagnostic] | None = None,
) -> Any:
    """The compiled mission, or an int exit code after printing every diagnostic (``run``,
    ``replay``, and ``eval`` before its workers start). ``absent``: plugins a record's run
    used that are not here as they were, said first when the mission does not compile
    (its unknown nodes are most likely theirs: no "did you mean" for them). ``failed``: a
    list that the diagnostics of a mission that does not compile are added to (``eval
    --json`` prints them as data too)."""
    from roomba_bt.behaviours import default_registry
    from roomba_bt.cli.mission_cmds import warn_of_broken_plugins
    from roomba_bt.mission import MissionError, Permissions, load_mission, reported

    registry = default_registry().expecting(p.short for p in absent) if absent else None
    try:
        mission = load_mission(
            path, params, profile=profile, baud=baud, permissions=granted or Permissions(),
            registry=registry,
        )  # fmt: skip
    except MissionError as exc:
        if failed is not None:
            failed += exc.diagnostics
        for plugin in absent:
            print(f"roomba-bt: {plugin.said()}", file=sys.stderr)
        for line in reported(exc.diagnostics):
            print(line, file=sys.stderr)
        return ExitCode.INVALID
    finally:  # the compile looked for the installed plugins if the mission names one
        warn_of_broken_plugins("roomba-bt", registry or default_registry())
    for warning in mission.warnings:
        print(str(warning), file=sys.stderr)
    return mission


def stream_packets(mission: Any, baud: int) -> tuple[int, ...]:
    """The mission's packets plus what the runtime needs, checked against the baud rate."""
    from roomba_bt.runtime.loop import stream_request

    return stream_request(mission.packets, baud)


def run_command(args: argparse.Namespace) -> int:
    checked = _checked_arguments(args)
    if isinstance(checked, int):
        return checked
    claimed = _claimed_record(args.record)
    if isinstance(claimed, int):
        return claimed
    try:
        # from before the port opens: a background job's first line to a ``stty tostop``
        # terminal (the tree drawn before the run) stopped it (SIGTTOU) with its port open;
        # the run ignores them on the wall clock, as its report does
        with terminal_stops_ignored(not args.fast):
            return _claimed_run(args, *checked, claimed)
    finally:
        if claimed is not None:
            claimed.release()  # a run that ended before its record began: the file as it was


def _claimed_record(path: str | None) -> ClaimedFile | int | None:
    """``--record``'s file, this run's alone, before the robot is opened: a path another run
    writes (a class that all typed ``--record run.jsonl`` in a shared folder) is refused
    here, exit 2, where before the second run emptied it under the first, which lost its
    record to NUL bytes. Not emptied yet: a run that fails before it starts keeps an earlier
    record as it was."""
    if not path:
        return None
    from roomba_bt.runtime.claimed import ClaimedFile

    try:
        return ClaimedFile(path)
    except OSError as exc:
        return _error(f"--record {path}: {exc.strerror or exc}", "run")


def _claimed_run(
    args: argparse.Namespace,
    params: dict[str, str],
    timeout: float | None,
    claimed: ClaimedFile | None,
) -> int:
    """The run, once its arguments are checked and its record claimed (``claimed``)."""
    from roomba_bt.cli.links import far_end
    from roomba_bt.robot.errors import ConnectionFailed
    from roomba_bt.runtime.display import observer_for

    args.started = datetime.now(UTC)  # a run that never starts says when it tried, too
    prepared = _mission_at_its_rate(args, params)
    if isinstance(prepared, int):
        return prepared
    mission, packets, opened = prepared
    profile = get_profile(args.profile)
    simulator = _simulator(args, profile)
    if isinstance(simulator, str):  # the world's problems, each at its file:line:col
        print(simulator, file=sys.stderr)
        return ExitCode.INVALID
    args.robot = robot_label(args.port, simulator)
    args.world_source = simulator.world.source if simulator is not None else None
    monitor = None
    if args.monitor is not None or args.watch:
        monitor = _live_monitor(args, mission, simulator, packets, params, profile)
        failed = monitor.bind()  # a port taken: exit 2 before the robot is opened
        if failed is not None:
            return failed
    try:
        link = far_end(args.port, args.baud, simulator, fast=args.fast, opened=opened)
    except ConnectionFailed as exc:
        if monitor is not None:
            monitor.finish(None)
        return _not_started(args, exc, "nothing sent: the port was not opened")
    observer = observer_for(
        args.display, sys.stdout, label=args.label or "", heartbeat_s=args.heartbeat_s
    )
    try:
        stack = _stack(args, mission, link, packets, params, timeout, observer, claimed)
    except BaseException as exc:  # the port let go of (its exclusive mode): it was left open
        with contextlib.suppress(Exception):
            link.close()
        if monitor is not None:
            monitor.finish(None)
        if isinstance(exc, OSError):  # the record cannot be written
            return _error(_record_refused(args, exc), args.command)
        raise  # a bug (main() says it, exit 70), or Ctrl-C
    if monitor is not None:
        monitor.start()  # the port is open: its URL now, not one a busy port never serves
    return _run_and_report(args, stack, observer, simulator, monitor)


def _record_refused(args: argparse.Namespace, exc: OSError) -> str:
    """Why the run does not start, its record not writable: the file not opened, or, with
    ``--require-record``, its header not written (a full disk; the file this run made
    removed). A lab that needs a record of every run got a 0-byte file and a summary line
    ``stopped at 0.000 s``, easy to miss; then a warning that "the run goes on" before
    the refusal that it did not start."""
    from roomba_bt.runtime.recording import RecordNotStarted

    why = exc.strerror or str(exc)
    if isinstance(exc, RecordNotStarted):
        return (
            f"--record {args.record}: the record's header could not be written ({why}); "
            "--require-record: not started, nothing sent"
        )
    return f"--record {args.record}: {why}"


def _mission_at_its_rate(
    args: argparse.Namespace, params: dict[str, str]
) -> tuple[Any, tuple[int, ...], Any] | int:
    """The mission compiled for the robot's model and the port's rate, its stream's packets
    and a port ``--profile auto`` or ``--baud auto`` opened to find them (None otherwise);
    or the exit code after saying why not."""
    from roomba_bt.cli.links import auto_baud, auto_profile
    from roomba_bt.robot.errors import ConnectionFailed

    try:  # --profile auto: identified first, since the mission is compiled for a model
        opened = auto_profile(args, "run")
    except ConnectionFailed as exc:
        return _not_started(args, exc, PROBED_ONLY)
    profile = get_profile(args.profile)
    ending = None if opened is None else end_in_problem(args.end_in, profile)
    if opened is not None and ending is not None:
        opened.close()  # the identification's Start left the robot in Passive
        return _error(ending, args.command)
    warned = baud_warning(args.baud, profile, simulated=not args.port)
    if warned is not None:
        print(f"roomba-bt run: {warned}", file=sys.stderr)
    if args.baud is None:  # --baud auto: the mission's stream is checked at the rate found
        try:
            args.baud, opened = auto_baud(args.port, profile)
        except ConnectionFailed as exc:
            return _not_started(args, exc, PROBED_ONLY)
    mission = load(args.mission, params, profile, args.baud, permissions(args, args.mission))
    if isinstance(mission, int):
        return mission
    try:
        packets = stream_packets(mission, args.baud)
    except BandwidthError as exc:
        return _error(f"{args.mission}: {exc}", args.command)
    if args.strict and mission.warnings:  # printed by load(), above; errors were exit 2
        # not started, as validate --strict fails it in CI: it started, and --strict judged
        # only what the run did, so such a mission ran under run --strict and could exit 0
        from roomba_bt.cli.validate_report import failed_strict

        said = failed_strict(args.mission, mission.warnings)
        print(f"roomba-bt: {said}; not started", file=sys.stderr)
        return ExitCode.STRICT
    return mission, packets, opened


#: the safe stop line of a run whose ``--baud auto`` or ``--profile auto`` probe found no
#: robot: the probe's Start and queries were all it wrote, and nothing of the mission
PROBED_ONLY = "nothing of the mission sent, only the probe's Start and queries; the port closed"


def _not_started(args: argparse.Namespace, exc: Exception, sent: str) -> int:
    """A run that never started (the port not opened, or no robot found by ``--baud auto``
    or ``--profile auto``): its summary, as every other run's ending has one, outcome NO
    CONNECTION, exit 3 (nothing of the mission sent: safe to retry). It was one line on
    stderr: a cron job's evening log had no ``outcome`` line to look for, and the hint said
    ``doctor --port URL``, not the port."""
    if getattr(args, "as_the_process", False):
        answer_given(ExitCode.CONNECTION)  # the port is closed: a signal changes nothing
    summary = RunSummary(Path(args.mission).stem, Outcome.NO_CONNECTION, reason=str(exc))
    summary.profile = "" if args.profile == AUTO_PROFILE else profile_line(args)
    summary.robot = robot_label(args.port, None)
    summary.label = args.label or ""
    summary.robot_answered = False
    summary.safe_stop = sent
    _timed(summary, args)
    summary.wall_time_s = (datetime.now(UTC) - args.started).total_seconds()
    print(summary)
    sys.stdout.flush()
    print(f"roomba-bt: {exc}", file=sys.stderr)
    return summary.exit_code


def robot_label(port: str | None, simulator: Simulator | None) -> str:
    """Which robot a run drives, as its summary, monitor line, page and record say it: the
    port as given (``/dev/ttyUSB0``, ``socket://10.0.0.7:2000``), or ``simulator WORLD``.
    Several robots run from one laptop, nothing said which one a summary or a page was of."""
    if port:
        return escaped(port, ANY_CONTROL)
    world = simulator.world.name if simulator is not None else ""
    return f"simulator {world}".strip()


def _stack(
    args: argparse.Namespace,
    mission: Any,
    link: Transport,
    packets: tuple[int, ...],
    params: dict[str, str],
    timeout: float | None,
    observer: TickObserver | None,
    claimed: ClaimedFile | None = None,
) -> RunStack:
    """The run's stack as the options say (OSError: the --record file cannot be written);
    ``claimed``: the --record file, claimed at the run's start."""
    from roomba_bt.cli.record_header import recording
    from roomba_bt.runtime.stack import RunStack

    # a shipped mission by its name (roomba-bt:dock.yaml), found by a replay wherever
    # roomba-bt is installed; a file of the user's by its path from the record's folder
    record = recording(args, mission, params, claimed) if args.record else None
    stack = RunStack(
        mission,
        link,
        profile=get_profile(args.profile),
        baud=args.baud,
        packets=packets,
        watchdog=args.watchdog,
        grace=args.grace,
        tick_limit=None if args.fast or not args.tick_limit else args.tick_limit,
        keep_awake=None if args.keep_awake else False,
        end_in=args.end_in,
        timeout_s=timeout,
        observer=observer,
        record=record,
        strict=args.strict,
    )
    stack.connection.profile_setting = profile_setting(args)  # a wrong profile's fix
    summary = stack.runner.summary  # the runtime says its settings as things; here, as flags
    if _fast_limit(args):  # no user gave it: its reason says whose it is
        summary.time_limit = f"--fast's own limit of {duration_said(FAST_TIMEOUT_S)}"
    elif timeout is not None and getattr(args, "duration", None) is not None:
        summary.time_limit = f"--duration {duration_said(timeout)}"
        summary.planned_end = True
    elif timeout is not None:
        summary.time_limit = f"--timeout {duration_said(timeout)}"
    summary.strict_named = "--strict"
    summary.profile = profile_line(args)  # where it came from, unless the flag named it
    summary.robot = args.robot
    summary.label = args.label or ""
    _timed(summary, args)
    return stack


def _timed(summary: RunSummary, args: argparse.Namespace) -> None:
    """The summary's wall-clock lines, which vary from run to run: the wall time and when it
    started (local time, as the morning's cron line and the reader's clock read); neither
    with ``--reproducible``."""
    summary.timings = not getattr(args, "reproducible", False)
    if summary.timings:
        summary.started = args.started.astimezone().isoformat(timespec="seconds")


def _checked_arguments(args: argparse.Namespace) -> tuple[dict[str, str], float | None] | int:
    """The parameters and the time limit, or the exit code after saying which argument is
    wrong (the mission's path is resolved into ``args.mission``)."""
    params = parse_params(args.param)
    if isinstance(params, str):
        return _error(params, args.command)
    timeout = _time_limit(args)
    if isinstance(timeout, str):
        return _error(timeout, args.command)
    if _fast_limit(args):
        timeout = FAST_TIMEOUT_S
    limit = None if args.wall_limit is None else limit_seconds(args.wall_limit, "--wall-limit")
    if isinstance(limit, str):
        return _error(limit, args.command)
    args.wall_limit_s = limit
    heartbeat = limit_seconds(args.heartbeat, "--heartbeat")
    if isinstance(heartbeat, str):
        return _error(heartbeat, args.command)
    args.heartbeat_s = heartbeat
    simulated = (args.world, args.plot, args.fast, args.battery is not None, args.odometry_error)
    if args.port and any(simulated):
        return _error(
            "--world, --plot, --fast, --battery and --odometry-error are for the simulator: "
            "drop them or --port",
            args.command,
        )
    faults = fault_options_set(args)
    if args.port and faults:
        return _error(
            f"{', '.join(faults)}: the simulator's faults, and --port is a real robot: drop "
            "them or --port (rehearse a bad cable on the simulator: no --port)",
            args.command,
        )
    args.faults = faults_given(args, odometry_error=args.odometry_error)
    if isinstance(args.faults, str):
        return _error(args.faults, args.command)
    token = chosen_token(args)
    if token:
        return _error(token, args.command)
    if args.record_max is not None and not args.record:
        return _error("--record-max limits the --record file: give --record FILE too", args.command)
    epoch = epoch_problem() if args.record else None
    if epoch is not None:  # the convention: stop rather than write the current time
        return _error(epoch, args.command)
    found = mission_file(args.mission)
    if isinstance(found, tuple):
        return _error(found[0], args.command)
    problem = chosen_profile(args, "run", mission_near(args.mission, found))
    args.mission = found
    if problem is None and args.profile != AUTO_PROFILE:  # auto: once it is identified
        problem = end_in_problem(args.end_in, get_profile(args.profile))
    if problem is not None:
        return _error(problem, args.command)
    return params, timeout


def _time_limit(args: argparse.Namespace) -> float | str | None:
    """The run's mission-time limit: ``--timeout`` (a guard: TIMEOUT, exit 1) or
    ``--duration`` (a planned shift's length: SUCCESS, exit 0), never both (one would never
    act); a message when they are both given or one is not a duration."""
    duration = getattr(args, "duration", None)
    if duration is None:
        return parse_timeout(args.timeout)
    if args.timeout is not None:
        return (
            f"--duration {duration} and --timeout {args.timeout}: give one (--duration: a "
            "planned end, SUCCESS; --timeout: a limit that ends the run as TIMEOUT)"
        )
    return parse_timeout(duration, "--duration")


def _fast_limit(args: argparse.Namespace) -> bool:
    """Whether the run takes ``--fast``'s own limit (:data:`FAST_TIMEOUT_S`): on the virtual
    clock with no ``--timeout``, and nobody watching (``--monitor``, ``--watch``: the page
    stops it, and a paused run's clock goes on)."""
    watched = args.monitor is not None or args.watch
    planned = getattr(args, "duration", None) is not None
    return bool(args.fast) and args.timeout is None and not planned and not watched


def end_in_problem(end_in: str, profile: RobotProfile) -> str | None:
    """``--end-in stop`` on a robot without Stop (173): a usage error before anything is sent
    (it was a warning at run time, and the run ended in Passive with exit 0)."""
    if end_in != "stop" or profile.has_command("stop"):
        return None
    return (
        f"argument --end-in: found stop, but the {profile.title} (--profile {profile.name}) "
        "has no Stop (173); allowed: --end-in passive"
    )


def _simulator(args: argparse.Namespace, profile: RobotProfile) -> Simulator | str | None:
    """The simulator when there is no ``--port`` (None with one); the world's problems as
    the lines to print (:func:`~roomba_bt.cli.worlds_cmd.world_error_text`)."""
    if args.port:
        return None
    from roomba_bt.cli.links import make_simulator
    from roomba_bt.sim import WorldError
    from roomba_bt.sim.faults import NO_FAULTS

    try:
        simulator = make_simulator(
            args.world,
            profile,
            args.seed,
            random_start=args.random_start,
            faults=None if args.faults == NO_FAULTS else args.faults,
            coverage=True,
            battery=args.battery,
            trace=bool(args.plot),  # only a plot reads the trajectory
        )
    except WorldError as exc:
        from roomba_bt.cli.worlds_cmd import world_error_text

        return world_error_text(exc, "run")
    world = simulator.world
    if not (args.random_start and world.start_region is not None):  # its given start
        from roomba_bt.cli.worlds_cmd import world_warnings_text

        for line in world_warnings_text(world.warnings):
            print(line, file=sys.stderr)
    if args.random_start and world.start_region is None:  # eval says it too
        x, y = world.start.x / 1000.0, world.start.y / 1000.0
        print(
            f"roomba-bt run: warning: --random-start: world {world.name!r} has no "
            f"robot.start_region: the robot starts at its start pose ({x:.2f}, {y:.2f}) m "
            "whatever the seed",
            file=sys.stderr,
        )
    return simulator


def _live_monitor(
    args: argparse.Namespace,
    mission: Any,
    simulator: Simulator | None,
    packets: tuple[int, ...],
    params: dict[str, str],
    profile: RobotProfile,
) -> LiveMonitor:
    """``--monitor`` / ``--watch``: the page and the reloads read the same parameters."""
    from roomba_bt.mission import load_mission

    return LiveMonitor(
        MonitorOptions.from_args(args), mission, simulator=simulator, packets=packets,
        robot=args.robot,
        started=args.started, label=args.label or "",
        loader=lambda path: load_mission(
            path, params, profile=profile, baud=args.baud, permissions=permissions(args, path)
        ),
    )  # fmt: skip


def _run_and_report(
    args: argparse.Namespace,
    stack: RunStack,
    observer: TickObserver | None,
    simulator: Simulator | None,
    monitor: LiveMonitor | None,
) -> int:
    """The run, then what it did: the tree's last state, the summary, what went wrong."""
    mission = stack.mission
    quiet = args.display == "none"
    if quiet and not args.verbose:  # nothing but the summary (and what went wrong)
        logging.getLogger().setLevel(max(logging.getLogger().level, logging.WARNING))
    if not quiet:  # as show draws it: the live tree's names feed the log and the record
        print(_render_tree(mission), flush=True)
    stack.runner.gate = monitor.session if monitor is not None else None
    # after the safe stop a signal is ignored until the run is closed, then ends the process
    # (robot/safety.py, InterruptGuard)
    stack.runner.hold_interrupts = True
    # on the virtual clock nothing drives meanwhile: Ctrl-Z suspends, Ctrl-\ quits
    stack.runner.on_wall_clock = not args.fast
    stack.runner.names_slow_ticks = True  # a plugin's blocking update named, --fast too
    stack.runner.wall_limit_s = args.wall_limit_s  # a stuck tree named (eval's HUNG)
    closed = False
    try:
        raise_lost_interrupt(args)  # one Python dropped as a plugin imported: nothing sent
        summary = _run_held(args, stack, monitor)
        stack.close()
        closed = True
        # the record's end note is out, the monitor shut down, the port closed (its exclusive
        # mode cleared) and an undelivered stop tried again: the answer is known, and a
        # signal now lets the report finish (2 s at most: one blocked on a pipe nobody reads
        # can still be ended) and the process exit with it, 3 for a run that never started
        # (answer_given). The process's run handlers go first: given back after the report,
        # they made a signal then "interrupted by SIGTERM", exit 130 (a program's call keeps
        # the run's hold through the report and gets its own back after it, as ever)
        if getattr(args, "as_the_process", False):
            put_back = terminal_stops_kept()  # as the run held them, through the report
            stack.runner.release_interrupts()
            put_back()
            answer_given(summary.exit_code)
        _report(args, stack, summary, observer, simulator)
        return summary.exit_code
    except BaseException as exc:
        # roomba-bt's own bug (a display, the monitor, the record, the runner: a behaviour's
        # is the summary's ERROR) or an interrupt before the run took the signals: the port
        # is closed all the same (its exclusive mode, an undelivered stop tried again), then
        # the exception goes on to main(), which says it in one line (exit 70, or 130)
        if not closed:
            stack.close()
        if not isinstance(exc, KeyboardInterrupt):
            with contextlib.suppress(OSError):
                print(f"roomba-bt: the run ended on an internal error; {_stop_said(stack)}",
                      file=sys.stderr)  # fmt: skip
        raise
    finally:
        stack.runner.release_interrupts()  # the summary is out


def _run_held(args: argparse.Namespace, stack: RunStack, monitor: LiveMonitor | None) -> RunSummary:
    """The run itself, its log lines stamped with mission time, and the monitor told how it
    ended (the page says it): its summary. Ctrl-C and SIGTERM end it with its summary (exit
    130); anything raised here is roomba-bt's own bug."""
    from roomba_bt.runtime.display import logging_off_the_tick, use_mission_clock

    use_mission_clock(stack.runner, label=args.label or "")
    try:
        # a stalled terminal must not hold up the tick loop on the wall clock; on the virtual
        # clock nothing drives meanwhile, and no line is dropped
        with logging_off_the_tick(blocks=args.fast):
            return stack.run(raise_interrupts=False)  # Ctrl-C: the summary, exit 130
    finally:
        use_mission_clock(None)
        if monitor is not None:
            monitor.finish(stack.runner.summary)


def _stop_said(stack: RunStack) -> str:
    """Whether the robot was stopped, once the stack is closed, for a run that ended on an
    internal error (its summary may be unfinished): ``the robot was stopped (the safe stop
    was delivered)``, or ``safe stop`` and what the summary's line would say of a stop not
    known delivered, in its words (``NOT DELIVERED: ...`` only for a robot that may be
    moving: :func:`~roomba_bt.runtime.ending.undelivered_said`; it said so of a robot seen
    stopped that then fell asleep, where the summary said ``asleep and stopped``)."""
    from roomba_bt.runtime.ending import undelivered_said

    connection = stack.connection
    if connection.safe_stopped:
        return "the robot was stopped (the safe stop was delivered) and its port closed"
    said = undelivered_said(connection)
    return f"safe stop {said}{connection.stop_report or 'the port failed'}"


def _report(
    args: argparse.Namespace,
    stack: RunStack,
    summary: RunSummary,
    observer: TickObserver | None,
    simulator: Simulator | None,
) -> None:
    """What the run did: on stdout the tree and the summary; on stderr what went wrong; the
    plot. The robot is stopped: a stdout that fails meanwhile (a hang-up: EIO; ``| head``:
    EPIPE; a full disk) takes its own part with it, never the stderr lines or the plot, and
    the summary's outcome is then said on stderr; the exit code still says how the run
    ended."""
    from roomba_bt.cli.streams import failed_stdout

    lost = None
    try:
        _report_on_stdout(args, stack, summary, observer, simulator)
    except OSError as exc:  # not the process's guarded stdout: a program's own stream
        lost = exc.strerror or str(exc)
    lost = lost or failed_stdout(saying=True)
    plotted = _plot(simulator, args.plot) if args.plot and simulator is not None else None
    with contextlib.suppress(OSError):
        if lost is not None:
            print(f"roomba-bt: the summary was lost with stdout ({lost}): "
                  f"{_outcome_said(summary)}", file=sys.stderr)  # fmt: skip
        _report_on_stderr(args, stack, summary)
        if plotted:
            print(plotted, file=sys.stderr)


#: A stderr line longer than this is said a clause a line (:func:`_journal_lines`).
JOURNAL_LINE = 200


def _journal_lines(said: str) -> list[str]:
    """A lost link's stderr line, 400 characters and more (the cause, the watchdog, the
    grace, the queries, the stream asked for again, in one sentence), as a journal reads
    it: the cause first, then each of its clauses (its ``; ``, outside brackets) on a line
    of its own, indented; every word kept. A short one stays one line."""
    if len(said) <= JOURNAL_LINE:
        return [said]
    clauses, depth, start = [], 0, 0
    for at, char in enumerate(said):
        depth += (char == "(") - (char == ")")
        if depth == 0 and said.startswith("; ", at):
            clauses.append(said[start:at])
            start = at + 2
    clauses.append(said[start:])
    return [clauses[0], *(f"  {clause}" for clause in clauses[1:])]


def _outcome_said(summary: RunSummary) -> str:
    """The summary's outcome, final mode and safe stop in one line (``outcome SUCCESS;
    final mode Passive; safe stop sent drive, ...``), for stderr when stdout failed."""
    wanted = ("outcome", "final mode", "safe stop")
    said = [" ".join(line.split()) for line in summary.lines() if line.startswith(wanted)]
    return "; ".join(said)


def _report_on_stdout(
    args: argparse.Namespace,
    stack: RunStack,
    summary: RunSummary,
    observer: TickObserver | None,
    simulator: Simulator | None,
) -> None:
    from roomba_bt.runtime.display import TerminalDisplay

    if isinstance(observer, TerminalDisplay):
        if stack.runner.has_snapshot:
            observer.render(stack.runner, as_left=stack.runner.tree_as_left)  # not [-]: stopped
        observer.close()  # the last screen drawn before the report is printed under it
    if args.display != "none":  # as the run left it: its stop marks every node INVALID
        print(_render_tree(stack.mission, status=True, as_ticked=stack.runner.tree_as_left))
    print(summary)
    if simulator is not None and simulator.swept is not None and simulator.swept.cleaning_time:
        print(_coverage_line(simulator, sys.stdout))
    if simulator is not None:
        print(_where_it_ended(simulator))
        if not summary.stop_delivered:  # what the run could not see, the simulator can
            print(f"simulator    the robot ended in {simulator.mode.label}, wheels "
                  f"{simulator.requested_left:.0f}/{simulator.requested_right:.0f} mm/s "
                  "(the run could not confirm its stop)")  # fmt: skip
        from roomba_bt.sim.narrate import what_the_line_did

        line = what_the_line_did(simulator, "computer")
        if line is not None:  # the faults asked for, counted: beside what the run found
            print(f"simulator    {line}")
    sys.stdout.flush()  # here, where its failure is noted, not at the process's exit


def _report_on_stderr(args: argparse.Namespace, stack: RunStack, summary: RunSummary) -> None:
    if (
        summary.outcome.exit_code
        in (
            ExitCode.INVALID,  # a wrong profile: what the robot is, and the fix
            ExitCode.CONNECTION,
            ExitCode.LINK_LOST,
            ExitCode.MISSION_FAILED,
            ExitCode.BEHAVIOUR_ERROR,
        )
        and summary.reason
    ):
        # a node's name in it: one line; a long reason's short first line where it has one,
        # the summary above it saying it whole
        reason = escaped(summary.headline or summary.reason, ANY_CONTROL)
        pointer = " (the summary's outcome says what was seen)" if summary.headline else ""
        said = f"{summary.outcome.value}: {reason}{pointer}"
        for line in _journal_lines(said) if summary.outcome is Outcome.CONNECTION_LOST else [said]:
            print(f"roomba-bt: {line}", file=sys.stderr)
    if summary.failed_strict:  # the outcome reads SUCCESS: say why the exit code is not 0
        findings = escaped("; ".join(summary.strict_findings()), ANY_CONTROL)
        print(f"roomba-bt: --strict: {findings}", file=sys.stderr)
    if summary.outcome is Outcome.TIMEOUT and _fast_limit(args):
        print("roomba-bt: no --timeout was given; give one to change the limit (--timeout 10h "
              "for a longer run)", file=sys.stderr)  # fmt: skip
    turned_away = isinstance(summary.link_error, TurnedAway)  # doctor would be turned away too
    if summary.outcome is Outcome.NO_CONNECTION and args.port and not turned_away:
        # doctor tries what start-up does not: each rate, a BRC pulse or a hang-up to wake it
        print(f"roomba-bt: `roomba-bt doctor --port {args.port}` finds the robot's rate, wakes "
              "it if it sleeps and says what else is wrong", file=sys.stderr)  # fmt: skip
    if summary.traceback:
        if getattr(args, "verbose", 0):
            print(summary.traceback, file=sys.stderr, end="")
        else:
            print("roomba-bt: run with -v for the traceback", file=sys.stderr)
    for refusal in stack.runner.refusals[:SHOWN_REFUSALS]:
        print(f"refused: {refusal}", file=sys.stderr)
    if summary.refused_commands > SHOWN_REFUSALS:  # the count is all of them: say the rest
        more = summary.refused_commands - SHOWN_REFUSALS
        print(f"refused: ... and {more} more (the summary counts them)", file=sys.stderr)
    for hint in stack.runner.refusals.hints():
        print(f"refused: {hint}", file=sys.stderr)


def _render_tree(mission: Any, status: bool = False, as_ticked: Any = None) -> str:
    """The tree as py_trees draws it, each name and message escaped to one line (a plugin's
    ``feedback_message`` reached the terminal raw: :func:`~roomba_bt.runtime.display.text_tree`),
    in the symbols and colours stdout can show (:func:`~roomba_bt.runtime.display.tree_symbols`:
    ``[ok]`` on an ASCII stdout, no colour with ``NO_COLOR``); ``as_ticked``: the statuses
    as the run left them (a :class:`~roomba_bt.runtime.display.TreeStatuses`). Each node is
    named as ``show`` names it (``timeout(after=2s)``, a node's ``name:`` after what it is:
    ``CompiledMission.reviewed_names``), before the run and after it: the live nodes' names,
    ``timeout``, made a user comparing it with ``show`` see two trees. The live names stay
    what the log and the record say (a golden recording holds them)."""
    from roomba_bt.runtime.display import text_tree, tree_symbols

    symbols = tree_symbols(sys.stdout)
    reviewed_names = getattr(mission, "reviewed_names", None)
    names = reviewed_names() if reviewed_names is not None else None
    return text_tree(
        mission.root, show_status=status, symbols=symbols, as_ticked=as_ticked, names=names
    )


def _where_it_ended(simulator: Any) -> str:
    """What the simulator saw of the robot at the end, which the robot's own sensors do not
    say: it fell off a drop (only the plot showed it; the summary read SUCCESS), or it is on
    the dock's contacts (and charging), or neither."""
    fell = next((e for e in simulator.events if e.kind == "fell"), None)
    if fell is not None:
        where = f"({fell.x / 1000:.2f}, {fell.y / 1000:.2f}) m at {fell.time:.1f} s"
        return (f"simulator    the robot FELL off a drop at {where} (a wheel went past the "
                "edge: Full mode, a reverse the Safe-mode cliff stop does not cover, or a "
                "mission that drove on)")  # fmt: skip
    if simulator.docked:
        charging = ", charging" if simulator.dock_powered else ", the dock unpowered"
        return f"simulator    ended on the dock's contacts{charging}"
    return (f"simulator    ended at ({simulator.x / 1000:.2f}, {simulator.y / 1000:.2f}) m, "
            "off the dock")  # fmt: skip


def _coverage_line(simulator: Any, stream: object) -> str:
    """``coverage 84.2 % of 36.7 m² (living-room 91 %, bedroom 80 %, ...)``; ``m2`` where
    ``stream`` cannot show ``²`` (an ASCII or Latin-1-less stdout)."""
    swept = simulator.swept
    swept.finish(simulator.time, simulator.x, simulator.y, simulator.theta)
    areas = ", ".join(f"{name} {100 * c:.0f} %" for name, c in swept.coverage_by_area().items())
    reachable = swept.area_m2(swept.reachable_total)
    m2 = "m\u00b2" if encodes(stream, "\u00b2") else "m2"
    return f"coverage     {100 * swept.coverage():.1f} % of {reachable:.1f} {m2} of reachable " + (
        f"floor ({areas})" if areas else "floor"
    )


def _plot(simulator: Any, path: str) -> str:
    try:
        from roomba_bt.sim.plot import plot_run
    except ImportError as exc:
        return f"--plot: {exc}"
    try:
        plot_run(simulator, path)
    except ImportError as exc:  # pyplot's PlotUnavailableError is said as it is
        needs = f"matplotlib is not installed (pip install 'roomba-bt[plot]'): {exc}"
        return f"--plot: {optional_import_failure(exc, needs)}"
    except OSError as exc:
        return f"--plot {path}: {exc.strerror or exc}"
    return f"trajectory written to {path}"


class Recorded(NamedTuple):
    """What a recorded run is replayed with (``replay``, the monitor's recorded runs)."""

    record: Record
    mission: Any
    profile: RobotProfile
    baud: int
    packets: tuple[int, ...]


def load_recorded(args: argparse.Namespace) -> Recorded | int:
    """The record ``args.record``, its mission (``--mission``, else the recorded one, by path
    or shipped name; ``-p`` over the recorded parameters; ``--allow-plugin-files``; the
    include folders its run was granted, where the record may grant them), profile, baud and
    packets; or an exit code after printing what is wrong."""
    from roomba_bt.runtime.provenance import absent_plugins
    from roomba_bt.runtime.recording import RecordError, load_record

    try:
        record = load_record(args.record)  # its header's fields checked there
    except RecordError as exc:
        return _error(str(exc), args.command)
    header = record.header
    profile = get_profile(header.get("profile", "create2"))
    mission_path = args.mission or header.get("mission")
    if not args.mission:
        mission_path = _from_the_record(args.record, header)
    found = _recorded_mission(
        args.record, mission_path, given=bool(args.mission), command=args.command
    )
    if isinstance(found, str) and not args.mission:
        which = _shipped_file_replayed(args.record, header, mission_path, found)
        if which is not None:
            print(which, file=sys.stderr)
    if isinstance(found, int):
        return found
    params = {name: str(value) for name, value in (header.get("parameters") or {}).items()}
    extra = parse_params(args.param)
    if isinstance(extra, str):
        return _error(extra, args.command)
    params.update(extra)
    baud: int = header.get("baud", 115200)
    granted = permissions(args, found)
    recorded_dirs = replayed_include_dirs(args.record, header, found)
    granted = replace(
        granted, include_dirs=tuple(dict.fromkeys((*granted.include_dirs, *recorded_dirs)))
    )
    absent = absent_plugins(header)
    mission = load(found, params, profile, baud, granted, absent)
    if isinstance(mission, int):
        if not args.mission:  # the errors above say what to write; this, where it goes
            said = _refused_recorded_mission(
                header, found, bool(args.allow_plugin_files), [p.name for p in absent]
            )
            print(said, file=sys.stderr)
        return mission
    packets = _recorded_packets(args.record, header, mission, found)
    if isinstance(packets, str):
        return _error(packets, args.command)
    return Recorded(record, mission, profile, baud, packets)


def _refused_recorded_mission(
    header: dict[str, Any], found: str, plugins_allowed: bool, absent: list[str]
) -> str:
    """What ``replay`` adds when the record's own mission no longer compiles (a 0.1.0
    mission that this release refuses): that the record is not at fault, and how to replay it
    after fixing the file. The validation errors alone left the upgrader to find
    ``--mission``, with which such a record replays byte for byte. A run that was allowed
    its plugin files (the header's ``options.allow_plugin_files``, never honoured: a record
    may come from someone else) is replayed with them only by ``--allow-plugin-files``
    (``plugins_allowed``): that is the fix then, where "fix a copy" sent the user to edit a
    mission that was whole; so is installing the plugin packages the run used that are not
    here as they were (``absent``, said first with the ``pip install`` that brings each)."""
    from roomba_bt import __version__
    from roomba_bt.runtime.provenance import UPGRADING, made_by_said
    from roomba_bt.runtime.recording import MADE_BY, header_text

    options = header.get("options")
    allowed_then = isinstance(options, dict) and options.get("allow_plugin_files") is True
    if allowed_then and not plugins_allowed:
        return (
            f"replay: the record's run was allowed the plugin files of its mission "
            f"{header_text(found)} (--allow-plugin-files); a replay imports them only when "
            "told: pass --allow-plugin-files if you trust them (they run as Python code)"
        )

    if absent:  # the mission is whole: its plugin is not here
        named = " and ".join(absent)
        return (
            f"replay: the record's mission {header_text(found)} names behaviours of plugin "
            f"{named}, not installed here as the record's run had it: install it as said "
            "above and replay again (the mission needs no fix)"
        )
    # the upgrade notes only where another release made the record (a file edited since is
    # refused by the release that made it too)
    notes = "" if header.get(MADE_BY) == __version__ else f' (the CHANGELOG\'s "{UPGRADING}")'
    return (
        f"replay: the record's mission {header_text(found)} is refused by roomba-bt "
        f"{__version__}; the "
        f"record was made by {made_by_said(header)}: fix a copy as said above{notes} and "
        "pass --mission FILE with the fixed file to replay this record"
    )


def _recorded_mission(
    record_path: str, mission_path: object, *, given: bool, command: str
) -> str | int:
    """The mission file a replay compiles: ``--mission`` (``given``), else the record's own,
    a path or a shipped mission's name (``roomba-bt:dock.yaml``, what a record of ``run
    dock`` holds). An older record holds a shipped mission's path in the installation that
    made it (``.../site-packages/roomba_bt/missions/dock.yaml``), which a
    moved venv, a new Python or another machine lacks: this installation's shipped mission of
    that name is replayed, and said so (its changes since are said as any file's are), rather
    than "not found; pass --mission dock", which would refuse an old record of ``run dock`` on
    every machine but the one that made it. An exit code after saying what is missing."""
    from roomba_bt import __version__
    from roomba_bt.mission.shipped import SHIPPED_PREFIX

    found = mission_file(str(mission_path)) if mission_path else None
    if isinstance(found, str):
        return found
    shipped = None if given else shipped_mission_at(mission_path)
    if shipped is not None:
        print(
            f"{record_path}: mission {mission_path!r} is not here (the installation that made "
            f"the record had it); replaying the shipped mission {shipped!r} of roomba-bt "
            f"{__version__}; --mission FILE replays another",
            file=sys.stderr,
        )
        return str(mission_file(shipped))
    gone = ""
    if isinstance(mission_path, str) and mission_path.startswith(SHIPPED_PREFIX) and not given:
        gone = f" (shipped with the roomba-bt that made the record, not with {__version__})"
    return _error(
        f"{record_path}: mission {mission_path!r} not found{gone}; pass --mission FILE", command
    )


def _shipped_file_replayed(
    record_path: str, header: dict[str, Any], named: object, found: str
) -> str | None:
    """Which file a replay of a shipped mission's record reads, when it may not be the one
    the run read: another installation's shipped file, still on this machine (a 0.1.0 record
    names the path in the venv that made it), or this installation's, when another release
    made the record (its mission may have changed since). Either was replayed without a word,
    and a difference read as the mission's. None when the record names no shipped mission,
    or this release's shipped file and this release made the record, or when
    :func:`_recorded_mission` said already that it replays this installation's."""
    from roomba_bt import __version__
    from roomba_bt.mission.shipped import SHIPPED_PREFIX
    from roomba_bt.runtime.provenance import made_by_said
    from roomba_bt.runtime.recording import MADE_BY

    if not isinstance(named, str):
        return None
    name = shipped_mission_at(named)
    if name is not None and not Path(named).is_file():
        return None  # gone: _recorded_mission said it replays this installation's
    if name is None and named.startswith(SHIPPED_PREFIX):
        name = named.removeprefix(SHIPPED_PREFIX).removesuffix(".yaml")
    ours = mission_file(name) if name is not None else None
    if name is None or not isinstance(ours, str):
        return None
    made_by = made_by_said(header)
    if Path(found).resolve() != Path(ours).resolve():
        return (
            f"{record_path}: replaying {found}, the shipped mission {name!r} of the "
            f"installation that made the record ({made_by}), not this installation's "
            f"({ours}, roomba-bt {__version__}): --mission {name} replays this one's"
        )
    if header.get(MADE_BY) == __version__:
        return None
    return (
        f"{record_path}: replaying the shipped mission {name!r} of roomba-bt {__version__} "
        f"({ours}); the record was made by {made_by}, whose {name!r} may differ: --mission "
        "FILE replays another"
    )


def _from_the_record(record_path: str, header: dict[str, Any]) -> object:
    """The header's mission as a path a replay opens: one relative to the record's folder
    (``../missions/dock.yaml``, what ``run --record`` writes) from there, or,
    where the record was moved away from it, its absolute path when recorded (``mission_path``),
    said on stderr; else as the header says it (a shipped name, an older record's path).
    Relative, so that a record committed beside its missions is found in every other
    checkout."""
    from roomba_bt.runtime.recording import MISSION_AT, header_text, recorded_path

    named = header.get("mission")
    if not isinstance(named, str) or Path(named).is_absolute():
        return named
    here = recorded_path(named, header, Path(record_path))
    if here is None:  # a shipped name, or a record made before (relative to the cwd)
        return named
    if here.is_file():
        return str(here)
    there = header.get(MISSION_AT)
    if isinstance(there, str) and Path(there).is_file():
        print(
            f"{record_path}: mission {named!r} is not beside the record "
            f"({header_text(str(here))}); replaying {header_text(there)}, where it was recorded",
            file=sys.stderr,
        )
        return there
    return str(here)


def shipped_mission_at(path: object) -> str | None:
    """The shipped mission's name a recorded mission path shows it was (a record of
    ``run dock`` holds ``.../site-packages/roomba_bt/missions/dock.yaml``: a moved venv or a
    new Python loses the path, not the mission), or None."""
    from roomba_bt.mission.shipped import shipped_missions

    if not isinstance(path, str):
        return None
    where = Path(path)
    if (where.parent.name, where.parent.parent.name) != ("missions", "roomba_bt"):
        return None
    return where.stem if where.suffix == ".yaml" and where.stem in shipped_missions() else None


def replay_command(args: argparse.Namespace) -> int:
    from roomba_bt.monitor.recorded import operator_replay, replay_judged
    from roomba_bt.runtime.display import StatusChangeLogger, TreeAsTicked
    from roomba_bt.runtime.recording import ending_text

    window = parse_window(args)
    if isinstance(window, str):
        return _error(window, args.command)
    recorded = load_recorded(args)
    if isinstance(recorded, int):
        return recorded
    record = recorded.record
    raise_lost_interrupt(args)  # one Python dropped as the record was read: no replay
    # the tree as its last tick left it: a replay ended by a difference stops it (all INVALID)
    as_ticked = TreeAsTicked() if args.display == "tree" else None
    observer = StatusChangeLogger() if args.display == "log" else as_ticked
    # a record whose run lost its link: its summary says that run's end, not the replay's stop
    summary, transport, lost = replay_judged(
        record, recorded.mission, profile=recorded.profile, packets=recorded.packets,
        baud=recorded.baud, name=args.record, raise_interrupts=False,
        progress=replay_progress("replay", record),
        gate=operator_replay(record, recorded.mission),  # the monitor's pauses, steps, forces
        until=window[1],
        observer=observer,
        stamp_logs=True,  # a mission's log lines with their t=, as the recorded run's
    )  # fmt: skip
    summary.strict_named = "run --strict"  # its warning of refusals: what would fail a run
    summary.label = record.label  # replays of several robots' runs told apart, as the runs
    if args.display == "tree":
        print(_render_tree(recorded.mission, status=True, as_ticked=as_ticked))
    print(summary)
    if summary.outcome is Outcome.INTERRUPTED:  # a signal's (the record's own stops are its
        # end: INPUT_ENDED): the operator's stop, exit 130, not a verdict on bytes it cut
        # short (its stop's drive 0 was "the first difference", exit 1, or 0 where it matched)
        print(
            f"replay: interrupted at mission time {summary.mission_time_s:.3f} s of "
            f"{record.last_t:.3f} s: no verdict on the tree's bytes"
        )
        return ExitCode.INTERRUPTED
    code = _replay_verdict(summary, transport, recorded, lost)
    ending = record.ending  # its end note, said last (a record made before has none)
    if ending is not None and lost is None:  # a lost link's: the summary's outcome said it
        print(f"replay: {ending_text(ending)}")
    return code


def _replay_verdict(
    summary: RunSummary,
    transport: ReplayTransport,
    recorded: Recorded,
    lost: tuple[str, str] | None,
) -> int:
    """What ``replay`` says of the bytes the tree wrote against the record's, printed, and
    its exit code: the same (0), the same up to where the recorded run's link failed
    (``lost``: :func:`~roomba_bt.runtime.stack.past_the_link_loss`'s sentences; 0), or the
    first difference, with what changed since the record was made (1)."""
    from roomba_bt.runtime.provenance import changed_plugins, changed_sources, drift_line
    from roomba_bt.runtime.recording import END_IN_UNSAID, end_in_unsaid, miscount_said

    record, mission = recorded.record, recorded.mission
    difference = transport.first_difference()
    if lost is not None:  # the same up to where the recorded run's link failed
        print(*(f"replay: {line}" for line in lost), sep="\n")
        return ExitCode.OK
    sources = changed_sources(record.header, mission.files, record.path)
    plugins = changed_plugins(record.header, mission.root)
    # what the replay ran on, said before its verdict: one line, when it is not what the
    # record was made with
    drift = drift_line(record.header, sources, plugins, same_bytes=difference is None)
    if drift is not None:
        print(f"replay: {drift}")
    compared, same = _compared(summary, transport, record, record.end_said())
    if compared is not None:
        print(compared)
    if difference is None:
        if record.miscounted is not None:  # an older record's end note, not the tree
            print(f"replay: {miscount_said(*record.miscounted)}")
        print(same)
        return ExitCode.OK
    offset, expected, sent = difference
    print(
        f"replay: first difference at mission time {summary.mission_time_s:.3f} s "
        f"(byte {offset} of {record.out_bytes} recorded): expected {expected}, sent {sent}"
    )
    for changed in (*sources, *plugins):
        print(f"replay: {changed}")
    stop_for_start = expected.startswith("Stop (173)") and sent.startswith("Start (128)")
    if stop_for_start and end_in_unsaid(record.header):  # its last bytes no stop's either
        print(f"replay: {END_IN_UNSAID}")
    unplayed = operator_acts(record)
    if unplayed:
        print(
            f"replay: the recorded run holds operator acts replay cannot do again ({unplayed}): "
            "a reload (the record has no copy of the new mission), or an act a record made "
            "before noted without its tick"
        )
    return ExitCode.MISSION_FAILED


def _compared(
    summary: RunSummary, transport: ReplayTransport, record: Record, unended: str | None
) -> tuple[str | None, str]:
    """What ``replay`` says of how far it compared (None: the whole record), and its verdict
    where the tree wrote the same bytes: up to ``--to`` (the transport ``ended_early``), up to
    where a record without its run's end ends (``unended``: :meth:`Record.end_said
    <roomba_bt.runtime.recording.Record.end_said>`, which the monitor's view says too), or
    the whole run."""
    if transport.ended_early:
        return (
            f"replay: compared up to mission time {summary.mission_time_s:.3f} s (--to); the "
            f"record goes on to {record.last_t:.3f} s",
            "replay: the tree wrote the same bytes up to there",
        )
    if unended is not None:
        return (
            f"replay: {unended}",
            f"replay: the tree wrote the same {record.out_bytes} bytes up to there",
        )
    return None, f"replay: the tree wrote the same {transport.written} bytes as the recorded run"


#: A record this long (about 20 minutes of a run) says how far its replay has gone.
PROGRESS_FROM_BYTES = 16 << 20


def replay_progress(who: str, record: Record) -> Callable[[float], None] | None:
    """What says, on stderr, how far the replay of a long record has gone (``replay: 30 %
    of long.jsonl (36:00 of 2:00:00)``); None for a short one. A 2-hour record took minutes
    to replay and said nothing meanwhile."""
    if record.size < PROGRESS_FROM_BYTES:
        return None
    total = record.last_t

    def progress(fraction: float) -> None:
        print(
            f"{who}: {fraction:.0%} of {record.path} ({_clock(fraction * total)} of "
            f"{_clock(total)} of the run)",
            file=sys.stderr, flush=True,
        )  # fmt: skip

    return progress


def _clock(seconds: float) -> str:
    minutes, secs = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def operator_acts(record: Record) -> str:
    """The monitor's acts the record notes that a replay cannot do again (``reload at 5.30
    s``), the first few; empty when there are none. A reload (the record has no copy of the
    mission it loaded), and an act noted without its tick (a record made before they had
    one); the others replay where they were done (``monitor/recorded.py``)."""
    acts = [
        f"{act} at {t:.2f} s"
        for t, note in record.notes
        for act in ("pause", "resume", "force", "reload")
        if act in note and (act == "reload" or not isinstance(note.get("tick"), int))
    ]
    return ", ".join(acts[:4]) + (", ..." if len(acts) > 4 else "")


def _recorded_packets(
    record_path: str, header: dict[str, Any], mission: Any, mission_path: str
) -> tuple[int, ...] | str:
    """The packets the record streams, or what is wrong: none listed, or the mission reads
    one the record lacks."""
    from roomba_bt.mission import RUNTIME_PACKETS

    recorded = header.get("packets")
    if not isinstance(recorded, list) or not all(isinstance(p, int) for p in recorded):
        return f'{record_path}:1: the header lists no stream packets ("packets")'
    missing = sorted((set(mission.packets) | set(RUNTIME_PACKETS)) - set(recorded))
    if missing:
        return (
            f"{record_path}: the recording streams packets {sorted(recorded)} but "
            f"{mission_path} reads {missing} too: it cannot be replayed against this mission "
            "(record it again with this mission)"
        )
    return tuple(recorded)
