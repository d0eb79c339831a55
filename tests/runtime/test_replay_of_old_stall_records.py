"""Records made before 2e6d3655 (session 39) of a run ended from outside around a stall, each
made by that code (``git worktree add /tmp/old 2e6d3655^``: the run of ``spin.yaml`` on
``roomba-bt sim --pty --stream-gap-at 1.5 --stream-gap-s 3 --faults-from-stream``, in the
process, as test_cli_pty.py's ``test_a_run_stopped_in_a_stall_over_the_pty_replays_byte_for_byte``
runs it), kept under tests/data/records:

- ``ctrl_c_before_a_tick_asked_after.jsonl``: a Ctrl-C in the gate before the tick on a frame
  held 0.5 s into the stream's gap; the stop, unconfirmed, was asked after with a Query List,
  which the end note's ``written`` counted (33 for 28: the link's count, moved on at the end
  by what the link alone wrote since). Its replay waited for those 5 bytes for ever: "first
  difference ... expected Drive (137) 89 00 00 00 00, sent nothing", exit 1.
- ``ctrl_c_in_a_stall.jsonl``: a Ctrl-C while the watchdog rode the gap, after its drive 0;
  the note, "after" the last frame's tick, has no count. Its replay ended at the tick and
  compared its stop with the watchdog's drive 0: "first difference ... expected Drive (137)
  89 00 00 00 00, sent Motors (138) 8a 00", exit 1.

Both replay to the stop now and say the known miscount, exit 0, as a stop asked for in a
stall does (test_cli_pty.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.oi import commands as oi
from roomba_bt.robot.discovery import PROBE_QUERY
from roomba_bt.runtime.recording import load_record

RECORDS = Path(__file__).resolve().parents[1] / "data" / "records"
SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def _replays_to_its_stop(name: str, said: str, capsys: pytest.CaptureFixture[str]) -> str:
    """``name``'s replay (of ``spin.yaml``): exit 0, no difference, ``said`` said, and the
    tree's bytes the record's, all of them; what it printed."""
    record = RECORDS / name
    code = main(["replay", str(record), "--mission", str(RECORDS / "spin.yaml")])
    out = capsys.readouterr().out
    assert code == 0 and "first difference" not in out, out
    assert f"replay: {said}" in out, out
    written = len(load_record(record).outbound)
    assert f"the tree wrote the same {written} bytes as the recorded run" in out, out
    return out


def test_an_old_ctrl_c_before_a_tick_whose_stop_was_asked_after_replays_to_its_stop(
    capsys: pytest.CaptureFixture[str],
) -> None:
    record = load_record(RECORDS / "ctrl_c_before_a_tick_asked_after.jsonl")
    ending, outbound = record.ending, record.outbound
    assert ending is not None and (ending["at"], ending["written"]) == ("before", 33), ending
    # as the old code counted it: the 28 bytes before the Ctrl-C and the probe's 5 after the stop
    assert outbound[28:].startswith(oi.halt().data + oi.motors_off().data + SAFE_END)
    assert outbound.endswith(SAFE_END + PROBE_QUERY), outbound.hex()
    _replays_to_its_stop(
        "ctrl_c_before_a_tick_asked_after.jsonl",
        "the end note counts 33 bytes written when the recorded run was stopped, 5 more than "
        "the 28 it wrote before its stop: a known miscount of records made by a roomba-bt "
        "0.2.0 development build before its stall-stop fix",
        capsys,
    )


def test_an_old_ctrl_c_in_a_stall_noted_without_a_count_replays_to_its_stop(
    capsys: pytest.CaptureFixture[str],
) -> None:
    record = load_record(RECORDS / "ctrl_c_in_a_stall.jsonl")
    ending, outbound = record.ending, record.outbound
    assert ending is not None and ending["at"] == "after" and "written" not in ending, ending
    assert record.watchdog_trips, record.notes  # the stall the watchdog rode, after the tick
    # the watchdog's drive 0 at byte 28, then the safe stop and the query that asked after it
    assert outbound[28:] == oi.halt().data + SAFE_END + PROBE_QUERY, outbound.hex()
    out = _replays_to_its_stop(
        "ctrl_c_in_a_stall.jsonl",
        "the end note counts no bytes written when the recorded run was interrupted in a stall "
        "its watchdog rode: a known miscount of records made before roomba-bt 0.2.0",
        capsys,
    )
    assert "replayed to the stop at byte 33" in out, out
    assert_quoted("docs/runtime.md", "replay: the end note counts no bytes", out)
