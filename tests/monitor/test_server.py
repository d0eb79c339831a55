"""The monitor's HTTP side without a browser: bad or unauthenticated requests get a clear
HTTP error and change nothing; a stalled page never holds up a tick."""

from __future__ import annotations

import asyncio
import gc
import json
import socket
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import waits  # its received(): a socket's read within a hang's bound
from waits import HANG_S, awaited, joined, waited  # tests/waits.py: a hang's bound

from roomba_bt.mission import load_mission
from roomba_bt.monitor import server as monitor_server
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.server import AFTER_TICK_S, UPDATE_PERIOD_S, MonitorServer, next_look
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.runtime.loop import MissionRunner, stream_request
from roomba_bt.sim import SimLink, Simulator, load_world

SHUTTLE = Path(__file__).resolve().parent / "missions" / "shuttle.yaml"


def _serve(host: str = "127.0.0.1", readonly: bool = False, live: bool = True) -> MonitorServer:
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    feed = RunFeed(mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True) if live else None
    server = MonitorServer(feed, session, host=host, port=0, readonly=readonly)
    server.start()
    return server


@pytest.fixture
def server() -> Iterator[MonitorServer]:
    served = _serve()
    yield served
    served.close()


def _call(
    url: str, body: bytes | None = None, headers: dict[str, str] | None = None
) -> tuple[int, Any]:
    request = urllib.request.Request(url, data=body, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=HANG_S) as reply:
            raw = reply.read()
            status = reply.status
    except urllib.error.HTTPError as exc:
        raw, status = exc.read(), exc.code
    try:
        return status, json.loads(raw)
    except json.JSONDecodeError:
        return status, raw.decode()


def _control(
    server: MonitorServer, payload: object, at: str = "/", **headers: str
) -> tuple[int, Any]:
    """POST ``payload`` as a control from the page at ``at`` (``/view/``: the view-only
    link's); a dict naming no run is sent for the run served (as the page sends it: every
    control names its run)."""
    base = f"http://127.0.0.1:{server.port}{at}api/control"
    if isinstance(payload, dict) and "run" not in payload:
        payload = {**payload, "run": server.feed.run_id}
    body = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
    return _call(base, body, {"Content-Type": "application/json", **headers})


def test_a_control_for_another_run_or_for_none_is_refused_and_changes_nothing(
    server: MonitorServer,
) -> None:
    """A page left open after its run was killed reconnected to the next run served on the
    port (another robot) and its Pause paused that one. A control names its run now: one
    for another run, or for none, is refused (409) with the run served here named."""
    assert server.session is not None
    served = server.feed.run_id
    got, body = _control(server, {"action": "pause", "run": "the-killed-run-s-id"})
    assert got == 409
    assert "this control was for another run ('the-killed-run-s-id')" in body["error"]
    assert "the run served here now is shuttle, started " in body["error"]
    assert "reload the page" in body["error"]
    got, body = _control(server, {"action": "pause", "run": None})
    assert got == 409
    assert f'{{"action": ..., "run": "{served}"}}' in body["error"]
    assert server.session._requests.empty() and not server.session.state.paused
    state = _call(f"http://127.0.0.1:{server.port}/api/state")
    assert state[0] in (200, 409)  # no tick yet: 409; the hello's header names the run
    assert _control(server, {"action": "pause", "run": served}) == (202, {"accepted": "pause"})


@pytest.mark.parametrize(
    ("payload", "status", "message"),
    [
        (b"{not json", 400, "not JSON"),
        (b'{"a":' * 5000 + b"1" + b"}" * 5000, 400, "nested too deeply"),  # was a 500, a traceback
        ([1, 2], 400, '"action"'),
        ({"action": "explode"}, 400, "allowed pause, resume, step, stop, break, force"),
        ({"action": "break", "node": 1.5, "value": "start"}, 400, "a node's index"),
        ({"action": "break", "node": "x", "value": "start"}, 400, "no node has that name"),
        ({"action": "break", "node": 999, "value": "start"}, 400, "node 999"),
        ({"action": "force", "node": 0, "value": "success"}, 409, "not a condition"),
        ({"action": "resume"}, 409, "not paused"),
        ({"action": "pause", "seen": "yesterday"}, 400, '"sent" of the last update'),
        ({"action": "pause", "seen": True}, 400, '"sent" of the last update'),
    ],
)
def test_a_bad_control_gets_a_clear_error_and_changes_nothing(
    server: MonitorServer, payload: object, status: int, message: str
) -> None:
    got, body = _control(server, payload)
    assert got == status
    assert message in body["error"]
    assert server.session is not None and server.session._requests.empty()


