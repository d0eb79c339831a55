"""The monitor's tests: a real headless Chromium (the OS's package, driven by Playwright).

Outside CI a machine without Chromium or Playwright skips the browser tests; under CI
(``CI=true``) a missing browser is a failure: ``.ci/run`` installs it.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from .live import LiveRun

#: the shuttle mission of the live page's tests (tests/monitor/missions)
SHUTTLE = Path(__file__).parent / "missions" / "shuttle.yaml"

BROWSER_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def _chromium() -> str | None:
    for candidate in (os.environ.get("ROOMBA_BT_CHROMIUM"), "chromium", "chromium-browser"):
        if candidate and (path := shutil.which(candidate)):
            return path
    return None


def _missing(why: str) -> None:
    if os.environ.get("CI") == "true":
        pytest.fail(f"{why}: CI must run the browser tests (.ci/run installs chromium)")
    pytest.skip(why)


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    """Headless Chromium with a fresh profile (Playwright gives each launch a new one)."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _missing("playwright is not installed (pip install 'roomba-bt[browser-test]')")
    executable = _chromium()
    if executable is None:
        _missing("no chromium on this machine (apt-get install chromium)")
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=executable, headless=True, args=BROWSER_ARGS
        )
        try:
            yield launched
        finally:
            launched.close()


#: a phone held upright (390 x 844 CSS pixels: an iPhone 12 to 14), with touch
PHONE = {"viewport": {"width": 390, "height": 844}, "is_mobile": True, "has_touch": True}


def _opened(browser: Any, **options: Any) -> Iterator[Any]:
    """A page in a fresh context; the test fails if the page's script raised."""
    context = browser.new_context(**options)
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        yield opened
    finally:
        context.close()
    assert not errors, f"the page raised: {errors}"


def on_screen(page: Any, selector: str) -> bool:
    """Whether the element is wholly inside the window (not scrolled off it)."""
    box = page.locator(selector).bounding_box()
    if not box:
        return False
    size = page.viewport_size
    right, bottom = box["x"] + box["width"], box["y"] + box["height"]
    return box["x"] >= 0 and box["y"] >= 0 and right <= size["width"] and bottom <= size["height"]


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    """A laptop's window."""
    yield from _opened(browser, viewport={"width": 1400, "height": 900})


@pytest.fixture
def phone(browser: Any) -> Iterator[Any]:
    """A phone's screen (:data:`PHONE`): the page's narrow layout."""
    yield from _opened(browser, **PHONE)


@pytest.fixture
def live() -> Iterator[LiveRun]:
    """The shuttle mission on the simulator, its monitor served (tests/monitor/live.py,
    imported here: it imports aiohttp, and ``pytest tests/monitor`` reads this conftest
    before tests/conftest.py skips the folder where the monitor extra is missing)."""
    from .live import start_live_run

    run = start_live_run(SHUTTLE)
    try:
        yield run
    finally:
        if run.thread.is_alive():
            run.finish()
        else:
            run.server.close()
