"""The simulator as a contract-suite backend: in process through ``SimLink`` (virtual clock),
and as ``roomba-bt sim --pty`` in a child process (real time, a real pty).

In process, :class:`SimRobot` gives the tests the same handle a :class:`FakeRobot` does:
every byte the connection wrote, each command with the simulator's mode when it arrived,
a fall to Passive (the robot drops off a ledge: wheel drop), a silent stream and a hang-up.
Everything runs in the caller's thread, so ``wait_until`` only has to look once.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from waits import HANG_S, line  # tests/waits.py: a hang's bound, a line within it

from roomba_bt.oi.encode import decode_command
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.sim import SimLink, Simulator, load_world

from .fake_robot import Received, RobotDouble

ROOT = pathlib.Path(__file__).resolve().parents[2]


class SimRobot(RobotDouble):
    """The in-process simulator behind the FakeRobot interface the contract tests use; its
    :attr:`link` is what the connection talks to."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__()
        self.simulator = simulator
        self.link = RecordingSimLink(self)

    @property
    def mode(self) -> OIMode:
        return OIMode(self.simulator.mode)

    def wait_until(self, predicate: Callable[[Any], bool], timeout: float = HANG_S) -> bool:
        return bool(predicate(self))

    def fall_to_passive(self, values: dict[int, int]) -> None:
        if not values.get(7, 0) & 0b1100 or len(values) > 1:
            pytest.skip("the simulator scripts a fall only as a wheel drop")
        self.simulator._fall()  # drops off a ledge: both wheel drops, Safe -> Passive

    def set_values(self, values: dict[int, int]) -> None:
        pytest.skip("the simulator's sensor values come from its world")

    def hang_up(self) -> None:
        self.simulator.disconnected = True
        self.closed.set()

    def stop(self) -> None:
        self.closed.set()


class RecordingSimLink(SimLink):
    """A SimLink that gives its robot every byte the host wrote and each command with the
    simulator's mode when it arrived, and withholds the stream while the robot is muted."""

    def __init__(self, robot: SimRobot) -> None:
        super().__init__(robot.simulator)
        self.robot = robot
        self._pending = bytearray()

    def write(self, data: bytes) -> None:
        self.robot.received += data
        self._pending += data
        while (decoded := decode_command(self._pending)) is not None:
            command, size = decoded
            del self._pending[:size]
            sim = self.simulator
            self.robot.commands.append(Received(sim.mode, command, sim.time))
            super().write(command.data)

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        return b"" if self.robot.muted else data


def make_sim_link(profile: RobotProfile) -> tuple[RecordingSimLink, SimRobot]:
    robot = SimRobot(Simulator(load_world("empty-room"), profile, seed=1))
    return robot.link, robot


@contextlib.contextmanager
def sim_pty_server(profile: RobotProfile, *options: str) -> Iterator[str]:
    """``roomba-bt sim --pty`` in a child process (with ``options``: faults); yields the pty
    path it prints."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "roomba_bt.cli",
            "sim",
            "--pty",
            "--profile",
            profile.name,
            *options,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert child.stdout is not None
        address = line(child.stdout, "roomba-bt sim --pty's address").strip()
        if not address:
            _, err = child.communicate(timeout=HANG_S)
            pytest.fail(f"roomba-bt sim --pty printed no address: {err}")
        yield address
    finally:
        if child.poll() is None:
            child.send_signal(signal.SIGINT)
            try:
                child.communicate(timeout=HANG_S)
            except subprocess.TimeoutExpired:
                child.kill()
                child.communicate(timeout=HANG_S)
