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

Bytes that keep coming without a frame are noise, or the robot at another rate (a Baud (129)
the run did not send): :func:`follow_baud` listens at the other OI rates when the watchdog
trips on garbage that holds no damaged frame of the run's rate (a noisy line's garbage does:
the robot talks at the run's rate, and a listen elsewhere could only miss it).

A robot that sleeps is in Passive; asleep is also named without asking when the model has
been in Passive past the OI's five minutes with nothing from us (:func:`asleep_by_idle`).

A robot silent from the start (no answer to the start-up's Query List at the run's rate) is
asked at the other OI rates before the run gives up (:func:`answers_elsewhere`): one that
answers there is named ("the robot answers at 19200 baud, not at the 115200 of the run"), not
left among the likely causes.
"""

from __future__ import annotations

import contextlib
import weakref
from typing import TYPE_CHECKING

from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import BATTERY_PACKETS, SLOT_SECONDS, SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.stream import stream_period
from roomba_bt.robot import wording
from roomba_bt.robot.discovery import OI_RATES, search, wake_pulse
from roomba_bt.robot.ending import fell_asleep, signals_deferred
from roomba_bt.robot.errors import (
    BaudChanged,
    ConnectionFailed,
    ConnectionSilent,
    LinkDown,
    ModeError,
    NoAnswer,
    RobotAsleep,
    StreamLost,
    idle_said,
    rate_of,
)
from roomba_bt.robot.link import LINK_ERRORS, LinkStatus
from roomba_bt.robot.wake import SLEEP_AFTER_S
from roomba_bt.transport.link_kind import LinkKind, link_of

#: Garbage that must have come since the last valid frame (or the last listen) before other
#: rates are tried.
GARBAGE_BYTES = 16
#: How long the port listens at another rate at least, and the frames it must find there.
LISTEN_S = 0.1
FRAMES_TO_FOLLOW = 2
#: While garbage keeps coming, how long after a listen that found nothing the next is tried:
#: a listen can miss the change (a hiccup of the host or of the robot's port, the change
#: landing after the listen began), and a robot still driving must hear drive 0 soon.
RETRY_AFTER_S = 0.1
#: A frame of the run's stream that came damaged this recently (its header, length and
#: packet ids in place) shows a noisy line at the robot's rate: no listen elsewhere
#: (:func:`follow_baud`). Half a second holds a damaged frame of most noisy stalls (the 5 %
#: bit flips damage a third of the run's 11-packet frames or more); the cost, a robot whose
#: rate changed just after such a frame is listened for that much later.
NOISY_FOR_S = 0.5

if TYPE_CHECKING:
    from roomba_bt.oi.identify import ProfileMismatch
    from roomba_bt.robot.connection import Connection

#: How long each query waits for its one-byte reply.
QUERY_TIMEOUT_S = 0.3


def _on_dock(connection: Connection) -> bool:
    """Whether the last frame saw the dock's contacts (charging sources, 34: the home base):
    a robot that slept there was charging, as a patrol's ``charge_for`` wait leaves it."""
    latest = connection.latest
    if latest is None or 34 not in latest.frame:
        return False
    return bool(latest.frame.charging_sources.home_base)


def idle_since(connection: Connection) -> float:
    """When we last gave the robot a reason to stay awake: a command or a BRC pulse
    (link clock)."""
    last = connection.writer.last_command_at
    wake = connection.wake
    if wake is not None and wake.last_pulse is not None:
        last = max(last, wake.last_pulse)
    return last


def asleep_by_idle(connection: Connection) -> RobotAsleep | None:
    """Asleep by the OI's rule: Passive, a profile that sleeps, and nothing from us (no
    command, no BRC pulse) for the five minutes it waits before sleeping. A stop written then
    meets a robot asleep, deaf until a BRC pulse: unconfirmed, said so (it was said as a line
    silent for half a second, as if the cable had failed)."""
    if not connection.profile.sleeps_in_passive or connection.mode is not OIMode.PASSIVE:
        return None
    idle = connection.transport.now() - idle_since(connection)
    if idle < SLEEP_AFTER_S:
        return None
    fell_asleep(
        connection.ending,
        f"the robot was asleep ({idle:.0f} s in Passive with nothing from us; asleep, it hears "
        "nothing until a BRC pulse)",
    )
    return RobotAsleep(
        connection.name, idle, keep_awake=connection.keep_awake, pulses=_pulses(connection),
        profile=connection.profile, on_dock=_on_dock(connection),
    )  # fmt: skip


