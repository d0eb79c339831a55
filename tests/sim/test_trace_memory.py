"""The trajectory is kept only when asked (a plot, an evaluation's record): without it a long
run's memory stays flat. A cheap stand-in for the 4-robot-hour figure in docs/reliability.md."""

from __future__ import annotations

import tracemalloc

from roomba_bt.oi import commands as C
from roomba_bt.sim import Simulator

from .helpers import BOX, world

IDS = [7, 9, 10, 11, 12, 35, 43, 44]


def growth_bytes(trace: bool, steps: int = 4000) -> tuple[int, Simulator]:
    """Bytes still allocated after ``steps`` more 15 ms steps of a robot driving in circles
    with a stream on, after a warm-up (its caches, its first frames) the same length."""
    sim = Simulator(world(BOX), seed=0, trace=trace)
    sim.receive(C.start().data + C.safe().data + C.stream(IDS).data + C.drive(200, 400).data)
    for _ in range(steps):
        sim.step()
        sim.read()
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for _ in range(steps):
            sim.step()
            sim.read()
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    grown = sum(stat.size_diff for stat in after.compare_to(before, "filename"))
    return grown, sim


def test_without_a_trace_a_minute_of_driving_allocates_nothing_that_stays() -> None:
    grown, sim = growth_bytes(trace=False)
    assert len(sim.trace) == 1  # the start only
    assert grown < 20_000, f"{grown} bytes kept over 60 s of driving"


def test_with_a_trace_the_same_minute_keeps_its_points() -> None:
    grown, sim = growth_bytes(trace=True)
    assert len(sim.trace) > 1900  # a point every 4th step of 2 x 4000
    assert grown > 60_000  # what the test above would see if the trace were kept
