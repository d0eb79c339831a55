"""A stop the robot took as the data of a long command a lost byte made: the run writes zeros
enough to end any command and the stop again, on the simulator's virtual clock too.

Drive (137) 140 mm/s spinning right is ``89 00 8c ff ff``; its opcode lost, the robot skips
``00`` (no opcode) and reads ``8c ff ff`` as a Song (140) of 255 notes: it waits for 510 data
bytes and takes the tree's ``mode: passive`` and the whole safe stop as notes, spinning on.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME, longest_data_bytes
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS
from roomba_bt.runtime.recording import STOP_LISTENED, load_record
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import SPIN, LosesTheOpcodeOf, record_run, spins_then_passive

#: the drive whose opcode the line loses: its data bytes then read as a 255-note Song
SONG_MAKER = oi.drive(140, -1).data

SPIN_THEN_SPIN_BACK = spins_then_passive(
    "spin-then-spin-back",
    ("1s", "velocity: 100 mm/s, radius: spin_left"),
    ("1s", "velocity: 140 mm/s, radius: spin_right"),
)


def test_the_longest_command_is_a_song_of_255_notes() -> None:
    """The zeros before a stop written again come from the opcode table, not a number: a
    Song's count byte at its wire maximum (255 notes of 2 bytes, after 2 fixed bytes)."""
    song = COMMANDS_BY_NAME["song"]
    assert longest_data_bytes() == song.fixed_data_bytes + 255 * 2 == 512
    assert len(STOP_RESYNC_ZEROS) == 512 and not any(STOP_RESYNC_ZEROS)


def test_a_stop_taken_as_song_notes_is_written_again_after_zeros(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Before, the run ended SUCCESS, ``safe stop sent ...``, the simulated robot in Safe
    spinning left at 100 mm/s: on the virtual clock the stop was not listened after."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN_THEN_SPIN_BACK)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = LosesTheOpcodeOf(simulator, SONG_MAKER)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2)
    with caplog.at_level(logging.WARNING, logger="roomba_bt"):
        summary = stack.run()
    stack.close()
    assert link.lost
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    assert summary.outcome is Outcome.SUCCESS and summary.exit_code == 0
    # the stop again from the Safe packet 35 showed, after the zeros, in one write
    again = STOP_RESYNC_ZEROS + oi.halt().data + oi.motors_off().data
    assert link.written.endswith(again + oi.pause_stream().data + oi.start().data)
    assert "not taken at first: a lost byte may have started a long command; sent 512 zeros" in (
        summary.safe_stop
    ), summary.safe_stop
    assert (
        "the stop was not taken at first: a lost byte may have started a long command; sent "
        "512 zeros and the stop again: heard" in caplog.text
    )


class LosesThePause(SimLink):
    """The simulator's link losing the opcode (150) of the first Pause Stream written once
    ``armed`` (the stop's): the ``00 80`` that reaches the robot is no opcode and Start."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.writes: list[bytes] = []
        self.lost = False
        self.armed = False

    def write(self, data: bytes) -> None:
        self.writes.append(bytes(data))
        if self.armed and not self.lost and bytes(data).startswith(oi.pause_stream().data):
            self.lost = True
            data = data[1:]
        super().write(data)


def test_a_stream_on_in_passive_with_the_wheels_still_confirms_the_stop() -> None:
    """The stop's Pause Stream lost and its Start heard: the frames that come on read Passive
    and the wheels still, as the stop leaves the robot; no zeros, no stop again."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = LosesThePause(simulator)
    connection = Connection(link, CREATE2)
    connection.start("passive", (7, 35, 43, 44))
    while connection.counters.frames < 5:
        connection.poll(0.05)
    stop = oi.pause_stream().data + oi.start().data
    link.armed = True
    assert connection.safe_stop() is True
    assert link.lost
    assert link.writes[-1] == stop and link.writes.count(stop) == 1  # written once
    assert simulator.mode is OIMode.PASSIVE and simulator.streaming
    connection.close()


def test_the_record_of_a_stop_written_again_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The record says its run's stop was listened after (``stop_listened``), and its replay
    listens on the recorded frames: it writes the zeros and the stop again where the recorded
    run did. Before, a replay never listened: ``first difference ... expected bytes 00 00 00
    00 00 00 00 00, sent nothing``, exit 1, for a run that had ended well."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    record = record_run(tmp_path, LosesTheOpcodeOf(simulator, SONG_MAKER), SPIN_THEN_SPIN_BACK)
    assert load_record(record).header[STOP_LISTENED] is True
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "sent 512 zeros and the stop again, heard at write 2" in out, out
    assert_quoted("docs/reliability.md", "safe stop sent ... (not taken at first", out)
    assert "replay: the tree wrote the same 564 bytes as the recorded run" in out, out


def test_a_record_without_stop_listened_is_replayed_without_listening(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A record made before ``stop_listened`` was written (its header without it) replays as
    it did then: the stop written once, no zeros; its difference at the end is said."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    record = record_run(tmp_path, LosesTheOpcodeOf(simulator, SONG_MAKER), SPIN_THEN_SPIN_BACK)
    lines = record.read_text().splitlines(keepends=True)
    header = json.loads(lines[0])
    del header[STOP_LISTENED]
    record.write_text(json.dumps(header) + "\n" + "".join(lines[1:]))
    capsys.readouterr()
    assert main(["replay", str(record)]) == 1
    out = capsys.readouterr().out
    assert "expected bytes 00 00 00 00 00 00 00 00, sent nothing" in out, out


def test_a_perfect_simulated_line_s_record_is_not_listened_after(tmp_path: Path) -> None:
    """The golden recordings' line (``SimLink`` on the virtual clock, losing nothing): its
    records say nothing of listening, and their replays end as they did."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    record = record_run(tmp_path, SimLink(simulator), SPIN_THEN_SPIN_BACK)
    assert STOP_LISTENED not in load_record(record).header


class DeafFromTheStop(SimLink):
    """The simulator's link on a line that loses bytes, losing every byte from the safe
    stop's first Pause Stream on (a wire to the robot that dies at the run's end): the robot
    streams on, in Safe, spinning."""

    loses_bytes = True

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.drove = self.deaf = False

    def write(self, data: bytes) -> None:
        self.drove = self.drove or bytes(data).startswith(oi.halt().data[:1])
        self.deaf = self.deaf or (self.drove and oi.pause_stream().data in bytes(data))
        if not self.deaf:
            super().write(data)


def test_the_record_of_a_timed_out_run_whose_stop_was_not_received_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its end note says ``connection lost`` (the stop not received after the time limit):
    the replay ends the tree at the recorded run's last tick, as the time limit did, and
    its stop, written three times and tried once more by ``close()``, is compared. Before,
    it was replayed as a link lost: its tree went on past the limit and starved, and "the
    replay does not fail as its link did (... the replay's own ending sent nothing)"."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    record = record_run(tmp_path, DeafFromTheStop(simulator), SPIN)
    assert simulator.mode is OIMode.SAFE  # the stop never reached it
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "the stop was written 3 times but not received" in out, out
    assert "replay: the tree wrote the same 2136 bytes as the recorded run" in out, out
    assert "does not fail as its link did" not in out
