"""``python -m bench.bench_runtime ticks``: the cost of ``stack.ticks()`` against
``stack.run()`` compares the same run made both ways (docs/performance.md quotes it)."""

from __future__ import annotations

from bench.bench_runtime import ticks_against_run


def test_ticks_and_run_are_measured_over_the_same_ticks() -> None:
    """Both ways run the same minute of bump-and-turn (the bench refuses two tick counts),
    and each tick costs some CPU: a ratio of two measures of the same work."""
    per_run, per_ticks, ticks = ticks_against_run(runs=1)
    assert ticks > 3000  # a minute of mission time at 15 ms a tick
    assert per_run > 0 and per_ticks > 0
