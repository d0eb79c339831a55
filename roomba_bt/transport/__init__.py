"""Bytes to and from a robot: the :class:`Transport` contract and the pyserial transport.

This layer knows no opcodes; :mod:`roomba_bt.robot` gives the bytes their meaning.
"""

from roomba_bt.transport.base import Transport, TransportError
from roomba_bt.transport.serial_port import (
    DEFAULT_BAUD,
    DEFAULT_WRITE_TIMEOUT,
    SerialTransport,
    open_transport,
)

__all__ = [
    "DEFAULT_BAUD",
    "DEFAULT_WRITE_TIMEOUT",
    "SerialTransport",
    "Transport",
    "TransportError",
    "open_transport",
]
