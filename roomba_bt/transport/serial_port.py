"""A :class:`~roomba_bt.transport.base.Transport` over any pyserial URL.

``serial.serial_for_url`` gives one object for every kind of port, so one class covers them:

    /dev/ttyUSB0, COM3          a USB serial cable (device path)
    socket://host:port          a raw TCP bridge (Wi-Fi serial adapters, ``roomba-bt sim``)
    rfc2217://host:port         a Telnet COM-port server (baud rate changes reach the far end)
    loop://                     a loopback: what is written is read back (tests, benchmarks)

Reads never block longer than asked: the port's own timeout stays 0 (take what is there) and
waiting for the first byte is a ``select`` on the port's descriptor where it has one, or a
read of one byte with the caller's timeout where it does not (``loop://``). Writes are bounded
by ``write_timeout`` so that a stop sent to a port whose far end stopped reading fails instead
of hanging.
"""

from __future__ import annotations

import contextlib
import logging
import os
import select
import socket
import threading
import time
import weakref
from collections.abc import Iterator
from typing import Any, cast

import serial
from serial import rfc2217, serialutil
from serial.urlhandler import protocol_socket

from roomba_bt.transport.base import TransportError
from roomba_bt.transport.device_identity import another_device, device_identity
from roomba_bt.transport.link_kind import LinkKind, link_of
from roomba_bt.transport.open_failure import (
    CLOSED_AT_ONCE,
    CLOSED_ERRORS,
    IN_USE,
    IN_USE_EXCLUSIVE,
    IN_USE_HERE,
    PORT_ALLOWED,
    SOCKET_CLOSED_TEXT,
    error_number,
    open_failure,
    url_problem,
)

log = logging.getLogger(__name__)

#: pyserial's words (serialposix) for a read the port said was ready that returned nothing:
#: Linux shows a device unplugged (a USB adapter pulled, a pty whose other end closed) so
#: "device reports readiness to read but returned no data (device disconnected or multiple
#: access on port?)", which a run's outcome carried raw after "the port is gone"
NO_DATA_TEXT = "device reports readiness to read but returned no data"
#: the same in our words, the port's kind left to the reason around it (``the port is gone
#: (the cable was pulled or the adapter reset)``; a pty's: the program at its other end
#: ended): pyserial's add nothing to them, its two guesses being these
NO_DATA_SAID = (
    "it said bytes were waiting and gave none: its other end gone, or another program "
    "reading the same port"
)

#: Bytes taken from the port in one read; a 115200 baud link carries 172 bytes per 15 ms.
READ_CHUNK = 4096
#: A read this large is taken for a backlog and the port is drained
#: (``SerialTransport._drained``): a tty gives at most 4 KiB a read (its line discipline's
#: buffer) however much more waits behind it; a stream at 115200 baud brings 2 KiB in 0.18 s
BACKLOG_SIGN = READ_CHUNK // 2
#: The most one read takes when the port holds a backlog: more than a pty or a USB serial
#: driver holds (64 KiB)
MAX_BACKLOG = 1 << 18
DEFAULT_BAUD = 115200
#: A stop sequence is 12 bytes; anything slower than this means the far end is gone.
DEFAULT_WRITE_TIMEOUT = 0.5
#: pyserial's RFC 2217 handler refuses to open with a write timeout ("not supported"): its
#: writes go to a TCP socket with the kernel's buffer, so they are opened without one.
NO_WRITE_TIMEOUT_SCHEMES = ("rfc2217://",)
#: How often a polled port (RFC 2217) is looked at while a read waits.
POLL_INTERVAL = 0.001
#: A polled port's own read timeout: it reads only what is already queued, so it never waits
#: this long (a read at timeout 0 would end after one byte: ``SerialTransport._queued``).
QUEUED_READ_TIMEOUT = 1.0
#: How often a device that vanished is tried again while the safe stop waits for it to come
#: back (``SerialTransport.reopen``): opening a path that is not there costs nothing.
REOPEN_EVERY_S = 0.05
#: A bridge's connection is tried again after this long at first, then twice as long each
#: time up to :data:`RECONNECT_MOST_S`: a bridge that reboots refuses at once, and an
#: ESP8266 serves few sockets; a connection tried every 50 ms for seconds only loads it.
RECONNECT_FIRST_S = 0.1
RECONNECT_MOST_S = 1.0
#: How long a new raw TCP connection is watched for its far end closing it at once (a bridge
#: still rebooting whose listener takes the connection and resets it, a server that has
#: another client): a robot's stream would come within a slot; a close comes at once.
RECONNECT_SETTLE_S = 0.05
#: The least time one try of a bridge's reconnection waits for its TCP connect, however
#: little of the wait is left: a loaded machine's connect to a bridge that answers takes
#: some milliseconds, and a try with no time to connect would only fail.
CONNECT_LEAST_S = 0.2


