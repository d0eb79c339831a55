"""Routine benchmarks (issue 7): how fast the simulator + a mission run on the virtual clock,
and how ``roomba-bt eval`` scales from 1 to 2 worker processes.

Every figure is measured in this process, beside its baseline:

* virtual-clock speed: seconds of mission time per second of CPU for whole episodes (mission
  compiled, connection, runtime, simulator), one process: the dock mission from 8 seeded
  poses near the dock, and bump-and-turn for 60 s in the corridor. Baseline: the simulator
  stepping alone for the same number of 15 ms steps, so the ratio shows what the mission and
  the runtime cost on top of the physics. Target: >= 100x real time.
* eval scaling: 48 dock episodes with ``jobs=1`` and ``jobs=2``; wall-time ratio. Target:
  >= 1.8x on 2 cores (the results are identical, which is tested, not benchmarked). Dock
  episodes last 10 s to 2 min, so with only a few the longest bounds the ratio; 48 is the
  size of a small evaluation (50-200). Also printed: the best two in-order workers could
  do with those episodes, and how much slower each episode ran beside the other worker.
* eval on Dask: the same 48 episodes on a local Dask cluster of 1 and of 2 worker processes
  (each cluster started and its workers' imports warmed before the clock starts: what a
  long-running cluster costs per evaluation). Target: >= 1.8x.
"""

from __future__ import annotations

import time
from pathlib import Path

from roomba_bt.evaluate import episode_specs, run_episodes
from roomba_bt.evaluate.report import SPEED_EPISODES, measure_scaling, two_worker_makespan
from roomba_bt.sim import Simulator, load_world

ROOT = Path(__file__).resolve().parents[1]
DOCK = str(ROOT / "missions" / "dock.yaml")
BUMP = str(ROOT / "missions" / "bump-and-turn.yaml")


def _speed(label: str, mission: str, world: str, **fields: object) -> float:
    specs = episode_specs(mission, world=world, runs=8, seed=100, **fields)
    started = time.perf_counter()
    results = run_episodes(specs, jobs=1)
    wall = time.perf_counter() - started
    simulated = sum(r.time_s for r in results)
    ticks = sum(r.ticks for r in results)
    sim = Simulator(load_world(world))
    started = time.perf_counter()
    for _ in range(ticks):
        sim.step()
    bare = time.perf_counter() - started
    print(
        f"   {label:34s} {simulated:7.0f} s mission time in {wall:5.2f} s = "
        f"{simulated / wall:5.0f}x real time (simulator alone: {simulated / bare:5.0f}x; "
        f"mission + runtime cost {wall / bare:4.1f}x the physics)"
    )
    return simulated / wall


def main() -> None:
    print("virtual-clock speed, one process (target >= 100x real time)")
    _speed("dock, empty room, 8 poses", DOCK, "empty-room", within_m=1.5)
    _speed("bump-and-turn, corridor, 8 x 60 s", BUMP, "corridor", timeout_s=90.0)
    specs = episode_specs(DOCK, world="empty-room", runs=SPEED_EPISODES, seed=200, within_m=1.5)
    wall_one, wall_two, one, two = measure_scaling(specs)
    same = [r.time_s for r in one] == [r.time_s for r in two]
    alone = [r.wall_s for r in one]
    bound = sum(alone) / two_worker_makespan(alone)
    beside = sum(r.wall_s for r in two) / sum(alone)
    print(
        f"eval scaling: {SPEED_EPISODES} dock episodes, best of 3, jobs=1 {wall_one:.2f} s, "
        f"jobs=2 {wall_two:.2f} s = {wall_one / wall_two:.2f}x (target >= 1.8x; in-order "
        f"bound {bound:.2f}x; an episode beside the other worker took {beside:.2f}x its time "
        f"alone; identical results: {same})"
    )
    dask_scaling()


def dask_scaling(repeats: int = 2) -> None:
    """Wall seconds of the 48 episodes on 1 and 2 Dask workers, each the best of ``repeats``."""
    from roomba_bt.evaluate.cluster import (
        ClusterUnavailableError,
        dask_client,
        run_on_client,
        warm_up,
    )

    specs = episode_specs(DOCK, world="empty-room", runs=SPEED_EPISODES, seed=200, within_m=1.5)
    walls: dict[int, float] = {}
    retried = 0
    try:
        for workers in (1, 2):
            with dask_client(None, workers) as client:
                warm_up(client)
                best = float("inf")
                for _ in range(repeats):
                    started = time.perf_counter()
                    results, again, _ = run_on_client(client, specs)
                    best = min(best, time.perf_counter() - started)
                    retried += again
                    assert all(r is not None for r in results)
                walls[workers] = best
    except ClusterUnavailableError as exc:
        print(f"eval on Dask: skipped ({exc})")
        return
    print(
        f"eval on Dask: {SPEED_EPISODES} dock episodes, best of {repeats}, 1 worker "
        f"{walls[1]:.2f} s, 2 workers {walls[2]:.2f} s = {walls[1] / walls[2]:.2f}x "
        f"(target >= 1.8x; {retried} retried)"
    )


if __name__ == "__main__":
    main()
