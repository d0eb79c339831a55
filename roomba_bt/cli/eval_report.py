"""What ``roomba-bt eval`` prints once its episodes are in, the same after a run
(:mod:`roomba_bt.cli.eval_cmd`) and for records read back (``eval --from``,
:mod:`roomba_bt.cli.eval_from`): each variant and its episodes (:class:`Variant`,
:class:`Evaluated`), their statistics, the report on stdout (text, or ``--json``), the exit
code with what decided it on stderr (and the ``roomba-bt run`` line that runs a buggy
episode again), and a refusal (exit 2; under ``--json`` on stdout too). ``--from`` reached
these as ``eval_cmd``'s private helpers; both commands now share them here.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import fault_options_set, limit_seconds, parse_timeout
from roomba_bt.printable import ANY_CONTROL, escaped
from roomba_bt.runtime.summary import ExitCode, Outcome

if TYPE_CHECKING:
    from collections.abc import Sequence

    from roomba_bt.cli.validate_report import Checked
    from roomba_bt.evaluate.parallel import Evaluation, Interruption
    from roomba_bt.evaluate.stats import Comparison, Summary
    from roomba_bt.mission import Diagnostic


@dataclass(frozen=True)
class Variant:
    """One thing evaluated: a mission with its parameters, labelled for the report."""

    #: the mission and every parameter that applied once: ``-p``'s that it does not
    #: override, then its own (``dock -p search_speed=250mm/s -p turn_speed=90mm/s``): a
    #: label of its own values alone read as if the ``-p`` base had not applied
    label: str
    #: how the results, the summary and the records name the mission
    #: (:func:`~roomba_bt.cli.eval_cmd.results_name`)
    mission: str
    params: tuple[tuple[str, str], ...]
    #: the file read: where the project file and the include folders are looked for
    path: str
    #: its own parameters, on top of ``-p`` (``--sweep``'s value, ``--variant``'s set)
    own: tuple[tuple[str, str], ...] = ()
    #: how the command line gave them (``--variant 'speed=fast'``), which a message about
    #: one of them names; "" for a mission's own variant
    given_as: str = ""


@dataclass(frozen=True)
class Evaluated:
    """A finished evaluation, what its report, plot and exit code are made of: each variant
    (``chosen``), its episodes (``done``) and its summary, in the same order, and each later
    variant compared with the first (or the line that says why there is no comparison)."""

    chosen: list[Variant]
    done: list[Evaluation]
    summaries: list[Summary]
    comparisons: list[Comparison | str]
    #: the episodes each variant was to run (``--runs``)
    runs: int


def refused(
    message: str, args: argparse.Namespace | None = None, errors: Sequence[dict[str, Any]] = ()
) -> int:
    """``message`` on stderr, exit 2; under ``--json`` (``args`` given) also on stdout as
    :func:`refusal_as_json` writes it, so a script's ``json.load`` reads why nothing ran;
    ``errors``: its places in a file (a world's problems), each as a diagnostic."""
    if args is not None and getattr(args, "json", False):
        said_alone = message.replace(" (said above)", "")  # stdout holds the errors too
        refusal_as_json(said_alone, [], getattr(args, "not_found", []), errors)
    print(f"roomba-bt eval: {message}", file=sys.stderr)
    return ExitCode.INVALID


def refusal_as_json(
    said: str,
    diagnostics: list[Diagnostic],
    not_found: Sequence[Checked] = (),
    errors: Sequence[dict[str, Any]] = (),
) -> None:
    """``eval --json`` refusing to start, on stdout as data a script reads (its ``json.load``
    of an empty stdout raised): ``{"error": what stops it, "errors": [...]}``, each error as
    ``validate --format json`` gives a diagnostic (``file``, ``line``, ``column``,
    ``message``, ...), a mission not found in the file asked for at no line or column (its
    ``file`` was null: a script could not tell which of several it was), then ``errors``
    as they are. stderr says the same as without ``--json``; the exit code is the same."""
    import json

    from roomba_bt.cli.validate_report import diagnostic_as_json, problem_as_json

    listed = [diagnostic_as_json(d) for d in diagnostics]
    listed += [problem_as_json(one) for one in not_found]
    print(json.dumps({"error": said, "errors": [*listed, *errors]}, indent=2))


def count_episodes(done: list[Evaluation]) -> int:
    return sum(len(e.results) for e in done)


def finished_said(done: list[Evaluation], evaluated: Evaluated) -> str:
    """``12 of 200 episode(s) finished``: of every variant's episodes."""
    planned = evaluated.runs * len(evaluated.chosen)
    return f"{count_episodes(done)} of {planned} episode(s) finished"


def interruption_of(done: list[Evaluation]) -> Interruption | None:
    """Why the evaluation stopped before its end: the first batch interrupted says (the
    later ones were skipped); None when it ran to its end."""
    from roomba_bt.evaluate.parallel import Interruption

    for e in done:
        if e.interrupted:  # an Evaluation a program made itself may not say why
            return e.interruption or Interruption("unknown", "for a reason not said")
    return None


def statistics(
    args: argparse.Namespace,
    chosen: list[Variant],
    done: list[Evaluation],
    world: str,
    profiles: list[str] | None = None,
) -> Evaluated:
    """Each variant's summary, and each later variant compared with the first: over the
    seeds both finished when interrupted, or a line saying why there is no comparison.
    ``profiles``: each variant's profile line (``eval --from``: as its records name it);
    None: ``--profile``'s for every variant."""
    from roomba_bt.cli.profile_choice import profile_line
    from roomba_bt.evaluate import summarize
    from roomba_bt.evaluate.stats import compare_finished

    shown = profiles or [profile_line(args)] * len(chosen)
    summaries = [
        replace(summarize(v.mission, world, e.results, line), timings=not args.reproducible)
        for v, e, line in zip(chosen, done, shown, strict=True)
    ]
    comparisons: list[Comparison | str] = []
    for v, e in zip(chosen[1:], done[1:], strict=True):
        c = compare_finished(chosen[0].label, v.label, done[0].results, e.results)
        if c is None:
            comparisons.append(f"A/B          {chosen[0].label} against {v.label}: no "
                               "comparison, no seed finished with both (interrupted)")  # fmt: skip
        else:
            comparisons.append(replace(c, interrupted=e.interrupted or done[0].interrupted))
    return Evaluated(chosen, done, summaries, comparisons, args.runs)


def print_report(
    args: argparse.Namespace,
    engine: str,
    evaluated: Evaluated,
    conditions: dict[str, Any] | None = None,
) -> None:
    """The summaries, coverage and comparisons on stdout: as JSON with ``--json`` (its
    ``conditions``: how the episodes were made, None when the records read do not say them
    all, ``eval --from``), else text. ``--reproducible``: the slow ticks' warning, measured
    on the host and so left out of the report, on stderr."""
    from roomba_bt.evaluate.coverage import summarize_coverage
    from roomba_bt.evaluate.keys import summarize_keys

    if args.reproducible:  # measured on the host: not in the report, still said
        for summary in evaluated.summaries:
            for said in summary.slow_said():
                print(escaped(f"roomba-bt eval: warning: {said}", ANY_CONTROL), file=sys.stderr)
    if args.json:
        _json_report(args, engine, evaluated, conditions)
        return
    chosen, done = evaluated.chosen, evaluated.done
    for v, s, e in zip(chosen, evaluated.summaries, done, strict=True):
        if len(chosen) > 1 or v.params:  # one variant's -p: said nowhere else in the text
            print(f"variant      {v.label}")
        print(s)
        coverage = summarize_coverage(e.results)
        if coverage is not None:
            print(coverage)
        for key in summarize_keys(e.results, args.key, args.key_units):
            print(key.line())
        print()
    for c in evaluated.comparisons:
        print(c)
        print()
    faults = faults_said(conditions)
    if faults:
        print(f"faults       {faults}")
    interruption = interruption_of(done)
    if interruption is not None:
        print(escaped(f"interrupted  {interruption.said}; {finished_said(done, evaluated)}",
                      ANY_CONTROL))  # fmt: skip
    if not args.reproducible and engine:  # which ran them, and what was lost: not the results
        retried = sum(e.retried for e in done)
        print(f"engine       {engine}; {retried} episode(s) run again after a worker was lost")


def faults_said(conditions: dict[str, Any] | None) -> str:
    """What went wrong on purpose in every episode, as the command line gave it
    (``--byte-drop-rate 0.01 --odometry-error 0.02``), for the text report: only ``--json``
    said it, and a report of 60 % docked read as the mission's own; "" when nothing was
    set (or the records read do not say, ``eval --from``)."""
    if conditions is None:
        return ""
    given = list(conditions.get("faults") or [])
    if conditions.get("odometry_error"):
        given.append(f"--odometry-error {conditions['odometry_error']:g}")
    if not given:
        return ""
    return f"{' '.join(given)} (in every episode, each drawing from its own seed)"


def _json_report(
    args: argparse.Namespace, engine: str, evaluated: Evaluated, conditions: dict[str, Any] | None
) -> None:
    """``--json``: the conditions, what made the episodes (the release, each plugin, each
    variant's files: :func:`~roomba_bt.cli.eval_cmd.made_by`), the ``--min-rate`` verdict
    (``passed``: each variant's and all of them; null without ``--min-rate``), each
    variant's summary and coverage, and the comparisons. ``--reproducible``: the engine, the
    episodes run again and the times measured on the wall clock null, so that the same
    episodes run again print the same."""
    import json

    from roomba_bt.evaluate.coverage import summarize_coverage
    from roomba_bt.evaluate.keys import summarize_keys
    from roomba_bt.evaluate.stats import METHODS, tidy

    made = getattr(args, "made_by", {})
    plugins: dict[str, Any] = {}
    for provenance in made.values():
        plugins.update(provenance["plugins"])
    summaries, done = evaluated.summaries, evaluated.done
    passed = [None if args.min_rate is None else s.rate >= args.min_rate for s in summaries]
    measured = not args.reproducible
    interruption = interruption_of(done)
    print(json.dumps(tidy({
        "conditions": conditions,
        "engine": (engine or None) if measured else None,
        "retried": sum(e.retried for e in done) if measured else None,
        "interrupted": interruption is not None,
        "interrupted_by": interruption.cause if interruption else None,
        "interruption": interruption.said if interruption else None,
        "passed": None if args.min_rate is None else all(passed),
        "plugins": dict(sorted(plugins.items())),
        "variants": [{"label": v.label, "params": dict(v.params), "own_params": dict(v.own),
                      **s.to_dict(),
                      "passed": ok, "sources": made.get(v.mission, {}).get("sources"),
                      "coverage": c.to_dict() if c is not None else None,
                      "keys": {k.name: k.to_dict()
                               for k in summarize_keys(e.results, args.key, args.key_units)}}
                     for v, s, c, ok, e in zip(evaluated.chosen, summaries,
                                               [summarize_coverage(e.results) for e in done],
                                               passed, done, strict=True)],
        "comparisons": [c.to_dict() for c in evaluated.comparisons if not isinstance(c, str)],
        "methods": METHODS,
    }), indent=2))  # fmt: skip


def verdict(args: argparse.Namespace, summaries: list[Summary], done: list[Evaluation]) -> int:
    """The exit code of a finished evaluation, with what decided it on stderr: 4 when a
    behaviour raised in an episode, one ran past ``--wall-limit`` or hung in a
    ``terminate()`` or ``shutdown()`` (HUNG, each worded as its reason says:
    :func:`hung_how`) or one's worker died running it (DIED), 1 when a success rate is below
    ``--min-rate``, else 0."""
    min_rate: float | None = args.min_rate
    low = [s for s in summaries if min_rate is not None and s.rate < min_rate]
    for s in low:
        print(
            f"roomba-bt eval: {s.mission}: success rate {100 * s.rate:.1f} % is below "
            f"--min-rate {100 * (min_rate or 0.0):.1f} %",
            file=sys.stderr,
        )
    from roomba_bt.evaluate.episode import DIED, HUNG

    bug = False
    for ending, how, then in (
        (Outcome.ERROR.value, "ended with a behaviour's exception (a bug in it or its plugin)",
         "see its traceback with"),
        *((HUNG, why, "run it alone with")
          for why in (HUNG_PAST_LIMIT, HUNG_IN_TERMINATE, HUNG_IN_SHUTDOWN)),
        (DIED, "killed the worker process running it (os._exit in a behaviour? a crash in C "
         "code?)", "run it alone with"),
    ):  # fmt: skip
        found = [
            r
            for e in done
            for r in e.results
            if r.outcome == ending and (ending != HUNG or hung_how(r.reason) == how)
        ]
        if found:
            bug = True
            print(
                f"roomba-bt eval: {len(found)} episode(s) {how}, the first: seed "
                f"{found[0].seed}: {escaped(found[0].reason, ANY_CONTROL)}; {then}: "
                f"{rerun_command(args, found[0])}",
                file=sys.stderr,
            )
    if bug:
        return ExitCode.BEHAVIOUR_ERROR
    return ExitCode.MISSION_FAILED if low else ExitCode.OK


#: What eval's closing line says of HUNG episodes, by how their reason begins (the run's
#: own words, ``runtime/ending.py``: :func:`hung_how`): a ``terminate()`` or a ``shutdown()``
#: that never returned, the run's end going on without it, was called "an endless loop?" too
HUNG_IN_TERMINATE = (
    "hung in a behaviour's terminate() that never returned (the run's end went on without it)"
)
HUNG_IN_SHUTDOWN = (
    "hung in a behaviour's shutdown() that never returned (the run's end went on without it)"
)
HUNG_PAST_LIMIT = "ran past --wall-limit (stuck: an endless loop in a behaviour?)"


def hung_how(reason: str) -> str:
    """How eval's closing line words a HUNG episode whose reason is ``reason``: the tree's
    stop's or the shutdown's words when the reason begins with them (``the tree's stop did
    not end within 5 s: ...``), else the wall limit's."""
    from roomba_bt.runtime.ending import SHUTDOWN_NOT_ENDED, STOP_NOT_ENDED

    if reason.startswith(STOP_NOT_ENDED):
        return HUNG_IN_TERMINATE
    return HUNG_IN_SHUTDOWN if reason.startswith(SHUTDOWN_NOT_ENDED) else HUNG_PAST_LIMIT


def rerun_command(args: argparse.Namespace, result: Any) -> str:
    """The ``roomba-bt run`` line that runs episode ``result`` again, alone, with its
    traceback: every option that shaped the episode, its seed and seeded start, world,
    parameters, profile, charge, mission time limit (``run --fast``'s own is 2 h, eval's
    15 min: a late error ran alone under another limit), encoders' error, faults and what
    the evaluation was allowed to load; for a HUNG one, its ``--wall-limit``, which then
    names where it is stuck as the evaluation did. ``run`` has no --within, --start-area nor
    --dock: with any of those the line says its start or world may differ."""
    from roomba_bt.evaluate.episode import HUNG

    words = ["roomba-bt", "-v", "run", result.mission, "--fast", "--random-start", "--seed",
             str(result.seed)]  # fmt: skip
    if args.world != "empty-room":
        words += ["--world", args.world]
    for name, value in dict(result.params).items():
        words += ["-p", f"{name}={value}"]
    if args.profile != "create2":
        words += ["--profile", args.profile]
    if args.battery is not None:
        words += ["--battery", f"{args.battery:g}"]
    timeout = parse_timeout(args.timeout)  # checked before any episode: seconds
    if isinstance(timeout, float):
        words += ["--timeout", f"{timeout:g}"]
    if args.odometry_error:  # each episode's draw is its seed's, as run's
        words += ["--odometry-error", f"{args.odometry_error:g}"]
    if getattr(args, "allow_plugin_files", False):
        words.append("--allow-plugin-files")
    limit = wall_limit(args)
    if result.outcome == HUNG and isinstance(limit, float):  # else the run hangs silently
        words += ["--wall-limit", f"{limit:g}"]
    for folder in getattr(args, "include_dir", None) or ():
        words += ["--include-dir", folder]
    for option in fault_options_set(args):  # each episode's draws are its seed's
        words += option.split(" ", 1)
    line = shlex.join(words)
    unmatched = [
        option for option, given in (
            ("--within", args.within is not None), ("--start-area", args.start_area is not None),
            ("--dock", bool(args.dock)),
        ) if given
    ]  # fmt: skip
    if unmatched:
        line += f" (run has no {', '.join(unmatched)}: its start or world may differ)"
    return line


def wall_limit(args: argparse.Namespace) -> float | str | None:
    """``--wall-limit`` in seconds (None: ``none``), by default
    :func:`~roomba_bt.evaluate.episode.default_wall_limit` of ``--timeout``; a message when
    either is not a duration. Here beside :func:`rerun_command`, whose line for a HUNG
    episode names it; ``eval`` checks it and gives it to the engine."""
    from roomba_bt.evaluate.episode import default_wall_limit

    if args.wall_limit is not None:
        return limit_seconds(args.wall_limit, "--wall-limit")
    timeout = parse_timeout(args.timeout)
    return default_wall_limit(timeout) if isinstance(timeout, float) else timeout
