"""A mission's blackboard keys as py_trees' own tools see them (a py_trees user's report):
``Blackboard.keys()``, ``py_trees.display.unicode_blackboard()`` and the activity stream
showed nothing of ``/mission/legs``, though a client could read it, because the keys were
written into the store with no client registering them."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import py_trees
import pytest

from roomba_bt.behaviours.blackboard import MISSION_CLIENT_NAME
from roomba_bt.mission import load_mission
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import write_mission

LEGS = """
mission: legs
blackboard:
  legs: {type: int, initial: 0}
  leg: {type: distance, initial: 5 cm}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, distance: "@leg"}
    - set: {key: legs, value: 1}
"""

OTHER = """
mission: other
blackboard:
  turns: {type: int, initial: 3}
tree: {log: done}
"""

Blackboard = py_trees.blackboard.Blackboard


@pytest.fixture(autouse=True)
def _clean(clean_blackboard: None) -> Iterator[None]:
    yield


@contextlib.contextmanager
def _ran(path: Path) -> Iterator[RunStack]:
    """The mission run to its success; its stack closed when the block ends (which takes
    its keys off the blackboard: the block looks at them before)."""
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
    stack = RunStack(load_mission(path), SimLink(simulator), profile=CREATE2, timeout_s=30)
    try:
        assert stack.run().outcome is Outcome.SUCCESS
        yield stack
    finally:
        stack.close()


def test_py_trees_tools_show_the_missions_keys_after_a_run(tmp_path: Path) -> None:
    Blackboard.enable_activity_stream()
    with _ran(write_mission(tmp_path, LEGS)):
        assert {"/mission/legs", "/mission/leg"} <= Blackboard.keys()
        shown = py_trees.display.unicode_blackboard(key_filter={"/mission/legs"})
        assert "/mission/legs" in shown and ": 1" in shown
        clients = py_trees.display.unicode_blackboard(display_only_key_metadata=True)
        assert "/mission/legs" in clients and "(rw)" in clients
        assert MISSION_CLIENT_NAME in Blackboard.clients.values()
        stream = Blackboard.activity_stream
        assert stream is not None
        writes = [item for item in stream.data if item.key == "/mission/legs"]
        assert [item.activity_type for item in writes] == ["INITIALISED", "WRITE"]
        assert all(Blackboard.clients[item.client_id] == MISSION_CLIENT_NAME for item in writes)


def test_the_next_missions_setup_replaces_the_keys_registered(tmp_path: Path) -> None:
    with _ran(write_mission(tmp_path, LEGS)):
        pass
    with _ran(write_mission(tmp_path, OTHER, "other.yaml")):
        registered = Blackboard.keys()
        mission_keys = {key for key in registered if key.startswith("/mission/")}
        assert mission_keys == {"/mission/turns"}
        assert list(Blackboard.clients.values()).count(MISSION_CLIENT_NAME) == 1


def test_a_closed_runs_keys_leave_py_trees_blackboard(tmp_path: Path) -> None:
    """The stack's close() takes its run's keys and client off the blackboard: the next run
    in the process reads none of them (a key it does not write is unwritten)."""
    with _ran(write_mission(tmp_path, LEGS)):
        assert "/mission/legs" in Blackboard.storage
    assert not [name for name in Blackboard.storage if name.startswith(("/mission/", "/roomba/"))]
    assert MISSION_CLIENT_NAME not in Blackboard.clients.values()
    registered = Blackboard.keys()
    assert not {key for key in registered if key.startswith("/mission/")}


def test_a_cleared_blackboard_is_registered_again_at_the_next_setup(tmp_path: Path) -> None:
    """A test's ``Blackboard.clear()`` between two runs forgets the client: the next setup
    registers the keys anew instead of failing on the forgotten one."""
    path = write_mission(tmp_path, LEGS)
    with _ran(path):
        Blackboard.clear()
    with _ran(path):
        registered = Blackboard.keys()
        assert "/mission/legs" in registered
