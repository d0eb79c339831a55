"""The failure a user reads first: down the path of failed children from the root, the
failed leaf on it, else the deepest message on it."""

from __future__ import annotations

import py_trees

from roomba_bt.behaviours.decorators import Guard
from roomba_bt.behaviours.lean import Retry
from roomba_bt.behaviours.reasons import failure_reason, running_in, while_stopped

FAILURE = py_trees.common.Status.FAILURE


def test_the_failed_leaf_and_its_message_come_first() -> None:
    leaf = py_trees.behaviours.Failure(name="charging")
    root = py_trees.composites.Sequence("mission", memory=True, children=[leaf])
    root.tick_once()
    leaf.feedback_message = "no charging state in packet 21"
    assert failure_reason(root) == "charging: no charging state in packet 21"


def test_when_the_leaves_were_reset_the_deepest_message_is_used() -> None:
    leaf = py_trees.behaviours.Failure(name="dock_drive_on")
    attempt = py_trees.composites.Sequence("attempt", memory=True, children=[leaf])
    retry = py_trees.decorators.Retry("retry", child=attempt, num_failures=1)
    root = py_trees.composites.Sequence("mission", memory=True, children=[retry])
    root.tick_once()
    assert root.status == FAILURE
    leaf.stop(py_trees.common.Status.INVALID)  # what a parallel or guard does to its children
    attempt.stop(py_trees.common.Status.INVALID)
    assert failure_reason(root).startswith("retry: final failure")


def test_the_path_of_the_failure_is_followed_not_the_last_failed_leaf() -> None:
    """A patrol (second branch) gives up after its retries; the low-battery check (first
    branch) also failed, and was the only failed leaf left: it used to be the reason."""
    low = py_trees.composites.Sequence(
        "low battery", memory=True, children=[py_trees.behaviours.Failure(name="battery")]
    )
    leaf = py_trees.behaviours.Failure(name="cliff")
    attempt = py_trees.composites.Sequence("attempt", memory=True, children=[leaf])
    retry = Retry("retry", child=attempt, num_failures=2)
    patrol = py_trees.composites.Sequence("patrol", memory=True, children=[retry])
    root = py_trees.composites.Selector("mission", memory=False, children=[low, patrol])
    root.tick_once()
    root.tick_once()
    assert root.status == FAILURE
    leaf.stop(py_trees.common.Status.INVALID)  # reset by a parent, as a retry or guard does
    attempt.stop(py_trees.common.Status.INVALID)
    assert (
        failure_reason(root) == "retry: gave up after 2 failed attempts; the last: cliff: failure"
    )


def test_a_flipped_status_is_named_without_its_canned_message() -> None:
    inverter = py_trees.decorators.Inverter(
        "nothing may be ahead", child=py_trees.behaviours.Success(name="wall")
    )
    root = py_trees.composites.Sequence("mission", memory=True, children=[inverter])
    root.tick_once()
    assert root.status == FAILURE
    # its name, and the condition that held under it
    assert failure_reason(root) == "nothing may be ahead (wall held)"


def test_a_forced_failure_after_a_condition_names_the_condition_then_the_decorator() -> None:
    """The patrol's pattern: drive until a cliff, then back off and fail on purpose so the
    retry tries again; its giving up names the cliff that held, then the ``force_failure``
    that failed the attempt (session 28: the cliff alone was said)."""
    cliff = py_trees.behaviours.Success(name="cliff(any)")
    until = py_trees.composites.Selector(
        "until", memory=False, children=[py_trees.behaviours.Failure(name="lap done"), cliff]
    )
    back_off = py_trees.decorators.SuccessIsFailure(
        "force_failure", child=py_trees.behaviours.Success(name="back off")
    )
    inverter = py_trees.decorators.Inverter(
        "inverter", child=py_trees.behaviours.Success(name="cliff(any) again")
    )
    react = py_trees.composites.Selector("fallback", memory=True, children=[inverter, back_off])
    attempt = py_trees.composites.Sequence("attempt", memory=True, children=[until, react])
    retry = Retry("retry", child=attempt, num_failures=2)
    root = py_trees.composites.Sequence("patrol", memory=True, children=[retry])
    root.tick_once()
    root.tick_once()
    assert root.status == FAILURE
    assert failure_reason(root) == (
        "retry: gave up after 2 failed attempts; the last: cliff(any) held, then "
        "force_failure: back off succeeded (success is failure)"
    )


