"""The monitor page in headless Chromium when things are not as they should be: the link to
the run drops and comes back, a phone's narrow screen, a recorded run rewound, the token in
the address bar (tests/monitor/test_browser.py has the page at work)."""

from __future__ import annotations

import json
import re
import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from waits import joined  # tests/waits.py: a hang's bound

from roomba_bt.mission import load_mission
from roomba_bt.monitor.recorded import NO_END
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.summary import Outcome

from .conftest import SHUTTLE, on_screen
from .live import LiveRun, replayed_record, start_live_run
from .test_browser import WAIT_MS


def _tick(page: Any) -> int:
    return int(page.inner_text("#tick"))


def test_a_dropped_link_turns_the_controls_off_a_control_says_it_was_not_sent_and_it_comes_back(
    live: LiveRun, page: Any
) -> None:
    """The page never connected again, kept its PAUSED banner and enabled controls, and a
    control clicked meanwhile failed without a word (an uncaught "Failed to fetch")."""
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    assert page.is_enabled("#pause")
    page.click("#pause")
    page.wait_for_selector('#banner:has-text("PAUSED for")', timeout=WAIT_MS)
    assert re.search(r"PAUSED for \d+ s — paused by the operator", page.inner_text("#banner"))
    port = live.server.port
    live.server.close()  # the link drops; the run goes on, paused
    page.wait_for_selector('#link:text("disconnected")', timeout=WAIT_MS)
    page.wait_for_selector('#banner:has-text("NO CONNECTION to the run")', timeout=WAIT_MS)
    assert "PAUSED then" in page.inner_text("#banner")
    for control in ("#pause", "#resume", "#step", "#stop"):
        assert page.is_disabled(control), control
    assert page.evaluate("document.body.classList.contains('stale')")
    page.keyboard.press("r")  # a stale page asks nothing (the HTTP side may reach the run)
    page.wait_for_selector('#alert:has-text("resume NOT sent: no connection to the run")',
                           timeout=WAIT_MS)  # fmt: skip
    assert live.session.state.paused  # nothing reached the run
    live.server = MonitorServer(live.feed, live.session, port=port)  # the network is back
    live.server.start()
    page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
    page.wait_for_selector("#resume:enabled", timeout=WAIT_MS)
    assert not page.evaluate("document.body.classList.contains('stale')")
    tick = _tick(page)
    page.wait_for_function(
        f"Number(document.getElementById('tick').textContent) > {tick + 10}", timeout=WAIT_MS
    )  # live again: the stream's ticks go on under the pause
    assert "PAUSED for" in page.inner_text("#banner")
    page.click("#resume")
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    assert not live.session.state.paused
    assert page.is_hidden("#alert")  # a control went through: the failed one's alert goes


def test_the_controls_are_off_until_the_page_knows_the_run(live: LiveRun, page: Any) -> None:
    """Before the socket's hello the four controls and the player looked usable."""
    page.route("**/static/monitor.js", lambda route: route.abort())
    page.goto(live.url)
    for control in ("#pause", "#resume", "#step", "#stop", "#live", "#timeline"):
        assert page.is_disabled(control), control
    assert page.is_hidden("#play") and page.is_hidden("#speed")


def test_on_a_phone_pause_and_stop_stay_on_the_screen_and_the_panels_stack(
    live: LiveRun, phone: Any
) -> None:
    phone.goto(live.url)
    phone.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    assert phone.evaluate("document.documentElement.scrollWidth") <= 390  # it was 916
    assert on_screen(phone, "#pause") and on_screen(phone, "#stop")
    robot = phone.locator("#robot-panel").bounding_box()
    tree = phone.locator("#tree-panel").bounding_box()
    assert robot and tree and robot["y"] >= tree["y"] + tree["height"]  # below, not beside
    phone.evaluate("window.scrollTo(0, document.body.scrollHeight)")
    phone.wait_for_timeout(100)
    assert on_screen(phone, "#pause") and on_screen(phone, "#stop")  # the header sticks
    phone.click("#pause")
    phone.wait_for_selector('#mode:text("Passive")', timeout=WAIT_MS)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[MonitorServer]:
    record_path = tmp_path_factory.mktemp("record") / "shuttle.jsonl"
    feed, _ = replayed_record(SHUTTLE, "6s", record_path)
    server = MonitorServer(feed, None, port=0)
    server.start()
    yield server
    server.close()


def _seek(page: Any, tick: int) -> None:
    page.eval_on_selector(
        "#timeline", "(el, v) => { el.value = v; el.dispatchEvent(new Event('input')); }", tick
    )
    page.wait_for_selector(f'#tick:text-is("{tick}")', timeout=WAIT_MS)


