"""The condition library: SUCCESS or FAILURE from this tick's sensor frame, never RUNNING.

Each condition reads only the packets it declares (so the stream asks for exactly those) and
decodes them through the typed views of :class:`~roomba_bt.oi.frames.SensorFrame` (packet 7
bit 0 is bump RIGHT, bit 1 bump LEFT; packet 14 bit 3 right wheel, bit 4 left wheel, ...).
Those whose result depends on nothing else (not the mode, the odometry or the blackboard) say
so with ``frame_pure``: a ``while``/``until`` guard made of them is not re-ticked while those
packets keep their values (:class:`~roomba_bt.behaviours.declare.FrameInputs`).
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import replace
from operator import attrgetter
from types import MappingProxyType
from typing import Any, ClassVar

from roomba_bt.behaviours.base import Condition
from roomba_bt.behaviours.blackboard import BlackboardRef, UnwrittenKey, declared_type, read_key
from roomba_bt.behaviours.declare import Comparison, Param, declare
from roomba_bt.behaviours.units import (
    ANGLE,
    ANY,
    CANONICAL,
    DISTANCE,
    INT,
    MARK,
    PERCENT,
    STR,
    UnitError,
    ValueType,
    described,
    enum,
    miswritten,
    shown,
)
from roomba_bt.oi.bits import (
    BUTTON_NAMES,
    CYCLE_BUTTONS,
    LIGHT_BUMPER_NAMES,
    ChargingState,
    Stasis,
)
from roomba_bt.oi.frames import (
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CHARGING_STATE_PACKETS,
    CLIFF_PACKETS,
    ENCODER_PACKETS,
    IR_PACKETS,
    LIGHT_BUMP_SIGNAL_PACKETS,
    LIGHT_BUMPER_PACKETS,
    VIRTUAL_WALL_PACKETS,
    SensorFrame,
)
from roomba_bt.oi.ir import REMOTE_BUTTONS, IRCharacter
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.oi.packets import PACKETS, PACKETS_BY_NAME, PacketSpec, packet_ids
from roomba_bt.oi.profiles import PROFILES, RobotProfile
from roomba_bt.robot.interface import Odometry, Snapshot
from roomba_bt.yamlsource import quoted

OPERATORS: dict[str, Callable[[Any, Any], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    "==": operator.eq,
    "!=": operator.ne,
    ">=": operator.ge,
    ">": operator.gt,
}


Flags = Mapping[str, Callable[[SensorFrame], bool]]


def _flags(view: str, names: Iterable[str], prefix: str = "", either: str = "any") -> Flags:
    """A flag condition's choices, in order, each with how it reads the frame: each of
    ``names``, the flag ``prefix`` + name of the frame's decoded ``view``; then ``any``, the
    view's flag ``either`` (the union it stores)."""
    flags = {name: attrgetter(f"{view}.{prefix}{name}") for name in names}
    return MappingProxyType({**flags, "any": attrgetter(f"{view}.{either}")})


_BUMP = _flags("bumps", ("left", "right"), "bump_", "any_bump")
_WHEEL_DROP = _flags("bumps", ("left", "right"), "wheel_drop_", "any_wheel_drop")
_OVERCURRENT = _flags("overcurrents", ("left_wheel", "right_wheel", "main_brush", "side_brush"))
_BUTTON = _flags("buttons", BUTTON_NAMES)


class _Flag(Condition):
    """One flag of a packet's decoded view (:mod:`roomba_bt.oi.bits`): the one the
    parameter :attr:`choice` names, or ``any``."""

    frame_pure = True

    #: the parameter naming the flag, and how each of its values reads it (:func:`_flags`)
    choice: ClassVar[str]
    flags: ClassVar[Flags]

    def __init__(self, name: str, params: Mapping[str, Any] | None = None) -> None:
        super().__init__(name, params)
        choice = self.params[self.choice]
        #: how it reads the flag, looked up once unless the choice is an @key value
        self._read = None if isinstance(choice, BlackboardRef) else self.flags[choice]

    def check(self, snapshot: Snapshot) -> bool:
        read = self._read
        if read is None:
            read = self.flags[self.value(self.choice)]
        return read(snapshot.frame)


@declare("bump", kind="condition", params=(Param("side", enum(*_BUMP), default="any"),),
         reads=BUMPS_PACKETS, primary="side")  # fmt: skip
