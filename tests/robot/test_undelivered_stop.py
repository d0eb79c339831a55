"""A stop that cannot reach the robot is reported as such, with the robot's last known state,
and the mode model follows only what was written (on the simulator, the port failing)."""

from __future__ import annotations

from typing import Any

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import describe_activity
from roomba_bt.robot.errors import PortLost
from roomba_bt.sim import SimLink, Simulator, parse_world

BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""
PACKETS = (7, 9, 10, 11, 12, 35, 43, 44)


class Pullable:
    """A simulator link whose cable can be pulled: every later write raises."""

    def __init__(self, link: SimLink) -> None:
        self.link = link
        self.pulled = False

    def write(self, data: bytes) -> None:
        if self.pulled:
            raise OSError(5, "Input/output error")
        self.link.write(data)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


def driving() -> tuple[Connection, Pullable]:
    link = Pullable(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2)))
    connection = Connection(link, CREATE2)
    connection.start("safe", PACKETS)
    connection.send_many([oi.drive(200, 32767)])
    while connection.counters.frames < 10:
        connection.poll(0.05)
    return connection, link


def test_a_batch_that_was_never_written_does_not_move_the_mode_model() -> None:
    connection, link = driving()
    link.pulled = True
    with pytest.raises(PortLost):
        connection.send_many([oi.full(), oi.drive(100, 0)])
    assert connection.mode is OIMode.SAFE  # Full was queued, never written
    assert connection.activity() == "at 200 mm/s"


def test_a_stop_that_cannot_be_written_is_reported_undelivered() -> None:
    connection, link = driving()
    link.pulled = True
    assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Safe at 200 mm/s; the stop was not delivered: the port is gone"
    )
    assert connection.mode is OIMode.SAFE  # not advanced to Passive by the unsent Start
    assert connection.safe_stopped is False


def test_a_delivered_stop_leaves_no_report() -> None:
    connection, _ = driving()
    assert connection.safe_stop() is True
    assert connection.stop_report is None
    assert connection.mode is OIMode.PASSIVE


def test_a_robot_never_told_to_move_has_its_undelivered_stop_said_quietly(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """``roomba-bt sensors`` with its cable pulled: "ERROR ... last seen in Passive with its
    wheels never commanded; the stop was not delivered" under the error that the port is
    gone, about a robot nothing had asked to move. Reported (the summary's line), logged at
    DEBUG; a robot that was driving is still an ERROR."""
    link = Pullable(SimLink(Simulator(parse_world(BOX, "<test>"), profile=CREATE2)))
    connection = Connection(link, CREATE2)
    connection.start("passive", PACKETS)
    while connection.counters.frames < 10:
        connection.poll(0.05)
    link.pulled = True
    with caplog.at_level("DEBUG", logger="roomba_bt.robot.ending"):
        assert connection.safe_stop() is False
    assert connection.stop_report == (
        "last seen in Passive with its wheels never commanded; the stop was not delivered: "
        "the port is gone"
    )
    assert [r.levelname for r in caplog.records] == ["DEBUG"]
    connection, link = driving()
    link.pulled = True
    caplog.clear()
    with caplog.at_level("DEBUG", logger="roomba_bt.robot.ending"):
        assert connection.safe_stop() is False
    assert [r.levelname for r in caplog.records] == ["ERROR"]


@pytest.mark.parametrize("straight", [0x8000, 0x7FFF])
def test_driving_straight_is_said_without_a_radius(straight: int) -> None:
    """``radius: straight`` is sent as 0x8000: it was said "radius 32768 mm"."""
    assert describe_activity(oi.drive(200, straight)) == "at 200 mm/s"
    assert describe_activity(oi.drive(200, -1000)) == "at 200 mm/s, radius -1000 mm"
