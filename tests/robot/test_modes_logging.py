"""What the mode machine logs, as a program that calls ``logging.basicConfig(level=INFO)``
sees it: ``transitions`` logged "Finished processing state Safe enter callbacks" at INFO for
each of the machine's changes, four a start-up, as if they were the program's own."""

from __future__ import annotations

import logging
import subprocess
import sys

import pytest
from transitions import Machine
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as oi
from roomba_bt.robot.modes import MACHINE_NAME, ModeModel


def _start_up(model: ModeModel) -> None:
    model.apply(oi.start(), 0.0)
    model.apply(oi.safe(), 0.1)


def test_the_mode_machine_says_nothing_at_info(caplog: pytest.LogCaptureFixture) -> None:
    """The root logger at DEBUG, no level on ``transitions`` (the CLI sets one: not here)."""
    caplog.set_level(logging.DEBUG)
    caplog.set_level(logging.NOTSET, logger="transitions")
    model = ModeModel()
    _start_up(model)
    assert model.machine.get_model_state(model._model).name == "Safe"  # it moved
    assert [r.getMessage() for r in caplog.records if r.name.startswith("transitions")] == []


def test_asked_for_by_name_its_records_show(caplog: pytest.LogCaptureFixture) -> None:
    """A level on ``transitions`` (its README's way, ``roomba-bt -vv``'s): they are wanted."""
    caplog.set_level(logging.INFO, logger="transitions")
    _start_up(ModeModel())
    assert f"{MACHINE_NAME}: Finished processing state Safe enter callbacks." in caplog.messages


def test_a_programs_own_machine_still_logs(caplog: pytest.LogCaptureFixture) -> None:
    """Only this library's machine is quiet: ``transitions`` is the program's too."""
    caplog.set_level(logging.INFO)
    caplog.set_level(logging.NOTSET, logger="transitions")

    class Door:
        pass

    door = Door()
    Machine(door, states=["shut", "open"], initial="shut", transitions=[["push", "shut", "open"]])
    door.push()  # type: ignore[attr-defined]
    assert "Finished processing state open enter callbacks." in caplog.messages


def test_the_library_configures_no_logger_level_or_handler() -> None:
    """Importing the mode model sets no level and adds no handler, on the root logger or on
    ``transitions``' (a fresh interpreter: pytest's own logging aside)."""
    script = (
        "import logging\n"
        "import roomba_bt.robot.modes\n"
        "root, ours = logging.getLogger(), logging.getLogger('transitions')\n"
        "core = logging.getLogger('transitions.core')\n"
        "print(root.level, len(root.handlers), ours.level, core.level)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=HANG_S, check=True
    )
    assert done.stdout.split() == [str(logging.WARNING), "0", "0", "0"]
