from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.episode import EpisodeResult
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


#: A 3 m x 2.5 m room; ``extra`` adds world lines (drops, virtual walls, events).
BOX = """
name: box
rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]
robot: {{start: {{at: [{x}, {y}], heading: {heading}}}}}
{extra}
"""
#: One leaf in Full mode with the brushes and the vacuum on, then Passive.
SWEEP = """
mission: sweep
tree:
  sequence:
    - mode: full
    - motors: {{main_brush: true, side_brush: true, vacuum: true}}
    - {leaf}
    - mode: passive
"""


Sweep = Callable[..., EpisodeResult]
SweepSpec = Callable[..., EpisodeSpec]


@pytest.fixture
def sweep_spec(tmp_path: Path) -> SweepSpec:
    """``sweep_spec(leaf, (x m, y m, heading deg), extra, timeout_s, **spec)``: the episode of
    the mission :data:`SWEEP` around ``leaf`` in the room :data:`BOX` on the simulator, from
    that start (``spec``: more :class:`EpisodeSpec` fields, such as ``seed``)."""

    def build(
        leaf: str,
        start: tuple[float, float, int],
        extra: str = "",
        timeout_s: float = 300.0,
        **spec: Any,
    ) -> EpisodeSpec:
        x, y, heading = start
        world = tmp_path / "box.yaml"
        world.write_text(BOX.format(x=x, y=y, heading=heading, extra=extra))
        mission = tmp_path / "sweep.yaml"
        mission.write_text(SWEEP.format(leaf=leaf))
        return EpisodeSpec(
            str(mission), str(world), random_start=False, timeout_s=timeout_s, **spec
        )

    return build


#: each episode :func:`sweep` ran in this session, by its arguments: "same spec, same result"
#: (:class:`EpisodeSpec`), and a ``cover`` of the room is seconds of CPU, which two tests
#: that ask the same episode (test_coverage_map.py: one pass, then two) need not pay twice.
#: The tests only read a result.
_SWEPT: dict[tuple[Any, ...], EpisodeResult] = {}


@pytest.fixture
def sweep(sweep_spec: SweepSpec) -> Sweep:
    """``sweep(...)``: :func:`sweep_spec`'s episode, run (once a session for the same
    arguments: :data:`_SWEPT`)."""

    def run(*args: Any, **kwargs: Any) -> EpisodeResult:
        spec = sweep_spec(*args, **kwargs)
        # the spec without its scratch paths, and the texts they hold: the episode itself
        key = (
            Path(spec.mission).read_text(),
            Path(spec.world).read_text(),
            dataclasses.replace(spec, mission="", world=""),
        )
        if key not in _SWEPT:
            _SWEPT[key] = run_episode(spec)
        return _SWEPT[key]

    return run
