"""``validate`` says what it can judge in one pass: a wrong value beside a read-before-write
error, and a decorator's bad option over its child's own errors (library report finding 3:
each came only once the other was fixed)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

Errors = Callable[..., list[str]]

UNWRITTEN = "reads blackboard key 'n' before anything writes it on some path"


def test_a_set_whose_value_alone_is_wrong_leaves_the_other_keys_judged(errors_of: Errors) -> None:
    """The ``set`` names its key: it writes ``armed`` once fixed, and ``n``, written by
    nothing, is said in the same pass as the set's wrong value."""
    errors = errors_of(
        """
        blackboard: {armed: bool, n: int}
        tree:
          sequence:
            - set: {key: armed, value: 3}
            - check: {key: armed, value: true}
            - check: {key: n, op: "==", value: 2}
        """
    )
    assert len(errors) == 2, errors
    assert "set.value: expected true or false, got 3" in errors[0]
    assert UNWRITTEN in errors[1]


def test_a_set_whose_key_did_not_resolve_still_holds_the_readers_back(errors_of: Errors) -> None:
    """A ``set`` whose key is unknown may write any key once fixed: no reader is said
    unwritten because of it (a false error), as before."""
    errors = errors_of(
        """
        blackboard: {n: int}
        tree:
          sequence:
            - set: {key: nn, value: 2}
            - check: {key: n, op: "==", value: 2}
        """
    )
    assert errors and not any(UNWRITTEN in error for error in errors), errors


@pytest.mark.parametrize(
    ("decorator", "option_error"),
    [
        ("repeat: {times: 0, do: DRIVE}", "repeat.times must be at least 1, got 0"),
        ("retry: {times: 0, do: DRIVE}", "retry.times must be at least 1, got 0"),
        ("timeout: {do: DRIVE}", "timeout needs after:"),
    ],
)
def test_a_decorator_s_bad_option_does_not_hide_its_child_s_errors(
    errors_of: Errors, decorator: str, option_error: str
) -> None:
    drive = "{drive: {velocity: 900 mm/s, duration: 1s}}"
    errors = errors_of(
        f"tree: {{sequence: [{{mode: safe}}, {{{decorator.replace('DRIVE', drive)}}}]}}"
    )
    assert any(option_error in error for error in errors), errors
    assert any("velocity 900 mm/s is out of range" in error for error in errors), errors
