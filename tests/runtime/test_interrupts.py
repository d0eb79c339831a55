"""Ctrl-C and SIGTERM in a run started from Python: the safe stop first, then the interrupt
raised again in the caller (the summary on it), so a program that runs two missions in a
row does not drive the second one after its operator pressed Ctrl-C. The CLI's own runs
(``raise_interrupts=False``) keep their summary and exit 130: ``test_loop.py`` and
``test_cli_pty.py``."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.safety import Terminated
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import SPIN, TapLink

SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def _stack(tmp_path: Path, kill_at_tick: int | None, signum: int) -> tuple[RunStack, TapLink]:
    """A spinning mission on the simulator's virtual clock; with ``kill_at_tick``, the
    process signals itself after that tick (what the operator's Ctrl-C or a ``kill`` does)."""
    path = tmp_path / "spin.yaml"
    path.write_text(textwrap.dedent(SPIN))
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))

    def observer(runner: MissionRunner) -> None:
        if runner.snapshot.tick == kill_at_tick:
            os.kill(os.getpid(), signum)

    stack = RunStack(load_mission(path), link, profile=CREATE2, timeout_s=5.0, observer=observer)
    return stack, link


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_the_interrupt_reaches_the_caller_after_the_safe_stop(tmp_path: Path, signum: int) -> None:
    first, first_link = _stack(tmp_path, 40, signum)
    second, second_link = _stack(tmp_path, None, signum)
    with pytest.raises(KeyboardInterrupt) as caught:
        first.run()
        second.run()  # the program's next mission: never started
    assert second_link.writes == []
    assert first_link.written.endswith(SAFE_END)  # drive 0, motors off, pause, Start
    assert first_link.simulator.mode is OIMode.PASSIVE
    assert first_link.simulator.requested_left == first_link.simulator.requested_right == 0
    summary = caught.value.summary  # type: ignore[attr-defined]
    assert summary is first.runner.summary
    assert summary.outcome is Outcome.INTERRUPTED
    assert summary.safe_stop.startswith("sent ")
    assert isinstance(caught.value, Terminated) == (signum == signal.SIGTERM)
    # the handlers the program had are back
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_the_cli_keeps_its_summary(tmp_path: Path) -> None:
    stack, link = _stack(tmp_path, 40, signal.SIGINT)
    summary = stack.run(raise_interrupts=False)
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.reason == "Ctrl-C"
    assert link.written.endswith(SAFE_END)


SCRIPT = """
import os, signal, sys, textwrap
from pathlib import Path
from roomba_bt.mission import load_mission
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack
from roomba_bt.sim import SimLink, Simulator, load_world

path = Path(sys.argv[1])
for number in (1, 2):
    print("mission", number, flush=True)
    def observer(runner):
        if runner.snapshot.tick == 40:
            os.kill(os.getpid(), signal.SIGTERM)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0))
    RunStack(load_mission(path), link, profile=CREATE2, timeout_s=5.0, observer=observer).run()
print("done", flush=True)
"""


def test_a_kill_ends_a_program_that_runs_two_missions(tmp_path: Path) -> None:
    path = tmp_path / "spin.yaml"
    path.write_text(textwrap.dedent(SPIN))
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(path)],
        capture_output=True, text=True, timeout=120, env=env,
    )  # fmt: skip
    assert done.stdout.split("\n")[:2] == ["mission 1", ""], done.stdout + done.stderr
    assert done.returncode != 0
    assert "Terminated: terminated by signal SIGTERM" in done.stderr
