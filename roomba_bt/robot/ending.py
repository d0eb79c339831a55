"""How a connection ends: what the safe stop sends, and what the robot was last seen doing.

Every ending (:meth:`~roomba_bt.robot.connection.Connection.close`, the context manager,
:meth:`~roomba_bt.robot.connection.Connection.safe_stop`) sends, from the mode the model
holds::

    [131]                 Safe, only in Passive while a Clean/Spot/Max/Seek Dock cycle may
                          be driving (drive 0 is not accepted in Passive; Safe ends the cycle:
                          Start does not, docs/protocol.md), one the session wrote or one the
                          robot started by itself (``CommandWriter.robot_cycle``: a button,
                          a schedule); not after a Seek Dock that docked (the last frame shows
                          the home base: the cycle ended there, and Safe on a powered dock
                          would stop the charge only to fall back to Passive), nor a cycle
                          of the robot's own on its home base
    [137][0][0][0][0]     drive 0            } only while the model is in Safe or Full: in
    [138][0]              motors off         } Passive and Off the robot refuses actuators
    [150][0]              pause the stream
    [128]  or  [173]      Start (back to Passive) or, with end_in="stop" where the profile
                          has it, Stop (Off)

A stop that cannot be delivered is reported with :func:`describe_activity` of the last wheel
command written ("last seen in Safe at 200 mm/s; ..."). :class:`SafeStop` is the session's
part that does it: it writes the sequence through the session's
:class:`~roomba_bt.robot.writer.CommandWriter` (whole: SIGINT/SIGTERM held meanwhile) and
keeps whether the stop reached the robot.
"""

from __future__ import annotations

import contextlib
import logging
import signal
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import STRAIGHT_RADII, Command, turns_wheels
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.odometry import encoder_delta
from roomba_bt.oi.opcodes import Effect, longest_data_bytes
from roomba_bt.oi.packets import packet_ids
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import StreamParser, stream_period
from roomba_bt.robot.baud_hunt import asks_after, found_words, hunt, put_back
from roomba_bt.robot.errors import PortLost, RobotError, WaitCutShort
from roomba_bt.robot.hazards import sets_going
from roomba_bt.robot.link import LINK_ERRORS, LinkStatus, StreamLink
from roomba_bt.robot.modes import OffsetDetector
from roomba_bt.robot.safety import ENDING_SIGNALS
from roomba_bt.robot.wake import KeepAwake
from roomba_bt.robot.wall_bound import WallBound, bounded
from roomba_bt.robot.writer import CommandWriter, OwnHalt
from roomba_bt.transport.link_kind import link_of

log = logging.getLogger(__name__)

EndMode = Literal["passive", "stop"]

#: Seconds the safe stop listens, once written while a stream ran, for frames that should no
#: longer come, once the frames already on their way have come (:meth:`SafeStop.in_flight`):
#: ten stream periods (15 ms each). A quiet this long after the last frame shows the stop
#: heard at once.
STOP_LISTEN = 0.15
#: Frames a robot that heard Pause Stream may still be seen to send after the frames on their
#: way (:meth:`SafeStop.in_flight`) have come: jitter (a robot that did not hear it sends ten);
#: also the stream periods that allowance has beside the link's round trip.
PAUSE_SLACK = 3
#: How many of the link's measured round trips the frames sent before the robot heard a
#: command may still take to come: the round trip itself, and as much again for its jitter
#: (Wi-Fi and Bluetooth bridges: 50-300 ms, and uneven).
ROUND_TRIPS_IN_FLIGHT = 2
#: Seconds below which a wait is taken as over: a virtual clock that adds each read's timeout
#: to a large time adds nothing for a wait under its last bit (the listen after the stop
#: looped for ever on ``bench.bench_robot``'s transport).
CLOCK_ROUNDING = 1e-6
#: Seconds of wall time after which the safe stop gives up waiting for the robot (the stop
#: is then unconfirmed, and says why): a last resort, for a wait whose end on the link's
#: clock never comes. Its longest own wait is some 4 s: two listens after the stop of
#: :data:`STOP_LISTEN` past the frames in flight (a round trip of :data:`ROUND_TRIP_CAP`,
#: twice), and a followed rate's quiet and Query List (``silence._stop_heard``). A replay
#: whose clock stood still read for ever there, and ignored Ctrl-C and SIGTERM, which wait
#: for the stop.
STOP_WALL_S = 10.0
#: The most a measured round trip counts for, in seconds (:func:`link_round_trip`):
#: the allowance it sets is also the time the mode model waits for a mode command to show,
#: during which a robot that really fell to Passive could still be sent actuator bytes. The
#: slowest link the tests run on has 0.5 s of latency (its reply a slot later), past any
#: bridge that works (Wi-Fi and Bluetooth: 50-300 ms); a slower link is logged, not followed.
ROUND_TRIP_CAP = 0.6
#: How many times a stop the stream contradicts is written: the first, and twice more, each
#: after :data:`STOP_RESYNC_ZEROS` (a robot that streams on after the stop may have taken it
#: as the data of a long command a lost byte made; a second stop alone went the same way).
STOP_ATTEMPTS = 3
#: Zeros written before a stop written again: as many as the longest command any byte can
#: start waits for (:func:`~roomba_bt.oi.opcodes.longest_data_bytes`, a Song (140) of 255
#: notes: 512), so whatever command a lost byte left the robot's parser in is over before
#: the stop's first byte. The run's own resends (:data:`~roomba_bt.robot.writer.RESYNC_ZEROS`,
#: 35) cover only the commands a run sends.
STOP_RESYNC_ZEROS = bytes(longest_data_bytes())
#: What a stop heard only when written again after :data:`STOP_RESYNC_ZEROS` says (the
#: port, the zeros, how many times again if more than once)
STOP_TAKEN_AGAIN = (
    "%s: the stop was not taken at first: a lost byte may have started a long command; sent "
    "%d zeros and the stop again%s: heard"
)
#: What a stop not confirmed says of a robot whose reset banner was read: stopped all the same
RESET_STOPPED = (
    "the robot reset (its start-up banner was read): its OI is Off, where its wheels and "
    "motors are stopped"
)
#: What a stop says of a robot whose reset banner was read and that answered in Passive to
#: the Start sent again after it (``baud_hunt.hunt``)
RESET_RESTARTED = (
    "the robot reset (its start-up banner was read; a Reset (7) made of lost bytes, most "
    "likely): sent Start again after its banner, it answered in Passive"
)
#: What a stop that ends in Off (``end_in="stop"``) says when it was not confirmed and the
#: robot, asked after, answered in Passive: the question needs Start (Off answers nothing),
#: so Stop (173) is written again once it has answered (:func:`stop_again`)
STOP_WRITTEN_AGAIN = (
    "the Stop (173) was not confirmed at first: asked after, which needs Start (the OI answers "
    "nothing in Off), the robot answered in Passive; Stop written again"
)
#: What it says instead where Stop could not be written again (the port failed): the robot is
#: left in Passive, where the Start of the question put it
STOP_LEFT_PASSIVE = (
    "the Stop (173) was not confirmed at first: asked after, which needs Start (the OI answers "
    "nothing in Off), the robot answered in Passive; Stop could not be written again ({error}): "
    "left in Passive"
)
#: Why a quiet after a stop with bytes in it that make no frame (how many) does not show it
#: heard: a robot a Baud (129) made of lost bytes moved to another rate streams on there
GARBAGE_AFTER = (
    "no valid frame came after it, but %d bytes that make none (the robot talking at another "
    "rate: a Baud (129) made of lost bytes, most likely)"
)
#: Reads at most of what waits unread in the port before a stop (each read takes all there
#: is: one is the rule; the bound is for a line that never runs dry)
BACKLOG_READS = 16
#: The share of the time a program did not read by which the frames that waited may fall
#: short of filling it and still show a stream that ran on: the robot's 15 ms slots against
#: the host's clock, and its first frame's way after the stream request (over TCP, Nagle's
#: 40 ms). A robot silent for longer before the stop is said silent.
BACKLOG_SLACK = 0.05
#: Stream periods the robot may have been silent when a stop is written for the quiet after
#: it to show the stop heard: a robot that heard Pause Stream had sent its last frame under a
#: period before it (a later one would come while the stop is listened after); the rest is
#: the robot's and the port's jitter. Longer, and the quiet began before the stop and shows
#: nothing of it (a cable pulled a moment before Ctrl-C, the watchdog not yet tripped).
QUIET_BEFORE_PERIODS = 3

