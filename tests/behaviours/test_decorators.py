"""Mission-time decorators and the while/until guard, on py_trees' own test behaviours.

Every test runs twice: ticked by ``tick_once`` (the direct path the runtime takes) and through
the py_trees generator ``tick`` (what visitors and stepping see); both must agree.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import py_trees
import pytest
from py_trees.behaviours import Failure, Running, StatusQueue, Success
from py_trees.common import Status

from roomba_bt.behaviours import decorators as d
from roomba_bt.behaviours import lean
from roomba_bt.behaviours.blackboard import read_key
from roomba_bt.behaviours.declare import ParamError
from roomba_bt.robot.testing import StubRobot


def ready(node: py_trees.behaviour.Behaviour, robot: StubRobot) -> py_trees.behaviour.Behaviour:
    for n in node.iterate():
        n.setup(robot=robot)
    return node


Tick = Callable[[py_trees.behaviour.Behaviour], None]
TICK: dict[str, Tick] = {"tick": lean.tick_generator}  # set by tick_path


@pytest.fixture(autouse=True, params=["direct", "generator"])
def tick_path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    def direct(node: py_trees.behaviour.Behaviour) -> None:
        assert isinstance(node, lean.Direct)  # our decorators all have the direct path
        node.tick_once()

    monkeypatch.setitem(TICK, "tick", direct if request.param == "direct" else lean.tick_generator)


def run(node: py_trees.behaviour.Behaviour, robot: StubRobot, ticks: int) -> list[Status]:
    out = []
    for _ in range(ticks):
        robot.set_frame({})
        TICK["tick"](node)
        out.append(node.status)
    return out


def test_timeout_counts_mission_time_not_wall_time(robot: StubRobot) -> None:
    child = Running("forever")
    node = ready(d.Timeout("timeout", child, 0.045), robot)
    assert run(node, robot, 4) == [Status.RUNNING] * 3 + [Status.FAILURE]
    assert child.status is Status.INVALID  # stopped


def test_timeout_passes_a_finished_child_through(robot: StubRobot) -> None:
    node = ready(d.Timeout("timeout", Success("ok"), 1.0), robot)
    assert run(node, robot, 1) == [Status.SUCCESS]


def test_delay_waits_then_ticks_the_child(robot: StubRobot) -> None:
    child = Success("ok")
    node = ready(d.Delay("delay", child, 0.03), robot)
    assert run(node, robot, 3) == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]


def test_repeat_times(robot: StubRobot) -> None:
    node = ready(d.Repeat("repeat", Success("ok"), times=3), robot)
    assert run(node, robot, 3) == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]
    assert node.feedback_message == "3 done"  # the tree shown at the end said "2 done"


def test_repeat_for_a_duration(robot: StubRobot) -> None:
    node = ready(d.Repeat("repeat", Success("ok"), duration=0.045), robot)
    assert run(node, robot, 4) == [Status.RUNNING] * 3 + [Status.SUCCESS]


def test_repeat_forever_and_failure_ends_it(robot: StubRobot) -> None:
    queue = StatusQueue("q", [Status.SUCCESS] * 5 + [Status.FAILURE], eventually=None)
    node = ready(d.Repeat("repeat", queue), robot)
    assert run(node, robot, 6) == [Status.RUNNING] * 5 + [Status.FAILURE]


def test_for_each_writes_each_item_before_the_child(robot: StubRobot) -> None:
    seen: list[object] = []

    class Record(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            seen.append(read_key("leg"))
            return Status.SUCCESS

    node = ready(d.ForEach("for_each", Record("record"), "leg", [1.0, 2.0, 3.0]), robot)
    assert run(node, robot, 3) == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]
    assert seen == [1.0, 2.0, 3.0]


def test_for_each_over_nothing_succeeds(robot: StubRobot) -> None:
    node = ready(d.ForEach("for_each", Failure("never"), "leg", []), robot)
    assert run(node, robot, 1) == [Status.SUCCESS]


def test_for_each_fails_with_its_child(robot: StubRobot) -> None:
    node = ready(d.ForEach("for_each", Failure("no"), "leg", [1, 2]), robot)
    assert run(node, robot, 1) == [Status.FAILURE]


def test_until_stops_the_child_when_the_condition_holds(robot: StubRobot) -> None:
    condition = StatusQueue("bump", [Status.FAILURE, Status.FAILURE, Status.SUCCESS], None)
    child = Running("drive")
    node = ready(d.Guard("until bump", condition, child, until=True), robot)
    assert run(node, robot, 3) == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]
    assert child.status is Status.INVALID


def test_while_fails_when_the_condition_stops_holding(robot: StubRobot) -> None:
    condition = StatusQueue("ok", [Status.SUCCESS, Status.FAILURE], None)
    child = Running("drive")
    node = ready(d.Guard("while ok", condition, child, until=False), robot)
    assert run(node, robot, 2) == [Status.RUNNING, Status.FAILURE]
    assert child.status is Status.INVALID


def test_guard_passes_the_child_result_through(robot: StubRobot) -> None:
    node = ready(d.Guard("while ok", Success("ok"), Failure("child"), until=False), robot)
    assert run(node, robot, 1) == [Status.FAILURE]
    node = ready(d.Guard("until never", Failure("no"), Success("child"), until=True), robot)
    assert run(node, robot, 1) == [Status.SUCCESS]


def test_guard_preempted_from_above_stops_its_child(robot: StubRobot) -> None:
    child = Running("drive")
    node = ready(d.Guard("while ok", Success("ok"), child, until=False), robot)
    run(node, robot, 1)
    node.stop(Status.INVALID)
    assert child.status is Status.INVALID


S, F = Status.SUCCESS, Status.FAILURE


def test_held_a_flickering_child_never_holds(robot: StubRobot) -> None:
    flicker = StatusQueue("bump", [S, F], eventually=None)  # over and over
    node = ready(d.Held("held", flicker, 0.015), robot)
    assert run(node, robot, 40) == [F] * 40


def test_held_a_steady_child_succeeds_at_the_first_tick_the_time_has_passed(
    robot: StubRobot,
) -> None:
    """Counted from the first tick of SUCCESS, on the mission clock: 45 ms is the 4th tick;
    1 s is the 67th after the first (1.005 s: 1 s is no whole number of 15 ms ticks)."""
    node = ready(d.Held("held", Success("bump"), 0.045), robot)
    assert run(node, robot, 6) == [F, F, F, S, S, S]
    node = ready(d.Held("held", Success("bump"), 1.0), robot)
    statuses = run(node, robot, 70)
    assert statuses.index(S) == 67 and statuses[67:] == [S, S, S]
    assert node.feedback_message == "held for 1 s"


def test_held_starts_again_when_the_child_fails(robot: StubRobot) -> None:
    queue = StatusQueue("bump", [S, S, F, S, S, S, S], eventually=S)
    node = ready(d.Held("held", queue, 0.03), robot)
    assert run(node, robot, 7) == [F, F, F, F, F, S, S]


def test_held_starts_again_after_a_tick_it_was_not_ticked_on(robot: StubRobot) -> None:
    """A guard or fallback that ticked it earlier: the hold it had does not count."""
    node = ready(d.Held("held", Success("bump"), 0.045), robot)
    assert run(node, robot, 3) == [F, F, F]
    robot.set_frame({})  # the tree ticked without it
    assert run(node, robot, 4) == [F, F, F, S]


def test_held_frames_lost_on_the_link_are_no_gap(robot: StubRobot) -> None:
    """Slots with no frame (``set_frame(ticks=2)``: one lost) are mission time, not ticks
    the node missed: the hold goes on through them."""
    node = ready(d.Held("held", Success("bump"), 0.045), robot)
    assert run(node, robot, 1) == [F]
    robot.set_frame({}, ticks=2)
    TICK["tick"](node)
    assert node.status is F  # 30 ms held
    assert run(node, robot, 1) == [S]  # 45 ms


def test_held_a_stop_counts_only_when_a_tick_is_missed(robot: StubRobot) -> None:
    """py_trees stops (INVALID) every child of a composite that starts afresh, which a
    sequence of conditions does on every tick: ticked again on the next tick, the hold goes
    on (its child succeeded on every tick). Stopped and left for a tick (a halt, a branch
    left), it starts again."""
    node = ready(d.Held("held", Success("bump"), 0.045), robot)
    assert run(node, robot, 2) == [F, F]
    node.stop(Status.INVALID)
    assert run(node, robot, 2) == [F, S]
    node.stop(Status.INVALID)
    robot.set_frame({})  # not ticked on this one
    assert run(node, robot, 4) == [F, F, F, S]


def test_held_in_a_sequence_of_conditions_holds(robot: StubRobot) -> None:
    """The sequence starts afresh on every tick, stopping its children first."""
    held = d.Held("held", Success("bump"), 0.045)
    node = ready(lean.Sequence("sequence", True, [Success("wall"), held]), robot)
    assert run(node, robot, 5) == [F, F, F, S, S]


def test_held_as_an_until_condition_ends_the_child_only_after_the_hold(
    robot: StubRobot,
) -> None:
    bump = StatusQueue("bump", [F, S, F, S, S, S], eventually=S)
    drive = Running("drive")
    node = ready(d.Guard("until held", d.Held("held", bump, 0.03), drive, until=True), robot)
    assert run(node, robot, 6) == [Status.RUNNING] * 5 + [S]
    assert drive.status is Status.INVALID  # stopped


@pytest.mark.parametrize(
    ("duration", "said"),
    [
        (0.005, "0.005 s is out of range: at least 0.015 s (one 15 ms tick)"),
        (-1, "-1 s is out of range"),
        (float("nan"), "nan s is out of range"),
        ("3 m", "unknown duration unit 'm'"),
        (None, "expected seconds"),
    ],
)
def test_held_refuses_a_bad_duration_as_the_compiler_does(duration: object, said: str) -> None:
    with pytest.raises(
        ParamError, match=re.escape("Held 'held': duration: ") + ".*" + re.escape(said)
    ):
        d.Held("held", Success("bump"), duration)  # type: ignore[arg-type]