try:  # a pty whose other side closed while it was being set up: termios.error, no OSError
    import fcntl
    import termios

    TERMIOS_ERRORS: tuple[type[Exception], ...] = (termios.error,)
except ImportError:  # not POSIX
    TERMIOS_ERRORS = ()
#: whether a device can be put in the kernel's exclusive mode (:class:`KernelExclusiveSerial`)
_POSIX = os.name == "posix"
_OPEN_ERRORS: tuple[type[Exception], ...] = (
    serial.SerialException, OSError, ValueError, *TERMIOS_ERRORS
)  # fmt: skip
#: The ports this process opened and has not yet let go of: a device it holds already is
#: refused by its own lock, said as its own (an earlier connection), not another program's.
_OPENED: weakref.WeakSet[SerialTransport] = weakref.WeakSet()


class KernelExclusiveSerial(serial.Serial):
    """A device port in the kernel's exclusive mode while it is open (POSIX ``TIOCEXCL``):
    any other open of the terminal by a user without ``CAP_SYS_ADMIN`` fails with EBUSY.

    pyserial's ``exclusive`` is an advisory ``flock``, which only programs that ask for the
    same lock heed: a student's ``serial.Serial(port)`` beside a run opened the robot's port
    and drove it backwards for 7.7 s, the run none the wiser. The mode is cleared before
    every close (``TIOCNXCL``), however the port is closed (pyserial's own ``__del__``
    too): a pty's mode outlives its opener while its other side is open (a simulator), and
    the next run on it was refused. A run killed outright cannot clear it: on a simulator's
    pty the next open by a user without ``CAP_SYS_ADMIN`` fails until the simulator is
    restarted (a real device forgets it when its last opener closes)."""

    def open(self) -> None:
        super().open()
        try:
            fcntl.ioctl(self.fileno(), termios.TIOCEXCL)
        except OSError as exc:  # a terminal that refuses: the advisory lock still holds
            log.warning(
                "%s: could not set the exclusive mode (%s): other programs can open it "
                "beside this one", self.port, exc.strerror or exc,
            )  # fmt: skip

    def close(self) -> None:
        if self.is_open and self.fd is not None:
            with contextlib.suppress(OSError):
                fcntl.ioctl(self.fd, termios.TIOCNXCL)
        super().close()


class _Rfc2217Port(rfc2217.Serial):
    """pyserial's RFC 2217 port, whose close closes its socket. pyserial's close skips
    ``socket.close()`` when ``shutdown()`` fails (the server closed the connection first)
    and forgets the socket, and its open calls that close when the negotiation fails: a
    server that closes each connection at once (one serving another client, a bridge
    rebooting) left the socket of every refused open, and of every try of a reconnection, to
    the garbage collector (a ``ResourceWarning``), out of :func:`_close_port`'s reach."""

    def close(self) -> None:
        sock = getattr(self, "_socket", None)  # pyserial's own, not in its stubs
        super().close()
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()


