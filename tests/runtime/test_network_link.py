"""A run through a WiFi-serial bridge (tests/runtime/simrun.py's ``BridgeLink``: latency,
ordered jitter, a hiccup that holds both directions and then lets the backlog through, no
byte lost), on the simulator's virtual clock: what the robot did is the simulator's own
record, not the wall clock's."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from roomba_bt.mission import Permissions, load_mission, load_mission_text
from roomba_bt.oi import commands as oi
from roomba_bt.oi.profiles import CREATE2, ROOMBA600
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Simulator, load_world

from .simrun import LEDGE, BridgeLink
from .test_strict import BLIND, OVER_THE_EDGE_BLIND

#: Safe, a wait, then the mission's own Start (``mode: passive``) and a wait after it
SAFE_THEN_PASSIVE = """
mission: safe-then-passive
tree:
  sequence:
    - mode: safe
    - wait: 2s
    - mode: passive
    - wait: 1s
"""
START = oi.start().data


def through_a_bridge(
    text: str, hold: tuple[float, float] | None = None, jitter: float = 0.0, **run: object
) -> tuple[RunSummary, BridgeLink]:
    """``text`` run to its end on a Roomba 600 behind a bridge of 20 ms each way."""
    simulator = Simulator(load_world("empty-room"), ROOMBA600, seed=0)
    link = BridgeLink(simulator, 0.02, jitter, hold)
    mission = load_mission_text(text, profile=ROOMBA600)
    stack = RunStack(mission, link, profile=ROOMBA600, timeout_s=60.0, **run)  # type: ignore[arg-type]
    return stack.run(raise_interrupts=False), link


def test_a_hiccup_as_the_mission_sends_start_is_no_fall_by_itself() -> None:
    # the bridge holds both ways for 250 ms as the mission's Start goes out: the frames
    # that waited (Safe, sent before the robot heard it) come in a burst, then Passive.
    # It was "went from Passive to Safe by itself (unexpected report)", then "from Safe to
    # Passive by itself (unknown)": --strict exit 7 for a run that did what it should
    _, clean = through_a_bridge(SAFE_THEN_PASSIVE)
    # the start-up's Start, then the mission's (the safe stop's comes with its pause)
    _, sent = [t for t, b in clean.writes if b == START]
    summary, link = through_a_bridge(SAFE_THEN_PASSIVE, hold=(sent - 0.005, 0.25), strict=True)
    assert [t for t, b in link.writes if b == START] == [0.0, sent]
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.falls == {} and summary.strict_findings() == []
    assert summary.exit_code == 0
    # the robot took the Start once the hold was over: the simulator's own record; and
    # mission time is the robot's (the backlog filled the hold's slots, none lost)
    *_, start = [e for e in link.simulator.events if e.detail == "Safe->Passive (start)"]
    assert start.time >= sent + 0.245
    assert summary.frames_lost == 0 and summary.stalls == summary.stalls_ridden == 1


#: ten seconds of mission time, nothing else: its length on the robot's clock tells
WAIT_10S = "mission: wait\ntree:\n  wait: 10s\n"
STREAM = 148  # the opcode of the stream request: the robot's stream begins when it hears it


def robot_time_of_the_run(summary: RunSummary, link: BridgeLink) -> float:
    """Seconds of the robot's clock from the stream request to the safe stop's write, less
    the link's way there and back: what the mission's time should have counted."""
    [asked] = [t for t, b in link.writes if b[0] == STREAM]
    stopped = link.writes[-1][0]
    return stopped - asked - 2 * link.latency


@pytest.mark.parametrize(
    ("jitter", "hold"), [(0.08, None), (0.01, (4.0, 3.0))], ids=["0-80 ms", "a 3 s hold"]
)
def test_mission_time_through_a_bridge_is_the_robot_s(
    jitter: float, hold: tuple[float, float] | None
) -> None:
    # no byte lost: no frame lost, and the wait lasts its 10 s on the robot. Through 0-80 ms
    # of jitter 43 frames were "lost" in 10 s (the wait 9.42 s on the robot); a stall ridden
    # through was counted twice, the gap then the backlog (a 10 s wait: 8.34 s)
    summary, link = through_a_bridge(WAIT_10S, hold, jitter, watchdog=0.3, grace=5.0)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.frames_lost == 0
    assert summary.mission_time_s == pytest.approx(10.0, abs=0.05)  # a batch's slots
    assert robot_time_of_the_run(summary, link) == pytest.approx(10.0, abs=jitter + 0.05)


def test_the_mode_guard_s_since_agrees_with_the_fall_s_mission_time(tmp_path: Path) -> None:
    # 0-80 ms of jitter, over the edge with a leaf that drives on, then a 0.6 s hold ridden
    # through: the last refusal said, after the hold, still has the robot "in Passive since"
    # the fall's mission time (0.5-0.9 s apart through a WiFi bridge, while mission time ran
    # ahead of the link's clock)
    (tmp_path / "blind.py").write_text(BLIND)
    (tmp_path / "blind.yaml").write_text(OVER_THE_EDGE_BLIND)
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    simulator = Simulator(load_world(tmp_path / "ledge.yaml"), CREATE2, seed=0)
    link = BridgeLink(simulator, 0.02, 0.08, (4.3, 0.6))
    mission = load_mission(tmp_path / "blind.yaml", permissions=Permissions(plugin_files=True))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=60.0, watchdog=0.3, grace=5.0)
    summary = stack.run(raise_interrupts=False)
    assert summary.stalls_ridden == 1 and summary.frames_lost == 0
    fell = re.fullmatch(r"t=([\d.]+) in blind_drive: cliff", summary.first_fall)
    last = stack.runner.refusals[-1]
    said = re.fullmatch(r"t=([\d.]+) blind_drive: .* in Passive since t=([\d.]+), .*", last)
    assert fell is not None and said is not None, (summary.first_fall, last)
    assert float(said[1]) > float(fell[1]) + 1.0  # said after the hold
    assert float(said[2]) == pytest.approx(float(fell[1]), abs=0.1)  # the jitter at most


#: a turn, then a drive: the turn ends while a hold keeps the frames back
TURN_THEN_DRIVE = """
mission: turn-then-drive
tree:
  sequence:
    - mode: safe
    - turn: {angle: 90deg}
    - drive: {velocity: 150 mm/s, distance: 30 cm}
"""
TURN = oi.drive(100, oi.Radius.TURN_COUNTER_CLOCKWISE).data
FORWARD = oi.drive(150, oi.Radius.STRAIGHT).data


def test_after_a_stall_the_wheels_get_the_tree_s_command_not_one_its_backlog_ended() -> None:
    # the bridge holds both ways for 1.5 s, 0.35 s into the turn: the robot turns on (the
    # watchdog's drive 0 is held too) and the turn's end is in the frames that waited, read
    # over several reads. The turn went out again at the first of them, the robot turning
    # back to a stale command until the rest were read and the drive came
    summary, link = through_a_bridge(TURN_THEN_DRIVE, hold=(0.6, 1.5), grace=3.0)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.stalls == summary.stalls_ridden == 1
    wheels = [(t, b) for t, b in link.writes if b[0] == oi.drive(0, 0).data[0]]
    assert [b for t, b in wheels if t < 0.6] == [TURN]
    after = [b for t, b in wheels if t >= 2.1]
    assert after[0] == FORWARD, after
    assert TURN not in after
