"""The robot's model named once (``roomba_bt/cli/profile_choice.py``): ``--profile``, then
``ROOMBA_BT_PROFILE``, then ``profile`` under ``[tool.roomba-bt]`` in the project file, then
create2; where it came from said in the summary; a bad value a usage error naming the
variable or the file and line, and the names allowed. ``auto`` identifies the robot on
``--port`` (test_profile_auto.py); elsewhere it is the default, said."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.cli.profile_choice import (
    DEFAULT_SOURCE,
    PROFILE_VARIABLE,
    BadSetting,
    ProfileChoice,
    choose_profile,
)
from roomba_bt.mission.include_path import configured_include_dirs
from roomba_bt.project import key_line

MISSION = "mission: sit\ntree:\n  wait: 0.1s\n"
#: the names a setting may hold, as every message says them
ALLOWED = "allowed: create2, roomba600, roomba500, auto (roomba-bt run --help, --profile)"

Capsys = pytest.CaptureFixture[str]


def project(folder: Path, profile: str, *, before: str = "") -> Path:
    """A project at ``folder``: its ``pyproject.toml`` naming ``profile`` (on line 4 when
    nothing comes ``before``), and a mission file in its ``missions`` folder (returned)."""
    (folder / "missions").mkdir(parents=True)
    (folder / "pyproject.toml").write_text(
        f'[project]\nname = "robots"\n{before}[tool.roomba-bt]\nprofile = {profile}\n'
    )
    mission = folder / "missions" / "sit.yaml"
    mission.write_text(MISSION)
    return mission


def run(mission: Path | str, *extra: str) -> int:
    return main(["run", str(mission), "--fast", "--display", "none", *extra])


def summary_profile(capsys: Capsys) -> str:
    """The summary's profile line ("" when it has none: the default, from nowhere)."""
    lines = capsys.readouterr().out.splitlines()
    return next((line.split(None, 1)[1] for line in lines if line.startswith("profile ")), "")


def test_the_flag_then_the_environment_then_the_project_then_create2(tmp_path: Path) -> None:
    mission = project(tmp_path / "robots", '"roomba600"')
    env = {PROFILE_VARIABLE: "roomba500"}
    assert choose_profile("create2", mission, environ=env) == ProfileChoice("create2", "--profile")
    assert choose_profile(None, mission, environ=env) == ProfileChoice(
        "roomba500", PROFILE_VARIABLE
    )
    from_file = ProfileChoice("roomba600", f"{tmp_path / 'robots' / 'pyproject.toml'}:4")
    assert choose_profile(None, mission, environ={PROFILE_VARIABLE: " "}) == from_file
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    assert choose_profile(None, elsewhere / "m.yaml", environ={}) == ProfileChoice(
        "create2", DEFAULT_SOURCE
    )


def test_the_environment_names_the_profile_of_a_run_and_the_summary_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    monkeypatch.setenv(PROFILE_VARIABLE, "Roomba500")  # as typed: case does not matter
    assert run(mission) == 0
    assert summary_profile(capsys) == "roomba500 (Roomba 500 series), from ROOMBA_BT_PROFILE"
    assert run(mission, "--profile", "roomba600") == 0  # the flag wins, said as before
    assert summary_profile(capsys) == "roomba600 (Roomba 600 series)"


def test_the_project_file_above_the_mission_names_it_with_its_file_and_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    mission = project(tmp_path, '"roomba500"')
    monkeypatch.chdir(tmp_path.parent)  # the mission's project, not the current directory's
    assert run(mission) == 0
    said = f"roomba500 (Roomba 500 series), from {tmp_path / 'pyproject.toml'}:4"
    assert summary_profile(capsys) == said
    monkeypatch.setenv(PROFILE_VARIABLE, "create2")  # the environment before the project
    assert run(mission) == 0
    assert summary_profile(capsys) == "create2 (iRobot Create 2), from ROOMBA_BT_PROFILE"


