"""Listening for the stream at another OI rate, and the port put back whatever happens.

The watchdog tripped while bytes kept coming, none of them a frame at the run's rate and none
a damaged one (:func:`~roomba_bt.robot.silence.follow_baud` decides when): the robot may talk
at another rate. The port goes there for a window, and comes back unless the stream's frames
came there::

    drive 0 written ── drained (tcdrain) ── one slot ──► 19200, listen ──► frames: stay
                       (it leaves at 115200)               nothing, or Ctrl-C ──► 115200

Two ways a listen can hurt the robot it is meant to protect, each guarded here:

* **the rate never comes back**: a port put back only when the listen returns is left at
  19200 by a Ctrl-C, SIGTERM, SIGHUP, SIGQUIT or SIGTSTP in its ~0.1 s, and the whole safe
  stop goes out there: the robot, at 115200, drives on in Safe with its brushes on, while
  the record shows a well-formed stop. So the port comes back on every way out of the
  listen (the signal's exception goes on after), and every write checks the port against
  the robot's rate first (``CommandWriter.at_robot_rate``), the safe stop's too;
* **the drive 0 before it is re-clocked**: a switch right after the watchdog's drive 0 is
  written, before its bytes have left, loses them (the robot heard 3 of 11). So what was
  written drains first (``StreamLink.switch_rate``), and on the wall clock the port waits
  one 15 ms slot more before it switches (:data:`SETTLE_S`): a drain that returns before the
  bytes are on the wire (a pseudo-terminal, whose far end reads them when it next runs; a
  USB adapter driver that returns once the adapter has them, its FIFO still sending) leaves
  them that long to go at the old rate.
"""

from __future__ import annotations

import contextlib
import logging
from typing import TYPE_CHECKING

from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.stream import StreamParser
from roomba_bt.robot.errors import PortLost

if TYPE_CHECKING:
    from roomba_bt.robot.link import StreamLink

log = logging.getLogger(__name__)

#: After the drain, before a listen's switch on the wall clock: one OI slot (see above).
SETTLE_S = SLOT_SECONDS


def listen_at(
    link: StreamLink, rate: int, seconds: float, enough: int, back_to: int | None = None
) -> bool:
    """Whether the stream's frames come at ``rate``: what was written leaves first (drained,
    and on the wall clock :data:`SETTLE_S` more, what is read meanwhile dropped), the port
    is set there, what it holds is discarded (read before the switch took effect: the old
    rate's bytes, valid frames at the old rate), and it listens ``seconds`` (:func:`heard`).
    The port is left at ``rate`` if they do; on any other way out, an exception too (Ctrl-C,
    a signal's), it is put back at ``back_to`` (default: :attr:`StreamLink.port_rate` before
    the listen). The link's own parser and its watchdog times are not touched (what is read
    meanwhile is only counted)."""
    was = link.port_rate if back_to is None else back_to
    parser = StreamParser(link.stream_ids, link.profile, mode_plus_one=link.mode_plus_one)
    link.drain_output()
    if getattr(link.transport, "wall_clock", True):
        _settle(link, SETTLE_S)
    log.debug("%s: listening at %d baud for %.0f ms", link.name, rate, seconds * 1000)
    try:
        link.switch_rate(rate)
        deadline = link.transport.now() + seconds
        link.read(0.0)  # queued before the switch: the old rate's (an RFC 2217 port's queue)
        found = heard(link, parser, deadline, enough)
    except BaseException:  # Ctrl-C, a signal's exception, the port failing: back, then on
        if was is not None:
            with contextlib.suppress(PortLost):  # marked lost, port_rate unknown: the
                link.switch_rate(was)  # safe stop sets it again or says the port gone
        raise
    if not found and was is not None:
        link.switch_rate(was)
    return found


def _settle(link: StreamLink, seconds: float) -> None:
    """Read (counted, dropped: the listen drops what came before its switch anyway) for
    ``seconds`` of the link's clock."""
    clock = link.transport.now
    deadline = clock() + seconds
    while (remaining := deadline - clock()) > 0:
        link.read(remaining)


def _by_the_deadline(link: StreamLink) -> bytes:
    """A listen's last read, its deadline passed: what the port holds. A replay gives there
    what its recorded run read before it switched the rate again or wrote
    (``ReplayTransport.recorded_reads``): reads stamped past their waits are the listen's."""
    recorded = getattr(link.transport, "recorded_reads", None)
    if recorded is None:
        return link.read(0.0)
    with recorded(up_to_the_switch=True):
        return link.read(0.0)


def heard(link: StreamLink, parser: StreamParser, deadline: float, enough: int) -> bool:
    """Whether, reading into ``parser`` until ``deadline``, the last ``enough`` or more
    frames came one after the other with nothing invalid after them. The whole window is
    read: the old rate's frames still in flight when the port switched (the network's,
    a USB adapter's FIFO) come first and pass, and the robot's bytes at its real rate
    follow as garbage, which voids them; a robot that did change its rate keeps sending
    valid frames to the end. A read with invalid bytes (checksum failures, skipped or
    out-of-range bytes) voids the frames counted so far, its own too. What came by the
    deadline is read even if the wait overran it (a host starved past the whole window
    still finds the frames sent meanwhile)."""
    clock = link.transport.now
    counters = parser.counters
    invalid = 0
    run = 0
    while True:
        remaining = deadline - clock()
        data = link.read(remaining) if remaining > 0 else _by_the_deadline(link)
        if data:
            run += len(parser.feed(data, clock()))
            now_invalid = counters.checksum_failures + counters.skipped_bytes + counters.implausible
            if now_invalid != invalid:
                invalid, run = now_invalid, 0
        if remaining <= 0:
            break
    return run >= enough
