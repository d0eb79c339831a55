"""Results as data: records written as JSON Lines or CSV read back to the same summary."""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.evaluate import EpisodeResult, episode_specs, run_episodes, summarize
from roomba_bt.evaluate.records import (
    COLUMNS,
    CutShort,
    ResultsFileError,
    from_record,
    iter_rows,
    kept_path,
    read_results,
    read_rows,
    results_format,
    to_record,
    write_results,
)

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")


@pytest.fixture(scope="module")
def results() -> list[EpisodeResult]:
    specs = episode_specs(BUMP, world="apartment", runs=3, seed=4,
                          params=(("duration", "4s"),), timeout_s=3.0)  # fmt: skip
    return run_episodes(specs)


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_results_file_reloads_to_the_same_summary(
    tmp_path: Path, results: list[EpisodeResult], suffix: str
) -> None:
    path = tmp_path / f"results{suffix}"
    assert write_results(path, results) == 3
    again = read_results(path)
    assert summarize(BUMP, "apartment", again) == summarize(BUMP, "apartment", results)
    assert [to_record(r) for r in again] == [to_record(r) for r in results]


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_record_keeps_the_profile_and_the_undeclared_keys(
    tmp_path: Path, results: list[EpisodeResult], suffix: str
) -> None:
    """A resumed run's or ``eval --from``'s summary says the model and the undeclared-key
    warnings of episodes read back: both are columns (a writer's ``;`` and ``=`` kept in
    CSV), and a file written before them reads back as episodes of no named model and no
    warning."""
    assert {r.profile for r in results} == {"create2"}
    odd = replace(results[0], undeclared=(("secret", " by 'probe' at a;b=c.py:17"),))
    path = tmp_path / f"results{suffix}"
    write_results(path, [odd, *results[1:]])
    again = read_results(path)
    assert again[0].undeclared == odd.undeclared and again[0].profile == "create2"
    assert (
        summarize(BUMP, "apartment", again)
        .undeclared_said()[0]
        .startswith("write_key('secret') by 'probe' at a;b=c.py:17: blackboard key 'secret'")
    )
    older = {k: v for k, v in to_record(odd).items() if k not in ("profile", "undeclared_keys")}
    kept = kept_path(odd.trajectory)
    assert from_record(older) == replace(odd, undeclared=(), profile="", trajectory=kept)


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_record_keeps_the_behaviour_that_held_its_ticks(
    tmp_path: Path, results: list[EpisodeResult], suffix: str
) -> None:
    """The report's ``slowest tick ... in sleepy (...)`` warning was said on the run alone:
    no column held it, and ``eval --from`` of the records a sweep is read from afterwards
    said none. ``slowest_tick_in`` and ``slowest_tick`` hold it (a ``:`` and ``(`` kept in
    CSV), empty for an episode no behaviour held; ``--reproducible`` leaves them empty
    (measured on the host); a file written before them reads back as no such tick."""
    where = "sleepy (Sleepy.update at a;b=c.py:11)"
    held = replace(results[0], slowest_in=where, slowest_tick_s=0.24093)
    path = tmp_path / f"results{suffix}"
    write_results(path, [held, *results[1:]])
    again = read_results(path)
    assert (again[0].slowest_in, again[0].slowest_tick_s) == (where, 0.24093)
    assert [(r.slowest_in, r.slowest_tick_s) for r in again[1:]] == [("", 0.0)] * 2
    assert (
        summarize(BUMP, "apartment", again)
        .slow_said()[0]
        .startswith(
            f"slowest tick 240.93 ms in {where}, in 1 of 3 episodes: a behaviour held the ticks"
        )
    )
    record = to_record(held)
    assert (record["slowest_tick_in"], record["slowest_tick"]) == (where, 0.24093)
    assert (to_record(results[1])["slowest_tick_in"], to_record(results[1])["slowest_tick"]) == (
        "",
        None,
    )
    write_results(path, [held], reproducible=True)
    assert (read_results(path)[0].slowest_in, read_results(path)[0].slowest_tick_s) == ("", 0.0)
    older = {k: v for k, v in record.items() if k not in ("slowest_tick", "slowest_tick_in")}
    assert (from_record(older).slowest_in, from_record(older).slowest_tick_s) == ("", 0.0)


