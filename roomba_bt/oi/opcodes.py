"""The opcode table: every command of both OI specifications, defined once.

Each entry names the command's data bytes (fixed arguments with their wire type and range, or
a variable tail), the OI modes that accept it, the mode it leads to, what else it does to the
link (its :class:`Effect`: a built-in cycle, stream control, a sensor reply, a baud change, the
OI going quiet), the robot profiles that have it, the actuator "channel" it drives and its
:class:`Delivery`: a state (two on one channel in one tick: the last wins) or an event (each
one is sent, in order). The encoder, the mode model, the
connection, the mission validator and the simulator read it; none of them names an opcode by
number for what it does.

Wire types (all big-endian)::

    B  unsigned byte      [0..255]
    b  signed byte        [-128..127], two's complement
    H  unsigned 16 bit    [high][low]
    h  signed 16 bit      [high][low], two's complement
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from roomba_bt.oi.modes import ALL_MODES, DRIVING_MODES, OPEN_MODES, OIMode
from roomba_bt.oi.packets import VALID_PACKET_IDS

ALL_PROFILES: frozenset[str] = frozenset({"create2", "roomba600", "roomba500"})
NEW_PROFILES: frozenset[str] = frozenset({"create2", "roomba600"})


@dataclass(frozen=True, slots=True)
class ArgSpec:
    """One fixed data argument of a command.

    ``choices``, when set, narrows ``minimum..maximum`` to the listed values (a packet id must
    be one the robot knows, not any byte)."""

    name: str
    code: str  # struct code: B, b, H, h
    minimum: int
    maximum: int
    unit: str = ""
    doc: str = ""
    choices: frozenset[int] | None = None

    @property
    def size(self) -> int:
        return 2 if self.code in "Hh" else 1

    def accepts(self, value: int) -> bool:
        if not self.minimum <= value <= self.maximum:
            return False
        return self.choices is None or value in self.choices

    @property
    def allowed(self) -> str:
        """What is allowed, in words, for error messages."""
        if self.choices is not None:
            return f"one of {_ranges(self.choices)}"
        unit = f" {self.unit}" if self.unit and self.unit not in ("bits", "ASCII") else ""
        return f"in {self.minimum}..{self.maximum}{unit}"


def _ranges(values: frozenset[int]) -> str:
    """``{0, 1, 2, 3, 7, 100}`` -> ``"0-3, 7, 100"``."""
    runs: list[list[int]] = []
    for v in sorted(values):
        if runs and v == runs[-1][1] + 1:
            runs[-1][1] = v
        else:
            runs.append([v, v])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs)


@dataclass(frozen=True, slots=True)
class TailSpec:
    """The variable-length tail of Song (140), Stream (148) and Query List (149).

    ``count_arg`` names the fixed argument that says how many items follow; each item is
    ``item`` (one or more byte arguments). The robot waits for exactly
    ``count x len(item)`` bytes, so the encoder and the simulator both read it from here::

        Song        [140][number][length=N][note 1][duration 1]...[note N][duration N]
        Stream      [148][N][id 1]...[id N]
        Query List  [149][N][id 1]...[id N]
    """

    count_arg: str
    item: tuple[ArgSpec, ...]

    @property
    def bytes_per_item(self) -> int:
        return sum(a.size for a in self.item)


class Effect(enum.Enum):
    """What a command does besides its mode change (``leads_to``) and its actuator channel.

    The connection and the simulator act on these; a command has at most one."""

    #: Spot (134), Clean (135), Max (136), Seek Dock (143): the robot's own cycle drives it
    #: while the OI stays in Passive (where Drive is refused) until the cycle ends there, or
    #: until a command that takes the OI out of Passive (:attr:`CommandSpec.ends_cycle`).
    BUILTIN_CYCLE = "builtin_cycle"
    #: Stream (148) ``[148][n][id 1]...[id n]``: a frame of these packets every 15 ms from
    #: now on, replacing the stream before; n = 0 stops it.
    STREAM = "stream"
    #: Pause/Resume Stream (150) ``[150][0]`` pauses, ``[150][1]`` resumes the last list.
    PAUSE_RESUME = "pause_resume"
    #: Sensors (142), Query List (149): one reply of the packets' data, no header, no checksum
    #: (while a stream runs it cannot be told apart from the stream).
    QUERY = "query"
    #: Baud (129): the robot changes its rate; the host waits 100 ms and follows.
    BAUD = "baud"
    #: Reset (7), Stop (173): the OI stops; streams end and the robot answers nothing but
    #: Start (and Reset).
    SILENCES = "silences"
    #: Power (133): the robot powers down (sleeps) until a button or the BRC pin wakes it.
    POWER_DOWN = "power_down"


class Delivery(enum.Enum):
    """How the per-tick batching (``robot.interface.Outbox``) treats several of a command in
    one tick. Data of the table, so that the batcher names no opcode."""

    #: The command sets a state of its channel (the wheels' speed, the LEDs, the stream's
    #: list): a later one in the same tick makes the earlier one moot, so the last one wins.
    STATE = "state"
    #: The command is something that happens (a song played, a button pressed, a song
    #: defined, a mode change, a query): dropping one changes what the robot does, so each
    #: one is sent, in the order queued.
    EVENT = "event"


#: The actuator channels whose commands set a lasting state (:attr:`CommandSpec.sets_state`).
STATE_CHANNELS = frozenset({"wheels", "motors", "leds", "scheduling_leds", "digits"})


@dataclass(frozen=True, slots=True)
class CommandSpec:
    """One OI command (opcode)."""

    opcode: int
    name: str
    title: str
    args: tuple[ArgSpec, ...]
    modes: frozenset[OIMode]
    leads_to: OIMode | None
    profiles: frozenset[str]
    channel: str | None = None
    variable: str | None = None  # description of a variable-length tail, if any
    doc: str = ""
    tail: TailSpec | None = None
    effect: Effect | None = None
    #: the batcher's rule for several in one tick (:class:`Delivery`); every STATE command
    #: has a channel (the one the last one wins on)
    delivery: Delivery = Delivery.EVENT

    @property
    def fixed_data_bytes(self) -> int:
        return sum(a.size for a in self.args)

    def tail_bytes(self, args: tuple[int, ...] | list[int]) -> int:
        """Bytes that must follow the fixed arguments ``args`` (0 for fixed-size commands)."""
        if self.tail is None:
            return 0
        index = [a.name for a in self.args].index(self.tail.count_arg)
        return args[index] * self.tail.bytes_per_item

    def data_bytes(self, args: tuple[int, ...] | list[int]) -> int:
        """All data bytes after the opcode, given the fixed arguments."""
        return self.fixed_data_bytes + self.tail_bytes(args)

    @property
    def is_actuator(self) -> bool:
        """Actuator commands are the ones only Safe and Full accept."""
        return self.modes == DRIVING_MODES

    @property
    def drives_wheels(self) -> bool:
        """A wheel command of the host's own: Drive (137), Drive Direct (145), Drive PWM
        (146), accepted in Safe and Full (a built-in cycle's wheels are the firmware's)."""
        return self.channel == "wheels" and self.is_actuator

    @property
    def sets_state(self) -> bool:
        """An actuator command whose effect lasts and is the same when sent again (the
        wheels, motors, LEDs and digits): a pause's resume sends these again. Play (141) and
        Buttons (165) are events (sent again, a song plays twice, a button is pressed twice),
        and a built-in cycle (Clean, Seek Dock) starts over and changes the mode."""
        return self.channel in STATE_CHANNELS and self.leads_to is None

    @property
    def changes_mode(self) -> bool:
        return self.leads_to is not None

    @property
    def ends_cycle(self) -> bool:
        """A built-in cycle has certainly ended after this command: it takes the OI to Safe or
        Full (the host takes the wheels) or to Off (the OI stops). Start (128) and the cycles
        themselves lead to Passive, where a cycle may still drive."""
        return self.leads_to is not None and self.leads_to is not OIMode.PASSIVE

    def cycle_may_run_after(self, before: bool) -> bool:
        """Whether a built-in cycle may be driving the robot once this command is written;
        ``before``: whether one could before it. A cycle command starts one; a command that
        :attr:`ends_cycle` ends it; any other leaves it as it was (Start too: Passive is
        where the cycle drives). The one rule of the session's writer and the tests' stub."""
        if self.effect is Effect.BUILTIN_CYCLE:
            return True
        return before and not self.ends_cycle


def _c(
    opcode: int,
    name: str,
    title: str,
    args: tuple[ArgSpec, ...] = (),
    *,
    modes: frozenset[OIMode] = OPEN_MODES,
    leads_to: OIMode | None = None,
    profiles: frozenset[str] = ALL_PROFILES,
    channel: str | None = None,
    variable: str | None = None,
    doc: str = "",
    tail: TailSpec | None = None,
    effect: Effect | None = None,
    delivery: Delivery | None = None,
) -> CommandSpec:
    """One table row; ``delivery`` is STATE for a command with a channel unless the row says
    EVENT (Play, Buttons), EVENT for the rest."""
    if delivery is None:
        delivery = Delivery.STATE if channel is not None else Delivery.EVENT
    return CommandSpec(
        opcode, name, title, args, modes, leads_to, profiles, channel, variable, doc, tail,
        effect, delivery,
    )  # fmt: skip


def _u8(name: str, lo: int = 0, hi: int = 255, unit: str = "", doc: str = "") -> ArgSpec:
    return ArgSpec(name, "B", lo, hi, unit, doc)


def _packet_id() -> ArgSpec:
    """A packet id of Sensors (142), Query List (149) and Stream (148): single packets 7-58
    and the groups 0-6, 100, 101, 106, 107 (the packet table's ids). 102-105 are named by
    neither spec: refused."""
    return ArgSpec(
        "packet_id", "B", 0, max(VALID_PACKET_IDS), "", "sensor packet or group id",
        VALID_PACKET_IDS,
    )  # fmt: skip


VELOCITY = ArgSpec("velocity", "h", -500, 500, "mm/s", "average wheel velocity")
RADIUS = ArgSpec("radius", "h", -2000, 2000, "mm", "turn radius; 0x8000/0x7FFF straight, -1/1 spin")

#: Song (140) and Play (141): the slot (0-4, though the text says "up to four songs"), the
#: song's length in notes and each note, a MIDI number and a duration. Named here, as the
#: encoder's ``song`` and the mission language's ``song`` leaf check the same ranges.
SONG_NUMBER = _u8("song_number", 0, 4)
SONG_LENGTH = _u8("song_length", 1, 16)
NOTE_NUMBER = _u8("note_number", 0, 255, "MIDI")
NOTE_DURATION = _u8("note_duration", 0, 255, "1/64 s")
#: the notes the robot plays (both specs: "the lowest musical note that Roomba will play is
#: Note #31"; G1 to G9). Any other byte of ``NOTE_NUMBER`` is a rest: no sound for its
#: duration, the spec's own meaning, so the encoder sends it as it is
PLAYABLE_NOTES = range(31, 128)
#: a note's duration is counted in 1/64 s (a half-second note is 32)
NOTE_STEPS_PER_SECOND = 64

#: Schedule (167)'s 14 time bytes: hour then minute, Sunday first.
_SCHEDULE_TIMES: tuple[ArgSpec, ...] = tuple(
    arg
    for day in ("sun", "mon", "tue", "wed", "thu", "fri", "sat")
    for arg in (_u8(f"{day}_hour", 0, 23, "h"), _u8(f"{day}_minute", 0, 59, "min"))
)

_COMMAND_LIST: tuple[CommandSpec, ...] = (
    _c(7, "reset", "Reset", modes=ALL_MODES, leads_to=OIMode.OFF, profiles=NEW_PROFILES,
       effect=Effect.SILENCES,
       doc="Resets the robot as if the battery were reinserted; it prints a banner."),
    _c(128, "start", "Start", modes=ALL_MODES, leads_to=OIMode.PASSIVE,
       doc="Starts the OI; the only way out of Off. Also the way back to Passive."),
    _c(129, "baud", "Baud", (_u8("baud_code", 0, 11),), effect=Effect.BAUD,
       doc="Changes the baud rate; wait 100 ms before sending at the new rate."),
    _c(130, "control", "Control", leads_to=OIMode.SAFE, doc="Identical to Safe (131)."),
    _c(131, "safe", "Safe", leads_to=OIMode.SAFE),
    _c(132, "full", "Full", leads_to=OIMode.FULL),
    _c(133, "power", "Power", leads_to=OIMode.PASSIVE, effect=Effect.POWER_DOWN,
       doc="Powers the robot down."),
    _c(134, "spot", "Spot", leads_to=OIMode.PASSIVE, channel="wheels",
       effect=Effect.BUILTIN_CYCLE),
    _c(135, "clean", "Clean", leads_to=OIMode.PASSIVE, channel="wheels",
       effect=Effect.BUILTIN_CYCLE),
    _c(136, "max", "Max", leads_to=OIMode.PASSIVE, channel="wheels",
       effect=Effect.BUILTIN_CYCLE),
    _c(137, "drive", "Drive", (VELOCITY, RADIUS), modes=DRIVING_MODES, channel="wheels"),
    _c(138, "motors", "Motors", (_u8("motor_bits", 0, 31, "bits"),),
       modes=DRIVING_MODES, channel="motors"),
    _c(139, "leds", "LEDs",
       (_u8("led_bits", 0, 255, "bits"), _u8("power_color"), _u8("power_intensity")),
       modes=DRIVING_MODES, channel="leds"),
    _c(140, "song", "Song", (SONG_NUMBER, SONG_LENGTH),
       variable="song_length x (note 0-255, duration 0-255 in 1/64 s)",
       doc=f"Defines a song; notes outside {PLAYABLE_NOTES[0]}-{PLAYABLE_NOTES[-1]} are rests.",
       tail=TailSpec("song_length", (NOTE_NUMBER, NOTE_DURATION))),
    _c(141, "play", "Play", (SONG_NUMBER,), modes=DRIVING_MODES, channel="speaker",
       delivery=Delivery.EVENT),
    _c(142, "sensors", "Sensors", (_packet_id(),), effect=Effect.QUERY,
       doc="Asks for one packet or group; the reply has no header and no checksum."),
    _c(143, "seek_dock", "Seek Dock", leads_to=OIMode.PASSIVE, channel="wheels",
       effect=Effect.BUILTIN_CYCLE),
    _c(144, "pwm_motors", "PWM Motors",
       (ArgSpec("main_brush_pwm", "b", -127, 127), ArgSpec("side_brush_pwm", "b", -127, 127),
        ArgSpec("vacuum_pwm", "b", 0, 127)),
       modes=DRIVING_MODES, channel="motors"),
    _c(145, "drive_direct", "Drive Direct",
       (ArgSpec("right_velocity", "h", -500, 500, "mm/s"),
        ArgSpec("left_velocity", "h", -500, 500, "mm/s")),
       modes=DRIVING_MODES, channel="wheels"),
    _c(146, "drive_pwm", "Drive PWM",
       (ArgSpec("right_pwm", "h", -255, 255), ArgSpec("left_pwm", "h", -255, 255)),
       modes=DRIVING_MODES, channel="wheels"),
    _c(148, "stream", "Stream", (_u8("packet_count", 0, 255),),
       variable="packet_count packet ids", channel="stream", effect=Effect.STREAM,
       doc="Starts a stream of the listed packets every 15 ms. A count of 0 is not described "
           "by either spec (peers send it to stop); prefer Pause/Resume Stream (150).",
       tail=TailSpec("packet_count", (_packet_id(),))),
    _c(149, "query_list", "Query List", (_u8("packet_count", 1, 255),),
       variable="packet_count packet ids", tail=TailSpec("packet_count", (_packet_id(),)),
       effect=Effect.QUERY),
    _c(150, "pause_resume_stream", "Pause/Resume Stream", (_u8("stream_state", 0, 1),),
       channel="stream", effect=Effect.PAUSE_RESUME),
    _c(162, "scheduling_leds", "Scheduling LEDs",
       (_u8("weekday_bits", 0, 255, "bits"), _u8("scheduling_bits", 0, 255, "bits")),
       modes=DRIVING_MODES, channel="scheduling_leds"),
    _c(163, "digit_leds_raw", "Digit LEDs Raw",
       tuple(_u8(f"digit_{n}_bits", 0, 255, "bits") for n in (3, 2, 1, 0)),
       modes=DRIVING_MODES, channel="digits",
       doc="Does not work on Create 2 / Roomba 600 firmware (Appendix B)."),
    _c(164, "digit_leds_ascii", "Digit LEDs ASCII",
       tuple(_u8(f"digit_{n}_ascii", 32, 126, "ASCII") for n in (3, 2, 1, 0)),
       modes=DRIVING_MODES, channel="digits"),
    _c(165, "buttons", "Buttons", (_u8("button_bits", 0, 255, "bits"),), channel="buttons",
       delivery=Delivery.EVENT, doc="Presses buttons; they release after 1/6 s."),
    _c(167, "schedule", "Schedule",
       (_u8("day_bits", 0, 127, "bits"), *_SCHEDULE_TIMES)),
    _c(168, "set_day_time", "Set Day/Time",
       (_u8("day", 0, 6), _u8("hour", 0, 23, "h"), _u8("minute", 0, 59, "min"))),
    _c(173, "stop", "Stop", leads_to=OIMode.OFF, profiles=NEW_PROFILES,
       effect=Effect.SILENCES,
       doc="Stops the OI: streams stop and the robot answers nothing until Start."),
)  # fmt: skip

COMMANDS: Mapping[int, CommandSpec] = MappingProxyType({c.opcode: c for c in _COMMAND_LIST})
COMMANDS_BY_NAME: Mapping[str, CommandSpec] = MappingProxyType({c.name: c for c in _COMMAND_LIST})

#: Commands that change the OI mode, by the mode they lead to (the mode model's triggers).
MODE_COMMANDS: tuple[CommandSpec, ...] = tuple(c for c in _COMMAND_LIST if c.leads_to is not None)


def longest_data_bytes() -> int:
    """The most data bytes any opcode byte can leave the robot's parser waiting for: a
    command's fixed arguments and, for a tail, as many items as its count byte can say at
    most on the wire (255, whatever range the table allows: a lost byte does not respect
    it). Song (140) of 255 notes waits 512 bytes. Zeros this many end any command a lost or
    changed byte made the robot start (0 is no opcode: the zeros left over are skipped),
    however long (``robot/ending.py``'s stop written again)."""
    longest = 0
    for spec in _COMMAND_LIST:
        data = spec.fixed_data_bytes
        if spec.tail is not None:
            count = next(a for a in spec.args if a.name == spec.tail.count_arg)
            data += ((1 << 8 * count.size) - 1) * spec.tail.bytes_per_item
        longest = max(longest, data)
    return longest


def opcodes(*names: str) -> tuple[int, ...]:
    """The opcodes of the commands named (``opcodes("drive", "drive_direct")`` -> ``(137,
    145)``): for a reader's list of what it sends, without the numbers. A name the table does
    not have raises KeyError when the reader is defined."""
    return tuple(COMMANDS_BY_NAME[name].opcode for name in names)
