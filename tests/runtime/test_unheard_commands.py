"""Bytes lost on their way to the robot: the run notices by the encoders that the robot does
not do what it was told, sets its parser in step and sends the command again
(runtime/motion_watch.py); a line that keeps losing commands ends the run."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as C
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.stall_asks import STALL_ASKS, STREAM_AGAIN_NOTE
from roomba_bt.robot.startup import STREAM_ASKS_AGAIN, stream_zeros
from roomba_bt.robot.writer import RESYNC_ZEROS
from roomba_bt.runtime.motion_watch import GIVE_UP_AFTER
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import RunStack, replay_record
from roomba_bt.runtime.summary import ExitCode, Outcome
from roomba_bt.sim import Faults, Simulator, load_world
from roomba_bt.sim.faults import HostLine

from .simrun import DRIVE_TO_WALL_AND_BACK_OFF, BridgeLink, Run, RunMission, write_mission

DRIVE_200 = C.drive(200, 0x8000).data  # 89 00 c8 80 00
STOP = C.halt().data  # 89 00 00 00 00
#: the stream DRIVE_60_CM asks for: [148][11] and its 11 packet ids
STREAM = bytes.fromhex("94 0b 07 09 0a 0b 0c 19 1a 22 23 2b 2c")


class LosesByte(HostLine):
    """A line that loses byte ``index`` of the first ``times`` writes equal to ``data``."""

    def __init__(self, data: bytes, index: int, times: int = 1) -> None:
        super().__init__(Faults(), 0)
        self.data, self.index, self.times = data, index, times

    def passed(self, data: bytes | bytearray) -> tuple[bytes, str]:
        if bytes(data) != self.data or not self.times:
            return bytes(data), ""
        self.times -= 1
        self.dropped += 1
        return bytes(data[: self.index] + data[self.index + 1 :]), f"lost byte {self.index}"


#: Safe, then 60 cm at 200 mm/s: 3 s of driving, which a robot standing never finishes
DRIVE_60_CM = """
mission: drive
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: 60 cm}
"""


def _lost_and_stopped(run: Run, *said: str) -> None:
    """The run ended as a lost connection (exit 8), its reason saying each of ``said``, and
    the simulated robot was left stopped in Passive."""
    summary = run.summary
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert summary.exit_code == ExitCode.LINK_LOST
    for words in said:
        assert words in summary.reason
    sim = run.simulator
    assert sim.mode.label == "Passive" and sim.requested_left == sim.requested_right == 0


def test_a_drive_whose_byte_was_lost_is_sent_again_and_the_robot_drives(
    run_mission: RunMission,
) -> None:
    """The noisy-cable report: Drive 200 arriving as ``89 00 80 00`` left the robot standing
    for 19 s while the tree drove, and the run ended SUCCESS. Now it stands a second or two,
    the parser is set in step by zeros and the drive sent again, in one write."""
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(DRIVE_200, 2), timeout=15.0)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.unheard, summary.unheard_obeyed) == (1, 1)
    assert summary.mission_time_s < 3.0 + 2.5  # it stood at most two looks
    assert any(data == RESYNC_ZEROS + DRIVE_200 for _, data in run.link.writes)
    unheard = next(line for line in summary.lines() if line.startswith("unheard"))
    assert "the wheels stood still for a second under Drive (137) velocity 200" in unheard
    assert "bytes from the computer to the robot were lost once" in unheard
    assert "check the cable" in unheard
    assert_quoted("docs/reliability.md", "unheard the robot did not do", unheard, numbers=True)


def test_a_stop_whose_byte_was_lost_is_sent_again_and_the_robot_stops(
    run_mission: RunMission,
) -> None:
    """The worse half: the drive 0 that ends a drive lost a byte, and the robot drove on
    while the tree waited, believing it stopped."""
    mission = DRIVE_60_CM + "    - wait: {duration: 6 s}\n"
    run = run_mission(mission, world="corridor", host_line=LosesByte(STOP, 3), timeout=15.0)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.unheard, summary.unheard_obeyed) == (1, 1)
    assert "the wheels turned for a second under Drive (137) velocity 0" in summary.unheard_first
    # 60 cm, then at most 2 s more at 200 mm/s before it stopped (6 s more without the watch)
    assert summary.distance_mm < 600 + 450
    assert run.simulator.requested_left == run.simulator.requested_right == 0


def test_a_line_that_keeps_losing_commands_ends_the_run_stopped(run_mission: RunMission) -> None:
    """Each of three drives loses a byte; each is put right, and the third ends the run: a
    line that loses that many commands cannot be trusted with the next stop."""
    mission = (
        DRIVE_60_CM
        + ("    - wait: {duration: 2 s}\n    - drive: {velocity: 200 mm/s, distance: 60 cm}\n") * 3
    )
    run = run_mission(
        mission, world="corridor", host_line=LosesByte(DRIVE_200, 2, times=3), timeout=40.0
    )
    _lost_and_stopped(
        run,
        f"the robot did not do what it was told {GIVE_UP_AFTER} times within 60 s",
        "bytes from the computer to the robot are being lost; check the cable",
    )
    assert run.summary.unheard_obeyed == GIVE_UP_AFTER
    assert run.summary.distance_mm < 3 * 600 + 400  # the third drive ended part of the way


def stop_and_go(name: str, times: int, *steps: str) -> str:
    """A mission that goes to Safe and repeats ``steps`` (each a step of a sequence, in flow
    style) ``times`` times: a patrol's stop and go."""
    body = "".join(f"              - {step}\n" for step in steps)
    return (
        f"mission: {name}\ntree:\n  sequence:\n    - mode: safe\n    - repeat:\n"
        f"        times: {times}\n        do:\n          sequence:\n{body}"
    )


