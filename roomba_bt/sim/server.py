"""The simulator on a wall clock, behind a pseudo-terminal or a TCP socket.

Any OI client can connect: a serial driver opens the pty's slave device as if it were
``/dev/ttyUSB0``; a Wi-Fi-bridge client connects to the socket (pyserial:
``serial.serial_for_url("socket://127.0.0.1:PORT")``). The loop steps the simulator every
15 ms of real time, feeds it every byte as soon as it arrives (so replies to Sensors and Query
List go out at once, not at the next step) and writes what it sends back.

Real serial ports lose what nobody reads; so does this: if the client does not read and the
kernel buffer is full, robot bytes are dropped rather than blocking the clock.
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket
import time
import tty
from collections.abc import Callable
from typing import Protocol

from roomba_bt.sim.robot import STEP_SECONDS, Simulator

#: If the host falls this far behind the 15 ms cadence (a suspended process), resynchronise
#: instead of bursting the missed steps.
MAX_LAG_SECONDS = 0.5


class Endpoint(Protocol):
    address: str

    def wait_read(self, timeout: float) -> bytes: ...

    def send(self, data: bytes) -> None: ...

    def hang_up(self) -> None: ...

    def close(self) -> None: ...


class PtyEndpoint:
    """A pseudo-terminal pair: the client opens :attr:`address` (the slave device)."""

    def __init__(self) -> None:
        self._master, self._slave = os.openpty()
        # Raw mode: no echo, no line editing, no CR/LF translation; bytes stay bytes.
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.address = os.ttyname(self._slave)
        self._hung_up = False

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
        self._listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listener.bind((host, port))
        self._listener.listen(1)
        self._listener.setblocking(False)
        bound_host, bound_port = self._listener.getsockname()[:2]
        self.address = f"socket://{bound_host}:{bound_port}"
        self._client: socket.socket | None = None
        self._hung_up = False

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
                    client, _ = self._listener.accept()
                    if self._client is not None:
                        client.close()  # busy: one far end only
                    else:
                        client.setblocking(False)
                        client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                        self._client = client
            elif self._client is not None:
                try:
                    data = self._client.recv(4096)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    data = b""
                if not data:
                    self._drop_client()
        return data

    def _drop_client(self) -> None:
        if self._client is not None:
            with contextlib.suppress(OSError):
                self._client.close()
            self._client = None

    def send(self, data: bytes) -> None:
        if self._client is None or self._hung_up:
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


def serve(
    simulator: Simulator,
    endpoint: Endpoint,
    should_stop: Callable[[], bool],
    clock: Callable[[], float] = time.monotonic,
) -> None:
    """Run ``simulator`` in real time on ``endpoint`` until ``should_stop()`` is true."""
    next_step = clock() + STEP_SECONDS
    while not should_stop():
        data = endpoint.wait_read(max(0.0, next_step - clock()))
        if data:
            simulator.receive(data)
        now = clock()
        if now - next_step > MAX_LAG_SECONDS:
            next_step = now
        while now >= next_step:
            simulator.step()
            next_step += STEP_SECONDS
        out = simulator.read()
        if out:
            endpoint.send(out)
        if simulator.disconnected:
            endpoint.hang_up()
