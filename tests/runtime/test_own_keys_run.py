"""A subtree's own blackboard keys at run time (session 36): two uses of one subtree each
keep their own mark, under ``/mission/leg#1/here`` and ``/mission/leg#2/here``, beside the
mission's own ``here``; a plugin's key parameter in the body writes the use's key; and the
run's keys, the uses' among them, are gone once the run is closed."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest

from roomba_bt.behaviours import INT, STR, Condition, Param, declare, default_registry, write_key
from roomba_bt.mission import load_mission_text
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.interface import Odometry, Snapshot
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world


@pytest.fixture(autouse=True)
def _clean(clean_blackboard: None) -> Iterator[None]:
    yield


@declare(
    "count_into",
    kind="condition",
    params=(Param("key", STR, from_blackboard=False, doc="an int key"),),
    writes_keys={"key": INT},
)
class CountInto(Condition):
    """Writes 1 to the key its parameter names (a plugin's key parameter)."""

    def check(self, snapshot: Snapshot) -> bool:
        write_key(str(self.value("key")), 1, self.name)
        return True


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
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=1, trace=False)
    with RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=20) as stack:
        summary = stack.run()
        assert summary.outcome is Outcome.SUCCESS, summary.exception
        board = stack.runner.blackboard
        assert board is not None
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


#: ``measure`` writes the key its parameter names; each ``leg`` passes its own ``here``
#: down by name and drives the distance ``measure`` put there
PASSED = """
mission: passed
subtrees:
  measure:
    parameters: {out: {type: str}, length: {type: distance}}
    tree:
      set: {key: "${out}", value: "${length}"}
  leg:
    blackboard: {here: distance}
    parameters: {length: {type: distance}}
    tree:
      sequence:
        - subtree: {id: measure, out: here, length: "${length}"}
        - drive: {distance: "@here"}
tree:
  sequence:
    - mode: safe
    - subtree: {id: leg, length: 10cm}
    - subtree: {id: leg, length: 20cm}
"""


def test_a_key_passed_down_by_name_is_the_uses_own_at_run_time() -> None:
    mission = load_mission_text(PASSED.lstrip(), name="passed.yaml")
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=1, trace=False)
    with RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=20) as stack:
        summary = stack.run()
        assert summary.outcome is Outcome.SUCCESS, summary.exception
        board = stack.runner.blackboard
        assert board is not None
        assert board.read("leg#1/here") == 100 and board.read("leg#2/here") == 200
        assert summary.distance_mm == pytest.approx(300, abs=15)
    assert not py_trees.blackboard.Blackboard.storage
