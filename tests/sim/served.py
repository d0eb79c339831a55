"""The simulator served on an endpoint (a pty, RFC 2217) in a thread, for the tests of the
real-time server's lines and of a transport over them."""

from __future__ import annotations

import threading

from waits import joined  # tests/waits.py: a hang's bound

from roomba_bt.oi.profiles import CREATE2
from roomba_bt.sim import Faults, Simulator, load_world
from roomba_bt.sim.server import Endpoint, serve


class Served:
    """A simulator served on ``endpoint`` in a thread, until the test ends."""

    def __init__(
        self,
        endpoint: Endpoint,
        baud: int = 115200,
        asleep: bool = False,
        faults: Faults | None = None,
    ) -> None:
        self.simulator = Simulator(load_world("empty-room"), CREATE2, 0, faults)
        self.simulator.baud = baud
        if asleep:
            self.simulator.fall_asleep("test")
        self.endpoint = endpoint
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=serve, args=(self.simulator, endpoint, self._stop.is_set), daemon=True
        )
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        joined(self._thread, "the served simulator's thread, told to stop")
        self.endpoint.close()
