"""The robot connection: start-up, the sensor stream, guarded commands, and a safe stop.

One :class:`Connection` owns one :class:`~roomba_bt.transport.Transport` and one
:class:`~roomba_bt.robot.modes.ModeModel`. Everything that leaves goes through the guard:

    command ──► ModeModel.check ──► Command.data (encoded, range-checked) ──► transport.write
                 (refused: ModeError,                                   then ModeModel.apply
                  nothing written)

Start-up (:meth:`Connection.start`)::

    [128]                 Start: the OI leaves Off for Passive
    [150][0]              pause a stream a previous session may have left running
    [149][1][35]          Query List, packet 35: the robot answers one byte (its mode), which
                          proves it listens at this baud and calibrates the "mode + 1" rule
    [131] or [132]        Safe or Full, if asked
    [148][n][ids...]      the stream, checked against the bandwidth before it is sent

Every ending (:meth:`Connection.close`, the context manager, :meth:`safe_stop`)::

    [137][0][0][0][0]     drive 0            } only while the model is in Safe or Full: in
    [138][0]              motors off         } Passive and Off the robot refuses actuators
    [150][0]              pause the stream
    [128]  or  [173]      Start (back to Passive) or, with end_in="stop" where the profile
                          has it, Stop (Off)

Reading happens in the caller's thread (:meth:`poll`), which is what the runtime uses: no
thread hop between a frame's arrival and the tick that reads it, and on the simulator's
virtual clock the caller's reads are what drive time. :meth:`start_reader` adds an optional
background reader for consumers that want to block on :meth:`wait_for_frame`. See
``docs/robot.md``.
"""

from __future__ import annotations

import contextlib
import enum
import logging
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple

import serial

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import BAUD_RATES, Command
from roomba_bt.oi.errors import UnsupportedCommandError
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.opcodes import Effect
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile, get_profile
from roomba_bt.oi.stream import ReplyParser, StreamParser, check_bandwidth
from roomba_bt.robot.errors import (
    ConnectionFailed,
    ModeError,
    PortLost,
    RobotError,
    StreamStalled,
)
from roomba_bt.robot.interface import SLOT_SECONDS, ModeChange
from roomba_bt.robot.modes import DEFAULT_SETTLE, ModeModel
from roomba_bt.transport.base import Transport, TransportError
from roomba_bt.transport.serial_port import DEFAULT_BAUD, SerialTransport

log = logging.getLogger(__name__)

#: What breaking a link raises, from our transport, pyserial, sockets or the simulator.
LINK_ERRORS = (OSError, serial.SerialException)
#: What a stop or a reconnect attempt may meet and must survive.
_RECOVERABLE = (RobotError, OSError, serial.SerialException)
#: The spec asks for 100 ms after Baud (129) before sending at the new rate.
BAUD_CHANGE_WAIT = 0.1
#: How long the input must stay quiet after pausing a stale stream, before the confirm query.
DRAIN_QUIET = 2 * SLOT_SECONDS
DRAIN_LIMIT = 0.25
NO_ANSWER_CAUSES = (
    "wrong baud rate (115200 by default; 19200 after holding Clean at power-off or a BRC pulse)",
    "no power or the robot asleep (press Clean or the power button)",
    "wrong cable or wiring (TX/RX swapped, adapter not a 5 V TTL serial)",
)
OPEN_CAUSES = ("wrong device path or URL", "the port in use by another program", "permissions")

EndMode = Literal["passive", "stop"]


class LinkStatus(enum.Enum):
    """Where the link stands; :attr:`Connection.status`."""

    OPEN = "open"  # port open, no stream running
    STREAMING = "streaming"
    STALLED = "stalled"  # the watchdog tripped; frames may come back
    LOST = "lost"  # the port raised: reconnect or give up
    STOPPED = "stopped"  # safe stop sent
    CLOSED = "closed"


class TimedFrame(NamedTuple):
    """A checked stream frame, when it arrived (link clock) and its number in the stream.

    A named tuple (immutable, built once per frame on the tick path, several times faster
    than a frozen dataclass). ``index`` is the frame's number, not ``tuple.index``: the
    field's name predates the tuple and is kept."""

    frame: SensorFrame
    time: float
    index: int  # type: ignore[assignment]


