"""The slowest tick's behaviour, named in the summary (runtime/tick_watch.py): a plugin's
``update()`` that blocks (``time.sleep``) showed under ``run --fast`` only as ``slowest 503.89
ms``, and the plugin's author, who tests there, could not tell which leaf it was. The blocking
here is half a second, twenty looks of the watch: whether it is named does not depend on the
machine's speed."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import Permissions
from roomba_bt.runtime.summary import ExitCode, RunSummary

from .simrun import RunMission, write_mission

PLUGIN = '''
import time

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("sleepy", kind="action")
class Sleepy(Action):
    """Blocks its first tick for half a second, then runs two ticks more."""

    def initialise(self):
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks == 1:
            time.sleep(0.5)
        return Status.SUCCESS if self.ticks >= 3 else Status.RUNNING
'''

MISSION = "plugins: [./sleepy.py]\ntree:\n  sequence: [{mode: safe}, {wait: 100ms}, sleepy]\n"


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path, MISSION, "m.yaml", {"sleepy.py": PLUGIN})


def test_run_fast_names_the_behaviour_of_its_slowest_tick(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On the virtual clock there is no tick guard; the ticks line names the leaf all the
    same, as the guard would: the behaviour, its method and the line it was blocked at."""
    argv = ["run", str(mission), "--fast", "--display", "none", "--allow-plugin-files"]
    assert main(argv) == ExitCode.OK
    out = capsys.readouterr().out
    ticks = next(line for line in out.splitlines() if line.startswith("ticks "))
    plugin = mission.parent / "sleepy.py"
    assert " ms in sleepy (Sleepy.update at " in ticks, ticks
    assert f"{plugin}:19)" in ticks, ticks  # the time.sleep line


def test_a_program_s_run_starts_no_watch_unless_asked(
    run_mission: RunMission, mission: Path
) -> None:
    """The evaluation's episodes (benchmarked per tick) and a program's runs start no watch
    thread: only ``roomba-bt run`` sets ``names_slow_ticks``."""
    run = run_mission(MISSION, permissions=Permissions(plugin_files=True), timeout=10.0)
    assert run.summary.max_tick_s > 0.4
    assert getattr(run.summary, "slowest_in", "") == ""


def test_only_a_slow_tick_is_named() -> None:
    """The ticks line names a behaviour only for a slowest tick over the 15 ms slot, and the
    watch only one whose stretch inside a behaviour was about as long as the slowest tick."""
    from roomba_bt.runtime.tick_watch import SlowTickWatch  # here: the tests above run on old code

    summary = RunSummary("m", ticks=3, max_tick_s=0.010, slowest_in="w (W.update at w.py:3)")
    assert "slowest 10.00 ms)" in str(summary)
    summary.max_tick_s = 0.5
    assert "slowest 500.00 ms in w (W.update at w.py:3))" in str(summary)
    watch = SlowTickWatch(summary, look_every_s=0.025)
    watch.longest_s, watch.where = 0.45, "w (W.update at w.py:3)"
    assert watch.culprit() == "w (W.update at w.py:3)"
    watch.longest_s = 0.2  # another, shorter tick's: not the slowest one
    assert watch.culprit() == ""
