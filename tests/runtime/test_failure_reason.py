"""The failure a user reads first: the failed leaf, else the deepest failed node's message."""

from __future__ import annotations

import py_trees

from roomba_bt.runtime.loop import _failure_reason

FAILURE = py_trees.common.Status.FAILURE


def test_the_failed_leaf_and_its_message_come_first() -> None:
    leaf = py_trees.behaviours.Failure(name="charging")
    root = py_trees.composites.Sequence("mission", memory=True, children=[leaf])
    root.tick_once()
    leaf.feedback_message = "no charging state in packet 21"
    assert _failure_reason(root) == "charging: no charging state in packet 21"


def test_when_the_leaves_were_reset_the_deepest_message_is_used() -> None:
    leaf = py_trees.behaviours.Failure(name="dock_drive_on")
    attempt = py_trees.composites.Sequence("attempt", memory=True, children=[leaf])
    retry = py_trees.decorators.Retry("retry", child=attempt, num_failures=1)
    root = py_trees.composites.Sequence("mission", memory=True, children=[retry])
    root.tick_once()
    assert root.status == FAILURE
    leaf.stop(py_trees.common.Status.INVALID)  # what a parallel or guard does to its children
    attempt.stop(py_trees.common.Status.INVALID)
    assert _failure_reason(root).startswith("retry: final failure")
