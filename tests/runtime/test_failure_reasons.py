"""The summary's failure names the node that failed the run, never a leaf that succeeded
before it (session 28: ``[drive 100ms, force_failure: {wait: 15ms}]`` said ``failure:
drive(velocity=100 mm/s, duration=100ms)``)."""

from __future__ import annotations

import pytest

from roomba_bt.runtime.summary import Outcome

from .simrun import RunMission


@pytest.mark.parametrize(
    ("steps", "reason"),
    [
        # a forced failure: the decorator, with its child's status
        ("[{mode: safe}, {drive: {velocity: 100 mm/s, duration: 100ms}},"
         " {force_failure: {wait: 15ms}}]",
         "force_failure: wait(15ms) succeeded (success is failure)"),
        ("[{log: hello}, {force_failure: {wait: 15ms}}]",
         "force_failure: wait(15ms) succeeded (success is failure)"),
        ("[{log: delayed}, {force_failure: {inverter: {bump: any}}}]",
         "force_failure: inverter succeeded (success is failure)"),
        # an inverted action ran and succeeded (it did not "hold"); an inverted condition held
        ("[{log: hello}, {inverter: {wait: 15ms}}]", "inverter: wait(15ms) succeeded (inverted)"),
        ("[{log: hello}, {inverter: {ir: {sees: dock}}}]", "ir(sees=dock) held"),
        # a condition that failed, a time limit that ran out
        ("[{log: hello}, {bump: any}]", "bump(any)"),
        ("[{log: hello}, {timeout: {after: 100ms, do: {wait: 1s}}}]",
         "timeout: the tree's 0.1 s limit ran out in wait"),
    ],
)  # fmt: skip
def test_the_failure_names_the_node_that_failed_the_run(
    run_mission: RunMission, steps: str, reason: str
) -> None:
    run = run_mission(f"tree:\n  sequence: {steps}\n")
    assert run.summary.outcome is Outcome.FAILURE
    assert run.summary.reason == reason
