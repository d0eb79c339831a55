"""``roomba-bt validate`` in a team's CI: each error once, a verdict naming every failing
file, ``--strict`` for warnings, and ``--format json|github`` for programs and annotations.

Found by a lab team (missions in git, CI and pre-commit): a library error was printed once
per mission that included it, under the library's name only, and the missions that failed
were named nowhere; a warning (a Full-mode drive with no cliff check) could not fail the
check; the output was text only, parsed with sed.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from team_repo import ESCAPES, team_repo  # beside this file

from roomba_bt.cli import main

Capsys = pytest.CaptureFixture[str]

EVERY_FILE = [
    "missions/delivery/square.yaml",
    "missions/delivery/to-kitchen.yaml",
    "missions/common/lib/escapes.yaml",
    "missions/common/lib/safe_drive.yaml",
]
SHARED = ["--include-dir", "missions/common"]
LIBRARY_ERROR = (
    "missions/common/lib/escapes.yaml:7:50: drive.distance: unknown distance unit 'parsecs' "
    "in '10 parsecs'; use one of: mm, cm, m [subtrees.back_off.tree.sequence[1].drive.distance]"
)

#: a drive in Full mode that reads no cliff: compiles, with the safety warning
FULL_DRIVE = """\
mission: w
tree:
  sequence:
    - mode: full
    - drive: {velocity: 200 mm/s, duration: 1s}
    - mode: passive
