"""The monitor's tests: a real headless Chromium (the OS's package, driven by Playwright).

Outside CI a machine without Chromium or Playwright skips the browser tests; under CI
(``CI=true``) a missing browser is a failure: ``.ci/run`` installs it.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from .live import LiveRun, start_live_run

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


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        yield opened
    finally:
        context.close()
    assert not errors, f"the page raised: {errors}"


@pytest.fixture
def live() -> Iterator[LiveRun]:
    """The shuttle mission on the simulator, its monitor served (tests/monitor/live.py)."""
    run = start_live_run(SHUTTLE)
    try:
        yield run
    finally:
        if run.thread.is_alive():
            run.finish()
        else:
            run.server.close()
