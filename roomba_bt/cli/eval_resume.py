"""``eval --out FILE`` run again: refused over earlier results, or resumed.

A sweep's ``--out`` holds hours of episodes. Running ``eval`` again with the same ``--out``
(to continue an interrupted sweep, or by a slip) wrote over them without a word. Now a
results file that holds episodes, or the ``FILE.partial.jsonl`` a killed sweep left, is
refused before any episode runs (exit 2), unless ``--force`` (replace it) or ``--resume``:
its episodes are read back, checked against this evaluation (the missions and parameters,
the seeds, what made them: the profile, the release, the world's and each mission file's
SHA-256, the plugins, each start pose, the ``--key`` columns), and only the (variant, seed)
pairs it lacks run. The file written at the end holds every episode in the plan's order, as one
uninterrupted run writes it, and the summary and comparisons count them all.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.runtime.claimed import IN_USE, held_by_a_writer

if TYPE_CHECKING:
    from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec
    from roomba_bt.evaluate.parallel import Evaluation
    from roomba_bt.evaluate.plan import EpisodePlan
    from roomba_bt.evaluate.records import CutShort, PartialResults
    from roomba_bt.sim.world import World

#: How far a record's start pose (m, degrees) may be from the one this evaluation draws for
#: its seed: the records keep ten significant digits
START_TOLERANCE = 1e-6


def add_resume_options(ev: argparse.ArgumentParser) -> None:
    """``--resume`` and ``--force``: what to do with an ``--out`` that holds episodes."""
    ev.add_argument(
        "--resume",
        action="store_true",
        help="--out holds episodes of an interrupted evaluation (or its .partial.jsonl "
        "does): check they were made alike, run only the missing (variant, seed) pairs, "
        "and write every episode to --out",
    )
    ev.add_argument(
        "--force",
        action="store_true",
        help="write over an --out that holds episodes (without it, such a file is refused)",
    )


class ResumeError(ValueError):
    """Why ``--out``'s episodes cannot be resumed or written over; the message names the
    file (and line) and what differs."""


@dataclass
class Resumed:
    """The episodes ``--out`` already holds, per variant, and those left to run."""

    #: per variant, the episodes read back, in the plan's order
    earlier: list[list[EpisodeResult]]
    #: per variant, the episodes not in the file, in the plan's order
    todo: list[EpisodePlan]
    #: per variant, every episode of the evaluation (each seed's place: ``place``)
    planned: list[EpisodePlan]
    #: a line each, the records found cut short at the end of a file and dropped
    #: (:class:`~roomba_bt.evaluate.records.CutShort`): what became of their episodes
    cut_said: list[str] = field(default_factory=list)
    #: the files the episodes read back came from (``--out``, its partial file): "read
    #: back from ab.jsonl" named ``--out`` alone when most came from the partial file
    read_from: list[str] = field(default_factory=list)

    @property
    def reused(self) -> int:
        return sum(len(results) for results in self.earlier)

    def record_into(self, partial: PartialResults) -> None:
        """The episodes read back written into the new partial file first: it is emptied
        when this evaluation claims it, and a second interruption would lose them."""
        for results in self.earlier:
            for result in results:
                partial.add(result)

    def read_back(self) -> list[list[EpisodeSpec]]:
        """Per variant, the specs of the episodes read back without a path (in the plan's
        order): what ``--plot`` runs again for their paths. A record written under
        ``--plot`` keeps its path (``records.kept_path``) and is drawn from it: a resumed
        sweep ran every finished episode again to draw it."""
        return [
            [batch[_placed(batch, result)] for result in earlier if not result.trajectory]
            for batch, earlier in zip(self.planned, self.earlier, strict=True)
        ]

    def merged(self, done: list[Evaluation]) -> list[Evaluation]:
        """Each variant's episodes, those read back and those run now, in the plan's order
        (the order an uninterrupted run writes them in)."""
        return [
            replace(e, results=sorted([*earlier, *e.results], key=_in_order_of(batch)))
            for e, earlier, batch in zip(done, self.earlier, self.planned, strict=True)
        ]


def _placed(plan: EpisodePlan, result: EpisodeResult) -> int:
    """Where ``result``'s episode is in ``plan``, which holds it (checked as it was read)."""
    place = plan.place(result.seed)
    assert place is not None, result.seed
    return place


def _in_order_of(plan: EpisodePlan) -> Callable[[EpisodeResult], int]:
    return lambda result: _placed(plan, result)


def partial_path(out: str) -> Path:
    """The file :class:`~roomba_bt.evaluate.records.PartialResults` writes beside ``out``."""
    return Path(f"{out}.partial.jsonl")


def earlier_files(out: str) -> list[Path]:
    """``--out`` and its partial file, those that exist and hold a record."""
    return [path for path in (Path(out), partial_path(out)) if _holds_records(path)]


