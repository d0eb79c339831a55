"""Robot profiles: every difference between the Roomba 500, Roomba 600 and Create 2.

A difference is a field here, never an ``if`` elsewhere. Each decision is explained in
``docs/protocol.md``; the short form:

* ``checksum_includes_header``: the 600/Create 2 spec sums the header 19 into the stream
  checksum (``19+5+29+2+25+13+0+163 = 256``); the 500 spec's worked example leaves it out
  (``5+29+2+25+13+0+182 = 256``) and so does its prose. The ``roomba500`` parser accepts both
  (its firmware is shared with the 600, whose spec says the opposite); the others are strict.
  What a simulated robot sends follows ``checksum_includes_header``.
* ``encoders_signed``: packets 43/44 are signed on the 600 / Create 2, unsigned on the 500.
  Odometry takes deltas modulo 2**16, so either gives the same distance.
* ``stasis_maximum``: 0-3 on the 600 (2 = stasis wheel too dirty), 0-1 on the 500.
* ``digit_leds_raw_works``: opcode 163 does not work on current firmware of any of them: the
  600 / Create 2 spec, the newer of the two, says so of "current Create 2 and Roomba 500/600
  firmware versions" (its Appendix B calls the bug open). The 500 spec describes 163 without
  that note, as the older document would; the newer one names the 500's firmware, so the
  ``roomba500`` profile warns too.
* ``has_display`` / ``buttons``: what the robot's top carries. Scheduling LEDs (162) and the
  Digit LEDs (163, 164) light "the Roomba 560 and 570" (both specs' words): the 500 series'
  clock-and-schedule panel, which the 600 series' scheduling models (650, 660) have too; the
  Create 2's top has no display and only the Clean, Spot and Dock buttons (packet 18's bits
  3-7, minute to clock, are the panel's). A mission leaf that needs the display or a panel
  button is an error at validate on a profile without it (``display_missing``,
  ``buttons_missing``); a plugin's bytes are still sent (the firmware takes them and shows
  nothing), and Digit LEDs Raw (163) keeps its warning on every profile.
* ``keeps_schedule``: Schedule (167) and Set Day/Time (168) set a clock and a weekly
  cleaning schedule that the robot keeps and its clock panel shows. Both specs list them
  for every model, the 600 spec's Appendix A "to allow full control of Roomba 600's rich
  user interface and scheduling functionality"; the Create 2's top has no clock, display or
  Schedule button, and no packet reads either back, so what a Create 2 does with them is
  written nowhere and nothing on it would show what was set. Decided: ``roomba-bt clock``
  refuses the ``create2`` profile (docs/protocol.md, "The clock and the schedule"); the
  opcode table keeps both commands on every profile, so a plugin's bytes still go out.
* ``reports_mode_plus_one``: some 600-series firmware reports OI mode + 1 in packet 35.
* ``sleeps_in_passive``: the robot sleeps after 5 minutes in Passive (keep-awake's default).
* ``slow_baud_how`` / ``slow_baud_until``: how the robot comes to talk at 19200 and what
  ends it, each spec's own procedure ("Serial Port Settings"): the 500 spec holds Clean
  "when powering on", the 600 spec "while powering off"; the 500 stays there until "the
  power is turned off", the 600 until "the processor loses battery power".
* ``power_on_bauds``: the rates the port talks at from power-on, the default first: "Baud:
  115200 or 19200" in both specs' "Serial Port Settings" (the original Create's 57600 is
  gone: the 600 spec's Appendix A, "The default baud rate has changed from 57600 to
  115200"). Any other rate of the Baud command (129), whose codes 0-11 (300 to 115200 bps,
  ``encode.BAUD_CODES``) both specs list alike, only once a host sent it, until the robot
  loses power. :meth:`RobotProfile.baud_problem` says so; ``sim --baud`` refuses such a
  rate (a simulated robot has just been powered on), ``run``/``sensors --baud`` warn.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from types import MappingProxyType

from roomba_bt.oi.bits import BUTTON_NAMES
from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.errors import UnsupportedCommandError
from roomba_bt.oi.opcodes import COMMANDS, COMMANDS_BY_NAME, CommandSpec
from roomba_bt.oi.packets import PACKETS, PacketSpec

#: Distance between the drive wheels, in mm: 235, the figure of AutonomyLab's libcreate
#: (``RobotModel::CREATE_2(V_3, 0.235, 115200, 0.5, 0.072)`` in ``src/types.cpp``), used by the
#: Create 2 ROS drivers, and PyRoombaAdapter's default ``wheel_span_mm=235.0``. Neither spec
#: text states it (the 600 spec's dimension drawing did not survive the text extraction).
WHEEL_BASE_MM = 235.0
#: Wheel diameter (mm) and encoder counts per revolution, from the 600 spec's packet 43 note.
WHEEL_DIAMETER_MM = 72.0
COUNTS_PER_REVOLUTION = 508.8

# The body, as the simulator models it and the behaviours that steer by their sensors assume
# it (one home, so the two cannot drift apart). Neither spec gives these figures; they are
# measured off a Roomba 600 / Create 2 and its light bumper's window.
#: Radius of the round body (340 mm across).
BODY_RADIUS_MM = 170.0
#: How far the omni IR receiver (on top of the bumper) is ahead of the wheels' axle.
OMNI_AHEAD_MM = 130.0
#: The light bumper's six sensors (packets 46-51: left, front left, centre left, centre right,
#: front right, right) as rays from the body's centre, degrees from the heading (CCW
#: positive), starting at the bumper and seeing this far beyond it.
LIGHT_BUMP_ANGLES_DEG = (65.0, 38.0, 12.0, -12.0, -38.0, -65.0)
LIGHT_BUMP_RANGE_MM = 150.0
#: The four cliff sensors (packets 9-12: left, front left, front right, right): points on the
#: floor this far from the body's centre, at these angles from the heading (degrees, CCW
#: positive). ``cover`` marks a drop where the sensors that saw it are.
CLIFF_SENSOR_ANGLES_DEG = (60.0, 20.0, -20.0, -60.0)
CLIFF_SENSOR_RADIUS_MM = 150.0

#: Where Baud (129) can be sent from, for advice on a robot at the wrong rate: the robot
#: layer's ``Connection.set_baud``; no ``roomba-bt`` command sends it.
SEND_BAUD = "in Python, Connection.set_baud(115200) sends Baud (129); no roomba-bt command does"

#: The rates a robot's port talks at from power-on, the default first: 115200, or 19200 after
#: the Clean-button or BRC procedure (both specs, "Serial Port Settings": "Baud: 115200 or
#: 19200"). The same on every profile; ``robot.discovery`` tries them in this order.
#: Passive without activity for this long: a robot whose profile ``sleeps_in_passive``
#: sleeps (600 spec, "Passive Mode"); keep-awake, the mode check's long waits and the
#: silence's diagnosis read this one value.
PASSIVE_SLEEP_S = 300.0
POWER_ON_BAUDS: tuple[int, ...] = (115200, 19200)

#: where both specs say the rates a robot starts at
_SERIAL_SETTINGS = '"Serial Port Settings"'

#: The stream frame's header byte (``frames.STREAM_HEADER``; frames imports this module), as
#: the sum of a frame that leaves it out of its checksum reads.
STREAM_CHECKSUM_HEADER = 19


@dataclass(frozen=True, slots=True, repr=False)
class RobotProfile:
    """What a robot model speaks; see the module docstring for each field's source.

    A shipped profile's repr is its name in the package (``roomba_bt.CREATE2``): it is the
    default of many signatures, and ``help(load_mission)`` showed its every field, the
    19200-baud sentences too, about 600 characters a signature. Another profile (one made
    with ``dataclasses.replace``) shows its fields."""

    name: str
    title: str
    checksum_includes_header: bool
    checksum_accepts_both: bool
    encoders_signed: bool
    stasis_maximum: int
    wall_signal_maximum: int
    digit_leds_raw_works: bool
    reports_mode_plus_one: bool
    #: the four-digit display and the scheduling LEDs (the module docstring)
    has_display: bool = True
    #: the buttons on its top, packet 18's names (the module docstring)
    buttons: tuple[str, ...] = BUTTON_NAMES
    #: a clock and weekly schedule of its own that 167 and 168 set (the module docstring)
    keeps_schedule: bool = True
    #: Passive sleeps after 5 minutes of inactivity (600 spec, "Passive Mode"); the 500 spec
    #: does not say, and is assumed to (a BRC pulse is harmless): the runtime keeps it awake.
    sleeps_in_passive: bool = True
    default_baud: int = POWER_ON_BAUDS[0]
    #: the rates its port talks at from power-on (the module docstring)
    power_on_bauds: tuple[int, ...] = POWER_ON_BAUDS
    wheel_base_mm: float = WHEEL_BASE_MM
    max_velocity_mm_s: int = 500
    max_radius_mm: int = 2000
    all_sensors_group: int = 100
    #: how it comes to talk at 19200 (its spec's "Serial Port Settings"), and what ends it
    slow_baud_how: str = (
        "its Clean button was held while it powered off, until a descending tune, or three "
        "BRC pulses 2 s after power-on"
    )
    slow_baud_until: str = (
        "until its processor loses battery power (take the battery out) or Baud (129) sets "
        "another rate"
    )

    def __repr__(self) -> str:
        shipped = _SHIPPED_NAMES.get(self.name)
        if shipped is not None and PROFILES.get(self.name) == self:
            return f"roomba_bt.{shipped}"
        fields = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in dataclass_fields(self))
        return f"RobotProfile({fields})"

    @property
    def at_19200(self) -> str:
        """How this robot comes to talk at 19200 and what brings it back, in a sentence."""
        return at_19200_of((self,))

    @property
    def baud_command_rates(self) -> tuple[int, ...]:
        """The rates Baud (129) can set (codes 0-11 of the opcode's argument, the same
        table in both specs), slowest first."""
        return tuple(sorted(BAUD_CODES))

    def baud_problem(self, rate: int) -> str | None:
        """Why this robot would not be talking at ``rate`` when a host opens its port, or
        None for a rate it talks at from power-on: ``the Roomba 600 series talks at 115200
        or 19200 from power-on (its OI spec, "Serial Port Settings"); 57600 only once a Baud
        (129) command has set it, until it loses power``."""
        if rate in self.power_on_bauds:
            return None
        rates = " or ".join(str(r) for r in self.power_on_bauds)
        said = f"the {self.title} talks at {rates} from power-on (its OI spec, {_SERIAL_SETTINGS})"
        if rate not in self.baud_command_rates:
            listed = ", ".join(str(r) for r in self.baud_command_rates)
            return f"{said}; {rate} is no rate of the OI at all (Baud (129) sets {listed})"
        return f"{said}; {rate} only once a Baud (129) command has set it, until it loses power"

    @property
    def checksum_sums(self) -> frozenset[int]:
        """The low bytes of a whole stream frame's sum (header included) that this robot's
        checksum gives: 0 when it covers the header 19, 19 when it leaves it out, both on
        the ``roomba500`` (``checksum_accepts_both``)."""
        if self.checksum_accepts_both:
            return frozenset((0, STREAM_CHECKSUM_HEADER))
        return frozenset((0 if self.checksum_includes_header else STREAM_CHECKSUM_HEADER,))

    def has_command(self, command: CommandSpec | int | str) -> bool:
        spec = _lookup(command)
        return self.name in spec.profiles

    def check_supported(self, command: CommandSpec | int | str) -> None:
        """Raise :class:`UnsupportedCommandError` if this robot does not have ``command``
        (Reset 7 and Stop 173 exist only on the 600 / Create 2)."""
        spec = _lookup(command)
        if self.name not in spec.profiles:
            raise UnsupportedCommandError(spec.name, self.name, tuple(sorted(spec.profiles)))

    def command_unavailable(self, command: CommandSpec | int | str) -> str | None:
        """Why this robot cannot be sent ``command`` (``reset (7) is not available on the
        Roomba 500 series (roomba500); it exists on create2, roomba600``), or ``None``: the
        500 spec has no Reset (7) or Stop (173), so what a 500 does with their bytes is not
        written anywhere. What validation reports at the node that declares it."""
        spec = _lookup(command)
        if self.name in spec.profiles:
            return None
        return (
            f"{spec.name} ({spec.opcode}) is not available on the {self.title} ({self.name}); "
            f"it exists on {', '.join(sorted(spec.profiles))}"
        )

    def display_missing(self) -> str | None:
        """Why this robot shows nothing of Scheduling LEDs (162) and Digit LEDs (164), or
        None: what validate says at a leaf that needs the display (``Declaration.needs``)."""
        if self.has_display:
            return None
        return (
            f"the {self.title} ({self.name}) has no digit display or scheduling LEDs: they are "
            "the clock panel of the Roomba 500 and 600 series (roomba500, roomba600)"
        )

    def clock_missing(self) -> str | None:
        """Why this robot keeps no clock or schedule that Set Day/Time (168) and Schedule
        (167) would set, or None: what ``roomba-bt clock`` refuses with."""
        if self.keeps_schedule:
            return None
        return (
            f"the {self.title} ({self.name}) keeps no clock or cleaning schedule to set: its "
            "top has no clock, display or Schedule button and no sensor packet reads them "
            "back, so nothing would show what was set; Schedule (167) and Set Day/Time (168) "
            "set the clock panel of the Roomba 500 and 600 series (roomba500, roomba600)"
        )

    def buttons_missing(self, names: Iterable[str]) -> str | None:
        """Which of ``names`` (packet 18's) this robot's top lacks, said, or None."""
        missing = [name for name in names if name not in self.buttons]
        if not missing:
            return None
        return (
            f"the {self.title} ({self.name}) has no {' or '.join(missing)} button: its buttons "
            f"are {', '.join(self.buttons)}; the others are the clock panel of the Roomba 500 "
            "and 600 series (roomba500, roomba600)"
        )

    def command_warning(self, command: CommandSpec | int | str) -> str | None:
        """A sentence to log before sending ``command`` to this robot, or ``None``.

        Only Digit LEDs Raw (163) has one: the 600 / Create 2 spec says it does not work on
        current Create 2 and Roomba 500/600 firmware. It is still sent (a user may have
        firmware where it works); the robot layer logs this so that a blank display is
        explained."""
        spec = _lookup(command)
        if spec.opcode == 163 and not self.digit_leds_raw_works:
            return (
                f"digit_leds_raw (163) does not work on current {self.title} firmware (the "
                "Roomba 600 / Create 2 OI spec: 'This opcode does not work in current Create 2 "
                "and Roomba 500/600 firmware versions'; its Appendix B: 'LEDs Raw: open'); the "
                f"display may stay blank. {self._digits_instead}"
            )
        return None

    @property
    def _digits_instead(self) -> str:
        """What to use instead of Digit LEDs Raw (163), which every profile warns of."""
        if self.has_display:
            return (
                "Use Digit LEDs ASCII (164) instead: the mission behaviour display "
                '(display: "hi!") sends it'
            )
        return (
            f"The {self.title} has no digit display at all: Digit LEDs ASCII (164), the mission "
            "behaviour display, lights the Roomba 500 and 600 series' one"
        )

    @property
    def commands(self) -> tuple[CommandSpec, ...]:
        return tuple(c for c in COMMANDS.values() if self.name in c.profiles)

    def packet(self, packet_id: int) -> PacketSpec:
        """The packet table entry as this robot reports it."""
        return self.packets[packet_id]

    @property
    def packets(self) -> Mapping[int, PacketSpec]:
        return _PROFILE_PACKETS[self.name]


def at_19200_of(profiles: Iterable[RobotProfile]) -> str:
    """How each of ``profiles`` comes to talk at 19200 and what brings it back: a sentence a
    procedure, the models that share one named together (``on the iRobot Create 2 or Roomba
    600 series, 19200 comes after ...``), as doctor says it of the models it could not tell
    apart: the Create 2's sentence and the 600's, word for word the same, were said twice."""
    ways: dict[tuple[str, str], list[str]] = {}
    for profile in profiles:
        ways.setdefault((profile.slow_baud_how, profile.slow_baud_until), []).append(profile.title)
    return "; ".join(
        f"on the {' or '.join(titles)}, 19200 comes after {how}, and lasts {until}"
        for (how, until), titles in ways.items()
    )


def _lookup(command: CommandSpec | int | str) -> CommandSpec:
    if isinstance(command, CommandSpec):
        return command
    try:
        return COMMANDS[command] if isinstance(command, int) else COMMANDS_BY_NAME[command]
    except KeyError:
        raise KeyError(f"no OI command is called {command!r}") from None


def command_warning(command: CommandSpec | int | str, profile: RobotProfile) -> str | None:
    """Module-level spelling of :meth:`RobotProfile.command_warning`."""
    return profile.command_warning(command)


CREATE2 = RobotProfile(
    name="create2",
    title="iRobot Create 2",
    checksum_includes_header=True,
    checksum_accepts_both=False,
    encoders_signed=True,
    stasis_maximum=3,
    wall_signal_maximum=1023,
    digit_leds_raw_works=False,
    reports_mode_plus_one=False,
    has_display=False,
    buttons=("clean", "spot", "dock"),
    keeps_schedule=False,
)
#: The Roomba 600 speaks the Create 2's OI; the differences are the mode + 1 firmware bug and
#: the clock panel (display, scheduling LEDs, its buttons) of its scheduling models.
ROOMBA600 = replace(
    CREATE2,
    name="roomba600",
    title="Roomba 600 series",
    reports_mode_plus_one=True,
    has_display=True,
    buttons=BUTTON_NAMES,
    keeps_schedule=True,
)
ROOMBA500 = RobotProfile(
    name="roomba500",
    title="Roomba 500 series",
    checksum_includes_header=False,
    checksum_accepts_both=True,
    encoders_signed=False,
    stasis_maximum=1,
    wall_signal_maximum=4095,
    digit_leds_raw_works=False,
    reports_mode_plus_one=False,
    slow_baud_how=(
        "its Clean button was held while it powered on, until a descending tune, or three "
        "BRC pulses 2 s after power-on"
    ),
    slow_baud_until=(
        "until it is powered off or its battery is taken out, or Baud (129) sets another rate"
    ),
)

PROFILES: Mapping[str, RobotProfile] = MappingProxyType(
    {p.name: p for p in (CREATE2, ROOMBA600, ROOMBA500)}
)
DEFAULT_PROFILE = CREATE2
#: the name each shipped profile has in the package, which its repr says
_SHIPPED_NAMES = {"create2": "CREATE2", "roomba600": "ROOMBA600", "roomba500": "ROOMBA500"}


def _packets_for(profile: RobotProfile) -> Mapping[int, PacketSpec]:
    table = dict(PACKETS)
    for pid in (43, 44):
        spec = table[pid]
        if profile.encoders_signed:
            table[pid] = replace(spec, signed=True, minimum=-32768, maximum=32767)
        else:
            table[pid] = replace(spec, signed=False, minimum=0, maximum=65535)
    table[58] = replace(table[58], maximum=profile.stasis_maximum)
    table[27] = replace(table[27], maximum=profile.wall_signal_maximum)
    return MappingProxyType(table)


_PROFILE_PACKETS: Mapping[str, Mapping[int, PacketSpec]] = MappingProxyType(
    {p.name: _packets_for(p) for p in (CREATE2, ROOMBA600, ROOMBA500)}
)


def get_profile(name: str) -> RobotProfile:
    """The profile called ``name``; a clear error lists the known ones."""
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(
            f"unknown robot profile {name!r}; known profiles: {', '.join(PROFILES)}"
        ) from None


def profile_given(profile: RobotProfile | str | None, caller: str) -> RobotProfile:
    """The model a public function was given as ``profile=``: a :class:`RobotProfile`, its
    name (``"roomba500"``, as ``configured_profile()``'s answer gives it), or None, which is
    ``create2`` as no argument is (docs/robot.md, Which robot: the library reads no setting
    of the command line's). One rule for every entry that takes a model (the mission
    functions, ``Connection``, ``Connection.open``, ``RunStack``, ``Simulator``), so each
    takes the same spellings: ``profile=None`` was an internal error inside a mission's
    diagnostics, a name the same with 'str', and ``RunStack(..., profile="create2")`` an
    AttributeError ('str' object has no attribute 'name'). Anything else is refused naming
    ``caller``."""
    if profile is None:
        return CREATE2
    if isinstance(profile, RobotProfile):
        return profile
    known = ", ".join(PROFILES)
    if isinstance(profile, str):
        if profile == "auto":  # the command line's, which identifies the robot on its port
            raise ValueError(
                f"{caller}(profile='auto'): 'auto' names no model here (the command line "
                "identifies the robot on its port first: "
                f"roomba_bt.robot.discovery.identify_robot); give one of {known}"
            )
        try:
            return get_profile(profile)
        except ValueError as exc:
            raise ValueError(f"{caller}(profile={profile!r}): {exc}") from None
    raise TypeError(
        f"{caller}(profile=...) takes a RobotProfile (roomba_bt.CREATE2, ...), a profile's "
        f"name ({known}) or None, not {type(profile).__name__}"
    )
