"""The simulator on a wall clock, behind a pseudo-terminal, a TCP socket or an RFC 2217 port.

Any OI client can connect: a serial driver opens the pty's slave device as if it were
``/dev/ttyUSB0``; a Wi-Fi-bridge client connects to the socket (pyserial:
``serial.serial_for_url("socket://127.0.0.1:PORT")``); a client that needs the modem lines
opens ``rfc2217://127.0.0.1:PORT`` (a Telnet COM-port server, RFC 2217). The loop steps the
simulator every 15 ms of real time, feeds it every byte as soon as it arrives (so replies to
Sensors and Query List go out at once, not at the next step) and writes what it sends back.

Real serial ports lose what nobody reads; so does this: if the client does not read and the
kernel buffer is full, robot bytes are dropped rather than blocking the clock.

**The line's baud rate.** A real line at two different rates carries garbage. Each endpoint
says the rate its client set, where it can know it (:meth:`Endpoint.line_baud`):

* the pty: the speed the client put in the terminal's settings (``tcsetattr``: pyserial's
  ``baudrate``), read from the pty's own side with ``tcgetattr``, since a pseudo-terminal
  keeps the speed but does not use it;
* RFC 2217: the rate the client's SET-BAUDRATE asked for;
* a raw TCP socket carries no rate: no mismatch is modelled.

When the client's rate is not the robot's (``Simulator.baud``: ``sim --baud``, or after Baud
129), the robot gets none of the client's bytes (framing errors) and the client reads the
robot's bytes scrambled (:func:`~roomba_bt.sim.link.at_wrong_baud`), as
:class:`~roomba_bt.sim.link.SimLink` does in-process.

**The modem lines.** The USB cables wire the robot's BRC pin to RTS or DTR (asserted = BRC
low). The RFC 2217 endpoint carries them: pyserial's own server side,
:class:`serial.rfc2217.PortManager`, reads the client's SET-CONTROL commands into a
:class:`VirtualLine`, and the loop hands RTS-or-DTR to ``Simulator.set_brc``
(:meth:`Endpoint.wake_line`). A pty has no modem lines to set (pyserial's ``rts`` raises
"Inappropriate ioctl for device" on it), but POSIX ties them to the speed: B0 (a hang-up)
drops DTR and RTS and a real speed asserts them, so the pty endpoint reads speed 0 as BRC high
and the return to a rate as BRC low, the falling edge that wakes the robot (the client's
fallback pulse, ``SerialTransport.hung_up``). A raw socket carries no lines.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import select
import socket
import termios
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from serial.rfc2217 import PortManager

from roomba_bt.oi.encode import BAUD_RATES
from roomba_bt.sim.link import at_wrong_baud
from roomba_bt.sim.narrate import Narrator
from roomba_bt.sim.robot import STEP_SECONDS, Simulator

log = logging.getLogger(__name__)

#: If the host falls this far behind the 15 ms cadence (a suspended process), resynchronise
#: instead of bursting the missed steps.
MAX_LAG_SECONDS = 0.5


#: termios speed constants -> bits per second, for the rates the OI knows
_TERMIOS_SPEEDS = {
    getattr(termios, f"B{rate}"): rate
    for rate in BAUD_RATES.values()
    if hasattr(termios, f"B{rate}")
}


class Endpoint(Protocol):
    address: str

    def line_baud(self) -> int | None:
        """The rate the client set on its side of the line; None if this endpoint cannot
        know it (then no mismatch is modelled)."""
        ...

    def wake_line(self) -> bool | None:
        """Whether the client holds BRC low (RTS or DTR asserted); None: no modem lines."""
        ...

    def wait_read(self, timeout: float) -> bytes: ...

    def send(self, data: bytes) -> None: ...

    def hang_up(self) -> None: ...

    def close(self) -> None: ...


class PtyEndpoint:
    """A pseudo-terminal pair: the client opens :attr:`address` (the slave device)."""

    def __init__(self) -> None:
        self._master, self._slave = os.openpty()
        try:
            # Raw mode: no echo, no line editing, no CR/LF translation; bytes stay bytes.
            tty.setraw(self._slave)
            os.set_blocking(self._master, False)
            self.address = os.ttyname(self._slave)
        except BaseException:  # both ends closed: nobody else has them (they were left open)
            os.close(self._master)
            os.close(self._slave)
            raise
        self._hung_up = False

    def _speed(self) -> int | None:
        """The output speed in the terminal's settings (a termios ``B`` constant), which the
        client's ``tcsetattr`` set (one settings block for both sides of a pty)."""
        try:
            speed: int = termios.tcgetattr(self._slave)[5]
        except termios.error:
            return None
        return speed

    def line_baud(self) -> int | None:
        """The client's rate; a rate the OI does not know (B0 included) is 0: no OI rate
        matches it."""
        speed = self._speed()
        return None if speed is None else _TERMIOS_SPEEDS.get(speed, 0)

    def wake_line(self) -> bool | None:
        """DTR and RTS as POSIX sets them from the speed: a pty has no lines of its own, but
        speed 0 (B0, a hang-up) drops them and a real speed asserts them (Linux raises both
        when a port opens and when it leaves B0). Asserted = BRC low, so a hang-up is BRC
        high and the return to a rate is BRC's falling edge: the wake."""
        speed = self._speed()
        return None if speed is None else speed != termios.B0

    def wait_read(self, timeout: float) -> bytes:
        if self._hung_up:
            time.sleep(timeout)
            return b""
        ready, _, _ = select.select([self._master], [], [], timeout)
        if not ready:
            return b""
        try:
            return os.read(self._master, 4096)
        except BlockingIOError:
            return b""
        except OSError as exc:  # EIO: no client has the slave open right now
            if exc.errno == errno.EIO:
                time.sleep(timeout)
                return b""
            raise

    def send(self, data: bytes) -> None:
        if self._hung_up:
            return
        with contextlib.suppress(BlockingIOError, OSError):
            os.write(self._master, data)

    def hang_up(self) -> None:
        """The simulated disconnect: close the master, the client sees the line drop."""
        if not self._hung_up:
            self._hung_up = True
            os.close(self._master)

    def close(self) -> None:
        self.hang_up()
        with contextlib.suppress(OSError):
            os.close(self._slave)