def _device_port(url: str, baud: int, write_timeout: float | None) -> serial.Serial:
    """A closed port for ``url``: a device path in the kernel's exclusive mode where the
    OS has one (:class:`KernelExclusiveSerial`), an RFC 2217 URL as :class:`_Rfc2217Port`,
    anything else as pyserial makes it."""
    settings: dict[str, Any] = {"baudrate": baud, "timeout": 0, "write_timeout": write_timeout}
    if url.lower().startswith("rfc2217://"):  # what serial_for_url makes, its close mended
        rfc_port = _Rfc2217Port(None, **settings)
        rfc_port.port = url
        return cast(serial.Serial, rfc_port)  # as serial_for_url's stubs type every port
    if "://" in url or not _POSIX:  # a URL (socket://, loop://), or Windows
        return serial.serial_for_url(url, do_not_open=True, **settings)
    port = KernelExclusiveSerial(None, **settings)
    port.port = url
    return port


def _port_text(url: object) -> str:
    """``url`` as the text of a port: a str, or a path object (``pathlib.Path``)."""
    if isinstance(url, os.PathLike):
        url = os.fspath(url)
    if not isinstance(url, str):
        raise TypeError(f"the port must be {PORT_ALLOWED}, as a str; got {url!r}")
    return url


def _held_here(url: str) -> bool:
    """Whether this process has the device ``url`` open already (:data:`_OPENED`, a link by
    another of its names too: /dev/serial/by-id/...), its lock what refused ``url``."""
    try:
        wanted = os.path.realpath(url)
        return any(t.is_open and os.path.realpath(t.name) == wanted for t in list(_OPENED))
    except (OSError, ValueError):
        return False


def _close_port(port: serial.SerialBase) -> None:
    """Close ``port``, whatever state it is in. pyserial's ``socket://`` close skips
    ``socket.close()`` when ``shutdown()`` fails (the peer already hung up), which leaks the
    socket: it is closed here too."""
    sock = getattr(port, "_socket", None)
    with contextlib.suppress(serial.SerialException, OSError):
        port.close()
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.close()


def _open_port(port: serial.Serial) -> None:
    """Open ``port``, closed again if its open fails part way: pyserial's ``socket://`` open
    connects, then reads what the far end had sent (``reset_input_buffer``), which raises
    when a bridge resets the new connection at once; the port, left open with its socket,
    was dropped, and its ``__del__`` leaked the socket (the close :func:`_close_port`
    mends)."""
    try:
        port.open()
    except BaseException:
        _close_port(port)
        raise


def _closed_at_once(port: serial.SerialBase) -> bool:
    """Whether the far end of a new raw TCP connection (``socket://``) closes it within
    :data:`RECONNECT_SETTLE_S`: looked at with ``MSG_PEEK``, so a byte of the robot's stream
    stays for the reads that follow. Other ports: False (an RFC 2217 port's open fails by
    itself when its server does not negotiate)."""
    sock = getattr(port, "_socket", None)
    if sock is None or isinstance(port, rfc2217.Serial):
        return False
    ready, _, _ = select.select([sock], [], [], RECONNECT_SETTLE_S)
    if not ready:
        return False
    try:
        return not sock.recv(1, socket.MSG_PEEK)
    except BlockingIOError:
        return False
    except OSError:  # reset
        return True


