"""An episode that kills the process running it (a behaviour calling ``os._exit``, a crash in C
code) is recorded as DIED, with how its worker died, and the sweep goes on, on the local pool and
on Dask; it ended the evaluation (Dask's ``KilledWorker`` as an internal error, exit 70; the
local pool after three deaths, exit 130). A Ctrl-C while a Dask worker restarted after a death
starts prints no traceback."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main

# A behaviour that ends its process on one seed (the episode's spec is read from the stack:
# nothing else in an episode knows its seed), and succeeds on every other.
_DIES_ON_SEED = """\
import os
import sys

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


def _seed():
    frame = sys._getframe()
    while frame is not None:
        spec = frame.f_locals.get("spec")
        if spec is not None and hasattr(spec, "seed"):
            return spec.seed
        frame = frame.f_back
    return None


@declare("dies_on_seed_3", kind="action", reads=(27,))
class DiesOnSeed3(Action):
    \"\"\"Ends the process running it, on seed 3.\"\"\"

    def update(self):
        if _seed() == 3:
            os._exit(1)
        return Status.SUCCESS
"""


def _mission(tmp_path: Path) -> Path:
    (tmp_path / "dies.py").write_text(_DIES_ON_SEED)
    mission = tmp_path / "dies.yaml"
    mission.write_text(
        "plugins: [./dies.py]\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n"
        "    - dies_on_seed_3\n"
    )
    return mission


@pytest.mark.parametrize(
    "engine",
    [["--jobs", "2"], ["--jobs", "1"], ["--jobs", "2", "--wall-limit", "none"],
     pytest.param(["--engine", "dask", "--jobs", "2"], marks=pytest.mark.extra("cluster"))],
)  # fmt: skip
def test_an_episode_that_kills_its_worker_is_recorded_as_died_and_the_sweep_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], engine: list[str]
) -> None:
    out = tmp_path / "out.jsonl"
    code = main(["eval", str(_mission(tmp_path)), "--runs", "6", "--seed", "1", "--timeout", "5s",
                 "--allow-plugin-files", "--no-progress", "--out", str(out), *engine])  # fmt: skip
    stdout, err = capsys.readouterr()
    assert code == 4, err
    assert "Traceback" not in err and "internal error" not in err, err
    assert "success      5/6 = 83.3 %" in stdout
    assert "DIED: the worker running it died: " in stdout
    assert "1 episode(s) killed the worker process running it" in err
    assert "the first: seed 3: the worker running it died: " in err
    assert "roomba-bt -v run " in err and " --seed 3 " in err
    from roomba_bt.evaluate.records import read_results

    records = read_results(out)
    assert [(r.seed, r.outcome) for r in records] == [
        (seed, "died" if seed == 3 else "success") for seed in range(1, 7)
    ]
    if "dask" in engine:
        assert "1 Dask worker(s) died running it, 1 more when it ran alone" in records[2].reason
    else:
        assert records[2].reason == (
            "the worker running it died: exit status 1, twice (the second time running it alone)"
        )


def test_a_local_worker_killed_from_outside_still_runs_its_episodes_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A death no episode repeats alone (the OOM killer, a kill -9) is no episode's fault: the
    episodes that were running finish alone, with their own results."""
    from roomba_bt.evaluate import episode_specs, run_episode
    from roomba_bt.evaluate.parallel import LocalRun, run_episodes

    marker = tmp_path / "killed"
    once = f"if _seed() == 3 and not os.path.exists({str(marker)!r}):"
    kill = f"open({str(marker)!r}, 'w').close(); os.kill(os.getpid(), 9)"
    (tmp_path / "once.py").write_text(
        _DIES_ON_SEED.replace("if _seed() == 3:", once).replace("os._exit(1)", kill)
    )
    mission = tmp_path / "once.yaml"
    mission.write_text("plugins: [./once.py]\ntree:\n  sequence:\n    - dies_on_seed_3\n")
    from roomba_bt.mission import Permissions

    specs = episode_specs(str(mission), runs=4, seed=1, timeout_s=5.0,
                          permissions=Permissions(plugin_files=True))  # fmt: skip
    run = LocalRun()
    results = run_episodes(specs, jobs=2, run=run)
    assert [r.outcome for r in results] == ["success"] * 4
    assert replace(results[2], wall_s=0.0) == replace(run_episode(specs[2]), wall_s=0.0)
    assert run.retried >= 1
    # how it died, read from the worker processes the pool started (its context kept them)
    assert "a worker process died: killed by SIGKILL (the OOM killer? a kill -9?)" in (
        capsys.readouterr().err
    )


