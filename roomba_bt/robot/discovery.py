"""Finding a robot on a port: which baud rate it talks at, a BRC pulse if it is silent, and
which model it is.

One function for ``roomba-bt doctor`` and ``--baud auto`` (``run``, ``sensors``), so both try
the same rates in the same order and read an answer the same way; and one for ``doctor``'s
stream check and ``--profile auto`` (:func:`identify_robot`), so both tell the models apart
from the same evidence. Not the start-up handshake
of a session (Start, the mode read twice, Safe or Full, the stream): that is
:meth:`Connection.start <roomba_bt.robot.connection.Connection.start>` with
:mod:`roomba_bt.robot.startup`.

The OI talks at 115200 (its default) or 19200 (after Clean is held at power-on on a Roomba
500, at power-off on a 600 / Create 2, or three BRC pulses after power-on:
``RobotProfile.at_19200``); those are the rates tried, 115200 first because it is the default and
so the likeliest (a rate the user names goes first). At each rate the probe sends::

    [0] x 35              zeros: complete a command the robot's parser may still wait in
                          (a byte of an earlier probe's query lost on a bad cable left it
                          waiting for packet ids: robot/writer.RESYNC_ZEROS); 0 is no opcode
    [128]                 Start: Passive, from any mode (Off included)
    [150][0]              pause a stream a previous program may have left running
                          ... read until the line is quiet (a stale stream, a banner)
    [149][3][35][21][34]  Query List: OI mode, charging state, charging sources

and expects exactly three bytes back, each in its packet's range, the mode reading Passive
(1, or 2 on firmware that reports mode + 1). At a wrong rate a real line carries nothing the
robot understands and returns nothing or garbage: garbage is a reply of the wrong length or
out of range, and is reported as such (the user learns something answered).

A robot asleep (five minutes in Passive) answers nothing at any rate. The USB cables wire
BRC to RTS or DTR; :func:`wake_pulse` holds them asserted (BRC low) for one second, the
length keep-awake uses (longer than the 50-500 ms pulses of the baud-change gesture), and
then the rates are tried again. A port whose modem lines cannot be set (a pty) is hung up
for that second instead (speed 0 drops DTR and RTS; the rate's return raises them).
"""

from __future__ import annotations

import errno
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import STREAM_HEADER, stream_frame_size
from roomba_bt.oi.identify import (
    MODEL_RANGE_PACKETS,
    Identification,
    checksum_covers_header,
    identify,
    stream_readings,
)
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.oi.packets import PACKETS, packet_ids
from roomba_bt.oi.profiles import POWER_ON_BAUDS
from roomba_bt.robot.wake import PULSE_LENGTH_S, HangUpLine, WakeLine
from roomba_bt.robot.writer import RESYNC_ZEROS
from roomba_bt.transport.base import Transport
from roomba_bt.transport.link_kind import link_of

#: The OI's rates, likeliest first: the default, then the rate Clean held at power-on (500)
#: or power-off (600 / Create 2) sets; the profiles' table (``oi.profiles.POWER_ON_BAUDS``).
OI_RATES: tuple[int, ...] = POWER_ON_BAUDS
#: OI mode, charging state, charging sources: one byte each, each with a narrow range.
PROBE_PACKETS: tuple[int, ...] = packet_ids("oi_mode", "charging_state", "charging_sources")
#: The probe's question, ``[149][3][35][21][34]``.
PROBE_QUERY = oi.query_list(PROBE_PACKETS).data
#: How long the line must stay quiet after Start and the pause before the query.
QUIET_S = 0.03
#: Give up draining after this long (a stream at another rate never goes quiet).
DRAIN_LIMIT_S = 0.25
#: How long to wait for the reply to the query.
REPLY_TIMEOUT_S = 0.3
#: After a wake pulse, the robot's time to come up before the rates are tried again.
WAKE_SETTLE_S = 0.5


