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

:class:`RealtimeSimLink` paces the same simulator to the wall clock (one 15 ms step per 15 ms
of wall time), so a run without ``--fast`` looks and feels like a robot.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from roomba_bt.sim.robot import STEP_SECONDS, Simulator

#: What a byte looks like when read at the wrong baud rate (a fixed, reversible scramble).
_GARBLE = bytes.maketrans(bytes(range(256)), bytes((b * 37 + 11) & 0xFF for b in range(256)))


def at_wrong_baud(data: bytes) -> bytes:
    """The robot's bytes as a host reading at another baud rate sees them: each byte mapped
    to another (the in-process link and the pty/RFC 2217 server share this model)."""
    return data.translate(_GARBLE)


class SimLink:
    """A :class:`~roomba_bt.sim.robot.Simulator` behind the Transport contract."""

    #: its clock is the simulator's, as fast as the host steps it: not the wall clock's pace
    wall_clock = False
    #: a read with nothing sent waits whole steps of the simulator, one at least (``read``):
    #: it gets a frame one step on however short its wait. A record says so
    #: (``runtime/recording.py``, ``READ_STEP``), and its replay gives each chunk to the read
    #: that got it here; None where the clock is not the simulator's steps
    read_step: float | None = STEP_SECONDS

    def __init__(self, simulator: Simulator, name: str = "sim://") -> None:
        self.simulator = simulator
        self.name = name if name != "sim://" else f"sim://{simulator.world.name}"
        self._open = True
        self.baud = simulator.profile.default_baud

    @property
    def loses_bytes(self) -> bool:
        """Whether bytes to the robot may be lost or changed on this line (the simulator's
        host-to-robot faults): the safe stop is then listened after on the virtual clock too,
        as on a cable (a perfect line cannot swallow it)."""
        faults = self.simulator.faults
        return faults.host_drop_rate > 0.0 or faults.host_corrupt_rate > 0.0

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
        # what the robot sent and the host did not read yet (replies.py's output): none on
        # most reads (the last read took the step's frame), and then read() would find
        # nothing; the step comes first without that call
        if sim._frame is None and not sim._out and not sim._delayed:
            data = b""
        else:
            data = sim.read()
        if not data:
            deadline = sim.time + (timeout if timeout > 0.0 else 0.0) - 1e-9
            while True:  # most reads step once; the simulator's slots make sim.step() fast
                sim.step()
                if sim.disconnected:
                    raise ConnectionError(
                        f"{self.name}: simulated disconnect at t={sim.time:.3f} s"
                    )
                data = sim.read()
                if data or sim.time >= deadline:
                    break
        return data if self.baud == sim.baud else at_wrong_baud(data)

    def set_baud(self, baud: int) -> None:
        self._check()
        self.baud = baud

    def set_wake_line(self, low: bool) -> None:
        """The modem line wired to BRC (asserted = low): see ``Simulator.set_brc``."""
        self._check()
        self.simulator.set_brc(low)

    def close(self) -> None:
        """Let go of the robot; its wheels' speeds settle to the 0 a stop asked for
        (:meth:`Simulator.settle_wheels`): a program that reads ``simulator.left_speed``
        after a run sees the robot stopped, as the safe stop left it."""
        if self._open:
            self.simulator.settle_wheels()
        self._open = False

    def now(self) -> float:
        return self.simulator.time

    def advance(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass without reading (bytes stay buffered)."""
        for _ in range(round(seconds / STEP_SECONDS)):
            self.simulator.step()


class RealtimeSimLink(SimLink):
    """A :class:`SimLink` whose simulated time follows the wall clock: never ahead of it, and
    never left behind.

    A robot streams every 15 ms whatever the host is doing. When the host was busy (a slow
    tick, a plugin that blocked, a paused debugger), the robot went on driving on its last
    command meanwhile and its frames queued up in the port; the next read gets them all at
    once (the runtime counts the stale ones and ticks on the newest). So each read first
    steps the simulator through every 15 ms slot that has passed on the wall clock, then
    waits for the next one; each write too, before the robot gets the bytes. Without that,
    a slow tree would stop the simulated world while it thinks, and a mission that drives
    blind for half a second on a robot would look safe here.

    The slots to catch up are those due when the read starts, so a host slower than real
    time cannot keep one read stepping for ever. ``clock`` and ``sleep`` are the wall
    clock's (tests hand in their own)."""

    wall_clock = True  # paced to it
    read_step = None  # a wait ends at its time on the wall clock

    def __init__(
        self,
        simulator: Simulator,
        name: str = "sim://",
        *,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        super().__init__(simulator, name)
        self._clock = clock
        self._sleep = sleep
        self._wall0 = clock()
        self._sim0 = simulator.time

    def _due(self) -> float:
        """The wall-clock time (``clock``) of the simulator's next 15 ms step."""
        return self._wall0 + (self.simulator.time + STEP_SECONDS - self._sim0)

    def _step(self) -> None:
        self.simulator.step()
        if self.simulator.disconnected:
            raise ConnectionError(
                f"{self.name}: simulated disconnect at t={self.simulator.time:.3f} s"
            )

    def _catch_up(self) -> float:
        """Step through the slots that passed on the wall clock; the wall time now."""
        now = self._clock()
        while self._due() <= now:
            self._step()
        return now

    def write(self, data: bytes) -> None:
        """The bytes reach the robot at the wall time they are written: a command written
        after a long tick (or by the tick guard during one) acts from now, not from where
        the simulator's clock was left."""
        self._check()
        self._catch_up()
        super().write(data)

    def read(self, timeout: float) -> bytes:
        self._check()
        sim = self.simulator
        started = self._catch_up()  # the slots that passed while the host was busy
        data = sim.read()
        deadline = started + max(timeout, 0.0)
        while not data:
            due = self._due()
            now = self._clock()
            if due > deadline:
                if deadline > now:
                    self._sleep(deadline - now)
                return b""
            if due > now:
                self._sleep(due - now)
            self._step()
            data = sim.read()
        return data if self.baud == sim.baud else at_wrong_baud(data)
