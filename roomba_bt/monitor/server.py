"""The monitor's web server: the app served in a thread of its own, started and closed.

aiohttp (the ``monitor`` extra) in a thread of its own with its own event loop: the tick loop
stays the main thread's, and the server reads the feed's ring (without a lock) when it
chooses. :meth:`MonitorServer.start` binds and returns once it serves (or raises what
stopped it); :meth:`MonitorServer.close` tells the pages the run ended and returns once the
thread has ended, its port free. What each URL answers, and who may ask, is
:mod:`.routes`; the pace of a page's live updates, :mod:`.pump`.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import logging
import threading
import time

from aiohttp import WSCloseCode, web

from roomba_bt.monitor.access import Tokens
from roomba_bt.monitor.address import DEFAULT_PORT
from roomba_bt.monitor.feed import RunFeed

# the names this module held before the routes and the pump had modules of their own: a
# program's or a test's ``from roomba_bt.monitor.server import ...`` finds them here still
# (rebinding one here changes nothing: set it on its own module)
from roomba_bt.monitor.pump import (
    AFTER_TICK_S,
    BEHIND_S,
    HEARTBEAT_S,
    PING_EVERY_S,
    TICK_POLL_S,
    TICK_WAIT_S,
    UPDATE_PERIOD_S,
    Socket,
    next_look,
    stamp,
)
from roomba_bt.monitor.routes import (
    COOKIE,
    MOTION_CONTROLS,
    NO_ENTRY,
    NO_ENTRY_PAGE,
    STALE_VIEW_S,
    STATIC_TYPES,
    VIEW_ONLY,
    VIEW_PATH,
    Handler,
    MonitorRoutes,
    cookie_name,
    foreign_request,
    given_token,
    late_control,
    see_the_view_path,
    token_access,
    viewing,
)
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import session_view

__all__ = [
    "AFTER_TICK_S",
    "BEHIND_S",
    "CLOSE_WITHIN_S",
    "COOKIE",
    "HEARTBEAT_S",
    "MOTION_CONTROLS",
    "NO_ENTRY",
    "NO_ENTRY_PAGE",
    "PING_EVERY_S",
    "STALE_VIEW_S",
    "STARTUP_FREEZE",
    "START_WITHIN_S",
    "STATIC_TYPES",
    "TICK_POLL_S",
    "TICK_WAIT_S",
    "UPDATE_PERIOD_S",
    "VIEW_ONLY",
    "VIEW_PATH",
    "Handler",
    "MonitorServer",
    "Socket",
    "cookie_name",
    "foreign_request",
    "given_token",
    "late_control",
    "next_look",
    "see_the_view_path",
    "session_view",
    "stamp",
    "token_access",
    "viewing",
]

log = logging.getLogger(__name__)

#: the longest ``start`` waits for the server to be bound: it waited 10 s, then gave the
#: page's URL (port 0 where 0 was asked) of a server that was not serving
START_WITHIN_S = 60.0
#: the longest ``close`` waits for the server's thread to end (the pages told the run ended,
#: up to 1 s each, and aiohttp's cleanup), its port free again. It waited 5 s and returned
#: with the thread still serving on a loaded machine, its port bound: a server started
#: again there was refused (address in use)
CLOSE_WITHIN_S = 60.0
#: how long the close lets a request still being handled end by itself before it is
#: cancelled (:func:`_end_leftover_tasks`): aiohttp's 60 s, and its 10 s of lingering on a
#: refused body's connection, held a run's end 10.5 s after anyone POSTed an oversized body
SHUTDOWN_S = 1.0


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
    """Serves one feed (a live run with its session, or a recorded run without one): its
    routes (:class:`~.routes.MonitorRoutes`) in a thread of its own, from :meth:`start` to
    :meth:`close`."""

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
        self.readonly = readonly or session is None
        self.tokens = Tokens.make(
            host, has_controls=not self.readonly, control=token, view=view_token
        )
        self.routes = MonitorRoutes(
            feed=feed,
            session=session,
            readonly=self.readonly,
            tokens=self.tokens,
            host=host,
            port=port,
        )
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopped: asyncio.Event | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._freezing = False

    @property
    def port(self) -> int:
        """The port it listens on: the one asked until :meth:`start` has bound it (port 0:
        the one the system chose). The routes' own, which the guard's refusal names."""
        return self.routes.port

    @property
    def pages(self) -> int:
        """How many pages are connected (their sockets open) now."""
        return self.routes.pages

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
            runner = web.AppRunner(
                self.app(), handle_signals=False, access_log=None, shutdown_timeout=SHUTDOWN_S
            )
            loop.run_until_complete(runner.setup())
            site = web.TCPSite(runner, self.host, self.port)
            loop.run_until_complete(site.start())
            address = runner.addresses[0]
            self.routes.port = int(address[1])
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
            loop.run_until_complete(_close_pages(self.routes.sockets))
        finally:
            loop.run_until_complete(runner.cleanup())
            _end_leftover_tasks(loop)
            loop.close()

    def app(self) -> web.Application:
        """The app this server serves (:meth:`.routes.MonitorRoutes.app`), made in its
        thread."""
        return self.routes.app()
