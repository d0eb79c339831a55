"""A signal after a run's answer is out (its summary, the exit code decided) ends the process
with that code: three Ctrl-Cs 0.3 s apart after a monitored run killed it by SIGINT (status
-2, "killed by signal INT" in systemd's log), the summary sometimes not printed, where the
command had said 130 (``robot/safety.py``: ``answer_given``,
``signals_wait_for_the_exit``)."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from waits import HANG_S  # tests/waits.py: a hang's bound

#: the command run as the process (``roomba-bt validate dock``), then a Ctrl-C as it exits:
#: Python's finalization put its handlers back to the default action, which killed it
CTRL_C_AS_IT_EXITS = """
import os, signal, sys
sys.argv = ["roomba-bt", "validate", "dock"]
from roomba_bt._entry import main
code = main()
os.kill(os.getpid(), signal.SIGINT)
sys.exit(code)
"""

#: a signal (``argv[2]``) while the last words are written (a run's summary, its answer 4
#: known), one whose last words never end (a stdout nobody reads: here a sleep), and one
#: whose words are out and flushed but whose exit is slow ("slow exit": a thread joined)
SIGNAL_IN_THE_LAST_WORDS = """
import os, signal, sys, time
from roomba_bt.robot.safety import answer_given, signals_wait_for_the_exit
answer_given(4)
os.kill(os.getpid(), int(sys.argv[2]))
print("the summary", flush=True)
if sys.argv[1] == "stuck":
    time.sleep(60)
if sys.argv[1] == "slow exit":
    signals_wait_for_the_exit()
    time.sleep(60)
sys.exit(4)
"""


def _run(script: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=HANG_S
    )


def test_a_ctrl_c_as_the_command_exits_leaves_its_exit_code() -> None:
    done = _run(CTRL_C_AS_IT_EXITS)
    assert done.returncode == 0, (done.returncode, done.stderr)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_in_the_last_words_lets_them_finish_with_the_command_s_code(
    signum: int,
) -> None:
    done = _run(SIGNAL_IN_THE_LAST_WORDS, "ends", str(int(signum)))
    assert (done.returncode, done.stdout) == (4, "the summary\n"), done.stderr


def test_last_words_that_never_end_are_ended_with_the_signal_s_code() -> None:
    """A write blocked on a pipe nobody reads is why a signal ends the process here: a
    thread ends it :data:`LAST_WORDS_S` after the signal, with ``128 + SIGTERM``: the report
    was cut short by the signal (session 37 to 38 exited with the command's answer, 4 here,
    0 for a run that succeeded: a script took a report cut short for a whole one). The
    answer is said on stderr, which takes it here."""
    done = _run(SIGNAL_IN_THE_LAST_WORDS, "stuck", str(int(signal.SIGTERM)))
    assert done.returncode == 128 + signal.SIGTERM, done.stderr
    assert (
        "roomba-bt: the report was cut short: SIGTERM came and it was not written within "
        "2 s; exit 143, where the command's answer was 4" in done.stderr
    ), done.stderr
    # the page's answer is a run's that succeeded (0), this program's 4
    said = done.stderr
    assert_quoted("docs/runtime.md", "roomba-bt: the report was cut short:", said, numbers=True)


def test_last_words_out_and_a_slow_exit_keep_the_command_s_answer() -> None:
    """The words written and flushed, only the interpreter's exit left (a thread it waits
    for): the signal cut nothing short, and the end it set going exits with the answer."""
    done = _run(SIGNAL_IN_THE_LAST_WORDS, "slow exit", str(int(signal.SIGTERM)))
    assert (done.returncode, done.stdout) == (4, "the summary\n"), done.stderr
    assert "cut short" not in done.stderr


#: a second signal whose handler runs inside the first's (three SIGTERMs sent together as a
#: summary printed): here the first handler's timer, as it starts, sends the second
SIGNAL_INSIDE_THE_HANDLER = """
import os, signal, sys, threading
from roomba_bt.robot import safety
from roomba_bt.robot.safety import answer_given

class Timer(threading.Timer):
    def start(self):
        os.kill(os.getpid(), signal.SIGTERM)  # its handler runs inside this one's
        for _ in range(1000):  # a few bytecodes: Python runs the pending handler here
            pass
        super().start()

safety.threading.Timer = Timer
answer_given(3)
os.kill(os.getpid(), signal.SIGTERM)
print("the summary", flush=True)
sys.exit(3)
"""


def test_a_signal_inside_the_first_one_s_handler_does_not_stop_the_exit() -> None:
    """A verifier's three SIGTERMs sent together as a run's summary printed left 3 of 6
    processes running for ever: the second's handler ran inside the first's and waited for
    a lock the first held. Now the command exits with its own code."""
    done = _run(SIGNAL_INSIDE_THE_HANDLER)
    assert (done.returncode, done.stdout) == (3, "the summary\n"), done.stderr
