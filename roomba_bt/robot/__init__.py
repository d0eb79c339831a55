"""The robot connection: mode model, guarded command path, safety on every exit.

:class:`Connection` (the session: start-up, guard, batching, safe stop) speaks to one robot
through a :class:`StreamLink` (bytes, the stream parser, the watchdog) over any
:class:`~roomba_bt.transport.Transport`;
:class:`ModeModel` is its ``transitions`` model of the OI modes and the guard of every
command; :mod:`~roomba_bt.robot.interface` is the contract with the behaviours above.

The names below are imported from their modules when first asked for (a module
``__getattr__``): every behaviour imports :mod:`~roomba_bt.robot.interface`, and importing it
runs this file, which would otherwise load the connection, the mode model (``transitions``)
and the serial transport too, about 45 M instructions that ``roomba-bt validate`` and a
mission's compile never use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from roomba_bt._lazy import lazy_exports

if TYPE_CHECKING:
    from roomba_bt.robot.connection import Connection, LinkCounters
    from roomba_bt.robot.errors import (
        ConnectionClosed,
        ConnectionFailed,
        LinkDown,
        ModeError,
        NoAnswer,
        PortLost,
        RobotError,
        StreamStalled,
    )
    from roomba_bt.robot.interface import (
        ModeChange,
        Odometer,
        Odometry,
        Outbox,
        RobotHandle,
        Snapshot,
    )
    from roomba_bt.robot.link import LinkStatus, StreamLink, TimedFrame
    from roomba_bt.robot.modes import ModeModel, infer_cause
    from roomba_bt.robot.safety import Terminated, sigterm_raises

__all__ = [
    "Connection",
    "ConnectionClosed",
    "ConnectionFailed",
    "LinkCounters",
    "LinkDown",
    "LinkStatus",
    "ModeChange",
    "ModeError",
    "ModeModel",
    "NoAnswer",
    "Odometer",
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

#: the module of this package that defines each name of :data:`__all__`
_MODULE_OF: dict[str, str] = {
    **dict.fromkeys(("Connection", "LinkCounters"), "connection"),
    **dict.fromkeys(
        (
            "ConnectionClosed",
            "ConnectionFailed",
            "LinkDown",
            "ModeError",
            "NoAnswer",
            "PortLost",
            "RobotError",
            "StreamStalled",
        ),
        "errors",
    ),
    **dict.fromkeys(
        ("ModeChange", "Odometer", "Odometry", "Outbox", "RobotHandle", "Snapshot"), "interface"
    ),
    **dict.fromkeys(("LinkStatus", "StreamLink", "TimedFrame"), "link"),
    **dict.fromkeys(("ModeModel", "infer_cause"), "modes"),
    **dict.fromkeys(("Terminated", "sigterm_raises"), "safety"),
}


__getattr__, __dir__ = lazy_exports(__name__, _MODULE_OF)
