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

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pty")

#: The terminal's session leader: it sets ``tostop`` if asked, starts the command given in a
#: process group of its own (the background; in its own, the terminal's foreground group,
#: when asked ``foreground``), keeps what the terminal's screen was sent in ``screen.out``
#: and prints how it ended: ``exit N`` or ``stopped by SIGTTOU`` (then kills it).
LEADER = textwrap.dedent(
    """
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
    deadline = time.monotonic() + 60
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
        print("still running after 60 s")
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
    (tmp_path / "circle.yaml").write_text(CIRCLE)
    command = [sys.executable, "-m", "roomba_bt.cli", *args]
    how = "foreground" if foreground else "tostop" if tostop else "-"
    done = subprocess.run(
        [sys.executable, "-c", LEADER, how, *command],
        capture_output=True, text=True, timeout=90, cwd=tmp_path,
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
