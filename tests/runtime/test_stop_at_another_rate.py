"""A stop the robot did not confirm, asked after: at the run's rate, and where garbage came,
written at each rate of Baud (129)'s table (``robot/baud_hunt.py``).

Drive (137) 129 mm/s spinning left is ``89 00 81 00 01``; its opcode lost, the robot skips
``00`` (no opcode) and reads ``81 00`` as Baud (129) code 0: it talks and listens at 300
baud from then on, spinning, and the run's stop at 115200 reaches nothing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.evaluate import episode
from roomba_bt.evaluate.episode import EpisodeSpec, run_episode
from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.baud_hunt import hunt_rates, hunt_seconds
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import ExitCode, RunSummary
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.faults import Faults

from .simrun import LosesTheOpcodeOf, spins_then_passive

#: the drive whose opcode the line loses: its data bytes then read as Baud (129) code 0
BAUD_MAKER = oi.drive(129, 1).data

SPINS = spins_then_passive("spins", ("5s", "velocity: 129 mm/s, radius: spin_left"))


def test_the_hunt_tries_every_rate_of_the_baud_table_but_the_runs() -> None:
    assert hunt_rates(115200) == (
        300,
        600,
        1200,
        2400,
        4800,
        9600,
        14400,
        19200,
        28800,
        38400,
        57600,
    )
    # bounded (docs/robot.md): a stop from Safe is 11 bytes (drive 0, motors off, pause, Start)
    assert 13.5 < hunt_seconds(115200, bytes(11), STOP_RESYNC_ZEROS) < 14.0


def _spun_on(
    tmp_path: Path, lossy: type[LosesTheOpcodeOf], **given: Any
) -> tuple[RunSummary, Simulator, LosesTheOpcodeOf]:
    """The spinning mission run to its end and closed on ``lossy``'s line, whose lost opcode
    makes a Baud to 300 (:data:`BAUD_MAKER`): its summary, the robot, the line; ``given``:
    the stack's other settings (``end_in``)."""
    path = tmp_path / "m.yaml"
    path.write_text(SPINS)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = lossy(simulator, BAUD_MAKER)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2, **given)
    summary = stack.run()
    stack.close()
    return summary, simulator, link


def test_a_robot_a_lost_byte_put_on_300_baud_is_stopped_there_and_put_back(
    tmp_path: Path,
) -> None:
    """Before, the run said ``NOT DELIVERED: ... the line is garbled`` and the simulated robot
    spun on at 300 baud; then it was stopped there and left at 300, where the next run at
    115200 could not reach it. Now it is sent Baud back to the run's rate and asked there."""
    summary, simulator, link = _spun_on(tmp_path, LosesTheOpcodeOf)
    assert link.lost and simulator.baud == 115200 == link.baud
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    assert summary.stop_delivered, summary.safe_stop
    assert "the robot had moved to 300 baud" in summary.safe_stop, summary.safe_stop
    assert "stopped there" in summary.safe_stop
    assert "sent Baud back to 115200, it answered in Passive at 115200" in summary.safe_stop
    assert_quoted("docs/robot.md", "safe stop sent ... (the robot had moved to 300", str(summary))


class LosesTheBaudBackToo(LosesTheOpcodeOf):
    """:class:`LosesTheOpcodeOf`, and every Baud (129) back to 115200 lost on the line too."""

    def write(self, data: bytes) -> None:
        if bytes(data) != oi.baud_rate(115200).data:
            super().write(data)


def test_a_robot_that_does_not_come_back_to_the_runs_rate_is_left_where_it_answered(
    tmp_path: Path,
) -> None:
    """The Baud back lost: the robot still talks at 300, and the port is left there, the
    summary saying so and how to find it."""
    summary, simulator, link = _spun_on(tmp_path, LosesTheBaudBackToo)
    assert simulator.baud == 300 == link.baud and simulator.mode is OIMode.PASSIVE
    assert summary.stop_delivered, summary.safe_stop
    assert (
        "sent Baud back to 115200, it did not answer there: the port is left at 300"
        in summary.safe_stop
    ), summary.safe_stop
    assert "`--baud auto` or roomba-bt doctor finds it" in summary.safe_stop