class Bump(_Flag):
    """A bumper is pressed (packet 7: bit 0 right, bit 1 left)."""

    choice, flags = "side", _BUMP


@declare("wheel_drop", kind="condition",
         params=(Param("side", enum(*_WHEEL_DROP), default="any"),),
         reads=BUMPS_PACKETS, primary="side")  # fmt: skip
class WheelDrop(_Flag):
    """A wheel has dropped, as when the robot is lifted or a wheel goes over an edge (packet
    7: bit 2 right, bit 3 left)."""

    choice, flags = "side", _WHEEL_DROP


_CLIFFS = dict(zip(("left", "front_left", "front_right", "right"), CLIFF_PACKETS, strict=True))


def _cliff_reads(params: Mapping[str, Any]) -> tuple[int, ...]:
    sensor = params.get("sensor", "any")
    return tuple(_CLIFFS.values()) if sensor == "any" else (_CLIFFS[sensor],)


def _cliff_compares(params: Mapping[str, Any]) -> tuple[tuple[str, Comparison], ...]:
    """A drop is 1 on each sensor it reads (any one of them, for ``any``): the Full-mode
    check reads from this that a cliff makes it succeed."""
    return tuple(("sensor", (packet, "==", 1.0)) for packet in _cliff_reads(params))


@declare(
    "cliff",
    kind="condition",
    params=(Param("sensor", enum(*_CLIFFS, "any"), default="any", from_blackboard=False),),
    reads=_cliff_reads,
    primary="sensor",
    compares=_cliff_compares,
)
class Cliff(Condition):
    """A cliff sensor sees a drop (packets 9-12), one sensor or any."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        sensor = self.value("sensor")
        if sensor == "any":
            return snapshot.frame.any_cliff
        return bool(snapshot.frame[_CLIFFS[sensor]])


@declare("wall", kind="condition", reads=packet_ids("wall"))
class Wall(Condition):
    """The right-side wall sensor sees a wall (packet 8)."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame.wall


@declare("virtual_wall", kind="condition", reads=VIRTUAL_WALL_PACKETS)
class VirtualWall(Condition):
    """A virtual wall beam is detected (packet 13)."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame.virtual_wall


_LIGHT_SIGNALS = dict(zip(LIGHT_BUMPER_NAMES, LIGHT_BUMP_SIGNAL_PACKETS, strict=True))
_SIGNAL_MAXIMUM = max(PACKETS[pid].maximum for pid in LIGHT_BUMP_SIGNAL_PACKETS)


def _light_reads(params: Mapping[str, Any]) -> tuple[int, ...]:
    sensor = params.get("sensor", "any")
    if params.get("threshold") is None:
        return LIGHT_BUMPER_PACKETS
    return tuple(_LIGHT_SIGNALS.values()) if sensor == "any" else (_LIGHT_SIGNALS[sensor],)


@declare(
    "light_bumper",
    kind="condition",
    params=(
        Param("sensor", enum(*LIGHT_BUMPER_NAMES, "any"), default="any", from_blackboard=False),
        # from 1: every signal is at least 0, so threshold 0 would be true on any robot (as
        # sensor: light_bump_left_signal >= 0 is refused)
        Param("threshold", INT, minimum=1, maximum=_SIGNAL_MAXIMUM, from_blackboard=False,
              doc="compare the signal (46-51) instead of the robot's own detection bit (45); 0 "
                  "would be true on any robot, and is refused"),
    ),
    reads=_light_reads,
    primary="sensor",
)  # fmt: skip
class LightBumper(Condition):
    """An obstacle near a light-bumper sensor: its bit (packet 45), or its signal (46-51)
    at or above a threshold."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        sensor, threshold = self.value("sensor"), self.value("threshold")
        frame = snapshot.frame
        if threshold is None:
            bumper = frame.light_bumper
            return bumper.any if sensor == "any" else bool(getattr(bumper, sensor))
        ids = _light_reads(self.params)
        return any(frame[pid] >= threshold for pid in ids)


_RECEIVERS = dict(zip(("omni", "left", "right"), IR_PACKETS, strict=True))
_IR_WHAT = ("red_buoy", "green_buoy", "force_field", "virtual_wall", "any_buoy", "dock",
            "remote", "anything")  # fmt: skip


