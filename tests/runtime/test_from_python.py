"""A run started from Python has the CLI's protections (a field trial's findings): the tick
guard on the wall clock by default (a plain behaviour that blocked 2 s drove the robot 0.6 m
with ``RunStack(...)`` as given), and a run in a worker thread, which Ctrl-C never reaches,
says so when it starts and is ended, its robot stopped, by ``stack.close()`` from the main
thread (it cut the link under the run: the stop was not delivered)."""

from __future__ import annotations

import threading

import py_trees
import pytest
from waits import joined, waited  # tests/waits.py: a hang's bound, no fixed bet

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import DEFAULT_TICK_LIMIT, Outcome, RunSummary
from roomba_bt.runtime.tick_guard import TickGuard
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, load_world

from .simrun import run_in_a_worker, wait_for_the_guard


class Blocks(py_trees.behaviour.Behaviour):
    """A plain behaviour that blocks its 10th tick until the wheels were stopped behind its
    back (:func:`wait_for_the_guard`): waiting on the network, ``input()``, a widget."""

    def setup(self, **kwargs: object) -> None:
        self.robot = kwargs["robot"]
        self.ticks = 0

    def update(self) -> py_trees.common.Status:
        self.ticks += 1
        if self.ticks == 10:
            wait_for_the_guard(self.robot)  # type: ignore[attr-defined]
        return py_trees.common.Status.SUCCESS if self.ticks > 20 else py_trees.common.Status.RUNNING


def _driving_tree(*beside: py_trees.behaviour.Behaviour) -> TreeMission:
    drive = Drive("forward", {"velocity": "100 mm/s", "distance": "5 cm"})
    both = py_trees.composites.Parallel(
        "both", policy=py_trees.common.ParallelPolicy.SuccessOnAll(), children=[drive, *beside]
    )
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Mode("safe", {"to": "safe"}), both]
    )
    return TreeMission(root, "from-python")


def test_a_run_on_the_wall_clock_has_the_tick_guard_by_default() -> None:
    link = RealtimeSimLink(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(_driving_tree(Blocks("blocks")), link, profile=CREATE2, timeout_s=20.0)
    try:
        summary = stack.run()
    finally:
        stack.close()
    assert summary.tick_halts == 1, summary  # the guard's drive 0, the behaviour named
    assert summary.tick_halt_first.startswith("blocks (Blocks.update at ")


def test_the_virtual_clock_has_none_by_default_and_a_limit_given_is_kept() -> None:
    """As ``roomba-bt run --fast``: the robot does not move while the host thinks."""

    def stack(**kwargs: object) -> RunStack:
        link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0))
        return RunStack(_driving_tree(), link, profile=CREATE2, **kwargs)  # type: ignore[arg-type]

    assert stack().runner.tick_guard is None
    assert stack(tick_limit=None).runner.tick_guard is None
    guard = stack(tick_limit=0.5).runner.tick_guard
    assert isinstance(guard, TickGuard) and guard.limit_s == 0.5
    wall = RunStack(
        _driving_tree(), RealtimeSimLink(Simulator(load_world("empty-room"), CREATE2, 0)),
        profile=CREATE2,
    )  # fmt: skip
    assert isinstance(wall.runner.tick_guard, TickGuard)
    assert wall.runner.tick_guard.limit_s == DEFAULT_TICK_LIMIT


def test_a_run_in_a_worker_thread_warns_and_close_from_the_main_thread_stops_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    driving = threading.Event()

    def observer(runner: MissionRunner) -> None:
        if runner.snapshot.tick >= 20:
            driving.set()

    root = py_trees.composites.Sequence("w", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("forward", {"velocity": "100 mm/s"}),
    ])  # fmt: skip
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    stack = RunStack(
        TreeMission(root, "worker"), RealtimeSimLink(simulator), profile=CREATE2, observer=observer
    )
    worker, result = run_in_a_worker(stack)
    try:
        waited(driving, "the run's 20th tick")
        assert simulator.requested_left > 0  # the robot drives
    finally:
        stack.close()  # from the main thread, while the worker runs: the run ends first
    assert not worker.is_alive()  # close() returned after the run's end
    joined(worker, "the run's worker")
    [summary] = result
    assert isinstance(summary, RunSummary), summary
    assert summary.outcome is Outcome.INTERRUPTED
    assert summary.reason.startswith("stack.close() from another thread")
    assert summary.stop_delivered, summary.safe_stop
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert any(
        "not the main thread: Ctrl-C and SIGTERM do not reach it" in text
        and "stack.close()" in text
        for text in warned
    ), warned
