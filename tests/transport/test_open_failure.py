"""A port that cannot be opened is refused with its cause and what to do, when the error
number tells it (another program holds it, permissions, no such device)."""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import socket
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import TYPE_CHECKING

import pytest
from serial import rfc2217
from waits import HANG_S, accepted, joined  # tests/waits.py: a hang's bound

from roomba_bt.transport import SerialTransport, TransportError
from roomba_bt.transport import open_failure as failures
from roomba_bt.transport.open_failure import IN_USE, open_failure

if TYPE_CHECKING:
    from conftest import SocketsMade  # tests/conftest.py: the fixture sockets_made's


def test_no_such_device_lists_the_serial_ports_present(monkeypatch: pytest.MonkeyPatch) -> None:
    ports = [SimpleNamespace(device=f"/dev/ttyUSB{n}") for n in (1, 0)]
    monkeypatch.setattr(failures.list_ports, "comports", lambda: ports)
    with pytest.raises(TransportError) as refused:
        SerialTransport.open("/dev/no-such-roomba")
    assert str(refused.value) == (
        "/dev/no-such-roomba: could not open the port: no such device: the cable unplugged, or "
        "the adapter has another name (serial ports present: /dev/ttyUSB0, /dev/ttyUSB1)"
    )
    monkeypatch.setattr(failures.list_ports, "comports", lambda: [])
    assert open_failure("/dev/ttyUSB0", errno.ENOENT) == (
        "no such device: the cable unplugged, or the adapter has another name "
        "(serial ports present: none)"
    )


@pytest.mark.skipif(os.name != "posix", reason="POSIX owners and groups")
def test_permission_denied_names_the_group_to_join_or_the_owner(tmp_path: Path) -> None:
    import grp
    import pwd

    device = tmp_path / "ttyUSB0"
    device.write_bytes(b"")
    status = device.stat()
    owner = pwd.getpwuid(status.st_uid).pw_name
    device.chmod(0o600)
    assert open_failure(str(device), errno.EACCES) == (
        f"permission denied: only its owner {owner} may use it (a udev rule can give it to a "
        'group: MODE="0660", GROUP="dialout")'
    )
    device.chmod(0o660)
    group = grp.getgrgid(status.st_gid).gr_name
    if group == "root":  # root's group is no group to join: a group of the machine's own
        others = [g for g in grp.getgrall() if g.gr_gid != 0]
        if os.geteuid() != 0 or not others:
            pytest.skip("needs a group other than root to give the file to")
        group = next((g.gr_name for g in others if g.gr_name == "dialout"), others[0].gr_name)
        os.chown(device, -1, grp.getgrnam(group).gr_gid)
    assert open_failure(str(device), errno.EACCES) == (
        f"permission denied: its group {group} may use it and this user is not in it "
        f"(sudo usermod -aG {group} $USER, then log out and in again)"
    )
    assert open_failure(str(device), errno.EAGAIN) == IN_USE
    assert open_failure("/dev/null", errno.EIO) is None  # nothing more than its message


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("setpriv") is None,
    reason="runs the CLI as another user (root and setpriv: CI)",
)
def test_a_user_who_may_not_open_the_port_is_told_why(tmp_path: Path) -> None:
    """As an unprivileged user, a root-only device: the run said "likely causes: wrong device
    path or URL, the port in use by another program, permissions"; it names the one."""
    device = "/dev/ttyS0" if os.path.exists("/dev/ttyS0") else None
    if device is None or os.stat(device).st_mode & 0o006:
        pytest.skip("no device closed to other users")
    tmp_path.chmod(0o755)
    done = subprocess.run(
        ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
         sys.executable, "-m", "roomba_bt.cli", "run", "dock", "--port", device],
        capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 3, done.stderr
    assert f"{device}: could not open the port: permission denied: " in done.stderr
    assert "likely causes" not in done.stderr


