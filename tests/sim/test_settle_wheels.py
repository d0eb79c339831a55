"""The simulator's wheel speeds after a run (a library user's report): ``sim.left_speed``
read after ``stack.close()`` still said 199.5 mm/s, the speed of the step before the safe
stop, though the robot was stopped; it changed only at the next step. Closing the link
settles the wheels to the stop, and what the simulator does next is the same bytes."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world


@pytest.fixture(autouse=True)
def _clean(clean_blackboard: None) -> Iterator[None]:
    yield


def _driving(seed: int = 3) -> Simulator:
    """A simulator in Safe at 200 mm/s, its stream running, a second into the drive."""
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=seed)
    started = (oi.start(), oi.safe(), oi.stream((7, 35, 41, 42, 43, 44)), oi.drive(200, 32767))
    for command in started:
        simulator.receive(command.data)
    simulator.run(1.0)
    assert simulator.left_speed and simulator.right_speed
    return simulator


def test_after_a_run_stopped_while_driving_the_wheels_read_0() -> None:
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
    mission = load_mission("bump-and-turn", {"duration": "20 s"})

    def enough(runner: MissionRunner) -> None:
        if runner.snapshot.time > 3.0:
            runner.request_stop("enough")

    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=30, observer=enough)
    try:
        assert stack.run().outcome is Outcome.INTERRUPTED
    finally:
        stack.close()
    assert simulator.mode is OIMode.PASSIVE
    assert (simulator.requested_left, simulator.requested_right) == (0, 0)
    assert (simulator.left_speed, simulator.right_speed) == (0, 0)


def test_settling_changes_nothing_the_simulator_does_next() -> None:
    settled, twin = _driving(), _driving()
    stop = oi.halt().data + oi.start().data  # drive 0, then Passive: the stream runs on
    settled.receive(stop)
    twin.receive(stop)
    settled.settle_wheels()
    assert settled.left_speed == 0 and twin.left_speed
    assert settled.run(2.0) == twin.run(2.0)
    assert settled.pose == twin.pose and settled.values == twin.values
    assert settled.battery_charge == twin.battery_charge


def test_wheels_still_asked_to_turn_wait_for_the_step() -> None:
    """A driving mode's speed other than 0, or a built-in cycle's wheels in Passive, move
    the robot: the step works them out, not the settling."""
    driving = _driving()
    driving.settle_wheels()
    assert driving.left_speed and driving.right_speed
    cleaning = _driving()
    cleaning.receive(oi.start().data + oi.clean().data)
    cleaning.run(0.5)
    speeds = (cleaning.left_speed, cleaning.right_speed)
    assert cleaning.builtin is not None and any(speeds)
    cleaning.settle_wheels()
    assert (cleaning.left_speed, cleaning.right_speed) == speeds