"""


@pytest.fixture
def repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return team_repo(tmp_path)


def test_a_library_error_is_said_once_and_every_mission_it_breaks_is_named(
    repo: Path, capsys: Capsys
) -> None:
    assert main(["validate", *SHARED, *EVERY_FILE]) == 2
    out, err = capsys.readouterr()
    assert err == ""
    assert out.splitlines() == [
        f"{LIBRARY_ERROR} (included from missions/delivery/square.yaml:2:11)",
        "missions/delivery/square.yaml: failed (an included file has errors: 1 error in "
        "missions/common/lib/escapes.yaml, included at line 2)",
        "missions/delivery/to-kitchen.yaml: failed (an included file has errors: 1 error in "
        "missions/common/lib/escapes.yaml, included at line 2)",
        "missions/common/lib/escapes.yaml: failed (1 error)",
        "missions/common/lib/safe_drive.yaml: failed (an included file has errors: 1 error in "
        "missions/common/lib/escapes.yaml, included at line 2)",
        "4 files: 0 ok, 0 with warnings only, 4 with errors",
    ]


def test_the_chain_of_a_mission_checked_alone_reaches_its_own_include(
    repo: Path, capsys: Capsys
) -> None:
    (repo / "missions/delivery/square.yaml").write_text(
        (repo / "missions/delivery/square.yaml").read_text().replace("mode: passive", "mde: x")
    )
    assert main(["validate", *SHARED, "missions/delivery/to-kitchen.yaml",
                 "missions/delivery/square.yaml"]) == 2  # fmt: skip
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == (
        f"{LIBRARY_ERROR} (included from missions/common/lib/safe_drive.yaml:2:11, "
        "from missions/delivery/to-kitchen.yaml:2:11)"
    )
    # square's own error, then its verdict: its own and the library's, said already
    assert lines[2].startswith("missions/delivery/square.yaml:7:7: unknown node 'mde'")
    assert lines[3] == (
        "missions/delivery/square.yaml: failed (1 error; an included file has errors: 1 error "
        "in missions/common/lib/escapes.yaml, included at line 2)"
    )


def test_quiet_leaves_out_the_files_that_passed_not_those_that_failed(
    repo: Path, capsys: Capsys
) -> None:
    (repo / "ok.yaml").write_text("tree: wall\n")
    assert main(["validate", "-q", *SHARED, "ok.yaml", "missions/delivery/to-kitchen.yaml"]) == 2
    out = capsys.readouterr().out
    assert "ok.yaml" not in out
    verdict, counts = out.splitlines()[-2:]
    assert verdict.startswith("missions/delivery/to-kitchen.yaml: failed (")
    assert counts == "2 files: 1 ok, 0 with warnings only, 1 with errors"  # the count stays
    (repo / "ok2.yaml").write_text("tree: wall\n")
    assert main(["validate", "-q", "ok.yaml", "ok2.yaml"]) == 0
    assert capsys.readouterr().out == ""  # all passed: nothing, as before


def test_a_file_given_twice_is_checked_and_said_once(repo: Path, capsys: Capsys) -> None:
    """``validate bad.yaml ./bad.yaml bad.yaml`` said its errors once and "failed" three times,
    counted as three files; a folder and a file in it, likewise. Each file once now, at its
    first place, the others warned about on stderr."""
    (repo / "ok.yaml").write_text("tree: wall\n")
    (repo / "bad.yaml").write_text("tree: {wal: {}}\n")
    assert main(["validate", "bad.yaml", "./bad.yaml", "ok.yaml", "bad.yaml", "nope.yaml",
                 "nope.yaml"]) == 2  # fmt: skip
    out, err = capsys.readouterr()
    assert [line.split(":")[0] for line in out.splitlines()] == [
        "bad.yaml", "bad.yaml", "ok.yaml", "nope.yaml", "3 files"
    ]  # fmt: skip
    assert err.splitlines()[:3] == [
        "roomba-bt validate: warning: ./bad.yaml is bad.yaml again: checked once",
        "roomba-bt validate: warning: bad.yaml is given twice: checked once",
        "roomba-bt validate: warning: nope.yaml is given twice: checked once",
    ]
    assert main(["validate", "-q", "missions/delivery", "missions/delivery/square.yaml",
                 *SHARED]) == 2  # fmt: skip
    out, err = capsys.readouterr()
    assert out.count("missions/delivery/square.yaml: failed") == 1
    assert "missions/delivery/square.yaml is given twice: checked once" in err


def test_strict_fails_on_warnings_with_exit_7_and_errors_stay_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "w1.yaml").write_text(FULL_DRIVE)
    assert main(["validate", "w1.yaml"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "w1.yaml: ok, with warnings"
    assert main(["validate", "--strict", "w1.yaml"]) == 7
    warning, verdict = capsys.readouterr().out.splitlines()
    assert warning.startswith("w1.yaml:5:7: warning: drive can turn the wheels in Full mode")
    assert verdict == "w1.yaml: failed --strict (1 warning)"
    (tmp_path / "bad.yaml").write_text("tree: {wal: {}}\n")
    assert main(["validate", "--strict", "w1.yaml", "bad.yaml"]) == 2  # an error: 2, as ever
    (tmp_path / "ok.yaml").write_text("tree: wall\n")
    assert main(["validate", "--strict", "ok.yaml"]) == 0


def test_strict_names_a_warning_that_comes_through_an_include(repo: Path, capsys: Capsys) -> None:
    (repo / "missions/common/lib/escapes.yaml").write_text(
        ESCAPES.replace("mode: safe", "mode: full").replace("10 parsecs", "10 cm")
    )
    assert main(["validate", "--strict", *SHARED, "missions/delivery/square.yaml"]) == 7
    # the mission's tree reaches the library's drive in Full mode: the use's warning
    assert capsys.readouterr().out.splitlines()[-1] == (
        "missions/delivery/square.yaml: failed --strict (1 warning)"
    )


def test_json_lists_every_diagnostic_with_its_chain_and_each_file_verdict(
    repo: Path, capsys: Capsys
) -> None:
    (repo / "w1.yaml").write_text(FULL_DRIVE)
    files = ["missions/delivery/to-kitchen.yaml", "w1.yaml", "missing.yaml"]
    assert main(["validate", "--format", "json", *SHARED, *files]) == 2
    out, err = capsys.readouterr()
    assert "missing.yaml: no such mission file" in err  # said on stderr as in text
    report = json.loads(out)
    assert report["exit_code"] == 2
    assert report["strict"] is False
    assert [(f["file"], f["verdict"], f["errors"], f["warnings"]) for f in report["files"]] == [
        ("missions/delivery/to-kitchen.yaml", "failed", 1, 0),
        ("w1.yaml", "ok, with warnings", 0, 1),
        ("missing.yaml", "failed", 1, 0),
    ]
    assert "no such mission file" in report["files"][2]["problem"]
    assert report["summary"] == {"files": 3, "ok": 0, "warnings_only": 1, "errors": 2}
    library, warning, missing = report["diagnostics"]
    assert missing == {  # the reason, not only the count: at no line (null)
        "file": "missing.yaml",
        "line": None,
        "column": None,
        "severity": "error",
        "message": missing["message"],
        "yaml_path": "",
        "included_from": [],
        "began_at": None,
        "used_in": [],
        "in_subtree": [],
        "checked_file": "missing.yaml",
    }
    assert missing["message"].startswith("no such mission file")
    assert library == {
        "file": "missions/common/lib/escapes.yaml",
        "line": 7,
        "column": 50,
        "severity": "error",
        "message": "drive.distance: unknown distance unit 'parsecs' in '10 parsecs'; use one "
        "of: mm, cm, m",
        "yaml_path": "subtrees.back_off.tree.sequence[1].drive.distance",
        "included_from": [
            {"file": "missions/common/lib/safe_drive.yaml", "line": 2, "column": 11},
            {"file": "missions/delivery/to-kitchen.yaml", "line": 2, "column": 11},
        ],
        "began_at": None,
        "used_in": [],
        "in_subtree": [],
        "checked_file": "missions/delivery/to-kitchen.yaml",
    }
    said = (warning["severity"], warning["checked_file"], warning["line"])
    assert said == ("warning", "w1.yaml", 5)
    assert main(["validate", "--format", "json", "--strict", "w1.yaml"]) == 7
    strict = json.loads(capsys.readouterr().out)
    assert (strict["exit_code"], strict["files"][0]["verdict"]) == (7, "failed")


def test_json_names_the_files_each_file_includes_valid_or_not(repo: Path, capsys: Capsys) -> None:
    """The reverse view docs/ci.md reads with jq (which missions a library reaches): each
    file's includes, through other libraries too, in the order first reached."""
    (repo / "m.yaml").write_text("include: [roomba-bt:lib/undock.yaml]\ntree: wall\n")
    assert main(["validate", "--format", "json", *SHARED, *EVERY_FILE, "m.yaml"]) == 2
    report = json.loads(capsys.readouterr().out)
    escapes, safe_drive = EVERY_FILE[2], EVERY_FILE[3]
    assert [(f["file"], f["includes"]) for f in report["files"]] == [
        (EVERY_FILE[0], [escapes]),
        (EVERY_FILE[1], [safe_drive, escapes]),
        (escapes, []),
        (safe_drive, [escapes]),
        ("m.yaml", ["roomba-bt:lib/undock.yaml"]),
    ]


