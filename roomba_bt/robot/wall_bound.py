"""A bound in wall time on waits that end on the link's clock: the safe stop's last resort.

Every wait of the safe stop (the listening after it, a followed rate's quiet and Query List,
the port's backlog) reads until a time of the link's clock (``Transport.now``). A clock that
does not move as it reads never brings that time: a replay's, at its float's last bit, added
nothing for a wait of 3.6e-16 s, and the wait for a quiet line read for ever, the stop's
signals deferred (only SIGKILL ended it); a transport of one's own may keep its clock so. While
:func:`bounded` holds, the link's :meth:`~roomba_bt.robot.link.StreamLink.read` checks the
bound first, and one past it raises :class:`~roomba_bt.robot.errors.WaitCutShort`, said in
the stop's report. The tick's own read (``StreamLink.read_checked``) is never bounded.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING

from roomba_bt.robot.errors import WaitCutShort

if TYPE_CHECKING:
    from roomba_bt.robot.link import StreamLink
    from roomba_bt.transport.base import Transport


class WallBound:
    """``seconds`` of wall time from its making for the waits of ``what`` (words for the
    report: "the safe stop's wait for the robot"); :attr:`cut` says the first wait it gave
    up, or None."""

    def __init__(self, seconds: float, what: str) -> None:
        self.seconds = seconds
        self.what = what
        self.until = time.monotonic() + seconds
        self.cut: str | None = None

    def check(self, transport: Transport) -> None:
        """Raise :class:`WaitCutShort` once the bound has passed: each read after it does (a
        wait that caught the error and went on is cut again)."""
        if time.monotonic() <= self.until:
            return
        error = WaitCutShort(
            f"{self.what} was given up after {self.seconds:g} s of wall time: the link's "
            f"clock ({transport.name}, at {transport.now():.3f} s) did not bring its end"
        )
        if self.cut is None:
            self.cut = str(error)
        raise error


@contextlib.contextmanager
def bounded(link: StreamLink, seconds: float, what: str) -> Iterator[WallBound]:
    """Meanwhile the link's reads are bounded by ``seconds`` of wall time (:class:`WallBound`,
    yielded: its :attr:`~WallBound.cut` says whether a wait was given up)."""
    bound = link.wall_bound = WallBound(seconds, what)
    try:
        yield bound
    finally:
        link.wall_bound = None