@dataclass(frozen=True, slots=True)
class LinkCounters:
    """Counters since the connection was made (across stream restarts)."""

    frames: int = 0
    checksum_failures: int = 0
    skipped_bytes: int = 0
    gaps: int = 0
    bytes_read: int = 0
    bytes_written: int = 0
    commands_sent: int = 0
    commands_refused: int = 0
    watchdog_trips: int = 0
    mode_readings_ignored: int = 0


class GapCounter:
    """Missing 15 ms slots, estimated from frame arrival times.

    Frames may arrive in bursts (the OS buffers them while the caller is busy), so single
    inter-arrival times lie. Inside a window of about a second the count is cumulative:
    slots elapsed since an anchor frame minus frames received since it, never below zero; at
    the end of a window that count is kept and the last frame becomes the new anchor, so the
    robot's and the host's clocks cannot drift apart into false gaps.
    """

    __slots__ = ("_anchor", "_locked", "_open", "_since_anchor", "slot", "window")

    def __init__(self, slot: float = SLOT_SECONDS, window: float = 1.0) -> None:
        self.slot = slot
        self.window = window
        self._anchor: float | None = None
        self._since_anchor = 0
        self._locked = 0
        self._open = 0

    @property
    def gaps(self) -> int:
        return self._locked + self._open

    def reset(self) -> None:
        """A new stream: the next frame is a new anchor, gaps so far are kept."""
        self._locked += self._open
        self._open = 0
        self._anchor = None

    def observe(self, arrival: float, count: int) -> int:
        """``count`` frames completed at ``arrival``; return the total gaps."""
        if count <= 0:
            return self.gaps
        if self._anchor is None:
            self._anchor, self._since_anchor = arrival, 0
            return self.gaps
        self._since_anchor += count
        elapsed = round((arrival - self._anchor) / self.slot)
        self._open = max(0, elapsed - self._since_anchor)
        if arrival - self._anchor >= self.window:
            self._locked += self._open
            self._open = 0
            self._anchor, self._since_anchor = arrival, 0
        return self.gaps


@dataclass(frozen=True, slots=True)
class ReconnectPolicy:
    """Reconnect with exponential backoff: ``initial``, ``initial*factor``... capped at
    ``maximum`` seconds, ``attempts`` tries (None: forever). The runtime opts in."""

    initial: float = 0.1
    factor: float = 2.0
    maximum: float = 5.0
    attempts: int | None = 10

    def delays(self) -> Iterator[float]:
        delay = self.initial
        tries = 0
        while self.attempts is None or tries < self.attempts:
            yield delay
            tries += 1
            delay = min(delay * self.factor, self.maximum)


