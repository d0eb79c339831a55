"""Coverage across a batch of episodes: mean and spread at fixed times and at the end, per
area, and the longest a robot went without new floor with its brushes on (idle).

Each episode's :class:`~roomba_bt.evaluate.episode.Coverage` comes from the simulator's swept
area (:mod:`roomba_bt.sim.coverage`); episodes whose brushes never ran have none and are left
out. ``roomba-bt eval`` prints :meth:`CoverageSummary.lines` under the success rate.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from roomba_bt.evaluate.episode import EpisodeResult

#: the fixed times coverage is reported at (s of mission time)
REPORT_TIMES_S = (300.0, 600.0, 1200.0)
#: a robot that cleans no new floor for this long (s of brush time) is stuck
STUCK_S = 60.0


@dataclass(frozen=True)
class Spread:
    """Mean, standard deviation, minimum and maximum of a sample (fractions 0..1)."""

    mean: float
    sd: float
    low: float
    high: float

    @classmethod
    def of(cls, values: Sequence[float]) -> Spread:
        sd = statistics.stdev(values) if len(values) > 1 else 0.0
        return cls(statistics.fmean(values), sd, min(values), max(values))

    def to_dict(self) -> dict[str, float]:
        return {"mean": self.mean, "sd": self.sd, "min": self.low, "max": self.high}

    def __str__(self) -> str:
        return (
            f"{100 * self.mean:5.1f} % (sd {100 * self.sd:4.1f}, "
            f"{100 * self.low:.1f}..{100 * self.high:.1f})"
        )


@dataclass(frozen=True)
class CoverageSummary:
    """Coverage of one mission's episodes."""

    area: str  # "" for all the reachable floor
    episodes: int
    #: (time s, spread) for each report time that every episode reached (or ended with
    #: success before: its coverage at the end holds)
    at: tuple[tuple[float, Spread], ...]
    final: Spread
    by_area: tuple[tuple[str, Spread], ...]
    longest_idle_s: float
    stuck: int  # episodes with STUCK_S of brush time without new floor
    #: per area, how many episodes could reach it (an area is in an episode's figures only
    #: when some of it is reachable from its start: not behind a virtual wall)
    reached: tuple[tuple[str, int], ...] = ()
    #: the batch's other episodes, left out of every figure: their brushes never ran (a
    #: mission that cleans only when it finds dirt, one that failed before its cleaning)
    never_cleaned: int = 0

    @property
    def partial(self) -> int:
        """Episodes that could reach only some of the areas (a start behind a virtual wall or
        in a closed-off room): their "reachable floor" is that part, not the whole."""
        return max((self.episodes - n for _, n in self.reached), default=0)

    def lines(self) -> list[str]:
        what = f"the {self.area}" if self.area else "the reachable floor"
        left_out = f" ({self.never_cleaned} never ran the brushes)" if self.never_cleaned else ""
        out = [f"coverage     of {what}, {self.episodes} episodes{left_out}: mean (sd, min..max)"]
        out += [f"  at {t / 60:4.0f} min {spread}" for t, spread in self.at]
        out.append(f"  at the end {self.final}")
        reached = dict(self.reached)
        for name, spread in self.by_area:
            n = reached.get(name, self.episodes)
            some = "" if n == self.episodes else f" ({n} of {self.episodes} episodes reached it)"
            out.append(f"  {name:<12s} {spread} at the end{some}")
        if self.partial and not self.area:
            out.append(
                f"  reach      {self.partial} of {self.episodes} episodes could reach only part "
                "of the floor (a start behind a virtual wall or in a closed-off room): their "
                "figures are of that part"
            )
        out.append(
            f"  idle       {self.stuck} of {self.episodes} episodes went {STUCK_S:.0f} s of "
            f"brush time without new floor (longest {self.longest_idle_s:.0f} s)"
        )
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain data for ``eval --json`` (fractions 0..1, times in s)."""
        return {
            "area": self.area,
            "episodes": self.episodes,
            "at": [{"time_s": t, **spread.to_dict()} for t, spread in self.at],
            "final": self.final.to_dict(),
            "by_area": {name: spread.to_dict() for name, spread in self.by_area},
            "longest_idle_s": self.longest_idle_s,
            "stuck": self.stuck,
            "reached": dict(self.reached),
            "never_cleaned": self.never_cleaned,
        }

    def __str__(self) -> str:
        return "\n".join(self.lines())


def summarize_coverage(
    results: Sequence[EpisodeResult], times: Sequence[float] = REPORT_TIMES_S
) -> CoverageSummary | None:
    """The coverage of the episodes that cleaned, or None if none did."""
    covered = [r.coverage for r in results if r.coverage is not None]
    if not covered:
        return None
    # a mission that ended by itself (the floor done) keeps its coverage to any later time
    # another episode reached; one cut short otherwise (a failure) ends the report times
    ran = [r for r in results if r.coverage is not None]
    cut = [r.time_s for r in ran if not r.succeeded]
    last = min(cut) if cut else max(r.time_s for r in ran)
    # every area any episode reached, in the world's order (the first episode's alone left
    # out the rooms it could not reach from its start)
    names = _in_order([name for name, _ in c.by_area] for c in covered)
    by_area = []
    reached = []
    for name in names:
        present = [v for c in covered if (v := dict(c.by_area).get(name)) is not None]
        by_area.append((name, Spread.of(present)))
        reached.append((name, len(present)))
    idle = [c.longest_idle_s for c in covered]
    return CoverageSummary(
        area=covered[0].area,
        episodes=len(covered),
        at=tuple((t, Spread.of([c.at(t) for c in covered])) for t in times if t <= last + 1e-6),
        final=Spread.of([c.final for c in covered]),
        by_area=tuple(by_area),
        longest_idle_s=max(idle),
        stuck=sum(1 for i in idle if i >= STUCK_S),
        reached=tuple(reached),
        never_cleaned=len(results) - len(covered),
    )


def _in_order(lists: Iterable[list[str]]) -> list[str]:
    """The names of every list, each once, in the order the lists share (the world's areas,
    each episode listing those it reached): a name is placed after the one before it."""
    merged: list[str] = []
    for names in lists:
        after = -1
        for name in names:
            if name in merged:
                after = merged.index(name)
            else:
                after += 1
                merged.insert(after, name)
    return merged
