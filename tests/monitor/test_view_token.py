"""The view-only link: a run shown to a class on a projector, or a link shared, without the
controls. Anyone with the page's one token could pause, step, force and stop the robot; where
a token is in force there is now a view token too, which reads everything the page shows and
drives nothing."""

from __future__ import annotations

import asyncio
import json
import threading
import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

import pytest
from waits import HANG_S, joined  # tests/waits.py: a hang's bound

from roomba_bt.monitor.access import SAME_TOKEN
from roomba_bt.monitor.server import MonitorServer

from .test_server import SHUTTLE, _call, _control, _serve

#: a token of the operator's own (32 URL-safe characters)
CHOSEN = "Bookmark-ed_token-0123456789abcd"


@pytest.fixture
def lan() -> Iterator[MonitorServer]:
    """A live run's monitor on every address: a token in force."""
    served = _serve(host="0.0.0.0")
    yield served
    served.close()


def _hello(server: MonitorServer, at: str = "/", **headers: str) -> dict[str, Any]:
    """The header of the WebSocket's first message (the hello) for the page at ``at`` with
    ``headers``."""
    import aiohttp

    async def first() -> dict[str, Any]:
        async with (
            aiohttp.ClientSession() as client,
            client.ws_connect(f"ws://127.0.0.1:{server.port}{at}ws", headers=headers) as ws,
        ):
            message = await asyncio.wait_for(ws.receive(), HANG_S)
            hello = json.loads(message.data)
            assert hello["type"] == "hello"
            return dict(hello["header"])

    got: list[dict[str, Any]] = []
    # an event loop of its own: the browser tests' driver may own this thread's
    reader = threading.Thread(target=lambda: got.append(asyncio.run(first())))
    reader.start()
    joined(reader, "the page's reader")  # the wait_for's bound at the latest
    assert got, "no hello"
    return got[0]


class NoRedirect(urllib.request.HTTPRedirectHandler):
    """A redirect answered, not followed: what the page's own answer is."""

    def redirect_request(self, *args: Any) -> None:
        return None


def _page_answer(server: MonitorServer, at: str, token: str) -> tuple[int, dict[str, str], str]:
    """``GET AT?token=TOKEN``: its status, the cookies it sets (``name: value; Path=...``)
    and where it sends the browser ("" for nowhere)."""
    url = f"http://127.0.0.1:{server.port}{at}?token={token}"
    try:
        reply = urllib.request.build_opener(NoRedirect).open(url, timeout=HANG_S)
    except urllib.error.HTTPError as exc:
        reply = exc
    with reply:
        headers = reply.headers
        cookies = dict(c.split("=", 1) for c in headers.get_all("Set-Cookie") or [])
        return reply.status, cookies, headers.get("Location", "")


def test_the_view_token_reads_the_run_and_gets_403_on_every_control(
    lan: MonitorServer,
) -> None:
    control, view = lan.token, lan.view_token
    assert control and view and view != control and len(view) >= 24
    assert lan.view_url == f"http://0.0.0.0:{lan.port}/view/?token={view}"
    base = f"http://127.0.0.1:{lan.port}"
    assert _call(f"{base}/view/?token={view}")[0] == 200
    assert _call(f"{base}/static/monitor.js", headers={"X-Monitor-Token": view})[0] == 200
    status, _ = _call(f"{base}/api/state", headers={"X-Monitor-Token": view})
    assert status == 409  # authorised: no tick yet (401/403 for a token it refuses)
    header = _hello(lan, **{"X-Monitor-Token": view})
    assert header["controls"] is False and header["view_only"] is True
    assert header["can_force"] is False  # the simulator's force: not for a viewer either
    condition = next(i for i, info in enumerate(lan.feed.infos) if info.condition)
    for payload in (
        {"action": "pause"},
        {"action": "stop"},
        {"action": "force", "node": condition, "value": "success"},
        {"action": "break", "node": 0, "value": "start"},
    ):
        got, body = _control(lan, payload, **{"X-Monitor-Token": view})
        assert got == 403, payload
        assert body["error"].startswith("view-only link: controls need the control link")
    assert lan.session is not None and lan.session._requests.empty()