@pytest.mark.parametrize("lossy", [LosesTheOpcodeOf, LosesTheBaudBackToo])
def test_end_in_stop_found_at_another_rate_ends_as_the_summary_says(
    tmp_path: Path, lossy: type[LosesTheOpcodeOf]
) -> None:
    """``end_in="stop"``: the question at the other rate needs Start, so the robot answers in
    Passive. Put back at the run's rate, it is sent Stop again and ends in Off; left at 300
    (the Baud back lost), it stays in Passive, and the summary says so: it said ``final mode
    Off`` of both robots in Passive."""
    summary, simulator, _ = _spun_on(tmp_path, lossy, end_in="stop")
    assert summary.stop_delivered, summary.safe_stop
    assert simulator.requested_left == simulator.requested_right == 0
    back = lossy is LosesTheOpcodeOf
    assert simulator.mode is (OIMode.OFF if back else OIMode.PASSIVE), summary.safe_stop
    assert summary.final_mode_text() == simulator.mode.label, summary.safe_stop
    assert ("Stop written again" in summary.safe_stop) is back, summary.safe_stop
    if not back:
        assert_quoted("docs/robot.md", "final mode Passive$", "\n".join(summary.lines()))


def test_a_baud_made_of_the_last_command_before_the_stop_is_no_quiet_and_is_hunted() -> None:
    """The opcode lost of the drive written just before the stop: the robot moved to 300
    baud as the stop went out at 115200 and streamed on there, garbage at the run's rate,
    no valid frame. That was taken for the quiet of a stop heard: ``sent``, the simulated
    robot left spinning in Safe at 300 baud. Bytes that make no frame after the stop are no
    quiet: the stop is asked after, found at 300 and the robot put back."""
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = LosesTheOpcodeOf(simulator, BAUD_MAKER)
    connection = Connection(link, CREATE2)
    connection.start("safe", (7, 35, 43, 44))
    while connection.counters.frames < 10:
        connection.poll(0.05)
    connection.send(oi.drive(129, 1))
    assert link.lost and simulator.baud == 300 and simulator.mode is OIMode.SAFE
    assert connection.safe_stop() is True, connection.stop_report
    assert "the robot had moved to 300 baud" in connection.ending.found_at
    assert simulator.baud == 115200 and simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    connection.close()


def dock_at_one_percent_lost(seed: int, monkeypatch: pytest.MonkeyPatch) -> tuple[Any, RunSummary]:
    """The dock episode ``seed`` of ``eval dock --host-drop-rate 0.01``: its simulator and
    the run's summary, kept as the episode measures them."""
    kept: list[tuple[Any, RunSummary]] = []
    measured = episode._measured

    def keep(
        spec: Any, world: Any, pose: Any, simulator: Any, summary: RunSummary, *rest: Any
    ) -> Any:
        kept.append((simulator, summary))
        return measured(spec, world, pose, simulator, summary, *rest)

    monkeypatch.setattr(episode, "_measured", keep)
    mission = str(Path(__file__).parents[2] / "roomba_bt" / "missions" / "dock.yaml")
    spec = EpisodeSpec(mission, seed=seed, faults=Faults(host_drop_rate=0.01), trace_every=0)
    run_episode(spec)
    return kept[0]


