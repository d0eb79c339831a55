"""The safe stop over a link with latency, and after a tick that blocked: the frames the robot
sent before it heard the stop come after it was written, and are not the robot streaming on.

Over a real pty (and ``socket://``) with the simulator's latency fault: every run of a mission
that ended well said ``CONNECTION LOST (the safe stop did not reach the robot)``, exit 3, the
robot in Passive at 0/0; and the stop written again put Drive and Motors into a robot already
in Passive. A tick that blocked a second, then ended the tree, did the same: the frames queued
meanwhile were read after the stop and taken for a robot that had not heard it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as oi
from roomba_bt.runtime.recording import load_record

from .simrun import WAITS_FOR_THE_GUARD, write_mission

CLI = [sys.executable, "-m", "roomba_bt.cli"]
SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data
PAUSE_START = oi.pause_stream().data + oi.start().data

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pty")

#: brushes and vacuum on, a short arc, everything off, and the tree's own Passive at its end
BUSY = """
mission: busy
tree:
  sequence:
    - mode: safe
    - motors: {main_brush: true, side_brush: true, vacuum: true}
    - drive: {velocity: 200 mm/s, radius: -600 mm, duration: 0.5s}
    - stop: {motors: true}
    - mode: passive
"""

#: spins with the motors on; its second tick blocks until the tick guard has stopped the
#: wheels behind its back (at most the suite's hang bound), then fails: the frames of the
#: blocked time queue
BLOCKS = (
    '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


@declare("blocks", kind="action", sends=opcodes("drive", "motors"))
class Blocks(Action):
    """Spins with the motors on, then blocks a tick and fails."""

    def start(self):
        self.send(commands.motors(7))
        self.ticks = 0

    def update(self):
        self.send(commands.drive(200, 1))
        self.ticks += 1
        if self.ticks < 3:
            return Status.RUNNING
        wait_for_the_guard(self.robot)
        return Status.FAILURE
'''
    + WAITS_FOR_THE_GUARD
)

BLOCKING_MISSION = """
mission: blocking
plugins: [./blocks.py]
tree:
  sequence:
    - mode: safe
    - blocks
    - mode: passive
"""

#: the simulator's summary line: "... N ignored actuator commands, mode X, wheels L/R mm/s"
SIM_SUMMARY = re.compile(r"(\d+) ignored actuator commands, mode (\w+), wheels (-?\d+)/(-?\d+)")


def _run(port: str, mission: Path, record: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, "run", str(mission), "--port", port, "--record", str(record), "--display",
         "none", *extra],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip


def _robot_at_the_end(sim: Any) -> tuple[int, str, int, int]:
    """The simulator stopped: its actuator commands ignored (refused in the mode it was in),
    its mode and its wheels."""
    _, err = sim.stop()
    found = SIM_SUMMARY.search(err)
    assert found is not None, err
    ignored, mode, left, right = found.groups()
    return int(ignored), mode, int(left), int(right)


@pytest.mark.parametrize(
    ("serve", "latency"),
    [("--pty", "0.06"), ("--pty", "0.2"), ("--tcp", "0.2")],
    ids=["pty-60ms", "pty-200ms", "socket-200ms"],
)
def test_a_stop_over_a_link_with_latency_is_delivered_and_sent_once(
    served_sim: Callable[..., Any], tmp_path: Path, serve: str, latency: str
) -> None:
    """The frames on their way when Pause Stream was written came after it, more than three
    in the 0.15 s listened: "NOT DELIVERED", exit 3, and the stop written again from the mode
    those old frames read (Safe), Drive and Motors into a robot in Passive."""
    where = ["127.0.0.1:0"] if serve == "--tcp" else []
    sim = served_sim(serve, *where, "--latency", latency)
    record = tmp_path / "run.jsonl"
    result = _run(sim.address, write_mission(tmp_path, BUSY), record)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "NOT DELIVERED" not in result.stdout
    assert "safe stop    sent pause_resume_stream, start" in result.stdout
    assert "final mode   Passive" in result.stdout
    # the stop written once: the tree's Start, then the stop's Pause Stream and Start
    assert load_record(record).outbound.endswith(oi.start().data + PAUSE_START)
    assert _robot_at_the_end(sim) == (0, "Passive", 0, 0)


def test_a_tick_that_blocked_then_ended_the_tree_has_its_stop_delivered(
    served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    """The frames queued while the tick blocked were read after the stop, taken for a robot
    that had not heard it: exit 3 for a mission that failed (1), and the stop written again,
    Drive and Motors into a robot in Passive."""
    sim = served_sim("--pty")
    record = tmp_path / "run.jsonl"
    mission = write_mission(tmp_path, BLOCKING_MISSION, plugins={"blocks.py": BLOCKS})
    result = _run(sim.address, mission, record, "--allow-plugin-files")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILURE" in result.stdout
    assert "tick guard   1 slow tick(s)" in result.stdout
    assert "NOT DELIVERED" not in result.stdout
    assert "safe stop    sent drive, motors, pause_resume_stream, start" in result.stdout
    outbound = load_record(record).outbound
    assert outbound.endswith(SAFE_END) and outbound.count(SAFE_END) == 1
    # the guard's drive 0 and motors off while it blocked; the tick ended the tree: the
    # brushes and vacuum not set going again before the stop
    assert outbound.count(oi.halt().data + oi.motors_off().data) == 2  # the guard's, the stop's
    assert outbound.count(oi.motors(7).data) == 1
    assert _robot_at_the_end(sim) == (0, "Passive", 0, 0)
