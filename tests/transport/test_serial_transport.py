"""SerialTransport over every kind of URL it is used with: loop://, a pty, a TCP socket."""

from __future__ import annotations

import contextlib
import os
import select
import socket
import struct
import subprocess
import sys
import termios
import threading
import time
import tty
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
import serial
from waits import HANG_S, accepted, line, reaped, received  # tests/waits.py: a hang's bound

from roomba_bt.transport import (
    SerialTransport,
    Transport,
    TransportError,
    open_transport,
    serial_port,
)

#: The most a wait here for another thread's or the kernel's event lasts: a hang's bound,
#: never a timing (ends as soon as the event comes)
WAIT_S = HANG_S


@dataclass
class FarEnd:
    """The other side of the link, as raw bytes: ``send`` to the transport, ``take`` from it
    (what it has, up to a size, within a hang's bound)."""

    url: str
    send: Callable[[bytes], None]
    take: Callable[[int], bytes]
    hang_up: Callable[[], None]
    echoes: bool = False  # loop://: what the transport writes comes back to it


@contextlib.contextmanager
def pty_far_end() -> Iterator[FarEnd]:
    master, slave = os.openpty()
    tty.setraw(slave)

    def take(size: int) -> bytes:
        return received(master, size, "the bytes the transport wrote, at the pty's far end")

    closed = threading.Event()

    def hang_up() -> None:
        if not closed.is_set():
            closed.set()
            os.close(master)
            os.close(slave)

    try:
        yield FarEnd(os.ttyname(slave), lambda data: os.write(master, data) and None, take, hang_up)
    finally:
        hang_up()


@contextlib.contextmanager
def tcp_far_end() -> Iterator[FarEnd]:
    listener = socket.create_server(("127.0.0.1", 0))
    connections: list[socket.socket] = []

    def accept() -> socket.socket:
        if not connections:
            connections.append(accepted(listener, "the transport's connection"))
        return connections[0]

    def hang_up() -> None:
        for conn in connections:
            conn.close()
        listener.close()

    try:
        yield FarEnd(
            f"socket://127.0.0.1:{listener.getsockname()[1]}",
            lambda data: accept().sendall(data),
            lambda size: received(accept(), size, "the bytes the transport wrote, at the far end"),
            hang_up,
        )
    finally:
        hang_up()


@contextlib.contextmanager
def loop_far_end() -> Iterator[FarEnd]:
    yield FarEnd("loop://", lambda data: None, lambda size: b"", lambda: None, echoes=True)


FAR_ENDS = {"loop": loop_far_end, "pty": pty_far_end, "tcp": tcp_far_end}


@pytest.fixture(params=list(FAR_ENDS))
def far_end(request: pytest.FixtureRequest) -> Iterator[FarEnd]:
    with FAR_ENDS[request.param]() as end:
        yield end


def read_until(transport: Transport, size: int, timeout: float = 2.0) -> bytes:
    data = b""
    for _ in range(int(timeout / 0.05)):
        data += transport.read(0.05)
        if len(data) >= size:
            break
    return data


def test_is_a_transport_and_round_trips_bytes(far_end: FarEnd) -> None:
    transport = open_transport(far_end.url)
    try:
        assert isinstance(transport, Transport)
        assert transport.is_open and transport.name == far_end.url
        transport.write(bytes([128, 131]))
        if far_end.echoes:
            assert read_until(transport, 2) == bytes([128, 131])
        else:
            got = b""
            while len(got) < 2:
                got += far_end.take(16)
            assert got == bytes([128, 131])
            far_end.send(bytes(range(200)))
            assert read_until(transport, 200) == bytes(range(200))
    finally:
        transport.close()
    assert not transport.is_open


def test_read_returns_nothing_after_the_timeout(far_end: FarEnd) -> None:
    transport = open_transport(far_end.url)
    try:
        before = transport.now()
        assert transport.read(0.05) == b""
        assert transport.now() >= before + 0.04
        assert transport.read(0) == b""
    finally:
        transport.close()


