"""The robot connection, the session half: one robot's session over one link.

One :class:`Connection` keeps one :class:`~roomba_bt.robot.modes.ModeModel` and drives one
:class:`~roomba_bt.robot.link.StreamLink` (the transport's bytes, the stream parser, the
watchdog). The session's parts, each beside its state::

    Connection ─┬─ StreamLink     robot/link.py     bytes, frames, the watchdog
                ├─ ModeModel      robot/modes.py    the OI mode predicted and reconciled
                ├─ CommandWriter  robot/writer.py   the guard, a tick's batch, each opcode's
                │                                   effect, Baud change (the command path)
                ├─ SafeStop       robot/ending.py   every ending: the stop sequence, whether
                │                                   it arrived, the port closed once
                └─ KeepAwake      robot/wake.py     BRC pulses where the profile sleeps

What is left here is the glue: start-up (:meth:`Connection.start`: Start, the robot's mode
asked twice, the mode, the stream; drawn in :mod:`~roomba_bt.robot.startup`), a Query List,
reading (:meth:`Connection.poll`, and why a stream stopped, :mod:`~roomba_bt.robot.silence`),
and the read-only views the runtime and the tests use (``name``, ``status``, ``counters``...).

Frames are read in the caller's thread (:meth:`poll`). See ``docs/robot.md``.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import weakref
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import BAUD_CODES, COMMAND_WANTED, Command, turns_wheels
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile, profile_given
from roomba_bt.oi.stream import ReplyParser, check_bandwidth, stream_period
from roomba_bt.robot.discovery import drain
from roomba_bt.robot.ending import EndMode, SafeStop, link_round_trip
from roomba_bt.robot.errors import (
    DEFAULT_WATCHDOG,
    ConnectionClosed,
    ModeError,
    NoAnswer,
    PortLost,
    RobotError,
    RobotReset,
    StreamStalled,
)
from roomba_bt.robot.interface import UNKNOWN_CAUSE, ModeChange
from roomba_bt.robot.link import LinkStatus, StreamLink, TimedFrame
from roomba_bt.robot.modes import DEFAULT_SETTLE, ModeModel
from roomba_bt.robot.silence import (
    _stop_heard,
    another_model,
    answers_elsewhere,
    asleep_by_idle,
    bytes_lost_said,
    dead_connection,
    explain_silence,
    follow_baud,
    garbled_line,
)
from roomba_bt.robot.stall_asks import StallAsks, ask_in_stall
from roomba_bt.robot.startup import (
    NO_ANSWER_CAUSES,
    STREAM_ASKS_AGAIN,
    ModeName,
    agreed_mode_reply,
    as_mode,
    no_answer_causes,
    not_a_mode,
    port_not_opened,
    stream_zeros,
)
from roomba_bt.robot.wake import KeepAwake, keep_awake_for, named_stall
from roomba_bt.robot.weak import weakly
from roomba_bt.robot.writer import RESYNC_ZEROS, CommandWriter
from roomba_bt.transport.base import Transport, TransportError
from roomba_bt.transport.link_kind import link_of
from roomba_bt.transport.serial_port import DEFAULT_BAUD, SerialTransport

__all__ = [
    "no_answer_causes",  # where the CLI has them from
    "NO_ANSWER_CAUSES",  # 0.1.0's, a device path's
    "port_not_opened",
    "Connection",
    "EndMode",
    "LinkCounters",
    "LinkStatus",
    "TimedFrame",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class LinkCounters:
    """Counters since the connection was made (across stream restarts)."""

    frames: int = 0
    checksum_failures: int = 0
    #: frames that passed the checksum with a value out of range (dropped like a failure)
    implausible_frames: int = 0
    skipped_bytes: int = 0
    bytes_read: int = 0
    bytes_written: int = 0
    commands_sent: int = 0
    commands_refused: int = 0
    watchdog_trips: int = 0
    mode_readings_ignored: int = 0


#: Connections not yet garbage: closed at the program's end if their user did not.
_LIVE: weakref.WeakSet[Connection] = weakref.WeakSet()


@atexit.register
def _close_at_exit() -> None:
    for connection in list(_LIVE):
        with contextlib.suppress(Exception):
            stop_left_open(connection.ending, "the program ended without close()")


def stop_left_open(ending: SafeStop, why: str) -> None:
    """The safe stop and close for a started session nobody closed: a library user's
    script that ended, or dropped its connection, left the robot driving in Safe.

    It takes the session's ending alone (its writer, link and port), never the connection:
    run when the connection is garbage, by a :func:`weakref.finalize` that holds ``ending``,
    the port is still referenced and open. From the connection's ``__del__`` in a collector
    pass, pyserial's own finalizer had closed the port first ("the stop was not delivered:
    the port is gone") and the robot drove on."""
    if ending.closed:
        return
    writer = ending.writer
    if writer.modes.mode not in DRIVING_MODES and writer.running_cycle is None:
        return  # never started, or stopped in Passive: nothing of ours can be moving
    doing = ending.activity()
    stopped = ending.close()
    if stopped:
        fate = "the safe stop was sent"
    elif ending.written:  # the line before says why it is not known to have arrived
        fate = "the safe stop was written, but its arrival is unconfirmed (said above)"
    else:
        fate = "the safe stop could not be delivered"
    log.warning(
        "%s: %s (the robot %s); %s (use `with Connection.open(...)` or call close())",
        writer.link.name, why, doing, fate,
    )  # fmt: skip


