"""A connection's start-up: the robot proven to listen, and the "mode + 1" rule learned.

:meth:`~roomba_bt.robot.connection.Connection.start` sends::

    [128]                 Start: the OI leaves Off for Passive
    [150][0]              pause a stream a previous session may have left running
                          ... read until the line is quiet (a stale stream, a banner)
    [149][1][35]  x 2     Query List, packet 35, twice: the robot answers one byte (its mode),
                          which proves it listens at this baud and calibrates the "mode + 1"
                          rule; the reply has no checksum, so two that agree are needed (up to
                          START_QUERIES asks: :func:`agreed_mode_reply`)
    [0] x 34, then again  after a Query List nobody answered, once: a byte of it lost on the
                          way to the robot leaves its parser waiting (``[149][35]`` waits for
                          35 ids); zeros and the quiet line set it in step, and it is asked
                          again at the same rate before the start-up blames the baud rate,
                          sleep or the wiring
    [131] or [132]        Safe or Full, if asked
    [148][n][ids...]      the stream, checked against the bandwidth before it is sent
    [0] x 35+, [148]...   no frame within the watchdog's time (100 ms) of the request: a
                          byte of it lost on the way leaves no stream (the robot waits for
                          an id, or streams another list), so the zeros that complete any
                          wait it left and the request again, up to STREAM_ASKS_AGAIN times
                          (:func:`stream_zeros`; ``Connection._stream_again``)
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Literal

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.robot import wording
from roomba_bt.robot.errors import ConnectionFailed, NoAnswer
from roomba_bt.robot.writer import RESYNC_ZEROS
from roomba_bt.transport.base import TransportError
from roomba_bt.transport.link_kind import LinkKind, link_of

log = logging.getLogger(__name__)

#: Most Query Lists of packet 35 at start-up, looking for two consecutive replies that agree.
START_QUERIES = 4
#: why a robot may not answer at all, whatever the link: its rate, its power or sleep
WRONG_RATE = (
    "wrong baud rate (115200 by default; 19200 after Clean held at power-on on a Roomba 500, "
    "at power-off on a 600 or Create 2, or three BRC pulses after power-on)"
)
#: why a robot may not answer, its power or sleep, as a Python caller is told it (the
#: command line's words: :func:`not_awake`)
NOT_AWAKE = f"no power or the robot asleep ({wording.PYTHON.wake_asleep})"


def not_awake(port: str = "") -> str:
    """Why a robot may not answer, its power or sleep, and what its owner can do, in the
    words of the caller (:data:`~roomba_bt.robot.wording.current`): a button at the robot,
    or for a service, which nobody watches, BRC and the power. On a pty (the simulator's
    ``sim --pty``), which has no modem lines, the start-up gave no BRC pulse: what pulses
    one there by a hang-up is said instead of a cable's wiring (the long-haul report: a run
    against ``sim --pty --asleep`` said "BRC wired to the port's RTS or DTR" of a pty)."""
    if port and link_of(port).kind is LinkKind.PTY:
        return f"no power or the robot asleep ({wording.current.wake_on_pty.format(port=port)})"
    return f"no power or the robot asleep ({wording.current.wake_asleep})"


def no_answer_causes(port: str) -> tuple[str, str, str]:
    """Why the robot on ``port`` may not answer: the rate, its power or sleep, and the
    link's wiring, a cable's or a bridge's serial side (a bridge's user was told to check
    a cable there is none of)."""
    return (WRONG_RATE, not_awake(port), link_of(port).wiring)


#: 0.1.0's name (in ``robot.connection.__all__``): the causes said for a device path, a
#: cable's wiring; a URL's are :func:`no_answer_causes` of it (a bridge's serial side).
NO_ANSWER_CAUSES = no_answer_causes("/dev/ttyUSB0")


def port_not_opened(url: str, exc: TransportError) -> ConnectionFailed:
    """Why ``url`` could not be opened, with what to check; a cause the error number told
    (another program holds it, permissions, no such device:
    :func:`~roomba_bt.transport.open_failure.open_failure`) is named alone."""
    if isinstance(exc.cause, str):
        return ConnectionFailed(url, f"could not open the port: {exc.cause}")
    causes = link_of(url).open_causes
    return ConnectionFailed(url, f"could not open the port ({exc.cause})", causes)


#: How many times the stream is asked for again when no frame came after its request. Each
#: try writes the zeros and the request (78 bytes for the dock mission's 23 packets): at 1 %
#: of bytes lost a request again loses one of its own 22 % of the time, and two tries leave
#: 2 dock runs of 100 without a stream; each costs the watchdog's 100 ms.
STREAM_ASKS_AGAIN = 4


def stream_zeros(ids: tuple[int, ...]) -> bytes:
    """The zeros written before a Stream request of ``ids`` asked for again: enough to end
    any wait the first request left the robot's parser in when it lost a byte. An id lost
    leaves it waiting for one more; the count lost makes the first id the count, so it waits
    for up to that many (group 100 first: 100), more than :data:`RESYNC_ZEROS` covers. A
    zero completes the wait as packet 0, a stream the request written after them replaces;
    0 is no opcode, so the zeros left over are skipped."""
    return bytes(max(len(RESYNC_ZEROS), *ids))


#: The modes :meth:`~roomba_bt.robot.connection.Connection.start` enters, by name (a type
#: checker then refuses ``start("turbo")`` before it runs).
ModeName = Literal["passive", "safe", "full"]


def as_mode(mode: OIMode | str) -> OIMode:
    """``"safe"`` or :attr:`OIMode.SAFE` to the mode; a clear error for anything else."""
    if isinstance(mode, OIMode):
        return mode
    try:
        return OIMode[mode.upper()]
    except KeyError:
        raise ValueError(f"unknown OI mode {mode!r}; use passive, safe or full") from None


def agreed_mode_reply(
    port: str,
    ask: Callable[[], SensorFrame | None],
    timeout: float,
    resync: Callable[[], object] | None = None,
) -> int:
    """Packet 35 as two consecutive Query List replies (``ask``: one Query List, its reply
    or None after ``timeout`` s) agree on it: a reply has no checksum, and one corrupted byte
    must not end the run or teach a wrong offset. A Query List nobody answered is asked once
    more after ``resync()`` (zeros, then the line left to go quiet): one byte of it lost on
    a bad cable must not end the start-up as "wrong baud rate, asleep or wiring"."""
    replies: list[int] = []
    unanswered = 0
    for _ in range(START_QUERIES):
        reply = ask()
        if reply is None and resync is not None and not unanswered:
            unanswered += 1
            log.warning(
                "%s: no answer to a Query List (149) within %g s; its parser set in step and "
                "asked again (a byte lost on the way to the robot?)", port, timeout,
            )  # fmt: skip
            resync()
            reply = ask()
        if reply is None:
            asked = "a Query List (149)" if not unanswered else "two Query Lists (149)"
            raise NoAnswer(
                port,
                f"the robot did not answer {asked} for packet 35 within {timeout:g} s",
                no_answer_causes(port),
            )
        replies.append(reply[OI_MODE_PACKET])
        if len(replies) >= 2:
            if replies[-1] == replies[-2]:
                return replies[-1]
            log.warning("%s: packet 35 replies disagree (%s); asking again", port, replies)
    raise ConnectionFailed(
        port,
        f"{START_QUERIES} replies to a Query List for packet 35 never agreed twice in a row "
        f"({replies})",
        ("a noisy line", WRONG_RATE, "another program talking to the robot"),
    )


#: The first byte of the start-up's Query List for packet 35, ``[149][1][35]``: a "mode"
#: that reads it is the port giving back what was written to it.
_QUERY_FIRST_BYTE = oi.query_list((OI_MODE_PACKET,)).data[0]


def not_a_mode(port: str, raw: int) -> ConnectionFailed:
    """The agreed reply is no mode reading right after Start; when it is the first byte of
    the query itself, the port echoes (a loopback, a cable with its data lines joined)."""
    if raw == _QUERY_FIRST_BYTE:
        return ConnectionFailed(
            port,
            f"the port gives back what is written to it (it answered {raw}, the first byte of "
            "the Query List just sent, for the OI mode): a loopback, not a robot",
            link_of(port).echo_causes,
        )
    return ConnectionFailed(
        port,
        f"the robot answered {raw} for its OI mode right after Start, "
        f"which is no mode (Passive reads 1, or 2 on firmware that reports mode + 1)",
        (WRONG_RATE, "another program talking to the robot"),
    )