#: Missions on a line that loses nothing. The stop-and-go ones write Drive 0, a drive, and
#: Drive 0 again between two of the watch's looks: the same bytes at both looks, and wheels
#: that rightly turned between. The watch compared the bytes, took them for one stop that
#: stood while the wheels turned, and ended these runs CONNECTION LOST, exit 8, naming the
#: cable (session 34's py_trees review: unheard3.yaml and inch.yaml).
CLEAN_RUNS = [
    pytest.param(DRIVE_60_CM + "    - wait: {duration: 3 s}\n", "empty-room", id="drive-wait"),
    *(
        pytest.param(
            stop_and_go("unheard3", 4, "drive: {velocity: 200 mm/s, duration: 1s}",
                        "wait: 1s", "drive: {velocity: -200 mm/s, duration: 500ms}",
                        "wait: 1500ms"),
            world, id=f"stop-and-go-{world}",
        )
        for world in ("empty-room", "apartment")
    ),
    pytest.param(
        stop_and_go("inch", 10, "drive: {velocity: 200 mm/s, distance: 6cm}", "wait: 700ms"),
        "apartment", id="inch-forward",
    ),
    pytest.param(
        stop_and_go("smallest", 1, "drive: {velocity: 200 mm/s, duration: 1s}", "wait: 1s",
                    "drive: {velocity: 200 mm/s, duration: 500ms}", "wait: 2s"),
        "empty-room", id="go-stop-go-stop",
    ),
]  # fmt: skip


@pytest.mark.parametrize(("mission", "world"), CLEAN_RUNS)
def test_a_clean_line_writes_nothing_more(
    run_mission: RunMission, mission: str, world: str
) -> None:
    run = run_mission(mission, world=world, timeout=60.0)
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.summary.unheard == 0
    assert not any(b"\x00" * 8 in data for _, data in run.link.writes)
    assert not any(line.startswith("unheard") for line in run.summary.lines())


