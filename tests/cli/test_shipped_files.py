"""The shipped missions and worlds can be read from an installed wheel: `roomba-bt missions
NAME` and `roomba-bt worlds [NAME]` print them (a newcomer found them only by opening the
package's folder: the docs say each mission is documented at its top)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission.shipped import SHIPPED_DIR, find_mission, shipped_missions
from roomba_bt.sim.world import WORLDS_DIR, parse_world, shipped_worlds


@pytest.mark.parametrize("name", sorted(shipped_missions()))
def test_a_shipped_mission_is_printed_with_its_comments(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["missions", name]) == 0
    assert capsys.readouterr().out == shipped_missions()[name].read_text(encoding="utf-8")


@pytest.mark.parametrize("path", sorted(SHIPPED_DIR.rglob("*.yaml")), ids=lambda p: p.name)
def test_what_a_shipped_file_says_an_installed_user_can_follow(
    path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``roomba-bt missions dock`` showed ``roomba-bt run missions/dock.yaml --fast``, exit 2
    in any folder but a checkout's, and sent its reader to ``docs/routines.md``, a file the
    wheel did not ship, then to "roomba-bt's repository: docs/routines.md", with no address:
    its commands name shipped missions by name, and a page of the docs by the command that
    prints it as installed, ``roomba-bt docs routines``."""
    from roomba_bt.cli.docs_cmd import pages

    monkeypatch.chdir(tmp_path)  # an empty folder, as an installed user's
    text = path.read_text(encoding="utf-8")
    for mission in re.findall(r"^#\s+roomba-bt (?:run|eval) (\S+)", text, re.M):
        assert find_mission(mission).path is not None, mission
    assert re.findall(r"docs/\S*|repository", text) == []
    assert set(re.findall(r"roomba-bt docs ([\w-]+)", text)) <= set(pages())


def test_a_library_file_is_printed_and_an_unknown_name_is_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["missions", "lib/docking"]) == 0
    assert "subtrees:" in capsys.readouterr().out
    assert main(["missions", "dok"]) == 2
    err = capsys.readouterr().err
    assert "no shipped mission or library file 'dok' (did you mean 'dock'?)" in err
    assert "lib/docking" in err


def test_worlds_lists_each_shipped_world_and_prints_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out
    for name in shipped_worlds():
        assert f"\n{name}  " in f"\n{out}"
    assert "8 x 6 m, a dock; areas: living-room, bedroom, kitchen" in out
    assert main(["worlds", "apartment"]) == 0
    text = capsys.readouterr().out
    assert text == (WORLDS_DIR / "apartment.yaml").read_text(encoding="utf-8")
    assert parse_world(text, "apartment.yaml").name == "apartment"
    assert main(["worlds", "apartmnt"]) == 2
    assert "roomba-bt worlds: no shipped world 'apartmnt' (did you mean 'apartment'?)" in (
        capsys.readouterr().err
    )


def test_worlds_cuts_a_long_description_and_list_of_areas_of_ones_own_world(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A world of one's own (``ROOMBA_BT_WORLDS``) is a stranger's file: its description of
    300,000 characters and its 1,000 areas were printed whole by ``worlds``; each is cut
    as a line shows a long text, its length said."""
    room = (WORLDS_DIR / "empty-room.yaml").read_text(encoding="utf-8")
    assert "areas:" not in room
    areas = "".join(f"  - {{name: area-{i:03}, rect: [0, 0, 1, 1]}}\n" for i in range(1000))
    text = re.sub(r"(?m)^description: .*$", f"description: {'D' * 300_000}", room)
    (tmp_path / "huge.yaml").write_text(f"{text}areas:\n{areas}")
    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(tmp_path))
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out
    assert f"\nhuge  {'D' * 500}... (300,000 characters)\n" in f"\n{out}"
    assert "areas: area-000, area-001" in out and "... (9,998 characters)" in out
    assert len(out) < 5_000, len(out)


def test_worlds_of_ones_own_come_before_the_shipped_ones(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``ROOMBA_BT_WORLDS`` replaced the shipped worlds' folder, and was documented nowhere:
    its folders now add the user's worlds, looked in before the shipped ones (one may take a
    shipped world's name), listed by ``worlds`` with their files and run by name."""
    own, more = tmp_path / "worlds", tmp_path / "more"
    for folder in (own, more):
        folder.mkdir()
    room = (WORLDS_DIR / "empty-room.yaml").read_text(encoding="utf-8")
    (own / "my-room.yaml").write_text(room.replace("name: empty-room", "name: my-room"))
    (more / "corridor.yaml").write_text(room)  # a shipped world's name: this one is taken
    monkeypatch.setenv("ROOMBA_BT_WORLDS", f"{own}{os.pathsep}{os.pathsep}{more}")
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out
    assert "\nmy-room  Empty room" in f"\n{out}" and f"your own: {own / 'my-room.yaml'}" in out
    assert f"your own: {more / 'corridor.yaml'}" in out and "apartment  " in out
    assert main(["worlds", "my-room"]) == 0
    assert "name: my-room" in capsys.readouterr().out
    assert main(["worlds", "my-rom"]) == 2
    assert "no ROOMBA_BT_WORLDS's or shipped world 'my-rom' (did you mean 'my-room'?)" in (
        capsys.readouterr().err
    )
    argv = ["run", "bump-and-turn", "--fast", "--display", "none", "-p", "duration=1s"]
    assert main([*argv, "--world", "my-room"]) == 0
    assert "robot        simulator my-room" in capsys.readouterr().out
    assert main([*argv, "--world", "corridor"]) == 0
    assert "robot        simulator empty-room" in capsys.readouterr().out
    assert main([*argv, "--world", "moon"]) == 2
    assert (
        "moon: world: found no such file or world in ROOMBA_BT_WORLDS's folders or the "
        "shipped ones; allowed: a YAML file or one of apartment, corridor, empty-room, "
        "my-room" in capsys.readouterr().err
    )


@pytest.mark.parametrize(
    ("folder", "problem"),
    [("nowhere", "no such folder"), ("a-file", "a file, not a folder")],
)
def test_a_worlds_variable_naming_no_folder_is_refused_naming_it(
    folder: str,
    problem: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A missing folder left no world at all: ``run`` said "allowed: a YAML file or one of"
    and nothing, ``worlds`` printed nothing with exit 0. Now both are usage errors (exit 2)
    naming the variable and the folder, after the command's name."""
    (tmp_path / "a-file").write_text("")
    given = str(tmp_path / folder)
    monkeypatch.setenv("ROOMBA_BT_WORLDS", given)
    said = f"ROOMBA_BT_WORLDS: {given!r}: {problem}; it names folders of your own"
    assert main(["worlds"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith(f"roomba-bt worlds: {said}")
    assert main(["run", "dock", "--fast", "--display", "none"]) == 2
    assert capsys.readouterr().err.startswith(f"roomba-bt run: {said}")
