"""A run started in the background of a terminal (``roomba-bt run ... &``).

The terminal stops a process of a background job that writes to it when ``stty tostop`` is
set, or that changes its settings at all (SIGTTOU), as Ctrl-Z does: on a robot, the last
Drive goes on with nobody reading the sensors. Each test makes that terminal (a pty whose
session leader is the foreground job) and starts the run in a process group of its own.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pty")

#: The terminal's session leader: it sets ``tostop`` if asked, starts the command given in a
#: process group of its own (the background; in its own, the terminal's foreground group,
#: when asked ``foreground``), keeps what the terminal's screen was sent in ``screen.out``
#: and prints how it ended: ``exit N`` or ``stopped by SIGTTOU`` (then kills it).
LEADER = textwrap.dedent(
    f"""
    import fcntl, os, signal, subprocess, sys, termios, time
    how, command = sys.argv[1], sys.argv[2:]
    os.setsid()
    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSCTTY, 0)
    if how == "tostop":
        attributes = termios.tcgetattr(slave)
        attributes[3] |= termios.TOSTOP
        termios.tcsetattr(slave, termios.TCSANOW, attributes)
    job = subprocess.Popen(command, stdin=slave, stdout=slave, stderr=slave,
                           process_group=None if how == "foreground" else 0)
    os.set_blocking(master, False)
    screen = bytearray()
    deadline = time.monotonic() + {HANG_S!r}
    while time.monotonic() < deadline:
        try:
            screen += os.read(master, 65536)  # read, so no write waits
        except OSError:
            pass
        with open("screen.out", "wb") as kept:
            kept.write(screen)
        pid, status = os.waitpid(job.pid, os.WNOHANG | os.WUNTRACED)
        if pid and os.WIFSTOPPED(status):
            print("stopped by", signal.Signals(os.WSTOPSIG(status)).name)
            job.kill()
            break
        if pid:
            print("exit", os.waitstatus_to_exitcode(status))
            break
        time.sleep(0.02)
    else:
        job.kill()
        print("still running after {HANG_S:g} s")
    """
)

CIRCLE = """\
mission: circle
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, radius: 200 mm}
      until: {bump: any}  # no warning before the run (validate's wall check)
"""


def _in_the_background(tmp_path: Path, *args: str, tostop: bool, foreground: bool = False) -> str:
    """``roomba-bt ARGS`` (``circle.yaml`` written first) as a background job of a terminal
    (or its foreground job): how it ended; the terminal's screen in ``screen.out``."""
    command = [sys.executable, "-m", "roomba_bt.cli", *args]
    return _job(tmp_path, command, "foreground" if foreground else "tostop" if tostop else "-")


