"""A stall during which a keep-awake line change held this process's reads names it: the
stall is then the host's own, not the line's (over RFC 2217 pyserial waited for the server's
answer to each line, 100 ms a pulse, past the 100 ms watchdog)."""

from __future__ import annotations

import pytest

from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import StreamStalled
from roomba_bt.robot.wake import KeepAwake
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

PACKETS = (7, 35)
HOLD_S = 0.15


class SlowLineLink(SimLink):
    """A link whose modem lines take :data:`HOLD_S` to set (the reads wait meanwhile)."""

    def set_wake_line(self, low: bool) -> None:
        super().set_wake_line(low)
        self.advance(HOLD_S)


def _stall(held_line: bool) -> StreamStalled:
    simulator = Simulator(
        load_world("empty-room"), CREATE2, 0, Faults(stream_stop_at=5.0), trace=False
    )
    link = SlowLineLink(simulator) if held_line else SimLink(simulator)
    connection = Connection(link, CREATE2, watchdog=0.1, keep_awake=False)
    connection.start("passive", PACKETS)
    while simulator.time < 5.0:
        connection.poll(0.0)
    # a pulse falls due in the silence the stopped stream leaves
    connection.wake = KeepAwake(link, clock=link.now)
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(100):
            connection.poll(0.05)
    return stalled.value


def test_a_stall_a_slow_line_change_held_says_so() -> None:
    stalled = _stall(held_line=True)
    assert stalled.held is not None
    assert "keep-awake BRC pulse held this process's reads for 150 ms" in str(stalled)


def test_a_stall_without_one_is_not_blamed_on_keep_awake() -> None:
    stalled = _stall(held_line=False)
    assert stalled.held is None
    assert "keep-awake" not in str(stalled)