def test_set_baud_changes_the_port_rate(far_end: FarEnd) -> None:
    transport = SerialTransport.open(far_end.url, 115200)
    try:
        assert transport.baud == 115200
        transport.set_baud(19200)
        assert transport.baud == 19200
        with pytest.raises(TransportError, match="could not set the baud rate to -5"):
            transport.set_baud(-5)
    finally:
        transport.close()


def test_drain_output_waits_for_what_was_written_and_says_a_closed_port(
    far_end: FarEnd,
) -> None:
    """Before a rate change the bytes written leave first (``tcdrain`` on a device; nothing
    to wait for on a socket): the watchdog's drive 0 was re-clocked at 19200 by a switch
    right after its write. A closed port is a TransportError naming it, not a traceback."""
    transport = SerialTransport.open(far_end.url, 115200)
    transport.write(bytes([137, 0, 0, 0, 0]))
    transport.drain_output()
    transport.set_baud(19200)
    if not far_end.echoes:
        got = b""
        while len(got) < 5:
            got += far_end.take(16)
        assert got == bytes([137, 0, 0, 0, 0])
    transport.close()
    if far_end.url.startswith("socket://"):
        return  # pyserial's socket port has no output of its own to drain, open or closed
    with pytest.raises(TransportError, match=f"{far_end.url}: could not drain the output"):
        transport.drain_output()


@pytest.mark.parametrize("kind", ["pty", "tcp"])
def test_a_vanished_far_end_raises_transport_error_naming_the_port(kind: str) -> None:
    with FAR_ENDS[kind]() as end:
        transport = open_transport(end.url)
        try:
            transport.write(b"\x80")
            end.take(1)
            end.hang_up()
            with pytest.raises(TransportError) as failed:
                for _ in range(50):
                    transport.read(0.02)
                    transport.write(bytes([137, 0, 0, 0, 0]))
            assert str(failed.value).startswith(end.url + ": could not ")
            assert isinstance(failed.value, ConnectionError)
        finally:
            transport.close()


