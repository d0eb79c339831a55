"""Every command names itself in its usage errors (session 36, a stranger's finding 12):
``run DIR`` said ``roomba-bt: s/: a directory ...`` where ``show DIR`` said ``roomba-bt
show: ...``."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main


@pytest.mark.parametrize("command", ["run", "show", "validate", "eval"])
def test_a_directory_given_as_the_mission_is_said_by_the_command(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([command, str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt {command}: {tmp_path}" in err, err


@pytest.mark.parametrize("command", ["replay", "monitor"])
def test_a_directory_given_as_the_record_is_said_by_the_command(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if command == "monitor":
        pytest.importorskip("aiohttp")
    assert main([command, str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt {command}: {tmp_path}: not a regular file" in err, err


@pytest.mark.parametrize("command", ["run", "show", "validate", "eval"])
def test_a_parameter_without_a_value_is_said_by_the_command(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``validate m.yaml -p laps`` and ``show`` said ``roomba-bt: -p 'laps': ...`` where
    ``run`` and ``eval`` named themselves (session 42, a stranger's finding)."""
    mission = tmp_path / "m.yaml"
    mission.write_text("parameters: {laps: {type: int, default: 1}}\ntree: {wait: 1s}\n")
    assert main([command, str(mission), "-p", "laps"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt {command}: -p 'laps': expected NAME=VALUE"), err