def test_a_record_has_the_columns_a_script_needs(results: list[EpisodeResult]) -> None:
    from roomba_bt.evaluate.records import COVERAGE_COLUMNS

    record = to_record(results[0])
    assert list(record) == [*COLUMNS, *COVERAGE_COLUMNS, "path"]  # run with a trace: a path
    assert list(to_record(replace(results[0], trajectory=()))) == [*COLUMNS, *COVERAGE_COLUMNS]
    assert record["seed"] == 4 and record["world"] == "apartment"
    assert record["outcome"] in ("SUCCESS", "FAILURE", "TIMEOUT")
    assert record["params"] == {"duration": "4s"}
    assert record["commands_sent"] > 0 and record["worker"]
    json.dumps(record)  # plain data


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_record_keeps_the_path_a_plot_draws(
    tmp_path: Path, results: list[EpisodeResult], suffix: str
) -> None:
    """``eval --resume --plot`` ran every episode read back again for its path: a record of
    an episode run for a plot keeps it (``path``), as the plot draws it, a few points where
    the trajectory has hundreds, none of them more than 5 mm (and the mm it is rounded to)
    from the line kept, and read back and kept again it is the same path."""
    import itertools
    import math

    traced = results[0]
    path = tmp_path / f"results{suffix}"
    write_results(path, [traced, replace(results[1], trajectory=())])
    again = read_results(path)
    kept = again[0].trajectory
    assert kept == kept_path(traced.trajectory) == kept_path(kept)
    assert again[1].trajectory == ()  # run without a trace: no path, an empty cell in CSV
    assert 2 <= len(kept) < len(traced.trajectory) / 4, (len(kept), len(traced.trajectory))
    assert kept[0] == tuple(round(v, 3) for v in traced.trajectory[0])

    def off(point: tuple[float, float]) -> float:
        """How far ``point`` is from the kept path's nearest segment."""
        far = math.inf
        for (ax, ay), (bx, by) in itertools.pairwise(kept):
            dx, dy = bx - ax, by - ay
            t = max(0.0, min(1.0, ((point[0] - ax) * dx + (point[1] - ay) * dy)
                             / ((dx * dx + dy * dy) or 1.0)))  # fmt: skip
            far = min(far, math.dist(point, (ax + t * dx, ay + t * dy)))
        return far

    assert max(off(p) for p in traced.trajectory) <= 0.005 + 0.001


def test_a_failure_names_its_stage() -> None:
    from roomba_bt.evaluate.episode import failure_stage

    assert failure_stage("find_dock(timeout=3s): no beam") == "find_dock"
    assert failure_stage("deadline of 10 s reached") == ""
    reason = "dock_time_limit(600 s): search: gave up after 600 s (stage search was running)"
    assert failure_stage(reason) == "search"
    # a while guard that stopped its node before a leaf ran names no stage (it read "stopped")
    assert failure_stage("stopped: a bumper is pressed no longer holds while 'clean' ran") == ""
    guarded = "stopped: a wheel has dropped, while 'clean' ran (stage cover was running)"
    assert failure_stage(guarded) == "cover"


