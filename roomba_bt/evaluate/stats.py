"""Statistics of a batch of episodes: success rate with a Wilson interval, time percentiles,
bumps, the robot's own falls to Passive summed (the hazards apart from the charger's, which
end a docking), and the failure reasons grouped.

Why Wilson: with 50 or 200 episodes and rates near 100 %, the textbook normal interval
(``p +- 1.96 sqrt(p(1-p)/n)``) collapses to zero width at 100 % and can leave [0, 1]; the
Wilson score interval stays inside [0, 1] and is honest at the edges (200 successes out of
200 give 98.1 %..100 %, not 100 %..100 %).
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass

from roomba_bt.behaviours.units import closest
from roomba_bt.evaluate.episode import TRAPPED_RADIUS_MM, EpisodeResult
from roomba_bt.printable import ANY_CONTROL, escaped
from roomba_bt.runtime.summary import (
    YOUR_ACTION_FIX,
    falls_in_order,
    falls_said,
    hazard_falls,
    undeclared_said,
)

Z95 = 1.959963984540054
#: How each figure of a summary and a comparison is computed, at what level: ``eval --json``
#: says it (``methods``) beside the figures, so that an archived summary or a paper's table
#: needs no knowledge of this module (docs/evaluation.md, "What the figures are").
METHODS = {
    "confidence_level": 0.95,
    "interval": "Wilson score interval of the success rate, z = 1.959963984540054",
    "median_time": "over the successful episodes: the 50th percentile, as p90_time",
    "p90_time": "over the successful episodes: linear interpolation between the closest "
    "ranks, at rank (n - 1) * q / 100 (numpy's default, 'linear')",
    "mcnemar_p": "exact McNemar test, two-sided: the binomial test of only_a out of "
    "only_a + only_b at 1/2, in integers; 1 with no discordant pair",
    "time_difference_interval": "distribution-free interval for the median of the paired "
    "differences B - A (order statistics at binomial ranks: coverage at least 0.95, not "
    "exactly; null under 6 pairs), over the pairs both succeeded: conditional on success",
    "coverage_difference_interval": "as time_difference_interval, over the pairs both ran "
    "their brushes in, succeeded or not",
    "multiple_comparisons": "not corrected: each variant is compared with A alone, each "
    "p-value and interval at its own level; for k comparisons together, read each p against "
    "0.05 / k (Bonferroni)",
}
#: an episode that spends this long (s) off the dock without progress (no new floor, no move
#: of TRAPPED_RADIUS_MM: :attr:`EpisodeResult.longest_trapped_s`) was trapped
TRAPPED_S = 60.0


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
    """A failure reason without the leaf's parameters, so equal causes group together. An
    ending other than the tree's FAILURE is said first, in capitals as the run's summary and
    the records say it (``TIMEOUT: --timeout 3 s of mission time ran out in drive``): its
    lower-case word read like the tree's own ``timeout`` decorator that failed a branch
    (``timeout: the tree's 8 s limit ran out in drive``)."""
    reason = result.reason or result.outcome
    stripped = _LEAF_PREFIX.sub("", reason)
    return f"{result.outcome.upper()}: {stripped}" if result.outcome != "failure" else stripped


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
    #: the episodes' wall-clock time summed (each counts the time it waited for a core)
    wall_s: float
    simulated_s: float
    #: the episodes' CPU time summed (:attr:`EpisodeResult.cpu_s`)
    cpu_s: float = 0.0
    #: the episodes that measured no CPU time (DIED; HUNG in C code, where no stack
    #: answered; records read back without the column, ``--reproducible``'s) and their
    #: mission time: the speed is of the others alone. Their mission time over the others'
    #: CPU time read high: a sweep with HUNG episodes said it ran faster than it did
    untimed: int = 0
    untimed_simulated_s: float = 0.0
    #: the robot profile, said when not the default (``runtime.summary.profile_shown``: "" for
    #: create2); ``eval --json`` has it in its conditions
    profile: str = ""
    #: the robot's own falls to Passive summed over the episodes, by cause, the commonest
    #: first (:attr:`EpisodeResult.falls`), the charger's among them; how many episodes had
    #: one or more, and by cause in the same order
    falls: tuple[tuple[str, int], ...] = ()
    episodes_with_falls: int = 0
    episodes_with_falls_by_cause: tuple[tuple[str, int], ...] = ()
    #: how many episodes fell on a hazard (a cliff, a wheel drop: any cause but the
    #: charger's, :func:`~roomba_bt.runtime.summary.hazard_falls`). A dock mission that
    #: docks in Safe falls to Passive on the charger in every episode: that is its success,
    #: and counted with the cliffs it read as a hazard met in every episode
    episodes_with_hazard_falls: int = 0
    #: whether the wall-clock and CPU times are said (:meth:`lines`, :meth:`to_dict`): other
    #: on every run of the same episodes; ``eval --reproducible`` leaves them out, and the
    #: slow ticks' warning (:meth:`slow_said`) with them: both whether a tick is found slow
    #: and its milliseconds are the host's, not the virtual clock's (the caller says it on
    #: stderr instead)
    timings: bool = True
    #: each key a behaviour wrote that the mission does not declare, who wrote it first and
    #: where, and the episodes it was written in (:attr:`EpisodeResult.undeclared`): said
    #: once, where each episode's run would have warned of it
    undeclared: tuple[tuple[str, str, int], ...] = ()
    #: of those keys, each that may be a misspelling of a declared key, with that key
    #: (:attr:`EpisodeResult.undeclared_like`): the warning's `` (did you mean ...?)``
    undeclared_like: tuple[tuple[str, str], ...] = ()
    #: each action of the user's own code whose commands the mode guard refused, its class
    #: and where, and the episodes (:attr:`EpisodeResult.refused_actions`): said once, with
    #: the fix ``run`` tells on stderr
    refused_actions: tuple[tuple[str, str, int], ...] = ()
    #: each behaviour an episode's slowest tick was in where behaviours held the ticks on the
    #: wall clock (:attr:`EpisodeResult.slowest_in`), the slowest of those ticks (host
    #: seconds) and the episodes: said once, as ``run`` names its slowest tick's behaviour
    slow_ticks: tuple[tuple[str, float, int], ...] = ()
    #: the longest time (s) an episode spent off the dock without progress, brushes on or
    #: off (:attr:`EpisodeResult.longest_trapped_s`), and how many spent TRAPPED_S or more
    longest_trapped_s: float = 0.0
    trapped: int = 0
    #: the robot's sensor frames the episodes lost on the line, summed
    #: (:attr:`EpisodeResult.frames_lost`), and in how many episodes: said when there were
    #: any (the line's faults, ``eval --byte-drop-rate``...), which only the records held
    frames_lost: int = 0
    episodes_with_frames_lost: int = 0
    #: how the successful episodes ended in the mission's own words (:attr:`EpisodeResult.said`),
    #: the commonest first: a patrol's "laps done" and "docked on a low battery" are both a
    #: success, and the rate alone mixed them
    endings: tuple[tuple[str, int], ...] = ()
    #: per ending of :attr:`endings`, in its order, the odometry distance (m) its episodes
    #: drove: the least, the median and the most. A patrol's lap round the apartment's
    #: kitchen table (6-8 m) and one round the flat (25 m or more) both read "patrol done
    #: (laps: 1)": ``--json`` could not tell them apart without the records
    ending_distances: tuple[tuple[float, float, float], ...] = ()

    @property
    def rate(self) -> float:
        return self.successes / self.runs if self.runs else 0.0

    def lines(self) -> list[str]:
        """The report's lines, each one line: a mission's file name and the names its failure
        reasons quote are escaped (``"\\n[ok] fake"`` made a line of its own)."""
        head = [
            f"mission      {self.mission} in {self.world}",
            *([f"profile      {self.profile}"] if self.profile else []),
        ]
        if not self.runs:  # interrupted before its first episode finished: no rate at all
            head.append("success      no episode finished")
            return [escaped(line, ANY_CONTROL) for line in head]
        lo, hi = self.interval
        med = "n/a" if self.median_time_s is None else f"{self.median_time_s:.1f} s"
        p90 = "n/a" if self.p90_time_s is None else f"{self.p90_time_s:.1f} s"
        out = [
            *head,
            f"success      {self.successes}/{self.runs} = {100 * self.rate:.1f} % "
            f"(95 % Wilson interval {100 * lo:.1f} %..{100 * hi:.1f} %)",
            f"time         median {med}, p90 {p90} (successful episodes, mission time)",
            f"bumps        {self.mean_bumps:.1f} per episode (bumper onsets in the simulator)",
            f"docked       {self.docked} of {self.runs} episodes ended on the dock's contacts",
            f"trapped      {self.trapped} of {self.runs} episodes spent {TRAPPED_S:.0f} s off the "
            f"dock without progress (no new floor, no move of {TRAPPED_RADIUS_MM / 1000:g} m; "
            f"brushes on or off; longest {self.longest_trapped_s:.0f} s)",
            *([f"falls        {self.falls_text()}"] if self.hazard_falls else []),
            *([f"charger      {self.charger_text()}"] if self.charger_arrivals else []),
            *([f"frames       {self.frames_text()}"] if self.frames_lost else []),
            f"simulated    {self.simulated_s:.0f} s of mission time"
            + (
                f"{self._cpu_said()}; {self.wall_s:.1f} s of wall-clock time summed over the "
                "episodes"
                if self.timings
                else ""
            ),
        ]
        slow = self.slow_said() if self.timings else []  # measured on the host: see timings
        said = (*self.undeclared_said(), *self.refused_said(), *slow)
        out += [f"warning      {line}" for line in said]
        if self.endings:
            out.append("successes    by what the mission said last")
            out += [
                f"  {count:4d}  {said or '(nothing said)'}  ({_driven(*distances)})"
                for (said, count), distances in zip(self.endings, self.ending_distances,
                                                    strict=True)
            ]  # fmt: skip
        if self.failures:
            out.append("failures")
            out += [f"  {count:4d}  {reason}" for reason, count in self.failures]
        return [escaped(line, ANY_CONTROL) for line in out]

    def __str__(self) -> str:
        return "\n".join(self.lines())

    @property
    def speed(self) -> float | None:
        """Mission seconds per CPU second, over the episodes that measured their CPU time
        (both sides of the ratio of the same episodes); None when none did."""
        if self.cpu_s <= 0:
            return None
        return (self.simulated_s - self.untimed_simulated_s) / self.cpu_s

    def _cpu_said(self) -> str:
        """The CPU time and the speed it gives; none measured when every episode HUNG or
        DIED (they record no CPU time: "0x real time" said the simulator stood still). The
        episodes without CPU time are said apart, their mission time left out of the speed."""
        speed = self.speed
        if speed is None:
            return ", CPU time not measured (HUNG and DIED episodes record none)"
        said = f" in {self.cpu_s:.1f} s of CPU time ({speed:.0f}x real time per CPU second"
        if self.untimed:
            measured = self.runs - self.untimed
            said += (f", over the {measured} episode(s) that measured it: {self.untimed} "
                     "DIED, HUNG or read back without CPU time left out")  # fmt: skip
        return said + ")"

    def undeclared_said(self) -> list[str]:
        """The undeclared keys written, each as ``run`` warns of it, and in how many of the
        episodes: ``write_key('secret') by 'probe' at lab.py:10: blackboard key 'secret' is
        not declared by the mission, in 3 of 20 episodes; ...``."""
        meant = dict(self.undeclared_like)
        return [
            undeclared_said(
                key, where, _hint(key, meant), episodes=f", in {episodes} of {self.runs} episodes"
            )
            for key, where, episodes in self.undeclared
        ]

    def refused_said(self) -> list[str]:
        """Each action of the user's own code whose commands the mode guard refused, in how
        many of the episodes, and what its author does about it: ``the mode guard refused
        commands of passive_drive (PassiveDrive (lab.py:7)), your code, in 3 of 20 episodes:
        an action that drives checks self.snapshot.mode ...`` (``run``'s stderr says it)."""
        return [
            f"the mode guard refused commands of {name} ({where}), your code, in {episodes} of "
            f"{self.runs} episodes: {YOUR_ACTION_FIX}"
            for name, where, episodes in self.refused_actions
        ]

    def slow_said(self) -> list[str]:
        """Each behaviour that held an episode's slowest tick on the wall clock, once, with
        the episodes and why it matters: ``slowest tick 217.36 ms in sleepy (Sleepy.update
        at x.py:11), in 3 of 20 episodes: ...``. A plugin that slept in its ``update`` was
        said by nothing but ``--wall-limit``'s HUNG; ``run`` names it on its ticks line."""
        return [
            f"slowest tick {slowest * 1000:.2f} ms in {where}, in {episodes} of {self.runs} "
            "episodes: a behaviour held the ticks on the wall clock (time.sleep, I/O); an "
            "episode ticks the tree on the virtual clock as fast as it allows, so such a wait "
            "slows every episode it is in (they are not hung)"
            for where, slowest, episodes in self.slow_ticks
        ]

    @property
    def hazard_falls(self) -> dict[str, int]:
        """The falls on a hazard by cause, the commonest first: every cause but the
        charger's (``run``'s ``falls`` line says these alone too)."""
        return hazard_falls(dict(self.falls))

    @property
    def charger_arrivals(self) -> int:
        """The falls to Passive on a powered charger: each the end of a docking in Safe (the
        OI's own drop), counted apart from the hazards."""
        return dict(self.falls).get("charger", 0)

    @property
    def episodes_with_charger_arrivals(self) -> int:
        return dict(self.episodes_with_falls_by_cause).get("charger", 0)

    def falls_text(self) -> str:
        """The episodes' falls to Passive on a hazard in the run summary's words, and how
        many episodes they were in, by cause when there are several: ``the robot fell to
        Passive by itself 13 times (cliff 12, wheel drop 1) in 4 of 200 episodes (cliff in
        4, wheel drop in 1)``; with one cause, its count of episodes is the one said before.
        The charger's are not among them (:meth:`charger_text`), as in ``run``'s summary."""
        hazards = self.hazard_falls
        said = f"{falls_said(hazards)} in {self.episodes_with_hazard_falls} of {self.runs} episodes"
        by_cause = [(c, n) for c, n in self.episodes_with_falls_by_cause if c in hazards]
        if len(by_cause) < 2:
            return said
        return f"{said} ({', '.join(f'{cause} in {episodes}' for cause, episodes in by_cause)})"

    def charger_text(self) -> str:
        """The dockings, the falls to Passive on the charger, and the episodes they were in:
        ``docked 200 times in 200 of 200 episodes (...)``, said as what they are."""
        docked = self.charger_arrivals
        times = "once" if docked == 1 else f"{docked} times"
        return (
            f"docked {times} in {self.episodes_with_charger_arrivals} of {self.runs} episodes "
            "(the robot drops to Passive by itself on the charger: how docking in Safe ends, "
            "not a hazard)"
        )

    def _distances_by_ending(self) -> dict[str, dict[str, float]]:
        """Each ending's distances (m), as ``--json`` names them."""
        pairs = zip(self.endings, self.ending_distances, strict=True)
        return {
            said: {"min": lo, "median": median, "max": hi} for (said, _), (lo, median, hi) in pairs
        }

    def frames_text(self) -> str:
        """``37 lost in 4 of 4 episodes (9.2 per episode; the robot's 15 ms sensor frames
        the run never read)``."""
        return (
            f"{self.frames_lost} lost in {self.episodes_with_frames_lost} of {self.runs} "
            f"episodes ({self.frames_lost / self.runs:.1f} per episode; the robot's 15 ms "
            "sensor frames the run never read)"
        )

    def to_dict(self) -> dict[str, object]:
        """The summary for scripts (``eval --json``): rates as fractions, times in seconds;
        ``rate`` and ``interval`` null when no episode finished."""
        meant = dict(self.undeclared_like)  # an undeclared key's did-you-mean
        return {
            "mission": self.mission,
            "world": self.world,
            "runs": self.runs,
            "successes": self.successes,
            "rate": self.rate if self.runs else None,
            "interval": list(self.interval) if self.runs else None,
            "median_time": self.median_time_s,
            "p90_time": self.p90_time_s,
            "mean_bumps": self.mean_bumps,
            "docked": self.docked,
            "trapped": self.trapped,
            "longest_trapped": self.longest_trapped_s,
            "failures": {reason: count for reason, count in self.failures},
            "success_endings": {said: count for said, count in self.endings},
            "success_distances": self._distances_by_ending(),
            "falls": dict(self.falls),
            "episodes_with_falls": self.episodes_with_falls,
            "episodes_with_falls_by_cause": dict(self.episodes_with_falls_by_cause),
            "hazard_falls": self.hazard_falls,
            "episodes_with_hazard_falls": self.episodes_with_hazard_falls,
            "charger_arrivals": self.charger_arrivals,
            "episodes_with_charger_arrivals": self.episodes_with_charger_arrivals,
            "frames_lost": self.frames_lost,
            "episodes_with_frames_lost": self.episodes_with_frames_lost,
            "wall_time": self.wall_s if self.timings else None,
            "cpu_time": self.cpu_s if self.timings else None,
            # mission time per CPU second of the episodes that measured it (not
            # mission_time / cpu_time: that counts the untimed episodes' mission time)
            "real_time_factor": self.speed if self.timings else None,
            "episodes_without_cpu_time": self.untimed if self.timings else None,
            "mission_time": self.simulated_s,
            "undeclared_keys": [
                {
                    "key": key,
                    "written": where.strip(),
                    "episodes": episodes,
                    "did_you_mean": meant.get(key),
                }
                for key, where, episodes in self.undeclared
            ],
            "refused_actions": [
                {"action": name, "where": where, "episodes": episodes}
                for name, where, episodes in self.refused_actions
            ],
            "slow_ticks": [
                {"in": where, "slowest_tick": slowest, "episodes": episodes}
                for where, slowest, episodes in self.slow_ticks
            ]
            if self.timings
            else None,
        }


def tidy(value: object, digits: int = 10) -> object:
    """``value`` with every float cut to ``digits`` significant digits, for JSON a person
    reads: a sum of 15 ms ticks is 27.885 s, not 27.884999999999998 (binary noise in the
    16th digit). Ten digits keep every figure's meaning (a tick is the 5th)."""
    if isinstance(value, float):
        return float(f"{value:.{digits}g}") if math.isfinite(value) else value
    if isinstance(value, dict):
        return {k: tidy(v, digits) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [tidy(v, digits) for v in value]
    return value


def _with_episodes(
    per_episode: Iterable[tuple[tuple[str, str], ...]],
) -> tuple[tuple[str, str, int], ...]:
    """Each name of the episodes' ``(name, where)`` pairs (an undeclared key and its writer,
    a refused action and its class), once, in the order first met: where the first episode
    that had it says, and the episodes it is in."""
    found: dict[str, tuple[str, int]] = {}
    for pairs in per_episode:
        for name, where in pairs:
            first, episodes = found.get(name, (where, 0))
            found[name] = (first, episodes + 1)
    return tuple((name, where, n) for name, (where, n) in found.items())


def _first_meant(per_episode: Iterable[tuple[tuple[str, str], ...]]) -> tuple[tuple[str, str], ...]:
    """Each undeclared key's declared key it may be, as the first episode that wrote it
    says (every episode runs the same mission, so they agree)."""
    meant: dict[str, str] = {}
    for pairs in per_episode:
        for key, like in pairs:
            meant.setdefault(key, like)
    return tuple(meant.items())


def _hint(key: str, meant: dict[str, str]) -> str:
    """`` (did you mean 'dirt_level'?)`` for ``key`` as ``run``'s summary says it
    (:func:`~roomba_bt.behaviours.units.closest`, a look-alike letter named too), "" when no
    declared key is like it."""
    like = meant.get(key)
    return closest(key, [like]) if like else ""


def summarize(
    mission: str, world: str, results: Sequence[EpisodeResult], profile: str = ""
) -> Summary:
    """Aggregate episodes into a :class:`Summary` (``profile``: as the text names it, "" for
    the default)."""
    runs = len(results)
    ok = [r for r in results if r.succeeded]
    times = [r.time_s for r in ok]
    groups = Counter(reason_group(r) for r in results if not r.succeeded)
    falls: Counter[str] = Counter()
    episodes_by_cause: Counter[str] = Counter()
    for r in results:
        falls.update(dict(r.falls))
        episodes_by_cause.update(cause for cause, _ in r.falls)
    in_order = falls_in_order(falls)
    slow: dict[str, tuple[float, int]] = {}  # the slowest tick in it, the episodes
    for r in results:
        if r.slowest_in:
            slowest, episodes = slow.get(r.slowest_in, (0.0, 0))
            slow[r.slowest_in] = (max(slowest, r.slowest_tick_s), episodes + 1)
    endings = success_endings(ok)
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
        cpu_s=sum(r.cpu_s for r in results),
        untimed=sum(1 for r in results if r.cpu_s <= 0),
        untimed_simulated_s=sum(r.time_s for r in results if r.cpu_s <= 0),
        profile=profile,
        falls=in_order,
        episodes_with_falls=sum(1 for r in results if r.falls),
        episodes_with_falls_by_cause=tuple((c, episodes_by_cause[c]) for c, _ in in_order),
        episodes_with_hazard_falls=sum(1 for r in results if hazard_falls(dict(r.falls))),
        undeclared=_with_episodes(r.undeclared for r in results),
        undeclared_like=_first_meant(r.undeclared_like for r in results),
        refused_actions=_with_episodes(r.refused_actions for r in results),
        slow_ticks=tuple((where, slowest, n) for where, (slowest, n) in slow.items()),
        longest_trapped_s=max((r.longest_trapped_s for r in results), default=0.0),
        trapped=sum(1 for r in results if r.longest_trapped_s >= TRAPPED_S),
        frames_lost=sum(r.frames_lost for r in results),
        episodes_with_frames_lost=sum(1 for r in results if r.frames_lost),
        endings=endings,
        ending_distances=tuple(
            _distances([r.distance_m for r in ok if r.said == said]) for said, _ in endings
        ),
    )


def _distances(driven: Sequence[float]) -> tuple[float, float, float]:
    """The least, the median and the most of ``driven`` (m; one at least)."""
    return min(driven), percentile(driven, 50) or 0.0, max(driven)


def _driven(lo: float, median: float, hi: float) -> str:
    """``6.4..48.4 m driven, median 7.8 m``; ``7.8 m driven`` when all drove as far."""
    if f"{lo:.1f}" == f"{hi:.1f}":
        return f"{lo:.1f} m driven"
    return f"{lo:.1f}..{hi:.1f} m driven, median {median:.1f} m"


def success_endings(successes: Sequence[EpisodeResult]) -> tuple[tuple[str, int], ...]:
    """What the successful episodes' missions said last, counted, the commonest first; none
    when no mission said anything (a mission without a ``log`` leaf: nothing to tell apart)."""
    said = Counter(r.said for r in successes)
    if not any(said):
        return ()
    return tuple(sorted(said.items(), key=lambda kv: (-kv[1], kv[0])))


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """The two-sided exact McNemar p-value: under "the change makes no difference" each
    discordant pair (success with one variant only) is a fair coin, so it is the binomial
    test of ``only_a`` out of ``only_a + only_b`` at 1/2 (1.0 when there is no discordant
    pair). Exact at any size (integer sums, one rounding at the end), hence no normal or
    chi-square approximation (those are poor for the few discordant pairs a 98 % mission
    leaves)."""
    n = only_a + only_b
    if n == 0:
        return 1.0
    tail = sum(_binomial_coefficients(n, min(only_a, only_b) + 1))
    # int / int divides exactly and rounds once: no float(2**n), which overflows past 1023
    p: float = 2 * tail / 2**n
    return min(1.0, p)


def _binomial_coefficients(n: int, count: int) -> Iterator[int]:
    """``comb(n, 0), comb(n, 1), ...``: the first ``count`` of them, each from the last
    (one multiplication and one exact division; ``math.comb`` each time is quadratic)."""
    c = 1
    for i in range(min(count, n + 1)):
        yield c
        c = c * (n - i) // (i + 1)


def median_interval(values: Sequence[float]) -> tuple[float, float] | None:
    """A distribution-free interval for the median (at least 95 % coverage): the order
    statistics ``(k, n + 1 - k)`` with ``k`` the largest rank whose binomial tail
    ``2 P(Bin(n, 1/2) <= k - 1)`` stays within 5 %. None when fewer than 6 values (no such
    ``k``: even the extremes cover the median with less than 95 %). Compared in integers
    (``2 P <= 0.05`` as ``40 * cumulative <= 2**n``): exact at any ``n``."""
    n = len(values)
    ordered = sorted(values)
    k = 0
    cumulative = 0  # P(Bin(n, 1/2) <= rank - 1) * 2**n
    bound = 2**n // 40  # 40 * cumulative > 2**n exactly when cumulative > bound (integers)
    for rank, coefficient in enumerate(_binomial_coefficients(n, n), start=1):
        cumulative += coefficient
        if cumulative > bound:
            break
        k = rank
    if k == 0:
        return None
    return (ordered[k - 1], ordered[n - k])


@dataclass(frozen=True)
class Comparison:
    """Two variants on the same seeds and start poses, episode by episode."""

    a: str
    b: str
    pairs: int
    both: int
    only_a: int
    only_b: int
    neither: int
    p_value: float
    #: B's time minus A's over the episodes both succeeded: median and its 95 % interval
    median_difference_s: float | None
    difference_interval: tuple[float, float] | None
    #: B's floor cleaned minus A's (fractions 0..1, success or not: a cleaning mission that
    #: times out still cleaned), over the pairs where both ran their brushes
    coverage_pairs: int = 0
    median_coverage_difference: float | None = None
    coverage_difference_interval: tuple[float, float] | None = None
    #: the evaluation was interrupted: the pairs are the seeds both variants finished
    interrupted: bool = False

    def lines(self) -> list[str]:
        med = self.median_difference_s
        if med is None:
            time = "no episode succeeded with both"
        else:
            ci = self.difference_interval
            within = (
                f"95 % interval {ci[0]:+.1f}..{ci[1]:+.1f} s" if ci else "too few for an interval"
            )
            both = "the episode" if self.both == 1 else f"the {self.both} episodes"
            time = f"median {med:+.1f} s ({within}) over {both} both succeeded"
        return [
            f"A/B          A = {self.a}",
            f"             B = {self.b}",
            f"paired       {self.pairs} episode{'s' if self.pairs != 1 else ''}, same seeds "
            "and start poses"
            + (" (interrupted: the seeds both variants finished)" if self.interrupted else ""),
            f"success      both {self.both}, only A {self.only_a}, only B {self.only_b}, "
            f"neither {self.neither}; exact McNemar p = {self.p_value:.3g}",
            f"time B - A   {time}",
            *self._coverage_lines(),
        ]

    def _coverage_lines(self) -> list[str]:
        med = self.median_coverage_difference
        if med is None:
            return []
        ci = self.coverage_difference_interval
        within = (
            f"95 % interval {100 * ci[0]:+.1f}..{100 * ci[1]:+.1f}"
            if ci
            else "too few for an interval"
        )
        over = "the episode" if self.coverage_pairs == 1 else f"the {self.coverage_pairs} episodes"
        return [
            f"coverage B-A median {100 * med:+.1f} points ({within}) over {over} both cleaned in"
        ]

    def __str__(self) -> str:
        return "\n".join(self.lines())

    def to_dict(self) -> dict[str, object]:
        return {
            "a": self.a,
            "b": self.b,
            "pairs": self.pairs,
            "both": self.both,
            "only_a": self.only_a,
            "only_b": self.only_b,
            "neither": self.neither,
            "mcnemar_p": self.p_value,
            "median_time_difference": self.median_difference_s,
            "time_difference_interval": (
                None if self.difference_interval is None else list(self.difference_interval)
            ),
            "interrupted": self.interrupted,
            "coverage_pairs": self.coverage_pairs,
            "median_coverage_difference": self.median_coverage_difference,
            "coverage_difference_interval": (
                None
                if self.coverage_difference_interval is None
                else list(self.coverage_difference_interval)
            ),
        }


def compare_finished(
    a: str, b: str, results_a: Sequence[EpisodeResult], results_b: Sequence[EpisodeResult]
) -> Comparison | None:
    """:func:`compare` over the seeds both variants finished (an interrupted evaluation);
    None when there is no such seed."""
    common = {r.seed for r in results_a} & {r.seed for r in results_b}
    if not common:
        return None
    return compare(
        a, b, [r for r in results_a if r.seed in common], [r for r in results_b if r.seed in common]
    )


def compare(
    a: str, b: str, results_a: Sequence[EpisodeResult], results_b: Sequence[EpisodeResult]
) -> Comparison:
    """Pair the episodes by seed (both lists from the same seeds); ValueError otherwise."""
    by_seed = {r.seed: r for r in results_b}
    if sorted(by_seed) != sorted(r.seed for r in results_a):
        raise ValueError("A and B must be run on the same seeds")
    pairs = [(ra, by_seed[ra.seed]) for ra in results_a]
    both = [(ra, rb) for ra, rb in pairs if ra.succeeded and rb.succeeded]
    only_a = sum(1 for ra, rb in pairs if ra.succeeded and not rb.succeeded)
    only_b = sum(1 for ra, rb in pairs if rb.succeeded and not ra.succeeded)
    differences = [rb.time_s - ra.time_s for ra, rb in both]
    cleaned = [
        rb.coverage.final - ra.coverage.final
        for ra, rb in pairs
        if ra.coverage is not None and rb.coverage is not None
    ]
    return Comparison(
        a=a,
        b=b,
        pairs=len(pairs),
        both=len(both),
        only_a=only_a,
        only_b=only_b,
        neither=len(pairs) - len(both) - only_a - only_b,
        p_value=mcnemar_exact(only_a, only_b),
        median_difference_s=percentile(differences, 50),
        difference_interval=median_interval(differences),
        coverage_pairs=len(cleaned),
        median_coverage_difference=percentile(cleaned, 50),
        coverage_difference_interval=median_interval(cleaned),
    )
