"""The monitor page in a real headless Chromium: a simulated run watched and driven from it.

In-process runs (tests/monitor/live.py) let a test read the simulator itself: every step's
wheel speeds and OI mode, every byte written, with the simulated time. Runs that must end
with the command's own exit code are ``roomba-bt run`` subprocesses.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest
from waits import HANG_S, joined, lines  # tests/waits.py: a hang's bound, lines within it

from roomba_bt.monitor.server import MonitorServer
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.runtime.summary import Outcome

from .conftest import SHUTTLE
from .live import MISSIONS as MISSIONS_DIR
from .live import LiveRun, replayed_record, start_live_run

HERE = Path(__file__).resolve().parent
#: the most a page is waited for to show what a test waits for: the suite's hang bound
#: (tests/waits.py), in Playwright's milliseconds; 15 s before, which a page and a run
#: sharing 2 loaded cores with the rest of the suite may need
WAIT_MS = round(HANG_S * 1000)
#: the ``child`` fixture (tests/conftest.py)
Child = Callable[[Sequence[str]], "subprocess.Popen[str]"]


def monitored_run(mission: Path) -> list[str]:
    """``roomba-bt run MISSION --monitor 0``: its page on a free port, no terminal display."""
    return [sys.executable, "-m", "roomba_bt.cli", "run", str(mission), "--monitor", "0",
            "--display", "none"]  # fmt: skip


def statuses_on_page(page: Any) -> str:
    return str(page.eval_on_selector_all(".node", "els => els.map(e => e.dataset.status).join('')"))


def test_the_page_shows_the_tree_its_statuses_the_mode_and_the_sensors(
    live: LiveRun, page: Any
) -> None:
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    names = page.eval_on_selector_all(".node", "els => els.map(e => e.dataset.name)")
    assert names == [info.name for info in live.feed.infos]
    assert "there and back" in names
    seen = [statuses_on_page(page)]
    for _ in range(300):  # the shuttle's drives flip every 0.3 s: forth, back, forth
        page.wait_for_timeout(100)
        now = statuses_on_page(page)
        if now != seen[-1]:
            seen.append(now)
        if len(seen) >= 3:
            break
    assert len(seen) >= 3, seen
    assert page.inner_text("#bumps").split() == ["·", "·"]  # no bump, no wheel drop lamps
    assert "%" in page.inner_text("#battery")
    running = page.eval_on_selector_all(".node.running", "els => els.map(e => e.dataset.name)")
    assert "sequence" in running  # the running path is highlighted from the root


def _pause_write(run: LiveRun) -> float:
    """Simulated time of the write carrying the pause's safe stop (from Safe mode)."""
    expected = b"".join(c.data for c in (oi.halt(), oi.motors_off(), oi.start()))
    for t, data in run.writes:
        if expected in data:
            return t
    raise AssertionError(f"no pause sequence {expected.hex()} among the writes")


def _wait_for_wheels_turning(page: Any) -> None:
    """Until the Robot panel shows a wheel speed other than ``L 0 R 0``."""
    page.wait_for_function(
        "document.querySelector('#wheels') && !/L 0 R 0/.test("
        "document.querySelector('#wheels').textContent)",
        timeout=WAIT_MS,
    )


def test_pause_stops_the_wheels_within_two_frames_in_passive_and_resume_drives_again(
    live: LiveRun, page: Any, until: Callable[[Callable[[], bool]], None]
) -> None:
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    _wait_for_wheels_turning(page)
    page.click("#pause")
    page.wait_for_selector('#mode:text("Passive")', timeout=WAIT_MS)
    page.wait_for_selector('#wheels:text("L 0 R 0")', timeout=WAIT_MS)
    assert "PAUSED" in page.inner_text("#banner")
    written = _pause_write(live)
    after = [s for s in live.steps if s.time > written + 1e-9]
    stopped = next(
        i for i, s in enumerate(after) if s.left == 0 and s.right == 0 and s.mode is OIMode.PASSIVE
    )
    assert stopped < 2, after[:3]  # at 0 and Passive within 2 frames of the pause
    frozen = live.feed.latest()
    assert frozen is not None and not frozen.ticked
    page.click("#resume")
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    resumed_at = len(live.steps)
    # until it drives again, and the page has said so (before, a fixed 0.5 s, then a look)
    until(lambda: any(s.left or s.right for s in live.steps[resumed_at:]))
    page.wait_for_selector('#events:has-text("resume (resumed by the operator): back to Safe")',
                           timeout=WAIT_MS)  # fmt: skip
    assert "pause (paused by the operator)" in page.inner_text("#events")


