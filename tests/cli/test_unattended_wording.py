"""What a robot that answers nothing at start-up tells its owner: "press Clean" to a person at
a terminal and to a Python program, the BRC wiring and the power to a service's owner, whom
nobody reads at the robot (``robot/wording.py``: ``UNATTENDED``; docs/unattended.md)."""

from __future__ import annotations

import io
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest

from roomba_bt import cli
from roomba_bt.robot import wording
from roomba_bt.robot.startup import NOT_AWAKE, no_answer_causes

DOCK = str(Path(__file__).resolve().parents[2] / "missions" / "dock.yaml")
PRESS = "no power or the robot asleep (press Clean or the power button)"


class Terminal(io.StringIO):
    """A stdin that is a TTY: a person ran the command."""

    def isatty(self) -> bool:
        return True


@pytest.fixture
def silent_bridge() -> Iterator[str]:
    """A ``socket://`` bridge that takes the connection and passes nothing on: a robot
    asleep (or without power) behind it."""
    listener = socket.create_server(("127.0.0.1", 0))
    try:
        yield f"socket://127.0.0.1:{listener.getsockname()[1]}"
    finally:
        listener.close()


def test_a_python_caller_is_told_to_press_clean() -> None:
    assert wording.current is wording.PYTHON
    assert no_answer_causes("/dev/ttyUSB0")[1] == PRESS == NOT_AWAKE


def test_the_command_line_at_a_terminal_says_press_clean_and_a_service_says_brc(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr("sys.stdin", Terminal())
    assert cli._command_line_wording() is wording.COMMAND_LINE
    monkeypatch.setattr("sys.stdin", io.StringIO())  # a service's: /dev/null, no TTY
    assert cli._command_line_wording() is wording.UNATTENDED
    monkeypatch.setattr("sys.stdin", None)  # none at all (pythonw, a daemon that closed it)
    assert cli._command_line_wording() is wording.UNATTENDED


def test_a_service_s_run_that_finds_no_robot_says_what_its_owner_can_do(
    silent_bridge: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: "press Clean or the power button" in a service's journal, nobody there."""
    monkeypatch.setattr("sys.stdin", io.StringIO())
    assert cli.main(["run", DOCK, "--port", silent_bridge, "--display", "none"]) == 3
    err = capsys.readouterr().err
    assert "no power or the robot asleep (unattended, a BRC pulse wakes it: BRC wired to " in err
    assert "keep-awake left on; else check the dock's power and the battery" in err
    assert "press Clean" not in err
    assert wording.current is wording.PYTHON  # the program's own words after the call


def test_a_run_at_a_terminal_that_finds_no_robot_says_press_clean(
    silent_bridge: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("sys.stdin", Terminal())
    assert cli.main(["run", DOCK, "--port", silent_bridge, "--display", "none"]) == 3
    assert PRESS in capsys.readouterr().err


@pytest.mark.parametrize(
    "words",
    [wording.PYTHON, wording.COMMAND_LINE, wording.UNATTENDED],
    ids=["python", "command line", "unattended"],
)
def test_a_pty_s_silence_names_the_hang_up_that_wakes_it_not_a_cable_s_brc_wiring(
    words: wording.ConnectionWording,
) -> None:
    """The long-haul report: a run against ``sim --pty --asleep`` (exit 3) was told of "BRC
    wired to the port's RTS or DTR", on a pty, which has none, and not that ``doctor``'s 1 s
    hang-up wakes it. A device path keeps its own words."""
    with wording.spoken(words):
        said = no_answer_causes("/dev/pts/7")[1]
        on_a_cable = no_answer_causes("/dev/ttyUSB0")[1]
    assert said.startswith("no power or the robot asleep (a pty has no modem lines")
    assert "`roomba-bt doctor --port /dev/pts/7`" in said and "1 s hang-up" in said
    assert "RTS or DTR" not in said
    assert on_a_cable == f"no power or the robot asleep ({words.wake_asleep})"
    if words is not wording.PYTHON:
        assert "run --baud auto" in said and "a run at a set rate adds no hang-up" in said
