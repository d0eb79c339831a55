"""``--record`` as a run killed outright leaves it, and ``replay`` of what it left."""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import subprocess
import sys
import tracemalloc
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.mission import load_mission
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.safety import SIGINT_SAID
from roomba_bt.robot.wording import COMMAND_LINE, spoken
from roomba_bt.runtime.display import MissionClockFormatter
from roomba_bt.runtime.recording import RecordingTransport, ReplayTransport, load_record
from roomba_bt.runtime.stack import Recording, RunStack, replay_record
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.runtime.tick_guard import stop_first
from roomba_bt.sim import SimLink, Simulator, load_world

from .installed import another_installation
from .simrun import (
    LEDGE,
    SPIN,
    BusyAfterTheFall,
    over_the_edge,
    record_run,
    stream_gap_link,
)

FRAME = bytes.fromhex("131a070009000a000b000c001906511a0a88220023022b020d2c020dca")
HEADER = {"profile": "create2", "baud": 115200, "mission": "bump-and-turn", "packets": [7]}
#: drive 0 and motors off in one write: the run's end before its tree's stop
STOP_FIRST = b"".join(command.data for command in stop_first())


class _Link:
    """A port on a clock the test moves: a stream frame every 15 ms; with ``drift``, the
    clock moves on every reading too, as the wall clock does."""

    name = "link"
    is_open = True

    def __init__(self, drift: float = 0.0) -> None:
        self.t = 50.0
        self.drift = drift

    def now(self) -> float:
        self.t += self.drift
        return self.t

    def read(self, timeout: float) -> bytes:
        self.t += 0.015
        return FRAME

    def write(self, data: bytes) -> None:
        pass

    def close(self) -> None:
        pass


def two_seconds_recorded(path: Path) -> tuple[RecordingTransport, float]:
    """A record being written to ``path``, 2 s of frames in, each with its tick's Drive, and
    the time of its last chunk; not closed (what a run killed now leaves is on disk)."""
    link = _Link()
    recording = RecordingTransport(link, path, HEADER)  # type: ignore[arg-type]
    for _ in range(134):
        recording.read(0.015)
        recording.write(bytes([137, 0, 200, 128, 0]))
    return recording, link.t - 50.0 - 0.015  # the first read's arrival is the record's 0


def test_the_record_reaches_the_file_as_the_run_goes(tmp_path: Path) -> None:
    """A run killed outright (kill -9) leaves what the record had flushed: before, only the
    run's end flushed it, and a killed 2 s run's record stopped at 1.22 s (an 8 KiB buffer).
    Now the file, read while the run goes on, holds the run up to a quarter second ago
    (recording.FLUSH_EVERY_S)."""
    path = tmp_path / "run.jsonl"
    recording, last_t = two_seconds_recorded(path)
    on_disk = path.read_text(encoding="utf-8")  # what a kill -9 now would leave
    lines = on_disk.splitlines()
    assert on_disk.endswith("\n")
    assert json.loads(lines[0])["format"] == "roomba-bt-record"
    assert json.loads(lines[-1])["t"] >= last_t - 0.25
    recording.close()


MISSIONS = Path(__file__).resolve().parents[2] / "missions"


def _recorded_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> list[str]:
    """The lines of a 3 s bump-and-turn record made on the virtual clock."""
    record = tmp_path / "run.jsonl"
    argv = ["run", str(MISSIONS / "bump-and-turn.yaml"), "--fast", "--display", "none",
            "-p", "duration=3s", "--record", str(record)]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    return record.read_text(encoding="utf-8").splitlines(keepends=True)


def _killed_at(lines: list[str], t: float) -> list[str]:
    """The record a run killed at ``t`` leaves: its lines up to then, no end line."""
    return [lines[0], *(line for line in lines[1:] if json.loads(line)["t"] <= t)]


def _left_a_minute(path: Path) -> Path:
    """``path`` as a killed run left it, read a minute later: no run is writing it (a record
    without its end line changed in the last seconds is taken for one a run still writes)."""
    an_hour_ago = path.stat().st_mtime - 3600
    os.utime(path, (an_hour_ago, an_hour_ago))
    return path


