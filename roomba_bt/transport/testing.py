"""Transports for tests and benchmarks: no port, no robot, a clock only the caller moves.

:class:`NullTransport` takes bytes and drops them and never has any to read: what a
:class:`~roomba_bt.robot.connection.Connection` costs, or refuses, with nothing on the line.
:class:`WriteLogTransport` also keeps every write, for tests that look at the wire (not
:class:`~roomba_bt.runtime.recording.RecordingTransport`, which records a run for ``--record``).
Subclasses give ``read`` something to hand out (a benchmark's stream frames).

They ship in the package, beside the contract they honour, the way
:mod:`roomba_bt.robot.testing` ships the robot handle that behaviour tests tick against: the
test suite and ``bench/`` use the same double, and neither has to import the other (the
tests' folders are not an importable package once installed).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from roomba_bt._lazy import moved_names

__all__ = ["NullTransport", "WriteLogTransport"]


class NullTransport:
    """A :class:`~roomba_bt.transport.base.Transport` with nothing at the far end.

    ``write`` drops the bytes, ``read`` returns ``b""`` at once, ``set_baud`` has no port to
    change; ``now()`` is :attr:`clock`, 0.0 until the caller (or a subclass) moves it.
    """

    name = "null"

    def __init__(self) -> None:
        self.clock = 0.0
        self.is_open = True

    def write(self, data: bytes) -> None:
        """Nobody listens: the bytes are dropped."""

    def read(self, timeout: float) -> bytes:
        return b""

    def set_baud(self, baud: int) -> None:
        """No port, so no rate to change."""

    def close(self) -> None:
        self.is_open = False

    def now(self) -> float:
        return self.clock


class WriteLogTransport(NullTransport):
    """A :class:`NullTransport` that keeps each write, as written, in :attr:`writes`."""

    name = "recording"

    def __init__(self) -> None:
        super().__init__()
        self.writes: list[bytes] = []

    def write(self, data: bytes) -> None:
        self.writes.append(bytes(data))


#: ``RecordingTransport``, :class:`WriteLogTransport`'s old name, the same as ``--record``'s
#: :class:`~roomba_bt.runtime.recording.RecordingTransport` (a file of the run's bytes, not a
#: list): kept for the tests of plugins that import it so, with a DeprecationWarning until 0.3.0
if not TYPE_CHECKING:  # to a type checker the old name is gone, and a typo no Any (PEP 562)
    __getattr__ = moved_names(
        __name__, {"RecordingTransport": "roomba_bt.transport.testing:WriteLogTransport"}
    )
