"""Replaying the record of a run whose link failed: the replay ends, on every transport
clock, and says what the recorded run's link did rather than "first difference"."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, RobotProfile
from roomba_bt.runtime.recording import ReplayTransport, load_record
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

from .simrun import SPIN, WAIT_IN_PASSIVE, record_run, write_mission

FRAME = "131a070009000a000b000c001906511a0a88220023022b020d2c020dca"
HEADER = {"format": "roomba-bt-record", "version": 2, "profile": "create2", "baud": 115200,
          "packets": [7, 9, 10, 11, 12, 25, 26, 34, 35, 43, 44]}  # fmt: skip


def _record(path: Path, *lines: dict[str, object]) -> Path:
    path.write_text("".join(json.dumps(line) + "\n" for line in (HEADER, *lines)))
    return path


def test_a_wait_under_the_clocks_last_bit_at_the_record_s_end_still_moves_it(
    tmp_path: Path,
) -> None:
    """At 5.678475 s, a wait of 3.6e-16 s added nothing to the replay's clock: the safe
    stop's wait for a quiet line, whose rest came to that, read for ever (a record of a run
    that followed a baud change, its replay deaf to Ctrl-C and SIGTERM). Any wait moves it."""
    path = _record(
        tmp_path / "run.jsonl",
        {"t": 0.0, "d": "out", "b": "80"},
        {"t": 5.678475, "d": "in", "b": FRAME},
        {"t": 5.68, "d": "end"},
    )
    transport = ReplayTransport(load_record(path))
    transport.write(b"\x80")  # Start, which the robot's bytes came after
    assert transport.read(10.0) == bytes.fromhex(FRAME)
    assert transport.now() == 5.678475
    assert transport.exhausted
    transport.read(3.608224830031759e-16)
    assert transport.now() > 5.678475
    transport.read(0.0)  # a read of what is there now: no time passes
    later = transport.now()
    transport.read(0.0)
    assert transport.now() == later


@pytest.mark.parametrize(("step", "given"), [(0.015, True), (None, False)])
def test_a_read_shorter_than_a_step_of_the_simulator_is_given_the_next_steps_chunk(
    tmp_path: Path, step: float | None, given: bool
) -> None:
    """On the in-process simulator a read with nothing sent waits whole 15 ms steps, one at
    least (``SimLink.read``): a wait of 2 ms got the next step's frame, and the replay gave
    that chunk only to a later read, whose wait reached its stamp. Its record says so
    (``read_step``); one made before does not, and replays as then."""
    header = {} if step is None else {"read_step": step}
    path = tmp_path / "run.jsonl"
    lines = ({**HEADER, **header}, {"t": 0.0, "d": "out", "b": "80"},
             {"t": 0.015, "d": "in", "b": FRAME}, {"t": 0.02, "d": "end"})  # fmt: skip
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    transport = ReplayTransport(load_record(path))
    transport.write(b"\x80")
    assert transport.read(0.002) == (bytes.fromhex(FRAME) if given else b"")
    assert transport.now() == (0.015 if given else 0.002)


def test_a_run_on_a_cable_losing_the_robots_bytes_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``run wall-follow --fast --byte-drop-rate 0.05 --record``: its replay said "first
    difference at mission time 15.720 s: expected Drive (137) 89 00 96 80 00, sent Drive
    (137) 89 00 00 00 00", exit 1, of a record nothing had changed (4 records in 10 of the
    shipped missions at 2 and 5 %): between broken frames the watchdog's short waits read
    the simulator's next frame, which its replay gave to the read after."""
    monkeypatch.chdir(tmp_path)
    argv = ["wall-follow", "--fast", "--display", "none", "--byte-drop-rate", "0.05"]
    assert main(["run", *argv, "--record", "r.jsonl"]) == 0
    assert load_record(tmp_path / "r.jsonl").header["read_step"] == 0.015
    capsys.readouterr()
    assert main(["replay", "r.jsonl", "--display", "none"]) == 0
    out = capsys.readouterr().out
    assert "replay: the tree wrote the same " in out and "first difference" not in out