def test_a_pause_when_paused_and_a_release_of_what_is_not_forced_are_refused(
    server: MonitorServer,
) -> None:
    """A pause of a paused run was 202 and did nothing (a resume of a running one is 409);
    a release of a condition not forced was 202 and said "no longer forced"."""
    assert server.session is not None
    server.session.state.paused = True
    got, body = _control(server, {"action": "pause"})
    assert got == 409 and body["error"] == "the run is already paused"
    condition = next(i for i, info in enumerate(server.feed.infos) if info.condition)
    got, body = _control(server, {"action": "force", "node": condition, "value": "none"})
    assert got == 409 and "is not forced: nothing to release" in body["error"]
    assert server.session._requests.empty()
    assert _control(server, {"action": "resume"}) == (202, {"accepted": "resume"})


@pytest.mark.parametrize("action", ["resume", "step", "force"])
def test_a_control_that_sets_the_robot_going_from_a_page_behind_the_run_is_refused(
    server: MonitorServer, action: str
) -> None:
    """A Resume pressed 2 s into a silent network stall reached the run 60 s later and the
    robot started cleaning the moment the network came back, the event log showing nothing
    late. The page stamps each control with the ``sent`` of its last update: a resume, step
    or force from a view more than STALE_VIEW_S behind is refused, said in the event log; the
    same from a page in time goes through."""
    assert server.session is not None
    server.session.state.paused = True
    condition = next(i for i, info in enumerate(server.feed.infos) if info.condition)
    payload = {"action": action, "node": condition, "value": "success"} if action == "force" \
        else {"action": action}  # fmt: skip
    got, body = _control(server, {**payload, "seen": time.monotonic() - 62})
    assert got == 409
    assert body["error"] == (
        f"your page was 62 s behind the run: look again and press {action.capitalize()} again"
    )
    assert server.session._requests.empty()
    assert server.feed.events[-1].kind == "control"
    assert server.feed.events[-1].text == (
        f"{action} refused: sent from a page 62 s behind the run; from 127.0.0.1"
    )
    got, body = _control(server, {**payload, "seen": time.monotonic() - 1})
    assert (got, body) == (202, {"accepted": action})


@pytest.mark.parametrize("seen", [-1e308, -1.0, 1e308])
def test_a_stamp_the_server_never_gave_is_a_bad_request(server: MonitorServer, seen: float) -> None:
    """``"seen": -1e308`` was refused as "your page was 1000...(309 digits) s behind the
    run", a line as long in the event log; a stamp below 0 or ahead of the server's clock is
    none it sent: 400, nothing queued, nothing in the event log."""
    assert server.session is not None
    server.session.state.paused = True
    events = len(server.feed.events)
    got, body = _control(server, {"action": "resume", "seen": seen})
    assert got == 400, body
    assert body["error"] == f'seen {seen!r}: allowed the "sent" of the last update the page had'
    assert server.session._requests.empty()
    assert len(server.feed.events) == events


def test_a_late_pause_or_stop_is_applied_it_stops_the_robot(server: MonitorServer) -> None:
    """Late, a pause or a stop still stops the robot: safe whenever it arrives."""
    assert server.session is not None
    long_ago = time.monotonic() - 600
    assert _control(server, {"action": "pause", "seen": long_ago}) == (202, {"accepted": "pause"})
    assert _control(server, {"action": "stop", "seen": long_ago}) == (202, {"accepted": "stop"})


def test_a_page_hears_from_the_run_every_second_when_nothing_changes() -> None:
    """A page tells a silent link (packets lost, the socket not closed) from a quiet run
    only if the run speaks when nothing changes: a recorded run's page, with nothing new
    after its hello, was sent nothing more. Each message carries ``sent``, the server's
    clock, which the page echoes as a control's ``seen``."""

    import aiohttp

    served = _serve(live=False)

    async def listen() -> list[dict[str, Any]]:
        received: list[dict[str, Any]] = []
        async with (
            aiohttp.ClientSession() as client,
            client.ws_connect(f"ws://127.0.0.1:{served.port}/ws") as ws,
        ):
            async for message in ws:
                received.append(json.loads(message.data))
                if len(received) == 4:
                    return received
        return received

    try:
        received = awaited(listen, "the page's reader")
    finally:
        served.close()
    assert [m["type"] for m in received] == ["hello", "update", "update", "update"]
    sent = [m["sent"] for m in received]
    assert sent == sorted(sent) and sent[1] < sent[2] < sent[3]
    assert all(m["finished"] is None and "state" not in m for m in received[1:])


