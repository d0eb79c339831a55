"""``--record`` and ``replay``: every byte in and out, with its time, and playing it back.

A record is JSON Lines, one object a line::

    {"format": "roomba-bt-record", "version": 2, "roomba_bt_version": "0.2.0",
     "profile": "create2", "baud": 115200, "mission": "../missions/dock.yaml",
     "relative_to": "record", "mission_path": "/home/me/repo/missions/dock.yaml",
     "parameters": {...}, "packets": [7, 9, ...], "watchdog": 0.1, "grace": 2.0,
     "port": "/dev/ttyUSB0", "started": "2025-03-04T09:12:05Z", "label": "robot 3",
     "sources": {"../missions/dock.yaml": "9f86d0...", "roomba-bt:lib/docking.yaml": ...},
     "plugins": {"roomba-bt-dirt": {"version": "0.1.0", "sha256": "84755334..."}},
     "simulator": {"world": "../worlds/lab.yaml", "world_sha256": ..., "seed": 0, ...},
     "options": {"timeout": "10min", "include_dirs": [], ...}}
    {"t": 0.000000, "d": "out", "b": "80"}          <- host -> robot, hex
    {"t": 0.015012, "d": "in",  "b": "1305..."}     <- robot -> host, hex
    {"t": 3.120000, "d": "note", "note": {...}}     <- an act: the monitor's force, the tick
                                                       guard's or the watchdog's drive 0
    {"t": 3.240000, "d": "note", "note": {"baud": 19200}}  <- the port's rate changed (a
                                                       listen at another rate, the port
                                                       put back, Baud (129) followed)
    {"t": 9.060000, "d": "note", "note": {"ended": "interrupted", "reason": "stopped by the
        operator", "time": 8.91, "tick": 594, "at": "before"}}   <- how the run ended
    {"t": 9.075000, "d": "end"}                     <- the run's end (version 2 on)

The end note (``ended``, written after the safe stop) holds the run's outcome, its reason, its
mission time and where its end came (the stream tick of its last frame, before or after the
tree's tick on it): ``replay`` and ``roomba-bt monitor`` say how the recorded run ended, and a
replay ends an interrupted run (the monitor's stop, Ctrl-C, ``stack.stop()``) or a timed-out
one where it ended, where before it ticked the tree on past it (the tree wrote a command where
the record holds the safe stop: a difference at the record's last bytes). A record without it
(made before) is replayed as before. A Ctrl-C or SIGTERM that came before the tick was written
whole (``"at": "before"``) notes the bytes of the "out" side written by then (``written``):
one that came between two writes of that tick left part of it on the wire, and the replay
writes the tick up to there (:meth:`ReplayTransport.interrupt_at`).

The header names the roomba-bt release that made the record (``roomba_bt_version``), the
SHA-256 of each file its mission was compiled from (``sources``) and each installed plugin
its tree used, with its version and its modules' digest (``plugins``;
``runtime/provenance.py``): a replay says in one line when it ran on other files or plugins,
and one that differs names each changed since. An older record may have none of them. The
header's ``mission`` names a shipped mission as an include does (``roomba-bt:dock.yaml``; an
older record, a path in the installation that made it), any other by its path from the
record's folder where the two share a folder below the root (``relative_to``: ``record``, so
that a record committed beside its missions replays in every checkout: its absolute path
is in ``mission_path``, for the reader), else by its absolute path. The simulator's
options (``simulator``) and the run's (``options``) say how to make it again;
``run --reproducible`` leaves out ``started`` (unless ``SOURCE_DATE_EPOCH`` gives it) and
``mission_path``, which change on every run with nothing changed.

``"stop_listened": true`` in the header (:data:`STOP_LISTENED`) says the
run's safe stop was listened and asked after (the wall clock; the simulator's line losing
bytes): its replay does the same on the recorded bytes (docs/runtime.md, Replaying a stop that
needed more than one try). A record without it is replayed without listening, as before.

The header also holds the run's ``watchdog`` and ``grace`` (seconds), and each watchdog trip
is a note (``{"watchdog": 0.101, "limit": 0.1}``, at the link time it tripped): a replay's
link trips where the record's did, and nowhere else (``StreamLink.replayed_trips``), so a
run whose watchdog stopped the wheels (a stall ridden through: a noisy cable, a paused
stream) replays byte for byte. A record made before (no ``watchdog`` in its header) is
replayed with the watchdog on the record's clock, at the default 100 ms and grace 2 s: its
stalls replay too, unless the run had another ``--watchdog`` or ``--grace``, or a read that
woke late (a loaded machine) took frames the record stamps past the watchdog, where the
live run did not trip (the replay does: a difference). Before, a replay ran no watchdog, and
the first stall of a record was its first difference ("expected Drive (137) 89 00 00 00 00,
sent nothing"). A stream asked for again during a silent stall is a note too
(``{"stream_again": 1, "silent": 0.667}``, at the link time it was written): a replay asks
where the record did and nowhere else (``robot/stall_asks.py``).

``t`` is the link's own clock (``transport.now()``) relative to the first byte, so a record
made on the virtual clock replays identically, and one made on a robot replays with the
robot's timing. Replay feeds the recorded "in" bytes, at their recorded times, through the same
parser, mode model and tree; the bytes the tree writes are compared with the recorded "out"
bytes to show where a changed mission decides differently.

The end line is written when the run closes the link, after its safe stop. A record without
it stops where its run did not end: a run killed outright (``kill -9``), a full disk, or a
version 1 record (they had no end line). Replay compares such a record up to where it ends:
the bytes the tree writes after the record's last robot bytes are not a difference (the live
run's were lost, or never written); before, the replay's own safe stop at the end of the
input was reported as the first difference ("expected nothing, sent Drive").

A record named ``*.gz`` (``--record run.jsonl.gz``) is written gzip-compressed, the same lines
(about 12 times smaller: a plain record is some 45 MB an hour of run); before, such a name got
plain text. Its flushes (every :data:`FLUSH_EVERY_S`) are zlib sync flushes, so the file as a
``kill -9`` leaves it decompresses up to its last flush, as a plain record reads up to its
own. A full disk or a file size limit ends it with the same note as a plain record
(:data:`RECORD_STOPPED`): the file is cut back to one of its last flushes, where the deflate
stream is at a byte's boundary after a whole line, and the note follows as a final block of
its own with gzip's trailer, so the file is a whole gzip file again (before, it got no note,
and its replay said the run was killed or its writing failed). A record is read by what its
first bytes are, not by its name (:func:`open_record`): gzip's magic number is decompressed
whatever the file is called (``cp run.jsonl.gz copy``), and a plain record named ``.gz`` is
read as plain text.

``run --record-max SIZE`` ends a record, plain or compressed, the same way at a size of the
user's (:attr:`RecordingTransport.max_bytes`): a night's run cannot fill the disk, and the
file up to the note is a record every reader takes.
"""

from __future__ import annotations

import contextlib
import errno
import gzip
import io
import json
import logging
import math
import os
import re
import shlex
import stat
import struct
import sys
import time
import zlib
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sized
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any, Literal, Protocol, TypeVar

from roomba_bt import __version__
from roomba_bt.errors import RoombaBtError
from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import BAUD_CODES, command_size, decode_command
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.printable import ANY_CONTROL, broken_link, escaped, shortened
from roomba_bt.robot import wording
from roomba_bt.robot.safety import interrupts_deferred
from roomba_bt.runtime.claimed import ClaimedFile, held_by_a_writer
from roomba_bt.runtime.summary import PLANNED_END
from roomba_bt.transport.base import Transport

log = logging.getLogger(__name__)

RECORD_FORMAT = "roomba-bt-record"
RECORD_VERSION = 2
#: the versions this roomba-bt reads: 1 is 2 without the end line
READ_VERSIONS = (1, 2)
#: the header field naming the roomba-bt release that made the record (none before 0.2.0,
#: whose records could not say which build made them)
MADE_BY = "roomba_bt_version"
#: the header field holding the SHA-256 of each file the mission was compiled from
SOURCES = "sources"
#: the header field naming each installed plugin (a distribution with an entry point in
#: ``roomba_bt.behaviours``) whose behaviours the mission's tree holds: its version and the
#: SHA-256 of its modules' files (absent before: no plugin could be told apart)
PLUGINS = "plugins"
#: the header field saying what its relative paths (``mission``, ``sources``' names, the
#: world and the include folders) are relative to: ``"record"``, the record file's folder
#: (absent before: every path was absolute, a shipped file's aside)
RELATIVE_TO = "relative_to"
RELATIVE_TO_RECORD = "record"
#: the header field holding the mission's absolute path when the run was recorded, for the
#: reader (and a replay of a record moved away from its mission); left out by ``run
#: --reproducible``, whose header is the same in every checkout
MISSION_AT = "mission_path"
#: the header field holding the simulator's options as the run was given them (``world``,
#: ``world_sha256``, ``seed``, ``random_start``, ``battery``, ``odometry_error``, ``fast``):
#: with the mission and the run's ``options`` (:data:`RUN_OPTIONS`), what runs it again.
#: Absent on a robot's port, and in a record made before
SIMULATOR = "simulator"
#: the header field holding the run's options that decide its bytes besides the mission and
#: the simulator, as given (``timeout``, ``include_dirs``, ``allow_plugin_files``, ``end_in``)
RUN_OPTIONS = "options"

#: header key, ``"stop"`` where the recorded run ended its stop in Off (``end_in="stop"``,
#: ``run --end-in stop``: Stop (173) for Start); absent for Start, as in an older record.
#: Its replay ends so too (:func:`recorded_end_in`): ended with Start, such a record's last
#: byte would be its first difference ("expected Stop (173) ad, sent Start (128) 80", exit 1)
END_IN = "end_in"


#: the last bytes a safe stop that ends in Off writes, from any mode: pause the stream
#: ``[150][0]``, then Stop ``[173]`` (``robot.ending.stop_sequence``; one ending in Passive
#: writes Start ``[128]`` last)
STOP_ENDING = oi.pause_stream().data + oi.stop().data


def recorded_end_in(header: Mapping[str, Any], ended: bytes = b"") -> Literal["passive", "stop"]:
    """How the recorded run's stop ended: :data:`END_IN`, or in a record made before it the
    run's ``options`` (``run --end-in``, :data:`RUN_OPTIONS`); where neither says (a record
    of 0.1.0's, or a Python program's ``end_in="stop"`` made before the header said it),
    ``"stop"`` if the recorded bytes ``ended`` (:attr:`Record.out_tail`) end as such a stop
    writes (:data:`STOP_ENDING`); Start (``"passive"``) else. The bytes are safe to go by:
    a safe stop that ends in Passive never writes Stop last, and a tree that wrote Stop
    itself turned the OI off, so its run's stop sends nothing, however it would end."""
    options = header.get(RUN_OPTIONS)
    given = header.get(END_IN, options.get("end_in") if isinstance(options, dict) else None)
    if given is None and ended.endswith(STOP_ENDING):
        return "stop"
    return "stop" if given == "stop" else "passive"


#: what ``replay`` says where the recorded run's stop ended with Stop and the replay's with
#: Start, the record saying nothing of it and its last bytes no stop's: the difference said,
#: not left a riddle at the record's end
END_IN_UNSAID = (
    "the recorded run wrote Stop (173) where the replay's stop wrote Start (128): the record "
    'does not say its run ended in Off (end_in="stop", run --end-in stop; a record made by '
    "0.1.0 says nothing of it), and its last bytes are not the stop's, by which a replay "
    "otherwise tells; the tree's own bytes are compared up to there"
)


def end_in_unsaid(header: Mapping[str, Any]) -> bool:
    """Whether the record's header says nothing of how its stop ended: neither :data:`END_IN`
    nor its ``options`` (:func:`recorded_end_in` then goes by its last bytes)."""
    options = header.get(RUN_OPTIONS)
    return END_IN not in header and not (isinstance(options, dict) and "end_in" in options)


#: header key, true where the recorded run's stop was listened after and asked after (the
#: wall clock, a real line; the simulator's line losing bytes to the robot:
#: ``ending.listened_after``): its replay takes the same decisions from the recorded bytes,
#: and writes the zeros, the stop again, the Query List and the other rates' stops the
#: recorded run wrote. A record made before has none: replayed as then, never listened after.
STOP_LISTENED = "stop_listened"

