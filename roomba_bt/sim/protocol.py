"""The Open Interface as the robot speaks it: commands cut from the host's bytes, dispatched by
opcode, the mode rules, and the commands that only set state (LEDs, songs, schedule, baud).

Commands are cut by the opcode table (:mod:`roomba_bt.oi.opcodes`): the opcode, the fixed
data bytes of ``CommandSpec.args``, then a variable tail counted by one of them::

    [137][vel hi][vel lo][rad hi][rad lo]          Drive: 4 fixed data bytes
    [148][n][id 1]...[id n]                        Stream: n ids after the count
    [140][song][length][note][dur]...              Song: 2 bytes a note

An incomplete command waits for its bytes; an unknown opcode is skipped one byte at a time.
The mode rules are the table's too: ``CommandSpec.modes`` (where a command is accepted; an
actuator command elsewhere is ignored and recorded in ``violations``) and ``leads_to`` (the
mode it changes to). Off and sleep answer only Start and Reset. In Safe, a wheel drop, a cliff
while driving forward or a powered charger drops the robot to Passive (:meth:`_safety`).

A layer of the simulator (see state.py): the top one, it reads every other.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable

from roomba_bt.oi.bits import PRESS_SECONDS, WHEEL_DROP_BITS, button_bits, held_clock_buttons
from roomba_bt.oi.encode import BAUD_RATES
from roomba_bt.oi.identify import parse_firmware
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import COMMANDS, COMMANDS_BY_NAME, CommandSpec, Effect
from roomba_bt.sim.cycles import BUTTON_CYCLES, CYCLES, BuiltinCycle
from roomba_bt.sim.faults import HostLine
from roomba_bt.sim.replies import StreamOutput
from roomba_bt.sim.robot_clock import RobotClock
from roomba_bt.sim.state import TracePoint, Violation
from roomba_bt.sim.world import ROBOT_RADIUS_MM

#: Passive without a byte from the host for this long: the robot sleeps.
PASSIVE_SLEEP_SECONDS = 300.0
#: The firmware a simulated robot runs unless told otherwise: the first release that wakes
#: by BRC on the dock (the 600 spec's Appendix B).
DEFAULT_FIRMWARE = "release-stm32-3.7.7"


def reset_banner(firmware: str) -> bytes:
    """What the firmware prints on Reset (7): the lines pycreate2's author captured on a
    Create 2, then the release line the 600 spec quotes (``r3_robot/tags/<firmware>``)."""
    return (
        b"bl-start\r\nSTR730\r\nbootloader id: #x47186549 82ECCFFF\r\n"
        b"bootloader info rev: #xF000\r\nbootloader rev: #x0001\r\n2007-05-14-1715-L   \r\n"
        b"Roomba by iRobot!\r\nstr730\r\n2012-03-22-1549-L\r\nbattery-current-zero 252\r\n"
        + f"r3_robot/tags/{firmware} CLEAN\r\n".encode("ascii")
    )


#: what Off (and a sleeping robot) answers: the commands the table accepts in Off (Start, Reset)
_WAKERS = frozenset(c.opcode for c in COMMANDS.values() if OIMode.OFF in c.modes)
_DRIVE = COMMANDS_BY_NAME["drive"].opcode
_START = COMMANDS_BY_NAME["start"].opcode
#: Drive, Drive Direct, Drive PWM: sent again with the same bytes, they change nothing
_WHEEL_COMMANDS = frozenset(c.opcode for c in COMMANDS.values() if c.drives_wheels)
#: read for every command executed, as globals: an enum member read off its class costs
#: about a thousand machine instructions on CPython 3.11 (its metaclass's ``__getattr__``)
_OFF, _BUILTIN_CYCLE = OIMode.OFF, Effect.BUILTIN_CYCLE


def _count_offset(spec: CommandSpec) -> int:
    """Data bytes before the argument that counts a command's variable tail."""
    assert spec.tail is not None
    offset = 0
    for arg in spec.args:
        if arg.name == spec.tail.count_arg:
            return offset
        offset += arg.size
    raise ValueError(f"{spec.name}: no argument {spec.tail.count_arg!r}")


