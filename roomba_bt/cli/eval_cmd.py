"""``roomba-bt eval``: how often does a mission succeed, and how fast?

    roomba-bt eval missions/dock.yaml --world empty-room --runs 200 --seed 1 --within 1.5 \
        --jobs 2 --plot dock.png

Runs N seeded episodes of the mission on the simulator's virtual clock, from random start
poses in the world's start region (or within ``--within`` metres of the dock), in ``--jobs``
worker processes, with a progress bar on stderr; then prints the success rate with its 95 %
Wilson interval, the median and p90 time, bumps, and the failure reasons grouped. The same
``--seed`` gives the same episodes whatever ``--jobs``. Exit codes: 0 (and 1 when
``--min-rate`` is given and not reached), 2 for invalid input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from roomba_bt.cli.arguments import add_param_option, parse_params, parse_timeout, plot_file
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.runtime.summary import ExitCode


def register(sub: Any) -> None:
    ev = sub.add_parser(
        "eval",
        help="run a mission many times on the simulator and report its success rate",
        description="Run MISSION in N seeded episodes on the simulator's virtual clock and "
        "report the success rate (95% Wilson interval), median and p90 time, bumps and the "
        "failure reasons. Exit codes: 0 done, 1 --min-rate not reached, 2 invalid input.",
    )
    ev.add_argument("mission", help="mission YAML file")
    ev.add_argument("--world", default="empty-room", help="a shipped world name or a YAML path")
    ev.add_argument("--runs", type=int, default=20, help="number of episodes (default 20)")
    ev.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    ev.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    ev.add_argument("--plot", metavar="FILE.png", type=plot_file,
                    help="draw every trajectory (matplotlib)")  # fmt: skip
    ev.add_argument(
        "--within", type=float, metavar="METRES",
        help="start within this distance of the docked pose (default: the world's region)",
    )  # fmt: skip
    add_param_option(ev, "set a mission parameter (repeatable)")
    ev.add_argument(
        "--dock",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="override a dock beam parameter: buoy_range=0.5 (m), force_field=0.3 (m), "
        "red=-5,25 (deg), green=-25,5, contact_tolerance=0.05 (m), angle_tolerance=6 (deg), "
        "family=discovery (characters 240-254)",
    )
    ev.add_argument("--battery", type=float, metavar="FRACTION", help="initial charge 0..1")
    ev.add_argument("--timeout", default="15min", help="mission time per episode (default 15min)")
    ev.add_argument("--profile", choices=sorted(PROFILES), default="create2")
    ev.add_argument("--min-rate", type=float, metavar="FRACTION",
                    help="exit 1 if the success rate is below this (for CI)")  # fmt: skip
    ev.add_argument("--no-progress", action="store_true", help="no progress bar")
    ev.set_defaults(func=eval_command)


def _error(message: str) -> int:
    print(f"roomba-bt eval: {message}", file=sys.stderr)
    return ExitCode.INVALID


def parse_dock(items: list[str]) -> tuple[tuple[str, Any], ...] | str:
    """``["buoy_range=0.5", "red=-5,25"]`` -> ((name, value), ...); a message on error."""
    from roomba_bt.evaluate.episode import DOCK_OVERRIDES

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
                if text not in ("drive-on", "discovery"):
                    return f"--dock {item!r}: family is drive-on or discovery"
                out.append((name, text))
            elif name in ("red", "green"):
                lo, hi = (float(v) for v in text.split(","))
                if not -90 <= lo < hi <= 90:
                    return f"--dock {item!r}: expected FROM,TO in degrees, -90 <= FROM < TO <= 90"
                out.append((name, (lo, hi)))
            else:
                value = float(text)
                if value <= 0:
                    return f"--dock {item!r}: expected a number above 0"
                out.append((name, value))
        except ValueError:
            return f"--dock {item!r}: {text!r} is not a number (or FROM,TO for red/green)"
    return tuple(out)


def eval_command(args: argparse.Namespace) -> int:
    from roomba_bt.evaluate import EvaluationError, episode_specs, summarize
    from roomba_bt.evaluate.parallel import ProgressBar, run_episodes

    if not Path(args.mission).is_file():
        return _error(f"{args.mission}: no such mission file")
    if args.runs < 1:
        return _error(f"--runs {args.runs}: expected at least 1")
    if args.jobs < 1:
        return _error(f"--jobs {args.jobs}: expected at least 1")
    if args.within is not None and args.within <= 0:
        return _error(f"--within {args.within}: expected a distance above 0 m")
    if args.battery is not None and not 0.0 <= args.battery <= 1.0:
        return _error(f"--battery {args.battery}: expected a fraction in 0..1")
    if args.min_rate is not None and not 0.0 <= args.min_rate <= 1.0:
        return _error(f"--min-rate {args.min_rate}: expected a fraction in 0..1")
    params = parse_params(args.param)
    if isinstance(params, str):
        return _error(params)
    timeout = parse_timeout(args.timeout)
    if isinstance(timeout, str) or timeout is None:
        return _error(str(timeout))
    dock = parse_dock(args.dock)
    if isinstance(dock, str):
        return _error(dock)
    specs = episode_specs(
        args.mission,
        world=args.world,
        runs=args.runs,
        seed=args.seed,
        params=tuple(sorted(params.items())),
        profile=args.profile,
        timeout_s=timeout,
        within_m=args.within,
        dock=dock,
        battery=args.battery,
    )
    # Check the mission and the world once, here, before any worker starts.
    from roomba_bt.cli.run_cmd import load
    from roomba_bt.evaluate.episode import build_world, start_pose
    from roomba_bt.oi.profiles import get_profile

    if isinstance(loaded := load(args.mission, params, get_profile(args.profile)), int):
        return loaded
    try:
        world = build_world(specs[0])
        start_pose(world, specs[0])
    except EvaluationError as exc:
        return _error(str(exc))
    progress = None if args.no_progress else ProgressBar(label=f"{Path(args.mission).stem} ")
    results = run_episodes(specs, jobs=args.jobs, progress=progress)
    summary = summarize(args.mission, world.name, results)
    print(summary)
    if args.plot:
        from roomba_bt.evaluate.plot import PlotUnavailableError, plot_trajectories

        try:
            plot_trajectories(world, results, args.plot, f"{Path(args.mission).stem} in "
                              f"{world.name}: {summary.successes}/{summary.runs}")  # fmt: skip
        except PlotUnavailableError as exc:
            print(f"roomba-bt eval: {exc}", file=sys.stderr)
            return ExitCode.INVALID
        except OSError as exc:
            return _error(f"--plot {args.plot}: {exc.strerror or exc}")
        print(f"trajectories written to {args.plot}", file=sys.stderr)
    if args.min_rate is not None and summary.rate < args.min_rate:
        print(
            f"roomba-bt eval: success rate {100 * summary.rate:.1f} % is below --min-rate "
            f"{100 * args.min_rate:.1f} %",
            file=sys.stderr,
        )
        return ExitCode.MISSION_FAILED
    return ExitCode.OK
