"""The in-process link to a simulator: the Transport contract on a virtual clock.

The robot connection talks to anything with ``name``, ``write``, ``read(timeout)``,
``set_baud``, ``close``, ``is_open`` and ``now()`` (structural typing: this module does not
import the transport layer). :class:`SimLink` is that, with the simulator behind it:

* ``write(data)`` hands the bytes to the robot at once (replies to 142/149 appear then);
* ``read(timeout)`` returns bytes the robot already sent or, if there are none, advances the
  simulator 15 ms at a time until some arrive or ``timeout`` seconds of *simulated* time
  have passed. A caller that keeps reading therefore drives the clock, and the stream
  arrives every 15 ms of virtual time, as fast as the host can compute it;
* ``now()`` is the simulated time, so frame timestamps and watchdogs run on the same clock.

The link has a baud rate, like a port: after Baud (129) the robot talks at its new rate, and
until ``set_baud`` follows, what the host reads is garbage (each byte mapped to another) and
what it writes never reaches the robot, as on a serial line at mismatched rates.
"""

from __future__ import annotations

from roomba_bt.sim.robot import STEP_SECONDS, Simulator

#: What a byte looks like when read at the wrong baud rate (a fixed, reversible scramble).
_GARBLE = bytes.maketrans(bytes(range(256)), bytes((b * 37 + 11) & 0xFF for b in range(256)))


class SimLink:
    """A :class:`~roomba_bt.sim.robot.Simulator` behind the Transport contract."""

    def __init__(self, simulator: Simulator, name: str = "sim://") -> None:
        self.simulator = simulator
        self.name = name if name != "sim://" else f"sim://{simulator.world.name}"
        self._open = True
        self.baud = simulator.profile.default_baud

    @property
    def is_open(self) -> bool:
        return self._open and not self.simulator.disconnected

    def _check(self) -> None:
        if not self._open:
            raise ConnectionError(f"{self.name}: link is closed")
        if self.simulator.disconnected:
            raise ConnectionError(
                f"{self.name}: simulated disconnect at t={self.simulator.time:.3f} s"
            )

    def write(self, data: bytes) -> None:
        self._check()
        if self.baud != self.simulator.baud:
            self.simulator.ignored_bytes += len(data)  # framing errors: nothing gets through
            return
        self.simulator.receive(data)

    def read(self, timeout: float) -> bytes:
        sim = self.simulator
        if not self._open or sim.disconnected:
            self._check()
        data = sim.read()
        if not data:
            deadline = sim.time + (timeout if timeout > 0.0 else 0.0) - 1e-9
            step, read = sim.step, sim.read
            while True:
                step()
                if sim.disconnected:
                    raise ConnectionError(
                        f"{self.name}: simulated disconnect at t={sim.time:.3f} s"
                    )
                data = read()
                if data or sim.time >= deadline:
                    break
        return data if self.baud == sim.baud else data.translate(_GARBLE)

    def set_baud(self, baud: int) -> None:
        self._check()
        self.baud = baud

    def close(self) -> None:
        self._open = False

    def now(self) -> float:
        return self.simulator.time

    def advance(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass without reading (bytes stay buffered)."""
        for _ in range(round(seconds / STEP_SECONDS)):
            self.simulator.step()
