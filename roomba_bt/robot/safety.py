"""Turning SIGTERM into an exception, so that ``with Connection(...)`` stops the robot.

Python turns SIGINT into :class:`KeyboardInterrupt`, which unwinds ``with`` blocks and so runs
:meth:`~roomba_bt.robot.connection.Connection.close`. SIGTERM (``kill``, systemd, a container
stopping) would end the process without unwinding anything and leave the robot driving in
Safe mode. Inside :func:`sigterm_raises` it raises :class:`Terminated` instead; the previous
handler comes back on the way out.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
from collections.abc import Iterator
from types import FrameType

log = logging.getLogger(__name__)


class Terminated(KeyboardInterrupt):
    """Raised in the main thread when SIGTERM arrives inside :func:`sigterm_raises`.

    A :class:`KeyboardInterrupt`, so whatever handles Ctrl-C (the CLI: exit code 130) handles
    it too, and ``except Exception`` does not swallow it.
    """

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        self.signum = signum
        super().__init__(f"terminated by signal {signal.Signals(signum).name}")


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated`; the old handler is restored.

    Signal handlers belong to the main thread: elsewhere this does nothing (and says so).
    """
    if threading.current_thread() is not threading.main_thread():
        log.debug("sigterm_raises() outside the main thread: SIGTERM left as it is")
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
