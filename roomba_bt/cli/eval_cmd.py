"""``roomba-bt eval``: how often does a mission succeed, and how fast? Did my change help?

    roomba-bt eval missions/dock.yaml --world empty-room --runs 200 --seed 1 --within 1.5 \
        --jobs 2 --plot dock.png --out results.jsonl
    roomba-bt eval A.yaml B.yaml --runs 100 --scheduler tcp://HOST:8786     # A/B, on Dask
    roomba-bt eval dock.yaml --sweep speed=150mm/s,200mm/s,250mm/s          # a sweep

Runs N seeded episodes of the mission on the simulator's virtual clock, from random start
poses in the world's start region (or within ``--within``, 1.5 or 1.5m, of the dock), in ``--jobs``
worker processes, with a progress bar on stderr; then prints the success rate with its 95 %
Wilson interval, the median and p90 time, bumps, the robot's own falls to Passive on a hazard
(``run``'s ``falls`` line summed, and in how many episodes) apart from the dockings (its drop
to Passive on the charger), and the failure reasons grouped. The same
``--seed`` gives the same episodes whatever ``--jobs`` or engine (``--engine dask``: a local
Dask cluster of ``--jobs`` workers; ``--scheduler``: an existing one). With two missions, a
``--sweep`` or ``--variant`` sets, every variant runs on the same seeds and start poses and
each is compared with the first (A): paired successes, the exact McNemar p-value, the median
time difference with its interval. ``--out`` writes one record per episode (JSON Lines or
CSV; one that already holds episodes is refused unless ``--force``, or ``--resume``: only the
(variant, seed) pairs it lacks run, :mod:`roomba_bt.cli.eval_resume`), ``--json`` prints the
summary as JSON; ``--seeds 1-40,42`` runs a list of seeds, ``--from FILE...`` reports on
results already written (:mod:`roomba_bt.cli.eval_from`). Variants run interleaved by seed
(A1 B1 A2 B2 ...), so an interrupted A/B is a smaller paired one. For a mission that runs the
brushes, the
floor covered at 5, 10 and 20 minutes and at the end (mean, sd, min..max; of ``--start-area``
if given; per area at the end) and how many episodes went a minute of brush time without
new floor. An episode still running after ``--wall-limit`` of wall-clock time (stuck in a
behaviour's loop: the virtual clock does not move) is recorded as HUNG, where it was stuck,
and its worker process replaced; one whose worker process dies running it, again when it runs
alone (``os._exit`` in a behaviour, a crash in C code), is recorded as DIED and the sweep goes
on. Ctrl-C prints what finished (exit 130). Exit codes: 0 (and 1 when ``--min-rate`` is given
and not reached), 2 for invalid input, 3 when the run environment failed: the ``--scheduler``
does not answer or is lost, the Dask cluster had no worker for ``--worker-wait``, local
worker processes were killed from outside again and again (what finished is summarised), or
a worker cannot compile a mission this machine compiled (a plugin not installed there), 4
when a behaviour raised in an episode, one ran past ``--wall-limit`` or one killed its worker
(a bug, not a mission outcome), 7 with ``--strict`` when a mission has compile-time warnings
(no episode runs), 70 on roomba-bt's own bug.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import (
    add_battery_option,
    add_command,
    add_fault_options,
    add_odometry_error_option,
    add_param_option,
    add_permission_options,
    add_profile_option,
    add_strict_option,
    add_wall_limit_option,
    fault_options_set,
    faults_given,
    fraction,
    given_once,
    limit_seconds,
    metres,
    mission_file,
    parse_params,
    parse_timeout,
    permissions,
    plot_file,
    results_file,
    seed_list,
)
from roomba_bt.cli.eval_from import add_from_option, report_from_files
from roomba_bt.cli.eval_report import (
    Evaluated,
    Variant,
    count_episodes,
    finished_said,
    interruption_of,
    print_report,
    refusal_as_json,
    refused,
    statistics,
    verdict,
    wall_limit,
)
from roomba_bt.cli.eval_resume import add_resume_options
from roomba_bt.cli.record_header import add_reproducible_option
from roomba_bt.printable import ANY_CONTROL, duration_said, escaped
from roomba_bt.runtime.summary import INTERNAL_ERROR_SAID, ExitCode

if TYPE_CHECKING:  # the evaluation is imported when it runs: the CLI starts faster
    from collections.abc import Sequence

    from roomba_bt.cli.eval_resume import Resumed
    from roomba_bt.cli.validate_report import Checked
    from roomba_bt.evaluate import EvaluationError
    from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, MissionNotCompiled
    from roomba_bt.evaluate.parallel import Engine, Evaluation, Interruption, Progress
    from roomba_bt.evaluate.plan import EpisodePlan
    from roomba_bt.evaluate.records import PartialResults
    from roomba_bt.mission import Diagnostic, Permissions
    from roomba_bt.sim.world import World


def register(sub: Any) -> None:
    ev = add_command(
        sub,
        "eval",
        eval_command,
        f"""run missions many times on the simulator: success rates

        Run MISSION in N seeded episodes on the simulator's virtual clock and report the success
        rate (95% Wilson interval), median and p90 time, bumps, the robot's own falls to
        Passive on a hazard, the dockings and the failure reasons. Exit codes:
        0 done, 1 --min-rate not reached, 2 invalid input, 3 the run environment failed:
        --scheduler unreachable or lost, no Dask worker for --worker-wait, local worker
        processes killed from outside again and again (what finished is summarised), a
        worker that cannot compile a mission (a plugin not installed there), 4 a
        behaviour raised in an episode, one hung (--wall-limit) or killed its worker process
        (DIED), 7 with --strict, a mission has compile-time warnings (no episode runs),
        {INTERNAL_ERROR_SAID}, 130 interrupted by Ctrl-C or a signal (what finished is
        summarised).
        """,
    )
    ev.add_argument(
        "missions",
        nargs="*",
        metavar="MISSION",
        help="mission YAML file or a shipped mission's name (dock); two or more: compare them "
        "(A/B) on the same seeds",
    )
    add_from_option(ev)
    _add_episode_options(ev)
    _add_output_options(ev)
    _add_start_options(ev)
    add_resume_options(ev)
    add_permission_options(ev)


def _add_episode_options(ev: argparse.ArgumentParser) -> None:
    """The world, how many episodes from which seed, and where they run."""
    ev.add_argument("--world", default="empty-room", help="a shipped world name or a YAML path")
    ev.add_argument("--runs", type=int, help="number of episodes (default 20)")
    ev.add_argument("--seed", type=int, help="first seed (default 0)")
    ev.add_argument(
        "--seeds", type=seed_list, metavar="LIST",
        help="run these seeds instead of --seed and --runs: 1-40,42,43, each range low to "
        "high (each variant; run and written in the order given; a seed given twice is "
        "refused)",
    )  # fmt: skip
    ev.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="worker processes, or the local Dask cluster's workers (default 1)",
    )
    ev.add_argument(
        "--engine",
        choices=("local", "dask"),
        default="local",
        help="local processes (default) or Dask distributed (the cluster extra)",
    )
    ev.add_argument(
        "--scheduler",
        metavar="tcp://HOST:8786",
        help="run on this Dask scheduler's cluster (implies --engine dask)",
    )
    ev.add_argument(
        "--worker-wait",
        metavar="DURATION",
        help="on Dask: stop when the cluster has had no worker this long (exit 3; what "
        "finished is summarised and written); default 2min; none: wait for ever",
    )


def _add_output_options(ev: argparse.ArgumentParser) -> None:
    """What is written (records, JSON, a plot) and the variants compared."""
    ev.add_argument(
        "--out", metavar="FILE", type=results_file,
        help="one record per episode: .jsonl (JSON Lines) or .csv",
    )  # fmt: skip
    ev.add_argument("--json", action="store_true", help="print the summary as JSON")
    ev.add_argument(
        "--key", action="append", default=[], metavar="NAME",
        help="report this blackboard key's value at each episode's end (repeatable; "
        "wp.distance: a record's field): a key:NAME column in --out, a summary line (numbers: "
        "mean, sd, min..max; else counts per value) and how many episodes never wrote it",
    )  # fmt: skip
    add_reproducible_option(ev)
    ev.add_argument(
        "--sweep",
        metavar="NAME=V1,V2,...",
        help="one variant per value of a mission parameter, compared with the first",
    )
    ev.add_argument(
        "--variant",
        action="append",
        default=[],
        metavar="NAME=VALUE[;NAME=VALUE]",
        help="a variant: these parameters on top of -p (repeatable; compared with the first)",
    )
    ev.add_argument(
        "--plot", metavar="FILE", type=plot_file,
        help="draw every trajectory (matplotlib), a panel per variant side by side; the "
        "suffix is the format: .png, .pdf, .svg or another matplotlib writes; with --resume "
        "the episodes read back run again for their paths",
    )  # fmt: skip


def _add_start_options(ev: argparse.ArgumentParser) -> None:
    """How each episode starts (pose, parameters, dock, charge), its limits, and CI's bar."""
    ev.add_argument(
        "--within", type=near_dock_distance, metavar="DISTANCE",
        help="start within this distance of the docked pose: metres (1.5) or with a unit "
        "(1.5m, 150cm); 0.05..20 m (default: the world's region)",
    )  # fmt: skip
    ev.add_argument(
        "--start-area", metavar="NAME",
        help="start in this named area of the world (the apartment's living-room, bedroom, "
        "kitchen); its coverage is the one reported",
    )  # fmt: skip
    add_param_option(ev, "set a mission parameter (repeatable)")
    ev.add_argument(
        "--dock",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="override a dock beam parameter: buoy_range=0.5 (m), force_field=0.3 (m), "
        "red=-5,25 (deg), green=-25,5, contact_tolerance=0.05 (m), angle_tolerance=6 (deg), "
        "family=discovery (characters 240-254); each in the range a world file's dock allows",
    )
    add_battery_option(ev)
    add_odometry_error_option(ev)
    add_fault_options(
        ev, "what goes wrong on the line and in the robot, in every episode, each drawing "
        "from its own seed (a sweep is repeatable); the same options as sim's",
    )  # fmt: skip
    ev.add_argument("--timeout", default="15min", help="mission time per episode (default 15min)")
    add_wall_limit_option(
        ev, "per episode",
        "and its worker process ended; default 60 s plus a tenth of --timeout; none: no "
        "limit, and --jobs 1 runs the episodes in this process",
    )  # fmt: skip
    add_profile_option(ev, "the simulated robot's model")
    ev.add_argument("--min-rate", type=fraction, metavar="FRACTION",
                    help="exit 1 if the success rate is below this, a fraction (0.9) or a "
                    "percent (90%%) (for CI)")  # fmt: skip
    add_strict_option(ev, "(no episode runs when one of the missions has any)")
    ev.add_argument("--no-progress", action="store_true", help="no progress bar")