#: header key, the seconds of the link's clock a read with nothing to give waits, one step at
#: least, where they come in steps: the in-process simulator's 15 ms (``SimLink.read_step``,
#: ``run --fast``). A read there whose wait was shorter than a step got the next step's
#: frame, and its replay, which gave a chunk only to a read whose wait reached its stamp,
#: gave it to the read after: on a cable losing the robot's bytes (``--byte-drop-rate``),
#: the watchdog's short waits between broken frames, the replay of 4 records in 10 differed
#: ("first difference ... expected Drive (137) 89 00 96 fc 18, sent nothing", exit 1).
#: A record made before has none: replayed as then.
READ_STEP = "read_step"

#: Seconds of the link's clock between two flushes of the record to the operating system: a
#: run killed outright (``kill -9``, the OOM killer) loses at most this much of its record.
#: Before, the file was flushed only at the run's end, and a killed 2 s run's record stopped
#: at 1.22 s (what an 8 KiB buffer held). A flush is a write(2) of what is buffered, not an
#: fsync: a power cut can still lose what the operating system had not written out.
FLUSH_EVERY_S = 0.25

#: A record path ending in this is written gzip-compressed (``--record run.jsonl.gz``).
COMPRESSED_SUFFIX = ".gz"
#: The two bytes every gzip file starts with (RFC 1952): a record is read compressed when it
#: starts with them, whatever its name.
GZIP_MAGIC = b"\x1f\x8b"
#: zlib's level for a compressed record: its default, 6. A 1-hour bump-and-turn record, 23.6 MB
#: plain, is 2.34 MB at 6 (its run took 4.6 s of wall time on the virtual clock, the plain
#: one's 5.0 s) and 2.81 MB at 1; the sync flushes cost 0.3 MB of it (``gzip -6`` of the
#: plain file: 2.03 MB). Measured: docs/runtime.md, Long unattended runs.
COMPRESS_LEVEL = 6


def compressed_name(path: str | Path) -> bool:
    """Whether ``run --record`` writes ``path`` gzip-compressed (its name ends in ``.gz``)."""
    return str(path).lower().endswith(COMPRESSED_SUFFIX)


class LineFile(Protocol):
    """What a record's lines are written to: a text file (a plain record), or
    :class:`_CompressedLines`."""

    @property
    def closed(self) -> bool: ...

    def write(self, text: str, /) -> int: ...

    def flush(self) -> None: ...

    def fileno(self) -> int: ...

    def close(self) -> None: ...


#: how many lines a compressed record gathers before it compresses them (some 5 KB of text,
#: as a text file's 8 KB buffer: a line alone would cost zlib a call each)
LINES_PER_COMPRESS = 64


class _CompressedLines:
    """A compressed record's lines, written through gzip into ``raw``, which closing closes
    (a :class:`gzip.GzipFile` handed a file leaves it open, and with it the record's lock).
    Its ``flush`` is the gzip file's, a zlib ``Z_SYNC_FLUSH`` written out to the file: what
    was written before it decompresses from the file as it stands, so a run killed outright
    leaves a readable record up to its last flush, as a plain one does. No file name and a
    zero time in the gzip header: ``run --reproducible`` writes the same bytes again.

    Whole whatever signal comes: ``GzipFile.write`` writes the compressed text to the file
    and only then counts it into the CRC-32 and length of gzip's trailer, and a run's
    signal handler raises wherever the main thread is: between the two, it leaves a
    trailer that does not match the text (``gzip -t``: crc error; replay refuses the whole
    record: 3 of 17 SIGTERM'd ``--fast`` records were so). So gzip is called only
    within :data:`~roomba_bt.robot.safety.interrupts_deferred`, where the interrupt waits
    for the call to end; and the lines are gathered here, not in a ``TextIOWrapper``, which
    drops what it had gathered when the write it hands them to raises (an interrupt at
    that write's first line), and whose every line a deferral around it would have cost
    as much again."""

    def __init__(self, raw: IO[bytes]) -> None:
        self._raw = raw
        with interrupts_deferred:  # gzip's header, written here in several writes, whole
            self._gzip = gzip.GzipFile(
                filename="", mode="wb", fileobj=raw, compresslevel=COMPRESS_LEVEL, mtime=0
            )
        #: the lines written since the last compress
        self._lines: list[str] = []
        #: after each flush that reached the file, the latest last: the file's size then
        #: (a sync flush ends on a byte, after a whole line), and the CRC-32 and length of
        #: the text up to there, which gzip's trailer holds (:meth:`end_with`)
        self._flushed: deque[tuple[int, int, int]] = deque(maxlen=FLUSHES_KEPT)

    @property
    def closed(self) -> bool:
        return self._raw.closed

    def fileno(self) -> int:
        return self._raw.fileno()

    def write(self, text: str) -> int:
        """Gather ``text`` (whole lines), compressed with the next :data:`LINES_PER_COMPRESS`
        or at the next flush. An interrupt here is raised with it gathered, or not."""
        if self._raw.closed:
            raise ValueError("write to a closed record")
        lines = self._lines
        lines.append(text)
        if len(lines) >= LINES_PER_COMPRESS:
            self._compress()
        return len(text)

    def _compress(self) -> None:
        """The gathered lines into gzip, whole (the interrupt of a signal meanwhile waits)."""
        with interrupts_deferred:
            text = "".join(self._lines).encode("utf-8")
            self._lines.clear()  # before the write: a full disk's lines are lost, not repeated
            self._gzip.write(text)

    def flush(self) -> None:
        with interrupts_deferred:  # a sync flush's bytes are all written, or none made
            self._compress()
            self._gzip.flush()
            self._flushed.append((self._raw.tell(), self._gzip.crc, self._gzip.tell()))

    def end_with(self, line: bytes, within: int | None = None) -> bool:
        """End the file, whose write just failed, with ``line`` (the recording's stop note)
        and gzip's trailer, as :func:`_mark_stopped` ends a plain record: cut back to the
        latest flush that leaves room for them within the bytes the file held (a size limit
        or a full disk is not gone past), or within ``within`` bytes when fewer (``run
        --record-max``), the chunks after it lost. The deflate stream there
        is at a byte's boundary (a sync flush), so a final block compressed on its own
        (nothing of it refers back) and the trailer's CRC-32 and length of the whole text
        make the file a whole gzip file again: ``zcat`` and every reader take it. Before, a
        compressed record got no note (its bytes could not be cut back to a line's end),
        and its replay said the run was killed or its writing failed. True if it was
        written; a device or a failure before the first flush gets none."""
        try:
            fd = self._raw.fileno()
            held = os.fstat(fd)
            if not stat.S_ISREG(held.st_mode):
                return False
            room = _room(held, within)
            for size, crc, length in reversed(self._flushed):
                ending = _gzip_ending(line, crc, length)
                if size + len(ending) <= room:
                    os.ftruncate(fd, size)
                    os.lseek(fd, size, os.SEEK_SET)
                    return os.write(fd, ending) == len(ending)
            return False
        except (OSError, ValueError):
            return False
        finally:
            _write_nowhere(self)

    def close(self) -> None:
        try:
            with interrupts_deferred:
                if not self._gzip.closed:
                    self._compress()
                    self._gzip.close()  # the last block and gzip's trailer
        finally:
            self._raw.close()


#: how many of a compressed record's last flushes are kept to cut back to (one each
#: :data:`FLUSH_EVERY_S` while frames come: some 16 s of record, 300 bytes to a few KB of it)
FLUSHES_KEPT = 64


def _gzip_ending(line: bytes, crc: int, length: int) -> bytes:
    """``line`` as a final deflate block compressed on its own, then gzip's trailer for a
    text whose first ``length`` bytes had the CRC-32 ``crc`` (RFC 1952: CRC-32, then the
    length modulo 2**32, both little-endian)."""
    deflate = zlib.compressobj(COMPRESS_LEVEL, zlib.DEFLATED, -zlib.MAX_WBITS)
    block = deflate.compress(line) + deflate.flush(zlib.Z_FINISH)
    trailer = struct.pack("<II", zlib.crc32(line, crc), (length + len(line)) & 0xFFFFFFFF)
    return block + trailer


def _open_for_writing(claimed: ClaimedFile, path: str) -> LineFile:
    """The record's file, emptied, for its lines: gzip-compressed when named ``.gz``."""
    if compressed_name(path):
        return _CompressedLines(claimed.open_binary())
    return claimed.open_text()


#: the bytes a required record's header may take on disk beyond its line's (a compressed
#: record's gzip header and deflate blocks: a short line compresses to more than itself),
#: made room for before an earlier record in the file is emptied (``ClaimedFile.make_room``)
HEADER_SLACK = 64


class RecordNotStarted(OSError):
    """A record the run may not go without (``required``, ``run --require-record``) could
    not be started: its header was not written (``strerror``: why; a full disk)."""