def test_seed_50_a_baud_made_of_lost_bytes_ends_stopped_in_passive_back_at_115200(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Before: NOT DELIVERED, the simulated robot in Safe at 300 baud, driving 228/370 mm/s;
    then stopped in Passive but left at 300 baud."""
    simulator, summary = dock_at_one_percent_lost(50, monkeypatch)
    assert simulator.baud == 115200 and simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    assert "the robot had moved to 300 baud" in summary.safe_stop, summary.safe_stop


def test_seed_51_a_reset_made_of_lost_bytes_is_started_again_after_its_banner(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The robot reset (its banner read) and the stop's Start, its last byte, was lost on the
    line too: the Query List after it found an Off robot, which answers nothing. Start is
    now sent again once the banner is over, and the robot answers in Passive. Before: said
    stopped in Off (unconfirmed), the simulated robot left in Off."""
    simulator, summary = dock_at_one_percent_lost(51, monkeypatch)
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    assert summary.stop_delivered and summary.safe_stop.startswith("sent "), summary.safe_stop
    assert "sent Start again after its banner, it answered in Passive" in summary.safe_stop


def test_seed_4_a_stop_after_a_stream_stopped_is_confirmed_by_a_query(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Power (133) or Stop (173) made of lost bytes stopped the stream; the stop's Start
    brought the robot to Passive, and the Query List after it shows so. Before: NOT
    DELIVERED, "the robot answers nothing", the robot in Passive at 0/0."""
    simulator, summary = dock_at_one_percent_lost(4, monkeypatch)
    assert simulator.mode is OIMode.PASSIVE
    assert summary.stop_delivered and summary.safe_stop.startswith("sent "), summary.safe_stop


def test_seed_67_a_power_made_of_lost_bytes_is_named_and_its_stop_confirmed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Drive Direct's lost byte made Power (133): the robot slept in Passive, the stream
    stopped. The run had put right two wheel commands' lost bytes, so the silence is said
    the OI gone Off by a lost byte, not a bare "the sensor stream stopped". The Query List
    after the stop lost its count on the line (``[149][35][21][34]``: the robot waited for
    35 packet ids); the stop written again after zeros, and asked again, is answered in
    Passive. Before: NOT DELIVERED, "the robot answers nothing"."""
    simulator, summary = dock_at_one_percent_lost(67, monkeypatch)
    assert simulator.mode is OIMode.PASSIVE
    assert summary.reason.startswith(
        "sim://empty-room: the robot's OI went Off mid-run: most likely a Stop (173) or "
        "Power (133) made of lost bytes on this line: bytes from the computer to the robot "
        "were lost in this run (a wheel command 2 times, put right); nothing arrived for 2.0 s"
    ), summary.reason
    # an OI gone Off answers no query: not "in Safe, which never sleeps" (its old ending)
    assert (
        "it answered no query, asked twice 1 s apart, as an OI gone Off does (last seen in "
        "Safe; else switched off, a flat battery, or " in summary.reason
    ), summary.reason
    assert "never sleeps" not in summary.reason
    assert summary.stop_delivered and summary.safe_stop.startswith("sent "), summary.safe_stop


def test_the_record_of_a_stop_started_again_after_a_reset_replays_byte_for_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run dock --fast --host-drop-rate 0.01 --seed 29``: a Reset made of lost bytes at the
    start, its stop sent Start again after the banner and asked after by a Query List. The
    replay does both on the recorded bytes. Before, it wrote neither: "compared up to there:
    the 349 bytes up to there are the same", and past it "the record holds bytes 80 95 03 23
    15 22, the replay's own ending sent bytes" (exit 0, the ending unchecked). The reset
    came before the stream's first frame: not started, exit 3."""
    record = tmp_path / "r.jsonl"
    faults = ["--fast", "--host-drop-rate", "0.01", "--seed", "29"]
    assert main(["run", "dock", *faults, "--record", str(record)]) == ExitCode.CONNECTION
    run = capsys.readouterr().out
    assert "sent Start again after its banner, it answered in Passive" in run, run
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert "replay: the tree wrote the same 355 bytes as the recorded run" in out, out
    assert "does not fail as its link did" not in out


class _RecordedEpisodeStack(RunStack):
    """An evaluation episode's stack that records its run to :attr:`record` (as ``run
    --record``) and closes as ``run`` does, its record's end line written."""

    record = Path("run.jsonl")

    def __init__(self, *args: Any, **options: Any) -> None:
        super().__init__(*args, record=Recording(self.record, DOCK), **options)

    def run(self, **options: Any) -> RunSummary:
        summary = super().run(**options)
        self.close()
        return summary


DOCK = str(Path(__file__).parents[2] / "roomba_bt" / "missions" / "dock.yaml")


@pytest.mark.parametrize(
    ("seed", "written"),
    [(4, 1099), (51, 731), (67, 6508)],
    ids=["query after a stopped stream", "start again after a reset", "stop written again"],
)
def test_the_record_of_a_stop_asked_after_replays_byte_for_byte(
    seed: int, written: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """The dock's 1 % sweep's seeds above, recorded: each run's link failed (a Power, a Reset
    made of lost bytes), and its stop was asked after by a Query List (seed 67's written
    again after zeros first, seed 51's Start sent again after the banner). The replay asks
    where the recorded run did, on the recorded bytes. Before, each was compared up to the
    link's failure only: "the record holds bytes 95 03 23 15 22, the replay's own ending
    sent bytes ", the ending unchecked."""
    record = tmp_path / "run.jsonl"
    monkeypatch.setattr(_RecordedEpisodeStack, "record", record)
    monkeypatch.setattr(episode, "RunStack", _RecordedEpisodeStack)
    run_episode(EpisodeSpec(DOCK, seed=seed, faults=Faults(host_drop_rate=0.01), trace_every=0))
    capsys.readouterr()
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert f"replay: the tree wrote the same {written} bytes as the recorded run" in out, out
    assert "does not fail as its link did" not in out