def test_a_breakpoint_pauses_the_run_where_the_node_starts_and_step_ticks_once(
    live: LiveRun, page: Any
) -> None:
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    back = "drive(velocity=-100 mm/s, distance=3 cm)"
    index = [i.name for i in live.feed.infos].index(back)
    page.click(f'.node[data-node="{index}"] .name')
    page.click('[data-break="start"]')
    page.wait_for_selector('#banner:has-text("breakpoint")', timeout=WAIT_MS)
    assert f"breakpoint: {back} starts" in page.inner_text("#banner")
    row = page.locator(f'.node[data-node="{index}"]')
    assert row.get_attribute("data-status") == "R"
    assert "●" in row.inner_text()
    ticked_before = sum(1 for r in live.feed.since(0)[0] if r.ticked)
    page.click("#step")
    page.wait_for_selector('#banner:has-text("stepped one tick")', timeout=WAIT_MS)
    ticked_after = sum(1 for r in live.feed.since(0)[0] if r.ticked)
    assert ticked_after - ticked_before == 1
    assert live.session.state.paused


def test_a_node_s_menu_opens_from_the_keyboard_and_sets_a_breakpoint(
    live: LiveRun, page: Any
) -> None:
    """A node's menu (breakpoints, forces) opened on a click only: the tree's names took no
    focus, so a keyboard could not reach it. A name is reached by Tab, Enter or Space opens
    its menu with the focus in it, Escape closes it, and the focus goes back to the name."""
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    name = '.node[data-name="there and back"] .name'
    focused = "document.activeElement"
    page.focus(name)
    assert page.evaluate(f"{focused}.textContent") == "there and back"
    page.keyboard.press("Enter")
    assert page.is_visible("#node-menu")
    assert page.inner_text("#node-menu-title") == "there and back"
    assert page.evaluate(f"document.getElementById('node-menu').contains({focused})")
    page.keyboard.press("Escape")
    assert page.is_hidden("#node-menu")
    assert page.evaluate(f"{focused}.textContent") == "there and back"
    page.keyboard.press(" ")  # Space too; the focus on the menu's first button: starts
    assert page.evaluate(f"{focused}.dataset.break") == "start"
    page.keyboard.press("Enter")
    page.wait_for_selector('#banner:has-text("breakpoint: there and back starts")',
                           timeout=WAIT_MS)  # fmt: skip
    assert page.is_hidden("#node-menu")
    assert page.evaluate(f"{focused}.textContent") == "there and back"
    assert live.session.state.paused


def test_a_subtree_folds_and_unfolds_from_the_keyboard(live: LiveRun, page: Any) -> None:
    """The ▾/▸ toggles took a mouse's click only: no focus, no key, and a screen reader heard
    nothing of whether a subtree was open. Tab reaches a parent's toggle, Enter or Space
    folds and unfolds its subtree (its node's menu stays shut), and ``aria-expanded`` says
    which; a leaf has no toggle to stop at."""
    page.goto(live.url)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    row = '.node[data-name="there and back"]'
    toggle = page.locator(f"{row} .toggle")
    children = page.locator(f'{row} ~ .node[data-name^="drive("]')
    assert children.count() == 2 and children.first.is_visible()
    assert toggle.get_attribute("aria-expanded") == "true"
    page.focus(f"{row} .name")
    page.keyboard.press("Shift+Tab")  # back from the name: its own toggle
    assert page.evaluate("document.activeElement.classList.contains('toggle')")
    page.keyboard.press("Enter")
    assert toggle.get_attribute("aria-expanded") == "false" and toggle.inner_text() == "▸"
    assert children.first.is_hidden() and children.last.is_hidden()
    assert page.is_hidden("#node-menu")
    page.keyboard.press(" ")
    assert toggle.get_attribute("aria-expanded") == "true" and toggle.inner_text() == "▾"
    assert children.first.is_visible() and children.last.is_visible()
    leaf = page.locator(f'{row} ~ .node[data-name^="drive("] .toggle').first
    assert leaf.get_attribute("tabindex") is None and leaf.get_attribute("aria-expanded") is None


RETRIED = """
mission: retried
tree:
  sequence:
    - mode: safe
    - repeat:
        do:
          retry:
            times: 3
            do:
              sequence:
                - {name: there, drive: {velocity: 100 mm/s, distance: 3 cm}}
                - drive: {velocity: -100 mm/s, distance: 3 cm}
"""


def test_the_page_names_a_node_as_the_printed_trees_do(
    page: Any, child: Child, tmp_path: Path
) -> None:
    """The page said ``retry`` where the trees ``run`` prints before and after said
    ``retry(times=3)`` (``show``'s names); a node renamed by ``name:`` keeps that name
    (``show``'s ``drive(...) named 'there'`` is for reviewing it). The node's own name
    stays its handle: ``data-name``, the API, the events."""
    mission = tmp_path / "retried.yaml"
    mission.write_text(RETRIED)
    proc = child(monitored_run(mission))
    page.goto(_url_from(proc))
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    assert page.inner_text('.node[data-name="retry"] .name') == "retry(times=3)"
    assert page.inner_text('.node[data-name="there"] .name') == "there"
    page.click("#stop")
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err


