"""Helpers for the simulator tests: small worlds written inline and a host that speaks OI."""

from __future__ import annotations

import math
from collections.abc import Iterable

from roomba_bt.oi import commands as C
from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.oi.stream import StreamParser, decode_reply
from roomba_bt.sim import Pose, Simulator, World, parse_world

BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""


def box_with_a_drop(drop_from_x: float, start: tuple[float, float]) -> str:
    """:data:`BOX`'s room, its floor a drop east of ``drop_from_x`` (m) to the wall, the
    robot starting at ``start`` (m) facing east, toward the drop."""
    return (
        "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\n"
        f"drops: [{{rect: [{drop_from_x}, 0, 4, 4]}}]\n"
        f"robot: {{start: {{at: [{start[0]}, {start[1]}], heading: 0}}}}\n"
    )


def world(text: str = BOX) -> World:
    return parse_world(text, "<test>")


def pose(x_m: float, y_m: float, heading_deg: float) -> Pose:
    return Pose(x_m * 1000.0, y_m * 1000.0, math.radians(heading_deg))


class Host:
    """Drives a simulator through bytes only, as a client on the wire would."""

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        self.parser: StreamParser | None = None

    def send(self, *commands: Command | bytes) -> None:
        self.sim.receive(b"".join(c if isinstance(c, bytes) else c.data for c in commands))

    def stream(self, ids: Iterable[int]) -> None:
        ids = list(ids)
        self.sim.read()
        self.send(C.stream(ids))
        self.parser = StreamParser(ids, self.sim.profile)

    def frames(self, seconds: float) -> list[SensorFrame]:
        assert self.parser is not None
        out: list[SensorFrame] = []
        for _ in range(round(seconds / 0.015)):
            self.sim.step()
            out += self.parser.feed(self.sim.read())
        return out

    def frame(self) -> SensorFrame:
        frames = self.frames(0.015)
        assert len(frames) == 1
        return frames[0]

    def query(self, ids: list[int]) -> SensorFrame:
        self.sim.read()
        self.send(C.query_list(ids))
        return decode_reply(ids, self.sim.read(), self.sim.profile)

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / 0.015)):
            self.sim.step()
        self.sim.read()


def make(
    text: str = BOX,
    start: Pose | None = None,
    profile: RobotProfile = CREATE2,
    mode: str | None = "safe",
    **kwargs: object,
) -> Host:
    sim = Simulator(world(text), profile, start=start, **kwargs)  # type: ignore[arg-type]
    host = Host(sim)
    if mode is not None:
        host.send(C.start())
        if mode == "safe":
            host.send(C.safe())
        elif mode == "full":
            host.send(C.full())
    return host


DOCK_WORLD = """
name: dock-box
rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]
dock: {at: [2, 0], facing: 90}
robot: {start: {at: [2, 1.2], heading: -90}}
"""


def docked_start() -> Pose:
    dock = world(DOCK_WORLD).dock
    assert dock is not None
    return dock.docked_pose