def test_bad_results_files_say_where(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"allowed: \.jsonl, \.csv"):
        results_format("out.txt")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('\nnot json\n{"seed": 1}\n', encoding="utf-8")  # read as it goes: the
    with pytest.raises(ResultsFileError, match=r"bad.jsonl:2:1: not JSON"):  # first bad line
        read_results(bad)
    bad.write_text('{"seed": 1}\n', encoding="utf-8")
    with pytest.raises(ResultsFileError, match=r"bad.jsonl:1: missing column 'mission'"):
        read_results(bad)
    bad.write_text("\n" + "[" * 100_000 + "]" * 100_000 + "\n", encoding="utf-8")
    with pytest.raises(ResultsFileError, match=r"bad.jsonl:2: nested too deeply"):
        read_results(bad)  # json's RecursionError was a traceback


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_coverage_is_in_the_records_and_reads_back(tmp_path: Path, suffix: str) -> None:
    from roomba_bt.evaluate.coverage import summarize_coverage
    from roomba_bt.evaluate.records import COVERAGE_COLUMNS

    clean = str(MISSIONS / "clean.yaml")
    specs = episode_specs(clean, world="apartment", runs=2, seed=3, timeout_s=40.0)
    cleaned = run_episodes(specs)
    assert all(r.coverage is not None for r in cleaned)
    path = tmp_path / f"results{suffix}"
    write_results(
        path,
        [
            *cleaned,
            *run_episodes(episode_specs(BUMP, world="apartment", runs=1, seed=4, timeout_s=2.0)),
        ],
    )
    again = read_results(path)
    assert [r.coverage for r in again[:2]] == [r.coverage for r in cleaned]
    assert again[2].coverage is None  # no brushes, no coverage
    summary = summarize_coverage(cleaned)
    assert summary is not None  # the same, and the episode that never cleaned counted
    assert summarize_coverage(again) == replace(summary, never_cleaned=1)
    record = to_record(cleaned[0])
    assert list(record) == [*COLUMNS, *COVERAGE_COLUMNS, "path"]
    assert record["coverage"] is not None and 0 < record["coverage"] <= 1
    # cut by the 40 s timeout: what it would have cleaned by 5 min is unknown, not carried
    assert cleaned[0].outcome == "timeout" and record["coverage_5min"] is None
    assert to_record(again[2])["coverage"] is None


@pytest.mark.parametrize(
    ("outcome", "expected"),
    [
        ("timeout", (0.15, None, None)),
        ("failure", (0.15, None, None)),
        ("success", (0.15, 0.18, 0.18)),
    ],
)
def test_coverage_after_the_end_is_empty_unless_the_mission_was_done(
    results: list[EpisodeResult], outcome: str, expected: tuple[float | None, ...]
) -> None:
    """An episode cut by --timeout 6min had coverage_10min == coverage_20min == its last
    value, which pandas then mixed with measured 10-minute values: after the end it is empty,
    unless the mission succeeded (done: its final coverage would not change)."""
    from dataclasses import replace

    from roomba_bt.evaluate.episode import Coverage

    curve = tuple((30.0 * i, 0.015 * i) for i in range(13))  # 0..360 s: 0.15 at 5 min
    cleaned = Coverage("", 0.18, curve, 0.18, (), 0.0, 360.0)
    ended = replace(results[0], outcome=outcome, time_s=360.0, coverage=cleaned)
    record = to_record(ended)
    got = (record["coverage_5min"], record["coverage_10min"], record["coverage_20min"])
    assert tuple(None if v is None else round(v, 9) for v in got) == expected
    # and it reads back, and writes again, the same (JSON null, an empty CSV cell)
    assert to_record(from_record(json.loads(json.dumps(record)))) == record


