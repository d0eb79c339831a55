"""roomba-bt's own bug (not a behaviour's: the runner, the display, the monitor, the record)
is one line naming the exception and where it came from, the traceback with ``-v``, and exit
70 (``ExitCode.INTERNAL_ERROR``), after the run's port was closed.

It was Python's traceback and exit 1 ("the mission failed"), and a run's ``stack.close()``
was skipped: the record's end note, the monitor's shutdown, the port's close (its kernel
exclusive mode cleared) and the retry of an undelivered stop. The bug is put in by patching
a function the run calls after its safe stop, or one a command calls."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.robot.connection import Connection
from roomba_bt.runtime.ending import RunEnding
from roomba_bt.runtime.summary import ExitCode

MISSION = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"


def _bug(*args: object, **kwargs: object) -> None:
    raise RuntimeError("a bug put in by the test")


@pytest.fixture
def closes(monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """What each :meth:`Connection.close` of the test returned (True: the robot stopped)."""
    returned: list[bool] = []
    close = Connection.close

    def counted(self: Connection) -> bool:
        returned.append(close(self))
        return returned[-1]

    monkeypatch.setattr(Connection, "close", counted)
    return returned


@pytest.mark.parametrize("verbose", [False, True], ids=["plain", "-v"])
def test_a_bug_in_the_runner_after_the_safe_stop_closes_the_port_and_exits_70(
    monkeypatch: pytest.MonkeyPatch,
    closes: list[bool],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    verbose: bool,
) -> None:
    monkeypatch.setattr(RunEnding, "sum_up", _bug)  # the summary's last figures
    record = tmp_path / "run.jsonl"
    argv = ["run", str(MISSION), "--fast", "--display", "none", "--timeout", "2s",
            "--record", str(record), *(["-v"] if verbose else [])]  # fmt: skip
    assert main(argv) == ExitCode.INTERNAL_ERROR == 70
    _, err = capsys.readouterr()
    assert closes == [True]  # the stack was closed: the robot stopped, the port let go of
    assert "the robot was stopped (the safe stop was delivered) and its port closed" in err
    assert "roomba-bt: internal error: RuntimeError: a bug put in by the test (at " in err
    assert ("Traceback (most recent call last)" in err) is verbose
    if not verbose:
        assert_quoted("docs/runtime.md", "roomba-bt: internal error: RuntimeError", err)
    assert ("with the traceback (run with -v)" in err) is not verbose
    assert '"ended": ' in record.read_text()  # the record's end note


def test_a_bug_in_another_command_is_one_line_and_exit_70(
    monkeypatch: pytest.MonkeyPatch, closes: list[bool], capsys: pytest.CaptureFixture[str]
) -> None:
    """``sensors``: its connection closes on the way out (``with connection``), and the
    bug is said as the run's is."""
    monkeypatch.setattr("roomba_bt.cli.sensors_cmd.format_table", _bug)
    assert main(["sensors", "--count", "1"]) == ExitCode.INTERNAL_ERROR
    out, err = capsys.readouterr()
    assert closes == [True]
    assert "roomba-bt: internal error: RuntimeError: a bug put in by the test" in err
    assert "Traceback" not in out + err


def test_a_bug_while_the_stack_is_built_lets_the_port_go(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Between the port's open and the run (``RunStack(...)``): the port was left open."""
    import roomba_bt.cli.links as links

    opened: list[Any] = []
    far_end: Callable[..., Any] = links.far_end

    def kept(*args: Any, **kwargs: Any) -> Any:
        opened.append(far_end(*args, **kwargs))
        return opened[-1]

    monkeypatch.setattr(links, "far_end", kept)
    monkeypatch.setattr("roomba_bt.runtime.stack.RunStack.__init__", _bug)
    assert main(["run", str(MISSION), "--fast", "--display", "none"]) == 70
    assert len(opened) == 1 and not opened[0].is_open
    assert "internal error: RuntimeError" in capsys.readouterr().err
