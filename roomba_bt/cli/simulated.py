"""The built-in simulator as the far end of ``run`` when no ``--port`` is given.

``--fast`` uses :class:`roomba_bt.sim.SimLink` as is: every read advances the virtual clock, as
fast as the host computes. Without it, :class:`RealtimeSimLink` paces the same simulator to the
wall clock (one 15 ms step per 15 ms of wall time), so a run looks and feels like a robot.
Both carry the same bytes through the same connection code as a serial port.
"""

from __future__ import annotations

import time

from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.sim import Faults, SimLink, Simulator, load_world
from roomba_bt.sim.robot import STEP_SECONDS


class RealtimeSimLink(SimLink):
    """A :class:`SimLink` whose simulated time never runs ahead of the wall clock."""

    def __init__(self, simulator: Simulator, name: str = "sim://") -> None:
        super().__init__(simulator, name)
        self._wall0 = time.monotonic()
        self._sim0 = simulator.time

    def read(self, timeout: float) -> bytes:
        self._check()
        sim = self.simulator
        data = sim.read()
        if data:
            return data
        deadline = time.monotonic() + max(timeout, 0.0)
        while True:
            due = self._wall0 + (sim.time + STEP_SECONDS - self._sim0)
            now = time.monotonic()
            if due > deadline:
                if deadline > now:
                    time.sleep(deadline - now)
                return b""
            if due > now:
                time.sleep(due - now)
            sim.step()
            if sim.disconnected:
                raise ConnectionError(f"{self.name}: simulated disconnect at t={sim.time:.3f} s")
            data = sim.read()
            if data:
                return data


DEFAULT_WORLD = "empty-room"


def make_simulator(
    world: str | None,
    profile: RobotProfile,
    seed: int,
    *,
    random_start: bool = False,
    faults: Faults | None = None,
) -> Simulator:
    """A simulator in ``world`` (a shipped name or a path); raises WorldError if invalid."""
    loaded = load_world(world or DEFAULT_WORLD)
    return Simulator(loaded, profile, seed, faults, random_start=random_start)


def make_link(simulator: Simulator, fast: bool) -> SimLink:
    return SimLink(simulator) if fast else RealtimeSimLink(simulator)