@dataclass(frozen=True, slots=True)
class Probe:
    """What one rate returned: the bytes after the query, and whether they are an answer."""

    baud: int
    reply: bytes
    noise: int  # bytes drained before the query (a stale stream, a banner, garbage)
    answered: bool

    @property
    def mode_raw(self) -> int | None:
        return self.reply[0] if self.answered else None

    @property
    def echoed(self) -> bool:
        """The reply is the query itself: the port gives back what is written to it (a
        loopback, a cable with its data lines joined), no robot."""
        return not self.answered and self.reply == PROBE_QUERY

    @property
    def seen(self) -> str:
        """What the line carried, in words."""
        if self.answered:
            return f"answered {list(self.reply)} to Query List {list(PROBE_PACKETS)}"
        if self.echoed:
            return f"the Query List itself back ({list(self.reply)}): the port echoes"
        if not self.reply and not self.noise:
            return "nothing"
        total = len(self.reply) + self.noise
        return f"{total} bytes that are no answer (a robot at another rate sends garbage)"


@dataclass(frozen=True, slots=True)
class Search:
    """The probes made, in order, and the rate that answered (None: none did)."""

    probes: tuple[Probe, ...]

    @property
    def found(self) -> Probe | None:
        return next((p for p in self.probes if p.answered), None)

    @property
    def baud(self) -> int | None:
        found = self.found
        return found.baud if found is not None else None


def rates_to_try(preferred: int | None = None) -> tuple[int, ...]:
    """``preferred`` (a rate the user named) first, then the OI's rates, likeliest first."""
    if preferred is None:
        return OI_RATES
    return (preferred, *(rate for rate in OI_RATES if rate != preferred))


def _wait(transport: Transport, seconds: float) -> int:
    """Read (and drop) for ``seconds`` of the link's clock; the bytes read."""
    clock = transport.now
    deadline = clock() + seconds
    seen = 0
    while (remaining := deadline - clock()) > 0:
        seen += len(transport.read(remaining))
    return seen


def drain(
    transport: Transport,
    read: Callable[[float], bytes] | None = None,
    *,
    quiet: float = QUIET_S,
    limit: float = DRAIN_LIMIT_S,
) -> int:
    """Read and drop until the line stays quiet for ``quiet`` s (at most ``limit`` s) on
    the transport's clock; the bytes dropped. ``read``: read through this instead of the
    transport (a link's, which counts the bytes and turns a failing port into
    ``PortLost``). A slow line wants a longer ``quiet``: its bytes come that late."""
    clock = transport.now
    read = transport.read if read is None else read
    started = quiet_since = clock()
    seen = 0
    while clock() - quiet_since < quiet and clock() - started < limit:
        data = read(quiet / 2)
        if data:
            seen += len(data)
            quiet_since = clock()
    return seen


def is_answer(reply: bytes) -> bool:
    """Three bytes, each in its packet's range, the mode reading Passive (1, or 2 with the
    mode + 1 firmware bug) since Start came just before."""
    if len(reply) != len(PROBE_PACKETS):
        return False
    for pid, value in zip(PROBE_PACKETS, reply, strict=True):
        spec = PACKETS[pid]
        if not spec.minimum <= value <= spec.maximum + (1 if pid == OI_MODE_PACKET else 0):
            return False
    return reply[0] in (int(OIMode.PASSIVE), int(OIMode.PASSIVE) + 1)


#: What the probe writes before its query: zeros, Start, the stream paused.
PROBE_START = RESYNC_ZEROS + oi.start().data + oi.pause_stream().data
#: Bits a byte takes on the line: a start bit, 8 data bits, a stop bit.
BITS_PER_BYTE = 10


def line_seconds(size: int, baud: int) -> float:
    """Seconds ``size`` bytes take on the line at ``baud``: what a write at a slow rate
    (300 baud: 33 ms a byte) takes to reach the robot after the port took it."""
    return size * BITS_PER_BYTE / baud