def test_a_good_control_is_accepted(server: MonitorServer) -> None:
    assert _control(server, {"action": "pause"}) == (202, {"accepted": "pause"})


def test_a_control_from_another_site_is_refused(server: MonitorServer) -> None:
    got, body = _control(server, {"action": "pause"}, Origin="http://evil.example")
    assert got == 403 and "another site" in body["error"]
    assert server.session is not None and server.session._requests.empty()
    got, _ = _control(server, {"action": "pause"}, Origin=f"http://127.0.0.1:{server.port}")
    assert got == 202


def test_a_page_of_another_site_reaching_the_loopback_by_dns_rebinding_is_refused(
    server: MonitorServer,
) -> None:
    """evil.example's DNS turns to 127.0.0.1: its page's requests reach the local monitor as
    same-origin ones (Host and Origin both evil.example:PORT). The control's Origin check
    compared only the two, so pause, resume, step, stop and force were accepted (202), and
    the state and the WebSocket answered any Host: the mission, the pose, the map."""
    evil = f"evil.example:{server.port}"
    got, body = _control(server, {"action": "pause"}, Host=evil, Origin=f"http://{evil}")
    assert got == 403 and "DNS rebinding" in body["error"], body
    assert server.session is not None and server.session._requests.empty()
    base = f"http://127.0.0.1:{server.port}"
    for path in ("/", "/api/state", "/ws"):
        status, body = _call(base + path, headers={"Host": evil})
        assert status == 403 and "evil.example" in body["error"], path
    assert _call(base + "/", headers={"Host": "localhost.evil.example"})[0] == 403
    # this machine's names, with this port, none, or a tunnel's (ssh -L 9000:127.0.0.1:PORT)
    for host in ("localhost", "LOCALHOST", "127.0.0.1", "[::1]"):
        for port in (f":{server.port}", "", ":9000"):
            status, _ = _call(base + "/", headers={"Host": f"{host}{port}"})
            assert status == 200, host + port
    got, _ = _control(server, {"action": "pause"}, Origin=f"http://localhost:{server.port}",
                      Host=f"localhost:{server.port}")  # fmt: skip
    assert got == 202


def _ws_status(port: int, origin: str | None, host: str | None = None) -> int:
    """The status of a WebSocket handshake with ``origin`` (101: accepted)."""
    headers = {"Connection": "Upgrade", "Upgrade": "websocket", "Sec-WebSocket-Version": "13",
               "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="}  # fmt: skip
    if origin is not None:
        headers["Origin"] = origin
    lines = ["GET /ws HTTP/1.1", f"Host: {host or f'127.0.0.1:{port}'}"]
    lines += [f"{k}: {v}" for k, v in headers.items()]
    return _raw_status(port, "\r\n".join(lines))


def _raw_status(port: int, head: str) -> int:
    """The status of a request sent by hand with ``head`` (the request line and headers, no
    blank line): what no browser or HTTP library sends."""
    with socket.create_connection(("127.0.0.1", port), timeout=HANG_S) as sock:
        sock.sendall(f"{head}\r\n\r\n".encode())
        return int(waits.received(sock, 200, "the server's answer").split()[1])


def test_a_request_with_no_host_or_an_empty_one_is_refused_on_loopback(
    server: MonitorServer,
) -> None:
    """``GET / HTTP/1.0`` with no ``Host`` (or ``Host:`` empty) was answered 200: the
    one exception to "any Host but this machine's is refused" on loopback."""
    port = server.port
    assert _raw_status(port, "GET / HTTP/1.0") == 403
    assert _raw_status(port, "GET / HTTP/1.1\r\nHost:") == 403
    assert _raw_status(port, f"GET / HTTP/1.0\r\nHost: 127.0.0.1:{port}") == 200
    status, body = _call(f"http://127.0.0.1:{port}/")  # urllib: Host sent
    assert status == 200, body


