"""The monitor's web server: the page, its live updates and the operator's controls.

aiohttp (the ``monitor`` extra) in a thread of its own with its own event loop: the tick loop
stays the main thread's, and the server reads the feed's ring (without a lock) when it
chooses. Per page, a pump sends at most 20 updates a second: from the newest tick's end (the
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
:data:`BEHIND_S`, before the sockets' buffers fill with minutes of updates (:class:`_Reading`).

Routes (all behind the token when one is set), each under ``/view/`` too: the view-only
link's pages, whose controls are off whatever the token, and whose cookie is their own::

    GET  /                the page (static/index.html); ``/?token=VIEW`` sends to ``/view/``
    GET  /static/NAME     its script and style, from the package
    GET  /ws              WebSocket: {"type": "hello", ...} then {"type": "update", ...},
                          at least one a second (:data:`HEARTBEAT_S`), each with "sent"
    GET  /api/state?tick=T  the run at tick T (timeline), with the path up to it
    POST /api/control     {"action": "pause"|"resume"|"step"|"stop"|"break"|"force",
                           "node": INDEX|NAME|PATH, "value": ..., "run": RUN_ID,
                           "seen": SENT}  (the last update's "sent": a resume, step or
                           force from a view over STALE_VIEW_S old is 409)
                           -> 202, or 400/401/403/409 (docs/monitor.md, HTTP API); a control
                           without the run id served now (the hello's header.run.id) is 409

Safety: on a loopback address no token is needed, and a request whose ``Host`` is not
127.0.0.1, localhost or [::1] (any port: a tunnel's) is refused (403: another site's name its DNS
points at 127.0.0.1, DNS rebinding); on any other, every request must carry the token printed
in the URL at start (``?token=``, the ``X-Monitor-Token`` header, or the cookie the page is
given), else 401 (none given) or 403 (wrong): a new token each run, or the operator's own
(``token=``: ``run --monitor-token``), which then guards a loopback address too. Where a
token is in force a second one, the view token (new each run, or ``view_token=``: ``run
--monitor-view-token``), opens the same page with its controls off (:mod:`.access`): the
hello says ``controls`` false and a control with it is 403, so a link shown to a class or
on a projector reads the run and drives nothing. On either, a
request whose ``Origin`` is not this server (a WebSocket, a control, a fetch from another
site's page) is refused (403), so another site open in the same browser can neither drive the
robot nor read the run.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import json
import logging
import math
import threading
import time
from collections.abc import Awaitable, Callable
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from aiohttp import WSCloseCode, WSMessage, WSMsgType, web

from roomba_bt.monitor.access import Access, Tokens
from roomba_bt.monitor.address import DEFAULT_PORT, is_loopback
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.session import ControlRefused, MonitorSession
from roomba_bt.monitor.views import header_view, path_view, run_view, state_view, tree_view
from roomba_bt.oi.frames import SLOT_SECONDS

log = logging.getLogger(__name__)

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
#: the longest ``start`` waits for the server to be bound: it waited 10 s, then gave the
#: page's URL (port 0 where 0 was asked) of a server that was not serving
START_WITHIN_S = 60.0
#: the longest ``close`` waits for the server's thread to end (the pages told the run ended,
#: up to 1 s each, and aiohttp's cleanup), its port free again. It waited 5 s and returned
#: with the thread still serving on a loaded machine, its port bound: a server started
#: again there was refused (address in use)
CLOSE_WITHIN_S = 60.0
#: how often the pump pings a page to learn how far it has read (one ping in flight at most:
#: a browser answers at once, without its script, when it reads the frame)
PING_EVERY_S = 0.5
#: the oldest view a control that sets the robot going may come from: a page stamps each
#: control with the ``sent`` of the last update it had (the server's clock: no clock of the
#: browser's is compared), and a resume, step or force sent from a page more than this behind
#: the run is refused. A Resume pressed 2 s into a network stall reached the run 60 s later
#: and set the robot cleaning unseen. A late pause, stop or breakpoint stops or holds the
#: robot: it is applied.
STALE_VIEW_S = 3.0
#: the controls that set the robot going, refused from a page :data:`STALE_VIEW_S` behind
MOTION_CONTROLS = frozenset({"resume", "step", "force"})
#: the login cookie's name, ``_PORT`` added (:func:`cookie_name`)
COOKIE = "roomba_bt_monitor"
#: where the view-only link's pages are (``/view/?token=VIEW``): their cookie is set for this
#: path alone, under a name of its own, so a view link opened in the operator's browser
#: leaves the control page's cookie as it was (one cookie for both made the control tab,
#: reloaded, view-only); and a page here has no controls, whichever token it holds
VIEW_PATH = "/view/"
#: a control with the view token: the link shared with a class opens no controls
VIEW_ONLY = (
    "view-only link: controls need the control link (the first monitor: URL the run printed, "
    "or --monitor-token)"
)
STATIC_TYPES = {".js": "text/javascript", ".css": "text/css", ".svg": "image/svg+xml"}
Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]
Socket = web.WebSocketResponse  # a page's


def cookie_name(request: web.Request, *, view: bool = False) -> str:
    """The login cookie's name for the port the browser asked (``roomba_bt_monitor_8765``;
    ``view``: the view-only pages', ``roomba_bt_monitor_view_8765``): a browser keeps one
    host's cookies together whatever the port, so two monitors on one host (a live run and
    a record's view, two robots) under one name took each other's cookie, and a reload of
    the other page got 403. The port of the ``Host`` header, the browser's own (a tunnel's
    local port, not the one this server bound); its scheme's default when it names none."""
    return f"{COOKIE}{'_view' if view else ''}_{request.url.port}"