def test_records_carry_no_binary_noise(tmp_path: Path) -> None:
    """--json was tidied (27.885) but the records said 27.884999999999998: every measured
    float is cut to ten significant digits where the episode is measured, so the JSONL and
    CSV files read like the summary and still read back to the same episodes."""
    specs = episode_specs(BUMP, world="corridor", runs=4, seed=0,
                          params=(("duration", "5s"),), timeout_s=10)  # fmt: skip
    ran = run_episodes(specs)
    path = tmp_path / "r.jsonl"
    write_results(path, ran)
    for line in path.read_text().splitlines():
        for column, value in json.loads(line).items():
            if isinstance(value, float):
                assert len(repr(abs(value)).replace(".", "").lstrip("0")) <= 10, (column, value)
    assert [to_record(r) for r in read_results(path)] == [to_record(r) for r in ran]


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_how_the_mission_ended_is_in_the_records(tmp_path: Path, suffix: str) -> None:
    """``mission_said``: the mission's last words (a patrol's laps done or its docking), read
    back as they were; a file written before the column reads back as nothing said."""
    specs = episode_specs(str(MISSIONS / "patrol.yaml"), world="empty-room", runs=1, seed=1,
                          params=(("laps", "1"),), timeout_s=300.0)  # fmt: skip
    ran = run_episodes(specs)
    assert ran[0].said.startswith("patrol done")
    path = tmp_path / f"results{suffix}"
    write_results(path, ran)
    assert read_results(path)[0].said == ran[0].said
    older = to_record(ran[0])
    del older["mission_said"]
    assert from_record(older).said == ""


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_last_record_cut_inside_a_character_is_cut_short_not_bad_utf8(
    tmp_path: Path, results: list[EpisodeResult], suffix: str
) -> None:
    """A kill between the bytes of a character (a ``mission_said`` in French) leaves a file
    that is not UTF-8 at its very end: given a list, the reader drops that record as cut
    short, as any other; without one (``read_results``) it is refused as before. Bytes not
    UTF-8 anywhere else are refused either way."""
    said = replace(results[-1], said="arrivé à la base")
    path = tmp_path / f"r{suffix}"
    write_results(path, [*results[:-1], said])
    data = path.read_bytes().replace(b"\\u00e9", "é".encode())  # JSON as pandas may write it
    path.write_bytes(data[: data.index("é".encode()) + 1])
    cut: list[CutShort] = []
    assert [row[2].seed for row in read_rows(path, cut)] == [4, 5]
    assert cut == [CutShort(str(path), 3 if suffix == ".jsonl" else 4, 6, BUMP)]
    with pytest.raises(ResultsFileError, match="not UTF-8 text"):
        read_results(path)
    path.write_bytes(data[:20] + b"\xff" + data[20:])
    with pytest.raises(ResultsFileError, match=r"not UTF-8 text \(byte 0xff\)"):
        read_rows(path, [])


def test_a_number_too_long_to_read_is_placed_not_said_in_pythons_words(
    tmp_path: Path, results: list[EpisodeResult]
) -> None:
    """A seed of 5,000 digits was ``--from Exceeds the limit (4300 digits) for integer string
    conversion ...; use sys.set_int_max_str_digits()``: no file, no line, a programmer's
    advice. A whole line and one a kill cut short alike."""
    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    long = lines[1].replace('"seed": 5,', f'"seed": {"9" * 5000},')
    path.write_text(lines[0] + long + lines[2])
    with pytest.raises(ResultsFileError) as said:
        read_rows(path, [])
    assert str(said.value) == (
        f"{path}:2: a number of more than 4,300 digits; its numbers are a few digits long"
    )
    path.write_text(lines[0] + lines[1] + long[:-30])  # the last line, cut: left out
    cut: list[CutShort] = []
    assert [row[2].seed for row in read_rows(path, cut)] == [4, 5]
    assert cut == [CutShort(str(path), 3, None, BUMP)]


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_a_pipe_given_as_results_is_never_opened(
    tmp_path: Path, suffix: str, pipe_read: Callable[..., tuple[object, bool]]
) -> None:
    """``eval --from results.jsonl`` (a pipe) and ``eval --out results.jsonl --resume`` waited
    in open() for a writer, for ever; a link to /dev/zero was read whole, a MemoryError."""
    from roomba_bt.cli.eval_resume import earlier_files

    fifo = tmp_path / f"results{suffix}"
    os.mkfifo(fifo)
    refused, opened = pipe_read(fifo, lambda: read_rows(fifo, []))
    assert (str(refused), opened) == (
        f"{fifo}: a device or a pipe, not a file; expected results as eval --out writes them "
        "(.jsonl or .csv)",
        False,
    )
    assert pipe_read(fifo, lambda: earlier_files(str(fifo))) == ([], False)


