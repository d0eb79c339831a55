"""The cleaning figures of ``docs/routines.md``: clean.yaml against the firmware's Clean.

    python -m roomba_bt.evaluate.coverage_report --docs docs --missions missions --jobs 2

Runs, on the same seeds (so the same start poses) for both missions:

* the apartment's living room: ``--runs`` starts in the living room, 20 minutes each,
  coverage of the living room at 5, 10 and 20 minutes; the coverage-over-time curves of both
  in one figure (``docs/routines/coverage-living-room.png``, the legend below the chart);
* the whole apartment: ``--apartment-runs`` starts anywhere, 60 minutes each, coverage per
  room, the longest brush time without new floor;
* the whole apartment with a low battery (20 %): the runs that reach the missions' 15 %
  threshold, and how many of them end docked;
* ``clean.yaml`` again in the first two, with the simulator's odometry error on
  (:data:`ODOMETRY_ERROR`: the encoders' wheel scales off by up to 1.5 %, the heading
  drifting), since the mission steers and maps by odometry alone;

and writes the tables between the ``<!-- coverage -->`` markers of ``routines.md``. About 35
minutes of CPU time with the default counts (``--runs 50``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from roomba_bt.evaluate import EpisodeSpec, run_episodes
from roomba_bt.evaluate.coverage import CoverageSummary, Spread, summarize_coverage
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.evaluate.parallel import ProgressBar
from roomba_bt.evaluate.report import picture
from roomba_bt.evaluate.stats import wilson_interval

BEGIN, END = "<!-- coverage -->", "<!-- /coverage -->"
MISSIONS = ("clean", "clean-builtin")
#: the low-battery runs' start charge: low enough that clean.yaml reaches its 15 % threshold
#: before its map says the floor is done (from 30 % it finished first and never docked)
LOW_BATTERY = 0.2
#: the odometry error of the drift rows (``Faults.odometry_error``)
ODOMETRY_ERROR = 0.015
#: the row of clean.yaml run with it
DRIFT = "clean, odometry error"
REPORT_TIMES_S = (300.0, 600.0, 1200.0)


def _specs(mission: Path, runs: int, minutes: int, **fields: object) -> list[EpisodeSpec]:
    return [
        EpisodeSpec(
            str(mission), "apartment", seed, params=(("duration", f"{minutes}min"),),
            timeout_s=minutes * 60.0 + 60.0, **fields,  # type: ignore[arg-type]
        )
        for seed in range(runs)
    ]  # fmt: skip


def _run(label: str, specs: list[EpisodeSpec], jobs: int) -> list[EpisodeResult]:
    return run_episodes(specs, jobs=jobs, progress=ProgressBar(label=f"{label} "))


def _pct(value: float) -> str:
    return f"{100 * value:.1f} %"


def _label(name: str) -> str:
    if name == DRIFT:
        return f"`clean.yaml`, odometry error {100 * ODOMETRY_ERROR:g} %"
    return f"`{name}.yaml`"


def _at(episodes: list[EpisodeResult], seconds: float) -> list[float]:
    """Each episode's coverage at ``seconds`` (one that ended sooner: its coverage then)."""
    return [r.coverage.at(seconds) for r in episodes if r.coverage is not None]


def _living_room_table(
    results: dict[str, list[EpisodeResult]], summaries: dict[str, CoverageSummary]
) -> list[str]:
    lines = [
        "| mission | 5 min | 10 min | 20 min | min at 20 min | 60 s without new floor |",
        "|---|---|---|---|---|---|",
    ]
    for name, s in summaries.items():
        at = {t: Spread.of(_at(results[name], t)) for t in REPORT_TIMES_S}
        cells = [f"{_pct(at[t].mean)} (sd {100 * at[t].sd:.1f})" for t in REPORT_TIMES_S]
        lines.append(
            f"| {_label(name)} | {' | '.join(cells)} | {_pct(at[1200.0].low)} | "
            f"{s.stuck} of {s.episodes} (longest {s.longest_idle_s:.0f} s) |"
        )
    return lines


def _paired_lines(results: dict[str, list[EpisodeResult]]) -> list[str]:
    """clean against the builtin at 10 min, start by start (the same seeds, the same poses)."""
    lines = []
    builtin = _at(results["clean-builtin"], 600.0)
    for name in ("clean", DRIFT):
        if name not in results:
            continue
        ours = _at(results[name], 600.0)
        # the same seeds from 0: the first len(ours) starts are the same starts
        gains = [a - b for a, b in zip(ours, builtin[: len(ours)], strict=True)]
        better = sum(1 for g in gains if g > 0)
        lines.append(
            f"* {_label(name)} at 10 minutes: {100 * sum(gains) / len(gains):+.1f} points from "
            f"`clean-builtin.yaml` on average (start by start: min {100 * min(gains):+.1f}, "
            f"max {100 * max(gains):+.1f}; ahead on {better} of {len(gains)} starts)"
        )
    return lines