def test_the_websocket_and_the_state_refuse_another_site_s_page(server: MonitorServer) -> None:
    """Any site open in the browser could open the WebSocket (it checked no Origin) and read
    the run: the mission, the robot's pose, the map."""
    port = server.port
    assert _ws_status(port, "http://evil.example") == 403
    assert _ws_status(port, "null") == 403
    assert _ws_status(port, f"http://127.0.0.1:{port}") == 101  # the page itself
    assert _ws_status(port, None) == 101  # not a browser: no Origin
    status, body = _call(
        f"http://127.0.0.1:{port}/api/state", headers={"Origin": "http://evil.example"}
    )
    assert status == 403 and "another site" in body["error"]


def test_a_token_protected_address_answers_the_machine_s_own_name() -> None:
    """On 0.0.0.0 the page is opened by this machine's name or address (any Host): the
    token guards it; a page of another site is refused by its Origin all the same."""
    served = _serve(host="0.0.0.0")
    try:
        base, token = f"http://127.0.0.1:{served.port}", served.token
        name = f"robot-laptop.local:{served.port}"
        assert _call(f"{base}/?token={token}", headers={"Host": name})[0] == 200
        got, _ = _control(
            served, {"action": "pause"}, Host=name, Origin=f"http://{name}",
            **{"X-Monitor-Token": str(token)},
        )  # fmt: skip
        assert got == 202
        got, _ = _control(
            served, {"action": "pause"}, Origin="http://evil.example",
            **{"X-Monitor-Token": str(token)},
        )  # fmt: skip
        assert got == 403
        assert _call(f"{base}/?token={token}", headers={"Host": "evil.example"})[0] == 200
    finally:
        served.close()


def test_readonly_and_recorded_runs_have_no_controls() -> None:
    readonly = _serve(readonly=True)
    recorded = _serve(live=False)
    try:
        got, body = _control(readonly, {"action": "pause"})
        assert got == 403 and "read-only" in body["error"]
        got, body = _control(recorded, {"action": "pause"})
        assert got == 409 and "recorded run" in body["error"]
    finally:
        readonly.close()
        recorded.close()


def test_assets_come_from_the_package_and_nothing_else(server: MonitorServer) -> None:
    base = f"http://127.0.0.1:{server.port}"
    status, text = _call(f"{base}/static/monitor.js")
    assert status == 200 and "WebSocket" in text
    assert _call(f"{base}/static/..%2fserver.py")[0] == 404
    assert _call(f"{base}/static/nothing.js")[0] == 404
    status, body = _call(f"{base}/api/state?tick=abc")
    assert status == 400 and "whole number" in body["error"]
    status, text = _call(f"{base}/")
    assert status == 200 and '<script src="static/monitor.js">' in text
    assert "http" not in text.split("<body>")[1].split("</body>")[0].replace("http-equiv", "")


def test_a_non_local_address_needs_the_token_for_everything() -> None:
    served = _serve(host="0.0.0.0")
    try:
        token = served.token
        assert token is not None and len(token) >= 20
        base = f"http://127.0.0.1:{served.port}"
        for path in ("/", "/static/monitor.js", "/api/state", "/ws"):
            status, body = _call(base + path)
            assert status == 401 and "token" in body["error"], path
        assert _call(f"{base}/?token=wrong")[0] == 403
        got, _ = _control(served, {"action": "pause"})
        assert got == 401
        got, _ = _control(served, {"action": "pause"}, **{"X-Monitor-Token": "wrong"})
        assert got == 403
        assert served.session is not None and served.session._requests.empty()
        assert _call(f"{base}/?token={token}")[0] == 200
        assert _control(served, {"action": "pause"}, **{"X-Monitor-Token": token})[0] == 202
    finally:
        served.close()


def test_a_browser_without_the_right_token_gets_a_page_saying_what_to_do() -> None:
    """Yesterday's link on a phone showed a raw ``{"error": "wrong token: ..."}``, naming
    "the URL printed when the run started", which the colleague sent the link never saw. A
    browser (``Accept: text/html``) gets a short page; an API client keeps the JSON."""
    served = _serve(host="0.0.0.0")
    browser = {"Accept": "text/html,application/xhtml+xml,*/*;q=0.8"}
    try:
        base = f"http://127.0.0.1:{served.port}"
        status, page = _call(f"{base}/?token=yesterdays-token", headers=browser)
        assert status == 403
        assert "<title>roomba-bt monitor: This link is for another run or has expired" in page
        assert "Ask whoever started the run for its link" in page
        assert "<code>--monitor-token</code>" in page
        status, page = _call(f"{base}/", headers=browser)
        assert status == 401 and "This link has no token" in page
        status, body = _call(f"{base}/?token=yesterdays-token")
        assert status == 403 and body["error"].startswith("wrong token: ")
    finally:
        served.close()


