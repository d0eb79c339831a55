"""Robot -> host bytes: replies to Sensors (142) and Query List (149), stream frames (148),
and the faults a serial link adds to them (corruption, latency).

A reply is the packets' data bytes in the order asked; a stream frame adds a header, the
n-bytes count, each packet's id, and a checksum that brings the frame's sum to 0::

    reply to [149][2][7][35]      [b7][b35]
    stream of [148][2][7][35]     [19][4][7][b7][35][b35][chk]      every 15 ms

Both are packed from the flat value list (state.py) by one precompiled :class:`struct.Struct`
per packet list (:class:`_Packer`). A stream frame's header and ids never change: its struct
leaves a zero byte in each of their places and in the checksum's, and one integer holding
them in those places is or-ed into the packed bytes. A frame of 23 packets has 25 such bytes,
and each value fetched from a list and packed by ``struct`` costs about 230 instructions,
the or of two 50-byte integers about 2,900 in all. The checksum is or-ed in with them: the
data bytes' sum (the header's and ids' is known) picks one of 256 integers, the header and
ids with each checksum byte (``_Packer.framing``), so the frame is built once, not the body
and then the body and its checksum (about 250 instructions less a frame). Distance (19) and
angle (20) report what accumulated since the last read. The stream frame itself is packed in
``Simulator.step`` (the hot path)::

    struct.pack(values...)    [00][00][00][b7][00][b35][00]     0: a header, id or checksum place
    | framing[sum]            [19][04][07][00][35][00][chk]     sum: of b7, b35 (and 19+4+7+35)
    = frame                   [19][04][07][b7][35][b35][chk]

A layer of the simulator (see state.py).
"""

from __future__ import annotations

import math
import struct
from collections import deque
from collections.abc import Callable
from operator import itemgetter

from roomba_bt.oi.odometry import OLD_FIRMWARE_ANGLE_FACTOR
from roomba_bt.oi.packets import VALID_PACKET_IDS, expand
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import byte_sum_for
from roomba_bt.sim.faults import RobotLine, bytes_to_next
from roomba_bt.sim.power import Power
from roomba_bt.sim.sensing import far_groups

#: n-bytes is one byte: a longer stream cannot be framed
MAX_STREAM_PAYLOAD = 255
_DEGREES_PER_RADIAN = 180.0 / math.pi
_OLD_ANGLE_PER_RADIAN = _DEGREES_PER_RADIAN * OLD_FIRMWARE_ANGLE_FACTOR
#: the analog signals the noise fault disturbs
_ANALOG = (22, 23, 27, 28, 29, 30, 31, 46, 47, 48, 49, 50, 51, 54, 55, 56, 57)


class _Packer:
    """Packs a list of packet ids from the flat value list in one ``struct`` call."""

    __slots__ = (
        "byte_sum", "far", "frame_tools", "framing", "getter", "has_angle", "has_distance",
        "pack", "size", "snapshot", "struct",
    )  # fmt: skip

    def __init__(
        self, ids: tuple[int, ...], profile: RobotProfile, stream: bool, noise: bool = False
    ) -> None:
        codes = [">"]
        idx: list[int] = []
        fixed = bytearray()  # a stream frame's header and ids in their places, zeros elsewhere
        if stream:
            codes.append("xx")
            fixed += bytes((19, stream_payload(ids, profile)))
        for pid in ids:
            if stream:
                codes.append("x")
                fixed.append(pid)
            for member in expand(pid):
                spec = profile.packet(member)
                codes.append(spec.struct_code)
                fixed += bytes(spec.size)
                idx.append(member)
        if stream:
            codes.append("x")  # the checksum's place
            fixed.append(0)
        self.struct = struct.Struct("".join(codes))
        #: its pack, bound once (a look-up less a frame)
        self.pack = self.struct.pack
        getter = itemgetter(*idx)
        self.getter: Callable[[list[int]], tuple[int, ...]] = (
            getter if len(idx) > 1 else (lambda v: (getter(v),))
        )
        members = {m for p in ids for m in expand(p)}
        #: the groups of far sensors it packs (sensing.py: measured every step while streamed)
        self.far = far_groups(members)
        self.has_distance = 19 in members
        self.has_angle = 20 in members
        #: the values need preparing before a frame: distance/angle since last read, noise
        self.snapshot = self.has_distance or self.has_angle or noise
        #: the bytes packed: a reply's, or a whole stream frame's, checksum included
        self.size = self.struct.size
        # The checksum byte is -(sum of the frame's bytes, less the header's 19 where the
        # profile's checksum leaves it out) & 0xFF; the sum taken as the parser takes it, of
        # the data bytes packed (byte_sum adds ``added``), the header's and ids' added here.
        self.byte_sum, added = byte_sum_for(self.size)
        bias = added - sum(fixed) + (0 if profile.checksum_includes_header else 19)
        #: a stream frame's header and ids, and its checksum byte for each low byte of the
        #: packed bytes' sum (``byte_sum(packed) & 0xFF``: the frame's, the bias taken off
        #: here, not every frame), or-ed into the packed bytes (none for a reply)
        header = int.from_bytes(fixed)
        self.framing = tuple(header | (bias - low & 0xFF) for low in range(256)) if stream else ()
        #: what a stream frame is made with, in one tuple (``Simulator.step``): called from
        #: locals, not as ``stream.pack(...)``, whose method look-up on an attribute holding
        #: a callable is not specialised in CPython 3.11 (about 150 instructions a call)
        self.frame_tools = (self.pack, self.getter, self.byte_sum, self.framing, self.size)


