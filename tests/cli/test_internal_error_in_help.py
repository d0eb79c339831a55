"""Exit 70 (roomba-bt's own bug: ``roomba-bt: internal error ...``) can end every command, but
only ``run --help`` listed it among its exit codes; each command that lists its exit codes
says it, in the words of one table (``ExitCode``)."""

from __future__ import annotations

import re
from collections.abc import Callable

import pytest

from roomba_bt.runtime.summary import INTERNAL_ERROR_SAID, ExitCode


@pytest.mark.parametrize("command", ["run", "replay", "sensors", "doctor", "eval", "validate"])
def test_every_command_that_lists_its_exit_codes_lists_70(
    command: str, help_text: Callable[[str], str]
) -> None:
    # argparse refills the text: a line may break anywhere, even after a hyphen
    text = re.sub(r"-\s+", "-", help_text(command))
    assert "xit " in text  # "Exit codes:" or "Exit 0 if"
    assert f"{int(ExitCode.INTERNAL_ERROR)} internal error (a bug in roomba-bt)" in text
    assert INTERNAL_ERROR_SAID.startswith(f"{int(ExitCode.INTERNAL_ERROR)} ")
