"""The monitor's blackboard at a rewound tick: a value that changes in place is shown as it was
at that tick (the cover's map showed the whole run's map at tick 100), and the values the
missions keep there read as something (a heading of 900 deg, a Python ``id()``)."""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours.coverage_map import Bearings, FloorMap
from roomba_bt.behaviours.docking.common import DockingRun
from roomba_bt.monitor.board_text import board_text
from roomba_bt.monitor.feed import SLOW_TEXT_TICKS, RunFeed
from roomba_bt.monitor.views import state_view
from roomba_bt.robot.interface import Odometry

from .live import feed_of_run

pytestmark = pytest.mark.usefixtures("clean_blackboard")


class Counts:
    """A mutable blackboard value, as the cover's map is: one object, changed every tick."""

    def __init__(self) -> None:
        self.ticks = 0

    def __repr__(self) -> str:
        return f"<counted {self.ticks} ticks>"


class SlowCounts(Counts):
    """One whose text takes longer than the feed takes every tick."""

    def __repr__(self) -> str:
        time.sleep(0.002)
        return super().__repr__()


class HeldUpCounts(Counts):
    """A quick text that the machine holds up now and then (the thread descheduled, a garbage
    collection) on fewer ticks in a row than :data:`SLOW_TEXT_TICKS`: every tenth tick and
    the ones after it."""

    def __repr__(self) -> str:
        if self.ticks % 10 < SLOW_TEXT_TICKS - 1:
            time.sleep(0.002)
        return super().__repr__()


class Counter(py_trees.behaviour.Behaviour):
    """Counts its ticks in the object under ``key`` (the same object every tick)."""

    def __init__(self, key: str, value: Counts) -> None:
        super().__init__(name="counter")
        self.key = key
        py_trees.blackboard.Blackboard.storage[key] = value

    def update(self) -> Status:
        py_trees.blackboard.Blackboard.storage[self.key].ticks += 1
        return Status.RUNNING


def _run(*counters: Counter) -> RunFeed:
    root = py_trees.composites.Parallel(
        "counting", policy=py_trees.common.ParallelPolicy.SuccessOnAll(), children=list(counters)
    )
    return feed_of_run(root, "counting", history=1000)


def test_a_rewound_tick_shows_a_changing_object_as_it_was_at_that_tick() -> None:
    feed = _run(Counter("/counts", Counts()))
    records = feed.since(0)[0]
    assert len(records) > 50
    shown = [state_view(feed, r, [])["blackboard"]["/counts"] for r in records[10:50:10]]
    # the count it had then, each different: not the run's last one for all of them
    assert len(set(shown)) == len(shown), shown
    assert all(text.startswith("<counted ") for text in shown)
    last = state_view(feed, records[-1], [])["blackboard"]["/counts"]
    assert last == repr(py_trees.blackboard.Blackboard.storage["/counts"])


def test_a_quick_value_held_up_on_a_tick_or_two_is_still_shown_as_it_was_at_each_tick() -> None:
    """One text over the budget (a busy computer: the thread descheduled in it) kept the
    cover's map as its object for the rest of the run, every rewound tick marked as now."""
    feed = _run(Counter("/held", HeldUpCounts()))
    assert feed.live_keys == set()
    records = feed.since(0)[0]
    shown = [state_view(feed, r, [])["blackboard"]["/held"] for r in records[9:50:10]]
    assert shown == [f"<counted {tick} ticks>" for tick in range(10, 51, 10)]


