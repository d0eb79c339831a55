"""Where a method returned a wrong value is told from its source only when it is certain:
the one ``return`` that can give it, or reaching the end; else the ``def`` is named, as
the definition, never as the place it returned (session 25: the report named the ``def``
line as where ``Status.INVALID`` came from)."""

from __future__ import annotations

import inspect
from typing import Any

from py_trees.common import Status

from roomba_bt.behaviours.returned import returned_from


class Plugin:
    """Methods returning as a plugin's update or check may."""

    def one_invalid(self, n: int) -> Status:
        if n < 2:
            return Status.RUNNING
        return Status.INVALID  # the line named

    def computed(self, status: Status) -> Status:
        if status is Status.SUCCESS:
            return Status.FAILURE
        return status

    def two_invalid(self, n: int) -> Status:
        if n:
            return Status.INVALID
        return Status.INVALID

    def forgets(self) -> None:
        def inner() -> Status:
            return Status.SUCCESS

        inner()

    def bare(self, n: int) -> Any:
        if n:
            return
        return "no"

    def bare_or_end(self, n: int) -> Any:
        if n:
            return
        if n > 1:
            return "no"


HERE = inspect.getsourcefile(Plugin)


def _line(method: Any, text: str) -> int:
    """The file's line of the first line of ``method`` that holds ``text``."""
    lines, first = inspect.getsourcelines(method)
    return first + next(i for i, line in enumerate(lines) if text in line)


def test_the_one_return_that_gives_the_value_is_named() -> None:
    at = _line(Plugin.one_invalid, "return Status.INVALID")
    assert returned_from(Plugin.one_invalid, Status.INVALID) == f"at {HERE}:{at}"
    at = _line(Plugin.bare, "return\n")
    assert returned_from(Plugin.bare, None) == f"at {HERE}:{at}"
    at = _line(Plugin.bare, 'return "no"')
    assert returned_from(Plugin.bare, "no") == f"at {HERE}:{at}"


def test_a_computed_value_or_two_returns_name_the_definition_only() -> None:
    """``return status`` may have given it; so may either of two; and a method that can
    also reach its end may have returned None there."""
    for method, value in [(Plugin.computed, Status.INVALID), (Plugin.two_invalid, Status.INVALID),
                          (Plugin.bare_or_end, None)]:  # fmt: skip
        defined = _line(method, "def ")
        assert returned_from(method, value) == f"{method.__name__}() defined at {HERE}:{defined}"


def test_none_from_a_method_without_a_return_is_its_end() -> None:
    """The return of a function defined inside it is not its own."""
    defined = _line(Plugin.forgets, "def forgets")
    assert returned_from(Plugin.forgets, None) == (
        f"forgets() defined at {HERE}:{defined}, which ends without a return"
    )