def probe(transport: Transport, baud: int, before: bytes = PROBE_START) -> Probe:
    """Set the port to ``baud``, write ``before`` (:data:`PROBE_START`; the safe stop's
    search for a robot a lost byte moved to another rate writes its stop there,
    :mod:`~roomba_bt.robot.baud_hunt`) and ask: see the module docstring. The waits grow
    with the time the bytes take on the line, which at 300 baud is most of them."""
    transport.set_baud(baud)
    transport.write(before)
    quiet = max(QUIET_S, 3 * line_seconds(1, baud))  # three bytes' time, at a slow rate
    noise = drain(transport, quiet=quiet, limit=DRAIN_LIMIT_S + line_seconds(len(before), baud))
    transport.write(PROBE_QUERY)
    clock = transport.now
    deadline = clock() + REPLY_TIMEOUT_S + line_seconds(len(PROBE_QUERY) + len(PROBE_PACKETS), baud)
    reply = b""
    while len(reply) < len(PROBE_PACKETS) and (remaining := deadline - clock()) > 0:
        reply += transport.read(remaining)
    if reply:
        reply += transport.read(quiet)  # anything more means it was not our reply
    return Probe(baud, reply, noise, is_answer(reply))


def search(transport: Transport, rates: Sequence[int]) -> Search:
    """Probe each of ``rates`` until one answers; the port is left at that rate."""
    probes: list[Probe] = []
    for rate in rates:
        result = probe(transport, rate)
        probes.append(result)
        if result.answered:
            break
    return Search(tuple(probes))


@dataclass(frozen=True, slots=True)
class WakePulse:
    """How a BRC pulse was given, in words (``how``), or why none could be (``problem``);
    ``gone``: the port's own error, when it said the device is no longer there (an
    unplugged USB adapter: EIO, ENXIO, ENODEV), not that it cannot pulse."""

    how: str | None
    problem: str | None = None
    gone: OSError | None = None


#: what a port's device answers once it is unplugged (a USB adapter pulled out, a pty whose
#: other end closed): the device is gone, not a line that cannot be pulsed
GONE_ERRNOS = frozenset({errno.EIO, errno.ENXIO, errno.ENODEV})


def _gone(exc: OSError) -> OSError | None:
    """``exc`` (or the port error a transport's error wraps) if it says the device is gone."""
    cause = getattr(exc, "cause", None)
    error = cause if isinstance(cause, OSError) else exc
    return error if error.errno in GONE_ERRNOS else None


def wake_pulse(transport: Transport, length: float = PULSE_LENGTH_S) -> WakePulse:
    """Pulse BRC for ``length`` s, then let the robot come up.

    First through the modem lines (RTS and DTR asserted: BRC low). Where they cannot be set
    (the ioctl fails: a pty, a few adapters) the line is hung up instead for ``length`` s
    (:class:`~roomba_bt.robot.wake.HangUpLine`: speed 0, the rate restored after; nothing
    is written meanwhile)."""
    if not isinstance(transport, WakeLine):
        return WakePulse(None, f"{transport.name} cannot drive modem lines")
    if getattr(transport, "modem_lines", True) is False:  # a raw TCP bridge: nor a hang-up
        return WakePulse(None, link_of(transport.name).no_modem_lines)
    try:
        transport.set_wake_line(True)
    except OSError as exc:
        if _gone(exc) is not None or not isinstance(transport, HangUpLine):
            return WakePulse(None, str(exc), _gone(exc))
        try:
            with transport.hung_up():
                _wait(transport, length)
        except OSError as hang_up_exc:
            problem = f"{exc}; nor by a hang-up: {hang_up_exc}"
            return WakePulse(None, problem, _gone(hang_up_exc))
        how = (
            f"pulsed BRC by a {length:g} s hang-up (the modem lines cannot be set here: "
            "speed 0 drops DTR and RTS, the rate's return raises them)"
        )
    else:
        try:
            try:
                _wait(transport, length)
            finally:
                transport.set_wake_line(False)  # BRC let go on every exit, Ctrl-C too
        except OSError as exc:
            return WakePulse(None, str(exc), _gone(exc))
        how = f"pulsed BRC low for {length:g} s (RTS and DTR)"
    _wait(transport, WAKE_SETTLE_S)
    return WakePulse(how)