def _job(tmp_path: Path, command: list[str], how: str) -> str:
    """``command`` (``circle.yaml`` written first) as a job of a terminal, ``how`` the
    leader's (:data:`LEADER`): how it ended; the terminal's screen in ``screen.out``."""
    (tmp_path / "circle.yaml").write_text(CIRCLE)
    done = subprocess.run(
        [sys.executable, "-c", LEADER, how, *command],
        capture_output=True, text=True, timeout=2 * HANG_S, cwd=tmp_path,  # the leader's first
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


#: what the live tree's redraw sends: the cursor home, the screen cleared
CLEAR_SCREEN = b"\x1b[H\x1b[J"


def test_a_run_in_the_background_of_a_terminal_prints_lines_not_the_live_tree(
    tmp_path: Path,
) -> None:
    """Two runs started with ``&`` in one terminal each cleared the screen and drew their
    live tree over the other's. ``--display auto`` draws the tree only for the terminal's
    foreground job; a background run prints a line per status change."""
    ended = _in_the_background(tmp_path, "run", "circle.yaml", "--timeout", "1s", tostop=False)
    assert ended == "exit 1", ended
    screen = (tmp_path / "screen.out").read_bytes()
    assert CLEAR_SCREEN not in screen
    assert b"INFO roomba_bt.run: drive(velocity=100 mm/s, radius=200 mm left) -> RUNNING" in screen
    ended = _in_the_background(
        tmp_path, "run", "circle.yaml", "--timeout", "1s", tostop=False, foreground=True
    )
    assert ended == "exit 1", ended
    assert CLEAR_SCREEN in (tmp_path / "screen.out").read_bytes()  # the foreground's tree


def test_a_run_in_the_background_writing_to_a_tostop_terminal_is_not_stopped(
    tmp_path: Path,
) -> None:
    """Its first log line once the run began (``-v``: the robot found) stopped it ("Stopped
    (tty output)" in bash): a warning while it drove would have left the robot driving. The
    terminal's stops are ignored while a run on the wall clock goes on."""
    ended = _in_the_background(
        tmp_path, "-v", "run", "circle.yaml", "--timeout", "1s", "--display", "none",
        tostop=True,
    )  # fmt: skip
    assert ended == "exit 1", ended  # the timeout, after its safe stop


@pytest.mark.parametrize(
    ("args", "code"),
    [((), "exit 1"), (("--port", "ttyUSB9", "--display", "none"), "exit 3")],
    ids=["its-tree-first", "no-connection"],
)
def test_a_run_in_the_background_of_a_tostop_terminal_writes_before_its_run_too(
    tmp_path: Path, args: tuple[str, ...], code: str
) -> None:
    """The run ignored the terminal's stops only from its run's start: its first write
    before (the tree drawn before the run, ``--display auto`` and ``tree``; a port that
    did not open, exit 3) stopped the job (SIGTTOU), the port open and a script waiting
    for an exit that never came. Ignored from before the port is opened now."""
    ended = _in_the_background(
        tmp_path, "run", "circle.yaml", "--timeout", "1s", *args, tostop=True
    )  # fmt: skip
    assert ended == code, ended
    screen = (tmp_path / "screen.out").read_bytes()
    if not args:
        assert b"drive(velocity=100 mm/s, radius=200 mm left)" in screen, screen
    else:
        assert b"outcome      NO CONNECTION" in screen, screen


#: a program's run tick by tick on the real-time simulator, the robot driving its circle
#: from the second tick on; the loop's body writes a line to the terminal at tick 30 (the
#: program's own write after the run, the robot stopped, is the terminal's to stop)
TICKS_PROGRAM = """
import sys
import roomba_bt
mission = roomba_bt.load_mission_text(open("circle.yaml").read())
simulator = roomba_bt.Simulator(
    roomba_bt.load_world("empty-room"), roomba_bt.CREATE2, seed=0, trace=False
)
stack = roomba_bt.RunStack(mission, roomba_bt.RealtimeSimLink(simulator),
                           profile=roomba_bt.CREATE2, timeout_s=1.0)
with stack:
    for tick in stack.ticks():
        if tick.number == 30:
            print("driving at tick 30:", stack.connection.writer.last_wheels, file=sys.stderr)
with open("outcome.txt", "w") as kept:  # the robot stopped: a line here may stop the job
    print("outcome", stack.summary.outcome.value, file=kept)
"""


def test_a_programs_loop_over_ticks_in_the_background_is_not_stopped_by_its_writes(
    tmp_path: Path,
) -> None:
    """``for tick in stack.ticks():`` runs the run in a worker thread, and the run's signal
    guard, which ignores the terminal's stops on the wall clock, does nothing outside the
    main thread: the loop body's line to a ``tostop`` terminal stopped the whole process
    (SIGTTOU) with the robot driving its circle, the simulator stopped with it here but a
    robot driving on. The loop keeps them ignored as ``run()`` does."""
    ended = _job(tmp_path, [sys.executable, "-c", TICKS_PROGRAM], "tostop")
    assert ended == "exit 0", ended
    screen = (tmp_path / "screen.out").read_bytes()
    assert b"driving at tick 30: Command(drive, [137, 0, 100, 0, 200])" in screen, screen
    assert (tmp_path / "outcome.txt").read_text() == "outcome timeout\n"


@pytest.mark.extra("monitor")
def test_a_monitored_run_in_the_background_is_not_stopped_by_its_keys(tmp_path: Path) -> None:
    """The monitor's keys put the terminal in cbreak mode, which stops a background job
    whether ``tostop`` is set or not: the run never started. Keys are read in the
    foreground only; the page's controls work."""
    ended = _in_the_background(
        tmp_path, "run", "circle.yaml", "--timeout", "1s", "--display", "none",
        "--monitor", "127.0.0.1:0", tostop=False,
    )  # fmt: skip
    assert ended == "exit 1", ended