@pytest.mark.parametrize(
    ("column", "value", "said"),
    [
        ("mission_time", "NaN", "found NaN; expected a finite number"),
        (
            "mission_time",
            "1e400",
            "found Infinity (a number too large to hold, such as 1e400); expected a finite number",
        ),
        ("mission", "5", "found 5; expected a string"),
        ("params", "[1]", "found [1]; expected an object of name: value text"),
        ("params", '{"side": 10}', 'found {"side": 10}; expected an object of name: value'),
        ("seed", "true", "found true; expected a whole number"),
        ("seed", "5.5", "found 5.5; expected a whole number"),
        ("fell", '"no"', "found 'no'; expected true or false"),
        ("outcome", '"\\u001b[2J"', "found '\\x1b[2J'; expected the outcome's word"),
        ("world_sha256", "7", "found 7; expected a string or null"),
        ("wall_time", "NaN", "found NaN; expected a finite number or null"),
    ],
)
def test_each_column_of_a_json_record_is_checked_as_the_writer_wrote_it(
    tmp_path: Path, results: list[EpisodeResult], column: str, value: str, said: str
) -> None:
    """``eval --from`` summarised ``"mission_time": NaN`` as "median nan s", ``"mission":
    5`` as a variant "5" and ``"params": [1]`` as ``-p [1]=``: each is refused at its line
    with the column, what was found and what is allowed."""
    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    record = json.loads(lines[1])
    record[column] = "PLACE"
    bad = json.dumps(record).replace('"PLACE"', value)
    path.write_text(lines[0] + bad + "\n" + lines[2])
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    assert str(refused.value).startswith(f"{path}:2: bad value (column {column!r}: {said}")


@pytest.mark.parametrize(
    ("column", "cell", "said"),
    [("mission_time", "nan", "found 'nan'; expected a finite number"),
     ("end_x", "1e400", "found '1e400'; expected a finite number"),
     ("docked", "yes", "found 'yes'; expected true or false (True or False in CSV)")],
)  # fmt: skip
def test_a_csv_cell_is_read_as_its_column_holds_it(
    tmp_path: Path, results: list[EpisodeResult], column: str, cell: str, said: str
) -> None:
    """A CSV cell is text: ``nan`` read as NaN, ``yes`` as False, before."""
    import csv

    path = tmp_path / "r.csv"
    write_results(path, results)
    with path.open(newline="") as written:
        rows = list(csv.DictReader(written))
    rows[0][column] = cell
    with path.open("w", newline="") as out:
        writer = csv.DictWriter(out, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    assert str(refused.value) == f"{path}:2: bad value (column {column!r}: {said})"


def test_eval_from_reads_a_file_as_a_stream_its_memory_not_growing_with_it(
    tmp_path: Path, results: list[EpisodeResult]
) -> None:
    """``eval --from`` read the whole file, decoded it whole and kept every line's record:
    200,000 lines of one episode took 2.2 GB. The memory traced while the report's
    episodes are read is now about the same for 400 lines as for 4,000 (it was 10 times)."""
    import tracemalloc

    from roomba_bt.cli.eval_from import read_variants

    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)

    def peak(copies: int) -> int:
        path.write_text("".join(lines * copies))
        tracemalloc.start()
        try:
            variants = read_variants([str(path)], [])
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
            assert [[r.seed for r in rs] for _, _, rs in variants] == [[4, 5, 6]]

    peak(1)  # the modules it imports the first time, not counted
    small, large = peak(130), peak(1300)
    assert large < 2 * small, (small, large)  # before: 4.2 MB and 42.5 MB
    rows = iter_rows(path)  # read as the caller goes: the first record before the file
    assert next(rows)[0] == 1
    rows.close()


def test_a_results_line_holding_a_key_twice_is_refused_at_its_line(
    tmp_path: Path, results: list[EpisodeResult]
) -> None:
    """JSON keeps the last of two ``"seed"``: the record was read as an episode of seed 9."""
    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text(lines[0] + lines[1].replace('"seed": 5,', '"seed": 5, "seed": 9,'))
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    assert str(refused.value) == (
        f'{path}:2: the key "seed" twice in one object; expected each key once, as eval --out '
        "writes it"
    )