class RecordingTransport:
    """Wraps a transport; writes every chunk in and out to a JSON Lines record.

    The record is a witness, not the run: a file that can no longer be written (the disk
    full, a USB stick pulled) stops the recording, said once, and the run goes on; the
    port's own errors are the port's. Before, the file's ``OSError`` rose from a read or a
    write of the port, and the run ended as a lost port without its safe stop."""

    def __init__(
        self,
        inner: Transport,
        path: str | Path,
        header: dict[str, Any],
        claimed: ClaimedFile | None = None,
        max_bytes: int | None = None,
        required: bool = False,
    ) -> None:
        """``claimed``: ``path`` already claimed (``run`` claims it before it opens the
        robot); else it is claimed here. Either way a file another run writes is refused
        (:class:`~roomba_bt.runtime.claimed.FileInUse`, an OSError) before it is emptied.
        ``max_bytes``: the file's size limit (``run --record-max``), None for none; less
        than :data:`MIN_RECORD_MAX` is a ValueError. ``required``: the run may not go on
        without its record (``run --require-record``): a header that cannot be written is
        :class:`RecordNotStarted`, not the warning that the run goes on."""
        if max_bytes is not None and max_bytes < MIN_RECORD_MAX:
            raise ValueError(
                f"max_bytes={max_bytes}: a record's size limit is {size_text(MIN_RECORD_MAX)} "
                "or more (its header and a few seconds of run)"
            )
        self._inner = inner
        #: the wrapped transport's word on its clock (``Transport``'s note)
        self.wall_clock: bool = getattr(inner, "wall_clock", True)
        #: the inner line's word on losing bytes to the robot (``SimLink.loses_bytes``)
        self.loses_bytes: bool = getattr(inner, "loses_bytes", False)
        self.name = inner.name
        self.path = str(path)
        #: written gzip-compressed (the path ends in ``.gz``)
        self.compressed = compressed_name(path)
        head = {"format": RECORD_FORMAT, "version": RECORD_VERSION, MADE_BY: __version__, **header}
        words = _clock_words(self.read_step, self.wall_clock, self.loses_bytes)
        line = json.dumps(head | words) + "\n"
        claiming = claimed is None
        claimed = claimed or ClaimedFile(path)
        if required:  # an earlier record is emptied only once the disk takes the header
            try:
                claimed.make_room(len(line.encode()) + HEADER_SLACK)
            except OSError as exc:
                if claiming:  # a caller's claim is the caller's to let go of
                    claimed.release()
                raise RecordNotStarted(exc.errno, exc.strerror or str(exc), self.path) from None
        self._file: LineFile = _open_for_writing(claimed, self.path)
        self._t0: float | None = None
        #: why and when the recording stopped before the run's end (None: it did not)
        self.stopped: str | None = None
        #: the file's size limit on disk (``run --record-max``; a compressed record's
        #: compressed size): the flush that finds the file past it stops the recording as
        #: a full disk does, cut back to within it, and the run goes on. A limit and not a
        #: rotation (decided): what is kept is the run's start, one file replay reads whole.
        self.max_bytes = max_bytes
        #: the run's mission time now (None before its first tick), for where the recording
        #: stopped: the run's stack gives its runner's; by itself, the record's own clock
        self.mission_time: Callable[[], float | None] = _no_mission_time
        self._flushed_at = -math.inf  # the header goes out at once, and the first chunk
        if required:
            self._header_or_refuse(line, claimed)
        else:
            self._put(line, 0.0)

    def _header_or_refuse(self, line: str, claimed: ClaimedFile) -> None:
        """Write the header of a record the run may not go without, or refuse: the file
        closed, removed when this claim made it and it is still empty (a full disk left
        a 0-byte file behind, beside the refusal), and :class:`RecordNotStarted` raised.
        Its caller says the refusal; a warning that "the run goes on" came before it."""
        try:
            self._file.write(line)
            self._flushed_at = 0.0
            self._flushed()
        except OSError as exc:
            with contextlib.suppress(OSError):
                if claimed.created and os.fstat(self._file.fileno()).st_size == 0:
                    os.unlink(self.path)  # still locked: no other writer has it meanwhile
            with contextlib.suppress(OSError):  # its flush fails again; the file is closed
                self._file.close()
            raise RecordNotStarted(exc.errno, exc.strerror or str(exc), self.path) from None

    def _put(self, line: str, now: float) -> None:
        """Write one line; flush when :data:`FLUSH_EVERY_S` of the link's clock has passed."""
        try:
            self._file.write(line)
            if now - self._flushed_at >= FLUSH_EVERY_S:
                self._flushed_at = now
                self._flushed()
        except OSError as exc:
            self._stop(exc.strerror or str(exc))

    def _flushed(self) -> None:
        """Flush the file, and stop the recording if that took it past :attr:`max_bytes`
        (checked at each flush, a stat of the file each :data:`FLUSH_EVERY_S`, not at each
        line: between two it grows by a fraction of a second of record, cut back then)."""
        self._file.flush()
        limit = self.max_bytes
        if limit is not None and os.fstat(self._file.fileno()).st_size > limit:
            option = wording.current.record_max  # the caller's: a flag, or a Python argument
            self._stop(f"{option} {size_text(limit)} reached", within=limit)

    def _stop(self, why: str, within: int | None = None) -> None:
        """The file cannot be written (``why``: the error's words), or may not grow past
        ``within`` bytes (:attr:`max_bytes`): close it (what it holds is a record up to
        here), ended by a note that says why, where there is room for one
        (:func:`_mark_stopped`)."""
        # before the first chunk (the header's write failed: ``--record /dev/full``) there is
        # no t0: 0 s, not now() - now(), which a moving clock made ``-0.000 s``
        t = self._inner.now() - self._t0 if self._t0 is not None else 0.0
        mission_time = self.mission_time()
        at = f"{t:.3f} s" if mission_time is None else f"mission time {mission_time:.3f} s"
        self.stopped = f"stopped at {at}: {why}; the file ends there"
        log.warning("%s: the record %s %s (the run goes on)", self.name, self.path, self.stopped)
        _mark_stopped(self._file, self.path, t, why, within)
        with contextlib.suppress(OSError):  # its flush fails again; the file is closed
            self._file.close()

    def flush(self) -> None:
        """Write out what is buffered (at the run's end, before the summary is made)."""
        if not self._file.closed:
            try:
                self._flushed()
            except OSError as exc:
                self._stop(exc.strerror or str(exc))

    def _log(self, direction: str, data: bytes) -> float:
        """Write one chunk, stamped now; returns the stamp."""
        now = self._inner.now()
        if self._t0 is None:
            self._t0 = now
        self._put(f'{{"t": {now - self._t0:.6f}, "d": "{direction}", "b": "{data.hex()}"}}\n', now)
        return now

    def note(self, payload: dict[str, Any], at: float | None = None) -> None:
        """Mark an act in the record: an operator's, the tick guard's or the watchdog's (a
        replay does the runtime's again; the monitor shows each). ``at``: the link time it
        was done at (the watchdog's trip, which a replay's link trips at); else now."""
        if self._file.closed:
            return
        now = self._inner.now()
        at = now if at is None else at
        t = at - (self._t0 if self._t0 is not None else at)
        self._put(json.dumps({"t": round(t, 6), "d": "note", "note": payload}) + "\n", now)

    def write(self, data: bytes) -> None:
        self._inner.write(data)
        if not self._file.closed:
            self._log("out", data)
            self.out_bytes += len(data)

    @property
    def read_step(self) -> float | None:
        """Its reads wait whole steps of the simulator (:data:`READ_STEP`), or None."""
        return None if self.wall_clock else getattr(self._inner, "read_step", None)

    #: the bytes of the record's "out" side so far, whoever wrote them (the link, the probe
    #: that asks after a stop, the baud hunt): an end note's ``written`` is one, read when
    #: the run was ended (``loop.note_written``)
    out_bytes = 0

    def read(self, timeout: float) -> bytes:
        """The inner read, recorded. The next :meth:`now` (the link's, right after the read:
        its frames' arrival) is the time the chunk was stamped with: a replay gives the
        chunk back at that time, and an arrival read after the record's own line was written
        (a slow write, the process preempted) put the live run's ticks elsewhere than its
        replay's, so a replay of a long run on a loaded machine differed where nothing had."""
        data = self._inner.read(timeout)
        if data and not self._file.closed:
            self._read_at = self._log("in", data)
        return data

    #: the stamp of the read just made, for the next :meth:`now` (None: none pending)
    _read_at: float | None = None

    def set_wake_line(self, low: bool) -> None:
        """Keep-awake's BRC pulses reach the port when it has modem lines (not recorded)."""
        inner = getattr(self._inner, "set_wake_line", None)
        if inner is not None:
            inner(low)

    def set_baud(self, baud: int) -> None:
        """The port's rate changed: noted (``{"baud": 19200}``), so that a reader sees the
        rate the bytes after it went out at (a listen at another rate, the port put back,
        Baud (129) followed). One cut short by an exception (Ctrl-C inside it) is noted with
        ``"cut_short"``: the port may be at either rate until the next note."""
        try:
            self._inner.set_baud(baud)
        except BaseException as exc:
            self.note({BAUD_NOTE: baud, "cut_short": type(exc).__name__})
            raise
        self.note({BAUD_NOTE: baud})

    def close(self) -> None:
        """Close the link, then end the record with its end line (the run ended here)."""
        try:
            self._inner.close()
        finally:
            self.end_record()

    def end_record(self) -> None:
        """End the record with its end line and close its file, the link left as it is (a
        connection a program handed to the run stays open: ``RunStack.close``)."""
        if not self._file.closed:
            now = self._inner.now()
            t = now - (self._t0 if self._t0 is not None else now)
            self._put(f'{{"t": {t:.6f}, "d": "end"}}\n', now)
        self.flush()
        if not self._file.closed:
            self._file.close()

    @property
    def is_open(self) -> bool:
        return self._inner.is_open

    def now(self) -> float:
        read_at = self._read_at
        if read_at is not None:
            self._read_at = None
            return read_at
        return self._inner.now()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


#: the note of a change of the port's rate (its value: the new rate, :meth:`RecordingTransport.
#: set_baud`)
BAUD_NOTE = "baud"
#: the note that ends a record whose file could no longer be written (its value: why, the
#: error's words: "File too large", "No space left on device"); the run went on without it
RECORD_STOPPED = "record_stopped"
#: how far back from a failed write's end of file a line's end is looked for
_TAIL_BYTES = 1 << 16


def _clock_words(step: float | None, wall_clock: bool, loses_bytes: bool) -> dict[str, Any]:
    """What a record's header says of its link's clock, for the replay: its stop was
    listened after (:data:`STOP_LISTENED`: the wall clock, a line losing bytes to the
    robot), its reads wait whole steps (:data:`READ_STEP`: the in-process simulator's)."""
    words: dict[str, Any] = {STOP_LISTENED: True} if wall_clock or loses_bytes else {}
    return words | ({READ_STEP: step} if step else {})


def _mark_stopped(file: LineFile, path: str, t: float, why: str, within: int | None = None) -> bool:
    """End the record at ``path`` (written through ``file``, whose write just failed) with a
    :data:`RECORD_STOPPED` note, so that its replay says the recording stopped, not "the run
    was killed?" (a full disk or ``ulimit -f`` read as a ``kill -9``). A write failed: the
    room for the note is made by cutting the file back to the end of a whole line at least
    the note's length before its end (a size limit or a full disk is then not gone past:
    the bytes were the file's); the few chunks cut are lost. The descriptor is then pointed
    at the null device, so that what ``file`` still buffers goes nowhere when it is closed
    (written after the note, it would be a cut line past it). True if the note was
    written; a device (``/dev/full``) or a file that cannot be read back gets none. A
    compressed record is cut back to one of its last flushes instead, and ended there as a
    whole gzip file (:meth:`_CompressedLines.end_with`). ``within``: the bytes the file
    may hold, when fewer than it holds (``run --record-max``: the note is within the limit).
    """
    note = json.dumps({"t": round(t, 6), "d": "note", "note": {RECORD_STOPPED: why}}) + "\n"
    data = note.encode("utf-8")
    if isinstance(file, _CompressedLines):  # cut back to a flush, not to a line's end
        return file.end_with(data, within)
    try:
        fd = file.fileno()
        held = os.fstat(fd)
        if not stat.S_ISREG(held.st_mode):
            return False
        cut = _line_end_before(path, held, _room(held, within) - len(data))
        if cut is None:
            return False
        os.ftruncate(fd, cut)
        os.lseek(fd, cut, os.SEEK_SET)
        return os.write(fd, data) == len(data)
    except (OSError, ValueError):
        return False
    finally:
        _write_nowhere(file)


def _room(held: os.stat_result, within: int | None) -> int:
    """The bytes a stopped record may end within: those the file ``held`` (what a full disk
    or a file size limit let it write), or ``within`` (``--record-max``) when fewer."""
    return held.st_size if within is None else min(within, held.st_size)


def _no_mission_time() -> float | None:
    """:attr:`RecordingTransport.mission_time` of a record made outside a run's stack."""
    return None


#: The units ``run --record-max`` takes, as a disk's or a file manager's sizes are written:
#: decimal (kB, MB, GB, TB: powers of 1000) and binary (KiB, MiB, GiB, TiB: of 1024), any
#: case (``500mb``); a bare number is refused (500 what?). Largest first: :func:`size_text`.
BYTE_UNITS: dict[str, int] = {
    "TB": 1000**4, "TiB": 1 << 40, "GB": 1000**3, "GiB": 1 << 30,
    "MB": 1000**2, "MiB": 1 << 20, "kB": 1000, "KiB": 1 << 10, "B": 1,
}  # fmt: skip


#: The least size limit a record takes (``run --record-max``): its header (a few KB) and
#: some seconds of run (a plain record writes about 13 kB a second, a compressed one 0.6 kB),
#: room to cut back to a whole line, or a compressed record's flush, with the note after it.
MIN_RECORD_MAX = 64 * 1000


def size_text(size: int) -> str:
    """``size`` bytes in the largest unit of :data:`BYTE_UNITS` that holds it whole: ``500
    MB``, ``2 GiB``, ``1500 MB``, ``100 B``; how a summary and a record's note say a limit."""
    unit, per = next((u, n) for u, n in BYTE_UNITS.items() if size % n == 0 and size >= n)
    return f"{size // per} {unit}"


def _write_nowhere(file: LineFile) -> None:
    """Point ``file``'s descriptor at the null device: what it still buffers (and a
    compressed record's trailer) goes nowhere when it is closed, not past the file's end."""
    with contextlib.suppress(OSError, ValueError):
        nowhere = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(nowhere, file.fileno())
        finally:
            os.close(nowhere)


def _line_end_before(path: str, held: os.stat_result, limit: int) -> int | None:
    """The offset just past the last newline at or before ``limit`` in the file ``held``
    (read through ``path``, checked to be the same file), after the header's; None if
    there is none in the last :data:`_TAIL_BYTES` before it."""
    if limit <= 0:
        return None
    with open(path, "rb") as reader:
        seen = os.fstat(reader.fileno())
        if (seen.st_dev, seen.st_ino) != (held.st_dev, held.st_ino):
            return None
        start = max(0, limit - _TAIL_BYTES)
        reader.seek(start)
        tail = reader.read(limit - start)
    at = tail.rfind(b"\n")
    return None if at < 0 else start + at + 1


def recorded_path(name: str, header: Mapping[str, Any], record: Path | None) -> Path | None:
    """Where a path of the record's header (its ``mission``, a ``sources`` name) is now: a
    relative one from the record's folder when the header says its paths are relative to it
    (:data:`RELATIVE_TO`), an absolute one as it is; None for a shipped file's name
    (``roomba-bt:...``), or a relative path of a record made before (relative to a folder
    nobody noted)."""
    if name.startswith("roomba-bt:"):  # mission.shipped's prefix (that package is not needed)
        return None
    path = Path(name)
    if path.is_absolute():
        return path
    if record is None or header.get(RELATIVE_TO) != RELATIVE_TO_RECORD:
        return None
    return Path(os.path.normpath(record.resolve().parent / path))