def _stop_dropped(ending: SafeStop) -> None:
    """A connection became garbage (its finalizer, :func:`stop_left_open`); it may run in
    any thread, and a finalizer's error could only be printed, never handled."""
    with contextlib.suppress(Exception):
        stop_left_open(ending, "the connection was dropped without close()")


# Long on purpose (a line past the guide's 400): the session's facade, where a program finds
# the robot's state, each part in its own module (link.py, writer.py, ending.py, startup.py,
# silence.py); what stays here is the start-up, the reads and one-line views of the parts.
class Connection:
    """One robot's session on a :class:`~roomba_bt.transport.Transport`: start it, read its
    sensors, send it commands, stop it. pycreate2's ``Create2(port)``, ``start()`` and
    ``safe()``, ``drive_direct(r, l)`` and ``get_sensors()`` are :meth:`open`,
    ``start("safe", packets)``, ``send(commands.drive_direct(r, l))`` (mm/s, the right wheel
    first, as the OI and pycreate2 take them) and :meth:`poll` (the frames the stream sent)
    or :meth:`query` (a Query List, no stream). Every ending stops the robot and leaves it in
    Passive: :meth:`close`, the end of a ``with`` block (an exception in it too), the object
    dropped, or the program's end without either (then with a warning)::

        >>> import roomba_bt
        >>> from roomba_bt import commands
        >>> world = roomba_bt.load_world("empty-room")
        >>> link = roomba_bt.SimLink(roomba_bt.Simulator(world, roomba_bt.CREATE2, seed=0))
        >>> with roomba_bt.Connection(link, roomba_bt.CREATE2) as robot:  # open(port): a robot
        ...     robot.start("safe", packets=(7, 35, 43, 44))  # bumps, mode, encoders
        ...     robot.send(commands.drive_direct(200, 200))
        ...     frames = robot.poll(0.5)  # what came, each frame 15 ms of the robot's
        ...     print(robot.mode, "bumped:", frames[-1].frame.any_bump)
        Safe bumped: False
        >>> print(robot.mode, link.simulator.requested_left)  # the with's end: stopped
        Passive 0.0

    The errors to catch: :class:`ModeError` (a command the mode refuses, nothing written),
    :class:`StreamStalled` (no frame for ``watchdog`` s: drive 0 sent if it drove; a loop that
    rides stalls through catches it), :class:`LinkDown` (the port or the stream lost),
    :class:`ConnectionFailed` (not opened, or no answer), all ``roomba_bt.RoombaBtError``.

    ``watchdog``: seconds without a valid frame (while a stream runs) before drive 0 is sent
    and :class:`StreamStalled` raised; 0 disables it. ``end_in``: ``"passive"`` (Start) or
    ``"stop"`` (Stop 173, on profiles that have it) on every ending.
    """

    def __init__(
        self,
        transport: Transport,
        profile: RobotProfile | str | None = DEFAULT_PROFILE,
        *,
        watchdog: float = DEFAULT_WATCHDOG,
        end_in: EndMode = "passive",
        settle: float = DEFAULT_SETTLE,
        baud: int | None = None,
        keep_awake: bool | None = None,
    ) -> None:
        if end_in not in ("passive", "stop"):
            raise ValueError(f"end_in must be 'passive' or 'stop', got {end_in!r}")
        if watchdog < 0:
            raise ValueError(f"watchdog must be >= 0 seconds, got {watchdog!r}")
        self.profile = profile_given(profile, "Connection")
        self.settle = settle
        if end_in == "stop" and not self.profile.has_command("stop"):
            log.warning(
                "%s has no Stop (173); the connection will end in Passive (Start)",
                self.profile.title,
            )
        self.modes = ModeModel(self.profile, settle=settle)
        self.link = StreamLink(
            transport, self.profile, watchdog=watchdog, reconcile=self.modes.reconcile,
            report=weakly(self._report_change, None), halt=weakly(self.stop_on_stall, False),
            ask_again=weakly(self._stream_again, False),
        )  # fmt: skip
        if baud is None:
            baud = int(getattr(transport, "baud", DEFAULT_BAUD))
        #: the command path (robot/writer.py) and the endings (robot/ending.py)
        self.writer = CommandWriter(self.link, self.modes, self.profile, baud)
        self.ending = SafeStop(self.writer, end_in)
        # Keep-awake (robot/wake.py): on by default where the profile sleeps in Passive.
        self.keep_awake = self.profile.sleeps_in_passive if keep_awake is None else keep_awake
        self.ending.wake = keep_awake_for(transport, self.link.name, self.keep_awake)
        # a stop written through a port that came back is heard if the stream falls quiet
        # and the robot answers, as after a stop at a rate the port followed (silence.py)
        self.ending.port_return.heard = weakly(self._stop_heard, False)
        #: when garbage was last judged (listened at other rates, or noise) and the bytes
        #: read by then (link clock; silence.follow_baud judges again while garbage comes)
        self.baud_listened: tuple[float, int] | None = None
        self._changes_said: Counter[str] = Counter()  # the robot's own falls, by cause
        self._falls: Counter[str] = Counter()  # ... this session's (:attr:`falls`)
        #: how many times the stream was asked for again, no frame having come after its
        #: request (:meth:`_stream_again`): bytes to the robot lost, most likely
        self.stream_asked_again = 0
        #: the stream asked for again when it went silent mid-run (robot/stall_asks.py)
        self.stall_asks = StallAsks()
        #: who waited the grace for frames, as a lost stream's reason says it (``then the
        #: run waited the 2 s grace``): ``roomba-bt sensors`` sets its own name, being no run
        self.waiter = "the run"
        #: the bytes to the robot this session found lost and put right, by what they were
        #: (``"a Query List"``, ``"the stream request"``, ``"a wheel command"``: the run's
        #: motion watch adds its own): the evidence a fall of unknown cause names the cable
        #: by (:meth:`cable_suspected`)
        self.lost_on_the_way: Counter[str] = Counter()
        _LIVE.add(self)
        # a program that dropped it unclosed (at its end: _close_at_exit, which says so)
        weakref.finalize(self, _stop_dropped, self.ending).atexit = False

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(
        cls,
        url: str,
        baud: int = DEFAULT_BAUD,
        profile: RobotProfile | str | None = DEFAULT_PROFILE,
        *,
        watchdog: float = DEFAULT_WATCHDOG,
        end_in: EndMode = "passive",
        write_timeout: float = 0.5,
        keep_awake: bool | None = None,
    ) -> Connection:
        """Open ``url`` (device path, ``socket://``, ``rfc2217://``, ``loop://``) at ``baud``, an
        OI rate (19200: ``profile.at_19200``); ``keep_awake`` as ``Connection``'s (wake.py).
        ``profile``: the robot's model, ``create2`` unless given; ``ROOMBA_BT_PROFILE`` and
        the project file's ``profile`` are the command line's and are not read here (a
        program runs the same in any shell and folder): ``profile=roomba_bt.configured_profile()``
        takes the command line's choice (``cli/profile_choice.py`` says why)."""
        if baud not in BAUD_CODES:
            rates = ", ".join(str(rate) for rate in BAUD_CODES)
            raise ValueError(f"baud {baud!r}: the OI talks at {rates}")
        profile = profile_given(profile, "Connection.open")  # before the port is opened
        try:
            transport = SerialTransport.open(url, baud, write_timeout=write_timeout)
        except TransportError as exc:
            raise port_not_opened(url, exc) from exc
        try:
            return cls(
                transport, profile, watchdog=watchdog, end_in=end_in, baud=baud,
                keep_awake=keep_awake,
            )  # fmt: skip
        except BaseException:  # a setting refused: the port (and its locks) let go at once
            transport.close()
            raise

    def start(
        self,
        mode: OIMode | ModeName = OIMode.SAFE,
        packets: Sequence[int] = (),
        confirm_timeout: float = 1.0,
    ) -> None:
        """Wake the OI, confirm the robot answers, enter ``mode``, start the stream.

        The stream request is checked (packet ids, bandwidth at :attr:`baud`) before a byte
        is sent. Raises :class:`ConnectionFailed` if the robot does not answer in
        ``confirm_timeout`` seconds.
        """
        target = as_mode(mode)
        if target is OIMode.OFF:
            raise ValueError("start() enters Passive, Safe or Full; use close() to end in Off")
        ids = tuple(packets)
        stream_command = oi.stream(ids) if ids else None
        if ids:
            check_bandwidth(ids, self.baud)
        self.ending.begin()
        self._falls = Counter()
        self.release_forward()
        self.send(oi.start())
        self.send(oi.pause_stream())
        drain(self.link.transport, self.link.read)  # a stale stream, a reset banner
        round_trips: list[float] = []
        try:
            raw = agreed_mode_reply(
                self.name,
                lambda: self._query_raw((OI_MODE_PACKET,), confirm_timeout, round_trips),
                confirm_timeout,
                self._resync,
            )
        except NoAnswer as silent:
            raise answers_elsewhere(self, silent) from None
        self.ending.round_trip = link_round_trip(round_trips, self.name)
        if not self.modes.calibrate(raw, self.link.transport.now(), self.name):
            raise not_a_mode(self.name, raw)
        self.ending.answered = True
        self.link.mode_plus_one = self.modes.plus_one
        # the frames the robot sent before it heard a mode command come a round trip later
        # (twice it, for jitter): on a link with latency the old mode they read is neither a
        # fall to Passive nor a resync (0.2 s: "went from Safe to Passive by itself" at once)
        in_flight = self.ending.in_flight(stream_period(ids, self.baud))
        self.modes.settle = max(self.settle, in_flight)
        if target is OIMode.SAFE:
            self.send(oi.safe())
        elif target is OIMode.FULL:
            self.send(oi.full())
        if stream_command is not None:
            self.send(stream_command)
        # without packets (``sensors`` below 57600) nothing streams: "streaming []" read as a
        # stream of nothing, so the log says how the sensors are read instead
        how = f"streaming {list(ids)}" if ids else "no stream (a Query List (149) each reading)"
        log.info("%s: %s in %s, %s", self.name, self.profile.title, target.label, how)

    def _resync(self) -> None:
        """The start-up's Query List went unanswered: the robot's OI parser set in step, as
        after bytes to it were lost (:data:`~roomba_bt.robot.writer.RESYNC_ZEROS`), then Start
        and the pause again (a Start lost leaves the OI Off, which answers no query), and what
        all that made it say read and dropped until the line is quiet."""
        self.writer.send_many((oi.start(), oi.pause_stream()), prefix=RESYNC_ZEROS)
        drain(self.link.transport, self.link.read)
        self.lost_on_the_way["a Query List"] += 1  # the start-up fails if it goes unanswered

    def _stream_again(self) -> bool:
        """The watchdog's time passed since Stream (148) was written and no frame came: a
        byte of the request lost on its way leaves the robot waiting for an id, or streaming
        another list, and nothing would ever ask again. The zeros that end any such wait
        (:func:`~roomba_bt.robot.startup.stream_zeros`) and the request again, in one
        write, up to :data:`~roomba_bt.robot.startup.STREAM_ASKS_AGAIN` times; said once.
        False (the watchdog's trip goes on as a trip) once given up, or while the wheels
        may turn (the watchdog's drive 0 comes first)."""
        ids = self.link.stream_ids
        if self.stream_asked_again >= STREAM_ASKS_AGAIN or not ids:
            return False
        wheels = self.writer.last_wheels
        if wheels is not None and turns_wheels(wheels) and self.modes.mode in DRIVING_MODES:
            return False
        self.stream_asked_again += 1
        self.lost_on_the_way["the stream request"] += 1  # the stream came, or the run ends
        log.log(
            logging.WARNING if self.stream_asked_again == 1 else logging.INFO,
            "%s: no sensor data came within %.0f ms of asking the robot for it: a byte of "
            "the request may have been lost on the way to the robot (%s?); asking again "
            "(%d of %d)", self.name, self.watchdog * 1000, link_of(self.name).lossy,
            self.stream_asked_again, STREAM_ASKS_AGAIN,
        )  # fmt: skip
        self.writer.send_many([oi.stream(ids)], prefix=stream_zeros(ids))
        return True

    def query(self, packet_ids: Sequence[int], timeout: float = 1.0) -> SensorFrame | None:
        """Query List (149) for ``packet_ids``; the decoded reply, or None after ``timeout``.

        Only while no stream runs (a reply has no header: it could not be told apart).
        """
        frame = self._query_raw(packet_ids, timeout)
        if frame is not None:
            self.ending.answered = True
            self.writer.reply, self.writer.reply_index = frame, self.link.index
            change = self.modes.reconcile(frame, self.link.index, self.link.transport.now())
            if change is not None:
                self._report_change(change)
        return frame

    def _query_raw(
        self, packet_ids: Sequence[int], timeout: float, round_trips: list[float] | None = None
    ) -> SensorFrame | None:
        """Query List and its reply, without telling the mode model; how long the reply took
        is added to ``round_trips`` (the start-up's, which the stop's allowance comes from: a
        user's later ``query()`` does not change it)."""
        if self.link.streaming:
            raise RobotError(
                "query() needs the stream paused: a reply cannot be told apart from its "
                "frames; send(commands.pause_stream()) first, and resume_stream() after"
            )
        reply = ReplyParser(tuple(packet_ids), self.profile, mode_plus_one=self.link.mode_plus_one)
        clock = self.link.transport.now
        asked = clock()
        self.send(oi.query_list(packet_ids))
        deadline = clock() + timeout
        while True:
            frame = reply.feed(self.link.read(max(0.0, deadline - clock())))
            if frame is not None:
                if round_trips is not None:  # the link's round trip: how late frames come
                    round_trips.append(clock() - asked)
                return frame
            if clock() >= deadline:
                return None

    # ------------------------------------------------------------------ what is known
    @property
    def name(self) -> str:
        return self.link.transport.name

    @property
    def transport(self) -> Transport:
        return self.link.transport

    @transport.setter
    def transport(self, transport: Transport) -> None:
        """Wrap or replace the port under a running link (a tap that times the writes)."""
        self.link.transport = transport

    @property
    def wake(self) -> KeepAwake | None:
        """The BRC pulses (robot/wake.py), or None; kept by the endings, which release it."""
        return self.ending.wake

    @wake.setter
    def wake(self, wake: KeepAwake | None) -> None:
        self.ending.wake = wake

    @property
    def watchdog(self) -> float:
        return self.link.watchdog

    @property
    def status(self) -> LinkStatus:
        return self.link.status

    @property
    def latest(self) -> TimedFrame | None:
        """The newest checked frame (None before the first)."""
        return self.link.latest

    @property
    def mode(self) -> OIMode:
        return self.modes.mode

    @property
    def last_fallback(self) -> ModeChange | None:
        return self.modes.last_fallback

    @property
    def counters(self) -> LinkCounters:
        link = self.link
        frames, checksums, skipped, implausible = link.parsed()
        return LinkCounters(
            frames=frames,
            checksum_failures=checksums,
            implausible_frames=implausible,
            skipped_bytes=skipped,
            bytes_read=link.bytes_read,
            bytes_written=link.bytes_written,
            commands_sent=self.writer.sent,
            commands_refused=self.writer.refused,
            watchdog_trips=link.watchdog_trips,
            mode_readings_ignored=self.modes.invalid_readings,
        )

    @property
    def profile_setting(self) -> str | None:
        """Where the profile was set, for a wrong profile's fix (a stall's, a 600's mode + 1
        warning): the command line's ``--profile``, ``ROOMBA_BT_PROFILE`` or a project
        file's ``path:line`` (:func:`~roomba_bt.robot.errors.profile_fix`); None (the
        default): the option and the Python argument both are named."""
        return self.modes.detector.setting

    @profile_setting.setter
    def profile_setting(self, setting: str | None) -> None:
        self.modes.detector.setting = setting

    # ------------------------------------------------------------------ reading
    def poll(self, timeout: float = 0.0) -> list[TimedFrame]:
        """New frames: what is there now, or wait up to ``timeout`` s for at least one.

        Reads in the caller's thread, reconciles the mode model with every frame, checks
        the watchdog. Raises :class:`PortLost` if the port fails and, once when the watchdog
        trips (frames coming back clear the stall), the stall's cause if it is already known
        (:class:`RobotReset`: the banner was read; :class:`RobotAsleep`; :class:`BaudChanged`:
        garbage, and frames at another rate) or
        :class:`StreamStalled` (see :meth:`check_stall` for riding it through; one whose
        ``mismatch`` is set, another model's frames, is certain at once: nothing to ride
        through, its fix worded for :attr:`profile_setting`).

        ``timeout`` is 0 or more: pyserial's ``None`` (wait for ever) and a ``-1`` meant so
        are refused (a -1 returned at once, and a program's loop over it spun the CPU).
        """
        if self.ending.closed:
            raise ConnectionClosed(self.name)
        if not (isinstance(timeout, int | float) and timeout >= 0):  # NaN too
            raise ValueError(
                f"poll(timeout={timeout!r}): a timeout is 0 or more seconds (0: what is "
                "there now); to wait for frames as they come, poll(0.1) in a loop"
            )
        try:
            frames = self.poll_frames(timeout)
        except PortLost:
            if self.ending.closed:  # closed by another thread while this one read
                raise ConnectionClosed(self.name) from None
            raise
        return self.link.read_timed(frames) if frames else []

    def poll_frames(self, timeout: float = 0.0) -> Sequence[SensorFrame]:
        """:meth:`poll`'s frames alone, the newest last: the runtime's read, once a tick.
        They came in one read, at ``link.arrival``; the newest is number ``link.index``."""
        link = self.link
        now = link.transport.now()  # the read's start too: read_checked need not ask again
        wake = self.ending.wake  # the attribute, not the property: once a tick
        if wake is not None and now >= wake.due:  # most polls: no pulse to start or end
            wake.tick(now)
            now = link.transport.now()  # driving the line may take time on a real port
        try:
            return link.read_checked(timeout, now)
        except StreamStalled as exc:
            if self.link.banner_seen():
                raise RobotReset(self.name, exc.halted, self._since_write()) from exc
            if exc.mismatch is not None:  # another model's frames: the stop's check too
                another_model(self, exc.mismatch)
                raise StreamStalled(
                    exc.port, exc.silent_for, exc.watchdog, exc.halted, exc.mismatch,
                    setting=self.profile_setting,
                ) from exc  # fmt: skip
            cause = (
                asleep_by_idle(self)
                or follow_baud(self)
                or named_stall(exc, wake, link.silent_since)
            )
            if cause is None:
                raise
            raise cause from exc

    def check_stall(self, bytes_before: int, grace: float, halted: bool) -> None:
        """While a stall is ridden through (the watchdog tripped, drive 0 sent): raise the
        cause once it is known. :class:`RobotReset` as soon as the firmware's banner is read;
        once no valid frame came for ``grace`` s (``bytes_before``: the bytes read when the
        stall began, to tell a stopped stream from a garbled line), :class:`StreamLost` for a
        garbled line, or for a silent one what asking the robot shows
        (:func:`~roomba_bt.robot.silence.explain_silence`: :class:`RobotAsleep` if a BRC
        pulse woke it; a word of the cable beside it when no frame came though the stream
        was asked for again, :meth:`_stream_again`). While garbage keeps coming the other
        rates are listened at again (a first listen can miss the change): :class:`BaudChanged`
        as soon as one finds it."""
        link = self.link
        if link.banner_seen():
            raise RobotReset(self.name, halted, self._since_write())
        followed = follow_baud(self)
        if followed is not None:
            raise followed
        now = link.transport.now()
        since = link.silent_since
        if now - since <= grace:
            if not link.bytes_since_frame:  # a silent line: the stream asked for again
                ask_in_stall(self, now, grace)
            return
        garbled = link.bytes_read - bytes_before
        cause = (
            garbled_line(self, now - since, grace, garbled, halted=halted)
            if garbled
            else dead_connection(self, now - since, grace, halted=halted)
            or explain_silence(self, now - since, grace, halted=halted)
        )
        asked = self.stall_asks.said()
        if asked:
            cause.also(asked)
        if self.stream_asked_again and link.stream_unanswered:
            cause.also(
                f"no frame came though the stream was asked for {self.stream_asked_again + 1} "
                "times: bytes from the computer to the robot may be lost (check "
                f"{link_of(self.name).byte_check}: roomba-bt doctor)"
            )
        raise cause

    def _since_write(self) -> float:
        """Seconds from the last command we wrote but the watchdog's own drive 0 (which
        comes after the stall began) to the stall's start: how soon after our bytes the
        robot went quiet (a reset banner then may be a byte of ours lost: RobotReset)."""
        writer = self.writer
        recent = [t for t in writer.recent_commands if t <= self.link.silent_since]
        return self.link.silent_since - recent[-1] if recent else float("inf")

    def _report_change(self, change: ModeChange) -> None:
        if change.fall:
            self._falls[change.cause] += 1
            self.writer.robot_stopped(change.cause)
        _say_change(self.name, change, self._changes_said, self.cable_suspected())

    def cable_suspected(self) -> str:
        """Why a fall to Passive of unknown cause may be the cable's, when this session has
        the evidence: bytes to the robot it found lost and put right (:attr:`lost_on_the_way`).
        A data byte after a lost one is read as an opcode, and a radius's or a count's 128 is
        Start: the robot drops to Passive, its frame showing no cliff, wheel drop or
        charger. "" without that evidence: a fall is not blamed on a cable never seen to
        lose a byte."""
        lost = bytes_lost_said(self)
        if not lost:
            return ""
        return (
            f"{lost}: a data byte after a lost one can be read as Start (128), so "
            f"{link_of(self.name).serial_side} is a likely cause"
        )

    @property
    def falls(self) -> dict[str, int]:
        """The robot's own falls to Passive since :meth:`start` by cause: ``{"cliff": 20}``."""
        return dict(self._falls)

    def halt(self) -> bool:
        """Drive 0 if the model says the robot may be driving; True if it was sent."""
        return self.writer.halt()

    def stop_on_stall(self) -> bool:
        """The watchdog's action: drive 0 if the model says the robot may be driving, and
        motors off with it if a brush or the vacuum runs (a run riding the stall through
        gives both their commands back once frames return: runtime/stall.py); True if it
        was sent."""
        return self.writer.halt(motors=True, by="the watchdog's drive 0")

    # ------------------------------------------------------------------ the bump reflex
    def hold_forward(self) -> None:
        """Drive 0 now if the wheels drive forward, and forward wheel commands kept, not
        written, while a bump onset waits for its confirming frame
        (:meth:`CommandWriter.hold_forward <roomba_bt.robot.writer.CommandWriter.hold_forward>`)."""
        self.writer.hold_forward()

    def release_forward(self) -> Command | None:
        """The hold ends; the forward command it kept, to be sent again, or None."""
        return self.writer.release_forward()

    @property
    def running_cycle(self) -> Command | None:
        """The built-in cycle that may be driving the robot now (:attr:`CommandWriter.running_cycle
        <roomba_bt.robot.writer.CommandWriter.running_cycle>`), or None."""
        return self.writer.running_cycle

    @property
    def forward_held(self) -> bool:
        """Whether the bump reflex holds forward motion (robot/hazards.py)."""
        return self.writer.forward_held

    # ------------------------------------------------------------------ writing
    def send(self, command: Command) -> None:
        """Guard, write, follow one command (:meth:`CommandWriter.send
        <roomba_bt.robot.writer.CommandWriter.send>`; a refused one raises, nothing written)."""
        try:
            self.writer.send(command)
        except (AttributeError, ModeError, PortLost):  # checked only then: free on the tick path
            if not isinstance(command, Command) or self.ending.closed:
                raise _refusal(self, command) from None
            raise

    def send_many(self, commands: Iterable[Command]) -> None:
        """Commands in one write (:meth:`CommandWriter.send_many
        <roomba_bt.robot.writer.CommandWriter.send_many>`: the safe stop's, the tick guard's,
        the monitor's; a tick's outbox goes by :meth:`send`, one command at a time): refused
        commands left out, the first refusal raised after the others are written."""
        self.writer.send_many(_sendable(self, commands))

    def set_baud(self, rate: int) -> None:
        """Baud (129) by rate (e.g. 19200); the port follows after 100 ms."""
        self.writer.set_baud(rate)

    @property
    def baud(self) -> int:
        """The rate the port talks at (it follows Baud, and a robot found at another rate)."""
        return self.writer.baud

    @baud.setter
    def baud(self, rate: int) -> None:
        self.writer.baud = rate

    # ------------------------------------------------------------------ endings
    def _stop_heard(self) -> bool:
        return _stop_heard(self)

    def stop_sequence(self) -> list[Command]:
        """What :meth:`safe_stop` sends from the current mode (:mod:`~roomba_bt.robot.ending`)."""
        return self.ending.sequence()

    def safe_stop(self) -> bool:
        """Stop the robot and leave it in Passive (or Off with ``end_in="stop"``).

        Never raises for a dead link: returns False and logs that the robot could not be
        stopped (writes are bounded by the transport's write timeout, so this cannot hang).
        """
        return self.ending.stop()

    def close(self) -> bool:
        """Safe stop (once), close the port. True if the robot was stopped (or never
        started); idempotent."""
        return self.ending.close()

    def activity(self) -> str:
        """What the last wheel command written had the robot doing: ``at 200 mm/s``,
        ``stopped``, ``in its Clean cycle``."""
        return self.ending.activity()

    @property
    def end_in(self) -> EndMode:
        return self.ending.end_in

    @property
    def robot_answered(self) -> bool:
        """Whether a robot ever answered (:attr:`SafeStop.robot_heard`): a valid frame or a
        reply, not bytes alone (noise)."""
        return self.ending.robot_heard

    @property
    def safe_stopped(self) -> bool | None:
        """True once a stop is known sent, False when one failed, None before any ending."""
        return self.ending.safe_stopped

    @property
    def stop_report(self) -> str | None:
        """Why the stop did not reach the robot, with its last known state (None: it did, or
        no stop was tried)."""
        return self.ending.stop_report

    @property
    def unheard(self) -> str | None:
        """Why a stop written now could not be known to arrive (the robot no longer answers
        or the line is garbled), or None."""
        return self.ending.unheard

    @unheard.setter
    def unheard(self, why: str | None) -> None:
        self.ending.unheard = why

    def __enter__(self) -> Connection:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _say_change(name: str, change: ModeChange, said: Counter[str], cable: str = "") -> None:
    """The robot's own fall to Passive, logged: a warning the first time a cause brings it
    in a connection's life, an INFO after it with the count (the shipped ``clean``, in Safe,
    meets each cliff it cleans up to through the firmware's stop: 18 warnings a run read as
    18 alarms); the charger's always an INFO (docking ends so, the OI dropping to Passive on
    the home base's contacts: a successful dock run had reported it as a WARNING)."""
    said[change.cause] += 1
    times = said[change.cause]
    first = times == 1 and change.cause != "charger"
    cause = f"{change.cause}; {cable}" if cable and change.cause == UNKNOWN_CAUSE else change.cause
    log.log(
        logging.WARNING if first else logging.INFO,
        "%s: the robot went from %s to %s by itself (%s)%s",
        name, change.previous.label, change.current.label, cause,
        "" if times == 1 else f", {times} times so far",
    )  # fmt: skip


def _refusal(connection: Connection, command: object) -> Exception:
    """Why ``command`` is not sent: raw bytes or an opcode (pycreate2's and PyRoombaAdapter's
    way) would pass the mode guard by; a closed connection read as a port gone."""
    if connection.ending.closed:
        return ConnectionClosed(connection.name)
    return TypeError(
        f"send() takes {COMMAND_WANTED}, not {type(command).__name__} {command!r:.40}: the "
        "mode guard reads the command, and raw bytes would pass it by"
    )


def _sendable(connection: Connection, commands: Iterable[Command]) -> list[Command]:
    """``commands``, each a :class:`Command` for an open connection (else :func:`_refusal`)."""
    commands = list(commands)
    for command in commands:
        if not isinstance(command, Command) or connection.ending.closed:
            raise _refusal(connection, command)
    return commands
