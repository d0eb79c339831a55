"""The robot connection: mode model, guarded command path, safety on every exit.

:class:`Connection` (the session: start-up, guard, batching, safe stop) speaks to one robot
through a :class:`StreamLink` (bytes, the stream parser, the watchdog) over any
:class:`~roomba_bt.transport.Transport`;
:class:`ModeModel` is its ``transitions`` model of the OI modes and the guard of every
command; :mod:`~roomba_bt.robot.interface` is the contract with the behaviours above.
"""

from roomba_bt.robot.connection import Connection, LinkCounters
from roomba_bt.robot.errors import (
    ConnectionFailed,
    LinkDown,
    ModeError,
    PortLost,
    RobotError,
    StreamStalled,
)
from roomba_bt.robot.interface import ModeChange, Odometry, Outbox, RobotHandle, Snapshot
from roomba_bt.robot.link import LinkStatus, StreamLink, TimedFrame
from roomba_bt.robot.modes import ModeModel, infer_cause
from roomba_bt.robot.safety import Terminated, sigterm_raises

__all__ = [
    "Connection",
    "ConnectionFailed",
    "LinkCounters",
    "LinkDown",
    "LinkStatus",
    "ModeChange",
    "ModeError",
    "ModeModel",
    "Odometry",
    "Outbox",
    "PortLost",
    "RobotError",
    "RobotHandle",
    "Snapshot",
    "StreamLink",
    "StreamStalled",
    "Terminated",
    "TimedFrame",
    "infer_cause",
    "sigterm_raises",
]
