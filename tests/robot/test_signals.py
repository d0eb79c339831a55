"""Endings by signal: SIGINT, SIGTERM, SIGHUP, SIGTSTP and SIGQUIT to a child process driving
the fake robot over a pty; and the helper restoring the previous handlers."""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Sequence

import pytest
from waits import HANG_S, joined, line  # tests/waits.py: a hang's bound, waits within it

from roomba_bt.robot.safety import (
    InterruptGuard,
    Terminated,
    interrupt_reason,
    signal_reason,
    sigterm_raises,
)
from roomba_bt.sim.server import PtyEndpoint

from .fake_robot import FakeRobot

CHILD = pathlib.Path(__file__).with_name("child_connection.py")
STOP_TO_PASSIVE = bytes([137, 0, 0, 0, 0, 138, 0, 150, 0, 128])


@pytest.mark.parametrize(
    ("signum", "raised"),
    [
        (signal.SIGINT, "KeyboardInterrupt"),
        (signal.SIGTERM, "Terminated"),
        (signal.SIGHUP, "Terminated"),  # the terminal gone: an SSH session dropped
        (signal.SIGTSTP, "Terminated"),  # Ctrl-Z: a suspended process cannot stop its robot
        (signal.SIGQUIT, "Terminated"),  # Ctrl-\: quit at once, the robot left driving
    ],
    ids=["SIGINT", "SIGTERM", "SIGHUP", "SIGTSTP", "SIGQUIT"],
)
def test_signal_to_a_child_leaves_the_robot_stopped_in_passive(
    signum: int, raised: str, child: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    endpoint = PtyEndpoint()
    with FakeRobot(endpoint) as robot:
        connection = child([sys.executable, str(CHILD), endpoint.address])
        assert connection.stdout is not None
        assert line(connection.stdout, "the child's ready").strip() == "ready"
        driving = bytes([137, 0, 120, 0x80, 0x00])
        assert robot.wait_until(lambda r: r.received.count(driving) >= 3)
        connection.send_signal(signum)
        out, err = connection.communicate(timeout=HANG_S)
        assert connection.returncode == 130, err
        assert out.strip() == raised
        robot.wait_for_stop(STOP_TO_PASSIVE)
        assert robot.wait_until(lambda r: r.mode.label == "Passive")
        assert robot.actuator_commands_outside_safe_or_full() == []


def test_only_a_hang_up_ignored_at_start_stays_ignored(
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """``nohup`` starts a process with SIGHUP ignored, and it stays so. A shell's background
    job without job control starts with SIGINT and SIGQUIT ignored too, by accident: a
    script's ``kill -INT`` is a stop asked for, and taken; SIGTERM is always taken (a
    supervisor's SIGKILL follows an ignored one, and would leave the robot driving)."""
    ignored = (signal.SIGHUP, signal.SIGINT, signal.SIGQUIT, signal.SIGTERM)
    script = (
        "import signal\n"
        f"for s in {[int(s) for s in ignored]}: signal.signal(s, signal.SIG_IGN)\n"
        "from roomba_bt.robot.safety import InterruptGuard, sigterm_raises\n"
        "with InterruptGuard() as guard, sigterm_raises():\n"
        "    print(sorted(s for s in range(1, 32) if signal.getsignal(s) is signal.SIG_IGN))\n"
    )
    out, err = child([sys.executable, "-c", script]).communicate(timeout=HANG_S)
    still_ignored = {int(s) for s in out.strip("[]\n").split(", ") if s}
    assert signal.SIGHUP in still_ignored, err
    assert not {signal.SIGINT, signal.SIGQUIT, signal.SIGTERM} & still_ignored


def test_sigterm_raises_terminated_and_restores_the_old_handler() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Terminated) as ended, sigterm_raises():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises inside the sleep
    assert isinstance(ended.value, KeyboardInterrupt)
    assert ended.value.signum == signal.SIGTERM
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.parametrize(
    "signum", [signal.SIGHUP, signal.SIGTSTP, signal.SIGQUIT], ids=["SIGHUP", "SIGTSTP", "SIGQUIT"]
)
def test_sigterm_raises_takes_the_hang_up_ctrl_z_and_ctrl_backslash_too(signum: int) -> None:
    before = signal.getsignal(signum)
    with pytest.raises(Terminated) as ended, sigterm_raises():
        os.kill(os.getpid(), signum)
        time.sleep(5)  # the handler raises inside the sleep
    assert ended.value.signum == signum
    assert signal.getsignal(signum) is before


@pytest.mark.parametrize("signum", [signal.SIGTSTP], ids=["SIGTSTP"])
def test_a_guard_where_nothing_drives_leaves_ctrl_z_alone(signum: int) -> None:
    """An evaluation, ``run --fast``, a replay: on the virtual clock nothing drives while the
    process is suspended, so Ctrl-Z keeps its meaning there; a run on the wall clock ends."""
    before = signal.getsignal(signum)
    hang_up = signal.getsignal(signal.SIGHUP)
    with InterruptGuard(wall_clock=False):
        assert signal.getsignal(signum) is before
        assert signal.getsignal(signal.SIGHUP) is not hang_up  # a hang-up still ends it
    with InterruptGuard():
        assert signal.getsignal(signum) is not before
    assert signal.getsignal(signum) is before
    assert signal.getsignal(signal.SIGHUP) is hang_up


@pytest.mark.parametrize("signum", [signal.SIGTTOU, signal.SIGTTIN], ids=["SIGTTOU", "SIGTTIN"])
def test_a_guard_on_the_wall_clock_ignores_the_terminals_stops_and_gives_them_back(
    signum: int,
) -> None:
    """A background job writing to a ``tostop`` terminal (SIGTTOU) or reading it (SIGTTIN)
    is stopped as by Ctrl-Z; on the wall clock the run ignores them (the write goes
    through), elsewhere they keep their meaning (tests/runtime/test_background.py runs it)."""
    before = signal.getsignal(signum)
    with InterruptGuard(wall_clock=False):
        assert signal.getsignal(signum) is before
    with InterruptGuard():
        assert signal.getsignal(signum) is signal.SIG_IGN
        os.kill(os.getpid(), signum)  # not stopped: the test goes on
    assert signal.getsignal(signum) is before
    guard = InterruptGuard(hold=True)
    with guard:
        pass
    assert signal.getsignal(signum) is signal.SIG_IGN  # until the summary is printed
    guard.release()
    assert signal.getsignal(signum) is before


def test_a_signal_s_interrupt_is_told_from_one_code_raises() -> None:
    """The runtime's handlers mark the interrupt they raise (session 29): one a plugin's code
    raises itself is its error (exit 4), the operator's Ctrl-C stays 130."""
    from roomba_bt.robot.safety import code_failure, interrupts_told_apart, signal_delivered

    # Python's own handler: the two cannot be told apart, so it is a signal's, as ever
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert signal_delivered(KeyboardInterrupt())
    assert not code_failure(KeyboardInterrupt())
    with interrupts_told_apart():
        assert not signal_delivered(KeyboardInterrupt())  # no signal: the code's
        with pytest.raises(KeyboardInterrupt) as sent:
            signal.raise_signal(signal.SIGINT)
        assert signal_delivered(sent.value)
        with pytest.raises(Terminated) as terminated:  # no handler of ours for SIGTERM here
            raise Terminated(signal.SIGTERM)
        assert signal_delivered(terminated.value)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # given back
    assert signal_delivered(sent.value)  # still, after the block
    with pytest.raises(KeyboardInterrupt) as raised, interrupts_told_apart():
        raise KeyboardInterrupt
    assert not signal_delivered(raised.value)  # marked on its way out of the block
    for other in (SystemExit(0), GeneratorExit(), RuntimeError("x")):
        assert code_failure(other) and not signal_delivered(other)
    with InterruptGuard(), pytest.raises(KeyboardInterrupt) as guarded:
        signal.raise_signal(signal.SIGINT)
    assert signal_delivered(guarded.value)
    with InterruptGuard():
        assert not signal_delivered(KeyboardInterrupt())
        assert not signal_delivered(Terminated(signal.SIGTERM))


def test_an_interrupt_raised_in_another_thread_is_never_a_signal_s() -> None:
    """Signals reach the main thread alone: a KeyboardInterrupt in a run's worker thread
    (``RunStack.ticks()``) was raised by code."""
    import threading

    from roomba_bt.robot.safety import RunAborted, code_failure, signal_delivered

    seen: list[bool] = []
    worker = threading.Thread(target=lambda: seen.append(signal_delivered(KeyboardInterrupt())))
    worker.start()
    joined(worker, "a thread's signal_delivered()")
    assert seen == [False]

    class Limit(RunAborted):
        """As an evaluation's wall-clock limit: raised into the run from outside."""

    assert not code_failure(Limit())


def test_a_hang_up_without_a_terminal_is_not_said_as_a_terminal_closed() -> None:
    """Under systemd, cron or ``setsid`` the run has no controlling terminal, and a SIGHUP
    comes from a program (``kill -HUP``, a logrotate ``postrotate``, ``systemctl reload``):
    it was said as "the terminal was closed (an SSH session dropped?)" all the same."""
    said = subprocess.run(
        [sys.executable, "-c", "import signal; from roomba_bt.robot import safety; "
         "print(safety.HAD_A_TERMINAL); print(safety.signal_reason(signal.SIGHUP))"],
        capture_output=True, text=True, timeout=HANG_S, start_new_session=True, check=True,
        stdin=subprocess.DEVNULL,
    )  # fmt: skip
    had, reason = said.stdout.splitlines()
    assert had == "False"
    assert reason.startswith("SIGHUP, with no terminal to hang up: sent by a program")
    assert "SSH" not in reason and "kill -HUP" in reason and "logrotate" in reason


def test_a_hang_up_of_a_run_in_a_terminal_says_the_terminal_was_closed() -> None:
    from roomba_bt.robot.safety import signal_reason

    assert signal_reason(signal.SIGHUP, terminal=True) == (
        "SIGHUP: the terminal was closed (an SSH session dropped?)"
    )


def test_a_guard_where_nothing_drives_takes_ctrl_backslash_as_sigterm() -> None:
    """Ctrl-\\ (SIGQUIT) ends every run with its safe stop, ``--fast`` and replays included
    (decided, session 35: it kept its core dump there, and a script's job, started with it
    ignored, lost it): an operator who presses it wants a stop."""
    before = signal.getsignal(signal.SIGQUIT)
    with InterruptGuard(wall_clock=False):
        assert signal.getsignal(signal.SIGQUIT) is not before
    assert signal.getsignal(signal.SIGQUIT) is before


def test_a_sigint_is_named_as_either_sender_would_have_sent_it() -> None:
    """A process cannot tell a terminal's Ctrl-C from another process's ``kill -INT``: the
    reason is true of both (it said ``Ctrl-C`` of a script's ``kill -INT $!``), and starts
    with ``Ctrl-C``, as logs were searched for."""
    said = signal_reason(signal.SIGINT)
    assert said == "Ctrl-C or kill -INT (SIGINT)"
    assert interrupt_reason(KeyboardInterrupt()) == said
    assert interrupt_reason(Terminated(signal.SIGTERM)) == "SIGTERM"


@pytest.mark.parametrize(
    ("signum", "said"),
    [
        (signal.SIGQUIT, "Ctrl-\\ or kill -QUIT (SIGQUIT): the run ended with its safe stop"),
        (signal.SIGTSTP, "Ctrl-Z or kill -TSTP (SIGTSTP): a suspended run could not stop"),
    ],
    ids=["SIGQUIT", "SIGTSTP"],
)
def test_the_other_keys_signals_are_named_as_sigint_is(signum: int, said: str) -> None:
    """Ctrl-\\ and Ctrl-Z named their key alone (``Ctrl-\\ (SIGQUIT)``), of a script's
    ``kill -QUIT`` too, where SIGINT's reason names both senders: said alike."""
    assert signal_reason(signum).startswith(said)
    assert interrupt_reason(Terminated(signum)) == signal_reason(signum)