def stream_payload(ids: tuple[int, ...], profile: RobotProfile) -> int:
    """The n-bytes of a stream frame of ``ids``: an id byte and the data of each packet."""
    return sum(1 + sum(profile.packet(m).size for m in expand(p)) for p in ids)


class StreamOutput(Power):
    """What the robot has sent and the host has not read; the stream it sends every step."""

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_delayed", "_flip_in", "_frame", "_gapped_stream", "_next_inject", "_out",
        "_plain_output", "_reply_packers", "_stream", "_stream_ids", "_stream_paused",
        "bytes_sent", "frames_sent", "robot_line",
    )  # fmt: skip

    def _init_output(self) -> None:
        faults = self.faults
        self._stream: _Packer | None = None
        self._stream_ids: tuple[int, ...] = ()
        self._stream_paused = False
        #: the stream held back during a ``stream_gap_at`` fault (robot.py), or None
        self._gapped_stream: _Packer | None = None
        self._next_inject = faults.inject_every if faults.inject_text else math.inf
        #: what was sent and not read yet, as sent: a list of byte strings, joined when read
        #: (one frame a step, read after each: read hands the frame itself over, no copy in
        #: and out of a buffer)
        self._out: list[bytes] = []
        #: the last stream frame sent straight out (no fault on the way), after everything in
        #: _out, or None: the step's frame kept in a slot and handed over by read itself, not
        #: appended to a list and joined out of it (about 300 instructions a step); anything
        #: sent after it moves it into _out first (:meth:`_emit`), so the order stays
        self._frame: bytes | None = None
        self._delayed: deque[tuple[float, bytes]] = deque()
        self._reply_packers: dict[tuple[int, ...], _Packer] = {}
        #: no fault touches the bytes on their way out: a frame goes straight into _out
        self._plain_output = not (
            faults.corrupt_rate
            or faults.latency
            or faults.bit_flip_rate
            or faults.truncate_rate
            or faults.drop_rate
            or faults.byte_drop_rate
        )
        #: bytes still to send before the next bit flip (drawn geometrically: one draw per
        #: flip, not one per byte)
        self._flip_in = self._next_flip() if faults.bit_flip_rate else 0
        #: the bytes' way to the host, when a fault loses some (None: every byte arrives)
        self.robot_line = RobotLine.of(faults, self.seed)
        self.bytes_sent = 0
        self.frames_sent = 0

    @property
    def streaming(self) -> bool:
        return self._stream is not None and not self._stream_paused

    @property
    def stream_ids(self) -> tuple[int, ...]:
        return self._stream_ids

    def _end_stream(self) -> None:
        self._stream = None
        self._gapped_stream = None
        self._stream_ids = ()

    def _on_sensors(self, args: bytes) -> None:
        if args[0] in VALID_PACKET_IDS:
            self._emit(self._pack_reply((args[0],)))

    def _on_query_list(self, args: bytes) -> None:
        ids = tuple(p for p in args[1:] if p in VALID_PACKET_IDS)
        if ids:
            self._emit(self._pack_reply(ids))

    def _on_stream(self, args: bytes) -> None:
        ids = tuple(p for p in args[1:] if p in VALID_PACKET_IDS)
        payload = stream_payload(ids, self.profile)
        if payload > MAX_STREAM_PAYLOAD:
            # Neither spec says what the robot does with a list whose frame cannot be
            # framed (n-bytes is one byte); the simulator refuses it and keeps what it had.
            why = f"stream of {payload} bytes (n-bytes is one byte: at most 255)"
            self.event("refused", why)
            return
        self._stream_ids = ids
        self._stream = _Packer(ids, self.profile, True, bool(self.faults.noise)) if ids else None
        self._settle_far()  # a stream reads them every step (sensing.py)
        self._stream_paused = False
        self.values[38] = min(len(ids), 108)

    def _on_pause_resume(self, args: bytes) -> None:
        self._stream_paused = args[0] == 0

    # ------------------------------------------------------------------ robot -> host
    def read(self) -> bytes:
        """Everything the robot has sent and the host has not read yet."""
        frame = self._frame
        out = self._out
        if frame is not None and not out:  # the usual read: the step's frame alone
            self._frame = None  # (a frame is kept apart only with no latency: none delayed)
            return frame
        if self._delayed:
            now = self.time
            while self._delayed and self._delayed[0][0] <= now + 1e-9:
                out.append(self._delayed.popleft()[1])
        if not out:
            return b""
        if frame is not None:  # the frame came last
            self._frame = None
            out.append(frame)
        data = b"".join(out)  # one byte string: itself
        out.clear()
        return data

    def _discard_output(self) -> None:
        """Nothing sent and unread reaches the host (the link lost)."""
        self._out.clear()
        self._frame = None
        self._delayed.clear()

    def _emit(self, data: bytes) -> None:
        if self.disconnected:
            return
        frame = self._frame
        if frame is not None:  # sent before these bytes
            self._frame = None
            self._out.append(frame)
        faults = self.faults
        if faults.corrupt_rate:
            rng = self._fault_rng
            rate = faults.corrupt_rate
            buf = bytearray(data)
            for i in range(len(buf)):
                if rng.random() < rate:
                    buf[i] = (buf[i] + rng.randrange(1, 256)) & 0xFF
            data = bytes(buf)
        if faults.bit_flip_rate:
            data = self._flip_bits(data)
        self.bytes_sent += len(data)
        if self.robot_line is not None:  # last: the bytes the other faults made, lost
            data = self.robot_line.passed(data)
            if not data:
                return
        if faults.latency:
            self._delayed.append((self.time + faults.latency, data))
        else:
            self._out.append(data)

    def _next_flip(self) -> int:
        """Bytes to the next flipped one: geometric with the per-byte rate (0: this one)."""
        return bytes_to_next(self._fault_rng, self.faults.bit_flip_rate)

    def _flip_bits(self, data: bytes) -> bytes:
        """``data`` with one bit flipped in each byte the geometric draws land on."""
        at = self._flip_in
        if at >= len(data):
            self._flip_in = at - len(data)
            return data
        buf = bytearray(data)
        rng = self._fault_rng
        while at < len(buf):
            buf[at] ^= 1 << rng.randrange(8)
            at += 1 + self._next_flip()
        self._flip_in = at - len(buf)
        return bytes(buf)

    def _pack_reply(self, ids: tuple[int, ...]) -> bytes:
        packer = self._reply_packers.get(ids)
        if packer is None:
            packer = self._reply_packers[ids] = _Packer(ids, self.profile, False)
        if packer.far:
            self._settle_far()
        return packer.pack(*packer.getter(self._snapshot_values(packer)))

    def _snapshot_values(self, packer: _Packer) -> list[int]:
        """The value list to send now: distance/angle since last read, noise if asked."""
        v = self.values
        if packer.has_distance:
            d = round(self._distance_acc)
            if d:
                d = -32768 if d < -32768 else 32767 if d > 32767 else d
                self._distance_acc -= d
            v[19] = d
        if packer.has_angle:
            acc = self._angle_acc
            if self.old_firmware_angle:
                a = round(acc * _OLD_ANGLE_PER_RADIAN)
                self._angle_acc -= a / _OLD_ANGLE_PER_RADIAN
            else:
                a = round(acc * _DEGREES_PER_RADIAN)
                self._angle_acc -= a / _DEGREES_PER_RADIAN
            v[20] = -32768 if a < -32768 else 32767 if a > 32767 else a
        if self.faults.noise:
            noisy = list(v)
            rng = self._fault_rng
            sigma = self.faults.noise
            for pid in _ANALOG:
                value = round(noisy[pid] + rng.gauss(0.0, sigma))
                if pid in (23, 54, 55, 56, 57):
                    noisy[pid] = max(-32768, min(32767, value))
                elif pid == 22:
                    noisy[pid] = max(0, min(65535, value))
                else:
                    noisy[pid] = max(0, min(4095, value))
            return noisy
        return v