def test_a_port_gone_is_said_in_our_words_not_pyserials(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run whose adapter was pulled (or whose ``sim --pty`` was killed) ended "the port is
    gone (...): it failed on read (device reports readiness to read but returned no data
    (device disconnected or multiple access on port?))": pyserial's words, raw. Said in
    ours; pyserial's add nothing to them."""
    with FAR_ENDS["pty"]() as end:
        transport = open_transport(end.url)
        try:

            def gone(size: int = 1) -> bytes:
                raise serial.SerialException(
                    "device reports readiness to read but returned no data (device "
                    "disconnected or multiple access on port?)"
                )

            monkeypatch.setattr(transport.port, "read", gone)
            with pytest.raises(TransportError) as failed:
                transport.read(0.02)
            assert failed.value.cause == (
                "it said bytes were waiting and gave none: its other end gone, or another "
                "program reading the same port"
            )
            assert str(failed.value).endswith(f"could not read: {failed.value.cause}")
            assert "readiness" not in str(failed.value)
        finally:
            transport.close()


def test_opening_a_missing_port_names_it() -> None:
    with pytest.raises(TransportError, match=r"^/dev/no-such-roomba: could not open the port"):
        open_transport("/dev/no-such-roomba")
    with pytest.raises(TransportError, match="could not open the port"):
        open_transport("nosuchscheme://x")


def test_a_device_is_opened_for_one_program_at_a_time() -> None:
    """A second opener of the same device (another roomba-bt on the robot) is refused at
    once, naming why; once the first closes, the device opens again."""
    from roomba_bt.transport.open_failure import IN_USE

    with pty_far_end() as end:
        holder = subprocess.Popen(
            [sys.executable, "-c", HOLD_THE_LOCK, end.url], stdout=subprocess.PIPE,
            stdin=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            assert holder.stdout is not None
            said = line(holder.stdout, "a process holding the port's lock")
            assert said == "held\n", said
            with pytest.raises(TransportError) as refused:
                SerialTransport.open(end.url)
        finally:
            holder.communicate("", timeout=HANG_S)
        assert refused.value.cause == IN_USE
        assert str(refused.value).startswith(f"{end.url}: could not open the port: another ")
        SerialTransport.open(end.url).close()


#: another program holding a device: pyserial's ``exclusive`` lock
HOLD_THE_LOCK = """
import fcntl, os, sys
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)
fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
print("held", flush=True)
sys.stdin.read()
"""


#: Linux's TIOCGEXCL (``_IOR('T', 0x40, int)``, not in Python's termios): whether a
#: terminal is in the kernel's exclusive mode
TIOCGEXCL = 0x80045440
#: whom a test that runs as root opens a device as: root's own open ignores the mode
NOBODY = 65534


def in_exclusive_mode(fd: int) -> bool:
    import fcntl
    import struct

    return struct.unpack("i", fcntl.ioctl(fd, TIOCGEXCL, bytes(4)))[0] != 0


def plain_open_error(path: str) -> int:
    """The errno of a plain ``os.open`` of ``path`` by another user's program (a student's
    ``serial.Serial(port)``), 0 when it opens. Root's opens ignore the exclusive mode, so a
    test running as root (CI) opens it in a forked child that became nobody, to whom the
    device is given; skipped where root cannot become nobody."""
    if os.geteuid() != 0:
        try:
            os.close(os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK))
        except OSError as exc:
            return exc.errno or -1
        return 0
    os.chown(path, NOBODY, NOBODY)
    child = os.fork()
    if child == 0:  # only os calls here, then _exit: nothing of pytest's runs in the child
        code = 0
        try:
            os.setgid(NOBODY)
            os.setuid(NOBODY)
        except OSError:
            os._exit(255)
        try:
            os.close(os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK))
        except OSError as exc:
            code = exc.errno or 254
        os._exit(code)
    code = reaped(child, "the child opening the device as nobody")
    if code == 255:
        pytest.skip("running as root, and root could not become nobody: root's opens ignore it")
    return code


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="TIOCGEXCL is Linux's")
def test_a_device_is_in_the_kernels_exclusive_mode_while_it_is_open() -> None:
    """The advisory flock stopped only roomba-bt: a student's pyserial script opened the
    robot's port beside a run and drove it backwards for 7.7 s. While a transport holds the
    device the terminal is in the kernel's exclusive mode (TIOCEXCL), so another user's plain
    open fails with EBUSY; closing clears it (a pty keeps the mode while its other side is
    open: the next run on a simulator would have been refused)."""
    import errno

    with pty_far_end() as end:
        probe = os.open(end.url, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)  # opened before
        try:
            assert not in_exclusive_mode(probe)
            assert plain_open_error(end.url) == 0
            transport = SerialTransport.open(end.url)
            assert in_exclusive_mode(probe)
            assert plain_open_error(end.url) == errno.EBUSY
            transport.close()
            assert not in_exclusive_mode(probe)
            assert plain_open_error(end.url) == 0
        finally:
            os.close(probe)


def test_a_device_in_exclusive_mode_is_said_to_be_in_use() -> None:
    """Another roomba-bt run by a user without root meets the kernel's EBUSY, not the flock:
    it is said as a device in use, with the one case where nothing holds it (a simulator's
    pty after a run on it was killed outright), not as pyserial's own words."""
    import errno

    from roomba_bt.transport.open_failure import IN_USE, open_failure

    said = open_failure("/dev/ttyUSB0", errno.EBUSY)
    assert said is not None and said.startswith(IN_USE)
    assert "restart" in said