#: Seconds a stop waits for a port that failed to come back at the same device path (a
#: loose connector, a USB adapter that reset), to deliver the stop alone, unless told
#: (:attr:`PortReturn.within`: a run's ``--grace``).
REOPEN_WITHIN_S = 2.0
#: What to do about a robot the stop could not reach over a port that is gone; ``reach``: the
#: link's way back to it (:attr:`~roomba_bt.transport.link_kind.LinkWords.reach`: doctor on
#: a device or a bridge; for a pty, that its path will not come back)
PORT_GONE_ADVICE = (
    "the robot may still be moving: pick it up or press its Clean or power button; {reach}"
)
#: What is said of a robot the stop could not reach, last seen stopped in Passive in frames
#: it sent after it heard every command written (a run the operator paused: the pause's own
#: stop confirmed), nothing sent since: it stays so unless something else moves it
SEEN_STOPPED = (
    "last seen stopped in Passive, in the frames it sent after every command written (it stays "
    "stopped unless something else moves it: its buttons, a schedule)"
)
#: The same of a robot whose stream carries no OI mode (packet 35: a program's own packet
#: list), its frames sent after every command written showing the wheel speeds it was last
#: asked for at 0 (packet 39, Drive's; 41/42, Drive Direct's), the run having written Passive
SEEN_STOPPED_UNMODED = (
    "last seen stopped, its requested wheel speeds at 0 in the frames it sent after every "
    "command written (the stream carries no OI mode, packet 35: Passive was written, not "
    "seen; it stays stopped unless something else moves it: its buttons, a schedule)"
)

#: Requested wheel velocities (left, right) and the encoders (left, right): what a stop the
#: robot streams on after says of its wheels.
_LEFT_VELOCITY, _RIGHT_VELOCITY = packet_ids("requested_left_velocity", "requested_right_velocity")
#: the requested velocity of a Drive (39): with 41/42, what a frame shows of the wheel speeds
#: the robot was last asked for (:func:`seen_stopped`)
(_VELOCITY,) = packet_ids("requested_velocity")
_ENCODERS = packet_ids("left_encoder_counts", "right_encoder_counts")

#: What a stop may meet and must survive.
_RECOVERABLE: tuple[type[Exception], ...] = (RobotError, *LINK_ERRORS)


def stop_sequence(
    mode: OIMode, *, builtin_may_run: bool, end_in: EndMode, profile: RobotProfile
) -> list[Command]:
    """What the safe stop sends from ``mode`` (see the module docstring)."""
    if mode is OIMode.OFF:
        return []
    commands: list[Command] = []
    if mode is OIMode.PASSIVE and builtin_may_run:
        # Clean, Spot, Max or Seek Dock drive the robot in Passive, where drive 0 is not
        # accepted; Safe (131) ends the cycle and makes drive 0 and motors off possible.
        commands.append(oi.safe())
        mode = OIMode.SAFE
    if mode in DRIVING_MODES:
        commands += [oi.halt(), oi.motors_off()]
    commands.append(oi.pause_stream())
    use_stop = end_in == "stop" and profile.has_command("stop")
    commands.append(oi.stop() if use_stop else oi.start())
    return commands


def describe_activity(command: Command | None, stopped_by: str = "") -> str:
    """What the last wheel command written had the robot doing: ``at 200 mm/s``,
    ``stopped``, ``in its Clean cycle``. With no command since the robot's own fall to
    Passive stopped the wheels (``stopped_by``, its cause:
    :attr:`~roomba_bt.robot.writer.CommandWriter.wheels_stopped_by`), ``with its wheels
    stopped by its own fall to Passive (charger)``: an overnight patrol asleep on its
    charger after 488 m of driving was said to have its wheels "never commanded"."""
    if command is None:
        if stopped_by:
            return f"with its wheels stopped by its own fall to Passive ({stopped_by})"
        return "with its wheels never commanded"
    spec = command.spec
    if spec.effect is Effect.BUILTIN_CYCLE:
        return f"in its {spec.title} cycle"
    if not any(command.args):
        return "stopped"
    if spec.name == "drive":
        velocity, radius = command.args
        if radius in (1, -1):  # the spec's turn in place
            return f"spinning {'left' if radius == 1 else 'right'} at {velocity} mm/s"
        turning = "" if radius in STRAIGHT_RADII else f", radius {radius} mm"
        return f"at {velocity} mm/s{turning}"
    values = ", ".join(
        f"{arg.name} {value} {arg.unit}".rstrip()
        for arg, value in zip(spec.args, command.args, strict=True)
    )
    return f"after {spec.name} ({values})"


#: :func:`wheels_seen`'s word for encoders that did not move
WHEELS_STILL = ", the wheels still"


