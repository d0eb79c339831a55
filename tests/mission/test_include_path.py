"""Include folders granted once for every command (``ROOMBA_BT_INCLUDE_PATH``, a project
file's ``[tool.roomba-bt] include-dirs``), the trust rules a project file is held to, and
what a refused include says: where a file may be read from, the fix, and the errors that
follow from it named as such (docs/missions.md, Include folders)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main
from roomba_bt.mission import Permissions, compile_mission

if TYPE_CHECKING:
    from roomba_bt.mission.include_path import IncludeGrant

Capsys = pytest.CaptureFixture[str]

INCLUDE_PATH_VARIABLE = "ROOMBA_BT_INCLUDE_PATH"


def configured_include_dirs(mission: str | Path) -> IncludeGrant:
    """The module's own, imported here: each test fails alone on a roomba-bt without it."""
    from roomba_bt.mission.include_path import configured_include_dirs as configured

    return configured(mission)


LIBRARY = """\
include: [roomba-bt:lib/undock.yaml]
blackboard: {legs: int}
subtrees:
  leg:
    parameters: {length: {type: distance}}
    tree: {drive: {velocity: 200 mm/s, distance: "${length}"}}
"""

#: a mission in a sibling folder of the team library, as the team's repository has them
MISSION = """\
mission: to-kitchen
include: [roomba-bt:lib/docking.yaml, ../common/lib/safe_drive.yaml]
tree:
  sequence:
    - subtree: {id: undock}
    - mode: safe
    - subtree: {id: leg, length: 50 cm}
    - set: {key: legs, value: 1}
    - mode: passive
"""


@pytest.fixture
def repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``missions/delivery/to-kitchen.yaml`` including ``missions/common/lib/safe_drive.yaml``,
    run from the repository's top, as CI runs it."""
    (tmp_path / "missions" / "common" / "lib").mkdir(parents=True)
    (tmp_path / "missions" / "delivery").mkdir()
    (tmp_path / "missions" / "common" / "lib" / "safe_drive.yaml").write_text(LIBRARY)
    (tmp_path / "missions" / "delivery" / "to-kitchen.yaml").write_text(MISSION)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def project(repo: Path, text: str) -> Path:
    path = repo / "pyproject.toml"
    path.write_text(text)
    return path


MISSION_PATH = "missions/delivery/to-kitchen.yaml"
COMMANDS = {
    "validate": ["validate", MISSION_PATH],
    "show": ["show", MISSION_PATH],
    "run": ["run", MISSION_PATH, "--fast", "--display", "none", "--timeout", "2min"],
    "eval": ["eval", MISSION_PATH, "--runs", "1", "--no-progress", "--timeout", "2min"],
}


@pytest.mark.parametrize("command", COMMANDS, ids=str)
def test_a_project_file_grants_its_include_folders_to_every_command(
    repo: Path, command: str, capsys: Capsys
) -> None:
    """``--include-dir missions/common`` was needed on every validate, show, run and eval
    (replay too: below); the project file says it once."""
    assert main(COMMANDS[command]) == 2
    assert "is outside the mission's folder" in "".join(capsys.readouterr())
    project(repo, '[tool.roomba-bt]\ninclude-dirs = ["missions/common"]\n')
    assert main(COMMANDS[command]) == 0, capsys.readouterr()
    assert "warning" not in capsys.readouterr().err


def test_replay_reads_it_too(repo: Path, capsys: Capsys) -> None:
    project(repo, '[tool.roomba-bt]\ninclude-dirs = ["missions/common"]\n')
    record = repo / "run.jsonl"
    argv = [*COMMANDS["run"], "--record", str(record)]
    assert main(argv) == 0
    assert main(["replay", str(record)]) == 0
    (repo / "pyproject.toml").unlink()  # the record holds the folder its run was granted
    assert main(["replay", str(record)]) == 0
    header = json.loads(record.read_text().splitlines()[0])
    header["options"]["include_dirs"] = []
    record.write_text("\n".join([json.dumps(header), *record.read_text().splitlines()[1:]]))
    assert main(["replay", str(record)]) == 2
    assert "is outside the mission's folder" in "".join(capsys.readouterr())


