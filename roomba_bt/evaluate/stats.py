"""Statistics of a batch of episodes: success rate with a Wilson interval, time percentiles,
bumps, and the failure reasons grouped.

Why Wilson: with 50 or 200 episodes and rates near 100 %, the textbook normal interval
(``p +- 1.96 sqrt(p(1-p)/n)``) collapses to zero width at 100 % and can leave [0, 1]; the
Wilson score interval stays inside [0, 1] and is honest at the edges (200 successes out of
200 give 98.1 %..100 %, not 100 %..100 %).
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

from roomba_bt.evaluate.episode import EpisodeResult

Z95 = 1.959963984540054


def wilson_interval(successes: int, runs: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion (95 % by default)."""
    if runs <= 0:
        return (0.0, 1.0)
    if not 0 <= successes <= runs:
        raise ValueError(f"successes must be in 0..{runs}, got {successes}")
    p = successes / runs
    z2 = z * z
    centre = (p + z2 / (2 * runs)) / (1 + z2 / runs)
    half = z * math.sqrt(p * (1 - p) / runs + z2 / (4 * runs * runs)) / (1 + z2 / runs)
    return (max(0.0, centre - half), min(1.0, centre + half))


def percentile(values: Sequence[float], q: float) -> float | None:
    """The ``q``-th percentile (0..100), linear between closest ranks; None if empty."""
    if not values:
        return None
    ordered = sorted(values)
    rank = (len(ordered) - 1) * q / 100.0
    lo = math.floor(rank)
    hi = min(lo + 1, len(ordered) - 1)
    return ordered[lo] + (ordered[hi] - ordered[lo]) * (rank - lo)


_LEAF_PREFIX = re.compile(r"^[a-z_][a-z0-9_]*\([^)]*\): ")


def reason_group(result: EpisodeResult) -> str:
    """A failure reason without the leaf's parameters, so equal causes group together."""
    reason = result.reason or result.outcome
    stripped = _LEAF_PREFIX.sub("", reason)
    return f"{result.outcome}: {stripped}" if result.outcome != "failure" else stripped


@dataclass(frozen=True)
class Summary:
    """What an evaluation found."""

    mission: str
    world: str
    runs: int
    successes: int
    interval: tuple[float, float]
    median_time_s: float | None
    p90_time_s: float | None
    mean_bumps: float
    #: episodes that ended on the dock's contacts (measured by the simulator)
    docked: int
    failures: tuple[tuple[str, int], ...]
    wall_s: float
    simulated_s: float

    @property
    def rate(self) -> float:
        return self.successes / self.runs if self.runs else 0.0

    def lines(self) -> list[str]:
        lo, hi = self.interval
        med = "n/a" if self.median_time_s is None else f"{self.median_time_s:.1f} s"
        p90 = "n/a" if self.p90_time_s is None else f"{self.p90_time_s:.1f} s"
        speed = self.simulated_s / self.wall_s if self.wall_s > 0 else 0.0
        out = [
            f"mission      {self.mission} in {self.world}",
            f"success      {self.successes}/{self.runs} = {100 * self.rate:.1f} % "
            f"(95 % Wilson interval {100 * lo:.1f} %..{100 * hi:.1f} %)",
            f"time         median {med}, p90 {p90} (successful episodes, mission time)",
            f"bumps        {self.mean_bumps:.1f} per episode (bumper onsets in the simulator)",
            f"docked       {self.docked} of {self.runs} episodes ended on the dock's contacts",
            f"simulated    {self.simulated_s:.0f} s of mission time in {self.wall_s:.1f} s of "
            f"CPU time ({speed:.0f}x real time per process)",
        ]
        if self.failures:
            out.append("failures")
            out += [f"  {count:4d}  {reason}" for reason, count in self.failures]
        return out

    def __str__(self) -> str:
        return "\n".join(self.lines())


def summarize(mission: str, world: str, results: Sequence[EpisodeResult]) -> Summary:
    """Aggregate episodes into a :class:`Summary`."""
    runs = len(results)
    ok = [r for r in results if r.succeeded]
    times = [r.time_s for r in ok]
    groups = Counter(reason_group(r) for r in results if not r.succeeded)
    return Summary(
        mission=mission,
        world=world,
        runs=runs,
        successes=len(ok),
        interval=wilson_interval(len(ok), runs),
        median_time_s=percentile(times, 50),
        p90_time_s=percentile(times, 90),
        mean_bumps=sum(r.bumps for r in results) / runs if runs else 0.0,
        docked=sum(r.docked for r in results),
        failures=tuple(sorted(groups.items(), key=lambda kv: (-kv[1], kv[0]))),
        wall_s=sum(r.wall_s for r in results),
        simulated_s=sum(r.time_s for r in results),
    )
