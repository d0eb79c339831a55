"""Shared helpers for the shipped-mission tests: paths and a world written inline."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MISSIONS = ROOT / "missions"
SHIPPED = sorted(MISSIONS.glob("*.yaml"))


@pytest.fixture(scope="module")
def cliff_world(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A room whose far half is a drop: driving straight ahead from the start finds it. One
    file a module (no test writes to it), so a module's shared run can be in it too."""
    path = tmp_path_factory.mktemp("cliff") / "cliff.yaml"
    path.write_text(
        "name: cliff-room\n"
        "rooms: [[[0, 0], [4, 0], [4, 2], [0, 2]]]\n"
        "drops: [{name: stairs, rect: [2.5, 0, 4, 2]}]\n"
        "robot: {start: {at: [1, 1], heading: 0}}\n"
    )
    return str(path)
