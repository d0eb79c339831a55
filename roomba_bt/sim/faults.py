"""Faults the simulator injects on request, so the robot connection is tested against the
failures a serial link and a real robot produce.

All draws come from a random generator seeded from the simulator's seed, so a faulty run is
as repeatable as a clean one.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from roomba_bt.oi.encode import BAUD_RATES
from roomba_bt.oi.frames import SLOT_SECONDS

#: the largest ``Faults.odometry_error`` (20 %: far worse than any encoder in use)
MAX_ODOMETRY_ERROR = 0.2


@dataclass(frozen=True, slots=True)
class Faults:
    """What goes wrong, and how often.

    ``corrupt_rate``   probability that a robot->host byte is replaced by a random byte
    ``bit_flip_rate``  probability that a robot->host byte has one of its bits flipped (what a
                       noisy line does; two flips of one bit position in opposite directions
                       within a frame cancel in the 8-bit checksum)
    ``truncate_rate``  probability that a stream frame is cut short: a random 1..n-1 bytes of
                       it are sent, the rest never (the next frame follows at once)
    ``drop_rate``      probability that a stream frame is never sent (its distance/angle lost)
    ``byte_drop_rate`` probability that a robot->host byte is lost on the line (a long or
                       cheap cable: the frame it was in is short by a byte, fails its checksum
                       or takes the next one's first byte, and the host's parser resyncs on
                       the next valid frame; :class:`RobotLine`)
    ``host_drop_rate`` probability that a host->robot byte is lost on the line (the robot's
                       parser then waits for it and takes the next command's bytes in its
                       place: a bad cable loses bytes both ways; :class:`HostLine`)
    ``host_corrupt_rate`` probability that a host->robot byte is replaced by a random byte
    ``latency``        seconds added before robot->host bytes become readable
    ``inject_text``    ASCII the "firmware" prints into the stream, every ``inject_every`` s
    ``disconnect_at``  simulated time (s) at which the link goes away for good (the robot
                       goes on with its last command: robot.py, ``_cut_link``)
    ``reset_at``       simulated time (s) at which the robot resets (as Reset, 7, does: the
                       firmware banner, the OI Off, the stream ended)
    ``stream_stop_at`` simulated time (s) at which the robot stops streaming (the port open,
                       the OI still listening)
    ``stream_gap_at``  simulated time (s) at which the stream pauses by itself for
                       ``stream_gap_s`` (0.8 s by default: the oracle's stream loss), then
                       goes on (a loose connector, a robot busy for a moment)
    ``sleep_at``       simulated time (s) at which the robot falls asleep (deaf until a BRC pulse)
    ``baud_change_at`` simulated time (s) at which the robot's serial port changes its rate
                       (as after a battery swap or a reset: the Create 2 comes back at its
                       default rate, whatever Baud, 129, had set) and streams on at it
    ``baud_change_to`` the rate it changes to (None: the other OI rate, 19200 from 115200
                       and 115200 from anything else)
    ``noise``          standard deviation, in raw units, added to analog sensor signals
                       (cliff, light-bump and wall signals, voltage, currents)
    ``odometry_error`` the encoders' error, as a fraction (0: exact, the default): each
                       wheel's counts are off by a seeded scale (see sim/state.py's
                       ``OdometryError``), and the heading they give drifts slowly
    ``from_stream``    the one-off times (``disconnect_at``, ``reset_at``, ``stream_stop_at``,
                       ``stream_gap_at``, ``sleep_at``, ``baud_change_at``) count from the
                       first step with a stream on (the host's Stream, 148), not from the
                       simulator's start: a served simulator's clock runs from its own start,
                       and a host that opened the port late (a slow start on a loaded
                       machine) found the fault long past; none comes while no stream was on
    """

    corrupt_rate: float = 0.0
    drop_rate: float = 0.0
    latency: float = 0.0
    inject_text: str = ""
    inject_every: float = 1.0
    disconnect_at: float | None = None
    noise: float = 0.0
    bit_flip_rate: float = 0.0
    truncate_rate: float = 0.0
    reset_at: float | None = None
    stream_stop_at: float | None = None
    stream_gap_at: float | None = None
    stream_gap_s: float = 0.8
    sleep_at: float | None = None
    baud_change_at: float | None = None
    baud_change_to: int | None = None
    odometry_error: float = 0.0
    from_stream: bool = False
    host_drop_rate: float = 0.0
    host_corrupt_rate: float = 0.0
    byte_drop_rate: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.from_stream, bool):
            raise ValueError(f"faults.from_stream: found {self.from_stream!r}; allowed: a bool")
        for name, lo, hi in (
            ("corrupt_rate", 0.0, 1.0),
            ("bit_flip_rate", 0.0, 1.0),
            ("truncate_rate", 0.0, 1.0),
            ("drop_rate", 0.0, 1.0),
            ("byte_drop_rate", 0.0, 1.0),
            ("host_drop_rate", 0.0, 1.0),
            ("host_corrupt_rate", 0.0, 1.0),
            ("latency", 0.0, 10.0),
            ("inject_every", SLOT_SECONDS, 3600.0),
            ("noise", 0.0, 4095.0),
            ("odometry_error", 0.0, MAX_ODOMETRY_ERROR),
            ("stream_gap_s", 0.0, 3600.0),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"faults.{name}: found {value!r}; allowed: a number {lo}..{hi}")
            if not lo <= value <= hi or math.isnan(value):
                raise ValueError(f"faults.{name}: found {value!r}; allowed: {lo}..{hi}")
        for name in (
            "disconnect_at", "reset_at", "stream_stop_at", "stream_gap_at", "sleep_at",
            "baud_change_at",
        ):  # fmt: skip
            at = getattr(self, name)
            if at is not None and not (
                isinstance(at, int | float) and not isinstance(at, bool) and at >= 0
            ):
                raise ValueError(f"faults.{name}: found {at!r}; allowed: seconds >= 0")
        if self.baud_change_to is not None and self.baud_change_to not in BAUD_RATES.values():
            rates = ", ".join(str(r) for r in sorted(BAUD_RATES.values()))
            raise ValueError(
                f"faults.baud_change_to: found {self.baud_change_to!r}; allowed: {rates}"
            )
        if not self.inject_text.isascii():
            raise ValueError(
                f"faults.inject_text: found {self.inject_text!r}; allowed: ASCII text only"
            )

    @property
    def timed(self) -> tuple[tuple[float, str], ...]:
        """The one-off faults (not the link's loss), as (time, kind), soonest first."""
        kinds = (
            ("reset", self.reset_at),
            ("stream stop", self.stream_stop_at),
            ("stream gap", self.stream_gap_at),
            (
                "stream gap end",
                None if self.stream_gap_at is None else self.stream_gap_at + self.stream_gap_s,
            ),
            ("sleep", self.sleep_at),
            ("baud change", self.baud_change_at),
        )
        return tuple(sorted((at, kind) for kind, at in kinds if at is not None))


NO_FAULTS = Faults()


def bytes_to_next(rng: random.Random, rate: float) -> int:
    """Bytes to the next one a per-byte fault of probability ``rate`` hits (0: this one),
    drawn geometrically: one draw per hit, not one per byte (a stream is 2 000 bytes a
    second, and ``eval`` runs hours of it)."""
    if rate >= 1.0:
        return 0
    u = 1.0 - rng.random()  # in (0, 1]
    return int(math.log(u) / math.log1p(-rate))


class RobotLine:
    """The robot->host direction of a bad cable (``Faults.byte_drop_rate``): each byte the
    robot sends is lost on its way with that probability, drawn from a generator of its own
    (``robot-line:SEED``), so the other faults of a seed draw as they did without it. The
    simulator's output (:meth:`StreamOutput._emit <roomba_bt.sim.replies.StreamOutput._emit>`)
    passes every byte through here last: stream frames, replies and injected text alike.

    What a marginal cable does, and what the host's parser must survive: a frame with a
    byte lost is one byte short, so its checksum fails, or it is completed by the next
    frame's header (``13 05 1d 02 19 [0d lost] 00 a3 | 13 ...``) and fails there; the parser
    skips to the next ``19`` that heads a valid frame. At 2 % of 29-byte frames' bytes,
    45 % of the frames are broken (``1 - 0.98**29``), and a broken frame can take the next
    one with it (docs/reliability.md, "A cable that loses bytes from the robot")."""

    __slots__ = ("_next", "_rate", "_rng", "dropped", "passed_on")

    def __init__(self, faults: Faults, seed: int) -> None:
        self._rate = faults.byte_drop_rate
        self._rng = random.Random(f"robot-line:{seed}")
        #: bytes still to pass before the next lost one
        self._next = bytes_to_next(self._rng, self._rate)
        #: bytes lost so far, and bytes that reached the host (``run``'s and ``sim``'s
        #: summaries say both)
        self.dropped = 0
        self.passed_on = 0

    @staticmethod
    def of(faults: Faults, seed: int) -> RobotLine | None:
        """The line's faults for a simulator with ``faults``; None when no robot->host byte
        is lost (the common case: the output tests for None)."""
        return RobotLine(faults, seed) if faults.byte_drop_rate else None

    def passed(self, data: bytes) -> bytes:
        """What of ``data`` reaches the host."""
        at = self._next
        if at >= len(data):  # the usual case at a low rate: the whole frame
            self._next = at - len(data)
            self.passed_on += len(data)
            return data
        kept = bytearray()
        start = 0
        while at < len(data):
            kept += data[start:at]
            self.dropped += 1
            start = at + 1
            at = start + bytes_to_next(self._rng, self._rate)
        kept += data[start:]
        self._next = at - len(data)
        self.passed_on += len(kept)
        return bytes(kept)


class HostLine:
    """The host->robot direction of a bad cable (``Faults.host_drop_rate``,
    ``host_corrupt_rate``): each byte the host writes is lost or replaced on its way, drawn
    from a generator of its own (``host-line:SEED``), so the robot->host faults of a seed
    draw as they did without it. The served simulator (``sim --pty``) and the in-process
    link hand the robot every byte through :meth:`Simulator.receive
    <roomba_bt.sim.protocol.OIProtocol.receive>`, which passes them through here first.

    A robot's OI parser knows nothing of a lost byte: it waits for the command's missing data
    byte and takes the next command's first byte as it (``89 00 80 00`` then ``89 ...``:
    a Drive of velocity 128, radius 137 nobody sent), which is what the runtime must notice
    (docs/reliability.md, "Bytes lost on the way to the robot")."""

    __slots__ = ("_corrupt", "_drop", "_rng", "corrupted", "dropped")

    def __init__(self, faults: Faults, seed: int) -> None:
        self._drop = faults.host_drop_rate
        self._corrupt = faults.host_corrupt_rate
        self._rng = random.Random(f"host-line:{seed}")
        #: bytes lost and bytes replaced so far (the ``sim`` summary says them)
        self.dropped = 0
        self.corrupted = 0

    @staticmethod
    def of(faults: Faults, seed: int) -> HostLine | None:
        """The line's faults for a simulator with ``faults``; None when they touch no
        host->robot byte (the common case: :meth:`OIProtocol.receive` tests for None)."""
        return HostLine(faults, seed) if faults.host_drop_rate or faults.host_corrupt_rate else None

    def passed(self, data: bytes | bytearray) -> tuple[bytes, str]:
        """What of ``data`` reaches the robot, and what the line did to it ("" for nothing:
        ``lost c8 of 89 00 c8 80 00``), for the simulator's event (``sim --log``)."""
        rng = self._rng
        kept = bytearray()
        lost: list[str] = []
        changed: list[str] = []
        for byte in data:
            if self._drop and rng.random() < self._drop:
                lost.append(f"{byte:02x}")
                continue
            if self._corrupt and rng.random() < self._corrupt:
                new = rng.randrange(256)
                changed.append(f"{byte:02x}->{new:02x}")
                byte = new
            kept.append(byte)
        if not lost and not changed:
            return bytes(data), ""
        self.dropped += len(lost)
        self.corrupted += len(changed)
        said = [f"lost {' '.join(lost)}"] if lost else []
        said += [f"changed {' '.join(changed)}"] if changed else []
        return bytes(kept), f"{', '.join(said)} of {bytes(data).hex(' ')} from the host"
