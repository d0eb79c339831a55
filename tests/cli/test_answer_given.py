"""A signal once a run's answer is NO CONNECTION (exit 3: not started, nothing of the mission
sent, a retry safe) leaves that answer and its exit code as they are (``answer_given`` in
``roomba_bt/robot/safety.py``; docs/runtime.md). It was 130, ``interrupted by SIGTERM``
under a summary that said NO CONNECTION, or 143 from the command's answer on; and a second
signal killed the process (status -15), where after a run's end it kept the run's code.

Each child brings the signal to itself at a set point of the answer (no timing): as the
summary is made, as the stderr lines after it are written, or once ``main`` has returned."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

ROOT = Path(__file__).resolve().parents[2]

#: ``roomba-bt run dock --port PORT`` through the entry point, the signal ``SIGNUM`` brought
#: at ``WHEN``: "summary" (the port never opened: as the summary is made), "report" (the
#: port opened, the robot silent: as the report's stderr lines are written), "exit" (once
#: ``main`` returned, before the process exits), "stuck" (as the summary is made, which then
#: never ends: a stdout nobody reads); ``TIMES``: how many are sent together
CHILD = """
import os, signal, sys, time
from roomba_bt.cli import run_cmd
from roomba_bt._entry import main

port, when, signum, times = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])

def bring():
    for _ in range(times):
        os.kill(os.getpid(), signum)
    for _ in range(1000):  # a Python handler runs between bytecodes, here at the latest
        pass

if when in ("summary", "stuck"):
    said = run_cmd.RunSummary.__str__
    def summary(self):
        bring()
        if when == "stuck":
            time.sleep(60)
        return said(self)
    run_cmd.RunSummary.__str__ = summary
elif when == "report":
    reported = run_cmd._report_on_stderr
    def report(*args):
        bring()
        return reported(*args)
    run_cmd._report_on_stderr = report

sys.argv = ["roomba-bt", "run", "dock", "--port", port, "--display", "none"]
code = main()
if when == "exit":
    bring()
sys.exit(code)
"""


def _answer(port: str, when: str, signum: int, times: int = 1) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CHILD, port, when, str(int(signum)), str(times)],
        capture_output=True, text=True, timeout=HANG_S, env={"PYTHONPATH": str(ROOT), "PATH": ""},
    )  # fmt: skip


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
@pytest.mark.parametrize("when", ["summary", "exit"])
def test_a_signal_after_a_port_that_never_opened_leaves_exit_3(
    tmp_path: Path, when: str, signum: int
) -> None:
    done = _answer(str(tmp_path / "ttyUSB9"), when, signum)
    assert done.returncode == 3, (done.returncode, done.stderr)
    assert "outcome      NO CONNECTION" in done.stdout
    assert "interrupted" not in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize("when", ["report", "exit"])
def test_a_sigterm_after_a_robot_that_never_answered_leaves_exit_3(
    silent_port: str, when: str
) -> None:
    """The port opened, nothing answered the start-up: the run's own ending, exit 3."""
    done = _answer(silent_port, when, signal.SIGTERM)
    assert done.returncode == 3, (done.returncode, done.stderr)
    assert "outcome      NO CONNECTION" in done.stdout
    assert "interrupted" not in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize("when", ["summary", "stuck"])
def test_three_sigterms_together_leave_exit_3_too(tmp_path: Path, when: str) -> None:
    """The rule of every answer (a run's end too): the signals after the first change
    nothing (the second killed the process: status -15, "killed by SIGTERM"), and a summary
    blocked on a pipe nobody reads ("stuck") is ended 2 s after the first with 143: cut
    short by the signal, its answer 3 said on stderr (decided, session 39; it was 3, as if
    the summary had been written whole)."""
    done = _answer(str(tmp_path / "ttyUSB9"), when, signal.SIGTERM, times=3)
    if when == "stuck":
        assert done.returncode == 128 + signal.SIGTERM, (done.returncode, done.stderr)
        assert "exit 143, where the command's answer was 3" in done.stderr, done.stderr
        return
    assert done.returncode == 3, (done.returncode, done.stderr)
    if when == "summary":
        assert "outcome      NO CONNECTION" in done.stdout


def test_a_programs_call_keeps_its_own_handlers(tmp_path: Path) -> None:
    """``main(argv)`` from a program: exit 3 all the same, and its handlers as they were (the
    answer's handler is the process's alone)."""
    from roomba_bt.cli import main

    before = [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)]
    argv = ["run", "dock", "--port", str(tmp_path / "ttyUSB9"), "--display", "none"]
    assert main(argv) == 3
    assert [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)] == before
