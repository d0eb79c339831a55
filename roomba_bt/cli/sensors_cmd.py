"""``roomba-bt sensors``: a live table of every decoded sensor, from a robot or the simulator."""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import (
    add_command,
    add_far_end_options,
    count,
    refresh_rate,
)
from roomba_bt.oi.frames import stream_frame_size
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import stream_budget
from roomba_bt.runtime.summary import DEFAULT_GRACE, INTERNAL_ERROR_SAID, ExitCode

if TYPE_CHECKING:
    from roomba_bt.oi.frames import SensorFrame
    from roomba_bt.robot.connection import Connection

#: The groups tried, most packets first: the first whose stream frame fits the baud rate's
#: 15 ms budget is the one a stream could carry. Group 100 (every packet, 80 data bytes, an
#: 84-byte frame) fits at 57600 and 115200; group 6 (7-42) at 38400; group 1 (7-16: bumps,
#: cliffs, walls, buttons, a 14-byte frame) down to 9600. Below that no stream fits.
GROUPS = (100, 6, 1)
#: Every packet (7-58): what the table shows at every rate. Where its stream does not fit
#: (below 57600) each table is one Query List (149) of it instead: at 19200 a stream would
#: carry group 1 alone, with no battery, mode or encoders, which is what one looks for; the
#: 80-byte reply takes 42 ms at 19200, 84 ms at 9600, so a few tables a second still come.
ALL_SENSORS = 100
#: Query Lists in a row left unanswered (1 s each) before the table gives up (exit 3).
QUERY_MISSES = 3


def group_for(baud: int) -> int | None:
    """The largest sensor group a stream can carry at ``baud``, or None."""
    for group in GROUPS:
        if stream_frame_size((group,)) <= stream_budget(baud):
            return group
    return None


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "sensors",
        sensors_command,
        f"""show every decoded sensor, live

        Stream every sensor packet (7-58) and show each decoded, with its unit, a few times
        a second; at a rate too slow for that stream (19200, 38400) each table is one Query
        List (149) of them instead. The robot stays in Passive and is left there.
        Without --port, the built-in simulator. Exit codes: 0 done (--count reached), 2
        invalid option or a wrong profile (the robot's frames are another model's, as run
        says it), 3 connection or stream failure, {INTERNAL_ERROR_SAID}, 130 interrupted.
        """,
    )
    add_far_end_options(
        parser,
        port_help="serial device or URL; default: the built-in simulator",
        world_help="simulator world (without --port)",
    )
    parser.add_argument("--count", type=count, default=0, help="stop after N refreshes (0: run)")
    parser.add_argument(
        "--rate", type=refresh_rate, default=5.0, help="refreshes a second (default 5, at most 66)"
    )


def format_table(frame: Any) -> str:
    """One row a packet of ``frame``. On a robot whose packet 35 reads the mode + 1 (a Roomba
    600's firmware bug, as the connection learned at start-up and its parser was told) the
    frame already reads the mode corrected; the row says so (it showed the raw reading:
    "2 safe" for a robot in Passive)."""
    rows = []
    for name, value in frame.as_dict().items():
        pid = next(p.id for p in PACKETS.values() if p.name == name)
        unit = PACKETS[pid].unit
        shown = _show(value)
        if pid == OI_MODE_PACKET and frame.layout.mode_plus_one:
            shown = _show_plus_one(value, frame[pid])
        rows.append(f"{pid:>3}  {name:<32} {shown:<40} {unit}")
    return "\n".join(rows)


def _show_plus_one(mode: object, raw: int) -> str:
    """Packet 35 of a robot that reports the mode + 1: the frame's corrected mode, or the
    byte as sent when it is no mode even less 1."""
    if not isinstance(mode, OIMode):
        return f"{raw} (no mode, even less 1 for a 600's mode + 1)"
    return f"{mode.value} {mode.name.lower()} (reads {raw}: a 600's mode + 1)"


def _show(value: object) -> str:
    slots = getattr(value, "__slots__", None)
    if slots and hasattr(value, "raw"):
        on = [s for s in slots if s != "raw" and getattr(value, s) is True]
        return f"{value.raw} [{', '.join(on) or '-'}]"
    if hasattr(value, "code") and hasattr(value, "source"):
        flags = [
            f
            for f in ("red_buoy", "green_buoy", "force_field", "virtual_wall")
            if getattr(value, f)
        ]
        return f"{value.code} {value.source.value} {' '.join(flags)}".strip()
    if hasattr(value, "name") and hasattr(value, "value"):
        return f"{value.value} {value.name.lower()}"
    return str(value)


def sensors_command(args: argparse.Namespace) -> int:
    from roomba_bt.cli.links import talk_to_robot

    return talk_to_robot(args, "sensors", lambda connection, _: _show_live(connection, args),
                         refuse=_no_stream_fits)  # fmt: skip


def _no_stream_fits(profile: RobotProfile, baud: int | None) -> str | None:
    """Why ``sensors`` cannot show a table at ``baud``: not even group 1 fits 15 ms (None,
    ``--baud auto`` before its probe: any rate it finds carries one)."""
    if baud is None or group_for(baud) is not None:
        return None
    return (
        f"--baud {baud}: no sensor stream fits in 15 ms at this rate (at most "
        f"{stream_budget(baud)} bytes a frame); allowed: 9600 or more"
    )


