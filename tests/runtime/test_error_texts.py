"""What a behaviour's exception says when it has no message (session 36, a stranger's
finding 12): ``raised MemoryError:  in its update()`` had two spaces and a colon for nothing."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from roomba_bt.runtime.teardown import behaviour_error


class _OutOfMemory(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        raise MemoryError


def test_an_exception_without_a_message_is_said_by_its_name_alone() -> None:
    node = _OutOfMemory("greedy")
    try:
        node.update()
    except MemoryError as exc:
        said = behaviour_error(exc)
    assert "raised MemoryError in its update() (" in said, said
    assert "  " not in said


def test_an_exception_with_a_message_keeps_it() -> None:
    try:
        raise ValueError("no room")
    except ValueError as exc:
        said = behaviour_error(exc)
    assert said.startswith("ValueError: no room ("), said