def test_github_annotates_the_library_once_and_each_mission_at_its_include(
    repo: Path, capsys: Capsys
) -> None:
    assert main(["validate", "--format", "github", *SHARED, *EVERY_FILE]) == 2
    lines = capsys.readouterr().out.splitlines()
    annotations = [line for line in lines if line.startswith("::")]
    title = "title=roomba-bt validate::"
    assert annotations == [
        # the library's error once, where it is
        "::error file=missions/common/lib/escapes.yaml,line=7,col=50,"
        + title
        + LIBRARY_ERROR.split(":7:50: ")[1]
        + " (included from missions/delivery/square.yaml:2:11)",
        # each file that fails through it, at its include: the mission is marked too
        *(
            f"::error file={file},line=2,col=11,{title}this include brings in 1 error: "
            + LIBRARY_ERROR
            for file in (EVERY_FILE[0], EVERY_FILE[1], EVERY_FILE[3])
        ),
    ]
    assert "missions/delivery/to-kitchen.yaml: failed (an included file has errors: 1 error in " \
        "missions/common/lib/escapes.yaml, included at line 2)" in lines  # fmt: skip


def test_github_escapes_what_would_end_a_property_or_the_message_and_marks_warnings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a,b:c.yaml").write_text("tree: {log: '100%\\nx', wal: 1}\n")
    (tmp_path / "w1.yaml").write_text(FULL_DRIVE)
    assert main(["validate", "--format", "github", "a,b:c.yaml"]) == 2
    [annotation] = [line for line in capsys.readouterr().out.splitlines() if line[:2] == "::"]
    assert annotation.startswith("::error file=a%2Cb%3Ac.yaml,line=1,col=")
    assert main(["validate", "--format", "github", "w1.yaml"]) == 0
    assert capsys.readouterr().out.startswith("::warning file=w1.yaml,line=5,col=7,")
    assert main(["validate", "--format", "github", "--strict", "w1.yaml"]) == 7
    assert capsys.readouterr().out.startswith(
        "::error file=w1.yaml,line=5,col=7,title=roomba-bt validate::warning (an error under "
        "--strict): drive can turn the wheels"
    )


