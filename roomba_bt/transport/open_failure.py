"""Why a serial port could not be opened, when its error number tells: what to do about it.

A first run on a new machine meets these before anything else (another program holds the
port, permissions, no such device, a name that is no serial port); "could not open the port
([Errno 13] ... Permission denied); likely causes: wrong device path or URL, the port in use
by another program, permissions" listed three guesses where the errno names the one.
"""

from __future__ import annotations

import errno
import importlib.util
import os
import re
import stat

from serial.tools import list_ports

from roomba_bt.transport.link_kind import NETWORK_PORTS, LinkKind, link_of

#: why a device that another process holds (``flock``) was not opened
IN_USE = (
    "another program has it open (another roomba-bt run, sensors, doctor or sim client?); "
    "two programs on one robot would each read half of its stream and mix their commands"
)
#: why a device in the kernel's exclusive mode (``TIOCEXCL``, EBUSY) was not opened: held by
#: another program, or left so by a run killed outright on a simulator's pty (a pty keeps the
#: mode while its other side is open; a real device forgets it when its last opener closes)
IN_USE_EXCLUSIVE = (
    f"{IN_USE} (on a simulator's pty: a run on it that was killed outright leaves it "
    "refused until the simulator is restarted)"
)
#: why a device that this process holds already was not opened: an earlier connection of
#: its own, not closed (a notebook cell run again while the first one's robot drives)
IN_USE_HERE = (
    "this process has it open already: an earlier Connection.open (or SerialTransport.open) "
    "of it that was not closed, a notebook cell run again? Its robot may still be driving: "
    "call that connection's close() (it stops the robot), or open it with "
    "`with Connection.open(...) as robot:`, which closes it at the block's end"
)
#: why a ``socket://`` connection failed that the far end closed before it sent a byte: a
#: server that takes one client at a time (``roomba-bt sim --tcp``, a Wi-Fi bridge) turns a
#: second away so, where the run said "the port is gone" and doctor "check the cable"
CLOSED_AT_ONCE = (
    "the far end closed the connection at once, before sending a byte: another client may "
    "hold it (a bridge or roomba-bt sim --tcp serves one client at a time: another run, "
    "sensors or doctor on this robot?)"
)
#: why a pty's path (``/dev/pts/N``) is not there: a pty lives as long as the program that
#: made it (``roomba-bt sim --pty``, socat) holds it; a user who gave one after the simulator
#: ended was told "the cable unplugged, or the adapter has another name"
NO_SUCH_PTY = (
    "no such pty: the program that made it (roomba-bt sim --pty, socat) has ended, or made "
    "another: start it again if need be and give the path it prints"
)
#: pyserial's words when an ``rfc2217://`` server did not answer its negotiation in time
RFC2217_UNANSWERED_TEXT = "does not seem to support RFC2217"
#: what they mean: a raw TCP bridge, or one that closed the connection before answering (on a
#: loaded host the negotiation's wait ran out before the write that meets the close failed)
RFC2217_UNANSWERED = (
    "the far end did not answer RFC 2217's negotiation: a bridge that speaks raw TCP (name "
    "it socket://HOST:PORT), or one that closed the connection at once: another client may "
    "hold it (a bridge or roomba-bt sim --tcp serves one client at a time: another run, "
    "sensors or doctor on this robot?)"
)
#: the error numbers of a connection the far end closed (a write after its close, a reset)
CLOSED_ERRORS = (errno.EPIPE, errno.ECONNRESET, errno.ECONNABORTED)
#: the error numbers of an address that could not be reached: no route to it, or its
#: connect unanswered (a bridge off, rebooting or out of Wi-Fi range)
UNREACHABLE_ERRORS = (errno.EHOSTUNREACH, errno.ENETUNREACH, errno.EHOSTDOWN, errno.ETIMEDOUT)
#: pyserial's ``socket://`` read of a connection the far end closed (no error number)
SOCKET_CLOSED_TEXT = "socket disconnected"


def closed_at_once(exc: BaseException) -> bool:
    """Whether ``exc``, or an error it was raised from, is a transport's
    :data:`CLOSED_AT_ONCE` (a run's lost port, doctor's failed read)."""
    seen: BaseException | None = exc
    for _ in range(4):  # the chain, a few links deep
        if seen is None:
            return False
        if getattr(seen, "cause", None) == CLOSED_AT_ONCE:
            return True
        seen = seen.__cause__ or seen.__context__
    return False


#: the network URLs, whose rest must be HOST:PORT
NETWORK_SCHEMES = ("socket", "rfc2217")
#: what a port may be named
PORT_ALLOWED = (
    "a device path (/dev/ttyUSB0, COM3) or a URL: socket://HOST:PORT, rfc2217://HOST:PORT"
)
#: ``HOST:PORT`` without a scheme (pyserial would take it for a device path)
_ADDRESS = re.compile(r"[A-Za-z0-9.-]+:[0-9]{1,5}")
#: most ports named where a device path named none
LISTED_PORTS = 6


