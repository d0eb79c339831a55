"""Records committed to a repository: replayed in another checkout, made again byte for byte,
and saying how to make them again (a team's CI, session 29)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.runtime.recording import load_record

ESCAPES = """\
subtrees:
  back_off:
    tree:
      drive: {{velocity: -100 mm/s, distance: {distance}}}
"""
PATROL = """\
mission: patrol
include: [../common/escapes.yaml]
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: 10 cm}
    - subtree: back_off
"""
WORLD = """\
name: lab
rooms:
  - {rect: [0, 0, 4, 3]}
robot:
  start: {at: [2.0, 1.5], heading: 0}
  start_region: {rect: [1.5, 1.0, 2.5, 2.0], heading: any}
"""


def _repository(root: Path, distance: str = "5 cm") -> Path:
    """A team's repository: a mission in ``missions/patrol`` including a library of the
    sibling folder ``missions/common``, a world, and a ``records`` folder."""
    (root / "missions" / "patrol").mkdir(parents=True)
    (root / "missions" / "common").mkdir()
    (root / "worlds").mkdir()
    (root / "records").mkdir()
    (root / "missions" / "common" / "escapes.yaml").write_text(ESCAPES.format(distance=distance))
    (root / "missions" / "patrol" / "patrol.yaml").write_text(PATROL)
    (root / "worlds" / "lab.yaml").write_text(WORLD)
    return root


def _record(
    root: Path, monkeypatch: pytest.MonkeyPatch, *extra: str, name: str = "patrol.jsonl"
) -> int:
    """``run`` from the repository's top, as its CI script does, recording into records/."""
    monkeypatch.chdir(root)
    return main([
        "run", "missions/patrol/patrol.yaml", "--fast", "--display", "none", "--world",
        "worlds/lab.yaml", "--include-dir", "missions/common", "--record", f"records/{name}",
        *extra,
    ])  # fmt: skip


def test_a_committed_record_replays_in_another_checkout_and_names_the_file_changed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The header named the mission and its files by absolute path: in CI's checkout
    elsewhere the replay said "mission '/…/co1/missions/…' not found; pass --mission", and
    with --mission it said nothing of the library changed. Paths are from the record's folder
    now, and the files are matched by where they lie from their mission."""
    first = _repository(tmp_path / "co1")
    assert _record(first, monkeypatch) == 0
    header = load_record(first / "records" / "patrol.jsonl").header
    assert header["mission"] == "../missions/patrol/patrol.yaml"
    assert header["relative_to"] == "record"
    assert header["mission_path"] == str((first / "missions/patrol/patrol.yaml").resolve())
    assert list(header["sources"]) == [
        "../missions/patrol/patrol.yaml",
        "../missions/common/escapes.yaml",
    ]
    second = tmp_path / "co2"
    first.rename(second)  # CI's checkout: another folder, the first one gone
    monkeypatch.chdir(second)
    capsys.readouterr()
    assert main(["replay", "records/patrol.jsonl", "--include-dir", "missions/common"]) == 0
    assert "the tree wrote the same" in capsys.readouterr().out
    # a pull request changes the library: the replay differs and names it
    (second / "missions/common/escapes.yaml").write_text(ESCAPES.format(distance="9 cm"))
    assert main(["replay", "records/patrol.jsonl", "--include-dir", "missions/common"]) == 1
    out = capsys.readouterr().out
    assert "1 of its 2 source files differs now" in out
    said = "replay: missions/common/escapes.yaml changed since this record was made"
    assert said in out
    # the same with --mission, from a third checkout holding the record elsewhere
    third = tmp_path / "pr"
    shutil.copytree(second, third)
    monkeypatch.chdir(third)
    argv = ["replay", str(second / "records/patrol.jsonl"), "--mission",
            "missions/patrol/patrol.yaml", "--include-dir", "missions/common"]  # fmt: skip
    assert main(argv) == 1
    assert said in capsys.readouterr().out


def test_a_record_made_before_names_the_file_changed_with_mission_in_another_checkout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A record made before holds absolute paths: it still loads, and with --mission in
    another checkout its files are matched by where they lie from the mission."""
    first = _repository(tmp_path / "repo")
    assert _record(first, monkeypatch) == 0
    record = first / "records" / "patrol.jsonl"
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    old = {k: v for k, v in header.items() if k not in ("relative_to", "mission_path",
                                                       "simulator", "options")}  # fmt: skip
    old["mission"] = header.get("mission_path", header["mission"])
    old["sources"] = {
        str((record.parent / name).resolve()): digest for name, digest in header["sources"].items()
    }
    record.write_text("".join([json.dumps(old) + "\n", *lines[1:]]), encoding="utf-8")
    clone = tmp_path / "pr1"
    shutil.copytree(first, clone)
    (clone / "missions/common/escapes.yaml").write_text(ESCAPES.format(distance="9 cm"))
    monkeypatch.chdir(clone)
    capsys.readouterr()
    argv = ["replay", "records/patrol.jsonl", "--mission", "missions/patrol/patrol.yaml",
            "--include-dir", "missions/common"]  # fmt: skip
    assert main(argv) == 1
    out = capsys.readouterr().out
    assert "1 of its 2 source files differs now" in out
    assert "replay: missions/common/escapes.yaml changed since this record was made" in out