def test_the_loopback_address_needs_no_token(server: MonitorServer) -> None:
    assert server.token is None
    assert server.url == f"http://127.0.0.1:{server.port}/"


def test_a_stalled_page_loses_updates_never_a_tick() -> None:
    """A WebSocket client that never reads, with a tiny receive buffer: the server's pump for
    it blocks on its full socket; the run goes on on the virtual clock, every tick kept."""
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    packets = stream_request(mission.packets, 115200)
    connection = Connection(SimLink(simulator), CREATE2, watchdog=0.5)  # type: ignore[arg-type]
    feed = RunFeed(history=None, mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True)
    server = MonitorServer(feed, session, port=0)
    server.start()
    stalled = socket.socket()
    stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1024)
    stalled.connect(("127.0.0.1", server.port))
    stalled.sendall(
        b"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    runner = MissionRunner(
        connection, mission, profile=CREATE2, packets=packets, timeout_s=120.0, gate=session
    )
    try:
        finished = threading.Event()
        result: list[Any] = []

        def run() -> None:
            result.append(runner.run())
            finished.set()

        threading.Thread(target=run, daemon=True).start()
        waited(finished, "the run beside a stalled page (held up?)")
        summary = result[0]
        assert summary.reason.startswith("the run's 2 min of mission time ran out")
        assert len(feed.since(0)[0]) == summary.ticks  # every tick recorded
        assert server.pages == 1
    finally:
        stalled.close()
        server.close()


def test_several_pages_watch_one_run() -> None:
    """Two pages connected to one run both get its hello and its updates."""
    import asyncio

    import aiohttp

    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    connection = Connection(SimLink(simulator), CREATE2, watchdog=0.5)  # type: ignore[arg-type]
    packets = stream_request(mission.packets, 115200)
    feed = RunFeed(mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True)
    server = MonitorServer(feed, session, port=0)
    server.start()
    runner = MissionRunner(
        connection, mission, profile=CREATE2, packets=packets, timeout_s=20.0, gate=session
    )

    connected = [threading.Event(), threading.Event()]

    async def page(received: list[dict[str, Any]], which: int) -> None:
        async with (
            aiohttp.ClientSession() as client,
            client.ws_connect(f"ws://127.0.0.1:{server.port}/ws") as ws,
        ):
            async for message in ws:
                received.append(json.loads(message.data))
                connected[which].set()
                if any("state" in m for m in received) and len(received) >= 3:
                    return

    async def two_pages() -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        first: list[dict[str, Any]] = []
        second: list[dict[str, Any]] = []
        await asyncio.wait_for(asyncio.gather(page(first, 0), page(second, 1)), HANG_S)
        return first, second

    thread = threading.Thread(target=runner.run, daemon=True)
    pages: list[tuple[list[dict[str, Any]], list[dict[str, Any]]]] = []
    # the pages' event loop in a thread of its own: the browser tests' driver may own this one
    watcher = threading.Thread(target=lambda: pages.append(asyncio.run(two_pages())))
    try:
        # both pages connected (their hello received) before the run starts: on the virtual
        # clock the whole run may otherwise end before a page has seen one of its ticks
        watcher.start()
        for which, event in enumerate(connected):
            waited(event, f"page {which}'s connecting")
        thread.start()
        joined(watcher, "the page's reader")  # the wait_for's bound at the latest
        first, second = pages[0]
    finally:
        session.request("stop")
        if thread.ident is not None:  # started
            joined(thread, "the run, told to stop")
        server.close()
    for received in (first, second):
        assert received[0]["type"] == "hello"
        assert received[0]["header"]["run"]["id"] == feed.run_id  # which run: sent first
        assert [n["name"] for n in received[0]["header"]["tree"]][:2] == ["sequence", "mode(safe)"]
        assert any(m.get("state", {}).get("robot", {}).get("mode") for m in received[1:])