@pytest.mark.parametrize(
    ("faults", "profile", "mission", "verdict"),
    [
        (Faults(disconnect_at=1.0), CREATE2, SPIN, "lost its link at mission time"),  # pulled
        (Faults(reset_at=1.0), CREATE2, SPIN, "lost its link at mission time"),
        # woken by BRC; asleep in Passive, as only there a robot sleeps
        (Faults(sleep_at=1.0), CREATE2, WAIT_IN_PASSIVE, "lost its link at mission time"),
        # pulled before the start-up's end: no tree's byte to compare
        (Faults(disconnect_at=0.0), CREATE2, SPIN, "lost its link before its tree's first tick"),
        # the listen at the new rate replayed whole (its reads stamped past their waits
        # too): the same bytes to the end, the stop's own
        (Faults(baud_change_at=1.0), CREATE2, SPIN, "the same 51 bytes as the recorded run"),
        # the wrong profile: its run ends at the watchdog's trip (certain there), the stop as
        # the replay's own: no difference at all (it went on querying through the grace)
        (Faults(), ROOMBA500, SPIN, "the tree wrote the same 28 bytes as the recorded run"),
    ],
    ids=["port gone", "reset", "asleep", "before the first tick", "baud change", "wrong profile"],
)
def test_the_replay_of_a_run_whose_link_failed_compares_the_tree_up_to_there_and_exits_0(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
    faults: Faults,
    profile: RobotProfile,
    mission: str,
    verdict: str,
) -> None:
    """Each ending of the noisy cable's table. Past the recorded run's last tick it wrote
    what its link's failure had it write (nothing, the port gone; a Query List; a wake),
    which the replay, on a line that cannot fail, does not: that was its "first
    difference", exit 1, read as "your mission changed". docs/runtime.md quotes the reset's
    replay (its port /dev/pts/0, its numbers a longer run's), the one before the first tick
    and the wrong profile's."""
    link = SimLink(Simulator(load_world("empty-room"), profile, 0, faults))
    record = record_run(tmp_path, link, mission)
    capsys.readouterr()
    caplog.clear()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert verdict in out, out
    assert "first difference" not in out
    if faults.reset_at is not None:
        port = {"sim://empty-room": "/dev/pts/0"}
        assert_quoted("docs/runtime.md", "outcome CONNECTION LOST (the recorded run's", out,
                      names=port)  # fmt: skip
        assert_quoted("docs/runtime.md", "safe stop not replayed", out)
        assert_quoted("docs/runtime.md", "replay: the recorded run lost its link at", out,
                      numbers=True)  # fmt: skip
        assert_quoted("docs/runtime.md", "replay: past there the replay", out)
    if faults.disconnect_at == 0.0:
        assert_quoted("docs/runtime.md", "replay: the recorded run lost its link before", out,
                      numbers=True)  # fmt: skip
    if profile is ROOMBA500:
        assert_quoted("docs/runtime.md", "replay: the tree wrote the same 28 bytes as", out)
    if "lost its link" not in verdict:
        ended = "wrong profile" if profile is ROOMBA500 else "connection lost"
        assert f"replay: the recorded run ended in {ended}" in out
        return
    # before the first tick nothing of the mission was sent: not started (exit 3's outcome)
    ended = "NO CONNECTION" if faults.disconnect_at == 0.0 else "CONNECTION LOST"
    _says_the_recorded_loss_not_its_own_stop(out, caplog, ended)


