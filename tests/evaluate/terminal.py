"""A terminal for the progress bars' tests: a text buffer that says it is a terminal, and
the ``TERM`` of one that takes control codes (the bars write none to ``TERM=dumb``, and a
test's own environment may be that)."""

from __future__ import annotations

import io

import pytest


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def a_terminal_that_takes_codes(monkeypatch: pytest.MonkeyPatch) -> None:
    """The bars write no code to a ``TERM=dumb`` terminal: a test's stand-in is none."""
    monkeypatch.setenv("TERM", "xterm")