def stopped_in_passive(frames: list[SensorFrame], detector: OffsetDetector) -> bool:
    """Whether the frames that came on after a stop that ends in Passive show it taken all
    the same: packet 35 reading Passive (``detector``'s reading) and the wheels still (their
    requested velocities 0, or the encoders unmoved over the frames). A lost byte left the
    last command short, the stop's Pause Stream went to finish it and its Start was heard
    (a third of the dock runs at 1 % lost): the robot is where the stop puts it, and zeros
    and the stop again would only say a long command where there is none."""
    last = frames[-1]
    if OI_MODE_PACKET not in last or detector.interpret(last[OI_MODE_PACKET]) is not OIMode.PASSIVE:
        return False
    if _LEFT_VELOCITY in last and _RIGHT_VELOCITY in last:
        return last[_LEFT_VELOCITY] == last[_RIGHT_VELOCITY] == 0
    return wheels_seen(frames) == WHEELS_STILL


def streamed_on(
    late: list[SensorFrame], in_flight: float, detector: OffsetDetector
) -> tuple[str, OIMode | None]:
    """What the frames that came after a stop the robot did not hear showed: how many, its
    mode (packet 35, read by ``detector``; also returned, for the stop written again, or
    None) and its wheels."""
    said = (
        f"{len(late)} sensor frames came in the {STOP_LISTEN:.2f} s after Pause Stream "
        f"(past the {in_flight:.2f} s the frames already on their way may take)"
    )
    last = late[-1]
    mode = detector.interpret(last[OI_MODE_PACKET]) if OI_MODE_PACKET in last else None
    if mode is not None:
        said += f", packet 35 still reading {mode.label}"
    return said + wheels_seen(late), mode


