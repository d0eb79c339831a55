"""`roomba-bt run` in-process on the virtual clock: exit codes and messages, never a traceback."""

from __future__ import annotations

import argparse
import bz2
import errno
import json
import logging
import lzma
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main, run_cmd
from roomba_bt.cli.arguments import parse_timeout
from roomba_bt.evaluate.episode import failure_stage
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.display import MissionClockFormatter
from roomba_bt.runtime.recording import load_record

from .simrun import SHORT_DRIVE, SPIN, write_mission

MISSION = SHORT_DRIVE


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path, MISSION, "short.yaml")


def _run_file(
    folder: Path, name: str, text: str, *options: str, plugins: dict[str, str] | None = None
) -> int:
    """``roomba-bt run FILE --fast OPTIONS``, ``text`` written first as ``folder/name`` with
    its ``plugins`` (file name: source) beside it: the exit code."""
    return main(["run", str(write_mission(folder, text, name, plugins)), "--fast", *options])


def test_run_fast_succeeds(mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out
    assert "safe stop    sent drive, motors, pause_resume_stream, start" in out


def test_the_summary_says_when_the_run_started_in_local_time(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A cron job's runs, appended to one log file every morning, each line in mission time,
    could not be told apart: the summary says the start's date and time, local, ISO 8601
    with its offset; ``--reproducible`` leaves it out, as its other wall-clock lines."""
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    [started] = [line for line in capsys.readouterr().out.splitlines() if "started" in line]
    assert re.fullmatch(r"started      \d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[+-]\d\d:\d\d", started)
    assert main(["run", str(mission), "--fast", "--display", "none", "--reproducible"]) == 0
    assert "started" not in capsys.readouterr().out


def test_parameter_from_the_command_line(
    mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "r.jsonl"
    code = main(["run", str(mission), "--fast", "--display", "none", "-p", "speed=150mm/s",
                 "--record", str(record)])  # fmt: skip
    assert code == 0
    assert load_record(record).header["parameters"] == {"speed": "150mm/s"}
    assert bytes([137, 0, 150]) in load_record(record).outbound


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-p", "speed"], "expected NAME=VALUE"),
        (["-p", "speed=900mm/s"], "900 mm/s"),
        (["--timeout", "soon"], "--timeout 'soon'"),
        (["--timeout", "nan"], "--timeout 'nan': must be a finite duration"),  # was no timeout
        (["--timeout", "1e999s"], "1e999 is too large a number for a duration"),
        (
            ["--timeout", "30min1h"],
            "'30min1h': a duration in several units is "
            "written the largest unit first, each once, e.g. 1h30min",
        ),
        (["--world", "no-such-world"], "no-such-world"),
        (["--baud", "19200", "-p", "speed=100mm/s"], None),
    ],
)
def test_bad_input_is_exit_2_with_a_message(
    mission: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str | None
) -> None:
    code = main(["run", str(mission), "--fast", "--display", "none", *args])
    err = capsys.readouterr().err
    if message is None:  # 19200 baud: the runtime's packets alone still fit (28 bytes)
        assert code == 0, err
        return
    assert code == 2, err
    assert message in err
    assert "Traceback" not in err


def test_run_takes_the_simulated_encoders_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """eval had --odometry-error and run did not: a bad episode under encoder error could be
    looked at only through eval --runs 1 --plot. With it the mission's odometry is off, so a
    drive of 1 m by the encoders ends elsewhere; with --port it is a usage error."""
    drive = tmp_path / "metre.yaml"
    drive.write_text("tree:\n  sequence:\n    - mode: safe\n    - drive: {distance: 1 m}\n")
    world = tmp_path / "room.yaml"
    world.write_text("rooms: [{rect: [0, 0, 4, 3]}]\nrobot: {start: {at: [1, 1.5], heading: 0}}\n")
    ended = []
    for error in ("0", "0.2"):
        argv = ["run", str(drive), "--fast", "--display", "none", "--world", str(world),
                "--seed", "4"]  # fmt: skip
        assert main([*argv, "--odometry-error", error]) == 0
        out = capsys.readouterr().out
        ended.append(next(line for line in out.splitlines() if "simulator    ended" in line))
    assert ended[0] == "simulator    ended at (2.00, 1.50) m, off the dock"
    assert ended[1] != ended[0], ended  # the seed's encoders count 13 % short
    code = main(["run", str(drive), "--port", "loop://", "--odometry-error", "0.01"])
    err = capsys.readouterr().err
    assert code == 2
    assert "--battery and --odometry-error are for the simulator: drop them or --port" in err


def test_invalid_mission_reports_file_line_col(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = "tree:\n  sequence:\n    - drive: {velocity: 600 mm/s}\n"
    assert _run_file(tmp_path, "bad.yaml", bad) == 2
    err = capsys.readouterr().err
    assert "bad.yaml:3:" in err
    assert "600" in err


def test_missing_mission_file_is_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "/no/such/mission.yaml", "--fast"]) == 2
    assert "no such mission file" in capsys.readouterr().err


def test_timeout_is_exit_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _run_file(tmp_path, "spin.yaml", SPIN, "--display", "none", "--timeout", "2s") == 1
    assert "TIMEOUT" in capsys.readouterr().out


def test_a_planned_shift_ends_at_its_duration_as_success_and_replays_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A nightly shift of 8 h ended by --timeout was TIMEOUT, exit 1 ("a person looks"),
    every night. ``--duration`` is its planned length: SUCCESS, exit 0, said so; its record
    replays up to that end and stops there, as at a time limit."""
    record = tmp_path / "shift.jsonl"
    argv = ["--display", "none", "--duration", "2s", "--record", str(record)]
    assert _run_file(tmp_path, "spin.yaml", SPIN, *argv) == 0
    assert (
        "outcome      SUCCESS (--duration 2 s of mission time reached in drive (the planned "
        "end))" in capsys.readouterr().out
    )
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "the recorded run ended in success at t=2.0" in out
    assert "the tree wrote the same" in out and "as the recorded run" in out


def test_a_duration_and_a_timeout_together_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["--duration", "8h", "--timeout", "9h"]
    assert _run_file(tmp_path, "spin.yaml", SPIN, *argv) == 2
    assert "--duration 8h and --timeout 9h: give one" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["dock.yaml", "bump-and-turn.yaml"])
def test_a_run_recorded_on_the_virtual_clock_replays_byte_for_byte(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On the virtual clock a reply and its request share a time stamp; the replay gave the
    start-up's mode reply to the read that drains the line before the query, and then
    failed ("answered 19 for its OI mode"). A reply now waits for its request."""
    mission = Path(__file__).resolve().parents[2] / "missions" / name
    record = tmp_path / "run.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main([*argv, "-p", "duration=3s"] if name.startswith("bump") else argv) == 0
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out
    assert "the tree wrote the same" in out


def test_a_replay_keeps_no_robot_awake(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """It said "no modem line to pulse BRC on this link: a robot left in Passive sleeps after
    5 minutes": there is no robot in a replay."""
    import logging

    from roomba_bt.mission import load_mission
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    mission = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"
    record = tmp_path / "run.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    loaded = load_record(record)
    caplog.set_level(logging.INFO, logger="roomba_bt")
    summary, transport = replay_record(
        loaded, load_mission(mission), profile=CREATE2, baud=115200, name="run.jsonl",
        packets=tuple(loaded.header["packets"]),
    )  # fmt: skip
    assert transport.first_difference() is None and summary.outcome.value == "success"
    assert not [r for r in caplog.records if r.name == "roomba_bt.robot.wake"]


def test_a_replay_whose_tree_stops_short_of_the_record_ends_at_that_difference(
    tmp_path: Path,
) -> None:
    """The robot's recorded bytes wait for the bytes the tree wrote before them (a reply comes
    after its request); a tree that does not write them (its mission changed since, a pause or
    a reload in the run) never got them, never ticked again and the replay spun for ever at
    100 % CPU. A subprocess, so the old hang is a timeout, not a stuck suite."""
    drive, wait = tmp_path / "drive.yaml", tmp_path / "wait.yaml"
    drive.write_text(SPIN)
    wait.write_text("mission: waiting\ntree:\n  sequence:\n    - mode: safe\n    - wait: 10s\n")
    record = tmp_path / "run.jsonl"
    run = ["run", str(drive), "--fast", "--display", "none", "--timeout", "2s"]
    assert main([*run, "--record", str(record)]) == 1
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "replay", str(record), "--mission", str(wait)],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "replay: first difference at mission time" in done.stdout
    assert "expected Drive (137)" in done.stdout and ", sent nothing" in done.stdout


def test_replay_of_a_malformed_record_is_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "bad.jsonl"
    record.write_text('{"format": "roomba-bt-record", "version": 1, "packets": [7]}\n{"t": "x"}\n')
    assert main(["replay", str(record)]) == 2
    err = capsys.readouterr().err
    assert "bad.jsonl:2:" in err


#: the two commands that read a record; ``monitor RECORD`` needs the monitor extra
READERS = ["replay", pytest.param("monitor", marks=pytest.mark.extra("monitor"))]
HEADER = {"format": "roomba-bt-record", "version": 1, "profile": "create2", "baud": 115200,
          "mission": "dock", "parameters": {}, "packets": [7, 35]}  # fmt: skip


@pytest.mark.parametrize("command", READERS)
@pytest.mark.parametrize(
    ("field", "value", "said"),
    [("baud", "fast", "header field 'baud' is 'fast'; allowed: the OI's rates 300, "),
     ("baud", 12345, "header field 'baud' is 12345"),
     ("profile", 3, "header field 'profile' is 3; known profiles: create2, roomba600, roomba500"),
     ("mission", ["dock"], "header field 'mission' is ['dock']"),
     ("parameters", ["speed"], "header field 'parameters' is ['speed']; expected {name: value}"),
     ("packets", [7, "35"], "header field 'packets' holds ['35'], not sensor packet ids"),
     ("packets", [7, 99], "header field 'packets' holds [99]"),
     ("packets", [], 'the header lists no stream packets ("packets")'),
     # 100,000 ids were replayed up to the stream's request: an ERROR, exit 1
     ("packets", [7] * 100_000, "header field 'packets' lists 100,000 ids; allowed: at most 255"),
     # each unknown id once, the first ten (100,000 of them were said whole: 500 KB)
     ("packets", [7, *range(300, 100_000)], "header field 'packets' holds [300, 301, 302, "
      "303, 304, 305, 306, 307, 308, 309] and 99,690 more, not sensor packet ids")],
)  # fmt: skip
def test_a_hand_edited_header_is_named_field_by_field(
    command: str,
    field: str,
    value: object,
    said: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``"baud": "fast"`` was a ValueError traceback out of both commands."""
    record = tmp_path / "edited.jsonl"
    chunk = '{"t": 0.0, "d": "out", "b": "80"}'
    record.write_text(json.dumps({**HEADER, field: value}) + f"\n{chunk}\n")
    assert main([command, str(record)]) == 2
    out, err = capsys.readouterr()
    assert f"{record}:1: {said}" in err
    assert "Traceback" not in out + err


@pytest.mark.parametrize("command", READERS)
def test_a_number_too_long_to_read_is_placed_not_an_internal_error(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A header's number of 5,000 digits was ``internal error: ValueError: Exceeds the limit
    (4300 digits) ...``, exit 70; in a chunk, Python's advice
    (``sys.set_int_max_str_digits()``) in the malformed chunk's words."""
    record = tmp_path / "long.jsonl"
    header = json.dumps(HEADER).replace('"version": 1', f'"version": {"1" * 5000}')
    record.write_text(header + '\n{"t": 0.0, "d": "out", "b": "80"}\n')
    assert main([command, str(record)]) == 2
    said = "a number of more than 4,300 digits; its numbers are a few digits long"
    assert capsys.readouterr().err.endswith(f"{record}:1: header holds {said}\n")
    record.write_text(json.dumps(HEADER) + f'\n{{"t": {"1" * 5000}, "d": "out", "b": "80"}}\n')
    assert main([command, str(record)]) == 2
    assert f"{record}:2: malformed chunk ({said}); expected" in capsys.readouterr().err


@pytest.mark.parametrize("line", [1, 2])
def test_a_line_nested_thousands_deep_is_placed_not_a_traceback(
    line: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "deep.jsonl"
    deep = "[" * 100_000 + "]" * 100_000
    record.write_text("\n".join([json.dumps(HEADER), deep] if line == 2 else [deep]) + "\n")
    assert main(["replay", str(record)]) == 2
    out, err = capsys.readouterr()
    assert f"{record}:{line}: " in err and "nested too deeply" in err
    assert "Traceback" not in out + err


@pytest.mark.parametrize("t", ["NaN", "-5", "Infinity", "0.5"])
def test_a_time_that_is_not_finite_or_goes_back_is_placed(
    t: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "edited.jsonl"
    chunks = ['{"t": 0.0, "d": "out", "b": "80"}', '{"t": 1.0, "d": "out", "b": "80"}',
              f'{{"t": {t}, "d": "in", "b": "01"}}']  # fmt: skip
    record.write_text("\n".join([json.dumps(HEADER), *chunks]) + "\n")
    assert main(["replay", str(record)]) == 2
    assert f"{record}:4: time " in capsys.readouterr().err


@pytest.mark.parametrize("command", READERS)
def test_a_record_with_a_byte_that_is_not_utf8_is_placed_not_a_traceback(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "damaged.jsonl"  # (the header whole: it is read first)
    record.write_bytes(json.dumps(HEADER).encode() + b'\n{"t": 0.0, \xff}\n')
    assert main([command, str(record)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"roomba-bt {command}: {record}:2:12: byte 0xff, not UTF-8 text; expected the JSON "
        "lines of a roomba-bt-record file (run --record)"
    )


@pytest.mark.parametrize("command", READERS)
@pytest.mark.parametrize(
    ("packed", "said"),
    [(lambda text: bz2.compress(text), "a bzip2-compressed file; records are read plain or "
      "gzip-compressed (.gz): bunzip2 it first"),
     (lambda text: lzma.compress(text), "an xz-compressed file; records are read plain or "
      "gzip-compressed (.gz): unxz it first"),
     (lambda text: text.decode().encode("utf-16"), "UTF-16 text (saved again by an editor?); "
      "records are UTF-8 JSON lines, as run --record writes them")],
)  # fmt: skip
def test_a_record_packed_otherwise_says_what_it_is(
    command: str,
    packed: Callable[[bytes], bytes],
    said: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each was ``1:1: byte 0xff, not UTF-8 text`` (0x42, 0xfd): nothing of what the file
    was, or what to do."""
    record = tmp_path / "packed.jsonl"
    record.write_bytes(
        packed(json.dumps(HEADER).encode() + b'\n{"t": 0.0, "d": "out", "b": "80"}\n')
    )
    assert main([command, str(record)]) == 2
    assert capsys.readouterr().err.strip() == f"roomba-bt {command}: {record}:1: {said}"


def test_a_header_an_editor_began_with_a_bom_is_read_and_a_boolean_version_is_not(
    tmp_path: Path,
) -> None:
    """Notepad's byte-order mark was ``header is not JSON: Unexpected UTF-8 BOM (decode using
    utf-8-sig)``, Python's advice; ``"version": true`` was read as version 1 (True == 1)."""
    record = tmp_path / "edited.jsonl"
    chunk = '\n{"t": 0.0, "d": "out", "b": "80"}\n'
    record.write_text("\ufeff" + json.dumps(HEADER) + chunk, encoding="utf-8")
    assert load_record(record).header["version"] == 1
    record.write_text(json.dumps({**HEADER, "version": True}) + chunk)
    with pytest.raises(ValueError, match=":1: record version True; this roomba-bt reads"):
        load_record(record)


def test_a_file_that_is_no_record_says_what_a_record_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``replay m.yaml`` (the mission given for its record) said ``header is not JSON:
    Expecting value``, and a JSON file of another kind ``not a roomba-bt-record file (header
    format field)``: neither what was found nor what a record is (session 42, a stranger's
    finding)."""
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\ntree: {wait: 1s}\n")
    other = tmp_path / "other.jsonl"
    other.write_text('{"format": "something-else", "version": 1}\n')
    wanted = "expected a file written by run --record (its first line a JSON header"
    assert main(["replay", str(mission)]) == 2
    err = capsys.readouterr().err
    assert f"{mission}:1:1: not a record: its first line is not JSON (Expecting value); " in err
    assert wanted in err and "Traceback" not in err
    assert main(["replay", str(other)]) == 2
    err = capsys.readouterr().err
    assert "not a roomba-bt-record file: its header's format is 'something-else'; " in err
    assert wanted in err


def test_a_record_is_read_a_line_at_a_time_and_a_device_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``replay /dev/zero`` was a MemoryError traceback, and a 1 GB file of zeros took 2 GB of
    memory: the file was read whole before its first line was looked at. A device is refused
    before it is opened, a line longer than any record's before more of it is read."""
    from roomba_bt.runtime import recording

    monkeypatch.setattr(recording, "MAX_RECORD_LINE", 1000)
    zeros = tmp_path / "zeros.jsonl"
    with zeros.open("wb") as file:
        file.truncate(1 << 30)  # sparse: no disk used
    monkeypatch.setattr(Path, "read_text", None)  # the whole file is never read
    assert main(["replay", str(zeros)]) == 2
    assert main(["replay", "/dev/zero"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"roomba-bt replay: {zeros}:1: a line of more than 1,000 bytes; a roomba-bt-record file's "
        "lines are a few KB (run --record writes them)",
        "roomba-bt replay: /dev/zero: not a regular file; a record is a file run --record wrote",
    ]


@pytest.mark.parametrize("command", READERS)
def test_a_pipe_given_as_a_record_is_refused_before_it_is_opened(
    command: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    pipe_read: Callable[..., tuple[object, bool]],
) -> None:
    """``monitor fifo.jsonl`` waited in ``open()`` for a writer, for ever: the size it says
    before reading a long record was asked of the pipe first."""
    fifo = tmp_path / "fifo.jsonl"
    os.mkfifo(fifo)
    assert pipe_read(fifo, lambda: main([command, str(fifo)])) == (2, False)
    assert capsys.readouterr().err.splitlines() == [
        f"roomba-bt {command}: {fifo}: not a regular file; a record is a file run --record wrote"
    ]


@pytest.mark.parametrize("command", READERS)
def test_a_missing_record_is_named_with_what_was_found_and_what_is_wanted(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``replay`` and ``monitor`` of a record that is not there said "cannot read record: No
    such file or directory", the error's text alone; a broken link the same. Exit 2, as a
    missing mission or world."""
    missing, link = tmp_path / "nope.jsonl", tmp_path / "link.jsonl"
    link.symlink_to("gone.jsonl")
    wanted = "wanted: a record file, as run MISSION --record FILE writes one"
    assert main([command, str(missing)]) == 2
    assert main([command, str(link)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"roomba-bt {command}: {missing}: record: found no such file; {wanted}",
        f"roomba-bt {command}: {link}: record: found a broken symbolic link (to 'gone.jsonl', "
        f"which does not exist); {wanted}",
    ]


@pytest.mark.parametrize(
    ("number", "found"),
    [
        (errno.EACCES, "a file this user may not read (permission denied)"),
        (errno.EIO, "a file that could not be read: Input/output error (EIO)"),
    ],
)
def test_a_record_that_cannot_be_read_says_why_in_words(
    number: int, found: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A record there but unreadable (root reads a chmod 000 file, so the error is made)."""
    from roomba_bt.runtime import recording

    record = tmp_path / "run.jsonl"
    record.write_text("{}\n")

    def refused(*args: object, **kwargs: object) -> None:
        raise OSError(number, os.strerror(number))

    monkeypatch.setattr(recording, "open_record", refused)
    with pytest.raises(recording.RecordError) as said:
        load_record(record)
    assert str(said.value) == (
        f"{record}: record: found {found}; wanted: a record file, as run MISSION --record FILE "
        "writes one"
    )


def test_summary_packets_are_dropped_when_they_do_not_fit_the_baud() -> None:
    from roomba_bt.runtime.loop import SUMMARY_PACKETS, stream_request

    assert set(SUMMARY_PACKETS) <= set(stream_request((7,), 115200))
    at_19200 = stream_request((7,), 19200)
    assert not set(SUMMARY_PACKETS) & set(at_19200)
    assert {7, 35, 43, 44} <= set(at_19200)


def _record_a_drive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    mission = tmp_path / "drive.yaml"
    mission.write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n"
        "    - drive: {velocity: 200 mm/s, distance: 20 cm}\n"
    )
    record = tmp_path / "drive.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    capsys.readouterr()
    return record


def test_replay_stops_at_the_first_difference_and_names_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = _record_a_drive(tmp_path, capsys)
    slower = tmp_path / "slower.yaml"
    slower.write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n"
        "    - drive: {velocity: 100 mm/s, distance: 20 cm}\n"
    )
    assert main(["replay", str(record), "--mission", str(slower)]) == 1
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("replay: first difference"))
    assert "first difference at mission time 1.0" in line
    # the mission given is not the recorded one: said, as a changed file is (session 29)
    assert f"replay: {slower} is not the recorded mission drive.yaml: a difference" in out
    assert "expected Drive (137) 89 00 c8 80 00, sent Drive (137) 89 00 64 80 00" in line
    assert "end of the record" not in out  # it stopped there, not at the record's end
    # the tree's input ended: nothing was lost (it read "CONNECTION LOST")
    assert "outcome      INPUT ENDED (first difference from the record)" in out


def test_replay_s_tree_after_a_difference_is_the_tree_as_its_last_tick_left_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``replay --display tree`` printed the tree after the run's end had stopped it: every
    node ``[-]``, even ``mode(safe)``, which had run (an upgrader's report). It shows the
    statuses of the last tick replayed: the mode done, the wait where the bytes differed."""
    record = _record_a_drive(tmp_path, capsys)
    slower = tmp_path / "slower.yaml"
    slower.write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n"
        "    - drive: {velocity: 100 mm/s, distance: 20 cm}\n"
    )
    assert main(["replay", str(record), "--mission", str(slower), "--display", "tree"]) == 1
    out = capsys.readouterr().out
    assert "--> mode(safe) [✓]" in out, out
    assert "--> wait(1s) [✓]" in out, out
    assert "--> drive(velocity=100 mm/s, distance=20 cm) [*]" in out, out


def test_a_replay_s_summary_says_the_run_s_label(
    mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run --label`` is in the record, and the run's summary says it first; a replay's
    summary did not, so replays of several robots' runs of one mission could not be told
    apart. It says it as the run did; a hand-edited label on one line, escaped."""
    record = tmp_path / "run.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--label", "robot 3"]
    assert main([*argv, "--record", str(record)]) == 0
    assert capsys.readouterr().out.startswith("label        robot 3\nmission      ")
    assert main(["replay", str(record)]) == 0
    assert capsys.readouterr().out.startswith("label        robot 3\nmission      ")
    header, *rest = record.read_text().splitlines(keepends=True)
    edited = tmp_path / "edited.jsonl"
    relabelled = {**json.loads(header), "label": "robot 3\noutcome      SUCCESS"}
    edited.write_text(json.dumps(relabelled) + "\n" + "".join(rest))
    assert main(["replay", str(edited)]) == 0
    said = capsys.readouterr().out
    assert said.startswith("label        robot 3\\x0aoutcome      SUCCESS\nmission      ")


def test_replay_checks_the_record_holds_the_missions_packets(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = _record_a_drive(tmp_path, capsys)
    walls = tmp_path / "walls.yaml"
    walls.write_text("tree:\n  sequence:\n    - wait: 1s\n    - sensor: wall_signal > 100\n")
    assert main(["replay", str(record), "--mission", str(walls)]) == 2
    err = capsys.readouterr().err
    assert "walls.yaml reads [27] too: it cannot be replayed against this mission" in err
    assert "Traceback" not in err


def test_a_robot_whose_battery_went_flat_is_named_as_such(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The simulated robot switches itself off at an empty battery; the run ends as a lost
    connection (exit 8), and the cause it gives first is the battery the last frame read."""
    go = "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 200 mm/s}\n"
    options = ["--display", "none", "--battery", "0.0002", "--world", "corridor"]
    assert _run_file(tmp_path, "go.yaml", go, *options) == 8
    err = capsys.readouterr().err
    assert "most likely a flat battery (the last frame read 0.0 %: it switched itself off" in err


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_record_that_cannot_be_written_stops_the_record_not_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A full disk under --record: the file's error rose from the port's read, and the run
    ended as a lost port without its safe stop. Now the record stops, the run goes on."""
    drive = (
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 200 mm/s, distance: 50 cm}\n"
    )
    options = ["--display", "none", "--record", "/dev/full"]
    assert _run_file(tmp_path, "drive.yaml", drive, *options) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out
    assert "safe stop    sent" in out
    # the first write that reached the disk failed (a buffer's worth of lines in)
    assert re.search(
        r"record       stopped at \d+\.\d{3} s: No space left on device; the file ends there", out
    )
    assert any("the record /dev/full stopped at" in r.getMessage() for r in caplog.records)


def test_a_record_is_not_written_over_a_file_that_is_not_one(
    mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run m.yaml --record m.yaml`` wrote the record over the mission file."""
    before = mission.read_text()
    argv = ["run", str(mission), "--fast", "--display", "none"]
    with pytest.raises(SystemExit) as refused:  # argparse's usage error
        main([*argv, "--record", str(mission)])
    assert refused.value.code == 2
    assert "a file that is not a record (a mission? a world?)" in capsys.readouterr().err
    assert mission.read_text() == before
    record = tmp_path / "run.jsonl"
    assert main([*argv, "--record", str(record)]) == 0  # a new file
    assert main([*argv, "--record", str(record)]) == 0  # an earlier record: written over
    (tmp_path / "empty.jsonl").write_text("")
    assert main([*argv, "--record", str(tmp_path / "empty.jsonl")]) == 0


def test_docking_reports_the_fall_to_passive_on_the_charger_as_information(
    caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    """A dock run that succeeded logged a WARNING for the end docking is for; a cliff or a
    wheel drop is still one."""
    with caplog.at_level(logging.INFO, logger="roomba_bt"):
        assert main(["run", "dock", "--fast", "--display", "none"]) == 0
    changes = [r for r in caplog.records if "by itself" in r.getMessage()]
    assert [(r.levelno, r.getMessage().rsplit(" ", 1)[-1]) for r in changes] == [
        (logging.INFO, "(charger)")
    ]


def test_the_summary_says_where_the_simulated_robot_ended(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A fall down the stairs read SUCCESS with nothing said (only the plot marked it); a
    docked robot said nothing of the dock."""
    world = tmp_path / "stairs.yaml"
    world.write_text(
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
        "drops: [{rect: [3, 0, 4, 3]}]\n"
        "robot: {start: {at: [1, 1.5], heading: 0}}\n"
    )
    off = (
        "tree:\n  sequence:\n    - mode: full\n    - drive: {velocity: 200 mm/s, distance: 2.5 m}\n"
    )
    code = _run_file(tmp_path, "off.yaml", off, "--world", str(world), "--display", "none")
    out = capsys.readouterr().out
    assert code == 0 and "outcome      SUCCESS" in out
    assert "simulator    the robot FELL off a drop at (3." in out
    assert main(["run", "dock", "--fast", "--display", "none"]) == 0
    assert "simulator    ended on the dock's contacts, charging" in capsys.readouterr().out


FOREVER = "tree:\n  repeat:\n    do: {wait: 1s}\n"


def test_fast_without_a_timeout_stops_at_its_own_limit_and_says_how_to_change_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """On the virtual clock a mission that never ends ran until the simulated battery was
    flat (10.8 h of mission time, then "connection lost", exit 3), or for ever on the
    charger (session 25). The limit is patched to 30 s here: the run is the same. Its reason
    names it as --fast's, not as a --timeout the user never gave ("--timeout 30 s ... ran
    out", then a note saying it was not one); the end a script reads is kept ("... of
    mission time ran out in wait": the stage)."""
    monkeypatch.setattr(run_cmd, "FAST_TIMEOUT_S", 30.0)
    forever = tmp_path / "forever.yaml"
    forever.write_text(FOREVER)
    assert main(["run", str(forever), "--fast", "--display", "none"]) == 1
    out, err = capsys.readouterr()
    reason = "--fast's own limit of 30 s of mission time ran out in wait"
    assert f"outcome      TIMEOUT ({reason})" in out
    assert "duration     30.00 s mission time" in out
    assert err.splitlines() == [
        f"roomba-bt: timeout: {reason}",
        "roomba-bt: no --timeout was given; give one to change the limit (--timeout 10h for a "
        "longer run)",
    ], err
    assert "--timeout 30" not in out + err
    assert failure_stage(reason) == "wait"
    # docs/runtime.md quotes the limit unpatched, 2 h
    assert_quoted("docs/runtime.md", "roomba-bt: timeout: --fast's", err, names={"30 s": "2 h"})
    assert_quoted("docs/runtime.md", "roomba-bt: no --timeout was given", err)
    assert_quoted("docs/runtime.md", "roomba-bt: timeout: ...", err)  # what a run says as it ends
    assert main(["run", str(forever), "--fast", "--display", "none", "--timeout", "20s"]) == 1
    out, err = capsys.readouterr()
    assert "(--timeout 20 s of mission time ran out in wait)" in out
    assert "own limit" not in out + err and "no --timeout" not in err
    # a limit of a minute or more as a person says it: it was "--timeout 86400 s" for a 1d
    assert main(["run", str(forever), "--fast", "--display", "none", "--timeout", "1min"]) == 1
    assert "(--timeout 1 min of mission time ran out in wait)" in capsys.readouterr().out


@pytest.mark.parametrize(("given", "seconds"), [("1d", 86400.0), ("1h30min", 5400.0),
                                                ("2h 15min", 8100.0), ("90", 90.0)])  # fmt: skip
def test_timeout_takes_days_and_several_units_as_a_mission_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], given: str, seconds: float
) -> None:
    """The soak: ``--timeout 1d`` was "unknown duration unit 'd'" and ``1h30min`` "expected a
    duration such as 500ms, 30s or 2min"; one grammar with the mission's durations now (its
    ``wait: 1h30min`` here), and the run takes it."""
    assert parse_timeout(given) == seconds
    waits = tmp_path / "waits.yaml"
    waits.write_text("tree:\n  timeout:\n    after: 1h30min\n    do: {wait: 1s}\n")
    assert main(["run", str(waits), "--fast", "--display", "none", "--timeout", given]) == 0
    assert "outcome      SUCCESS" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("given", "limited"),
    [({}, True), ({"fast": False}, False), ({"timeout": "1h"}, False),
     ({"monitor": 8080}, False), ({"watch": True}, False)],
)  # fmt: skip
def test_the_fast_limit_is_for_unwatched_fast_runs_without_a_timeout(
    given: dict[str, object], limited: bool
) -> None:
    """With ``--monitor`` or ``--watch`` someone watches, and stops it from the page."""
    args = {"fast": True, "timeout": None, "monitor": None, "watch": False, **given}
    assert run_cmd._fast_limit(argparse.Namespace(**args)) is limited


#: names, a log leaf's text and a failure that fake lines: "[ok] ..." at a line's start
FAKING = r"""
mission: "faked\n[ok] mission"
description: "faked\n[ok] robot stopped"
tree:
  sequence:
    - sequence:
        name: "steps\n[ok] robot stopped"
        children:
          - log: "said\n[ok] said"
          - wait: 0.1s
            name: "waited\n[ok] waited"
    - sensor: oi_mode == 0
      name: "never\n[ok] never"
"""


#: ``_run_file`` of a mission that fails (exit 1): what it showed (stdout, stderr, the log)
Shown = Callable[..., tuple[str, str, str]]


@pytest.fixture
def run_shown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> Shown:
    """``run_shown(name, text, *options, plugins=...)``: :func:`_run_file` of a mission that
    fails (exit 1); what it printed on stdout and stderr, and what it logged as the run's
    formatter writes it (pytest's handler holds the records): where a text could fake a line."""
    caplog.set_level(logging.INFO)

    def run(
        name: str, text: str, *options: str, plugins: dict[str, str] | None = None
    ) -> tuple[str, str, str]:
        assert _run_file(tmp_path, name, text, *options, plugins=plugins) == 1
        out, err = capsys.readouterr()
        return out, err, "\n".join(MissionClockFormatter().format(r) for r in caplog.records)

    return run


@pytest.mark.parametrize("display", ["log", "tree"])
def test_what_a_mission_wrote_fakes_no_line_of_the_run(run_shown: Shown, display: str) -> None:
    """A name, a ``log`` leaf's text and the mission's name printed raw: a "\\n" in them
    started a line of its own ("[ok] robot stopped") in the status-change log, the tree at
    the end, the summary and the failure's line on stderr. Each stays on its line, escaped."""
    out, err, logged = run_shown("faking.yaml", FAKING, "--display", display)
    faked = [line for line in (out + err + logged).splitlines() if line.startswith("[ok]")]
    assert not faked, out + err + logged
    assert "mission      faked\\x0a[ok] mission" in out
    assert "outcome      FAILURE (never\\x0a[ok] never)" in out
    assert "roomba-bt: failure: never\\x0a[ok] never" in err
    if display == "log":
        assert "INFO roomba_bt.run: steps\\x0a[ok] robot stopped -> SUCCESS" in logged
    assert "INFO roomba_bt.mission: said\\x0a[ok] said" in logged
    assert "-- said\\x0a[ok] said" in out  # the log leaf's text, in the tree at the end


#: a plugin's action whose message clears the screen and fakes a line, then fails
SAYER = '''
from py_trees.common import Status
from roomba_bt.behaviours import Action, declare


@declare("sayer", kind="action")
class Sayer(Action):
    """Says what no mission file may hold (a file's texts are refused such characters)."""

    def update(self):
        self.feedback_message = "\\x1b[2J\\n[ok] robot stopped"
        return Status.FAILURE if self.snapshot.time >= 0.1 else Status.RUNNING
'''


@pytest.mark.parametrize("display", ["log", "tree"])
def test_a_plugin_s_feedback_message_is_escaped_where_it_is_printed(
    run_shown: Shown, display: str
) -> None:
    """A plugin's ``feedback_message`` is code's text, not a file's: nothing refused its
    ``ESC [2J`` or its newline, and the tree at the end (py_trees' drawing) printed it raw,
    clearing the screen and faking a line under it. Escaped where it is printed, on its
    leaf's line, as the summary and the failure's line on stderr have it."""
    mission = "plugins: [./sayer.py]\ntree:\n  sequence: [sayer]\n"
    options = ["--display", display, "--allow-plugin-files"]
    out, err, logged = run_shown("m.yaml", mission, *options, plugins={"sayer.py": SAYER})
    shown = out + err + logged
    assert "\x1b[2J" not in shown, shown  # (the live tree's own redraw is ESC [H ESC [J)
    assert not [line for line in shown.splitlines() if line.startswith("[ok]")], shown
    said = "\\x1b[2J\\x0a[ok] robot stopped"
    assert f"--> sayer [✕] -- {said}" in out  # the tree at the end
    assert f"outcome      FAILURE (sayer: {said})" in out
    assert f"roomba-bt: failure: sayer: {said}" in err


def test_a_control_character_never_reaches_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``"\\e[2J"`` in a name (it clears the screen) is refused with the file, before a run."""
    faking = 'tree:\n  wait: 0.1s\n  name: "\\e[2J[ok] cleared"\n'
    assert _run_file(tmp_path, "faking.yaml", faking) == 2
    out, err = capsys.readouterr()
    assert "\x1b" not in out + err
    assert "control character U+001B" in err and "faking.yaml:3:" in err


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (a full disk)")
def test_a_run_that_must_be_recorded_refuses_to_start_when_its_header_cannot_be_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A lab that needs a record of every run: with the disk full the run started anyway and
    left a 0-byte file. ``--require-record`` refuses, exit 2, nothing sent; without it the
    run goes on as before, its summary saying where the record stopped."""
    argv = ["--display", "none", "--timeout", "1s", "--record", "/dev/full"]
    assert _run_file(tmp_path, "spin.yaml", SPIN, *argv, "--require-record") == 2
    out, err = capsys.readouterr()
    assert "--record /dev/full: the record's header could not be written" in err
    assert "--require-record: not started, nothing sent" in err
    assert "the run goes on" not in err  # the refusal alone, no warning that it runs before it
    assert "outcome" not in out  # no run, no summary
    assert _run_file(tmp_path, "spin.yaml", SPIN, *argv) == 1  # the timeout's, as before
    assert "record       stopped at 0.000 s: No space left on device" in capsys.readouterr().out


def test_a_long_lost_link_line_is_said_a_clause_a_line_for_the_journal() -> None:
    """A sleeping robot's stderr line was 457 characters: the cause, the watchdog, the
    grace, the queries and the stream asked for again in one sentence. The cause stays the
    first line, each clause follows on its own, every word kept; brackets hold theirs."""
    said = (
        "connection lost: /dev/pts/1: the sensor stream stopped: nothing arrived for 2.0 s (the "
        "robot switched off or stopped streaming, or the cable); the watchdog sent drive 0 "
        "after 100 ms, then the run waited the 2 s grace; it answered no query, asked twice 1 s "
        "apart, and it was in Safe, which never sleeps: switched off, a flat battery, or the "
        "cable; the stream was asked for again 2 times within the grace (zeros; then the "
        "request), and nothing came"
    )
    lines = run_cmd._journal_lines(said)
    assert lines[0].endswith("nothing arrived for 2.0 s (the robot switched off or stopped "
                             "streaming, or the cable)")  # fmt: skip
    assert lines[3] == (
        "  the stream was asked for again 2 times within the grace (zeros; then the request), "
        "and nothing came"
    )
    assert "; ".join(line.strip() for line in lines) == said
    assert run_cmd._journal_lines("connection lost: a; b") == ["connection lost: a; b"]
    # as the run prints them on stderr, each after "roomba-bt: " (docs/unattended.md's journal)
    journal = "\n".join(f"roomba-bt: {line}" for line in lines)
    assert_quoted("docs/unattended.md", "roomba-bt: connection lost: ...", journal)
    assert_quoted("docs/unattended.md", "roomba-bt: the watchdog sent drive 0", journal)


@pytest.mark.skipif(sys.platform == "win32", reason="a file size limit (RLIMIT_FSIZE)")
def test_a_required_record_that_cannot_be_written_leaves_the_earlier_record_in_its_file(
    tmp_path: Path,
) -> None:
    """``--require-record`` into a file that holds an earlier record, where the disk takes
    no more (here a file size limit, as a quota or a full disk): refused, exit 2, and the
    earlier record is as it was. It was emptied before the header failed (session 36)."""
    import resource

    earlier = '{"format": "roomba-bt-record", "version": 2}\n{"t": 0.0}\n'
    record = tmp_path / "run.jsonl"
    record.write_text(earlier, encoding="utf-8")
    mission = write_mission(tmp_path, SPIN, "spin.yaml")
    limit = len(earlier.encode())

    def limited() -> None:  # in the child: no file of it grows past the earlier record
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    argv = ["run", str(mission), "--fast", "--display", "none", "--timeout", "1s"]
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt", *argv, "--record", str(record), "--require-record"],
        capture_output=True, text=True, timeout=HANG_S, preexec_fn=limited,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).parents[2])},
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert "the record's header could not be written (File too large)" in done.stderr
    assert "--require-record: not started, nothing sent" in done.stderr
    assert record.read_text(encoding="utf-8") == earlier


#: a plugin's action that raises on its first tick
BOOM_PLUGIN = """
from py_trees.common import Status
from roomba_bt.behaviours import Action, declare


@declare("boom", kind="action", params=(), reads=())
class Boom(Action):
    \"\"\"Raises in its update.\"\"\"

    def update(self):
        raise RuntimeError("sensor calibration lost")
"""

BOOM = """\
plugins: [./boom.py]
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, duration: 0.1s}
      name: pre
    - motors: {main_brush: on}
    - timeout: {after: 3s, do: {boom: {}}}
"""


@pytest.mark.parametrize("display", ["log", "tree"])
def test_after_a_behaviour_s_exception_the_tree_and_the_log_show_how_far_the_run_got(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
    display: str,
) -> None:
    """After a behaviour raised, the tree printed at the end showed every node ``[-]``, even
    ``mode(safe)``, which had succeeded (the tree's stop marks them INVALID), and the log
    never printed the failing tick's lines (``motors -> SUCCESS``): neither told how far the
    run had got (session 36, a stranger's finding). The tree shows each node's last status,
    the raising leaf says what it raised, and the failing tick's lines are logged."""
    caplog.set_level(logging.INFO, logger="roomba_bt.run")
    options = ("--display", display, "--allow-plugin-files")
    assert _run_file(tmp_path, "boom.yaml", BOOM, *options, plugins={"boom.py": BOOM_PLUGIN}) == 4
    out = capsys.readouterr().out
    tree = out[out.index("{-} sequence [") : out.index("mission ")]
    assert "--> mode(safe) [✓]" in tree, tree
    assert "--> drive(velocity=200 mm/s, duration=0.1s) named 'pre' [✓]" in tree, tree
    assert "--> motors(main_brush=on) [✓]" in tree, tree
    assert "--> boom [-] -- raised RuntimeError" in tree, tree
    if display == "log":
        logged = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.run"]
        assert logged[-2:] == ["pre -> SUCCESS", "motors(main_brush=on) -> SUCCESS"], logged


def _marks(screen: str) -> dict[str, str]:
    """Each node's status mark in a drawing of the tree, by its name (``--> pre [✓]``)."""
    drawn = (re.match(r"\s*\S+ (.+?) \[(.)\]", line) for line in screen.splitlines())
    return {m.group(1): m.group(2) for m in drawn if m is not None}


def test_after_a_behaviour_s_exception_the_live_tree_s_last_screen_is_the_tree_as_left(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The live tree's last screen is drawn after the run's end has stopped the tree, which
    marks every node INVALID: it showed ``[-]`` on every node, ``mode(safe)`` and the
    sequence too, right above the tree printed after the run with the marks the run left
    (session 37). It shows those marks: the same as the tree under it, which names each
    node as ``show`` does (the live screen keeps the nodes' own, shorter names)."""
    options = ("--display", "tree", "--allow-plugin-files")
    assert _run_file(tmp_path, "boom.yaml", BOOM, *options, plugins={"boom.py": BOOM_PLUGIN}) == 4
    out = capsys.readouterr().out
    # the last screen (its sensor lines, then the live tree), then the tree after the run
    *_, live, final = out[: out.index("mission ")].split("{-} sequence [")
    shown, left = _marks("{-} sequence [" + live), _marks("{-} sequence [" + final)
    assert shown["sequence"] == "*", live
    for name in ("mode(safe)", "pre", "motors(main_brush=on)"):
        assert shown[name] == "✓", live
    as_shown = {"pre": "drive(velocity=200 mm/s, duration=0.1s) named 'pre'"}
    as_shown |= {"timeout": "timeout(after=3s)"}
    assert shown == {name: left[as_shown.get(name, name)] for name in shown}, (live, final)


DECORATED = """
mission: decorated
tree:
  sequence:
    - mode: safe
    - timeout:
        after: 2s
        do: {drive: {velocity: 100 mm/s, distance: 5 cm}}
    - retry: {times: 2, do: {wait: 0.1s}}
      name: twice
"""


def test_the_trees_before_and_after_the_run_are_named_as_show_draws(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """``run`` drew its trees with the live nodes' names, ``timeout`` and ``twice``, where
    ``show`` drew ``timeout(after=2s)`` and ``retry(times=2) named 'twice'``: a user comparing
    the two saw two trees, and once the tree before the run was show's, the tree after it
    still said ``timeout [✓]``. The log keeps the live names (the record and the golden
    recordings hold them)."""
    path = tmp_path / "decorated.yaml"
    path.write_text(DECORATED)
    assert main(["show", str(path)]) == 0
    shown = capsys.readouterr().out.splitlines()
    caplog.set_level(logging.INFO, logger="roomba_bt.run")
    assert main(["run", str(path), "--fast", "--display", "log"]) == 0
    out = capsys.readouterr().out
    tree = shown[1 : shown.index("")]  # after the mission's line, up to the packets
    assert "    -^- timeout(after=2s)" in tree
    assert "    -^- retry(times=2) named 'twice'" in tree
    assert out.splitlines()[: len(tree)] == tree
    after = out.splitlines()[len(tree) :]
    assert "    -^- timeout(after=2s) [✓]" in after
    assert (
        "    -^- retry(times=2) named 'twice' [✓] -- succeeded [status: 0 failure from 2]" in after
    )
    assert "twice -> SUCCESS" in caplog.messages  # the log's name: the node's own