def test_a_device_this_process_holds_is_said_to_be_its_own(tmp_path: Path) -> None:
    """Opened twice by one program (a notebook cell run again while the first connection's
    robot drives): not "another program has it open", which sent its user looking for one;
    this process's own earlier connection, and how to close it. By another of its names too
    (a /dev/serial/by-id/ link)."""
    from roomba_bt.transport.open_failure import IN_USE_HERE

    with pty_far_end() as end:
        first = SerialTransport.open(end.url)
        link = tmp_path / "by-id-robot"
        link.symlink_to(end.url)
        for name in (end.url, str(link)):
            with pytest.raises(TransportError) as refused:
                SerialTransport.open(name)
            assert refused.value.cause == IN_USE_HERE, refused.value
            assert "this process has it open already" in str(refused.value)
            assert "close()" in str(refused.value)
        first.close()
        SerialTransport.open(end.url).close()


@pytest.mark.parametrize(
    ("url", "said"),
    [
        ("socket://localhost", "found 'socket://localhost'; allowed: socket://HOST:PORT, a port"),
        ("rfc2217://h:99999", "a port in 1..65535"),
        ("nosuchscheme://x", "a URL of no scheme pyserial knows; allowed: a device path"),
        ("", "an empty port name"),
    ],
)
def test_a_url_that_names_no_port_is_said_before_pyserial(url: str, said: str) -> None:
    """From Python as ``--port`` says it: pyserial's own words were "'<=' not supported
    between instances of 'int' and 'NoneType'"."""
    with pytest.raises(TransportError) as refused:
        SerialTransport.open(url)
    assert str(refused.value).startswith(f"{url}: could not open the port: found ")
    assert said in str(refused.value)


def test_a_port_that_is_no_text_is_a_type_error_naming_what_is_allowed() -> None:
    """``Connection.open(None)`` (an unset environment variable): it was "'NoneType' object
    has no attribute 'startswith'"."""
    with pytest.raises(TypeError, match=r"the port must be a device path .*; got None"):
        SerialTransport.open(None)  # type: ignore[arg-type]


def test_socket_urls_may_be_opened_twice() -> None:
    """``exclusive`` is a device's lock; a socket:// URL is two connections to a server."""
    with tcp_far_end() as end:
        first = SerialTransport.open(end.url)
        second = SerialTransport.open(end.url)
        first.close()
        second.close()


def test_write_to_a_closed_transport_is_a_transport_error() -> None:
    transport = open_transport("loop://")
    transport.close()
    transport.close()  # twice is fine
    with pytest.raises(TransportError, match="loop://: could not write"):
        transport.write(b"\x80")


def test_a_far_end_that_stops_reading_times_the_write_out_instead_of_hanging() -> None:
    with pty_far_end() as end:
        transport = SerialTransport.open(end.url, write_timeout=0.2)
        try:
            chunk = bytes(4096)
            with pytest.raises(TransportError, match="timed out: the far end is not reading"):
                for _ in range(10_000):  # the pty's buffer fills: then the bounded write fails
                    transport.write(chunk)
        finally:
            transport.close()


def test_hung_up_holds_speed_0_refuses_writes_and_restores_the_rate_on_any_exit() -> None:
    """The BRC pulse of a port without settable modem lines (docs/doctor.md): a pty's own
    side reads the speed the client set, so B0 and the rate's return are seen there."""
    with pty_far_end() as end:
        transport = SerialTransport.open(end.url, 19200)
        slave = os.open(end.url, os.O_RDWR | os.O_NOCTTY)
        try:
            with pytest.raises(OSError, match="Inappropriate ioctl"):
                transport.set_wake_line(True)  # why the fallback exists
            with transport.hung_up():
                assert termios.tcgetattr(slave)[5] == termios.B0
                with pytest.raises(TransportError, match="hung up \\(speed 0\\)"):
                    transport.write(b"\x80")
            assert termios.tcgetattr(slave)[5] == termios.B19200
            assert transport.baud == 19200
            transport.write(b"\x80")
            assert end.take(16) == b"\x80", "nothing was written while hung up"
            with pytest.raises(KeyboardInterrupt), transport.hung_up():
                raise KeyboardInterrupt
            assert termios.tcgetattr(slave)[5] == termios.B19200, "restored after Ctrl-C"
            transport.write(b"\x81")
        finally:
            os.close(slave)
            transport.close()