class OIProtocol(StreamOutput):
    """Host bytes to commands, commands to state; the mode rules."""

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_buttons_until", "_commands", "_data_sizes", "_drive_modes", "_held_until", "_inbuf",
        "_last_activity", "_paused_at", "_rng", "_song_until", "_tails", "baud", "brc_low",
        "brc_pulses", "builtin", "cycle_commands_pause", "deaf", "digits",
        "firmware", "heard", "host_line", "ignored_bytes", "leds", "paused_cycle", "robot_clock",
        "scheduling_leds", "songs",
    )  # fmt: skip

    def _init_protocol(self) -> None:
        profile = self.profile
        self.baud = profile.default_baud
        self.leds: tuple[int, int, int] = (0, 0, 0)
        self.scheduling_leds: tuple[int, int] = (0, 0)
        self.digits: tuple[int, int, int, int] = (32, 32, 32, 32)
        self.songs: dict[int, tuple[tuple[int, int], ...]] = {}
        #: what Set Day/Time (168) and Schedule (167) set (robot_clock.py)
        self.robot_clock = RobotClock()
        self._song_until = 0.0
        self._buttons_until = 0.0
        #: the first of those two still to come while its packet shows (37 a song playing,
        #: 18 buttons pressed), else infinity: the step looks at one time, not two packets
        self._held_until = math.inf
        self.builtin: BuiltinCycle | None = None
        #: whether a cycle command into a running cycle pauses it, as the 600 / Create 2 spec
        #: says (:meth:`_cycle_command`); off: it starts its own cycle in its place, the
        #: behaviour the golden recordings were made with (tests/golden builds its simulators
        #: with the default). Every simulator the CLI builds (run, sim, sensors, eval) turns
        #: it on.
        self.cycle_commands_pause = False
        #: the cycle a cycle command paused (wheels and brushes stopped), until the same
        #: command resumes it, another cycle command replaces it or a mode command ends it
        self.paused_cycle: BuiltinCycle | None = None
        self._paused_at = 0.0
        self._rng = random.Random(f"robot:{self.seed}")  # the built-in cycles' choices
        self._last_activity = 0.0
        self.brc_low = False
        self.brc_pulses = 0
        #: the release the reset banner names; before release-3.8.2 / release-stm32-3.7.7 a
        #: BRC pulse does not wake the robot on the dock
        self.firmware = DEFAULT_FIRMWARE
        #: asleep by the five-minute idle rule: deaf to the serial line until BRC wakes it
        self.deaf = False
        self.ignored_bytes = 0
        #: the bytes' way from the host, when a fault loses or changes some (None: a clean
        #: line, every byte arrives)
        self.host_line = HostLine.of(self.faults, self.seed)
        #: told of each command the robot takes in, before its mode is checked (``sim --log``,
        #: :class:`~roomba_bt.sim.narrate.Narrator`); None: nobody is told
        self.heard: Callable[[CommandSpec, bytes], None] | None = None
        self._inbuf = bytearray()
        self._commands: dict[int, CommandSpec] = {c.opcode: c for c in profile.commands}
        self._data_sizes = {c.opcode: c.fixed_data_bytes for c in profile.commands}
        #: variable tails from the opcode table: (offset of the count byte, bytes per item)
        self._tails = {
            c.opcode: (1 + _count_offset(c), c.tail.bytes_per_item)
            for c in profile.commands
            if c.tail is not None
        }
        #: where the wheel commands are accepted (drives_wheels: the three are actuators)
        self._drive_modes = self._commands[_DRIVE].modes

    @property
    def day_time(self) -> tuple[int, int, int]:
        """Set Day/Time (168)'s day, hour and minute as last taken, as 0.2.0 kept them
        (the clock as it runs on: ``robot_clock.shows(time)``)."""
        return self.robot_clock.day_time

    @property
    def schedule(self) -> bytes:
        """Schedule (167)'s data bytes as last taken, as 0.2.0 kept them."""
        return self.robot_clock.schedule

    # ------------------------------------------------------------------ host -> robot
    def receive(self, data: bytes | bytearray) -> None:
        """Take bytes from the host. A command whose data bytes have not all arrived waits
        for them, as the robot does; unknown opcodes are skipped one byte at a time."""
        if self.disconnected or not data:
            return
        if self.host_line is not None:
            data, what = self.host_line.passed(data)
            if what:
                self.event("line", what)
            if not data:
                return
        self._last_activity = self.time
        buf = self._inbuf
        commands = self._commands
        sizes = self._data_sizes
        tails = self._tails
        if not buf:  # the common case: exactly one whole fixed-size command
            if self._repeats_wheels(data):
                return
            spec = commands.get(data[0])
            if spec is not None and spec.tail is None and len(data) == 1 + sizes[data[0]]:
                self._execute(spec, bytes(data[1:]))
                return
        buf += data
        while buf:
            op = buf[0]
            spec = commands.get(op)
            if spec is None:
                del buf[0]
                self.ignored_bytes += 1
                continue
            need = 1 + sizes[op]
            if len(buf) < need:
                return
            tail = tails.get(op)
            if tail is not None:
                count_at, per_item = tail
                need += buf[count_at] * per_item
                if len(buf) < need:
                    return
            args = bytes(buf[1:need])
            del buf[:need]
            self._execute(spec, args)

    def _repeats_wheels(self, command: bytes | bytearray) -> bool:
        """The wheel command in force sent again (a client sends one a frame): it changes
        nothing, so it is neither executed nor told to :attr:`heard` (``sim --log``)."""
        return command == self._last_drive and not self.asleep and self.mode in self._drive_modes

    def _execute(self, spec: CommandSpec, args: bytes) -> None:
        op = spec.opcode
        if self.deaf:
            return  # power saving: the UART is not listening (a BRC pulse wakes it)
        if op in _WHEEL_COMMANDS and self._repeats_wheels(bytes((op,)) + args):
            return
        if self.heard is not None:
            self.heard(spec, args)
        if self.asleep or self.mode is _OFF:
            # Off (and asleep) answers nothing but Start, and Reset where it exists.
            if op not in _WAKERS:
                if spec.is_actuator:
                    self.violations.append(Violation(self.time, op, spec.name, OIMode.OFF))
                return
        elif self.mode not in spec.modes:
            if spec.is_actuator:
                self.violations.append(Violation(self.time, op, spec.name, self.mode))
            return
        if spec.effect is _BUILTIN_CYCLE:
            self._start_cycle(spec)
            return
        if spec.leads_to is not None:
            self._command_mode(spec)
        handler = _HANDLERS.get(op)
        if handler is not None:
            handler(self, args)

    def _start_cycle(self, spec: CommandSpec) -> None:
        """Spot, Clean, Max or Seek Dock, sent or its button pushed: into a running cycle a
        pause with :attr:`cycle_commands_pause` (:meth:`_cycle_command`), else the cycle
        started in place of any other."""
        if self.cycle_commands_pause:
            self._cycle_command(spec)
            return
        self._command_mode(spec)
        _HANDLERS[spec.opcode](self, b"")

    # ------------------------------------------------------------------ modes
    def _command_mode(self, spec: CommandSpec) -> None:
        """The mode ``spec`` leads to, the wheels stopped and a cycle ended on the way,
        but for Start (128) in Passive while a cycle runs or is paused: it changes nothing.
        Why (docs/protocol.md "What ends a built-in cycle"): neither spec
        says Start ends a cycle, and Passive is where the robot runs one ("watch Roomba
        perform a cleaning cycle"); Safe and Full end it ("Roomba waits with all motors and
        LEDs off"), Power, Stop and Reset turn the OI off or asleep. The robot layer never
        relies on Start (it sends Safe first); a simulator that ended the cycle at Start would
        hide a stop that ended a cycle by Start alone."""
        target = spec.leads_to
        assert target is not None
        if (
            spec.opcode == _START
            and self.mode is OIMode.PASSIVE
            and (self.builtin is not None or self.paused_cycle is not None)
        ):
            return
        self.asleep = self.deaf = False
        self.builtin = self.paused_cycle = None
        self._stop_wheels()
        if target is not OIMode.SAFE and target is not OIMode.FULL:
            self.motor_bits = 0
            self.brush_pwm = (0, 0, 0)
        self._set_mode(target, spec.name)

    def _set_mode(self, mode: OIMode, cause: str) -> None:
        # the mode, and the wheels and brushes its callers stopped, draw other currents
        self._power_due = True
        if mode is not self.mode:
            self.event("mode", f"{self.mode.label}->{mode.label} ({cause})")
            self.mode = mode
            if self.keeps_trace:
                self.trace.append(TracePoint(self.time, self.x, self.y, self.theta, mode))
        # Some 600-series firmware reports mode + 1 in packet 35 (the profile says which).
        self.values[35] = int(mode) + (1 if self.profile.reports_mode_plus_one else 0)

    def _safety(self) -> None:
        """Safe mode's own rules, checked when a wheel drop, cliff, dock or the wall charger's
        plug shows: stop the motors and drop to Passive (the event says which cause)."""
        v = self.values
        cause = ""
        if v[7] & WHEEL_DROP_BITS:
            cause = "wheel drop"
        elif v[9] or v[10] or v[11] or v[12]:
            cause = self._cliff_cause(self.left_speed, self.right_speed)
        if not cause and self.docked and self.dock_powered:
            cause = "powered charger"
        if not cause and self.plugged_in:
            cause = "internal charger plugged in"
        if cause:
            self._stop_wheels()
            self.left_speed = self.right_speed = 0.0
            self.motor_bits = 0
            self.brush_pwm = (0, 0, 0)
            self._set_mode(OIMode.PASSIVE, f"safety: {cause}")

    def _cliff_cause(self, left: float, right: float) -> str:
        """Why a cliff stops these wheel speeds in Safe mode, or "" if it does not. The spec's
        words: "a cliff while moving forward (or moving backward with a small turning radius,
        less than one robot radius)". Forward is the centre moving forward (the wheels' speeds
        sum > 0); a turn in place has radius 0. A differential drive's centre turns on a
        radius of half the wheel base x |right + left| / |right - left|: compared with the
        body's radius multiplied out, so a spin needs no division by 0. Straight back, or
        back on a wide arc, no cliff sensor leads and the robot goes on (and may fall)."""
        forward = left + right
        if forward > 0.0:
            return "cliff while driving forward"
        if -forward * self.profile.wheel_base_mm / 2.0 < ROBOT_RADIUS_MM * abs(right - left):
            return "cliff while turning tighter than the robot's radius"
        return ""

    def set_brc(self, low: bool) -> None:
        """The BRC pin (wired to a modem line on the USB cables). Its falling edge resets the
        five-minute Passive sleep counter and wakes a sleeping robot, into Passive with no
        stream (the 600 spec, "Passive Mode")::

            BRC  ────┐       ┌────      falling edge: counter reset / wake
                     └───────┘
        """
        if low and not self.brc_low:
            self.brc_pulses += 1
            self._last_activity = self.time
            if (
                self.asleep
                and (not self.docked or self._wakes_on_dock())
                and self.battery_charge > 0.0  # a flat battery wakes for nothing
            ):
                self.asleep = self.deaf = False
                self._set_mode(OIMode.PASSIVE, "BRC pulse")
                self.event("wake", "BRC pulse")
        self.brc_low = low

    def fall_asleep(self, cause: str) -> None:
        """Asleep as after five idle minutes in Passive (``sim --asleep``, the ``sleep_at``
        fault): in Passive with its motors off, no stream, deaf to every byte (Start and
        Query List included) until a BRC pulse. The 600 spec's only wake for this sleep is
        the BRC pulse ("Passive Mode"; Appendix B: "Dock wakeup: BRC pulse"); Start is what
        Off listens for, and a robot asleep answers no byte (robotics.stackexchange.com/q/10666).
        A robot in Safe or Full never sleeps: the fault waits for Passive
        (``Simulator._timed_fault``); called in Safe or Full (a test's direct call), it drops
        the robot to Passive first."""
        self.builtin = self.paused_cycle = None
        self._stop_wheels()
        self.left_speed = self.right_speed = 0.0
        self.motor_bits = 0
        self.brush_pwm = (0, 0, 0)
        self._set_mode(OIMode.PASSIVE, cause)
        self._fall_asleep(cause, deaf=True)

    def _cycle_command(self, spec: CommandSpec) -> None:
        """Spot, Clean, Max or Seek Dock with :attr:`cycle_commands_pause` on. The 600 /
        Create 2 spec says each "will pause a cleaning cycle if one is already in progress"
        (the 500 spec is silent; a 500's buttons do the same, so every profile does it).
        Decided, where the spec says no more:

        * a cycle runs (any of the four: Seek Dock drives as the cleaning cycles do): it
          pauses, wheels and brushes stopped, in Passive; the command starts nothing;
        * the same command while it is paused resumes it where it was (its time limit
          counts the running time only), as a second press of the button does;
        * another cycle command while one is paused starts that cycle (the paused one is
          dropped); a mode command (Start, Safe, Full, Power, Reset, Stop) ends a paused
          cycle as it ends a running one.
        """
        running, paused = self.builtin, self.paused_cycle
        self._command_mode(spec)  # Passive; clears both
        if running is not None:
            self.paused_cycle, self._paused_at = running, self.time
            self.event("builtin", f"{running.name} paused ({spec.name})")
        elif paused is not None and paused.name == spec.name:
            paused.started += self.time - self._paused_at
            self._settle_far()
            self.builtin = paused
            self.event("builtin", f"{paused.name} resumed")
        else:
            _HANDLERS[spec.opcode](self, b"")

    def _wakes_on_dock(self) -> bool:
        version = parse_firmware(self.firmware)
        return version is None or version.wakes_by_brc_on_dock

    def _fall_asleep(self, cause: str, *, deaf: bool = False) -> None:
        """Sleep; the stream ends. The five-minute power saving (``deaf``) answers nothing
        until a BRC pulse (the 600 spec, "Passive Mode"; a robot asleep there answers no
        byte: robotics.stackexchange.com/q/10666); after Power (133) Start wakes it too."""
        self.asleep = True
        self.deaf = deaf
        self._end_stream()
        self.event("sleep", cause)

    # ------------------------------------------------------------------ command handlers
    def _on_reset(self, args: bytes) -> None:
        self._end_stream()
        self.songs.clear()
        self._inbuf.clear()
        self._emit(reset_banner(self.firmware))

    def _on_start(self, args: bytes) -> None:
        return None  # the mode change (leads_to) is all Start does

    def _on_stop(self, args: bytes) -> None:
        self._end_stream()

    def _on_power(self, args: bytes) -> None:
        self._fall_asleep("power (133)")

    def _on_baud(self, args: bytes) -> None:
        self.baud = BAUD_RATES.get(args[0], self.baud)

    def _on_leds(self, args: bytes) -> None:
        self.leds = (args[0], args[1], args[2])

    def _on_scheduling_leds(self, args: bytes) -> None:
        self.scheduling_leds = (args[0], args[1])

    def _on_digits(self, args: bytes) -> None:
        self.digits = (args[0], args[1], args[2], args[3])

    def _on_song(self, args: bytes) -> None:
        number, length = args[0], args[1]
        if number > 4:
            return
        notes = args[2 : 2 + 2 * length]
        self.songs[number] = tuple((notes[i], notes[i + 1]) for i in range(0, len(notes), 2))

    def _on_play(self, args: bytes) -> None:
        """Play (141): packets 36/37 show the song for its length. A slot never defined is
        ignored (both specs: "you must add one or more songs ... for the Play command to
        work"), and so is a Play while a song plays (the 600 and 500 specs are silent, the
        original Create OI spec says "this command does not work if a song is already
        playing"; docs/protocol.md), said as event ``refused``."""
        song = self.songs.get(args[0])
        if song is None:
            return
        if self.values[37] and self.time < self._song_until:
            self.event("refused", f"play {args[0]} ignored: song {self.values[36]} still playing")
            return
        self.values[36] = args[0]
        self.values[37] = 1
        self._song_until = self.time + sum(d for _, d in song) / 64.0
        self._held_until = min(self._held_until, self._song_until)

    def _on_buttons(self, args: bytes) -> None:
        self._press(args[0])

    def press_button(self, name: str) -> None:
        """A finger on the button ``name`` (packet 18's), as a world's ``press`` event puts
        it: pressed as Buttons (165) presses it. A button this robot's top lacks (the clock
        panel's on a Create 2) is said as event ``refused`` and presses nothing."""
        if name not in self.profile.buttons:
            self.event("refused", f"press {name}: the {self.profile.title} has no {name} button")
            return
        self._press(button_bits(name))

    def _press(self, pushed: int) -> None:
        """The buttons pushed: packet 18 for 1/6 s (both specs), and in Passive a Clean,
        Spot or Dock button starts its cycle as its command does (:data:`BUTTON_CYCLES`);
        in Safe and Full the robot "does not respond to button presses" (both specs)."""
        self.values[18] = pushed
        self._buttons_until = self.time + PRESS_SECONDS
        self._held_until = min(self._held_until, self._buttons_until)
        if self.mode is OIMode.PASSIVE:
            cycle = next((name for bit, name in BUTTON_CYCLES if pushed & bit), None)
            if cycle is not None:
                self._start_cycle(COMMANDS_BY_NAME[cycle])

    def _release_held(self, now: float) -> None:
        """A song's end or the buttons' release is due by ``now``: its packet cleared."""
        v = self.values
        if v[37] and now >= self._song_until:
            v[37] = 0
        if v[18] and now >= self._buttons_until:
            v[18] = 0
        song = self._song_until if v[37] else math.inf
        buttons = self._buttons_until if v[18] else math.inf
        self._held_until = min(song, buttons)


