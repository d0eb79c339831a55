"""The built-in simulator as the far end of ``run`` and ``sensors`` when no ``--port`` is given.

``--fast`` uses :class:`roomba_bt.sim.SimLink` as is: every read advances the virtual clock, as
fast as the host computes. Without it, :class:`roomba_bt.sim.RealtimeSimLink` paces the same
simulator to the wall clock. Both carry the same bytes through the same connection code as a
serial port.
"""

from __future__ import annotations

from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.sim import Faults, RealtimeSimLink, SimLink, Simulator, load_world

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
    """The virtual-clock link (``fast``) or the wall-clock one."""
    return SimLink(simulator) if fast else RealtimeSimLink(simulator)
