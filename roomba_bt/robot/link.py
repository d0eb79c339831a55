"""The link: bytes to and from one transport, the sensor stream cut into frames, the watchdog.

The half of a :class:`~roomba_bt.robot.connection.Connection` that knows bytes and frames but
not what a command means (the session, the other half, decides what is sent and keeps the
mode model). Reading happens in the caller's thread, which is what the runtime wants: no
thread hop between a frame's arrival and the tick that reads it, and on the simulator's
virtual clock the caller's reads are what move time::

    transport.read ──► StreamParser.feed ──► reconcile(frame, index, arrival) ──► SensorFrame
     (OSError: PortLost)  (checksum, resync)    (the session's mode model)       (TimedFrame)

    no valid frame for ``watchdog`` s while a stream runs ──► halt() ──► StreamStalled
                                                      (once; frames coming back clear it)
    none at all since Stream (148) was written, ──► ask_again(): the request again, while
    not even a damaged one                         the session has tries left

Each trip is noted in the run's record when the transport keeps one (``note``: the runtime's
``RecordingTransport``), at the link time it tripped at; a replay's link trips at those
times and nowhere else (:attr:`StreamLink.replayed_trips`): its clock is the record's, and a
read that woke late on the live run's loaded machine took frames the record stamps past the
watchdog, where the live run had no trip.
"""

from __future__ import annotations

import enum
import logging
import math
from collections import deque
from collections.abc import Callable, Sequence
from typing import NamedTuple

import serial

from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.identify import (
    ChecksumMismatch,
    ProfileMismatch,
    RangeMismatch,
    checksum_mismatch,
    range_mismatch,
)
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import StreamParser, shows_reset_banner
from roomba_bt.robot.errors import PortLost, StreamStalled, TurnedAway
from roomba_bt.robot.interface import ModeChange
from roomba_bt.robot.listen import listen_at
from roomba_bt.robot.wall_bound import WallBound
from roomba_bt.transport.base import Transport, TransportError
from roomba_bt.transport.link_kind import link_of
from roomba_bt.transport.open_failure import CLOSED_AT_ONCE
from roomba_bt.transport.serial_port import TERMIOS_ERRORS

log = logging.getLogger(__name__)

#: What breaking a link raises, from our transport, pyserial, sockets, termios or the simulator.
LINK_ERRORS: tuple[type[Exception], ...] = (OSError, serial.SerialException, *TERMIOS_ERRORS)

#: Chunks read kept for :meth:`StreamLink.banner_seen` (one chunk per read: a few frames).
RECENT_CHUNKS = 16

#: How far past its limit the watchdog's wait ends (the check is "silent for more than").
WATCHDOG_MARGIN = 0.001

#: The session's mode model, told of every frame: the change the robot made by itself, if any.
Reconcile = Callable[[SensorFrame, int, float], ModeChange | None]


class LinkStatus(enum.Enum):
    """Where the link stands; :attr:`Connection.status`."""

    OPEN = "open"  # port open, no stream running
    STREAMING = "streaming"
    STALLED = "stalled"  # the watchdog tripped; frames may come back
    LOST = "lost"  # the port raised: the link is gone
    STOPPED = "stopped"  # safe stop sent
    CLOSED = "closed"


#: read on every tick: a module constant (an Enum class's member lookup goes through its
#: metaclass's ``__getattr__`` hook, several times the cost of a global)
_STREAMING, _STALLED = LinkStatus.STREAMING, LinkStatus.STALLED


class TimedFrame(NamedTuple):
    """A checked stream frame, when it arrived (link clock) and its number in the stream.

    A named tuple (immutable, several times faster to make than a frozen dataclass;
    :meth:`StreamLink.read_timed` makes it by ``tuple.__new__``, as the named tuple's own
    ``__new__`` is a Python call binding each field). What ``Connection.poll`` gives; the
    runtime reads the frames alone (``Connection.poll_frames``), with no TimedFrame made a
    tick. ``index`` is the frame's number, not ``tuple.index``: the field's name predates
    the tuple and is kept."""

    frame: SensorFrame
    time: float
    index: int  # type: ignore[assignment]


_new_tuple = tuple.__new__