def _takes_clock_command(robot: OIProtocol, name: str) -> bool:
    """Whether the robot takes Schedule (167) or Set Day/Time (168) now: not while packet 18
    shows the Clock or Schedule button pressed (both specs), said as event ``refused``."""
    held = held_clock_buttons(robot.values[18])  # cleared at the release (_release_held)
    if held:
        robot.event("refused", f"{name} ignored: the {held} button is pressed")
    return not held


def _on_schedule(robot: OIProtocol, args: bytes) -> None:
    if _takes_clock_command(robot, "schedule"):
        robot.robot_clock.set_schedule(args)


def _on_day_time(robot: OIProtocol, args: bytes) -> None:
    if _takes_clock_command(robot, "set_day_time"):
        robot.robot_clock.set(args, robot.time)


def _cycle_starter(name: str) -> Callable[[OIProtocol, bytes], None]:
    cycle = CYCLES[name]

    def start(robot: OIProtocol, args: bytes) -> None:
        robot._settle_far()  # a cycle reads the far sensors every step, from its first
        robot.builtin = cycle(name, robot.time, robot._rng)
        robot.event("builtin", name)

    return start


#: what each command does beyond its mode change, by the opcode table's names
_HANDLERS_BY_NAME: dict[str, Callable[[OIProtocol, bytes], None]] = {
    "reset": OIProtocol._on_reset,
    "start": OIProtocol._on_start,
    "baud": OIProtocol._on_baud,
    "power": OIProtocol._on_power,
    "drive": OIProtocol._on_drive,
    "motors": OIProtocol._on_motors,
    "leds": OIProtocol._on_leds,
    "song": OIProtocol._on_song,
    "play": OIProtocol._on_play,
    "sensors": OIProtocol._on_sensors,
    "pwm_motors": OIProtocol._on_pwm_motors,
    "drive_direct": OIProtocol._on_drive_direct,
    "drive_pwm": OIProtocol._on_drive_pwm,
    "stream": OIProtocol._on_stream,
    "query_list": OIProtocol._on_query_list,
    "pause_resume_stream": OIProtocol._on_pause_resume,
    "scheduling_leds": OIProtocol._on_scheduling_leds,
    "digit_leds_raw": OIProtocol._on_digits,
    "digit_leds_ascii": OIProtocol._on_digits,
    "buttons": OIProtocol._on_buttons,
    "schedule": _on_schedule,
    "set_day_time": _on_day_time,
    "stop": OIProtocol._on_stop,
}
_HANDLERS = {COMMANDS_BY_NAME[name].opcode: h for name, h in _HANDLERS_BY_NAME.items()}
# Spot, Clean, Max, Seek Dock: each starts the cycle of its name
_HANDLERS |= {
    c.opcode: _cycle_starter(c.name) for c in COMMANDS.values() if c.effect is Effect.BUILTIN_CYCLE
}

assert set(_HANDLERS) <= set(COMMANDS), "a handler for an opcode the table does not have"