def test_a_stop_and_go_whose_stop_was_lost_is_still_put_right(run_mission: RunMission) -> None:
    """Stop and go, its first stop's byte lost: the robot drives on through the pause. A
    stop written once and standing since the last look is judged as before the watch went
    by writes: the second look finds it, and the robot stops."""
    mission = stop_and_go("pauses", 2, "drive: {velocity: 200 mm/s, duration: 1s}", "wait: 3s")
    run = run_mission(mission, world="corridor", host_line=LosesByte(STOP, 3), timeout=20.0)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.unheard, summary.unheard_obeyed) == (1, 1)
    assert "the wheels turned for a second under Drive (137) velocity 0" in summary.unheard_first
    assert any(data == RESYNC_ZEROS + STOP for _, data in run.link.writes)
    # two drives of 20 cm, and at most 2 s more at 200 mm/s before the stop was heard
    assert summary.distance_mm < 2 * 200 + 450


def test_a_robot_wedged_with_no_bump_gets_one_resend_and_no_blame_on_the_cable(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """Backing into the corridor's end (no bumper behind): the wheels stall. The watch cannot
    tell that from a lost byte until it sent the drive again; then it says so once, sends
    nothing more, and leaves the run to its tree."""
    mission = """
    mission: back
    tree:
      sequence:
        - mode: safe
        - drive: {velocity: -200 mm/s, distance: 3 m}
    """
    run = run_mission(mission, world="corridor", timeout=16.0)
    summary = run.summary
    assert summary.outcome is Outcome.TIMEOUT
    assert (summary.unheard, summary.unheard_obeyed, summary.unheard_stalled) == (1, 0, 1)
    assert sum(data.startswith(RESYNC_ZEROS) for _, data in run.link.writes) == 1
    unheard = next(line for line in summary.lines() if line.startswith("unheard"))
    assert "once the command sent again did not help either (the robot wedged" in unheard
    assert "check the cable" not in unheard
    # the first warning, on a simulator with no line faults, blamed lost bytes alone: wheels
    # that stand still under a drive are said to be a wedge first
    first = next(r.getMessage() for r in caplog.records if "did not do what" in r.getMessage())
    assert "the robot may be wedged with no bump shown or its wheels stalled, or bytes" in first


def test_a_reset_right_after_our_stream_request_names_the_cable_too(
    run_mission: RunMission,
) -> None:
    """The noisy-cable report: a lost 148 made the stream request's packet id 7 a Reset, and
    the run blamed a battery dip alone. Before the stream's first frame: not started."""
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(STREAM, 0), timeout=10.0)
    reason = run.summary.reason
    assert run.summary.outcome is Outcome.NO_CONNECTION
    assert "the robot reset: its start-up banner was on the line" in reason
    assert "a battery or power dip" in reason
    assert "or a byte of our command 0.00 s before lost on the line (a bad cable" in reason


def test_a_query_list_that_lost_a_byte_is_asked_again_before_blaming_the_baud_rate(
    run_mission: RunMission,
) -> None:
    """``[149][1][35]`` arriving as ``[149][35]``: the robot waits for 35 packet ids and
    answers nothing; the start-up gave up at once with "wrong baud rate, asleep, wiring"."""
    query = C.query_list((35,)).data
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(query, 1), timeout=10.0)
    assert run.summary.outcome is Outcome.SUCCESS
    assert any(data.startswith(RESYNC_ZEROS + C.start().data) for _, data in run.link.writes)


def test_a_robot_that_never_answers_is_asked_twice_and_the_baud_rate_named(
    run_mission: RunMission,
) -> None:
    query = C.query_list((35,)).data
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(query, 1, times=2), timeout=10.0)
    assert run.summary.outcome is Outcome.NO_CONNECTION
    assert "did not answer two Query Lists (149) for packet 35 within 1 s" in run.summary.reason
    assert "wrong baud rate" in run.summary.reason