def _apartment_table(summaries: dict[str, CoverageSummary]) -> list[str]:
    names = [name for name, _ in next(iter(summaries.values())).by_area]
    lines = [
        f"| mission | all rooms | {' | '.join(names)} | 60 s without new floor |",
        "|---|---|" + "---|" * len(names) + "---|",
    ]
    for mission, s in summaries.items():
        areas = dict(s.by_area)
        cells = [f"{_pct(areas[n].mean)} (min {_pct(areas[n].low)})" for n in names]
        lines.append(
            f"| {_label(mission)} | {_pct(s.final.mean)} (min {_pct(s.final.low)}) | "
            f"{' | '.join(cells)} | {s.stuck} of {s.episodes} "
            f"(longest {s.longest_idle_s:.0f} s) |"
        )
    return lines


def _curves_figure(results: dict[str, list[EpisodeResult]], path: Path) -> None:
    from roomba_bt.sim.plot import pyplot

    fig = curves_figure(results)
    try:
        # cut to fit what is drawn, the legend below the chart included
        fig.savefig(str(path), bbox_inches="tight")
    finally:
        pyplot().close(fig)


def curves_figure(results: dict[str, list[EpisodeResult]]) -> Any:
    """The living room's coverage over time, each mission's mean and its 10th..90th
    percentile band (a matplotlib ``Figure``, for the caller to save and close)."""
    from roomba_bt.sim.plot import pyplot

    fig, ax = pyplot().subplots(figsize=(7, 4.5), dpi=110)
    means_drawn, bands_drawn = [], []  # the legend's two columns: a row a mission
    for name, episodes in results.items():
        covered = [r.coverage for r in episodes if r.coverage is not None]
        # an episode that ended sooner (the floor done) keeps its coverage to the end
        times = [t for t, _ in max((c.curve for c in covered), key=len)]
        means, lows, highs = [], [], []
        for t in times:
            values = sorted(c.at(t) for c in covered)
            means.append(100 * sum(values) / len(values))
            lows.append(100 * values[len(values) // 10])
            highs.append(100 * values[(9 * len(values)) // 10])
        minutes = [t / 60 for t in times]
        shown = _label(name).replace("`", "")
        (line,) = ax.plot(minutes, means, label=f"{shown} (mean)")
        band = ax.fill_between(minutes, lows, highs, color=line.get_color(), alpha=0.15,
                               label=f"{shown} (10th..90th percentile)")  # fmt: skip
        means_drawn.append(line)
        bands_drawn.append(band)
    ax.set_xlabel("time (min)")
    ax.set_ylabel("living room covered (%)")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    # below the chart, not on it: "lower right" hid the bands from 5 minutes on (as eval
    # --plot's legends, below each map); a row a mission, its mean beside its band
    ax.legend(handles=[*means_drawn, *bands_drawn], loc="upper center",
              bbox_to_anchor=(0.5, -0.14), ncol=2, fontsize=8, frameon=False)  # fmt: skip
    ax.set_title(f"Apartment living room, {len(next(iter(results.values())))} seeded starts")
    fig.tight_layout()
    return fig


def _battery_lines(results: dict[str, list[EpisodeResult]]) -> list[str]:
    """Each mission's low-battery runs that ended docked and charging, with the count's 95 %
    Wilson interval: of 4 runs, "3 of 4" alone read as 75 %, where the runs allow 30-95 %."""
    lines = []
    for name, episodes in results.items():
        docked = sum(1 for r in episodes if r.docked and r.charging)
        lo, hi = wilson_interval(docked, len(episodes))
        lines.append(
            f"* {_label(name)}: {docked} of {len(episodes)} runs (95 % Wilson interval "
            f"{100 * lo:.1f}..{100 * hi:.1f} %) ended docked and charging "
            f"(outcomes: {', '.join(sorted({r.outcome for r in episodes}))}; "
            f"fell: {sum(r.fell for r in episodes)})"
        )
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description="The cleaning figures of docs/routines.md: clean.yaml against the "
        "firmware's Clean."
    )
    parser.add_argument("--docs", type=Path, required=True, help="the docs folder")
    parser.add_argument("--missions", type=Path, required=True, help="the missions folder")
    parser.add_argument("--runs", type=int, default=50, help="living-room starts (50)")
    parser.add_argument("--apartment-runs", type=int, default=10, help="apartment starts (10)")
    parser.add_argument(
        "--drift-runs",
        type=int,
        default=50,
        help="starts with the odometry error on, in each experiment (50)",
    )
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    page = args.docs / "routines.md"
    text = page.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        print(f"{page}: no {BEGIN} ... {END} section to fill", file=sys.stderr)
        return 2
    figures = args.docs / "routines"
    figures.mkdir(exist_ok=True)
    living: dict[str, list[EpisodeResult]] = {}
    apartment: dict[str, list[EpisodeResult]] = {}
    battery: dict[str, list[EpisodeResult]] = {}
    for name in MISSIONS:
        mission = args.missions / f"{name}.yaml"
        living[name] = _run(f"{name} living room", _specs(mission, args.runs, 20,
                            start_area="living-room"), args.jobs)  # fmt: skip
        apartment[name] = _run(f"{name} apartment", _specs(mission, args.apartment_runs, 60),
                               args.jobs)  # fmt: skip
        battery[name] = _run(f"{name} low battery", _specs(mission, args.apartment_runs, 60,
                             battery=LOW_BATTERY), args.jobs)  # fmt: skip
    mission = args.missions / "clean.yaml"
    drift = {"odometry_error": ODOMETRY_ERROR}
    runs = min(args.drift_runs, args.runs)
    living[DRIFT] = _run("clean, odometry error, living room", _specs(mission, runs, 20,
                         start_area="living-room", **drift), args.jobs)  # fmt: skip
    runs = min(args.drift_runs, args.apartment_runs)
    apartment[DRIFT] = _run("clean, odometry error, apartment", _specs(mission, runs, 60,
                            **drift), args.jobs)  # fmt: skip
    battery[DRIFT] = _run("clean, odometry error, low battery", _specs(mission, runs, 60,
                          battery=LOW_BATTERY, **drift), args.jobs)  # fmt: skip
    living_cov = {n: summarize_coverage(r) for n, r in living.items()}
    apartment_cov = {n: summarize_coverage(r) for n, r in apartment.items()}
    if any(s is None for s in (*living_cov.values(), *apartment_cov.values())):
        print("a mission ran no brushes", file=sys.stderr)
        return 1
    living_ok = {n: s for n, s in living_cov.items() if s is not None}
    apartment_ok = {n: s for n, s in apartment_cov.items() if s is not None}
    _curves_figure(living, figures / "coverage-living-room.png")
    section = _section(args, living, living_ok, apartment_ok, battery)
    before, _, rest = text.partition(BEGIN)
    _, _, after = rest.partition(END)
    page.write_text(before + "\n".join(section) + after, encoding="utf-8")
    print(f"{page}: coverage section written", file=sys.stderr)
    return 0


def _section(
    args: argparse.Namespace,
    living_results: dict[str, list[EpisodeResult]],
    living: dict[str, CoverageSummary],
    apartment: dict[str, CoverageSummary],
    battery: dict[str, list[EpisodeResult]],
) -> list[str]:
    """The lines between BEGIN and END: the three experiments' tables and the figure."""
    return [
        BEGIN,
        f"Living room of the apartment, {args.runs} seeded starts in the living room (the same "
        "for every row), 20 minutes at most (`clean.yaml` stops sooner when its map says the "
        "floor is done: its coverage then holds); coverage of the living room's reachable "
        "floor, mean (sd):",
        "",
        *_living_room_table(living_results, living),
        "",
        *_paired_lines(living_results),
        "",
        f"The odometry error ({100 * ODOMETRY_ERROR:g} %): the simulator's encoders count each "
        "wheel with a seeded scale error (a common one up to 1.5 %, a difference between the "
        "wheels up to 0.15 %) and the heading they give drifts up to 0.9 deg a minute of "
        "driving (`roomba-bt eval --odometry-error 0.015`); the robot's true path is "
        "unchanged, only what the mission can know of it. Its rows ran the first "
        f"{min(args.drift_runs, args.runs)} living-room starts and the first "
        f"{min(args.drift_runs, args.apartment_runs)} apartment starts.",
        "",
        picture(
            "coverage-living-room.png",
            "Coverage of the living room over time, in percent of its floor, for each row of "
            "the table above: the mean as a line, the 10th to 90th percentile as a band",
        ),
        "",
        f"Whole apartment, {args.apartment_runs} seeded starts anywhere, 60 minutes each; "
        "coverage per room at the end, mean (min):",
        "",
        *_apartment_table(apartment),
        "",
        f"Whole apartment from {100 * LOW_BATTERY:.0f} % of charge (the 15 % threshold comes "
        f"after about 7 minutes of cleaning), {args.apartment_runs} starts, 60 minutes:",
        "",
        *_battery_lines(battery),
        "",
        "Produced by `make coverage` (`python -m roomba_bt.evaluate.coverage_report`).",
        END,
    ]


if __name__ == "__main__":
    raise SystemExit(main())