@dataclass(frozen=True, slots=True)
class Found:
    """Where the robot answered: the rate, every probe made and the wake pulse, if one was
    needed (``woken``) or could not be given (``wake_problem``)."""

    baud: int | None
    before_wake: Search
    after_wake: Search | None
    wake_problem: str | None
    #: how the wake pulse was given (:attr:`WakePulse.how`: by the modem lines, or by a
    #: hang-up where they cannot be set), None where none was
    wake_how: str | None = None

    @property
    def woken(self) -> bool:
        return self.after_wake is not None and self.after_wake.baud is not None

    @property
    def answer(self) -> Probe | None:
        """The probe that answered (its reply holds the mode reading after Start)."""
        return next((p for p in self.probes if p.answered), None)

    @property
    def probes(self) -> tuple[Probe, ...]:
        after = self.after_wake.probes if self.after_wake is not None else ()
        return self.before_wake.probes + after


def find_robot(transport: Transport, preferred: int | None = None, *, wake: bool = True) -> Found:
    """Try the rates; if none answers and ``wake``, pulse BRC and try them again."""
    rates = rates_to_try(preferred)
    first = search(transport, rates)
    if first.baud is not None or not wake:
        return Found(first.baud, first, None, None)
    pulse = wake_pulse(transport)
    if pulse.problem is not None:
        return Found(None, first, None, pulse.problem)
    second = search(transport, rates)
    return Found(second.baud, first, second, None, pulse.how)


#: How long doctor listens, writing nothing, for a stream a run left running (its stop not
#: delivered): several 15 ms frames, and a Wi-Fi link's usual delay.
OVERHEAR_S = 0.15
#: The encoder packets a run always streams: moving counts mean turning wheels.
_ENCODERS = packet_ids("left_encoder_counts", "right_encoder_counts")


@dataclass(frozen=True, slots=True)
class Overheard:
    """A stream that was running before anything was written: its first and last whole
    frames' readings (packet id -> raw value), cut by the packet table alone."""

    first: Mapping[int, int]
    last: Mapping[int, int]

    @property
    def mode_raw(self) -> int | None:
        """Packet 35 as the last frame read it (the mode + 1 rule not applied), or None."""
        return self.last.get(OI_MODE_PACKET)

    @property
    def wheels_turned(self) -> bool | None:
        """Whether the encoders moved between the first and the last frame; None when the
        stream carries no encoders or one frame alone came."""
        if self.first is self.last or not all(p in self.last for p in _ENCODERS):
            return None
        return any(self.first.get(p) != self.last[p] for p in _ENCODERS)


def overheard(transport: Transport, seconds: float = OVERHEAR_S) -> Overheard | None:
    """Listen ``seconds`` without writing a byte: a robot whose run lost its link (a Wi-Fi
    bridge that reset, a cable pulled) streams on, in the mode the run left it in. The
    frames it sent, cut by their ``[19][n]`` headers and checksums, or None if none came."""
    clock = transport.now
    deadline = clock() + seconds
    data = b""
    while (remaining := deadline - clock()) > 0:
        data += transport.read(remaining)
    frames: list[dict[int, int]] = []
    at = 0
    while at + 3 <= len(data):
        size = data[at + 1] + 3
        readings = {}
        if data[at] == STREAM_HEADER and checksum_covers_header(data[at : at + size]) is not None:
            readings = stream_readings(data[at : at + size])
        if readings:
            frames.append(readings)
            at += size
        else:
            at += 1
    return Overheard(frames[0], frames[-1]) if frames else None


def describe_silence(found: Found) -> str:
    """One sentence: what each rate returned (for an error message)."""
    seen = "; ".join(f"{p.baud}: {p.seen}" for p in found.probes)
    if found.wake_problem is not None:
        seen += f"; no BRC pulse possible ({found.wake_problem})"
    elif found.after_wake is not None:  # a pty's was a hang-up, not a BRC pulse by its lines
        after = len(found.after_wake.probes)
        seen += f" (the last {after} after the wake: {found.wake_how or 'a BRC pulse'})"
    return seen


