"""A run in a worker thread: signals reach only the main thread, so the program's main thread
catches Ctrl-C or SIGTERM and calls ``RunStack.stop``; the run ends INTERRUPTED with its safe
stop delivered (``stack.close()`` from the main thread had cut the link under it: connection
lost, the stop not delivered)."""

from __future__ import annotations

import threading

import py_trees
from waits import joined, waited  # tests/waits.py: a hang's bound, no fixed bet

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Simulator, load_world

from .simrun import TapLink, run_in_a_worker

SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def test_a_run_in_a_worker_thread_is_stopped_by_the_main_thread() -> None:
    driving, stopped = threading.Event(), threading.Event()

    def observer(runner: MissionRunner) -> None:
        if runner.snapshot.tick == 40:  # driving: the main thread stops it now
            driving.set()
            waited(stopped, "the main thread's stop")

    root = py_trees.composites.Sequence("w", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("forward", {"velocity": "100 mm/s"}),
    ])  # fmt: skip
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(TreeMission(root, "worker"), link, profile=CREATE2, observer=observer)
    worker, result = run_in_a_worker(stack)
    waited(driving, "the run's 40th tick")
    assert link.simulator.requested_left > 0  # the robot drives
    stack.stop("the operator pressed Ctrl-C")  # what the main thread's handler does
    stopped.set()
    joined(worker, "the run's worker thread, stopped")
    stack.close()
    [summary] = result
    assert isinstance(summary, RunSummary), summary
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.reason == "the operator pressed Ctrl-C"
    assert summary.safe_stop.startswith("sent ") and summary.stop_delivered
    assert link.written.endswith(SAFE_END)
    assert link.simulator.mode is OIMode.PASSIVE
    assert link.simulator.requested_left == link.simulator.requested_right == 0
