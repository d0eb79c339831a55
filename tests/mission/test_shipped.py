"""Shipped missions by name, the shipped library's include name, ``roomba-bt missions``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import compile_mission
from roomba_bt.mission.shipped import (
    DOCKING_LIBRARY,
    SHIPPED_DIR,
    describe_shipped,
    find_mission,
    shipped_file,
    shipped_missions,
)

ROOT = Path(__file__).resolve().parents[2]
FIVE = {"dock", "dock-builtin", "patrol", "bump-and-turn", "wall-follow"}
Capsys = pytest.CaptureFixture[str]


def test_the_shipped_missions_are_package_data() -> None:
    assert SHIPPED_DIR == ROOT / "roomba_bt" / "missions"
    assert set(shipped_missions()) >= FIVE
    assert shipped_file(DOCKING_LIBRARY) == SHIPPED_DIR / "lib" / "docking.yaml"
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert '"missions/*.yaml", "missions/lib/*.yaml"' in pyproject


def test_the_repository_paths_link_to_the_one_copy() -> None:
    """``missions/dock.yaml`` (docs, tests, the Makefile's history) is a link, not a copy.
    An sdist (the tree with a ``PKG-INFO``, where packagers run the tests) holds no links:
    setuptools writes each as a copy of the file it names, so there the bytes are the same."""
    from_sdist = (ROOT / "PKG-INFO").is_file()
    for name in shipped_missions():
        link, shipped = ROOT / "missions" / f"{name}.yaml", SHIPPED_DIR / f"{name}.yaml"
        if from_sdist:
            assert link.read_bytes() == shipped.read_bytes(), link
        else:
            assert link.is_symlink() and link.resolve() == shipped
    library = sorted(p.name for p in (SHIPPED_DIR / "lib").iterdir())
    assert sorted(p.name for p in (ROOT / "missions" / "lib").iterdir()) == library
    if not from_sdist:
        assert (ROOT / "missions" / "lib").resolve() == SHIPPED_DIR / "lib"


def test_a_name_finds_the_shipped_mission_and_a_file_wins(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert find_mission("dock").path == SHIPPED_DIR / "dock.yaml"
    assert find_mission("dock.yaml").path == SHIPPED_DIR / "dock.yaml"
    assert find_mission("roomba-bt:patrol.yaml").path == SHIPPED_DIR / "patrol.yaml"
    (tmp_path / "dock.yaml").write_text("tree: wall\n")
    assert find_mission("dock.yaml").path == Path("dock.yaml")
    missing = find_mission("dok")
    assert missing.path is None
    assert missing.problem.startswith("dok: no such mission file, and no shipped mission")
    assert "dock-builtin" in missing.problem
    assert missing.problem.endswith("(did you mean 'dock'?)")
    assert find_mission("sub/dock").path is None, "a path is never taken for a name"
    # a checkout's path from the README, in a folder without it (a pip user's)
    from_docs = find_mission("missions/dock.yaml")
    assert from_docs.path is None and from_docs.problem is not None
    assert from_docs.problem.endswith("; the shipped mission 'dock' is named alone: dock")


def test_a_directory_or_a_device_is_named_as_such(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "missions").mkdir()
    assert find_mission("missions").problem == (
        "missions: a directory, not a mission file (a .yaml file)"
    )
    assert find_mission("/dev/null").problem == (
        "/dev/null: not a regular file; a mission is a .yaml file"
    )
    (tmp_path / "dock").mkdir()
    assert find_mission("dock").path == SHIPPED_DIR / "dock.yaml", "a name still finds it"


def test_a_shipped_name_cannot_climb_out_of_the_package() -> None:
    assert shipped_file("roomba-bt:../mission/shipped.py") is None
    assert shipped_file("roomba-bt:lib/nope.yaml") is None
    assert shipped_file("lib/docking.yaml") is None


def test_a_users_mission_includes_the_shipped_library_by_name(
    mission_file: Callable[..., Path],
) -> None:
    path = mission_file(
        """
        include: [roomba-bt:lib/docking.yaml]
        tree:
          subtree: {id: dock, time_limit: 2min}
        """,
        "far/away/mine.yaml",
    )
    mission, diagnostics = compile_mission(path)
    assert diagnostics == []
    assert mission is not None and 34 in mission.packets


def test_an_unknown_library_name_says_what_the_library_holds(
    mission_file: Callable[..., Path],
) -> None:
    path = mission_file("include: [roomba-bt:lib/dockin.yaml]\ntree: wall\n")
    _, diagnostics = compile_mission(path)
    assert [d.message for d in diagnostics] == [
        "included file 'roomba-bt:lib/dockin.yaml' is not in the shipped library; "
        "it holds roomba-bt:lib/docking.yaml, roomba-bt:lib/undock.yaml"
    ]


def test_another_package_s_file_is_refused_saying_only_the_shipped_library_is_named_so(
    mission_file: Callable[..., Path],
) -> None:
    """Session 35's library report (finding 10): ``makerspace-bt:lib/x.yaml`` was looked for
    as a file of that name in the mission's folder, "not found", and the docs disagreed on
    whether a package could provide one."""
    path = mission_file("include: [makerspace-bt:lib/x.yaml]\ntree: wall\n")
    _, diagnostics = compile_mission(path)
    assert [f"{d.line}:{d.column}: {d.message}" for d in diagnostics] == [
        "1:11: included file 'makerspace-bt:lib/x.yaml' names a file of package "
        "'makerspace-bt': only the shipped library is included by a package's name "
        "(roomba-bt:PATH, such as roomba-bt:lib/docking.yaml); a plugin package provides "
        "behaviours, not included files: put the library in the mission's folder, or allow the "
        "FOLDER that holds it with permissions=Permissions(include_dirs=(Path('FOLDER'),)) and "
        "include it by its path"
    ]


def test_a_file_whose_name_has_a_colon_is_still_included(
    mission_file: Callable[..., Path],
) -> None:
    mission_file("subtrees: {hello: {tree: {log: hi}}}\n", "my:lib.yaml")
    path = mission_file("include: [my:lib.yaml]\ntree: {subtree: {id: hello}}\n")
    mission, diagnostics = compile_mission(path)
    assert diagnostics == [] and mission is not None


def test_a_missing_relative_include_names_the_library(mission_file: Callable[..., Path]) -> None:
    path = mission_file("include: [lib/docking.yaml]\ntree: wall\n")
    _, diagnostics = compile_mission(path)
    assert "the shipped docking library is roomba-bt:lib/docking.yaml" in diagnostics[0].message


def test_missions_lists_each_with_description_and_parameters(capsys: Capsys) -> None:
    assert main(["missions"]) == 0
    out = capsys.readouterr().out
    for name in FIVE:
        assert f"\n{name}  " in f"\n{out}"
    assert "dock  Dock on the home base from its beams within 10min; succeed when charging." in out
    assert "    laps: int, default 2" in out
    assert "    time_limit: duration, default 10min  give up after this long" in out
    assert (
        "\nlibrary (include by name): roomba-bt:lib/docking.yaml, roomba-bt:lib/undock.yaml\n"
        in out
    )
    # then each library file's subtrees, with their doc: and parameters
    library = out.split("library (include by name): ", 1)[1]
    assert "\nroomba-bt:lib/docking.yaml\n    dock  Dock from the beams (no Seek Dock)" in library
    assert "\n        time_limit: duration, default 10min  give up after this long\n" in library
    assert "\nroomba-bt:lib/undock.yaml\n    undock  On a powered dock:" in library


def test_describe_shipped_matches_the_compiled_missions() -> None:
    for entry in describe_shipped():
        mission, diagnostics = compile_mission(entry.path)
        assert mission is not None, diagnostics
        assert entry.description == mission.description
        assert [p.name for p in entry.parameters] == list(mission.parameters)
        # each default as show says it, as written: clean's go_home was listed "True"
        assert {p.name: p.default for p in entry.parameters} == mission.parameters_shown


def test_validate_and_show_take_names(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "dock", "dock-builtin", "bump-and-turn"]) == 0
    assert capsys.readouterr().out.count(": ok") == 3
    assert main(["show", "dock-builtin"]) == 0
    assert capsys.readouterr().out.startswith("dock-builtin: Seek Dock (143)")
    assert main(["validate", "nothing-like-it"]) == 2
    assert "nothing-like-it: no such mission file" in capsys.readouterr().err


def test_run_takes_a_name(capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["run", "dock-builtin", "--fast", "--display", "none"]) == 0
    assert main(["run", "dok", "--fast"]) == 2
    assert "dok: no such mission file, and no shipped mission" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["dock", "dock.yaml", "roomba-bt:dock.yaml"])
def test_load_mission_takes_a_shipped_name_as_the_cli_does(name: str) -> None:
    """From Python as ``roomba-bt run dock``: it was "cannot read mission file: No such file
    or directory" (the one way in was ``shipped_missions()["dock"]``)."""
    from roomba_bt.mission import load_mission

    assert load_mission(name).name == "dock"


def test_load_mission_reads_a_file_before_a_shipped_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from roomba_bt.mission import load_mission

    monkeypatch.chdir(tmp_path)
    (tmp_path / "dock").write_text("mission: mine\ntree:\n  sequence:\n    - mode: safe\n")
    assert load_mission("dock").name == "mine"


def test_the_listing_reads_a_description_s_escape_as_a_mission_does() -> None:
    """``roomba-bt missions`` had its own ``${name}`` pattern: ``$${`` stayed doubled and a
    ``$${speed}`` took the default, though a mission reads it as the text ``${speed}``."""
    from roomba_bt.mission.shipped import ShippedParameter, _with_defaults

    speed = ShippedParameter("speed", "speed", "200 mm/s", "")
    assert _with_defaults("at ${speed}, not $${speed}; ${other}", (speed,)) == (
        "at 200 mm/s, not ${speed}; ${other}"
    )


def test_a_patrol_that_docks_on_a_low_battery_says_so_under_its_success(capsys: Capsys) -> None:
    """At 3 % the patrol docks at once, no lap done: a success as its file says, which the
    owner read in the evening as a patrol done (a Pi owner's report). Its own words, the
    summary's ``mission said``, tell which way it ended."""
    argv = ["run", "patrol", "--battery", "3%", "--fast", "--display", "none"]
    assert main([*argv, "--profile", "roomba600"]) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS\nmission said the battery is below 15%: the patrol ended " in out
    assert "before its 2 laps were done; docking" in out


def test_a_shipped_file_is_named_by_its_shipped_name_from_a_folder_above_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A user whose venv lies under the folder they work in (``~/roomba/venv``, run from
    ``~``) was told ``roomba/venv/lib/python3.11/site-packages/roomba_bt/missions/
    patrol.yaml:134:17: wait(10min) may run in Passive ...``: the path from the working
    folder came before the shipped name, which docs/unattended.md quotes
    (``roomba-bt:patrol.yaml:134:17``)."""
    from roomba_bt.mission import load_mission

    monkeypatch.chdir(SHIPPED_DIR.parent.parent)
    (said,) = load_mission("patrol", {"charge_for": "10min"}).waits_past_sleep
    assert said.startswith("roomba-bt:patrol.yaml:"), said
