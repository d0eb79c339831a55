"""The guarded command path against a bare ``serial.write`` of the same bytes, same run.

For each port kind (``loop://`` and a pty whose far end a thread drains), per command:

* bare       ``port.write(b"\\x89\\x00\\x64\\x80\\x00")`` on the pyserial object itself;
* guard      ``Connection.send(cmd)`` with ``cmd`` encoded once: mode guard, bookkeeping,
             ``SerialTransport.write``;
* full path  ``Connection.send(drive(v, r))``: encode (argument checks) + guard + write, what a
             behaviour's command costs from the outbox to the wire;
* outbox     ``Connection.send_many`` of one tick's outbox (drive + LEDs + song play) in
             one write, against one bare write of the same 12 bytes.

Ratios only mean something within one run: both sides run here, on the same port.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
import tty
from collections.abc import Callable, Iterator

import serial

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Radius
from roomba_bt.robot.connection import Connection
from roomba_bt.transport.serial_port import SerialTransport

CALLS = 3_000
BATCH = 300  # 300 ticks of 12 bytes fit in loop://'s 4096-byte queue
REPEAT = 5


def _best_per_call(
    variants: dict[str, Callable[[], object]], calls: int, reset: Callable[[], None]
) -> dict[str, float]:
    """Best-of-``REPEAT`` seconds per call of each variant. The variants take turns within
    each repeat (so a busy moment on a shared machine hits all of them), timed in batches of
    ``BATCH`` calls with the port's input emptied between batches (``loop://`` holds at most
    4096 bytes)."""
    best = dict.fromkeys(variants, float("inf"))
    batches = max(1, calls // BATCH)
    for _ in range(REPEAT):
        for name, fn in variants.items():
            elapsed = 0.0
            for _ in range(batches):
                reset()
                started = time.perf_counter()
                for _ in range(BATCH):
                    fn()
                elapsed += time.perf_counter() - started
            best[name] = min(best[name], elapsed / (batches * BATCH))
    return best


@contextlib.contextmanager
def _pty_port() -> Iterator[serial.SerialBase]:
    master, slave = os.openpty()
    tty.setraw(slave)
    stop = threading.Event()

    def drain() -> None:
        while not stop.is_set():
            try:
                os.read(master, 65536)
            except OSError:
                return

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    port = serial.serial_for_url(os.ttyname(slave), baudrate=115200, timeout=0, write_timeout=1)
    try:
        yield port
    finally:
        port.close()
        stop.set()
        os.close(slave)
        os.close(master)
        reader.join(1.0)


@contextlib.contextmanager
def _loop_port() -> Iterator[serial.SerialBase]:
    port = serial.serial_for_url("loop://", baudrate=115200, timeout=0, write_timeout=1)
    try:
        yield port
    finally:
        port.close()


def _measure(kind: str, port: serial.SerialBase) -> None:
    connection = Connection(SerialTransport(port, kind), watchdog=0)
    connection.send_many([oi.start(), oi.safe()])  # no robot: the model alone moves to Safe
    drive = oi.drive(100, Radius.STRAIGHT)
    data = drive.data
    tick = [drive, oi.leds(0, 0, 0), oi.play(0)]
    tick_bytes = b"".join(c.data for c in tick)

    def reset() -> None:
        if kind == "loop://":
            port.reset_input_buffer()  # type: ignore[attr-defined]

    times = _best_per_call(
        {
            "bare": lambda: port.write(data),
            "guarded": lambda: connection.send(drive),
            "full": lambda: connection.send(oi.drive(100, Radius.STRAIGHT)),
            "bare_tick": lambda: port.write(tick_bytes),
            "outbox": lambda: connection.send_many(tick),
        },
        CALLS,
        reset,
    )
    bare, guarded, full = times["bare"], times["guarded"], times["full"]
    bare_tick, outbox = times["bare_tick"], times["outbox"]
    print(f"   {kind:8s} bare serial.write        {bare * 1e6:7.2f} us/command")
    print(f"   {kind:8s} guard + write            {guarded * 1e6:7.2f} us  ({guarded / bare:.2f}x)")
    print(f"   {kind:8s} encode + guard + write   {full * 1e6:7.2f} us  ({full / bare:.2f}x)")
    print(
        f"   {kind:8s} tick outbox (3 commands) {outbox * 1e6:7.2f} us  "
        f"({outbox / bare_tick:.2f}x one bare write of the same {len(tick_bytes)} bytes)"
    )


class _NullTransport:
    """Takes bytes and drops them: what the guard itself costs, without any port."""

    name = "null"
    is_open = True

    def write(self, data: bytes) -> None:
        pass

    def read(self, timeout: float) -> bytes:
        return b""

    def set_baud(self, baud: int) -> None:
        pass

    def close(self) -> None:
        pass

    def now(self) -> float:
        return time.monotonic()


def _guard_alone() -> None:
    connection = Connection(_NullTransport(), watchdog=0)
    connection.send_many([oi.start(), oi.safe()])
    drive = oi.drive(100, Radius.STRAIGHT)
    times = _best_per_call(
        {
            "guard": lambda: connection.send(drive),
            "encode": lambda: oi.drive(100, Radius.STRAIGHT),
        },
        CALLS * 4,
        lambda: None,
    )
    guard, encode = times["guard"], times["encode"]
    print(f"   no port  guard + bookkeeping        {guard * 1e6:7.2f} us/command")
    print(f"   no port  encode (oi layer)          {encode * 1e6:7.2f} us/command")


def main() -> None:
    _guard_alone()
    for kind, opener in (("loop://", _loop_port), ("pty", _pty_port)):
        with opener() as port:
            _measure(kind, port)


if __name__ == "__main__":
    main()
