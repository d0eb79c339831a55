"""Structural dead ends (roomba_bt.mission.deadends, docs/missions.md "Validation"): a step
after one that never succeeds, an alternative after one that never fails, a guard decided
on its first tick, a retry that never retries, a parallel of a condition and its inverter
(warnings), and ``held`` as a step ticked once (an error). Each rule is pinned by a tree
it finds, and each exception (what something around an endless node ends it by: a guard, a
timeout, a reactive parent) by a tree it leaves alone."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from roomba_bt.mission import CompiledMission


def _steps(steps: list[str]) -> str:
    """A mission whose tree is ``mode: safe`` then ``steps``, one per line from line 4."""
    return "tree:\n  sequence:\n    - mode: safe\n" + "".join(f"    - {s}\n" for s in steps)


def _dead_ends(mission: CompiledMission) -> list[str]:
    """The dead-end warnings, as ``line:col first words``."""
    said = ("can never run", "never runs", "never retries", "can never succeed")
    return [
        f"{w.line}:{w.column} {w.message.split(':')[0]}"
        for w in mission.warnings
        if any(s in w.message for s in said) and w.severity == "warning"
    ]


@pytest.mark.parametrize(
    ("steps", "said"),
    [
        # pytrees session 34, neverend.yaml: the run pushed into the wall until --timeout
        (["drive: {velocity: 100 mm/s}", "log: after"], ["5:7 log(after) can never run"]),
        # repeatforever.yaml, seqnever.yaml, invwait.yaml
        (["repeat: {do: {wait: 1s}}", "log: after"], ["5:7 log(after) can never run"]),
        (["force_failure: {wait: 1s}", "log: never"], ["5:7 log(never) can never run"]),
        (["inverter: {wait: 1s}", "log: never"], ["5:7 log(never) can never run"]),
        # parallnever.yaml: a parallel (policy all) with a branch that never succeeds
        (["parallel: [{wait: 1s}, {drive: {velocity: 100 mm/s}}]", "log: after"],
         ["5:7 log(after) can never run"]),
        # unreach.yaml: a fallback's alternative after one that never fails
        (["fallback: [{force_success: {bump: any}}, {log: b}]"], ["4:49 log(b) can never run"]),
        (["fallback: [{wait: 1s}, {log: b}]"], ["4:31 log(b) can never run"]),
        # guards.yaml: a guard decided on its first tick
        (["drive: {velocity: 100 mm/s, duration: 1s}\n      until: {force_success: {bump: any}}"],
         ["4:7 drive(velocity=100 mm/s, duration=1s) never runs"]),
        (["drive: {velocity: 100 mm/s, duration: 1s}\n      while: {force_failure: {bump: any}}"],
         ["4:7 drive(velocity=100 mm/s, duration=1s) never runs"]),
        (["wait: 1s\n      while: {held: {for: 1s, do: {inverter: {bump: any}}}}"],
         ["4:7 wait(1s) never runs"]),
        # retrynever.yaml, retryfailnever.yaml
        (["retry: {times: 5, do: {force_success: {bump: any}}}"], ["4:7 retry never retries"]),
        (["retry: {times: 3, do: {wait: 1s}}"], ["4:7 retry never retries"]),
        # parnever.yaml: both read on the first tick, one of them fails on it
        (["parallel: [{bump: any}, {inverter: {bump: any}}]"],
         ["4:7 the parallel can never succeed"]),
    ],
)  # fmt: skip
def test_a_dead_end_is_warned_of(
    compile_text: Callable[..., CompiledMission], steps: list[str], said: list[str]
) -> None:
    assert _dead_ends(compile_text(_steps(steps))) == said


@pytest.mark.parametrize(
    "steps",
    [
        # an endless node at the end of the tree: a patrol
        ["repeat: {do: {wait: 1s}}"],
        ["drive: {velocity: 100 mm/s}"],
        # something around the endless drive ends it, and the step after runs
        ["drive: {velocity: 100 mm/s}\n      until: {bump: any}", "log: after"],
        ["reactive_fallback: [{bump: any}, {drive: {velocity: 100 mm/s}}]", "log: after"],
        ["fallback: [{timeout: {after: 5s, do: {drive: {velocity: 100 mm/s}}}}, {log: cut}]",
         "log: after"],
        ["force_success: {timeout: {after: 5s, do: {repeat: {do: {wait: 1s}}}}}", "log: after"],
        ["parallel: {policy: one, children: [{wait: 1s}, {drive: {velocity: 100 mm/s}}]}",
         "log: after"],
        # a parallel that drives until a cliff fails it, as meant; conditions that change
        ["parallel: [{drive: {velocity: 100 mm/s}}, {inverter: {cliff: any}}]"],
        ["wait: 1s\n      until: {held: {for: 1s, do: {bump: any}}}", "log: after"],
        ["drive: {velocity: 100 mm/s, duration: 1s}\n      while: {inverter: {bump: any}}"],
        # a retry of what can fail; a fallback whose first alternative can fail
        ["retry: {times: 3, do: {sequence: [{wait: 1s}, {bump: any}]}}"],
        ["fallback: [{bump: any}, {log: b}]"],
        # held ticked on every tick: under a loop, a guard, a reactive fallback
        ["retry: {times: 50, do: {sequence: [{held: {for: 45ms, do: wall}}, {log: held}]}}"],
        ["repeat: {do: {retry: {times: 50, do: {parallel: [{held: {for: 45ms, do: wall}}]}}}}"],
        ["wait: 1s\n      until: {sequence: [{held: {for: 45ms, do: wall}}, {bump: any}]}"],
        ["reactive_fallback: [{reactive_sequence: [{held: {for: 45ms, do: wall}}, {wait: 1s}]},"
         " {wait: 1s}]"],
        ["retry: {times: 9, do: {inverter: {inverter: {sequence: [{held: {for: 45ms, do:"
         " wall}}]}}}}"],
        # a decorator that answers held's first FAILURE otherwise, or ticks it again
        ["inverter: {held: {for: 45ms, do: wall}}", "log: after"],
        ["force_success: {timeout: {after: 5s, do: {held: {for: 45ms, do: wall}}}}"],
        ["retry: {times: 50, do: {timeout: {after: 5s, do: {held: {for: 45ms, do: wall}}}}}"],
        ["delay: {for: 1s, do: {held: {for: 45ms, do: wall}}}"],
        ["reactive_fallback: [{sequence: [{held: {for: 45ms, do: wall}}, {log: held}]},"
         " {wait: 1s}]"],
    ],
)  # fmt: skip
def test_what_something_ends_is_no_dead_end(
    compile_text: Callable[..., CompiledMission], steps: list[str]
) -> None:
    assert _dead_ends(compile_text(_steps(steps))) == []


def test_held_as_a_step_ticked_once_is_an_error(errors_of: Callable[..., list[str]]) -> None:
    """decos.yaml (pytrees session 34): ``outcome FAILURE (held: held 0 s of 0.045 s so
    far)`` on every run."""
    errors = errors_of(_steps(["held: {for: 45ms, do: {inverter: {bump: any}}}", "log: after"]))
    assert len(errors) == 1
    assert errors[0].startswith("4:7: held is FAILURE on the tick it starts")
    assert "ticked once: the sequence fails here on every run" in errors[0]
    assert "until: {held: ...}" in errors[0]


@pytest.mark.parametrize(
    ("steps", "where"),
    [
        # verify session 34: n03_repeatheld.yaml, a repeat stops at its child's FAILURE
        (["repeat: {times: 3, do: {sequence: [{held: {for: 45ms, do: wall}}, {log: held}]}}"],
         "4:43: held is FAILURE on the tick it starts (its hold has lasted 0 s), and as a step "
         "of this sequence (4:31) it is ticked once: the sequence fails here"),
        # n10_rseqheld.yaml: a reactive_sequence fails when a child fails
        (["reactive_sequence: [{held: {for: 100ms, do: wall}}, {wait: 1s}]"],
         "4:28: held is FAILURE on the tick it starts (its hold has lasted 0 s), and as a step "
         "of this reactive_sequence (4:7) it is ticked once: the reactive_sequence fails here"),
        # parheld.yaml: a failed branch fails a parallel, whatever its policy
        (["parallel: {policy: one, children: [{wait: 3s}, {held: {for: 2s, do: wall}}]}"],
         "4:55: held is FAILURE on the tick it starts (its hold has lasted 0 s), and as a branch "
         "of this parallel (4:7) it is ticked once: the parallel fails here"),
        # a decorator that passes its child's FAILURE up (timeout, repeat, oneshot): as the
        # held directly in the sequence
        (["timeout: {after: 5s, do: {held: {for: 45ms, do: wall}}}", "log: after"],
         "4:33: held is FAILURE on the tick it starts (its hold has lasted 0 s), passed up by "
         "timeout (4:7), and as a step of this sequence (2:3) it is ticked once"),
        (["oneshot: {repeat: {times: 2, do: {held: {for: 45ms, do: wall}}}}", "log: after"],
         "4:41: held is FAILURE on the tick it starts (its hold has lasted 0 s), passed up by "
         "repeat (4:17) and oneshot (4:7), and as a step of this sequence (2:3) it is ticked "
         "once"),
        # the node a guard runs ends the guard as it ends: not ticked again
        (["sequence: [{held: {for: 45ms, do: wall}}, {log: held}]\n      until: {bump: any}"],
         "4:19: held is FAILURE on the tick it starts (its hold has lasted 0 s), and as a step "
         "of this sequence (4:7) it is ticked once: the sequence fails here"),
    ],
)  # fmt: skip
def test_held_whose_first_failure_fails_its_parent_is_an_error(
    errors_of: Callable[..., list[str]], steps: list[str], where: str
) -> None:
    """Under a loop that stops at a failure, in a reactive sequence, as a parallel's branch:
    each ran ``outcome FAILURE (held: held 0 s of ... so far)`` on every run."""
    errors = errors_of(_steps(steps))
    assert len(errors) == 1, errors
    assert errors[0].startswith(where)


@pytest.mark.parametrize(
    ("step", "said"),
    [
        ("retry: {times: 3, do: {set: {key: n, value: 1}}}",
         "retry never retries: set(key=n, value=1) (line 7) never fails"),
        ("fallback: [{mark: at}, {log: b}]",
         "log(b) can never run: the alternative before it, mark(at) (line 7), never fails"),
    ],
)  # fmt: skip
def test_set_and_mark_never_fail(
    compile_text: Callable[..., CompiledMission], step: str, said: str
) -> None:
    """``set`` and ``mark`` write their key and succeed on the tick they start: a value
    that is not of the key's type raises (``write_key``'s ``KeyType``, a behaviour error
    that ends the run), never FAILURE. Declared ``never_fails``, as ``wait`` and ``log``:
    a retry around one never retries, an alternative after one never runs."""
    mission = compile_text("blackboard:\n  n: int\n  at: mark\n" + _steps([step]))
    assert any(said in w.message for w in mission.warnings), mission.warnings


def test_dead_ends_fail_validate_strict(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """Warnings, as the other tree warnings: the mission compiles (``--strict`` fails it)."""
    mission = compile_text(_steps(["drive: {velocity: 100 mm/s}", "log: after"]))
    [warning] = [w for w in mission.warnings if "can never run" in w.message]
    assert warning.severity == "warning"
    assert "drive(velocity=100 mm/s) (line 4), never succeeds" in warning.message


def test_warnings_come_in_line_order_and_a_guarded_step_is_named_by_its_node(
    compile_text: Callable[..., CompiledMission],
) -> None:
    """pytrees session 34, guards.yaml: the warnings came by check (lines 8, 5, 7, 9), and
    the step blocked after ``while: {held: ...}`` was named ``until force_success`` at its
    guard's line, not the ``drive`` written above it."""
    drive = "drive(velocity=100 mm/s, duration=1s)"
    mission = compile_text(
        _steps(
            [
                "drive: {velocity: 100 mm/s, duration: 1s}\n"
                "      while: {held: {for: 1s, do: {inverter: {bump: any}}}}",
                "drive: {velocity: 100 mm/s, duration: 1s}\n"
                "      until: {force_success: {bump: any}}",
            ]
        )
    )
    assert _dead_ends(mission) == [
        f"4:7 {drive} never runs",
        f"6:7 {drive} can never run",
        f"6:7 {drive} never runs",
    ]
    [blocked] = [w.message for w in mission.warnings if "can never run" in w.message]
    assert f"the step before it, {drive} (line 4, while held), never succeeds" in blocked
    assert [(w.file, w.line, w.column) for w in mission.warnings] == sorted(
        (w.file, w.line, w.column) for w in mission.warnings
    )
