"""Fixtures for the command-line tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from runtime.simrun import SHORT_DRIVE, write_mission  # tests/runtime: the short drive


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    """The short drive the command lines here run: ``short.yaml``, 20 cm at a ``speed``
    parameter that defaults to 200 mm/s."""
    return write_mission(tmp_path, SHORT_DRIVE, "short.yaml")