@pytest.mark.parametrize(
    ("port", "said"),
    [
        ("192.168.1.20:8888", "a network address needs its scheme: socket://HOST:PORT"),
        ("robot.local:23", "a network address needs its scheme: socket://HOST:PORT"),
        ("{file}", "not a serial port but a file (--port takes a serial port's character device"),
        ("{folder}", "not a serial port but a folder"),
        ("/dev/null", "not a serial port: a device, but no terminal"),
        ("socket://127.0.0.1:{closed}", "nothing listens at 127.0.0.1:{closed}: is the bridge"),
    ],
    ids=["address", "host-name", "file", "folder", "no-terminal", "refused"],
)
def test_a_port_that_is_no_port_says_what_it_is(tmp_path: Path, port: str, said: str) -> None:
    """A mission file given as the port, a folder, /dev/null, a bridge's address without
    ``socket://``, a bridge not running: each was "could not open the port (...); likely
    causes: wrong device path or URL, the port in use by another program, permissions"."""

    mission = tmp_path / "dock.yaml"
    mission.write_text("mission: x\n")
    with socket.socket() as unused:  # a port nothing listens on
        unused.bind(("127.0.0.1", 0))
        closed = unused.getsockname()[1]
    url = port.format(file=mission, folder=tmp_path, closed=closed)
    with pytest.raises(TransportError) as refused:
        SerialTransport.open(url)
    said = said.format(closed=closed)
    assert str(refused.value).startswith(f"{url}: could not open the port: {said}")


# pyserial's RFC 2217 client names its reader thread with the deprecated setDaemon/setName
@pytest.mark.filterwarnings("ignore:set(Daemon|Name)\\(\\) is deprecated:DeprecationWarning")
def test_an_rfc2217_server_that_closes_at_once_is_said_as_a_network_s(
    sockets_made: Callable[[ModuleType], SocketsMade],
) -> None:
    """An ``rfc2217://`` server that closes the connection while it is negotiated (one that
    serves another client, a bridge that reboots) was "Broken pipe; likely causes: wrong
    device path or URL, the port in use by another program, permissions"; it is said as
    ``socket://``'s is: another client may hold it. The refused open's socket is closed:
    pyserial's close, which its failed open calls, skipped ``socket.close()`` when
    ``shutdown()`` failed and forgot the socket, left to the garbage collector (a
    ``ResourceWarning``, hidden here by a filter until session 40)."""
    import threading

    sockets = sockets_made(rfc2217)
    listener = socket.create_server(("127.0.0.1", 0))

    def close_each() -> None:
        with contextlib.suppress(OSError):  # the listener shut: the test is over
            while True:
                accepted(listener, "the next try's connection").close()

    closer = threading.Thread(target=close_each, daemon=True)
    closer.start()
    url = f"rfc2217://127.0.0.1:{listener.getsockname()[1]}"
    try:
        with pytest.raises(TransportError) as refused:
            SerialTransport.open(url)
    finally:
        listener.shutdown(socket.SHUT_RDWR)  # ends the accept, which a close left waiting
        joined(closer, "the listener's accept")
        listener.close()
    # the write that meets the close fails (EPIPE), or, on a loaded host, pyserial's wait for
    # the negotiation runs out first ("Remote does not seem to support RFC2217", said raw
    # until session 36's CI met it): either way the words say another client may hold it
    said = str(refused.value)
    assert said in (
        f"{url}: could not open the port: {failures.CLOSED_AT_ONCE}",
        f"{url}: could not open the port: {failures.RFC2217_UNANSWERED}",
    ), said
    assert "device path" not in said and "permission" not in said
    assert len(sockets.made) == 1 and sockets.all_closed()  # closed, not left to the GC


def test_an_rfc2217_negotiation_left_unanswered_is_said_with_what_it_means() -> None:
    """pyserial's own words for a server that did not answer the negotiation in time
    reached the user raw (``Remote does not seem to support RFC2217 or BINARY mode
    [we-BINARY:False(INACTIVE), ...]``)."""
    message = (
        "Remote does not seem to support RFC2217 or BINARY mode [we-BINARY:False(INACTIVE), "
        "we-RFC2217:False(REQUESTED)]"
    )
    said = failures.open_failure("rfc2217://127.0.0.1:7000", None, message)
    assert said == failures.RFC2217_UNANSWERED
    assert "socket://" in said and "another client may hold it" in said
