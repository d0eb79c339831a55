"""The Python examples of docs/plugins.md run as written: the blackboard fixture, a mission
with a plugin file on the simulator from pytest (``RunStack`` and ``assert_success_rate``,
the plugin file allowed), and an action that waits for Safe/Full and fails once stranded."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from py_trees.common import Status

from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "plugins.md"


def _blocks(section: str) -> list[str]:
    text = DOC.read_text(encoding="utf-8")
    assert section in text, f"docs/plugins.md lost its section {section!r}"
    body = text.split(section, 1)[1].split("\n## ", 1)[0]
    return [str(b) for b in re.findall(r"```python\n(.*?)```", body, flags=re.DOTALL)]


def _run(block: str, name: str) -> dict[str, Any]:
    namespace: dict[str, Any] = {"__name__": f"docs_plugins_{name}"}
    exec(compile(block, f"{DOC}:{name}", "exec"), namespace)
    return namespace


def test_the_testing_examples_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """The fixture clears the blackboard; the mission naming near_wall.py runs on the
    simulator to SUCCESS with the plugin file allowed, once and from the start three times."""
    _, fixture, on_sim = _blocks("## 3. Test it without a robot")
    assert "Blackboard.clear()" in fixture
    assert "clean_blackboard" in _run(fixture, "fixture")
    monkeypatch.chdir(ROOT)  # the example's path is relative to the repository, as pytest's
    namespace = _run(on_sim, "simulator")
    namespace["test_near_wall_stops_the_drive_in_the_corridor"]()
    namespace["test_near_wall_succeeds_from_the_corridor_s_start"]()


def test_the_wait_for_driving_mode_example_fails_once_stranded() -> None:
    """``creep`` drives in Safe, waits (RUNNING) in Passive, and fails after the grace with
    the cause; nothing is sent while it waits."""
    [creep] = _blocks("## 4. An action: spot cleaning")[1:]
    cls = _run(creep, "creep")["Creep"]
    robot = StubRobot(mode=OIMode.SAFE)
    node = cls("creep", {})
    node.setup(robot=robot)
    robot.set_frame({})
    node.tick_once()
    assert node.status is Status.RUNNING
    assert [c.opcode for c in robot.flush()] == [137]
    robot.set_frame({}, mode=OIMode.PASSIVE)  # a cliff in Safe: the OI drops to Passive
    node.tick_once()
    assert node.status is Status.RUNNING and robot.flush() == []
    robot.set_frame({}, ticks=70)  # 1.05 s later, still in Passive
    node.tick_once()
    assert node.status is Status.FAILURE
    assert "left Safe/Full mode and was not brought back within 1 s" in node.feedback_message