def test_the_pool_s_private_attributes_are_not_read() -> None:
    """How a dead worker ended, and the ending of the workers at a Ctrl-C, are read from the
    processes the pool's context started (its public ``mp_context``), not from
    ``ProcessPoolExecutor``'s private ``_processes``, which a Python release may rename or
    empty at its shutdown."""
    import ast
    from concurrent.futures import ProcessPoolExecutor

    import roomba_bt.evaluate

    with ProcessPoolExecutor(max_workers=1) as pool:  # no worker starts before a submit
        private = {name for name in vars(pool) if name.startswith("_")}
    read = []
    for path in sorted(Path(roomba_bt.evaluate.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            named = node.attr if isinstance(node, ast.Attribute) else None
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                named = node.value  # getattr(pool, "_processes")
            if named in private:
                read.append(f"{path.name}:{node.lineno}: {named}")
    assert "_processes" in private  # what the test looks for is there to be read
    assert read == []


def test_the_seeds_said_of_a_dead_worker_in_an_a_b_name_their_variants(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An A/B runs each seed once per variant: a worker killed from outside in a sweep of
    dock against my-dock was said as ``seed(s) 28, 28 were running``, the same seed twice
    with nothing to tell which episode was which. Each is said with its variant, as its
    progress bar and the report label it: ``3 (.../once.yaml)``, ``3 (.../once-b.yaml)``."""
    marker = tmp_path / "killed"
    once = f"if _seed() == 3 and not os.path.exists({str(marker)!r}):"
    kill = f"open({str(marker)!r}, 'w').close(); os.kill(os.getpid(), 9)"
    (tmp_path / "once.py").write_text(
        _DIES_ON_SEED.replace("if _seed() == 3:", once).replace("os._exit(1)", kill)
    )
    tree = "plugins: [./once.py]\ntree:\n  sequence:\n    - dies_on_seed_3\n"
    (tmp_path / "once.yaml").write_text(tree)
    (tmp_path / "once-b.yaml").write_text(tree)
    code = main(["eval", str(tmp_path / "once.yaml"), str(tmp_path / "once-b.yaml"),
                 "--runs", "4", "--seed", "1", "--timeout", "5s", "--jobs", "2",
                 "--allow-plugin-files", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 0, err
    said = [line for line in err.splitlines() if "a worker process died" in line]
    variant = r"\(\S*/once(-b)?\.yaml\)"
    assert len(said) == 1 and re.search(rf"seed\(s\) (\d {variant}, )*3 {variant}", said[0])
    assert re.search(r"seed\(s\) [\d, ]+ (were|ran)", err) is None, err


_DIES_ONCE_THEN_RUNS = """\
import os
import time

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare

DIED = {died!r}


@declare("dies_once_then_runs", kind="action", reads=(27,))
class DiesOnceThenRuns(Action):
    \"\"\"Ends its process the first time (writing its pid), then runs until stopped.\"\"\"

    def update(self):
        if not os.path.exists(DIED):
            with open(DIED, "w") as f:
                f.write(str(os.getpid()))
            os._exit(1)
        time.sleep(0.05)
        return Status.RUNNING
"""


def _replacement_importing(eval_pid: int, dead: int, seen: set[int]) -> int | None:
    """The worker process the nanny started after ``dead`` died (a child of the evaluation
    not seen before it died) once it is importing (a tenth of a second of CPU: Python has
    taken over SIGINT, and Dask's imports take several times that), or None."""
    import psutil

    for child in psutil.Process(eval_pid).children():
        try:
            spawned = "spawn_main" in " ".join(child.cmdline())
            busy = sum(child.cpu_times()[:2]) >= 0.1
        except psutil.Error:
            continue
        if spawned and busy and child.pid not in seen and child.pid != dead:
            return int(child.pid)
    return None


@pytest.mark.extra("cluster")
def test_ctrl_c_while_a_dask_worker_restarts_prints_no_traceback(tmp_path: Path) -> None:
    """The nannies (in the evaluation's process) start a worker again after one died, once
    Ctrl-C is the evaluation's: the new worker started with Ctrl-C live, and a Ctrl-C while it
    imported Dask printed its KeyboardInterrupt traceback under the summary. The SIGINT here
    goes to the whole process group, as a terminal's, while that worker imports."""
    psutil = pytest.importorskip("psutil")
    died = tmp_path / "died"
    (tmp_path / "once.py").write_text(_DIES_ONCE_THEN_RUNS.format(died=str(died)))
    mission = tmp_path / "once.yaml"
    mission.write_text("plugins: [./once.py]\ntree:\n  sequence:\n    - dies_once_then_runs\n")
    proc = subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", "eval", str(mission), "--runs", "2",
         "--engine", "dask", "--jobs", "1", "--allow-plugin-files", "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
    )  # fmt: skip
    try:
        seen: set[int] = set()
        replacement = None
        deadline = time.monotonic() + HANG_S
        while replacement is None:
            # ended: what it said (its workers may hold its pipes: bounded); still running
            # past the bound: said so, not a communicate() that waits for its end for ever
            assert proc.poll() is None, proc.communicate(timeout=HANG_S)
            assert time.monotonic() < deadline, f"no worker started again in {HANG_S:g} s (hung?)"
            if not died.exists() or not died.read_text():
                seen.update(c.pid for c in psutil.Process(proc.pid).children())
                time.sleep(0.01)  # another process's file: no event to wait on
                continue
            replacement = _replacement_importing(proc.pid, int(died.read_text()), seen)
        os.killpg(proc.pid, signal.SIGINT)
        _, stderr = proc.communicate(timeout=HANG_S)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=HANG_S)
    assert proc.returncode == 130, stderr
    assert b"Traceback" not in stderr and b"KeyboardInterrupt" not in stderr, stderr.decode()


@pytest.mark.parametrize("verbose", [[], ["-v"]])
@pytest.mark.extra("cluster")
def test_dask_s_own_lines_on_a_worker_death_are_its_detail_shown_with_v(
    tmp_path: Path, verbose: list[str]
) -> None:
    """A worker of a local Dask cluster dies: Dask's own log lines (a task marked as failed, a
    nanny restarting a worker, a worker removed with what it held) came on stderr between
    ours, a wall of its internals. Now every line is ours (what died, what runs again, the
    DIED record), and Dask's are its detail, shown with -v."""
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt", *verbose, "eval", str(_mission(tmp_path)), "--runs",
         "6", "--seed", "1", "--timeout", "5s", "--allow-plugin-files", "--no-progress",
         "--engine", "dask", "--jobs", "2"],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 4, done.stderr
    assert "roomba-bt eval: seed 3 killed its workers again, alone: recorded as DIED" in done.stderr
    lines = done.stderr.splitlines()
    dask = [
        line for line in lines if line.startswith(("ERROR distributed.", "WARNING distributed."))
    ]
    if verbose:
        assert dask, done.stderr
    else:
        assert all(line.startswith("roomba-bt eval: ") for line in lines), done.stderr
