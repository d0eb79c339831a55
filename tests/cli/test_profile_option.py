"""``--profile`` is one option on every command that takes it: its choices, its default
(the environment's, the project's, else create2) and what it changes, in the help (run,
validate, sensors and eval had no help text, and sim took free text). ``run``'s summary
and ``eval``'s text summary name the profile when it is not the default, and read as before
when it is."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main

COMMANDS = ["run", "validate", "show", "sensors", "eval", "sim"]
MISSION = "mission: sit\ntree:\n  wait: 0.1s\n"


@pytest.mark.parametrize("command", COMMANDS)
def test_every_profile_option_says_its_choices_default_and_effect(
    command: str, help_text: Callable[[str], str]
) -> None:
    text = help_text(command)
    # auto where the command connects to a robot and can identify it (a port's run, sensors)
    choices = "create2,roomba500,roomba600" + (",auto" if command in ("run", "sensors") else "")
    assert f"--profile {{{choices}}}" in text
    assert "Default: ROOMBA_BT_PROFILE, else profile under [tool.roomba-bt]" in text
    assert "create2 (iRobot Create 2; the default), roomba600 (Roomba 600 series), " \
        "roomba500 (Roomba 500 series)" in text  # fmt: skip
    assert "stream checksum" in text and "packet 35" in text and "Stop 173" in text


def test_sim_refuses_a_profile_it_does_not_know(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["sim", "--pty", "--profile", "roomba700"])
    assert exit_.value.code == 2
    assert "argument --profile" in capsys.readouterr().err


def test_the_run_summary_names_a_profile_other_than_the_default(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    assert main(["run", str(mission), "--fast", "--display", "none", "--profile", "roomba500"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == ["mission      sit", "profile      roomba500 (Roomba 500 series)"]
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == ["mission      sit", "robot        simulator empty-room"]  # no profile
    assert lines[2].startswith("started ") and lines[3].startswith("outcome ")


def test_the_eval_summary_names_a_profile_other_than_the_default(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    base = ["eval", str(mission), "--runs", "1", "--jobs", "1", "--no-progress"]
    assert main([*base, "--profile", "roomba600"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1] == "profile      roomba600 (Roomba 600 series)", lines
    assert main(base) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].startswith("success "), lines