def idle_at(connection: Connection, moment: float) -> float | None:
    """How long the robot had been without a command or a BRC pulse from us at ``moment``
    (link clock), or None if none is known before it: the watchdog's own drive 0, written
    after a stream stopped, read as "-0 s" idle when it stopped."""
    before = [t for t in connection.writer.recent_commands if t <= moment]
    pulse = connection.wake.last_pulse if connection.wake is not None else None
    if pulse is not None and pulse <= moment:
        before.append(pulse)
    return moment - max(before) if before else None


def dead_connection(
    connection: Connection, silent_for: float, grace: float, *, halted: bool
) -> ConnectionSilent | None:
    """Nothing arrived for the grace, not a byte: on a network link the connection is taken
    for dead (marked lost, so the safe stop closes it and tries a new one, ``PortReturn``);
    None on any other link, or if a byte came since the last frame.

    A network connection that carries not a byte for the grace while a stream runs is dead.
    A bridge that works carries the robot's frame every 15 ms; the stalls of an ordinary
    Wi-Fi are what ``--grace`` is set for, and the stream was asked for again twice within
    it (:mod:`~roomba_bt.robot.stall_asks`); a half-open TCP connection (an ESP8266 that
    rebooted or left Wi-Fi range: no reset reaches us) takes every byte written to it and
    fails only after minutes of TCP's resends. Asking the robot a Query List there, as on a
    cable, would only let it drive on 1.6 s more: the query is asked through the new
    connection after the stop instead (``PortReturn.heard_stop``), where an answer shows the
    robot heard it. Not a device path nor a pty: their ports fail by themselves when they
    go, and a silence there is the robot's or its stream's."""
    link = connection.link
    if link.bytes_since_frame or link_of(connection.name).kind is not LinkKind.NETWORK:
        return None
    link.status = LinkStatus.LOST
    link.streaming = False
    connection.ending.port_return.silent = True
    return ConnectionSilent(
        connection.name, silent_for, grace, watchdog=connection.watchdog, halted=halted
    )


def explain_silence(
    connection: Connection, silent_for: float, grace: float, *, halted: bool
) -> LinkDown:
    """Nothing arrived for the grace: ask the robot, wake it if it does not answer; the
    cause to raise (see the module docstring). Writing may raise
    :class:`~roomba_bt.robot.errors.PortLost`: then that is the cause."""

    def lost(probed: str, *, answers_nothing: bool = True, back: float | None = None) -> StreamLost:
        return StreamLost(
            connection.name, silent_for, grace, 0, watchdog=connection.watchdog,
            halted=halted, probed=probed, waiter=connection.waiter, came_back=back,
            lost_before=bytes_lost_said(connection) if answers_nothing else "",
        )  # fmt: skip

    # how long it had been without a command or a pulse when the stream stopped
    idle = idle_at(connection, connection.link.silent_since)
    clock = connection.transport.now
    asked = clock()
    try:
        connection.send(oi.pause_stream())
    except ModeError:  # the model says Off: nothing to ask
        return lost("", answers_nothing=False)
    if _answers(connection):
        return lost(
            "the robot still answers a query (its OI is on): it stopped streaming by itself",
            answers_nothing=False,
        )
    connection.unheard = "the robot answers nothing"  # unless a pulse wakes it
    if not connection.profile.sleeps_in_passive:
        line = link_of(connection.name).line
        return lost(f"it answered no query either (switched off, a flat battery, or {line})")
    if connection.mode in DRIVING_MODES:
        return _asked_again(connection, silent_for, grace, halted=halted, asked=asked)
    pulse = wake_pulse(connection.transport)
    if pulse.gone is not None:  # unplugged meanwhile: the silence was the cable's
        return connection.link.lost("a BRC pulse", pulse.gone)
    if pulse.problem is not None:  # nothing known of the robot: not said Off
        return lost(
            "it answered no query either, and no BRC pulse could wake it to tell sleep from "
            f"the rest ({pulse.problem})",
            answers_nothing=False,
        )
    if _answers(connection):
        connection.unheard = None
        if idle is None or idle < SLEEP_AFTER_S:  # no sleep by the OI's rule: said as seen
            return lost(
                f"it answered again after a BRC pulse ({pulse.how}), having been "
                f"{idle_said(idle)} in Passive without a command or a pulse from us: too soon "
                "to sleep (the OI sleeps after 5 minutes of that)",
                answers_nothing=False, back=silent_for + connection.transport.now() - asked,
            )  # fmt: skip
        return RobotAsleep(
            connection.name, idle, keep_awake=connection.keep_awake, on_dock=_on_dock(connection),
            pulses=_pulses(connection), woken_by=pulse.how, profile=connection.profile,
        )  # fmt: skip
    return lost(
        f"it answered no query, not even after a BRC pulse ({pulse.how}): "
        f"{_silent_causes(connection)}"
    )