def near_dock_distance(text: str) -> float:
    """``--within``: metres (``1.5``) or a distance (``1.5m``, ``150cm``), in the range of a
    world's ``start_region.near_dock`` (500 m blamed the world: "no free pose")."""
    from roomba_bt.sim.world import NEAR_DOCK_RANGE_M

    return metres(text, *NEAR_DOCK_RANGE_M)


def parse_dock(items: list[str]) -> tuple[tuple[str, Any], ...] | str:
    """``["buoy_range=0.5", "red=-5,25"]`` -> ((name, value), ...); a message on error. Each
    number in the range a world file's ``dock:`` allows (the same table: ``DOCK_LIMITS``)."""
    from roomba_bt.evaluate.episode import DOCK_OVERRIDES
    from roomba_bt.sim.world import DOCK_BEAM_LIMIT, DOCK_FAMILIES, DOCK_LIMITS

    out: list[tuple[str, Any]] = []
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or name not in DOCK_OVERRIDES:
            return (
                f"--dock {item!r}: expected FIELD=VALUE with FIELD one of "
                f"{', '.join(DOCK_OVERRIDES)}"
            )
        try:
            if name == "family":
                if text not in DOCK_FAMILIES:
                    return f"--dock {item!r}: family is {' or '.join(DOCK_FAMILIES)}"
                out.append((name, text))
            elif name in ("red", "green"):
                lo, hi = (float(v) for v in text.split(","))
                beam = DOCK_BEAM_LIMIT
                if not (beam.holds(lo) and beam.holds(hi) and lo < hi):
                    return (
                        f"--dock {name}={text.strip()}: expected FROM,TO in degrees, "
                        f"{beam.lo:g} <= FROM < TO <= {beam.hi:g}"
                    )
                out.append((name, (lo, hi)))
            else:
                value = float(text)
                limit = DOCK_LIMITS[name]
                if not limit.holds(value):
                    return f"--dock {name}={text.strip()}: expected {limit.allowed()}"
                out.append((name, value))
        except ValueError:
            return f"--dock {item!r}: {text!r} is not a number (or FROM,TO for red/green)"
    return tuple(out)


