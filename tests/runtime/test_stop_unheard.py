"""The end of a run on a cable whose host-to-robot wire died: the tree ends well, the robot
never hears the stop and streams on; the run must not say it stopped it."""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import spins_then_passive

PAUSE_START = oi.pause_stream().data + oi.start().data
HALT, MOTORS_OFF = oi.halt().data, oi.motors_off().data

SPIN_A_WHILE = spins_then_passive("spin-a-while", ("2s", "velocity: 100 mm/s, radius: spin_left"))


class CutTxAt:
    """The simulator's link through a relay that drops every host-to-robot byte from
    ``cut_at`` (simulated seconds) on, silently; the robot's frames still come. On the wall
    clock as a port is (where the stop is checked against the stream)."""

    wall_clock = True

    def __init__(self, simulator: Simulator, cut_at: float) -> None:
        self.link = SimLink(simulator)
        self.simulator = simulator
        self.cut_at = cut_at
        self.dropped = 0
        self.tail = b""  # what was dropped

    def write(self, data: bytes) -> None:
        if self.simulator.time >= self.cut_at:
            self.dropped += len(data)
            self.tail += data
        else:
            self.link.write(data)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


def test_a_run_whose_stop_the_robot_never_heard_is_no_success(tmp_path: Path) -> None:
    """It said ``outcome SUCCESS``, ``final mode Passive``, ``safe stop sent ...``, exit 0,
    with the robot still in Safe, spinning. The tree's own ``mode: passive`` went unheard
    too: the model's Passive is what was written; packet 35 after the stop reads Safe, and
    the stop is written again from Safe, drive 0 in it."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN_A_WHILE)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = CutTxAt(simulator, cut_at=1.0)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2)
    summary = stack.run()
    stack.close()
    assert link.dropped > 0
    assert (
        simulator.mode is OIMode.SAFE and simulator.requested_left < 0 < simulator.requested_right
    )
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 8
    assert summary.reason.startswith("the safe stop did not reach the robot")
    assert summary.reason.endswith("(the run had ended: success)")
    assert summary.safe_stop.startswith(  # "stopped": the tree's own drive 0, unheard too
        "NOT DELIVERED: last seen in Safe (the last wheel command written: stopped); the stop "
        "was written 3 times but not received: "
    ), summary.safe_stop
    # the first stop from the Passive written ([150 0][128]), the next two from the Safe
    # seen, each after zeros (a long command a lost byte made may have taken the first)
    again = STOP_RESYNC_ZEROS + HALT + MOTORS_OFF + PAUSE_START
    assert link.tail.endswith(PAUSE_START + again + again)
    # what the frames after the stop showed: still in Safe, still spinning
    assert "packet 35 still reading Safe, the wheels turning (-" in summary.safe_stop
    assert "final mode   unknown: last seen in Safe, the stop was not delivered" in str(summary)
    # the tester's relay, docs/runtime.md: its wire cut, "it is now the line above"
    assert_quoted("docs/runtime.md", "outcome CONNECTION LOST (the safe stop did not reach the "
                  "robot (the run had ended: success", str(summary))  # fmt: skip


class SilentThenCtrlC(SimLink):
    """The simulator's link, the robot's frames lost from ``mute_at`` (simulated seconds) on
    (a cable pulled), and Ctrl-C pressed ``after`` seconds later, before the watchdog trips.
    On the wall clock as a port is."""

    wall_clock = True

    def __init__(self, simulator: Simulator, mute_at: float, after: float) -> None:
        super().__init__(simulator)
        self.mute_at = mute_at
        self.press_at: float | None = mute_at + after

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        if self.press_at is not None and self.simulator.time >= self.press_at:
            self.press_at = None
            os.kill(os.getpid(), signal.SIGINT)
        return b"" if self.simulator.time >= self.mute_at else data


@pytest.mark.parametrize(
    ("after", "halt", "said"),
    [
        # the watchdog not yet tripped; the port read once more for what waited unread
        # before the stop was written (one 15 ms step of this link's clock)
        (0.05, "the drive 0 before the tree's stop", "for 0.07 s before it, and none after it"),
        # tripped: its drive 0 sent, the grace not yet out
        (0.5, "the watchdog's drive 0", "for 0.51 s before it"),
    ],
)
def test_ctrl_c_after_the_robot_fell_silent_is_no_confirmed_stop(
    tmp_path: Path, after: float, halt: str, said: str
) -> None:
    """Ctrl-C 0.05 s into a silence (the watchdog's 0.1 s not yet out): the summary said
    ``safe stop sent ...``, ``final mode Passive``, of a robot nothing was heard from after
    the stop, nor for 0.05 s before it. Half a second into it the stop was unconfirmed, but
    ``final mode`` read ``last seen in Passive``: the model after the stop written, not the
    Safe the robot was last seen in. The run's own drive 0 before the stop (the watchdog's,
    the one before the tree's stop), no frame after it, was said ``stopped``: the spin is
    named, that drive 0 unconfirmed."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN_A_WHILE)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    link = SilentThenCtrlC(simulator, mute_at=1.0, after=after)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2)
    summary = stack.run(raise_interrupts=False)
    stack.close()
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.stalls == (after > 0.1)
    assert summary.safe_stop == (
        f"NOT DELIVERED: last seen in Safe spinning left at 100 mm/s (then {halt}, which no "
        "frame showed heard); the stop was written but is unconfirmed: the robot had sent no "
        f"valid frame {said}"
    )
    assert "final mode   unknown: last seen in Safe, the stop was not delivered" in str(summary)
