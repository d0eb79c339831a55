"""What the tests of a subtree's own keys share, checked (tests/mission/test_own_keys*.py)
and run (tests/runtime/test_own_keys_run.py): one mission text and one plugin, so the two
sides test the same thing and a change to either is made here once."""

from __future__ import annotations

from roomba_bt.behaviours import INT, STR, Condition, Param, declare, write_key
from roomba_bt.robot.interface import Snapshot


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


#: ``leg`` owns ``here``; ``measure`` writes the key its parameter names, and each ``leg``
#: drives the distance ``measure`` put in its own ``here`` (10 cm, then 20 cm)
PASSED = """
mission: passed
subtrees:
  measure:
    parameters: {out: {type: str}, length: {type: distance, default: 25cm}}
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