def variants(args: argparse.Namespace, params: dict[str, str]) -> list[Variant] | str:
    """The missions x (sweep values or variant sets); a message on error."""
    sets = _variant_sets(args, params)
    if isinstance(sets, str):
        return sets
    from roomba_bt.evaluate.interleave import variant_label

    out = []
    for mission in args.missions:
        for extra, given_as in sets:
            merged = {**params, **extra}
            path = getattr(args, "mission_paths", {}).get(mission, mission)
            name = results_name(mission, path)
            # a shipped mission as --from labels its records: dock, however it was named
            label = variant_label(name, params.items(), extra.items())
            out.append(Variant(label, name, tuple(sorted(merged.items())), path,
                               tuple(extra.items()), given_as))  # fmt: skip
    if len({v.label for v in out}) < len(out):
        return "the same variant twice: give each mission or value once"
    return out


def _variant_sets(
    args: argparse.Namespace, params: dict[str, str]
) -> list[tuple[dict[str, str], str]] | str:
    """Each variant's own parameters and how the command line gave them (``--sweep``'s
    values, ``--variant``'s sets; one empty set without either); a message on error."""
    if args.sweep and args.variant:
        return "--sweep and --variant: give one or the other"
    if args.sweep:
        name, sep, values = args.sweep.partition("=")
        if not sep or not name.strip() or not values.strip():
            return f"--sweep {args.sweep!r}: expected NAME=V1,V2,..., e.g. speed=150mm/s,200mm/s"
        if name.strip() in params:  # the sweep's values would win, and -p's never run
            return f"-p {name.strip()} and --sweep {name.strip()}: give its values in --sweep alone"
        return [({name.strip(): v.strip()}, "--sweep") for v in values.split(",") if v.strip()]
    sets: list[tuple[dict[str, str], str]] = []
    for item in args.variant:
        parsed = parse_params([p for p in item.split(";") if p.strip()])
        if isinstance(parsed, str):
            return parsed.replace("-p", "--variant", 1)
        sets.append((parsed, f"--variant {shlex.quote(item)}"))
    return sets or [({}, "")]


def results_name(given: str, found: str) -> str:
    """How an evaluation names the mission ``given`` (found at ``found``): a file the user
    gave as given (relative to where ``eval`` ran, if given so); a shipped mission named
    alone (``dock``) by its shipped name, ``roomba-bt:dock.yaml``, as a record and the
    rows' ``sources`` name it. Its path in site-packages differed from one installation
    to the next, so two venvs' ``--reproducible`` results were never the same bytes."""
    from roomba_bt.mission.shipped import shipped_name

    if Path(given).is_file():
        return given
    return shipped_name(Path(found).resolve()) or found


def eval_command(args: argparse.Namespace) -> int:
    if args.from_files is not None:  # the report of episodes run before: none runs
        return report_from_files(args)
    problem = _check_arguments(args)
    if problem is not None:
        return refused(problem, args)
    plan = _plan(args)
    if isinstance(plan, int):
        return plan
    chosen, planned, world = plan
    resumed = _resumed(args, chosen, planned, world)
    if isinstance(resumed, int):
        return resumed
    batches = resumed.todo
    engine = _engine(args, batches)
    partial = _partial(args)
    if isinstance(partial, int):
        return partial
    if partial is not None:
        resumed.record_into(partial)
    done = _run(args, chosen, batches, engine, partial, resumed.earlier)
    if isinstance(done, int):
        if partial is not None:
            partial.done(keep=resumed.reused > 0)  # the episodes read back are kept there
        return done
    done = resumed.merged(done)
    # the records first: a summary that fails (a bug in the statistics) loses no episode
    unwritten = _save(args, done, partial)
    try:
        evaluated = statistics(args, chosen, done, world.name)
        print_report(args, engine.describe(), evaluated, run_conditions(args))
    except Exception:
        kept = args.out if unwritten is None else partial.path if partial else None
        if kept is not None:
            print(f"roomba-bt eval: the summary failed; the {count_episodes(done)} episode(s) that "
                  f"finished are in {kept}", file=sys.stderr)  # fmt: skip
        raise
    if unwritten is not None:
        return refused(unwritten, args)
    interruption = interruption_of(done)
    if interruption is not None:
        return _stopped(args, done, evaluated, interruption)
    if args.plot:
        traced = _paths_read_back(args, evaluated, resumed.read_back(), engine)
        if isinstance(traced, int):
            return traced
        plotted = _plot(args.plot, world, traced)
        if plotted is not None:
            return plotted
    return verdict(args, evaluated.summaries, done)


