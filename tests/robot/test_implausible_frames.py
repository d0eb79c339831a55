"""Frames that pass the checksum but cannot be what the robot sent change nothing: not the mode
model, not a hazard, not the "mode + 1" offset (on the simulator, through the whole connection,
and on the stub the behaviour tests use)."""

from __future__ import annotations

import itertools
from typing import Any

import pytest

from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.testing import StubRobot
from roomba_bt.sim import SimLink, Simulator, parse_world

PACKETS = (7, 9, 10, 11, 12, 35, 43, 44)
BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""


class Splicing:
    """A simulator link that hands out extra bytes, as a noisy line would, on the next read."""

    def __init__(self, link: SimLink) -> None:
        self.link = link
        self.extra = b""

    def read(self, timeout: float) -> bytes:
        data = self.link.read(timeout)
        if self.extra and data:
            data, self.extra = data + self.extra, b""
        return data

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


def connected(profile: RobotProfile = CREATE2) -> tuple[Connection, Splicing]:
    link = Splicing(SimLink(Simulator(parse_world(BOX, "<test>"), profile=profile)))
    connection = Connection(link, profile)
    connection.start("safe", PACKETS)
    while connection.counters.frames < 10:
        connection.poll(0.05)
    return connection, link


def forged(values: dict[int, int], encoders: tuple[int, int]) -> bytes:
    """A frame with a right checksum (what two cancelling bit flips leave)."""
    layout = layout_for(PACKETS, CREATE2)
    base = {pid: 0 for pid in layout.members} | {35: 2, 43: encoders[0], 44: encoders[1]}
    return layout.stream_frame(base | values)


@pytest.mark.parametrize(
    "values",
    [{35: 4}, {7: 0b0001_0000}, {7: 0b1111_0000}, {7: 0b0100_0000, 35: 4}],
    ids=["mode 4", "reserved bit 4", "reserved bits 4-7", "both"],
)
def test_a_frame_out_of_range_is_dropped_whole_on_the_simulator(values: dict[int, int]) -> None:
    connection, link = connected()
    assert connection.mode is OIMode.SAFE and connection.modes.plus_one is False
    latest = connection.latest
    assert latest is not None
    frames_before = connection.counters.frames
    link.extra = forged(values, (latest.frame[43], latest.frame[44]))
    seen = []
    while connection.counters.frames < frames_before + 10:
        seen += connection.poll(0.05)
    assert connection.counters.implausible_frames == 1
    assert connection.mode is OIMode.SAFE and connection.modes.plus_one is False
    assert connection.last_fallback is None
    assert not any(t.frame.any_hazard for t in seen)
    assert all(t.frame[7] < 16 for t in seen)
    connection.close()


def test_an_encoder_jump_is_dropped_and_odometry_goes_on() -> None:
    connection, link = connected()
    latest = connection.latest
    assert latest is not None
    link.extra = forged({}, (latest.frame[43] + 4000, latest.frame[44]))
    frames_before = connection.counters.frames
    seen = []
    while connection.counters.frames < frames_before + 10:
        seen += connection.poll(0.05)
    assert connection.counters.implausible_frames == 1
    steps = [abs(b.frame[43] - a.frame[43]) for a, b in itertools.pairwise(seen)]
    assert max(steps) < 30
    connection.close()


def test_the_stub_keeps_its_mode_and_hazards_on_such_a_frame() -> None:
    stub = StubRobot(mode=OIMode.SAFE)
    snapshot = stub.set_frame({7: 0b1111_0000, 35: 4})
    assert snapshot.mode is OIMode.SAFE
    assert not snapshot.frame.any_wheel_drop and not snapshot.frame.any_bump
    assert not snapshot.frame.bumps.wheel_drop_left and not snapshot.frame.bumps.wheel_drop_right
