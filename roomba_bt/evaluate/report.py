"""The figures of ``docs/routines.md``, measured by one command (``make routines``)::

    python -m roomba_bt.evaluate.report --docs docs   # every experiment, 2 worker processes
    python -m roomba_bt.evaluate.report --scale 0.1 --jobs 1 --no-write   # a quick look

Every experiment is a batch of seeded episodes (:mod:`roomba_bt.evaluate.episode`) of the
missions in ``--missions`` (default ``missions``); the tables it prints are written between
the ``<!-- figures:begin -->`` and ``<!-- figures:end -->`` markers of ``DOCS/routines.md``
(the rest of the page is prose that this command never touches), and the trajectory plots
next to it in ``DOCS/routines/``. Nothing here is hard-coded: run it again and the page shows
what the code does now.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from roomba_bt.evaluate import episode_specs
from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, build_world
from roomba_bt.evaluate.parallel import ProgressBar, run_episodes
from roomba_bt.evaluate.stats import Summary, summarize

#: The page (in the ``--docs`` folder) and the folder of its plots, which it links to.
PAGE = "routines.md"
FIGURES = "routines"
BEGIN, END = "<!-- figures:begin -->", "<!-- figures:end -->"


def picture(file: str, shows: str | None = None) -> str:
    """The Markdown of the plot ``FIGURES/file``, its alternative text saying what it shows
    (``shows``, else :data:`SHOWS`'s) and where it is. The wheel leaves the plots out
    (pyproject.toml: 1.2 MB beside the wheel's 1.6), so a Markdown viewer of the installed
    page (``roomba-bt docs routines --path``) shows that text in the plot's place: a bare
    title (``patrol``) said nothing."""
    where = f"docs/{FIGURES}/{file} of roomba-bt's source distribution"
    return f"![{shows or SHOWS[file]} (the picture: {where})]({FIGURES}/{file})"


#: each episode's path, as every plot of :func:`build` draws them
_PATHS = (
    "each episode's path from its start (a dot), green where the mission succeeded and red "
    "where it did not, over the world's walls and furniture"
)
_TO_DOCK = "toward the dock (its buoys and force field drawn at the south wall)"
#: what each plot of :func:`build` shows, for its alternative text (:func:`picture`)
SHOWS = {
    "dock-empty-room.png": f"Dock in the empty room: {_PATHS}, {_TO_DOCK}",
    "dock-apartment.png": f"Dock in the apartment: {_PATHS}, {_TO_DOCK}",
    "patrol-corridor.png": f"Patrol of the corridor: {_PATHS}, around the block in its middle",
    "patrol-low-battery.png": f"Patrol of the corridor on a low battery: {_PATHS}, from the "
    "loop to the dock on the south wall",
    "bump-and-turn-corridor.png": f"Bump-and-turn in the corridor: {_PATHS}, straight lines "
    "from wall to wall for a minute",
}

#: The dock's beam parameters at the ends of the ranges the dock mission is meant to handle
#: (the simulator's defaults are GUIDE.md section 5's: red -5..25, green -25..5 deg, buoys
#: 1 m, force field 0.6 m, contacts 7.5 cm and 6 deg).
BEAM_VARIANTS: dict[str, tuple[tuple[str, Any], ...]] = {
    "short beams (buoys 0.5 m, field 0.3 m)": (("buoy_range", 0.5), ("force_field", 0.3)),
    "long beams (buoys 2 m, field 1 m)": (("buoy_range", 2.0), ("force_field", 1.0)),
    "narrow buoys (red -3..15, green -15..3 deg)": (("red", (-3, 15)), ("green", (-15, 3))),
    "wide buoys (red -10..40, green -40..10 deg)": (("red", (-10, 40)), ("green", (-40, 10))),
    "tight contacts (5 cm, 4 deg)": (("contact_tolerance", 0.05), ("angle_tolerance", 4.0)),
    "Discovery dock (characters 240-254)": (("family", "discovery"),),
}


@dataclass
class Experiment:
    key: str
    label: str
    mission: str
    world: str
    runs: int
    fields: dict[str, Any] = field(default_factory=dict)
    plot: str | None = None


def experiments(scale: float, missions: Path) -> list[Experiment]:
    def n(runs: int) -> int:
        return max(2, math.ceil(runs * scale))

    dock, builtin = str(missions / "dock.yaml"), str(missions / "dock-builtin.yaml")
    out = [
        Experiment("dock-empty", "dock, empty room, within 1.5 m, any heading", dock,
                   "empty-room", n(200), {"within_m": 1.5}, "dock-empty-room.png"),
        Experiment("dock-apartment", "dock, apartment, anywhere (every room, any heading)", dock,
                   "apartment", n(100), {}, "dock-apartment.png"),
    ]  # fmt: skip
    for i, (label, overrides) in enumerate(BEAM_VARIANTS.items()):
        out.append(
            Experiment(f"dock-beams-{i}", f"dock, empty room, 1.5 m, {label}", dock,
                       "empty-room", n(100), {"within_m": 1.5, "dock": overrides})
        )  # fmt: skip
    out += [
        Experiment("builtin-empty", "dock-builtin (143), empty room, within 1.5 m", builtin,
                   "empty-room", n(200), {"within_m": 1.5}),
        Experiment("builtin-apartment", "dock-builtin (143), apartment", builtin, "apartment",
                   n(100), {}),
        Experiment("patrol", "patrol, corridor, 2 laps", str(missions / "patrol.yaml"),
                   "corridor", n(50), {"timeout_s": 900.0}, "patrol-corridor.png"),
        Experiment("patrol-low", "patrol, corridor, battery 15.2 % (threshold 15 %)",
                   str(missions / "patrol.yaml"), "corridor", n(50),
                   {"battery": 0.152, "timeout_s": 900.0}, "patrol-low-battery.png"),
        Experiment("bump", "bump-and-turn, corridor, 60 s",
                   str(missions / "bump-and-turn.yaml"), "corridor", n(50),
                   {"timeout_s": 90.0}, "bump-and-turn-corridor.png"),
        Experiment("bump-apartment", "bump-and-turn, apartment (stairs), 60 s",
                   str(missions / "bump-and-turn.yaml"), "apartment", n(20),
                   {"timeout_s": 90.0}),
    ]  # fmt: skip
    return out


def run_experiment(
    exp: Experiment, jobs: int, seed: int, quiet: bool
) -> tuple[Summary, list[EpisodeResult]]:
    specs = episode_specs(exp.mission, world=exp.world, runs=exp.runs, seed=seed, **exp.fields)
    progress = None if quiet else ProgressBar(label=f"{exp.key:18s} ")
    results = run_episodes(specs, jobs=jobs, progress=progress)
    return summarize(Path(exp.mission).name, exp.world, results), results


def _pct(summary: Summary) -> str:
    lo, hi = summary.interval
    return f"{100 * summary.rate:.1f} % ({100 * lo:.1f}..{100 * hi:.1f})"


def _seconds(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.0f} s"


def dock_table(rows: Sequence[tuple[Experiment, Summary]]) -> list[str]:
    lines = [
        "| experiment | runs | success (95 % Wilson) | median | p90 | bumps/run | "
        "most frequent failure |",
        "|---|---:|---|---:|---:|---:|---|",
    ]
    for exp, s in rows:
        failure = f"{s.failures[0][1]} x {s.failures[0][0]}" if s.failures else "none"
        lines.append(
            f"| {exp.label} | {s.runs} | {_pct(s)} | {_seconds(s.median_time_s)} | "
            f"{_seconds(s.p90_time_s)} | {s.mean_bumps:.1f} | {failure} |"
        )
    return lines


def patrol_lines(exp: Experiment, s: Summary, results: Sequence[EpisodeResult]) -> list[str]:
    loops = [r.loops for r in results]
    low = "battery" in exp.fields
    if low:  # the robot docks: sitting near the dock is the point, not a stall
        stall, stuck = "n/a (docks)", "n/a"
    else:
        stall = f"{max(r.longest_stall_s for r in results):.1f} s"
        stuck = str(sum(1 for r in results if r.longest_stall_s > 30.0))
    line = (
        f"| {exp.label} | {s.runs} | {_pct(s)} | {_seconds(s.median_time_s)} | "
        f"{min(loops):.2f}..{max(loops):.2f} | {stall} | {stuck} | "
        f"{s.docked} of {s.runs}{' (all must)' if low else ''} |"
    )
    return [line]


def _spread(counts: Iterable[int]) -> str:
    """``0: 12, 1: 3`` (-1 counted as ``none``); ``no bump`` when empty."""
    histogram: dict[int, int] = {}
    for c in counts:
        histogram[c] = histogram.get(c, 0) + 1
    text = ", ".join(f"{k if k >= 0 else 'none'}: {v}" for k, v in sorted(histogram.items()))
    return text or "no bump"


def bump_lines(s: Summary, results: Sequence[EpisodeResult]) -> list[str]:
    """Reaction to bumps, from the simulator's bumper state at every 15 ms step."""
    steps = [c for r in results for c in r.contact_steps]
    histogram: dict[int, int] = {}
    for c in steps:
        histogram[c] = histogram.get(c, 0) + 1
    spread = ", ".join(f"{k} ticks: {v}" for k, v in sorted(histogram.items()))
    worst = max(steps) if steps else 0
    outcomes = ", ".join(f"{count} {reason}" for reason, count in s.failures) or "none"
    reactions = [r for e in results for r in e.reaction_steps]
    return [
        f"- {s.runs} runs, {len(steps)} bumps; ticks the bumper stayed pressed after the bump "
        f"frame: {spread or 'no bump'}; worst **{worst}** (bar: at most 2).",
        "- ticks from the bump frame to the write that ended forward motion: "
        f"{_spread(r[0] for r in reactions)}; to the back-off: "
        f"{_spread(r[1] for r in reactions)} (0: written in the bump frame's own tick).",
        f"- {s.successes} of {s.runs} runs drove the full minute; the others stopped as "
        f"designed: {outcomes}.",
    ]


#: Episodes in the speed and scaling figures: dock episodes last 10 s to 2 min of mission
#: time, so with few of them the longest ones bound what a second job can do (two workers
#: taking them in order: 8 episodes ~1.8x at best, 24 ~1.9x, 48 ~1.99x). Evaluations are
#: 50-200 episodes; 48 is the size of a small one.
SPEED_EPISODES = 48
REPEATS = 3


def speed_lines(missions: Path, jobs_seed: int = 100, episodes: int = SPEED_EPISODES) -> list[str]:
    """Virtual-clock speed on one core, and the 1 -> 2 jobs scaling of ``eval``."""
    specs = episode_specs(str(missions / "dock.yaml"), world="empty-room", runs=episodes,
                          seed=jobs_seed, within_m=1.5)  # fmt: skip
    wall_one, wall_two, one, two = measure_scaling(specs)
    simulated = sum(r.time_s for r in one)
    walls = [r.wall_s for r in one]
    # the best two workers can do with these episodes, dispatched in order (the pool's way)
    bound = sum(walls) / two_worker_makespan(walls)
    # what sharing the machine cost: an episode's time beside the other worker over alone
    beside = sum(r.wall_s for r in two) / (sum(walls) or 1.0)
    return [
        f"- Simulator + mission + runtime on the virtual clock, one process ({episodes} dock "
        f"episodes, best of {REPEATS}): {simulated:.0f} s of mission time in {wall_one:.1f} s = "
        f"**{simulated / wall_one:.0f}x** real time (target 100x).",
        f"- `eval` with 2 jobs instead of 1 on the same {episodes} episodes: {wall_one:.1f} s -> "
        f"{wall_two:.1f} s = **{wall_one / wall_two:.2f}x** (target 1.8x; two workers taking "
        f"these episodes in order can do at most {bound:.2f}x; each episode took "
        f"{beside:.2f}x its time alone while the other worker ran beside it).",
    ]


def measure_scaling(
    specs: Sequence[EpisodeSpec], repeats: int = REPEATS
) -> tuple[float, float, list[EpisodeResult], list[EpisodeResult]]:
    """Wall seconds of ``specs`` with 1 and with 2 jobs, each the best of ``repeats``
    (alternated: a shared machine's cores are noisy, and noise only ever adds time); the
    results of the best run of each (their ``wall_s`` are those runs' episodes)."""
    wall_one = wall_two = math.inf
    one: list[EpisodeResult] = []
    two: list[EpisodeResult] = []
    for _ in range(repeats):
        started = time.perf_counter()
        results = run_episodes(specs, jobs=1)
        elapsed = time.perf_counter() - started
        if elapsed < wall_one:
            wall_one, one = elapsed, results
        started = time.perf_counter()
        results = run_episodes(specs, jobs=2)
        elapsed = time.perf_counter() - started
        if elapsed < wall_two:
            wall_two, two = elapsed, results
    return wall_one, wall_two, one, two


def two_worker_makespan(durations: Sequence[float]) -> float:
    """When the last of ``durations`` ends if two workers take them in order, each the next
    one as soon as it is free."""
    free = [0.0, 0.0]
    for duration in durations:
        first = 0 if free[0] <= free[1] else 1
        free[first] += duration
    return max(free) or 1.0


def build(
    scale: float, jobs: int, seed: int, quiet: bool, missions: Path, figures: Path | None
) -> str:
    """The figures section of the page; the plots into ``figures`` unless it is None."""
    results: dict[str, tuple[Experiment, Summary, list[EpisodeResult]]] = {}
    started = time.perf_counter()
    for exp in experiments(scale, missions):
        summary, episodes = run_experiment(exp, jobs, seed, quiet)
        results[exp.key] = (exp, summary, episodes)
        if figures is not None and exp.plot:
            from roomba_bt.evaluate.plot import PlotUnavailableError, plot_trajectories

            figures.mkdir(parents=True, exist_ok=True)
            spec = episode_specs(exp.mission, world=exp.world, runs=1, **exp.fields)[0]
            try:
                plot_trajectories(build_world(spec), episodes, figures / exp.plot,
                                  f"{exp.label}: {summary.successes}/{summary.runs}")  # fmt: skip
            except PlotUnavailableError as exc:
                print(f"report: {exc}", file=sys.stderr)
    took = time.perf_counter() - started
    out = [BEGIN, "", f"Measured by `python -m roomba_bt.evaluate.report` (seeds {seed}.., "
           f"scale {scale:g}, {jobs} jobs) in {took:.0f} s.", ""]  # fmt: skip
    out += ["### Docking", ""]
    dock_rows = [(e, s) for k, (e, s, _) in results.items() if k.startswith(("dock", "builtin"))]
    out += dock_table(dock_rows)
    out += ["", "Failure reasons of the dock mission, grouped:", ""]
    for key in ("dock-empty", "dock-apartment"):
        exp, s, _ = results[key]
        reasons = "; ".join(f"{c} x {r}" for r, c in s.failures) or "none"
        out.append(f"- {exp.label}: {reasons}")
    out += ["", picture("dock-empty-room.png"), picture("dock-apartment.png"), ""]
    out += ["### Patrol", "",
            "| experiment | runs | success (95 % Wilson) | median | loops around the block | "
            "longest stall | stuck (> 30 s) | ended docked |",
            "|---|---:|---|---:|---|---:|---:|---|"]  # fmt: skip
    for key in ("patrol", "patrol-low"):
        exp, s, episodes = results[key]
        out += patrol_lines(exp, s, episodes)
    out += ["", picture("patrol-corridor.png"), picture("patrol-low-battery.png"), ""]
    out += ["### Bump-and-turn: reaction", ""]
    for key in ("bump", "bump-apartment"):
        exp, s, episodes = results[key]
        out += [f"{exp.label}:", ""]
        out += bump_lines(s, episodes)
        out.append("")
    out += [picture("bump-and-turn-corridor.png")]
    out += ["", "### Speed", ""]
    out += speed_lines(missions)
    out += ["", END]
    return "\n".join(out)


def write(section: str, doc: Path) -> None:
    """Replace the text between the markers of ``doc`` (appending them if absent)."""
    text = doc.read_text(encoding="utf-8") if doc.exists() else ""
    pattern = re.compile(re.escape(BEGIN) + r".*?" + re.escape(END), re.S)
    if pattern.search(text):
        text = pattern.sub(lambda _: section, text)
    else:
        text = text.rstrip("\n") + "\n\n" + section + "\n"
    doc.write_text(text, encoding="utf-8")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m roomba_bt.evaluate.report",
        description="Measure the figures of docs/routines.md and write them there.",
    )
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--scale",
        type=float,
        default=1.0,
        help="multiply every experiment's number of runs (quick looks)",
    )
    parser.add_argument(
        "--docs",
        type=Path,
        metavar="DIR",
        help=f"write the figures into DIR/{PAGE} and the plots into DIR/{FIGURES}/",
    )
    parser.add_argument(
        "--missions",
        type=Path,
        default=Path("missions"),
        metavar="DIR",
        help="the folder of the shipped missions (default: missions)",
    )
    parser.add_argument("--no-write", action="store_true", help="print, do not edit the doc")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    if args.scale <= 0 or args.jobs < 1:
        parser.error("--scale must be above 0 and --jobs at least 1")
    if not args.no_write and args.docs is None:
        parser.error("--docs DIR: where to write the figures (or --no-write to print them)")
    if not args.no_write and not args.docs.is_dir():
        parser.error(f"--docs {args.docs}: no such directory")
    if not args.missions.is_dir():
        parser.error(f"--missions {args.missions}: no such directory")
    figures = None if args.no_write else args.docs / FIGURES
    missions = args.missions.resolve()
    section = build(args.scale, args.jobs, args.seed, args.quiet, missions, figures)
    print(section)
    if not args.no_write:
        doc = args.docs / PAGE
        write(section, doc)
        print(f"written to {doc}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