def _stopped(
    args: argparse.Namespace,
    done: list[Evaluation],
    evaluated: Evaluated,
    interruption: Interruption,
) -> int:
    """The ending of an evaluation that stopped before its end (its summary and records
    out): why, said on stderr, and its exit code; with ``--out``, how to run the episodes
    left (``--resume``: a Ctrl-C's user was not told). A ``--plot`` is not drawn then, and
    that is said: the file was not made, without a word."""
    failed, bug = interruption.environment_failed, interruption.behaviour_failed
    said = interruption.said if failed or bug else f"interrupted {interruption.said}"
    print(f"roomba-bt eval: {said}; {finished_said(done, evaluated)}, summarised above",
          file=sys.stderr)  # fmt: skip
    if args.out and not bug:  # the way on, where a thousand-episode sweep's user looks
        finished = count_episodes(done)
        left = evaluated.runs * len(evaluated.chosen) - finished
        again = "again" if args.resume else "with --resume"
        held = "those finished" if finished else "none: no episode finished"  # not "those"
        print(f"roomba-bt eval: the same command {again} runs the {left} episode(s) left "
              f"(--out {args.out} holds {held})", file=sys.stderr)  # fmt: skip
    if args.plot:
        then = " (--resume with --plot draws every episode once the rest have run)"
        print(f"roomba-bt eval: --plot {args.plot} not drawn: the evaluation stopped before its "
              f"end{then if args.out else ''}", file=sys.stderr)  # fmt: skip
    if bug:  # threads left stuck in a behaviour: its HUNG episodes named, exit 4
        verdict(args, evaluated.summaries, done)
        return ExitCode.BEHAVIOUR_ERROR
    # the workers or the cluster gone: the run environment failed, not the missions
    # (3, as a connection's failure); a signal is the operator's (130)
    return ExitCode.CONNECTION if failed else ExitCode.INTERRUPTED


def _paths_read_back(
    args: argparse.Namespace, evaluated: Evaluated, specs: list[list[EpisodeSpec]], engine: Engine
) -> Evaluated | int:
    """``evaluated`` with the paths of the episodes ``--resume`` read back without one
    (``specs``), for ``--plot``: a record written under ``--plot`` keeps its path (the
    ``path`` column, :func:`~roomba_bt.evaluate.records.kept_path`) and is drawn from it,
    but one written without (or before roomba-bt kept them) has none, and the plot of a
    resumed sweep drew only the episodes run in its last invocation. Each episode is
    decided by its spec alone, so each such one runs again for its path, the same as an
    uninterrupted sweep's; its record stays the one read back (the summary and ``--out``
    are not touched). One that runs otherwise now (an option the records do not carry,
    ``--timeout``, ``--battery``..., given otherwise) is said. An exit code when the runs
    again were stopped: no plot then."""
    count = sum(len(batch) for batch in specs)
    if not count:
        return evaluated
    print(f"roomba-bt eval: --plot: the {count} episode(s) read back without a path run again "
          "for theirs (their records were written without --plot)", file=sys.stderr)  # fmt: skip
    again = _run(args, evaluated.chosen, specs, engine)
    if isinstance(again, int):
        return again
    if interruption_of(again) is not None:
        print(f"roomba-bt eval: --plot {args.plot} not drawn: interrupted while the episodes "
              "read back ran again for their paths; the summary and the records are above",
              file=sys.stderr)  # fmt: skip
        return ExitCode.INTERRUPTED
    from roomba_bt.evaluate.records import same_episode

    paths = [{r.seed: r for r in e.results} for e in again]
    done, otherwise = [], []
    for e, ran in zip(evaluated.done, paths, strict=True):
        results = []
        for result in e.results:
            now = ran.get(result.seed)
            if now is None:  # run in this invocation: its path is there
                results.append(result)
                continue
            if not same_episode(now, result):
                otherwise.append(result.seed)
            results.append(replace(result, trajectory=now.trajectory))
        done.append(replace(e, results=results))
    if otherwise:
        seeds = ", ".join(str(seed) for seed in sorted(set(otherwise)))
        print(f"roomba-bt eval: warning: --plot: {len(otherwise)} episode(s) read back ran "
              f"otherwise now than their records say (seeds {seeds}): an option the records do "
              "not carry (--timeout, --battery, --dock, --odometry-error, the faults) differs "
              "from the first run's; their paths are of this run", file=sys.stderr)  # fmt: skip
    return replace(evaluated, done=done)


def _engine(args: argparse.Namespace, batches: Sequence[Sequence[EpisodeSpec]]) -> Engine:
    """Where the episodes run, as the options say (checked before: each limit a number or
    None), with no more workers than episodes (a local Dask cluster would start each one's
    process); more local processes than cores warned about."""
    from roomba_bt.evaluate.parallel import Engine

    jobs = max(1, min(args.jobs, sum(len(batch) for batch in batches)))
    limit, wait = wall_limit(args), worker_wait(args)
    engine = Engine("dask" if args.scheduler or args.engine == "dask" else "local", jobs,
                    args.scheduler, limit if isinstance(limit, float) else None,
                    wait if isinstance(wait, float) else None)  # fmt: skip
    if engine.scheduler is None:
        _warn_if_more_jobs_than_cores(jobs)
    return engine


