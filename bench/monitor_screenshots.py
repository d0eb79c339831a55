"""``make monitor-screenshots``: the pictures of the monitor page in ``docs/monitor.md``.

The dock mission runs in the apartment on the simulator's virtual clock with the monitor on.
Once ``dock_approach`` has been running for two seconds of mission time, the tick thread is
held (not paused: the robot stays in Safe, as a live page shows it mid-approach), headless
Chromium opens the page and takes the screenshots, and the run is then stopped.

Needs the ``monitor`` and ``browser-test`` extras and the OS's Chromium (``apt-get install
chromium``).
"""

from __future__ import annotations

import shutil
import sys
import threading
from pathlib import Path
from typing import Any

from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import world_view
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack
from roomba_bt.sim import SimLink, Simulator, load_world

ROOT = Path(__file__).resolve().parents[1]
IMAGES = ROOT / "docs" / "images"
APPROACH_S = 2.0


class HoldMidApproach(MonitorSession):
    """Holds the tick thread once ``dock_approach`` has run for :data:`APPROACH_S`."""

    def __init__(self, feed: RunFeed, **kwargs: Any) -> None:
        super().__init__(feed, **kwargs)
        self.held = threading.Event()
        self.release = threading.Event()
        self._approach = next(i.index for i in feed.infos if i.name.startswith("dock_approach"))
        self._since: float | None = None

    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        record = self.feed.latest()
        if record is None or self.held.is_set():
            return
        if record.statuses[self._approach] != "R":
            self._since = None
            return
        if self._since is None:
            self._since = record.time
        elif record.time - self._since >= APPROACH_S:
            self.held.set()
            self.release.wait(120)


def main() -> int:
    from playwright.sync_api import sync_playwright

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("needs chromium: apt-get install chromium", file=sys.stderr)
        return 2
    mission = load_mission(ROOT / "missions" / "dock.yaml", {}, profile=CREATE2)
    simulator = Simulator(load_world("apartment"), CREATE2, 3)
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=900.0)
    packets = stack.packets

    def truth() -> tuple[float, float, float]:
        return (simulator.x, simulator.y, simulator.theta)

    feed = RunFeed(truth=truth, world=world_view(simulator), mission_name=mission.name)
    feed.set_tree(mission.root)
    session = HoldMidApproach(feed, simulator=True, stream_packets=packets)
    server = MonitorServer(feed, session, port=0)
    url = server.start()
    stack.runner.gate = session
    thread = threading.Thread(target=stack.run, daemon=True)
    thread.start()
    if not session.held.wait(300):
        print("the dock run never reached two seconds of approach", file=sys.stderr)
        return 1
    IMAGES.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=chromium, headless=True, args=["--no-sandbox", "--disable-gpu"]
        )
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        page.wait_for_selector('#mode:text("Safe")')
        page.wait_for_timeout(800)
        page.screenshot(path=str(IMAGES / "monitor-dock-approach.png"))
        approach = next(i.index for i in feed.infos if i.name.startswith("dock_approach"))
        # clicked near the name's start: the menu opens where the click was, and from the
        # middle of the long name it ran past the picture's right edge (its title and its
        # last button cut off)
        page.click(f'.node[data-node="{approach}"] .name', position={"x": 12, "y": 8})
        page.wait_for_timeout(200)
        page.screenshot(
            path=str(IMAGES / "monitor-node-menu.png"),
            clip={"x": 0, "y": 0, "width": 900, "height": 560},
        )
        browser.close()
    session.request("stop")
    session.release.set()
    thread.join(30)
    server.close()
    for name in ("monitor-dock-approach.png", "monitor-node-menu.png"):
        print(f"wrote docs/images/{name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
