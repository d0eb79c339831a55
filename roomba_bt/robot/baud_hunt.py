"""The safe stop's search for a robot it could not confirm stopped: asked at the run's rate,
then, where the line brought garbage, the stop written at each other rate of the OI's table.

A byte lost on the way to the robot can make a Baud (129) of a command's data (a Drive whose
opcode byte was lost: its velocity's high byte read as 129, the next as the code): the robot
then talks and listens at another rate, the run reads garbage, and the stop written at the
run's rate reaches nothing (the simulator's seed 50 at 1 % lost drove on at 300 baud). A stop
not confirmed is followed by::

    run's rate     [149][3][35][21][34]          Query List: Passive answered -> heard
                   [0] x n  the stop  [149]...   again, zeros first: a byte of the stop or
                                                 of the query lost on the line
    garbage came:  for each other rate of the table (Baud (129)'s codes, 300 first)
      rate         [0] x n  the stop  [149]...   zeros (at most HUNT_ZEROS_S of them), the
                                                 stop from the mode last seen, a Query List
                   answered Passive -> found, then put back (:func:`put_back`):
      found rate   [129][run's code]              Baud to the run's rate, 100 ms (the spec)
      run's rate   [149][3][35][21][34]           answered Passive -> back at the run's rate;
                                                  else the port stays at the found rate (said)

The probe is :func:`~roomba_bt.robot.discovery.probe`'s (the quiet, the query, an answer
read as Passive): the stop's Start is what makes Passive the answer. Silence alone (a cable,
a robot switched off) is asked at the run's rate only: a robot a Baud moved streams on at its
new rate, which reads as garbage.

Slowest first: a lost opcode's data bytes are most often a speed's or
a radius' high byte (0, 1, 255), and Baud's codes 0 and 1 are 300 and 600 baud. Zeros are
capped by time (:data:`HUNT_ZEROS_S`), not the full :data:`~roomba_bt.robot.ending.
STOP_RESYNC_ZEROS`: 512 zeros take 17 s at 300 baud, a robot driving meanwhile. The search
is bounded by :func:`hunt_seconds` (13.9 s from 115200, most of it at the slow rates).
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from dataclasses import dataclass

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import BAUD_CODES, baud_rate
from roomba_bt.robot.discovery import (
    DRAIN_LIMIT_S,
    PROBE_PACKETS,
    PROBE_QUERY,
    QUIET_S,
    REPLY_TIMEOUT_S,
    Probe,
    drain,
    line_seconds,
    probe,
)
from roomba_bt.robot.link import LINK_ERRORS, StreamLink
from roomba_bt.robot.writer import BAUD_CHANGE_WAIT

#: What a robot that reset is sent before it is asked at the run's rate: Start (128), its OI
#: Off after the reset (:func:`hunt`)
RESTART = oi.start().data
#: Seconds of zeros at most before the stop at each rate of the search: all
#: ``STOP_RESYNC_ZEROS`` from 19200 up, 15 at 300 baud.
HUNT_ZEROS_S = 0.5


def hunt_rates(run_rate: int) -> tuple[int, ...]:
    """The rates of Baud (129)'s table (``oi.encode.BAUD_CODES``) but the run's, slowest
    (code 0) first: see the module docstring."""
    return tuple(
        rate for rate, _ in sorted(BAUD_CODES.items(), key=lambda item: item[1]) if rate != run_rate
    )


def zeros_at(rate: int, zeros: bytes) -> bytes:
    """As many of ``zeros`` as take :data:`HUNT_ZEROS_S` at ``rate`` at most."""
    return zeros[: int(HUNT_ZEROS_S / line_seconds(1, rate))]


def probe_seconds(rate: int, written: int) -> float:
    """The longest a probe at ``rate`` after ``written`` bytes waits on the link's clock:
    its drain's limit, the reply's wait and the quiet after it."""
    quiet = max(QUIET_S, 3 * line_seconds(1, rate))
    reply = REPLY_TIMEOUT_S + line_seconds(len(PROBE_QUERY) + len(PROBE_PACKETS), rate)
    return DRAIN_LIMIT_S + line_seconds(written, rate) + reply + quiet


def hunt_seconds(run_rate: int, stop: bytes, zeros: bytes) -> float:
    """The search's bound on the link's clock, each rate's probe at its longest: a reset's
    drain, the first ask and the stop again at the run's rate, the other rates, and the Baud
    back with its wait and a probe at the run's rate (:func:`put_back`). docs/robot.md says
    it: 13.9 s from 115200 with a stop from Safe."""
    asked = DRAIN_LIMIT_S + probe_seconds(run_rate, 0)
    back = BAUD_CHANGE_WAIT + probe_seconds(run_rate, 0)
    return (
        asked
        + back
        + sum(
            probe_seconds(rate, len(zeros_at(rate, zeros)) + len(stop))
            for rate in (run_rate, *hunt_rates(run_rate))
        )
    )


@dataclass(frozen=True)
class Hunt:
    """What the search found: the probes made, in order; the rate that answered, or None."""

    probes: tuple[Probe, ...]

    @property
    def found(self) -> int | None:
        return next((p.baud for p in self.probes if p.answered), None)


def hunt(
    link: StreamLink, run_rate: int, stop: bytes, zeros: bytes, *, garbled: bool, reset: bool
) -> Hunt:
    """Ask at ``run_rate`` whether the robot heard the stop; if not, write ``stop`` after
    :func:`zeros_at` there and ask again (the stop's Start, or the query's count, lost on the
    line: seed 67 of the dock's 1 % sweep asked ``[149][35][21][34]``, a query of 35 packets
    the robot waited on), and if the line was ``garbled``, at each of :func:`hunt_rates` too,
    until one answers. A robot that ``reset`` (its banner read) is sent Start again
    first, once its banner is over (the line quiet): its OI is Off, where it answers nothing
    but Start, and the stop's Start may have been lost too (seed 51 of the dock's 1 % sweep)
    or come while it booted. The port is left at the rate that answered, else put back at
    ``run_rate`` (also on a port that fails meanwhile, and on Ctrl-C)."""
    transport = link.transport
    probes: list[Probe] = []
    link.drain_output()  # the stop's bytes leave at the run's rate
    link.port_rate = None  # the probes set the port's rate themselves: unknown until done
    found = False
    try:
        if reset:  # the banner's last bytes first: a Start within them may be lost
            drain(transport, quiet=QUIET_S, limit=DRAIN_LIMIT_S)
        probes.append(probe(transport, run_rate, RESTART if reset else b""))
        # the run's rate once more first: a byte of the stop or of the query lost there
        rates: Sequence[int] = (run_rate, *(hunt_rates(run_rate) if garbled else ()))
        for rate in rates:
            if probes[-1].answered:
                break
            probes.append(probe(transport, rate, zeros_at(rate, zeros) + stop))
        found = probes[-1].answered
    except LINK_ERRORS:  # the port failed: the next write sets the run's rate again
        return Hunt(tuple(probes))
    finally:
        if not found:
            with contextlib.suppress(*LINK_ERRORS):
                link.switch_rate(run_rate)
    if found:  # else switch_rate set it (the run's rate), or left it unknown on a failure
        link.port_rate = probes[-1].baud
    return Hunt(tuple(probes))


def put_back(link: StreamLink, found: int, run_rate: int) -> bool:
    """Send a robot the search found at ``found`` baud back to ``run_rate``: Baud (129) with
    the run's code, written at ``found``; the 100 ms the spec asks before the new rate
    (:data:`~roomba_bt.robot.writer.BAUD_CHANGE_WAIT`, read away on the link's clock); then
    a Query List at ``run_rate``. Left at 300 baud, the robot answered nothing to the next
    run at 115200 until it was powered off. True if it answered there in Passive: the port
    is then at ``run_rate``; else it is left at ``found``, where the robot last answered
    (also on a port that fails meanwhile, and on Ctrl-C)."""
    transport = link.transport
    back = False
    link.port_rate = None  # as in :func:`hunt`: the rate is the probes' until done
    try:
        transport.write(baud_rate(run_rate).data)
        link.drain_output()  # the Baud leaves at ``found`` before the port changes
        drain(transport, quiet=BAUD_CHANGE_WAIT, limit=BAUD_CHANGE_WAIT)
        back = probe(transport, run_rate, b"").answered
    except LINK_ERRORS:  # the port failed: the next write sets the rate again
        return False
    finally:
        if not back:
            with contextlib.suppress(*LINK_ERRORS):
                link.switch_rate(found)
    if back:
        link.port_rate = run_rate
    return back


def asks_after(link: StreamLink) -> bool:
    """Whether a stop not confirmed is asked after on this link: on the wall clock, and on
    the simulator's virtual one where its line loses bytes to the robot (as
    ``ending.listened_after``, whether or not a stream ran); in a replay where the recorded
    run's stop was (``ReplayTransport.loses_bytes``), on the recorded bytes."""
    transport = link.transport
    if not transport.is_open:
        return False
    return bool(getattr(transport, "wall_clock", True) or getattr(transport, "loses_bytes", False))


def found_words(found: int, run_rate: int, *, back: bool) -> str:
    """What a stop that reached the robot only at ``found`` baud says, in the summary and the
    log; ``back``: whether :func:`put_back` brought the robot back to ``run_rate``."""
    said = (
        f"the robot had moved to {found} baud (a Baud (129) made of lost bytes, most likely): "
        f"stopped there, it answered in Passive at {found}; "
    )
    if back:
        return said + f"sent Baud back to {run_rate}, it answered in Passive at {run_rate}"
    return said + (
        f"sent Baud back to {run_rate}, it did not answer there: the port is left at {found} "
        f"(the robot talks at {found}, not {run_rate}, until it is powered off; "
        "`--baud auto` or roomba-bt doctor finds it)"
    )