class _ConnectWithin:
    """The ``socket`` module as pyserial's ``socket://`` and ``rfc2217://`` handlers see it
    while a reconnection tries: their TCP connect waits at most ``seconds``, not their own 5 s
    (``create_connection(..., timeout=5)``, fixed in both, with no setting of their own);
    every other name is the module's."""

    def __init__(self, seconds: float) -> None:
        self._seconds = seconds

    def create_connection(
        self, address: tuple[str, int], timeout: float | None = None, *args: Any, **kwargs: Any
    ) -> socket.socket:
        bound = self._seconds if timeout is None else min(timeout, self._seconds)
        return socket.create_connection(address, bound, *args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(socket, name)


class _TimeoutBefore:
    """pyserial's ``Timeout`` as its RFC 2217 handler makes them while a reconnection tries:
    each ends by ``deadline`` (``time.monotonic``) at the latest. The handler's negotiation
    waits its network timeout (3 s, a URL's ``?timeout=``) for each step (the Telnet
    options, the port's settings, flow control, the modem lines), whatever a caller has
    left: a bridge that connects and does not answer the options held the safe stop 3 s
    past the grace."""

    def __init__(self, deadline: float) -> None:
        self._deadline = deadline

    def __call__(self, duration: float | None) -> serialutil.Timeout:
        left = max(self._deadline - time.monotonic(), 0.0)
        return serialutil.Timeout(left if duration is None else min(duration, left))


#: one reconnection's bound on the handlers' open at a time (:func:`_open_within`)
_OPEN_BOUND = threading.Lock()
#: pyserial's network handlers, whose connect :func:`_open_within` bounds
_NETWORK_HANDLERS = (protocol_socket, rfc2217)


@contextlib.contextmanager
def _open_within(seconds: float) -> Iterator[None]:
    """pyserial's network handlers open within ``seconds`` inside the block: their connect
    (:class:`_ConnectWithin`; a bridge that does not answer at all, an ESP8266 still
    rebooting or out of Wi-Fi range, no refusal, the SYN unanswered, held one try of the
    safe stop's reconnection 5 s, past a 2 s grace), and the RFC 2217 handler's
    negotiation after it (:class:`_TimeoutBefore`). The handlers' module names are swapped
    for the block, under a lock; another thread's open meanwhile is bounded too, and
    nothing else changes for it."""
    deadline = time.monotonic() + seconds
    with _OPEN_BOUND:
        for handler in _NETWORK_HANDLERS:
            handler.socket = _ConnectWithin(seconds)  # type: ignore[attr-defined]
        rfc2217.Timeout = _TimeoutBefore(deadline)  # type: ignore[attr-defined]
        try:
            yield
        finally:
            rfc2217.Timeout = serialutil.Timeout  # type: ignore[attr-defined]
            for handler in _NETWORK_HANDLERS:
                handler.socket = socket  # type: ignore[attr-defined]


class SerialTransport:
    """Bytes over a pyserial port, with errors wrapped in :class:`TransportError`."""

    def __init__(self, port: serial.SerialBase, name: str | None = None) -> None:
        self.name: str = name if name is not None else str(port.port)
        self._attach(port)
        #: a raw TCP connection (``socket://``), whose far end may close it on a second client
        self._socket = self.name.lower().startswith("socket://")
        #: why the modem lines reach no robot here (a raw TCP bridge), or None
        words = link_of(self.name)
        self._no_lines = words.no_modem_lines if words.modem_lines is False else None
        #: whether a read has given a byte yet: a connection closed before is a far end that
        #: turned this client away (:data:`~roomba_bt.transport.open_failure.CLOSED_AT_ONCE`)
        self._heard = False
        #: the device the path named when opened (None for a URL): a reopen opens that one
        self._identity = device_identity(self.name)
        #: why the last :meth:`reopen` found the path naming another device, or None
        self.other_device: str | None = None

    def _attach(self, port: serial.SerialBase) -> None:
        """Read and write through ``port`` (an open pyserial port: the first, or the one a
        reopen brought back)."""
        self._port = port
        self._wait_handle: Any = getattr(port, "fd", None) or getattr(port, "_socket", None)
        # pyserial's RFC 2217 port reads its socket in a thread of its own: a select on the
        # socket would race that thread, so its reads poll the port's queue instead.
        self._polled = isinstance(port, rfc2217.Serial)
        # A polled port's read takes one byte and returns when its timeout is 0 (its queue
        # holds single bytes, and a read ends as soon as the timeout has expired): it reads
        # what is queued (``in_waiting``, there at once) with a timeout that never elapses.
        port.timeout = QUEUED_READ_TIMEOUT if self._polled else 0
        self._port_timeout: float = port.timeout
        if self._polled:
            self._wait_handle = None
        self._hung_up = False

    @classmethod
    def open(
        cls,
        url: str,
        baud: int = DEFAULT_BAUD,
        *,
        write_timeout: float = DEFAULT_WRITE_TIMEOUT,
        brc_high: bool = False,
    ) -> SerialTransport:
        """Open ``url`` (device path or pyserial URL) at ``baud``, 8N1, no flow control.

        A device is opened for this process alone: a second roomba-bt on the same robot, a
        ``sensors`` beside a ``run``, would take every other chunk of the stream and
        interleave its commands with the run's; it is refused at once instead,
        :data:`~roomba_bt.transport.open_failure.IN_USE`. Two locks: pyserial's ``exclusive``
        (an advisory ``flock``, which every roomba-bt takes, root's too) and the kernel's
        exclusive mode of the terminal (:class:`KernelExclusiveSerial`, which refuses any
        other program's open, a plain ``serial.Serial(port)`` too, unless it runs as root).

        pyserial asserts RTS and DTR when it opens a port, which on the usual cables pulls
        BRC low (a wake pulse). ``brc_high``: open with both released, so that the robot
        sees no pulse until :meth:`set_wake_line` gives one (``doctor`` says when it wakes
        the robot instead of waking it unknowingly).

        A ``url`` that names no port (not a str, an empty one, a URL pyserial cannot read:
        :func:`~roomba_bt.transport.open_failure.url_problem`) is refused before pyserial
        is asked; its own words were a TypeError or an AttributeError."""
        url = _port_text(url)
        problem = url_problem(url)
        if problem is not None:
            raise TransportError(url, "open the port", problem)
        if url.startswith(NO_WRITE_TIMEOUT_SCHEMES):
            write_timeout = None  # type: ignore[assignment]  # the handler refuses one
        try:
            port = _device_port(url, baud, write_timeout)
            if brc_high:
                port.rts = False
                port.dtr = False
            if isinstance(port, serial.Serial):  # a device, not a socket:// or loop:// URL
                port.exclusive = True
            _open_port(port)
        except _OPEN_ERRORS as exc:
            known = open_failure(url, error_number(exc), str(exc))
            if known in (IN_USE, IN_USE_EXCLUSIVE) and _held_here(url):
                known = IN_USE_HERE
            raise TransportError(url, "open the port", known or exc) from exc
        opened = cls(port, url)
        _OPENED.add(opened)
        return opened

    @property
    def port(self) -> serial.SerialBase:
        """The underlying pyserial object (for diagnostics; do not read from it)."""
        return self._port

    @property
    def is_open(self) -> bool:
        return bool(self._port.is_open)

    @property
    def baud(self) -> int:
        return int(self._port.baudrate)

    def now(self) -> float:
        return time.monotonic()

    def write(self, data: bytes) -> None:
        if self._hung_up:
            raise TransportError(
                self.name, "write", "the line is hung up (speed 0) for a BRC pulse"
            )
        try:
            written = self._port.write(data)
            if written is not None and written != len(data):
                raise TransportError(
                    self.name, "write", f"only {written} of {len(data)} bytes were written"
                )
        except TransportError:
            raise
        except serial.SerialTimeoutException as exc:
            raise TransportError(
                self.name, "write", "timed out: the far end is not reading"
            ) from exc
        except (serial.SerialException, OSError, ValueError, TypeError) as exc:
            raise TransportError(self.name, "write", self._failure(exc)) from exc

    def read(self, timeout: float) -> bytes:
        try:
            if self._polled:
                data = self._queued()
                if not data and timeout > 0:
                    data = self._poll(timeout)
            else:
                data = self._port.read(READ_CHUNK)
                if not data and timeout > 0:
                    data = self._wait(timeout)
                if len(data) >= BACKLOG_SIGN:
                    data = self._drained(data)
        except (serial.SerialException, OSError, ValueError, TypeError) as exc:
            raise TransportError(self.name, "read", self._failure(exc)) from exc
        if data:
            self._heard = True
        return data

    def _failure(self, exc: BaseException) -> BaseException | str:
        """The cause a failed read or write is said with: ``exc``, unless the far end of a
        ``socket://`` closed the connection before it sent a byte, or pyserial's words for a
        port that is gone are said in ours (:data:`NO_DATA_SAID`). A second client of the
        simulator's TCP server (or of a bridge that serves one) is closed at once, and was
        told "the port is gone ... Broken pipe", its stop "NOT DELIVERED", and doctor sent
        its user to check the cable of a robot that was fine, driven by another run."""
        closed = error_number(exc) in CLOSED_ERRORS or SOCKET_CLOSED_TEXT in str(exc)
        if self._socket and not self._heard and closed:
            return CLOSED_AT_ONCE
        return NO_DATA_SAID if NO_DATA_TEXT in str(exc) else exc

    def _wait(self, timeout: float) -> bytes:
        """What comes within ``timeout`` seconds on a port that had nothing."""
        if self._wait_handle is not None:
            ready, _, _ = select.select([self._wait_handle], [], [], timeout)
            return self._port.read(READ_CHUNK) if ready else b""
        self._set_timeout(timeout)
        try:
            first: bytes = self._port.read(1)
        finally:
            self._set_timeout(0.0)
        return first + self._port.read(READ_CHUNK) if first else b""

    def _drained(self, data: bytes) -> bytes:
        """``data`` (half a chunk or more) and the rest of what waits in the port, up to
        :data:`MAX_BACKLOG`: after the process did not run for a while (a laptop suspended),
        the OS holds seconds of frames (a pty or a USB serial driver up to 64 KiB), and read a
        chunk at a time they came as several batches, the first given the gap's slots and the
        others counted again by their frames: the mission clock ran ahead (10.6 s of mission
        time in 8.75 s after a 4 s stop). In one batch the runtime counts them once."""
        chunks = [data]
        total = len(data)
        while total < MAX_BACKLOG:
            data = self._port.read(READ_CHUNK)  # the port's timeout is 0: what is there
            if not data:
                break
            chunks.append(data)
            total += len(data)
        return b"".join(chunks)

    def _queued(self) -> bytes:
        """All a polled port's queue holds, in one read (on ``timeout = 0`` pyserial's RFC
        2217 read gives one byte: a tick whose read came past the watchdog's deadline took
        one byte of a queued frame and tripped, the rest of it counted as garbage)."""
        port = self._port
        assert isinstance(port, rfc2217.Serial)
        waiting = port.in_waiting
        if waiting:
            return bytes(port.read(waiting))
        reader = getattr(port, "_thread", None)  # what pyserial's own read checks first
        if reader is None or not reader.is_alive():
            raise serial.SerialException("connection failed (reader thread died)")
        return b""

    def _poll(self, timeout: float) -> bytes:
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            time.sleep(min(POLL_INTERVAL, remaining))
            data = self._queued()
            if data:
                return data
        return b""

    def _set_timeout(self, timeout: float) -> None:
        if timeout != self._port_timeout:
            self._port.timeout = timeout
            self._port_timeout = timeout

    def drain_output(self) -> None:
        """Wait until the bytes written have left the port (``tcdrain`` on a device; nothing
        to wait for on a socket, whose bytes are the kernel's once written). Before a rate
        change: a ``tcsetattr`` right after a ``write`` re-clocks the bytes still in the
        driver's buffer or a USB adapter's FIFO at the new rate (the watchdog's drive 0 was
        lost so, at the switch to listen at 19200). Without flow control (ours: none) a
        device drains within the bytes' own time on the wire."""
        try:
            self._port.flush()
        except _OPEN_ERRORS as exc:  # pyserial's, the OS's, termios' (a pty gone)
            raise TransportError(self.name, "drain the output", exc) from exc

    def set_baud(self, baud: int) -> None:
        try:
            self._port.baudrate = baud
        except (serial.SerialException, OSError, ValueError) as exc:
            raise TransportError(self.name, f"set the baud rate to {baud}", exc) from exc

    @property
    def modem_lines(self) -> bool:
        """Whether the modem lines may reach the robot: not over a raw TCP bridge."""
        return self._no_lines is None

    def set_wake_line(self, low: bool) -> None:
        """Drive the robot's BRC pin through the modem lines: RTS and DTR together (cables
        wire one or the other), asserted = BRC low. ``rfc2217://`` carries them to the far
        end without waiting for its answer (:meth:`_send_control`); a raw ``socket://``
        bridge has none, and says so (no pulse is said given that could not be);
        ``loop://`` keeps them."""
        if self._no_lines is not None:
            raise TransportError(self.name, "set the modem lines (BRC)", self._no_lines)
        try:
            if self._polled:
                self._send_control(low)
            else:
                self._port.rts = low
                self._port.dtr = low
        except (serial.SerialException, OSError, ValueError) as exc:
            raise TransportError(self.name, "set the modem lines (BRC)", exc) from exc

    def _send_control(self, low: bool) -> None:
        """RTS and DTR of an ``rfc2217://`` port, sent without waiting for the server's
        acknowledgement. pyserial's ``port.rts = ...`` waits for it, polling every 50 ms: two
        lines took 100-107 ms each pulse, on the tick thread, which held the stream's reads
        past the 100 ms watchdog at every keep-awake pulse (drive 0 mid-mission once a
        minute). The request is the same Telnet subnegotiation pyserial sends, written through
        the port's own write lock, on the socket that carries the commands, so it is never
        cut into a command's bytes and reaches the far end in the order it was written. A
        server that refuses it is not told (nor was the robot's BRC pin ever confirmed)."""
        on = (rfc2217.SET_CONTROL_RTS_ON, rfc2217.SET_CONTROL_DTR_ON)
        off = (rfc2217.SET_CONTROL_RTS_OFF, rfc2217.SET_CONTROL_DTR_OFF)
        port = self._port
        assert isinstance(port, rfc2217.Serial)
        for value in on if low else off:
            port.rfc2217_send_subnegotiation(rfc2217.SET_CONTROL, value)

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        """Hang the line up for the block: output speed 0 (``B0``), then the rate it had.

        The BRC pulse of a port whose modem lines cannot be set one by one (a pty: TIOCMSET
        fails with ENOTTY). POSIX (termios, "Baud Rates"): at B0 "the modem control lines
        shall no longer be asserted", so DTR and RTS drop; Linux's serial drivers assert them
        again when a real speed comes back, as they did when the port opened::

            speed  115200 ──┐  B0   ┌── 115200
            DTR    asserted └───────┘ asserted
            BRC    low      ┌───────┐ low       the falling edge at the restore wakes it
                   ─────────┘       └──────

        pyserial takes ``baudrate = 0`` as ``termios.B0`` on POSIX, so no termios call of our
        own is needed. Nothing is written meanwhile (:meth:`write` refuses: a byte at B0 is a
        byte at no rate), and the rate comes back on every exit, an exception or Ctrl-C too.
        """
        if self._no_lines is not None:  # a bridge's rate is its own: no hang-up crosses it
            raise TransportError(self.name, "hang up (set the speed to 0)", self._no_lines)
        rate = self.baud
        try:
            self._port.baudrate = 0
        except (serial.SerialException, OSError, ValueError) as exc:
            with contextlib.suppress(serial.SerialException, OSError, ValueError):
                self._port.baudrate = rate  # pyserial keeps the refused 0 as its setting
            raise TransportError(self.name, "hang up (set the speed to 0)", exc) from exc
        self._hung_up = True
        try:
            yield
        finally:
            self._hung_up = False
            self.set_baud(rate)

    @property
    def reopens(self) -> bool:
        """Whether :meth:`reopen` can bring this port back: a device path (a link to one
        too: ``/dev/serial/by-id/...``, socat's ``link=``) and a bridge's URL (a new
        connection reaches the same robot's serial port), not a pty's own ``/dev/pts/N`` (a
        pty never comes back: its number, reused, is another program's) nor ``loop://``."""
        return link_of(self.name).reopens

    def reopen(self, within: float) -> float | None:
        """Open the same device path or URL again, trying until ``within`` seconds have
        passed: a loose connector that comes back, a USB adapter that reset, a Wi-Fi bridge
        that rebooted or a network that dropped the connection. The seconds it took, or None
        if it did not come back. A device is tried every :data:`REOPEN_EVERY_S`; a bridge
        with a backoff (:data:`RECONNECT_FIRST_S` doubling to :data:`RECONNECT_MOST_S`), each
        try's TCP connect, and an RFC 2217 server's negotiation after it, waiting what is
        left of ``within`` (:data:`CONNECT_LEAST_S` at least; pyserial's own are 5 s for a
        host that does not answer at all and 3 s for each step of a negotiation not
        answered).

        The old port is closed first: while it is held open, Linux keeps the vanished
        device's number taken, and the adapter that comes back gets the next one
        (``/dev/ttyUSB1``); a bridge that serves one client at a time would turn the new
        connection away while the old one stands. Only for the safe stop (``SafeStop``): the
        mission is never carried on over a port that came back (docs/robot.md, Losing the
        link)."""
        old = self._port
        settings = (self.name, int(old.baudrate), old.write_timeout)
        network = link_of(self.name).kind is LinkKind.NETWORK
        pause = RECONNECT_FIRST_S if network else REOPEN_EVERY_S
        began = time.monotonic()  # pyserial's close of a socket:// port sleeps 0.3 s
        self.close()
        self.other_device = None
        while True:
            try:
                # the path leading to another device (a pty's number reused by another
                # program, another adapter at /dev/ttyUSB0): not opened, so not a byte, nor
                # the open's RTS and DTR, reaches it; tried again until the grace is out
                self.other_device = another_device(self._identity, device_identity(self.name))
                if self.other_device is not None:
                    raise FileNotFoundError(self.other_device)
                port = _device_port(*settings)
                if isinstance(port, serial.Serial):  # a device, not a URL
                    port.exclusive = True
                    _open_port(port)
                else:
                    left = within - (time.monotonic() - began)
                    with _open_within(max(left, CONNECT_LEAST_S)):
                        _open_port(port)
                if _closed_at_once(port):
                    _close_port(port)
                    raise ConnectionResetError("the far end closed the new connection at once")
            except _OPEN_ERRORS:
                took = time.monotonic() - began
                if took >= within:
                    return None
                time.sleep(min(pause, within - took))
                if network:
                    pause = min(2 * pause, RECONNECT_MOST_S)
                continue
            break
        self._attach(port)
        self._identity = device_identity(self.name)
        return time.monotonic() - began

    def close(self) -> None:
        _close_port(self._port)

    def __repr__(self) -> str:
        state = "open" if self.is_open else "closed"
        return f"SerialTransport({self.name!r}, {state})"


def open_transport(
    url: str,
    baud: int = DEFAULT_BAUD,
    *,
    write_timeout: float = DEFAULT_WRITE_TIMEOUT,
    brc_high: bool = False,
) -> SerialTransport:
    """Open any pyserial URL or device path; see :class:`SerialTransport`."""
    return SerialTransport.open(url, baud, write_timeout=write_timeout, brc_high=brc_high)
