"""A stream that went silent mid-run, asked for again within the grace.

A byte lost on its way to the robot can make a Pause Stream of a command's data (a Drive's
``96 00``, its opcode lost, read as ``[150][0]``), and a robot may stop its stream by itself.
Nothing comes then, the watchdog trips, and the run waited the grace and ended "the sensor
stream stopped" (exit 3), though the robot heard every byte after that one. Now, while the
watchdog's stall is ridden through and nothing at all arrives (not a byte: garbage is a
line's, :func:`~roomba_bt.robot.silence.follow_baud`'s), the stream is asked for again at a
third and at two thirds of the grace (:data:`STALL_ASKS`), as the start-up asks for a stream
that never came (``Connection._stream_again``): in one write, the zeros that end any wait a
lost byte left the robot's parser in (:func:`~roomba_bt.robot.startup.stream_zeros`), then
the request::

    last frame ── 100 ms: watchdog, drive 0 ── grace/3: [0]x35 [148][n][ids] ── 2 grace/3: again
      frames back: the stall ridden through, the mission goes on     none by the grace: its end

Nothing more is written on a clean run (no stall) nor during a stall of garbage or of frames
that come back before a third of the grace (a Wi-Fi bridge's holds of 100 ms). The stall
stays the one the watchdog tripped on, its silence counted from its last frame: the request
is the same stream's, written as its bytes (no new stream to the link, which would start
the grace again and count a second stall).

Each ask is noted in the run's record (``{"stream_again": 1, "silent": 0.667}``, at the link
time it was written), and a replay asks where its record did and nowhere else
(:attr:`StallAsks.replayed`): its reads come at other times on the record's clock, and a
record made before asks nowhere.
"""

from __future__ import annotations

import logging
from collections import deque
from typing import TYPE_CHECKING

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.startup import stream_zeros

if TYPE_CHECKING:
    from roomba_bt.robot.connection import Connection

log = logging.getLogger("roomba_bt.robot.connection")

#: How many times a stream silent mid-run is asked for again within one stall's grace, at
#: even steps of it: a request again of the dock mission's 23 packets arrives whole 78 % of
#: the time at 1 % of the bytes lost, two 95 %; a third would come too near the grace's end
#: for the stream to show before it.
STALL_ASKS = 2
#: The record's note of an ask (its number in the stall), for the replay
STREAM_AGAIN_NOTE = "stream_again"


class StallAsks:
    """A session's asks for a stream that went silent mid-run (the module docstring).

    ``replayed``: where a replay's record asked (link times, in order), or None on a live
    link, which asks by the grace."""

    def __init__(self) -> None:
        #: this session's asks, and the current stall's
        self.total = 0
        self.in_stall = 0
        self._stall_from: float | None = None  # the silence the current stall's asks are for
        self.replayed: deque[float] | None = None

    def due(self, silent_since: float, now: float, grace: float) -> bool:
        """Whether the stream is asked for again now, the line silent since ``silent_since``
        (``now - silent_since`` within ``grace``)."""
        if silent_since != self._stall_from:  # another stall
            self._stall_from, self.in_stall = silent_since, 0
        replayed = self.replayed
        if replayed is not None:
            while replayed and replayed[0] < silent_since:  # the replay went elsewhere
                replayed.popleft()
            if replayed and replayed[0] <= now:
                replayed.popleft()
                return True
            return False
        step = grace / (STALL_ASKS + 1)
        return self.in_stall < STALL_ASKS and now - silent_since >= (self.in_stall + 1) * step

    def said(self) -> str:
        """What the current stall's asks add to its cause when the stream did not come back
        ("" if there were none)."""
        if not self.in_stall:
            return ""
        times = "once" if self.in_stall == 1 else f"{self.in_stall} times"
        return (
            f"the stream was asked for again {times} within the grace (zeros, then the "
            "request), and nothing came"
        )


def ask_in_stall(connection: Connection, now: float, grace: float) -> None:
    """During a stall ridden through, the line silent (not a byte since the last frame): the
    stream asked for again if one is due (:meth:`StallAsks.due`), noted in the record, said
    once a run (later asks at INFO)."""
    link = connection.link
    asks = connection.stall_asks
    ids = link.stream_ids
    since = link.silent_since
    if not ids or connection.mode is OIMode.OFF or not asks.due(since, now, grace):
        return
    asks.in_stall += 1
    asks.total += 1
    note = getattr(link.transport, "note", None)  # a record's (run --record), for a replay
    if callable(note):
        note({STREAM_AGAIN_NOTE: asks.in_stall, "silent": round(now - since, 6)}, at=now)
    log.log(
        logging.WARNING if asks.total == 1 else logging.INFO,
        "%s: nothing has come for %.2f s: the sensor stream stopped (a byte lost on the way "
        "to the robot can make a Pause Stream of a command's data, or the robot stopped it); "
        "asking for it again (%d of %d in this stall)", connection.name, now - since,
        asks.in_stall, STALL_ASKS,
    )  # fmt: skip
    # the same stream asked for again: its bytes, not a new Stream (148) to the writer, whose
    # effect would start the link's stream afresh (the silence, the grace's measure, from
    # now, and the watchdog's trip ended: a second trip, a second stall)
    connection.writer.send_many((), prefix=stream_zeros(ids) + oi.stream(ids).data)
