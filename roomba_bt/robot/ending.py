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
command written ("last seen in Safe at 200 mm/s; ..."). :class:`SafeStop` is the session's
part that does it: it writes the sequence through the session's
:class:`~roomba_bt.robot.writer.CommandWriter` (whole: SIGINT/SIGTERM held meanwhile) and
keeps whether the stop reached the robot.
"""

from __future__ import annotations

import contextlib
import logging
import signal
from collections.abc import Iterator
from typing import Literal

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import STRAIGHT_RADII, Command
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import Effect
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.robot.errors import PortLost, RobotError
from roomba_bt.robot.link import LINK_ERRORS, LinkStatus
from roomba_bt.robot.safety import ENDING_SIGNALS
from roomba_bt.robot.wake import KeepAwake
from roomba_bt.robot.writer import CommandWriter

log = logging.getLogger(__name__)

EndMode = Literal["passive", "stop"]

#: What a stop may meet and must survive.
_RECOVERABLE: tuple[type[Exception], ...] = (RobotError, *LINK_ERRORS)


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
        turning = "" if radius in STRAIGHT_RADII else f", radius {radius} mm"
        return f"at {velocity} mm/s{turning}"
    values = ", ".join(
        f"{arg.name} {value} {arg.unit}".rstrip()
        for arg, value in zip(spec.args, command.args, strict=True)
    )
    return f"after {spec.name} ({values})"


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold the signals that end a run (:data:`~roomba_bt.robot.safety.ENDING_SIGNALS`)
    while a stop sequence is written, so it leaves whole."""
    blockable = set(ENDING_SIGNALS)
    try:
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blockable)
    except (AttributeError, OSError, ValueError):  # not POSIX: nothing to hold
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


class SafeStop:
    """The endings of one session: the stop sequence written whole from the mode the model
    holds, whether it reached the robot, and the port closed once.

    ``safe_stopped``: True once a stop is known sent, False when one failed (``stop_report``
    then says why, with what the robot was last seen doing), None before any ending.
    ``unheard``: why a stop written now could not be known to arrive (the robot no longer
    answers, or the line is garbled), or None.
    """

    def __init__(self, writer: CommandWriter, end_in: EndMode) -> None:
        self.writer = writer
        self.end_in: EndMode = end_in
        self.safe_stopped: bool | None = None
        self.stop_report: str | None = None
        self.unheard: str | None = None
        self.closed = False

    def begin(self) -> None:
        """A session starts (again): nothing has ended."""
        self.closed = False
        self.safe_stopped = None
        self.unheard = None

    def sequence(self) -> list[Command]:
        """What :meth:`stop` sends from the current mode (:func:`stop_sequence`)."""
        writer = self.writer
        return stop_sequence(
            writer.modes.mode, builtin_may_run=writer.builtin_may_run, end_in=self.end_in,
            profile=writer.profile,
        )  # fmt: skip

    def stop(self) -> bool:
        """Stop the robot and leave it in Passive (or Off with ``end_in="stop"``); never
        raises for a dead link (False, and the stop report logged)."""
        link = self.writer.link
        if self.writer.modes.mode is OIMode.OFF:  # never started (or ended in Off by Stop):
            self.safe_stopped = True  # nothing written, nothing to stop; not "unconfirmed"
            return True
        if not link.transport.is_open:
            return self._undelivered("the stop was not delivered: the port is gone")
        lost = link.status is LinkStatus.LOST
        try:
            with signals_deferred():
                self.writer.send_many(self.sequence())
        except PortLost:
            return self._undelivered("the stop was not delivered: the port is gone")
        except _RECOVERABLE as exc:
            return self._undelivered(f"the stop was not delivered: {exc}")
        if lost:
            return self._undelivered(
                "the stop was written but is unconfirmed: the port had failed before it"
            )
        if self.unheard is not None:
            return self._undelivered(f"the stop was written but is unconfirmed: {self.unheard}")
        if link.bytes_read == 0:  # written for a robot that may hear and not answer (TX cut)
            return self._undelivered(
                "the stop was written but is unconfirmed: the robot never answered"
            )
        link.streaming = False
        link.status = LinkStatus.STOPPED
        self.safe_stopped = True
        return True

    def activity(self) -> str:
        """What the last wheel command written had the robot doing (:func:`describe_activity`)."""
        return describe_activity(self.writer.last_wheels)

    def _undelivered(self, why: str) -> bool:
        """The stop did not reach the robot: say so, with what the robot was last seen
        doing; False (what :meth:`stop` returns)."""
        writer = self.writer
        # never told to move and seen in Passive, or never seen at all: nothing was left
        # driving (``sensors``, ``doctor``); the summary or the error says the port's fate
        idle = writer.last_wheels is None and (
            writer.link.bytes_read == 0 or writer.modes.mode is OIMode.PASSIVE
        )
        level = logging.DEBUG if idle else logging.ERROR
        if writer.link.bytes_read == 0:  # nothing was ever seen of it
            report = why
        else:
            report = f"last seen in {writer.modes.mode.label} {self.activity()}; {why}"
        if report != self.stop_report:  # close() tries once more: said once, not twice
            log.log(level, "%s: %s", self.writer.link.name, report)
        self.stop_report = report
        self.safe_stopped = False
        return False

    def close(self, wake: KeepAwake | None) -> bool:
        """Stop (once), release keep-awake, close the port. True if the robot was stopped
        (or never started); idempotent."""
        if self.closed:
            return bool(self.safe_stopped)
        self.closed = True
        stopped = True
        if self.safe_stopped is True:
            pass  # already stopped: a second stop sequence would only add bytes
        elif self.writer.modes.mode is not OIMode.OFF:  # stop() reports a port already gone
            stopped = self.stop()
        if wake is not None:
            with contextlib.suppress(*LINK_ERRORS):
                wake.release()
        link = self.writer.link
        link.transport.close()
        link.status = LinkStatus.CLOSED
        if self.safe_stopped is None:
            self.safe_stopped = stopped
        return stopped
