"""A port opened again for the safe stop is the device the run drove: a USB adapter by its
``/dev/serial/by-id`` names, a pty by its node (made anew when its number is reused), any
other device by its path and number; a link made again is followed as its maker's word."""

from __future__ import annotations

import pytest

from roomba_bt.transport.device_identity import DeviceIdentity, another_device

FTDI = "usb-FTDI_FT231X_USB_UART_D30AB12C-if00-port0"
CH340 = "usb-1a86_USB_Serial-if00-port0"
LINK = (40, 1_000)


def _device(
    path: str, *, by_id: tuple[str, ...] = (), made: int = 5, link: tuple[int, int] | None = None
) -> DeviceIdentity:
    rdev = {"/dev/ttyUSB0": 0xBC00, "/dev/ttyUSB1": 0xBC01}.get(path, 0x8800)
    return DeviceIdentity(path, link, rdev, made, frozenset(by_id))


@pytest.mark.parametrize(
    ("opened", "now", "said"),
    [
        # the same adapter back at another number (given by its by-id path): the same one
        (_device("/dev/ttyUSB0", by_id=(FTDI,)), _device("/dev/ttyUSB1", by_id=(FTDI,)), None),
        # /dev/ttyUSB0 re-enumerated as another adapter: not the run's
        (
            _device("/dev/ttyUSB0", by_id=(FTDI,)),
            _device("/dev/ttyUSB0", by_id=(CH340,)),
            f"/dev/ttyUSB0 is the USB adapter {CH340} now; the run's was {FTDI}",
        ),
        # a pty's number handed out again: its node made later
        (
            _device("/dev/pts/0", link=LINK),
            _device("/dev/pts/0", made=9, link=LINK),
            "/dev/pts/0 is another pseudo-terminal now: its number reused by another program",
        ),
        # socat's link= made again for its new pty: followed
        (_device("/dev/pts/0", link=LINK), _device("/dev/pts/3", made=9, link=(41, 2_000)), None),
        (_device("/dev/ttyS0"), _device("/dev/ttyS0"), None),
        (_device("/dev/ttyS0"), _device("/dev/ttyAMA0"), "it leads to /dev/ttyAMA0 now, not to "
         "/dev/ttyS0"),
        # unknown on either side (a URL, a path not there): the open itself decides
        (None, _device("/dev/ttyS0"), None),
        (_device("/dev/ttyS0"), None, None),
    ],
    ids=["adapter-renumbered", "another-adapter", "pty-reused", "link-remade", "same", "moved",
         "not-known", "not-there"],
)  # fmt: skip
def test_another_device_is_told_apart(
    opened: DeviceIdentity | None, now: DeviceIdentity | None, said: str | None
) -> None:
    assert another_device(opened, now) == said