def _holds_records(path: Path) -> bool:
    """Whether ``path`` holds a line after a CSV's header (or any JSON line): an episode,
    or something that is not one, which is not written over either."""
    header = 1 if path.suffix.lower() == ".csv" else 0
    found = 0
    # a pipe (open() waits for a writer, for ever) or a device holds no records: not opened.
    # Read up to the first record, a line at most 64 KiB at a time: the whole file was read
    # into a list, and an --out linked to /dev/zero was a MemoryError, exit 70
    if path.exists() and not path.is_file():
        return False
    try:
        with path.open(encoding="utf-8", errors="replace") as text:
            while found <= header and (line := text.readline(1 << 16)):
                found += bool(line.strip())
    except (FileNotFoundError, IsADirectoryError):
        return False
    return found > header


def refused_over(args: argparse.Namespace) -> str | None:
    """The problem with ``--out``, before any episode runs: a file holding episodes,
    without ``--resume`` or ``--force``; ``--resume`` and ``--force`` together, or
    ``--resume`` without ``--out``; a sweep writing it now (its partial file's lock), which
    neither resumes nor writes over."""
    if args.resume and args.force:
        return (
            "--resume and --force: give one (--resume keeps --out's episodes, --force drops them)"
        )
    if args.out is None:
        return "--resume: give --out FILE, the results to resume" if args.resume else None
    if held_by_a_writer(partial_path(args.out)):  # a sweep running now: not an earlier one's
        return f"--out {args.out}: {IN_USE}"
    if args.resume or args.force:
        return None
    held = earlier_files(args.out)
    if not held:
        return None
    # --out itself is "the file": its name, said just before, said again read as two files
    said = " and ".join("the file" if path == Path(args.out) else str(path) for path in held)
    holds, them = ("hold", "them") if len(held) > 1 else ("holds", "it")
    return (
        f"--out {args.out}: {said} already {holds} episodes of an earlier evaluation; give "
        f"--resume to run only the episodes missing from {them} (the same missions, parameters "
        f"and options), --force to write over {them}, or another --out"
    )


def resume(
    args: argparse.Namespace,
    chosen: list[Any],
    batches: list[EpisodePlan],
    world: World,
) -> Resumed:
    """``--out``'s episodes (and its partial file's) that this evaluation would run, checked
    against it, and the specs left to run; with neither ``--resume`` nor a file, every spec.
    ResumeError naming the file, line and what differs when a record was made otherwise."""
    found: list[dict[int, EpisodeResult]] = [{} for _ in batches]
    cut: list[CutShort] = []
    read_from: list[str] = []
    if args.resume:
        variant_of = {(v.mission, v.params): i for i, v in enumerate(chosen)}
        made_by: dict[str, dict[str, Any]] = getattr(args, "made_by", {})
        for path in earlier_files(args.out):
            for line, row, result in _rows(path, cut):
                where = f"{path}:{line}"
                index = variant_of.get((result.mission, tuple(sorted(result.params))))
                named = _named(result.mission, result.params)
                if index is None:
                    raise ResumeError(f"{where}: {named} is no variant of this "
                                      "evaluation (its missions, -p, --sweep or --variant "
                                      f"differ){_runs_instead(result, chosen)}")  # fmt: skip
                spec_at = batches[index].place(result.seed)
                if spec_at is None:
                    raise ResumeError(f"{where}: seed {result.seed} of {named} is not "
                                      "among this evaluation's seeds (--seed, --runs or "
                                      "--seeds differ)")  # fmt: skip
                spec = batches[index][spec_at]
                _check_alike(where, row, result, spec, made_by.get(result.mission, {}), world)
                kept = found[index].setdefault(result.seed, result)  # --out's, then the partial's
                if kept is result and str(path) not in read_from:
                    read_from.append(str(path))
    pairs = list(zip(found, batches, strict=True))
    earlier = [sorted(held.values(), key=_in_order_of(batch)) for held, batch in pairs]
    todo = [batch.without(held) for held, batch in pairs]
    cut_said = [_cut_said(one, chosen, found, batches) for one in cut]
    return Resumed(earlier, todo, batches, cut_said, read_from)


def _cut_said(
    cut: CutShort,
    chosen: list[Any],
    found: list[dict[int, EpisodeResult]],
    planned: Sequence[EpisodePlan],
) -> str:
    """The line that says a record cut short at a file's end was dropped, and what becomes
    of its episode: it runs again (the usual case: a sweep killed as it wrote it), or the
    other file holds it (``--out`` cut by a full disk, the partial file whole)."""
    mine = [i for i, v in enumerate(chosen) if cut.mission in (None, v.mission)]
    if cut.seed is None:  # the episodes no record holds run: it is among them, if any
        then = "cut before its seed, its episode runs again unless another record holds it"
    elif all(planned[i].place(cut.seed) is None for i in mine):
        then = "its seed is not among this evaluation's"
    elif all(cut.seed in found[i] for i in mine if planned[i].place(cut.seed) is not None):
        then = "its episode is read back from the other file"
    else:
        then = "the episode runs again"
    return f"{cut.said(len({v.mission for v in chosen}) > 1)}: dropped; {then}"


