"""Evaluate missions on the simulator: seeded episodes, statistics, parallel runs, plots.

``roomba-bt eval`` (:mod:`roomba_bt.cli.eval_cmd`) and the pytest helper
(:func:`roomba_bt.evaluate.testing.assert_success_rate`) are built from these parts:

* :mod:`~roomba_bt.evaluate.episode`: one mission run on the virtual clock from a seeded pose,
  measured on the simulator (:class:`EpisodeSpec` -> :class:`EpisodeResult`);
* :mod:`~roomba_bt.evaluate.sources`: a mission and its includes as texts, so an episode spec
  is self-contained (no shared file system);
* :mod:`~roomba_bt.evaluate.parallel`: many episodes in worker processes, same results for
  any number of jobs; :mod:`~roomba_bt.evaluate.cluster`: the same on a Dask cluster;
* :mod:`~roomba_bt.evaluate.records`: one record per episode as JSON Lines or CSV, and back;
* :mod:`~roomba_bt.evaluate.stats`: success rate with a Wilson interval, percentiles, grouped
  failure reasons; paired A/B comparison (exact McNemar, median time difference);
* :mod:`~roomba_bt.evaluate.plot`: every trajectory on one picture (matplotlib, optional);
* :mod:`~roomba_bt.evaluate.wheels`: an episode's wheel reversals (``bench.wheel_reversals``);
* :mod:`~roomba_bt.evaluate.report`: the figures of ``docs/routines.md``, by one command.

This package sits at the top of the stack beside the CLI: it imports the runtime, the mission
compiler and the simulator; nothing below imports it.
"""

from roomba_bt.evaluate.episode import (
    EpisodeResult,
    EpisodeSpec,
    EvaluationError,
    run_episode,
)
from roomba_bt.evaluate.parallel import ProgressBar, run_episodes
from roomba_bt.evaluate.plan import EpisodePlan
from roomba_bt.evaluate.stats import Summary, percentile, summarize, wilson_interval


def episode_plan(
    mission: str,
    *,
    world: str = "empty-room",
    runs: int = 20,
    seed: int = 0,
    **fields: object,
) -> EpisodePlan:
    """``runs`` episodes with seeds ``seed``, ``seed + 1``, ...; other fields as given: each
    one's spec made as it is taken (:class:`~roomba_bt.evaluate.plan.EpisodePlan`)."""
    template = EpisodeSpec(mission, world, seed, **fields)  # type: ignore[arg-type]
    return EpisodePlan(template, range(seed, seed + runs))


def episode_specs(
    mission: str,
    *,
    world: str = "empty-room",
    runs: int = 20,
    seed: int = 0,
    **fields: object,
) -> list[EpisodeSpec]:
    """:func:`episode_plan`'s specs, made now, in a list."""
    return list(episode_plan(mission, world=world, runs=runs, seed=seed, **fields))


__all__ = [
    "EpisodePlan",
    "EpisodeResult",
    "EpisodeSpec",
    "EvaluationError",
    "ProgressBar",
    "Summary",
    "episode_plan",
    "episode_specs",
    "percentile",
    "run_episode",
    "run_episodes",
    "summarize",
    "wilson_interval",
]