def test_the_control_token_still_controls_and_a_wrong_token_is_refused_as_before(
    lan: MonitorServer,
) -> None:
    control = str(lan.token)
    header = _hello(lan, **{"X-Monitor-Token": control})
    assert header["controls"] is True and header["view_only"] is False
    assert header["can_force"] is True  # the simulator
    assert _control(lan, {"action": "pause"}, **{"X-Monitor-Token": control})[0] == 202
    assert _control(lan, {"action": "pause"})[0] == 401
    got, body = _control(lan, {"action": "pause"}, **{"X-Monitor-Token": "x" * 24})
    assert got == 403 and "wrong token" in body["error"]
    assert _call(f"http://127.0.0.1:{lan.port}/?token={str(lan.view_token)[:-1]}")[0] == 403


def test_a_viewer_cannot_take_the_controls_by_the_cookie(lan: MonitorServer) -> None:
    """The view link's pages are under /view/, whose cookie is their own (its name and its
    Path): one browser kept one cookie for both links, and a view link opened in the
    operator's browser made the control tab, reloaded, view-only. A page there has no
    controls whichever token it holds, so neither a viewer's cookie nor the control page's,
    which the browser sends there too, gives it the controls."""
    control, view = str(lan.token), str(lan.view_token)
    name, view_name = f"roomba_bt_monitor_{lan.port}", f"roomba_bt_monitor_view_{lan.port}"
    assert _page_answer(lan, "/view/", view) == (
        200, {view_name: f"{view}; HttpOnly; Path=/view/; SameSite=Strict"}, ""
    )  # fmt: skip
    assert _page_answer(lan, "/", control) == (
        200, {name: f"{control}; HttpOnly; Path=/; SameSite=Strict"}, ""
    )  # fmt: skip
    # a bookmark of the view link from before it had its path: there, no cookie set here
    assert _page_answer(lan, "/", view) == (303, {}, f"/view/?token={view}")
    assert _page_answer(lan, "/view", view) == (303, {}, f"/view/?token={view}")
    viewer = {"Cookie": f"{view_name}={view}"}
    both = {"Cookie": f"{name}={control}; {view_name}={view}"}  # the operator's browser
    for cookies in (viewer, both, {"Cookie": f"{name}={control}"}):
        assert _hello(lan, "/view/", **cookies)["controls"] is False
        assert _control(lan, {"action": "pause"}, "/view/", **cookies)[0] == 403
    assert _hello(lan, "/view/", **{"X-Monitor-Token": control})["controls"] is False
    assert lan.session is not None and lan.session._requests.empty()
    assert _hello(lan, "/", **both)["controls"] is True  # the view page's cookie: not sent
    assert _control(lan, {"action": "pause"}, **both)[0] == 202


def test_loopback_without_a_token_has_no_view_link_and_keeps_its_controls() -> None:
    served = _serve()
    try:
        assert served.token is None and served.view_token is None and served.view_url is None
        header = _hello(served)
        assert header["controls"] is True and header["view_only"] is False
        assert _control(served, {"action": "pause"})[0] == 202
    finally:
        served.close()


def test_a_chosen_view_token_puts_a_control_token_in_force_on_loopback() -> None:
    """A view token alone would guard nothing there: without a token everyone controls."""
    from roomba_bt.mission import load_mission
    from roomba_bt.monitor.feed import RunFeed
    from roomba_bt.monitor.session import MonitorSession
    from roomba_bt.oi.profiles import CREATE2

    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    feed = RunFeed(mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True)
    with pytest.raises(ValueError, match=SAME_TOKEN):
        MonitorServer(feed, session, port=0, token=CHOSEN, view_token=CHOSEN)
    served = MonitorServer(feed, session, port=0, view_token=CHOSEN)
    served.start()
    try:
        assert served.token is not None and served.view_token == CHOSEN
        base = f"http://127.0.0.1:{served.port}"
        assert _call(f"{base}/")[0] == 401
        assert _control(served, {"action": "pause"}, **{"X-Monitor-Token": CHOSEN})[0] == 403
        assert _control(served, {"action": "pause"}, **{"X-Monitor-Token": served.token})[0] == 202
    finally:
        served.close()


def test_a_readonly_or_recorded_monitor_has_one_token_and_no_view_link() -> None:
    """Nothing to withhold: its one token's page has no controls already."""
    for served in (_serve(host="0.0.0.0", readonly=True), _serve(host="0.0.0.0", live=False)):
        try:
            assert served.token is not None and served.view_token is None
            header = _hello(served, **{"X-Monitor-Token": served.token})
            assert header["controls"] is False and header["view_only"] is False
        finally:
            served.close()
