"""Fixtures for the command-line tests."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from runtime.simrun import SHORT_DRIVE, write_mission  # tests/runtime: the short drive

from roomba_bt.cli import main


@pytest.fixture
def help_text(capsys: pytest.CaptureFixture[str]) -> Callable[[str], str]:
    """A command's ``--help`` as one line: argparse's line breaks undone, so a test reads a
    sentence the width of the terminal broke."""

    def text_of(command: str) -> str:
        with pytest.raises(SystemExit):
            main([command, "--help"])
        return " ".join(capsys.readouterr().out.split())

    return text_of


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    """The short drive the command lines here run: ``short.yaml``, 20 cm at a ``speed``
    parameter that defaults to 200 mm/s."""
    return write_mission(tmp_path, SHORT_DRIVE, "short.yaml")
