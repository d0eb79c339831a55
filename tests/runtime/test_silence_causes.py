"""A stream that stops with nothing on the line is explained by asking the robot once the
grace runs out (robot/silence.py): a robot that answers stopped streaming; one that answers
only after a BRC pulse was asleep (at any time, not only after the OI's five minutes); one
that never answers is switched off or cut off. On the virtual clock, in process."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.mission import load_mission
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

WAIT_IN_PASSIVE = """
mission: wait-in-passive
tree:
  wait: 10min
"""
SPIN = """
mission: spin
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, radius: spin_left}
"""


class NoModemLines(SimLink):
    """A link whose modem lines cannot be set (a pty): BRC cannot be pulsed."""

    def set_wake_line(self, low: bool) -> None:
        raise OSError(25, "Inappropriate ioctl for device")


def run(
    tmp_path: Path, text: str, faults: Faults, link_type: type[SimLink] = SimLink
) -> tuple[RunSummary, Simulator]:
    path = tmp_path / "m.yaml"
    path.write_text(text)
    mission = load_mission(path, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, faults, trace=False)
    stack = RunStack(mission, link_type(simulator), profile=CREATE2, timeout_s=60.0)
    summary = stack.run()
    stack.close()
    return summary, simulator


def test_a_robot_that_fell_asleep_early_is_woken_by_a_pulse_and_named_asleep(
    tmp_path: Path,
) -> None:
    summary, simulator = run(tmp_path, WAIT_IN_PASSIVE, Faults(sleep_at=5.0))
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert summary.exit_code == 3
    assert "the robot was asleep" in summary.reason
    assert "until a BRC pulse woke it (pulsed BRC low for 1 s" in summary.reason
    assert "sensor stream stopped" not in summary.reason
    assert [e.kind for e in simulator.events if e.kind in ("sleep", "wake")] == ["sleep", "wake"]
    assert not simulator.asleep and simulator.mode is OIMode.PASSIVE


def test_a_robot_that_only_stopped_streaming_is_said_to_still_answer(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, SPIN, Faults(stream_stop_at=3.0))
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the sensor stream stopped" in summary.reason
    assert "the robot still answers a query (its OI is on)" in summary.reason
    assert "asleep" not in summary.reason
    assert simulator.brc_pulses == 1  # keep-awake's first only: it answered, no wake pulse
    assert summary.stop_delivered and simulator.mode is OIMode.PASSIVE


def test_a_robot_that_cannot_be_pulsed_is_not_called_asleep(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, WAIT_IN_PASSIVE, Faults(sleep_at=5.0), NoModemLines)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the sensor stream stopped" in summary.reason
    assert "no BRC pulse could wake it" in summary.reason
    assert [e.kind for e in simulator.events if e.kind == "wake"] == []  # no pulse woke it
