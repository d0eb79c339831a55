"""The link's round trip, which the stop's listening and the mode model's settle are widened
by, is the quickest of the start-up's Query List replies and at most ``ROUND_TRIP_CAP``: one
slow reply (a loaded host) kept as the longest let actuator bytes go to a robot that had
really fallen to Passive for a second, the whole session (on the simulator's clock)."""

from __future__ import annotations

import logging
from typing import Any

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.ending import ROUND_TRIP_CAP
from roomba_bt.sim import Faults, SimLink, Simulator, parse_world

BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""
PACKETS = (7, 35)
QUERY_MODE = oi.query_list((35,)).data


class SlowFirstReply:
    """A simulator link whose host stalls ``stall`` s (simulated) on its first Query List:
    that one reply is read late, the link itself is quick."""

    def __init__(self, link: SimLink, stall: float) -> None:
        self.link = link
        self.stall = stall

    def write(self, data: bytes) -> None:
        self.link.write(data)
        if bytes(data) == QUERY_MODE and self.stall:
            simulator = self.link.simulator
            until = simulator.time + self.stall
            while simulator.time < until:
                simulator.step()
            self.stall = 0.0

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


def simulator(latency: float = 0.0) -> Simulator:
    faults = Faults(latency=latency)
    return Simulator(parse_world(BOX, "<test>"), profile=CREATE2, faults=faults)


def test_one_slow_start_up_reply_does_not_widen_the_session_s_allowances() -> None:
    connection = Connection(SlowFirstReply(SimLink(simulator()), stall=0.8), CREATE2)
    connection.start("safe", PACKETS)
    assert connection.ending.round_trip < 0.1
    assert connection.modes.settle == connection.settle  # the cable's 0.1 s, not ~1.7 s


def test_a_later_query_does_not_change_the_round_trip() -> None:
    connection = Connection(SimLink(simulator()), CREATE2)
    connection.start("safe")
    measured = connection.ending.round_trip
    link = connection.link.transport
    assert isinstance(link, SimLink)
    link.simulator.faults = Faults(latency=0.9)
    assert connection.query((35,)) is not None
    assert connection.ending.round_trip == measured


@pytest.mark.parametrize("latency", [0.7, 2.0])
def test_a_slower_link_is_capped_and_logged(latency: float, caplog: Any) -> None:
    connection = Connection(SimLink(simulator(latency)), CREATE2, watchdog=1.0 + latency)
    with caplog.at_level(logging.WARNING):
        connection.start("safe", PACKETS, confirm_timeout=latency + 1.0)
    assert connection.ending.round_trip == ROUND_TRIP_CAP
    assert "answered a Query List after" in caplog.text