def test_a_results_line_longer_than_a_records_is_refused_before_it_is_read_whole(
    tmp_path: Path, results: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``eval --from`` and ``--resume`` read a results line whole, however long (a 100 MB
    line took 334 MB): a line longer than a record's longest (``MAX_RECORD_LINE``, made
    small here) is refused at its line with the limit, only that much of it read."""
    import tracemalloc

    from roomba_bt.runtime import recording

    monkeypatch.setattr(recording, "MAX_RECORD_LINE", 10_000)
    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    long = lines[1].replace('"mission_said": ""', '"mission_said": "' + "x" * 5_000_000 + '"')
    path.write_text(lines[0] + long + lines[2])
    tracemalloc.start()
    try:
        with pytest.raises(ResultsFileError) as refused:
            read_rows(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert str(refused.value).startswith(
        f"{path}:2: a line of more than 10,000 characters (the rest of it not read); allowed: "
    )
    assert peak < 1_000_000, peak  # the 5 MB line was read whole
    path.write_text("".join(lines).replace("\n", "\r\n"))  # a line's end is no part of it
    assert [row[0] for row in read_rows(path)] == [1, 2, 3]


@pytest.mark.parametrize(
    ("column", "value", "said"),
    [
        ("bumps", "-3", "found -3; expected a whole number (0 or more)"),
        ("mission_time", "-5.0", "found -5.0; expected a finite number (0 or more)"),
        ("cpu_time", "-0.5", "found -0.5; expected a finite number or null (0 or more)"),
        ("falls", "3", "found 3; expected the sum of falls_by_cause's counts, 0"),
        ("hazard_falls", "1", "found 1; expected the sum of falls_by_cause's counts but the "
         "charger's, 0"),
        ("falls_by_cause", '{"cliff": -1}', 'found {"cliff": -1}; expected an object of cause: '
         "count"),
        ("falls_by_cause", '{"cliff": "2"}', 'found {"cliff": "2"}; expected an object of '
         "cause: count"),
    ],
)  # fmt: skip
def test_a_results_value_out_of_its_columns_range_is_refused(
    tmp_path: Path, results: list[EpisodeResult], column: str, value: str, said: str
) -> None:
    """``"bumps": -3`` was summarised as -3.0 bumps an episode and ``"falls": 3`` with no
    cause as falls the table of causes did not have: each column's range is the writer's
    table's (``COLUMNS``), refused at its line with what was found and what is allowed."""
    path = tmp_path / "r.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    record = json.loads(lines[1])
    record[column] = "PLACE"
    path.write_text(lines[0] + json.dumps(record).replace('"PLACE"', value) + "\n")
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    assert str(refused.value).startswith(f"{path}:2: bad value (column {column!r}: {said}")


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
@pytest.mark.parametrize(
    ("column", "value", "said"),
    [
        ("coverage", 1.5, "found 1.5; expected a finite number or null (from 0 to 1)"),
        ("coverage_overall", -0.1, "found -0.1; expected a finite number or null (from 0 to 1)"),
        ("longest_idle", -1.0, "found -1.0; expected a finite number or null (0 or more)"),
        ("coverage_by_area", {"kitchen": 1.25}, 'found {"kitchen": 1.25}; expected an object '
         "of area: fraction, or null (from 0 to 1)"),
        ("coverage_curve", [[30.0, 2.0]], "found [30.0, 2.0]; expected a list of [t, fraction],"
         " or null (t 0 or more, fraction from 0 to 1)"),
    ],
)  # fmt: skip
def test_a_coverage_out_of_its_range_is_refused_in_either_format(
    tmp_path: Path, suffix: str, column: str, value: Any, said: str
) -> None:
    """A coverage over 1 was summarised as 150 % of the floor cleaned."""
    path = tmp_path / f"r{suffix}"
    write_results(path, [_cleaned()])
    if suffix == ".jsonl":
        record = json.loads(path.read_text())
        record[column] = value
        path.write_text(json.dumps(record) + "\n")
    else:
        import csv

        with path.open(newline="") as written:
            row = next(csv.DictReader(written))
        row[column] = _csv_cell(value)
        with path.open("w", newline="") as out:
            writer = csv.DictWriter(out, fieldnames=list(row))
            writer.writeheader()
            writer.writerow(row)
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    if suffix == ".csv":  # a cell is text: said as the text it is
        said = said.replace('{"kitchen": 1.25}', '{"kitchen": "1.25"}').replace(
            "[30.0, 2.0]", '["30.0", "2.0"]'
        )
        said = re.sub(r"found (-?[\d.]+);", r"found '\1';", said)
    assert (
        str(refused.value)
        == f"{path}:{2 if suffix == '.csv' else 1}: bad value (column {column!r}: {said})"
    )