def test_github_messages_and_properties_are_escaped_as_the_actions_toolkit_does() -> None:
    from roomba_bt.cli.validate_report import command_data, command_property

    assert command_data("100% done\r\nnext\x1b[2J") == "100%25 done%0D%0Anext\\x1b[2J"
    assert command_property("a,b:c\n.yaml") == "a%2Cb%3Ac%0A.yaml"


def test_a_file_it_cannot_read_has_its_verdict_on_stdout_and_its_reason_in_json(
    repo: Path, capsys: Capsys
) -> None:
    """A CI log that keeps stdout alone showed only the files that passed, and JSON's
    ``said`` pointed "above", where a JSON document has nothing."""
    assert main(["validate", "missing.yaml", "dock"]) == 2
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("missing.yaml: failed (cannot read: no such mission file")
    assert out[1] == "dock: ok"
    assert main(["validate", "--format", "json", "missing.yaml"]) == 2
    (entry,) = json.loads(capsys.readouterr().out)["files"]
    assert entry["said"].startswith("failed (cannot read: no such mission file")
    assert "above" not in entry["said"]


#: a mission that gives the shipped docking subtree a speed its search leaf refuses
BAD_DOCK_SPEED = """\
include: [roomba-bt:lib/docking.yaml]
tree:
  sequence:
    - mode: safe
    - subtree: {id: dock, search_speed: 900 mm/s}
"""


@pytest.mark.parametrize("form", ["text", "json", "github"])
def test_a_shipped_file_is_named_by_its_shipped_name_in_every_format(
    form: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """A diagnostic in a shipped file (``validate dock``, or a mission that includes the
    shipped library) named it by its site-packages path, a different line on every machine:
    it is named as an include writes it and a record holds it. The package lies outside the
    working folder here, as an installed wheel's does."""
    from roomba_bt.mission.shipped import SHIPPED_DIR

    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.yaml").write_text(BAD_DOCK_SPEED)
    said = []
    for argv in (["m.yaml"], ["dock", "-p", "time_limit=abc"]):
        assert main(["validate", "--format", form, *argv]) == 2
        said.append(capsys.readouterr().out)
    assert str(SHIPPED_DIR) not in "".join(said)
    library, dock = "roomba-bt:lib/docking.yaml", "roomba-bt:dock.yaml"
    if form == "json":
        included, own = (json.loads(out) for out in said)
        # the use gave the speed: said there, the library's place named by its shipped name
        [at_use] = included["diagnostics"]
        assert (at_use["file"], at_use["line"]) == ("m.yaml", 5)
        assert [(u["file"], u["line"]) for u in at_use["in_subtree"]] == [(library, 43)]
        assert [(d["file"], d["line"]) for d in own["diagnostics"]] == [(dock, 17)]
    elif form == "github":
        assert said[0].startswith("::error file=m.yaml,line=5,col=7,")
        assert f"(in subtree dock, {library}:43:44 [subtrees.dock.tree." in said[0]
        assert said[1].startswith(f"::error file={dock.replace(':', '%3A')},line=17,col=3,")
    else:
        assert said[0].startswith("m.yaml:5:7: dock_search: speed 900 mm/s is out of range")
        assert f"(in subtree dock, {library}:43:44 [subtrees.dock.tree." in said[0]
        assert "m.yaml: failed (1 error)" in said[0]
        assert said[1].startswith(f"{dock}:17:3: parameter time_limit=abc (from the command line)")
