"""A page's live updates: the pump that sends them, paced by the run's ticks.

Per page, a pump sends at most 20 updates a second: from the newest tick's end (the
ring's ``ended``) and the 15 ms between frames it knows when the first tick after its 50 ms
period ends, wakes 1 ms after that, then takes what the ring gained since it last sent,
merges it (the newest statuses, every node that flipped in between, the new events) and
sends one message. Its Python work (a few tenths of a millisecond) so falls in the ~15 ms the
tick thread sleeps until the next frame instead of holding the GIL when a frame arrives, and
it wakes once an update (it looked every 2 ms before: about 5 wake-ups an update, each one a
chance to want the GIL while a tick held it); a late tick is looked for every 2 ms. The tick
thread is never asked to wake the server: a wake-up from it (a
write to the loop's self-pipe) releases the GIL mid-``after_tick`` and cost it up to 0.4 ms
(measured). With no tick for 50 ms (a recorded run, a run that ended or is held) it sends
anyway. A page whose socket is slow holds up only its own pump; when it catches up, it is
sent the newest state and the ticks in between are lost to it, never to the robot. A page
that stopped reading (a lid closed) is held as soon as it leaves a ping unanswered for
:data:`BEHIND_S`, before the sockets' buffers fill with minutes of updates (:class:`Reading`).

The pump runs in the server's event loop (:mod:`.server`'s thread), one task per page's
socket (:mod:`.routes`' ``/ws``), and reads the feed's ring without a lock.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import time
from typing import TYPE_CHECKING, Any

from aiohttp import WSMessage, WSMsgType, web

from roomba_bt.monitor.views import path_view, session_view, state_view, tree_view
from roomba_bt.oi.frames import SLOT_SECONDS

if TYPE_CHECKING:
    from roomba_bt.monitor.feed import Ring, RunFeed, TickRecord
    from roomba_bt.monitor.session import MonitorSession

UPDATE_PERIOD_S = 0.05  # at most 20 updates a second per page
TICK_WAIT_S = 0.05  # the longest a pump waits for a tick's end before it sends anyway
TICK_POLL_S = 0.002  # how often it looks for that end when a tick is late
AFTER_TICK_S = 0.001  # how long after a tick's expected end the pump looks
#: the longest a page hears nothing: with nothing new (a record, a run that ended) the pump
#: sends an update anyway, so a page that hears nothing for longer knows its link is silent
#: (packets lost, the socket not closed: a train's tunnel) and says so
HEARTBEAT_S = 1.0
#: a page that has not answered the pump's ping for this long is behind (it stopped reading:
#: a laptop's lid closed, a phone's browser frozen in a pocket) and is sent nothing until it
#: answers: the sockets' buffers (megabytes on a loopback) held every update meanwhile, and a
#: page woken after a minute showed 26 s of minute-old updates in turn. Held, it reads at
#: most this long's updates on waking, then the newest state (the pump merges what it held)
BEHIND_S = 1.0
#: how often the pump pings a page to learn how far it has read (one ping in flight at most:
#: a browser answers at once, without its script, when it reads the frame)
PING_EVERY_S = 0.5
Socket = web.WebSocketResponse  # a page's


def next_look(ended: float, due: float, period: float = SLOT_SECONDS) -> float:
    """:data:`AFTER_TICK_S` after the first tick end at or after ``due``, ticks ending every
    ``period`` from ``ended`` (the newest tick's end)::

        ended        +15 ms       +30 ms       +45 ms   +60 ms
          |------------|------------|-----due----|x        x = the look
    """
    steps = max(1, math.ceil((due - ended - AFTER_TICK_S) / period))
    return ended + steps * period + AFTER_TICK_S


class Reading:
    """How far a page has read its socket, from the pump's pings (the WebSocket's own: the
    other end answers each with a pong when it reads it, after every message sent before it,
    a browser without its page's script). The pump sends an update only while the page keeps
    up; a write that blocks cannot tell, since the sockets' buffers take minutes of updates
    first. Used by the page's socket's handler (the pongs) and its pump, in the server's
    event loop alone."""

    def __init__(self) -> None:
        self._sent = 0  # the number of the last ping sent
        self._answered = 0  # the number of the last ping answered
        self._when = 0.0  # when the last ping was sent (the loop's clock)

    def answered(self, data: bytes) -> None:
        """A pong: its ping's number (another pong, a browser's unasked one, is ignored)."""
        with contextlib.suppress(ValueError):
            self._answered = max(self._answered, int(data))

    def behind(self, now: float) -> bool:
        """Whether the page has left a ping unanswered for :data:`BEHIND_S`."""
        return self._answered < self._sent and now - self._when > BEHIND_S

    async def caught_up(self) -> None:
        """Return once the page is not :meth:`behind` (at once, mostly): held meanwhile."""
        loop = asyncio.get_running_loop()
        while self.behind(loop.time()):
            await asyncio.sleep(UPDATE_PERIOD_S)

    async def send(self, ws: Socket, text: str) -> None:
        """``text`` sent, then a ping when one is due (none in flight, the last one
        :data:`PING_EVERY_S` ago)."""
        await ws.send_str(text)
        now = asyncio.get_running_loop().time()
        if self._answered < self._sent or now - self._when < PING_EVERY_S:
            return
        self._sent += 1
        self._when = now
        await ws.ping(str(self._sent).encode())

    async def heard(self, ws: Socket, message: WSMessage) -> None:
        """A message from the page: a pong noted, a ping of its own answered (autoping is
        off, so that the pongs reach :meth:`answered`)."""
        if message.type is WSMsgType.PONG:
            self.answered(message.data)
        elif message.type is WSMsgType.PING:
            await ws.pong(message.data)


def stamp() -> float:
    """The server's time for the ``sent`` of its messages, which a page echoes as a
    control's ``seen``: monotonic (a clock set meanwhile changes no age), to the ms."""
    return round(time.monotonic(), 3)