def test_a_record_ends_with_the_runs_end_line_and_replays_whole(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = _recorded_run(tmp_path, capsys)
    assert json.loads(lines[-1]) == {"t": json.loads(lines[-2])["t"], "d": "end"}
    assert main(["replay", str(tmp_path / "run.jsonl")]) == 0
    out = capsys.readouterr().out
    assert "the tree wrote the same" in out and "as the recorded run" in out
    assert "without the run's end" not in out


class _Stamped(logging.Handler):
    """The ``roomba_bt.mission`` lines (a mission's ``log`` leaves) as the command line's
    formatter writes them when each is logged: ``t=`` is the mission clock's then."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.setFormatter(MissionClockFormatter())
        self.lines: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(self.format(record))


def test_a_replay_stamps_the_mission_s_log_lines_as_its_run_did(tmp_path: Path) -> None:
    """``replay``'s runner is made inside ``replay_record``, where the command line could not
    give it the mission clock: its ``log`` lines came without the ``t=`` (and the ``--label``)
    the recorded run's had. Each is now the run's line, stamped alike."""
    mission = tmp_path / "logs.yaml"
    mission.write_text(
        "mission: logs\ntree:\n  sequence:\n    - log: first\n    - wait: 0.5s\n"
        "    - log: second\n",
        encoding="utf-8",
    )
    record = tmp_path / "run.jsonl"
    said = _Stamped()
    logger = logging.getLogger("roomba_bt.mission")
    level = logger.level
    logger.addHandler(said)
    logger.setLevel(logging.INFO)
    try:
        argv = ["run", str(mission), "--fast", "--display", "none", "--label", "robot 3"]
        assert main([*argv, "--record", str(record)]) == 0
        ran, said.lines = said.lines, []
        assert main(["replay", str(record), "--display", "none"]) == 0
        replayed = said.lines
    finally:
        logger.removeHandler(said)
        logger.setLevel(level)
    assert ran == [
        "t=0.000 [robot 3] INFO roomba_bt.mission: first",
        "t=0.510 [robot 3] INFO roomba_bt.mission: second",
    ]
    assert replayed == ran
    assert MissionClockFormatter.clock is None  # the stamping ends with the replay


def test_a_killed_runs_record_is_compared_up_to_where_it_ends(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """kill -9 leaves no end line; the replay's own safe stop at the end of the input was
    the first difference: 'expected nothing, sent Drive (137) 89 00 00 00 00', exit 1."""
    killed = tmp_path / "killed.jsonl"
    lines = _killed_at(_recorded_run(tmp_path, capsys), 1.2)
    killed.write_text("".join(lines), encoding="utf-8")
    outbound = sum(len(json.loads(x)["b"]) // 2 for x in lines[1:] if '"out"' in x)
    assert main(["replay", str(_left_a_minute(killed))]) == 0
    out = capsys.readouterr().out
    assert (
        "replay: the record ends at 1.200 s without the run's end: the run was killed, or "
        "writing its record failed (a full disk, a file size limit?; the run's summary says "
        "which)" in out
    )
    assert f"replay: the tree wrote the same {outbound} bytes up to there" in out
    assert "first difference" not in out


def test_a_killed_runs_record_still_shows_a_difference_before_its_end(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Up to where it ends it is compared as a whole record is: a command the tree writes
    while robot bytes recorded after it remain would have been in the record."""
    killed = tmp_path / "killed.jsonl"
    lines = _killed_at(_recorded_run(tmp_path, capsys), 1.2)
    last_out = max(i for i, line in enumerate(lines) if '"out"' in line)
    killed.write_text("".join(lines[:last_out] + lines[last_out + 1 :]), encoding="utf-8")
    assert main(["replay", str(_left_a_minute(killed))]) == 1
    out = capsys.readouterr().out
    assert "without the run's end: the run was killed, or writing its record failed" in out
    assert "replay: first difference at mission time" in out and "expected nothing, sent" in out


def _listened_after(lines: list[str]) -> list[str]:
    """``lines`` with the header of a record made on the wall clock (a robot's, a pty's),
    whose run listened after its stop (``stop_listened``), as its replay then does."""
    return [json.dumps({**json.loads(lines[0]), "stop_listened": True}) + "\n", *lines[1:]]


def test_the_replay_of_a_record_a_full_disk_cut_says_where_it_ends_not_a_lost_robot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A wall-clock run's record stopped by a full disk (or ``--record-max``): the run went
    on and ended SUCCESS in Passive. Its replay listened after its own stop past the cut,
    heard nothing there, and said CONNECTION LOST, NOT DELIVERED, and an ERROR line. It now
    says where the record ends and why, and judges no stop it holds nothing of."""
    lines = _listened_after(_killed_at(_recorded_run(tmp_path, capsys), 1.2))
    cut = tmp_path / "cut.jsonl"
    note = {"t": 1.2, "d": "note", "note": {"record_stopped": "No space left on device"}}
    cut.write_text("".join(lines) + json.dumps(note) + "\n", encoding="utf-8")
    with caplog.at_level(logging.WARNING):
        assert main(["replay", str(cut)]) == 0
    out = capsys.readouterr().out
    assert (
        "outcome      INPUT ENDED (end of the record: it ends at 1.200 s, before its run's "
        "end: the recording stopped (No space left on device))" in out
    )
    assert "NOT DELIVERED" not in out and "CONNECTION LOST" not in out
    assert "ERROR" not in caplog.text
    assert "the tree wrote the same" in out and "up to there" in out


@pytest.mark.parametrize(("ended", "listened"), [(True, True), (False, False)])
def test_a_replay_listens_after_its_stop_past_the_record_only_where_the_record_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], ended: bool, listened: bool
) -> None:
    """Used up, a record with its end line holds what the robot sent after the stop (a
    pulled cable's: nothing), and its replay's stop is judged on it as the run's was; one
    cut short holds nothing of the run's end, and its replay's stop is not listened after."""
    lines = _listened_after(_recorded_run(tmp_path, capsys))
    record = tmp_path / "listened.jsonl"
    record.write_text("".join(lines if ended else lines[:-1]), encoding="utf-8")
    loaded = load_record(_left_a_minute(record))
    transport = ReplayTransport(loaded)
    assert transport.loses_bytes  # the chunks still to give: listened, as the run did
    for _, side, data in loaded.chunks():  # the recorded run's reads and writes, in order
        if side == "out":
            transport.write(data)
        else:
            assert transport.read(3600.0) == data
    assert transport.exhausted and transport.difference is None
    assert transport.loses_bytes is listened


def test_a_record_made_before_the_end_line_is_compared_up_to_where_it_ends(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = _recorded_run(tmp_path, capsys)
    old = tmp_path / "v1.jsonl"
    header = {**json.loads(lines[0]), "version": 1}
    old.write_text("".join([json.dumps(header) + "\n", *lines[1:-1]]), encoding="utf-8")
    assert main(["replay", str(_left_a_minute(old))]) == 0
    out = capsys.readouterr().out
    assert ": version 1 records have no end line, or the run was killed" in out


def test_a_record_whose_last_line_is_cut_is_replayed_up_to_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """`head -c 5000 run.jsonl`, as a kill or a full disk leaves it: the whole record was
    refused, exit 2, 'malformed chunk'. The cut line is dropped with a warning naming it."""
    whole = "".join(_recorded_run(tmp_path, capsys))
    cut = tmp_path / "cut.jsonl"
    at = whole.rindex("\n", 0, 5000) + 20  # 20 characters into a line (the header's length aside)
    cut.write_text(whole[:at], encoding="utf-8")
    number = whole[:at].count("\n") + 1  # the line cut short
    assert not whole[:at].endswith("\n")
    with caplog.at_level(logging.WARNING):
        assert main(["replay", str(_left_a_minute(cut))]) == 0
    out = capsys.readouterr().out
    assert f"{cut}:{number}: the last line is cut short" in caplog.text
    assert f"the record is read up to line {number - 1}" in caplog.text
    assert "without the run's end: the run was killed, or writing its record failed" in out
    assert "the tree wrote the same" in out and "up to there" in out


@pytest.mark.parametrize("ending", ["", "\n"])
def test_a_malformed_line_before_the_last_or_ended_is_still_an_error(
    ending: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Only a last line without its newline is taken for one cut short."""
    lines = _recorded_run(tmp_path, capsys)
    damaged = tmp_path / "damaged.jsonl"
    if ending:  # the last line malformed, but whole: not a cut
        damaged.write_text("".join([*lines[:40], lines[40][:20] + ending]), encoding="utf-8")
    else:  # a line in the middle malformed, the last one cut
        damaged.write_text("".join([*lines[:40], lines[40][:20] + "\n", *lines[41:50],
                                    lines[50][:20]]), encoding="utf-8")  # fmt: skip
    assert main(["replay", str(damaged)]) == 2
    assert f"{damaged}:41: malformed chunk" in capsys.readouterr().err


def test_a_long_chunk_line_is_read_in_memory_near_its_size(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stranger's record with a line of 40 MB of hex ended ``replay`` in a MemoryError
    (exit 70) after 2.7 GB: the chunk's pattern kept a mark for every byte pair it matched.
    A line of 2 MB of hex is read with less than 4 bytes held for each of its characters
    (120 before); one of an odd number of digits is a malformed chunk, as before."""
    lines = _recorded_run(tmp_path, capsys)
    long = '{"t": 0.000000, "d": "in", "b": "' + "00" * 1_000_000 + '"}\n'
    record = tmp_path / "long.jsonl"
    record.write_text("".join([lines[0], long, *lines[1:]]), encoding="utf-8")
    tracemalloc.start()
    try:
        load_record(record)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4 * len(long), peak
    record.write_text("".join([lines[0], long.replace('00"', '0"', 1), *lines[1:]]))
    assert main(["replay", str(record)]) == 2
    assert f"{record}:2: malformed chunk (ValueError: non-hexadecimal" in capsys.readouterr().err


def _replayed(
    path: Path, until: float | None = None
) -> tuple[RunSummary, tuple[int, str, str] | None, int]:
    """``path`` replayed as ``roomba-bt replay`` does (up to mission time ``until``, as
    ``--to`` does): its summary, its first difference and the bytes the tree wrote."""
    record = load_record(path)
    mission = load_mission(record.mission_file or "", {}, profile=CREATE2)
    summary, transport = replay_record(
        record, mission, profile=CREATE2, packets=record.header["packets"], baud=115200,
        name=str(path), until=until,
    )  # fmt: skip
    return summary, transport.first_difference(), transport.written


def test_a_replay_ended_early_from_python_names_its_argument(tmp_path: Path) -> None:
    """``replay_record(..., until=1.0)``: the summary's reason named ``--to``, a flag of
    ``roomba-bt replay`` the program never gave; it names the argument (and ``--to`` while
    a ``roomba-bt`` command runs)."""
    path = record_run(tmp_path, stream_gap_link())
    summary, _, _ = _replayed(path, until=1.0)
    assert summary.reason == "the end of the window, mission time 1 s (replay_record's until)"
    with spoken(COMMAND_LINE):
        summary, _, _ = _replayed(path, until=1.0)
    assert summary.reason == "the end of the window, mission time 1 s (--to)"


def test_a_run_whose_watchdog_stopped_the_wheels_replays_byte_for_byte(tmp_path: Path) -> None:
    """The watchdog's drive 0 in a stream gap, the stall ridden through and the wheels' command
    again: the replay does each at the same time. Before, a replay ran no watchdog and the
    stall was its first difference ('expected Drive (137) 89 00 00 00 00, sent nothing'),
    exit 1: every record of a noisy cable, and the monitor's view of it, stopped there."""
    path = record_run(tmp_path, stream_gap_link())
    record = load_record(path)
    assert record.header["watchdog"] == 0.1 and record.header["grace"] == 2.0
    [trip] = record.watchdog_trips or []
    assert 1.0 < trip < 1.2  # noted at the link time it tripped
    assert bytes.fromhex("8900000000") in record.outbound  # the stall's drive 0
    summary, difference, written = _replayed(path)
    assert difference is None, difference
    assert written == len(record.outbound)
    assert summary.stalls == summary.stalls_ridden == 1


def test_a_record_made_before_the_trips_were_noted_replays_its_stall_on_its_silence(
    tmp_path: Path,
) -> None:
    """A record without ``watchdog`` in its header (made before, as the soak's were): the
    replay's watchdog trips on the record's silence, at the default 100 ms."""
    path = record_run(tmp_path, stream_gap_link())
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    header = {k: v for k, v in json.loads(lines[0]).items() if k not in ("watchdog", "grace")}
    old = [json.dumps(header) + "\n", *(x for x in lines[1:] if '"watchdog"' not in x)]
    path.write_text("".join(old), encoding="utf-8")
    assert load_record(path).watchdog_trips is None
    summary, difference, _ = _replayed(path)
    assert difference is None, difference
    assert summary.stalls == 1


class _WokeLate(SimLink):
    """The host wakes late once, at 1 s: its read returns 0.2 s later with the frames sent
    meanwhile (a loaded machine), stamped then: past the watchdog's time, with no trip."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.late = True

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        if self.late and self.simulator.time >= 1.0:
            self.late = False
            for _ in range(round(0.2 / 0.015)):
                self.simulator.step()
                data += self.simulator.read()
        return data


def test_a_read_that_woke_late_is_no_trip_in_the_replay(tmp_path: Path) -> None:
    """The replay's watchdog trips where the record's did, not on the record's silence: the
    frames of a late read are stamped past the watchdog's time, and a replay that tripped on
    them sent a drive 0 the run never sent."""
    path = record_run(tmp_path, _WokeLate(Simulator(load_world("empty-room"), CREATE2, 0)))
    assert load_record(path).watchdog_trips == []
    summary, difference, _ = _replayed(path)
    assert difference is None, difference
    assert summary.stalls == 0


class _BusyAtTheEnd(SimLink):
    """A port's link (on the wall clock, a read of nothing waits for nothing) whose host is
    busy a slot after the run's end sent drive 0 and motors off (its tree's stop, on a
    loaded machine) while the robot streams on: the safe stop finds that frame waiting."""

    wall_clock = True

    def write(self, data: bytes) -> None:
        super().write(data)
        if data == STOP_FIRST:
            self.advance(0.015)

    def read(self, timeout: float) -> bytes:
        return super().read(timeout) if timeout > 0.0 else self.simulator.read()


def test_the_frames_the_safe_stop_read_first_are_read_by_its_replay(tmp_path: Path) -> None:
    """The safe stop reads what waits unread in the port before it writes the stop (robot/
    ending.py): a run on the wall clock whose host was busy at its end (a pty run under
    load: its tree's stop took a slot after drive 0 and motors off) read a frame there. The
    replay read nothing there, and its stop was its first difference: "expected Drive (137)
    89 00 00 00 00, sent Drive (137) 89 00 00 00 00 0.00 s early: the recorded run read 1
    more of the robot's chunks before writing it", exit 1. It reads what the run read."""
    path = record_run(tmp_path, _BusyAtTheEnd(Simulator(load_world("empty-room"), CREATE2, 0)),
                      tick_limit=60.0)  # fmt: skip
    record = load_record(path)
    chunks = list(record.chunks())
    [first] = [i for i, (_, d, b) in enumerate(chunks) if (d, b) == ("out", STOP_FIRST)]
    assert chunks[first + 1][1] == "in" and chunks[first + 2][1] == "out"  # the frame waited
    summary, difference, written = _replayed(path)
    assert difference is None, difference
    assert written == len(record.outbound)
    assert summary.safe_stop.startswith("drive 0, motors off before the tree's stop, then sent")


def _replay_peak(path: Path) -> int:
    """The peak of Python's allocations while ``path`` is read and replayed."""
    import tracemalloc

    from roomba_bt.mission import load_mission
    from roomba_bt.mission.shipped import shipped_missions
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    profile = get_profile("create2")
    tracemalloc.start()
    try:
        record = load_record(path)
        mission = load_mission(
            shipped_missions()["bump-and-turn"], record.header["parameters"], profile=profile
        )
        summary, transport = replay_record(
            record, mission, profile=profile, packets=record.header["packets"], baud=115200,
            name=str(path),
        )  # fmt: skip
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert transport.first_difference() is None and summary.ticks > 1000
    return peak


def test_a_replay_reads_the_record_as_it_goes_its_memory_not_growing_with_it(
    tmp_path: Path,
) -> None:
    """A replay held every chunk of the record (341 MB for a 2-hour run): one four times as
    long took about four times the memory. Now it reads the record as it replays it."""
    peaks = []
    for seconds in (20, 80):
        path = tmp_path / f"{seconds}.jsonl"
        argv = ["run", "bump-and-turn", "--fast", "--world", "corridor", "--display", "none"]
        assert main([*argv, "-p", f"duration={seconds}s", "--record", str(path)]) == 0
        peaks.append(_replay_peak(path))
    short, long = peaks
    assert long - short < 0.1 * short, peaks


def test_the_replay_of_a_long_record_says_how_far_it_has_gone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A 2-hour record took minutes to replay and said nothing meanwhile."""
    from roomba_bt.cli import run_cmd

    path = tmp_path / "run.jsonl"
    argv = ["run", "bump-and-turn", "--fast", "--world", "corridor", "--display", "none"]
    assert main([*argv, "-p", "duration=20s", "--record", str(path)]) == 0
    capsys.readouterr()
    assert main(["replay", str(path)]) == 0
    assert "% of" not in capsys.readouterr().err  # a short record: nothing to wait for
    monkeypatch.setattr(run_cmd, "PROGRESS_FROM_BYTES", 0)  # as long as a long one
    assert main(["replay", str(path)]) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "% of" in line]
    assert said[0].startswith(f"replay: 10% of {path} (0:02 of 0:20 of the run)"), said
    assert len(said) == 10 and said[-1].startswith(f"replay: 100% of {path}"), said
    # the pages' long.jsonl, a run of 1 h 10 min: its clock said in hours, as replay and
    # monitor RECORD say it (one function for both)
    long = load_record(path)
    long.last_t = 70 * 60.0
    page = {str(path): "long.jsonl"}
    said: dict[str, str] = {}
    for who, fraction in (("replay", 0.3), ("monitor", 0.1)):
        progress = run_cmd.replay_progress(who, long)
        assert progress is not None
        progress(fraction)
        said[who] = capsys.readouterr().err
    assert_quoted("docs/runtime.md", "replay: 30% of long.jsonl", said["replay"], names=page)
    assert_quoted("docs/monitor.md", "monitor: 10% of long.jsonl", said["monitor"], names=page)


def test_a_command_written_late_after_its_frame_replays_at_its_recorded_time(
    tmp_path: Path,
) -> None:
    """A replay wrote each command at the time of the frame its tick ran on, the live run at
    its own later time: the mode model waits ``settle`` after a mode command for packet 35
    to follow, from when it was written. After a cliff fall a host busy for 0.36 s wrote Safe
    0.36 s after the fall's frame, and the frames queued meanwhile (in Passive) came with it;
    the replay, its Safe 0.36 s earlier, took them for a second fall, and its tree starved
    where the live one went on (session 27's run1.jsonl: ``expected Motors (138) 8a 07, sent
    nothing`` at 75 s of 92 s)."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    source, path = tmp_path / "edge.yaml", tmp_path / "run.jsonl"
    source.write_text(over_the_edge(brushes_again=True))
    mission = load_mission(source, {}, profile=CREATE2)
    link = BusyAfterTheFall(Simulator(load_world(tmp_path / "ledge.yaml"), CREATE2, 0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=20.0,
                     record=Recording(path, str(source)))  # fmt: skip
    live = stack.run()
    stack.close()
    assert live.outcome is Outcome.SUCCESS, live.reason
    assert live.falls == {"cliff": 1} and live.stale_frames_dropped >= 20
    record = load_record(path)
    summary, difference, written = _replayed(path)
    assert difference is None, difference
    assert written == record.out_bytes
    assert summary.falls == live.falls and summary.ticks == live.ticks


def test_a_record_made_before_the_end_note_still_replays_and_says_no_ending(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The end note is new: a record without it is read and replayed as before."""
    lines = _recorded_run(tmp_path, capsys)
    [ending] = [line for line in lines if '"ended"' in line]
    assert json.loads(ending)["note"] == {
        "ended": "success", "reason": "", "time": 3.03, "tick": 202, "at": "after"
    }  # fmt: skip
    older = tmp_path / "older.jsonl"
    older.write_text("".join(line for line in lines if line != ending), encoding="utf-8")
    assert load_record(older).ending is None
    assert main(["replay", str(older)]) == 0
    out = capsys.readouterr().out
    assert "the tree wrote the same" in out and "replay: the recorded run" not in out
    assert main(["replay", str(tmp_path / "run.jsonl")]) == 0
    assert "replay: the recorded run ended in success at t=3.03 s\n" in capsys.readouterr().out


WAITED = """\
mission: early
tree:
  sequence:
    - mode: safe
    - wait: {wait}
    - drive: {{velocity: 100 mm/s, radius: spin_left, duration: 1s}}
    - wait: 1s
"""


def test_a_command_the_replayed_tree_writes_before_its_frames_is_a_difference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A record made with ``wait: 3s``, replayed against the mission changed to ``wait: 1s``:
    the tree writes the drive 2 s before the live run did, the same bytes. Before, the clock
    jumped to the drive's recorded time over the 133 frames between, and the replay made up a
    gap ("no frame was read for 2.00 s"), 198 lost frames and a poor link, then said "the tree
    wrote the same 43 bytes", exit 0. Now it is the first difference, exit 1, and nothing is
    made up."""
    source, path = tmp_path / "early.yaml", tmp_path / "run.jsonl"
    source.write_text(WAITED.format(wait="3s"))
    argv = ["run", str(source), "--fast", "--display", "none", "--record", str(path)]
    assert main(argv) == 0
    source.write_text(WAITED.format(wait="1s"))
    capsys.readouterr()
    assert main(["replay", str(path)]) == 1
    out = capsys.readouterr().out
    assert (
        "expected Drive (137) 89 00 64 00 01, sent Drive (137) 89 00 64 00 01 2.00 s early: "
        "the recorded run read 133 more of the robot's chunks before writing it"
    ) in out, out
    assert_quoted("docs/runtime.md", "replay: first difference at mission time 1.020 s", out)
    summary, difference, _ = _replayed(path)
    assert difference is not None
    assert summary.frames_lost == 0 and summary.unread_gaps == 0
    source.write_text(WAITED.format(wait="3s"))  # the recorded mission: the same bytes
    assert main(["replay", str(path)]) == 0


INTERRUPTING = '''\
import os
import signal
from roomba_bt.behaviours import Condition, declare

@declare("interrupting", kind="condition")
class Interrupting(Condition):
    """A Ctrl-C landing inside a tick: the first tick past 50 whose tree queued a command
    (the signal itself: a ``raise KeyboardInterrupt`` of the plugin's own is its error)."""

    def check(self, snapshot):
        queued = self.robot.outbox.queued
        if os.environ.get("INTERRUPT_MID_TICK") and snapshot.tick >= 50 and queued:
            signal.raise_signal(signal.SIGINT)
        return True
'''
SPINS_WHILE = """\
mission: interrupted
plugins: [./interrupting.py]
tree:
  parallel:
    - sequence:
        - mode: safe
        - drive: {velocity: 200 mm/s, radius: spin_left, duration: 1s}
        - drive: {velocity: 100 mm/s, radius: spin_right, duration: 1s}
    - wait: 60s
      while: {interrupting: {}}
"""


def test_a_ctrl_c_inside_a_tick_is_noted_before_it_and_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C (or SIGTERM) raised inside the tree's tick ends the run before that tick's
    commands are written. The end note said "after" the tick, so the replay ticked it in full
    and wrote the spin the live run never sent, where the record holds the safe stop:
    "expected Drive (137) 89 00 00 00 00, sent Drive (137) 89 00 64 ff ff", exit 1."""
    (tmp_path / "interrupting.py").write_text(INTERRUPTING)
    source, path = tmp_path / "interrupted.yaml", tmp_path / "run.jsonl"
    source.write_text(SPINS_WHILE)
    monkeypatch.setenv("INTERRUPT_MID_TICK", "1")
    argv = ["run", str(source), "--fast", "--display", "none", "--allow-plugin-files"]
    assert main([*argv, "--record", str(path)]) == 130
    monkeypatch.delenv("INTERRUPT_MID_TICK")
    ending = load_record(path).ending
    assert ending is not None
    assert (ending["reason"], ending["tick"], ending["at"]) == (SIGINT_SAID, 68, "before")
    capsys.readouterr()
    # the record's own "allow_plugin_files": true is never honoured: the flag is the fix
    assert main(["replay", str(path)]) == 2
    err = capsys.readouterr().err
    assert "fix a copy" not in err, err
    assert (
        f"replay: the record's run was allowed the plugin files of its mission {source} "
        "(--allow-plugin-files); a replay imports them only when told: pass "
        "--allow-plugin-files if you trust them (they run as Python code)"
    ) in err, err
    assert main(["replay", str(path), "--allow-plugin-files"]) == 0
    out = capsys.readouterr().out
    assert "replay: the tree wrote the same 38 bytes as the recorded run" in out, out
    assert f"replay: the recorded run was interrupted ({SIGINT_SAID}) at t=1.02 s" in out


class _CtrlCBetweenFrames(SimLink):
    """A Ctrl-C that comes while the run waits for its next frame (in the read), after
    ``after`` reads: the tick before it was written whole."""

    def __init__(self, simulator: Simulator, after: int) -> None:
        super().__init__(simulator)
        self.reads_left = after

    def read(self, timeout: float) -> bytes:
        self.reads_left -= 1
        if self.reads_left == 0:
            raise KeyboardInterrupt
        return super().read(timeout)


def _interrupted_record(tmp_path: Path, mission: str, link: Any) -> Path:
    """The record of ``mission`` run over ``link`` until the link's Ctrl-C ends it."""
    source, path = tmp_path / "m.yaml", tmp_path / "run.jsonl"
    source.write_text(mission)
    stack = RunStack(load_mission(source, {}, profile=CREATE2), link, profile=CREATE2,
                     record=Recording(path, str(source)))  # fmt: skip
    assert stack.run(raise_interrupts=False).outcome is Outcome.INTERRUPTED
    stack.close()
    return path


def test_a_ctrl_c_between_frames_is_still_noted_after_the_last_tick(tmp_path: Path) -> None:
    """The other half: an interrupt in the wait for a frame comes after the last tick, which
    the replay then ticks in full, as live."""
    link = _CtrlCBetweenFrames(Simulator(load_world("empty-room"), CREATE2, 0), after=80)
    path = _interrupted_record(tmp_path, SPIN, link)
    ending = load_record(path).ending
    assert ending is not None and (ending["reason"], ending["at"]) == (SIGINT_SAID, "after")
    summary, difference, written = _replayed(path)
    assert difference is None and written == load_record(path).out_bytes
    assert summary.ticks > 1


def test_a_record_a_run_is_still_writing_is_said_to_be_so_not_killed(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    record_held: Callable[[Path], subprocess.Popen[str]],
) -> None:
    """A record read while its run wrote it was called killed ('the run was killed?'), and
    its replay's end the run's: no end line, and a run holds its lock. Judged by the lock,
    not the file's age: one unchanged for an hour (a run 10 minutes in, a long stall) is
    still being written while its run holds it, and one changed a moment ago is not once
    the run was killed (``kill -9``: its lock went with it); before, the age said both
    wrong."""
    live = tmp_path / "live.jsonl"
    live.write_text("".join(_killed_at(_recorded_run(tmp_path, capsys), 1.2)), encoding="utf-8")
    run = record_held(_left_a_minute(live))
    assert load_record(live).being_written
    assert main(["replay", str(live)]) == 0
    out = capsys.readouterr().out
    assert (
        "replay: the record ends at 1.200 s without the run's end: the record is still being "
        "written (a run in progress?)" in out
    )
    assert "killed" not in out
    run.kill()  # kill -9
    run.wait(timeout=HANG_S)
    os.utime(live)  # changed a moment ago: read 2 s after the kill
    assert not load_record(live).being_written
    assert main(["replay", str(live)]) == 0
    assert "the run was killed, or writing its record failed" in capsys.readouterr().out
    assert not load_record(tmp_path / "run.jsonl").being_written  # ended: whatever its age


def test_where_no_lock_can_be_asked_for_the_record_s_age_says_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without flock (Windows), a record without its end line that changed in the last
    seconds is taken for one a run writes, as before the lock was asked."""
    from roomba_bt.runtime import claimed

    monkeypatch.setattr(claimed, "fcntl", None)
    live = tmp_path / "live.jsonl"
    live.write_text("".join(_killed_at(_recorded_run(tmp_path, capsys), 1.2)), encoding="utf-8")
    assert load_record(live).being_written
    assert not load_record(_left_a_minute(live)).being_written


def test_a_record_cut_short_by_a_file_size_limit_says_so_not_killed(
    tmp_path: Path, child: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    """``ulimit -f 20``: the recording stopped at 20 KiB while the run went on ("File too
    large" in its summary), and its replay said "the run was killed?". The record now ends
    with a note saying why (room made for it by cutting back to a whole line), and replay
    says the recording stopped."""
    record = tmp_path / "cut.jsonl"
    limit = 20 * 1024
    script = (
        "import resource, sys\n"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))\n"
        "from roomba_bt.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    mission = str(MISSIONS / "bump-and-turn.yaml")
    run = child([sys.executable, "-c", script, "run", mission, "--fast", "--display", "none",
                 "-p", "duration=6s", "--record", str(record)])  # fmt: skip
    out, err = run.communicate(timeout=HANG_S)
    assert run.returncode == 0, err
    assert "stopped at" in out and "File too large" in out
    assert record.stat().st_size <= limit
    lines = record.read_text(encoding="utf-8").splitlines()
    assert json.loads(lines[-1])["note"] == {"record_stopped": "File too large"}
    loaded = load_record(record)  # every line whole: nothing cut in the middle of one
    assert loaded.recording_stopped == "File too large"
    assert not loaded.being_written
    unended = loaded.unended()
    assert unended is not None and unended.startswith("the recording stopped (File too large)")
    assert "killed" not in unended


def test_a_record_names_its_robot_and_start_and_one_without_them_still_loads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The header had no port and no start time: a record copied off the laptop could not
    be tied to a robot or a lesson. A record made before has neither and replays as ever."""
    lines = _recorded_run(tmp_path, capsys)
    header = json.loads(lines[0])
    assert header["port"] == "simulator empty-room"
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", header["started"])
    older = tmp_path / "older.jsonl"
    before = {k: v for k, v in header.items() if k not in ("port", "started")}
    older.write_text("".join([json.dumps(before) + "\n", *lines[1:]]), encoding="utf-8")
    assert main(["replay", str(older)]) == 0
    assert "as the recorded run" in capsys.readouterr().out
    wrong = tmp_path / "wrong.jsonl"
    wrong.write_text("".join([json.dumps({**header, "port": 3}) + "\n", *lines[1:]]))
    assert main(["replay", str(wrong)]) == 2
    assert f"{wrong}:1: header field 'port' is 3; expected text" in capsys.readouterr().err


def test_a_record_that_fails_at_its_header_stopped_at_zero_not_minus_zero() -> None:
    """``--record /dev/full``: the header's write fails before the first chunk, and the
    warning said ``stopped at -0.000 s`` (now() - now() on a clock that moves)."""
    recording = RecordingTransport(_Link(drift=0.001), "/dev/full", {})  # type: ignore[arg-type]
    assert recording.stopped is not None
    assert recording.stopped.startswith("stopped at 0.000 s: No space left on device")


def _mission_with_a_library(folder: Path, velocity: str) -> Path:
    """A mission driving by a subtree of its own library, which also includes the shipped
    undock library; the library's drive at ``velocity``."""
    (folder / "moves.yaml").write_text(
        f"subtrees:\n  forward:\n    tree: {{drive: {{velocity: {velocity}, distance: 10cm}}}}\n",
        encoding="utf-8",
    )
    mission = folder / "trip.yaml"
    mission.write_text(
        "include: [moves.yaml, 'roomba-bt:lib/undock.yaml']\n"
        "tree:\n"
        "  sequence:\n"
        "    - subtree: undock\n"
        "    - mode: safe\n"
        "    - subtree: forward\n",
        encoding="utf-8",
    )
    return mission


def test_a_record_names_the_roomba_bt_that_made_it_and_each_file_its_mission_came_from(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Records carried no version and nothing of the files they were made with: an owner
    could not tell which build made a file, nor that a shipped library had changed since."""
    from roomba_bt import __version__
    from roomba_bt.mission.shipped import SHIPPED_DIR

    mission = _mission_with_a_library(tmp_path, "200 mm/s")
    record = tmp_path / "trip.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    capsys.readouterr()
    header = json.loads(record.read_text(encoding="utf-8").splitlines()[0])
    assert header["roomba_bt_version"] == __version__
    undock = (SHIPPED_DIR / "lib" / "undock.yaml").read_bytes()
    assert header["sources"] == {  # by their paths from the record's folder (session 29)
        mission.name: hashlib.sha256(mission.read_bytes()).hexdigest(),
        "moves.yaml": hashlib.sha256((tmp_path / "moves.yaml").read_bytes()).hexdigest(),
        "roomba-bt:lib/undock.yaml": hashlib.sha256(undock).hexdigest(),
    }
    assert next(iter(header["sources"])) == mission.name  # the mission's first
    bad = tmp_path / "bad.jsonl"
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    bad.write_text("".join([json.dumps({**header, "sources": ["x"]}) + "\n", *lines[1:]]))
    assert main(["replay", str(bad)]) == 2
    assert f"{bad}:1: header field 'sources' is ['x']; expected {{file: SHA-256}}" in (
        capsys.readouterr().err
    )


def test_a_replay_that_differs_names_the_files_changed_since_the_record_was_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """An old record of a mission including the shipped undock library differed on replay
    once the library changed (``expected Drive ... sent Drive 0``), and nothing said why:
    the owner hunted for a change in their own mission. A record made before (no digests)
    says nothing more than it did."""
    mission = _mission_with_a_library(tmp_path, "200 mm/s")
    record = tmp_path / "trip.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    capsys.readouterr()
    # the record as a previous release would have made it (0.2.0, replayed by a later one:
    # 0.1.0 named no files) with another undock library
    monkeypatch.setattr("roomba_bt.runtime.provenance.__version__", "0.3.0")
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    header["roomba_bt_version"] = "0.2.0"
    header["sources"]["roomba-bt:lib/undock.yaml"] = "0" * 64
    record.write_text("".join([json.dumps(header) + "\n", *lines[1:]]), encoding="utf-8")
    _mission_with_a_library(tmp_path, "150 mm/s")  # and the owner's library changed since
    assert main(["replay", str(record)]) == 1
    out = capsys.readouterr().out
    assert "replay: first difference at" in out
    moves = (tmp_path / "moves.yaml").resolve()
    assert (
        f"replay: {moves} changed since this record was made: a difference may come from it" in out
    )
    assert (
        "replay: roomba-bt:lib/undock.yaml changed since this record was made (roomba-bt "
        "0.2.0 -> 0.3.0): a difference may come from it" in out
    )
    assert_quoted("docs/runtime.md", "replay: roomba-bt:lib/undock.yaml changed", out)
    assert str(mission.resolve()) not in out  # the mission file itself is as it was
    older = tmp_path / "older.jsonl"
    before = {k: v for k, v in header.items() if k not in ("roomba_bt_version", "sources")}
    older.write_text("".join([json.dumps(before) + "\n", *lines[1:]]), encoding="utf-8")
    assert main(["replay", str(older)]) == 1
    out = capsys.readouterr().out
    assert "replay: first difference at" in out
    assert "changed since" not in out


def test_a_record_of_a_shipped_mission_made_before_replays_it_where_its_path_is_gone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A record made before session 29 of ``run dock`` holds the mission's path in the
    installation that made it; a moved venv, a new Python or another machine lacks that path.
    The replay refused it ("not found; pass --mission FILE, or --mission bump-and-turn"), on
    every machine but the one that made it: it now replays this installation's shipped
    mission of that name, and says so. A path elsewhere, or a shipped name this release
    does not ship, is still refused."""
    lines = _recorded_run(tmp_path, capsys)
    header = json.loads(lines[0])
    gone = "/usr/lib/python3.12/site-packages/roomba_bt/missions/bump-and-turn.yaml"
    moved = tmp_path / "moved.jsonl"
    moved.write_text("".join([json.dumps({**header, "mission": gone}) + "\n", *lines[1:]]))
    assert main(["replay", str(moved)]) == 0
    out, err = capsys.readouterr()
    assert "as the recorded run" in out
    assert (
        f"{moved}: mission {gone!r} is not here (the installation that made the record had "
        "it); replaying the shipped mission 'bump-and-turn' of roomba-bt" in err
    )
    page = {str(moved): "r.jsonl", "bump-and-turn": "dock"}  # the page's record is of dock
    assert_quoted("docs/runtime.md", "r.jsonl: mission '/usr/lib/", err, names=page)
    elsewhere = "/home/me/missions/bump-and-turn.yaml"  # not the shipped one's folder
    moved.write_text("".join([json.dumps({**header, "mission": elsewhere}) + "\n", *lines[1:]]))
    assert main(["replay", str(moved)]) == 2
    assert capsys.readouterr().err.rstrip().endswith("not found; pass --mission FILE")
    unshipped = "roomba-bt:retired.yaml"  # shipped by the release that made the record
    moved.write_text("".join([json.dumps({**header, "mission": unshipped}) + "\n", *lines[1:]]))
    assert main(["replay", str(moved)]) == 2
    assert (
        f"mission {unshipped!r} not found (shipped with the roomba-bt that made the record, "
        "not with" in capsys.readouterr().err
    )


def test_a_replay_says_which_shipped_file_it_reads_when_another_may_have_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 0.1.0 record of ``run dock`` names the shipped file in the venv that made it; where
    that venv is still on the machine, the replay read the old release's file without a
    word, and one made by another release replayed this release's shipped mission alike.
    Each says now which file it reads, and how to choose another (``--mission``)."""
    from roomba_bt import __version__
    from roomba_bt.mission.shipped import SHIPPED_DIR

    lines = _recorded_run(tmp_path, capsys)
    header = {k: v for k, v in json.loads(lines[0]).items() if k != "roomba_bt_version"}
    old = tmp_path / "old-venv/lib/python3.11/site-packages/roomba_bt/missions"
    old.mkdir(parents=True)
    old_file = old / "bump-and-turn.yaml"
    old_file.write_bytes((SHIPPED_DIR / "bump-and-turn.yaml").read_bytes())
    ours = SHIPPED_DIR / "bump-and-turn.yaml"
    record = tmp_path / "old.jsonl"
    record.write_text("".join([json.dumps({**header, "mission": str(old_file)}) + "\n",
                               *lines[1:]]))  # fmt: skip
    assert main(["replay", str(record)]) == 0
    err = capsys.readouterr().err
    assert (
        f"{record}: replaying {old_file}, the shipped mission 'bump-and-turn' of the "
        "installation that made the record (roomba-bt 0.1.0 or earlier, as the record names "
        f"no release), not this installation's ({ours}, roomba-bt {__version__}): --mission "
        "bump-and-turn replays this one's" in err
    )
    assert main(["replay", str(record), "--mission", "bump-and-turn"]) == 0
    assert "replaying" not in capsys.readouterr().err
    by_name = {**header, "mission": "roomba-bt:bump-and-turn.yaml"}
    record.write_text("".join([json.dumps({**by_name, "roomba_bt_version": "0.1.9"}) + "\n",
                               *lines[1:]]))  # fmt: skip
    assert main(["replay", str(record)]) == 0
    assert (
        f"{record}: replaying the shipped mission 'bump-and-turn' of roomba-bt {__version__} "
        f"({ours}); the record was made by roomba-bt 0.1.9, whose 'bump-and-turn' may differ: "
        "--mission FILE replays another" in capsys.readouterr().err
    )
    record.write_text("".join([json.dumps({**by_name, "roomba_bt_version": __version__})
                               + "\n", *lines[1:]]))  # fmt: skip
    assert main(["replay", str(record)]) == 0
    assert "replaying" not in capsys.readouterr().err


def test_a_record_of_a_shipped_mission_run_by_name_replays_in_another_installation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``roomba-bt run dock --record r.jsonl`` wrote the shipped file's path into the header
    (``.../site-packages/roomba_bt/missions/dock.yaml``), which only the venv that made it
    has. The header names a shipped mission as an include names it, so a replay in another
    venv, or on another machine, finds its own."""
    import shutil

    with monkeypatch.context() as patched:  # the machine that records
        another_installation(patched, tmp_path / "venv")
        record = tmp_path / "run.jsonl"
        argv = ["run", "bump-and-turn", "--fast", "--display", "none", "-p", "duration=2s"]
        assert main([*argv, "--record", str(record)]) == 0
    shutil.rmtree(tmp_path / "venv")  # the venv is gone; this one replays it
    capsys.readouterr()
    monkeypatch.chdir(tmp_path)
    assert main(["replay", str(record)]) == 0
    out, err = capsys.readouterr()
    assert "replay: the tree wrote the same" in out and "as the recorded run" in out
    assert "not here" not in err and "differ" not in out
    header = load_record(record).header
    assert header["mission"] == "roomba-bt:bump-and-turn.yaml"
    assert "roomba-bt:bump-and-turn.yaml" in header["sources"]


FAR_S29 = '''\
from roomba_bt.behaviours import Condition, declare

FAR = {far}


@declare("far_s29", kind="condition")
class FarS29(Condition):
    """Whether to drive far: the plugin's own answer."""

    def check(self, snapshot):
        return FAR
'''
FAR_OR_NEAR = """\
mission: far-or-near
tree:
  sequence:
    - mode: safe
    - selector:
        - sequence:
            - far_s29: {}
            - drive: {velocity: 200 mm/s, distance: 5 cm}
        - drive: {velocity: 100 mm/s, distance: 5 cm}
"""


def _plugin(
    monkeypatch: pytest.MonkeyPatch, site: Path, version: str | None, far: bool = True
) -> None:
    """The distribution ``bt-far-s29`` installed on ``site`` (on sys.path) at ``version``
    (None: uninstalled, its module and metadata gone), its condition ``far_s29`` answering
    ``far``; what the next command loads (a fresh registry, the module imported again)."""
    import importlib
    import shutil

    import roomba_bt.behaviours.registry as registry

    for old in site.glob("bt_far_s29-*.dist-info"):
        shutil.rmtree(old)
    module = site / "s29_far.py"
    if version is None:
        module.unlink()
    else:
        module.write_text(FAR_S29.format(far=far), encoding="utf-8")
        info = site / f"bt_far_s29-{version}.dist-info"
        info.mkdir(parents=True)
        (info / "METADATA").write_text(
            f"Metadata-Version: 2.1\nName: bt-far-s29\nVersion: {version}\n"
        )
        (info / "entry_points.txt").write_text("[roomba_bt.behaviours]\ns29_far = s29_far\n")
    sys.modules.pop("s29_far", None)
    importlib.invalidate_caches()
    monkeypatch.setattr(registry, "_DEFAULT", None)


def test_a_record_names_its_plugins_and_a_replay_that_differs_names_the_one_changed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A behaviour from an installed plugin package had no digest in the record: a replay
    after the plugin changed (upgraded, or edited in an editable install) differed, and
    nothing said why. The header names each plugin the tree used, its version and its
    modules' digest, and a replay that differs names the plugin changed since."""
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # the edited module read again
    _plugin(monkeypatch, site, "1.0", far=True)
    mission, record = tmp_path / "far.yaml", tmp_path / "far.jsonl"
    mission.write_text(FAR_OR_NEAR, encoding="utf-8")
    assert main(["run", str(mission), "--fast", "--display", "none", "--record", str(record)]) == 0
    capsys.readouterr()
    plugins = load_record(record).header["plugins"]
    assert list(plugins) == ["bt-far-s29"] and plugins["bt-far-s29"]["version"] == "1.0"
    assert re.fullmatch("[0-9a-f]{64}", plugins["bt-far-s29"]["sha256"])
    assert main(["replay", str(record)]) == 0
    assert "plugin" not in capsys.readouterr().out  # the same plugin: nothing said

    _plugin(monkeypatch, site, "1.0", far=False)  # edited in place, its version unchanged
    assert main(["replay", str(record)]) == 1
    out = capsys.readouterr().out
    assert "replay: first difference at" in out
    assert (
        "replay: plugin bt-far-s29 1.0's code changed since this record was made (the same "
        "version: an editable install, or a rebuild): a difference may come from it" in out
    )
    dirt = {"bt-far-s29": "roomba-bt-dirt"}  # the pages' plugin, their versions
    assert_quoted("docs/plugins.md", "replay: plugin roomba-bt-dirt 0.1.0's code", out,
                  numbers=True, names=dirt)  # fmt: skip
    _plugin(monkeypatch, site, "2.0", far=False)  # upgraded
    assert main(["replay", str(record)]) == 1
    out = capsys.readouterr().out
    assert (
        "replay: plugin bt-far-s29 changed since this record was made (1.0 -> 2.0): a "
        "difference may come from it" in out
    )
    assert_quoted("docs/runtime.md", "replay: plugin roomba-bt-dirt changed", out, numbers=True,
                  names=dirt)  # fmt: skip
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    bad = tmp_path / "bad.jsonl"
    bad.write_text("".join([json.dumps({**header, "plugins": ["x"]}) + "\n", *lines[1:]]))
    assert main(["replay", str(bad)]) == 2
    assert f"{bad}:1: header field 'plugins' is ['x']; expected " in capsys.readouterr().err


@pytest.mark.parametrize(
    "command", ["replay", pytest.param("monitor", marks=pytest.mark.extra("monitor"))]
)
def test_a_replay_whose_recorded_plugin_is_not_installed_says_so_first(
    command: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The header names the plugin and its version, yet a replay (the monitor's too) of a
    record whose plugin was uninstalled said only ``unknown node 'far_s29'``, with any
    "did you mean" a built-in of a near name would give: the plugin is said first, and the
    node is not offered a built-in."""
    from roomba_bt.runtime.provenance import absent_plugins

    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    _plugin(monkeypatch, site, "1.0", far=True)
    mission, record = tmp_path / "far.yaml", tmp_path / "far.jsonl"
    mission.write_text(FAR_OR_NEAR, encoding="utf-8")
    assert main(["run", str(mission), "--fast", "--display", "none", "--record", str(record)]) == 0
    capsys.readouterr()
    _plugin(monkeypatch, site, None)  # pip uninstall bt-far-s29
    assert main([command, str(record)]) == 2
    err = capsys.readouterr().err
    first, second, *_, last = err.splitlines()
    assert first == (
        "roomba-bt: this record was made with plugin bt-far-s29 1.0, which is not "
        "installed (pip install bt-far-s29==1.0)"
    )
    assert second.endswith(
        "unknown node 'far_s29' (perhaps of plugin bt-far-s29 1.0, not installed) "
        "[tree.sequence[1].selector[0].sequence[0].far_s29]"
    )
    if command == "replay":  # its last word sent the user to fix a mission that was whole
        assert last == (
            f"replay: the record's mission {mission} names behaviours of plugin bt-far-s29, "
            "not installed here as the record's run had it: install it as said above and "
            "replay again (the mission needs no fix)"
        ), last
        lab = {"bt-far-s29": "roomba-bt-lab", str(mission): "lab.yaml"}  # docs/plugins.md's
        assert_quoted("docs/plugins.md", "roomba-bt: this record was made with plugin", err,
                      numbers=True, names=lab)  # fmt: skip
        assert_quoted("docs/plugins.md", "replay: the record's mission lab.yaml", err, names=lab)
    header = load_record(record).header
    _plugin(monkeypatch, site, "2.0", far=True)  # another version: said by its version
    [other] = absent_plugins(header)
    assert other.said() == (
        "this record was made with plugin bt-far-s29 1.0, and 2.0 is installed (pip install "
        "bt-far-s29==1.0)"
    )
    assert main(["replay", str(record)]) == 0  # it compiles: the drift line says the rest
    assert "this record was made with" not in capsys.readouterr().err


def test_a_replay_says_in_one_line_that_it_ran_on_other_files_than_the_record_was_made_with(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The files changed since were named only when the replay differed: one whose bytes
    were the same said nothing of running on other files (a shipped library changed in an
    upgrade, in a branch the run never took), and a difference with no file changed said
    nothing of the roomba-bt that made the record. One line says it now, before the verdict:
    changed files and plugins always, another release only when the bytes differ (an older
    record that still replays is the common case: not noise on every one)."""
    from roomba_bt import __version__

    mission = _mission_with_a_library(tmp_path, "200 mm/s")
    record = tmp_path / "trip.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    assert "recorded with" not in capsys.readouterr().out  # nothing differs: nothing said
    mission.write_text(mission.read_text() + "# a comment: the same tree\n", encoding="utf-8")
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    said = f"replay: recorded with roomba-bt {__version__} (this release too); 1 of its 3 "
    assert f"{said}source files differs now\nreplay: the tree wrote the same" in out
    assert "changed since" not in out  # the names are for a difference
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    # a later release replays a 0.2.0 record (0.1.0 wrote no release: said otherwise)
    monkeypatch.setattr("roomba_bt.runtime.provenance.__version__", "0.3.0")
    header["roomba_bt_version"] = "0.2.0"
    header["sources"][mission.name] = hashlib.sha256(mission.read_bytes()).hexdigest()
    older = tmp_path / "older.jsonl"
    older.write_text("".join([json.dumps(header) + "\n", *lines[1:]]), encoding="utf-8")
    assert main(["replay", str(older)]) == 0
    assert "recorded with" not in capsys.readouterr().out  # the same bytes: the release unsaid
    _mission_with_a_library(tmp_path, "150 mm/s")  # the tree decides otherwise now
    header["sources"] = load_record(record).header["sources"]  # each digest as the files now
    header["sources"]["moves.yaml"] = hashlib.sha256(
        (tmp_path / "moves.yaml").read_bytes()
    ).hexdigest()
    header["sources"][mission.name] = hashlib.sha256(mission.read_bytes()).hexdigest()
    older.write_text("".join([json.dumps(header) + "\n", *lines[1:]]), encoding="utf-8")
    assert main(["replay", str(older)]) == 1
    out = capsys.readouterr().out
    assert "replay: recorded with roomba-bt 0.2.0 (this is 0.3.0)\n" in out
    assert_quoted("docs/runtime.md", "replay: recorded with roomba-bt 0.2.0 (this is", out)
    assert "changed since" not in out


def test_a_hand_edited_header_reaches_the_terminal_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stranger's record wrote its ``roomba_bt_version`` raw in replay's "recorded with"
    line: an escape sequence there retitled the window and recoloured the output (OSC 52
    writes the clipboard). Every header text is shown escaped, as the label is."""
    mission = _mission_with_a_library(tmp_path, "200 mm/s")
    record = tmp_path / "trip.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--record", str(record)]
    assert main(argv) == 0
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    header["roomba_bt_version"] = "V\x1b]0;PWNED\x07\x1b[31m\u202e"
    header["label"] = "L\x1b[2J"
    edited = tmp_path / "edited.jsonl"
    edited.write_text("".join([json.dumps(header) + "\n", *lines[1:]]), encoding="utf-8")
    mission.write_text(mission.read_text() + "# a comment: the same tree\n", encoding="utf-8")
    capsys.readouterr()
    assert main(["replay", str(edited)]) == 0
    out, err = capsys.readouterr()
    assert "\x1b" not in out + err and "\u202e" not in out + err, out + err
    assert "replay: recorded with roomba-bt V\\x1b]0;PWNED\\x07\\x1b[31m\\u202e (this is" in out


TWO_A_TICK = """
mission: two-a-tick
tree:
  sequence:
    - mode: safe
    - parallel:
        - motors: {main_brush: true}
        - drive: {velocity: 100 mm/s, radius: spin_left, duration: 1s}
"""


class _CtrlCBetweenWrites(SimLink):
    """A Ctrl-C that comes between two writes of one tick: before its first Drive (137),
    which the tick's flush writes after its Motors (138)."""

    def write(self, data: bytes) -> None:
        if data[0] == 137 and not getattr(self, "interrupted", False):
            self.interrupted = True
            raise KeyboardInterrupt
        super().write(data)


def test_a_ctrl_c_between_two_writes_of_a_tick_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Ctrl-C that lands between two of a tick's writes left part of the tick on the wire
    (its Motors, not its Drive). The end note said "before" the tick, and the replay ended
    before ticking it: "expected Motors (138) 8a 04, sent Drive (137) 89 00 00 00 00", exit
    1. The note holds the bytes written when it came (``written``), and the replay ticks
    that frame and writes its commands up to there. A record made before (no ``written``)
    replays as it did."""
    link = _CtrlCBetweenWrites(Simulator(load_world("empty-room"), CREATE2, 0))
    path = _interrupted_record(tmp_path, TWO_A_TICK, link)
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    record = load_record(path)
    outbound = record.outbound
    assert f"replay: the tree wrote the same {len(outbound)} bytes as the recorded run" in out
    assert f"replay: the recorded run was interrupted ({SIGINT_SAID}) at t=0.01 s" in out
    ending = record.ending
    assert ending is not None and (ending["reason"], ending["at"]) == (SIGINT_SAID, "before")
    motors = bytes.fromhex("8a04")
    assert outbound[ending["written"] - 2 : ending["written"]] == motors  # then the safe stop
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    made_before = tmp_path / "before.jsonl"
    made_before.write_text(
        "".join(re.sub(r', "written": \d+', "", line) for line in lines), encoding="utf-8"
    )
    assert main(["replay", str(made_before)]) == 1
    assert "expected Motors (138) 8a 04" in capsys.readouterr().out


@pytest.mark.parametrize("tick", [-5, 2.5, True, "40"])
def test_a_note_whose_tick_is_no_stream_tick_is_refused_at_its_line(
    tick: object, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A hand-edited ``"tick": -5`` was taken: the replay paused at tick 0 and said the run
    diverged there."""
    lines = _recorded_run(tmp_path, capsys)
    note = {"t": 0.5, "d": "note", "note": {"pause": "paused by the operator", "at": "before",
                                           "tick": tick}}  # fmt: skip
    edited = tmp_path / "edited.jsonl"
    edited.write_text("".join([*lines[:40], json.dumps(note) + "\n", *lines[40:]]), "utf-8")
    assert main(["replay", str(edited)]) == 2
    err = capsys.readouterr().err
    assert f"{edited}:41: a note's tick is {json.dumps(tick)}; expected the stream's tick" in err


def test_a_key_written_twice_in_a_line_is_refused_at_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A chunk line with two ``"d"`` (JSON keeps the last) replayed to a difference, exit 1:
    no line run --record writes holds a key twice. A header's alike."""
    lines = _recorded_run(tmp_path, capsys)
    chunk = json.loads(lines[40])
    twice = lines[40].replace('"d": ', f'"d": "{"in" if chunk["d"] == "out" else "out"}", "d": ')
    damaged = tmp_path / "damaged.jsonl"
    damaged.write_text("".join([*lines[:40], twice, *lines[41:]]), encoding="utf-8")
    assert main(["replay", str(damaged)]) == 2
    assert (
        capsys.readouterr()
        .err.strip()
        .endswith(
            f'{damaged}:41: the key "d" twice in one object; expected each key once, as run '
            "--record writes it"
        )
    )
    header = lines[0].replace('{"format": ', '{"format": "x", "format": ')
    damaged.write_text("".join([header, *lines[1:]]), encoding="utf-8")
    assert main(["replay", str(damaged)]) == 2
    assert f'{damaged}:1: header holds the key "format" twice' in capsys.readouterr().err