def test_stop_ends_the_run_as_ctrl_c_with_the_safe_stop(page: Any, child: Child) -> None:
    proc = child(monitored_run(SHUTTLE))
    page.goto(_url_from(proc))
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    page.click("#stop")
    out, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    assert "outcome      INTERRUPTED (stopped by the operator)" in out
    # a robot still driving got drive 0 and motors off before the tree's stop (the wall clock)
    stopped = r"safe stop    (drive 0, motors off before the tree's stop, then )?sent drive, motors"
    assert re.search(stopped + r", pause_resume_stream, start", out), out
    assert "Traceback" not in err


def test_the_end_of_a_run_whose_link_was_lost_says_each_thing_once(
    page: Any, child: Child, served_sim: Callable[..., Any]
) -> None:
    """The simulator killed under a run (its TCP bridge gone, as a robot's Wi-Fi one): the
    page's banner ran the summary's final mode and safe stop together, five lines saying the
    stop was not delivered three times, and the robot panel's title said the final mode the
    row under it says. The banner says what happened, where the robot was left and what to
    do, a line each; the title says the stop was not delivered, once."""
    sim = served_sim("--tcp", "127.0.0.1:0")
    proc = child([*monitored_run(SHUTTLE), "--port", sim.address])
    page.goto(_url_from(proc))
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    sim.proc.kill()  # the link lost while the shuttle drives
    sim.proc.communicate(timeout=HANG_S)
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 8, err
    page.wait_for_selector('#link:text("ended")', timeout=WAIT_MS)
    happened, robot, to_do = page.inner_text("#banner").split("\n")
    assert happened.startswith(f"the run ended: connection lost: {sim.address}: the port is gone")
    assert robot.startswith("the robot: last seen in Safe"), robot
    assert "the stop was not delivered" in robot and "final mode" not in robot, robot
    assert to_do.startswith("the robot may still be moving: pick it up"), to_do
    title = page.inner_text("#robot-panel h2").lower()  # CSS caps
    assert title == "robot: last seen before the run ended (the stop was not delivered)", title
    assert page.inner_text("#robot tr:first-child td:nth-child(2)") == (
        "unknown: last seen in Safe, the stop was not delivered"
    )


def _url_from(proc: subprocess.Popen[str]) -> str:
    assert proc.stdout is not None
    said = lines(proc.stdout, lambda line: line.startswith("monitor: "), "the monitor's URL")
    assert said[-1].startswith("monitor: "), f"no 'monitor: URL' line from roomba-bt run: {said}"
    return said[-1].split()[1]


def test_a_recorded_run_on_the_timeline_shows_that_ticks_statuses(
    page: Any, tmp_path: Path
) -> None:
    record_path = tmp_path / "shuttle.jsonl"
    feed, summary = replayed_record(SHUTTLE, "4s", record_path)
    assert summary.ticks > 200
    records = feed.since(0)[0]
    final = records[-1].statuses
    chosen = next(r for r in records[100:] if r.statuses != final and r.changed)
    server = MonitorServer(feed, None, port=0)
    server.start()
    try:
        page.goto(server.url)
        page.wait_for_selector('#source:text("record")', timeout=WAIT_MS)
        assert page.is_hidden("#controls")
        assert page.is_hidden("#no-controls")  # a player: its badge and ▶ say what it is
        page.eval_on_selector(
            "#timeline",
            "(el, v) => { el.value = v; el.dispatchEvent(new Event('input')); }",
            chosen.tick,
        )
        page.wait_for_selector(f'#tick:text-is("{chosen.tick}")', timeout=WAIT_MS)
        page.wait_for_function(
            f"Array.from(document.querySelectorAll('.node')).map(e => e.dataset.status)"
            f".join('') === {json.dumps(chosen.statuses)}",
            timeout=WAIT_MS,
        )
        assert f"{chosen.tick * 0.015:.3f}" in page.inner_text("#time")
    finally:
        server.close()


def test_watch_reloads_a_valid_change_and_refuses_an_invalid_one(
    page: Any, tmp_path: Path, child: Child
) -> None:
    mission = tmp_path / "shuttle.yaml"
    mission.write_text(SHUTTLE.read_text())
    proc = child([*monitored_run(mission), "--watch"])
    page.goto(_url_from(proc))
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    mission.write_text(SHUTTLE.read_text().replace("there and back", "out and home"))
    page.wait_for_selector('.node[data-name="out and home"]', timeout=WAIT_MS)
    page.wait_for_selector('#events li:has-text("reloaded shuttle")', timeout=WAIT_MS)
    page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)  # the new tree drives
    broken = SHUTTLE.read_text().replace("velocity: 100 mm/s", "velocity: fast")
    mission.write_text(broken)
    refused = page.wait_for_selector('#events li:has-text("reload refused")', timeout=WAIT_MS)
    assert re.search(rf"{re.escape(str(mission))}:\d+:\d+", refused.inner_text())
    tick = int(page.inner_text("#tick"))
    page.wait_for_function(
        f"Number(document.getElementById('tick').textContent) > {tick + 20}",
        timeout=WAIT_MS,
    )  # the run goes on
    assert page.query_selector('.node[data-name="out and home"]') is not None
    page.click("#stop")
    out, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130
    assert re.search(rf"reload refused: {re.escape(str(mission))}:\d+:\d+", err), err
    assert "new tree starts at the next safe point" in out


