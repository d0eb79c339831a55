"""The robot's port changes its rate in the middle of a run (a battery swap or a reset brings
a Create 2 back at its default rate): the run names it ("the robot now talks at another baud
rate"), follows it and stops the robot at the new rate; noise at the run's rate is not taken
for one. On the virtual clock, in process."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.mission import load_mission
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

SPIN = """
mission: spin
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, radius: spin_left}
"""


def run(tmp_path: Path, faults: Faults, timeout: float = 10.0) -> tuple[RunSummary, Simulator]:
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    mission = load_mission(path, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, faults, trace=False)
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=timeout)
    summary = stack.run()
    stack.close()
    return summary, simulator


def test_a_baud_change_mid_run_is_named_followed_and_the_robot_stopped(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, Faults(baud_change_at=3.0))
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 3
    assert "the robot now talks at another baud rate: 19200, not the 115200" in summary.reason
    assert "drive 0 sent again at 19200" in summary.reason
    assert "garbage since" in summary.reason
    assert summary.stop_delivered
    # the stop reached the robot at its new rate: stopped, in Passive
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    # stopped within the watchdog, the listen and a slot or two of the change
    stops = [e.time for e in simulator.events if e.kind == "mode" and "Passive" in e.detail]
    assert stops and stops[-1] - 3.0 <= 0.1 + 0.1 + 0.06


def test_noise_at_the_run_rate_is_not_taken_for_a_baud_change(tmp_path: Path) -> None:
    summary, _ = run(tmp_path, Faults(bit_flip_rate=0.02), timeout=20.0)
    assert "baud rate" not in summary.reason, summary.reason