#: Seconds a robot last seen in Safe or Full that answered no query is given before it is
#: asked once more: as long as a BRC pulse would have taken (it is never asleep there).
ASK_AGAIN_AFTER_S = 1.0


def _asked_again(
    connection: Connection, silent_for: float, grace: float, *, halted: bool, asked: float
) -> StreamLost:
    """The robot, last seen in Safe or Full, answered no query: asked once more after
    :data:`ASK_AGAIN_AFTER_S`, with no BRC pulse: Safe and Full never sleep, so a pulse
    could tell nothing; and on a port without modem lines the pulse is a hang-up, whose
    speed 0 loses the bytes still queued for a frozen line (the watchdog's drive 0 among
    them: a robot frozen behind its adapter for 3 s would spin on after it came back, and
    the run call it asleep). One that answers now came back: a frozen adapter or cable, not
    sleep."""
    link = connection.link
    clock = link.transport.now
    deadline = clock() + ASK_AGAIN_AFTER_S
    while (now := clock()) < deadline:  # what comes meanwhile is the old stream's
        link.read(deadline - now)
        if clock() <= now:  # a clock that does not move (a replay past its record)
            break
    mode = connection.mode.label  # last seen in, before the robot's reply
    reply = _reply(connection)
    if reply is None:
        asked_twice = f"it answered no query, asked twice {ASK_AGAIN_AFTER_S:g} s apart"
        lost_before = bytes_lost_said(connection)
        if lost_before:  # the reason says the OI went Off mid-run: Off answers no query, and
            # "in Safe, which never sleeps" read as if the robot were still there in Safe
            probed = (
                f"{asked_twice}, as an OI gone Off does (last seen in {mode}; else "
                f"{_silent_causes(connection)})"
            )
        else:
            probed = f"{asked_twice}, and it was in {mode}, which never sleeps: " + (
                _silent_causes(connection)
            )
        return StreamLost(
            connection.name, silent_for, grace, 0, watchdog=connection.watchdog, halted=halted,
            waiter=connection.waiter, probed=probed, lost_before=lost_before,
        )  # fmt: skip
    connection.unheard = None
    # the mode the robot answered with, not the model's: it may have fallen to Passive
    # meanwhile (driven onto its dock while the line was frozen)
    answered = connection.modes.detector.interpret(reply.oi_mode_raw)
    if answered is None or answered.label == mode:
        said = f"it answered again, in {mode}, which never sleeps"
    else:
        said = f"it answered again, in {answered.label} (last seen in {mode}, which never sleeps)"
    return StreamLost(
        connection.name, silent_for, grace, 0, watchdog=connection.watchdog, halted=halted,
        waiter=connection.waiter, came_back=silent_for + clock() - asked, probed=said,
    )  # fmt: skip