def test_a_back_off_that_lost_a_byte_is_judged_though_the_bumper_is_pressed(
    run_mission: RunMission,
) -> None:
    """A robot pushing a wall may stall with its bumper pressed: excused. One backing away
    from it is free to move: its back-off that lost a byte stood 16 s against the wall."""
    back_off = C.drive(-100, 0x8000).data
    mission = DRIVE_TO_WALL_AND_BACK_OFF + "    - wait: {duration: 2 s}\n"
    run = run_mission(mission, host_line=LosesByte(back_off, 4), timeout=30.0)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.unheard, summary.unheard_obeyed) == (1, 1)
    assert "under Drive (137) velocity -100" in summary.unheard_first


class LosesByteOfEvery(HostLine):
    """A line that loses, in order, byte ``index`` of the next write that ends in ``data``,
    for each ``(data, index)`` of ``losses`` (a request asked for again comes after zeros,
    in the same write)."""

    def __init__(self, *losses: tuple[bytes, int]) -> None:
        super().__init__(Faults(), 0)
        self.losses = list(losses)

    def passed(self, data: bytes | bytearray) -> tuple[bytes, str]:
        if not self.losses or not bytes(data).endswith(self.losses[0][0]):
            return bytes(data), ""
        lost, index = self.losses.pop(0)
        self.dropped += 1
        at = len(data) - len(lost) + index
        return bytes(data[:at] + data[at + 1 :]), f"lost byte {at}"


@pytest.mark.parametrize(
    "lost",
    [
        pytest.param(1, id="the count: the first id read as it, another list streamed"),
        pytest.param(5, id="an id: the robot waits for one more"),
        pytest.param(12, id="the last id"),
    ],
)
def test_a_stream_request_that_lost_a_byte_is_asked_for_again(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture, lost: int
) -> None:
    """A byte of Stream (148) lost on the line left no stream: the run waited the grace and
    ended "the sensor stream stopped ... it stopped streaming by itself", exit 3, 3 runs of
    40 at 1 % bytes lost. Now no frame within the watchdog's time asks again, after the zeros
    that end any wait the lost byte left, and the run goes on."""
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(STREAM, lost), timeout=10.0)
    assert run.summary.outcome is Outcome.SUCCESS
    requests = [data for _, data in run.link.writes if data.endswith(STREAM)]
    assert requests == [STREAM, stream_zeros(tuple(STREAM[2:])) + STREAM]
    assert len(stream_zeros(tuple(STREAM[2:]))) >= len(RESYNC_ZEROS)
    said = [r.getMessage() for r in caplog.records if "asking again" in r.getMessage()]
    assert len(said) == 1
    assert "no sensor data came within 100 ms of asking the robot for it" in said[0]
    assert "a byte of the request may have been lost on the way to the robot" in said[0]


def test_a_stream_request_lost_every_time_ends_the_run_not_started(run_mission: RunMission) -> None:
    """Asked again :data:`STREAM_ASKS_AGAIN` times; then the ending of a stream lost (here
    the line garbled: the zeros ended the second request's wait with packet group 0, a list
    the run cannot read), the robot stopped in Passive, with a word of the cable. No frame
    came, so the tree never ticked and nothing of the mission was sent: NO CONNECTION, exit
    3, safe to retry (decided; it was exit 8, "lost after the run started", which a
    service's ``RestartPreventExitStatus=8`` left for a person; 0.1.0 said CONNECTION LOST,
    exit 3)."""
    line = LosesByteOfEvery(*[(STREAM, 5)] * (STREAM_ASKS_AGAIN + 1))
    run = run_mission(DRIVE_60_CM, host_line=line, timeout=10.0)
    summary = run.summary
    assert (summary.outcome, summary.exit_code) == (Outcome.NO_CONNECTION, ExitCode.CONNECTION)
    assert summary.ticks == 0
    for words in (
        "the line is garbled",
        f"no frame came though the stream was asked for {STREAM_ASKS_AGAIN + 1} times: bytes "
        "from the computer to the robot may be lost (check the cable",
    ):
        assert words in summary.reason
    assert summary.reason.endswith(
        "; the mission did not start: no sensor frame came after the robot answered the "
        "start-up, so nothing of the mission was sent"
    )
    sim = run.simulator
    assert sim.mode.label == "Passive" and sim.requested_left == sim.requested_right == 0
    assert sum(data.endswith(STREAM) for _, data in run.link.writes) == STREAM_ASKS_AGAIN + 1


