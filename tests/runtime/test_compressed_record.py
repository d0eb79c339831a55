"""``--record run.jsonl.gz``: a record written gzip-compressed, and every reader of records
(``replay``, ``--record``'s check of the file it writes over; ``roomba-bt monitor RECORD``:
tests/monitor/test_cli.py) reading it, whatever its name."""

from __future__ import annotations

import errno
import gzip
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.robot.safety import InterruptGuard
from roomba_bt.runtime.claimed import ClaimedFile
from roomba_bt.runtime.recording import (
    FLUSH_EVERY_S,
    GZIP_MAGIC,
    MAX_BLANK_LINES,
    RecordingTransport,
    RecordNotStarted,
    RecordSize,
    load_record,
    record_size,
)

from .test_recording import HEADER, MISSIONS, _left_a_minute, _Link, two_seconds_recorded

BUMP_AND_TURN = str(MISSIONS / "bump-and-turn.yaml")


def _record(path: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> Path:
    """A 3 s bump-and-turn recorded on the virtual clock into ``path``: compressed when
    its name ends in ``.gz``, as every one here but ``plain.jsonl``."""
    argv = ["run", BUMP_AND_TURN, "--fast", "--display", "none", "-p", "duration=3s"]
    assert main([*argv, "--record", str(path), *extra]) == 0
    capsys.readouterr()
    assert path.read_bytes().startswith(GZIP_MAGIC) == (path.suffix == ".gz")
    return path


def _replayed(path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """``replay path``'s stdout; it must find no difference."""
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    assert "the tree wrote the same" in out, out
    return out


def test_a_record_named_gz_is_written_compressed_and_replays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--record x.jsonl.gz`` wrote plain text under a ``.gz`` name (``file``: ASCII text),
    and ``replay`` refused a gzipped record ('byte 0x8b, not UTF-8 text')."""
    record = _record(tmp_path / "run.jsonl.gz", capsys)
    data = record.read_bytes()
    assert data.startswith(GZIP_MAGIC)
    lines = gzip.decompress(data).decode("utf-8").splitlines()
    assert json.loads(lines[0])["format"] == "roomba-bt-record"
    assert json.loads(lines[-1])["d"] == "end"
    assert len(data) * 4 < sum(len(line) + 1 for line in lines)  # it compresses
    assert "as the recorded run" in _replayed(record, capsys)
    assert load_record(record).ended


def test_a_compressed_record_made_twice_is_the_same_bytes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run --reproducible`` writes the same record again: gzip's header holds no time
    and no file name that would differ."""
    first = _record(tmp_path / "a.jsonl.gz", capsys, "--reproducible")
    second = _record(tmp_path / "b.jsonl.gz", capsys, "--reproducible")
    assert first.read_bytes() == second.read_bytes()


def test_a_compressed_record_reaches_the_file_as_the_run_goes(tmp_path: Path) -> None:
    """A run killed outright leaves a plain record readable up to its last flush (a quarter
    second ago); a compressed one too: each flush is a zlib sync flush, so what the file
    holds at any moment decompresses up to there, though gzip's trailer is not written."""
    path = tmp_path / "run.jsonl.gz"
    recording, last_t = two_seconds_recorded(path)
    killed = tmp_path / "killed.jsonl.gz"
    shutil.copyfile(path, killed)  # what a kill -9 now would leave
    recording.close()
    assert killed.read_bytes().startswith(GZIP_MAGIC)
    record = load_record(_left_a_minute(killed))
    assert not record.ended and record.last_t >= last_t - 0.25
    assert record.unended() is not None and "killed" in str(record.unended())


def test_a_record_is_read_by_its_bytes_not_its_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Decided: compressed or not is what the file's first bytes say (gzip's magic number),
    so a compressed record renamed, or a plain one named ``.gz``, replays all the same."""
    compressed = _record(tmp_path / "run.jsonl.gz", capsys)
    renamed = compressed.rename(tmp_path / "renamed.jsonl")
    _replayed(renamed, capsys)
    plain = _record(tmp_path / "plain.jsonl", capsys)
    named_gz = plain.rename(tmp_path / "plain.jsonl.gz")
    _replayed(named_gz, capsys)


def test_damaged_compressed_data_is_an_error_naming_the_file_not_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = _record(tmp_path / "run.jsonl.gz", capsys)
    data = bytearray(record.read_bytes())
    data[len(data) // 2 : len(data) // 2 + 64] = b"\xff" * 64
    record.write_bytes(bytes(data))
    assert main(["replay", str(record)]) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt replay: {record}:" in err and "damaged compressed data" in err, err
    assert "Traceback" not in err


@pytest.mark.parametrize("field", ["crc", "length"])
def test_a_record_whose_gzip_trailer_is_torn_is_replayed_up_to_it_and_said_so(
    field: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A run ended by a signal inside a gzip write left a trailer (CRC-32, then length) that
    did not match its text, every line readable: replay refused the whole file, exit 2.
    It replays (exit by the bytes), and a warning says where the record is damaged."""
    record = _record(tmp_path / "run.jsonl.gz", capsys)
    data = bytearray(record.read_bytes())
    at = len(data) - (8 if field == "crc" else 4)
    data[at] ^= 0xFF
    record.write_bytes(bytes(data))
    assert main(["replay", str(record)]) == 0
    captured = capsys.readouterr()
    assert "the tree wrote the same" in captured.out, captured.out
    assert "Traceback" not in captured.err
    said = caplog.text  # the CLI's log handler writes it to stderr
    assert f"{record}: damaged after line" in said, said
    assert "gzip trailer" in said and "gzip -t refuses the file" in said
    assert ("CRC check failed" if field == "crc" else "Incorrect length") in said
    assert load_record(record).ended  # the run's end line, before the damage, was read


def test_a_compressed_record_may_be_written_over_as_a_plain_one_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--record`` writes over an earlier record only; a compressed one was taken for
    someone else's file ('a file that is not a record') and refused."""
    record = _record(tmp_path / "run.jsonl.gz", capsys)
    _record(record, capsys)
    _replayed(record, capsys)
    mission = tmp_path / "mission.gz"
    mission.write_bytes(gzip.compress(b"tree: {wait: 1s}\n"))
    argv = ["run", BUMP_AND_TURN, "--fast", "--display", "none", "--record", str(mission)]
    with pytest.raises(SystemExit):
        main(argv)
    assert "a file that is not a record" in capsys.readouterr().err


def test_a_compressed_record_cut_by_a_file_size_limit_says_so_as_a_plain_one_does(
    tmp_path: Path, child: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    """``ulimit -f``: the recording stops and the run goes on to its safe stop, as for a
    plain record. The compressed file held no note of why (its replay said "the run was
    killed, or writing its record failed"); it now ends with the plain record's note, and
    is a whole gzip file up to there."""
    record = tmp_path / "cut.jsonl.gz"
    limit = 8 * 1024
    script = (
        "import resource, sys\n"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))\n"
        "from roomba_bt.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    run = child([sys.executable, "-c", script, "run", BUMP_AND_TURN, "--fast", "--display",
                 "none", "-p", "duration=20s", "--record", str(record)])  # fmt: skip
    out, err = run.communicate(timeout=HANG_S)
    assert run.returncode == 0, err
    assert "stopped at" in out and "File too large" in out
    assert "final mode   Passive" in out and "safe stop    sent" in out  # stopped as ever
    assert record.stat().st_size <= limit
    lines = gzip.decompress(record.read_bytes()).decode("utf-8").splitlines()
    assert json.loads(lines[-1])["note"] == {"record_stopped": "File too large"}
    loaded = load_record(record)
    assert not loaded.ended and loaded.last_t > 1.0
    assert loaded.recording_stopped == "File too large"
    assert str(loaded.unended()).startswith("the recording stopped (File too large)")


