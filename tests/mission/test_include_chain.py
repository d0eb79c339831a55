"""A diagnostic in an included file names the include chain that reached it.

A team repository (docs/ci.md) keeps a library in ``missions/common/lib/``; missions in
sibling folders include it. An error in the library was reported under the library's name
alone, once per mission, and nothing said which mission had failed; ``Diagnostic`` had no
field a wrapper could read it from either.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from team_repo import ESCAPES, team_repo  # beside this file

from roomba_bt.mission import (
    Diagnostic,
    IncludeSite,
    MissionError,
    Permissions,
    load_mission,
    validate_files,
)


@pytest.fixture
def repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return team_repo(tmp_path)


SHARED = Permissions(include_dirs=(Path("missions/common"),))


def test_an_error_in_a_library_names_the_include_chain_that_reached_it(repo: Path) -> None:
    [through_two] = validate_files(["missions/delivery/to-kitchen.yaml"], permissions=SHARED)
    assert (through_two.file, through_two.line, through_two.column) == (
        "missions/common/lib/escapes.yaml", 7, 50,
    )  # fmt: skip
    assert through_two.included_from == (
        IncludeSite("missions/common/lib/safe_drive.yaml", 2, 11),
        IncludeSite("missions/delivery/to-kitchen.yaml", 2, 11),
    )
    assert through_two.checked_file == "missions/delivery/to-kitchen.yaml"
    assert str(through_two).endswith(
        "[subtrees.back_off.tree.sequence[1].drive.distance] (included from "
        "missions/common/lib/safe_drive.yaml:2:11, from missions/delivery/to-kitchen.yaml:2:11)"
    )


def test_each_mission_through_the_library_gets_its_own_chain_and_the_library_none(
    repo: Path,
) -> None:
    files = [
        "missions/delivery/square.yaml",
        "missions/delivery/to-kitchen.yaml",
        "missions/common/lib/escapes.yaml",
    ]
    found = validate_files(files, permissions=SHARED)
    assert [d.checked_file for d in found] == files
    assert [str(s) for s in found[0].included_from] == ["missions/delivery/square.yaml:2:11"]
    assert found[2].included_from == ()  # the library checked on its own: its own error
    # one place to fix, reached three ways: the same once the chains are set aside
    assert {d.located() for d in found} == {found[2]}


def test_the_existing_fields_keep_their_places_and_defaults() -> None:
    """``Diagnostic(file, line, column, message, yaml_path, severity)`` as before; the chain
    is the last field, empty by default."""
    d = Diagnostic("m.yaml", 3, 5, "bad", "tree.x", "warning")
    assert (d.file, d.line, d.column, d.message, d.yaml_path, d.severity) == (
        "m.yaml", 3, 5, "bad", "tree.x", "warning",
    )  # fmt: skip
    assert d.included_from == ()
    assert d.checked_file == "m.yaml"
    assert str(d) == "m.yaml:3:5: warning: bad [tree.x]"


def test_a_warning_in_a_library_and_a_load_mission_error_carry_the_chain_too(repo: Path) -> None:
    (repo / "missions/common/lib/escapes.yaml").write_text(
        ESCAPES.replace("mode: safe", "mode: full").replace("10 parsecs", "10 cm")
    )
    [warning] = validate_files(["missions/delivery/square.yaml"], permissions=SHARED)
    assert warning.severity == "warning"  # a drive in Full mode that reads no cliff
    # a check that follows the mission's tree into the library: said at the use
    assert warning.file == "missions/delivery/square.yaml"
    assert warning.in_subtree[0].file == "missions/common/lib/escapes.yaml"
    assert warning.checked_file == "missions/delivery/square.yaml"
    (repo / "missions/common/lib/escapes.yaml").write_text(ESCAPES)
    with pytest.raises(MissionError) as raised:
        load_mission("missions/delivery/to-kitchen.yaml", permissions=SHARED)
    assert "from missions/delivery/to-kitchen.yaml:2:11)" in str(raised.value)


@pytest.mark.parametrize(
    ("written", "error"),
    [
        (
            "  escape_bump:\n    tre: {subtree: back_off}\n",
            "subtree 'escape_bump': unknown key 'tre'",
        ),
        ("  escape_bump: [back_off]\n", "subtree 'escape_bump' must be a mapping"),
    ],
)
def test_a_subtree_defined_wrongly_is_one_error_not_one_more_at_each_use(
    written: str, error: str, repo: Path
) -> None:
    """A library subtree written wrongly gave its error, then "unknown subtree" at each of
    its uses, in every mission: a cascade that buried the one line to fix. Its uses now say
    nothing more (as a wrongly declared blackboard key's do), nor do the arguments given
    there (the parameters it declares are not known)."""
    library = ESCAPES.replace("10 parsecs", "10 cm")
    library = library[: library.index("  escape_bump:")] + written
    (repo / "missions/common/lib/escapes.yaml").write_text(library)
    square = repo / "missions/delivery/square.yaml"
    square.write_text(square.read_text().replace("escape_bump", "{id: escape_bump, turn: 90deg}"))
    files = ["missions/delivery/square.yaml", "missions/delivery/to-kitchen.yaml"]
    found = validate_files(files, permissions=SHARED)
    assert [(d.file, d.checked_file) for d in found] == [
        ("missions/common/lib/escapes.yaml", file) for file in files
    ]
    assert all(d.message.startswith(error) for d in found)
