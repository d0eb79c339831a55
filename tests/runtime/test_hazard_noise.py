"""On the simulator: a corrupted frame that passes every check and shows a hazard does not end
an action (the next frame does not confirm it); a real bump still does, one frame late."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.mission import load_mission
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser
from roomba_bt.runtime.loop import stream_request
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import TapLink

SPIN_UNTIL_CLIFF = """
mission: spin-until-cliff
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, radius: spin_left}
      until: {cliff: {}}
"""


class ForgingLink(TapLink):
    """Appends, once, after ``at`` s, a copy of the frame just read with a front cliff set and
    a right checksum: what two cancelling bit flips can leave."""

    def __init__(self, simulator: Simulator, packets: tuple[int, ...], at: float) -> None:
        super().__init__(simulator)
        self.parser = StreamParser(packets)
        self.layout = layout_for(packets, CREATE2)
        self.at = at
        self.forged_at: float | None = None

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        frames = self.parser.feed(data) if data else []
        if frames and self.forged_at is None and self.simulator.time >= self.at:
            self.forged_at = self.simulator.time
            data += self.layout.stream_frame(dict(frames[-1]) | {11: 1})
        return data


def test_one_forged_cliff_frame_does_not_end_the_drive(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(SPIN_UNTIL_CLIFF)
    mission = load_mission(path, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    link = ForgingLink(simulator, stream_request(mission.packets, 115200), at=0.5)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=2.0)
    summary = stack.run()
    assert link.forged_at is not None
    assert summary.outcome is Outcome.TIMEOUT, summary.reason
    assert summary.unconfirmed_hazards == 1
    # it kept spinning after the forged frame until the time ran out
    assert summary.mission_time_s >= 2.0
