"""The bump reflex on the simulator's virtual clock: while a bump onset waits for the frame
that confirms it, forward motion is held at 0 (drive 0 in the onset frame's own tick), the
action goes on; a real bump gets the tree's reaction one frame later, a phantom (one corrupted
frame) costs a 15 ms pause and the forward command is written again."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser
from roomba_bt.runtime.loop import stream_request
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Simulator, load_world

from .simrun import DRIVE_TO_WALL_AND_BACK_OFF, TapLink

HALT = bytes((137, 0, 0, 0, 0))
FORWARD = commands.drive(200, commands.Radius.STRAIGHT).data
BACK = commands.drive(-100, commands.Radius.STRAIGHT).data
SLOT = 0.015


class BumpTap(TapLink):
    """Every write with the simulated time (:class:`TapLink`); notes when a frame first
    showed a bump; with ``forge_at``, once after that many seconds appends to a read a copy of
    its last frame with the right bumper pressed and a right checksum (two cancelling bit
    flips)."""

    def __init__(self, simulator: Simulator, packets: tuple[int, ...], forge_at: float = 0.0):
        super().__init__(simulator)
        self.parser = StreamParser(packets)
        self.layout = layout_for(packets, CREATE2)
        self.forge_at = forge_at
        self.forged_at: float | None = None
        self.bumped_at: float | None = None

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        frames = self.parser.feed(data) if data else []
        now = self.simulator.time
        if frames and self.bumped_at is None and any(f[7] & 0b11 for f in frames):
            self.bumped_at = now
        if frames and self.forge_at and self.forged_at is None and now >= self.forge_at:
            self.forged_at = now
            data += self.layout.stream_frame(dict(frames[-1]) | {7: 0b01})
        return data

    def written_at(self, when: float) -> list[bytes]:
        return [data for t, data in self.writes if abs(t - when) < 1e-9]


def run(tmp_path: Path, forge_at: float = 0.0) -> tuple[RunSummary, BumpTap]:
    path = tmp_path / "m.yaml"
    path.write_text(DRIVE_TO_WALL_AND_BACK_OFF)
    mission = load_mission(path, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    link = BumpTap(simulator, stream_request(mission.packets, 115200), forge_at)
    summary = RunStack(mission, link, profile=CREATE2, timeout_s=30.0).run()
    return summary, link


def test_a_real_bump_stops_forward_motion_in_its_frame_and_backs_off_one_frame_later(
    tmp_path: Path,
) -> None:
    summary, link = run(tmp_path)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    bumped = link.bumped_at
    assert bumped is not None
    assert link.written_at(bumped) == [HALT]  # the reflex: no step further into the wall
    later = [(t, data) for t, data in link.writes if t > bumped + 1e-9]
    assert later[0] == (later[0][0], BACK)  # the tree's reaction, the next frame
    assert abs(later[0][0] - (bumped + SLOT)) < 1e-9
    assert summary.unconfirmed_hazards == 0


def test_a_one_frame_phantom_bump_pauses_the_wheels_for_one_frame_only(tmp_path: Path) -> None:
    summary, link = run(tmp_path, forge_at=0.5)
    forged = link.forged_at
    assert forged is not None and link.bumped_at is not None and forged < link.bumped_at
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.unconfirmed_hazards == 1
    assert link.written_at(forged) == [HALT]
    assert link.written_at(forged + SLOT) == [FORWARD]  # driving again: the action went on
    # no back-off before the real bump: the phantom did not end the drive
    assert all(data != BACK for t, data in link.writes if t < link.bumped_at)