def _resumed(
    args: argparse.Namespace, chosen: list[Variant], planned: list[EpisodePlan], world: World
) -> Resumed | int:
    """The episodes ``--out`` holds that ``--resume`` keeps, and those left to run
    (:mod:`roomba_bt.cli.eval_resume`); exit 2 when ``--out`` holds episodes and neither
    ``--resume`` nor ``--force`` was given, or they were not made as this evaluation makes
    them (what differs said)."""
    from roomba_bt.cli.eval_resume import ResumeError, refused_over, resume

    problem = refused_over(args)
    if problem is not None:
        return refused(problem, args)
    try:
        resumed = resume(args, chosen, planned, world)
    except ResumeError as exc:
        return refused(f"--resume: {exc}", args)
    for said in resumed.cut_said:
        print(f"roomba-bt eval: --resume: {said}", file=sys.stderr)
    if args.resume:
        left = sum(len(batch) for batch in resumed.todo)
        files = " and ".join(resumed.read_from) or args.out
        print(f"roomba-bt eval: --resume: {resumed.reused} episode(s) read back from {files}, "
              f"{left} to run", file=sys.stderr)  # fmt: skip
    return resumed


def _save(
    args: argparse.Namespace, done: list[Evaluation], partial: PartialResults | None
) -> str | None:
    """``--out``'s records written (before any statistics), with what made them
    (:func:`made_by`); the problem when they could not be (the partial file is then kept,
    and the message names it)."""
    out: str | None = args.out
    if out is None:
        return None
    from roomba_bt.evaluate.records import write_results

    assert partial is not None
    try:
        write_results(
            out, [r for e in done for r in e.results], getattr(args, "made_by", None),
            reproducible=args.reproducible,
        )  # fmt: skip
    except OSError as exc:
        partial.done(keep=True)
        problem = exc.strerror or exc
        return f"--out {out}: {problem}; the summary is above, the records in {partial.path}"
    partial.done()
    print(f"results written to {out}", file=sys.stderr)
    return None


#: The most episodes one evaluation runs (a million: days of a 2-core machine's time).
MAX_RUNS = 1_000_000


def _check_arguments(args: argparse.Namespace) -> str | None:
    """The missions found (their paths kept in ``args.mission_paths``, each file once:
    :func:`given_once`; those not found in ``args.not_found``, said with the missions that
    do not compile, :func:`_compiled`) and every number in its range; the first problem's
    message."""
    if not args.missions:
        return "give a MISSION to evaluate (or --from FILE... to report on results)"
    args.key = list(dict.fromkeys(args.key))  # a key named twice is reported once
    from roomba_bt.cli.validate_report import Checked

    found = [(mission, mission_file(mission)) for mission in args.missions]
    # each as validate has it: --json names the file asked for, as validate --format json
    not_found = list(
        {m: Checked(m, problem=f[0]) for m, f in found if isinstance(f, tuple)}.values()
    )
    args.not_found = not_found
    named = [(mission, f) for mission, f in found if not isinstance(f, tuple)]
    if not named:  # each on its line, as validate says them: they were joined with "; "
        if len(not_found) == 1:
            return str(not_found[0].problem)
        _say_not_found(not_found)
        return _cannot_be_evaluated(len(not_found), len(not_found))
    args.mission_paths = dict(given_once("eval", named, "evaluated"))
    args.missions = list(args.mission_paths)
    problem = _profile_of_the_missions(args)
    if problem is not None:
        return problem
    problem = _seeds_chosen(args)
    if problem is not None:
        return problem
    if not 1 <= args.runs <= MAX_RUNS:
        # each episode's spec is made before the first runs: 10^11 ran the memory out
        return f"--runs {args.runs}: expected 1..{MAX_RUNS:,} (more: several evaluations)"
    if args.jobs < 1:
        return f"--jobs {args.jobs}: expected at least 1"
    if args.scheduler is not None and not args.scheduler.strip():
        return "--scheduler '': expected the scheduler's address, e.g. tcp://HOST:8786"
    # --within, --battery, --min-rate and --odometry-error: read and checked by argparse
    args.faults = faults_given(args)
    if isinstance(args.faults, str):
        return args.faults
    for limit in (wall_limit(args), worker_wait(args)):
        if isinstance(limit, str):
            return limit
    if args.out is not None:
        from roomba_bt.evaluate.records import results_format

        try:
            results_format(args.out)
        except ValueError as exc:
            return f"--out {exc}"
    return None


def _seeds_chosen(args: argparse.Namespace) -> str | None:
    """``args.seeds`` each episode's seed, ``args.seed`` and ``args.runs`` the first and how
    many: ``--seeds`` (a list), else ``--seed`` (0) and ``--runs`` (20) in a row; the
    problem when both ways are given."""
    if args.seeds is None:
        args.seed = 0 if args.seed is None else args.seed
        args.runs = 20 if args.runs is None else args.runs
        return None
    given = [
        option
        for option, value in (("--seed", args.seed), ("--runs", args.runs))
        if value is not None
    ]
    if given:
        return f"--seeds and {' and '.join(given)}: give the seeds one way"
    args.seed, args.runs = args.seeds[0], len(args.seeds)
    return None


def _say_not_found(not_found: list[Checked]) -> None:
    """Each mission not found on its own line, as ``validate`` says each."""
    for one in not_found:
        print(f"roomba-bt eval: {one.problem}", file=sys.stderr)


def _cannot_be_evaluated(count: int, given: int) -> str:
    """The line after the missions that cannot run, each said on its own."""
    return f"{count} of {given} missions cannot be evaluated (said above); no episode runs"


def _profile_of_the_missions(args: argparse.Namespace) -> str | None:
    """``args.profile`` the simulated robot's model (:mod:`roomba_bt.cli.profile_choice`): the
    flag, the environment, or the project file above each mission; missions of projects
    that name different models are compared on none of them (the problem, said)."""
    from roomba_bt.cli.profile_choice import BadSetting, mission_near, resolved_profile

    choices = []
    for given, found in args.mission_paths.items():
        choice = resolved_profile(args.profile, "eval", mission_near(given, found))
        if isinstance(choice, BadSetting):
            return str(choice)
        choices.append(choice)
    if len({choice.name for choice in choices}) > 1:
        named = "; ".join(f"{c.name} ({c.source})" for c in choices)
        return f"the missions' projects name different robots ({named}): give --profile NAME"
    args.profile, args.profile_source = choices[0].name, choices[0].source
    return None