class _FillsUp(io.RawIOBase):
    """A file on a disk with ``room`` bytes free: the write that reaches them writes what
    fits, and the next one raises ENOSPC, as write(2) does on a full disk."""

    def __init__(self, file: io.RawIOBase, room: int) -> None:
        super().__init__()
        self._file = file
        self._room = room

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._file.fileno()

    def tell(self) -> int:
        return self._file.tell()

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        return self._file.seek(offset, whence)

    def write(self, data: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        if self._room == 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        taken = self._file.write(bytes(data[: self._room])) or 0
        self._room -= taken
        return taken

    def close(self) -> None:
        self._file.close()
        super().close()


class _ClaimedOnAFullDisk(ClaimedFile):
    """``run --record``'s claim of a file on a disk with ``room`` bytes free."""

    def __init__(self, path: Path, room: int) -> None:
        super().__init__(path)
        self._room = room

    def open_binary(self) -> IO[bytes]:
        raw = super().open_binary().detach()  # type: ignore[attr-defined]
        return io.BufferedWriter(_FillsUp(raw, self._room))

    def _write_at(self, data: bytes, offset: int) -> int:
        """What the disk takes of ``data`` past the file's end (``make_room``'s trial)."""
        if self._room == 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return super()._write_at(data[: self._room], offset)

    def open_text(self, newline: str | None = None) -> IO[str]:
        return io.TextIOWrapper(self.open_binary(), encoding="utf-8", newline=newline)  # type: ignore[arg-type]


class _SignalledAsItWrites(_FillsUp):
    """A file whose next write once :attr:`armed` brings ``signum`` to this process as the
    write returns: its handler's interrupt comes inside ``GzipFile.write``, after the
    compressed text reached the file and before it was counted into gzip's trailer."""

    def __init__(self, file: io.RawIOBase, signum: int) -> None:
        super().__init__(file, room=1 << 40)
        self.signum = signum
        self.armed = False

    def write(self, data: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        taken = super().write(data)
        if self.armed:
            self.armed = False
            signal.raise_signal(self.signum)
        return taken


class _ClaimedSignalled(ClaimedFile):
    """``run --record``'s claim of a file that brings a signal as it is written
    (:class:`_SignalledAsItWrites`, unbuffered: gzip writes to it straight)."""

    def __init__(self, path: Path, signum: int) -> None:
        super().__init__(path)
        self.signum = signum
        self.raw: _SignalledAsItWrites | None = None

    def open_binary(self) -> IO[bytes]:
        raw = super().open_binary().detach()  # type: ignore[attr-defined]
        self.raw = _SignalledAsItWrites(raw, self.signum)
        return self.raw  # type: ignore[return-value]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_while_gzip_writes_leaves_a_whole_compressed_record(
    tmp_path: Path, signum: int
) -> None:
    """The run's handler raised wherever the main thread was: inside ``GzipFile.write``,
    between its write of the compressed text and its count of it, the record's trailer no
    longer matched its text (``gzip -t``: crc error, length error) and replay refused the
    whole file, exit 2: 3 of 17 SIGTERM'd ``--fast`` records (session 35). The interrupt
    now comes once the line is written; the record ends with its end line, a whole gzip
    file."""
    path = tmp_path / "run.jsonl.gz"
    claimed = _ClaimedSignalled(path, signum)
    recording = RecordingTransport(_Link(), path, HEADER, claimed)  # type: ignore[arg-type]
    assert claimed.raw is not None
    with pytest.raises(KeyboardInterrupt), InterruptGuard(wall_clock=False):
        claimed.raw.armed = True
        for _ in range(1000):  # 15 s of frames: the signal comes in the first second
            recording.read(0.015)
            recording.write(bytes([137, 0, 200, 128, 0]))
    assert not claimed.raw.armed
    recording.close()
    text = gzip.decompress(path.read_bytes()).decode("utf-8")  # CRC check failed, before
    lines = [json.loads(line) for line in text.splitlines()]
    assert lines[-1]["d"] == "end"
    assert load_record(path).ended


def test_signalled_fast_runs_leave_compressed_records_that_verify(
    tmp_path: Path, script_job: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    """``kill -TERM`` / ``kill -INT`` to ``run --fast --record X.gz`` started from a script,
    as the long-haul operator's loop did (3 of 17 records failed ``gzip -t``): each sent
    once the record is under way, at a moment of the run's own; every record is a whole
    gzip file ending with the run's end line, and the robot was stopped and left in
    Passive."""
    for trial, signum in enumerate([signal.SIGTERM, signal.SIGINT] * 3):
        record = tmp_path / f"k_{trial}.jsonl.gz"
        run = script_job(["run", BUMP_AND_TURN, "--fast", "--display", "none", "-p",
                          "duration=1h", "--record", str(record)])  # fmt: skip
        while run.poll() is None and (not record.exists() or record.stat().st_size < 20000):
            time.sleep(0.01)  # until the run is well into its record
        run.send_signal(signum)
        out, err = run.communicate(timeout=HANG_S)
        assert run.returncode == 130, err
        assert "final mode   Passive" in out and "safe stop    sent" in out
        text = gzip.decompress(record.read_bytes()).decode("utf-8")  # CRC check failed, before
        assert json.loads(text.splitlines()[-1])["d"] == "end", trial
        assert load_record(record).ending is not None


@pytest.mark.parametrize("name", ["run.jsonl", "run.jsonl.gz"])
def test_a_record_cut_by_a_full_disk_ends_with_its_note_plain_or_compressed(
    tmp_path: Path, name: str
) -> None:
    """ENOSPC: the recording stops (said once, the run goes on) and the file, within the
    bytes it held, ends with the note of why, read back by ``load_record``. A compressed
    record got no note (replay: "the run was killed, or writing its record failed")."""
    path, room = tmp_path / name, 6000
    link = _Link()
    recording = RecordingTransport(link, path, HEADER, _ClaimedOnAFullDisk(path, room))  # type: ignore[arg-type]
    for _ in range(1000):  # 15 s of frames: far more than the room
        recording.read(0.015)
        recording.write(bytes([137, 0, 200, 128, 0]))
    stopped = recording.stopped
    assert stopped is not None and "No space left on device" in stopped
    recording.close()  # the run's end: nothing more reaches the file
    assert path.stat().st_size <= room
    loaded = load_record(path)
    assert loaded.recording_stopped == "No space left on device"
    assert str(loaded.unended()).startswith("the recording stopped (No space left on device)")
    stopped_at = float(stopped.split()[2])  # "stopped at 0.765 s: ..."
    last_chunk = max(t for t, _, _ in loaded.chunks())
    # read up to the cut: a plain record's last whole line with room for the note after it;
    # a compressed one's last flush, or the one before when fewer bytes than the note's
    # reached the file after it
    assert stopped_at - 3 * FLUSH_EVERY_S <= last_chunk < stopped_at
    if name.endswith(".gz"):  # a whole gzip file: its trailer's CRC and length check out
        text = gzip.decompress(path.read_bytes()).decode("utf-8")
        assert json.loads(text.splitlines()[-1])["note"] == {
            "record_stopped": "No space left on device"
        }


@pytest.mark.parametrize("made_here", [True, False])
@pytest.mark.parametrize("name", ["run.jsonl", "run.jsonl.gz"])
def test_a_required_record_on_a_full_disk_refuses_and_leaves_no_empty_file_it_made(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, name: str, made_here: bool
) -> None:
    """``run --require-record`` on a full disk: the header is not written, and the record
    refuses (the caller's "not started") without first warning that the run goes on, and
    removes the 0-byte file it made; a file that was there before is not removed, nor
    emptied (it was: the file was emptied before its header failed, session 36)."""
    path = tmp_path / name
    if not made_here:
        path.write_text("an earlier record\n", encoding="utf-8")
    claimed = _ClaimedOnAFullDisk(path, room=0)
    with pytest.raises(RecordNotStarted, match="No space left on device"):
        RecordingTransport(_Link(), path, HEADER, claimed, required=True)  # type: ignore[arg-type]
    assert "the run goes on" not in caplog.text
    assert path.exists() is not made_here
    claimed.release()  # as run's end does
    assert path.exists() is not made_here
    if not made_here:
        assert path.read_text(encoding="utf-8") == "an earlier record\n"


@pytest.mark.parametrize("name", ["run.jsonl", "run.jsonl.gz"])
def test_a_required_record_with_room_for_only_part_of_its_header_keeps_the_earlier_one(
    tmp_path: Path, name: str
) -> None:
    """A disk that takes a few bytes more, not the header: the earlier record is as it was."""
    path = tmp_path / name
    path.write_text("an earlier record\n", encoding="utf-8")
    claimed = _ClaimedOnAFullDisk(path, room=20)
    with pytest.raises(RecordNotStarted, match="No space left on device"):
        RecordingTransport(_Link(), path, HEADER, claimed, required=True)  # type: ignore[arg-type]
    claimed.release()
    assert path.read_text(encoding="utf-8") == "an earlier record\n"


#: the run each record size limit's test makes: a plain record writes its 64 kB in about
#: 10 s of run, a compressed one in about 80 s (each run well under a second on --fast)
LIMITED_RUNS = [("run.jsonl", "duration=20s"), ("run.jsonl.gz", "duration=3min")]


@pytest.mark.parametrize(("name", "duration"), LIMITED_RUNS)
def test_a_record_stops_at_its_size_limit_and_the_run_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, duration: str
) -> None:
    """``run --record-max``: a night's record could fill the disk. At the limit the recording
    stops with the note a full disk writes, the file (compressed or not) within the limit
    on disk; the run goes on to its end and safe stop, its summary saying the mission time
    of the cut; the record replays up to there."""
    path = tmp_path / name
    argv = ["run", BUMP_AND_TURN, "--fast", "--display", "none", "-p", duration]
    assert main([*argv, "--record", str(path), "--record-max", "64kB"]) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out and "safe stop    sent" in out
    said = re.search(
        r"record       stopped at mission time (\d+\.\d{3}) s: --record-max 64 kB reached; "
        "the file ends there",
        out,
    )
    assert said is not None, out
    cut = float(said[1])
    assert path.stat().st_size <= 64_000
    loaded = load_record(path)
    assert not loaded.ended and loaded.recording_stopped == "--record-max 64 kB reached"
    # the file is checked at each flush, and cut back to a whole line or a flush before it
    assert cut - 4 * FLUSH_EVERY_S <= loaded.last_t <= cut + 2 * FLUSH_EVERY_S
    replayed = _replayed(path, capsys)
    assert "the recording stopped (--record-max 64 kB reached)" in replayed


def test_a_python_caller_s_record_size_limit_is_said_in_its_words(tmp_path: Path) -> None:
    """``RunStack(record=Recording(..., max_bytes=...))``: the stop names the argument the
    program set, not ``--record-max``, a flag it never gave (in the summary and the record)."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import Recording, RunStack
    from roomba_bt.sim import SimLink, Simulator, load_world

    path = tmp_path / "run.jsonl"
    mission = load_mission(BUMP_AND_TURN, {"duration": "20s"}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    limited = Recording(path, BUMP_AND_TURN, max_bytes=64_000)
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, record=limited)
    summary = stack.run()
    stack.close()
    assert load_record(path).recording_stopped == "Recording's max_bytes 64 kB reached"
    assert "--record-max" not in str(summary)


def test_a_record_size_limit_below_the_least_is_refused_before_the_file_is_made(
    tmp_path: Path,
) -> None:
    """From Python, as ``--record-max`` refuses it: a limit the header and a few seconds of
    run do not fit in, said before the file is claimed or emptied."""
    path = tmp_path / "small.jsonl"
    with pytest.raises(ValueError, match="max_bytes=1000: a record's size limit is 64 kB or more"):
        RecordingTransport(_Link(), path, HEADER, max_bytes=1000)  # type: ignore[arg-type]
    assert not path.exists()


def test_a_record_size_limit_without_a_record_is_a_usage_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", BUMP_AND_TURN, "--fast", "--record-max", "1GB"]) == 2
    assert "--record-max limits the --record file: give --record FILE too" in (
        capsys.readouterr().err
    )


def test_a_compressed_record_s_text_size_is_its_trailer_s_and_unknown_without_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``roomba-bt monitor``'s notice said a compressed record's file size as the record's.
    Its text's size is in gzip's trailer; a run killed while writing it leaves none, and the
    notice says the file's size alone, and that the record's own is known once read (taken
    to be ten times the file's, for whether to say anything at all)."""
    from roomba_bt.cli import monitor_cmd

    path, killed = tmp_path / "run.jsonl.gz", tmp_path / "killed.jsonl.gz"
    recording, _ = two_seconds_recorded(path)
    shutil.copyfile(path, killed)  # what a kill -9 now would leave
    recording.close()
    text = len(gzip.decompress(path.read_bytes()))
    assert record_size(path) == RecordSize(path.stat().st_size, text, compressed=True)
    assert record_size(killed) == RecordSize(killed.stat().st_size, None, compressed=True)
    plain = tmp_path / "plain.jsonl"
    plain.write_bytes(gzip.decompress(path.read_bytes()))
    assert record_size(plain) == RecordSize(text, text, compressed=False)

    size = killed.stat().st_size
    monkeypatch.setattr(monitor_cmd, "READING_NOTICE_BYTES", 10 * size)
    notice = monitor_cmd.reading_notice(str(killed))
    assert notice is not None
    assert f"({size / 1e6:.1f} MB compressed, its record's own size known once read)" in notice
    monkeypatch.setattr(monitor_cmd, "READING_NOTICE_BYTES", 10 * size + 1)
    assert monitor_cmd.reading_notice(str(killed)) is None


def test_a_record_of_blank_lines_is_refused_at_the_first_too_many(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stranger's 1 MB ``.gz`` of a gigabyte of line ends (a blank line costs the read of
    a chunk, for one byte) kept ``replay`` and ``monitor`` reading for most of an hour.
    :data:`MAX_BLANK_LINES` of them are read past, as an editor may leave a few; the next
    is refused at its line, exit 2."""
    lines = gzip.decompress(_record(tmp_path / "run.jsonl.gz", capsys).read_bytes())
    header, rest = lines.split(b"\n", 1)
    for blanks, rc in ((MAX_BLANK_LINES, 0), (MAX_BLANK_LINES + 1, 2)):
        path = tmp_path / f"blank{blanks}.jsonl.gz"
        path.write_bytes(gzip.compress(header + b"\n" * (blanks + 1) + rest))
        assert main(["replay", str(path)]) == rc
        err = capsys.readouterr().err
        assert (rc == 2) == (
            f"{path}:{MAX_BLANK_LINES + 2}: 10,001 blank lines; allowed: at most 10,000 "
            "(run --record writes none: a file damaged, or no record)" in err
        ), err


def test_a_small_compressed_file_of_a_great_many_lines_is_refused_early(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A stranger's 3 MB ``.gz`` of 27 million short chunk lines (1 GB of text, each line
    valid) kept ``replay`` reading for minutes: a compressed record holding more lines than
    bytes (run --record's hold one line in about 4) is refused at the line it is found
    (counted from 100,000 lines on; 1,000 here), saying how to read it if it is a record.
    A real record, and the same lines decompressed, are read."""
    from roomba_bt.runtime import recording

    monkeypatch.setattr(recording, "DENSITY_CHECKED_FROM", 1000)
    record = _record(tmp_path / "run.jsonl.gz", capsys)
    assert load_record(record).ended  # a real record: far fewer lines than bytes
    header = gzip.decompress(record.read_bytes()).split(b"\n", 1)[0]
    lines = header + b"\n" + b'{"t": 0.000000, "d": "in", "b": "00"}\n' * 50_000
    small = tmp_path / "small.jsonl.gz"
    small.write_bytes(gzip.compress(lines))
    assert main(["replay", str(small)]) == 2
    err = capsys.readouterr().err
    said = re.search(rf"{small}:(\d+): ([\d,]+) lines from ([\d,]+) bytes of compressed data", err)
    assert said is not None, err
    assert int(said[1]) <= 11_000  # at the first count past it, not the file's end
    assert "If it is a record, decompress it (zcat small.jsonl.gz > small.jsonl)" in err
    plain = tmp_path / "small.jsonl"
    plain.write_bytes(lines)  # the way out: a plain file's lines cost its size on the disk
    assert load_record(plain).out_bytes == 0
