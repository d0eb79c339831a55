"""One writer per output file: ``run --record`` and ``eval --out`` refuse a file another
roomba-bt writes (a classroom where every student typed ``--record run.jsonl``: the second
run truncated the first's record under it, leaving NUL bytes and a lost run)."""

from __future__ import annotations

import contextlib
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from waits import HANG_S, line  # tests/waits.py: a hang's bound, a line within it

from roomba_bt.cli import main
from roomba_bt.runtime.recording import RecordingTransport, load_record
from roomba_bt.transport.testing import NullTransport

from .simrun import write_mission

MISSION = """
mission: short-drive
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: 5 cm}
"""
BUMP = str(Path(__file__).resolve().parents[2] / "missions" / "bump-and-turn.yaml")
#: what a refused second writer is told, after the option and the path
SAID = "another roomba-bt (a run or an eval) is writing it"
#: a port that is not there: a run that got as far as opening it would exit 3
NO_PORT = "/dev/roomba-bt-test-no-such-port"
#: an earlier run's record, which a refused or failed run must leave as it was
EARLIER = '{"format": "roomba-bt-record", "version": 2}\n{"t": 0.0, "d": "end"}\n'

#: another process writing the file (a run): holds its lock, an exclusive flock, until told
#: to stop
HOLD_THE_FILE = """
import fcntl, os, sys
fd = os.open(sys.argv[1], os.O_WRONLY)
fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
print("held", flush=True)
sys.stdin.read()
"""


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path, MISSION, "short.yaml")


@pytest.fixture
def held_elsewhere(tmp_path: Path) -> Iterator[Path]:
    """An earlier record that another process (another run) is writing now."""
    with held(tmp_path / "run.jsonl", EARLIER) as path:
        yield path


@contextlib.contextmanager
def held(path: Path, content: str) -> Iterator[Path]:
    """``path``, holding ``content``, claimed by another process until the block ends."""
    path.write_text(content)
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD_THE_FILE, str(path)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout is not None
        said = line(holder.stdout, f"a process holding {path.name}")
        assert said == "held\n", said
        yield path
    finally:
        holder.communicate("", timeout=HANG_S)


def test_a_record_another_run_writes_is_refused_before_the_robot_is_opened(
    held_elsewhere: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Exit 2 with the file and why, before the port is tried (a missing port would be exit
    3), and the other run's record is not touched."""
    code = main(["run", BUMP, "--port", NO_PORT, "--record", str(held_elsewhere)])
    assert code == 2
    err = capsys.readouterr().err
    assert f"roomba-bt run: --record {held_elsewhere}: {SAID}" in err
    assert "give this one another file" in err
    assert NO_PORT not in err
    assert held_elsewhere.read_text() == EARLIER


def test_a_simulated_run_into_a_record_another_run_writes_is_refused_whole(
    held_elsewhere: Path, mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The simulator's run too: before, it emptied the file under the other run and wrote its
    own record into it (the other's lost, NUL bytes where it went on writing)."""
    code = main(["run", str(mission), "--fast", "--display", "none",
                 "--record", str(held_elsewhere)])  # fmt: skip
    assert code == 2
    captured = capsys.readouterr()
    assert SAID in captured.err
    assert "outcome" not in captured.out  # it never ran
    assert held_elsewhere.read_text() == EARLIER


def test_a_run_that_fails_before_it_starts_leaves_the_record_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The record is claimed at the start but emptied only when the run begins: a run whose
    port is missing keeps an earlier record whole, and leaves no empty file where there was
    none."""
    earlier = tmp_path / "earlier.jsonl"
    earlier.write_text(EARLIER)
    assert main(["run", BUMP, "--port", NO_PORT, "--record", str(earlier)]) == 3
    assert earlier.read_text() == EARLIER
    new = tmp_path / "new.jsonl"
    assert main(["run", BUMP, "--port", NO_PORT, "--record", str(new)]) == 3
    assert not new.exists()
    capsys.readouterr()


def test_a_record_is_free_again_once_its_run_ended(
    mission: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The lock goes with the run: the same path, run after run, is written each time."""
    from roomba_bt.runtime.claimed import ClaimedFile

    record = tmp_path / "run.jsonl"
    for _ in range(2):
        assert main(["run", str(mission), "--fast", "--display", "none",
                     "--record", str(record)]) == 0  # fmt: skip
        assert load_record(record).ended
        ClaimedFile(record).release()  # nobody holds it
    capsys.readouterr()


def test_a_record_made_from_python_is_refused_where_another_writes_it(tmp_path: Path) -> None:
    """``RunStack(record=Recording(path))`` and ``RecordingTransport`` claim the file too:
    refused with FileInUse (an OSError), the file not emptied."""
    from roomba_bt.runtime.claimed import ClaimedFile, FileInUse

    path = tmp_path / "run.jsonl"
    path.write_text(EARLIER)
    with ClaimedFile(path), pytest.raises(FileInUse) as refused:
        RecordingTransport(NullTransport(), path, {"profile": "create2"})
    assert refused.value.strerror is not None and SAID in refused.value.strerror
    assert refused.value.filename == str(path)
    assert path.read_text() == EARLIER


def test_a_claimed_file_is_emptied_only_when_it_is_written(tmp_path: Path) -> None:
    from roomba_bt.runtime.claimed import ClaimedFile

    path = tmp_path / "out.jsonl"
    path.write_text("an earlier sweep's results\n")
    claim = ClaimedFile(path)
    assert path.read_text() == "an earlier sweep's results\n"
    with claim.open_text() as out:
        out.write("new\n")
    assert path.read_text() == "new\n"
    ClaimedFile(path).release()  # the writer's close let go of the lock


def test_eval_out_another_sweep_writes_is_refused_before_any_episode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two sweeps into one ``--out``: both said "results written" and the file held one
    sweep's episodes. A sweep holds its partial file (``OUT.partial.jsonl``, the records as
    they finish) from its start: the second is refused before its first episode, exit 2,
    and neither the first's partial records nor an earlier ``OUT`` are emptied."""
    out = tmp_path / "e.jsonl"
    earlier = '{"seed": 100, "outcome": "success"}\n'
    out.write_text(earlier)
    first_sweeps = '{"seed": 0, "outcome": "success"}\n'
    with held(tmp_path / "e.jsonl.partial.jsonl", first_sweeps) as partial:
        code = main(["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--timeout", "1s",
                     "--no-progress", "--out", str(out)])  # fmt: skip
        assert code == 2
        captured = capsys.readouterr()
        assert f"roomba-bt eval: --out {out}: {SAID}" in captured.err
        assert "results written" not in captured.err
        assert "success" not in captured.out  # no episode ran
        assert out.read_text() == earlier
        assert partial.read_text() == first_sweeps


def test_eval_out_is_written_and_free_again_after_the_sweep(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from roomba_bt.runtime.claimed import ClaimedFile

    out = tmp_path / "e.jsonl"
    for _ in range(2):
        assert main(["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--timeout", "1s",
                     "--no-progress", "--out", str(out), "--force"]) in (0, 1)  # fmt: skip
        assert len(out.read_text().splitlines()) == 1
        ClaimedFile(out).release()  # nobody holds it
    assert "results written" in capsys.readouterr().err
