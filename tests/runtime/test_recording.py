"""``--record`` as a run killed outright leaves it, and ``replay`` of what it left."""

from __future__ import annotations

import json
from pathlib import Path

from roomba_bt.runtime.recording import RecordingTransport

FRAME = bytes.fromhex("131a070009000a000b000c001906511a0a88220023022b020d2c020dca")
HEADER = {"profile": "create2", "baud": 115200, "mission": "bump-and-turn", "packets": [7]}


class _Link:
    """A port on a clock the test moves: a stream frame every 15 ms."""

    name = "link"
    is_open = True

    def __init__(self) -> None:
        self.t = 50.0

    def now(self) -> float:
        return self.t

    def read(self, timeout: float) -> bytes:
        self.t += 0.015
        return FRAME

    def write(self, data: bytes) -> None:
        pass

    def close(self) -> None:
        pass


def test_the_record_reaches_the_file_as_the_run_goes(tmp_path: Path) -> None:
    """A run killed outright (kill -9) leaves what the record had flushed: before, only the
    run's end flushed it, and a killed 2 s run's record stopped at 1.22 s (an 8 KiB buffer).
    Now the file, read while the run goes on, holds the run up to a quarter second ago
    (recording.FLUSH_EVERY_S)."""
    path = tmp_path / "run.jsonl"
    link = _Link()
    recording = RecordingTransport(link, path, HEADER)  # type: ignore[arg-type]
    for _ in range(134):  # 2 s of frames, each with the tick's Drive
        recording.read(0.015)
        recording.write(bytes([137, 0, 200, 128, 0]))
    last_t = link.t - 50.0 - 0.015  # the first read's arrival is the record's 0
    on_disk = path.read_text(encoding="utf-8")  # what a kill -9 now would leave
    lines = on_disk.splitlines()
    assert on_disk.endswith("\n")
    assert json.loads(lines[0])["format"] == "roomba-bt-record"
    assert json.loads(lines[-1])["t"] >= last_t - 0.25
    recording.close()
