"""The modem lines of an ``rfc2217://`` port: set without waiting for the server's answer.

pyserial's ``port.rts = ...`` on RFC 2217 waits for the server's acknowledgement, polling
every 50 ms: a keep-awake pulse (RTS and DTR) held the tick thread 100-107 ms, past the
100 ms watchdog, once a minute. :meth:`SerialTransport.set_wake_line` sends the same request
and returns; the simulator's server still sees BRC go low and high (a pulse)."""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Iterator

import pytest
from serial import rfc2217, serialutil
from sim.served import Served  # tests/sim: the simulator served in a thread
from waits import accepted, joined, received, until  # tests/waits.py: a hang's bound

from roomba_bt.sim.server import Rfc2217Endpoint
from roomba_bt.transport import SerialTransport, TransportError

pytestmark = pytest.mark.filterwarnings(
    "ignore:set(Daemon|Name)\\(\\) is deprecated:DeprecationWarning"
)


@pytest.fixture
def served() -> Iterator[Served]:
    one = Served(Rfc2217Endpoint("127.0.0.1", 0, 115200))
    yield one
    one.close()


def test_set_wake_line_does_not_wait_for_the_servers_answer(
    served: Served, monkeypatch: pytest.MonkeyPatch
) -> None:
    simulator, endpoint = served.simulator, served.endpoint
    transport = SerialTransport.open(endpoint.address, brc_high=True)
    try:
        waited: list[str] = []
        real_wait = rfc2217.TelnetSubnegotiation.wait

        def wait(self: rfc2217.TelnetSubnegotiation, timeout: float = 3) -> None:
            waited.append(self.name)
            real_wait(self, timeout)

        monkeypatch.setattr(rfc2217.TelnetSubnegotiation, "wait", wait)
        transport.set_wake_line(True)
        assert waited == [], "the tick thread waited for the server's acknowledgement"
        until(lambda: endpoint.wake_line() is True, "BRC going low")
        transport.set_wake_line(False)
        assert waited == []
        until(lambda: endpoint.wake_line() is False, "BRC going high")
        until(lambda: simulator.brc_pulses == 1, "the robot's seeing one BRC pulse")
        transport.write(b"\x80")  # the port still carries bytes after the lines
        until(lambda: simulator.mode.name == "PASSIVE", "Passive, after Start")
    finally:
        transport.close()


def test_a_read_takes_everything_queued_not_one_byte(
    served: Served,
) -> None:
    """pyserial's RFC 2217 read at timeout 0 gives one byte: a tick that came past the
    watchdog's deadline read one byte of a queued frame and tripped the watchdog, the rest
    counted as garbage (a false baud change followed from it)."""
    endpoint = served.endpoint
    transport = SerialTransport.open(endpoint.address)
    try:
        transport.write(bytes([128, 148, 1, 7]))  # Start, stream packet 7 (5-byte frames)
        port = transport.port
        until(lambda: port.in_waiting >= 20, "the stream's first 20 bytes")
        queued = port.in_waiting
        assert len(transport.read(0.0)) >= queued
        transport.write(bytes([150, 0]))
    finally:
        transport.close()


def test_a_server_gone_is_a_transport_error_not_silence(
    served: Served,
) -> None:
    endpoint = served.endpoint
    transport = SerialTransport.open(endpoint.address)
    try:
        served.close()
        with pytest.raises(TransportError):
            for _ in range(500):
                transport.read(0.01)
    finally:
        transport.close()


class _SwallowingProxy:
    """A bridge between the client and the simulator's RFC 2217 server: its first
    connection carried both ways; every later one reaches the server but swallows what the
    client sends (a bridge back from a reboot whose serial server does not answer the
    options yet), so no Telnet option is ever agreed."""

    def __init__(self, upstream: tuple[str, int]) -> None:
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"rfc2217://127.0.0.1:{self.listener.getsockname()[1]}"
        self._upstream = upstream
        self.clients: list[socket.socket] = []
        self._sockets: list[socket.socket] = [self.listener]
        self._threads = [threading.Thread(target=self._accept, daemon=True)]
        self._threads[0].start()

    def _accept(self) -> None:
        with contextlib.suppress(OSError):
            while True:
                client = accepted(self.listener, "the next client of the bridge")
                server = socket.create_connection(self._upstream)
                self._sockets += [client, server]
                swallowed = bool(self.clients)
                self.clients.append(client)
                pipes = [(server, client), (client, None if swallowed else server)]
                for ends in pipes:
                    self._threads.append(
                        threading.Thread(target=self._pipe, args=ends, daemon=True)
                    )
                    self._threads[-1].start()

    @staticmethod
    def _pipe(source: socket.socket, sink: socket.socket | None) -> None:
        with contextlib.suppress(OSError):
            while data := received(source, 4096, "the bridge's next bytes"):
                if sink is not None:
                    sink.sendall(data)

    def drop_first(self) -> None:
        """The bridge's first connection reset (it rebooted)."""
        self.clients[0].shutdown(socket.SHUT_RDWR)

    def close(self) -> None:
        """Its sockets shut, which ends the accept and the reads its threads wait in (a
        close alone leaves them waiting, each thread left running), then closed."""
        self.listener.shutdown(socket.SHUT_RDWR)
        joined(self._threads[0], "the bridge's accept")  # no connection comes after it
        for sock in self._sockets[1:]:
            with contextlib.suppress(OSError):  # one the far end closed first
                sock.shutdown(socket.SHUT_RDWR)
        for thread in self._threads[1:]:
            joined(thread, "a bridge's pipe")
        for sock in self._sockets:
            sock.close()


def test_a_reconnection_s_rfc2217_negotiation_waits_no_longer_than_asked(
    served: Served, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A bridge that connects and does not answer the options held a reconnection
    pyserial's own 3 s a step of the negotiation (its network timeout), past the grace the
    stop waits: each wait now ends by what is left of it."""
    host, port = served.endpoint.address.split("://")[1].split(":")
    proxy = _SwallowingProxy((host, int(port)))
    transport = SerialTransport.open(proxy.url)
    waits: list[float | None] = []
    real_init = serialutil.Timeout.__init__

    def spied(self: serialutil.Timeout, duration: float | None) -> None:
        if threading.current_thread() is threading.main_thread():
            waits.append(duration)
        real_init(self, duration)

    try:
        proxy.drop_first()
        monkeypatch.setattr(serialutil.Timeout, "__init__", spied)
        assert transport.reopen(within=0.5) is None
        monkeypatch.undo()
        assert len(proxy.clients) >= 2, "no reconnection reached the bridge"
        assert waits and all(wait is not None and wait <= 0.5 for wait in waits), waits
        assert rfc2217.Timeout is serialutil.Timeout  # as it was, for other opens
    finally:
        transport.close()
        proxy.close()
