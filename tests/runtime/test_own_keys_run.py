"""A subtree's own blackboard keys at run time (session 36): two uses of one subtree each
keep their own mark, under ``/mission/leg#1/here`` and ``/mission/leg#2/here``, beside the
mission's own ``here``; a plugin's key parameter in the body writes the use's key; and the
run's keys, the uses' among them, are gone once the run is closed."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import py_trees
import pytest

from roomba_bt.behaviours import default_registry
from roomba_bt.behaviours.blackboard import RunBoard
from roomba_bt.mission import CompiledMission, load_mission_text
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.interface import Odometry
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .own_keys import PASSED, CountInto


@pytest.fixture(autouse=True)
def _clean(clean_blackboard: None) -> Iterator[None]:
    yield


@contextmanager
def run_in_the_empty_room(mission: CompiledMission) -> Iterator[tuple[RunSummary, RunBoard]]:
    """``mission`` run to its end in the empty room: its summary, once it succeeded, and its
    blackboard, read before the run is closed (closing it frees the run's keys)."""
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=1, trace=False)
    with RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=20) as stack:
        summary = stack.run()
        assert summary.outcome is Outcome.SUCCESS, summary.exception
        board = stack.runner.blackboard
        assert board is not None
        yield summary, board


#: each leg marks where it starts and drives until 10 cm (the first) or 20 cm (the second)
#: from its own mark; a mission key ``here`` counts nothing the legs do
LEGS = """
mission: legs
blackboard:
  here: {type: int, initial: 5}
  legs: {type: int, initial: 0}
subtrees:
  leg:
    parameters:
      dist: {type: distance}
    blackboard:
      here: mark
      legs: {type: int, initial: 0}
    tree:
      sequence:
        - mark: {key: here}
        - drive: {velocity: 200 mm/s}
          until: {odometry: {since: here, distance: "${dist}"}}
        - count_into: {key: legs}
tree:
  sequence:
    - mode: safe
    - subtree: {id: leg, dist: 10cm}
    - subtree: {id: leg, dist: 20cm}
    - check: {key: here, value: 5}
    - check: {key: legs, value: 0}
"""


def test_two_uses_of_a_subtree_each_keep_their_own_mark() -> None:
    registry = default_registry().with_behaviours([CountInto])
    mission = load_mission_text(LEGS.lstrip(), name="legs.yaml", registry=registry)
    with run_in_the_empty_room(mission) as (summary, board):
        first, second = board.read("leg#1/here"), board.read("leg#2/here")
        assert isinstance(first, Odometry) and isinstance(second, Odometry)
        # the second leg marked where the first ended, 10 cm on, and drove 20 cm from there
        assert first.distance_mm == pytest.approx(0, abs=1)
        assert second.distance_mm == pytest.approx(100, abs=10)
        assert summary.distance_mm == pytest.approx(300, abs=15)
        shown = board.shown()
        assert shown["/mission/here"] == 5 and shown["/mission/legs"] == 0
        assert shown["/mission/leg#1/legs"] == 1 and shown["/mission/leg#2/legs"] == 1
    assert not py_trees.blackboard.Blackboard.storage  # closed: the uses' keys are gone too


def test_a_key_passed_down_by_name_is_the_uses_own_at_run_time() -> None:
    mission = load_mission_text(PASSED.lstrip(), name="passed.yaml")
    with run_in_the_empty_room(mission) as (summary, board):
        assert board.read("leg#1/here") == 100 and board.read("leg#2/here") == 200
        assert summary.distance_mm == pytest.approx(300, abs=15)
    assert not py_trees.blackboard.Blackboard.storage
