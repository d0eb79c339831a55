"""``roomba-bt monitor RECORD --from/--to`` and ``replay --to``: a window of a long record.

A 12-hour record took 190 s and 561 MB to open whole; a window keeps only its own ticks and
stops reading at its end, and shows in it what the whole record's page shows there."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.recording import load_record

from .conftest import SHUTTLE


@pytest.fixture(scope="module")
def shuttle_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """20 s of the shuttle (its statuses flip a few times a second), recorded."""
    record = tmp_path_factory.mktemp("window") / "shuttle.jsonl"
    argv = ["run", str(SHUTTLE), "--fast", "--timeout", "20s", "--display", "none"]
    assert main([*argv, "--record", str(record)]) == 1  # it times out
    return record


def _replayed(record: Path, window: tuple[float, float | None] = (0.0, None)) -> RunFeed:
    loaded = load_mission(SHUTTLE, {}, profile=CREATE2)
    recorded = load_record(record)
    packets = tuple(recorded.header["packets"])
    feed, _ = replay_into_feed(recorded, loaded, CREATE2, packets, 115200, "shuttle", window=window)
    return feed


def test_a_window_holds_the_same_ticks_as_the_whole_record_there(shuttle_record: Path) -> None:
    whole = _replayed(shuttle_record)
    window = _replayed(shuttle_record, (5.0, 10.0))
    first, last = window.window()
    assert first is not None and last is not None
    assert 5.0 <= first.time < 5.02 and 10.0 <= last.time < 10.02
    assert window.ring.first == first.seq > 0  # the ticks before it are counted, not kept
    assert window.record(first.seq - 1) is None
    for seq in range(first.seq, last.seq + 1):  # each tick as the whole record's page has it
        assert window.record(seq) == whole.record(seq)
    assert window.at(first.tick - 10)[0] == first  # a seek before the window: its start
    # the events before the window are the whole record's too
    before = [(e.kind, e.text) for e in whole.events if e.time < 5.0]
    assert before and before == [(e.kind, e.text) for e in window.events if e.time < 5.0]
    assert window.finished is not None
    assert window.finished.startswith("shown up to t=10.00 s of mission time (--to); the record")
    assert "diverged" not in window.finished
    assert window.ending is None  # the safe stop shown is the recorded run's, not here


def test_replay_to_compares_up_to_there(
    shuttle_record: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["replay", str(shuttle_record), "--to", "5s"]) == 0
    out = capsys.readouterr().out
    assert "replay: compared up to mission time 5.0" in out, out
    assert "replay: the tree wrote the same bytes up to there" in out
    assert "first difference" not in out


@pytest.mark.parametrize(
    ("command", "options", "said"),
    [
        ("monitor", ["--from", "10s", "--to", "5s"], "--from 10s is not before --to 5s"),
        ("monitor", ["--from", "1h"], "--from 1h: the record ends at 20.0"),
        ("monitor", ["--to", "soon"], "--to 'soon': "),
        ("replay", ["--to", "0"], "--to '0': must be a finite duration, more than 0 s"),
    ],
)
def test_a_window_that_will_not_do_is_said_exit_2(
    shuttle_record: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
    options: list[str],
    said: str,
) -> None:
    if command == "monitor":
        pytest.importorskip("aiohttp")
        options = [*options, "--monitor", "0"]
    assert main([command, str(shuttle_record), *options]) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt {command}: {said}" in err, err
    assert "Traceback" not in err
