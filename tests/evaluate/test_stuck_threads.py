"""An in-process sweep (``eval --jobs 1 --wall-limit none``) whose episodes each leave a
thread stuck in a behaviour's ``terminate()`` (the run's end goes on without it:
``runtime/ending.py``): each such thread is a daemon, so the process can still exit, and
the sweep stops once :data:`~roomba_bt.evaluate.parallel.THREADS_LEFT_CAP` of them are
left (each holds its episode's tree, connection and simulator until the process exits),
with a clear message and exit 4; eval's closing line words them from their reason, not as
"an endless loop?"."""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py

from roomba_bt.evaluate import parallel
from roomba_bt.runtime import ending

#: a leaf that runs until stopped; its terminate() notes its process and how many threads
#: are stuck in it now, this one's included (``stops.txt`` beside it), then waits on an
#: Event nobody sets
HANG_ON_STOP = '''\
import os
import threading
from pathlib import Path

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare

RELEASE = threading.Event()
STUCK = {"roomba-bt tree stop", "roomba-bt shutdown"}


@declare("hang_on_stop", kind="action", params=(), reads=(), sends=())
class HangOnStop(Action):
    """Runs until stopped; its terminate() never returns."""

    def update(self):
        return Status.RUNNING

    def terminate(self, new_status):
        stuck = sum(1 for t in threading.enumerate() if t.name in STUCK and t.is_alive())
        with open(Path(__file__).with_name("stops.txt"), "a") as noted:
            noted.write(f"{os.getpid()} {stuck}\\n")
        RELEASE.wait()
'''

MISSION = "mission: hang_on_stop\nplugins: [./hang.py]\ntree:\n  hang_on_stop\n"

STUCK = {"roomba-bt tree stop", "roomba-bt shutdown"}


@pytest.fixture
def mission(tmp_path: Path) -> Iterator[Path]:
    """The mission and its plugin; the plugin's Event set when the test ends, so that every
    thread left in its terminate() ends too."""
    (tmp_path / "hang.py").write_text(HANG_ON_STOP)
    path = tmp_path / "m.yaml"
    path.write_text(MISSION)
    yield path
    for module in list(sys.modules.values()):
        if getattr(module, "__file__", None) == str(tmp_path / "hang.py"):
            module.RELEASE.set()


def _stuck() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name in STUCK and t.is_alive()]


def test_a_sweep_whose_episodes_each_hang_in_terminate_stops_at_the_cap(
    mission: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """20 episodes in this process, each leaving its terminate() stuck (the stop's bound
    made short): the sweep ends, its stuck threads are daemons and no more than the cap,
    and it stops there with a message that says why and what to do, exit 4."""
    from roomba_bt.cli import main

    monkeypatch.setattr(ending, "TREE_STOP_LIMIT_S", 0.05)
    monkeypatch.setattr(parallel, "THREADS_LEFT_CAP", 4)
    before = len(_stuck())
    code = main([
        "eval", str(mission), "--runs", "20", "--jobs", "1", "--wall-limit", "none",
        "--timeout", "0.2s", "--allow-plugin-files",
    ])  # fmt: skip
    out, err = capsys.readouterr()
    left = _stuck()
    assert all(t.daemon for t in left)
    assert len(left) - before == 4, err  # not one per episode: 20
    assert code == 4, out + err
    assert "4 of 20 episode(s) finished" in err, err
    assert (
        "the sweep stopped: 4 episode(s) left a thread stuck in a behaviour's terminate() "
        "or shutdown() in this process"
    ) in err, err
    assert (
        "4 episode(s) hung in a behaviour's terminate() that never returned (the run's end "
        "went on without it), the first: seed "
    ) in err, err
    assert "endless loop" not in err, err
    # docs/evaluation.md quotes both lines (3 episodes, a cap of 10: numbers of its example)
    assert_quoted("docs/evaluation.md", "roomba-bt eval: 3 episode(s) hung", err, numbers=True)
    assert_quoted("docs/evaluation.md", "roomba-bt eval: the sweep stopped:", err, numbers=True)


def test_a_worker_an_episode_left_a_stuck_thread_in_is_retired_and_replaced(
    mission: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--jobs 2``: each episode leaves its terminate() stuck in its worker. A worker kept
    them all (one per episode it ran, each holding its tree and simulator until it ended);
    now a worker that has one runs no other episode: it is retired, and a new worker takes
    the rest. Every terminate() began in a worker with no thread stuck from before, and
    every episode ran, HUNG."""
    from roomba_bt.cli import main

    monkeypatch.setattr(ending, "TREE_STOP_LIMIT_S", 0.05)  # the forked workers' too
    code = main([
        "eval", str(mission), "--runs", "6", "--jobs", "2", "--timeout", "0.2s",
        "--allow-plugin-files",
    ])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 4, out + err
    assert "6 episode(s) hung in a behaviour's terminate() that never returned" in err, err
    stops = [line.split() for line in (mission.parent / "stops.txt").read_text().splitlines()]
    assert len(stops) == 6, stops
    assert {stuck for _, stuck in stops} == {"1"}, stops  # its own alone
    assert len({pid for pid, _ in stops}) == 6, stops  # each in a worker of its own