def test_a_value_too_slow_to_take_each_tick_says_it_is_the_current_one() -> None:
    feed = _run(Counter("/slow", SlowCounts()))
    assert feed.live_keys == {"/slow"}
    records = feed.since(0)[0]
    rewound = state_view(feed, records[len(records) // 2], [])["blackboard"]["/slow"]
    assert rewound.endswith("(its value now, not at this tick)")
    newest = state_view(feed, records[-1], [])["blackboard"]["/slow"]
    assert "not at this tick" not in newest


def test_the_cover_map_s_heading_is_an_angle_of_a_turn_not_the_turns_summed() -> None:
    bearings = Bearings(FloorMap(), Odometry(theta_rad=5 * math.pi / 2))  # 900 deg once
    assert repr(bearings).endswith(", 90 deg>")
    bearings.pose = Odometry(theta_rad=-0.001)
    assert repr(bearings).endswith(", 0 deg>")  # not "-0"
    bearings.pose = Odometry(theta_rad=-3 * math.pi / 4)
    assert repr(bearings).endswith(", -135 deg>")


def test_a_docking_run_reads_as_its_start_not_a_python_id() -> None:
    run = DockingRun(140000000000, 927.24, "dock_time_limit(300 s)")
    assert repr(run) == "<docking run since t=927.24 s (dock_time_limit(300 s))>"
    assert run == DockingRun(140000000000, 927.24, "dock_time_limit(300 s)")
    assert run != DockingRun(140000000001, 927.24, "dock_time_limit(300 s)")  # another limit


@dataclass
class Waypoint:
    """A plugin's record: a dataclass with the repr the decorator writes."""

    distance: float
    turn: float


@dataclass
class Leg:
    """One that says itself how it reads."""

    distance: float

    def __repr__(self) -> str:
        return f"<leg of {self.distance:.0f} mm>"


@pytest.mark.parametrize(
    ("value", "shown"),
    [
        # a mission's record key: its fields, JSON's words, a float to 4 decimals
        ({"distance": 1000.0, "turn": math.pi / 2, "room": "kitchen", "done": False},
         '{"distance": 1000.0, "turn": 1.5708, "room": "kitchen", "done": false}'),
        # a mark: the odometry's fields, None as null, no "-0.0"
        (Odometry(x_mm=-0.00001, theta_rad=-math.pi),
         '{"x_mm": 0.0, "y_mm": 0.0, "theta_rad": -3.1416, "distance_mm": 0.0, '
         '"angle_rad": 0.0, "left_counts": null, "right_counts": null, "path_mm": 0.0}'),
        (Waypoint(300.0, 0.1 + 0.2), '{"distance": 300.0, "turn": 0.3}'),
        ([{"distance": 500.0}, None], '[{"distance": 500.0}, null]'),
        ((1, "two"), '[1, "two"]'),
        ("hello", '"hello"'),
        (3, "3"),
        # a class's own repr says how it reads: kept
        (DockingRun(1, 927.24, "dock_time_limit(300 s)"),
         "<docking run since t=927.24 s (dock_time_limit(300 s))>"),
        (Leg(1200.0), "<leg of 1200 mm>"),
        (Status.RUNNING, "<Status.RUNNING: 'RUNNING'>"),
    ],
)  # fmt: skip
def test_a_record_reads_as_json_like_text_not_a_python_repr(value: object, shown: str) -> None:
    """``{'distance': 1000.0, 'turn': 1.5707963267948966}`` and ``Odometry(x_mm=...,
    left_counts=None, ...)`` were what a parent read on the page."""
    assert board_text(value) == shown


def test_a_long_value_is_cut_and_a_list_holding_itself_says_so() -> None:
    shown = board_text(list(range(100_000)))  # made only as far as it is shown
    assert len(shown) == 200 and shown.startswith("[0, 1, 2, ") and shown.endswith("...")
    itself: list[object] = []
    itself.append(itself)
    assert board_text(itself) == "[[...]]"  # as Python's repr says it
    record: dict[str, object] = {"name": "loop"}
    record["self"] = [record]
    assert board_text(record) == '{"name": "loop", "self": [{...}]}'
    deep: list[object] = []
    for _ in range(5 * sys.getrecursionlimit()):  # no cycle: deeper than Python recurses
        deep = [deep]
    assert board_text(deep) == "[" * 197 + "..."


class Records(py_trees.behaviour.Behaviour):
    """Writes what a mission's ``set`` and ``mark`` write: a record (a dict) and a mark (an
    :class:`Odometry`)."""

    def update(self) -> Status:
        storage = py_trees.blackboard.Blackboard.storage
        storage["/mission/wp"] = {"distance": 1000.0, "turn": math.pi / 2}
        storage["/mission/start"] = Odometry(x_mm=12.5)
        return Status.RUNNING


def test_the_page_s_blackboard_shows_a_record_and_a_mark_as_json_like_text() -> None:
    feed = feed_of_run(Records(name="records"), "records", history=1000)
    board = state_view(feed, feed.since(0)[0][-1], [])["blackboard"]
    assert board["/mission/wp"] == '{"distance": 1000.0, "turn": 1.5708}'
    assert board["/mission/start"].startswith('{"x_mm": 12.5, "y_mm": 0.0, ')
