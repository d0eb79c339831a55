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
import threading
from pathlib import Path

import py_trees
import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.safety import SIGINT_SAID, Terminated
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import SLOW_TERM, SPIN, TapLink

SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def _signal_main(signum: int) -> None:
    """``signum`` to the main thread, where the handlers run: ``os.kill`` to the process may
    be taken by another thread of the suite's (a server a test left, a pool), and under load
    the main thread then went on past the phase the test sends it in (CI: a signal sent
    during the safe stop was seen during the shutdown after it)."""
    signal.pthread_kill(threading.main_thread().ident or 0, signum)


def _stack(tmp_path: Path, kill_at_tick: int | None, signum: int) -> tuple[RunStack, TapLink]:
    """A spinning mission on the simulator's virtual clock; with ``kill_at_tick``, the
    process signals itself after that tick (what the operator's Ctrl-C or a ``kill`` does)."""
    path = tmp_path / "spin.yaml"
    path.write_text(textwrap.dedent(SPIN))
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))

    def observer(runner: MissionRunner) -> None:
        if runner.snapshot.tick == kill_at_tick:
            _signal_main(signum)

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
    assert summary.reason == SIGINT_SAID
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
        capture_output=True, text=True, timeout=HANG_S, env=env,
    )  # fmt: skip
    assert done.stdout.split("\n")[:2] == ["mission 1", ""], done.stdout + done.stderr
    assert done.returncode != 0
    assert "Terminated: terminated by signal SIGTERM" in done.stderr


class _SignalsAt(py_trees.behaviour.Behaviour):
    """Succeeds at once; its ``shutdown()`` signals the process (the operator's Ctrl-C or a
    ``kill`` coming while the run shuts its nodes down) and then finishes its work."""

    def __init__(self, signum: int | None, done: list[str]) -> None:
        super().__init__("closer")
        self.signum, self.done = signum, done

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS

    def shutdown(self) -> None:
        if self.signum is not None:
            _signal_main(self.signum)
        self.done.append("shut down")  # the rest of its shutdown ran: the signal waited


class _SignalOnSafeStop(TapLink):
    """Signals the process when the safe stop's drive 0 and motors off are written."""

    def __init__(self, simulator: Simulator, signum: int) -> None:
        super().__init__(simulator)
        self.signum = signum

    def write(self, data: bytes) -> None:
        super().write(data)
        if oi.halt().data + oi.motors_off().data in data:
            _signal_main(self.signum)


def _late_stack(signum: int, during: str, done: list[str]) -> tuple[RunStack, TapLink]:
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    link = _SignalOnSafeStop(simulator, signum) if during == "safe stop" else TapLink(simulator)
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        Drive("forward", {"velocity": "100 mm/s", "duration": "0.3 s"}),
        _SignalsAt(signum if during == "shutdown" else None, done),
    ])  # fmt: skip
    return RunStack(TreeMission(root, "late"), link, profile=CREATE2, timeout_s=5.0), link


#: what the reason says a late signal came during: the phase, and the behaviour it came in
_SAID = {
    "safe stop": "the safe stop",
    "shutdown": f"the behaviours' shutdown(), in closer (_SignalsAt.shutdown at {__file__}:"
    f"{_SignalsAt.shutdown.__code__.co_firstlineno + 2})",
}


