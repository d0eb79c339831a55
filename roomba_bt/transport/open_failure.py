"""Why a serial port could not be opened, when its error number tells: what to do about it.

A first run on a new machine meets these three before anything else; "could not open the
port ([Errno 13] ... Permission denied); likely causes: wrong device path or URL, the port in
use by another program, permissions" lists all three where the errno names the one.
"""

from __future__ import annotations

import errno
import os

from serial.tools import list_ports

#: why a device that another process holds (``flock``) was not opened
IN_USE = (
    "another program has it open (another roomba-bt run, sensors, doctor or sim client?); "
    "two programs on one robot would each read half of its stream and mix their commands"
)
#: most ports named where a device path named none
LISTED_PORTS = 6


def open_failure(device: str, code: int | None) -> str | None:
    """The cause of a failed open of ``device`` told by its errno ``code``, with what to do;
    None when the errno tells nothing more than its own message."""
    if code in (errno.EAGAIN, errno.EWOULDBLOCK):
        return IN_USE
    if code == errno.EACCES:
        return IN_USE if os.name == "nt" else no_permission(device)  # Windows: held by another
    if code == errno.ENOENT:
        return no_such_device()
    return None


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