def test_the_startup_freeze_is_undone_when_the_last_server_closes() -> None:
    """gc.freeze is the run's: a library user's process gets its collector back as it was."""
    assert gc.get_freeze_count() == 0
    first = _serve()
    assert gc.get_freeze_count() > 0  # start-up objects moved out of the collector's sight
    second = _serve()
    first.close()
    assert gc.get_freeze_count() > 0  # the second one still serves
    second.close()
    assert gc.get_freeze_count() == 0
    first.close()  # a second close changes nothing
    assert gc.get_freeze_count() == 0


def test_a_process_that_froze_objects_itself_keeps_its_freeze() -> None:
    gc.freeze()
    try:
        frozen = gc.get_freeze_count()
        served = _serve()
        assert gc.get_freeze_count() == frozen  # the monitor left freezing to the process
        served.close()
        assert gc.get_freeze_count() == frozen  # and did not undo the process's own
    finally:
        gc.unfreeze()


def test_the_pump_looks_just_after_the_first_tick_end_due_after_its_period() -> None:
    # the newest tick ended at 10.000 s; ticks end every 15 ms; the period ends at 10.050 s
    assert next_look(10.000, 10.050) == pytest.approx(10.000 + 4 * SLOT_SECONDS + AFTER_TICK_S)
    # the look is the first one at or after the period's end
    assert next_look(10.000, 10.0455) == pytest.approx(10.046)
    assert next_look(10.000, 10.0465) == pytest.approx(10.061)
    # a tick that ended after the period was due: the next end
    assert next_look(10.000, 9.990) == pytest.approx(10.016)


def test_a_body_refused_as_too_large_leaves_no_task_pending_at_the_end(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A POST over 64 KiB is refused with 413 while its client goes on sending: its handler
    was still reading when the server closed, and "ERROR asyncio: Task was destroyed but it
    is pending!" followed the run's summary, as if the run had failed. aiohttp 3.9 on (the
    monitor extra's floor) cancels such a handler itself once its shutdown period is out,
    and ``_end_leftover_tasks`` ends what it leaves: this holds the two together. The
    period, ``SHUTDOWN_S`` (aiohttp's 60 s, and 10 s of lingering on this connection, held
    ``close()`` 10.5 s), is a time, not asserted: this test took 10-11 s before it, 1 s after."""
    server = _serve()
    size = 5_000_000
    with socket.create_connection(("127.0.0.1", server.port), timeout=HANG_S) as client:
        client.sendall(
            f"POST /api/control HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
            f"Content-Type: application/json\r\nContent-Length: {size}\r\n\r\n".encode()
        )
        sender = threading.Thread(target=client.sendall, args=(b"a" * size,), daemon=True)
        sender.start()  # the whole body, as curl sends it, while the 413 is read
        answer = waits.received(client, 64, "the server's answer to the body too large")
        assert answer.startswith(b"HTTP/1.1 413"), "the body is refused"
        sender.join(HANG_S)  # its body taken whole (the 413 read) before the server closes
        server.close()
        del server  # its loop, and any task left on it, are destroyed with it
        gc.collect()  # a pending task is said when it is destroyed
    destroyed = [r for r in caplog.records if "Task was destroyed" in r.getMessage()]
    assert destroyed == []


@pytest.mark.parametrize("killed", [False, True])
def test_a_killed_run_s_record_tells_the_page_its_last_tick_has_no_end(
    killed: bool, tmp_path: Path
) -> None:
    """The page titled a killed run's last tick "its last tick before the run ended", an end
    its record does not hold (the banner said so): the header and the updates carry
    ``no_end``, which the robot panel's title says (``Robot: its last recorded tick (no end
    recorded: ...)``); a whole record's is null (its panel shows the end)."""

    import aiohttp

    from roomba_bt.monitor.recorded import NO_END

    from .live import replayed_record

    feed, _ = replayed_record(SHUTTLE, "3s", tmp_path / "run.jsonl", killed=killed)
    server = MonitorServer(feed, None, port=0)
    server.start()

    async def listen() -> list[dict[str, Any]]:
        async with (
            aiohttp.ClientSession() as client,
            client.ws_connect(f"ws://127.0.0.1:{server.port}/ws") as ws,
        ):
            return [json.loads((await ws.receive()).data) for _ in range(2)]

    try:
        status, state = _call(f"http://127.0.0.1:{server.port}/api/state")
        hello, update = awaited(listen, "the page's reader")
    finally:
        server.close()
    expected = NO_END if killed else None
    assert status == 200 and state["header"]["no_end"] == expected, state["header"]
    assert hello["header"]["no_end"] == expected
    assert update["type"] == "update" and update["no_end"] == expected
    assert ("without the run's end" in update["finished"]) is killed, update["finished"]


