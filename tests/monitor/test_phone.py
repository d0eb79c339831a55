"""The monitor page on a phone held upright (390 px wide, in headless Chromium): a parent
watching a cleaning run. What matters is on the screen however far the page is scrolled: the
run's state, mode and battery beside the controls, the tree's running node, and a control's
answer on its way."""

from __future__ import annotations

import re
from typing import Any

from .conftest import on_screen
from .live import MISSIONS, LiveRun, start_live_run
from .test_browser import DEEPEST_RUNNING_ROW, WAIT_MS


def test_the_run_s_state_mode_and_battery_stay_on_the_screen_beside_the_controls(
    live: LiveRun, phone: Any
) -> None:
    """They were in the robot panel, below the tree and the events: scrolled to the path or
    the blackboard, the page showed neither whether the run was paused nor the battery."""
    phone.goto(live.url)
    phone.wait_for_selector('#status-mode:text-is("Safe")', timeout=WAIT_MS)
    assert phone.inner_text("#status-state") == "running"
    assert re.fullmatch(r"\d+ %", phone.inner_text("#status-battery"))
    phone.evaluate("window.scrollTo(0, document.body.scrollHeight)")
    phone.wait_for_timeout(100)
    for shown in ("#status-bar", "#link", "#pause", "#stop"):  # #link: the staleness badge
        assert on_screen(phone, shown), shown
    phone.click("#pause")
    phone.wait_for_selector('#status-mode:text-is("Passive")', timeout=WAIT_MS)
    assert phone.inner_text("#status-state").startswith("PAUSED")
    assert on_screen(phone, "#banner")  # why: paused by the operator, under the controls


#: where the deepest RUNNING node's name is, and the bottom of the page's stuck top
RUNNING_NODE_AND_TOP = """() => {
  const deepest = DEEPEST_RUNNING_ROW;
  if (!deepest) return null;
  const name = deepest.querySelector('.name').getBoundingClientRect();
  const stuck = Array.from(document.querySelectorAll('header, #alert, #banner'))
    .filter((e) => !e.hidden).map((e) => e.getBoundingClientRect().bottom);
  return {name: deepest.dataset.name, top: name.top, bottom: name.bottom,
          stuck: Math.max(...stuck)};
}""".replace("DEEPEST_RUNNING_ROW", DEEPEST_RUNNING_ROW)


#: the tree's scrollTop once it has stood still for three looks 50 ms apart: a wheel's scroll
#: is animated, and read at once it was caught on its way (202, then 0: a flake in CI)
SETTLED_TREE_SCROLL = """() => new Promise(resolve => {
    let last = -1, same = 0;
    const look = setInterval(() => {
        const now = document.querySelector('#tree').scrollTop;
        same = now === last ? same + 1 : 0;
        last = now;
        if (same >= 3) { clearInterval(look); resolve(now); }
    }, 50);
})"""


def test_the_running_node_is_kept_on_the_screen_until_the_reader_scrolls_the_tree(
    phone: Any,
) -> None:
    """The page scrolled a little (the tree's top under the stuck header), the running node
    was kept in the tree's box but under the header: off the screen. It is kept where it
    shows; a reader who scrolls the tree keeps the view they chose."""
    run = start_live_run(MISSIONS / "clean.yaml")  # about 70 rows: the tree scrolls
    try:
        phone.goto(run.url)
        phone.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
        phone.evaluate("window.scrollTo(0, 250)")
        phone.wait_for_function(
            f"(({RUNNING_NODE_AND_TOP})() || {{top: -1}}).top"
            f" >= ({RUNNING_NODE_AND_TOP})().stuck"
            f" && ({RUNNING_NODE_AND_TOP})().bottom <= window.innerHeight",
            timeout=WAIT_MS,
        )
        assert phone.evaluate("window.scrollY") == 250  # the page stays where the reader put it
        tree = phone.locator("#tree").bounding_box()
        assert tree is not None
        phone.mouse.move(tree["x"] + 40, tree["y"] + tree["height"] - 20)
        phone.mouse.wheel(0, -400)  # the reader scrolls the tree up: follow goes off
        phone.wait_for_selector('#follow[aria-pressed="false"]', timeout=WAIT_MS)
        kept = phone.evaluate(SETTLED_TREE_SCROLL)  # the wheel's scroll may still be moving
        phone.wait_for_timeout(300)  # several updates: the view stays where the reader put it
        assert phone.eval_on_selector("#tree", "el => el.scrollTop") == kept
    finally:
        run.finish()


def test_a_control_s_button_says_it_is_on_its_way_until_the_run_answers(
    live: LiveRun, phone: Any
) -> None:
    """A press showed nothing until the run's answer: on a slow link the parent pressed
    again, or took the robot for stopped. The button says "Pausing…" and takes no second
    press until the answer; Stop still goes meanwhile; a refusal gives the button back."""
    held: list[Any] = []  # the controls' requests, held as a slow link holds them
    phone.route("**/api/control", lambda route: held.append(route))
    phone.goto(live.url)
    phone.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    phone.click("#pause")
    phone.wait_for_selector('#pause:text-is("Pausing…")', timeout=WAIT_MS)
    assert phone.is_disabled("#pause") and phone.is_enabled("#stop")
    assert phone.get_attribute("#pause", "aria-busy") == "true"
    assert not live.session.state.paused  # nothing reached the run yet
    held.pop().continue_()
    phone.wait_for_selector('#pause:text-is("Pause")', timeout=WAIT_MS)
    phone.wait_for_selector('#mode:text("Passive")', timeout=WAIT_MS)
    assert phone.get_attribute("#pause", "aria-busy") == "false"
    phone.click("#resume")
    phone.wait_for_selector('#resume:text-is("Resuming…")', timeout=WAIT_MS)
    live.session.request("resume")  # the terminal's key meanwhile: this one comes too late
    phone.wait_for_selector('#mode:text("Safe")', timeout=WAIT_MS)
    held.pop().continue_()
    phone.wait_for_selector('#alert:has-text("resume refused (409: ")', timeout=WAIT_MS)
    assert phone.inner_text("#resume") == "Resume"
    assert phone.get_attribute("#resume", "aria-busy") == "false"