def test_a_fall_of_unknown_cause_names_the_cable_where_bytes_were_seen_lost(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """Drive 200 with its opcode lost, ``00 c8 80 00``: its radius's 80 is Start, and the
    robot drops to Passive with no cliff or wheel drop in its frame. Said "unknown" alone,
    though the run had already asked for its stream again (a byte of it lost)."""
    line = LosesByteOfEvery((STREAM, 5), (DRIVE_200, 0))
    run = run_mission(DRIVE_60_CM, host_line=line, timeout=10.0)
    summary = run.summary
    assert summary.falls == {"unknown": 1}
    falls = next(line for line in summary.lines() if line.startswith("falls"))
    assert "the robot fell to Passive by itself once (unknown); bytes from the computer to " in (
        falls
    )
    assert "lost in this run (the stream request once, put right): a data byte after a lost " in (
        falls
    )
    assert "can be read as Start (128), so the cable is a likely cause" in falls
    said = next(r.getMessage() for r in caplog.records if "by itself" in r.getMessage())
    assert "went from Safe to Passive by itself (unknown; bytes from the computer to the" in said
    assert run.simulator.mode.label == "Passive"


def test_a_fall_of_unknown_cause_blames_no_cable_never_seen_to_lose_a_byte(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    run = run_mission(DRIVE_60_CM, host_line=LosesByte(DRIVE_200, 0), timeout=10.0)
    summary = run.summary
    assert summary.falls == {"unknown": 1}
    falls = next(line for line in summary.lines() if line.startswith("falls"))
    assert falls.endswith("the robot fell to Passive by itself once (unknown)")
    assert not any(
        "cable" in r.getMessage() for r in caplog.records if "by itself" in r.getMessage()
    )


class ArrivesAs(HostLine):
    """A line on which the first write equal to ``data`` reaches the robot as ``into``: what
    a byte lost before a command's data can make of it (a ``96 00`` read as Pause Stream,
    an ``ad`` as Stop)."""

    def __init__(self, data: bytes, into: bytes) -> None:
        super().__init__(Faults(), 0)
        self.data, self.into = data, into

    def passed(self, data: bytes | bytearray) -> tuple[bytes, str]:
        if bytes(data) != self.data or not self.into:
            return bytes(data), ""
        into, self.into = self.into, b""
        self.dropped += 1
        return into, "made another command"


PAUSE = C.pause_stream().data  # 96 00
ASKED_AGAIN = stream_zeros(tuple(STREAM[2:])) + STREAM


def test_a_stream_paused_mid_run_is_asked_for_again_and_the_run_rides_it_through(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """The robot heard the drive and then a Pause Stream made of lost bytes: nothing came,
    and the run waited the grace and ended "the sensor stream stopped" (exit 3; 2 dock runs
    of 100 at 1 % of the bytes lost). Now the stream is asked for again at a third of the
    grace (the zeros, then the request), it comes back, and the drive ends as a stall ridden
    through; said once."""
    run = run_mission(DRIVE_60_CM, host_line=ArrivesAs(DRIVE_200, DRIVE_200 + PAUSE), timeout=10.0)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.stalls, summary.stalls_ridden) == (1, 1)
    asks = [(t, data) for t, data in run.link.writes if data.endswith(STREAM)]
    assert [data for _, data in asks] == [STREAM, ASKED_AGAIN]
    paused_at = next(t for t, data in run.link.writes if data == DRIVE_200)
    assert asks[1][0] - paused_at == pytest.approx(2.0 / (STALL_ASKS + 1), abs=0.05)
    said = [r for r in caplog.records if "asking for it again" in r.getMessage()]
    assert len(said) == 1 and said[0].levelname == "WARNING"
    assert "the sensor stream stopped (a byte lost on the way to the robot can make a Pause " in (
        said[0].getMessage()
    )
    sim = run.simulator
    assert sim.mode.label == "Passive" and sim.requested_left == sim.requested_right == 0


def test_a_stream_that_does_not_come_back_ends_the_run_with_the_asks_said(
    run_mission: RunMission,
) -> None:
    """A Stop (173) made of lost bytes leaves the OI Off, which hears no stream request: the
    stream is asked for again :data:`STALL_ASKS` times, then the grace ends the run as
    before, exit 3, the asks said beside the cause and the robot left stopped in Passive
    (the stop's Start)."""
    stop = C.stop().data
    run = run_mission(DRIVE_60_CM, host_line=ArrivesAs(DRIVE_200, DRIVE_200 + stop), timeout=10.0)
    _lost_and_stopped(
        run,
        "the sensor stream stopped: nothing arrived for 2.0 s",
        f"the stream was asked for again {STALL_ASKS} times within the grace (zeros, then the "
        "request), and nothing came",
    )
    assert sum(data == ASKED_AGAIN for _, data in run.link.writes) == STALL_ASKS


def test_a_gap_that_ends_before_a_third_of_the_grace_asks_nothing(tmp_path: Path) -> None:
    """A stall whose frames come back by themselves before a third of the grace (a Wi-Fi
    bridge that held every byte 0.5 s) writes nothing more than the watchdog's drive 0 and
    the wheels' command again."""
    link = BridgeLink(Simulator(load_world("empty-room"), CREATE2, 0), 0.02, 0.0, (1.0, 0.5))
    mission = load_mission(write_mission(tmp_path, DRIVE_60_CM))
    summary = RunStack(mission, link, profile=CREATE2, timeout_s=10.0).run()
    assert summary.outcome is Outcome.SUCCESS
    assert (summary.stalls, summary.stalls_ridden) == (1, 1)
    assert [data for _, data in link.writes if data.endswith(STREAM)] == [STREAM]


@pytest.mark.parametrize(
    ("line", "asked_mid_run"),
    [
        pytest.param(lambda: LosesByte(STREAM, 5), [], id="its request lost a byte"),
        pytest.param(lambda: ArrivesAs(DRIVE_200, DRIVE_200 + PAUSE), [1], id="paused mid-run"),
    ],
)
def test_a_stream_asked_for_again_is_replayed_byte_for_byte(
    run_mission: RunMission,
    tmp_path: Path,
    line: Callable[[], HostLine],
    asked_mid_run: list[int],
) -> None:
    """A request again at start-up follows the watchdog's time: the record notes it as a
    trip. One mid-run follows the grace on the run's clock: the record notes it as itself.
    Either way a replay, whose reads come at other times, asks again where the run did."""
    record_path = tmp_path / "run.rec"
    run = run_mission(DRIVE_60_CM, host_line=line(), timeout=10.0, record=record_path)
    assert run.summary.outcome is Outcome.SUCCESS
    record = load_record(record_path)
    notes = [note[STREAM_AGAIN_NOTE] for _, note in record.notes if STREAM_AGAIN_NOTE in note]
    assert notes == asked_mid_run
    mission = load_mission(tmp_path / "mission.yaml")
    summary, transport = replay_record(
        record, mission, profile=CREATE2, packets=record.header["packets"],
        baud=record.header["baud"], name="run.rec",
    )  # fmt: skip
    assert transport.first_difference() is None and transport.written == record.out_bytes
    assert summary.outcome is Outcome.SUCCESS