def worker_wait(args: argparse.Namespace) -> float | str | None:
    """``--worker-wait`` in seconds (None: ``none``), by default
    :data:`~roomba_bt.evaluate.parallel.WORKER_WAIT_S`; a message when it is not a
    duration."""
    from roomba_bt.evaluate.parallel import WORKER_WAIT_S

    if args.worker_wait is None:
        return WORKER_WAIT_S
    return limit_seconds(args.worker_wait, "--worker-wait")


def _plan(args: argparse.Namespace) -> tuple[list[Variant], list[EpisodePlan], World] | int:
    """The variants and their episodes (a plan each: its specs are made as they are run);
    each mission and the world checked once, here, before any worker starts. An exit code
    on a problem (said on stderr)."""
    from roomba_bt.evaluate import EvaluationError, episode_plan
    from roomba_bt.evaluate.episode import build_world, start_pose

    params = parse_params(args.param)
    if isinstance(params, str):
        return refused(params, args)
    timeout = parse_timeout(args.timeout)
    if isinstance(timeout, str) or timeout is None:
        return refused(str(timeout), args)
    dock = parse_dock(args.dock)
    if isinstance(dock, str):
        return refused(dock, args)
    chosen = variants(args, params)
    if isinstance(chosen, str):
        return refused(chosen, args)
    batches = [
        episode_plan(
            v.mission,
            world=args.world,
            runs=args.runs,
            seed=args.seed,
            params=v.params,
            profile=args.profile,
            timeout_s=timeout,
            time_limit=f"--timeout {duration_said(timeout)}",  # as its reasons name the limit
            within_m=args.within,
            dock=dock,
            battery=args.battery,
            start_area=args.start_area,
            odometry_error=args.odometry_error,
            faults=args.faults,
            permissions=permissions(args, v.path),
            trace_every=2 if args.plot else 0,  # only the plot reads trajectories
            simplify_path=bool(args.plot),  # as drawn, made in the worker
        )
        for v in chosen
    ]
    if args.seeds is not None:  # --seeds: the same specs, each on its seed of the list
        batches = [replace(batch, seeds=args.seeds) for batch in batches]
    missions = _compiled(args, chosen)
    if isinstance(missions, int):
        return missions
    same = _same_variant_twice(chosen, missions)
    if same is not None:
        return refused(same, args)
    try:
        world = build_world(batches[0][0])
        start_pose(world, batches[0][0])
        batches = _reading_keys(args, chosen, missions, batches)
    except EvaluationError as exc:
        return refused(str(exc), args, _world_errors(exc))
    args.made_by = made_by(args, chosen, missions, world)
    _warn_if_one_start(args, world)
    _warn_of_given_start(args, world)
    return chosen, batches, world


def _compiled(args: argparse.Namespace, chosen: list[Variant]) -> list[Any] | int:
    """Each variant's mission compiled (its warnings printed), or an exit code: 2 for an
    error, every mission's errors said first, and the missions not found (``eval`` stopped
    at the first, and its user fixed the files one run at a time; a file's other variants are
    not compiled again to say its errors again); 7 with ``--strict`` when one has
    compile-time warnings, each such variant said as ``run --strict`` says it, in ``validate
    --strict``'s words, before any worker starts (``eval`` ran every episode of such a
    mission, exit 0, what CI's ``validate --strict`` failed)."""
    from roomba_bt.cli.run_cmd import load
    from roomba_bt.cli.validate_report import failed_strict
    from roomba_bt.oi.profiles import get_profile

    missions = []
    invalid: list[str] = []
    failed: list[Diagnostic] = []
    for v in chosen:
        if v.mission in invalid:
            continue
        loaded = load(v.path, dict(v.params), get_profile(args.profile),
                      granted=_naming_the_variant(permissions(args, v.path), v),
                      failed=failed)  # fmt: skip
        if isinstance(loaded, int):
            invalid.append(v.mission)
        missions.append(loaded)
    if invalid or args.not_found:
        _say_not_found(args.not_found)
        count, given = len(invalid) + len(args.not_found), len(args.mission_paths)
        said = (f"{count} of {given + len(args.not_found)} missions cannot be evaluated; "
                "no episode runs")  # fmt: skip
        if args.json:
            refusal_as_json(said, failed, args.not_found)
        if given + len(args.not_found) == 1:
            return ExitCode.INVALID  # its errors are the whole story
        return refused(_cannot_be_evaluated(count, given + len(args.not_found)))
    warned = [(v, m) for v, m in zip(chosen, missions, strict=True) if m.warnings]
    if not (args.strict and warned):
        return missions
    for v, mission in warned:
        said = failed_strict(v.label, mission.warnings)
        print(f"roomba-bt eval: {said}; no episode runs", file=sys.stderr)
    if args.json:
        fails = "; ".join(failed_strict(v.label, m.warnings) for v, m in warned)
        refusal_as_json(f"{fails}; no episode runs", [w for _, m in warned for w in m.warnings])
    return ExitCode.STRICT


def _same_variant_twice(chosen: list[Variant], missions: list[Any]) -> str | None:
    """Two variants of a mission whose compiled parameters are equal, the same value in two
    spellings (``--sweep speed=300mm/s,0.3m/s``), said as the same variant given twice is:
    they ran twice and were "compared" with no word."""
    first: dict[tuple[str, str], Variant] = {}
    for v, mission in zip(chosen, missions, strict=True):
        values = (v.mission, repr(sorted(mission.parameters.items())))
        earlier = first.setdefault(values, v)
        if earlier is not v:
            return (f"{earlier.label} and {v.label}: the same variant twice (the mission reads "
                    "the same values): give each value once")  # fmt: skip
    return None


