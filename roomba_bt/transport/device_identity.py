"""Which device a serial port's path names, so that a port opened again for the safe stop
is the one the run drove, not another program's that took its place.

A link to a simulator's pty (as socat's ``link=`` makes) was left behind when the simulator
died, and another session's ``sim --pty`` got the same ``/dev/pts/0``: the stop was opened
"again" through the link and its bytes went into that program's line, said as "the port
came back". On a Raspberry Pi the same can happen to ``/dev/ttyUSB0``, re-enumerated as
another adapter. What tells a device apart:

* a USB adapter: its ``/dev/serial/by-id`` names (its make and serial number), whatever
  ``ttyUSB`` number it comes back at;
* a pseudo-terminal: its number and when its node was made (a pty is made anew each time
  its number is handed out, so a reused number has a newer node);
* any other device: its resolved path and device number.

A link made again (socat's ``link=`` pointed at its new pty, a file renamed over the old
link) is its maker's word that the new target is the robot: it is followed, as before.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass

from roomba_bt.transport.link_kind import PTY_DEVICES

#: where udev names each USB serial adapter by its make and serial number
BY_ID = "/dev/serial/by-id"


@dataclass(frozen=True, slots=True)
class DeviceIdentity:
    """What a port's path named when it was looked at."""

    #: the device's own path, every link resolved (``/dev/ttyUSB0``, ``/dev/pts/3``)
    device: str
    #: the path's own link (its inode and change time) when the path is a link, else None:
    #: a link made again has another
    link: tuple[int, int] | None
    #: the device number (major and minor)
    rdev: int
    #: when the device's node was made (its change time, ns): a pty's number reused is newer
    made_ns: int
    #: the ``/dev/serial/by-id`` names that lead to it (a USB adapter's make and serial)
    by_id: frozenset[str]


def device_identity(path: str) -> DeviceIdentity | None:
    """The device ``path`` names now, or None for a URL, a path not there or no device."""
    if "://" in path:
        return None
    try:
        own = os.lstat(path)
        device = os.path.realpath(path)
        node = os.stat(device)
    except (OSError, ValueError):
        return None
    if not stat.S_ISCHR(node.st_mode):
        return None
    link = (own.st_ino, own.st_ctime_ns) if stat.S_ISLNK(own.st_mode) else None
    return DeviceIdentity(device, link, node.st_rdev, node.st_ctime_ns, _by_id(device))


def _by_id(device: str) -> frozenset[str]:
    """The ``/dev/serial/by-id`` names of ``device`` (none off Linux, or for no USB one)."""
    try:
        names = os.listdir(BY_ID)
    except OSError:
        return frozenset()
    here = os.path.join
    return frozenset(n for n in names if os.path.realpath(here(BY_ID, n)) == device)


def another_device(opened: DeviceIdentity | None, now: DeviceIdentity | None) -> str | None:
    """Why the device the path names ``now`` is not the one ``opened`` (in words for the
    summary), or None when it is, or when either is unknown (a URL; a path not there,
    which the open itself then refuses)."""
    if opened is None or now is None:
        return None
    if opened.link is not None and now.link != opened.link:
        return None  # the link made again: its maker pointed it at the robot
    if opened.by_id or now.by_id:
        if opened.by_id & now.by_id:
            return None
        return (
            f"{now.device} is the USB adapter {_adapter(now)} now; the run's was {_adapter(opened)}"
        )
    if now.device.startswith(PTY_DEVICES):
        if (now.device, now.rdev, now.made_ns) == (opened.device, opened.rdev, opened.made_ns):
            return None
        return f"{now.device} is another pseudo-terminal now: its number reused by another program"
    if (now.device, now.rdev) == (opened.device, opened.rdev):
        return None
    return f"it leads to {now.device} now, not to {opened.device}"


def _adapter(identity: DeviceIdentity) -> str:
    """A USB adapter as its by-id names say it (make and serial number)."""
    return ", ".join(sorted(identity.by_id)) or "with no serial number"
