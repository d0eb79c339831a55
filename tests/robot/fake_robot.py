"""A minimal robot that speaks OI bytes on the far end of a pty or a TCP socket.

Not the simulator: no world, no physics; but the same line. Its far end is one of the
simulator server's endpoints (:class:`~roomba_bt.sim.server.PtyEndpoint`,
:class:`~roomba_bt.sim.server.TcpEndpoint`: ``endpoint.address`` is what the connection
opens), so the contract tests meet the pty and the socket as ``roomba-bt sim`` serves them,
and the robot's side of a line is written once. It decodes the commands it receives with the
protocol layer's own table (``decode_command``), records every byte and, for every command,
the mode it was in when the command arrived; applies mode commands the way the spec says;
answers Sensors (142) and Query List (149) from :attr:`FakeRobot.values`; streams frames every
15 ms while asked to; and can be scripted: fall back to Passive with a cause, stop streaming,
go silent, hang up.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi.encode import Command, decode_command
from roomba_bt.oi.errors import OIError
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.robot.discovery import PROBE_QUERY
from roomba_bt.sim.server import Endpoint

SLOT = 0.015


@dataclass(frozen=True)
class Received:
    """One command as the fake robot took it, and the mode it was in at that moment."""

    mode: OIMode
    command: Command
    time: float


class RobotDouble:
    """What the contract tests read from either robot double (:class:`FakeRobot` here,
    ``SimRobot`` on the simulator): every byte the host wrote, each command with the mode it
    arrived in, and whether the stream is withheld (``muted``: the link stays, no frames)."""

    def __init__(self) -> None:
        self.received = bytearray()
        self.commands: list[Received] = []
        self.muted = False
        self.closed = threading.Event()
        self._lock = threading.RLock()

    def opcodes(self) -> list[int]:
        with self._lock:
            return [r.command.opcode for r in self.commands]

    def wait_until(self, predicate: Callable[[Any], bool], timeout: float = HANG_S) -> bool:
        """Whether ``predicate`` of the robot came true within ``timeout`` s (each double's own)."""
        raise NotImplementedError

    def ended_with(self, stop: bytes) -> bool:
        """Whether ``stop`` is the last the host wrote, but for the Query Lists that ask
        whether the robot heard it (``robot.discovery.PROBE_QUERY``, written by
        ``robot.ending.asked_after``). The safe stop asks so when the quiet after the stop
        shows nothing: the robot had sent no frame for over three stream periods before it.
        A robot double whose thread a loaded machine held that long before the stop had its
        stop asked after, answered and confirmed: the bytes ended with the query, not the
        stop (1 of 6 rounds beside two busy loops)."""
        with self._lock:
            written = bytes(self.received)
        while written.endswith(PROBE_QUERY):
            written = written[: -len(PROBE_QUERY)]
        return written.endswith(stop)

    def wait_for_stop(self, stop: bytes, timeout: float = HANG_S) -> None:
        """Wait until :meth:`ended_with` ``stop``; else fail, saying the last bytes the host
        wrote (the query after it, bytes before it, or nothing of it)."""
        if not self.wait_until(lambda robot: robot.ended_with(stop), timeout):
            with self._lock:
                last = list(self.received[-40:])
            raise AssertionError(
                f"the stop {list(stop)} is not the last the robot received (Query Lists "
                f"asking after it aside) within {timeout:g} s; its last bytes: {last}"
            )

    def actuator_commands_outside_safe_or_full(self) -> list[Received]:
        with self._lock:
            return [
                r
                for r in self.commands
                if r.command.spec.modes <= DRIVING_MODES and r.mode not in DRIVING_MODES
            ]


class FakeRobot(RobotDouble):
    """See the module docstring. Use as a context manager (starts and stops its thread)."""

    def __init__(
        self,
        endpoint: Endpoint,
        profile: RobotProfile = CREATE2,
        *,
        plus_one: bool = False,
        silent: bool = False,
    ) -> None:
        super().__init__()
        self.endpoint = endpoint
        self.profile = profile
        self.plus_one = plus_one
        self.silent = silent
        self.mode = OIMode.OFF
        self.values: dict[int, int] = {}
        self.unknown_bytes = 0
        self.streaming = False
        self.stream_ids: tuple[int, ...] = ()
        self.frames_sent = 0
        self._pending = bytearray()
        self._inject = bytearray()
        self._changed = threading.Condition(self._lock)
        self._running = True
        self._thread = threading.Thread(target=self._run, name="fake robot", daemon=True)

    # ---------------------------------------------------------------- lifecycle
    def __enter__(self) -> FakeRobot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def stop(self) -> None:
        self._running = False
        self.endpoint.close()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(HANG_S)  # told to stop: ends within a frame, idle

    # ---------------------------------------------------------------- scripting
    def fall_to_passive(self, values: dict[int, int]) -> None:
        """Safe -> Passive by itself, with the sensor values that caused it (once the robot
        has taken the mode and stream commands already on their way)."""
        assert self.wait_until(lambda r: r.streaming and r.mode in DRIVING_MODES)
        with self._lock:
            self.values.update(values)
            self.mode = OIMode.PASSIVE

    def set_values(self, values: dict[int, int]) -> None:
        with self._lock:
            self.values.update(values)

    def inject(self, data: bytes) -> None:
        """Bytes the "firmware" prints into the stream before the next frame (a banner)."""
        with self._lock:
            self._inject += data

    def hang_up(self) -> None:
        """The cable is pulled: the link closes under the connection."""
        self._running = False
        self.endpoint.hang_up()

    def wait_until(self, predicate: Callable[[FakeRobot], bool], timeout: float = HANG_S) -> bool:
        deadline = time.monotonic() + timeout
        with self._changed:
            while not predicate(self):
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(left)
        return True

    # ---------------------------------------------------------------- the robot
    def _reported_mode(self) -> int:
        return int(self.mode) + (1 if self.plus_one else 0)

    def _sensor_values(self) -> dict[int, int]:
        values = dict(self.values)
        values[35] = self._reported_mode()
        return values

    def _run(self) -> None:
        next_frame = time.monotonic() + SLOT
        try:
            while self._running:
                wait = max(0.0, next_frame - time.monotonic())
                try:
                    data = self.endpoint.wait_read(wait)
                except (OSError, ValueError):  # closed under the read by stop or hang_up
                    break
                if data:
                    self._take(data)
                now = time.monotonic()
                if now >= next_frame:
                    self._send_frame()
                    next_frame += SLOT
                    if next_frame < now:
                        next_frame = now + SLOT
        except OSError:
            pass
        finally:
            self.closed.set()
            with self._changed:
                self._changed.notify_all()

    def _send_frame(self) -> None:
        with self._lock:
            text, self._inject = bytes(self._inject), bytearray()
        if text:
            self.endpoint.send(text)
        with self._lock:
            if not (self.streaming and self.stream_ids) or self.muted or self.mode is OIMode.OFF:
                return
            layout = layout_for(self.stream_ids, self.profile, True)
            frame = layout.stream_frame(
                self._sensor_values(), include_header=self.profile.checksum_includes_header
            )
            self.frames_sent += 1
        self.endpoint.send(frame)

    def _take(self, data: bytes) -> None:
        replies = bytearray()
        with self._changed:
            self.received += data
            self._pending += data
            while self._pending:
                try:
                    decoded = decode_command(self._pending)
                except OIError:
                    self.unknown_bytes += 1
                    del self._pending[:1]
                    continue
                if decoded is None:
                    break
                command, size = decoded
                del self._pending[:size]
                self.commands.append(Received(self.mode, command, time.monotonic()))
                replies += self._apply(command)
            self._changed.notify_all()
        if replies and not self.silent:
            self.endpoint.send(bytes(replies))

    def _apply(self, command: Command) -> bytes:
        """Change state for ``command``; return the reply bytes, if any."""
        opcode = command.opcode
        if self.mode is OIMode.OFF and opcode != 128:
            return b""  # the OI listens for Start only
        spec = command.spec
        if spec.leads_to is not None:
            self.mode = spec.leads_to
            if self.mode is OIMode.OFF:
                self.streaming = False
            return b""
        if opcode == 148:
            self.stream_ids = tuple(command.args[1:])
            self.streaming = bool(self.stream_ids)
        elif opcode == 150:
            self.streaming = bool(command.args[0])
        elif opcode in (142, 149):
            ids = (command.args[0],) if opcode == 142 else tuple(command.args[1:])
            return layout_for(ids, self.profile, False).pack(self._sensor_values())
        return b""
