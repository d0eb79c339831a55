"""The far end of ``run`` and ``sensors``: a robot's serial port, or the built-in simulator
when no ``--port`` is given.

Either way the result is a :class:`~roomba_bt.transport.Transport`, and everything above it
(connection, runner, display, record) is the same code. ``--fast`` uses
:class:`roomba_bt.sim.SimLink` as is: every read advances the virtual clock, as fast as the
host computes. Without it, :class:`roomba_bt.sim.RealtimeSimLink` paces the same simulator to
the wall clock.
"""

from __future__ import annotations

from dataclasses import replace

from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.robot.connection import OPEN_CAUSES
from roomba_bt.robot.errors import ConnectionFailed
from roomba_bt.sim import Faults, RealtimeSimLink, SimLink, Simulator, load_world
from roomba_bt.transport import SerialTransport, Transport, TransportError

DEFAULT_WORLD = "empty-room"


def open_port(url: str, baud: int) -> Transport:
    """The serial port (device path or pyserial URL) to a robot; :class:`ConnectionFailed`
    names the port and what to check if it cannot be opened."""
    try:
        return SerialTransport.open(url, baud)
    except TransportError as exc:
        raise ConnectionFailed(url, f"could not open the port ({exc.cause})", OPEN_CAUSES) from exc


def make_simulator(
    world: str | None,
    profile: RobotProfile,
    seed: int,
    *,
    random_start: bool = False,
    faults: Faults | None = None,
    coverage: bool = False,
    battery: float | None = None,
) -> Simulator:
    """A simulator in ``world`` (a shipped name or a path), its battery at ``battery`` (a
    fraction) instead of the world's if given; raises WorldError if invalid.
    ``coverage``: it tracks the floor cleaned (:mod:`roomba_bt.sim.coverage`)."""
    loaded = load_world(world or DEFAULT_WORLD)
    if battery is not None:
        loaded = replace(loaded, battery=battery)
    return Simulator(loaded, profile, seed, faults, random_start=random_start, coverage=coverage)


def make_link(simulator: Simulator, fast: bool) -> SimLink:
    """The virtual-clock link (``fast``) or the wall-clock one."""
    return SimLink(simulator) if fast else RealtimeSimLink(simulator)