def test_a_shipped_mission_named_by_name_takes_the_current_directorys_project(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    project(tmp_path, '"roomba600"')
    monkeypatch.chdir(tmp_path / "missions")
    assert run("bump-and-turn", "-p", "duration=1s") == 0
    assert summary_profile(capsys).startswith("roomba600 (Roomba 600 series), from ")


#: a test true only on a Roomba 500, whose wall signal reads up to 4095 (the others' 1023):
#: a warning, which --strict fails (exit 7), on any other profile
WALL_500 = "mission: wall\ntree:\n  sensor: wall_signal > 1500\n"


def test_the_project_profile_reaches_validate_and_eval(tmp_path: Path, capsys: Capsys) -> None:
    mission = project(tmp_path, '"roomba500"')
    mission.write_text(WALL_500)
    assert main(["validate", "--strict", str(mission)]) == 0
    assert main(["validate", "--strict", str(mission), "--profile", "create2"]) == 7
    assert "can never be true on the iRobot Create 2" in capsys.readouterr().out
    mission.write_text(MISSION)
    assert main(["eval", str(mission), "--runs", "1", "--jobs", "1", "--no-progress"]) == 0
    assert "profile      roomba500 (Roomba 500 series), from " in capsys.readouterr().out


@pytest.mark.parametrize(
    "command",
    [["run", "sit.yaml", "--fast"], ["validate", "sit.yaml"], ["sensors", "--count", "1"],
     ["sim", "--pty"], ["eval", "sit.yaml", "--runs", "1"]],
    ids=lambda words: words[0],
)  # fmt: skip
def test_a_bad_environment_value_is_a_usage_error_naming_it_and_the_names_allowed(
    command: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sit.yaml").write_text(MISSION)
    monkeypatch.setenv(PROFILE_VARIABLE, "roomba560")
    assert main(command) == 2
    err = capsys.readouterr().err
    assert f"{PROFILE_VARIABLE}='roomba560': no robot profile of that name; {ALLOWED}" in err


@pytest.mark.parametrize("value", ['"roomba5"', "500", '["roomba500"]'])
def test_a_bad_project_value_is_an_error_at_its_file_and_line(
    value: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    mission = project(tmp_path, value, before="# robots\n")
    where = f"{tmp_path / 'pyproject.toml'}:5"
    assert run(mission) == 2
    assert f"{where}: [tool.roomba-bt] profile = " in capsys.readouterr().err
    # validate: a diagnostic at its line and column, in every --format
    assert main(["validate", str(mission)]) == 2
    out = capsys.readouterr().out
    assert f"{where}:1: [tool.roomba-bt] profile = " in out and ALLOWED in out
    assert main(["show", str(mission)]) == 2
    assert where in capsys.readouterr().err
    monkeypatch.chdir(tmp_path)
    assert main(["sim", "--pty"]) == 2
    assert where in capsys.readouterr().err


def test_a_project_file_of_another_user_names_no_profile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """As its include folders: a ``pyproject.toml`` someone else left above a mission is
    not read (said as a warning), and the default is taken."""
    mission = project(tmp_path, '"roomba500"')
    path = tmp_path / "pyproject.toml"
    if os.geteuid() == 0:
        os.chown(path, 4242, 4242)
    else:
        monkeypatch.setattr(os, "getuid", lambda: path.stat().st_uid + 1)
    assert run(mission) == 0
    captured = capsys.readouterr()
    assert "profile " not in captured.out  # the default: create2, no line
    assert captured.err.count("not read, owned by another user") == 1  # said once, not twice
    monkeypatch.chdir(tmp_path)  # sensors reads no mission: the current directory's project
    assert main(["sensors", "--count", "1"]) == 0
    captured = capsys.readouterr()
    assert "(iRobot Create 2)" in captured.out.splitlines()[0]


@pytest.mark.parametrize(
    ("command", "whom"),
    [("validate", "validate talks to no robot"), ("run", "the simulator simulates")],
)
def test_auto_where_no_robot_is_identified_is_the_default_said(
    command: str, whom: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``ROOMBA_BT_PROFILE=auto``, set in a shell for its runs on a port: ``validate`` and
    a run on the simulator have no robot to identify, and take create2, saying so."""
    mission = tmp_path / "wall.yaml"
    mission.write_text(WALL_500)
    monkeypatch.setenv(PROFILE_VARIABLE, "auto")
    words = [command, "--strict", str(mission), *(["--fast"] if command == "run" else [])]
    assert main(words) == 7  # checked for the Create 2: the test can never be true
    said = (
        f"roomba-bt {command}: ROOMBA_BT_PROFILE=auto identifies a robot on --port; {whom}: "
        "the iRobot Create 2 (create2), the default"
    )
    assert said in capsys.readouterr().err


def test_the_flag_auto_is_for_the_commands_that_connect(capsys: Capsys) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["validate", "sit.yaml", "--profile", "auto"])
    assert exit_.value.code == 2
    assert "argument --profile: invalid choice: 'auto'" in capsys.readouterr().err


def test_the_include_folders_reading_knows_the_profile_key(tmp_path: Path) -> None:
    """The same table: ``profile`` beside ``include-dirs`` is no unknown key to warn of."""
    mission = project(tmp_path, '"roomba500"')
    assert configured_include_dirs(mission, environ={}).warnings == ()


def test_missions_of_projects_naming_different_robots_are_not_evaluated_together(
    tmp_path: Path, capsys: Capsys
) -> None:
    first = project(tmp_path / "a", '"roomba500"')
    second = project(tmp_path / "b", '"roomba600"')
    assert main(["eval", str(first), str(second), "--runs", "1", "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert "the missions' projects name different robots (roomba500 (" in err
    assert "give --profile NAME" in err


def test_the_key_line_is_found_in_its_table_only(tmp_path: Path) -> None:
    path = tmp_path / "pyproject.toml"
    path.write_text(
        '[tool.other]\nprofile = "x"\n\n[tool."roomba-bt"]  # ours\n'
        'include-dirs = []\n  profile="roomba500"\n'
    )
    assert key_line(path, "profile") == 6
    assert key_line(path, "include-dirs") == 5
    assert key_line(path, "missing") == 0


def test_a_bad_setting_says_its_place(tmp_path: Path) -> None:
    assert str(BadSetting("bad", "p.toml", 3)) == "p.toml:3: bad"
    assert str(BadSetting("bad")) == "bad"


def test_the_library_reads_no_setting_and_configured_profile_reads_them_when_asked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``Connection`` and ``load_mission`` take their ``profile=`` (create2 by default) and
    never the environment or the project file, which are the command line's; a program asks
    for the command line's choice with ``configured_profile`` (docs/robot.md, Which robot)."""
    import roomba_bt
    from roomba_bt.transport.testing import NullTransport

    mission = project(tmp_path / "robots", '"roomba500"')
    mission.write_text(WALL_500)  # a warning on any model but the 500: what it was made for
    monkeypatch.chdir(tmp_path / "robots")
    assert roomba_bt.load_mission(mission).warnings, "compiled for create2, not the project's"
    assert roomba_bt.Connection(NullTransport()).profile is roomba_bt.CREATE2
    assert roomba_bt.configured_profile(mission) == "roomba500"  # the project file
    assert roomba_bt.configured_profile() == "roomba500"  # above the current folder
    given = roomba_bt.get_profile(roomba_bt.configured_profile(mission))
    assert not roomba_bt.load_mission(mission, profile=given).warnings
    monkeypatch.setenv(PROFILE_VARIABLE, "roomba600")  # the environment before the project
    assert roomba_bt.Connection(NullTransport()).profile is roomba_bt.CREATE2
    assert roomba_bt.configured_profile(mission) == "roomba600"
    monkeypatch.setenv(PROFILE_VARIABLE, "roomba560")
    with pytest.raises(ValueError, match=r"ROOMBA_BT_PROFILE='roomba560': no robot profile"):
        roomba_bt.configured_profile(mission)