class _TtyPort:
    """A port as a tty gives its bytes: at most 4095 a read (its line discipline's buffer),
    whatever more waits behind it; nothing once empty (the port's timeout is 0)."""

    def __init__(self, waiting: bytes) -> None:
        self.waiting = waiting
        self.reads = 0

    def read(self, size: int) -> bytes:
        self.reads += 1
        taken, self.waiting = self.waiting[: min(size, 4095)], self.waiting[min(size, 4095) :]
        return taken


def test_a_backlog_is_read_whole_in_one_read() -> None:
    """After the process did not run for a while the OS holds seconds of frames (a pty took
    20 KiB here), and a tty gives at most 4 KiB a read: read a chunk at a time, the backlog
    came as several batches that the runtime counted twice (over a pty, after a 4 s SIGSTOP:
    10.6 s of mission time in 8.75 s; now 8.80 s in 8.83 s)."""
    from roomba_bt.transport.serial_port import BACKLOG_SIGN, READ_CHUNK

    with pty_far_end() as far:
        transport = open_transport(far.url)
        try:
            backlog = bytes(i % 251 for i in range(5 * READ_CHUNK + 17))
            real = transport._port  # type: ignore[attr-defined]
            transport._port = _TtyPort(backlog)  # type: ignore[attr-defined]
            assert transport.read(0.0) == backlog  # in one read, not six
            small = bytes(BACKLOG_SIGN - 1)
            port = transport._port = _TtyPort(small)  # type: ignore[attr-defined]
            assert transport.read(0.0) == small and port.reads == 1  # not drained: one read
        finally:
            transport._port = real  # type: ignore[attr-defined]
            transport.close()


def _pty() -> tuple[int, int, str]:
    """A raw pty pair and its device path: a far end a test opens and closes itself."""
    master, slave = os.openpty()
    tty.setraw(slave)
    return master, slave, os.ttyname(slave)


def test_a_device_path_that_comes_back_is_reopened_and_carries_bytes(tmp_path: Path) -> None:
    """A loose connector: the device behind a link (``/dev/serial/by-id/...``) goes and comes
    back. ``reopen`` opens the same path again (for the safe stop alone) and the port reads
    and writes there; the old port was closed first."""
    first = _pty()
    link = tmp_path / "robot"
    link.symlink_to(first[2])
    transport = SerialTransport.open(str(link))
    assert transport.reopens
    second = _pty()
    back = tmp_path / "robot.back"
    back.symlink_to(second[2])
    back.replace(link)
    for fd in first[:2]:
        os.close(fd)
    try:
        took = transport.reopen(within=2.0)
        assert took is not None and took >= 0.0
        transport.write(b"\x80")
        assert os.read(second[0], 1) == b"\x80"
        os.write(second[0], b"\x01")
        assert transport.read(1.0) == b"\x01"
    finally:
        transport.close()
        for fd in second[:2]:
            os.close(fd)


def _until_the_file_clock_passes(made_ns: int, probe: Path) -> None:
    """Until a node made now has a later change time than ``made_ns``: the kernel stamps
    nodes from a coarse clock (a tick of 1 to 10 ms), so a pty made again within the same
    tick has the same time as the first. A file touched here is stamped by the same clock;
    the wait ends on its first tick past, not after a fixed guess (it was 50 ms)."""
    deadline = time.monotonic() + HANG_S  # a clock that never moves: fail, do not hang
    probe.touch()
    while os.stat(probe).st_ctime_ns <= made_ns:
        assert time.monotonic() < deadline, f"the file clock did not move in {HANG_S:g} s"
        time.sleep(0.001)
        os.utime(probe)


