"""The robot connection: mode model, guarded command path, safety on every exit.

:class:`Connection` speaks to one robot over any :class:`~roomba_bt.transport.Transport`;
:class:`ModeModel` is its ``transitions`` model of the OI modes and the guard of every
command; :mod:`~roomba_bt.robot.interface` is the contract with the behaviours above.
"""

from roomba_bt.robot.connection import (
    Connection,
    GapCounter,
    LinkCounters,
    LinkStatus,
    ReconnectPolicy,
    TimedFrame,
)
from roomba_bt.robot.errors import (
    ConnectionFailed,
    LinkDown,
    ModeError,
    PortLost,
    RobotError,
    StreamStalled,
)
from roomba_bt.robot.interface import ModeChange, Odometry, Outbox, RobotHandle, Snapshot, StubRobot
from roomba_bt.robot.modes import ModeModel, infer_cause
from roomba_bt.robot.safety import Terminated, sigterm_raises

__all__ = [
    "Connection",
    "ConnectionFailed",
    "GapCounter",
    "LinkCounters",
    "LinkDown",
    "LinkStatus",
    "ModeChange",
    "ModeError",
    "ModeModel",
    "Odometry",
    "Outbox",
    "PortLost",
    "ReconnectPolicy",
    "RobotError",
    "RobotHandle",
    "Snapshot",
    "StreamStalled",
    "StubRobot",
    "Terminated",
    "TimedFrame",
    "infer_cause",
    "sigterm_raises",
]
