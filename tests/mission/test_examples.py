"""Every shipped example mission loads and compiles; every library file validates."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import Permissions, load_mission, validate_files
from roomba_bt.robot.testing import StubRobot

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"
MISSIONS = sorted(EXAMPLES.glob("*.yaml"))
LIBRARIES = sorted((EXAMPLES / "lib").glob("*.yaml"))


def test_there_are_examples() -> None:
    assert len(MISSIONS) >= 5
    assert LIBRARIES


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_example_compiles_and_ticks(path: Path) -> None:
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    assert mission.name
    assert mission.packets
    robot = StubRobot()
    mission.setup(robot)
    robot.set_frame({pid: 0 for pid in (*mission.packets, 35)})
    mission.root.tick_once()  # one tick on a quiet frame: no exception, no port


@pytest.mark.parametrize("path", LIBRARIES, ids=lambda p: p.name)
def test_library_validates(path: Path) -> None:
    assert validate_files([path]) == []
