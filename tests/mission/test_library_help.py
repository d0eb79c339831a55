"""A library's maintainer refactoring it (session 35's library report, findings 6 and 8):
a renamed subtree lists the known ones, a forgotten include names the granted file that
defines the subtree, a moved file is offered where it went, an include cycle names each
file by its path (two ``docking.yaml``), a subtree parameter that hides a mission's of
another type is a warning, and a mission parameter a library's body reads says how a
subtree gets one."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import Diagnostic, Permissions, validate_file

LIBRARY = """\
subtrees:
  drive_leg:
    parameters:
      laps: {type: distance, default: 30cm}
    tree:
      drive: {velocity: 100 mm/s, distance: "${laps}"}
  back_off:
    tree:
      drive: {velocity: -100 mm/s, distance: 5cm}
"""


@pytest.fixture
def repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``lib/nav/recovery.yaml`` (granted) and a ``missions/`` folder, the working folder
    their parent."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lib/nav").mkdir(parents=True)
    (tmp_path / "lib/nav/recovery.yaml").write_text(LIBRARY)
    (tmp_path / "missions").mkdir()
    return tmp_path


GRANTED = Permissions(include_dirs=(Path("lib"),))


def _said(repo: Path, mission: str) -> list[Diagnostic]:
    (repo / "missions/m.yaml").write_text(mission)
    return validate_file("missions/m.yaml", permissions=GRANTED).diagnostics


def _tree(include: str, use: str) -> str:
    return f"include: [{include}]\ntree:\n  sequence:\n    - mode: safe\n    - {use}\n"


def test_a_renamed_subtree_lists_the_known_ones(repo: Path) -> None:
    [error] = _said(repo, _tree("../lib/nav/recovery.yaml", "subtree: recover_bump"))
    assert error.message == "unknown subtree 'recover_bump'; known: back_off, drive_leg"


def test_a_forgotten_include_names_the_granted_file_that_defines_it(repo: Path) -> None:
    [error] = _said(repo, "tree:\n  sequence:\n    - mode: safe\n    - subtree: drive_leg\n")
    assert error.message == (
        "unknown subtree 'drive_leg' (lib/nav/recovery.yaml defines it: include it)"
    )


def test_a_moved_file_is_offered_and_the_docking_library_not_named(repo: Path) -> None:
    [error, _] = _said(repo, _tree("../lib/recovery.yaml", "subtree: drive_leg"))
    assert error.message.endswith(
        "paths are relative to the including file; moved? a file of that name is "
        "'../lib/nav/recovery.yaml')"
    )
    assert "docking" not in error.message


def test_an_include_cycle_names_each_file_by_its_path(repo: Path) -> None:
    (repo / "lib/docking.yaml").write_text("include: [nav/recovery.yaml]\nsubtrees: {}\n")
    (repo / "lib/nav/recovery.yaml").write_text("include: [../docking.yaml]\n" + LIBRARY)
    said = _said(repo, _tree("../lib/nav/recovery.yaml", "subtree: drive_leg"))
    [cycle] = [d for d in said if "include cycle" in d.message]
    assert cycle.message == (
        "include cycle: lib/nav/recovery.yaml -> lib/docking.yaml -> lib/nav/recovery.yaml"
    )


def test_a_subtree_parameter_hiding_a_mission_one_of_another_type_is_a_warning(
    repo: Path,
) -> None:
    mission = "parameters:\n  laps: {type: int, default: 2}\n" + _tree(
        "../lib/nav/recovery.yaml", 'repeat: {times: "${laps}", do: {subtree: drive_leg}}'
    )
    [warning] = _said(repo, mission)
    assert (warning.severity, warning.file, warning.line) == ("warning", "missions/m.yaml", 7)
    assert warning.message.startswith(
        "subtree 'drive_leg' has its own parameter 'laps' (distance (mm)), which hides the "
        "mission's 'laps' (int) in its body"
    )
    same_type = mission.replace("{type: int, default: 2}", "{type: distance, default: 1m}")
    assert _said(repo, same_type.replace('"${laps}"', "2")) == []


def test_a_mission_parameter_a_library_reads_says_how_a_subtree_gets_one(repo: Path) -> None:
    (repo / "lib/nav/recovery.yaml").write_text(
        LIBRARY.replace("velocity: 100 mm/s", 'velocity: "${cruise}"')
    )
    [error] = validate_file("lib/nav/recovery.yaml").diagnostics
    assert "unknown parameter ${cruise} (a subtree's body sees its own parameters" in error.message
    assert "declare cruise in the subtree's parameters, and let each use give it" in (error.message)