def _ir_constraints(params: Mapping[str, Any]) -> list[str]:
    """``button`` picks one of the remote's buttons, so it goes with ``sees: remote`` only:
    without it (``sees`` is ``anything`` by default) it was ignored, and ``ir: {button:
    spot}`` succeeded at the dock's beams. Refused rather than taken to mean ``sees:
    remote``: ``sees: dock, button: spot`` says two things, and the reference says the
    button is for the remote alone. A ``sees`` read from the blackboard is not known here."""
    sees = params.get("sees", "anything")
    if "button" not in params or sees == "remote" or isinstance(sees, BlackboardRef):
        return []
    return [f"button: only goes with sees: remote (sees is {sees}): write sees: remote, "
            "button: ... for one button of the remote"]  # fmt: skip


@declare(
    "ir",
    kind="condition",
    params=(
        Param("sees", enum(*_IR_WHAT), default="anything"),
        Param("receiver", enum(*_RECEIVERS), default="omni", from_blackboard=False),
        Param("button", enum(*sorted(set(REMOTE_BUTTONS.values()))),
              doc="this button of the remote only; only with sees: remote (else an error)"),
    ),
    reads=lambda p: (_RECEIVERS[p.get("receiver", "omni")],),
    primary="sees",
    constraints=_ir_constraints,
)  # fmt: skip
class InfraRed(Condition):
    """An IR character on the omni (17), left (52) or right (53) receiver: a dock's red or
    green buoy or force field, a virtual wall (162, or a Virtual Wall Lighthouse's fence), a
    remote button.

    The buoys and the force field are a dock's alone: a 560/570's Virtual Wall Lighthouse
    sends beams of the same names, but as other characters (the 500 spec's ``0LLLL0BB``,
    8-91, against the docks' 160-173 and 240-254), so ``any_buoy`` never fires at one. Its
    fence keeps the robot out as a virtual wall does, and counts as one."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        char: IRCharacter = getattr(snapshot.frame, f"ir_{self.value('receiver')}")
        sees = self.value("sees")
        if sees == "anything":
            return char.code != 0
        if sees == "dock":
            return char.from_dock
        if sees == "remote":
            button = self.value("button")
            return char.remote_button is not None and button in (None, char.remote_button)
        if sees == "virtual_wall":
            return char.virtual_wall
        return char.from_dock and bool(getattr(char, sees))


_CHARGING: dict[str, Callable[[ChargingState], bool]] = {
    "charging": lambda s: s.is_charging,
    "not_charging": lambda s: s is ChargingState.NOT_CHARGING,
    "reconditioning": lambda s: s is ChargingState.RECONDITIONING,
    "full_charging": lambda s: s is ChargingState.FULL_CHARGING,
    "trickle_charging": lambda s: s is ChargingState.TRICKLE_CHARGING,
    "waiting": lambda s: s is ChargingState.WAITING,
    "fault": lambda s: s is ChargingState.FAULT,
}


@declare("charging", kind="condition",
         params=(Param("state", enum(*_CHARGING), default="charging"),),
         reads=CHARGING_STATE_PACKETS, primary="state")  # fmt: skip
class Charging(Condition):
    """The charging state (packet 21) is the one named (``charging``: any charging state)."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        return bool(_CHARGING[self.value("state")](snapshot.frame.charging_state))


@declare("on_home_base", kind="condition", reads=CHARGING_SOURCES_PACKETS)
class OnHomeBase(Condition):
    """The home base powers the robot (packet 34, bit 1)."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame.charging_sources.home_base


def _exactly_one(*names: str) -> Callable[[Mapping[str, Any]], list[str]]:
    """A declaration's ``constraints``: one of ``names`` given, not none, not several."""

    def constraints(params: Mapping[str, Any]) -> list[str]:
        if sum(name in params for name in names) != 1:
            return [f"give exactly one of {', '.join(names)}"]
        return []

    return constraints


