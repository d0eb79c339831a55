"""The dirt plugin: its declarations, both behaviours on a stub robot, and its example mission
in a simulated room with dirt on the floor."""

from __future__ import annotations

import re
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status
from roomba_bt_dirt import DirtDetect, SpotClean

from roomba_bt.behaviours import default_registry
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
MISSION, WORLD = EXAMPLES / "dirt.yaml", EXAMPLES / "dirty-room.yaml"


def installed() -> bool:
    try:
        distribution("roomba-bt-dirt")
    except PackageNotFoundError:
        return False
    return True


needs_install = pytest.mark.skipif(
    not installed(), reason="pip install -e plugins/roomba-bt-dirt to test its entry point"
)


@pytest.fixture
def robot() -> StubRobot:
    py_trees.blackboard.Blackboard.clear()
    return StubRobot(mode=OIMode.SAFE)


@needs_install
def test_both_come_through_the_entry_point_group() -> None:
    registry = default_registry()
    dirt, spot = registry.get("dirt_detect"), registry.get("spot_clean")
    assert dirt is not None and dirt.cls is DirtDetect and "roomba-bt-dirt" in dirt.origin
    assert spot is not None and spot.cls is SpotClean
    assert dirt.packets({}) == (15,)
    assert spot.leads_to is OIMode.PASSIVE and spot.sends == (134,)


def test_dirt_detect_compares_packet_15_with_the_level(robot: StubRobot) -> None:
    node = DirtDetect("dirt_detect", {"level": 20})
    node.setup(robot=robot)
    for level, expected in ((0, Status.FAILURE), (19, Status.FAILURE), (20, Status.SUCCESS)):
        robot.set_frame({15: level, 35: 2})
        node.tick_once()
        assert node.status is expected, level


def test_spot_clean_sends_134_then_waits_for_the_spiral_to_end(robot: StubRobot) -> None:
    node = SpotClean("spot_clean", {"settle": 1.0, "timeout": 60.0})
    node.setup(robot=robot)
    robot.set_frame({43: 0, 44: 0, 35: 1})
    node.tick_once()
    assert [list(c.data) for c in robot.flush()] == [[134]]
    assert node.status is Status.RUNNING
    for counts in range(1, 20):  # the spiral turns the wheels
        robot.set_frame({43: counts * 10, 44: counts * 12, 35: 1})
        node.tick_once()
        assert node.status is Status.RUNNING
    still = 0
    while node.status is Status.RUNNING:  # then they stand still
        robot.set_frame({43: 190, 44: 228, 35: 1})
        node.tick_once()
        still += 1
    assert node.status is Status.SUCCESS and still == 67  # 1 s of 15 ms ticks
    assert robot.flush() == []  # nothing more on the wire


def test_spot_clean_fails_when_the_spiral_outlasts_the_timeout(robot: StubRobot) -> None:
    node = SpotClean("spot_clean", {"settle": 1.0, "timeout": 1.0})
    node.setup(robot=robot)
    counts = 0
    while node.status in (Status.INVALID, Status.RUNNING):
        counts += 5
        robot.set_frame({43: counts, 44: counts, 35: 1})
        node.tick_once()
    assert node.status is Status.FAILURE
    assert "still running after 1 s" in node.feedback_message


@needs_install
def test_the_example_drives_onto_the_dirt_and_spot_cleans(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The dirty-room world's patch is 1.3 m ahead: the drive ends there (dirt_detect), not
    after its 2.5 m, and the robot's spot spiral runs to its end (30 s in the simulator)."""
    from roomba_bt.cli import main

    argv = ["run", str(MISSION), "--world", str(WORLD), "--fast", "--display", "none"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert re.search(r"outcome\s+SUCCESS", out), out + err
    found = re.search(r"duration\s+([\d.]+) s mission time", out)
    # 1.3 m at 200 mm/s then a 30 s spiral; the whole 2.5 m drive first would take over 42 s
    assert found is not None and 30.0 < float(found.group(1)) < 40.0