def test_a_coverage_by_area_is_numbers_in_json_not_their_text(tmp_path: Path) -> None:
    """``"coverage_by_area": {"kitchen": "0.5"}`` was read as the fraction 0.5: JSON Lines
    hold each area's fraction as a number, as eval --out writes it."""
    path = tmp_path / "r.jsonl"
    write_results(path, [_cleaned()])
    record = json.loads(path.read_text())
    record["coverage_by_area"] = {"hall": 0.25, "kitchen": "0.5"}
    path.write_text(json.dumps(record) + "\n")
    with pytest.raises(ResultsFileError) as refused:
        read_rows(path)
    assert str(refused.value) == (
        f'{path}:1: bad value (column \'coverage_by_area\': found {{"kitchen": "0.5"}}; '
        "expected an object of area: fraction, or null)"
    )
    record["coverage_by_area"] = {"hall": 0.25, "kitchen": 0.5}  # as written: it reads
    path.write_text(json.dumps(record) + "\n")
    assert read_rows(path)[0][2].coverage is not None


def _cleaned() -> EpisodeResult:
    """An episode that cleaned (its coverage columns written), of no run."""
    from roomba_bt.evaluate.episode import Coverage

    coverage = Coverage(area="", final=0.5, curve=((0.0, 0.0), (30.0, 0.5)), overall=0.5,
                        by_area=(("hall", 0.25), ("kitchen", 0.5)), longest_idle_s=3.0,
                        cleaning_s=40.0)  # fmt: skip
    return EpisodeResult(
        seed=1, outcome="success", reason="", time_s=40.0, wall_s=0.1, ticks=600,
        start=(1.0, 1.0, 0.0), end=(2.0, 1.0, 90.0), bumps=0, contact_steps=(), docked=False,
        charging=False, cliffs=0, fell=False, violations=0, loops=0.0, longest_stall_s=1.0,
        mission="clean.yaml", world="apartment", coverage=coverage,
    )  # fmt: skip


def _csv_cell(value: Any) -> str:
    """A value as eval --out writes it in a CSV cell."""
    if isinstance(value, dict):
        return ";".join(f"{k}={v!r}" for k, v in value.items())
    if isinstance(value, list):
        return ";".join(f"{t!r}:{c!r}" for t, c in value)
    return repr(value)


def test_eval_from_reads_a_line_met_again_to_the_character_once(
    tmp_path: Path, results: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    """200,000 copies of one line took ``eval --from`` 23 s of CPU: each was parsed,
    checked and made an episode, to be found the same as the first. A line the same to the
    character as one taken is the same record: it is made an episode once, in any file;
    one that differs (another run's wall-clock time) is still read and compared."""
    from roomba_bt.cli.eval_from import read_variants
    from roomba_bt.evaluate import records

    made: list[int] = []
    real = records.from_record
    monkeypatch.setattr(records, "from_record", lambda row: made.append(1) or real(row))
    path, again = tmp_path / "r.jsonl", tmp_path / "again.jsonl"
    write_results(path, results)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines * 100))
    other = json.loads(lines[0]) | {"wall_time": 99.0}  # the same episode, run again
    again.write_text(lines[2] + json.dumps(other) + "\n")
    variants = read_variants([str(path), str(again)], [])
    assert [[r.seed for r in rs] for _, _, rs in variants] == [[4, 5, 6]]
    assert len(made) == 4, len(made)  # three lines, and the one of another wall time


def test_episodes_read_back_share_their_words(tmp_path: Path, results: list[EpisodeResult]) -> None:
    """``--resume`` and ``--from`` keep the episodes they read until the report: each record
    was made of its line's own strings (mission, world, outcome, reason, worker...), 1.5 KB
    a record of a 2 000-line file. They are shared as a result from a worker's are: about
    1 KB (on CPython 3.11)."""
    import tracemalloc

    path = tmp_path / "r.jsonl"
    write_results(path, [replace(results[i % 3], seed=i) for i in range(2000)])
    read_results(path)  # what it imports the first time, not counted
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        again = read_results(path)
        per_record = (tracemalloc.get_traced_memory()[0] - before) / len(again)
    finally:
        tracemalloc.stop()
    assert again[0].mission is again[3].mission and again[0].reason is again[3].reason
    assert per_record < 1300, per_record