class TcpEndpoint:
    """A TCP server for one client at a time (a serial line has one far end)."""

    def __init__(self, host: str, port: int) -> None:
        self._listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            self._listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self._listener.bind((host, port))
            self._listener.listen(1)
            self._listener.setblocking(False)
        except BaseException:  # a port in use, a host not of this machine: nothing served
            self._listener.close()
            raise
        bound_host, bound_port = self._listener.getsockname()[:2]
        self.address = f"socket://{bound_host}:{bound_port}"
        self._client: socket.socket | None = None
        self._hung_up = False

    def line_baud(self) -> int | None:
        return None  # a raw socket carries bytes, not a rate

    def wake_line(self) -> bool | None:
        return None

    def _accepted(self, client: socket.socket) -> None:
        """A client connected (subclasses start their protocol here)."""

    def _incoming(self, data: bytes) -> bytes:
        """The robot's share of what the client sent."""
        return data

    def _outgoing(self, data: bytes) -> bytes:
        return data

    def wait_read(self, timeout: float) -> bytes:
        if self._hung_up:
            time.sleep(timeout)
            return b""
        watch: list[socket.socket] = [self._listener]
        if self._client is not None:
            watch.append(self._client)
        ready, _, _ = select.select(watch, [], [], timeout)
        data = b""
        for sock in ready:
            if sock is self._listener:
                with contextlib.suppress(BlockingIOError):
                    client, peer = self._listener.accept()
                    if self._client is not None:
                        self._turn_away(client, peer)
                    else:
                        client.setblocking(False)
                        client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                        self._client = client
                        self._accepted(client)
            elif self._client is not None:
                try:
                    data = self._client.recv(4096)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    data = b""
                if not data:
                    self._drop_client()
                else:
                    data = self._incoming(data)
        return data

    def _turn_away(self, client: socket.socket, peer: Any) -> None:
        """A second client, while one is connected: closed at once (a serial line has one
        far end, and two clients would each read half the stream and mix their commands),
        and said here. Its own side can only see the close (a raw socket has no channel for
        a reason beside the robot's bytes): roomba-bt says "the far end closed the
        connection at once: another client may hold it". Before, the simulator said
        nothing, and the second run took the robot for dead."""
        where = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        log.warning(
            "%s: turned a second client away (%s): one client at a time, as on a serial "
            "line, and the first is still connected", self.address, where,
        )  # fmt: skip
        client.close()

    def _drop_client(self) -> None:
        if self._client is not None:
            with contextlib.suppress(OSError):
                self._client.close()
            self._client = None

    def send(self, data: bytes) -> None:
        if self._client is None or self._hung_up:
            return
        self._send_raw(self._outgoing(data))

    def _send_raw(self, data: bytes) -> None:
        if self._client is None:
            return
        try:
            self._client.send(data)
        except (BlockingIOError, InterruptedError):
            pass
        except OSError:
            self._drop_client()

    def hang_up(self) -> None:
        self._hung_up = True
        self._drop_client()
        with contextlib.suppress(OSError):
            self._listener.close()

    def close(self) -> None:
        self.hang_up()


