"""Why the stream stopped: the robot asked, once the grace ran out with nothing on the line.

Nothing arriving has several causes that look alike on the line: the robot stopped streaming
(its OI still on), it fell asleep (deaf until a BRC pulse), it was switched off or its
battery went flat, or the cable. Asking tells the first two from the rest::

    [150][0]          pause the stream (nothing must run while a reply is awaited)
    [149][1][35]      Query List, packet 35: an awake robot answers one byte, its mode
      answered ──────► awake: it stopped streaming                    StreamLost (said so)
      nothing ──► BRC pulse: RTS/DTR low 1 s, or a 1 s hang-up where the lines cannot be set
                  [149][1][35] again
                    answered ──► it was asleep: the pulse woke it      RobotAsleep
                    nothing ───► switched off, a flat battery, the cable  StreamLost

Bytes that keep coming without a frame are noise, or the robot at another rate (a battery
swap or a reset brings a Create 2 back at its default rate): :func:`follow_baud` listens at
the other OI rates when the watchdog trips on garbage.

A robot that sleeps is in Passive; asleep is also named without asking when the model has
been in Passive past the OI's five minutes with nothing from us (:func:`asleep_by_idle`).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.robot.errors import (
    BaudChanged,
    LinkDown,
    ModeError,
    RobotAsleep,
    StreamLost,
    StreamStalled,
)
from roomba_bt.robot.handshake import OI_RATES, wake_pulse
from roomba_bt.robot.wake import SLEEP_AFTER_S

#: Garbage that must have come since the last valid frame before other rates are tried.
GARBAGE_BYTES = 16
#: How long the port listens at another rate, and the frames it must find there.
LISTEN_S = 0.1
FRAMES_TO_FOLLOW = 2

if TYPE_CHECKING:
    from roomba_bt.robot.connection import Connection

#: How long each query waits for its one-byte reply.
QUERY_TIMEOUT_S = 0.3


def asleep_by_idle(connection: Connection) -> RobotAsleep | None:
    """Asleep by the OI's rule: Passive, a profile that sleeps, and nothing from us (no
    command, no BRC pulse) for the five minutes it waits before sleeping."""
    if not connection.profile.sleeps_in_passive or connection.mode is not OIMode.PASSIVE:
        return None
    idle = connection.transport.now() - connection.idle_since
    if idle < SLEEP_AFTER_S:
        return None
    return RobotAsleep(
        connection.name, idle, keep_awake=connection.keep_awake, pulses=_pulses(connection)
    )


def explain_silence(
    connection: Connection, silent_for: float, grace: float, *, halted: bool
) -> LinkDown:
    """Nothing arrived for the grace: ask the robot, wake it if it does not answer; the
    cause to raise (see the module docstring). Writing may raise
    :class:`~roomba_bt.robot.errors.PortLost`: then that is the cause."""

    def lost(probed: str) -> StreamLost:
        return StreamLost(
            connection.name, silent_for, grace, 0, watchdog=connection.watchdog,
            halted=halted, probed=probed,
        )  # fmt: skip

    # how long it had been without a command or a pulse when the stream stopped
    idle = connection.link.silent_since - connection.idle_since
    try:
        connection.send(oi.pause_stream())
    except ModeError:  # the model says Off: nothing to ask
        return lost("")
    if _answers(connection):
        return lost(
            "the robot still answers a query (its OI is on): it stopped streaming by itself"
        )
    connection.unheard = "the robot answers nothing"  # unless a pulse wakes it
    if not connection.profile.sleeps_in_passive:
        return lost("it answered no query either (switched off, a flat battery, or the cable)")
    pulse = wake_pulse(connection.transport)
    if pulse.problem is not None:
        return lost(
            "it answered no query either, and no BRC pulse could wake it to tell sleep from "
            f"the rest ({pulse.problem})"
        )
    if _answers(connection):
        connection.unheard = None
        return RobotAsleep(
            connection.name, idle, keep_awake=connection.keep_awake,
            pulses=_pulses(connection), woken_by=pulse.how,
        )  # fmt: skip
    return lost(
        f"it answered no query, not even after a BRC pulse ({pulse.how}): switched off, a "
        "flat battery, or the cable"
    )


def _answers(connection: Connection) -> bool:
    return connection.query((OI_MODE_PACKET,), QUERY_TIMEOUT_S) is not None


def _pulses(connection: Connection) -> bool:
    wake = connection.wake
    return wake is not None and wake.unavailable is None


def follow_baud(connection: Connection, stalled: StreamStalled) -> BaudChanged | None:
    """The watchdog tripped while bytes kept coming: if the stream's frames come at another
    OI rate, the robot changed its rate (the port is left there, drive 0 sent again at it,
    where the robot understands it); None if they do not (noise: the stall is ridden through
    at the run's rate)::

        115200 ▒▒▒▒▒▒▒▒ (100 ms, no frame) ──► port at 19200, listen 100 ms ──► 2 frames
    """
    link = connection.link
    if link.bytes_since_frame < GARBAGE_BYTES or not link.stream_ids:
        return None
    was = connection.baud
    garbage_s = link.transport.now() - link.silent_since
    since_wall = time.time() - garbage_s  # the last valid frame, for the message
    for rate in OI_RATES:
        if rate == was or not link.listen_at(rate, LISTEN_S, FRAMES_TO_FOLLOW):
            continue
        link.set_baud(rate)  # the link's parser starts again at the new rate
        connection.baud = rate
        halted = connection.halt()
        return BaudChanged(connection.name, rate, was, garbage_s, since_wall, halted=halted)
    return None
