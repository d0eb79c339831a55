"""The byte-level contract every link to a robot honours, and its one error type.

A transport moves bytes and keeps a clock; it knows no opcodes. Three kinds implement it:
:class:`~roomba_bt.transport.serial_port.SerialTransport` (any ``serial_for_url`` URL), the
simulator's in-process link (virtual clock) and test doubles. The contract is structural
(:class:`typing.Protocol`), so the simulator need not import this package.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from roomba_bt.errors import RoombaBtError


class TransportError(ConnectionError, RoombaBtError):
    """The port could not be opened, read or written; names the port and the cause.

    A subclass of :class:`ConnectionError` (so of :class:`OSError`): code that catches "the
    link is gone" catches it together with the simulator's own ``ConnectionError``.
    """

    def __init__(self, port: str, action: str, cause: BaseException | str) -> None:
        self.port = port
        self.action = action
        self.cause = cause
        reason = cause if isinstance(cause, str) else (str(cause) or type(cause).__name__)
        super().__init__(f"{port}: could not {action}: {reason}")


@runtime_checkable
class Transport(Protocol):
    """Bytes in, bytes out, and the clock the bytes are timed against.

    * ``write`` sends all of ``data`` or raises (an :class:`OSError` subclass such as
      :class:`TransportError`, or ``serial.SerialException``); it never blocks unbounded.
    * ``read(timeout)`` returns what is available now; if nothing is, it waits up to
      ``timeout`` seconds for some, and returns ``b""`` if none came.
    * ``now()`` is this link's clock: :func:`time.monotonic` on real ports, the simulator's
      virtual time in-process. Frame arrival times and watchdogs use it, so the same code
      runs live and on a virtual clock.

    A transport whose clock is not the wall clock's pace says so with a class attribute
    ``wall_clock = False`` (the simulator's :class:`~roomba_bt.sim.SimLink`, a replay): it is
    not part of the protocol, and one without it is taken to run on the wall clock. The
    runner reads it to warn of wall-clock timers in a tree (py_trees' ``Timeout``).
    """

    name: str

    def write(self, data: bytes) -> None: ...

    def read(self, timeout: float) -> bytes: ...

    def set_baud(self, baud: int) -> None: ...

    def close(self) -> None: ...

    @property
    def is_open(self) -> bool: ...

    def now(self) -> float: ...
