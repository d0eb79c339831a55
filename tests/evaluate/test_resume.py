"""``eval --out FILE`` again: refused over earlier episodes, ``--force``d, or ``--resume``d
(the episodes FILE lacks run, and FILE ends as an uninterrupted run writes it)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main
from roomba_bt.cli.eval_resume import refused_over

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")
#: an A/B of two variants, byte-stable (``--reproducible``)
SWEEP = ["eval", BUMP, "--sweep", "duration=1s,2s", "--no-progress", "--reproducible"]


def _sweep(out: Path, runs: int, *options: str, values: str = "1s,2s") -> int:
    """The A/B of ``duration`` ``values``, ``runs`` seeds each, written to ``out``."""
    argv = ["eval", BUMP, "--sweep", f"duration={values}", "--no-progress", "--reproducible"]
    return main([*argv, "--runs", str(runs), "--out", str(out), *options])


@pytest.fixture
def uninterrupted(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, str]:
    """What a run of 4 seeds per variant writes, as JSON Lines and CSV, and its report."""
    written = {}
    for suffix in (".jsonl", ".csv"):
        assert _sweep(tmp_path / f"full{suffix}", 4) == 0
        written[suffix] = (tmp_path / f"full{suffix}").read_text()
        written[f"{suffix} report"] = capsys.readouterr().out
    return written


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_resumed_sweep_writes_what_an_uninterrupted_one_writes(
    suffix: str,
    tmp_path: Path,
    uninterrupted: dict[str, str],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The seeds ``--out`` holds are read back, only the others run, and the file and the
    report (every episode summarised and compared) are those of one run of them all."""
    out = tmp_path / f"r{suffix}"
    assert _sweep(out, 2) == 0
    capsys.readouterr()
    assert _sweep(out, 4, "--resume") == 0
    report, err = capsys.readouterr()
    assert f"--resume: 4 episode(s) read back from {out}, 4 to run" in err
    assert out.read_text() == uninterrupted[suffix]
    assert report == uninterrupted[f"{suffix} report"]
    assert "paired       4 episodes" in report


