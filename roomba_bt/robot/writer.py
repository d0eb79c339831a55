"""The command path of a session: the guard, each opcode's effect, a batch in one write.

Every command a :class:`~roomba_bt.robot.connection.Connection` sends leaves through one
:class:`CommandWriter`::

    command ──► ModeModel.check ──► Command.data (encoded, range-checked) ──► link.write
                 (refused: ModeError,                                   then ModeModel.apply
                  nothing written)                                      and the opcode's Effect

The runner writes a tick's outbox command by command, each through :meth:`CommandWriter.send`
(one write a command; each one let through is noted as its channel's standing command, each
one refused counted). :meth:`CommandWriter.send_many` writes a batch in one write, each command
guarded against the mode the commands before it lead to: the safe stop's sequence
(:mod:`~roomba_bt.robot.ending`), the tick guard's stop, the monitor's pause and resume; a
Baud (129) in it sends what came before at the old rate and the rest after the port
followed. What a written command
changes on our side of the link is the opcode table's
:class:`~roomba_bt.oi.opcodes.Effect`: a new stream, a pause, a baud change, a built-in cycle
that may drive in Passive.
"""

from __future__ import annotations

import contextlib
import logging
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from typing import NamedTuple

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import BAUD_RATES, Command
from roomba_bt.oi.errors import UnsupportedCommandError
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import Effect
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.oi.stream import check_bandwidth
from roomba_bt.robot.errors import ModeError, PortLost
from roomba_bt.robot.hazards import drives_forward, sets_going
from roomba_bt.robot.interface import docked_by_seek_dock, on_home_base
from roomba_bt.robot.link import StreamLink
from roomba_bt.robot.modes import ModeModel

log = logging.getLogger(__name__)
#: the effects every write asks about, read off the Enum class once: a member read off its
#: class goes through the Enum's metaclass, about 900 instructions in CPython 3.11 (twice a
#: command written, a Drive Direct every few ticks of a docking run)
_STREAM, _BAUD = Effect.STREAM, Effect.BAUD

#: The spec asks for 100 ms after Baud (129) before sending at the new rate.
BAUD_CHANGE_WAIT = 0.1
#: Command times kept for :attr:`CommandWriter.recent_commands`.
RECENT_COMMANDS = 8
#: Zero bytes that bring the robot's OI parser back in step after bytes from us were lost
#: on the line (:meth:`CommandWriter.send_many`'s ``prefix``): a parser left waiting in a
#: command for data bytes that never came takes them as those bytes. The longest such wait
#: of a command a run sends is the start-up's Query List ``[149][1][35]`` with its count
#: lost, ``[149][35]``: 35 packet ids (then zeros ask for packet group 0, an answer the
#: start-up reads and drops); a Song (140) of 16 notes waits 34 data bytes. A command that
#: zeros complete is harmless or at once replaced: a Drive of velocity 0 or ``vel hi * 256``
#: (the wheel command written after the zeros, in the same write, replaces it), Motors or
#: LEDs off, a song of no notes; 0 is no opcode, so the zeros left over are skipped one by
#: one. (A Stream or Query List whose count byte came whole may wait for up to 255 ids: not
#: covered.)
RESYNC_ZEROS = bytes(35)


class OwnHalt(NamedTuple):
    """A drive 0 the session wrote on its own (:meth:`CommandWriter.own_stop`): ``writes``,
    :attr:`~CommandWriter.wheel_writes` once it was written (still the count: no wheel
    command since); ``before``, the wheel command the robot obeys if it never heard it;
    ``at``, when it was written (link clock); ``by``, the drive 0 as said (``the watchdog's
    drive 0``)."""

    writes: int
    before: Command | None
    at: float
    by: str


