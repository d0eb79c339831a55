"""``eval --seeds 1-40,42,43`` (a list of seeds) and ``eval --from FILE...`` (the report of
episodes already run, read from their records; none runs)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")
#: an A/B of two variants, byte-stable (``--reproducible``)
AB = ["eval", BUMP, "--sweep", "duration=1s,2s", "--no-progress", "--reproducible"]


def test_seeds_runs_the_seeds_listed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.jsonl"
    assert main([*AB, "--seeds", "3,5-6", "--out", str(out), "--json"]) == 0
    conditions = json.loads(capsys.readouterr().out)["conditions"]
    assert (conditions["seeds"], conditions["seed"], conditions["runs"]) == ([3, 5, 6], 3, 3)
    seeds = [json.loads(line)["seed"] for line in out.read_text().splitlines()]
    assert seeds == [3, 5, 6, 3, 5, 6]  # each variant's, in order


def test_seeds_run_and_are_written_in_the_order_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--seeds 6,3,5`` ran and wrote 3, 5, 6: a user reading the records (or
    ``conditions.seeds``) in the order typed read them in another. Kept as given, in JSON
    Lines, CSV and ``--json``; the text report is the one of the same seeds upwards (the
    statistics do not depend on the order)."""
    import csv

    assert main([*AB, "--seeds", "3,5,6"]) == 0
    upwards = capsys.readouterr().out
    out, table = tmp_path / "r.jsonl", tmp_path / "r.csv"
    assert main([*AB, "--seeds", "6,3,5", "--out", str(out)]) == 0
    assert capsys.readouterr().out == upwards
    assert [json.loads(line)["seed"] for line in out.read_text().splitlines()] == [6, 3, 5] * 2
    assert main([*AB, "--seeds", "6,3,5", "--out", str(table), "--json"]) == 0
    conditions = json.loads(capsys.readouterr().out)["conditions"]
    assert (conditions["seeds"], conditions["seed"], conditions["runs"]) == ([6, 3, 5], 6, 3)
    with table.open(newline="") as rows:
        assert [int(row["seed"]) for row in csv.DictReader(rows)] == [6, 3, 5] * 2


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (
            ["--seeds", "5-3"],
            "argument --seeds: found '5-3': a range from high to low; "
            "allowed: from low to high, 3-5",
        ),
        (["--seeds", "1,x"], "argument --seeds: found 'x'"),
        (
            ["--seeds", "5,3,3,1"],
            "argument --seeds: found seed 3 as '3' twice; allowed: each seed once (a seed is "
            "one episode, the same each time it runs: twice, it would count twice)\n",
        ),
        (
            ["--seeds", "1-40,42,30-50"],
            "argument --seeds: found seed 30 in '1-40' and '30-50' (12 seeds given twice); ",
        ),
        (["--seeds", "-1"], "argument --seeds: found '-1'"),
        (["--seeds", "1-3", "--runs", "3"], "--seeds and --runs: give the seeds one way"),
        (["--seeds", "1-3", "--seed", "1"], "--seeds and --seed: give the seeds one way"),
    ],
)
def test_a_bad_seed_list_exits_2_before_any_episode(
    options: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    try:
        code = main([*AB, *options])
    except SystemExit as exc:  # argparse's own: its usage, then the problem
        code = int(exc.code or 0)
    assert code == 2
    assert said in capsys.readouterr().err


@pytest.fixture
def ran(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[Path, str]:
    """An A/B of 3 seeds written to a file, and the report it printed."""
    out = tmp_path / "ab.jsonl"
    assert main([*AB, "--runs", "3", "--out", str(out)]) == 0
    return out, capsys.readouterr().out


def test_from_reports_the_records_as_the_run_did(
    ran: tuple[Path, str], capsys: pytest.CaptureFixture[str]
) -> None:
    out, report = ran
    assert main(["eval", "--from", str(out)]) == 0
    again, err = capsys.readouterr()
    assert again == report
    assert f"6 episode(s) of 2 variant(s) read from {out}; none run" in err


@pytest.mark.parametrize("named", ["bump-and-turn", "roomba-bt:bump-and-turn.yaml"])
def test_from_labels_a_shipped_mission_as_the_run_did(
    named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval dock`` said ``variant dock`` and ``A = dock``, and ``eval --from`` of its
    results ``roomba-bt:dock.yaml`` (the records' name) for both: one label now, the name
    ``roomba-bt missions`` lists, however the run named it."""
    out = tmp_path / "ab.jsonl"
    run = ["eval", named, "--sweep", "duration=1s,2s", "--no-progress", "--reproducible"]
    assert main([*run, "--runs", "1", "--out", str(out)]) == 0
    report = capsys.readouterr().out
    assert "variant      bump-and-turn -p duration=1s\n" in report, report
    assert "A = bump-and-turn -p duration=1s" in report
    assert main(["eval", "--from", str(out)]) == 0
    assert capsys.readouterr().out == report


def test_from_merges_files_each_episode_once(
    ran: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pieces of one sweep (an interrupted run and its rest, another machine's share) read
    together: an episode in two of them counts once, and the report is the whole sweep's."""
    out, report = ran
    lines = out.read_text().splitlines(keepends=True)
    first, rest = tmp_path / "first.jsonl", tmp_path / "rest.jsonl"
    first.write_text("".join(lines[:4]))
    rest.write_text("".join(lines[3:]))
    assert main(["eval", "--from", str(first), str(rest), "--json"]) == 0
    merged = json.loads(capsys.readouterr().out)
    assert merged["conditions"] is None  # the records do not say them all
    assert [v["runs"] for v in merged["variants"]] == [3, 3]
    assert merged["comparisons"][0]["pairs"] == 3
    assert main(["eval", "--from", str(first), str(rest)]) == 0
    assert capsys.readouterr().out == report


def test_from_refuses_one_episode_with_two_results(
    ran: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, _ = ran
    row = json.loads(out.read_text().splitlines()[1])
    row["outcome"] = "FAILURE"
    other = tmp_path / "other.jsonl"
    other.write_text(json.dumps(row) + "\n")
    assert main(["eval", "--from", str(out), str(other)]) == 2
    err = capsys.readouterr().err
    assert f"--from {other}:1: seed 1 of {BUMP} is at {out}:2 too, with other results" in err


@pytest.mark.parametrize(
    ("change", "said"),
    [
        ({"world": "apartment"}, "the episode ran in world 'apartment', {out}:1 in"),
        ({"world_sha256": "0" * 64}, "of SHA-256 000000000000..., {out}:1 in one of"),
    ],
)
def test_from_refuses_episodes_of_two_worlds(
    ran: tuple[Path, str],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: dict[str, str],
    said: str,
) -> None:
    """An apartment's results and an empty room's were merged with no word, each variant
    labelled with the first file's world and the two worlds' seeds paired as the same
    starts (the verifier, session 35): another world, by name or by its file's SHA-256, is
    refused, naming both places, as ``--resume`` refuses it."""
    out, _ = ran
    row = json.loads(out.read_text().splitlines()[0])
    assert row["world_sha256"]  # the records carry the world file's digest
    row.update(change, seed=99)
    other = tmp_path / "other.jsonl"
    other.write_text(json.dumps(row) + "\n")
    assert main(["eval", "--from", str(out), str(other)]) == 2
    err = capsys.readouterr().err
    assert f"--from {other}:1: the episode ran in world " in err
    assert said.format(out=out) in err
    assert "give each world's files alone" in err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["eval", BUMP, "--from", "x.jsonl"], f"--from and {BUMP}: --from runs no mission"),
        (["eval", "--from", "missing.jsonl"], "--from missing.jsonl: No such file"),
        (["eval"], "give a MISSION to evaluate (or --from FILE... to report on results)"),
    ],
)
def test_from_without_records_or_with_a_mission_exits_2(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    assert f"roomba-bt eval: {said}" in capsys.readouterr().err


def _rows_changed(out: Path, **columns: object) -> None:
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    for row in rows:
        row.update(columns)
        for column in [c for c, v in columns.items() if v is None]:
            del row[column]
    out.write_text("".join(json.dumps(row) + "\n" for row in rows))


@pytest.mark.parametrize(
    ("columns", "options", "said"),
    [
        ({"profile": "roomba500"}, [], "profile      roomba500 (Roomba 500 series)"),
        ({"profile": None}, [], "profile      not recorded (results written before records"),
        ({"profile": None}, ["--profile", "roomba600"], "profile      roomba600 (Roomba 600"),
        ({"undeclared_keys": {"secret": " by 'probe' at lab.py:17"}}, [],
         "warning      write_key('secret') by 'probe' at lab.py:17: blackboard key 'secret' "
         "is not declared by the mission, in 3 of 3 episodes"),
    ],
)  # fmt: skip
def test_from_says_the_profile_and_warnings_the_records_hold(
    ran: tuple[Path, str],
    columns: dict[str, object],
    options: list[str],
    said: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Records name the model their episodes ran as and the keys written undeclared: the
    report says them as the run did (create2 unsaid); records written before the profile
    column are said to be of no known model unless --profile names it."""
    out, report = ran
    _rows_changed(out, **columns)
    assert main(["eval", "--from", str(out), *options]) == 0
    again = capsys.readouterr().out
    assert said in again, again
    assert "profile" not in report


@pytest.mark.parametrize(
    ("content", "said"),
    [
        (None, "{path}: a directory; expected results as eval --out writes them (.jsonl or "
         ".csv)"),
        (b"\xff\xfe", "{path}: not UTF-8 text (byte 0xff); expected results as eval --out"),
        (b'{"seed": 1, "outc\n', "{path}:1:18: not JSON (Invalid control character at); "
         "expected one JSON object a line, as eval --out writes it"),
        (b"[1, 2]\n", "{path}:1: found a JSON array; expected an object per line, as eval --out"),
    ],
)  # fmt: skip
def test_from_a_file_that_holds_no_results_says_which_and_why_in_one_line(
    tmp_path: Path, content: bytes | None, said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A directory read as "Is a directory" (or "unknown results format '(no suffix)'"), a
    file not UTF-8 as the codec's words without the file's name, a line cut short as the
    JSON decoder's words alone: each is said as what it is, naming the file, and what a
    results file holds, on one line, exit 2."""
    path = tmp_path / "r.jsonl"
    if content is None:
        path.mkdir()
    else:
        path.write_bytes(content)
    assert main(["eval", "--from", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"roomba-bt eval: --from {said.format(path=path)}"), err
    if "not JSON" in said:  # the page quotes the message after the command's words
        message = err.removeprefix("roomba-bt eval: --from ")
        names = {str(path): "ab.jsonl"}  # its line and column are an example's
        assert_quoted("docs/evaluation.md", "ab.jsonl:41:201: not JSON", message, True, names)


def test_from_leaves_out_the_last_record_a_killed_sweep_cut_short(
    ran: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The partial file of a sweep killed as it wrote a record ends inside it, without its
    end of line: ``--from`` refused it ("not JSON ..., the line cut short"), and the report
    of a killed sweep needed the file edited. The record is left out, said in one line; a
    file holding nothing else has no episode to report on."""
    out, _ = ran
    lines = out.read_bytes().splitlines(keepends=True)
    partial = tmp_path / "k.jsonl.partial.jsonl"
    partial.write_bytes(b"".join(lines[:5]) + lines[5][: len(lines[5]) // 2])
    assert main(["eval", "--from", str(partial), "--json"]) == 0
    report, err = capsys.readouterr()
    assert [v["runs"] for v in json.loads(report)["variants"]] == [3, 2]
    assert err == (f"roomba-bt eval: --from {partial}:6: the record of seed 2 of {BUMP} was cut "
                   "short as it was written (the file ends inside it: the sweep was killed, or "
                   f"the disk was full): left out\nroomba-bt eval: 5 episode(s) of 2 variant(s) "
                   f"read from {partial}; none run\n")  # fmt: skip
    # docs/evaluation.md quotes the first line, of a sweep of its own: dock, line 42, seed 20
    assert_quoted("docs/evaluation.md", "roomba-bt eval: --from ab.jsonl.partial.jsonl:", err,
                  numbers=True, names={str(partial): "ab.jsonl.partial.jsonl",
                                       BUMP: "roomba-bt:dock.yaml"})  # fmt: skip
    partial.write_bytes(b'{"seed": 1, "outc')
    assert main(["eval", "--from", str(partial)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt eval: --from {partial}:1: the record of seed 1 was cut")
    assert err.endswith(f"left out\nroomba-bt eval: --from {partial}: no episode to report on\n")


@pytest.mark.parametrize(
    "options",
    [["--seeds", "1-2"], ["--runs", "2"], ["--out", "o.jsonl"], ["--plot", "p.png"],
     ["--resume"], ["--sweep", "duration=1s,2s"], ["-p", "duration=1s"], ["--key", "k"]],
)  # fmt: skip
def test_from_refuses_the_options_of_a_run_it_would_drop(
    ran: tuple[Path, str],
    options: list[str],
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``--from ab.jsonl --seeds 1-2`` reported every seed, and ``--out`` or ``--plot``
    wrote nothing, without a word: refused, naming the option, exit 2."""
    monkeypatch.chdir(ran[0].parent)
    assert main(["eval", "--from", str(ran[0]), *options]) == 2
    err = capsys.readouterr().err
    assert err == (f"roomba-bt eval: --from and {options[0]}: --from reports on the episodes "
                   f"its files hold as they are (it runs none and writes no file); {options[0]} "
                   "is for a run: give one or the other\n")  # fmt: skip
    assert sorted(p.name for p in ran[0].parent.iterdir()) == ["ab.jsonl"]


def test_a_resume_of_a_partial_file_not_utf8_is_refused_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """It was roomba-bt's internal error (exit 70): the codec's error is a ValueError,
    which the reader did not turn into its own."""
    out = tmp_path / "r.jsonl"
    (tmp_path / "r.jsonl.partial.jsonl").write_bytes(b"\xff\xfe\n")
    assert main([*AB, "--runs", "2", "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert err == (f"roomba-bt eval: --resume: {out}.partial.jsonl: not UTF-8 text (byte 0xff); "
                   "expected results as eval --out writes them (.jsonl or .csv); --resume "
                   "reads it back (--force: write over it)\n")  # fmt: skip


@pytest.mark.parametrize(
    ("row", "said"),
    [
        (lambda cells: cells[:5], "{path}:2: 5 cells in a header of {n} columns (the row cut "
         "short?); expected a cell under each column, as eval --out writes them"),
        (lambda cells: [*cells, "more"], "{path}:2: {n1} cells in a header of {n} columns; "
         "expected a cell under each column"),
        (lambda cells: ["z" if c == "0" else c for c in cells], "{path}:2: bad value (column "
         "'seed': found 'z'; expected a whole number)"),
    ],
)  # fmt: skip
def test_from_a_csv_row_cut_short_or_too_long_is_said_so(
    tmp_path: Path, row: Any, said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A CSV row cut short read its missing cells as None, said as "bad value (float()
    argument must be a string or a real number, not 'NoneType')"; a bad cell named no
    column ("invalid literal for int() with base 10: 'z'")."""
    import csv

    out = tmp_path / "r.csv"
    assert main([*AB, "--runs", "1", "--out", str(out)]) == 0
    with out.open(newline="") as file:
        header, first, *_ = list(csv.reader(file))
    cut = tmp_path / "cut.csv"
    with cut.open("w", newline="") as file:
        csv.writer(file).writerows([header, row(first)])
    capsys.readouterr()
    assert main(["eval", "--from", str(cut)]) == 2
    err = capsys.readouterr().err
    n = len(header)
    assert err.startswith(f"roomba-bt eval: --from {said.format(path=cut, n=n, n1=n + 1)}"), err
    assert err.count("\n") == 1