def garbled_line(
    connection: Connection, silent_for: float, grace: float, garbled: int, *, halted: bool
) -> StreamLost:
    """Bytes kept coming for the grace (``garbled`` of them) and none made a frame: noise, or
    a robot of another model (its frames pass that model's checksum, or only its range holds
    their values: the profile is wrong,
    :meth:`~roomba_bt.robot.link.StreamLink.profile_mismatch`). What a stop written now
    cannot be known to have reached is said with it."""
    link = connection.link
    mismatch = link.profile_mismatch()
    noisy = link.damaged_frame_at > link.silent_since  # its frames, damaged: at our rate
    if mismatch is not None:
        another_model(connection, mismatch)
    else:
        connection.unheard = (
            f"the line is garbled (the robot's frames come damaged at {connection.baud})"
            if noisy
            else f"the line is garbled (no valid frame at {connection.baud} or another OI rate)"
        )
    return StreamLost(
        connection.name, silent_for, grace, garbled, watchdog=link.watchdog, halted=halted,
        waiter=connection.waiter, mismatch=mismatch, setting=connection.profile_setting,
    )  # fmt: skip


def bytes_lost_said(connection: Connection) -> str:
    """The bytes to the robot this run found lost and put right
    (:attr:`~roomba_bt.robot.connection.Connection.lost_on_the_way`), in words: "bytes from
    the computer to the robot were lost in this run (a wheel command 2 times, put right)";
    "" if none were. A robot that answers nothing after such a run most likely took a lost
    byte's neighbours for Stop (173) or Power (133) (``StreamLost``'s ``lost_before``; a
    fall to Passive, for Start: ``Connection.cable_suspected``)."""
    lost = connection.lost_on_the_way
    if not lost:
        return ""
    said = ", ".join(
        f"{what} {'once' if times == 1 else f'{times} times'}" for what, times in lost.items()
    )
    return f"bytes from the computer to the robot were lost in this run ({said}, put right)"


#: At or below this charge (%) in the last frame, a robot that answers nothing most likely
#: switched itself off: it was running on an empty battery.
FLAT_PERCENT = 1.0


def _silent_causes(connection: Connection) -> str:
    """The likely causes of a robot that answers nothing, the likeliest first: a flat battery
    when the last frame read the charge (packets 25, 26) at :data:`FLAT_PERCENT` or less."""
    last = connection.link.frame
    line = link_of(connection.name).line
    if last is not None and last.carries(BATTERY_PACKETS):
        percent = last.battery_percent
        if percent <= FLAT_PERCENT:
            return (
                f"most likely a flat battery (the last frame read {percent:.1f} %: it switched "
                f"itself off; put it on its charger), else switched off or {line}"
            )
    return f"switched off, a flat battery, or {line}"


def _reply(connection: Connection) -> SensorFrame | None:
    """The robot's answer to a Query List of its mode (packet 35), or None."""
    return connection.query((OI_MODE_PACKET,), QUERY_TIMEOUT_S)


def _answers(connection: Connection) -> bool:
    return _reply(connection) is not None


def _pulses(connection: Connection) -> bool:
    wake = connection.wake
    return wake is not None and wake.unavailable is None


def listen_window(packet_ids: tuple[int, ...], rate: int) -> float:
    """How long to listen at ``rate`` for :data:`FRAMES_TO_FOLLOW` frames of ``packet_ids``:
    the first may be cut by the window's start, and a frame longer than the 15 ms slot at a
    slow rate comes once per its own transfer time (10 bits a byte)::

        |▒▒▒[ frame ][ frame ][ frame ]|     (frames to follow + 1) transfers + a slot

    Group 100 (84 bytes) at 19200: 44 ms a frame, a window of 146 ms, not 100."""
    transfer = stream_period(packet_ids, rate)
    return max(LISTEN_S, (FRAMES_TO_FOLLOW + 1) * transfer + SLOT_SECONDS)


