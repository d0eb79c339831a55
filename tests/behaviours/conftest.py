from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot


@pytest.fixture(autouse=True)
def _fresh_blackboard(clean_blackboard: None) -> None:
    """Every test here runs on an empty blackboard (``clean_blackboard``, tests/conftest.py)."""


@pytest.fixture
def robot() -> StubRobot:
    return StubRobot(mode=OIMode.SAFE)


Make = Callable[..., RobotBehaviour]


@pytest.fixture
def make(robot: StubRobot) -> Make:
    """``make(cls, **params)``: a behaviour with ``params`` (canonical units), set up on the
    stub robot (or on ``robot=`` another one)."""

    def build(cls: type[RobotBehaviour], robot: StubRobot = robot, **params: Any) -> RobotBehaviour:
        behaviour = cls(cls.declaration.name, params)
        behaviour.setup(robot=robot)
        return behaviour

    return build