def _says_the_recorded_loss_not_its_own_stop(
    out: str, caplog: pytest.LogCaptureFixture, ended: str = "CONNECTION LOST"
) -> None:
    """A replay whose recorded run lost its link says how that run ended, in its summary's
    outcome (once: not again on a last line), and no stop of its own: it printed "ERROR ...
    the stop was written but is unconfirmed", "outcome CONNECTION LOST (the safe stop did
    not reach the robot (the run had ended: input ended: end of the record))" and "safe
    stop NOT DELIVERED" of a replay that reaches no robot (``monitor RECORD``'s rule)."""
    from roomba_bt.monitor.recorded import NO_STOP_REPLAYED

    assert f"outcome      {ended} (the recorded run's: " in out, out
    assert f"safe stop    {NO_STOP_REPLAYED}" in out, out
    assert "did not reach the robot" not in out and "NOT DELIVERED" not in out
    assert "the recorded run ended in" not in out
    said = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert not any("unconfirmed" in text or "not delivered" in text for text in said), said


def test_a_followed_baud_change_replays_its_listen_and_its_stop_as_the_run_did(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The listen at the new rate read frames stamped past its deadline (on the virtual
    clock a read takes the simulator's next 15 ms slot; on a loaded pty the read returns
    late), and its replay, which gives a chunk only to a read whose wait reaches it, left
    them out: its drive 0 came two chunks early, it read nothing more past that
    difference, and the stop the live run had confirmed was NOT DELIVERED (the pty test's
    failure under load). The replay's last read of the listen gives what the run read
    there before it switched again or wrote."""
    mission = write_mission(tmp_path, SPIN)
    record = tmp_path / "run.jsonl"
    argv = ["run", str(mission), "--fast", "--baud-change-at", "1.5", "--timeout", "5s"]
    assert main([*argv, "--display", "none", "--record", str(record)]) == 8
    stop = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("safe stop"))
    assert stop == "safe stop    sent drive, motors, pause_resume_stream, start"
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert stop in out
    assert "the tree wrote the same 51 bytes as the recorded run" in out


def test_the_replay_of_a_stopped_stream_asked_for_again_writes_the_same_bytes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A robot that stopped streaming by itself: its run asked for the stream again within
    the grace and rode the gap through (it ended that way, exit 3, before: robot/stall_asks.py);
    the replay asks where the record did, and writes the same bytes to the run's end."""
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0, Faults(stream_stop_at=1.0)))
    record = record_run(tmp_path, link)
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "the tree wrote the same 105 bytes as the recorded run" in out, out
    assert "first difference" not in out
    assert "replay: the recorded run ended in timeout" in out


def test_a_change_of_the_tree_before_the_link_failed_is_still_a_difference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The recorded run's cable was pulled at 1 s; its mission, replayed at another speed,
    differs from its first drive: exit 1, as any changed mission."""
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0, Faults(disconnect_at=1.0)))
    record = record_run(tmp_path, link)
    capsys.readouterr()
    faster = write_mission(tmp_path, SPIN.replace("100 mm/s", "150 mm/s"), "faster.yaml")
    assert main(["replay", str(record), "--mission", str(faster)]) == 1
    out = capsys.readouterr().out
    assert "first difference at mission time" in out
    assert "lost its link" not in out


def test_a_replay_that_wrote_nothing_past_bytes_that_are_no_commands_says_nothing(
    tmp_path: Path,
) -> None:
    """The record of a robot that fell asleep in a pause holds, after the stop's zeros (no
    OI commands: the difference is shown as bytes), the run's asking after it; the replay
    wrote nothing there, and was said to have ``sent bytes `` (nothing after the word)."""
    lines = [
        {"t": 0.0, "d": "out", "b": "80"},
        {"t": 0.1, "d": "out", "b": "0000"},
        {"t": 0.2, "d": "out", "b": "9503231522"},
        {"t": 0.3, "d": "end"},
    ]
    record = load_record(_record(tmp_path / "asleep.jsonl", *lines))
    transport = ReplayTransport(record)
    transport.write(b"\x80")
    transport.write(b"\x00\x00")
    assert transport.first_difference() == (3, "bytes 95 03 23 15 22", "nothing")
