"""``make icount``: instructions per simulator step and per mission tick, by callgrind.

The development machine's speed moves by up to 2x within an hour (its host's load), so a
time measured now and one measured an hour ago do not compare. The number of instructions
the CPU executes for the same work does not move: ``valgrind --tool=callgrind`` counts them,
the same count whatever else the machine is doing. Each figure is the difference of two runs
in fresh interpreters, with and without the work, so start-up and imports cancel out:

* simulator cases of ``bench/bench_sim.py``: (count for N steps - count for 0 steps) / N;
  the replays of recorded episodes (``bench/sim_replay.py``: the simulator alone, its robot
  moving as in a dock or bump-and-turn episode): the same over the recording's steps;
* whole episodes of a shipped mission (``roomba_bt.evaluate``, simulator included):
  (count for the episodes - count for none) / ticks.

Slow (valgrind runs Python about 50x slower): 1 to 3 minutes on 2 cores. Not part of
``make bench``; the figures go into ``docs/performance.md`` beside the timings.

``python -m bench.icount --sim [case ...]``: only the simulator's cases (all, or those named).

``python -m bench.icount --against 626461e``: issue 18's mission + runtime cost per tick in
instructions, that commit's code (``git archive``: its package and missions) against this
tree's, on the same kinds of episodes (:data:`EPISODES`). Per side and episode kind, four
runs with the same set-up (specs built, world loaded, one idle simulator): nothing more; the
episodes; the idle simulator stepped as many times as the episodes ticked; the episodes cut
to their first ticks (``bench_routines.SETUP_TIMEOUT_S``). Mission + runtime per tick is
(episodes - stepping) / ticks; without the set-up it leaves out the cut episodes' count and
ticks too. Takes 5 to 10 minutes on 2 cores.

``python -m bench.icount --setup [--against COMMIT]``: what an evaluation pays that is not per
tick, per episode kind (:data:`EPISODES`): the same set-up as ``--against`` (the specs built,
the world loaded, one idle simulator), then none, one or three episodes cut to their first
ticks (``bench_routines.SETUP_TIMEOUT_S``). Each episode's set-up (mission compiled or rebuilt,
simulator, connection and handshake, tree, its first ticks) is (three - one) / 2; the first
episode's one-off cost (the behaviours imported and registered, the plugin entry points
scanned, the mission's first compile, anything else done once a process) is
(one - none) - that. Also the whole ``roomba-bt validate missions/dock.yaml`` command and the
interpreter's own start (``python -c pass``), a new user's first taste. With ``--against``,
the same for that commit's code. Takes 3 to 6 minutes a side on 2 cores.
"""

from __future__ import annotations

import compileall
import contextlib
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from importlib.metadata import entry_points
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STEPS = 2000
SIM_CASES = ("open", "g100", "mission", "client", "dock", "bump")
#: the cases that replay a recorded episode (bench/sim_replay.py), all its steps
REPLAYS = ("dock", "bump")
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
    from bench import sim_replay

    if case in REPLAYS:
        _, replay = sim_replay.prepare(case)
        if steps:
            replay()
        return
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


def _child_against(work: str, mission: str, world: str, fields_json: str, steps: str) -> None:
    """The same set-up, then ``work``: none, the episodes, ``steps`` idle steps, or the
    episodes cut short; with whichever ``roomba_bt`` the working directory holds."""
    from bench.bench_routines import SETUP_TIMEOUT_S
    from roomba_bt.evaluate import episode_specs
    from roomba_bt.evaluate.episode import run_episode
    from roomba_bt.sim import Simulator, load_world

    fields = json.loads(fields_json)
    runs = fields.pop("runs")
    specs = episode_specs(mission, world=world, runs=runs, seed=100, **fields)
    short = episode_specs(
        mission, world=world, runs=runs, seed=100, **{**fields, "timeout_s": SETUP_TIMEOUT_S}
    )
    sim = Simulator(load_world(world))
    if work == "episodes":
        print(f"TICKS {sum(run_episode(spec).ticks for spec in specs)}")
    elif work == "short":
        print(f"TICKS {sum(run_episode(spec).ticks for spec in short)}")
    elif work == "physics":
        for _ in range(int(steps)):
            sim.step()


def callgrind(module: str, *args: str, code: Path = ROOT) -> tuple[int, str]:
    """Instructions of one child run, ``python -m module --child *args`` under callgrind,
    and what it printed; ``roomba_bt`` from ``code`` (its working directory; ``bench`` from
    this tree). Every bench that counts instructions runs its children here."""
    return _counted(["-m", module, "--child", *args], code, str(ROOT))