def test_a_record_moved_away_from_its_mission_replays_it_where_it_was_recorded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The absolute path is kept for the reader, and for a record copied out of its
    repository: the mission beside it is looked for first, then where it was recorded."""
    repo = _repository(tmp_path / "repo")
    assert _record(repo, monkeypatch) == 0
    away = tmp_path / "elsewhere" / "deep" / "patrol.jsonl"
    away.parent.mkdir(parents=True)
    shutil.copy(repo / "records" / "patrol.jsonl", away)
    capsys.readouterr()
    assert main(["replay", str(away), "--include-dir", "missions/common"]) == 0
    err = capsys.readouterr().err
    assert "mission '../missions/patrol/patrol.yaml' is not beside the record" in err
    assert f"replaying {(repo / 'missions/patrol/patrol.yaml').resolve()}" in err
    shutil.rmtree(repo)
    assert main(["replay", str(away)]) == 2
    assert "not found; pass --mission FILE" in capsys.readouterr().err


def test_reproducible_runs_write_the_same_record_and_summary_in_any_checkout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Re-recording with nothing changed changed every record (its ``started``, its absolute
    paths) and every saved summary (the wall time, the slowest tick). ``--reproducible``
    leaves them out, and ``started`` is SOURCE_DATE_EPOCH's, as the convention has it."""
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    made = []
    for checkout in ("a", "b"):
        repo = _repository(tmp_path / checkout)
        assert _record(repo, monkeypatch, "--reproducible") == 0
        made.append(((repo / "records/patrol.jsonl").read_bytes(), capsys.readouterr().out))
    assert made[0] == made[1]
    summary = made[0][1]
    assert "wall" not in summary and "slowest" not in summary and "ticks        " in summary
    header = json.loads(made[0][0].splitlines()[0])
    assert header["started"] == "2023-11-14T22:13:20Z" and "mission_path" not in header
    monkeypatch.delenv("SOURCE_DATE_EPOCH")
    repo = tmp_path / "a"
    assert _record(repo, monkeypatch, "--reproducible", name="again.jsonl") == 0
    assert "started" not in load_record(repo / "records/again.jsonl").header
    assert _record(repo, monkeypatch, name="plain.jsonl") == 0  # without: as before
    assert "started" in load_record(repo / "records/plain.jsonl").header
    assert "s wall" in capsys.readouterr().out
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    assert _record(repo, monkeypatch, name="bad.jsonl") == 2
    assert "SOURCE_DATE_EPOCH='yesterday': expected a whole number of seconds" in (
        capsys.readouterr().err
    )


def test_a_record_holds_what_makes_it_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The header had no world, seed, random start, charge or encoder error, nor the run's
    include folders: a record could not be made again from itself. Made again from its
    header alone, in the record's folder, it is the same bytes."""
    repo = _repository(tmp_path / "repo")
    options = ["--seed", "7", "--random-start", "--battery", "60%", "--odometry-error", "0.02",
               "--timeout", "30s", "--reproducible"]  # fmt: skip
    assert _record(repo, monkeypatch, *options) == 0
    record = repo / "records" / "patrol.jsonl"
    header = load_record(record).header
    simulator, run = header["simulator"], header["options"]
    assert simulator == {
        "world": "../worlds/lab.yaml", "world_sha256": simulator["world_sha256"], "seed": 7,
        "random_start": True, "battery": 0.6, "odometry_error": 0.02, "fast": True,
    }  # fmt: skip
    assert run == {"timeout": "30s", "include_dirs": ["../missions/common"],
                   "allow_plugin_files": False, "end_in": "passive"}  # fmt: skip
    again = ["run", header["mission"], "--world", simulator["world"], "--seed",
             str(simulator["seed"]), "--battery", str(simulator["battery"]), "--odometry-error",
             str(simulator["odometry_error"]), "--timeout", run["timeout"], "--end-in",
             run["end_in"], "--display", "none", "--reproducible",
             "--record", "again.jsonl"]  # fmt: skip
    again += ["--random-start"] * simulator["random_start"] + ["--fast"] * simulator["fast"]
    for folder in run["include_dirs"]:
        again += ["--include-dir", folder]
    monkeypatch.chdir(record.parent)
    assert main(again) == 0
    assert (record.parent / "again.jsonl").read_bytes() == record.read_bytes()
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    assert main(["run", "dock", "--fast", "--display", "none", "--record", "d.jsonl"]) == 0
    assert load_record(tmp_path / "d.jsonl").header["simulator"]["world"] == "empty-room"


