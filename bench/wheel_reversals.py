"""Wheel reversals per minute of the shipped wall-following missions on the simulator.

A reversal is a wheel's commanded speed (Drive / Drive Direct) changing sign
(:mod:`roomba_bt.evaluate.wheels`); the simulator has no acceleration limit, so only this
count shows what a real Create 2's wheel motors would go through. Two missions:

* ``clean`` in the apartment, from the living room, for its 20 minutes with
  ``go_home=false`` (the cleaning alone: the dock subtree is another behaviour);
* ``wall-follow`` in the empty room, its 60 s.

For each: reversals per minute (mean over the seeds), the shortest interval between two
reversals of one wheel, and how many came within 0.1 s and 0.15 s of that wheel's previous
one (chatter, not a manoeuvre). ``python -m bench.wheel_reversals [--runs N]``
(docs/routines.md has the figures).
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from roomba_bt.evaluate import EpisodeSpec
from roomba_bt.evaluate.wheels import WheelReversals, count_reversals

ROOT = Path(__file__).resolve().parents[1]
#: (label, mission, world, spec fields)
RUNS: tuple[tuple[str, str, str, dict[str, object]], ...] = (
    ("clean, apartment (living room), 20 min", "clean.yaml", "apartment",
     {"start_area": "living-room", "timeout_s": 1260.0, "params": (("go_home", "false"),)}),
    ("wall-follow, empty room, 60 s", "wall-follow.yaml", "empty-room", {"timeout_s": 90.0}),
)  # fmt: skip


def measure(mission: str, world: str, runs: int, fields: dict[str, object]) -> list[WheelReversals]:
    """The reversals of ``runs`` seeded episodes (seeds 0..runs-1)."""
    path = str(ROOT / "missions" / mission)
    return [
        count_reversals(EpisodeSpec(path, world, seed, trace_every=0, **fields))[1]  # type: ignore[arg-type]
        for seed in range(runs)
    ]


def line(label: str, seen: list[WheelReversals]) -> str:
    shortest = min((s.shortest_s for s in seen if s.shortest_s is not None), default=None)
    total = sum(len(s.events) for s in seen)
    fast = sum(s.chatter(0.1) for s in seen)
    chatter = sum(s.chatter() for s in seen)
    return (
        f"{label:42s} {statistics.fmean(s.per_minute for s in seen):6.1f} a minute, "
        f"shortest {1000 * shortest if shortest is not None else float('nan'):4.0f} ms; "
        f"within 0.1 s: {fast} of {total}, within 0.15 s: {chatter}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=4, help="seeds per mission (default 4)")
    args = parser.parse_args()
    for label, mission, world, fields in RUNS:
        print(line(label, measure(mission, world, args.runs, fields)), flush=True)


if __name__ == "__main__":
    main()