def header_text(text: str) -> str:
    """A text a record's header gave (its release, a file's or a plugin's name, its world),
    as the terminal is shown it: a control or bidirectional character escaped (``\\x1b``,
    ``\\u202e``), never written raw. A header may be hand-edited by someone else, and one
    raw escape sequence retitles the window, recolours or hides lines, or (OSC 52) writes
    the clipboard."""
    return escaped(text, ANY_CONTROL)


def record_holder(record: Path, mission: Path) -> Path:
    """The folder that holds both ``record`` and the ``mission`` it replays (a repository with
    ``records/``, ``missions/`` and ``worlds/``), symbolic links followed: the only folder a
    path the record names may lie in (:func:`held_to_record`)."""
    return Path(os.path.commonpath([record.resolve().parent, mission.resolve()]))


def held_to_record(path: Path, holder: Path) -> bool:
    """Whether ``path``, symbolic links followed, is inside ``holder`` (:func:`record_holder`),
    and ``holder`` is no file system's root: the rule every path a record names is held to
    before it is opened (its include folders, its world). A record may come from someone
    else, and its header could name ``~/.pgpass`` or ``/etc/shadow`` (docs/records.md)."""
    return holder != Path(holder.anchor) and path.resolve().is_relative_to(holder.resolve())


def utc_stamp(moment: datetime) -> str:
    """``2025-03-04T09:12:05Z``: when a run started, as its record's header and the monitor's
    page say it (ISO 8601, UTC, to the second)."""
    return moment.astimezone(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


#: the reproducible-builds convention's variable (https://reproducible-builds.org/specs/
#: source-date-epoch/): seconds since 1970-01-01 UTC to write in place of the current time
SOURCE_DATE_EPOCH = "SOURCE_DATE_EPOCH"


def source_date_epoch(environ: Mapping[str, str] | None = None) -> datetime | None:
    """The time :data:`SOURCE_DATE_EPOCH` gives (``environ``: the process's environment by
    default), which a record's ``started`` says instead of the run's start, so that a run
    recorded again with nothing changed writes the same bytes; None when it is not set (or
    empty). ValueError naming the variable when it is not a whole number of seconds: the
    convention asks a tool to stop there rather than write the current time."""
    text = (os.environ if environ is None else environ).get(SOURCE_DATE_EPOCH, "")
    if not text:
        return None
    if not text.isascii() or not text.isdigit():
        raise ValueError(
            f"{SOURCE_DATE_EPOCH}={text!r}: expected a whole number of seconds since "
            "1970-01-01 UTC (date +%s)"
        )
    try:
        return datetime.fromtimestamp(int(text), UTC)
    except (OverflowError, ValueError, OSError):
        raise ValueError(f"{SOURCE_DATE_EPOCH}={text!r}: a time past what a date holds") from None


#: the end note's key: the run's outcome (``Outcome.value``)
ENDED = "ended"
#: the outcomes that come from outside the tree (an operator, a signal, the run's time limit),
#: which a replay, whose tree would go on, brings about where the end note says
ENDED_FROM_OUTSIDE = ("interrupted", "timeout")
#: how an end note's reason starts where the run's tree had ended well and its safe stop did
#: not reach the robot (``teardown.note_undelivered_stop``): the note says ``connection
#: lost``, its link had not failed before the stop
UNDELIVERED_STOP = "the safe stop did not reach the robot (the run had ended: "


def tree_ended(note: Mapping[str, Any]) -> str:
    """How the recorded run's tree ended: the end note's outcome, or, where a stop that did
    not reach the robot made a run that had ended well a lost connection, the ending it had
    (``timeout``, ``success``). A replay ends such a run where its tree ended, as it would
    have (a timeout at its tick), and compares its stop, not a link's failure: before, a
    timed-out run's stop unconfirmed was replayed as a link lost, the replay's tree went on
    past the time limit, starved, and its own stop was not compared."""
    outcome, reason = str(note.get(ENDED)), str(note.get("reason") or "")
    planned = reason.endswith(f"({PLANNED_END})") and "of mission time reached" in reason
    if outcome == "success" and planned:
        return "timeout"  # ``run --duration``: ended from outside its tree, as a time limit
    if not reason.startswith(UNDELIVERED_STOP):
        return outcome
    had = reason[len(UNDELIVERED_STOP) :]
    return had.split(":", 1)[0].split(")", 1)[0]


#: the end note's key, for a Ctrl-C or SIGTERM that came before its tick was written whole:
#: how many bytes of the record's "out" side were written when it came. More than were
#: written before that tick: it came between two of the tick's writes (its flush), and the
#: replay ticks that frame and writes its commands up to there (``stack.RecordedEnd``);
#: before, such a record's replay differed at the first command the live run had written
#: of the tick ("expected Motors (138) 8a 04, sent Drive (137) 89 00 00 00 00"), exit 1
WRITTEN = "written"
#: What ``replay`` says of a record whose end note's :data:`WRITTEN` counts more than its run
#: wrote before a stop asked for in a stall, or a Ctrl-C or signal that came inside a tick
#: before a stop that was asked after (``{noted}``, ``{before}``; ``{more}`` the
#: difference): an older release's count was the link's at the stop, moved on at the end by
#: what the link alone wrote since, so the Query List that asks after a stop not confirmed
#: (written past the link, after the stop) was among it. Its replay would wait for bytes
#: that came after the stop and say "first difference ... expected Drive (137) 89 00 00 00
#: 00, sent nothing", exit 1, of a faithful record
MISCOUNT = (
    "the end note counts {noted} bytes written when the recorded run was stopped, {more} more "
    "than the {before} it wrote before its stop: a known miscount of records made by a "
    "roomba-bt 0.2.0 development build before its stall-stop fix (the count took in the "
    "Query List that asks after the stop), not a difference in behaviour; replayed to the "
    "stop at byte {before}"
)
#: What ``replay`` says of a record whose end note of a Ctrl-C or signal that came in a stall
#: the watchdog rode (after the last frame's tick, the watchdog's drive 0 written since)
#: counts nothing (``{before}``: the bytes its run wrote before its stop): an older release
#: noted such an interrupt without :data:`WRITTEN`, and its replay would end at the tick,
#: its stop compared with the watchdog's drive 0: "first difference ... expected Drive (137)
#: 89 00 00 00 00, sent Motors (138) 8a 00", exit 1
UNCOUNTED = (
    "the end note counts no bytes written when the recorded run was interrupted in a stall "
    "its watchdog rode: a known miscount of records made before roomba-bt 0.2.0 (they "
    "noted no count for a Ctrl-C or signal there), not a difference in behaviour; replayed "
    "to the stop at byte {before}"
)


def miscount_said(noted: int | None, before: int) -> str:
    """What ``replay`` says of an older record's end note whose count was wrong (``noted``,
    :data:`MISCOUNT`) or missing (None, :data:`UNCOUNTED`), its run having written
    ``before`` bytes before its stop (``Record.miscounted``)."""
    if noted is None:
        return UNCOUNTED.format(before=before)
    return MISCOUNT.format(noted=noted, before=before, more=noted - before)


def end_note(
    outcome: str,
    reason: str,
    mission_time: float,
    ended_at: tuple[int, str] | None,
    written: int | None = None,
) -> dict[str, Any]:
    """The record's end note: how its run ended, and where (``ended_at``: the tick and
    half, ``RunSummary.ended_at``; None: before the first frame). ``written``: for a run
    ended from outside (a stop, a Ctrl-C), the bytes of the record's "out" side written by
    then (:data:`WRITTEN`), counted by the record itself, so the probe's Query List after a
    stop not confirmed is not among them: "before" the tick was written whole, the part of
    it written; "after" it, those of the tick and any since (a stop between frames, in a
    stall: the watchdog's drive 0, which the replay writes before it ends)."""
    note: dict[str, Any] = {ENDED: outcome, "reason": reason, "time": round(mission_time, 3)}
    if ended_at is not None:
        note["tick"], note["at"] = ended_at
        if written is not None:
            note[WRITTEN] = written
    return note


def ending_text(note: dict[str, Any]) -> str:
    """How the recorded run ended, in words: ``the recorded run was stopped by the operator
    at t=44.17 s``, ``... was interrupted (Ctrl-C) at t=3.20 s``, ``... ended in success at
    t=12.00 s``."""
    outcome, reason = str(note.get(ENDED)), str(note.get("reason") or "")
    time = note.get("time")
    at = f" at t={time:.2f} s" if isinstance(time, int | float) else ""
    if outcome == "interrupted" and reason.startswith("stopped by"):
        return f"the recorded run was {reason}{at}"
    if outcome == "interrupted":
        return f"the recorded run was interrupted{f' ({reason})' if reason else ''}{at}"
    return f"the recorded run ended in {outcome}{at}{f': {reason}' if reason else ''}"


class RecordError(ValueError, RoombaBtError):
    """A record file that cannot be replayed; names the file and line."""


class TornTrailer(RecordError):
    """A compressed record whose every line decompressed, ``after`` of them, but whose gzip
    trailer (the text's CRC-32 and length) does not match them (``reason``: gzip's words)."""

    def __init__(self, path: Path, after: int, reason: str) -> None:
        super().__init__(f"{path}:{after + 1}: damaged compressed data ({reason})")
        self.after = after
        self.reason = reason


#: what gzip says of a trailer that does not match the text it ends
_TORN_TRAILER = re.compile(r"CRC check failed|Incorrect length of data produced")


def _up_to_damage(
    path: Path, lines: Iterator[tuple[int, str, bool, int]]
) -> Iterator[tuple[int, str, bool, int]]:
    """``lines``, up to a gzip trailer that does not match them (:class:`TornTrailer`), said
    once in a warning: the record is read and replayed up to there, each line checked as
    any record's, not refused whole (exit 2): every line of such a record is readable (an
    older release's run ended by a signal inside a gzip write leaves one).
    Compressed data that does not decompress is still refused, its line named: what it
    decompresses to past the damage cannot be trusted."""
    try:
        yield from lines
    except TornTrailer as exc:
        log.warning(
            "%s: damaged after line %d: its gzip trailer (the CRC-32 and length of the text) "
            "does not match the text (%s); the %d lines were read, each checked, and are "
            "replayed, but gzip -t refuses the file (zcat reads it). A run of a 0.2.0 "
            "development build ended by a signal inside a write of its record could leave it "
            "so",
            path, exc.after, exc.reason, exc.after,
        )  # fmt: skip


@dataclass
class Record:
    """A record file, checked whole by :func:`load_record` but not held in memory: its chunks
    are read again from the file, a line at a time, when asked (:meth:`chunks`). A record
    is about 45 MB an hour of run, and its chunks held as Python objects took 341 MB for a
    2-hour run (``replay`` read it whole first); the notes, few, are kept."""

    header: dict[str, Any]
    #: the file; :meth:`chunks` reads it again, up to :attr:`size`
    path: Path
    notes: list[tuple[float, dict[str, Any]]] = field(default_factory=list)
    #: whether the record holds its run's end line (False: it stops short of the run's end)
    ended: bool = False
    #: the time of its last line, seconds of the record's clock
    last_t: float = 0.0
    #: the time of its last chunk of bytes (the run's end line may come later: a safe stop
    #: listened after on the virtual clock, nothing read meanwhile): where a replay is done
    last_chunk_t: float = 0.0
    #: the bytes of the file that were checked (of its text: a compressed record's
    #: decompressed): a line cut short, or lines written after the check (a record still
    #: being written), are not read again
    size: int = 0
    #: how many bytes the host wrote in the recorded run (its "out" chunks' total)
    out_bytes: int = 0
    #: the last of those bytes (up to :data:`OUT_TAIL`): how its stop ended, where its header
    #: does not say (:func:`recorded_end_in`)
    out_tail: bytes = b""
    #: no end line, and a run holds the record's lock when it is read (``run --record``'s
    #: :class:`~roomba_bt.runtime.claimed.ClaimedFile`), or, where no lock can be asked for,
    #: the file changed in the last :data:`STILL_WRITTEN_S` seconds: a run writes it still
    being_written: bool = False
    #: the number of its last line, dropped as cut short (no newline at its end: the run
    #: killed, a full disk); None: none was
    cut_line: int | None = None
    #: the end note's ``written`` and the bytes the recorded run wrote before its stop,
    #: where its replay found the first past the second (:data:`MISCOUNT`), or found none
    #: noted where the run rode a stall before its stop (None, :data:`UNCOUNTED`); None:
    #: not so (:func:`miscount_said`)
    miscounted: tuple[int | None, int] | None = None

    @property
    def label(self) -> str:
        """The recorded run's label (``run --label``; "" for none), on one line: a replay's
        summary and a recorded run's page say it, as the run's did, so that replays of
        several robots' runs of one mission can be told apart. A hand-edited header's
        control characters are shown escaped (``\\n``), never written to the terminal."""
        return header_text(self.header.get("label") or "")

    @property
    def mission_file(self) -> str | None:
        """The header's ``mission`` as a path to compile (``load_mission``): one relative to
        the record's folder (``../missions/dock.yaml``, as ``run --record`` writes it) from
        there, a shipped name or an absolute path as it is; None when the header has none."""
        named = self.header.get("mission")
        if not isinstance(named, str):
            return None
        here = recorded_path(named, self.header, self.path)
        return named if here is None else str(here)

    def unended(self) -> str | None:
        """Why the record holds no end line, or None when it does: its recording stopped
        (its :data:`RECORD_STOPPED` note), a run writes it still, or, with no word in the
        file, its run was killed or its writing failed where no note fitted."""
        if self.ended:
            return None
        stopped = self.recording_stopped
        if stopped is not None:
            return (
                f"the recording stopped ({stopped}); the run went on without it, and its "
                "summary said where the record ends"
            )
        if self.being_written:  # it was said to be killed, or its replay's end its run's
            return STILL_WRITTEN
        if self.header.get("version") == 1:
            return "version 1 records have no end line, or the run was killed"
        return UNENDED

    def end_said(self) -> str | None:
        """How a record without its run's end ends, as ``replay`` and the monitor's recorded
        run both say it (one text: the monitor said "input ended" of a killed run's record,
        where ``replay`` said it was killed), or None when it holds its run's end: ``the
        record ends at 5.055 s without the run's end: the run was killed, ...`` and, for a
        last line cut short, which line was dropped."""
        unended = self.unended()
        if unended is None:
            return None
        said = f"the record ends at {self.last_t:.3f} s without the run's end: {unended}"
        if self.cut_line is not None:
            said += f"; its last line ({self.cut_line}) was cut short and is left out"
        return said

    @property
    def recording_stopped(self) -> str | None:
        """Why the recording stopped before its run's end (the file could not be written:
        "File too large"), as its last note says; None if it says nothing of it."""
        for _, note in reversed(self.notes):
            why = note.get(RECORD_STOPPED)
            if why is not None:
                return str(why)
        return None

    @property
    def ending(self) -> dict[str, Any] | None:
        """The record's end note (how its run ended: :data:`ENDED`), or None for a record
        made before it was written, or one whose run was killed before its end."""
        return next((n for _, n in reversed(self.notes) if isinstance(n.get(ENDED), str)), None)

    @property
    def watchdog_trips(self) -> list[float] | None:
        """When the recorded run's watchdog tripped (its notes), or None for a record made
        before they were noted (no ``watchdog`` in its header): the replay's own watchdog
        trips on the record's silence then."""
        if "watchdog" not in self.header:
            return None
        return [t for t, note in self.notes if "watchdog" in note]

    def chunks(self) -> Iterator[tuple[float, str, bytes]]:
        """The "in" and "out" chunks ``(t, direction, bytes)`` in the file's order, read from
        the file as they are asked for. A file changed since it was checked (cut shorter,
        replaced) ends them there, said once."""
        lines = _record_lines(self.path, self.size)
        try:
            next(lines)  # the header
            for number, line, _, _ in lines:
                item = _chunk(self.path, number, line) if line.strip() else None
                if isinstance(item, tuple):
                    yield item
        except TornTrailer:  # said once, when the record was loaded; it ends there
            return
        except RecordError as exc:
            log.warning("%s; the record changed since it was read: it ends here", exc)

    @property
    def outbound(self) -> bytes:
        """Every byte the host wrote in the recorded run (read from the file)."""
        return b"".join(b for _, d, b in self.chunks() if d == "out")


#: Where no lock can be asked for (no ``flock``: :func:`_being_written`), a record without
#: its end line whose file changed this few seconds before it was read is taken for one a
#: run is still writing: a run flushes its record every :data:`FLUSH_EVERY_S` of its link's
#: clock while frames come, and a stall rides through for ``--grace`` (2 s by default) at
#: most before the run ends.
STILL_WRITTEN_S = 5.0
STILL_WRITTEN = "the record is still being written (a run in progress?)"
#: a record without its end line, a run's lock or a word of why: either cause is said (a
#: record cut by a full disk read as a killed run's, though the run had gone on)
UNENDED = (
    "the run was killed, or writing its record failed (a full disk, a file size limit?; "
    "the run's summary says which)"
)


#: The blank lines a record may hold (run --record writes none; an editor may add a few).
#: Each costs a read of the file's lines as a chunk does, 2 us, for one byte: a stranger's
#: 1 MB .gz of a gigabyte of line ends kept ``replay`` and ``monitor`` reading for most of
#: an hour (16 MB of them, 40 s).
MAX_BLANK_LINES = 10_000


#: the most packet ids a stream request holds (its count is one byte): a header's ``packets``
#: with more was replayed until the request was encoded, an ERROR with exit 1
MAX_STREAM_IDS = 255


def load_record(path: str | Path) -> Record:
    """Check a record whole and return it (its chunks are read again when replayed, not
    kept); :class:`RecordError` names the file and line of anything malformed.

    A malformed last line without its newline is a line cut short (the run killed as it was
    written, the disk full): it is dropped with a warning naming it, and the record read up to
    it (without its end line, so replay compares it up to there). Before, the whole record
    was refused (``malformed chunk``). A malformed line anywhere else is an error."""
    path = Path(path)
    lines = _record_lines(path)
    _, first, _, size = next(lines)
    record = Record(_header(path, first), path, size=size)
    last = 0.0
    blank = 0
    for number, line, whole, end in _up_to_damage(path, lines):
        if not line.strip():
            blank += 1
            if blank > MAX_BLANK_LINES:
                raise RecordError(
                    f"{path}:{number}: {blank:,} blank lines; allowed: at most "
                    f"{MAX_BLANK_LINES:,} (run --record writes none: a file damaged, or no "
                    "record)"
                )
            continue
        if record.ended:
            raise RecordError(f"{path}:{number}: a line after the run's end line")
        try:
            item = _chunk(path, number, line)
        except RecordError:
            if whole:  # only the last line can lack its newline
                raise
            log.warning(
                "%s:%d: the last line is cut short (no newline at its end: the run killed, "
                "or the disk full?); dropped, the record is read up to line %d",
                path, number, number - 1,
            )  # fmt: skip
            record.cut_line = number
            break
        record.size = end
        if isinstance(item, dict):  # an operator's act (a note), or the run's end
            record.last_t = max(record.last_t, item["t"])
            if item["d"] == "end":
                record.ended = True
            else:
                record.notes.append((item["t"], item["note"]))
            continue
        t = item[0]
        if not math.isfinite(t) or t < last:
            raise RecordError(
                f"{path}:{number}: time {t!r} s; expected a finite time, not before the line "
                f"before it ({last:g} s)"
            )
        last = record.last_t = record.last_chunk_t = t
        if item[1] == "out":
            record.out_bytes += len(item[2])
            record.out_tail = (record.out_tail + item[2])[-OUT_TAIL:]
    if not record.ended:
        record.being_written = _being_written(path)
    return record


#: how many of a record's last "out" bytes :func:`load_record` keeps (:attr:`Record.out_tail`)
OUT_TAIL = 16


def _being_written(path: Path) -> bool:
    """Whether a run writes the record at ``path`` now: its lock held (a run 10 minutes in
    whose file had not changed for 5 s was "killed", a file read 2 s after a ``kill -9``
    "in progress"); where no lock can be asked for, the file changed in the last
    :data:`STILL_WRITTEN_S` seconds."""
    held = held_by_a_writer(path)
    if held is not None:
        return held
    try:
        return time.time() - path.stat().st_mtime < STILL_WRITTEN_S
    except OSError:  # read a moment ago: gone since, it is no run's
        return False


#: The longest line of a record (decided): a chunk is one read of the port in hex, a few KB
#: as a rule; a serial read is at most 256 KiB (512 KiB of hex), but the real-time
#: simulator's read after a stalled host returns all it stepped through (1 MiB of hex after
#: 5.7 minutes with the smallest frame). 64 MiB holds hours of such a stall and bounds what a
#: file of zeros costs; a longer line is refused before more of it is read.
MAX_RECORD_LINE = 64 << 20


def _record_lines(path: Path, size: int | None = None) -> Iterator[tuple[int, str, bool, int]]:
    """Each line of the record file ``path`` (its first ``size`` bytes, when given): its
    number, its text without its line end, whether it had one (only the last line may not)
    and the byte offset of its end; at least one. Read a line at a time, each at most
    :data:`MAX_RECORD_LINE` bytes: the file was read whole first, and ``replay /dev/zero``
    ran out of memory (a MemoryError traceback). A device or a pipe is refused before it is
    opened, as a mission is. A compressed record (:func:`open_record`) is read decompressed:
    its lines, their numbers and the offsets of their ends are those of its text."""
    try:
        if not stat.S_ISREG(path.stat().st_mode):
            raise RecordError(f"{path}: not a regular file; a record is a file run --record wrote")
        with open_record(path) as file:
            number = end = 0
            for number, data in enumerate(_read_lines(path, file), 1):
                end += len(data)
                if size is not None and end > size:
                    break
                yield number, _line_text(path, number, data), data.endswith(b"\n"), end
    except OSError as exc:
        found = _unreadable(path, exc)
        raise RecordError(f"{path}: record: found {found}; {RECORD_WANTED}") from None
    if number == 0:
        raise RecordError(f"{path}:1: empty file; expected a {RECORD_FORMAT} header line")


#: what ``replay`` and ``monitor`` take, said where a record path is wrong
RECORD_WANTED = "wanted: a record file, as run MISSION --record FILE writes one"


def _unreadable(path: Path, exc: OSError) -> str:
    """What is at the record path ``path`` whose read failed with ``exc``, in a user's words:
    ``replay``/``monitor`` of a missing record said "cannot read record: No such file or
    directory", the error's bare text, where a mission or a world names what it found and
    what it wants."""
    if exc.errno in (errno.ENOENT, errno.ENOTDIR):
        return broken_link(path) if path.is_symlink() else "no such file"
    if exc.errno in (errno.EACCES, errno.EPERM):
        return "a file this user may not read (permission denied)"
    name = errno.errorcode.get(exc.errno or 0)
    return f"a file that could not be read: {exc.strerror or exc}" + (f" ({name})" if name else "")


def open_record(path: Path) -> io.BufferedIOBase:
    """The record file ``path`` for reading, as its first bytes say: gzip's magic number
    (:data:`GZIP_MAGIC`) is decompressed whatever the file's name (a copy renamed, a ``.gz``
    lost on the way), anything else is read as it is, a ``.gz`` name or not (decided: the
    bytes are the record, the name only a hint; a wrong one costs the user nothing)."""
    with path.open("rb") as file:
        start = file.read(8)
    if start.startswith(GZIP_MAGIC):
        return gzip.open(path, "rb")
    for signature, what in NOT_A_RECORD:
        if start.startswith(signature):
            raise RecordError(f"{path}:1: {what}")
    return path.open("rb")


#: How files that are no record's text start, and what is said of each: they were "byte
#: 0xff, not UTF-8 text" at 1:1 (a record compressed with another tool than gzip, or saved
#: again by an editor as UTF-16).
NOT_A_RECORD: tuple[tuple[bytes, str], ...] = (
    (b"BZh", "a bzip2-compressed file; records are read plain or gzip-compressed (.gz): "
     "bunzip2 it first"),
    (b"\xfd7zXZ\x00", "an xz-compressed file; records are read plain or gzip-compressed "
     "(.gz): unxz it first"),
    (b"\x28\xb5\x2f\xfd", "a zstd-compressed file; records are read plain or "
     "gzip-compressed (.gz): unzstd it first"),
    (b"PK\x03\x04", "a ZIP archive; unzip the record (run --record's .jsonl or .jsonl.gz) "
     "from it"),
    (b"\xff\xfe", "UTF-16 text (saved again by an editor?); records are UTF-8 JSON lines, as "
     "run --record writes them"),
    (b"\xfe\xff", "UTF-16 text (saved again by an editor?); records are UTF-8 JSON lines, as "
     "run --record writes them"),
)  # fmt: skip


#: the bytes a zlib sync flush ends with (an empty stored block): the end of a compressed
#: record whose run was killed, or writes it still (no gzip trailer yet)
SYNC_FLUSH_END = b"\x00\x00\xff\xff"


@dataclass(frozen=True)
class RecordSize:
    """A record file's size in bytes, and the size of the text it holds (the same for a
    plain record; None where a compressed one's cannot be told before it is read)."""

    file: int
    text: int | None
    compressed: bool


def record_size(path: Path) -> RecordSize:
    """How big the record at ``path`` is, without reading it through: a compressed record's
    text size is its gzip trailer's (the last 4 bytes: the text's length modulo 2**32),
    unknown where the file does not end with one (a run killed, or writing it still: it
    ends with its last sync flush, :data:`SYNC_FLUSH_END`) or holds 4 GiB of text or more
    (the trailer's length then smaller than the file). OSError when it cannot be read, or
    is no regular file (``monitor fifo.jsonl`` waited in ``open`` for a writer, for ever)."""
    if not stat.S_ISREG(path.stat().st_mode):
        raise OSError(f"{path}: not a regular file")
    with path.open("rb") as file:
        size = os.fstat(file.fileno()).st_size
        if file.read(len(GZIP_MAGIC)) != GZIP_MAGIC:
            return RecordSize(size, size, compressed=False)
        file.seek(max(size - 8, 0))
        trailer = file.read(8)
    text = int.from_bytes(trailer[4:], "little") if len(trailer) == 8 else None
    if trailer.endswith(SYNC_FLUSH_END) or text is None or text < size:
        text = None
    return RecordSize(size, text, compressed=True)


_Line = TypeVar("_Line", str, bytes)
_Read = TypeVar("_Read", str, bytes, covariant=True)


class _LineReader(Protocol[_Read]):
    """A file read a line at a time, text or bytes."""

    def readline(self, size: int = -1, /) -> _Read: ...


def bounded_lines(file: _LineReader[_Line]) -> Iterator[_Line]:
    """``file``'s lines (bytes, or text: each as the file gives them), each read at most
    :data:`MAX_RECORD_LINE` + 1 long: a longer one is known by its length
    (:func:`over_line_limit`) before the rest of it is read. A record's lines, and a results
    file's (``eval --from`` read a 100 MB line whole: 334 MB)."""
    while data := file.readline(MAX_RECORD_LINE + 1):
        yield data


def over_line_limit(line: Sized) -> bool:
    """Whether a line :func:`bounded_lines` gave is longer than :data:`MAX_RECORD_LINE`
    (it was cut there, the rest of it unread)."""
    return len(line) > MAX_RECORD_LINE


def _read_lines(path: Path, file: io.BufferedIOBase) -> Iterator[bytes]:
    """``file``'s lines, each cut at :data:`MAX_RECORD_LINE` + 1 bytes. A compressed record
    that stops short (its run killed, a full disk, or a run writing it still: no gzip
    trailer yet) ends at what decompresses, as a plain one ends where its file does; its
    cut line, if any, is not seen. Compressed bytes that do not decompress are a
    :class:`RecordError` at the line they are in (a traceback from zlib before), and so
    are more lines than :data:`MAX_LINES_PER_COMPRESSED_BYTE` allows."""
    number = 0
    lines = bounded_lines(file)
    check_at = DENSITY_CHECKED_FROM if isinstance(file, gzip.GzipFile) else math.inf
    while True:
        try:
            data = next(lines, b"")
        except EOFError:  # gzip: "Compressed file ended before the end-of-stream marker"
            return
        except (zlib.error, gzip.BadGzipFile) as exc:
            if number and _TORN_TRAILER.match(str(exc)):
                raise TornTrailer(path, number, str(exc)) from None
            raise RecordError(
                f"{path}:{number + 1}: damaged compressed data ({exc}); expected a "
                f"{RECORD_FORMAT} file as run --record wrote it (gzip when named .gz)"
            ) from None
        if not data:
            return
        number += 1
        if number >= check_at:  # a compressed record's: not a small file of a great many
            _lines_compressed(path, number, os.lseek(file.fileno(), 0, os.SEEK_CUR))
            check_at = number + DENSITY_CHECKED_EVERY
        yield data


#: The most lines a compressed record holds for each byte of its file (decided). A line
#: costs a read and a check, twice (3.5 us each), whatever its length: a stranger's 3 MB
#: ``.gz`` of 27 million short chunk lines (1 GB of text) kept ``replay`` reading for
#: minutes. Measured, a record holds one line in 4 of its bytes (``run idle.yaml --fast
#: --record``: 20 minutes standing still, its most repetitive, 80,016 lines in 341 KB;
#: ``gzip -9`` of its text one in 3; a moving robot's one in 13): 1 is three times that.
#: Bytes are not bounded so, only lines: a stalled host's long line of an idle robot's
#: frames compresses 336 times, as much as a file made to be small does (344).
MAX_LINES_PER_COMPRESSED_BYTE = 1
#: from how many lines, and then every how many, the lines are counted against the bytes
#: read (the compressed bytes are read ahead of the lines, in blocks: a few lines first
#: would be judged by a block)
DENSITY_CHECKED_FROM = 100_000
DENSITY_CHECKED_EVERY = 10_000


def _lines_compressed(path: Path, lines: int, compressed: int) -> None:
    """RecordError when ``lines`` came from ``compressed`` bytes of a compressed record,
    more than :data:`MAX_LINES_PER_COMPRESSED_BYTE` allows; it names how to read it if it
    is a record: decompressed, a file whose size its lines cost."""
    if lines <= MAX_LINES_PER_COMPRESSED_BYTE * compressed:
        return
    plain = path.name.removesuffix(".gz") if path.name.endswith(".gz") else f"{path.name}.txt"
    raise RecordError(
        f"{path}:{lines}: {lines:,} lines from {compressed:,} bytes of compressed data; "
        f"allowed: at most {MAX_LINES_PER_COMPRESSED_BYTE} a byte (run --record's hold one "
        "line in about 4 bytes): a small file of a great many lines, which would be read for "
        f"minutes. If it is a record, decompress it (zcat {shlex.quote(path.name)} > "
        f"{shlex.quote(plain)}) and give that"
    )


def _line_text(path: Path, number: int, data: bytes) -> str:
    """Line ``number`` of a record as text, without its line end."""
    if over_line_limit(data):
        raise RecordError(
            f"{path}:{number}: a line of more than {MAX_RECORD_LINE:,} bytes; a {RECORD_FORMAT} "
            "file's lines are a few KB (run --record writes them)"
        )
    try:
        return data.decode("utf-8").rstrip("\r\n")
    except UnicodeDecodeError as exc:  # a damaged copy, or not a record at all
        raise RecordError(
            f"{path}:{number}:{exc.start + 1}: byte 0x{data[exc.start]:02x}, not UTF-8 text; "
            f"expected the JSON lines of a {RECORD_FORMAT} file (run --record)"
        ) from None


#: what ``int`` says of a number longer than it reads (4,300 digits by default): its
#: advice, ``sys.set_int_max_str_digits()``, is a programmer's
_TOO_LONG = "integer string conversion"


def long_number(exc: Exception) -> str:
    """What a reader of a stranger's JSON says of ``exc``, the ``ValueError`` of
    ``json.loads``: a number too long (``a number of more than 4,300 digits; ...``), else
    its own words."""
    if _TOO_LONG not in str(exc):
        return str(exc)
    return (
        f"a number of more than {sys.get_int_max_str_digits():,} digits; its numbers are a "
        "few digits long"
    )


class DuplicateKey(ValueError):
    """A JSON object of a stranger's file holding one key twice (``args[0]``, the key)."""


def _each_key_once(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``json.loads``' object hook: the object, DuplicateKey when a key is in it twice."""
    found = dict(pairs)
    if len(found) != len(pairs):  # the rare case: which key, in the order written
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise DuplicateKey(key)
            seen.add(key)
    return found


def json_read(text: str) -> Any:
    """``text``, a line of a file roomba-bt wrote (a record's, a results file's), as JSON
    that holds each key of an object once: ``json.loads`` keeps the last of two, so a chunk
    line with two ``"b"`` replayed to a difference (exit 1) where it is no line run
    --record writes. DuplicateKey (a ValueError) names the key."""
    return json.loads(text, object_pairs_hook=_each_key_once)


def twice(exc: DuplicateKey) -> str:
    """What is said of a key written twice in one object."""
    return f"the key {json.dumps(exc.args[0])} twice in one object; expected each key once"


#: what a record is, said where a file given as one is not
_RECORD_WANTED = (
    f"a file written by run --record (its first line a JSON header, format {RECORD_FORMAT!r})"
)


def _header(path: Path, line: str) -> dict[str, Any]:
    """The record's first line: its header, every field checked (:func:`header_problem`)."""
    try:  # a byte-order mark an editor wrote before it: read past, as a mission's is
        header = json_read(line.removeprefix("\ufeff"))
    except DuplicateKey as exc:
        raise RecordError(f"{path}:1: header holds {twice(exc)}") from None
    except json.JSONDecodeError as exc:
        raise RecordError(  # a mission given for its record said only "Expecting value"
            f"{path}:1:{exc.colno}: not a record: its first line is not JSON ({exc.msg}); "
            f"expected {_RECORD_WANTED}"
        ) from None
    except RecursionError:  # json's decoder recurses: a line nested thousands deep
        raise RecordError(f"{path}:1: header nested too deeply to be a record's") from None
    except ValueError as exc:  # a number too long to read: it was an internal error, exit 70
        raise RecordError(f"{path}:1: header holds {long_number(exc)}") from None
    if not isinstance(header, dict) or header.get("format") != RECORD_FORMAT:
        found = (
            f"its header's format is {shortened(repr(header['format']))}"
            if isinstance(header, dict) and "format" in header
            else "its first line has no format field"
            if isinstance(header, dict)
            else "its first line is no JSON object"
        )
        raise RecordError(
            f"{path}:1: not a {RECORD_FORMAT} file: {found}; expected {_RECORD_WANTED}"
        )
    if type(header.get("version")) is not int or header["version"] not in READ_VERSIONS:
        raise RecordError(
            f"{path}:1: record version {header.get('version')!r}; this roomba-bt reads "
            f"versions {', '.join(map(str, READ_VERSIONS))}"
        )
    problem = header_problem(header)
    if problem is not None:
        raise RecordError(f"{path}:1: {problem}")
    return header


#: A chunk's line as :class:`RecordingTransport` writes it, read without the JSON decoder (a
#: third of its time; a record is read twice, :class:`Record`); any other line, JSON's way.
#: Its hex is one run of digits, its even length checked apart: a repeated group,
#: ``(?:[0-9a-f]{2})*``, kept a mark per byte pair, and a stranger's line of 40 MB of hex
#: took 2.7 GB before the match ended (a MemoryError, exit 70).
_CHUNK_LINE = re.compile(r'\{"t": ([0-9]+\.[0-9]+), "d": "(in|out)", "b": "([0-9a-f]*)"\}')


def _chunk(path: Path, number: int, line: str) -> tuple[float, str, bytes] | dict[str, Any]:
    """Line ``number``: a chunk ``(t, "in" | "out", bytes)``, or a note or the end line (its
    object)."""
    written = _CHUNK_LINE.fullmatch(line)
    if written is not None and len(written[3]) % 2 == 0:  # odd: JSON's way, said malformed
        return float(written[1]), written[2], bytes.fromhex(written[3])
    problem: str | None = None
    try:
        item = json_read(line)
        if not isinstance(item, dict):
            raise TypeError(f"a JSON {type(item).__name__}, not an object")
        if item.get("d") == "end":
            item["t"] = float(item["t"])
            return item
        if item.get("d") == "note":
            if isinstance(item.get("note"), dict):
                item["t"] = float(item["t"])  # checked here, once
                problem = _tick_problem(item["note"])
                if problem is None:
                    return item
            else:
                raise TypeError("a note's 'note' must be an object")
        else:
            t, d, b = float(item["t"]), str(item["d"]), bytes.fromhex(item["b"])
    except RecursionError:
        raise RecordError(f"{path}:{number}: a chunk nested too deeply to be one") from None
    except DuplicateKey as exc:
        raise RecordError(f"{path}:{number}: {twice(exc)}, as run --record writes it") from None
    except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        said = long_number(exc) if _TOO_LONG in str(exc) else f"{type(exc).__name__}: {exc}"
        raise RecordError(
            f"{path}:{number}: malformed chunk ({said}); expected "
            '{"t": seconds, "d": "in"|"out", "b": hex}'
        ) from None
    if problem is not None:
        raise RecordError(f"{path}:{number}: {problem}")
    if d not in ("in", "out"):
        raise RecordError(f"{path}:{number}: direction {d!r}; allowed: in, out, note, end")
    return t, d, b


def _tick_problem(note: dict[str, Any]) -> str | None:
    """What is wrong with a note's ``tick`` (the stream's tick an act was done at, where a
    replay does it again), or None: a hand-edited ``"tick": -5`` was taken, the replay
    paused at tick 0 and said it diverged there."""
    if "tick" not in note:
        return None
    tick = note["tick"]
    if type(tick) is int and tick >= 0:
        return None
    return (
        f"a note's tick is {json.dumps(tick)}; expected the stream's tick it was done at, "
        "a whole number from 0"
    )


def header_problem(header: dict[str, Any]) -> str | None:
    """What is wrong with a record's header fields (each read by ``replay`` and the monitor's
    recorded runs), or None. A hand-edited header with ``"baud": "fast"`` was a traceback."""
    profile = header.get("profile", "create2")
    if not isinstance(profile, str) or profile not in PROFILES:
        return f"header field 'profile' is {profile!r}; known profiles: {', '.join(PROFILES)}"
    baud = header.get("baud", 115200)
    if type(baud) is not int or baud not in BAUD_CODES:
        rates = ", ".join(str(rate) for rate in sorted(BAUD_CODES))
        return f"header field 'baud' is {baud!r}; allowed: the OI's rates {rates}"
    mission = header.get("mission")
    if mission is not None and not isinstance(mission, str):
        return f"header field 'mission' is {mission!r}; expected the mission file's path"
    parameters = header.get("parameters", {})
    if not isinstance(parameters, dict) or not all(
        isinstance(k, str) and isinstance(v, str | int | float) for k, v in parameters.items()
    ):
        return f"header field 'parameters' is {parameters!r}; expected {{name: value}}"
    for name in ("watchdog", "grace"):  # the run's, read by replay (absent before)
        seconds = header.get(name, 0.0)
        if type(seconds) not in (int, float) or not 0.0 <= seconds < math.inf:
            return f"header field {name!r} is {seconds!r}; expected seconds, 0 or more"
    step = header.get(READ_STEP, 1.0)
    if type(step) not in (int, float) or not 0.0 < step <= 1.0:
        return f"header field {READ_STEP!r} is {step!r}; expected seconds, above 0 up to 1"
    end_in = header.get(END_IN, "passive")
    if end_in not in ("passive", "stop"):
        return f"header field {END_IN!r} is {end_in!r}; expected 'stop' (or none: Start)"
    relative_to = header.get(RELATIVE_TO, RELATIVE_TO_RECORD)
    if relative_to != RELATIVE_TO_RECORD:
        return f"header field {RELATIVE_TO!r} is {relative_to!r}; expected {RELATIVE_TO_RECORD!r}"
    for name in (SIMULATOR, RUN_OPTIONS):  # read by the user, not by a replay
        options = header.get(name, {})
        if not isinstance(options, dict):
            return f"header field {name!r} is {options!r}; expected {{option: value}}"
    for name in ("port", "started", "label", MADE_BY, MISSION_AT):  # which robot, when, ...
        text = header.get(name)
        if text is not None and not isinstance(text, str):
            return f"header field {name!r} is {text!r}; expected text"
    sources = header.get(SOURCES, {})
    if not isinstance(sources, dict) or not all(
        isinstance(k, str) and isinstance(v, str) for k, v in sources.items()
    ):
        return f"header field {SOURCES!r} is {sources!r}; expected {{file: SHA-256}}"
    plugins = header.get(PLUGINS, {})
    if not isinstance(plugins, dict) or not all(
        isinstance(k, str) and isinstance(v, dict) and set(v) == {"version", "sha256"}
        and all(isinstance(text, str) for text in v.values())
        for k, v in plugins.items()
    ):  # fmt: skip
        return (
            f"header field {PLUGINS!r} is {plugins!r}; expected "
            '{distribution: {"version": text, "sha256": SHA-256}}'
        )
    return _packets_problem(header.get("packets"))


def _packets_problem(packets: object) -> str | None:
    """What is wrong with a header's ``packets``, the stream's packet ids, or None."""
    if not isinstance(packets, list) or not packets:
        return 'the header lists no stream packets ("packets")'
    unknown = [p for p in packets if type(p) is not int or p not in PACKETS]
    if unknown:  # each once, the first few (a stranger's list of 100,000 said 500 KB of it)
        said = list(dict.fromkeys(shortened(repr(p), 40) for p in unknown))
        more = f" and {len(said) - 10:,} more" if len(said) > 10 else ""
        return f"header field 'packets' holds [{', '.join(said[:10])}]{more}, not sensor packet ids"
    if len(packets) > MAX_STREAM_IDS:  # the Stream command's count is one byte
        return (
            f"header field 'packets' lists {len(packets):,} ids; allowed: at most "
            f"{MAX_STREAM_IDS} (a stream's request), as run --record writes them"
        )
    return None


def command_at(stream: bytes | bytearray, offset: int) -> str:
    """The OI command of ``stream`` (host -> robot bytes, commands back to back) that holds
    byte ``offset``: ``Drive (137) 89 00 c8 80 00``; ``nothing`` past the end."""
    if offset >= len(stream):
        return "nothing"
    at = 0
    while at <= offset:
        try:
            decoded = decode_command(stream[at:])
        except EncodeError:
            decoded = None
        if decoded is None:  # not a command from here: show the bytes themselves
            return _bytes_at(stream, offset)
        command, size = decoded
        if at + size > offset:
            spec = command.spec
            return f"{spec.title} ({spec.opcode}) {stream[at : at + size].hex(' ')}"
        at += size
    return _bytes_at(stream, offset)


def _bytes_at(stream: bytes | bytearray, offset: int) -> str:
    """Up to 8 bytes of ``stream`` from ``offset``, or ``nothing`` past its end: a replay
    that wrote nothing there was said to have sent ``bytes `` (the record of a robot that
    fell asleep in a pause: ``the replay's own ending sent bytes ``)."""
    shown = stream[offset : offset + 8]
    return f"bytes {shown.hex(' ')}" if shown else "nothing"


#: Seconds of the record's clock a replay waits, past the robot's next recorded bytes, for
#: the bytes the tree wrote before them (:meth:`ReplayTransport.starved`).
STARVED_AFTER_S = 1.0

#: A chunk's time stamp is rounded to the microsecond (``"t": 3.240000``): one the recorded
#: run read at the very end of a wait (the safe stop's listening, whose end its clock's float
#: sums reach at 3.2399999999) may be stamped just past it, and a replay, whose clock adds
#: the same waits, left it for the next read: its stop again came a chunk early, a
#: difference. Half the rounding's step of slack gives it where it was read.
STAMP_SLACK = 0.5e-6

#: Bytes a replay keeps past the first difference, of the recorded bytes and of the tree's,
#: to name the commands there: the longest OI command (a Script, 152) is 102 bytes.
DIFFERENCE_CONTEXT = 256


def read_reach(now: float, timeout: float, step: float | None) -> float:
    """Where a read's wait of ``timeout`` from ``now`` ends on a record's clock: at its time,
    or on a link whose reads wait whole steps (:data:`READ_STEP`) at the first step at or
    past it, one at least, as ``SimLink.read`` steps (its clock, and so the record's, is on
    its steps: a chunk's stamp is one)."""
    if step is None:
        return now + timeout
    return now + max(1, math.ceil((timeout - 1e-9) / step)) * step


class ReplayTransport:
    """A transport that plays back the "in" side of a record on the recorded clock.

    ``read`` returns the next recorded chunk and sets the clock to its time; ``write``
    compares what the host sends with the record's "out" side. A chunk is not given before
    the host has written what it had written when the chunk was recorded: a reply comes
    after its request. On the virtual clock (``run --fast --record``) a reply and its request
    share a time stamp, and a read that drains the line before the request (as the start-up
    does) took the reply away.

    The record is read as the replay goes (:meth:`Record.chunks`), and of either side only
    the bytes of the command being compared are kept (:attr:`written` counts the tree's),
    so a replay's memory does not grow with the record's length: it held every chunk, 341 MB
    for a 2-hour run. The robot's chunks are read ahead of the replay only while the tree
    has written past the recorded bytes read so far (they wait in a queue, :attr:`pending`).
    ``progress(fraction)`` is called at each tenth of the record's time replayed.

    A record without its end line (:meth:`Record.unended`) is compared up to where it ends:
    what the tree writes once the robot's last recorded bytes are given, past the recorded
    ones, is no difference (the live run's were lost with the rest of its record, or it was
    killed before writing them), so the replay's own safe stop is not one.
    """

    #: the recorded clock, as fast as the replay reads it
    wall_clock = False
    #: whether the recorded run's stop was listened after (:data:`STOP_LISTENED`): then the
    #: replay's is too, on the recorded bytes, as a line that loses bytes to the robot's is
    _listened = False

    def __init__(
        self,
        record: Record,
        name: str = "replay",
        progress: Callable[[float], None] | None = None,
    ) -> None:
        self.name = name
        self._chunks = record.chunks()
        self._more = True  # the file has chunks not read yet
        self._inbound: deque[tuple[float, bytes, int]] = deque()  # read, not given yet
        self._out_read = 0  # the recorded "out" bytes read from the file so far
        #: each recorded "out" chunk read and not yet written by the tree: (the offset of
        #: its end, its time), for :meth:`write`'s clock
        self._out_times: deque[tuple[int, float]] = deque()
        self._recorded = record.out_bytes
        self._listened = bool(record.header.get(STOP_LISTENED, False))
        #: the recorded link's read step (:data:`READ_STEP`), or None: a read's wait as given
        self.read_step: float | None = record.header.get(READ_STEP)
        self._ended = record.ended
        self._progress = progress
        self._last_t = record.last_chunk_t  # a replay's last read or write is its 100 %
        self._tenths = 0
        # the command being compared starts at byte _start of both sides: each side's bytes
        # from there (the tree's capped past a difference)
        self._start = 0
        self._expected = bytearray()
        self._sent = bytearray()
        self._parsable = True  # whether the bytes so far are whole OI commands
        self._now = 0.0
        self._open = True
        #: how many bytes the tree wrote
        self.written = 0
        #: byte offset of the first difference from the recorded "out" side, once there is one
        self.difference: int | None = None
        self._starved_at: int | None = None  # where the tree stopped short (:meth:`starved`)
        #: a write early (:meth:`_early_by`): the robot's chunks not given yet that the recorded
        #: run had read before it, and the seconds of the record's clock it came before its time
        self.early: tuple[int, float] | None = None
        #: inside :meth:`recorded_reads`: a read gives what the recorded run read before the
        #: tree's next write, whatever the clock
        self._as_recorded = False
        #: the replay was ended before the record's end (:meth:`end_here`: ``--to``)
        self.ended_early = False
        #: the bytes the tree had written when the recorded run's link failed, after its
        #: last tick, the same as the record's up to there (``stack.LinkLostAfter``); None:
        #: its link did not fail, or the replay did not get there
        self.link_lost_from: int | None = None
        #: the recorded run's changes of the port's rate, ``(time, rate)`` in order, not yet
        #: done again (:meth:`set_baud`)
        self._rate_changes = deque(
            (t, note[BAUD_NOTE]) for t, note in record.notes if BAUD_NOTE in note
        )

    def _read_chunk(self, queue: bool = True) -> bool:
        """Read the record's next chunk into the queue (``queue``; else the robot's chunk is
        dropped: the replay is over) or the recorded bytes; False at the record's end."""
        if self._more:
            for t, d, b in self._chunks:
                if d == "out":
                    self._out_read += len(b)
                    self._expected += b
                    self._out_times.append((self._out_read, t))
                elif queue:
                    self._inbound.append((t, b, self._out_read))
                return True
            self._more = False
        return False

    def interrupt_at(self, offset: int, interrupt: Callable[[], None]) -> None:
        """Call ``interrupt`` (which raises) instead of a write that would take the tree past
        byte ``offset`` of the "out" side: where the recorded run's Ctrl-C came between two
        writes of one tick (the end note's :data:`WRITTEN`). A write the interrupt cut in two
        is not in the record (:class:`RecordingTransport` notes a write once it returned),
        so ``offset`` is between two writes."""
        self._interrupt = (offset, interrupt)

    #: (offset, what raises there): :meth:`interrupt_at`; None: no interrupt to do again
    _interrupt: tuple[int, Callable[[], None]] | None = None

    def end_here(self) -> None:
        """End the replay here, as if the record ended here (``--to``: a window of a long
        record): nothing more of it is read, and what the tree writes from now on (the
        replay's own safe stop, where the recorded run went on) is not compared; a
        difference found before stays one."""
        self.ended_early = True
        self._more = False
        self._inbound.clear()

    def write(self, data: bytes) -> None:
        """Compare ``data`` with the record's "out" side, and move the clock to the time the
        recorded run wrote those bytes (:meth:`_written_at`)."""
        if self.ended_early:
            self.written += len(data)
            return
        start = self.written
        if self._interrupt is not None and start + len(data) > self._interrupt[0]:
            interrupt, self._interrupt = self._interrupt[1], None
            interrupt()  # the recorded run's Ctrl-C came before these bytes
        self.written += len(data)
        if self.difference is None:
            while start + len(data) > self._out_read and self._read_chunk():
                pass
            at = start - self._start
            recorded = self._expected[at : at + len(data)]
            same = len(data)
            if recorded != data:
                same = next(
                    (i for i, (a, b) in enumerate(zip(recorded, data, strict=False)) if a != b),
                    len(recorded),
                )
            if same > 0 and self._early_by(start):  # the same bytes, before their frames
                self.difference = start
            elif same < len(data) and (
                # past the end of a record that stops short of its run's end: no difference
                same < len(recorded) or self._ended or not self.exhausted
            ):
                self.difference = start + same
            if self.difference is None:
                self._written_at(start)
        self._keep(data)

    def _early_by(self, start: int) -> bool:
        """Whether the tree writes byte ``start`` of the "out" side before the replay gave it
        the robot's chunks the recorded run had read before writing it (each queued chunk
        holds the recorded bytes written before it): the tree decided on fewer frames than
        the live run did, sooner (a ``wait`` shortened since). Kept for
        :meth:`first_difference` (:attr:`early`): how many chunks and seconds early. Before,
        only the bytes were compared: the clock jumped to the write's recorded time over
        those frames, and the replay made up a gap ("no frame was read for 2.00 s"), lost
        frames and a poor link, then said "the tree wrote the same bytes", exit 0."""
        unread = 0
        for _, _, written_before in self._inbound:
            if written_before > start:
                break
            unread += 1
        if not unread:
            return False
        at = self._out_time(start)
        self.early = (unread, max(0.0, (self._now if at is None else at) - self._now))
        return True

    def _out_time(self, start: int) -> float | None:
        """The recorded time of the "out" chunk that holds byte ``start`` (None: none read)."""
        times = self._out_times
        while times and times[0][0] <= start:
            times.popleft()
        return times[0][1] if times else None

    def write_passed(self) -> bool:
        """Whether the clock is past the time the recorded run wrote the bytes the tree has
        still to write (``stack.RecordedEnd``: an end note's count past its stop's bytes,
        :data:`MISCOUNT`)."""
        while self.written >= self._out_read and self._read_chunk():
            pass
        return (at := self._out_time(self.written)) is not None and self._now > at + STAMP_SLACK

    def _written_at(self, start: int) -> None:
        """The clock moves on to the recorded time of the chunk that holds byte ``start`` of
        the "out" side: the live run wrote it then, on its link's clock. A tick that wrote
        late after its frame (a slow tick, the process preempted, a slow write of the record
        on a loaded machine; the real-time simulator catches up at a write, as the robot's
        world goes on) stamped the command later than the frame, and the mode model times
        each mode command by that stamp (``ModeModel.apply``: packet 35 may show the old mode
        for ``settle`` s after it). Written at the frame's time, the frames that had queued
        meanwhile, still in Passive after a cliff, would come past that window and be taken
        for a second fall, and the tree, in Safe live, would starve there (``expected Motors
        (138) 8a 07, sent nothing`` at 75.36 s of a 92.6 s record).

        The jump goes no further than the robot's next recorded chunk, which the replay has
        still to give: the frames in between are not skipped (an early write, which would
        skip them, is a difference before this: :meth:`_early_by`)."""
        at = self._out_time(start)
        if at is None:
            return
        if self._inbound and self._inbound[0][0] < at:
            at = self._inbound[0][0]
        if at > self._now:
            self._now = at

    def _keep(self, data: bytes) -> None:
        """Keep the tree's bytes of the command being compared, and drop each command that
        was the same on both sides (past a difference, :data:`DIFFERENCE_CONTEXT` bytes)."""
        sent, expected = self._sent, self._expected
        if self.difference is not None:
            room = self.difference - self._start + DIFFERENCE_CONTEXT - len(sent)
            sent += data[: max(room, 0)]
            return
        sent += data
        while sent:
            size = min(len(sent), len(expected))  # compared and the same
            if self._parsable:
                try:
                    whole = command_size(sent)
                except EncodeError:  # no commands from here: command_at shows bytes
                    self._parsable = False
                    continue
                if whole is None or whole > len(expected):
                    return
                size = whole
            if size == 0:
                return
            del sent[:size], expected[:size]
            self._start += size

    def read(self, timeout: float) -> bytes:
        if self.difference is not None or self.exhausted:  # a difference ends the replay
            return self._nothing_for(timeout)
        if self._up_to_the_switch:
            return self._read_before_the_switch()
        t, data, written_before = self._inbound[0]
        late = t - STAMP_SLACK > read_reach(self._now, timeout, self.read_step)  # its rounding
        if (late and not self._as_recorded) or self.written < written_before:
            return self._nothing_for(timeout)
        self._inbound.popleft()
        self._now = max(self._now, t)
        if self._progress is not None and self._last_t > 0:
            tenths = min(int(10 * t / self._last_t), 10)
            if tenths > self._tenths:
                self._tenths = tenths
                self._progress(tenths / 10)
        return data

    def _nothing_for(self, timeout: float) -> bytes:
        """A read that gives nothing: the clock moves on by ``timeout``, and by one step of
        the float at least for any ``timeout`` > 0. A wait whose rest was under the clock's
        last bit (``5.678475 + 3.6e-16`` is ``5.678475``) added nothing: the safe stop's
        wait for a quiet line after a followed baud change (``silence._stop_heard``) read
        for ever at the record's end, its signals deferred, and only SIGKILL ended the
        replay."""
        moved = read_reach(self._now, timeout, self.read_step)
        if timeout > 0.0 and moved <= self._now:
            moved = math.nextafter(self._now, math.inf)
        self._now = moved
        return b""

    @contextlib.contextmanager
    def recorded_reads(self, up_to_the_switch: bool = False) -> Iterator[None]:
        """Meanwhile a read gives each of the robot's chunks that the recorded run read before
        the bytes the tree has still to write, at its recorded time, whatever the replay's
        clock says; the chunks recorded after those bytes wait for them as ever. The safe
        stop's read of the port's backlog (``read_backlog``, robot/ending.py) does
        what the recorded run did there: that run's host had meanwhile taken time the
        replay's clock does not keep (its tree's stop, a loaded machine), and the frames the
        robot sent then waited in the port. Before, the replay read nothing there, and its
        stop, written before those frames, was its first difference (``expected Drive (137)
        89 00 00 00 00, sent Drive (137) 89 00 00 00 00 0.00 s early: the recorded run read 1
        more of the robot's chunks before writing it``, exit 1, a pty run's record under
        load). A record made on a virtual clock has none there: nothing is read.

        ``up_to_the_switch``: a read gives, in one, every chunk the recorded run read before
        its next write and its next change of the port's rate: the last read of a listen at
        another rate (``robot/listen.heard``), which takes what came by the listen's end
        even where the wait overran it. The live run's reads there were stamped past their
        waits (the simulator's 15 ms slot on the virtual clock; a loaded host on a pty),
        and the replay, which gives a chunk only to a read whose wait reaches its stamp,
        left them out of the listen: its drive 0 at the new rate came chunks early, and
        past that difference it read nothing more, so its stop, confirmed live, was NOT
        DELIVERED (``run --fast --baud-change-at 1.5`` every time; the pty's replay under
        load, tests/runtime/test_cli_pty.py)."""
        self._as_recorded = True
        self._up_to_the_switch = up_to_the_switch
        try:
            yield
        finally:
            self._as_recorded = False
            self._up_to_the_switch = False

    #: inside :meth:`recorded_reads` with ``up_to_the_switch``: a read gives at once what
    #: the recorded run read before its next change of rate or its next write
    _up_to_the_switch = False

    def _read_before_the_switch(self) -> bytes:
        """The robot's chunks the recorded run read before the tree's next write and the
        port's next change of rate (its next :data:`BAUD_NOTE`), joined, the clock at the
        last one's time; nothing if there are none."""
        switch_at = self._rate_changes[0][0] if self._rate_changes else math.inf
        given = bytearray()
        while not self.exhausted:
            t, data, written_before = self._inbound[0]
            if self.written < written_before or t > switch_at:
                break
            self._inbound.popleft()
            given += data
            self._now = max(self._now, t)
        return bytes(given)

    @property
    def loses_bytes(self) -> bool:
        """Whether the replay's stop is listened after (``robot.ending.listened_after``): where
        the recorded run's was (:data:`STOP_LISTENED`), unless the record stopped short of its
        run's end and is used up. Past such a record's end there is nothing to hear: the
        replay's stop was called NOT DELIVERED, CONNECTION LOST, logged as an ERROR, in the
        replay of a run that ended well in Passive and whose record a full disk or
        ``--record-max`` cut (the record of a pulled cable has its end line: judged as ever)."""
        return self._listened and (self._ended or not self.exhausted)

    @property
    def exhausted(self) -> bool:
        """Whether every chunk the robot sent has been given."""
        while not self._inbound and self._read_chunk():
            pass
        return not self._inbound

    @property
    def pending(self) -> int:
        """The robot's chunks read from the record and not given yet."""
        return len(self._inbound)

    def starved(self) -> bool:
        """Whether the replay waits for ever: the robot's next recorded bytes wait for bytes
        the tree has not written, and the clock is :data:`STARVED_AFTER_S` past them. The tree
        writes only when it ticks, and ticks only on those bytes' frames: it stopped short of
        the recorded run (a mission changed since, a reload in the run). That is its first
        difference (the command expected, nothing sent)."""
        if self.difference is not None or self.exhausted:
            return False
        t, _, written_before = self._inbound[0]
        if self.written < written_before and self._now > t + STARVED_AFTER_S:
            self.difference = self._starved_at = self.written
            return True
        return False

    def first_difference(self) -> tuple[int, str, str] | None:
        """``(byte offset, command expected, command sent)`` of the first difference between
        what the tree wrote and the record's "out" side, or None when they are the same."""
        offset = self.difference
        if offset is None and self.written < self._recorded and not self.ended_early:
            offset = self.written
        if offset is None:
            return None
        while offset + DIFFERENCE_CONTEXT >= self._out_read and self._read_chunk(queue=False):
            pass  # the recorded command's bytes
        at = offset - self._start
        if not self._parsable:
            return offset, _bytes_at(self._expected, at), _bytes_at(self._sent, at)
        sent = "nothing" if offset == self._starved_at else command_at(self._sent, at)
        if self.early is not None:
            chunks, seconds = self.early
            sent += (
                f" {seconds:.2f} s early: the recorded run read {chunks} more of the robot's "
                "chunks before writing it"
            )
        return offset, command_at(self._expected, at), sent

    def set_baud(self, baud: int) -> None:
        """The port changes its rate where the recorded run changed it: the clock moves on to
        the time the record notes that change at (:data:`BAUD_NOTE`). A run on the wall clock
        switched a drained port one slot after the watchdog's drive 0 (robot/listen.py); on
        the record's clock it switched at once, listened 15 ms short of the live run's
        window, and missed its last frame there: the drive 0 at the followed rate came a
        chunk early, a difference (exit 1) in the replay of every run that followed a baud
        change. Once the tree's changes and the record's part ways (another rate), the clock
        is left alone."""
        changes = self._rate_changes
        if not changes:
            return
        at, rate = changes.popleft()
        if rate != baud:
            changes.clear()
        elif at > self._now:
            self._now = at

    def close(self) -> None:
        self._open = False

    @property
    def is_open(self) -> bool:
        return self._open

    def now(self) -> float:
        return self._now