def follow_baud(connection: Connection) -> BaudChanged | None:
    """The watchdog tripped while bytes kept coming: if the stream's frames come at another
    OI rate, the robot changed its rate (the port is left there, drive 0 sent again at it,
    where the robot understands it); None if they do not (noise, or a listen that missed:
    the stall is ridden through at the run's rate, and this is called again while garbage
    keeps coming, :data:`RETRY_AFTER_S` after the garbage was last judged)::

        115200 ▒▒▒▒▒▒▒▒ (100 ms, no frame) ──► port at 19200, listen 100 ms ──► 2 frames
                                                   nothing: 115200, 100 ms ──► listen again
        115200 ▒▒[19 n id .. bad sum]▒▒ ──► no listen: a noisy line at the robot's rate

    From the specs ("Serial Port Settings", Baud (129)): a robot's
    rate changes only by Baud, or at power-on (where the OI comes up Off and streams
    nothing). Garbage that holds a damaged frame of the run's stream (its header, length and
    packet ids in place, the checksum or a value wrong: :attr:`StreamLink.damaged_frame_at`)
    is the robot talking at the run's rate over a noisy line, and a listen elsewhere can only
    miss it: no listen while one came in the last :data:`NOISY_FOR_S`, the garbage judged,
    the next judgement on new garbage. At another rate no damaged frame shows (three or more
    bytes would have to fall in place): the listen comes at the trip, not after a long
    silence, since a robot that changed its rate did not understand the watchdog's drive 0
    and drives on until it is sent again at its rate. Before, a line with 5 % of its bytes
    flipped was listened at 19200 at most trips, the port away from the robot's rate 0.1 s
    each time."""
    link = connection.link
    if not link.stream_ids:
        return None
    now = link.transport.now()
    last = connection.baud_listened
    if last is not None and last[0] > link.silent_since:  # judged in this stall
        if now - last[0] < RETRY_AFTER_S or link.bytes_read - last[1] < GARBAGE_BYTES:
            return None
    elif link.garbage_since_frame < GARBAGE_BYTES:  # a frame cut by a late read is not
        return None
    if now - link.damaged_frame_at < NOISY_FOR_S:  # the robot's frames, hurt: noise
        connection.baud_listened = (now, link.bytes_read)  # judged: next on new garbage
        return None
    was = connection.baud
    garbage_s = now - link.silent_since
    garbage_bytes = link.bytes_since_frame
    try:
        for rate in OI_RATES:
            if rate == was:
                continue
            window = listen_window(link.stream_ids, rate)
            # a signal waits for the listen's end (0.1-0.15 s; where the process can hold
            # it): the port then at the rate the robot talks at, for the safe stop
            with signals_deferred():
                if not link.listen_at(rate, window, FRAMES_TO_FOLLOW, was):
                    continue
                link.set_baud(rate)  # the link's parser starts again at the new rate
                connection.baud = rate
            _confirm_at(connection, rate)
            halted = connection.writer.halt(by="the drive 0 at the rate followed")
            return BaudChanged(
                connection.name, rate, was, garbage_s, garbage_bytes, halted=halted,
                user=connection.waiter,
            )  # fmt: skip
    finally:
        connection.baud_listened = (link.transport.now(), link.bytes_read)
    return None


def _confirm_at(connection: Connection, rate: int) -> None:
    """The port followed the robot to ``rate`` on its frames alone: the stop written there is
    unconfirmed until the robot answers a Query List there (asked after the stop, the stream
    paused; the answer's mode is the final mode seen)."""
    _confirmed_by_quiet(
        connection,
        f"the port followed the robot to {rate} baud on its frames alone, and it answered no "
        f"query at {rate} after the stop (it may not hear there)",
    )


def another_model(connection: Connection, mismatch: ProfileMismatch) -> None:
    """The stream stalled on frames of another model (``mismatch``: they fail the profile's
    checksum or range and pass another's): the robot streams, and its frames, refused, can
    neither show a silence before the stop nor one after it. A stop written now is known
    heard once its Pause Stream quiets the line and the robot answers a Query List (whose
    one-byte reply no profile's frame rules refuse); until then it is unconfirmed, with the
    mismatch and its fix. It was said unconfirmed because "the robot had sent no valid
    frame for 0.11 s before it", a silence that was only the profile's."""
    likely = mismatch.likely[0]
    fix = wording.current.profile_named.format(name=likely.name)  # a program has no --profile
    _confirmed_by_quiet(
        connection,
        f"its frames fail {mismatch.fails} (most likely a {likely.title}: {fix}), and it "
        "neither went quiet after Pause Stream nor answered a query",
    )