def _rows(path: Path, cut: list[CutShort]) -> list[tuple[int, dict[str, Any], EpisodeResult]]:
    """The records of ``path``, a last one cut short dropped into ``cut``."""
    from roomba_bt.evaluate.records import ResultsFileError, read_rows

    try:
        return read_rows(path, cut)
    except ResultsFileError as exc:
        raise ResumeError(f"{exc}; --resume reads it back (--force: write over it)") from None


#: how many of this evaluation's variants a refused record's line names
_VARIANTS_SAID = 3


def _runs_instead(result: EpisodeResult, chosen: list[Any]) -> str:
    """What this evaluation runs, said after a record of no variant of it; and, where a
    mission of it has the record's file name under another path, why: a path is matched as
    given (``../m.yaml`` from one folder, ``proj/m.yaml`` from another, the same file),
    where the refusal named only the record's and a stranger saw the same mission twice."""
    names = [_named(v.mission, v.params) for v in chosen[:_VARIANTS_SAID]]
    more = len(chosen) - _VARIANTS_SAID
    said = f"; this evaluation runs {', '.join(names)}" + (f" and {more} more" if more > 0 else "")
    base = Path(result.mission).name
    moved = [
        v.mission
        for v in chosen
        if v.mission != result.mission and ":" not in v.mission and Path(v.mission).name == base
    ]
    if moved and ":" not in result.mission:
        said += (
            f" ({moved[0]} and {result.mission} name a file {base}: a mission is matched by "
            "its path as given, so give it as the first run did, from the folder it ran in)"
        )
    return said


def _named(mission: str, params: Iterable[tuple[str, str]]) -> str:
    """A variant as a command line gives it: ``dock.yaml -p speed=250mm/s``."""
    return " ".join([mission, *(f"-p {name}={value}" for name, value in params)])


def _check_alike(
    where: str,
    row: dict[str, Any],
    result: EpisodeResult,
    spec: EpisodeSpec,
    made_by: dict[str, Any],
    world: World,
) -> None:
    """ResumeError when the record at ``where`` was not made as this evaluation makes
    ``spec``'s episode: another world, profile (a record that names one), release, mission
    file or plugin (the provenance columns), another start pose for its seed (``--within``,
    ``--start-area``, the world's start region), or other ``--key`` columns."""
    if result.world != world.name:
        raise ResumeError(f"{where}: the episode ran in world {result.world!r}, this "
                          f"evaluation's is {world.name!r} (--world; --force writes over "
                          "it)")  # fmt: skip
    if result.profile and result.profile != spec.profile:  # "": a file written before
        raise ResumeError(f"{where}: the episode ran as profile {result.profile!r}, this "
                          f"evaluation's is {spec.profile!r} (--profile)")  # fmt: skip
    for column, now in made_by.items():
        then = _provenance(column, row.get(column))
        if then != now:
            raise ResumeError(f"{where}: {column} differs from this evaluation's ({_said(then)} "
                              f"in the file, {_said(now)} now): the episodes were made by "
                              "another release, world, mission file or plugin; --force writes "
                              "over them")  # fmt: skip
    from roomba_bt.evaluate.episode import start_pose

    pose = start_pose(world, spec)
    drawn = (pose.x / 1000.0, pose.y / 1000.0, math.degrees(pose.theta))
    if any(abs(a - b) > START_TOLERANCE for a, b in zip(result.start, drawn, strict=True)):
        raise ResumeError(f"{where}: seed {result.seed} started at ({result.start[0]:.3f}, "
                          f"{result.start[1]:.3f}) m, where this evaluation starts it at "
                          f"({drawn[0]:.3f}, {drawn[1]:.3f}) m: --within, --start-area or "
                          "the world's start region differ")  # fmt: skip
    keys = tuple(name for name, _ in result.keys)
    if keys != spec.keys:
        raise ResumeError(f"{where}: the record reports the keys {list(keys)}, this evaluation "
                          f"--key {list(spec.keys)}")  # fmt: skip


def _provenance(column: str, value: Any) -> Any:
    """A provenance cell as :func:`~roomba_bt.cli.eval_cmd.made_by` has it: a CSV cell
    (``name=SHA-256;...``, ``name=version:SHA-256;...``; empty: none) read back; a column
    absent (a file written before it) or an empty cell is None."""
    if not isinstance(value, str) or column not in ("sources", "plugins"):
        return value if value != "" else None
    pairs = [item.partition("=")[::2] for item in value.split(";") if item]
    if column == "sources":
        return dict(pairs)
    return {
        name: dict(zip(("version", "sha256"), about.rsplit(":", 1), strict=False))
        for name, about in pairs
    }


def _said(value: Any) -> str:
    """A provenance value, shortened for a message (a digest's first 12 hex digits)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_said(v)}" for k, v in value.items()) + "}"
    if isinstance(value, str) and len(value) == 64:
        return value[:12] + "..."
    return "none" if value is None else str(value)