def merged_ticks(feed: RunFeed, records: list[TickRecord], *, again: bool) -> dict[str, Any]:
    """The ticks the ring gained since a page's last update, as one update's ``state`` and
    ``path``: the newest tick's state with every node that flipped in any of them (of its
    tree) marked ``changed``, and a path through eight of them at most and the newest.
    ``again``: the run's end, its newest tick sent once more, nothing flipped anew."""
    last = records[-1]
    _, earlier = feed.at(last.tick)
    state = state_view(feed, last, earlier)
    flipped = {i for r in records if r.tree == last.tree for i in r.changed}
    state["changed"] = [] if again else sorted(flipped)
    stride = max(1, len(records) // 8)
    return {"state": state, "path": path_view([] if again else [*records[:-1:stride], last])}


async def after_a_tick(ring: Ring, last_sent: float, reading: Reading) -> None:
    """Wait out the update period, then until just after a tick's end (the tick thread has
    recorded a tick and is about to sleep until the next frame), or :data:`TICK_WAIT_S`.

    Frames come every 15 ms, so ticks end every 15 ms: from the newest one's end
    (``ring.ended``) the pump sleeps until :data:`AFTER_TICK_S` after the first end due
    after its period, and wakes once, not every 2 ms, never in the middle of a tick that
    is on time. If no tick has just ended there (a late frame), it looks every
    :data:`TICK_POLL_S`; a run with no ticks (recorded, ended) is sent after the period."""
    await reading.caught_up()  # first, a page that stopped reading is held
    loop = asyncio.get_running_loop()
    due = last_sent + UPDATE_PERIOD_S
    ticking = loop.time() - ring.ended < TICK_WAIT_S
    look = next_look(ring.ended, due) if ticking else due
    await asyncio.sleep(max(look - loop.time(), 0.0))
    give_up, seen = loop.time() + TICK_WAIT_S, ring.count
    while loop.time() < give_up:
        if ticking and loop.time() - ring.ended < AFTER_TICK_S + TICK_POLL_S:
            return  # a tick has just ended
        if not ticking and ring.count != seen:
            return
        await asyncio.sleep(TICK_POLL_S)


async def pump(
    ws: Socket,
    hello: dict[str, Any],
    reading: Reading,
    feed: RunFeed,
    session: MonitorSession | None,
) -> None:
    """One page's updates, until its socket closes: ``hello`` first, then an update after
    each period's tick (:func:`after_a_tick`) with what the ring gained since the last one
    merged, or a heartbeat; ``reading`` paces it to how far the page has read."""
    loop = asyncio.get_running_loop()
    latest = feed.latest()
    seq = latest.seq if latest else 0
    event_seq = -1
    generation = -1
    sent_session: dict[str, Any] | None = None
    finished: str | None = None
    await ws.send_str(json.dumps({**hello, "sent": stamp()}))
    heard = loop.time()  # when the page was last sent a message
    while not ws.closed:
        last_sent = loop.time()
        records = feed.ring.since(seq)
        new_events = [e._asdict() for e in feed.events_after(event_seq)]
        now_session = session_view(session)
        if (
            records
            or new_events
            or now_session != sent_session
            or feed.finished != finished
            or last_sent - heard >= HEARTBEAT_S  # nothing new: the page hears the link
        ):
            message: dict[str, Any] = {"type": "update", "session": now_session}
            # the run has ended since: its newest tick again, as the safe stop left the
            # robot (no tick shows that: views.after_the_end), nothing flipped anew
            again = not records and feed.finished != finished and feed.ending is not None
            if again and (newest := feed.latest()) is not None:
                records = [newest]
            if records:
                last = records[-1]
                message.update(merged_ticks(feed, records, again=again))
                if last.tree != generation:
                    generation = last.tree
                    message["tree"] = tree_view(feed, last.tree)
                seq = last.seq + 1
            first, newest = feed.window()
            message["window"] = [first.tick if first else 0, newest.tick if newest else 0]
            if new_events:
                message["events"] = new_events
                event_seq = new_events[-1]["seq"]
            message["no_end"] = feed.no_end  # read before finished: end() sets it first
            message["finished"] = finished = feed.finished
            message["sent"] = stamp()
            sent_session = now_session
            try:
                await reading.send(ws, json.dumps(message))
            except (ConnectionResetError, RuntimeError):
                return
            heard = loop.time()
        await after_a_tick(feed.ring, last_sent, reading)