def test_a_link_left_to_a_pty_number_another_program_got_is_not_reopened(
    tmp_path: Path,
) -> None:
    """A link to a simulator's pty, left as it was when the simulator died, while another
    program's pty got the same number: the reopen took it for the port come back, and the
    stop's bytes went into that program's line. The device is told apart (its pty made
    anew): not opened, not a byte written, and said why."""
    first = _pty()
    link = tmp_path / "robot"
    link.symlink_to(first[2])
    transport = SerialTransport.open(str(link))
    transport.close()
    made = os.stat(first[2]).st_ctime_ns
    for fd in first[:2]:
        os.close(fd)
    _until_the_file_clock_passes(made, tmp_path / "clock")  # the next node made is newer
    held = [_pty() for _ in range(20)]  # the lowest free number is handed out: the first's
    try:
        other = next((pty for pty in held if pty[2] == first[2]), None)
        if other is None:
            pytest.skip(f"another process took {first[2]} meanwhile")
        assert transport.reopen(within=0.3) is None
        assert transport.other_device == (
            f"{first[2]} is another pseudo-terminal now: its number reused by another program"
        )
        os.set_blocking(other[0], False)
        with pytest.raises(BlockingIOError):
            os.read(other[0], 1)  # nothing reached the other program's line
    finally:
        transport.close()
        for pty in held:
            os.close(pty[0])
            os.close(pty[1])


def test_a_device_path_that_does_not_come_back_is_said_so(tmp_path: Path) -> None:
    master, slave, path = _pty()
    link = tmp_path / "robot"
    link.symlink_to(path)
    transport = SerialTransport.open(str(link))
    link.unlink()  # the adapter gone, its link with it
    os.close(master)
    os.close(slave)
    assert transport.reopen(within=0.2) is None
    assert not transport.is_open


def test_neither_loop_nor_a_pty_s_own_path_is_reopened() -> None:
    """A pty's number, reused, is another program's line, and ``loop://`` has no far end:
    a device path (or a link to one) and a bridge's URL come back."""
    master, slave, path = _pty()
    try:
        for port in (path, "loop://"):
            transport = SerialTransport.open(port)
            assert not transport.reopens, port
            transport.close()
    finally:
        os.close(master)
        os.close(slave)


