"""The summary's failure names the node that failed the run, never a leaf that succeeded
before it (session 28: ``[drive 100ms, force_failure: {wait: 15ms}]`` said ``failure:
drive(velocity=100 mm/s, duration=100ms)``)."""

from __future__ import annotations

import pytest

from roomba_bt.runtime.summary import Outcome

from .simrun import RunMission

#: a tree's failure, and the reason it gives: the node that failed the run
FAILED_NODES = [
    # a forced failure: the decorator, with its child's status
    ("[{mode: safe}, {drive: {velocity: 100 mm/s, duration: 100ms}},"
     " {force_failure: {wait: 15ms}}]",
     "force_failure: wait(15ms) succeeded (success is failure)"),
    ("[{log: hello}, {force_failure: {wait: 15ms}}]",
     "force_failure: wait(15ms) succeeded (success is failure)"),
    ("[{log: delayed}, {force_failure: {inverter: {bump: any}}}]",
     "force_failure: inverter succeeded, as bump(any) did not hold (success is failure)"),
    # nested flips: each said as it ended, down to the leaf (they said only "inverter")
    ("[{log: hello}, {inverter: {inverter: {bump: any}}}]",
     "inverter: inverter succeeded, as bump(any) did not hold (inverted)"),
    ("[{log: hello}, {inverter: {name: not not, inverter: {inverter: {wait: 15ms}}}}]",
     "inverter: not not succeeded, as inverter failed, as wait(15ms) succeeded (inverted)"),
    ("[{log: hello}, {inverter: {selector: [{bump: any}, {inverter: {cliff: any}}]}}]",
     "inverter: inverter succeeded, as cliff(any) did not hold (inverted)"),
    ("[{log: hello}, {inverter: {sequence: [{log: a}, {inverter: {bump: any}}]}}]",
     "inverter: inverter succeeded, as bump(any) did not hold (inverted)"),
    # an inverter around a composite that a leaf decided: that leaf
    ("[{log: hello}, {inverter: {selector: [{bump: any}, {wait: 15ms}]}}]",
     "inverter: wait(15ms) succeeded (inverted)"),
    # an inverted action ran and succeeded (it did not "hold"); an inverted condition held
    ("[{log: hello}, {inverter: {wait: 15ms}}]", "inverter: wait(15ms) succeeded (inverted)"),
    ("[{log: hello}, {inverter: {ir: {sees: dock}}}]", "ir(dock) held"),
    # a condition that failed, a time limit that ran out
    ("[{log: hello}, {bump: any}]", "bump(any)"),
    ("[{log: hello}, {timeout: {after: 100ms, do: {wait: 1s}}}]",
     "timeout: the tree's 0.1 s limit ran out in wait"),
]  # fmt: skip

#: a ``while`` guard that stopped its node: the reason says only what happened
WHILE_GUARDS = [
    # h1 (session 28): the guard failed on its first tick, and the reason said the drive
    # "ran"; it was never started
    ("[{mode: safe}, {drive: {velocity: 100 mm/s, duration: 300ms},"
     " while: {held: {for: 1s, do: {inverter: {bump: any}}}}}]",
     "stopped: held: held 0 s of 1 s so far,"
     " before 'drive(velocity=100 mm/s, duration=300ms)' started"),
    # a minute and more in the unit the mission wrote it in: it said "of 120 s"
    ("[{mode: safe}, {wait: 1s, while: {held: {for: 2min, do: {inverter: {bump: any}}}}}]",
     "stopped: held: held 0 s of 2 min so far, before 'wait(1s)' started"),
    ("[{mode: safe}, {wait: 1s, while: {sensor: bumps_wheel_drops > 4}}]",
     "stopped: sensor(bumps_wheel_drops > 4) does not hold, before 'wait(1s)' started"),
    # an odometry guard with no mark counts from the run's start: it said "since a mark"
    ("[{mode: safe}, {drive: {velocity: 200 mm/s, duration: 5s}, name: outbound,"
     " while: {inverter: {odometry: {distance: 30cm}}}}]",
     "stopped: the robot has travelled the distance since the run began, while 'outbound'"
     " ran (odometry(distance=30cm) held) (stage outbound was running)"),
    ("[{mode: safe}, {mark: m}, {drive: {velocity: 200 mm/s, radius: spin_left,"
     " duration: 5s}, name: round, while: {inverter: {odometry: {since: m, angle: 90deg}}}}]",
     "stopped: the robot has turned the angle since mark 'm', while 'round' ran"
     " (odometry(since=m, angle=90deg) held) (stage round was running)"),
]  # fmt: skip


@pytest.mark.parametrize(("steps", "reason"), FAILED_NODES + WHILE_GUARDS)
def test_the_failure_names_the_node_that_failed_the_run(
    run_mission: RunMission, steps: str, reason: str
) -> None:
    """Each tree is a ``sequence`` of ``steps``; the blackboard declares the mark ``m`` that
    the last guard counts from (the other trees leave it unused)."""
    run = run_mission(f"blackboard: {{m: mark}}\ntree:\n  sequence: {steps}\n")
    assert run.summary.outcome is Outcome.FAILURE
    assert run.summary.reason == reason