def _show_live(connection: Connection, args: argparse.Namespace) -> int:
    """The table of every packet, ``args.rate`` times a second, ``args.count`` times (0:
    until interrupted), from the stream where the whole of it fits the rate, else a Query
    List each; the robot is left in Passive (the caller's ``with``)."""
    if group_for(args.baud) == ALL_SENSORS:
        connection.start("passive", (ALL_SENSORS,))
        _show_streamed(connection, connection.profile, args)
    else:
        connection.start("passive")  # no stream: a reply has no header to tell it apart
        _show_queried(connection, connection.profile, args)
    return ExitCode.OK


def _print_table(connection: Connection, profile: RobotProfile, frame: SensorFrame) -> None:
    """One table, over the last on a terminal."""
    prefix = "\x1b[H\x1b[J" if sys.stdout.isatty() else ""
    print(f"{prefix}{connection.name}  ({profile.title})\n{format_table(frame)}\n", flush=True)


def _show_queried(connection: Connection, profile: RobotProfile, args: argparse.Namespace) -> None:
    """A Query List (149) of every packet when a table is due. One unanswered (a byte lost
    on the line) is said and asked again; :data:`QUERY_MISSES` in a row end the command as
    a lost connection (exit 3), as a stream that stays silent does."""
    from roomba_bt.robot.errors import ConnectionFailed

    shown = misses = 0
    due = time.monotonic()  # the first table at once
    while args.count == 0 or shown < args.count:
        time.sleep(max(0.0, due - time.monotonic()))
        frame = connection.query((ALL_SENSORS,))
        if frame is None:
            misses += 1
            if misses >= QUERY_MISSES:
                raise ConnectionFailed(
                    connection.name, f"no reply to {misses} Query Lists (149) in a row"
                )
            print("roomba-bt: no reply to a Query List (149) within 1 s; asking again",
                  file=sys.stderr)  # fmt: skip
            continue
        misses = 0
        due = time.monotonic() + 1.0 / args.rate
        _print_table(connection, profile, frame)
        shown += 1


def _show_streamed(connection: Connection, profile: RobotProfile, args: argparse.Namespace) -> None:
    """The newest frame of the stream when a table is due; a watchdog trip is ridden through
    as ``run`` does; at the end what the line lost, if anything (:func:`_say_the_link`)."""
    tally = _FramesTally()
    try:
        _stream_tables(connection, profile, args, tally)
    finally:  # done, a Ctrl-C, the stream lost: what the line lost, as run's summary says it
        _say_the_link(connection, tally)


class _FramesTally:
    """The stream's frames read and the robot's 15 ms slots they spanned, on the run's
    schedule (:class:`~roomba_bt.runtime.schedule.SlotSchedule`): a slot with no frame read
    is a frame the line lost."""

    def __init__(self) -> None:
        from roomba_bt.runtime.schedule import SlotSchedule

        self.schedule = SlotSchedule()
        self.read = 0
        self.spanned = 0

    def add(self, count: int, arrival: float) -> None:
        self.read += count
        # (the first batch is one slot on the schedule however many frames it holds)
        self.spanned += max(count, self.schedule.slots(count, arrival))


def _say_the_link(connection: Connection, tally: _FramesTally) -> None:
    """The run summary's ``frames`` and ``link`` lines on stderr, for a line that lost or
    garbled any of the robot's bytes (a cable that broke a third of the frames showed its
    tables and exit 0, saying nothing: each table is the newest whole frame, and one came)."""
    from roomba_bt.runtime.summary import RunSummary, link_lines

    summary = RunSummary("sensors", robot=connection.name)
    summary.take_counters(connection.counters)
    summary.ticks, summary.frames_lost = tally.read, tally.spanned - tally.read
    for line in link_lines(summary, "each table showed the robot as the last whole frame had it"):
        print(f"roomba-bt sensors: {line}", file=sys.stderr)


def _stream_tables(
    connection: Connection, profile: RobotProfile, args: argparse.Namespace,
    tally: _FramesTally,
) -> None:  # fmt: skip
    """:func:`_show_streamed`'s loop, each batch of frames counted in ``tally``."""
    from roomba_bt.robot.errors import StreamStalled

    shown = 0
    #: a watchdog trip being ridden through, as ``run`` does: (bytes read then, drive 0 sent)
    stall: tuple[int, bool] | None = None
    last = -math.inf  # the first frame is shown at once
    while args.count == 0 or shown < args.count:
        try:
            frames = connection.poll(0.1)
            if frames:
                tally.add(len(frames), frames[-1].time)
        except StreamStalled as stalled:  # a flaky line is what one looks at it for
            if stalled.mismatch is not None:  # another model's frames: certain now
                raise
            stall = (connection.link.bytes_read, stalled.halted)
            print(f"roomba-bt: {stalled}; waiting up to {DEFAULT_GRACE:g} s for valid "
                  "frames", file=sys.stderr)  # fmt: skip
            frames = []
        if stall is not None:
            if not frames:  # the cause, once known or the grace is over (exit 3)
                connection.check_stall(stall[0], DEFAULT_GRACE, stall[1])
                continue
            stall = None
            print("roomba-bt: valid frames are back", file=sys.stderr)
        if not frames or time.monotonic() - last < 1.0 / args.rate:
            continue
        last = time.monotonic()
        _print_table(connection, profile, frames[-1].frame)
        shown += 1