def test_a_reason_is_one_line_whatever_the_names_it_quotes() -> None:
    """A mission's name for a node ("\\n[ok] fake") went raw into the reason, and so into the
    summary, the log, the monitor and eval's report, where it started a line of its own; a
    control character ("\\x1b[2J": a cleared screen) too. They are escaped."""
    leaf = py_trees.behaviours.Failure(name="never\n[ok] fake")
    root = py_trees.composites.Sequence("\x1b[2J", memory=True, children=[leaf])
    root.tick_once()
    leaf.feedback_message = "held \x1b[2J"
    assert failure_reason(root) == "never\\x0a[ok] fake: held \\x1b[2J"
    condition = py_trees.decorators.Inverter(
        "inverter", child=py_trees.behaviours.Success(name="cliff\n[ok] fake")
    )
    condition.tick_once()
    said = while_stopped(condition, "clean\n[ok] fake")
    assert "\n" not in said and said.startswith("stopped: cliff\\x0a[ok] fake held"), said
    running = py_trees.behaviours.Running(name="drive\n[ok] fake(speed=1)")
    running.tick_once()
    assert running_in(running) == " in drive\\x0a[ok] fake"


def _guard_of(*leaves: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """A ``while`` guard's condition as bump-and-turn writes it, ticked once: a reactive
    sequence of the leaves, which leave no message (as the ``sensor`` leaves do not)."""
    condition = py_trees.composites.Sequence("guard", memory=False, children=list(leaves))
    condition.tick_once()
    for leaf in leaves:
        leaf.feedback_message = ""  # py_trees' canned "failure"
    return condition


def test_a_condition_named_by_what_stopped_the_run_is_said_once() -> None:
    """bump-and-turn and wall-follow name each guard leaf by what its failing means
    (``stopped: cliff front left``); the reason said "stopped: stopped: cliff front left no
    longer holds while ...", the words doubled and the meaning backwards."""
    held = py_trees.behaviours.Success(name="stopped: cliff on the left")
    seen = py_trees.behaviours.Failure(name="stopped: cliff front left")
    condition = _guard_of(held, seen)
    guarded = "bump and turn for a while"
    said = while_stopped(condition, guarded)
    assert said == "stopped: cliff front left, while 'bump and turn for a while' ran"
    said = while_stopped(condition, guarded, started=False)
    assert said == "stopped: cliff front left, before 'bump and turn for a while' started"
    seen.feedback_message = "forced to FAILURE by the operator"
    assert while_stopped(condition, guarded) == (
        "stopped: cliff front left: forced to FAILURE by the operator, "
        "while 'bump and turn for a while' ran"
    )


def test_a_condition_named_otherwise_still_no_longer_holds() -> None:
    """A name that says what holds keeps the runtime's words around it."""
    condition = _guard_of(py_trees.behaviours.Failure(name="no cliff ahead"))
    assert while_stopped(condition, "clean") == (
        "stopped: no cliff ahead no longer holds while 'clean' ran"
    )


def test_a_forced_failure_after_a_while_guard_names_what_stopped_the_guarded_node() -> None:
    """A library's bump recovery: ``fallback[drive while not bump, force_failure(recover)]``
    in a ``retry``. Giving up said only "force_failure: bump_recovery succeeded (success is
    failure)", never that the bumper stopped the drive: the guard's reason comes first."""
    bump = py_trees.behaviours.StatusQueue(
        name="bump(any)", queue=[FAILURE], eventually=py_trees.common.Status.SUCCESS
    )
    drive = py_trees.behaviours.Running(name="drive(1m)")
    guard = Guard(
        "drive(1m)", py_trees.decorators.Inverter("inverter", child=bump), drive, until=False
    )
    recover = py_trees.decorators.SuccessIsFailure(
        "force_failure", child=py_trees.behaviours.Success(name="bump_recovery")
    )
    attempt = py_trees.composites.Selector("fallback", memory=True, children=[guard, recover])
    retry = Retry("retry", child=attempt, num_failures=1)
    root = py_trees.composites.Sequence("patrol", memory=True, children=[retry])
    root.tick_once()  # the drive runs: nothing bumped yet
    root.tick_once()  # the bumper: the guard stops the drive, the recovery fails the try
    assert root.status == FAILURE
    assert failure_reason(root) == (
        "retry: gave up after 1 failed attempt; the last: stopped: bump(any) held while "
        "'drive(1m)' ran (stage drive was running), then force_failure: bump_recovery "
        "succeeded (success is failure)"
    )