def test_a_page_that_stopped_reading_is_sent_the_newest_state_not_a_backlog() -> None:
    """A laptop's lid closed: its page reads nothing for a while, then reads on. It was sent
    every update meanwhile (the sockets' buffers held them: 26 s of minute-old updates after
    a minute), which it then showed in turn, far behind the run. The pump holds a page that
    has not answered its ping for :data:`BEHIND_S`: on reading on it gets at most the
    updates of that second or so, then the newest state."""
    import asyncio

    import aiohttp

    from .live import start_live_run

    live = start_live_run(SHUTTLE)
    feed = live.feed

    def newest() -> int:
        latest = feed.latest()
        return latest.tick if latest else 0

    async def page() -> tuple[int, int]:
        async with (
            aiohttp.ClientSession() as client,
            client.ws_connect(f"ws://127.0.0.1:{live.server.port}/ws", max_msg_size=0) as ws,
        ):
            while "state" not in json.loads((await ws.receive()).data):
                pass  # the hello, and updates until the run has ticked
            stalled_at = newest()
            while newest() < stalled_at + 400:  # the lid closed for 6 s of the run's ticks
                await asyncio.sleep(0.05)  # reading nothing meanwhile
            woke_at, stale = newest(), 0
            while True:  # reads on: how many updates came before one of now
                message = json.loads((await ws.receive()).data)
                if message.get("state", {}).get("tick", -1) >= woke_at:
                    return stale, woke_at - stalled_at
                stale += 1

    try:
        stale, behind = awaited(page, "the page's reader")
    finally:
        live.finish()
    # 6 s of updates at 20 a second is 120: one second or so of them, at most 2 s
    assert stale <= 2 * round(1 / UPDATE_PERIOD_S) + 4, (stale, behind)


def test_a_server_whose_app_cannot_be_made_says_so_from_start(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The app was made outside the serving thread's ``try``: its failure was a thread's
    traceback on stderr, and ``start()`` returned the URL of a server that was not serving
    after waiting 10 s. It is ``start()``'s error now, at once."""
    feed = RunFeed(mission_name="dock")
    server = MonitorServer(feed, None, host="127.0.0.1", port=0)

    def broken() -> Any:
        raise OSError("no page to serve")

    monkeypatch.setattr(server, "app", broken)
    tracebacks: list[object] = []
    monkeypatch.setattr(threading, "excepthook", tracebacks.append)
    with pytest.raises(OSError, match="no page to serve"):
        server.start()
    assert tracebacks == []


def test_a_server_that_is_not_serving_in_time_is_an_error_not_a_url(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A bind that never completes (a host name whose lookup hangs) gave the URL with port
    0 after 10 s; it is an error naming the address after ``START_WITHIN_S``."""
    from roomba_bt.monitor import server as server_module

    feed = RunFeed(mission_name="dock")
    server = MonitorServer(feed, None, host="127.0.0.1", port=0)
    held = threading.Event()
    monkeypatch.setattr(server, "_serve", lambda: held.wait(10))
    monkeypatch.setattr(server_module, "START_WITHIN_S", 0.2)
    try:
        with pytest.raises(OSError, match=r"did not start on 127\.0\.0\.1:0 within 0.2 s"):
            server.start()
    finally:
        held.set()


def test_close_returns_once_the_server_has_ended_and_its_port_is_free(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The server's shutdown held for 6 s (a loaded machine's thread, a slow cleanup):
    ``close`` returns once its thread has ended and the port is free to listen on again. It
    gave up on the thread after 5 s and returned with it serving, its port still bound: a
    server started again there was refused (address in use)."""
    server = _serve()
    told = monitor_server._close_pages

    async def held(sockets: set[Any]) -> None:
        await asyncio.sleep(6.0)
        await told(sockets)

    monkeypatch.setattr(monitor_server, "_close_pages", held)
    server.close()
    assert server._thread is not None and not server._thread.is_alive()
    with socket.socket() as again:  # as aiohttp binds
        again.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        again.bind(("127.0.0.1", server.port))  # no listener left: no OSError (in use)
        again.listen(1)
