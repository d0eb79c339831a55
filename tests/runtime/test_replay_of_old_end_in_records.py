"""Records of runs ended in Off (``end_in="stop"``, ``run --end-in stop``) whose header does
not say so, each made by that code and kept under tests/data/records, of ``safe_sit.yaml``
(Safe, then a 0.1 s wait; on the simulator):

- ``end_in_stop_0_1_0.jsonl``: ``roomba-bt run safe_sit.yaml --fast --end-in stop --record``
  by 0.1.0 (``git worktree add /tmp/v010 e80f20a``), whose header had no ``options``;
- ``end_in_stop_by_a_program.jsonl``: a Python program's ``RunStack(..., end_in="stop",
  record=Recording(...))`` by a 0.2.0 development build before the header's ``end_in``
  (``git worktree add /tmp/old f7b8c36a^``).

Their replay ended its stop with Start, as a run does by default, and each record's last
byte was its first difference ("expected Stop (173) ad, sent Start (128) 80", exit 1). Their
last bytes say how the stop ended (``recording.recorded_end_in``): they replay to it now."""

from __future__ import annotations

from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.oi import commands as oi
from roomba_bt.runtime.recording import END_IN_UNSAID, load_record

RECORDS = Path(__file__).resolve().parents[1] / "data" / "records"
#: the safe stop from Safe that ends in Off: drive 0, motors off, pause the stream, Stop
STOP_IN_OFF = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.stop().data


def _replay(record: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(["replay", str(record), "--mission", str(RECORDS / "safe_sit.yaml")])
    return code, capsys.readouterr().out


@pytest.mark.parametrize("name", ["end_in_stop_0_1_0.jsonl", "end_in_stop_by_a_program.jsonl"])
def test_an_old_record_ended_in_stop_replays_to_its_end(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    record = load_record(RECORDS / name)
    assert "end_in" not in record.header and "options" not in record.header, record.header
    assert record.outbound.endswith(STOP_IN_OFF), record.outbound.hex()
    code, out = _replay(RECORDS / name, capsys)
    assert code == 0 and "first difference" not in out, out
    assert f"the tree wrote the same {record.out_bytes} bytes as the recorded run" in out, out
    assert "final mode   Off" in out, out


def test_an_old_record_whose_stop_is_not_its_last_bytes_says_what_differs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A record whose header says nothing and whose last bytes are not a stop's (here the
    program's, a Start written after its Stop, as a Stop the robot did not confirm was asked
    after): replayed ending in Passive, as before, and the difference at its Stop said, not
    left a bare "expected Stop (173) ad, sent Start (128) 80"."""
    text = (RECORDS / "end_in_stop_by_a_program.jsonl").read_text()
    last = '"b": "89000000008a009600ad"}'
    assert text.count(last) == 1
    changed = tmp_path / "asked_after.jsonl"
    changed.write_text(text.replace(last, '"b": "89000000008a009600ad80"}'))
    code, out = _replay(changed, capsys)
    assert code == 1, out
    assert "expected Stop (173) ad, sent Start (128) 80" in out, out
    assert f"replay: {END_IN_UNSAID}" in out.splitlines(), out
    assert_quoted("docs/runtime.md", "replay: the recorded run wrote Stop (173)", out)