def _naming_the_variant(granted: Permissions, variant: Variant) -> Permissions:
    """``granted``, its messages naming the ``--variant`` or ``--sweep`` value each of the
    variant's own parameters came from (of ten variants, "from the command line" left the
    user to find the bad one)."""
    origins = tuple((name, variant.given_as) for name, _ in variant.own)
    return replace(granted, wording=replace(granted.wording, origins=origins))


def _world_errors(exc: EvaluationError) -> list[dict[str, Any]]:
    """The world's problems behind ``exc`` (:func:`~roomba_bt.evaluate.episode.build_world`
    raises it from the :class:`~roomba_bt.sim.world.WorldError`), each at its file, line
    and column as ``--json`` lists a mission's errors (a world not found: the name or path
    asked for, at no line); none for a problem that is no world's."""
    from roomba_bt.cli.validate_report import error_as_json
    from roomba_bt.sim.world import WorldError

    cause = exc.__cause__
    if not isinstance(cause, WorldError):
        return []
    return [error_as_json(p.source, p.message, p.line or None, p.column or None)
            for p in cause.problems]  # fmt: skip


def _reading_keys(
    args: argparse.Namespace,
    chosen: list[Variant],
    missions: list[Any],
    batches: list[EpisodePlan],
) -> list[EpisodePlan]:
    """The episodes, each reading the ``--key`` values at its end, once every variant's
    mission can report each one (``evaluate.keys.key_problem``: declared under its
    ``blackboard:``, not a record named whole nor a mark; else EvaluationError, before any
    episode runs); each key's unit kept (``args.key_units``) for the summary."""
    from roomba_bt.evaluate import EvaluationError
    from roomba_bt.evaluate.keys import key_problem, key_unit

    args.key_units = {}
    for name in args.key:
        for v, mission in zip(chosen, missions, strict=True):
            problem = key_problem(name, mission.blackboard_keys, v.mission)
            if problem is not None:
                raise EvaluationError(problem)
        args.key_units[name] = key_unit(name, missions[0].blackboard_keys)
    if not args.key:
        return batches
    return [batch.with_fields(keys=tuple(args.key)) for batch in batches]


def made_by(
    args: argparse.Namespace, chosen: list[Variant], missions: list[Any], world: World
) -> dict[str, dict[str, Any]]:
    """What made each variant's episodes, by its mission as the results name it: the
    roomba-bt release, the world file's digest, each file the mission was compiled from
    (by its path from ``--out``'s folder, else the working folder's, as a record names them
    from its own) and each installed plugin its tree used, as a record's header has them
    (``records.PROVENANCE_COLUMNS``). The results said none of it, so a committed results
    file could not be told from one of another release or another library."""
    from roomba_bt import __version__
    from roomba_bt.runtime.provenance import file_digest, plugin_digests, source_digests

    folder = Path(args.out).resolve().parent if args.out else Path.cwd()
    world_digest = file_digest(Path(world.source))
    return {
        v.mission: {
            "roomba_bt_version": __version__,
            "world_sha256": world_digest,
            "sources": source_digests(m.files, folder),
            "plugins": plugin_digests(m.root),
        }
        for v, m in zip(chosen, missions, strict=True)
    }


def _warn_if_more_jobs_than_cores(jobs: int) -> None:
    """``--jobs 500`` on 2 cores started 500 processes that took turns on them: no faster,
    the memory of 500 interpreters, and each episode's wall time 250 times its CPU time."""
    import os

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if cores and jobs > cores:
        print(
            f"roomba-bt eval: warning: --jobs {jobs} on {cores} core(s): the processes take "
            f"turns on the cores (no faster than --jobs {cores}, and each one's memory)",
            file=sys.stderr,
        )


def _warn_if_one_start(args: argparse.Namespace, world: World) -> None:
    """The seed draws the start pose (and the encoders' error): a world without a start
    region, with neither --within nor --start-area nor --odometry-error, runs one episode
    ``--runs`` times, which the report's interval would count as that many."""
    varied = (world.start_region, args.within, args.start_area, args.odometry_error or None)
    if args.runs > 1 and all(given is None for given in varied):
        x, y = world.start.x / 1000.0, world.start.y / 1000.0
        print(
            f"roomba-bt eval: warning: world {world.name!r} has no robot.start_region and "
            f"neither --within nor --start-area was given: all {args.runs} episodes start at "
            f"({x:.2f}, {y:.2f}) m and run alike (the seed draws only the start); the "
            "interval below counts one episode as many",
            file=sys.stderr,
        )


def _warn_of_given_start(args: argparse.Namespace, world: World) -> None:
    """The world's warnings (a given ``robot.start`` whose body reaches over a drop) on
    stderr, once for the whole evaluation, when the episodes start at that given pose (no
    start region, --within or --start-area draws one), as ``run --world`` and ``validate``
    say them: eval said nothing, and every episode may fall at once."""
    if world.start_region is not None or args.within is not None or args.start_area is not None:
        return
    from roomba_bt.cli.worlds_cmd import world_warnings_text

    for line in world_warnings_text(world.warnings):
        print(line, file=sys.stderr)


def _partial(args: argparse.Namespace) -> PartialResults | int | None:
    """``--out``'s records as they finish (:class:`PartialResults`), with what made them as
    ``--out`` has it; an exit code when its file cannot be made."""
    out: str | None = args.out
    if out is None:
        return None
    from roomba_bt.evaluate.records import PartialResults

    try:
        return PartialResults(out, getattr(args, "made_by", None), reproducible=args.reproducible)
    except OSError as exc:
        return refused(f"--out {out}: {exc.strerror or exc}", args)


