"""The guarded command path against a bare ``serial.write`` of the same bytes, same run.

For each port kind (``loop://`` and a pty whose far end a thread drains), per command:

* bare       ``port.write(b"\\x89\\x00\\x64\\x80\\x00")`` on the pyserial object itself;
* guard      ``Connection.send(cmd)`` with ``cmd`` encoded once: mode guard, bookkeeping,
             ``SerialTransport.write``;
* full path  ``Connection.send(drive(v, r))``: encode (argument checks) + guard + write, what a
             behaviour's command costs from the outbox to the wire;
* outbox     ``Connection.send_many`` of one tick's outbox (drive + LEDs + song play) in
             one write, against one bare write of the same 11 bytes.

And with no port at all: the guard alone, the encoder alone, and ``Connection.poll`` of one
stream frame against the protocol layer's ``StreamParser.feed`` of the same bytes.

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
from roomba_bt.oi.encode import Radius, decode_command
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser
from roomba_bt.robot.connection import Connection
from roomba_bt.transport.base import Transport
from roomba_bt.transport.serial_port import SerialTransport
from roomba_bt.transport.testing import NullTransport

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


@contextlib.contextmanager
def _robotless(transport: Transport, watchdog: float = 0) -> Iterator[Connection]:
    """A connection with no robot at the far end, in Safe by the model alone, closed before
    its port is (closed after, it said "the port is gone"; left open, "dropped without
    close()"). It ends in Off by the model alone too (Stop): a robot that never answered
    cannot confirm a stop, and the close said so; a real robot's stop is not this."""
    connection = Connection(transport, watchdog=watchdog)
    connection.send_many([oi.start(), oi.safe()])
    try:
        yield connection
    finally:
        connection.send(oi.stop())
        connection.close()


def _measure(kind: str, port: serial.SerialBase) -> None:
    with _robotless(SerialTransport(port, kind)) as connection:
        _measure_on(kind, port, connection)


def _measure_on(kind: str, port: serial.SerialBase, connection: Connection) -> None:
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


class _NullPort(NullTransport):
    """Takes bytes and drops them: what the guard itself costs, without any port; on a
    port's clock (:func:`time.monotonic`, read for every command written) so that the figure
    stays the one docs/performance.md gives."""

    def now(self) -> float:
        return time.monotonic()


def _guard_alone() -> None:
    drive = oi.drive(100, Radius.STRAIGHT)
    with _robotless(_NullPort()) as connection:
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


class _StreamTransport(NullTransport):
    """Hands out the same chunk of stream frames on every read, like a port that always has
    one frame waiting; its clock moves 15 ms a read. As a robot, it streams from Stream (148)
    until Pause Stream (150 0) and again from Resume (150 1): it streamed on whatever was
    written, so the safe stop's check (frames after Pause Stream: not heard) found the stop
    of the bench's connection not received, twice, and said so."""

    def __init__(self, chunk: bytes) -> None:
        super().__init__()
        self.chunk = chunk
        self.streaming = False

    def write(self, data: bytes) -> None:
        while decoded := decode_command(data):
            command, size = decoded
            if command.name == "stream":
                self.streaming = True
            elif command.name == "pause_resume_stream":
                self.streaming = bool(command.args[0])
            data = data[size:]

    def read(self, timeout: float) -> bytes:
        if not self.streaming:  # nothing comes: the wait passes
            self.clock += timeout
            return b""
        self.clock += 0.015
        return self.chunk


def _poll_against_parser() -> None:
    """What ``Connection.poll`` adds per frame (mode reconcile, arrival times, gaps,
    watchdog) to the protocol layer's :class:`StreamParser` alone."""
    ids = (7, 8, 9, 10, 11, 12, 13, 17, 19, 20, 21, 22, 25, 26, 34, 35, 43, 44, 45, 52, 53, 58)
    layout = layout_for(ids, CREATE2, True)
    frame = layout.stream_frame({35: 2})
    parser = StreamParser(ids, CREATE2)
    with contextlib.closing(Connection(_StreamTransport(frame), watchdog=0.1)) as connection:
        connection.send_many([oi.start(), oi.safe(), oi.stream(ids)])
        connection.modes.detector.offset = 0  # what start()'s query learns on a real robot
        times = _best_per_call(
            {"parser": lambda: parser.feed(frame), "poll": lambda: connection.poll(0.0)},
            CALLS * 4,
            lambda: None,
        )
    print(f"   no port  StreamParser.feed, 1 frame  {times['parser'] * 1e6:7.2f} us/frame")
    print(
        f"   no port  Connection.poll, 1 frame    {times['poll'] * 1e6:7.2f} us/frame  "
        f"({times['poll'] / times['parser']:.2f}x)"
    )


def main() -> None:
    _guard_alone()
    _poll_against_parser()
    for kind, opener in (("loop://", _loop_port), ("pty", _pty_port)):
        with opener() as port:
            _measure(kind, port)


if __name__ == "__main__":
    main()