def wheels_seen(frames: list[SensorFrame]) -> str:
    """What the wheels did over ``frames`` (two or more) as far as they show it: the
    requested velocities (packets 42, 41) if carried, else the encoders' counts (43, 44)
    from the first to the last; "" if they carry neither."""
    first, last = frames[0], frames[-1]
    if _LEFT_VELOCITY in last and _RIGHT_VELOCITY in last:
        left, right = last[_LEFT_VELOCITY], last[_RIGHT_VELOCITY]
        return f", the wheels at {left}/{right} mm/s (left/right)"
    if not all(pid in frame for pid in _ENCODERS for frame in (first, last)):
        return ""
    left, right = (encoder_delta(first[pid], last[pid]) for pid in _ENCODERS)
    if left == right == 0:
        return WHEELS_STILL
    return f", the wheels turning ({left:+d}/{right:+d} encoder counts, left/right)"


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold the signals that end a run (:data:`~roomba_bt.robot.safety.ENDING_SIGNALS`)
    while a stop sequence is written, so it leaves whole."""
    blockable = set(ENDING_SIGNALS)
    try:
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blockable)
    except (AttributeError, OSError, ValueError):  # not POSIX: nothing to hold
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def link_round_trip(seconds: Sequence[float], port: str) -> float:
    """The link's round trip from the start-up's Query Lists, answered ``seconds`` after each
    was written (0 for none). A link with latency (a Wi-Fi or Bluetooth bridge,
    ``socket://``) still brings frames the robot sent before it heard the stop that long
    after it: they are not the robot streaming on (:meth:`SafeStop.in_flight`). The quickest
    reply is the round trip (a floor: a slower one is a host that was busy, and jitter is
    :data:`ROUND_TRIPS_IN_FLIGHT`'s), capped at :data:`ROUND_TRIP_CAP`. The longest ever kept
    let one slow reply on a loaded host widen the stop's listening and the mode model's
    settle for the whole session."""
    if not seconds:
        return 0.0
    quickest = min(seconds)
    if quickest > ROUND_TRIP_CAP:
        log.warning(
            "%s: the robot answered a Query List after %.2f s at the quickest; the frames "
            "on their way are allowed for a round trip of %.2f s at most",
            port, quickest, ROUND_TRIP_CAP,
        )  # fmt: skip
    return min(quickest, ROUND_TRIP_CAP)


@dataclass(frozen=True)
class Backlog:
    """Frames that waited unread in the port when a stop was about to be written
    (:func:`read_backlog`): ``sent_until``, when the robot sent the last of them (link
    clock); ``frames``, how many; ``waited``, the seconds since the last frame read before."""

    sent_until: float
    frames: int
    waited: float


def read_backlog(link: StreamLink, baud: int) -> Backlog | None:
    """Read the frames the robot sent that the program had not read (a script asleep in
    ``time.sleep`` while the stream ran, then Ctrl-C), as a poll would, before the stop
    is written: nothing is waited for. Left in the port, the listening after the stop
    took them for frames sent after it, and the time since the last frame *read* for
    the robot's silence before it ("no valid frame for 0.15 s"): a stop the robot heard
    was called unconfirmed. When the robot sent the last of them (link clock): now if
    they fill the time since the last frame read (or the stream's start: a script that
    never polled), a stream that ran on; else as many stream periods after it as there
    were frames (a robot that fell silent meanwhile);
    None if nothing waited. Only on the wall clock, as the listening after the stop, and in
    a replay (a transport's ``recorded_reads``: ``ReplayTransport``'s), where it reads what
    the recorded run read here, at its recorded times (nothing, for a run on a virtual
    clock): before, it read nothing, and a frame the live run had read there was its
    stop's difference. A part of :meth:`SafeStop.stop`, out of the class because it reads
    only the link."""
    transport = link.transport
    recorded = getattr(transport, "recorded_reads", None)
    if not (
        link.streaming
        and link.status is LinkStatus.STREAMING
        and transport.is_open
        and (recorded is not None or getattr(transport, "wall_clock", True))
    ):
        return None
    with recorded() if recorded is not None else contextlib.nullcontext():
        # the last frame read, or the stream's start if none was read since
        last_read, index_then = link.silent_since, link.index
        take_unread(link, 0.0)
        waited = link.index - index_then
        if not waited:
            return None
        now = transport.now()
        period = stream_period(link.stream_ids, baud)
        sent_until = last_read + waited * period
        quiet = now - QUIET_BEFORE_PERIODS * period - BACKLOG_SLACK * (now - last_read)
        if sent_until >= quiet:
            sent_until = now
        elif take_unread(link, QUIET_BEFORE_PERIODS * period):
            # short of it: a robot silent since, or a stream that lagged (a loaded host's
            # robot double); a frame within a few periods more says which
            sent_until = transport.now()
        return Backlog(sent_until, waited, now - last_read)


def take_unread(link: StreamLink, wait: float) -> bool:
    """What the port holds (and, ``wait`` > 0, the first frame within ``wait`` s) fed to
    the link as a poll would; whether a frame came. A port that fails is left to the
    stop to say."""
    clock = link.transport.now
    index, deadline = link.index, clock() + wait
    with contextlib.suppress(*_RECOVERABLE):
        for _ in range(BACKLOG_READS):
            left = deadline - clock()
            data = link.read(left if left > 0.0 else 0.0)
            if data:
                link.ingest(data, clock())
                if wait and link.index > index:
                    break  # the frame waited for
            elif left <= 0.0:
                break  # nothing more there, and no more to wait
    return link.index > index


def confirmed_by(confirm: Callable[[], bool] | None) -> bool:
    """Whether ``confirm`` says the robot heard the stop (False if there is none, or asking
    failed)."""
    if confirm is None:
        return False
    try:
        return confirm()
    except _RECOVERABLE:
        return False


class PortReturn:
    """The wait, at a stop, for a port that failed to come back at the same device path (a
    loose connector, a USB adapter that reset) or URL (a Wi-Fi bridge that rebooted: a new
    connection reaches the same robot), to deliver the stop alone: the mission is not
    carried on (the robot may have moved meanwhile). ``within``: how long (a run's
    ``--grace``); ``heard``: the connection's question after the stop written through it
    (the stream quiet, a Query List answered); ``said``: what the wait found ("" before one);
    ``silent``: the connection did not fail but carried nothing for the grace, and was taken
    for dead (``silence.dead_connection``): said so.
    """

    def __init__(self) -> None:
        self.within = REOPEN_WITHIN_S
        self.heard: Callable[[], bool] | None = None
        self.said = ""
        self.silent = False

    def wait(self, link: StreamLink) -> bool | None:
        """True if the port came back (the link open again, no stream known to run), False
        if it did not or was already waited for in this ending, None where the transport
        cannot reopen (a simulator, a replay, ``loop://``, a pty's own path) or the far
        end turned this run away (its robot was never this run's to stop)."""
        reopen: Callable[[float], float | None] | None = getattr(link.transport, "reopen", None)
        if reopen is None or not getattr(link.transport, "reopens", False) or link.turned_away:
            return None
        if self.said or self.within <= 0:  # waited for already (``close()``'s stop)
            return False
        took = reopen(self.within)
        port = link_of(link.name).reopened
        if self.silent:
            self.said = f"{port}, silent, was closed; " + (
                f"no new one came within {self.within:g} s"
                if took is None
                else f"a new one came after {took:.2f} s"
            )
        elif took is None:
            self.said = f"{port} did not come back within {self.within:g} s"
            elsewhere = getattr(link.transport, "other_device", None)
            if elsewhere:  # its path leads to another device: nothing was written into it
                self.said += f" ({link.name} leads to another device: {elsewhere}; not opened)"
        else:
            self.said = f"{port} came back after {took:.2f} s"
        if took is None:
            return False
        link.status = LinkStatus.OPEN
        link.streaming = False
        return True

    def heard_stop(self, port: str) -> bool:
        """Whether the robot heard the stop written through the port that came back: said
        either way (logged when it did: the run still ends as a lost port)."""
        if not confirmed_by(self.heard):
            self.said += "; the stop was written through it, and no robot answered after it"
            return False
        self.said += ": the robot heard the stop written through it"
        log.warning("%s: %s (the mission is not carried on)", port, self.said)
        return True


def listened_after(link: StreamLink) -> bool:
    """Whether the stop is checked against the stream after it: on the wall clock, and on
    the simulator's virtual one where its line loses bytes on the way to the robot
    (``loses_bytes``: a lost byte can make a long command that takes the stop as its data,
    as on a cable; the run's end waits the listen's frames). A perfect simulated line cannot
    swallow the stop: its runs end where they did (the golden recordings). A replay
    listens where its record says the recorded run did (``ReplayTransport.loses_bytes``),
    and decides on the recorded bytes as that run did."""
    transport = link.transport
    on_a_line = getattr(transport, "wall_clock", True) or getattr(transport, "loses_bytes", False)
    return bool(on_a_line) and link.streaming and link.status is LinkStatus.STREAMING


class SafeStop:
    """The endings of one session: the stop sequence written whole from the mode the model
    holds, whether it reached the robot, and the port closed once.

    ``safe_stopped``: True once a stop is known sent, False when one failed (``stop_report``
    then says why, with what the robot was last seen doing), None before any ending.
    ``unheard``: why a stop written now could not be known to arrive (the robot no longer
    answers, or the line is garbled), or None. ``confirm``: asked after the stop is written
    while ``unheard`` is set, whether the robot answers after all (then the stop is known
    delivered): the port followed the robot to another rate on its frames alone, and only an
    answer there shows it hears at that rate. ``wake``: the session's keep-awake, released
    at :meth:`close` (here, not on the connection: a connection dropped without ``close()``
    is ended from this part alone, :func:`~roomba_bt.robot.connection.stop_when_dropped`).
    """

    def __init__(self, writer: CommandWriter, end_in: EndMode) -> None:
        self.writer = writer
        self.end_in: EndMode = end_in
        self.wake: KeepAwake | None = None
        self.safe_stopped: bool | None = None
        self.stop_report: str | None = None
        self.stop_advice = ""  # the report's what to do, or "" (:func:`gone_advice`)
        self.unheard: str | None = None
        self.confirm: Callable[[], bool] | None = None
        self.closed = False
        #: what is said of a stop that did not arrive, taken before it was written
        #: (:func:`before_stop`: the mode, the wheels, what the frames showed of them)
        self._before: tuple[OIMode, Command | None, str, str, str] = (
            writer.modes.mode, writer.last_wheels, writer.wheels_stopped_by, "",
            describe_activity(writer.last_wheels, writer.wheels_stopped_by),
        )  # fmt: skip
        #: the mode packet 35 read in frames that came after a stop (it was not heard)
        self._seen: OIMode | None = None
        #: when a valid frame of the running stream last came (link clock), as the stop is
        #: written and listened after; None before its first
        self._heard_at: float | None = None
        #: why the quiet after a stop shows nothing (:meth:`_quiet_unproven`), or None
        self._unproven: str | None = None
        #: bytes after the stop's last valid frame (or the stop) that make none: no quiet
        self._garbage_after = 0
        #: the link's count of valid frames when a stop was last said not delivered
        self._unseen_from = -1
        #: whether the last stop's sequence was written whole (:attr:`safe_stopped` says
        #: whether it is known to have arrived)
        self.written = False
        #: frames that waited unread in the port as the stop was written, and for how long
        #: the program had not read it (:func:`read_backlog`), or None
        self._unread: tuple[int, float] | None = None
        #: the link's round trip (the quickest of the start-up's Query List replies, at most
        #: :data:`ROUND_TRIP_CAP` seconds; :func:`link_round_trip`), 0 before any
        self.round_trip = 0.0
        #: the wait for a port that failed to come back, for the stop alone
        self.port_return = PortReturn()
        #: a reply the start-up agreed on, or any query's, came (:attr:`robot_heard`)
        self.answered = False
        #: the last stop not known delivered met a robot this session set nothing going
        #: for: none answered, or one seen only in Passive, its wheels never commanded
        self.nothing_set_going = False
        #: why the robot is taken for asleep (:func:`fell_asleep`), while :attr:`unheard`
        self.asleep_said: str | None = None
        #: the last stop not known delivered met a robot its frames had shown stopped after
        #: every command written (:func:`seen_stopped`), and of those one that then slept
        self.seen_still = self.asleep_stopped = False
        #: the stop being said undelivered found the port gone (:meth:`_port_gone`)
        self._gone = False
        #: the stop answered only at another rate (``baud_hunt.found_words``), or ""; the
        #: reset banner read before a stop not confirmed (Off: stopped; :func:`asked_after`)
        self.found_at, self.reset_seen = "", False
        #: how many times the last stop was written again, after zeros, before the robot
        #: took it (:data:`STOP_TAKEN_AGAIN`); 0: at once, or never
        self.taken_again = 0

    def begin(self) -> None:
        """A session starts (again): nothing has ended."""
        self.closed = False
        self.safe_stopped = None
        self.unheard = None
        self.confirm = None
        self.port_return.said = ""
        self.port_return.silent = False

    def in_flight(self, period: float) -> float:
        """Seconds after a command is written that frames the robot sent before it heard it
        may still come: :data:`ROUND_TRIPS_IN_FLIGHT` measured round trips, and
        :data:`PAUSE_SLACK` stream ``period`` s for the frame in flight and the port's
        buffers (a link never measured: those alone, the 45 ms of old)."""
        return ROUND_TRIPS_IN_FLIGHT * self.round_trip + PAUSE_SLACK * period

    def sequence(self) -> list[Command]:
        """What :meth:`stop` sends from the current mode (:func:`stop_sequence`)."""
        writer = self.writer
        return stop_sequence(
            writer.modes.mode, builtin_may_run=writer.cycle_may_drive, end_in=self.end_in,
            profile=writer.profile,
        )  # fmt: skip

    def stop(self) -> bool:
        """Stop the robot and leave it in Passive (or Off with ``end_in="stop"``); never
        raises for a dead link (False, and the stop report logged). A stop written while a
        stream ran is checked against it (:meth:`_contradicted`) and written once more if the
        robot streams on. Its waits for the robot end on the link's clock, and, as a last
        resort, after :data:`STOP_WALL_S` of wall time (the stop then unconfirmed, said so):
        the signals that would end a stuck wait are held or deferred while it runs."""
        with bounded(self.writer.link, STOP_WALL_S, "the safe stop's wait for the robot") as bound:
            return self._stop(bound)

    def _stop(self, bound: WallBound) -> bool:
        """:meth:`stop`, its waits bounded by ``bound``."""
        writer = self.writer
        link = writer.link
        if writer.modes.mode is OIMode.OFF:  # never started (or ended in Off by Stop):
            self.safe_stopped = True  # nothing written, nothing to stop; not "unconfirmed"
            return True
        self.written = False
        self.taken_again, self.found_at, self.reset_seen = 0, "", False
        backlog = read_backlog(link, writer.baud)
        self._unread = None if backlog is None else (backlog.frames, backlog.waited)
        # what the robot was last seen or told to do, before the stop moves the model on;
        # once more after a stop not delivered (close()'s), nothing heard since: what was
        # seen before that one (it moved the model on to Passive without the robot)
        if self.safe_stopped is not False or link.index != self._unseen_from:
            self._before = before_stop(self)
            self._seen = None
        self._unproven = None
        # before the stream's first frame the wait is the stream request's way to the robot
        # and a slot (over TCP, 40 ms and more of Nagle's delay): no silence, the watchdog's
        streamed = link.frame is not None and link.arrival >= link.silent_since
        self._heard_at = link.arrival if streamed else None
        if backlog is not None:  # frames that waited unread: when the robot sent them
            self._heard_at = backlog.sent_until
        came_back = None
        if link.status is LinkStatus.LOST or not link.transport.is_open:
            came_back = self.port_return.wait(link)  # for the stop alone
        if came_back is False or not link.transport.is_open:
            return self._undelivered(self._port_gone())
        unconfirmed = self._unconfirmed_before(link)
        failed = self._write_heard(listened_after(link))
        if failed is None and came_back and not self.port_return.heard_stop(link.name):
            failed = self._port_gone()
        if failed is not None:
            return self._undelivered(failed)
        if unconfirmed is not None and unconfirmed is self.unheard and confirmed_by(self.confirm):
            self.unheard = unconfirmed = None  # it answered after the stop: it heard it
        elif unconfirmed is None:  # a quiet after the stop that began before it
            unconfirmed = self._unproven
        if unconfirmed is None and not self.robot_heard:  # a robot that may hear and not
            unconfirmed = "no robot answered"  # answer (its TX line cut)
        if bound.cut is not None:  # a wait given up: nothing it would have shown is known
            unconfirmed = bound.cut
        if unconfirmed is not None and bound.cut is None:
            unconfirmed = asked_after(self, unconfirmed)
        if unconfirmed is not None:
            return self._undelivered(f"the stop was written but is unconfirmed: {unconfirmed}")
        link.streaming = False
        link.status = LinkStatus.STOPPED
        self.safe_stopped = True
        return True

    def _unconfirmed_before(self, link: StreamLink) -> str | None:
        """Why a stop written now could not be known to arrive, known before it is written:
        the port failed, the silence's diagnosis (the line, the robot; unless :attr:`confirm`
        says it heard the stop), the watchdog tripped with nothing heard since (no diagnosis
        yet: it pauses the stream and asks); None if none."""
        if link.status is LinkStatus.LOST:
            return "the port had failed before it"
        if self.unheard is not None:
            return self.unheard
        if link.status is LinkStatus.STALLED and link.streaming:
            silent = link.transport.now() - link.silent_since
            return f"the robot had sent no valid frame for {silent:.2f} s before it"
        return None

    def _write_heard(self, checked: bool) -> str | None:
        """Write the stop; ``checked``: listen after it (:meth:`_contradicted`), and write it
        again after :data:`STOP_RESYNC_ZEROS` while the robot streams on, up to
        :data:`STOP_ATTEMPTS` in all (said: :data:`STOP_TAKEN_AGAIN`). Why it did not reach the
        robot, or None. A stop the robot streamed on after leaves the model where it was
        (as the robot is, as far as it was seen), so that a later stop (``close()``) sends
        it whole again."""
        writer = self.writer
        saved = (
            writer.modes.snapshot(), writer.last_wheels, writer.builtin_may_run,
            writer.robot_cycle,
        )  # fmt: skip
        contradiction = None
        for attempt in range(STOP_ATTEMPTS if checked else 1):
            if attempt:  # the robot did not hear it: the model back where it was, again
                self._restore(saved)
            written_at = writer.link.transport.now()
            failed = self._write(STOP_RESYNC_ZEROS if attempt else b"")
            if failed is not None:
                return failed
            contradiction = self._contradicted(written_at) if checked else None
            if contradiction is None:
                self._unproven = self._quiet_unproven(written_at) if checked else None
                if attempt:  # said, for the summary's reader and the log
                    self.taken_again = attempt
                    log.warning(STOP_TAKEN_AGAIN, writer.link.name, len(STOP_RESYNC_ZEROS),
                                f" ({attempt} times)" if attempt > 1 else "")  # fmt: skip
                return None
            if not attempt:
                log.warning(
                    "%s: the stop was not taken at first (%s): a lost byte may have started a "
                    "long command; sending %d zeros and the stop again", writer.link.name,
                    contradiction, len(STOP_RESYNC_ZEROS),
                )  # fmt: skip
        self._restore(saved)
        return f"the stop was written {STOP_ATTEMPTS} times but not received: {contradiction}"

    def _restore(self, saved: tuple[tuple[Any, ...], Command | None, bool, str | None]) -> None:
        """The model, the wheels and the stream as they were before a stop not heard, the
        model in the mode packet 35 read after it if that is another (a ``mode: passive``
        the robot never heard either: the stop is sent again from Safe, drive 0 in it)."""
        writer = self.writer
        now = writer.link.transport.now()
        writer.modes.restore(saved[0])
        writer.last_wheels, writer.builtin_may_run, writer.robot_cycle = saved[1:]
        if self._seen is not None and self._seen is not writer.modes.mode:
            writer.modes.force(self._seen, now)
        writer.link.pause_resume(True, now)

    def _write(self, prefix: bytes = b"") -> str | None:
        """Write the stop sequence whole, after ``prefix`` (zeros, in the same write), the
        port at the robot's rate first, whatever a listen at another rate cut short by a
        signal left it at (``at_robot_rate``: before, every byte of the stop went out at
        19200 to a robot at 115200, which drove on); why it could not be, or None."""
        try:
            with signals_deferred():
                self.writer.at_robot_rate()
                self.writer.send_many(self.sequence(), prefix=prefix)
        except PortLost:
            return self._port_gone()
        except _RECOVERABLE as exc:
            return f"the stop was not delivered: {exc}"
        self.written = True
        return None

    def _contradicted(self, written_at: float) -> str | None:
        """What the stream says of a stop written at ``written_at`` (Pause Stream in it).
        The frames the robot sent before it heard it come first, for :meth:`in_flight` s
        (the port's backlog after a tick that blocked, read at once; those on their way over
        a link with latency): they show the robot as it was before the stop, and are neither
        counted nor read for its mode. A quiet of :data:`STOP_LISTEN` s after the last frame
        shows the stop heard, unless bytes that make no frame came in it (kept for
        :meth:`_quiet_unproven`: :data:`GARBAGE_AFTER`; the robot a Baud made of lost bytes
        put on 300 baud was said stopped); frames still coming :data:`STOP_LISTEN` s past the
        frames in flight, more than :data:`PAUSE_SLACK`, show it unheard (the host-to-robot
        wire dead, the robot still in Safe and driving): what they showed, or None."""
        link = self.writer.link
        parser = StreamParser(link.stream_ids, link.profile, mode_plus_one=link.mode_plus_one)
        clock = link.transport.now
        in_flight = self.in_flight(stream_period(link.stream_ids, self.writer.baud))
        stale_until = written_at + in_flight
        deadline = stale_until + STOP_LISTEN
        last = written_at  # when the last frame came (the write, before any)
        late: list[SensorFrame] = []  # the frames sent after the robot should have heard it
        unframed = self._garbage_after = 0  # bytes read since the last valid frame (or the write)
        try:
            while (now := clock()) < deadline and now - last < STOP_LISTEN:
                wait = min(deadline, last + STOP_LISTEN) - now
                if wait < CLOCK_ROUNDING:  # at the bound: a clock that moves by the wait
                    break  # read (a virtual one) may not move at all, and looped for ever
                data = link.read(wait)
                new = parser.feed(data, clock()) if data else []
                unframed = 0 if new else unframed + len(data)
                if new:
                    last = self._heard_at = clock()
                    if last > stale_until:
                        late += new
        except (PortLost, WaitCutShort):  # the stop was written; the quiet it cut short
            return None  # shows nothing (:meth:`_quiet_unproven`, :meth:`stop` say so)
        self._garbage_after = max(0, unframed - parser.pending)
        if clock() - last >= STOP_LISTEN - CLOCK_ROUNDING or len(late) <= PAUSE_SLACK:
            return None  # the stream stopped: it heard Pause Stream
        detector = self.writer.modes.detector
        if self.end_in == "passive" and stopped_in_passive(late, detector):
            return None  # Pause Stream lost (a command's data a lost byte left short), Start not
        said, seen = streamed_on(late, in_flight, detector)
        if seen is not None:  # the mode the stop written again is sent from
            self._seen = seen
        return said

    def _quiet_unproven(self, written_at: float) -> str | None:
        """Why the quiet after a stop written at ``written_at`` does not show it heard: the
        port failed while it was listened after, bytes came after it that make no frame
        (garbage: the robot may talk at another rate, asked after and hunted for by
        :func:`asked_after`), or no valid frame came after it and none for over
        :data:`QUIET_BEFORE_PERIODS` stream periods before it (the robot fell silent first);
        None if the robot was heard after it, or up to it."""
        link = self.writer.link
        if link.status is LinkStatus.LOST:
            return "the port failed while the robot was listened to after it"
        if self._garbage_after:  # not a quiet: the robot may talk at another rate
            return GARBAGE_AFTER % self._garbage_after
        if self._heard_at is None:  # no frame of this stream yet: no silence to measure
            return None
        silent = written_at - self._heard_at
        period = stream_period(link.stream_ids, self.writer.baud)
        if silent <= QUIET_BEFORE_PERIODS * period:  # heard after it (< 0), or up to it
            return None
        unread = ""
        if self._unread is not None:  # read only as the stop was written
            frames, waited = self._unread
            unread = (
                f" (the program had not read the port for {waited:.2f} s: the {frames} "
                "frames it held stop short of that)"
            )
        return (
            f"the robot had sent no valid frame for {silent:.2f} s before it{unread}, and none "
            "after it"
        )

    @property
    def robot_heard(self) -> bool:
        """Whether a robot ever answered: a valid stream frame, or a reply (the start-up's
        agreed mode, a query's). Bytes alone are not one: a pty of random bytes, no robot
        behind it, was said to have left a robot in Passive, its stop sent."""
        return self.answered or self.writer.link.index > 0

    @property
    def last_seen(self) -> OIMode:
        """The mode the robot was last seen in as the last stop was written (or packet 35
        read after it): what is known of a robot the stop did not reach, whose model may
        have moved on with a stop written but unconfirmed."""
        return self._seen if self._seen is not None else self._before[0]

    def activity(self) -> str:
        """What the robot's wheels were last told, in words (:func:`wheels_words`)."""
        return wheels_words(self, unheard_halt(self))

    def _port_gone(self) -> str:
        """Why a stop to a port that failed was not delivered. A far end that closed the
        connection before it sent a byte turned this run away: the robot there is another
        client's, fine, and was never this run's to stop (the second client of a
        simulator's TCP server was told its stop was NOT DELIVERED: the port is gone)."""
        link = self.writer.link
        if link.turned_away:
            return (
                "not sent: the far end closed the connection at once, and this run reached "
                "no robot (another client may hold it; its run is not affected)"
            )
        self._gone = True  # what to do now, said unless nothing was set going
        said = self.port_return.said
        came_back = f" ({said})" if said else ""
        return f"the stop was not delivered: the port is gone{came_back}"

    def _undelivered(self, why: str) -> bool:
        """The stop did not reach the robot: say so, with what the robot was last seen
        doing before the stop was written (the mode and the wheels the model held then, not
        the Passive and drive 0 of the stop itself); False (what :meth:`stop` returns)."""
        writer = self.writer
        mode, wheels, _, still, activity = self._before
        # never told to move and seen in Passive, or never seen at all: nothing was left
        # driving (``sensors``, ``doctor``); the summary or the error says the port's fate
        if self._seen is not None:  # in the frames after the stop: what the robot is in
            mode = self._seen
        heard = self.robot_heard
        idle = wheels is None and (not heard or mode is OIMode.PASSIVE)
        self.nothing_set_going = idle
        still = still if self._seen is None else ""  # no frame came after the stop to say more
        asleep = self.unheard is not None and self.unheard is self.asleep_said
        self.seen_still = heard and bool(still)
        self.asleep_stopped = self.seen_still and asleep
        level = logging.DEBUG if idle else logging.WARNING if still else logging.ERROR
        if not heard:  # nothing was ever seen of it
            report = why
        else:
            report = last_seen_words(mode, activity, self._seen is not None, still)
            report += f"; {why}"
        gone, self._gone = self._gone, False
        self.stop_advice = gone_advice(self.writer.link.name, gone, idle, still)
        if self.stop_advice:
            report += f": {self.stop_advice}"
        if report != self.stop_report:  # close() tries once more: said once, not twice
            log.log(level, "%s: %s", self.writer.link.name, report)
        self.stop_report = report
        self.safe_stopped = False
        self._unseen_from = writer.link.index
        return False

    def close(self) -> bool:
        """Stop (once), release keep-awake, close the port. True if the robot was stopped
        (or never started); idempotent."""
        if self.closed:
            return bool(self.safe_stopped)
        self.closed = True
        stopped = True
        if self.safe_stopped is True:
            pass  # already stopped: a second stop sequence would only add bytes
        elif self.writer.modes.mode is not OIMode.OFF:  # stop() reports a port already gone
            stopped = self.stop()
        if self.wake is not None:
            with contextlib.suppress(*LINK_ERRORS):
                self.wake.release()
        link = self.writer.link
        link.transport.close()
        link.status = LinkStatus.CLOSED
        if self.safe_stopped is None:
            self.safe_stopped = stopped
        return stopped


def gone_advice(port: str, gone: bool, idle: bool, still: str) -> str:
    """What to do about the robot a stop not delivered left on ``port``, that port ``gone``
    (the report's tail; "" for any other stop, or a robot the run set nothing going): the
    port's way back, with :data:`PORT_GONE_ADVICE` first unless its frames showed it
    ``still``. Kept apart (:attr:`SafeStop.stop_advice`) for the monitor's banner, which
    says it on a line of its own after where the robot was left. A part of
    :meth:`SafeStop._undelivered`."""
    if not gone or idle:
        return ""
    reach = link_of(port).reach
    return reach if still else PORT_GONE_ADVICE.format(reach=reach)


def fell_asleep(ending: SafeStop, why: str) -> None:
    """The robot is taken for asleep (5 minutes in Passive with nothing from us, its stream
    stopped: ``silence.asleep_by_idle``), ``why`` saying so: a stop written now is unheard
    (:attr:`SafeStop.unheard`), and one seen stopped before it slept is said asleep and
    stopped (:attr:`SafeStop.asleep_stopped`: a robot asleep does not move; the summary's
    "NOT DELIVERED" in capitals is for one that may). Out of the class for its size."""
    ending.unheard = ending.asleep_said = why


def seen_stopped(ending: SafeStop) -> str:
    """What the robot's last frame shows of it stopped with nothing written since that
    could set it going ("" if nothing): the frame was sent after the robot heard the last
    command (past :meth:`SafeStop.in_flight`), no built-in cycle may drive, the last Motors
    command written runs no brush nor the vacuum, and either
    packet 35 reads Passive and its wheels are still (the requested velocities at 0 where
    streamed, else the last wheel command a drive 0, heard before it went to Passive):
    :data:`SEEN_STOPPED`; or, on a stream without packet 35, the run wrote Passive after a
    drive 0 and the frame shows the requested wheel speeds it carries (39; 41/42) at 0:
    :data:`SEEN_STOPPED_UNMODED`. A run held paused (the pause's safe stop: drive 0, motors
    off, Start, confirmed by seconds of frames) whose cable was then pulled was said "may
    still be moving: pick it up". A robot never told to move is said so
    (:meth:`SafeStop._undelivered`'s idle). Out of the class for its size."""
    writer = ending.writer
    link = writer.link
    frame, wheels, motors = link.frame, writer.last_wheels, writer.last_motors
    if frame is None or wheels is None or writer.cycle_may_drive:
        return ""
    if motors is not None and sets_going(motors):  # a brush or the vacuum left running
        return ""
    if link.arrival <= writer.last_command_at + ending.in_flight(
        stream_period(link.stream_ids, writer.baud)
    ):
        return ""  # a command may have come after it: what it did is not seen
    if OI_MODE_PACKET not in frame:  # the wheels' speeds alone, where the frame shows them
        stopped = describe_activity(wheels) == "stopped" and writer.modes.mode is OIMode.PASSIVE
        return SEEN_STOPPED_UNMODED if stopped and asked_to_stand(frame) else ""
    if writer.modes.detector.interpret(frame[OI_MODE_PACKET]) is not OIMode.PASSIVE:
        return ""
    if _LEFT_VELOCITY in frame and _RIGHT_VELOCITY in frame:
        still = frame[_LEFT_VELOCITY] == frame[_RIGHT_VELOCITY] == 0
    else:
        still = describe_activity(wheels) == "stopped"
    return SEEN_STOPPED if still else ""


def last_seen_words(mode: OIMode, activity: str, after_stop: bool, still: str) -> str:
    """What a stop not delivered says the robot was last seen doing: in ``mode``,
    ``activity`` (its wheels: :func:`wheels_words`), ``after_stop`` in frames that came after
    the stop, or ``still``, what its frames showed of it stopped (:func:`seen_stopped`). A
    part of :meth:`SafeStop._undelivered`."""
    if after_stop:
        return f"last seen in {mode.label} (the last wheel command written: {activity})"
    if still:  # the pause's stop, seen taken: nothing to pick up
        return still
    return f"last seen in {mode.label} {activity}"


def unheard_halt(ending: SafeStop) -> OwnHalt | None:
    """The session's own drive 0 (``CommandWriter.own_halt``: the watchdog's, the tick
    guard's, the bump reflex's) if it is still the last wheel command written, the one
    before it turned the wheels, and no frame sent after the robot could have heard it shows
    them stopped (its requested speeds, packet 39 or 41/42, at 0: one frame's encoders show
    nothing of it); else None. A Wi-Fi bridge that dropped mid-run: the watchdog tripped,
    wrote its drive 0 into the dying socket, then the port was found gone, and the report
    said "last seen in Safe stopped" of a robot last seen driving at 326 mm/s."""
    writer = ending.writer
    own = writer.own_halt
    if own is None or own.writes != writer.wheel_writes or writer.last_wheels is None:
        return None
    if own.before is None or not turns_wheels(own.before):
        return None  # the wheels stood before it: stopped either way
    link = writer.link
    frame = link.frame
    after = own.at + ending.in_flight(stream_period(link.stream_ids, writer.baud))
    if frame is not None and link.arrival > after and asked_to_stand(frame):
        return None  # a frame sent after it shows the wheels asked to stand: it was heard
    return own


def asked_to_stand(frame: SensorFrame) -> bool:
    """Whether ``frame`` shows the wheel speeds the robot was last asked for (packet 39,
    Drive's; or 41 and 42, Drive Direct's), all at 0."""
    shown = [pid for pid in (_VELOCITY, _LEFT_VELOCITY, _RIGHT_VELOCITY) if pid in frame]
    return (_VELOCITY in shown or len(shown) >= 2) and not any(frame[pid] for pid in shown)


def before_stop(ending: SafeStop) -> tuple[OIMode, Command | None, str, str, str]:
    """What is said of a stop that did not arrive, taken before it is written (the stop moves
    the model on): the mode, the wheel command the robot obeys as far as is known (the one
    before the session's own drive 0 no frame showed heard: :func:`unheard_halt`), what
    stopped the wheels, what its frames showed of it stopped (:func:`seen_stopped`), and its
    wheels in words (:func:`wheels_words`). A part of :meth:`SafeStop._stop`."""
    writer = ending.writer
    unheard = unheard_halt(ending)
    wheels = writer.last_wheels if unheard is None else unheard.before
    return (
        writer.modes.mode, wheels, writer.wheels_stopped_by, seen_stopped(ending),
        wheels_words(ending, unheard),
    )  # fmt: skip


def wheels_words(ending: SafeStop, unheard: OwnHalt | None) -> str:
    """What the robot's wheels were last told, in words (:func:`describe_activity`); after
    the session's own drive 0 no frame showed heard (``unheard``: :func:`unheard_halt`), the
    command before it, and that drive 0 said unconfirmed: ``spinning left at 100 mm/s (then
    the watchdog's drive 0, which no frame showed heard)``."""
    writer = ending.writer
    if unheard is None:
        return describe_activity(writer.last_wheels, writer.wheels_stopped_by)
    return f"{describe_activity(unheard.before)} (then {unheard.by}, which no frame showed heard)"


def asked_after(ending: SafeStop, unconfirmed: str) -> str | None:
    """A stop not confirmed (``unconfirmed`` says why), asked after: a Query List at the
    run's rate, and where garbage came, the stop at each other rate
    (:func:`~roomba_bt.robot.baud_hunt.hunt`). None if the robot answered in Passive
    (at another rate: :attr:`SafeStop.found_at` said); else why it is unconfirmed, a reset's
    robot said stopped (:attr:`SafeStop.reset_seen`: the OI is Off after it, its wheels
    still). A part of :meth:`SafeStop.stop`, out of the class for its size."""
    writer = ending.writer
    link = writer.link
    ending.reset_seen = link.banner_seen()
    if not ending.robot_heard or not asks_after(link):
        return unconfirmed
    stop = b"".join(
        command.data
        for command in stop_sequence(
            ending.last_seen, builtin_may_run=writer.cycle_may_drive, end_in="passive",
            profile=writer.profile,
        )
    )  # fmt: skip
    garbled = link.bytes_since_frame > 0 and not ending.reset_seen
    with signals_deferred():
        found = hunt(
            link, writer.baud, stop, STOP_RESYNC_ZEROS, garbled=garbled, reset=ending.reset_seen
        ).found
    if found == writer.baud and ending.reset_seen:
        ending.found_at = RESET_RESTARTED
        log.warning("%s: %s", link.name, RESET_RESTARTED)
    if found is None:
        if ending.reset_seen:
            return f"{unconfirmed}; {RESET_STOPPED}"
        return unconfirmed
    if found != writer.baud:
        with signals_deferred():
            back = put_back(link, found, writer.baud)
        ending.found_at = found_words(found, writer.baud, back=back)
        log.warning("%s: %s", link.name, ending.found_at)
        if not back:  # left in Passive at that rate, where it answered (docs/robot.md): so
            writer.baud = found  # the model, which a Stop (end_in="stop") had put in Off
            writer.modes.force(OIMode.PASSIVE, link.transport.now())
            ending.answered = True
            return None
    ending.answered = True
    stop_again(ending)
    return None


def stop_again(ending: SafeStop) -> None:
    """After a stop that ends in Off (``end_in="stop"``) was not confirmed and the robot,
    asked after, answered in Passive at the run's rate: the model in Passive, as the answer
    showed (the question's Start put it there: the OI answers nothing in Off), and Stop (173)
    written again, the line just shown to carry, so the robot ends in the Off it was asked
    for, its wheels and motors stopped as in Passive. It was left in Passive while the model
    held Off: the summary said ``final mode Off`` of a robot in Passive, and whether a run
    ended in Off hung on the machine's load (a stall before the stop has it asked after). The
    summary says it (:data:`STOP_WRITTEN_AGAIN`, after :attr:`SafeStop.found_at`'s words)."""
    writer = ending.writer
    if ending.end_in != "stop" or not writer.profile.has_command("stop"):
        return
    writer.modes.force(OIMode.PASSIVE, writer.link.transport.now())
    said = STOP_WRITTEN_AGAIN
    try:
        with signals_deferred():
            writer.send(oi.stop())
    except _RECOVERABLE as exc:
        said = STOP_LEFT_PASSIVE.format(error=exc)
        log.warning("%s: %s", writer.link.name, said)
    ending.found_at = f"{ending.found_at}; {said}" if ending.found_at else said