def test_a_bridge_that_resets_is_reconnected_past_one_that_turns_the_connection_away(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Wi-Fi bridge that rebooted: its connection reset, then its listener takes the first
    new connection and resets it at once (still rebooting), then serves again. ``reopen``
    connects again (a new connection reaches the same robot), past the one turned away, and
    bytes pass both ways on the new connection.

    The reopen looks for the far end's reset (:data:`RECONNECT_SETTLE_S`, 50 ms) once the
    bridge has dealt with the connection: a look before it was a bet on this test's thread
    taking the connection within the 50 ms, lost on a loaded machine (the turned one taken
    for served, no second connection made: "the bridge's new connection was not made")."""
    listener = socket.create_server(("127.0.0.1", 0))
    url = f"socket://127.0.0.1:{listener.getsockname()[1]}"
    transport = SerialTransport.open(url)
    assert transport.reopens
    first = accepted(listener, "the transport's connection")
    first.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    first.close()  # the bridge reboots: RST
    served: list[socket.socket] = []
    dealt = threading.Semaphore(0)  # one for each connection the bridge took
    looked = serial_port._closed_at_once

    def after_the_bridge(port: serial_port.serial.SerialBase) -> bool:
        assert dealt.acquire(timeout=WAIT_S), "the bridge took no connection"
        return looked(port)

    def bridge_back() -> None:
        turned = accepted(listener, "the reopen's first try")  # still rebooting: reset at once
        turned.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        turned.close()
        dealt.release()
        served.append(accepted(listener, "the reopen's second try"))
        dealt.release()

    monkeypatch.setattr(serial_port, "_closed_at_once", after_the_bridge)
    thread = threading.Thread(target=bridge_back, daemon=True)
    thread.start()
    try:
        took = transport.reopen(within=WAIT_S)  # a hang's bound: it ends once connected
        assert took is not None, "the bridge's new connection was not made"
        thread.join(WAIT_S)  # it takes the connection the reopen made, at once
        assert served, "the reopen took the connection turned away for served"
        transport.write(b"\x80")
        assert received(served[0], 1, "the byte written after the reopen") == b"\x80"
        served[0].sendall(b"\x01")
        assert transport.read(1.0) == b"\x01"
    finally:
        transport.close()
        for sock in (*served, listener):
            sock.close()


def _open_reset_as_it_reads(
    monkeypatch: pytest.MonkeyPatch, listener: socket.socket
) -> list[socket.socket]:
    """pyserial's ``socket://`` open, connected, reads what the far end sent first
    (``reset_input_buffer``): a bridge that resets the new connection at once makes that
    read raise, and the socket's ``shutdown`` fails after it. Made so here every time (in
    CI it was a race): the bridge (``listener``) resets each new connection before the
    read. The sockets the opens made are returned, to see each closed."""
    made: list[socket.socket] = []
    handler = serial_port.protocol_socket.Serial
    read_as_pyserial = handler.reset_input_buffer

    def reset_as_it_reads(port: serial_port.protocol_socket.Serial) -> None:
        made.append(port._socket)
        turned = accepted(listener, "the open's connection")
        turned.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        turned.close()  # RST
        select.select([port._socket], [], [], HANG_S)  # the reset, on its way
        read_as_pyserial(port)  # raises: the connection was reset

    monkeypatch.setattr(handler, "reset_input_buffer", reset_as_it_reads)
    return made


def test_an_open_of_a_bridge_that_resets_at_once_leaves_no_socket_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """CI failed on a socket left open (``ResourceWarning`` from the port's ``__del__``)
    by a reopen's try that the bridge turned away as pyserial's open read."""
    listener = socket.create_server(("127.0.0.1", 0))
    url = f"socket://127.0.0.1:{listener.getsockname()[1]}"
    try:
        made = _open_reset_as_it_reads(monkeypatch, listener)
        with pytest.raises(TransportError):
            SerialTransport.open(url)
        assert len(made) == 1 and made[0].fileno() == -1  # closed, not left to the GC
    finally:
        listener.close()


def test_a_reopen_turned_away_as_it_reads_leaves_no_socket_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    url = f"socket://127.0.0.1:{listener.getsockname()[1]}"
    transport = SerialTransport.open(url)
    first = accepted(listener, "the transport's connection")
    try:
        made = _open_reset_as_it_reads(monkeypatch, listener)
        assert transport.reopen(within=0.3) is None
        assert made and all(sock.fileno() == -1 for sock in made)
    finally:
        transport.close()
        for sock in (first, listener):
            sock.close()


def test_a_bridge_that_stays_down_is_said_not_to_come_back() -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    transport = SerialTransport.open(f"socket://127.0.0.1:{listener.getsockname()[1]}")
    accepted(listener, "the transport's connection").close()
    listener.close()  # nothing listens there any more
    assert transport.reopen(within=0.3) is None
    assert not transport.is_open


def test_a_bridge_that_does_not_answer_holds_a_reconnection_no_longer_than_asked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A host that answers no SYN (an ESP8266 still rebooting, out of Wi-Fi range) held
    each try's connect pyserial's 5 s, past the grace the stop waits; a try now connects
    within what is left of it. The listener's backlog, full, leaves new SYNs unanswered."""
    listener = socket.create_server(("127.0.0.1", 0), backlog=0)
    address = listener.getsockname()
    transport = SerialTransport.open(f"socket://127.0.0.1:{address[1]}")
    accepted(listener, "the transport's connection").close()
    filler = socket.create_connection(address)  # the backlog's one place, taken
    bounds: list[float | None] = []  # each try's connect timeout (a wall-clock bound: flaky)
    connect = socket.create_connection

    def bounded(where: tuple[str, int], timeout: float | None = None) -> socket.socket:
        bounds.append(timeout)
        return connect(where, timeout)

    monkeypatch.setattr(socket, "create_connection", bounded)
    try:
        assert transport.reopen(within=0.5) is None
        assert bounds and all(b is not None and b <= 0.5 for b in bounds), bounds  # not 5 s
        assert serial_port.protocol_socket.socket is socket  # as it was, for other opens
    finally:
        filler.close()
        listener.close()
