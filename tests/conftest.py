"""Suite-wide: under ``CI=true`` a test skipped for a missing test dependency fails instead;
``clean_blackboard`` for the folders whose tests write py_trees' blackboard.

Outside CI a missing optional package (the peer clients pycreate2 and PyRoombaAdapter,
matplotlib, jsonschema, the example wall-follow plugin) skips its tests with the install
hint; in CI that would hide a broken install step, so the skip becomes a failure that says
which package is missing.
"""

from __future__ import annotations

import os
from collections.abc import Generator, Iterator

import py_trees
import pytest

#: skip reasons that mean "a test dependency is not installed"
MISSING_DEPENDENCY = ("could not import", "No module named", "pip install")


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() == "true"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, None]:
    outcome = yield
    report: pytest.TestReport = outcome.get_result()
    if not (in_ci() and report.skipped and isinstance(report.longrepr, tuple)):
        return
    reason = str(report.longrepr[2])
    if any(sign in reason for sign in MISSING_DEPENDENCY):
        report.outcome = "failed"
        report.longrepr = f"CI=true: a test dependency is missing, so this fails: {reason}"


@pytest.fixture
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is one per process: empty before the test and after it."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()