def test_a_record_replays_with_the_include_folders_its_run_was_granted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The header held ``--include-dir``'s folders and the replay never read them: a record
    made with ``--include-dir`` (or with ROOMBA_BT_INCLUDE_PATH, which the header did not even
    hold) was refused at its include unless the replay was given the folder again."""
    repo = _repository(tmp_path / "repo")
    assert _record(repo, monkeypatch) == 0
    capsys.readouterr()
    assert main(["replay", "records/patrol.jsonl"]) == 0
    assert "the tree wrote the same" in capsys.readouterr().out
    monkeypatch.chdir(tmp_path)  # from anywhere: the folder is read from the record's
    assert main(["replay", "repo/records/patrol.jsonl"]) == 0
    # granted by the environment: recorded too, and replayed without it
    monkeypatch.chdir(repo)
    monkeypatch.setenv("ROOMBA_BT_INCLUDE_PATH", "missions/common")
    assert main([
        "run", "missions/patrol/patrol.yaml", "--fast", "--display", "none", "--world",
        "worlds/lab.yaml", "--record", "records/by-env.jsonl",
    ]) == 0  # fmt: skip
    header = load_record(repo / "records" / "by-env.jsonl").header
    assert header["options"]["include_dirs"] == ["../missions/common"]
    monkeypatch.delenv("ROOMBA_BT_INCLUDE_PATH")
    capsys.readouterr()
    assert main(["replay", "records/by-env.jsonl"]) == 0


def test_a_record_grants_no_folder_outside_the_one_that_holds_it_and_its_mission(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A record from a stranger is held to a project file's rule: a folder its header names
    outside the folder holding the record and its mission (``/etc``, ``..``) is not granted,
    and said once; the include is refused at its line as ever."""
    repo = _repository(tmp_path / "repo")
    assert _record(repo, monkeypatch) == 0
    record = repo / "records" / "patrol.jsonl"
    lines = record.read_text().splitlines()
    header = json.loads(lines[0])
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    header["options"]["include_dirs"] = ["/etc", "../../elsewhere", "../missions/common"]
    record.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    capsys.readouterr()
    assert main(["replay", "records/patrol.jsonl"]) == 0  # its own folder still granted
    err = capsys.readouterr().err
    assert "include folder '/etc' of the recorded run is outside the folder" in err
    assert "include folder '../../elsewhere' of the recorded run is outside" in err
    assert "common" not in err
    page = {"records/patrol.jsonl": "r.jsonl", str(repo): "/home/me/repo"}
    assert_quoted("docs/runtime.md", "roomba-bt: warning: r.jsonl: include", err, names=page)
    # the library moved outside: the record's word does not reach it
    shutil.copy(repo / "missions/common/escapes.yaml", elsewhere / "escapes.yaml")
    patrol = repo / "missions/patrol/patrol.yaml"
    patrol.write_text(PATROL.replace("../common/escapes.yaml", "../../../elsewhere/escapes.yaml"))
    assert main(["replay", "records/patrol.jsonl"]) == 2
    assert "is outside the mission's folder" in capsys.readouterr().err


def test_a_record_naming_a_file_outside_its_folder_as_its_mission_never_shows_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A record's mission is not held to its folder (decided, docs/runtime.md: a record made
    in /tmp of ~/m.yaml shares only the root with it, and replays): what makes that safe is
    that the file is only ever compiled, never quoted, never run, and a replay writes to no
    robot. A stranger's header naming a secret file gets "not a mission file", no line of it."""
    repo = _repository(tmp_path / "repo")
    assert _record(repo, monkeypatch) == 0
    secret = tmp_path / "home" / ".pgpass"
    secret.parent.mkdir()
    secret.write_text("db.example.com:5432:prod:admin:S3cretPgPass\n")
    record = repo / "records" / "patrol.jsonl"
    lines = record.read_text().splitlines()
    header = json.loads(lines[0])
    for named in (str(secret), "../../home/.pgpass"):
        header["mission"] = named
        record.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
        capsys.readouterr()
        assert main(["replay", "records/patrol.jsonl"]) == 2
        out, err = capsys.readouterr()
        assert "this file is not a mission file" in out + err
        assert "S3cret" not in out + err and "db.example" not in out + err
