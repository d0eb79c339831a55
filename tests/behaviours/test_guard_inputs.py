"""A ``while``/``until`` guard leaves its condition as it is while nothing it reads changed.

The guard re-ticks its condition subtree on every frame; a subtree of frame-pure conditions
(:class:`~roomba_bt.behaviours.declare.FrameInputs`) ticked again on the same values of its
packets would end with the statuses it has, so the guard skips that tick. These tests check
that every node's status after every tick is what re-ticking gives (random trees and frames,
against the same tree whose conditions are not taken to be pure, ticked by the guard's plain
steps), and that whatever else may
change a condition's result makes the guard tick it again.
"""

from __future__ import annotations

from typing import Any

import py_trees
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from py_trees.behaviour import Behaviour
from py_trees.behaviours import Running
from py_trees.common import Status

from roomba_bt.behaviours import conditions as c
from roomba_bt.behaviours import decorators as d
from roomba_bt.behaviours import lean
from roomba_bt.behaviours.base import Condition
from roomba_bt.behaviours.blackboard import BlackboardRef, write_key
from roomba_bt.behaviours.frame_inputs import FrameInputs
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.interface import Snapshot
from roomba_bt.robot.testing import StubRobot

CHECKED: list[str] = []


class CountedBump(c.Bump):
    """``bump``, counting its checks; pure, as it says."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        CHECKED.append(self.name)
        return super().check(snapshot)


class CountedSensor(c.Sensor):
    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        CHECKED.append(self.name)
        return super().check(snapshot)


class PlainBump(c.Bump):
    """``bump`` not taken to be pure: the guard always ticks it (the reference)."""

    frame_pure = False


class PlainSensor(c.Sensor):
    frame_pure = False


def _leaf(spec: tuple[str, str], pure: bool, name: str) -> Condition:
    kind, option = spec
    if kind == "bump":
        return (CountedBump if pure else PlainBump)(name, {"side": option})
    test = c.COMPARISON.parse(option)
    return (CountedSensor if pure else PlainSensor)(name, {"test": test})


def build(spec: Any, pure: bool, counter: list[int]) -> Behaviour:
    if spec[0] in ("sequence", "selector"):
        cls = lean.Sequence if spec[0] == "sequence" else lean.Selector
        children = [build(child, pure, counter) for child in spec[2]]
        return cls(spec[0], spec[1], children)
    counter[0] += 1
    return _leaf(spec, pure, f"leaf{counter[0]}")


def _conditions() -> st.SearchStrategy[Any]:
    leaves = st.one_of(
        st.tuples(st.just("bump"), st.sampled_from(["left", "right", "any"])),
        st.tuples(
            st.just("sensor"),
            st.sampled_from(["cliff_left == 0", "wall_signal > 100", "cliff_right != 0"]),
        ),
    )
    return st.recursive(
        leaves,
        lambda children: st.tuples(
            st.sampled_from(["sequence", "selector"]),
            st.booleans(),
            st.lists(children, min_size=1, max_size=3),
        ),
        max_leaves=6,
    )


#: one tick: the frame's values (small ranges: frames repeat often), and how it is ticked
_TICKS = st.lists(
    st.tuples(
        st.integers(0, 3), st.integers(0, 1), st.integers(0, 1), st.sampled_from([50, 150]),
        st.sampled_from(["direct"] * 6 + ["generator", "stop", "force", "release"]),
    ),
    min_size=1,
    max_size=25,
)  # fmt: skip


def _run(spec: Any, until: bool, ticks: list[Any], pure: bool) -> list[list[str]]:
    robot = StubRobot()
    guard = d.Guard("guard", build(spec, pure, [0]), Running("drive"), until=until)
    for node in guard.iterate():
        node.setup(robot=robot)
    first = next(n for n in guard.iterate() if isinstance(n, Condition))
    seen = []
    for bumps, cliff_left, cliff_right, wall_signal, how in ticks:
        robot.set_frame({7: bumps, 9: cliff_left, 12: cliff_right, 27: wall_signal, 35: 2})
        if how == "generator":
            lean.tick_generator(guard)
        elif how == "stop":
            guard.stop(Status.INVALID)
        else:
            if how == "force":  # as the monitor forces a condition, then ticks
                first.update = lambda: Status.SUCCESS  # type: ignore[method-assign]
            elif how == "release":
                vars(first).pop("update", None)
            if pure:
                guard.tick_once()
            else:  # the reference: the guard's steps, nothing skipped nor folded
                lean.Stepped.tick_direct(guard)
        seen.append([f"{n.name}={n.status.name}" for n in guard.iterate()])
        seen[-1].append(guard.feedback_message)
    return seen


@settings(max_examples=300, deadline=None)
@given(_conditions(), st.booleans(), _TICKS)
def test_a_guard_skipping_its_condition_ends_each_tick_as_re_ticking_does(
    spec: Any, until: bool, ticks: list[Any]
) -> None:
    assert _run(spec, until, ticks, pure=True) == _run(spec, until, ticks, pure=False)


def _guard(robot: StubRobot, *conditions: Condition, until: bool = False) -> d.Guard:
    condition = conditions[0] if len(conditions) == 1 else lean.Sequence("all", False, conditions)
    guard = d.Guard("guard", condition, Running("drive"), until=until)
    for node in guard.iterate():
        node.setup(robot=robot)
    return guard


def _counted(robot: StubRobot, **params: Any) -> CountedBump:
    return CountedBump("bump", {"side": "any", **params})


@pytest.fixture(autouse=True)
def _no_checks_yet() -> None:
    CHECKED.clear()


def test_the_condition_is_ticked_again_only_when_a_packet_it_reads_changes() -> None:
    robot = StubRobot()
    clear = CountedSensor("clear", {"test": c.COMPARISON.parse("bumps_wheel_drops == 0")})
    wall = CountedSensor("wall", {"test": c.COMPARISON.parse("wall_signal > 100")})
    guard = _guard(robot, clear, wall)
    for bumps, signal, ticked in ((0, 200, 2), (0, 200, 0), (0, 201, 2), (1, 201, 1), (1, 201, 0)):
        robot.set_frame({7: bumps, 27: signal, 22: robot.snapshot.tick})  # 22: changes
        CHECKED.clear()
        guard.tick_once()
        assert len(CHECKED) == ticked, (bumps, signal)
    assert guard.status is Status.FAILURE and "clear" in guard.feedback_message


def test_a_forced_condition_is_ticked_and_released_again() -> None:
    robot = StubRobot()
    bump = _counted(robot)
    guard = _guard(robot, bump, until=True)
    robot.set_frame({7: 0})
    guard.tick_once()
    bump.update = lambda: Status.SUCCESS  # type: ignore[method-assign]  # the monitor's force
    guard.tick_once()
    assert guard.status is Status.SUCCESS
    del bump.update
    guard.tick_once()
    assert bump.status is Status.FAILURE and guard.status is Status.RUNNING


def test_a_check_patched_on_the_class_or_the_node_is_ticked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    robot = StubRobot()
    bump = _counted(robot)
    guard = _guard(robot, bump, until=True)
    robot.set_frame({7: 0})
    guard.tick_once()
    monkeypatch.setattr(CountedBump, "check", lambda self, snapshot: True)
    guard.tick_once()
    assert guard.status is Status.SUCCESS
    monkeypatch.undo()
    guard.tick_once()
    guard.tick_once()
    assert guard.status is Status.RUNNING
    bump.check = lambda snapshot: True  # type: ignore[method-assign]
    guard.tick_once()
    assert guard.status is Status.SUCCESS


def test_debug_logging_ticks_the_condition() -> None:
    robot = StubRobot()
    guard = _guard(robot, _counted(robot))
    robot.set_frame({7: 0})
    guard.tick_once()
    previous = py_trees.logging.level
    py_trees.logging.level = py_trees.logging.Level.DEBUG
    try:
        CHECKED.clear()
        guard.tick_once()
    finally:
        py_trees.logging.level = previous
    assert CHECKED == ["bump"]


def test_a_new_robot_is_read() -> None:
    first, second = StubRobot(), StubRobot()
    bump = _counted(first)
    guard = _guard(first, bump, until=True)
    first.set_frame({7: 0})
    guard.tick_once()
    second.set_frame({7: 1})
    for node in guard.iterate():
        node.setup(robot=second)
    guard.tick_once()
    assert guard.status is Status.SUCCESS


def test_conditions_reading_more_than_the_frame_are_always_ticked() -> None:
    robot = StubRobot()
    write_key("side", "left")
    by_key = CountedBump("bump", {"side": BlackboardRef("side")})
    mode = c.OIModeIs("oi_mode", {"is": "safe"})
    for condition in (by_key, mode):
        assert FrameInputs.of(condition) is None or condition is None
        guard = _guard(robot, condition)
        robot.set_frame({7: 2, 35: 2})
        guard.tick_once()
        assert guard.status is Status.RUNNING
        write_key("side", "right")
        robot.set_frame({7: 2, 35: 2}, mode=OIMode.PASSIVE)
        guard.tick_once()
        assert guard.status is Status.FAILURE
        write_key("side", "left")


def test_a_subclass_with_its_own_check_is_not_taken_to_be_pure() -> None:
    class Stateful(c.Bump):
        def check(self, snapshot: Snapshot) -> bool:
            self.seen = getattr(self, "seen", 0) + 1
            return self.seen > 1

    robot = StubRobot()
    stateful = Stateful("stateful", {"side": "any"})
    guard = _guard(robot, stateful, until=True)
    robot.set_frame({7: 0})
    guard.tick_once()
    guard.tick_once()
    assert guard.status is Status.SUCCESS