def _as_mode(mode: OIMode | str) -> OIMode:
    if isinstance(mode, OIMode):
        return mode
    try:
        return OIMode[mode.upper()]
    except KeyError:
        raise ValueError(f"unknown OI mode {mode!r}; use passive, safe or full") from None


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM while a stop sequence is written, so it leaves whole."""
    blockable = {signal.SIGINT, signal.SIGTERM}
    try:
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blockable)
    except (AttributeError, OSError, ValueError):  # not POSIX: nothing to hold
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


class Connection:
    """A robot on a :class:`~roomba_bt.transport.Transport`: see the module docstring.

    ``watchdog``: seconds without a valid frame (while a stream runs) before drive 0 is sent
    and :class:`StreamStalled` raised; 0 disables it. ``end_in``: ``"passive"`` (Start) or
    ``"stop"`` (Stop 173, on profiles that have it) on every ending.
    """

    def __init__(
        self,
        transport: Transport,
        profile: RobotProfile | str = DEFAULT_PROFILE,
        *,
        watchdog: float = 0.1,
        end_in: EndMode = "passive",
        settle: float = DEFAULT_SETTLE,
        baud: int | None = None,
        reopen: Callable[[], Transport] | None = None,
    ) -> None:
        if end_in not in ("passive", "stop"):
            raise ValueError(f"end_in must be 'passive' or 'stop', got {end_in!r}")
        if watchdog < 0:
            raise ValueError(f"watchdog must be >= 0 seconds, got {watchdog!r}")
        self.transport = transport
        self.profile = get_profile(profile) if isinstance(profile, str) else profile
        self.watchdog = watchdog
        self.end_in: EndMode = end_in
        self.settle = settle
        self.baud = baud if baud is not None else int(getattr(transport, "baud", DEFAULT_BAUD))
        self._reopen = reopen
        if end_in == "stop" and not self.profile.has_command("stop"):
            log.warning(
                "%s has no Stop (173); the connection will end in Passive (Start)",
                self.profile.title,
            )
        # One lock for the mode model and the stream state: the reader thread reconciles
        # frames while the caller sends; neither may see the other's half-done update.
        self._write_lock = threading.RLock()
        self._state = threading.Condition(self._write_lock)
        self.modes = ModeModel(self.profile, settle=settle)
        self._parser: StreamParser | None = None
        self._stream_ids: tuple[int, ...] = ()
        self._streaming = False
        self._stream_started = 0.0
        self._last_frame_time: float | None = None
        self._latest: TimedFrame | None = None
        self._index = 0
        self._gaps = GapCounter()
        self._parsed_before = (0, 0, 0)  # frames, checksum failures, skipped: older parsers
        self._bytes_read = 0
        self._bytes_written = 0
        self._sent = 0
        self._refused = 0
        self._trips = 0
        self._status = LinkStatus.OPEN if transport.is_open else LinkStatus.CLOSED
        self._closed = False
        self.safe_stopped: bool | None = None
        self._builtin_may_run = False  # a Clean/Spot/Max/Seek Dock cycle may be driving
        self._start_args: tuple[OIMode, tuple[int, ...], float] | None = None
        self._reader: threading.Thread | None = None
        self._reader_stop = threading.Event()
        self._reader_queue: list[TimedFrame] = []
        self._reader_error: BaseException | None = None

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(
        cls,
        url: str,
        baud: int = DEFAULT_BAUD,
        profile: RobotProfile | str = DEFAULT_PROFILE,
        *,
        watchdog: float = 0.1,
        end_in: EndMode = "passive",
        write_timeout: float = 0.5,
    ) -> Connection:
        """Open ``url`` (device path, ``socket://``, ``rfc2217://``, ``loop://``)."""

        def reopen() -> Transport:
            return SerialTransport.open(url, baud, write_timeout=write_timeout)

        try:
            transport = reopen()
        except TransportError as exc:
            raise ConnectionFailed(
                url, f"could not open the port ({exc.cause})", OPEN_CAUSES
            ) from exc
        return cls(transport, profile, watchdog=watchdog, end_in=end_in, baud=baud, reopen=reopen)

    @property
    def name(self) -> str:
        return self.transport.name

    def start(
        self,
        mode: OIMode | str = OIMode.SAFE,
        packets: Sequence[int] = (),
        confirm_timeout: float = 1.0,
    ) -> None:
        """Wake the OI, confirm the robot answers, enter ``mode``, start the stream.

        The stream request is checked (packet ids, bandwidth at :attr:`baud`) before a byte
        is sent. Raises :class:`ConnectionFailed` if the robot does not answer in
        ``confirm_timeout`` seconds.
        """
        if self._reader is not None:
            raise RobotError("start() reads the robot's reply itself: call it before start_reader")
        target = _as_mode(mode)
        if target is OIMode.OFF:
            raise ValueError("start() enters Passive, Safe or Full; use close() to end in Off")
        ids = tuple(packets)
        stream_command = oi.stream(ids) if ids else None
        if ids:
            check_bandwidth(ids, self.baud)
        self._start_args = (target, ids, confirm_timeout)
        self._closed = False
        self.safe_stopped = None
        self.send(oi.start())
        self.send(oi.pause_stream())
        self._streaming = False
        self._drain()
        reply = self.query((OI_MODE_PACKET,), confirm_timeout)
        if reply is None:
            raise ConnectionFailed(
                self.name,
                f"the robot did not answer a Query List (149) for packet 35 within "
                f"{confirm_timeout:g} s",
                NO_ANSWER_CAUSES,
            )
        if self.modes.mode is not OIMode.PASSIVE or self.modes.plus_one is None:
            raise ConnectionFailed(
                self.name,
                f"the robot answered {reply[OI_MODE_PACKET]} for its OI mode right after Start, "
                f"which is no mode (Passive reads 1, or 2 on firmware that reports mode + 1)",
                (*NO_ANSWER_CAUSES[:1], "another program talking to the robot"),
            )
        if target is OIMode.SAFE:
            self.send(oi.safe())
        elif target is OIMode.FULL:
            self.send(oi.full())
        if stream_command is not None:
            self.send(stream_command)
        log.info(
            "%s: %s in %s, streaming %s", self.name, self.profile.title, target.label, list(ids)
        )

    def _drain(self) -> None:
        """Read and drop input until it stays quiet (a stale stream, a reset banner)."""
        clock = self.transport.now
        started = quiet_since = clock()
        while clock() - quiet_since < DRAIN_QUIET and clock() - started < DRAIN_LIMIT:
            if self._read(DRAIN_QUIET / 2):
                quiet_since = clock()

    def query(self, packet_ids: Sequence[int], timeout: float = 1.0) -> SensorFrame | None:
        """Query List (149) for ``packet_ids``; the decoded reply, or None after ``timeout``.

        Only while no stream runs (a reply has no header: it could not be told apart).
        """
        if self._streaming:
            raise RobotError("query() needs the stream paused: a reply cannot be told apart")
        reply = ReplyParser(tuple(packet_ids), self.profile)
        self.send(oi.query_list(packet_ids))
        clock = self.transport.now
        deadline = clock() + timeout
        while True:
            frame = reply.feed(self._read(max(0.0, deadline - clock())))
            if frame is not None:
                now = clock()
                change = self.modes.reconcile(frame, self._index, now)
                if change is not None:
                    self._report_change(change)
                return frame
            if clock() >= deadline:
                return None

    # ------------------------------------------------------------------ reading
    @property
    def status(self) -> LinkStatus:
        return self._status

    @property
    def latest(self) -> TimedFrame | None:
        """The newest checked frame (None before the first)."""
        return self._latest

    @property
    def latest_time(self) -> float | None:
        """Link-clock arrival time of :attr:`latest`."""
        return None if self._latest is None else self._latest.time

    @property
    def mode(self) -> OIMode:
        return self.modes.mode

    @property
    def last_fallback(self) -> ModeChange | None:
        return self.modes.last_fallback

    @property
    def stream_ids(self) -> tuple[int, ...]:
        return self._stream_ids

    @property
    def streaming(self) -> bool:
        return self._streaming

    @property
    def counters(self) -> LinkCounters:
        parser = self._parser.counters if self._parser is not None else None
        frames, checksums, skipped = self._parsed_before
        if parser is not None:
            frames += parser.frames
            checksums += parser.checksum_failures
            skipped += parser.skipped_bytes
        return LinkCounters(
            frames=frames,
            checksum_failures=checksums,
            skipped_bytes=skipped,
            gaps=self._gaps.gaps,
            bytes_read=self._bytes_read,
            bytes_written=self._bytes_written,
            commands_sent=self._sent,
            commands_refused=self._refused,
            watchdog_trips=self._trips,
            mode_readings_ignored=self.modes.invalid_readings,
        )

    def poll(self, timeout: float = 0.0) -> list[TimedFrame]:
        """New frames: what is there now, or wait up to ``timeout`` s for at least one.

        Reads in the caller's thread, reconciles the mode model with every frame, checks
        the watchdog. Raises :class:`PortLost` if the port fails and :class:`StreamStalled`
        once when the watchdog trips (frames coming back clear the stall). With the
        background reader running, returns the frames it queued since the last poll.
        """
        if self._reader is not None:
            return self._take_queued(timeout)
        return self._read_frames(timeout)

    def _read_frames(self, timeout: float) -> list[TimedFrame]:
        clock = self.transport.now
        deadline = clock() + timeout
        out: list[TimedFrame] = []
        while True:
            remaining = deadline - clock()
            data = self._read(max(0.0, remaining))
            if data:
                out += self._ingest(data, clock())
            if out or remaining <= 0:
                break
        self._check_watchdog(clock())
        return out

    def _read(self, timeout: float) -> bytes:
        try:
            data = self.transport.read(timeout)
        except LINK_ERRORS as exc:
            raise self._lost("read", exc) from exc
        self._bytes_read += len(data)
        return data

    def _lost(self, action: str, exc: BaseException) -> PortLost:
        self._status = LinkStatus.LOST
        self._streaming = False
        cause = exc.cause if isinstance(exc, TransportError) else exc
        return PortLost(self.name, f"the port failed on {action} ({cause}); the link is lost")

    def _ingest(self, data: bytes, arrival: float) -> list[TimedFrame]:
        if self._parser is None:
            return []
        with self._state:
            frames = self._parser.feed(data)
            if not frames:
                return []
            out: list[TimedFrame] = []
            reconcile = self.modes.reconcile
            index = self._index
            for frame in frames:
                index += 1
                change = reconcile(frame, index, arrival)
                if change is not None:
                    self._report_change(change)
                out.append(TimedFrame(frame, arrival, index))
            self._index = index
            self._latest = out[-1]
            self._last_frame_time = arrival
            self._gaps.observe(arrival, len(out))
            if self._status is LinkStatus.STALLED:
                log.warning("%s: the sensor stream is back", self.name)
                self._status = LinkStatus.STREAMING
            if self._reader is not None:  # only the reader's consumers wait on it
                self._state.notify_all()
            return out

    def _report_change(self, change: ModeChange) -> None:
        log.warning(
            "%s: the robot went from %s to %s by itself (%s)",
            self.name,
            change.previous.label,
            change.current.label,
            change.cause,
        )

    def _check_watchdog(self, now: float) -> None:
        if not self._streaming or self.watchdog <= 0 or self._status is not LinkStatus.STREAMING:
            return
        reference = self._last_frame_time
        if reference is None:
            reference = self._stream_started
        silent = now - reference
        if silent <= self.watchdog:
            return
        self._status = LinkStatus.STALLED
        self._trips += 1
        halted = self._halt()
        error = StreamStalled(self.name, silent, self.watchdog, halted)
        log.error("%s", error)
        raise error

    def _halt(self) -> bool:
        """Drive 0 if the model says the robot may be driving; True if it was sent."""
        if self.modes.mode not in DRIVING_MODES:
            return False
        self.send(oi.halt())
        return True

    # ------------------------------------------------------------------ reader thread
    def start_reader(self, read_timeout: float = 0.01) -> None:
        """Read in a background thread; :meth:`poll` then returns what it queued and
        :meth:`wait_for_frame` blocks on it. The watchdog is checked by the thread too.

        Not for the simulator's in-process link: its reads drive the virtual clock, so they
        belong to the caller that owns time.
        """
        if self._reader is not None:
            return
        self._reader_stop.clear()
        self._reader_error = None
        thread = threading.Thread(
            target=self._reader_loop, args=(read_timeout,), name=f"roomba-bt reader {self.name}",
            daemon=True,
        )  # fmt: skip
        self._reader = thread
        thread.start()

    def stop_reader(self, timeout: float = 1.0) -> None:
        thread, self._reader = self._reader, None
        if thread is None:
            return
        self._reader_stop.set()
        if thread is not threading.current_thread():
            thread.join(timeout)

    def _reader_loop(self, read_timeout: float) -> None:
        while not self._reader_stop.is_set():
            try:
                frames = self._read_frames(read_timeout)
            except StreamStalled as exc:
                self._post_error(exc)
                continue
            except BaseException as exc:  # handed to the consumer's thread
                self._post_error(exc)
                return
            if frames:
                with self._state:
                    self._reader_queue += frames
                    self._state.notify_all()

    def _post_error(self, exc: BaseException) -> None:
        with self._state:
            self._reader_error = exc
            self._state.notify_all()

    def _raise_reader_error(self) -> None:
        error, self._reader_error = self._reader_error, None
        if error is not None:
            raise error

    def _take_queued(self, timeout: float) -> list[TimedFrame]:
        with self._state:
            if not self._reader_queue and self._reader_error is None and timeout > 0:
                self._state.wait_for(
                    lambda: bool(self._reader_queue) or self._reader_error is not None, timeout
                )
            self._raise_reader_error()
            out, self._reader_queue = self._reader_queue, []
            return out

    def wait_for_frame(self, timeout: float = 1.0) -> TimedFrame | None:
        """The next frame to arrive after this call, or None after ``timeout`` seconds."""
        last = self._index
        if self._reader is None:
            clock = self.transport.now
            deadline = clock() + timeout
            while True:
                frames = self._read_frames(max(0.0, deadline - clock()))
                if frames:
                    return frames[0]
                if clock() >= deadline:
                    return None
        with self._state:
            self._state.wait_for(
                lambda: self._index > last or self._reader_error is not None, timeout
            )
            self._raise_reader_error()
            latest = self._latest
            return latest if latest is not None and latest.index > last else None

    # ------------------------------------------------------------------ writing
    def send(self, command: Command) -> None:
        """Guard, then write ``command``'s bytes, then update the mode model.

        A refused command raises (:class:`ModeError`,
        :class:`~roomba_bt.oi.errors.UnsupportedCommandError`,
        :class:`~roomba_bt.oi.errors.BandwidthError` for a stream that does not fit) and
        nothing is written.
        """
        with self._write_lock:
            self._send(command, None)

    def send_many(self, commands: Iterable[Command]) -> None:
        """A tick's outbox, in order, in one write. Each command is guarded against the mode
        the commands before it lead to (so ``safe`` then ``drive`` passes). Refused commands
        are left out; after the others are written the first refusal is raised."""
        refused: list[Exception] = []
        with self._write_lock:
            batch = bytearray()
            try:
                for command in commands:
                    try:
                        self._send(command, batch)
                    except (ModeError, UnsupportedCommandError) as exc:
                        refused.append(exc)
            finally:
                if batch:
                    self._write(bytes(batch))
        if refused:
            for extra in refused[1:]:
                log.warning("%s: also refused: %s", self.name, extra)
            raise refused[0]

    def _send(self, command: Command, batch: bytearray | None) -> None:
        spec = command.spec
        try:
            self.modes.check(command)
        except (ModeError, UnsupportedCommandError):
            self._refused += 1
            raise
        if spec.effect is Effect.STREAM:
            check_bandwidth(command.args[1:], self.baud)
        warning = self.profile.command_warning(spec)
        if warning is not None:
            log.warning("%s: %s", self.name, warning)
        if batch is None or spec.effect is Effect.BAUD:  # the rest goes at the new rate
            if batch:
                self._write(bytes(batch))
                batch.clear()
            self._write(command.data)
        else:
            batch += command.data
        now = self.transport.now()
        self.modes.apply(command, now)
        self._sent += 1
        self._after(command, now)

    def _write(self, data: bytes) -> None:
        try:
            self.transport.write(data)
        except LINK_ERRORS as exc:
            raise self._lost("write", exc) from exc
        self._bytes_written += len(data)

    def _after(self, command: Command, now: float) -> None:
        """What a written command changes on our side of the link (the opcode table's
        :class:`~roomba_bt.oi.opcodes.Effect` and mode)."""
        spec = command.spec
        effect = spec.effect
        if effect is Effect.STREAM:
            self._new_stream(tuple(command.args[1:]), now)
        elif effect is Effect.PAUSE_RESUME:
            self._streaming = bool(command.args[0]) and bool(self._stream_ids)
            self._stream_started = now
            self._last_frame_time = None
            if self._streaming:
                self._status = LinkStatus.STREAMING
        elif effect is Effect.SILENCES:
            self._streaming = False
        if effect is Effect.BUILTIN_CYCLE:
            self._builtin_may_run = True
        elif spec.ends_cycle:
            self._builtin_may_run = False
        elif effect is Effect.BAUD:
            self._change_baud(BAUD_RATES[command.args[0]])

    def _new_stream(self, ids: tuple[int, ...], now: float) -> None:
        with self._state:
            if self._parser is not None:
                c = self._parser.counters
                frames, checksums, skipped = self._parsed_before
                self._parsed_before = (
                    frames + c.frames,
                    checksums + c.checksum_failures,
                    skipped + c.skipped_bytes,
                )
            self._stream_ids = ids
            self._parser = StreamParser(ids, self.profile) if ids else None
            self._streaming = bool(ids)
            self._stream_started = now
            self._last_frame_time = None
            self._gaps.reset()
            self._status = LinkStatus.STREAMING if ids else LinkStatus.OPEN

    def _change_baud(self, rate: int) -> None:
        """Baud (129) was written: wait the 100 ms the spec asks (reading, so the link's
        clock moves on a virtual link too), then change the port's rate."""
        clock = self.transport.now
        deadline = clock() + BAUD_CHANGE_WAIT
        while (remaining := deadline - clock()) > 0:
            data = self._read(remaining)
            if data:
                self._ingest(data, clock())
        try:
            self.transport.set_baud(rate)
        except LINK_ERRORS as exc:
            raise self._lost("baud change", exc) from exc
        self.baud = rate
        if self._parser is not None:
            self._new_stream(self._stream_ids, clock())

    def set_baud(self, rate: int) -> None:
        """Baud (129) by rate (e.g. 19200); the port follows after 100 ms."""
        if self._stream_ids:
            check_bandwidth(self._stream_ids, rate)
        self.send(oi.baud_rate(rate))

    # ------------------------------------------------------------------ endings
    def stop_sequence(self) -> list[Command]:
        """What :meth:`safe_stop` sends from the current mode (see the module docstring)."""
        mode = self.modes.mode
        if mode is OIMode.OFF:
            return []
        commands: list[Command] = []
        if mode is OIMode.PASSIVE and self._builtin_may_run:
            # Clean, Spot, Max or Seek Dock drive the robot in Passive, where drive 0 is not
            # accepted; Safe (131) ends the cycle and makes drive 0 and motors off possible.
            commands.append(oi.safe())
            mode = OIMode.SAFE
        if mode in DRIVING_MODES:
            commands += [oi.halt(), oi.motors_off()]
        commands.append(oi.pause_stream())
        use_stop = self.end_in == "stop" and self.profile.has_command("stop")
        commands.append(oi.stop() if use_stop else oi.start())
        return commands

    def safe_stop(self) -> bool:
        """Stop the robot and leave it in Passive (or Off with ``end_in="stop"``).

        Never raises for a dead link: returns False and logs that the robot could not be
        stopped (writes are bounded by the transport's write timeout, so this cannot hang).
        """
        if not self.transport.is_open:
            log.error("%s: the port is closed; could not stop the robot", self.name)
            self.safe_stopped = False
            return False
        lost = self._status is LinkStatus.LOST
        try:
            with _signals_deferred():
                self.send_many(self.stop_sequence())
            if lost:
                raise PortLost(self.name, "the link was lost before the stop: it is unconfirmed")
        except _RECOVERABLE as exc:
            log.error(
                "%s: could not stop the robot (%s); it may still be in %s mode",
                self.name,
                exc,
                self.modes.mode.label,
            )
            self.safe_stopped = False
            return False
        self._streaming = False
        self._status = LinkStatus.STOPPED
        self.safe_stopped = True
        return True

    def close(self) -> bool:
        """Safe stop (once), stop the reader, close the port. True if the robot was stopped
        (or never started); idempotent."""
        if self._closed:
            return bool(self.safe_stopped)
        self._closed = True
        stopped = True
        if self.safe_stopped is True:
            pass  # already stopped: a second stop sequence would only add bytes
        elif self.modes.mode is not OIMode.OFF:  # safe_stop reports a port already gone
            stopped = self.safe_stop()
        self.stop_reader()
        self.transport.close()
        self._status = LinkStatus.CLOSED
        if self.safe_stopped is None:
            self.safe_stopped = stopped
        return stopped

    def __enter__(self) -> Connection:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ------------------------------------------------------------------ reconnect
    def reconnect(
        self, policy: ReconnectPolicy | None = None, sleep: Callable[[float], None] = time.sleep
    ) -> int:
        """Reopen the port and repeat :meth:`start` with the same arguments, backing off
        between attempts; return the attempt that worked. Needs a connection made by
        :meth:`open` (or given ``reopen``) and started once. The mode model starts afresh
        (the robot is in whatever mode Start leaves it); a background reader is stopped and
        must be started again."""
        if self._reopen is None or self._start_args is None:
            raise RobotError("reconnect() needs Connection.open(...) (or reopen=) and a start()")
        policy = policy or ReconnectPolicy()
        mode, ids, confirm = self._start_args
        last: BaseException | None = None
        attempt = 0
        for attempt, delay in enumerate(policy.delays(), 1):
            sleep(delay)
            self.stop_reader()
            self.transport.close()
            try:
                self.transport = self._reopen()
                self._reset_link()
                self.start(mode, ids, confirm)
            except _RECOVERABLE as exc:
                last = exc
                log.warning("%s: reconnect attempt %d failed: %s", self.name, attempt, exc)
                continue
            log.info("%s: reconnected on attempt %d", self.name, attempt)
            return attempt
        raise ConnectionFailed(
            self.name, f"could not reconnect after {attempt} attempts (last: {last})"
        )

    def _reset_link(self) -> None:
        self.modes = ModeModel(self.profile, settle=self.settle)
        self._parser = None
        self._stream_ids = ()
        self._streaming = False
        self._last_frame_time = None
        self._gaps.reset()
        self._status = LinkStatus.OPEN
        self._closed = False