class StreamLink:
    """One transport, its stream parser and its watchdog.

    ``reconcile`` is called with every checked frame (the session's mode model) and
    ``report`` with what it returns when the robot changed mode by itself; ``halt`` is what
    the watchdog does when it trips (the session sends drive 0 if the robot may be driving,
    and says whether it did). ``watchdog``: seconds without a valid frame while a stream runs;
    0 disables it. ``ask_again`` is what the watchdog does instead when no frame at all came
    since the stream was asked for (a byte of the request lost on the line leaves no
    stream): the session writes the request again and says True, or False once it has
    given up (the trip is then a trip).
    """

    def __init__(
        self,
        transport: Transport,
        profile: RobotProfile,
        *,
        watchdog: float,
        reconcile: Reconcile,
        report: Callable[[ModeChange], None],
        halt: Callable[[], bool],
        ask_again: Callable[[], bool] = lambda: False,
    ) -> None:
        self.transport = transport
        self.profile = profile
        self.watchdog = watchdog
        self._reconcile = reconcile
        self._report = report
        self._halt = halt
        self._ask_again = ask_again
        self.status = LinkStatus.OPEN if transport.is_open else LinkStatus.CLOSED
        #: the far end closed the connection before it sent a byte (another client holds
        #: it: :data:`~roomba_bt.transport.open_failure.CLOSED_AT_ONCE`): no robot was reached
        self.turned_away = False
        self.stream_ids: tuple[int, ...] = ()
        self.streaming = False
        #: the newest checked frame (None before the first), when it arrived (link clock)
        #: and its number in the stream: :attr:`latest` in one
        self.frame: SensorFrame | None = None
        self.arrival = 0.0
        self.index = 0
        self.bytes_read = 0
        self.bytes_written = 0
        #: the rate the port was last set to (None: unknown, a change cut short by an
        #: exception, Ctrl-C among them): what a write checks against the robot's rate
        #: (``CommandWriter.at_robot_rate``). Where the transport says none, the session sets
        #: it to the rate it opened at.
        baud = getattr(transport, "baud", None)
        self.port_rate: int | None = int(baud) if isinstance(baud, int) else None
        #: when a frame of the running stream last came damaged (link clock; -inf: none):
        #: its header, length and packet ids in place, its checksum or a value wrong. The
        #: robot's own frames at the port's rate, hurt on the line: not another rate
        self.damaged_frame_at = -math.inf
        self._refused_seen = 0  # the parser's refused candidates when last looked at
        self.watchdog_trips = 0
        #: whether packet 35 reads the mode + 1, as the session learned at start-up (None:
        #: as the profile expects); the parser's range for packet 35 follows it
        self.mode_plus_one: bool | None = None
        self._parser: StreamParser | None = None
        self._parsed_before = (0, 0, 0, 0)  # frames, checksum failures, skipped, implausible
        #: when the last valid frame arrived, or the stream started (or resumed) if none
        #: has since (link clock): what the watchdog measures from
        self._silent_since = 0.0
        self._bytes_at_frame = 0  # bytes_read when the last valid frame came
        #: :attr:`index` when Stream (148) was last written (no frame since while they agree)
        self._index_at_request = 0
        #: the last chunks read (a reset's banner comes just before the stream stops)
        self._recent: deque[bytes] = deque(maxlen=RECENT_CHUNKS)
        #: a replay's watchdog: the link times its recorded run's watchdog tripped at, in
        #: order; it trips there (while a stream runs) and nowhere else. None: it trips on
        #: the silence, as on a robot
        self.replayed_trips: deque[float] | None = None

    @property
    def name(self) -> str:
        return self.transport.name

    # ------------------------------------------------------------------ bytes
    #: a bound in wall time on the waits that read now (the safe stop's:
    #: :func:`~roomba_bt.robot.wall_bound.bounded`), or None
    wall_bound: WallBound | None = None

    def read(self, timeout: float) -> bytes:
        bound = self.wall_bound
        if bound is not None:
            bound.check(self.transport)
        try:
            data = self.transport.read(timeout)
        except LINK_ERRORS as exc:
            raise self.lost("read", exc) from exc
        if data:
            self.bytes_read += len(data)
            self._recent.append(data)
        return data

    def write(self, data: bytes) -> None:
        try:
            self.transport.write(data)
        except LINK_ERRORS as exc:
            raise self.lost("write", exc) from exc
        self.bytes_written += len(data)

    def set_baud(self, rate: int) -> None:
        """The port follows the robot to ``rate`` (what it wrote drained first); a running
        stream starts a new parser."""
        self.switch_rate(rate)
        if self._parser is not None:
            self.new_stream(self.stream_ids, self.transport.now())

    def drain_output(self) -> None:
        """Wait until what was written has left the port (the transport's ``drain_output``:
        ``tcdrain``); a transport without one delivers on write (the simulator's link) or
        has no wire (a replay)."""
        drain = getattr(self.transport, "drain_output", None)
        if drain is None:
            return
        try:
            drain()
        except LINK_ERRORS as exc:
            raise self.lost("drain", exc) from exc

    def switch_rate(self, rate: int) -> None:
        """Set the port to ``rate``, what was written drained first so that it leaves at the
        rate it was written for (:meth:`drain_output`). :attr:`port_rate` is unknown (None)
        until the change is done: one cut short (Ctrl-C inside it) is set again before the
        next write (``CommandWriter.at_robot_rate``)."""
        self.drain_output()
        self.port_rate = None
        try:
            self.transport.set_baud(rate)
        except LINK_ERRORS as exc:
            raise self.lost("baud change", exc) from exc
        self.port_rate = rate

    def listen_at(self, rate: int, seconds: float, enough: int, back_to: int | None = None) -> bool:
        """Whether the stream's frames come at ``rate`` (:func:`~roomba_bt.robot.listen.
        listen_at`); the port left there if they do, put back at ``back_to`` (default: the
        rate it has) on every other way out, Ctrl-C too."""
        return listen_at(self, rate, seconds, enough, back_to)

    def lost(self, action: str, exc: BaseException) -> PortLost:
        """Mark the link lost; the error to raise."""
        self.status = LinkStatus.LOST
        self.streaming = False
        cause = exc.cause if isinstance(exc, TransportError) else exc
        if cause == CLOSED_AT_ONCE:  # turned away, not gone: the robot may be fine
            self.turned_away = True
            return TurnedAway(self.name, f"{cause}; nothing reached a robot")
        return PortLost(
            self.name,
            f"the port is gone ({link_of(self.name).gone}): it failed on {action} ({cause}); the "
            "link is lost",
        )

    def banner_seen(self) -> bool:
        """Whether the firmware's start-up banner is in the last chunks read with no valid
        frame of the stream after it: it reset (:func:`~roomba_bt.oi.stream.shows_reset_banner`).
        Off the tick path: a stall's and an unconfirmed stop's question."""
        ids = self.stream_ids
        stream = StreamParser(ids, self.profile, mode_plus_one=self.mode_plus_one) if ids else None
        return shows_reset_banner(b"".join(self._recent), stream)

    @property
    def silent_since(self) -> float:
        """When the last valid frame arrived, or the stream started if none has (link
        clock): what the watchdog measures from."""
        return self._silent_since

    @property
    def bytes_since_frame(self) -> int:
        """Bytes read since the last valid frame (garbage, if a stall has any)."""
        return self.bytes_read - self._bytes_at_frame

    @property
    def garbage_since_frame(self) -> int:
        """:attr:`bytes_since_frame` less the bytes the parser holds as the start of a frame
        still to come (a frame cut by a late read is not garbage yet)."""
        parser = self._parser
        pending = parser.pending if parser is not None else 0
        return max(0, self.bytes_since_frame - pending)

    # ------------------------------------------------------------------ the stream
    def new_stream(self, ids: tuple[int, ...], now: float) -> None:
        """Stream (148) was written: frames of ``ids`` from now on (none: no stream)."""
        self._parsed_before = self.parsed()  # the old parser's counts, kept
        self.stream_ids = ids
        self._parser = (
            StreamParser(ids, self.profile, mode_plus_one=self.mode_plus_one) if ids else None
        )
        self.streaming = bool(ids)
        self._silent_since = now
        self._bytes_at_frame = self.bytes_read
        self._index_at_request = self.index
        self._refused_seen = 0  # the new parser's count
        self.status = LinkStatus.STREAMING if ids else LinkStatus.OPEN

    def pause_resume(self, resume: bool, now: float) -> None:
        """Pause/Resume Stream (150) was written."""
        self.streaming = resume and bool(self.stream_ids)
        self._silent_since = now
        if self.streaming:
            self.status = LinkStatus.STREAMING

    def parsed(self) -> tuple[int, int, int, int]:
        """Frames, checksum failures, skipped bytes and frames dropped as out of range since
        the link was made."""
        frames, checksums, skipped, implausible = self._parsed_before
        if self._parser is not None:
            c = self._parser.counters
            frames += c.frames
            checksums += c.checksum_failures
            skipped += c.skipped_bytes
            implausible += c.implausible
        return frames, checksums, skipped, implausible

    def checksum_mismatch(self) -> ChecksumMismatch | None:
        """Whether the running stream's frames fail the profile's checksum and pass another
        model's (read off the parser's counters: only when a stream is declared lost)."""
        parser = self._parser
        if parser is None:
            return None
        counters = parser.counters
        return checksum_mismatch(
            self.profile, frames=counters.frames, failures=counters.checksum_failures,
            other_checksum=counters.other_checksum,
        )  # fmt: skip

    def range_mismatch(self) -> RangeMismatch | None:
        """Whether the running stream's frames pass the profile's checksum but carry a value
        only another model's range holds (read off the parser's last such frame: only when a
        stream is declared lost)."""
        parser = self._parser
        if parser is None:
            return None
        counters = parser.counters
        return range_mismatch(
            self.profile, parser.out_of_range, self.stream_ids, refused=counters.implausible,
            checksum_failures=counters.checksum_failures, mode_plus_one=self.mode_plus_one,
        )  # fmt: skip

    def profile_mismatch(self) -> ProfileMismatch | None:
        """The frames show a robot of another model (:meth:`checksum_mismatch`, else
        :meth:`range_mismatch`), or None: what a stall or a lost stream names with its fix."""
        return self.checksum_mismatch() or self.range_mismatch()

    @property
    def latest(self) -> TimedFrame | None:
        """The newest checked frame, when it arrived and its number (None before the first)."""
        frame = self.frame
        return None if frame is None else TimedFrame(frame, self.arrival, self.index)

    def read_checked(self, timeout: float, now: float | None = None) -> Sequence[SensorFrame]:
        """What is there now, or wait up to ``timeout`` s for at least one frame; then the
        watchdog. ``now``: the link clock's time if the caller has just read it. The frames
        alone: they all came in one read, at :attr:`arrival`, and the newest is number
        :attr:`index` (the runtime reads them so, once a tick, with no :class:`TimedFrame`
        made for each: a named tuple's making is about a tenth of the link's cost a frame).

        The wait never outlasts the watchdog's own deadline: a read blocked for the caller's
        whole ``timeout`` (the runtime polls with 50 ms) would check the watchdog up to that
        much late, which over a loaded pty put drive 0 283 ms after the last frame::

            last frame ──── watchdog (100 ms) ──┐ the read returns here, drive 0
                                                 └ not at the end of the caller's timeout

        Once a frame on the tick path, so (over 60 lines on purpose) the common case, a read
        that brings exactly one whole frame, is written out here: :meth:`read`, the parser's
        :meth:`~roomba_bt.oi.stream.StreamParser.take` and :meth:`_checked` for that one
        frame, with no call of this class's own (each was about a tenth of the link's cost
        a frame).
        """
        transport = self.transport  # its methods called, not bound: most polls read once
        if now is None:
            now = transport.now()
        deadline = now + timeout
        # When the watchdog trips if no valid frame comes: a margin past its limit, so the
        # check after the wait finds it tripped. Most polls come well before it: the
        # conditions under which it can trip are read only when it would cut the wait.
        trips = self.replayed_trips
        if trips is None:
            due = self._silent_since + self.watchdog + WATCHDOG_MARGIN
        else:
            due = replayed_due(trips, now)
        if due < deadline and self.streaming and self.watchdog > 0 and self.status is _STREAMING:
            deadline = due if due > now else now
        while True:
            wait = deadline - now
            try:
                data = transport.read(wait if wait > 0.0 else 0.0)
            except LINK_ERRORS as exc:
                raise self.lost("read", exc) from exc
            now = transport.now()  # once a read: the frames' arrival, the deadline's, the
            # watchdog's now
            if data:
                self.bytes_read += len(data)
                self._recent.append(data)
                parser = self._parser
                if parser is not None:
                    frame = parser.take(data, now)
                    if frame is not None:  # one whole frame: _checked's work, for it alone
                        index = self.index = self.index + 1
                        # read, then called: a method-call lookup of a function kept in an
                        # attribute is not specialised by CPython 3.11 (generic every frame)
                        reconcile = self._reconcile
                        change = reconcile(frame, index, now)
                        if change is not None:
                            self._report(change)
                        self.frame = frame
                        self.arrival = self._silent_since = now
                        self._bytes_at_frame = self.bytes_read
                        if self.status is _STALLED:
                            self.status = _STREAMING
                        return (frame,)  # a tuple: one allocation, a list's is two
                    frames = parser.search(data, now)
                    counters = parser.counters  # a damaged frame among the bytes?
                    refused = counters.checksum_failures + counters.implausible
                    if refused != self._refused_seen:
                        self._refused_seen = refused
                        self.damaged_frame_at = now
                    if frames:  # a frame that came now leaves nothing silent for the watchdog
                        return self._checked(frames, now)
            if now >= deadline:  # no read past the deadline (a virtual clock's read of
                break  # 0 s still steps once)
        self._check_watchdog(now)
        return ()

    def ingest(self, data: bytes, arrival: float) -> list[TimedFrame]:
        """Feed ``data`` that arrived at ``arrival`` to the parser; the frames it completed."""
        parser = self._parser
        if parser is None:
            return []
        frames = parser.feed(data, arrival)
        return self.read_timed(self._checked(frames, arrival)) if frames else []

    def _checked(self, frames: list[SensorFrame], arrival: float) -> list[SensorFrame]:
        """``frames``, just checked (at least one), each told to the mode model and
        numbered; the newest is :attr:`frame`."""
        reconcile = self._reconcile
        index = self.index
        for frame in frames:
            index += 1
            change = reconcile(frame, index, arrival)
            if change is not None:
                self._report(change)
        self.index = index
        self.frame = frames[-1]
        self.arrival = self._silent_since = arrival
        self._bytes_at_frame = self.bytes_read
        if self.status is _STALLED:
            self.status = _STREAMING
        return frames

    def read_timed(self, frames: Sequence[SensorFrame]) -> list[TimedFrame]:
        """The frames the last read checked (:meth:`read_checked`), each with its arrival and
        its number."""
        arrival = self.arrival
        first = self.index - len(frames) + 1
        return [
            _new_tuple(TimedFrame, (frame, arrival, index))
            for index, frame in enumerate(frames, first)
        ]

    @property
    def stream_unanswered(self) -> bool:
        """Whether no valid frame came since Stream (148) was last written."""
        return self.index == self._index_at_request

    def _request_unheard(self) -> bool:
        """Whether the robot may not have heard the stream request: no frame of it came,
        not even a damaged one (its header, length and ids in place, its checksum or a
        value wrong: a noisy line, another model's checksum), which would show it heard."""
        return self.index == self._index_at_request and self.damaged_frame_at < self._silent_since

    def _check_watchdog(self, now: float) -> None:
        if not self.streaming or self.watchdog <= 0 or self.status is not _STREAMING:
            return
        silent = now - self._silent_since
        trips = self.replayed_trips
        if trips is None:
            if silent <= self.watchdog:
                return
        elif trips and trips[0] <= now:
            trips.popleft()
        else:
            return
        note = getattr(self.transport, "note", None)  # a record's (run --record), for a replay
        if callable(note):  # noted before a request again too: a replay asks where it did
            note({"watchdog": round(silent, 6), "limit": self.watchdog}, at=now)
        if self._request_unheard() and self._ask_again():
            return  # the stream asked for again: the watchdog counts from that request
        self.status = LinkStatus.STALLED
        self.watchdog_trips += 1
        halted = self._halt()
        raise StreamStalled(self.name, silent, self.watchdog, halted, self.profile_mismatch())


def replayed_due(trips: deque[float], now: float) -> float:
    """When a replay's watchdog trips next (:attr:`StreamLink.replayed_trips`): the recorded
    run's next trip after ``now``; those up to ``now`` that it did not trip at (the replay
    went elsewhere: no stream running then) are dropped."""
    while trips and trips[0] <= now:
        trips.popleft()
    return trips[0] if trips else math.inf
