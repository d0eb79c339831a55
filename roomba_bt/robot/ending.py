"""How a connection ends: what the safe stop sends, and what the robot was last seen doing.

Every ending (:meth:`~roomba_bt.robot.connection.Connection.close`, the context manager,
:meth:`~roomba_bt.robot.connection.Connection.safe_stop`) sends, from the mode the model
holds::

    [131]                 Safe, only in Passive while a Clean/Spot/Max/Seek Dock cycle may
                          be driving (drive 0 is not accepted in Passive; Safe ends the cycle)
    [137][0][0][0][0]     drive 0            } only while the model is in Safe or Full: in
    [138][0]              motors off         } Passive and Off the robot refuses actuators
    [150][0]              pause the stream
    [128]  or  [173]      Start (back to Passive) or, with end_in="stop" where the profile
                          has it, Stop (Off)

A stop that cannot be delivered is reported with :func:`describe_activity` of the last wheel
command written ("last seen in Safe at 200 mm/s; ...").
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator
from typing import Literal

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import Effect
from roomba_bt.oi.profiles import RobotProfile

EndMode = Literal["passive", "stop"]


def stop_sequence(
    mode: OIMode, *, builtin_may_run: bool, end_in: EndMode, profile: RobotProfile
) -> list[Command]:
    """What the safe stop sends from ``mode`` (see the module docstring)."""
    if mode is OIMode.OFF:
        return []
    commands: list[Command] = []
    if mode is OIMode.PASSIVE and builtin_may_run:
        # Clean, Spot, Max or Seek Dock drive the robot in Passive, where drive 0 is not
        # accepted; Safe (131) ends the cycle and makes drive 0 and motors off possible.
        commands.append(oi.safe())
        mode = OIMode.SAFE
    if mode in DRIVING_MODES:
        commands += [oi.halt(), oi.motors_off()]
    commands.append(oi.pause_stream())
    use_stop = end_in == "stop" and profile.has_command("stop")
    commands.append(oi.stop() if use_stop else oi.start())
    return commands


def describe_activity(command: Command | None) -> str:
    """What the last wheel command written had the robot doing: ``at 200 mm/s``,
    ``stopped``, ``in its Clean cycle``."""
    if command is None:
        return "with its wheels never commanded"
    spec = command.spec
    if spec.effect is Effect.BUILTIN_CYCLE:
        return f"in its {spec.title} cycle"
    if not any(command.args):
        return "stopped"
    if spec.name == "drive":
        velocity, radius = command.args
        if radius in (1, -1):  # the spec's turn in place
            return f"spinning {'left' if radius == 1 else 'right'} at {velocity} mm/s"
        turning = "" if radius in (-32768, 32767) else f", radius {radius} mm"
        return f"at {velocity} mm/s{turning}"
    values = ", ".join(
        f"{arg.name} {value} {arg.unit}".rstrip()
        for arg, value in zip(spec.args, command.args, strict=True)
    )
    return f"after {spec.name} ({values})"


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM while a stop sequence is written, so it leaves whole."""
    blockable = {signal.SIGINT, signal.SIGTERM}
    try:
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blockable)
    except (AttributeError, OSError, ValueError):  # not POSIX: nothing to hold
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)
