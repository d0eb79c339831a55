"""The watchdog trips on its own deadline, not at the end of the caller's read: a poll that
may wait long for a frame still sends drive 0 100 ms after the last valid one (on the
virtual clock: each read moves the simulator's time, so the figure is exact)."""

from __future__ import annotations

from collections import deque

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import StreamStalled
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

PACKETS = (7, 9, 10, 11, 12, 35, 43, 44)
WATCHDOG = 0.1


@pytest.mark.parametrize("poll_timeout", [0.05, 0.5, 2.0])
def test_a_long_poll_still_stops_the_wheels_when_the_watchdog_is_due(
    poll_timeout: float,
) -> None:
    simulator = Simulator(
        load_world("empty-room"), CREATE2, 0, Faults(stream_stop_at=1.0), trace=False
    )
    connection = Connection(SimLink(simulator), CREATE2, watchdog=WATCHDOG)
    connection.start("safe", PACKETS)
    connection.send(oi.drive(200, 32767))
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(1000):
            connection.poll(poll_timeout)
    assert stalled.value.halted
    latest = connection.latest
    assert latest is not None
    # tripped one slot at most past the watchdog, whatever the poll's own timeout
    assert WATCHDOG < stalled.value.silent_for <= WATCHDOG + SLOT_SECONDS
    assert simulator.time - latest.time <= WATCHDOG + SLOT_SECONDS
    assert simulator.requested_left == simulator.requested_right == 0  # drive 0 arrived


def test_a_replays_watchdog_trips_at_the_recorded_time_and_nowhere_else() -> None:
    """``replayed_trips``: a replay's link trips where its record's did (here 0.3 s after the
    last frame, a run whose read woke late), not on the silence at 100 ms; a recorded trip
    passed with no stream to trip is dropped, not done late."""
    simulator = Simulator(
        load_world("empty-room"), CREATE2, 0, Faults(stream_stop_at=1.0), trace=False
    )
    connection = Connection(SimLink(simulator), CREATE2, watchdog=WATCHDOG)
    connection.link.replayed_trips = deque([0.01])  # before the stream: never tripped
    connection.start("safe", PACKETS)
    connection.send(oi.drive(200, 32767))
    while simulator.time < 1.0:
        connection.poll(0.05)
    last = connection.link.silent_since
    connection.link.replayed_trips.append(last + 0.3)
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(1000):
            connection.poll(0.05)
    assert stalled.value.silent_for == pytest.approx(0.3)
    assert not connection.link.replayed_trips
    assert simulator.requested_left == simulator.requested_right == 0  # its drive 0