def _command_count(args: Sequence[str], code: Path) -> int:
    """Instructions of one whole command, ``python *args`` under callgrind in ``code``
    (``roomba_bt`` from there), start-up and imports included."""
    return _counted(args, code, str(code))[0]


def _counted(args: Sequence[str], code: Path, path: str) -> tuple[int, str]:
    """``python *args`` under callgrind in ``code`` with ``PYTHONPATH`` ``path``: its
    instructions and what it printed."""
    done = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, *args],
        cwd=code, capture_output=True, text=True, check=False,
        # string hashes vary the count otherwise
        env={**os.environ, "PYTHONHASHSEED": "0", "PYTHONPATH": path},
    )  # fmt: skip
    found = _COLLECTED.search(done.stderr)
    if done.returncode != 0 or found is None:
        raise RuntimeError(f"callgrind run python {args} failed:\n{done.stderr[-2000:]}")
    return int(found.group(1)), done.stdout


def _compiled(code: Path) -> None:
    """Byte-compile ``code``'s package before counting, as pip does when it installs the
    wheel. Without the ``.pyc`` files (a fresh ``git archive``, or ``PYTHONDONTWRITEBYTECODE``
    set, as on the development machine) every child would compile the modules an episode
    imports late (the behaviours, on the first compile of a mission) from source, and count
    that as the episode's: a cost of the checkout, larger the more code it has, not of a tick.
    The same for the installed plugins' packages (the example plugin, installed editable: its
    source is imported by every process's first registry use), as pip compiles a plugin's
    wheel; found without importing them."""
    compileall.compile_dir(code / "roomba_bt", quiet=1)
    for ep in entry_points(group="roomba_bt.behaviours"):
        spec = importlib.util.find_spec(ep.module.partition(".")[0])
        for folder in (spec.submodule_search_locations or []) if spec is not None else []:
            compileall.compile_dir(folder, quiet=1)


def _count(*args: str, code: Path = ROOT) -> tuple[int, str]:
    """:func:`callgrind` of this module's child."""
    return callgrind("bench.icount", *args, code=code)


def _sim_line(case: str) -> str:
    from bench import sim_replay

    steps = sim_replay.load(case)["steps"] if case in REPLAYS else STEPS
    with_work, _ = _count("sim", case, str(steps))
    without, _ = _count("sim", case, "0")
    label = f"{case} (replay)" if case in REPLAYS else case
    return f"   simulator, {label:<13} {(with_work - without) / steps:10,.0f} instructions / step"


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


def _against_cell(code: Path, entry: tuple[str, str, int, dict[str, object]]) -> dict[str, int]:
    """One side's four counts for one episode kind, and its ticks."""
    mission, world, runs, fields = entry
    args = (str(code / "missions" / mission), world, json.dumps({**fields, "runs": runs}))
    base, _ = _count("against", "none", *args, "0", code=code)
    episodes, out = _count("against", "episodes", *args, "0", code=code)
    ticks = int(re.findall(r"TICKS (\d+)", out)[-1])
    physics, _ = _count("against", "physics", *args, str(ticks), code=code)
    short, out = _count("against", "short", *args, "0", code=code)
    short_ticks = int(re.findall(r"TICKS (\d+)", out)[-1])
    return {
        "base": base, "episodes": episodes, "physics": physics, "short": short,
        "ticks": ticks, "short_ticks": short_ticks,
    }  # fmt: skip


def against(commit: str) -> int:
    """Print the mission + runtime instructions per tick of ``commit`` and of this tree."""
    from bench.bench_routines import archived

    with archived(commit, "icount-against-") as old:
        if old is None:
            return 0
        for code in (old, ROOT):
            _compiled(code)
        cells = [
            (side, code, entry)
            for entry in EPISODES
            for side, code in ((commit, old), ("this tree", ROOT))
        ]
        with ThreadPoolExecutor(max_workers=2) as pool:
            counts = list(pool.map(lambda cell: _against_cell(cell[1], cell[2]), cells))
    print(f"mission + runtime instructions per tick (callgrind), {commit} against this tree")
    for index, (side, _, (mission, world, runs, _)) in enumerate(cells):
        found = counts[index]
        ticks = found["ticks"]
        physics = (found["physics"] - found["base"]) / ticks
        cost = (found["episodes"] - found["physics"]) / ticks
        steady = (found["episodes"] - found["short"]) / (ticks - found["short_ticks"]) - physics
        setup = (found["short"] - found["base"]) / runs
        line = (
            f"   {mission} in {world}, {runs} episodes, {side:10s} {ticks:6d} ticks: mission + "
            f"runtime {cost:9,.0f} / tick (physics alone {physics:7,.0f}); without the set-up "
            f"({setup / 1e6:5.1f} M an episode) {steady:9,.0f} / tick"
        )
        if index % 2:
            before = counts[index - 1]
            old_cost = (before["episodes"] - before["physics"]) / before["ticks"]
            line += f"; ratio to {commit}: {cost / old_cost:.3f}"
        print(line, flush=True)
    return 0