@pytest.mark.parametrize("during", ["shutdown", "safe stop"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_the_stop_is_raised_once_the_stop_is_done(
    during: str, signum: int, capfd: pytest.CaptureFixture[str]
) -> None:
    done: list[str] = []
    first, link = _late_stack(signum, during, done)
    second, second_link = _late_stack(signum, "nothing", [])
    with pytest.raises(KeyboardInterrupt) as caught:
        first.run()
        second.run()  # the program's next mission: never started
    assert second_link.writes == []
    assert isinstance(caught.value, Terminated) == (signum == signal.SIGTERM)
    summary = caught.value.summary  # type: ignore[attr-defined]
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    why = SIGINT_SAID if signum == signal.SIGINT else "SIGTERM"
    assert summary.reason == f"{why} during {_SAID[during]} (the run had ended: success)"
    assert done == ["shut down"]  # the stop and the shutdown were finished first
    assert link.written.endswith(SAFE_END) and summary.safe_stop.startswith("sent ")
    err = capfd.readouterr().err
    assert "waiting for it to end (then the interrupt is raised)" in err
    assert "summary follows" not in err


@pytest.mark.parametrize("during", ["shutdown", "safe stop"])
def test_the_cli_reports_a_signal_during_the_stop_as_interrupted(
    during: str, capfd: pytest.CaptureFixture[str]
) -> None:
    done: list[str] = []
    stack, _link = _late_stack(signal.SIGINT, during, done)
    summary = stack.run(raise_interrupts=False)
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.reason == f"{SIGINT_SAID} during {_SAID[during]} (the run had ended: success)"
    assert done == ["shut down"]
    assert "waiting for it to end (the summary follows)" in capfd.readouterr().err


def test_a_signal_during_the_stop_of_a_failed_run_keeps_its_outcome() -> None:
    from roomba_bt.runtime.summary import RunSummary
    from roomba_bt.runtime.teardown import note_late_interrupt

    summary = RunSummary("m", outcome=Outcome.ERROR, reason="behaviour x raised E: e")
    note_late_interrupt(summary, Terminated(signal.SIGTERM))
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4
    assert summary.reason == "behaviour x raised E: e; then SIGTERM during the safe stop"


class _CtrlCBeforeTheFirstByte(TapLink):
    """Ctrl-C comes as the run's first write is about to go: nothing reaches the robot."""

    def write(self, data: bytes) -> None:
        _signal_main(signal.SIGINT)  # the handler raises here, before the write
        super().write(data)


def test_a_ctrl_c_before_the_first_byte_says_nothing_needed_stopping() -> None:
    link = _CtrlCBeforeTheFirstByte(Simulator(load_world("empty-room"), CREATE2, 0))
    root = Drive("forward", {"velocity": "100 mm/s"})
    stack = RunStack(TreeMission(root, "early"), link, profile=CREATE2, timeout_s=5.0)
    summary = stack.run(raise_interrupts=False)
    stack.close()
    assert link.writes == []  # not a byte written
    assert summary.outcome is Outcome.INTERRUPTED
    assert summary.safe_stop == "nothing to stop: the robot was never started"
    assert summary.stop_delivered
    assert_quoted("docs/runtime.md", "safe stop nothing to stop", str(summary))
    assert "NOT DELIVERED" not in str(summary)


class _SignalsOnTerminate(py_trees.behaviour.Behaviour):
    """Runs until stopped; its ``terminate()`` at the run's end signals the process (the
    operator's second Ctrl-C while a plugin's terminate blocks) and notes the wheels."""

    def __init__(self, runner: list[MissionRunner], seen: list[object]) -> None:
        super().__init__("slow_term")
        self.runner, self.seen = runner, seen

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.RUNNING

    def terminate(self, new_status: py_trees.common.Status) -> None:
        if new_status is py_trees.common.Status.INVALID and self.runner:
            _signal_main(signal.SIGINT)
            self.seen.append(self.runner[0].connection.writer.last_wheels.args)  # type: ignore[union-attr]


def test_a_signal_during_the_trees_stop_says_the_tree_is_stopping(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """A Ctrl-C while the tree's stop runs (a terminate that blocks) says so, and that drive
    0 and motors off went out before it: not "the safe stop is under way", which was not."""
    runners: list[MissionRunner] = []
    seen: list[object] = []
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        py_trees.composites.Parallel(
            "both", policy=py_trees.common.ParallelPolicy.SuccessOnAll(), children=[
                Drive("forward", {"velocity": "100 mm/s"}), _SignalsOnTerminate(runners, seen),
            ],
        ),
    ])  # fmt: skip
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(TreeMission(root, "t"), link, profile=CREATE2, timeout_s=0.3, tick_limit=0.25)
    runners.append(stack.runner)
    summary = stack.run(raise_interrupts=False)
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    line = _SignalsOnTerminate.terminate.__code__.co_firstlineno + 2  # its signal
    assert summary.reason == (
        f"{SIGINT_SAID} during the tree's stop, in slow_term (_SignalsOnTerminate.terminate at "
        f"{__file__}:{line}) (the run had ended: timeout: the run's 0.3 s of mission time "
        "ran out in forward)"
    ), summary.reason  # it said "during the safe stop", which had not begun
    assert summary.safe_stop.startswith("drive 0, motors off before the tree's stop, then sent")
    assert summary.stop_delivered
    assert seen == [(0, 0)]
    err = capfd.readouterr().err
    assert (
        "roomba-bt: the run is ending: drive 0 and motors off were sent; its tree is being "
        "stopped (each running behaviour's terminate(), for at most 5 s), the safe stop "
        "after it; waiting for it to end (the summary follows)"
    ) in err, err
    assert "the safe stop is under way" not in err
    assert link.written.endswith(oi.halt().data + oi.motors_off().data + SAFE_END)


#: a plugin leaf that drives until stopped; its terminate() at the run's end is where the
#: operator's second Ctrl-C comes
CTRL_C_IN_TERMINATE = SLOW_TERM.replace(
    "            self.SEEN.append(",
    "            os.kill(os.getpid(), signal.SIGINT)\n            self.SEEN.append(",
).replace(
    "from py_trees.common import Status",
    "import os\nimport signal\n\nfrom py_trees.common import Status",
)


def test_the_cli_says_a_ctrl_c_in_a_terminate_came_during_the_trees_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``roomba-bt run`` on the wall clock: the run times out, and a Ctrl-C comes while its
    tree is stopped. The run still ends with its safe stop, exit 130, and its reason names the
    tree's stop and the terminate() it came in (it said "during the safe stop")."""
    from roomba_bt.cli import main

    (tmp_path / "slowterm.py").write_text(CTRL_C_IN_TERMINATE)
    mission = tmp_path / "m.yaml"
    mission.write_text("plugins: [./slowterm.py]\ntree:\n  sequence: [{mode: safe}, slow_term]\n")
    run = ["run", str(mission), "--allow-plugin-files", "--timeout", "0.3s", "--display", "none"]
    assert main(run) == 130
    said = capsys.readouterr()
    text = said.out + said.err
    line = CTRL_C_IN_TERMINATE.splitlines().index("            os.kill(os.getpid(), signal.SIGINT)")
    assert (
        f"{SIGINT_SAID} during the tree's stop, in slow_term (SlowTerm.terminate at "
        f"{tmp_path / 'slowterm.py'}:{line + 1}) (the run had ended: timeout: "
    ) in text, text
    assert (
        "safe stop    drive 0, motors off before the tree's stop, then sent drive, motors" in text
    )
    assert "during the safe stop" not in text
