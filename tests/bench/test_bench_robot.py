"""``python -m bench.bench_robot`` says its figures and nothing else: its connections have no
robot, and they end without the warnings a robot's would deserve (tests/robot checks those)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from bench.bench_robot import _StreamTransport
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection

ROOT = Path(__file__).resolve().parents[2]


def test_the_bench_prints_its_figures_and_no_warning() -> None:
    """It printed the safe stop's check on its streaming transport ("the stop was written 2
    times but not received"), "the robot never answered", "the port is gone" and "dropped
    without close()" for each of its connections."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-m", "bench.bench_robot"], cwd=ROOT, env=env, capture_output=True,
        text=True, timeout=300, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert "Connection.poll, 1 frame" in done.stdout and "pty      guard + write" in done.stdout


def test_a_stop_on_its_streaming_transport_is_heard_on_the_stream_s_evidence() -> None:
    """It streamed on whatever was written: the safe stop's check found frames after Pause
    Stream and said the stop not received. It stops streaming there, as a robot does."""
    ids = (7, 35)
    frame = layout_for(ids, CREATE2, True).stream_frame({35: 2})
    connection = Connection(_StreamTransport(frame), watchdog=0.1)
    connection.send_many([oi.start(), oi.safe(), oi.stream(ids)])
    connection.modes.detector.offset = 0  # as in the bench
    assert connection.poll(0.0)
    assert connection.close()
    assert connection.stop_report is None