def test_the_environment_variable_grants_like_include_dir(
    repo: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``os.pathsep``-separated as ``PYTHONPATH`` is, relative to the current directory; an
    entry that is no folder is a warning, the others still granted."""
    assert main(["validate", MISSION_PATH]) == 2
    monkeypatch.setenv(INCLUDE_PATH_VARIABLE, os.pathsep.join(["nowhere", "missions/common", ""]))
    assert main(["validate", MISSION_PATH]) == 0
    err = capsys.readouterr().err
    assert f"roomba-bt: warning: {INCLUDE_PATH_VARIABLE}: 'nowhere' is no folder" in err


def test_a_project_file_grants_nothing_outside_its_own_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """A project file may have come with the mission (an emailed folder): it widens the
    mission's reach only to what came with it. ``..``, an absolute path elsewhere and a
    symbolic link out of its folder are not granted, each said as a warning."""
    secret = tmp_path / "home" / "secret"
    secret.mkdir(parents=True)
    (secret / "lib.yaml").write_text("subtrees: {pause: {tree: {wait: 1s}}}\n")
    mail = tmp_path / "mail"
    (mail / "missions").mkdir(parents=True)
    (mail / "link").symlink_to(secret)
    (mail / "pyproject.toml").write_text(
        f'[tool.roomba-bt]\ninclude-dirs = ["..", "{secret}", "link", "missions"]\n'
    )
    mission = mail / "missions" / "m.yaml"
    mission.write_text("include: [../../home/secret/lib.yaml]\ntree: {subtree: pause}\n")
    grant = configured_include_dirs(mission)
    assert grant.folders == ((mail / "missions").resolve(),)
    assert len(grant.warnings) == 3
    assert all("is outside this file's folder" in w for w in grant.warnings)
    monkeypatch.chdir(tmp_path)
    assert main(["validate", str(mission)]) == 2
    out, err = capsys.readouterr()
    assert "include '../../home/secret/lib.yaml' is outside the mission's folder" in out
    assert err.count("is outside this file's folder") == 3
    assert_quoted("docs/missions.md", "roomba-bt: warning: .../pyproject.toml:", err)


def test_a_project_file_of_another_user_is_not_read(
    repo: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """As git reads a repository's configuration: a ``/tmp/pyproject.toml`` another user
    left above a mission grants nothing."""
    path = project(repo, '[tool.roomba-bt]\ninclude-dirs = ["missions/common"]\n')
    if os.geteuid() == 0:
        os.chown(path, 4242, 4242)
    else:  # not root: the file is this user's, so "this user" is made another one
        monkeypatch.setattr(os, "getuid", lambda: path.stat().st_uid + 1)
    assert configured_include_dirs(MISSION_PATH).folders == ()
    assert main(["validate", MISSION_PATH]) == 2
    assert "not read, owned by another user" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ('[tool.roomba-bt]\ninclude-dirs = "missions/common"\n', "a list of folders is expected"),
        ('[tool.roomba-bt]\ninclude_dirs = ["missions/common"]\n', "unknown key 'include_dirs'"),
        ("[tool.roomba-bt\n", "not valid TOML"),
        ('[tool.roomba-bt]\ninclude-dirs = ["missions/common/lib/safe_drive.yaml"]\n',
         "is a file, not a folder: give its folder"),
    ],
    ids=["not-a-list", "misspelt", "not-toml", "a-file"],
)  # fmt: skip
def test_a_project_file_that_grants_nothing_says_why(
    repo: Path, text: str, said: str, capsys: Capsys
) -> None:
    project(repo, text)
    assert main(["validate", MISSION_PATH]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt: warning: {repo / 'pyproject.toml'}"), err
    assert said in err


def test_a_pyproject_without_the_table_is_passed_over(repo: Path) -> None:
    """A plugin package's own ``pyproject.toml`` between the mission and the project's."""
    project(repo, '[tool.roomba-bt]\ninclude-dirs = ["missions/common"]\n')
    (repo / "missions" / "delivery" / "pyproject.toml").write_text('[project]\nname = "x"\n')
    assert configured_include_dirs(MISSION_PATH).folders == (
        (repo / "missions" / "common").resolve(),
    )


def test_the_refusal_says_where_it_looked_and_the_fix(repo: Path, capsys: Capsys) -> None:
    assert main(["validate", MISSION_PATH, "--include-dir", "missions/delivery"]) == 2
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (
        f"{MISSION_PATH}:2:39: include '../common/lib/safe_drive.yaml' is outside the mission's "
        "folder (missions/delivery), the shipped library and the include folders granted "
        "(missions/delivery); allow its folder with --include-dir missions/common/lib, or for "
        f"every command with {INCLUDE_PATH_VARIABLE} or include-dirs under [tool.roomba-bt] in "
        "a pyproject.toml (roomba-bt run --help, --include-dir) [include[1]]"
    )


def test_what_follows_from_a_refused_include_says_so(repo: Path, capsys: Capsys) -> None:
    """``undock`` came through the refused library: "did you mean 'dock'?" (the docking
    library is included) and "the shipped roomba-bt:lib/undock.yaml defines it" sent the
    user the wrong way; so did a did-you-mean for its blackboard key."""
    assert main(["validate", MISSION_PATH]) == 2
    out = capsys.readouterr().out
    lines = out.splitlines()
    follows = "(the include of '../common/lib/safe_drive.yaml' at line 2 failed, and may have"
    assert lines[1].startswith(f"{MISSION_PATH}:5:21: unknown subtree 'undock' {follows}")
    assert lines[2].startswith(f"{MISSION_PATH}:7:21: unknown subtree 'leg' {follows}")
    assert f"unknown blackboard key 'legs' {follows}" in lines[3]
    assert lines[4:] == [f"{MISSION_PATH}: failed (4 errors)"]  # the file's verdict
    assert "did you mean" not in out and "defines it" not in out


def test_an_include_not_found_says_where_it_looked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "lib").mkdir()
    (tmp_path / "missions").mkdir()
    path = tmp_path / "missions" / "m.yaml"
    path.write_text("include: [../lib/nowhere.yaml]\ntree: {wait: 1s}\n")
    monkeypatch.chdir(tmp_path)
    granted = Permissions(include_dirs=(tmp_path / "lib",))
    _, diagnostics = compile_mission(path, permissions=granted)
    assert diagnostics[0].message == (
        "included file '../lib/nowhere.yaml' not found (looked for lib/nowhere.yaml: paths "
        "are relative to the including file)"
    )


def test_include_dir_naming_a_file_says_so(repo: Path, capsys: Capsys) -> None:
    with pytest.raises(SystemExit):
        main(["validate", MISSION_PATH, "--include-dir", "missions/common/lib/safe_drive.yaml"])
    assert (
        "found 'missions/common/lib/safe_drive.yaml': a file, not a folder; give the folder "
        "that holds it (--include-dir missions/common/lib)"
    ) in capsys.readouterr().err


def test_include_dir_naming_a_pipe_or_a_broken_link_says_what_it_is(
    tmp_path: Path, capsys: Capsys
) -> None:
    """A named pipe given as ``--include-dir`` was "there is no such directory": it is there."""
    fifo, link = tmp_path / "lib", tmp_path / "gone"
    os.mkfifo(fifo)
    link.symlink_to(tmp_path / "nowhere")
    for given, said in [
        (fifo, "a named pipe (FIFO), not a folder"),
        (
            link,
            f"a broken symbolic link (to {str(tmp_path / 'nowhere')!r}, which does not "
            "exist), not a folder",
        ),
        (tmp_path / "none", "there is no such directory"),
    ]:
        with pytest.raises(SystemExit):
            main(["validate", MISSION_PATH, "--include-dir", str(given)])
        assert f"found {str(given)!r}: {said}" in capsys.readouterr().err