def test_a_rewound_record_s_robot_panel_is_titled_by_the_tick_it_shows(
    recorded: MonitorServer, page: Any
) -> None:
    """It said "its last tick before the run ended" at every tick of a record. At the
    record's end it shows what the recorded run's safe stop left the robot in."""
    page.goto(recorded.url)
    page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
    first, last = recorded.feed.window()
    assert first is not None and last is not None
    middle = recorded.feed.since(0)[0][(last.seq - first.seq) // 2].tick
    _seek(page, middle)
    assert page.inner_text("#robot-panel h2").lower() == f"robot at tick {middle}"
    _seek(page, last.tick)
    title = page.inner_text("#robot-panel h2").lower()
    assert title == "robot after the run ended: stopped, passive", title
    assert page.inner_text("#mode") == "Passive"


def test_a_killed_run_s_record_s_robot_panel_says_its_last_tick_has_no_end_after_it(
    tmp_path: Path, page: Any
) -> None:
    """A killed run's record (no end line) titled its last tick "Robot: its last tick
    before the run ended", an end the record does not hold, while the banner said the
    record ends without the run's end: the title says so too."""
    feed, _ = replayed_record(SHUTTLE, "6s", tmp_path / "killed.jsonl", killed=True)
    server = MonitorServer(feed, None, port=0)
    server.start()
    try:
        page.goto(server.url)
        page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
        page.wait_for_selector('#banner:has-text("without the run\'s end")', timeout=WAIT_MS)
        _, last = feed.window()
        assert last is not None
        _seek(page, last.tick)
        title = page.inner_text("#robot-panel h2").lower()
        assert title == f"robot: its last recorded tick ({NO_END})", title
        first, _ = feed.window()
        assert first is not None
        _seek(page, first.tick)  # rewound: the tick it shows
        assert page.inner_text("#robot-panel h2").lower() == f"robot at tick {first.tick}"
    finally:
        server.close()


def test_a_rewound_record_s_streamed_packets_are_those_of_the_tick_shown(
    recorded: MonitorServer, page: Any
) -> None:
    """The streamed-packets panel of a recorded run: every packet the run streamed, each
    value as the record has it at the tick the timeline shows (bits also in binary)."""
    page.goto(recorded.url)
    page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
    page.click("#packets-panel summary")
    records = recorded.feed.since(0)[0]
    middle = records[len(records) // 2]
    _seek(page, middle.tick)
    assert middle.frame is not None
    layout = recorded.feed.layouts[middle.layout]
    bits = {pid for pid in layout.members if PACKETS[pid].unit == "bits"}
    expected = [
        [str(pid), f"{value} = 0b{value:b}" if pid in bits else str(value)]
        for pid, value in zip(layout.members, middle.frame, strict=True)
    ]
    shown = page.eval_on_selector_all(
        "#packets tr[data-packet]",
        "rows => rows.map(r => [r.dataset.packet, r.cells[2].textContent])",
    )
    assert shown == expected
    title = page.inner_text("#packets-title").lower()  # CSS caps
    assert title == f"({len(expected)}) at tick {middle.tick}"


def test_a_seek_brings_its_events_into_view(recorded: MonitorServer, page: Any) -> None:
    """The events list stayed scrolled at 0.000 s whatever the tick shown."""
    page.goto(recorded.url)
    page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
    events = recorded.feed.events_after(-1)
    assert len(events) > 20  # more than the panel shows at once
    late = events[-3]
    _seek(page, late.tick)
    visible = page.evaluate(
        """() => {
            const box = document.getElementById('events-panel').getBoundingClientRect();
            const past = document.querySelectorAll('#events li:not(.future)');
            const last = past[past.length - 1].getBoundingClientRect();
            return last.top >= box.top && last.bottom <= box.bottom + 1;
        }"""
    )
    assert visible
    assert late.text in page.inner_text("#events")


def test_the_token_leaves_the_address_bar_and_the_cookie_still_opens_the_page(
    page: Any,
) -> None:
    run = start_live_run(SHUTTLE, host="0.0.0.0")
    try:
        token = run.server.token
        assert token
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert "token" not in page.url, page.url  # a screen share showed it
        response = page.reload()  # the cookie, Path=/, authorises the reload
        assert response is not None and response.status == 200
        page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        page.click("#pause")
        page.wait_for_selector('#banner:has-text("PAUSED")', timeout=WAIT_MS)
        assert json.dumps(run.session.state.paused) == "true"
    finally:
        run.finish()


def test_a_node_menu_left_open_across_a_drop_and_a_reload_closes_with_the_old_tree(
    live: LiveRun, page: Any, tmp_path: Path
) -> None:
    """The menu names its node by its index in the tree: left open while the link was down
    and the mission reloaded (``run --watch``), it came back enabled, and its break or force
    went to that index, another node of the new tree (here a wait put before ``mode``)."""
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    page.click('.node[data-name="there and back"] .name')
    page.wait_for_selector("#node-menu:visible", timeout=WAIT_MS)
    port = live.server.port
    live.server.close()
    page.wait_for_selector('#link:text("disconnected")', timeout=WAIT_MS)
    changed = tmp_path / "shuttle.yaml"
    changed.write_text(
        SHUTTLE.read_text()
        .replace("there and back", "out and home")
        .replace("    - mode: safe\n", "    - wait: 10ms\n    - mode: safe\n")
    )
    live.session.reload(load_mission(changed, {}, profile=CREATE2))
    deadline = time.monotonic() + WAIT_MS / 1000
    while "out and home" not in [info.name for info in live.feed.infos]:
        assert time.monotonic() < deadline, "the reload was not applied"
        time.sleep(0.01)
    live.server = MonitorServer(live.feed, live.session, port=port)
    live.server.start()
    page.wait_for_selector('.node[data-name="out and home"]', timeout=WAIT_MS)
    page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
    assert page.is_hidden("#node-menu")
    assert page.evaluate("view.menuNode") is None
    assert live.session.state.breakpoints == {}


#: counts the page's WebSockets (before its script runs)
COUNT_SOCKETS = """
window.sockets = [];
const NativeSocket = window.WebSocket;
window.WebSocket = class extends NativeSocket {
  constructor(...args) { super(...args); window.sockets.push(this); }
};
"""


def test_the_browser_s_online_while_a_try_is_connecting_opens_no_second_socket(
    live: LiveRun, page: Any
) -> None:
    """A try stuck connecting (a port that takes the connection and never answers, as a
    half-up Wi-Fi or tunnel does), then the browser's ``online``: it opened a second socket
    beside the first; two fed the page, and one's close marked a live page stale."""
    page.add_init_script(COUNT_SOCKETS)
    page.goto(live.url)
    page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
    port = live.server.port
    live.server.close()
    silent = socket.socket()
    try:
        silent.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        silent.bind(("127.0.0.1", port))
        silent.listen(8)  # takes the connection (the kernel's backlog), answers nothing
        page.wait_for_function(
            "window.sockets.length >= 2"  # the first try since the drop, stuck connecting
            " && window.sockets.at(-1).readyState === WebSocket.CONNECTING",
            timeout=WAIT_MS,
        )
        opened = page.evaluate(
            """() => {
                const before = window.sockets.length;
                window.dispatchEvent(new Event("online"));
                return window.sockets.length - before;
            }"""
        )
        assert opened == 0
    finally:
        silent.close()  # the try stuck connecting fails: the page tries again
    live.server = MonitorServer(live.feed, live.session, port=port)
    live.server.start()
    page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
    assert (
        page.evaluate("window.sockets.filter((s) => s.readyState === WebSocket.OPEN).length") == 1
    )


def test_two_monitors_on_one_host_keep_a_cookie_each(page: Any) -> None:
    """A browser keeps one host's cookies together whatever the port: the second monitor's
    page overwrote the first's cookie (one name), and the first page's reload got 403."""
    first = start_live_run(SHUTTLE, host="0.0.0.0")
    second = start_live_run(SHUTTLE, host="0.0.0.0")
    try:
        assert first.server.token != second.server.token
        page.goto(first.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        other = page.context.new_page()
        other.goto(second.url)
        other.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        for shown in (page, other):
            response = shown.reload()  # each by its own cookie
            assert response is not None and response.status == 200, response.status
            shown.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
        names = sorted(cookie["name"] for cookie in page.context.cookies())
        assert names == sorted(f"roomba_bt_monitor_{run.server.port}" for run in (first, second)), (
            names
        )
    finally:
        first.finish()
        second.finish()


def test_a_silent_link_says_so_and_turns_off_what_sets_the_robot_going(
    live: LiveRun, page: Any
) -> None:
    """A network stall that closes nothing (a train's tunnel: packets lost, no FIN) left the
    page under a green "connected" badge with Resume enabled; a Resume pressed then reached
    the run a minute later. Silent for 2 s, the page says so, resume and step are off (pause
    and stop still go: late, they are safe), and a key says it was not sent."""
    stalled: list[bool] = []  # the messages from the run are dropped while it holds True

    def through_a_stalling_network(route: Any) -> None:
        run = route.connect_to_server()
        run.on_message(lambda message: None if stalled else route.send(message))

    page.route_web_socket("**/ws", through_a_stalling_network)
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    page.click("#pause")
    page.wait_for_selector("#resume:enabled", timeout=WAIT_MS)
    stalled.append(True)
    page.wait_for_selector('#link:has-text("no word from the run for")', timeout=WAIT_MS)
    assert page.is_disabled("#resume") and page.is_disabled("#step")
    assert page.is_enabled("#stop")
    assert "NO WORD from the run for" in page.inner_text("#banner")
    assert page.evaluate("document.body.classList.contains('stale')")
    page.keyboard.press("r")
    page.wait_for_selector('#alert:has-text("resume NOT sent: no word from the run for")',
                           timeout=WAIT_MS)  # fmt: skip
    assert live.session.state.paused  # nothing reached the run
    stalled.clear()  # the network is back: fresh word from the run
    page.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
    page.wait_for_selector("#resume:enabled", timeout=WAIT_MS)
    assert not page.evaluate("document.body.classList.contains('stale')")
    page.click("#resume")
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    assert not live.session.state.paused


def test_the_event_log_scrolled_up_stays_where_the_reader_left_it(live: LiveRun, page: Any) -> None:
    """The live log was rebuilt and snapped to its bottom at every update (20 a second), so
    it could not be scrolled back nor a line selected. Scrolled up, it stays; at the bottom,
    it follows the new events, as a terminal does."""
    for n in range(80):
        live.feed.event("note", f"an event to scroll past, number {n}")
    page.goto(live.url)
    page.wait_for_selector('#events li:has-text("number 79")', timeout=WAIT_MS)
    box = "document.getElementById('events-panel')"
    assert page.evaluate(f"{box}.scrollHeight > {box}.clientHeight")
    page.evaluate("document.querySelector('#events li').dataset.marked = 'kept'")
    page.evaluate(f"{box}.scrollTop = 0")
    tick = _tick(page)
    page.wait_for_function(
        f"Number(document.getElementById('tick').textContent) > {tick + 20}", timeout=WAIT_MS
    )  # updates came
    live.feed.event("note", "a new event while the reader is up")
    page.wait_for_selector('#events li:has-text("while the reader is up")', timeout=WAIT_MS)
    assert page.evaluate(f"{box}.scrollTop") == 0
    assert page.evaluate("document.querySelector('#events li[data-marked]') !== null")  # kept
    page.evaluate(f"{box}.scrollTop = {box}.scrollHeight")
    live.feed.event("note", "a new event at the bottom")
    page.wait_for_selector('#events li:has-text("at the bottom")', timeout=WAIT_MS)
    page.wait_for_function(
        f"{box}.scrollHeight - {box}.scrollTop - {box}.clientHeight < 2", timeout=WAIT_MS
    )


def test_a_browser_s_shortcut_is_no_control_and_q_stops_the_run(live: LiveRun, page: Any) -> None:
    """The page took a key by its letter alone: Ctrl+R or Cmd+R, the browser's reload, read
    "r" and resumed a paused robot (Alt+R too), Ctrl+N stepped it. A shortcut now sends
    nothing; the four letters alone are the terminal's keys, q (Stop's title says "key q")
    too, which did nothing."""
    sent: list[str] = []
    page.on(
        "request",
        lambda request: (
            sent.append(json.loads(request.post_data or "{}").get("action", ""))
            if request.url.endswith("/api/control")
            else None
        ),
    )
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    page.click("#pause")
    page.wait_for_selector("#step:enabled", timeout=WAIT_MS)
    for shortcut in ("Control+r", "Meta+r", "Alt+r", "Control+n", "Control+p", "Control+q"):
        page.keyboard.press(shortcut)
    page.wait_for_selector("#step:enabled", timeout=WAIT_MS)  # a reload, if there was one
    page.keyboard.press("n")  # a key's request leaves at its press: after any of those
    page.wait_for_selector('#events:has-text("pause (stepped one tick)")', timeout=WAIT_MS)
    assert sent == ["pause", "step"], sent
    assert live.session.state.paused
    assert live.runner.summary.steps == 1
    page.keyboard.press("q")
    joined(live.thread, "the run, stopped by the page's q")  # not told to stop by the test
    assert live.result[0].outcome is Outcome.INTERRUPTED, live.result[0].outcome
    assert sent == ["pause", "step", "stop"], sent


def test_a_record_s_node_menu_says_why_its_buttons_are_off(
    recorded: MonitorServer, page: Any
) -> None:
    """A record's player opened a node's menu of greyed buttons that said nothing (and, as
    its run is over, would have said the run ended, which is not why)."""
    page.goto(recorded.url)
    page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
    page.click('.node[data-name="there and back"] .name')
    assert all(b.is_disabled() for b in page.query_selector_all("#node-menu button"))
    why = page.inner_text("#node-menu-why")
    assert why == "a recorded run: breakpoints and forces are for a live run", why