def url_problem(text: str) -> str | None:
    """What is wrong with ``text`` as a port, before pyserial is asked (``run --port``, and
    :meth:`~roomba_bt.transport.serial_port.SerialTransport.open` from Python): a device path
    is taken as given; a URL needs a scheme pyserial has a handler for
    (``serial.urlhandler.protocol_<scheme>``), and HOST:PORT after the network ones. None:
    nothing. A typo in a URL had pyserial's own words ("'<=' not supported between instances
    of 'int' and 'NoneType'"), or "could not open" with a fix about the device's group."""
    if not text:
        return f"found {text!r}, an empty port name; allowed: {PORT_ALLOWED}"
    scheme, sep, rest = text.partition("://")
    if not sep:
        return None
    scheme = scheme.lower()  # as pyserial reads it
    handler = f"serial.urlhandler.protocol_{scheme}"
    if not re.fullmatch(r"[a-z0-9]+", scheme) or importlib.util.find_spec(handler) is None:
        return f"found {text!r}, a URL of no scheme pyserial knows; allowed: {PORT_ALLOWED}"
    if scheme in NETWORK_SCHEMES:
        host, colon, port = rest.partition("?")[0].rstrip("/").rpartition(":")
        if not (host and colon and port.isdigit() and 0 < int(port) < 65536):
            return f"found {text!r}; allowed: {scheme}://HOST:PORT, a port in 1..65535"
    return None


def open_failure(device: str, code: int | None, message: str = "") -> str | None:
    """The cause of a failed open of ``device`` told by its errno ``code`` (or by what the
    name is, or pyserial's ``message`` of an unanswered RFC 2217 negotiation), with what to
    do; None when they tell nothing more than the error's message."""
    if RFC2217_UNANSWERED_TEXT in message:
        return RFC2217_UNANSWERED
    if _ADDRESS.fullmatch(device):
        return (
            "a network address needs its scheme: socket://HOST:PORT (a Wi-Fi bridge, roomba-bt "
            "sim --tcp) or rfc2217://HOST:PORT"
        )
    if code in (errno.EAGAIN, errno.EWOULDBLOCK):
        return IN_USE
    if code == errno.EBUSY:
        return IN_USE_EXCLUSIVE
    if code == errno.EACCES:
        return IN_USE if os.name == "nt" else no_permission(device)  # Windows: held by another
    not_a_port = not_a_device(device)
    if not_a_port is not None:
        return not_a_port
    if code == errno.ENOTTY:
        return "not a serial port: a device, but no terminal (a USB serial adapter is /dev/ttyUSB*)"
    if code == errno.ECONNREFUSED:
        return link_of(device).refused
    if code in UNREACHABLE_ERRORS:
        return link_of(device).unreachable or None
    if code in CLOSED_ERRORS and device.lower().startswith(NETWORK_PORTS):
        return CLOSED_AT_ONCE  # an rfc2217:// server closed it while it was negotiated
    if code == errno.ENOENT:
        return NO_SUCH_PTY if link_of(device).kind is LinkKind.PTY else no_such_device()
    return None


def not_a_device(device: str) -> str | None:
    """Why ``device``, a path that exists, can be no serial port (a regular file, a folder,
    a pipe: a serial port is a character device, /dev/ttyUSB0, or a URL); None for one that
    may be (a character device, a name not there, a URL). ``--port`` says it as a usage
    error (exit 2), since no retry mends it: it was exit 3, "could not start", which a
    service told to retry that (systemd's ``Restart=on-failure``) did every minute."""
    try:
        mode = os.stat(device).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISCHR(mode):
        return None
    what = "a folder" if stat.S_ISDIR(mode) else "a file"
    return (
        f"not a serial port but {what} (--port takes a serial port's character device such "
        "as /dev/ttyUSB0 or /dev/serial/by-id/..., or a URL such as socket://HOST:PORT)"
    )


def no_permission(device: str) -> str:
    """The user may not open ``device``: on Linux a serial adapter belongs to a group
    (dialout, uucp) whose members may; or only its owner may (a udev rule changes that)."""
    try:
        import grp
        import pwd

        status = os.stat(device)
        group = grp.getgrgid(status.st_gid).gr_name
        owner = pwd.getpwuid(status.st_uid).pw_name
    except (ImportError, OSError, KeyError):
        return "permission denied: this user may not open it"
    if status.st_mode & 0o060 == 0o060 and group != "root":
        return (
            f"permission denied: its group {group} may use it and this user is not in it "
            f"(sudo usermod -aG {group} $USER, then log out and in again)"
        )
    return (
        f"permission denied: only its owner {owner} may use it (a udev rule can give it to a "
        'group: MODE="0660", GROUP="dialout")'
    )


def no_such_device() -> str:
    """No device by that name: unplugged, or named otherwise; the serial ports this machine
    has (pyserial's own listing), so the right one can be picked."""
    try:
        present = sorted(port.device for port in list_ports.comports())
    except Exception:  # a listing is a hint, never a reason to fail
        present = []
    listed = ", ".join(present[:LISTED_PORTS]) + (", ..." if len(present) > LISTED_PORTS else "")
    return (
        "no such device: the cable unplugged, or the adapter has another name "
        f"(serial ports present: {listed or 'none'})"
    )


def error_number(exc: BaseException) -> int | None:
    """The error number of ``exc`` or of the error it was raised from: pyserial wraps a
    refused socket or a termios failure in a SerialException that has none of its own; a
    connect that timed out (no number of its own) is ETIMEDOUT."""
    seen: BaseException | None = exc
    for _ in range(4):  # the chain, a few links deep
        if seen is None:
            return None
        code = getattr(seen, "errno", None)
        if isinstance(code, int):
            return code
        if isinstance(seen, TimeoutError):  # a connect unanswered: socket.timeout, no number
            return errno.ETIMEDOUT
        args = getattr(seen, "args", ())
        if seen is not exc and args and isinstance(args[0], int):  # termios.error(25, ...)
            return args[0]
        seen = seen.__cause__ or seen.__context__
    return None
