"""A cycle the robot heard though the run never sent one: a Drive whose opcode the line lost.

Drive 135 mm/s straight is ``89 00 87 80 00``; its opcode lost, the robot reads ``00`` (no
opcode), ``87``: Clean (135), and starts its cleaning cycle, leaving Safe for Passive. The
run's watch for a cycle the robot starts by itself said "its Clean, Spot or Dock button, or
its schedule", and the owner went to the buttons: in Safe and Full the robot ignores them
(both specs), so a cycle begun by a fall from Safe with no cause in its frame is a byte of
the run's own read as a cycle command, and the words now name the line.
"""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.oi.modes import OIMode
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Faults
from roomba_bt.sim.faults import HostLine

from .simrun import Run, RunMission

#: Drive 135 mm/s straight: its second byte, 135, is Clean's opcode
DRIVE_135 = C.drive(135, 32768).data
#: the safe stop of a run that ends a cycle: Safe first, drive 0, motors off, pause, Start
SAFE_FIRST_STOP = bytes.fromhex("83 89 00 00 00 00 8a 00 96 00 80")


class LosesTheOpcode(HostLine):
    """A line that loses the first byte of the first write that ends in :data:`DRIVE_135`."""

    def __init__(self) -> None:
        super().__init__(Faults(), 0)
        self.done = False

    def passed(self, data: bytes | bytearray) -> tuple[bytes, str]:
        if self.done or not bytes(data).endswith(DRIVE_135):
            return bytes(data), ""
        self.done = True
        self.dropped += 1
        at = len(data) - len(DRIVE_135)
        return bytes(data[:at] + data[at + 1 :]), f"lost byte {at}"


#: Safe, a short drive (the one whose opcode is lost), then a wait the tree holds in any mode
DRIVE_THEN_WAIT = """
mission: drive then wait
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 135 mm/s, distance: 5 cm}
    - wait: 8s
"""

#: Safe, then a drive that fails once the robot has left Safe (the run's end sees the cycle)
DRIVE_ON = """
mission: drive on
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 135 mm/s, distance: 2 m}
"""


def _left_stopped(run: Run) -> None:
    """The safe stop ended the cycle (Safe first, then drive 0, motors off, the pause and
    Start) and the simulated robot stands in Passive, its wheels still a second later."""
    assert run.link.writes[-1][1] == SAFE_FIRST_STOP
    sim = run.simulator
    sim.run(1.0)
    assert sim.mode is OIMode.PASSIVE
    assert sim.left_speed == sim.right_speed == 0


def test_a_cycle_seen_driving_after_a_fall_of_no_cause_names_the_line(
    run_mission: RunMission,
) -> None:
    """Found by the looks (the tree waits on in Passive): said as the line's, not a button's."""
    run = run_mission(DRIVE_THEN_WAIT, host_line=LosesTheOpcode(), timeout=20.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE
    assert summary.reason.startswith(
        "the robot started a cycle the run did not send: it left Safe by itself at t=0.045 "
        "with no cliff, wheel drop or charger in its frame, and Safe ignores the buttons, "
        "then drove "
    ), summary.reason
    assert (
        "a Clean (135), Spot (134), Max (136) or Seek Dock (143) made of a byte lost or "
        "changed on the line, most likely (a data byte read as an opcode: check the cable "
        "and its adapter: roomba-bt doctor)"
    ) in summary.reason
    assert "button, or its schedule" not in summary.reason
    _left_stopped(run)


def test_a_cycle_the_run_ended_on_before_a_look_is_still_ended(
    run_mission: RunMission,
) -> None:
    """The drive fails a second after the fall (the robot not brought back to Safe), before
    the once-a-second looks had seen the cycle drive: the run's stop was Start alone, which
    ends no cycle, and the robot went on cleaning after the run (at 300 mm/s, bouncing off
    the walls). A Passive begun by a fall of no cause needs no look: the run's end judges
    what it drove there, and its stop sends Safe first."""
    run = run_mission(DRIVE_ON, host_line=LosesTheOpcode(), timeout=20.0)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE
    assert summary.reason.startswith("drive(velocity=135 mm/s, distance=2 m): the robot left")
    assert summary.robot_cycle.startswith(
        "the robot was moving in Passive with no command of the run's as the run ended ("
    ), summary.robot_cycle
    assert "since it left Safe by itself at t=0.045" in summary.robot_cycle
    assert summary.robot_cycle.endswith(", or a hand; the safe stop ends it with Safe first")
    _left_stopped(run)
