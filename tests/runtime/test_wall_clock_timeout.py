"""py_trees' own Timeout reads the wall clock: in a tree run on a virtual clock (the
simulator's SimLink, a replay, ``--fast``) it never fires, and the run says so once."""

from __future__ import annotations

import logging

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours.decorators import Timeout
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import TapLink
from .test_teardown import HandBuilt


class Forever(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        return Status.RUNNING


class WallClockTapLink(TapLink):
    wall_clock = True  # as a robot's port says by saying nothing


def _run(root: py_trees.behaviour.Behaviour, link: TapLink) -> Outcome:
    return RunStack(HandBuilt(root), link, profile=CREATE2, timeout_s=1.0).run().outcome


def _warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]


def test_a_wall_clock_timeout_on_the_virtual_clock_is_warned_of_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    root = py_trees.composites.Sequence("root", memory=True, children=[
        py_trees.decorators.Timeout("half a second", Forever("wait"), duration=0.5),
        Timeout("ours", Forever("also"), 0.5),
    ])  # fmt: skip
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    with caplog.at_level(logging.WARNING):
        outcome = _run(root, link)
    assert outcome is Outcome.TIMEOUT  # 1 s of mission time: py_trees' 0.5 s never fired
    (warning,) = [w for w in _warnings(caplog) if "Timeout" in w]
    assert "py_trees.decorators.Timeout 'half a second' reads the wall clock" in warning
    assert "roomba_bt.behaviours.decorators.Timeout (timeout: in a mission's YAML)" in warning
    assert "'ours'" not in warning


def test_no_warning_on_the_wall_clock_nor_for_ours(caplog: pytest.LogCaptureFixture) -> None:
    wall = py_trees.decorators.Timeout("wall", Forever("wait"), duration=60.0)
    with caplog.at_level(logging.WARNING):
        _run(wall, WallClockTapLink(Simulator(load_world("empty-room"), CREATE2, 0)))
        _run(
            Timeout("ours", Forever("also"), 0.5),
            TapLink(Simulator(load_world("empty-room"), CREATE2, 0)),
        )
    assert [w for w in _warnings(caplog) if "Timeout" in w] == []
