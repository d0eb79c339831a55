"""Where the monitor listens: ``[HOST:]PORT``, and whether that address needs a token.

Kept apart from the server so that the command line can check ``--monitor`` without the
optional web library installed."""

from __future__ import annotations

import contextlib
import ipaddress
import socket

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765


def is_loopback(host: str) -> bool:
    """127.0.0.0/8, ::1 or localhost: only programs on this machine can reach it."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def parse_address(text: str | None) -> tuple[str, int]:
    """``[HOST:]PORT``; empty or None: 127.0.0.1 and the default port. ValueError names what
    was found and what is allowed."""
    if not text:
        return DEFAULT_HOST, DEFAULT_PORT
    host, sep, port_text = text.rpartition(":")
    if not sep:
        host, port_text = DEFAULT_HOST, text
    host = host.strip("[]") or DEFAULT_HOST
    try:
        port = int(port_text)
    except ValueError:
        raise ValueError(
            f"found {text!r}; allowed: [HOST:]PORT, e.g. 8765 or 0.0.0.0:8765"
        ) from None
    if not 0 <= port <= 65535:
        raise ValueError(f"found port {port}; allowed: 0 to 65535 (0: any free port)")
    return host, port


#: addresses no packet goes to (TEST-NET-1, documentation IPv6): a UDP socket "connected" to
#: one learns the address its route would leave from, and sends nothing
_ROUTE_PROBES = ((socket.AF_INET, "192.0.2.1"), (socket.AF_INET6, "2001:db8::1"))


def lan_addresses(ipv6: bool = False) -> list[str]:
    """This machine's addresses another machine on the LAN may open the page by: the one the
    default route leaves from, and those its name resolves to, loopback and link-local left
    out. A bare host name often does not resolve from a phone on a home LAN; an address does.
    Empty when none is found (no network)."""
    found: list[str] = []
    families = [family for family, _ in _ROUTE_PROBES if ipv6 or family == socket.AF_INET]
    for family, probe in _ROUTE_PROBES:
        if family not in families:
            continue
        with contextlib.suppress(OSError), socket.socket(family, socket.SOCK_DGRAM) as sock:
            sock.connect((probe, 9))
            found.append(str(sock.getsockname()[0]))
    with contextlib.suppress(OSError):
        for family, _, _, _, sockaddr in socket.getaddrinfo(socket.gethostname(), None):
            if family in families:
                found.append(str(sockaddr[0]))
    shown: list[str] = []
    for text in found:
        try:
            address = ipaddress.ip_address(text.split("%")[0])
        except ValueError:
            continue
        if address.is_loopback or address.is_link_local or address.is_unspecified:
            continue
        if str(address) not in shown:
            shown.append(str(address))
    return shown
