"""A Wi-Fi bridge that resets, for the tests: a TCP proxy in front of ``roomba-bt sim --tcp``
that passes bytes both ways until :meth:`ResettingBridge.reset`, which resets both of its
connections (RST, as an ESP8266 that reboots leaves them) and turns new clients away for a
while (each one taken and reset at once, as the bridge's listener does while it reboots).
After that, a new client is joined to a new connection to the simulator: the same robot.
:meth:`ResettingBridge.go_silent` is the other way a bridge goes: its client's connection
left open and never read nor written again (a half-open connection: the bridge rebooted or
left Wi-Fi range, and no reset reached the client), the next client served.
"""

from __future__ import annotations

import contextlib
import select
import socket
import struct
import threading
import time

from waits import accepted, joined, received  # tests/waits.py: a hang's bound

#: how long the proxy's loop waits for a socket to be ready before it looks at its state
_POLL_S = 0.01


def _reset(sock: socket.socket) -> None:
    """Close ``sock`` with a TCP reset (SO_LINGER of 0), not a graceful FIN."""
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    sock.close()


class ResettingBridge:
    """A proxy to ``upstream`` (``socket://HOST:PORT``) on a free local port, :attr:`url`;
    :attr:`clients` counts the clients it joined to the simulator."""

    def __init__(self, upstream: str) -> None:
        host, port = upstream.removeprefix("socket://").rsplit(":", 1)
        self._upstream = (host, int(port))
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self._listener.getsockname()[1]}"
        self.clients = 0
        self._pair: tuple[socket.socket, socket.socket] | None = None
        #: the clients' connections left open and silent (:meth:`go_silent`)
        self._silent: list[socket.socket] = []
        self._down_until = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def reset(self, down_s: float) -> None:
        """The bridge reboots: both connections reset, new clients turned away for ``down_s``."""
        with self._lock:
            self._down_until = time.monotonic() + down_s
            self._drop()

    def go_silent(self) -> None:
        """The bridge goes silent without closing: nothing passes either way on its client's
        connection, which stays open; its connection to the robot is gone (the robot's side
        of a bridge that rebooted), and the next client is served."""
        with self._lock:
            assert self._pair is not None
            client, robot = self._pair
            robot.close()
            self._silent.append(client)
            self._pair = None

    def close(self) -> None:
        self._stop.set()
        joined(self._thread, "the bridge's accepting thread, told to stop")
        with self._lock:
            self._drop()
            for sock in self._silent:
                sock.close()
        self._listener.close()

    def _drop(self) -> None:
        if self._pair is not None:
            for sock in self._pair:
                _reset(sock)
            self._pair = None

    def _serve(self) -> None:
        while not self._stop.is_set():
            with self._lock:
                pair = self._pair
            watched = [self._listener, *(pair or ())]
            try:
                ready, _, _ = select.select(watched, [], [], _POLL_S)
            except (OSError, ValueError):  # a pair reset meanwhile (closed: fd -1)
                continue
            with self._lock:
                for sock in ready:
                    if sock is self._listener:
                        self._accept()
                    elif self._pair is not None and sock in self._pair:
                        self._pass_on(sock)

    def _accept(self) -> None:
        client = accepted(self._listener, "the client select() said was waiting")
        if self._pair is not None or time.monotonic() < self._down_until:
            _reset(client)
            return
        robot = socket.create_connection(self._upstream)
        for sock in (client, robot):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._pair = (client, robot)
        self.clients += 1

    def _pass_on(self, source: socket.socket) -> None:
        """What ``source`` has, to the other side; a side that closed closes both."""
        assert self._pair is not None
        client, robot = self._pair
        target = robot if source is client else client
        try:
            data = received(source, 4096, "the bytes select() said were waiting")
            if data:
                target.sendall(data)
                return
        except OSError:
            pass
        self._drop()
