"""``make icount``: instructions per simulator step and per mission tick, by callgrind.

The development machine's speed moves by up to 2x within an hour (its host's load), so a
time measured now and one measured an hour ago do not compare. The number of instructions
the CPU executes for the same work does not move: ``valgrind --tool=callgrind`` counts them,
the same count whatever else the machine is doing. Each figure is the difference of two runs
in fresh interpreters, with and without the work, so start-up and imports cancel out:

* simulator cases of ``bench/bench_sim.py``: (count for N steps - count for 0 steps) / N;
* whole episodes of a shipped mission (``roomba_bt.evaluate``, simulator included):
  (count for the episodes - count for none) / ticks.

Slow (valgrind runs Python about 50x slower): 1 to 3 minutes on 2 cores. Not part of
``make bench``; the figures go into ``docs/performance.md`` beside the timings.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STEPS = 2000
SIM_CASES = ("open", "g100", "mission", "client")
#: (mission, world, episodes, eval fields): seeds from 100, as in bench_routines
EPISODES = (
    ("dock.yaml", "empty-room", 3, {"within_m": 1.5}),
    ("bump-and-turn.yaml", "corridor", 2, {"timeout_s": 90.0}),
)
EPISODES_BY_MISSION = {entry[0]: entry for entry in EPISODES}
_COLLECTED = re.compile(r"Collected : (\d+)")


def _child_sim(case: str, steps: int) -> None:
    """The work counted: ``steps`` steps of one bench_sim case (the robot built either way)."""
    import bench.bench_sim as sim_bench

    sim_bench.STEPS = steps
    prepare = {
        "open": sim_bench._physics_only([100], open_floor=True),
        "g100": sim_bench._physics_only([100]),
        "mission": sim_bench._physics_only(sim_bench.MISSION_PACKETS),
        "client": sim_bench._with_client(),
    }[case]
    run = prepare()
    if steps:
        run()


def _child_episodes(mission: str, world: str, runs: int) -> None:
    from roomba_bt.evaluate import episode_specs
    from roomba_bt.evaluate.episode import run_episode

    fields = dict(EPISODES_BY_MISSION[mission][3])
    specs = episode_specs(
        str(ROOT / "missions" / mission), world=world, runs=max(runs, 1), seed=100, **fields
    )
    ticks = sum(run_episode(spec).ticks for spec in specs[:runs])
    print(f"TICKS {ticks}")


def _count(*args: str) -> tuple[int, str]:
    """Instructions of one child run under callgrind, and what it printed."""
    done = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
         sys.executable, "-m", "bench.icount", "--child", *args],
        cwd=ROOT, capture_output=True, text=True, check=False,
        env={**os.environ, "PYTHONHASHSEED": "0"},  # string hashes vary the count otherwise
    )  # fmt: skip
    found = _COLLECTED.search(done.stderr)
    if done.returncode != 0 or found is None:
        raise RuntimeError(f"callgrind run {args} failed:\n{done.stderr[-2000:]}")
    return int(found.group(1)), done.stdout


def _sim_line(case: str) -> str:
    with_work, _ = _count("sim", case, str(STEPS))
    without, _ = _count("sim", case, "0")
    return f"   simulator, {case:<8} {(with_work - without) / STEPS:10,.0f} instructions / step"


def _episode_line(mission: str, world: str, runs: int) -> str:
    with_work, out = _count("episodes", mission, world, str(runs))
    without, _ = _count("episodes", mission, world, "0")
    found = re.search(r"TICKS (\d+)", out)
    ticks = int(found.group(1)) if found else 0
    per_tick = (with_work - without) / ticks if ticks else float("nan")
    return (
        f"   {mission} in {world}, {runs} episodes ({ticks} ticks) "
        f"{per_tick:10,.0f} instructions / tick (simulator included)"
    )


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        kind, *rest = argv[1:]
        if kind == "sim":
            _child_sim(rest[0], int(rest[1]))
        else:
            _child_episodes(rest[0], rest[1], int(rest[2]))
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed: instruction counts need valgrind --tool=callgrind")
        return 2
    with ThreadPoolExecutor(max_workers=2) as pool:  # each job runs two valgrind processes
        futures = [pool.submit(_sim_line, case) for case in SIM_CASES]
        futures += [pool.submit(_episode_line, m, w, n) for m, w, n, _ in EPISODES]
        for future in futures:
            print(future.result(), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
