"""Where the monitor listens: ``[HOST:]PORT``, and whether that address needs a token.

Kept apart from the server so that the command line can check ``--monitor`` without the
optional web library installed."""

from __future__ import annotations

import ipaddress

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
