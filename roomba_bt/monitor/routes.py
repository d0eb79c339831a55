"""The monitor's routes: what each URL answers, and who may ask (the aiohttp app).

Routes (all behind the token when one is set), each under ``/view/`` too: the view-only
link's pages, whose controls are off whatever the token, and whose cookie is their own::

    GET  /                the page (static/index.html); ``/?token=VIEW`` sends to ``/view/``
    GET  /static/NAME     its script and style, from the package
    GET  /ws              WebSocket: {"type": "hello", ...} then {"type": "update", ...},
                          at least one a second (:data:`.pump.HEARTBEAT_S`), each with "sent"
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

The app is served by :mod:`.server` (its thread, its event loop); a page's socket runs its
updates' pump (:mod:`.pump`).
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

from roomba_bt.monitor.access import Access, Tokens
from roomba_bt.monitor.address import is_loopback
from roomba_bt.monitor.controls import ControlRefused
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.pump import Reading, Socket, pump, stamp
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import (
    header_view,
    path_view,
    run_view,
    session_view,
    state_view,
    tree_view,
)

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


@dataclass(eq=False, kw_only=True)
class MonitorRoutes:
    """What each URL answers for one feed (a live run with its session, or a recorded run
    without one), behind the guard (:meth:`_guard`): the app :class:`~.server.MonitorServer`
    serves in its thread. It holds what the handlers share: the pages connected, their
    sockets (told when the run ends), and the port the server bound, which the guard's
    refusal names."""

    feed: RunFeed
    session: MonitorSession | None
    readonly: bool
    tokens: Tokens
    host: str
    #: the port asked, then the one bound (``MonitorServer.start``: port 0 is any)
    port: int
    pages: int = 0  # connected now
    sockets: set[Socket] = field(default_factory=set)  # theirs, told when the run ends

    def app(self) -> web.Application:
        """The aiohttp app: each route at ``/`` and under :data:`VIEW_PATH`, behind the guard;
        a request's body at most 64 KiB (a control is a line of JSON)."""
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
        if self.tokens.control is not None:
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
        if self.tokens.control is not None and (view or access is Access.CONTROL):
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
        ws = web.WebSocketResponse(heartbeat=20, autoping=False)  # the pongs: Reading's
        await ws.prepare(request)
        self.pages += 1
        self.sockets.add(ws)
        hello = {"type": "hello", "header": self._header(request)}
        reading = Reading()
        updates = asyncio.get_running_loop().create_task(
            pump(ws, hello, reading, self.feed, self.session)
        )
        try:
            async for message in ws:  # the page sends nothing but pongs; read to see it close
                if message.type is WSMsgType.ERROR:
                    break
                await reading.heard(ws, message)
        finally:
            updates.cancel()
            self.pages -= 1
            self.sockets.discard(ws)
        return ws