def viewing(request: web.Request) -> bool:
    """Whether ``request`` is the view-only link's (its page, assets, socket or API, under
    :data:`VIEW_PATH`)."""
    return request.path.startswith(VIEW_PATH)


class _StartupFreeze:
    """``gc.freeze`` while a monitor serves, undone when the last one closes.

    Before the run: move every object alive (modules, aiohttp's, the mission's tree) out of
    the cyclic collector's sight. A run's first full collection walks every
    object start-up made, in whichever thread allocates at that moment, the tick thread most
    likely: 70-95 ms measured (60 000 ticks on the virtual clock with the monitor's feed; 69 ms
    without it), so one tick of the run overran by that much. Frozen, the full collection
    walks only what the run made since: 16 ms. Frozen objects are still freed when their last
    reference goes; only a reference cycle among them would outlive the run, so the freeze is
    the run's, not the process's: the last server to close calls ``gc.unfreeze`` (the objects
    go back to the oldest generation), and a library user's process is left as it was. If
    the process had frozen objects of its own before (``gc.get_freeze_count()`` above 0), it
    manages freezing itself: the monitor neither freezes nor unfreezes.

    No collection before the freeze: in ``roomba-bt run --monitor`` one found nothing to free
    at that point (0 objects, in 110 ms on a loaded machine: all start-up garbage was gone
    already), so it cost the run's start for nothing; in a long-lived process (a test suite,
    a notebook) it walked every object the process held (150 000 in the test suite: 72 ms of
    CPU at each monitor's start). Cyclic garbage alive at the freeze is only kept until the
    unfreeze, when the collector frees it as before.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._users = 0
        self._frozen = False

    def acquire(self) -> None:
        with self._lock:
            self._users += 1
            if self._users == 1 and gc.get_freeze_count() == 0:
                gc.freeze()
                self._frozen = True

    def release(self) -> None:
        with self._lock:
            self._users -= 1
            if self._users == 0 and self._frozen:
                gc.unfreeze()
                self._frozen = False


STARTUP_FREEZE = _StartupFreeze()


def next_look(ended: float, due: float, period: float = SLOT_SECONDS) -> float:
    """:data:`AFTER_TICK_S` after the first tick end at or after ``due``, ticks ending every
    ``period`` from ``ended`` (the newest tick's end)::

        ended        +15 ms       +30 ms       +45 ms   +60 ms
          |------------|------------|-----due----|x        x = the look
    """
    steps = max(1, math.ceil((due - ended - AFTER_TICK_S) / period))
    return ended + steps * period + AFTER_TICK_S


class _Reading:
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


def _error(status: int, message: str) -> web.Response:
    return web.json_response({"error": message}, status=status)


#: a browser's page for a link without its token, or with another run's (each run makes a
#: new one): the JSON error an API client gets read as a raw line on a phone, and named "the
#: URL printed when the run started", which a colleague sent the link never saw
NO_ENTRY_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width">
<title>roomba-bt monitor: {title}</title></head>
<body style="font-family: sans-serif; max-width: 36em; margin: 2em auto; padding: 0 1em">
<h1 style="font-size: 1.3em">{title}</h1>
<p>{what}</p>
<p>Ask whoever started the run for its link: each run makes a new one, so yesterday's
link, or a bookmark of it, does not open today's run.</p>
<p>For a bookmark that keeps working, the run is started with <code>--monitor-token</code>
(and <code>--monitor-view-token</code> for the view-only link).</p>
</body></html>
"""
#: the page's title and first line for a link without a token (401) and with a wrong one (403)
NO_ENTRY = {
    401: (
        "This link has no token",
        "This address needs the token of the run's link (it ends in <code>?token=...</code>).",
    ),
    403: (
        "This link is for another run or has expired",
        "The token in this link (or in the cookie of an earlier visit) is not this run's.",
    ),
}


def _refused(request: web.Request, status: int, message: str) -> web.Response:
    """A missing or wrong token's answer: a short page saying what to do for a browser
    (``Accept: text/html``: a page opened from a link), the JSON error for an API client."""
    if "text/html" not in request.headers.get("Accept", ""):
        return _error(status, message)
    title, what = NO_ENTRY[status]
    page = NO_ENTRY_PAGE.format(title=title, what=what)
    return web.Response(status=status, text=page, content_type="text/html")


def session_view(session: MonitorSession | None) -> dict[str, Any]:
    """What the page shows of the operator's session: paused (why, since which tick, the
    countdown to the robot's sleep), the breakpoints and forced conditions by node index; a
    recorded run's: none of them."""
    if session is None:
        return {"paused": False, "pause_reason": "", "paused_tick": None, "sleep_note": "",
                "breakpoints": {}, "forced": {}}  # fmt: skip
    state = session.state
    return {
        "paused": state.paused,
        "pause_reason": state.pause_reason,
        "paused_tick": state.paused_tick,
        "sleep_note": state.sleep_note,
        "breakpoints": {str(k): v for k, v in state.breakpoints.items()},
        "forced": {str(k): v for k, v in state.forced.items()},
    }


def late_control(feed: RunFeed, action: str, seen: object, by: str | None) -> web.Response | None:
    """400 for a ``seen`` that is no stamp; 409 for a control that sets the robot going
    (:data:`MOTION_CONTROLS`) from a page whose last update (its ``seen``, the ``sent``
    it echoes) is more than :data:`STALE_VIEW_S` old: the operator pressed it looking
    at a run that has moved on, or the request sat in a stalled network; said in the
    event log too, as the controls applied are. None: in time, or a stop or pause (late,
    still safe), or no ``seen`` (an API client that shows no view)."""
    if seen is None:
        return None
    now = time.monotonic()
    # a stamp this clock cannot have given (below 0, ahead of it): a 409 said "your page
    # was 1000...(309 digits) s behind the run" of -1e308, in the event log too
    if (
        not isinstance(seen, int | float)
        or isinstance(seen, bool)
        or not math.isfinite(seen)
        or not 0 <= seen <= now + 1.0
    ):
        return _error(400, f'seen {seen!r}: allowed the "sent" of the last update the page had')
    behind = now - seen
    if action not in MOTION_CONTROLS or behind <= STALE_VIEW_S:
        return None
    said = f"{behind:.0f} s behind the run"
    feed.event(
        "control", f"{action} refused: sent from a page {said}{f'; from {by}' if by else ''}"
    )
    return _error(409, f"your page was {said}: look again and press {action.capitalize()} again")


def foreign_request(request: web.Request, bound: str, port: int) -> web.Response | None:
    """403 for a request another site's page made: on a loopback address, one whose
    ``Host`` is not this machine (``127.0.0.1``, ``localhost``, ``[::1]``, any port):
    a name of another site that its DNS turned to 127.0.0.1 (DNS rebinding) makes the
    browser treat this server as that site; on any address, one whose ``Origin`` (the
    page that made it: every WebSocket and control has one) is not this server. ``bound``:
    the address the server listens on, ``port`` its port. A request with no ``Host`` or an
    empty one (HTTP/1.0 allows it) is refused on loopback too: every browser, curl and
    urllib send one, so only a hand-made request lacks it, and "any Host but this machine's
    is refused" held with one exception."""
    host = request.headers.get("Host", "")
    if is_loopback(bound) and not _local_host(host, bound):
        said = (
            f"Host {host!r} refused (another site's name pointed at this machine: DNS rebinding)"
            if host
            else "a request with no Host header refused"
        )
        return _error(
            403,
            f"this monitor listens on {bound} and answers only requests addressed "
            f"to 127.0.0.1, localhost or [::1] (http://127.0.0.1:{port}/); {said}",
        )
    origin = request.headers.get("Origin")
    if origin is not None and urlsplit(origin).netloc.lower() != host.lower():
        return _error(403, f"a request from another site ({origin}) is refused")
    return None


def _local_host(host: str, bound: str) -> bool:
    """``host`` (a ``Host`` header) names this machine's loopback, with any port or none:
    the name is what a rebinding page cannot fake (its own is in its URL); the port may
    be another than this one (``ssh -L 9000:127.0.0.1:8765``, then localhost:9000)."""
    try:
        parts = urlsplit(f"//{host}")
        parts.port  # noqa: B018 - a port that is not a number raises here
    except ValueError:
        return False
    name = (parts.hostname or "").lower()
    return name in {"127.0.0.1", "localhost", "::1", bound.strip("[]").lower()}


async def see_the_view_path(request: web.Request) -> web.Response:
    """303 See Other to the view-only page, the query kept: from ``/view`` (its relative URLs
    and its cookie's path need the slash), and from ``/?token=VIEW``."""
    query = f"?{request.query_string}" if request.query_string else ""
    return web.Response(status=303, headers={"Location": f"{VIEW_PATH}{query}"})


def given_token(request: web.Request) -> str:
    """The request's token, "" for none. The first one given decides: the query, the header,
    then the cookie of the request's path (under :data:`VIEW_PATH` the view pages' own
    first: the browser sends the control page's too, set for every path)."""
    cookies = request.cookies
    return (
        request.query.get("token")
        or request.headers.get("X-Monitor-Token")
        or (cookies.get(cookie_name(request, view=True)) if viewing(request) else None)
        or cookies.get(cookie_name(request))
        or ""
    )


def token_access(tokens: Tokens, request: web.Request) -> Access | None:
    """What the request's token is, whatever its path (every request without a token in
    force: the loopback default); None: none given, or neither token."""
    if tokens.control is None:
        return Access.CONTROL
    given = given_token(request)
    return tokens.access(given) if given else None


def _end_leftover_tasks(loop: asyncio.AbstractEventLoop) -> None:
    """Cancel what the server's shutdown left running, and let it end, before ``loop`` is
    closed: a request refused with 413 while its client still sends the body keeps its
    handler reading it, and closing the loop on it wrote "ERROR asyncio: Task was destroyed
    but it is pending!" after the run's summary, which read as a failed run."""
    leftover = asyncio.all_tasks(loop)
    for task in leftover:
        task.cancel()
    loop.run_until_complete(asyncio.gather(*leftover, return_exceptions=True))


async def _close_pages(sockets: set[web.WebSocketResponse]) -> None:
    """Tell each page the run is over (it keeps what it shows) instead of waiting on it."""
    for ws in list(sockets):
        with contextlib.suppress(Exception):
            await asyncio.wait_for(
                ws.close(code=WSCloseCode.GOING_AWAY, message=b"the run ended"), 1.0
            )


def _wait_until_serving(ready: threading.Event, thread: threading.Thread, address: str) -> None:
    """Wait for the serving ``thread`` to set ``ready`` (bound, or failed with its error
    kept): it waited 10 s, then gave the URL of a server not serving (port 0 where 0 was
    asked). A thread that ended without either, or no answer by :data:`START_WITHIN_S`, is
    an OSError."""
    began = time.monotonic()
    while not ready.wait(0.05):
        if not thread.is_alive():
            raise OSError("the monitor's server ended before it was serving")
        if time.monotonic() - began > START_WITHIN_S:
            raise OSError(
                f"the monitor's server did not start on {address} within {START_WITHIN_S:g} s"
            )


class MonitorServer:
    """Serves one feed (a live run with its session, or a recorded run without one)."""

    def __init__(
        self,
        feed: RunFeed,
        session: MonitorSession | None = None,
        *,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        readonly: bool = False,
        token: str | None = None,
        view_token: str | None = None,
    ) -> None:
        """``token``: the control token (None: a new one off loopback, none on it);
        ``view_token``: the view-only one (None: a new one wherever a control token is in
        force and there are controls to withhold); ValueError when they are the same."""
        self.feed = feed
        self.session = session
        self.host = host
        self.port = port
        self.readonly = readonly or session is None
        self.tokens = Tokens.make(
            host, has_controls=not self.readonly, control=token, view=view_token
        )
        self.pages = 0
        self._sockets: set[web.WebSocketResponse] = set()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopped: asyncio.Event | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._freezing = False

    # ---------------------------------------------------------------- lifecycle
    @property
    def token(self) -> str | None:
        """The control token (None: none in force, the loopback default)."""
        return self.tokens.control

    @property
    def view_token(self) -> str | None:
        """The view-only token (None: no view-only link)."""
        return self.tokens.view

    @property
    def url(self) -> str:
        """The page's URL with the control token (the operator's)."""
        return self._url_with(self.token)

    @property
    def view_url(self) -> str | None:
        """The view-only page's URL with the view token (to share: no controls), or None."""
        return self._url_with(self.view_token, VIEW_PATH) if self.view_token else None

    def _url_with(self, token: str | None, path: str = "/") -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        query = f"?token={token}" if token else ""
        return f"http://{host}:{self.port}{path}{query}"

    def start(self) -> str:
        """Bind and serve in a background thread; returns the page's URL. Raises OSError when
        the address cannot be bound."""
        self._thread = threading.Thread(target=self._serve, name="roomba-bt monitor", daemon=True)
        self._thread.start()
        _wait_until_serving(self._ready, self._thread, f"{self.host}:{self.port}")
        if self._error is not None:
            raise self._error
        if not self._freezing:
            STARTUP_FREEZE.acquire()
            self._freezing = True
        return self.url

    def close(self, grace_s: float = 0.0) -> None:
        """Stop serving (after ``grace_s``, so pages get the last update)."""
        if self._freezing:
            self._freezing = False
            STARTUP_FREEZE.release()
        loop, stopped = self._loop, self._stopped
        if loop is None or stopped is None or self._thread is None:
            return
        if grace_s > 0:
            threading.Event().wait(grace_s)
        with contextlib.suppress(RuntimeError):
            loop.call_soon_threadsafe(stopped.set)
        self._thread.join(CLOSE_WITHIN_S)
        if self._thread.is_alive():  # its port stays bound while it runs
            log.warning(
                "the monitor's server on %s:%s did not stop within %g s: its port stays taken "
                "until it does", self.host, self.port, CLOSE_WITHIN_S,
            )  # fmt: skip

    def _serve(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self._loop = loop
        self._stopped = asyncio.Event()
        runner: web.AppRunner | None = None
        try:  # the app made in here too: a failure is start()'s error, not a thread's traceback
            runner = web.AppRunner(self.app(), handle_signals=False, access_log=None)
            loop.run_until_complete(runner.setup())
            site = web.TCPSite(runner, self.host, self.port)
            loop.run_until_complete(site.start())
            address = runner.addresses[0]
            self.port = int(address[1])
        except BaseException as exc:
            self._error = exc
            self._ready.set()
            if runner is not None:
                loop.run_until_complete(runner.cleanup())
            loop.close()
            return
        self._ready.set()
        try:
            loop.run_until_complete(self._stopped.wait())
            loop.run_until_complete(_close_pages(self._sockets))
        finally:
            loop.run_until_complete(runner.cleanup())
            _end_leftover_tasks(loop)
            loop.close()

    # ---------------------------------------------------------------- app
    def app(self) -> web.Application:
        app = web.Application(middlewares=[self._guard], client_max_size=64 * 1024)
        for path in ("/", VIEW_PATH):  # the same page: what it may do is the path's
            app.router.add_get(path, self._page)
            app.router.add_get(f"{path}static/{{name}}", self._static)
            app.router.add_get(f"{path}ws", self._socket)
            app.router.add_get(f"{path}api/state", self._state)
            app.router.add_post(f"{path}api/control", self._control)
        app.router.add_get(VIEW_PATH.rstrip("/"), see_the_view_path)
        return app

    @web.middleware
    async def _guard(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        refused = foreign_request(request, self.host, self.port)
        if refused is not None:
            return refused
        if self.token is not None:
            if not given_token(request):
                return _refused(
                    request, 401,
                    "this monitor needs its token: open the URL printed when the run started "
                    "(it ends in ?token=...)",
                )  # fmt: skip
            if self._access(request) is None:
                return _refused(
                    request, 403, "wrong token: open the URL printed when the run started"
                )
        return await handler(request)

    def _access(self, request: web.Request) -> Access | None:
        """What the request's token lets it do (:func:`token_access`), under
        :data:`VIEW_PATH` at most to view."""
        access = token_access(self.tokens, request)
        return Access.VIEW if access is Access.CONTROL and viewing(request) else access

    def _controls(self, request: web.Request) -> bool:
        """Whether this request's page may control the run: a live run, not read-only, and
        opened with the control token (or with none in force)."""
        return not self.readonly and self._access(request) is Access.CONTROL

    async def _page(self, request: web.Request) -> web.StreamResponse:
        access = token_access(self.tokens, request)
        view = viewing(request)
        if access is Access.VIEW and not view and "token" in request.query:
            # the view link as it was before it had a path of its own (a projector's
            # bookmark of /?token=VIEW): to its path, so its cookie is not the control page's
            return await see_the_view_path(request)
        html = resources.files("roomba_bt.monitor").joinpath("static/index.html").read_text("utf-8")
        response = web.Response(text=html, content_type="text/html")
        response.headers["Cache-Control"] = "no-store"
        # the token this page was opened with, in its path's cookie: the control page's holds
        # the control token alone, and a view page's, set for its path, cannot replace it
        if self.token is not None and (view or access is Access.CONTROL):
            response.set_cookie(
                cookie_name(request, view=view), given_token(request),
                path=VIEW_PATH if view else "/", httponly=True, samesite="Strict",
            )  # fmt: skip
        return response

    async def _static(self, request: web.Request) -> web.StreamResponse:
        name = request.match_info["name"]
        suffix = name[name.rfind(".") :] if "." in name else ""
        if (
            "/" in name
            or name.startswith(".")
            or suffix not in STATIC_TYPES
            or name == "index.html"
        ):
            return _error(404, f"no asset {name!r}")
        asset = resources.files("roomba_bt.monitor").joinpath("static", name)
        if not asset.is_file():
            return _error(404, f"no asset {name!r}")
        return web.Response(body=asset.read_bytes(), content_type=STATIC_TYPES[suffix])

    def _header(self, request: web.Request) -> dict[str, Any]:
        """The run's header as this request's page may have it: ``controls`` only with the
        control token; ``view_only`` says a view link's page has them off for that reason."""
        session = self.session
        controls = self._controls(request)
        return header_view(
            self.feed,
            {
                "readonly": self.readonly,
                "controls": controls,
                "view_only": not self.readonly and not controls,
                "can_force": bool(session and session.allow_force and controls),
                "watching": session.state.watching if session else None,
            },
        )

    async def _state(self, request: web.Request) -> web.StreamResponse:
        text = request.query.get("tick")
        try:
            tick = int(text) if text is not None else None
        except ValueError:
            return _error(400, f"tick {text!r}: allowed a whole number of ticks (15 ms each)")
        if tick is None:
            latest = self.feed.latest()
            tick = latest.tick if latest else 0
        record, earlier = self.feed.at(tick)
        if record is None:
            return _error(409, "no tick recorded yet")
        body = {
            "header": self._header(request),
            "state": state_view(self.feed, record, earlier),
            "tree": tree_view(self.feed, record.tree),
            "path": path_view(self.feed.path(record.seq)),
            "events": [e._asdict() for e in self.feed.events_after(-1)],  # not the ticks
            "session": session_view(self.session),
            "sent": stamp(),
        }
        return web.json_response(body)

    async def _control(self, request: web.Request) -> web.StreamResponse:
        if self.session is None:
            return _error(409, "a recorded run has no controls: it can only be watched")
        if self.readonly:
            return _error(403, "this monitor is read-only (--monitor-readonly): no controls")
        if not self._controls(request):
            return _error(403, VIEW_ONLY)
        try:
            body = await request.json()
        except (json.JSONDecodeError, UnicodeDecodeError):
            return _error(400, 'the body is not JSON; expected {"action": "pause"} or similar')
        except RecursionError:  # json's decoder recurses: a body nested thousands deep
            return _error(400, 'the body is nested too deeply; expected {"action": "pause"}')
        if not isinstance(body, dict) or not isinstance(body.get("action"), str):
            return _error(400, 'expected a JSON object with "action" (a string)')
        node = body.get("node")
        if node is not None and (
            not isinstance(node, int | str) or isinstance(node, bool) or node == ""
        ):
            return _error(
                400, f"node {node!r}: allowed a node's index (a whole number), name or path"
            )
        value = body.get("value")
        if value is not None and not isinstance(value, str):
            return _error(400, f"value {value!r}: allowed a string")
        other_run = self._other_run(body.get("run"))
        if other_run is not None:
            return _error(409, other_run)
        late = late_control(self.feed, body["action"], body.get("seen"), request.remote)
        if late is not None:
            return late
        try:
            self.session.request(body["action"], node, value, by=request.remote or None)
        except ControlRefused as exc:
            return _error(409, str(exc))
        except ValueError as exc:
            return _error(400, str(exc))
        return web.json_response({"accepted": body["action"]}, status=202)

    def _other_run(self, given: object) -> str | None:
        """Why a control for ``given`` (the run id the page was loaded for, the body's
        ``"run"``) is refused, or None when it names the run served now. A page left open
        after its run was killed reconnects to whatever run is served on the port next (on
        loopback, or with a fixed token, nothing else stops it): its Pause paused another
        robot. So every control names its run, and one that names no run is refused too."""
        feed = self.feed
        if given == feed.run_id:
            return None
        run = run_view(feed)  # its texts cut, as the page shows them
        label, robot = run["label"], run["robot"]
        now = (
            f"the run served here now is {f'{label}: ' if label else ''}"
            f"{run['mission']}{f' on {robot}' if robot else ''}, started "
            f"{run['started']} (id {feed.run_id})"
        )
        if given is None or given == "":
            return (
                f'a control names the run it is for: {{"action": ..., "run": "{feed.run_id}"}} '
                f"(GET /api/state: header.run.id); {now}; nothing was done"
            )
        return (
            f"this control was for another run ({str(given)[:40]!r}): {now}; nothing was done "
            "(reload the page to watch this run)"
        )

    async def _socket(self, request: web.Request) -> web.StreamResponse:
        ws = web.WebSocketResponse(heartbeat=20, autoping=False)  # the pongs: _Reading's
        await ws.prepare(request)
        self.pages += 1
        self._sockets.add(ws)
        hello = {"type": "hello", "header": self._header(request)}
        pump = asyncio.get_running_loop().create_task(self._pump(ws, hello, reading := _Reading()))
        try:
            async for message in ws:  # the page sends nothing but pongs; read to see it close
                if message.type is WSMsgType.ERROR:
                    break
                await reading.heard(ws, message)
        finally:
            pump.cancel()
            self.pages -= 1
            self._sockets.discard(ws)
        return ws

    async def _after_a_tick(self, last_sent: float, reading: _Reading) -> None:
        """Wait out the update period, then until just after a tick's end (the tick thread has
        recorded a tick and is about to sleep until the next frame), or :data:`TICK_WAIT_S`.

        Frames come every 15 ms, so ticks end every 15 ms: from the newest one's end
        (``ring.ended``) the pump sleeps until :data:`AFTER_TICK_S` after the first end due
        after its period, and wakes once, not every 2 ms, never in the middle of a tick that
        is on time. If no tick has just ended there (a late frame), it looks every
        :data:`TICK_POLL_S`; a run with no ticks (recorded, ended) is sent after the period."""
        await reading.caught_up()  # first, a page that stopped reading is held
        loop = asyncio.get_running_loop()
        ring = self.feed.ring
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

    async def _pump(self, ws: Socket, hello: dict[str, Any], reading: _Reading) -> None:
        feed = self.feed
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
            now_session = session_view(self.session)
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
                    _, earlier = feed.at(last.tick)
                    state = state_view(feed, last, earlier)
                    flipped = {i for r in records if r.tree == last.tree for i in r.changed}
                    state["changed"] = [] if again else sorted(flipped)
                    message["state"] = state
                    stride = max(1, len(records) // 8)
                    message["path"] = path_view([] if again else [*records[:-1:stride], last])
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
            await self._after_a_tick(last_sent, reading)