def test_a_non_local_address_refuses_a_page_without_the_token(page: Any) -> None:
    run = start_live_run(SHUTTLE, host="0.0.0.0")
    try:
        token = run.server.token
        assert token and run.url.endswith(f"/?token={token}")
        port = run.server.port
        response = page.goto(f"http://127.0.0.1:{port}/")
        assert response is not None and response.status == 401
        assert "This link has no token" in page.content()
        response = page.goto(f"http://127.0.0.1:{port}/?token=wrong")
        assert response is not None and response.status == 403
        assert "This link is for another run or has expired" in page.inner_text("h1")
        control = page.request.post(
            f"http://127.0.0.1:{port}/api/control", data=json.dumps({"action": "pause"})
        )
        assert control.status == 401  # no token given: refused, nothing changes
        assert not run.session.state.paused
        page.goto(f"http://127.0.0.1:{port}/?token={token}")
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    finally:
        run.finish()


def test_a_view_only_link_has_its_controls_off_and_cannot_pause(page: Any) -> None:
    """A run shown to a class on a projector, or a link shared, drove the robot: the page's
    one token was the controls'. The view link's page shows the run, says it is view only,
    has its buttons, keys and node menu off, and its own request (with its cookie) to pause
    is refused; its reload (the cookie alone) is view-only too."""
    run = start_live_run(SHUTTLE, host="0.0.0.0")
    try:
        view_url = run.server.view_url
        assert view_url and run.server.view_token != run.server.token
        page.goto(view_url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert page.is_visible(f"#no-controls:text-is({json.dumps(VIEW_ONLY_NOTE)})")
        assert page.is_hidden("#controls")
        for button in ("#pause", "#resume", "#step", "#stop"):
            assert page.is_disabled(button), button
        page.click('.node[data-name="there and back"] .name')
        assert page.is_visible("#node-menu")
        assert all(b.is_disabled() for b in page.query_selector_all("#node-menu button"))
        # and says why (its greyed buttons said nothing)
        why = page.inner_text("#node-menu-why")
        assert why == "view only: breakpoints and forces are on the control link", why
        page.keyboard.press("Escape")
        tick = int(page.inner_text("#tick"))
        page.keyboard.press("p")
        status = page.evaluate(
            """async (run) => (await fetch("api/control", {method: "POST",
                 headers: {"Content-Type": "application/json"},
                 body: JSON.stringify({action: "pause", run})})).status""",
            run.feed.run_id,
        )
        assert status == 403
        page.wait_for_function(
            f"Number(document.getElementById('tick').textContent) > {tick + 20}",
            timeout=WAIT_MS,
        )  # the run went on
        assert not run.session.state.paused and run.session._requests.empty()
        page.reload()
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert page.is_visible("#no-controls") and page.is_hidden("#controls")
    finally:
        run.finish()


def test_a_view_link_opened_in_the_operator_s_browser_leaves_the_control_tab_its_controls(
    page: Any,
) -> None:
    """One browser kept one cookie for both links: the operator opened the view link (to see
    what the class sees) and the control tab, reloaded, was view-only. The view link's page
    is under /view/ with a cookie of its own: the control tab reloaded keeps its controls and
    pauses the run, and the view tab reloaded is still view-only."""
    run = start_live_run(SHUTTLE, host="0.0.0.0")
    try:
        page.goto(run.url)
        page.wait_for_selector("#pause:enabled", timeout=WAIT_MS)
        viewer = page.context.new_page()
        viewer.goto(str(run.server.view_url))
        viewer.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert viewer.is_visible("#no-controls") and viewer.is_hidden("#controls")
        for shown in (page, viewer):
            response = shown.reload()  # each by its own cookie: the token left the URL
            assert response is not None and response.status == 200, response.status
            shown.wait_for_selector('#link:text-is("connected")', timeout=WAIT_MS)
        assert viewer.is_visible("#no-controls") and viewer.is_hidden("#controls")
        page.wait_for_selector("#pause:enabled", timeout=WAIT_MS)
        assert page.is_hidden("#no-controls")
        page.click("#pause")
        page.wait_for_selector("#resume:enabled", timeout=WAIT_MS)  # paused: the server said
        assert run.session.state.paused
    finally:
        run.finish()


#: what a live page without controls says where they would be, by why it has none
VIEW_ONLY_NOTE = "view only: the controls are on the control link"
READONLY_NOTE = "read-only (--monitor-readonly): no controls on this page"


@pytest.mark.parametrize(
    ("readonly", "note"), [(True, READONLY_NOTE), (False, None)], ids=["readonly", "controls"]
)
def test_a_readonly_page_says_why_it_has_no_controls(
    page: Any, readonly: bool, note: str | None
) -> None:
    """``--monitor-readonly``'s page had its controls gone and said nothing of it: a viewer
    took it for broken. It says why where they would be (and the terminal's keys, in its
    tooltip); a page with its controls says nothing."""
    run = start_live_run(SHUTTLE, readonly=readonly)
    try:
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        if note is None:
            assert page.is_hidden("#no-controls") and page.is_visible("#controls")
        else:
            assert page.is_visible(f"#no-controls:text-is({json.dumps(note)})")
            assert page.is_hidden("#controls")
            assert "terminal keys" in (page.get_attribute("#no-controls", "title") or "")
    finally:
        run.finish()


BRUSHES = HERE / "missions" / "brushes.yaml"


def test_the_robot_panel_shows_the_brushes_and_vacuum_on_and_off_while_paused(
    page: Any,
) -> None:
    """An owner watching a clean could not see whether the brushes were on: the panel had no
    cleaning motor. It shows what the motors' command set and, streamed, their currents."""
    run = start_live_run(BRUSHES)
    try:
        page.goto(run.url)
        page.wait_for_selector('#motors:has-text("main brush ON")', timeout=WAIT_MS)
        motors = page.inner_text("#motors")
        assert "main brush ON inward" in motors
        assert "side brush ON clockwise" in motors
        assert "vacuum ON" in motors
        label = page.locator("#robot tr", has=page.locator("#motors")).locator("td").first
        assert label.inner_text() == "motors (Motors (138))"
        assert "main" in page.inner_text("#brush-currents")
        page.click("#pause")
        page.wait_for_selector('#mode:text("Passive")', timeout=WAIT_MS)
        page.wait_for_selector('#motors:has-text("off while paused")', timeout=WAIT_MS)
        assert "main brush off" in page.inner_text("#motors")
    finally:
        run.finish()


CRUMBS, DUSTY_ROOM = HERE / "missions" / "crumbs.yaml", HERE / "missions" / "dusty-room.yaml"
#: a pixel of a dirt patch on the Path panel: its fill, rgba(190,140,70,.35), over the room's
#: floor, #f4f4ee
DIRT_ON_THE_FLOOR = (225, 208, 179)
COUNT_PIXELS = """([r, g, b]) => {
  const canvas = document.getElementById('path');
  const data = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
  let count = 0;
  for (let i = 0; i < data.length; i += 4) {
    if (Math.abs(data[i] - r) <= 2 && Math.abs(data[i + 1] - g) <= 2
        && Math.abs(data[i + 2] - b) <= 2) count++;
  }
  return count;
}"""


def test_the_page_shows_every_streamed_packet_and_the_world_s_dirt(page: Any) -> None:
    """A plugin author's condition read dirt detect (15) over the world's crumbs: the page
    showed neither the packet (the robot panel's sensors are a fixed set) nor the crumbs.
    The streamed-packets panel, opened, lists every packet of the stream request with its
    name and unit and its value live; the Path panel shades each dirt patch."""
    run = start_live_run(CRUMBS, world=str(DUSTY_ROOM))
    try:
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert page.is_hidden("#packets")  # closed: its summary line only
        page.click("#packets-panel summary")
        dirt = '#packets tr[data-packet="15"]'
        page.wait_for_selector(f'{dirt} td:nth-child(3):text-is("40")', timeout=WAIT_MS)
        assert page.inner_text(f"{dirt} td:nth-child(2)") == "dirt_detect"
        wall = '#packets tr[data-packet="27"]'
        assert page.inner_text(f"{wall} td:nth-child(2)") == "wall_signal"
        assert page.inner_text('#packets tr[data-packet="43"] td:nth-child(4)') == "counts"
        assert page.inner_text('#packets tr[data-packet="7"] td:nth-child(3)') == "0 = 0b0"
        rows = page.eval_on_selector_all(
            "#packets tr[data-packet]", "rs => rs.map(r => +r.dataset.packet)"
        )
        assert rows == list(run.feed.layouts[-1].members)  # the stream request, in its order
        assert page.inner_text("#packets-title") == f"({len(rows)})"
        assert page.evaluate(COUNT_PIXELS, DIRT_ON_THE_FLOOR) > 1000  # both patches shaded
    finally:
        run.finish()


def test_after_the_run_the_robot_panel_shows_it_stopped_in_passive(page: Any, child: Child) -> None:
    """The robot panel froze on the last tick before the run's safe stop: the page of an
    ended run showed Safe, the wheels at their last speed and the brushes on. It shows what
    the stop left (Passive, the wheels at 0, the motors off) and says the run ended."""
    proc = child(monitored_run(BRUSHES))
    page.goto(_url_from(proc))
    page.wait_for_selector('#motors:has-text("main brush ON")', timeout=WAIT_MS)
    _wait_for_wheels_turning(page)
    page.click("#stop")
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    page.wait_for_selector('#link:text("ended")', timeout=WAIT_MS)
    assert page.inner_text("#mode") == "Passive"
    assert page.inner_text("#wheels") == "L 0 R 0"
    motors = page.inner_text("#motors")
    assert "main brush off" in motors and "vacuum off" in motors, motors
    assert "safe stop" in motors
    title = page.inner_text("#robot-panel h2")
    assert title.lower() == "robot after the run ended: stopped, passive", title  # CSS caps
    banner = page.inner_text("#banner")
    assert banner.startswith("the run ended: interrupted: stopped by the operator"), banner


def test_an_ended_run_s_timeline_says_it_reads_no_more_and_a_drag_does_not_stay(
    page: Any, child: Child
) -> None:
    """A page left open after its run: the timeline still took a drag, the slider stayed
    where it was dropped, and the label said ``live`` over the panels of the run's end: the
    seek went to a monitor that had closed with the run, and nothing said so. The timeline
    is off and says why."""
    proc = child(monitored_run(BRUSHES))
    page.goto(_url_from(proc))
    _wait_for_wheels_turning(page)
    page.click("#packets-panel summary")
    page.click("#stop")
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    page.wait_for_selector('#link:text("ended")', timeout=WAIT_MS)
    page.wait_for_selector("#timeline:disabled", timeout=WAIT_MS)
    # the streamed packets' title at the run's end, one line beside its marker (it took two,
    # its words squeezed into a column)
    title = page.inner_text("#packets-title").lower()  # in capitals before
    assert title.endswith(": the last frame, before the run's safe stop"), title
    lines_high = page.eval_on_selector(
        "#packets-panel summary",
        "s => s.getBoundingClientRect().height"
        " / parseFloat(getComputedStyle(s.querySelector('h2')).lineHeight)",
    )
    assert lines_high < 1.5, lines_high
    label = page.inner_text("#timeline-label")
    assert label.startswith("last tick "), label
    assert "the monitor has closed: no rewinding here" in label, label
    last = page.eval_on_selector("#timeline", "t => t.value")
    # a drag all the same (the slider is off; a script's input event): the seek finds no
    # monitor, and the slider goes back to the tick the panels show
    page.eval_on_selector(
        "#timeline", "t => { t.value = t.min; t.dispatchEvent(new Event('input')); }"
    )
    page.wait_for_function(
        f"document.querySelector('#timeline').value === {json.dumps(last)}", timeout=WAIT_MS
    )
    title = page.inner_text("#robot-panel h2")
    assert title.lower() == "robot after the run ended: stopped, passive", title


def test_a_run_s_label_leads_the_tab_s_title_and_the_header(page: Any) -> None:
    """Several robots' pages in one browser were told apart by their ports alone (the tabs
    all read the mission's name): ``run --label`` leads the title and shows in the header."""
    run = start_live_run(SHUTTLE, robot="/dev/ttyUSB1", label="robot 3")
    try:
        page.goto(run.url)
        page.wait_for_selector('#run-label:text("robot 3")', timeout=WAIT_MS)
        assert page.title() == "robot 3 · shuttle on /dev/ttyUSB1 · roomba-bt monitor"
    finally:
        run.finish()
    unlabelled = start_live_run(SHUTTLE, robot="/dev/ttyUSB1")
    try:
        page.goto(unlabelled.url)
        page.wait_for_selector('#mission:text("shuttle")', timeout=WAIT_MS)
        assert page.title() == "shuttle on /dev/ttyUSB1 · roomba-bt monitor"
        assert not page.is_visible("#run-label")
    finally:
        unlabelled.finish()


#: the deepest RUNNING node's row (the leaf at work), null when none runs: a JS expression
DEEPEST_RUNNING_ROW = """(() => {
  const rows = Array.from(document.querySelectorAll('.node[data-status="R"]'));
  const depth = (row) => Number(row.dataset.depth);
  return rows.length ? rows.reduce((a, b) => (depth(b) > depth(a) ? b : a)) : null;
})()"""
#: the deepest RUNNING node's name, and whether it is inside the tree panel's visible box
DEEPEST_RUNNING_IN_VIEW = """() => {
  const deepest = DEEPEST_RUNNING_ROW;
  if (!deepest) return null;
  const box = document.getElementById('tree').getBoundingClientRect();
  const name = deepest.querySelector('.name').getBoundingClientRect();
  return [deepest.dataset.name, name.top >= box.top && name.bottom <= box.bottom
          && name.left >= box.left && name.left < box.right];
}""".replace("DEEPEST_RUNNING_ROW", DEEPEST_RUNNING_ROW)


@pytest.mark.usefixtures("clean_blackboard")  # the cover's map left there: other tests saw it
def test_a_big_tree_stays_readable_and_its_running_node_in_view(page: Any) -> None:
    """The page fitted the clean mission's whole tree to the panel: 6 px text. Its labels stay
    at 12 px or more, the tree scrolls, and the deepest running node is kept in view;
    "follow" off leaves the scroll to the reader."""
    run = start_live_run(MISSIONS_DIR / "clean.yaml")
    try:
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        size = page.eval_on_selector(
            ".node .name", "el => parseFloat(getComputedStyle(el).fontSize)"
        )
        assert size >= 11, size
        assert page.eval_on_selector("#tree", "el => el.scrollHeight > el.clientHeight")
        page.wait_for_function(
            f"({DEEPEST_RUNNING_IN_VIEW})() && ({DEEPEST_RUNNING_IN_VIEW})()[1]",
            timeout=WAIT_MS,
        )
        page.click("#follow")
        page.eval_on_selector("#tree", "el => { el.scrollTop = 0; el.scrollLeft = 0; }")
        page.wait_for_timeout(300)  # several updates: the view stays where the reader put it
        assert page.eval_on_selector("#tree", "el => el.scrollTop") == 0
    finally:
        run.finish()


#: the focused element's text, whether it is inside the tree panel's visible box, and the tick
FOCUSED_IN_VIEW = """() => {
  const el = document.activeElement, box = document.getElementById('tree').getBoundingClientRect();
  const at = el.getBoundingClientRect();
  return [el.textContent, at.top >= box.top - 1 && at.bottom <= box.bottom + 1,
          Number(document.getElementById('tick').textContent)];
}"""


@pytest.mark.usefixtures("clean_blackboard")  # the cover's map left there: other tests saw it
def test_a_node_reached_by_tab_stays_in_view_as_the_run_goes_on(page: Any) -> None:
    """A keyboard's reader Tabbed to a node far from the running one (the clean mission's
    docking leaves, at the tree's end): the browser scrolled it into view, then *follow* pulled
    the view back to the running node at the next update, the focused name (whose menu Enter
    opens) out of sight. Tab onto a node turns *follow* off, as the wheel does; a click on a
    node leaves it on."""
    run = start_live_run(MISSIONS_DIR / "clean.yaml")
    try:
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        page.locator(".node .name").first.click()  # a click's focus: follow stays on
        assert page.get_attribute("#follow", "aria-pressed") == "true"
        # the menu the click may have opened closed, the focus on the root's name (in CI the
        # menu twice did not open after this click; not seen here: not what this test is of)
        page.keyboard.press("Escape")
        last = page.locator(".node .name").last
        for _ in range(page.locator(".node .name, .node .toggle[role=button]").count() + 20):
            page.keyboard.press("Tab")
            if last.evaluate("el => el === document.activeElement"):
                break
        name, shown, tick = page.evaluate(FOCUSED_IN_VIEW)
        assert name == last.text_content() and shown, (name, shown)
        page.wait_for_function(  # updates came (40 ticks): follow had pulled the view away
            f"Number(document.getElementById('tick').textContent) > {tick + 40}",
            timeout=WAIT_MS,
        )
        assert page.evaluate(FOCUSED_IN_VIEW)[:2] == [name, True]
        assert page.get_attribute("#follow", "aria-pressed") == "false"
    finally:
        run.finish()


#: each row shown whose status ends right of the tree's panel (its name, by how many px)
STATUSES_OFF_THE_PANEL = """() => {
  const box = document.getElementById('tree').getBoundingClientRect();
  return [...document.querySelectorAll('.node')].filter(row => !row.hidden)
    .map(row => [row.dataset.name,
                 row.querySelector('.st').getBoundingClientRect().right - box.right])
    .filter(([, past]) => past > 0.5);
}"""


@pytest.mark.usefixtures("clean_blackboard")  # the cover's map left there: other tests saw it
@pytest.mark.parametrize("width", [1400, 800, 390])
def test_a_long_name_keeps_its_status_in_the_panel_and_says_itself_whole(
    browser: Any, width: int
) -> None:
    """The clean mission's leaves with their parameters (``cover(speed=300 mm/s, edge_time=
    3min, ...)``, its ``log(message=...)``) pushed their status off the tree panel's right
    edge, past a horizontal scroll: in a laptop's window the log's, in a narrower one (the
    robot's panel beside the tree) or on a phone most of the deep rows'. A name is cut with
    an ellipsis and its status stays in the panel; the whole name is its title (a mouse's
    hover), and shown wrapped while it has the keyboard's focus."""
    context = browser.new_context(viewport={"width": width, "height": 800})
    page = context.new_page()
    run = start_live_run(MISSIONS_DIR / "clean.yaml")
    try:
        page.goto(run.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        page.click("#follow")  # the view left where the test puts it
        page.eval_on_selector("#tree", "el => { el.scrollTop = 0; el.scrollLeft = 0; }")
        assert page.evaluate(STATUSES_OFF_THE_PANEL) == []
        log = page.locator('.node[data-name^="log"] .name').first
        label = log.text_content()
        assert label is not None and label.startswith('log(message="cleaning stopped:'), label
        assert log.get_attribute("title") == label
        cut = "el => el.scrollWidth > el.clientWidth"
        assert log.evaluate(cut)  # shown cut short
        log.focus()
        assert not log.evaluate(cut)  # shown whole, wrapped, while focused
        assert page.evaluate(STATUSES_OFF_THE_PANEL) == []
    finally:
        run.finish()
        context.close()


def test_a_page_left_open_does_not_take_the_next_run_served_on_its_port(page: Any) -> None:
    """A run killed outright (no clean close of the page's socket), a new run started with
    the same --monitor port, perhaps on another robot: the page left open reconnected to it
    and showed it as its own, controls live, and its Pause paused the other robot. Now it
    names the other run, keeps its controls off, and a control it sends anyway is refused."""
    first = start_live_run(SHUTTLE, robot="/dev/ttyUSB0")
    port = first.server.port
    try:
        page.goto(first.url)
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert page.title() == "shuttle on /dev/ttyUSB0 · roomba-bt monitor"
        assert page.inner_text("#robot-name") == "on /dev/ttyUSB0"
        first.server.close()  # the run's process gone: its socket drops, no "ended" close
        page.wait_for_selector('#link:text("disconnected")', timeout=WAIT_MS)
    finally:
        first.finish()
    second = start_live_run(SHUTTLE, port=port, robot="/dev/ttyUSB1")
    try:
        banner = page.wait_for_selector('#banner:has-text("a different run")', timeout=WAIT_MS)
        assert banner is not None
        assert re.search(
            r"a different run is now served here \(shuttle on /dev/ttyUSB1, started "
            r"\d\d:\d\d:\d\d\): reload to watch it",
            banner.inner_text(),
        ), banner.inner_text()
        assert page.inner_text("#link") == "another run"
        for control in ("#pause", "#resume", "#step", "#stop"):
            assert page.is_disabled(control), control
        page.keyboard.press("p")
        page.wait_for_selector('#alert:has-text("pause NOT sent: a different run")',
                               timeout=WAIT_MS)  # fmt: skip
        # a control sent anyway (an old tab's script, a race with the hello): refused
        assert page.evaluate("control('pause')") is False
        assert "pause refused (409: this control was for another run" in page.inner_text("#alert")
        page.wait_for_timeout(300)  # the page connects no more: still the other run's banner
        assert "a different run" in page.inner_text("#banner")
        assert second.session._requests.empty() and not second.session.state.paused
        assert page.title() == "shuttle on /dev/ttyUSB0 · roomba-bt monitor"  # still A's
        page.reload()  # the operator's choice: now it is the second run's page
        page.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        assert page.title() == "shuttle on /dev/ttyUSB1 · roomba-bt monitor"
        page.click("#pause")
        page.wait_for_selector('#mode:text("Passive")', timeout=WAIT_MS)
        assert second.session.state.paused
    finally:
        second.finish()


def test_a_run_held_at_its_mission_s_end_says_its_resume_ends_the_run(page: Any) -> None:
    """A breakpoint on the tick the whole mission ends holds the run there, paused; the
    banner said "resume goes back to the mission's mode", where the resume ends the run with
    the mission's outcome (the event log said so, the banner not)."""
    run = start_live_run(HERE / "missions" / "wait-then-drive.yaml")
    try:
        run.session.request("break", 0, "end")  # the root: held when the mission ends
        page.goto(run.url)
        page.wait_for_selector('#banner:has-text("the mission ended")', timeout=WAIT_MS)
        banner = page.inner_text("#banner")
        assert "breakpoint: sequence ends" in banner, banner
        assert "the mission ended: SUCCESS; resume or step ends the run with it" in banner
        assert "goes back to the mission's mode" not in banner, banner
        title = page.get_attribute("#resume", "title")
        assert title == "end the run with the mission's outcome (key r)", title
        page.click("#resume")
        joined(run.thread, "the run held at its end, resumed")
        assert run.result[0].outcome is Outcome.SUCCESS
    finally:
        if run.thread.is_alive():
            run.finish()
        else:
            run.server.close()
