"""A second Ctrl-C after the safe stop, while the run closes: the record's end note, the port's
close and its kernel exclusive mode cleared still happen, and the summary is printed.

Killed there (the signals took their default action right after the safe stop), the run left
the simulator's pty in exclusive mode (TIOCEXCL), which refused the next run by a user
without root until the simulator restarted, and a record without its end note. The second
signal is sent by the run to itself from a hook at a known point of its closing, never after
a guessed delay.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from transport.test_serial_transport import in_exclusive_mode  # tests/transport: TIOCGEXCL
from waits import HANG_S, ended  # tests/waits.py: a child's end, no fixed bet

from roomba_bt.robot.safety import CLOSING_UNDER_WAY
from roomba_bt.runtime.recording import load_record

from .simrun import SPIN
from .test_cli_pty import _wait_for_driving, ends_with_the_safe_stop

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="a pty, and TIOCGEXCL is Linux's"
)

#: ``roomba-bt`` as the process itself (``main()``, its signals its own), with a hook that
#: sends the process a SIGINT as the run's closing reaches ``where``: the record's end note
#: (the first thing after the safe stop), or the stack's close (after the monitor's shutdown)
HOOKED_RUN = """
import os, signal, sys
from roomba_bt.cli import main
from roomba_bt.runtime import stack

where = sys.argv.pop(1)

def interrupted_first(original):
    def hooked(*args, **kwargs):
        os.write(2, b"hook: SIGINT\\n")
        os.kill(os.getpid(), signal.SIGINT)
        return original(*args, **kwargs)
    return hooked

if where == "end note":
    stack.end_note = interrupted_first(stack.end_note)
else:
    stack.RunStack.close = interrupted_first(stack.RunStack.close)
sys.exit(main())
"""


@pytest.mark.parametrize("where", ["end note", "close"])
def test_a_second_ctrl_c_while_the_run_closes_leaves_the_port_free_and_the_record_whole(
    served_sim: Callable[..., Any], tmp_path: Path, where: str
) -> None:
    port: str = served_sim("--pty").address
    mission, record = tmp_path / "spin.yaml", tmp_path / "run.jsonl"
    mission.write_text(textwrap.dedent(SPIN))
    proc = subprocess.Popen(
        [sys.executable, "-c", HOOKED_RUN, where, "run", str(mission), "--port", port,
         "--record", str(record), "--display", "log"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        _wait_for_driving(record, proc)
        proc.send_signal(signal.SIGINT)  # the first Ctrl-C: the safe stop
        out, err = ended(proc)
    finally:
        if proc.poll() is None:  # _wait_for_driving failed
            proc.kill()
            proc.communicate(timeout=HANG_S)
    assert "hook: SIGINT" in err  # the second one was sent, where it was meant to be
    assert proc.returncode == 130, out + err
    assert "outcome      INTERRUPTED (Ctrl-C or kill -INT (SIGINT))" in out  # the summary
    assert CLOSING_UNDER_WAY in err  # what the second one waits for
    ran = load_record(record)
    assert ran.ending is not None  # the end note
    assert ends_with_the_safe_stop(ran.outbound)
    try:  # root's open ignores the exclusive mode: its TIOCGEXCL says it
        probe = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError as exc:
        pytest.fail(f"the port is refused after the run: {exc}")
    try:
        assert not in_exclusive_mode(probe)  # closed as a port: the next run may open it
    finally:
        os.close(probe)