#: the whole command a user runs first, and the interpreter alone (``--setup``)
VALIDATE = ("-m", "roomba_bt.cli", "validate", "missions/dock.yaml")
BARE = ("-c", "pass")


def _setup_cell(
    code: Path, mission: str, world: str, fields: Mapping[str, object]
) -> dict[str, int]:
    """One side's counts for one episode kind: the set-up alone, one and three cut episodes."""
    counts: dict[str, int] = {}
    for runs in (0, 1, 3):
        args = (
            str(code / "missions" / mission),
            world,
            json.dumps({**fields, "runs": max(runs, 1)}),
        )
        counts[str(runs)], out = _count(
            "against", "short" if runs else "none", *args, "0", code=code
        )
        if runs:
            counts[f"ticks{runs}"] = int(re.findall(r"TICKS (\d+)", out)[-1])
    return counts


def setup(commit: str | None) -> int:
    """Print the one-off and per-episode set-up instructions of this tree (and ``commit``'s)."""
    from bench.bench_routines import archived

    with contextlib.ExitStack() as stack:
        sides: list[tuple[str, Path]] = [("this tree", ROOT)]
        if commit is not None:
            old = stack.enter_context(archived(commit, "icount-setup-"))
            if old is None:
                return 0
            sides.insert(0, (commit, old))
        for _, code in sides:
            _compiled(code)
        with ThreadPoolExecutor(max_workers=2) as pool:
            cells = {
                (side, mission): pool.submit(_setup_cell, code, mission, world, fields)
                for side, code in sides
                for mission, world, _, fields in EPISODES
            }
            commands = {
                (side, name): pool.submit(_command_count, args, code)
                for side, code in sides
                for name, args in (("validate", VALIDATE), ("bare", BARE))
            }
            print("one-off and per-episode set-up, instructions (callgrind)")
            for mission, world, _, _ in EPISODES:
                for side, _ in sides:
                    found = cells[side, mission].result()
                    per_episode = (found["3"] - found["1"]) / 2
                    one_off = found["1"] - found["0"] - per_episode
                    ticks = (found["ticks3"] - found["ticks1"]) / 2
                    print(
                        f"   {mission} in {world}, {side + ':':10s} first episode's one-off "
                        f"{one_off / 1e6:6.1f} M; each episode's set-up {per_episode / 1e6:5.1f} M "
                        f"(cut after {ticks:.0f} ticks)",
                        flush=True,
                    )
            for side, _ in sides:
                validate = commands[side, "validate"].result()
                bare = commands[side, "bare"].result()
                print(
                    f"   {' '.join(VALIDATE[1:])}, {side + ':':10s} {validate / 1e6:6.1f} M "
                    f"(python -c pass: {bare / 1e6:5.1f} M)",
                    flush=True,
                )
    return 0


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        kind, *rest = argv[1:]
        if kind == "sim":
            _child_sim(rest[0], int(rest[1]))
        elif kind == "against":
            _child_against(*rest[:5])
        else:
            _child_episodes(rest[0], rest[1], int(rest[2]))
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed: instruction counts need valgrind --tool=callgrind")
        return 2
    if argv[:1] == ["--setup"] and len(argv) in (1, 3) and argv[1:2] in ([], ["--against"]):
        return setup(argv[2] if len(argv) == 3 else None)
    if argv[:1] == ["--against"] and len(argv) == 2:
        return against(argv[1])
    if argv[:1] == ["--sim"]:  # only the simulator's cases (those named, or all)
        with ThreadPoolExecutor(max_workers=2) as pool:
            for line in pool.map(_sim_line, argv[1:] or SIM_CASES):
                print(line, flush=True)
        return 0
    _compiled(ROOT)
    with ThreadPoolExecutor(max_workers=2) as pool:  # each job runs two valgrind processes
        futures = [pool.submit(_sim_line, case) for case in SIM_CASES]
        futures += [pool.submit(_episode_line, m, w, n) for m, w, n, _ in EPISODES]
        for future in futures:
            print(future.result(), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
