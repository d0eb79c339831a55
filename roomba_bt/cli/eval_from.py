"""``roomba-bt eval --from FILE...``: the report of episodes already run, read from results.

Several machines' sweeps, or an interrupted one's pieces, merged by a script: the statistics
(``summarize``, and the McNemar and median machinery of ``compare``) were reachable only from
Python. ``--from`` reads the records (JSON Lines or CSV, as ``--out`` writes them), groups
them by variant (the mission and its parameters, in the order first met) and prints the
report ``eval`` prints after running them: each variant's summary, and each later variant
compared with the first over the seeds both have; ``--json`` as ``eval --json``, with
``conditions`` null (the records do not say them all) and ``from`` the files read. No
episode runs.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from roomba_bt.evaluate.episode import EpisodeResult
    from roomba_bt.evaluate.parallel import Evaluation
    from roomba_bt.evaluate.records import CutShort


def add_from_option(ev: argparse.ArgumentParser) -> None:
    """``--from FILE...``: report on these results instead of running episodes."""
    ev.add_argument(
        "--from", dest="from_files", nargs="+", metavar="FILE",
        help="run nothing: summarise and compare the episodes in these results files (.jsonl "
        "or .csv, as --out writes them; several are merged), by variant; with --json as JSON; "
        "the options that choose, vary or write episodes (--seeds, --runs, --out, --plot, "
        "--resume, -p, --sweep, --key...) are refused with it",
    )  # fmt: skip


#: The options of a run that ``--from`` would not use (each option, its ``args`` name): it
#: chooses no episode, varies no parameter and writes no file. Given with it they were
#: dropped without a word (``--from ab.jsonl --seeds 1-10`` reported every seed; ``--out``
#: and ``--plot`` wrote nothing); the ``key:`` columns are the records' own.
RUN_ONLY = (
    ("--seed", "seed"), ("--seeds", "seeds"), ("--runs", "runs"), ("--out", "out"),
    ("--plot", "plot"), ("--resume", "resume"), ("--force", "force"), ("--sweep", "sweep"),
    ("--variant", "variant"), ("-p", "param"), ("--key", "key"),
)  # fmt: skip


#: a variant's episodes by seed: where each was first read, its result and the row of it
#: a record met again is compared with (:func:`~roomba_bt.evaluate.records.compared_row`)
_Seeds = dict[int, tuple[str, "EpisodeResult", dict[str, Any]]]


class FromFilesError(ValueError):
    """Results that cannot be reported on: the message names the file (and line)."""


def read_variants(
    files: list[str], cut: list[CutShort] | None = None
) -> list[tuple[str, tuple[tuple[str, str], ...], list[EpisodeResult]]]:
    """Each variant's episodes in ``files``: (mission, parameters, results in seed order), in
    the order first met. A (variant, seed) met again must be the same episode (as written
    by another run with ``--reproducible``, its wall-clock columns aside): it counts once;
    another one is refused, naming both places. Given ``cut``, a file's last record cut
    short (a killed sweep's partial file) is left out and put there instead of refused."""
    from roomba_bt.evaluate.records import ResultsFileError, iter_rows

    found: dict[tuple[str, tuple[tuple[str, str], ...]], _Seeds] = {}
    worlds: list[tuple[str, str, str | None]] = []  # the first record's: place, name, SHA-256
    seen: set[bytes] = set()  # the lines taken: one met again is the same record, skipped
    for path in files:
        try:  # read as a stream: a record met again is compared, not kept
            for line, row, result in iter_rows(path, cut, seen):
                _found(found, worlds, f"{path}:{line}", row, result)
        except (ResultsFileError, ValueError) as exc:
            raise FromFilesError(str(exc)) from None
    if not found:
        raise FromFilesError(f"{', '.join(files)}: no episode to report on")
    return [
        (mission, params, [result for _, (_, result, _) in sorted(episodes.items())])
        for (mission, params), episodes in found.items()
    ]


def _found(
    found: dict[tuple[str, tuple[tuple[str, str], ...]], _Seeds],
    worlds: list[tuple[str, str, str | None]],
    where: str,
    row: dict[str, Any],
    result: EpisodeResult,
) -> None:
    """The record at ``where`` put among ``found`` (its variant's, by seed), FromFilesError
    when it ran in another world than the first, or its seed is there with other results."""
    from roomba_bt.evaluate.records import compared_row

    episodes = found.setdefault((result.mission, tuple(sorted(result.params))), {})
    _one_world(worlds, where, result.world, row.get("world_sha256") or None)
    first = episodes.get(result.seed)
    if first is None:  # its row compared kept once: 200,000 lines of one episode made it
        episodes[result.seed] = (where, result, compared_row(result))  # twice a line
    elif compared_row(result) != first[2]:
        raise FromFilesError(f"{where}: seed {result.seed} of {result.mission} is at "
                             f"{first[0]} too, with other results: two runs made "
                             "otherwise (count each file alone)")  # fmt: skip


def _one_world(
    worlds: list[tuple[str, str, str | None]], where: str, name: str, digest: str | None
) -> None:
    """FromFilesError when the record at ``where`` ran in another world than the first
    record read (by name, or by the file's SHA-256 where both records have it): the seeds of
    two worlds paired as "the same starts" compared nothing (an apartment's file and an
    empty room's were merged, labelled the first's world). ``--resume`` refuses the same."""
    if not worlds:
        worlds.append((where, name, digest))
        return
    first_at, first_name, first_digest = worlds[0]
    other_file = digest is not None and first_digest is not None and digest != first_digest
    if name != first_name or other_file:
        if name != first_name:
            said = f"world {name!r}, {first_at} in {first_name!r}"
        else:  # the same name, another file (edited between the sweeps)
            said = (f"world {name!r} of SHA-256 {(digest or '')[:12]}..., {first_at} in one "
                    f"of {(first_digest or '')[:12]}... (the world file changed)")  # fmt: skip
        raise FromFilesError(f"{where}: the episode ran in {said}: a report compares "
                             "episodes of one world; give each world's files alone")  # fmt: skip


def report_from_files(args: argparse.Namespace) -> int:
    """The report of ``args.from_files``' episodes (:func:`read_variants`) as ``eval``
    prints it after running them; exit 2 when a file cannot be read, or a mission was also
    given (``--from`` runs nothing), else 0 (or 1 under ``--min-rate``, 4 when an episode
    was a bug's: :func:`~roomba_bt.cli.eval_report.verdict`)."""
    from roomba_bt.cli.eval_report import (
        Variant,
        count_episodes,
        print_report,
        refused,
        statistics,
        verdict,
    )
    from roomba_bt.evaluate.parallel import Evaluation

    if args.missions:
        return refused(f"--from and {args.missions[0]}: --from runs no mission: "
                               "give one or the other", args)  # fmt: skip
    ignored = next((option for option, dest in RUN_ONLY if getattr(args, dest, None)), None)
    if ignored is not None:
        return refused(f"--from and {ignored}: --from reports on the episodes its files hold "
                       f"as they are (it runs none and writes no file); {ignored} is for a "
                       "run: give one or the other", args)  # fmt: skip
    cut: list[CutShort] = []
    try:
        variants = read_variants(args.from_files, cut)
    except FromFilesError as exc:
        _left_out(cut)
        return refused(f"--from {exc}", args)
    _left_out(cut)
    chosen = [
        Variant(_label(mission, params), mission, params, mission)
        for mission, params, _ in variants
    ]
    done = [Evaluation(results) for _, _, results in variants]
    first = variants[0][2][0]
    profiles = [_profile_said(results, args.profile) for _, _, results in variants]
    _as_read(args, first, done)
    evaluated = statistics(args, chosen, done, first.world, profiles)
    print_report(args, "", evaluated)
    print(f"roomba-bt eval: {count_episodes(done)} episode(s) of {len(chosen)} variant(s) "
          f"read from {', '.join(args.from_files)}; none run", file=sys.stderr)  # fmt: skip
    return verdict(args, evaluated.summaries, done)


def _left_out(cut: list[CutShort]) -> None:
    """Each file's last record cut short (a killed sweep's partial file), said left out of
    the report: such a file was refused, and the report of a killed sweep's episodes needed
    the file edited first."""
    for one in cut:
        print(f"roomba-bt eval: --from {one.said(True)}: left out", file=sys.stderr)


def _label(mission: str, params: tuple[tuple[str, str], ...]) -> str:
    """A variant's label as ``eval`` gave it when it ran: a shipped mission by its name
    (``dock``: it said ``roomba-bt:dock.yaml``, the records' name, where the run said
    ``dock``), then its parameters (:func:`~roomba_bt.evaluate.interleave.variant_label`)."""
    from roomba_bt.evaluate.interleave import variant_label

    return variant_label(mission, params)


def _profile_said(results: list[EpisodeResult], given: str | None) -> str:
    """A variant's profile line as its records name the model (``roomba500 (Roomba 500
    series)``, "" for create2, as ``eval`` says it after a run); episodes of several models
    each named; records written before the column (none named): ``--profile``'s if given,
    else said to be unknown rather than taken for create2."""
    from roomba_bt.oi.profiles import PROFILES
    from roomba_bt.printable import escaped
    from roomba_bt.runtime.summary import profile_shown

    named = list(dict.fromkeys(r.profile for r in results))
    if named == [""]:
        if given is None:
            return "not recorded (results written before records named it; --profile to say it)"
        named = [given]
    said = [
        profile_shown(PROFILES[name]) if name in PROFILES else escaped(name or "not recorded")
        for name in named
    ]
    if len(said) == 1:
        return said[0]
    return "mixed: " + ", ".join(line or "create2" for line in said)


def _as_read(args: argparse.Namespace, first: EpisodeResult, done: list[Evaluation]) -> None:
    """``args`` as the report reads them, from the records: the ``key:`` columns they have
    (their units are the missions', which the records do not keep), the most episodes of a
    variant, the first record's world and profile (the line to run an episode again names
    them; create2 in records written before they named it), no provenance of this run,
    and no times measured when the records have none."""
    results = [r for e in done for r in e.results]
    args.key = list(dict.fromkeys(name for r in results for name, _ in r.keys))
    args.key_units = dict.fromkeys(args.key, "")
    args.runs = max(len(e.results) for e in done)
    args.world = first.world
    args.profile = args.profile or first.profile or "create2"
    args.made_by = {}
    # records written with --reproducible have no wall-clock columns: said as that run did
    args.reproducible = args.reproducible or not any(r.wall_s or r.cpu_s for r in results)