@declare(
    "battery",
    kind="condition",
    params=(
        Param("above", PERCENT, minimum=0, maximum=100),
        Param("below", PERCENT, minimum=0, maximum=100),
    ),
    reads=packet_ids("battery_charge", "battery_capacity"),
    constraints=_exactly_one("above", "below"),
)
class Battery(Condition):
    """Battery charge (25) as a percent of capacity (26) above or below a level."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        percent = snapshot.frame.battery_percent
        above = self.value("above")
        if above is not None:
            return percent > float(above)
        return percent < self.number("below")


@declare("oi_mode", kind="condition",
         params=(Param("is", enum("off", "passive", "safe", "full"), required=True),),
         reads=(OI_MODE_PACKET,), primary="is")  # fmt: skip
class OIModeIs(Condition):
    """The OI mode (packet 35, as reconciled by the robot layer) is the one named."""

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.mode is OIMode[str(self.value("is")).upper()]


@declare(
    "odometry",
    kind="condition",
    params=(
        Param("since", STR, from_blackboard=False, doc="a mark key; default: the start"),
        Param("distance", DISTANCE, minimum=0,
              doc="at least this path length: every mm the centre moved, forward or back"),
        Param("angle", ANGLE, minimum=0,
              doc="at least this net heading change: a turn back undoes a turn, either way"),
    ),
    reads=ENCODER_PACKETS,
    reads_keys={"since": MARK},
    constraints=_exactly_one("distance", "angle"),
)  # fmt: skip
class OdometrySince(Condition):
    """The robot has travelled a distance, or turned an angle, since a mark (or the start).

    ``distance`` is the path (``Odometry.path_mm``, the summary's ``distance``): 10 cm forward
    then 10 cm back is 20 cm travelled. It was the net signed distance, which a back-off
    cancelled: a "travelled too far" limit around manoeuvres that back up never tripped.
    ``angle`` stays the net heading change (how far the robot now faces from where it faced,
    not wrapped: two whole turns one way are 720deg): what a lap counted by heading
    (``patrol``) needs, where the wiggles of a wall follow must not add up."""

    def held_means(self) -> str:
        """What its holding means, for a ``while`` guard's reason: the one of distance or
        angle it tests, since its mark or, with none, since the run began (the first
        sentence of the description, "a distance, or turned an angle, since a mark", said
        a mark that was not there)."""
        since = self.value("since")
        what = (
            "travelled the distance" if self.value("distance") is not None else "turned the angle"
        )
        return f"the robot has {what} since " + (f"mark {since!r}" if since else "the run began")

    def check(self, snapshot: Snapshot) -> bool:
        since = self.value("since")
        mark = read_key(since) if since else None
        if since and mark is None:  # only a tree built in Python: a mission's are proved
            raise UnwrittenKey(
                f"since is {since!r}, but nothing has marked blackboard key {since!r} before "
                f"{self.name!r} was checked (a Mark node first, or it counts from nothing)"
            )
        base = mark if isinstance(mark, Odometry) else Odometry()
        now = snapshot.odometry
        distance = self.value("distance")
        if distance is not None:
            return now.path_mm - base.path_mm >= float(distance)
        return abs(math.degrees(now.angle_rad - base.angle_rad)) >= self.number("angle")


_STASIS = {"moving": Stasis.FORWARD_PROGRESS, "stuck": Stasis.NO_PROGRESS, "dirty": Stasis.DIRTY}
(_STASIS_PACKET,) = packet_ids("stasis")


def _stasis_compares(params: Mapping[str, Any]) -> tuple[tuple[str, Comparison], ...]:
    """``stasis: dirty`` is ``stasis == 2``: a test a Roomba 500 (stasis 0..1) never passes."""
    state = params.get("state", "stuck")
    if not isinstance(state, str):  # from the blackboard: known only at run time
        return ()
    return (("state", (_STASIS_PACKET, "==", float(_STASIS[state]))),)


@declare("stasis", kind="condition",
         params=(Param("state", enum(*_STASIS), default="stuck"),),
         reads=packet_ids("stasis"), primary="state", compares=_stasis_compares)  # fmt: skip
class StasisIs(Condition):
    """The stasis caster (58) reports forward progress, none, or (600 series) too dirty."""

    frame_pure = True

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.frame.stasis is _STASIS[self.value("state")]


@declare("overcurrent", kind="condition",
         params=(Param("motor", enum(*_OVERCURRENT), default="any"),),
         reads=packet_ids("overcurrents"), primary="motor")  # fmt: skip
class Overcurrent(_Flag):
    """A motor draws too much current (packet 14: 0 side brush, 2 main, 3 right, 4 left)."""

    choice, flags = "motor", _OVERCURRENT


def _button_on_top(params: Mapping[str, Any], profile: RobotProfile) -> str | None:
    """Why the chosen robot's packet 18 never shows the button named, or None: its top
    lacks it (the clock panel's ``minute`` on a Create 2). The bit is in the packet all the
    same, always 0, so the condition runs and never holds: a warning, not an error."""
    name = params.get("name")
    if not isinstance(name, str) or name == "any":
        return None
    missing = profile.buttons_missing((name,))
    if missing is None:
        return None
    return f"{missing}; packet 18's {name} bit reads 0 there for ever: this never holds"


#: what a press of each button of ``CYCLE_BUTTONS`` starts in Passive
_CYCLE_STARTED = {"clean": "cleaning cycle", "spot": "spot cycle", "dock": "search for its dock"}


def _waits_in_passive(params: Mapping[str, Any]) -> str | None:
    """What waiting in Passive for a button that starts a cycle there (Clean, Spot, Dock, or
    ``any``) meets: the press starts the robot's own cycle (the OI spec), and the run ends
    at the press (runtime/long_run.py). Unsaid, a maker's "wait for the Clean button, then
    dance", with no ``mode: safe`` first, validates clean, and the robot drives off
    cleaning."""
    name = params.get("name", "any")
    if name == "any":
        starts = "Clean, Spot and Dock buttons each start a cycle of its own"
    elif name in CYCLE_BUTTONS:
        starts = f"{name.capitalize()} button starts its own {_CYCLE_STARTED[name]}"
    else:  # minute, hour...: nothing starts at them
        return None
    return (
        f"in Passive the robot's {starts} (the OI spec; the run ends at the press); put "
        "`mode: safe` first (Safe and Full start no cycle at a button)"
    )


@declare("button", kind="condition", params=(Param("name", enum(*_BUTTON), default="any"),),
         reads=packet_ids("buttons"), primary="name", needs=_button_on_top,
         needs_only_warns=True, in_passive=_waits_in_passive)  # fmt: skip
class Button(_Flag):
    """A button on the robot is pressed (packet 18): SUCCESS on every frame it is held, so
    a press of a finger (several frames; the firmware's Buttons (165) 1/6 s) is seen again
    and again; ``button_pressed`` is the one frame a press begins.

    In Passive a press of Clean, Spot or Dock starts the robot's own cycle (the OI spec):
    the validator warns of such a ``button`` reachable in Passive (the declaration's
    ``in_passive``), and the run ends at the press
    (``runtime.long_run.RobotCycleWatch.pressed``)."""

    choice, flags = "name", _BUTTON


#: how many ticks (15 ms each) a button seen down and down again is taken for one press:
#: 150 ms, shorter than any release and press again of a finger, and than the 1/6 s a
#: Buttons (165) command holds one
SAME_PRESS_TICKS = 10


@declare("button_pressed", kind="condition",
         params=(Param("name", enum(*_BUTTON), default="any"),),
         reads=packet_ids("buttons"), primary="name", needs=_button_on_top,
         needs_only_warns=True, in_passive=_waits_in_passive)  # fmt: skip
class ButtonPressed(_Flag):
    """A press of a button on the robot begins (packet 18): SUCCESS on the one frame it is
    down after a frame it was up, FAILURE while it is held and after. One press, one
    SUCCESS, however long the finger stays: ``until: {button_pressed: clean}`` in a
    ``repeat`` beeps once a press (``button`` beeps on each frame it is held). A button it
    saw down at most 150 ms ago (``SAME_PRESS_TICKS``) and finds down still is the same
    press, though the tree ticked without it between (a ``play`` before it in a ``repeat``
    takes a frame or two: each round counted the held button again, 6 songs a press); a
    button already down the first time it is ticked, or after a longer gap, counts as a
    press beginning: the frames between are not known to it."""

    choice, flags = "name", _BUTTON
    #: its answer depends on the frame before too: not a function of this frame's packets
    frame_pure = False

    def __init__(self, name: str, params: Mapping[str, Any] | None = None) -> None:
        super().__init__(name, params)
        #: the tick it last read the button on, whether it was down then, and its answer
        #: then (ticked twice in one tick, as a guard and a child, it answers the same)
        self._seen_tick: int | None = None
        self._was_down = False
        self._answer = False

    def check(self, snapshot: Snapshot) -> bool:
        tick = snapshot.tick
        if tick == self._seen_tick:
            return self._answer
        held_before = (
            self._was_down
            and self._seen_tick is not None
            and tick - self._seen_tick <= SAME_PRESS_TICKS
        )
        down = bool(super().check(snapshot))
        self._seen_tick, self._was_down = tick, down
        self._answer = down and not held_before
        return self._answer


_COMPARISON = re.compile(
    r"^\s*([a-z_][a-z0-9_]*)\s*(<=|>=|==|!=|<|>)\s*(-?[0-9]+(?:\.[0-9]+)?)\s*$", re.ASCII
)


def comparison_verdict(op: str, number: float, lo: int, hi: int) -> str | None:
    """``"never"`` or ``"always"`` when every reading ``lo..hi`` (whole numbers: a packet's
    raw values) answers ``reading op number`` the same way; None when some answer each way."""
    whole = number == int(number)
    if op in ("<", "<="):
        never, always = not OPERATORS[op](lo, number), OPERATORS[op](hi, number)
    elif op in (">", ">="):
        never, always = not OPERATORS[op](hi, number), OPERATORS[op](lo, number)
    else:
        absent = not whole or not lo <= number <= hi
        only = lo == hi == number
        never, always = (absent, only) if op == "==" else (only, absent)
    return "never" if never else "always" if always else None


def comparison_problem(
    test: Comparison, packets: Mapping[int, PacketSpec], where: str = ""
) -> str | None:
    """Why ``test`` cannot tell anything apart with these packets' ranges (``stasis == 7``:
    never true, stasis reads 0..3), or None."""
    pid, op, number = test
    spec = packets[pid]
    verdict = comparison_verdict(op, number, spec.minimum, spec.maximum)
    if verdict is None:
        return None
    said = "can never be true" if verdict == "never" else "is always true"
    return (
        f"'{spec.name} {op} {number:g}' {said}{where}: {spec.name} reads "
        f"{spec.minimum}..{spec.maximum}"
    )


def _widest(pid: int) -> PacketSpec:
    """The packet's range over every robot model (a Roomba 500's unsigned encoders, a
    Create 2's signed ones): what a mission for any of them may compare against."""
    specs = [profile.packet(pid) for profile in PROFILES.values()]
    lo, hi = min(s.minimum for s in specs), max(s.maximum for s in specs)
    return replace(specs[0], minimum=lo, maximum=hi)


def _parse_comparison(value: object) -> Comparison:
    """The whole expression grammar: ``packet_name op number``; never ``eval``. A test no
    robot's reading can change the answer of (``stasis == 7``, ``wall_signal >= 0``) is an
    error: a loop until it never ends, or ends at once (a test true or false only on the
    chosen model is a warning: :func:`roomba_bt.mission.checks.sensor_ranges`)."""
    match = _COMPARISON.match(value) if isinstance(value, str) else None
    if match is None:
        raise UnitError(
            "expected a comparison such as 'wall_signal > 100' (packet op number), got "
            + described(value)
            + (miswritten(value) if isinstance(value, str) else "")
        )
    name, op, number = match.groups()
    spec = PACKETS_BY_NAME.get(name)
    if spec is None:
        from roomba_bt.behaviours.units import closest

        raise UnitError(f"unknown sensor packet {name!r}{closest(name, list(PACKETS_BY_NAME))}")
    if not math.isfinite(float(number)):  # 400 digits: "internal error (OverflowError)"
        widest = _widest(spec.id)
        raise UnitError(
            f"{quoted(number)} is too large a number to compare {name} with: {name} reads "
            f"{widest.minimum}..{widest.maximum}"
        )
    test = (spec.id, op, float(number))
    problem = comparison_problem(test, {spec.id: _widest(spec.id)}, " on any OI robot")
    if problem is not None:
        raise UnitError(problem)
    return test


COMPARISON = ValueType(
    "comparison",
    _parse_comparison,
    json_schema=(("type", "string"), ("description", "packet_name op number")),
)


def _sensor_reads(params: Mapping[str, Any]) -> tuple[int, ...]:
    test = params.get("test")
    return (test[0],) if isinstance(test, tuple) else ()


@declare(
    "sensor",
    kind="condition",
    params=(Param("test", COMPARISON, required=True, from_blackboard=False,
                  doc="'packet_name op number', e.g. 'wall_signal > 100'"),),
    reads=_sensor_reads,
    primary="test",
)  # fmt: skip
class Sensor(Condition):
    """Compare any sensor packet's raw value, by name: ``sensor: wall_signal > 100``."""

    frame_pure = True

    def __init__(self, name: str, params: Mapping[str, Any] | None = None) -> None:
        super().__init__(name, params)
        test = self.params.get("test")
        #: (packet id, comparison, number), looked up once: the test is never an @key value
        self._compare = (test[0], OPERATORS[test[1]], test[2]) if isinstance(test, tuple) else None

    def check(self, snapshot: Snapshot) -> bool:
        if self._compare is None:
            pid, op, number = self.value("test")
            return OPERATORS[op](snapshot.frame[pid], number)
        pid, compare, number = self._compare
        return compare(snapshot.frame[pid], number)


#: the operators that order (a number with a number, a text with a text)
_ORDERING = frozenset({"<", "<=", ">=", ">"})
_NUMERIC_TEXT = re.compile(r"\s*[-+]?(\d|\.\d)")


def _comparable(params: Mapping[str, Any]) -> list[str]:
    """``check``'s constraint: a value that ``op`` can order. From Python ``value="200 mm"``
    is text, which a number is never less or greater than: the check was False on every
    tick, silently (the compiler types a mission's value by the key's declaration)."""
    value, op = params.get("value"), params.get("op", "==")
    if op not in _ORDERING or isinstance(value, BlackboardRef):
        return []
    if isinstance(value, str) and _NUMERIC_TEXT.match(value):
        return [
            f"value {value!r} is text, and {op} orders a number only with a number: give the "
            "number in the key's unit (mm, mm/s, s, deg), e.g. 200.0"
        ]
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        return [
            f"value {value!r} ({type(value).__name__}) cannot be ordered with {op}: give a "
            "number or a text"
        ]
    return []


@declare(
    "check",
    kind="condition",
    params=(
        Param("key", STR, required=True, from_blackboard=False),
        Param("op", enum(*OPERATORS), default="=="),
        Param("value", ANY, required=True, doc="typed by the key's declaration"),
    ),
    reads_keys=("key",),
    constraints=_comparable,
)
class CheckKey(Condition):
    """Compare a blackboard key with a value. A key not written yet makes the check False; a
    value that cannot be compared with the key's (a plugin wrote another type) ends the run
    as an error: a bug, not a False. A False says the value found, as py_trees'
    CheckBlackboardVariableValue does (``n is 2, not == 1``): the outcome quoted only the
    node's name, which says what was wanted, never what was there."""

    def check(self, snapshot: Snapshot) -> bool:
        key = str(self.value("key"))
        current = read_key(key)
        op, value = self.value("op"), self.value("value")
        try:
            holds = bool(OPERATORS[op](current, value))
        except TypeError:
            if current is None:  # not written yet
                self.feedback_message = f"{key} is not written yet"
                return False
            raise TypeError(
                f"check: key {key!r} holds {current!r} ({type(current).__name__}), which "
                f"cannot be compared with {value!r} ({type(value).__name__}) by {op}"
            ) from None
        self.feedback_message = "" if holds else _not_held(key, current, op, value)
        return holds


def _not_held(key: str, current: Any, op: str, value: Any) -> str:
    """``d is 500 mm, not < 200 mm``: a quantity in its unit, as ``set`` and ``show`` write
    it (the key holds the canonical ``500.0``, which read as no distance at all); any other
    value as Python writes it (``'bye'``), so that a text is told from a number."""
    vtype = declared_type(key)
    if vtype is None or vtype.name not in CANONICAL:
        return f"{key} is {current!r}, not {op} {value!r}"
    return f"{key} is {shown(vtype, current)}, not {op} {shown(vtype, value)}"


CONDITIONS: tuple[type[Condition], ...] = (
    Bump, WheelDrop, Cliff, Wall, VirtualWall, LightBumper, InfraRed, Charging, OnHomeBase,
    Battery, OIModeIs, OdometrySince, StasisIs, Overcurrent, Button, ButtonPressed, Sensor,
    CheckKey,
)  # fmt: skip