def _confirmed_by_quiet(connection: Connection, unheard: str) -> None:
    """A stop written from now on is unconfirmed (``unheard`` says why) unless the line goes
    quiet after it and the robot answers a Query List (:func:`_stop_heard`)."""
    connection.unheard = unheard
    # weakly: the ending outlives a dropped connection (its finalizer holds it), and a
    # connection it held would never become garbage
    held = weakref.ref(connection)
    connection.ending.confirm = lambda: (alive := held()) is not None and _stop_heard(alive)


#: After a stop at a followed rate: how long the line must stay quiet (the stream's pause
#: heard), and how long bytes may keep coming before it is taken as not heard.
QUIET_S = 0.1
QUIET_WITHIN_S = 0.5


def _stop_heard(connection: Connection) -> bool:
    """Whether the robot heard the stop just written: its stream stopped (nothing for
    :data:`QUIET_S`, within :data:`QUIET_WITHIN_S`: a robot that did not hear the pause
    streams on, and its frames' first byte would pass for a reply) and it answers a Query
    List."""
    link = connection.link
    clock = link.transport.now
    give_up = clock() + QUIET_WITHIN_S
    quiet_until = clock() + QUIET_S
    while (now := clock()) < quiet_until:
        if now >= give_up:
            return False
        if link.read(min(quiet_until, give_up) - now):
            quiet_until = clock() + QUIET_S
    return _answers(connection)


def answers_elsewhere(connection: Connection, silent: NoAnswer) -> ConnectionFailed:
    """The robot answered no Query List at start-up at the run's rate: ask at the other OI
    rates (:func:`~roomba_bt.robot.discovery.search`: Start, pause the stream, a Query List;
    no BRC pulse). A rate that answers is the cause, named; the port is left there so the
    stop that ends the run reaches the robot (in Passive: the probe's Start put it there)::

        115200  [128][150 0][149 1 35] ... nothing ──► 19200 [128][150 0][149 3 35 21 34]
                                                             answered: "answers at 19200"

    No rate answers (or the port cannot change its rate): ``silent`` as it was, with its
    likely causes."""
    link = connection.link
    transport = link.transport
    run_rate = connection.baud
    others = tuple(rate for rate in OI_RATES if rate != run_rate)
    try:
        link.drain_output()  # the start-up's bytes leave at the run's rate
        link.port_rate = None  # the search sets the port's rate itself: unknown until done
        found = search(transport, others)
        if found.baud is None:
            link.switch_rate(run_rate)
            return silent
    except LINK_ERRORS:  # the next write sets the run's rate again (CommandWriter.at_robot_rate)
        return silent
    except BaseException:  # Ctrl-C: back at the run's rate, where the safe stop goes
        with contextlib.suppress(*LINK_ERRORS):
            link.switch_rate(run_rate)
        raise
    link.port_rate = connection.baud = found.baud
    # it answered, on this port: its bytes count as heard (the summary's final mode, the
    # stop's confirmation), as the link's own reads would; the probe read them itself
    answer = found.found
    connection.link.bytes_read += len(answer.reply) if answer is not None else 0
    connection.ending.answered = True
    # how a robot comes to talk at 19200, said only of one found there: one found at its
    # default 115200 (a run opened at another rate) was told how a 600 comes to 19200
    how = (
        f" ({connection.profile.at_19200})" if found.baud != connection.profile.default_baud else ""
    )
    return ConnectionFailed(
        connection.name,
        f"the robot answers at {found.baud} baud, not at {rate_of(run_rate, connection.waiter)}: "
        f"it answered no Query List at {run_rate}, and Start and a Query List at "
        f"{found.baud}{how}; open "
        f"it at {found.baud} (--baud {found.baud} or --baud auto; in Python, "
        f"Connection.open(port, baud={found.baud}))",
    )