def test_a_resume_reads_the_partial_file_a_killed_sweep_left(
    tmp_path: Path, uninterrupted: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``kill -9`` leaves ``OUT.partial.jsonl`` (rows as ``OUT``'s, in the order they
    finished) and no ``OUT``: ``--resume`` reads it, and it is gone once ``OUT`` is written."""
    out = tmp_path / "r.jsonl"
    rows = uninterrupted[".jsonl"].splitlines(keepends=True)
    (tmp_path / "r.jsonl.partial.jsonl").write_text("".join([rows[5], rows[0], rows[1]]))
    assert _sweep(out, 4) == 2  # refused: the partial file holds episodes
    assert "r.jsonl.partial.jsonl already holds episodes" in capsys.readouterr().err
    assert _sweep(out, 4, "--resume") == 0
    assert f"3 episode(s) read back from {out}.partial.jsonl, 5 to run" in capsys.readouterr().err
    assert out.read_text() == uninterrupted[".jsonl"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["full.csv", "full.jsonl", "r.jsonl"]


def _second_row_changed(out: Path, **columns: object) -> None:
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    rows[1].update(columns)
    out.write_text("".join(json.dumps(row) + "\n" for row in rows))


def _other_sources(out: Path) -> None:
    """The mission file was another when the second episode ran."""
    _second_row_changed(out, sources={BUMP: "0" * 64})


def _another_profile(out: Path) -> None:
    """The second episode ran as a Roomba 500."""
    _second_row_changed(out, profile="roomba500")


def _another_key(out: Path) -> None:
    """The second episode was run with ``--key found``."""
    _second_row_changed(out, **{"key:found": 3})


@pytest.mark.parametrize(
    ("options", "change", "said"),
    [
        (["--values", "1s,3s"], None,
         ":3: " + f"{BUMP} -p duration=2s is no variant of this evaluation"),
        (["--runs", "1"], None, ":2: seed 1 of"),
        (["--seed", "1"], None, ":1: seed 0 of"),
        (["--within", "1.0"], None, ":1: seed 0 started at"),
        (["--world", "corridor"], None, ":1: the episode ran in world 'empty-room', this "
         "evaluation's is 'corridor' (--world; --force writes over it)"),
        ([], _another_key, ":2: the record reports the keys ['found'], this evaluation --key []"),
        ([], _other_sources, ":2: sources differs from this evaluation's ({"),
        ([], _another_profile,
         ":2: the episode ran as profile 'roomba500', this evaluation's is 'create2'"),
    ],
)  # fmt: skip
def test_a_resume_refuses_episodes_made_otherwise(
    options: list[str],
    change: object,
    said: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each record is checked against this evaluation (its variant, its seed, the files that
    made it, its start pose, its keys): one made otherwise is named by file:line with what
    differs, exit 2, no episode runs and the file is left as it was."""
    out = tmp_path / "r.jsonl"
    assert _sweep(out, 2) == 0
    if callable(change):
        change(out)
    before = out.read_text()
    capsys.readouterr()
    if options[:1] == ["--values"]:
        assert _sweep(out, 2, "--resume", values=options[1]) == 2
    elif options[:1] == ["--runs"]:
        assert _sweep(out, int(options[1]), "--resume") == 2
    else:
        assert _sweep(out, 2, "--resume", *options) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt eval: --resume: {out}{said}" in err, err
    assert out.read_text() == before


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (["--resume", "--force"], "--resume and --force: give one"),
        (["--resume"], "--resume: give --out FILE, the results to resume"),
    ],
)
def test_resume_and_force_are_checked_before_any_episode(
    options: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [*SWEEP, "--runs", "2", *options]
    out = [] if options == ["--resume"] else ["--out", "never-made.jsonl"]
    assert main([*argv, *out]) == 2
    assert f"roomba-bt eval: {said}" in capsys.readouterr().err
    assert not Path("never-made.jsonl").exists()


@pytest.mark.parametrize(
    ("holding", "said"),
    [
        (["r.jsonl"], "the file already holds episodes"),
        (["r.jsonl.partial.jsonl"], "{folder}/r.jsonl.partial.jsonl already holds episodes"),
        (["r.jsonl", "r.jsonl.partial.jsonl"], "the file and {folder}/r.jsonl.partial.jsonl "
         "already hold episodes"),
    ],
)  # fmt: skip
def test_an_out_holding_episodes_is_named_once_and_said_in_good_grammar(
    tmp_path: Path, holding: list[str], said: str
) -> None:
    """The refusal said "--out c2.jsonl: c2.jsonl already hold(s) episodes": --out's own
    name twice, and a plural for one file. "it" or "them" as the files are one or two."""
    for name in holding:
        (tmp_path / name).write_text('{"seed": 1}\n', encoding="utf-8")
    out = str(tmp_path / "r.jsonl")
    args = argparse.Namespace(out=out, resume=False, force=False)
    refusal = refused_over(args)
    assert refusal is not None
    assert refusal.startswith(f"--out {out}: " + said.format(folder=tmp_path)), refusal
    them = "them" if len(holding) > 1 else "it"
    assert f"missing from {them} " in refusal and f"--force to write over {them}," in refusal


def test_a_resume_with_nothing_left_runs_no_episode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    assert _sweep(out, 2) == 0
    before = out.read_text()
    capsys.readouterr()
    assert _sweep(out, 2, "--resume") == 0
    assert "4 episode(s) read back" in capsys.readouterr().err
    assert out.read_text() == before


def _plotted(monkeypatch: pytest.MonkeyPatch) -> list[list[tuple[str, list[tuple[Any, ...]]]]]:
    """What each ``--plot`` is given to draw, per panel its title and each episode's seed,
    outcome, start and path (the data, not the pixels), instead of a picture."""
    import roomba_bt.evaluate.plot as plot

    drawn: list[list[tuple[str, list[tuple[Any, ...]]]]] = []

    def plot_variants(world: object, panels: Any, path: object) -> None:
        drawn.append([
            (title, [(r.seed, r.succeeded, r.start, r.trajectory) for r in results])
            for title, results in panels
        ])  # fmt: skip

    monkeypatch.setattr(plot, "plot_variants", plot_variants)
    return drawn


def test_the_plot_of_a_resumed_sweep_is_that_of_an_uninterrupted_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--plot`` after ``--resume`` drew the episodes run in that invocation alone (a
    results file kept no path), under titles counting them all; then it ran every episode
    read back again for its path. A record written under ``--plot`` keeps its path now: the
    episodes read back are drawn from it, none runs again, and the plot's data, the report
    and ``--out`` are those of one uninterrupted run."""
    drawn = _plotted(monkeypatch)
    plot = ["--plot", str(tmp_path / "ab.png")]
    assert _sweep(tmp_path / "full.jsonl", 4, *plot) == 0
    full_report = capsys.readouterr().out
    out = tmp_path / "r.jsonl"
    assert _sweep(out, 2, *plot) == 0
    capsys.readouterr()
    assert _sweep(out, 4, "--resume", *plot) == 0
    report, err = capsys.readouterr()
    full, _, resumed = drawn
    assert [len(episodes) for _, episodes in resumed] == [4, 4]
    assert all(path for _, episodes in resumed for *_, path in episodes)
    assert resumed == full
    assert report == full_report and out.read_text() == (tmp_path / "full.jsonl").read_text()
    assert "run again" not in err and "otherwise" not in err, err


def test_a_path_run_again_otherwise_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The records do not carry ``--timeout``: resumed with another, the episodes read back
    run otherwise for their paths than their records say, and stderr says which."""
    _plotted(monkeypatch)
    out = tmp_path / "r.jsonl"
    assert _sweep(out, 1, "--timeout", "1s", values="2s") == 0
    capsys.readouterr()
    assert _sweep(out, 2, "--resume", "--plot", str(tmp_path / "p.png"), values="2s") == 0
    err = capsys.readouterr().err
    assert "warning: --plot: 1 episode(s) read back ran otherwise now than their records " in err
    assert "say (seeds 0): an option the records do not carry (--timeout, " in err


@pytest.fixture
def killed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> bytes:
    """The partial file a sweep of 4 seeds per variant left when killed after its last
    record: written by the sweep itself (its removal at the end skipped), ``--out`` never
    made. Its lines are in the order the episodes finished."""
    from roomba_bt.evaluate.records import PartialResults

    with monkeypatch.context() as patched:
        patched.setattr(PartialResults, "done", lambda self, keep=False: self._file.close())
        assert _sweep(tmp_path / "k.jsonl", 4) == 0
    (tmp_path / "k.jsonl").unlink()
    capsys.readouterr()
    return (tmp_path / "k.jsonl.partial.jsonl").read_bytes()


def _last_line(data: bytes) -> tuple[bytes, bytes]:
    """The lines before the last, and the last (with its end of line)."""
    start = data.rstrip(b"\n").rfind(b"\n") + 1
    return data[:start], data[start:]


def _cut_at(last: bytes, where: str) -> int:
    """A byte offset in the last line: its first byte, just after the seed's digits (the
    seed not yet known: "3" may be the start of "31"), just after the seed's comma, half
    way, all but its closing brace."""
    seed_end = last.index(b'"seed": ') + len(b'"seed": 3')
    offsets = {"first byte": 1, "inside the seed": seed_end, "after the seed": seed_end + 1,
               "half way": len(last) // 2, "all but the brace": len(last) - 2}  # fmt: skip
    return offsets[where]


@pytest.mark.parametrize(
    "where", ["first byte", "inside the seed", "after the seed", "half way", "all but the brace"]
)
def test_a_resume_drops_the_last_record_a_kill_cut_short_and_runs_it_again(
    where: str,
    killed: bytes,
    tmp_path: Path,
    uninterrupted: dict[str, str],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A sweep killed as it wrote a record (or on a full disk) leaves its last line cut
    short, without its end of line: ``--resume`` refused the file ("not JSON ... the line
    cut short"), and a killed sweep could not be resumed. The line is dropped, said once,
    and its episode runs again: ``--out`` ends as an uninterrupted run writes it."""
    before, last = _last_line(killed)
    assert json.loads(last)["seed"] == 3  # the cut offsets name a one-digit seed
    partial = tmp_path / "k.jsonl.partial.jsonl"
    partial.write_bytes(before + last[: _cut_at(last, where)])
    assert _sweep(tmp_path / "k.jsonl", 4, "--resume") == 0
    err = capsys.readouterr().err
    said = f"roomba-bt eval: --resume: {partial}:8: "
    if where in ("first byte", "inside the seed"):
        said += ("the last record was cut short as it was written (the file ends inside it: the "
                 "sweep was killed, or the disk was full): dropped; cut before its seed, its "
                 "episode runs again unless another record holds it\n")  # fmt: skip
    else:
        said += ("the record of seed 3 was cut short as it was written (the file ends inside "
                 "it: the sweep was killed, or the disk was full): dropped; the episode runs "
                 "again\n")  # fmt: skip
    assert said in err and err.count(" cut short ") == 1, err
    assert f"7 episode(s) read back from {partial}, 1 to run" in err
    assert (tmp_path / "k.jsonl").read_text() == uninterrupted[".jsonl"]
    assert not partial.exists()


def test_a_whole_last_record_without_its_end_of_line_is_kept(
    killed: bytes, tmp_path: Path, uninterrupted: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Cut just before its end of line, the record is whole: read back, nothing runs."""
    (tmp_path / "k.jsonl.partial.jsonl").write_bytes(killed.rstrip(b"\n"))
    assert _sweep(tmp_path / "k.jsonl", 4, "--resume") == 0
    err = capsys.readouterr().err
    assert "8 episode(s) read back" in err and "0 to run" in err and "cut short" not in err
    assert (tmp_path / "k.jsonl").read_text() == uninterrupted[".jsonl"]


@pytest.mark.parametrize(
    ("bad", "said"),
    [
        ("middle", ":3:"),  # a line of the middle cut short, its end of line kept
        ("whole last", ":8:"),  # the last line cut short, but with its end of line
    ],
)
def test_a_bad_line_that_is_no_kill_trace_is_still_refused(
    bad: str, said: str, killed: bytes, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Only the last line, without its end of line, is a kill's trace: a bad line with its
    end of line (in the middle, or last) was written so, and is refused naming file:line,
    exit 2, no episode run and the file as it was."""
    lines = killed.splitlines(keepends=True)
    index = 2 if bad == "middle" else -1
    lines[index] = lines[index][: len(lines[index]) // 2] + b"\n"
    partial = tmp_path / "k.jsonl.partial.jsonl"
    partial.write_bytes(b"".join(lines))
    assert _sweep(tmp_path / "k.jsonl", 4, "--resume") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt eval: --resume: {partial}{said}") and "not JSON" in err
    assert "cut short" not in err
    assert partial.read_bytes() == b"".join(lines)
    assert not (tmp_path / "k.jsonl").exists()


@pytest.mark.parametrize("keep", [0, 2])  # the row's end of line lost, or more of it
def test_a_csv_out_cut_short_at_its_end_is_resumed(
    keep: int, tmp_path: Path, uninterrupted: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """``--out r.csv`` is written at the end; a full disk, or a kill then, cuts its last row
    (the partial file, kept, holds it: here there is none). A CSV cell cut short may read as
    another value, so a last row without its end of line is dropped whatever it reads as."""
    out = tmp_path / "r.csv"
    data = uninterrupted[".csv"].encode()
    out.write_bytes(data[: len(data) - len(b"\r\n") - keep])
    assert _sweep(out, 4, "--resume") == 0
    err = capsys.readouterr().err
    assert f"--resume: {out}:9: the record of seed 3 was cut short" in err, err
    assert "7 episode(s) read back" in err and ", 1 to run" in err
    assert out.read_text() == uninterrupted[".csv"]


def test_a_partial_file_ending_in_nul_bytes_is_resumed(
    killed: bytes, tmp_path: Path, uninterrupted: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """A power cut can leave a file's last block as NUL bytes after its last line."""
    (tmp_path / "k.jsonl.partial.jsonl").write_bytes(killed + b"\0" * 300)
    assert _sweep(tmp_path / "k.jsonl", 4, "--resume") == 0
    err = capsys.readouterr().err
    assert ":9: the last record was cut short" in err and "0 to run" in err
    assert (tmp_path / "k.jsonl").read_text() == uninterrupted[".jsonl"]


@pytest.mark.parametrize("out", [True, False])
def test_an_interrupted_evaluation_says_its_plot_is_not_drawn(
    out: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C after the second of 5 episodes: the summary and the records of the two are
    out, exit 130, and ``--plot``'s file was not made without a word; now said, with how to
    draw them all, and how to run the rest (``--resume``, given an ``--out`` to resume)."""
    from roomba_bt.evaluate.progress import ProgressBars

    def ctrl_c_at_the_second(self: ProgressBars, b: int) -> object:
        def progress(done: int, total: int, result: object) -> None:
            if done == 2:
                raise KeyboardInterrupt

        return progress

    monkeypatch.setattr(ProgressBars, "bar", ctrl_c_at_the_second)
    plot = tmp_path / "p.png"
    written = ["--out", str(tmp_path / "r.jsonl")] if out else []
    argv = ["eval", BUMP, "-p", "duration=1s", "--runs", "5", "--jobs", "1", "--wall-limit",
            "none", "--plot", str(plot), *written]  # fmt: skip
    assert main(argv) == 130
    err = capsys.readouterr().err
    said = f"roomba-bt eval: --plot {plot} not drawn: the evaluation stopped before its end"
    then = " (--resume with --plot draws every episode once the rest have run)" if out else ""
    assert f"{said}{then}\n" in err, err
    assert not plot.exists()
    left = f"the same command with --resume runs the 3 episode(s) left (--out {tmp_path}/r.jsonl"
    assert (left in err) == out
    if out:
        assert len((tmp_path / "r.jsonl").read_text().splitlines()) == 2
    if out:  # docs/evaluation.md quotes both lines, of its own files and 1963 episodes left
        names = {str(plot): "ab.png", f"{tmp_path}/r.jsonl": "ab.jsonl"}
        assert_quoted("docs/evaluation.md", "roomba-bt eval: --plot ab.png not drawn", err,
                      names=names)  # fmt: skip
        assert_quoted("docs/evaluation.md", "roomba-bt eval: the same command with --resume", err,
                      numbers=True, names=names)  # fmt: skip


def test_a_resume_names_each_file_it_read_episodes_from(
    killed: bytes, tmp_path: Path, uninterrupted: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """ "read back from k.jsonl" named ``--out`` alone, also when most of the episodes came
    from its partial file."""
    out = tmp_path / "k.jsonl"
    out.write_text("".join(uninterrupted[".jsonl"].splitlines(keepends=True)[:2]))
    (tmp_path / "k.jsonl.partial.jsonl").write_bytes(killed)
    assert _sweep(out, 4, "--resume") == 0
    said = f"8 episode(s) read back from {out} and {out}.partial.jsonl, 0 to run"
    assert said in capsys.readouterr().err
    assert out.read_text() == uninterrupted[".jsonl"]


def test_a_resume_from_another_folder_says_the_path_is_matched_as_given(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same file, named ``sub/m.yaml`` by the first run and ``m.yaml`` by a resume from
    ``sub/``, was refused naming only the record's mission: the stranger saw no difference
    (session 42, a stranger's finding). The refusal stays; it names what this evaluation
    runs and why the two differ."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "m.yaml").write_text("mission: m\ntree: {wait: 30ms}\n")
    argv = ["eval", "--no-progress", "--reproducible", "--runs"]
    monkeypatch.chdir(tmp_path)
    assert main([*argv, "1", "sub/m.yaml", "--out", "r.jsonl"]) == 0
    monkeypatch.chdir(tmp_path / "sub")
    capsys.readouterr()
    assert main([*argv, "2", "m.yaml", "--out", "../r.jsonl", "--resume"]) == 2
    err = capsys.readouterr().err
    assert (
        "--resume: ../r.jsonl:1: sub/m.yaml is no variant of this evaluation (its missions, -p, "
        "--sweep or --variant differ); this evaluation runs m.yaml (m.yaml and sub/m.yaml name "
        "a file m.yaml: a mission is matched by its path as given, so give it as the first run "
        "did, from the folder it ran in)"
    ) in err, err


def test_an_evaluation_interrupted_before_its_first_episode_says_out_holds_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C before any episode finished said ``(--out r.jsonl holds those finished)``
    of an empty file (session 42, a stranger's finding): it says it holds none."""
    import roomba_bt.evaluate.parallel as parallel

    def ctrl_c(_: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(parallel, "run_episode", ctrl_c)
    out = tmp_path / "r.jsonl"
    argv = ["eval", BUMP, "--runs", "3", "--jobs", "1", "--wall-limit", "none", "--out", str(out)]
    assert main([*argv, "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert (
        f"the same command with --resume runs the 3 episode(s) left (--out {out} holds none: "
        "no episode finished)\n"
    ) in err, err