#: Seconds of stream a sample reads (33 frames at one per 15 ms).
SAMPLE_S = 0.5
#: A sample's packets: bumps, mode, charging state, and those whose ranges tell the models
#: apart (a 14-byte frame: fits the 28 bytes of 19200).
SAMPLE_PACKETS: tuple[int, ...] = (
    packet_ids("bumps_wheel_drops", "oi_mode", "charging_state") + MODEL_RANGE_PACKETS
)


@dataclass(frozen=True, slots=True)
class StreamSample:
    """A short stream cut into frames by the packet table alone (no profile: the profile is
    what is being found out): each frame's checksum convention (True: the header summed in,
    a 600 / Create 2; False: left out, a 500), the widest reading of each packet, the bytes
    that were no frame, all the bytes read, how late the first came (None: none did), and
    when each whole frame was read, on the link's clock (a network link's jitter and gaps:
    ``doctor``'s timing)."""

    frame_size: int
    conventions: tuple[bool, ...]
    readings: Mapping[int, int]
    skipped: int
    received: int
    latency: float | None
    arrivals: tuple[float, ...] = ()

    @property
    def frames(self) -> int:
        return len(self.conventions)

    @property
    def header_in_checksum(self) -> bool | None:
        """The convention most frames follow; None when no frame came."""
        if not self.conventions:
            return None
        return sum(self.conventions) > len(self.conventions) / 2


def sample_stream(
    transport: Transport, packets: Sequence[int] = SAMPLE_PACKETS, seconds: float = SAMPLE_S
) -> StreamSample:
    """Stream (148) ``packets`` for ``seconds`` of the link's clock, then pause it."""
    ids = tuple(packets)
    size = stream_frame_size(ids)
    transport.write(oi.stream(ids).data)
    clock = transport.now
    sent = clock()
    deadline = sent + seconds
    data = b""
    latency = None
    reads: list[tuple[int, float]] = []  # (bytes read by then, when)
    while (remaining := deadline - clock()) > 0:
        chunk = transport.read(remaining)
        if chunk:
            data += chunk
            reads.append((len(data), clock()))
        if data and latency is None:  # the first frame's bytes: the line's delay
            latency = clock() - sent
    transport.write(oi.pause_stream().data)
    arrivals: list[float] = []
    read = 0
    conventions: list[bool] = []
    readings: dict[int, int] = {}
    at = skipped = 0
    while at + size <= len(data):
        frame = data[at : at + size]
        verdict = checksum_covers_header(frame)
        if verdict is None:
            at += 1
            skipped += 1
            continue
        conventions.append(verdict)
        for pid, value in stream_readings(frame).items():
            readings[pid] = max(value, readings.get(pid, value))
        at += size
        while reads[read][0] < at:  # the read that brought the frame's last byte
            read += 1
        arrivals.append(reads[read][1])
    return StreamSample(
        size, tuple(conventions), readings, skipped, len(data), latency, tuple(arrivals)
    )


def identify_robot(transport: Transport, baud: int) -> Identification | str:
    """``--profile auto``: the models the robot at ``baud`` may be, told as ``doctor`` tells
    them without ``--allow-reset``: the mode reading right after Start (:func:`probe`: 2 is a
    600's mode + 1), then a :func:`sample_stream` (the checksum convention, readings only one
    model's range allows). Never Reset (7): it restarts a 600's or a Create 2's OI, and the
    500 spec has no such opcode. Why nothing could be told, instead, when the robot did not
    answer; the stream is left paused, the robot in Passive."""
    answer = probe(transport, baud)
    if not answer.answered:
        return (
            f"no answer to Start and a Query List at {baud} baud ({answer.seen}); the "
            "start-up says why"
        )
    drain(transport)
    sample = sample_stream(transport)
    drain(transport)  # the paused stream's last frames
    readings = sample.readings
    return identify(
        mode_plus_one=answer.reply[0] == int(OIMode.PASSIVE) + 1,
        header_in_checksum=sample.header_in_checksum,
        readings={pid: readings[pid] for pid in MODEL_RANGE_PACKETS if pid in readings},
    )