def _run(
    args: argparse.Namespace,
    chosen: list[Variant],
    batches: Sequence[Sequence[EpisodeSpec]],
    engine: Engine,
    partial: PartialResults | None = None,
    earlier: Sequence[Sequence[EpisodeResult]] = (),
) -> list[Evaluation] | int:
    """Every variant's episodes on the engine, their progress bars drawn together (counting
    in the episodes ``earlier``, per variant, that ``--resume`` read back), each record into
    ``partial`` as it finishes; an exit code when the cluster is not there."""
    from roomba_bt.evaluate.cluster import ClusterUnavailableError, SchedulerUnreachableError
    from roomba_bt.evaluate.episode import MissionNotCompiled
    from roomba_bt.evaluate.parallel import evaluate
    from roomba_bt.evaluate.progress import ProgressBars

    bars = None
    if not args.no_progress:
        already = [(len(e), sum(r.succeeded for r in e)) for e in earlier]
        already = already or [(0, 0)] * len(chosen)
        bars = ProgressBars(
            [v.label for v in chosen],
            [done + len(batch) for (done, _), batch in zip(already, batches, strict=True)],
            already=already,
        )
    shown = [bars.bar(b) if bars is not None else None for b in range(len(chosen))]
    progress = shown if partial is None else [_recorded(partial, bar) for bar in shown]
    try:
        try:
            return evaluate(batches, engine, progress, [v.label for v in chosen])
        finally:
            if bars is not None:
                bars.end()  # before what is said next, an error's words too
    except SchedulerUnreachableError as exc:
        print(f"roomba-bt eval: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    except ClusterUnavailableError as exc:
        return refused(str(exc))
    except MissionNotCompiled as exc:
        _not_on_the_worker(args, exc)
        return ExitCode.CONNECTION


def _not_on_the_worker(args: argparse.Namespace, exc: MissionNotCompiled) -> None:
    """A worker that cannot compile a mission this machine compiled, said once (its first
    episode there stops the evaluation: every other would fail alike), with what this
    machine's tree used that the worker may lack: the installed plugins and their versions
    (the worker's compiler knows only that a node is unknown), else the modules a plugin
    file imports, which its import error names."""
    for line in str(exc).splitlines():
        print(f"roomba-bt eval: {escaped(line, ANY_CONTROL)}", file=sys.stderr)
    plugins = getattr(args, "made_by", {}).get(exc.mission, {}).get("plugins") or {}
    if plugins:
        here = ", ".join(f"{name} {about['version']}" for name, about in plugins.items())
        need = f"the installed plugin(s) its tree uses here: {here}"
    else:
        need = "what its plugin files import"
    print(f"roomba-bt eval: install on every worker {need}, and this roomba-bt release (exit "
          "3: the run environment failed, not the mission)", file=sys.stderr)  # fmt: skip


def _recorded(partial: PartialResults, bar: Progress | None) -> Progress:
    def progress(done: int, total: int, result: EpisodeResult) -> None:
        partial.add(result)
        if bar is not None:
            bar(done, total, result)

    return progress


def run_conditions(args: argparse.Namespace) -> dict[str, Any]:
    """How the episodes were made, for an archived ``--json`` summary: the mission time per
    episode (s), the first seed, the episodes per variant, the world as given, ``--within``
    (m), ``--start-area``, the dock's overrides (lengths in m, angles in degrees), the
    encoders' error, the initial charge (None: the world's), the profile, and the version of
    roomba-bt that ran them. The arguments were checked before any episode ran."""
    from roomba_bt import __version__

    dock = parse_dock(args.dock)
    overrides = (
        {}
        if isinstance(dock, str)
        else {  # str: a problem; none here, checked before
            name: list(value) if isinstance(value, tuple) else value for name, value in dock
        }
    )
    return {
        "timeout": parse_timeout(args.timeout),
        "wall_limit": wall_limit(args),
        "params": parse_params(args.param),  # -p's, under every variant's own
        "seed": args.seed,
        "runs": args.runs,
        "seeds": args.seeds,  # --seeds' list; null: --seed and --runs in a row
        "world": args.world,
        "within": args.within,
        "start_area": args.start_area,
        "dock": overrides,
        "odometry_error": args.odometry_error,
        "faults": fault_options_set(args),  # ["--host-drop-rate 0.01"]; [] for none
        "battery": args.battery,
        "profile": args.profile,
        "min_rate": args.min_rate,
        "world_sha256": _world_digest(args),
        "roomba_bt_version": __version__,
    }


def _world_digest(args: argparse.Namespace) -> str | None:
    """The world file's SHA-256 (:func:`made_by`'s, the same for every variant)."""
    made: dict[str, dict[str, Any]] = getattr(args, "made_by", {})
    return next((provenance["world_sha256"] for provenance in made.values()), None)


def _plot(out: str, world: World, evaluated: Evaluated) -> int | None:
    """Every variant's trajectories drawn to ``out``, a panel each side by side (one variant:
    one picture), each as its record keeps it (:func:`~roomba_bt.evaluate.records.kept_path`):
    an episode read back by ``--resume`` is drawn as one run now; an exit code if that
    failed."""
    from roomba_bt.evaluate.plot import PlotUnavailableError, plot_variants
    from roomba_bt.evaluate.records import kept_path

    chosen, summaries = evaluated.chosen, evaluated.summaries
    done = [
        replace(e, results=[replace(r, trajectory=kept_path(r.trajectory)) for r in e.results])
        for e in evaluated.done
    ]
    if len(chosen) == 1:
        said = " ".join([Path(chosen[0].path).stem, *(f"-p {k}={v}" for k, v in chosen[0].params)])
        titles = [f"{said} in {world.name}: {summaries[0].successes}/{summaries[0].runs}"]
    else:
        titles = [
            f"{v.label}: {s.successes}/{s.runs}" for v, s in zip(chosen, summaries, strict=True)
        ]
    try:
        plot_variants(world, [(t, e.results) for t, e in zip(titles, done, strict=True)], out)
    except PlotUnavailableError as exc:
        print(f"roomba-bt eval: {exc}", file=sys.stderr)
        return ExitCode.INVALID
    except OSError as exc:
        return refused(f"--plot {out}: {exc.strerror or exc}")
    print(f"trajectories written to {out}", file=sys.stderr)
    return None
