"""The simulator as a contract-suite backend: in process through ``SimLink`` (virtual clock),
and as ``roomba-bt sim --pty`` in a child process (real time, a real pty).

In process, :class:`SimRobot` gives the tests the same handle a :class:`FakeRobot` does:
every byte the connection wrote, each command with the simulator's mode when it arrived,
a fall to Passive (the robot drops off a ledge: wheel drop), a silent stream and a hang-up.
Everything runs in the caller's thread, so ``wait_until`` only has to look once.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import pathlib
import signal
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from roomba_bt.oi.encode import decode_command
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.profiles import RobotProfile

from .fake_robot import Received

ROOT = pathlib.Path(__file__).resolve().parents[2]


def simulator_missing() -> str | None:
    """Why the simulator backends cannot run, or None if they can."""
    if importlib.util.find_spec("roomba_bt.sim") is None:
        return "roomba_bt.sim is not in the tree yet"
    try:
        from roomba_bt.sim import SimLink, Simulator, load_world  # noqa: F401
    except ImportError as exc:
        return f"roomba_bt.sim does not import: {exc}"
    return None


class RecordingSimLink:
    """A SimLink that records what the host wrote and can withhold the stream ("muted")."""

    def __init__(self, link: Any) -> None:
        self.link = link
        self.name: str = link.name
        self.muted = False
        self.received = bytearray()
        self.commands: list[Received] = []
        self._pending = bytearray()

    @property
    def simulator(self) -> Any:
        return self.link.simulator

    @property
    def baud(self) -> int:
        return int(self.link.baud)

    @property
    def is_open(self) -> bool:
        return bool(self.link.is_open)

    def write(self, data: bytes) -> None:
        self.received += data
        self._pending += data
        while (decoded := decode_command(self._pending)) is not None:
            command, size = decoded
            del self._pending[:size]
            sim = self.simulator
            self.commands.append(Received(sim.mode, command, sim.time))
            self.link.write(command.data)

    def read(self, timeout: float) -> bytes:
        data: bytes = self.link.read(timeout)
        return b"" if self.muted else data

    def set_baud(self, baud: int) -> None:
        self.link.set_baud(baud)

    def close(self) -> None:
        self.link.close()

    def now(self) -> float:
        return float(self.link.now())


class SimRobot:
    """The in-process simulator behind the FakeRobot interface the contract tests use."""

    def __init__(self, link: RecordingSimLink) -> None:
        self.link = link
        self.closed = threading.Event()

    @property
    def received(self) -> bytearray:
        return self.link.received

    @property
    def commands(self) -> list[Received]:
        return self.link.commands

    @property
    def mode(self) -> OIMode:
        return OIMode(self.link.simulator.mode)

    @property
    def muted(self) -> bool:
        return self.link.muted

    @muted.setter
    def muted(self, value: bool) -> None:
        self.link.muted = value

    def opcodes(self) -> list[int]:
        return [r.command.opcode for r in self.commands]

    def wait_until(self, predicate: Callable[[Any], bool], timeout: float = 5.0) -> bool:
        return bool(predicate(self))

    def fall_to_passive(self, values: dict[int, int]) -> None:
        if not values.get(7, 0) & 0b1100 or len(values) > 1:
            pytest.skip("the simulator scripts a fall only as a wheel drop")
        self.link.simulator._fall()  # drops off a ledge: both wheel drops, Safe -> Passive

    def set_values(self, values: dict[int, int]) -> None:
        pytest.skip("the simulator's sensor values come from its world")

    def hang_up(self) -> None:
        self.link.simulator.disconnected = True
        self.closed.set()

    def stop(self) -> None:
        self.closed.set()

    def actuator_commands_outside_safe_or_full(self) -> list[Received]:
        return [
            r
            for r in self.commands
            if r.command.spec.modes <= DRIVING_MODES and r.mode not in DRIVING_MODES
        ]


def make_sim_link(profile: RobotProfile) -> tuple[RecordingSimLink, SimRobot]:
    from roomba_bt.sim import SimLink, Simulator, load_world

    simulator = Simulator(load_world("empty-room"), profile, seed=1)
    link = RecordingSimLink(SimLink(simulator))
    return link, SimRobot(link)


@contextlib.contextmanager
def sim_pty_server(profile: RobotProfile) -> Iterator[str]:
    """``roomba-bt sim --pty`` in a child process; yields the pty path it prints."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", "sim", "--pty", "--profile", profile.name],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert child.stdout is not None
        address = child.stdout.readline().strip()
        if not address:
            _, err = child.communicate(timeout=10)
            pytest.fail(f"roomba-bt sim --pty printed no address: {err}")
        yield address
    finally:
        if child.poll() is None:
            child.send_signal(signal.SIGINT)
            try:
                child.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                child.kill()
                child.communicate()