class CommandWriter:
    """Guards, writes and follows the commands of one session over ``link``.

    It keeps what the written commands leave behind: ``modes`` (the session's mode model,
    moved by each command), the port's ``baud``, the last wheel command, whether a built-in
    cycle may be driving, when the last command went, and the counts sent and refused.
    """

    # long on purpose: the state the written commands leave, one attribute with its why each
    def __init__(
        self, link: StreamLink, modes: ModeModel, profile: RobotProfile, baud: int
    ) -> None:
        self.link = link
        self.modes = modes
        self.profile = profile
        #: the robot's rate: the port's, once every change of it is done (a session starts
        #: with the port at it, whether or not its transport keeps a rate to read)
        self.baud = link.port_rate = baud
        self.sent = 0
        self.refused = 0
        #: the last wheel command written (Drive, Drive Direct, PWM, a cleaning cycle)
        self.last_wheels: Command | None = None
        #: wheel commands written: what tells runtime/motion_watch.py a command that stood
        #: from equal bytes written again (Drive 0, 200, 0 between two of its looks)
        self.wheel_writes = 0
        #: why :attr:`last_wheels` is None after wheels were commanded: the cause of the
        #: robot's own fall to Passive that stopped them (``charger``; :meth:`robot_stopped`),
        #: "" while none has. Not cleared by a wheel command after it: ``last_wheels`` says
        #: that one, and this is read only while it is None (:func:`describe_activity
        #: <roomba_bt.robot.ending.describe_activity>`: "with its wheels stopped by its own
        #: fall to Passive (charger)", not "never commanded" after 488 m of driving)
        self.wheels_stopped_by = ""
        #: the last Motors (138) or PWM Motors (144) written, by the tree or by a batch (the
        #: safe stop's, the tick guard's, the monitor's pause: their "motors off"): what the
        #: robot's brushes and vacuum obey, for the monitor's robot panel, which showed the
        #: tree's last one (the brushes on) after a halt had turned them off
        self.last_motors: Command | None = None
        #: a Clean/Spot/Max/Seek Dock cycle may be driving
        self.builtin_may_run = False
        #: the last reply to a program's Query List (``Connection.query``: pycreate2's way
        #: to read the sensors, with no stream) and the stream frame count when it came:
        #: the robot as last seen, until a stream frame comes after it (:attr:`seen_frame`)
        self.reply: SensorFrame | None = None
        self.reply_index = -1
        #: a cycle the robot runs that this session did not write (a Clean, Spot or Dock
        #: button pressed, its schedule): what its caller saw of it (the runtime: the robot
        #: drove in Passive by itself), until a command that ends cycles (Safe, Full, Off);
        #: None: none seen. The safe stop ends it as its own (:attr:`cycle_may_drive`)
        self.robot_cycle: str | None = None
        #: told each time the robot goes to Passive: a command written that leads there
        #: (Start, a cycle: any caller's, the monitor's pause too) or its own fall
        #: (:meth:`robot_stopped`). The runtime measures from there what the robot drives in
        #: Passive by itself (``runtime/ending.py``, ``RunEnding.robot_cycle``); None: nobody
        self.on_passive: Callable[[], None] | None = None
        #: told of each command that ends cycles (Safe, Full, Stop, Reset: ``ends_cycle``)
        #: as it is written, before :attr:`builtin_may_run` and :attr:`robot_cycle` follow
        #: it: the runtime judges what the robot drove in Passive by itself until then
        #: (``RobotCycleWatch.leaving_passive``); None: nobody
        self.on_cycle_end: Callable[[Command], None] | None = None
        #: when the last command was written (link clock)
        self.last_command_at = float("-inf")
        #: when the last few commands were written (link clock): how long the robot had been
        #: without one at a moment past, the watchdog's own drive 0 after it aside
        self.recent_commands: deque[float] = deque(maxlen=RECENT_COMMANDS)
        #: the bump reflex (robot/hazards.py): while a bump onset waits for its confirming
        #: frame, forward wheel commands are kept, not written; the one to send again after
        self.forward_held = False
        self.held_wheels: Command | None = None
        #: while a tree is stopped (:meth:`hold_motion`): what is told of each command that
        #: would set the robot going, which is not written; None: no such hold
        self.motion_held: Callable[[Command], None] | None = None
        #: the Reset (7) or Stop (173) written last: the OI is off and streams nothing more,
        #: so a run that sees it ends (runtime/loop.py); None before any
        self.silenced_by: Command | None = None
        #: the last drive 0 the session wrote on its own (the watchdog's, the tick guard's,
        #: the bump reflex's: :meth:`own_stop`), or None: what the end's report reads, so
        #: that a watchdog's drive 0 written into a dying bridge is not said as "stopped"
        self.own_halt: OwnHalt | None = None

    def send(self, command: Command) -> None:
        """Guard, then write ``command``'s bytes, then update the mode model.

        A refused command raises (:class:`ModeError`,
        :class:`~roomba_bt.oi.errors.UnsupportedCommandError`,
        :class:`~roomba_bt.oi.errors.BandwidthError` for a stream that does not fit) and
        nothing is written.
        """
        self._send(command, None)

    def send_many(self, commands: Iterable[Command], prefix: bytes = b"") -> None:
        """Commands in order, in one write: the safe stop's sequence, the tick guard's stop,
        the monitor's pause and resume (a tick's outbox goes by :meth:`send`, one command at
        a time). Each command is guarded against the mode the commands before it lead to (so
        ``safe`` then ``drive`` passes). Refused commands are left out; after the others are
        written the first refusal is raised. ``prefix``: bytes that go first in the same
        write, no command (:data:`RESYNC_ZEROS`, the run's resend after bytes were lost)."""
        refused: list[Exception] = []
        batch = bytearray(prefix)
        # the model follows what was written: if the batch never leaves, it is put back
        saved = self.modes.snapshot(), self.last_wheels, self.last_motors, self.wheel_writes
        try:
            for command in commands:
                try:
                    self._send(command, batch)
                except (ModeError, UnsupportedCommandError) as exc:
                    refused.append(exc)
        finally:
            if batch:
                try:
                    self.at_robot_rate()
                    self.link.write(bytes(batch))
                except PortLost:
                    self.modes.restore(saved[0])
                    self.last_wheels, self.last_motors, self.wheel_writes = saved[1:]
                    raise
        if refused:
            for extra in refused[1:]:
                log.warning("%s: also refused: %s", self.link.name, extra)
            raise refused[0]

    def _send(self, command: Command, batch: bytearray | None) -> None:
        spec = command.spec
        try:
            self.modes.check(command)
        except (ModeError, UnsupportedCommandError):
            self.refused += 1
            raise
        if self.forward_held and spec.channel == "wheels":
            if drives_forward(command):  # the bump reflex: kept for release_forward
                self.held_wheels = command
                return
            self.held_wheels = None  # the tree wants something else now
        if self.motion_held is not None and sets_going(command):
            self.motion_held(command)  # a tree's stop sets nothing going: not written
            return
        effect = spec.effect
        if effect is _STREAM:
            check_bandwidth(command.args[1:], self.baud)
        warning = self.profile.command_warning(spec)
        if warning is not None:
            log.warning("%s: %s", self.link.name, warning)
        if batch is None or effect is _BAUD:  # the rest goes at the new rate
            link = self.link
            if link.port_rate != self.baud:  # a rate change cut short (Ctrl-C in a listen)
                self.at_robot_rate()
            if batch:
                link.write(bytes(batch))
                batch.clear()
            link.write(command.data)
        else:
            batch += command.data
        now = self.link.transport.now()
        self.last_command_at = now
        self.recent_commands.append(now)
        self.modes.apply(command, now)
        channel = spec.channel
        if channel == "wheels":
            self.last_wheels = command
            self.wheel_writes += 1
        elif channel == "motors":
            self.last_motors = command
        self.sent += 1
        if effect is not None or spec.leads_to is not None:  # not a plain actuator command
            self._after(command, now)

    def _after(self, command: Command, now: float) -> None:
        """What a written command changes on our side of the link (the opcode table's
        :class:`~roomba_bt.oi.opcodes.Effect` and mode)."""
        spec = command.spec
        effect = spec.effect
        if effect is Effect.STREAM:
            self.link.new_stream(tuple(command.args[1:]), now)
        elif effect is Effect.PAUSE_RESUME:
            self.link.pause_resume(bool(command.args[0]), now)
        elif effect is Effect.SILENCES:
            self.link.streaming = False
            self.silenced_by = command
        if spec.ends_cycle and self.on_cycle_end is not None:
            self.on_cycle_end(command)
        self.builtin_may_run = spec.cycle_may_run_after(self.builtin_may_run)
        if spec.leads_to is not None:  # a mode command: Safe, Full, Off end any cycle
            if spec.leads_to is not OIMode.PASSIVE:
                self.robot_cycle = None
            elif self.on_passive is not None:  # Start, a cycle: the robot goes to Passive
                self.on_passive()
        if effect is Effect.BAUD:
            self._change_baud(BAUD_RATES[command.args[0]])

    def _change_baud(self, rate: int) -> None:
        """Baud (129) was written: the robot's rate is ``rate`` from now on (a Ctrl-C in the
        wait leaves the port to be set there before the safe stop: :meth:`at_robot_rate`);
        wait the 100 ms the spec asks (reading, so the link's clock moves on a virtual link
        too), then change the port's rate (what was written drained first)."""
        link = self.link
        self.baud = rate
        clock = link.transport.now
        deadline = clock() + BAUD_CHANGE_WAIT
        while (remaining := deadline - clock()) > 0:
            data = link.read(remaining)
            if data:
                link.ingest(data, clock())
        link.set_baud(rate)

    def at_robot_rate(self) -> None:
        """The port at the robot's rate (:attr:`baud`) before bytes are written: set again if
        the link's last change of it was another rate's, or cut short (a listen at another
        rate that a Ctrl-C, SIGTERM or SIGHUP ended: the whole safe stop went out at 19200
        to a robot at 115200, which drove on). Nothing to do on the common path."""
        link = self.link
        if link.port_rate != self.baud:
            log.debug("%s: the port set back to %d baud before a write", link.name, self.baud)
            link.switch_rate(self.baud)

    def set_baud(self, rate: int) -> None:
        """Baud (129) by rate (e.g. 19200); the port follows after 100 ms."""
        if self.link.stream_ids:
            check_bandwidth(self.link.stream_ids, rate)
        self.send(oi.baud_rate(rate))

    @property
    def running_cycle(self) -> Command | None:
        """The Clean/Spot/Max/Seek Dock command written last while its cycle may still be
        driving the robot (in Passive; :attr:`cycle_may_drive`: not a Seek Dock that docked),
        else None."""
        wheels = self.last_wheels
        if wheels is not None and self.cycle_may_drive:
            return wheels if wheels.spec.effect is Effect.BUILTIN_CYCLE else None
        return None

    @property
    def seen_frame(self) -> SensorFrame | None:
        """The newest frame the robot sent: the stream's last, or a Query List reply asked
        since (:attr:`reply`). A program that docks as pycreate2 does (Seek Dock, then Query
        Lists until the home base shows) streams nothing: its ending, judged by the stream
        alone, took the docked cycle for one that may still drive and sent Safe first, which
        ends the charge the program had just reached."""
        reply = self.reply
        if reply is not None and self.reply_index == self.link.index:
            return reply
        return self.link.frame

    @property
    def cycle_may_drive(self) -> bool:
        """Whether a built-in cycle may be driving the robot as the stream last showed it:
        :attr:`builtin_may_run`, unless it was Seek Dock and the last frame shows the home
        base's power (:func:`~roomba_bt.robot.interface.docked_by_seek_dock`: docked, the
        cycle ended there); or :attr:`robot_cycle`, a cycle the robot started by itself,
        unless the last frame shows the home base (which of its cycles it ran is not known:
        one on its dock has docked or not yet left, and Safe there would stop the charge).
        What the safe stop asks before it sends Safe to end a cycle."""
        frame = self.seen_frame
        if self.builtin_may_run and not docked_by_seek_dock(self.last_wheels, frame):
            return True
        return self.robot_cycle is not None and not on_home_base(frame)

    def halt(self, motors: bool = False, by: str = "") -> bool:
        """Drive 0 if the model says the robot may be driving; True once it was written at
        the robot's rate (:meth:`at_robot_rate`) and has left the port (drained: a rate
        change right after it, a listen at another rate, re-clocked it, and the robot heard
        3 watchdog drive 0s of 11 while the summary counted all 11 sent). The watchdog's
        action, and the tick guard's. ``motors`` (the watchdog's): motors off in the same
        write when a brush or the vacuum runs (:meth:`motors_running`), as the tick guard
        does: a stream that stalled left the brushes and vacuum running on the spot while
        the wheels stood. ``by``: whose drive 0 it is when not the caller's own
        (:meth:`own_stop`)."""
        if self.modes.mode not in DRIVING_MODES:
            return False
        with self.own_stop(by):
            if motors and self.motors_running():
                self.send_many((oi.halt(), oi.motors_off()))
            else:
                self.send(oi.halt())
        self.link.drain_output()
        return True

    @property
    def wheels_before_own_halt(self) -> Command | None:
        """The wheel command written before the session's own drive 0 when that is still the
        last one written (:attr:`own_halt`), else :attr:`last_wheels`: what the robot obeys
        if that drive 0 never reached it."""
        own = self.own_halt
        if own is not None and own.writes == self.wheel_writes and self.last_wheels is not None:
            return own.before
        return self.last_wheels

    @contextlib.contextmanager
    def own_stop(self, by: str) -> Iterator[None]:
        """The drive 0 written in it is the session's own (``by``, as said: ``the watchdog's
        drive 0``, ``the tick guard's drive 0``), not its caller's command: kept as
        :attr:`own_halt` with the wheel command it replaced (two in a row keep the first's),
        for the end's report. "" for a caller's own halt (``Connection.halt()``): nothing
        kept."""
        before, writes = self.wheels_before_own_halt, self.wheel_writes
        yield
        wheels = self.last_wheels
        if by and self.wheel_writes != writes and wheels is not None and not any(wheels.args):
            self.own_halt = OwnHalt(self.wheel_writes, before, self.last_command_at, by)

    def motors_running(self) -> bool:
        """The last Motors command written runs a brush or the vacuum, in a mode where the
        robot obeys it (:attr:`last_motors`, forgotten at the robot's own fall to Passive)."""
        motors = self.last_motors
        return motors is not None and sets_going(motors) and self.modes.mode in DRIVING_MODES

    def robot_stopped(self, cause: str) -> None:
        """The robot fell to Passive by itself (a cliff, a wheel drop, the charger): it
        stopped its wheels and motors, so the commands written before drive nothing now.
        Forgotten, as the runtime's outbox forgets them (``Outbox.robot_stopped``): the tick
        guard and the run's end took the robot for moving after the tree's Safe again, and
        the bump reflex kept the drive from before the fall and sent it again (the robot
        drove back over the edge) once an onset cleared. ``cause`` (``cliff``, ``charger``)
        is kept as what stopped the wheels (:attr:`wheels_stopped_by`)."""
        self.last_wheels = self.last_motors = self.held_wheels = None
        self.wheels_stopped_by = cause
        if self.on_passive is not None:
            self.on_passive()

    def hold_forward(self) -> None:
        """A bump onset waits for the frame that confirms it (robot/hazards.py): drive 0 now
        if the last wheel command drives forward, so the robot does not push on into what it
        may have hit, and until :meth:`release_forward` forward wheel commands are kept, not
        written (the action goes on: the tree does not know of the bump yet)."""
        if self.forward_held:
            return
        self.forward_held = True
        wheels = self.last_wheels
        if wheels is not None and drives_forward(wheels) and self.modes.mode in DRIVING_MODES:
            with self.own_stop("the bump reflex's drive 0"):
                self.send(oi.halt())
            self.held_wheels = wheels

    def hold_motion(self, held: Callable[[Command], None] | None) -> None:
        """While a behaviour tree is stopped (each running node's ``terminate()``, before the
        safe stop), a command that would set the robot going (:func:`sets_going
        <roomba_bt.robot.hazards.sets_going>`: a wheel turning, a built-in cycle, a brush or
        the vacuum) is not written, whichever way it came (``Connection.send`` straight from a
        plugin's ``terminate``, a batch); ``held(command)`` is told of it. Drive 0, motors
        off, a mode, a song, the LEDs are written as ever. ``None`` ends the hold.

        Decided: held, not written and undone later. py_trees' ``terminate()`` is where a
        behaviour stops what it started; a drive written there could only last until the
        safe stop that follows the tree's stop, which is as long as the slowest terminate
        blocks (a plugin's ``time.sleep``, a network call): the Open Interface has no
        command timeout, so the robot drove on, unwatched, for that long. A tick guard
        watching the stop would have stopped it only after its limit, and raising in the
        terminate would skip the rest of its clean-up (its file, its socket)."""
        self.motion_held = held

    def release_forward(self) -> Command | None:
        """The onset was confirmed or cleared: the hold ends. The forward command it kept (the
        one driving when it began, or the last one sent since), to be sent again unless the
        tick sends another; None when nothing was held."""
        self.forward_held = False
        held, self.held_wheels = self.held_wheels, None
        return held