@dataclass
class VirtualLine:
    """The serial port :class:`serial.rfc2217.PortManager` configures: it keeps what the
    client set (rate, framing, RTS, DTR) instead of driving hardware."""

    baudrate: int
    bytesize: int = 8
    parity: str = "N"
    stopbits: int = 1
    xonxoff: bool = False
    rtscts: bool = False
    break_condition: bool = False
    rts: bool = False
    dtr: bool = False
    # the lines a robot would drive back: the cable has none of them wired
    cts: bool = False
    dsr: bool = False
    ri: bool = False
    cd: bool = False

    def reset_input_buffer(self) -> None:
        """Nothing is buffered on this side."""

    def reset_output_buffer(self) -> None:
        """Nothing is buffered on this side."""


class Rfc2217Endpoint(TcpEndpoint):
    """A TCP server speaking RFC 2217 (Telnet COM-port control): the client opens
    ``rfc2217://HOST:PORT`` and its baud rate and modem lines reach the simulator."""

    def __init__(self, host: str, port: int, baud: int) -> None:
        super().__init__(host, port)
        self.address = self.address.replace("socket://", "rfc2217://", 1)
        self._initial_baud = baud
        self.line = VirtualLine(baud)
        self._manager: PortManager | None = None

    def line_baud(self) -> int | None:
        return int(self.line.baudrate) if self._manager is not None else None

    def wake_line(self) -> bool | None:
        return bool(self.line.rts or self.line.dtr)

    def _accepted(self, client: socket.socket) -> None:
        self.line = VirtualLine(self._initial_baud)
        # PortManager duck-types both: it sets attributes on the port and writes to the other
        line: Any = self.line
        writer: Any = _Writer(self)
        self._manager = PortManager(line, writer)

    def _incoming(self, data: bytes) -> bytes:
        if self._manager is None:
            return data
        return b"".join(self._manager.filter(data))

    def _outgoing(self, data: bytes) -> bytes:
        if self._manager is None:
            return data
        return b"".join(self._manager.escape(data))

    def _drop_client(self) -> None:
        super()._drop_client()
        # a closed port lets its lines go: BRC high
        self._manager = None
        self.line.rts = self.line.dtr = False


class _Writer:
    """What PortManager writes its Telnet answers to: the client's socket, unescaped."""

    def __init__(self, endpoint: Rfc2217Endpoint) -> None:
        self._endpoint = endpoint

    def write(self, data: bytes) -> None:
        self._endpoint._send_raw(bytes(data))


def serve(
    simulator: Simulator,
    endpoint: Endpoint,
    should_stop: Callable[[], bool],
    clock: Callable[[], float] = time.monotonic,
    narrator: Narrator | None = None,
) -> None:
    """Run ``simulator`` in real time on ``endpoint`` until ``should_stop()`` is true; a
    ``narrator`` (``sim --log``) is told after each read and each round of steps."""
    next_step = clock() + STEP_SECONDS
    # The line as the robot finds it when it comes up is no edge (a pty's lines read as
    # asserted from the start: BRC low, not a pulse).
    simulator.brc_low = bool(endpoint.wake_line())
    while not should_stop():
        data = endpoint.wait_read(max(0.0, next_step - clock()))
        wake = endpoint.wake_line()
        if wake is not None and wake != simulator.brc_low:
            simulator.set_brc(wake)
        if data:
            if _same_rate(endpoint, simulator):
                simulator.receive(data)
            else:
                simulator.ignored_bytes += len(data)  # framing errors: nothing gets through
        now = clock()
        if now - next_step > MAX_LAG_SECONDS:
            next_step = now
        while now >= next_step:
            simulator.step()
            next_step += STEP_SECONDS
        out = simulator.read()
        if out:
            endpoint.send(out if _same_rate(endpoint, simulator) else at_wrong_baud(out))
        if narrator is not None:
            narrator.catch_up()
        if simulator.disconnected:
            endpoint.hang_up()


def _same_rate(endpoint: Endpoint, simulator: Simulator) -> bool:
    rate = endpoint.line_baud()
    return rate is None or rate == simulator.baud
