"""The link side of a tick alone: recorded stream bytes read through a real
:class:`~roomba_bt.robot.connection.Connection`, with no simulator, tree or runtime loop.

What the runtime does with one stream frame before its tick starts is
``Connection.poll_frames`` (keep-awake, the read, the stream parser, the mode model, the
watchdog) and ``HazardConfirmation.frame``. :func:`prepare` replays the simulator's recording of an
episode (``bench/data/sim_replay.json``, :mod:`bench.sim_replay`) once to collect the chunks
the robot sent, one per 15 ms step, and returns a function that reads them back through a
started connection: the host's start-up commands (Start, Safe, the stream the episode asked
for) written first, then ``poll_frames`` until every chunk is read, each frame handed to the hazard
confirmation as the runtime does. The chunks' transport keeps its own clock (15 ms a read)
and drives a BRC line, so keep-awake runs as it does on the simulator.

``--noisy`` damages the recorded bytes the same way every run (a flipped byte now and then,
a chunk split in two, garbage between frames) so the parser's slow paths are measured too.

A digest of every frame handed over (its index, arrival time and values, after the hazard
confirmation) and of the link's counters, the mode and the link's status is printed: two
versions of the link that print the same digest handed the runtime the same frames (the
runs counted by callgrind leave the frames out of the digest, which would cost more than
the link).

``python -m bench.link_replay [dock|bump] [--noisy] [--icount]``: the digest, and with
``--icount`` the instructions a frame by callgrind ((replay of all chunks - replay of none) /
chunks, each in a fresh interpreter).
"""

from __future__ import annotations

import hashlib
import random
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: a stream frame every 15 ms
SLOT = 0.015


def recorded(kind: str) -> tuple[str, tuple[int, ...], list[bytes]]:
    """The profile, the stream's packet ids and the chunks the robot sent in the recorded
    episode ``kind``, one a step, from the first step after the stream was asked on."""
    from bench import sim_replay

    recording = sim_replay.load(kind)
    ids: tuple[int, ...] = ()
    streamed_from = 0
    for tick, what, arg in recording["inputs"]:
        if what == "receive" and arg.startswith("94"):  # Stream (148): [148][n][ids...]
            ids = tuple(bytes.fromhex(arg)[2:])
            streamed_from = tick
            break
    chunks = list(sim_replay.sent(recording))[streamed_from:]
    return str(recording["profile"]), ids, chunks


def damaged(chunks: list[bytes], seed: int = 18) -> list[bytes]:
    """The same chunks with noise, the same every run: one chunk in 40 a byte flipped, one
    in 40 split over two reads, one in 60 garbage (with a stray header byte) before it."""
    rng = random.Random(seed)
    out: list[bytes] = []
    for chunk in chunks:
        data = bytearray(chunk)
        roll = rng.random()
        if data and roll < 0.025:
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        elif roll < 0.042:
            data[:0] = bytes((0x55, 19, 0xAA))[: rng.randrange(1, 4)]
        if data and 0.05 <= roll < 0.075:
            cut = rng.randrange(1, len(data))
            out += (bytes(data[:cut]), bytes(data[cut:]))
        else:
            out.append(bytes(data))
    return out


class ChunkTransport:
    """The recorded chunks behind the Transport contract: one chunk a read, 15 ms a read on
    its own clock; writes are kept; a BRC line that can be driven."""

    name = "replay://"
    is_open = True
    baud = 115200

    def __init__(self, chunks: list[bytes]) -> None:
        self.chunks = chunks
        self.at = 0
        self.time = 0.0
        self.written = bytearray()

    def read(self, timeout: float) -> bytes:
        self.time += SLOT
        at = self.at
        if at >= len(self.chunks):
            return b""
        self.at = at + 1
        return self.chunks[at]

    def now(self) -> float:
        return self.time

    def write(self, data: bytes) -> None:
        self.written += data

    def set_baud(self, baud: int) -> None:
        self.baud = baud

    def set_wake_line(self, low: bool) -> None:
        pass

    def close(self) -> None:
        pass


def prepare(kind: str, noisy: bool = False) -> tuple[int, Callable[[int, bool], str]]:
    """The number of chunks of ``kind`` and a function that polls a started connection until
    it has read that many of them (or fewer) and returns the digest of what it handed over."""
    from roomba_bt.oi import commands as oi
    from roomba_bt.oi.modes import OIMode
    from roomba_bt.robot.connection import Connection
    from roomba_bt.robot.hazards import HazardConfirmation

    profile, ids, chunks = recorded(kind)
    if noisy:
        chunks = damaged(chunks)
    transport = ChunkTransport(chunks)
    connection = Connection(transport, profile, watchdog=0.1)
    connection.modes.calibrate(1, 0.0)  # the robot answered Passive right after Start
    connection.link.mode_plus_one = connection.modes.plus_one
    connection.send(oi.start())
    connection.send(oi.safe())
    connection.send(oi.stream(ids))
    assert connection.mode is OIMode.SAFE
    hazards = HazardConfirmation()

    def run(reads: int, frames_digested: bool = True) -> str:
        digest = hashlib.sha256()
        poll, confirm, link = connection.poll_frames, hazards.frame, connection.link
        if not frames_digested:  # what is counted: no digest of each frame
            while transport.at < reads:
                for got in poll(0.05):
                    confirm(got)
        while transport.at < reads:
            batch = poll(0.05)
            first = link.index - len(batch) + 1  # the frames' numbers, and when they came
            for index, got in enumerate(batch, first):
                frame = confirm(got)
                digest.update(repr((index, link.arrival, frame.values)).encode())
        counters = connection.counters
        digest.update(repr((counters, hazards.held, hazards.unconfirmed)).encode())
        digest.update(repr((connection.mode, connection.link.status)).encode())
        return digest.hexdigest()[:16]

    return len(chunks), run


def _child(kind: str, noisy: bool, reads: int) -> None:
    _, run = prepare(kind, noisy)
    print(run(reads, False))


def _count(kind: str, noisy: bool, reads: int) -> int:
    from bench.icount import callgrind

    return callgrind("bench.link_replay", kind, "noisy" if noisy else "clean", str(reads))[0]


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        _child(argv[1], argv[2] == "noisy", int(argv[3]))
        return 0
    kind = next((arg for arg in argv if not arg.startswith("--")), "dock")
    noisy = "--noisy" in argv
    chunks, run = prepare(kind, noisy)
    print(f"{kind}{' (noisy)' if noisy else ''}: {chunks} chunks, digest {run(chunks, True)}")
    if "--icount" in argv:
        full, none = _count(kind, noisy, chunks), _count(kind, noisy, 0)
        print(f"Connection.poll_frames + HazardConfirmation.frame: {(full - none) / chunks:,.0f} "
              "instructions a chunk (callgrind)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
