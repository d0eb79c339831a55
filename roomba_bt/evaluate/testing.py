"""A pytest helper for mission authors: "this mission succeeds in 95 % of 50 runs".

::

    from roomba_bt.evaluate.testing import assert_success_rate

    def test_dock_in_the_apartment() -> None:
        assert_success_rate("missions/dock.yaml", world="apartment", runs=50,
                            within_s=600, rate=0.90)

Each run is a seeded episode on the simulator's virtual clock (seeds ``seed`` ..
``seed + runs - 1``); an episode counts as a success when the mission succeeds within
``within_s`` seconds of mission time. The assertion compares the observed rate with
``rate`` and, when it fails, prints the whole report (interval, times, failure reasons).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from roomba_bt.evaluate import episode_specs
from roomba_bt.evaluate.parallel import run_episodes
from roomba_bt.evaluate.stats import Summary, summarize


def assert_success_rate(
    mission: str,
    *,
    world: str = "empty-room",
    runs: int = 50,
    within_s: float = 180.0,
    rate: float = 0.95,
    seed: int = 0,
    jobs: int = 1,
    params: Mapping[str, str] | None = None,
    **spec: Any,
) -> Summary:
    """Run the episodes; raise AssertionError (with the report) if fewer than ``rate`` of
    them succeed within ``within_s``. Returns the summary for further checks."""
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"rate must be a fraction in 0..1, got {rate}")
    specs = episode_specs(
        mission,
        world=world,
        runs=runs,
        seed=seed,
        timeout_s=within_s,
        params=tuple(sorted((params or {}).items())),
        **spec,
    )
    results = run_episodes(specs, jobs=jobs)
    summary = summarize(mission, world, results)
    if summary.rate < rate:
        raise AssertionError(
            f"{mission} succeeded in {summary.successes} of {runs} runs within {within_s:g} s "
            f"({100 * summary.rate:.1f} %), wanted at least {100 * rate:.1f} %\n{summary}"
        )
    return summary
