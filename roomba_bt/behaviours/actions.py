"""The action library: mode changes, driving, the robot's own cleaning modes, actuators.

Every action hands :class:`~roomba_bt.oi.encode.Command` objects to the outbox; the runtime
checks them against the mode model and writes them after the tick. Durations, timeouts and
distances count the mission clock (``snapshot.time``) and the odometry of the snapshot, so a
replay decides exactly as the live run did. An action that starts the wheels stops them when
it ends, however it ends (success, failure, or preempted by a guard or a higher branch):
:meth:`~roomba_bt.behaviours.declare.Action.terminate` queues ``[137][0][0][0][0]``.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours import reversing
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import write_key
from roomba_bt.behaviours.declare import Param, declare, moving_minimum
from roomba_bt.behaviours.driving import WHEEL, cycle_may_run, on_home_base
from roomba_bt.behaviours.units import (
    ANGLE,
    ANY,
    BOOL,
    DISTANCE,
    DURATION,
    INT,
    MARK,
    PERCENT,
    RADIUS,
    RADIUS_WORDS,
    SPEED,
    STR,
    BareNumber,
    ItemErrors,
    UnitError,
    ValueType,
    closest,
    described,
    enum,
    parse_quantity,
)
from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import LED_NAMES, LED_SPEC_NAMES, led_bits, motor_bits
from roomba_bt.oi.encode import NOTE_NAMES, Note, Radius, note_name, note_number
from roomba_bt.oi.frames import CHARGING_SOURCES_PACKETS, ENCODER_PACKETS, SLOT_SECONDS
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.odometry import SLOWEST_MOVING_SPEED_MM_S, WHEEL_SPEED_STEP_MM_S, speed_steps
from roomba_bt.oi.opcodes import (
    COMMANDS_BY_NAME,
    NOTE_DURATION,
    NOTE_STEPS_PER_SECOND,
    PLAYABLE_NOTES,
    SONG_LENGTH,
    SONG_NUMBER,
    opcodes,
)
from roomba_bt.oi.packets import PACKETS_BY_NAME
from roomba_bt.printable import ANY_CONTROL, TEXT_LIMIT, duration_said, escaped, shortened
from roomba_bt.robot.hazards import sets_going
from roomba_bt.yamlsource import quoted

log = logging.getLogger("roomba_bt.mission")

# Ranges read from the opcode table, never retyped.
_VELOCITY = COMMANDS_BY_NAME["drive"].args[0]
_RADIUS = COMMANDS_BY_NAME["drive"].args[1]
_LED_COLOR = COMMANDS_BY_NAME["leds"].args[1]
_LED_INTENSITY = COMMANDS_BY_NAME["leds"].args[2]
_MAIN_BRUSH_PWM, _SIDE_BRUSH_PWM, _VACUUM_PWM = COMMANDS_BY_NAME["pwm_motors"].args

_RADIUS_WORDS: dict[str, int] = {
    "straight": int(Radius.STRAIGHT),
    "spin_left": int(Radius.TURN_COUNTER_CLOCKWISE),
    "spin_right": int(Radius.TURN_CLOCKWISE),
}
assert tuple(_RADIUS_WORDS) == RADIUS_WORDS


def _parse_notes(value: object) -> tuple[tuple[int, int], ...]:
    """``["C4 250ms", "rest 125ms", "A#4 1s"]`` -> ((60, 16), (0, 8), (70, 64)). Every bad
    note is said (:class:`ItemErrors`: a mission says each at the note's own place)."""
    if not isinstance(value, list):
        one = f": write it as a list, [{quoted(value)}]" if isinstance(value, str) else ""
        raise UnitError(
            'expected a list of notes such as ["C4 250ms", "rest 125ms"], got '
            f"{described(value)}{one}"
        )
    if not value:  # a list, though "expected a list" said it was not one
        raise UnitError(
            f"a song has {SONG_LENGTH.minimum} to {SONG_LENGTH.maximum} notes, got none (an "
            'empty list): give at least one, such as ["C4 250ms"]'
        )
    notes: list[tuple[int, int]] = []
    problems: list[tuple[int, str]] = []
    for index, item in enumerate(value):
        try:
            notes.append(_note(item))
        except UnitError as exc:
            problems.append((index, str(exc)))
    if problems:
        raise ItemErrors("note", len(value), problems)
    if len(notes) > SONG_LENGTH.maximum:
        raise UnitError(_split_the_song(len(notes)))
    return tuple(notes)


def _notes_from_to(first: int, last: int) -> str:
    """``notes 1-16``, ``note 17``: a part of a song said in its error."""
    return f"note {first}" if first == last else f"notes {first}-{last}"


def _split_the_song(count: int) -> str:
    """The error of a song over the robot's 16 notes, with the way on: its notes in 16s, a
    slot each (5 slots: 80 notes), played one after the other, each ``play`` followed by a
    wait for packet 37 to show the song over (a Play while a song plays is ignored)."""
    most = SONG_LENGTH.maximum
    slots = -(-count // most)
    if slots > SONG_NUMBER.maximum + 1:
        room = (SONG_NUMBER.maximum + 1) * most
        return (
            f"a song has at most {most} notes, got {count}: the robot's "
            f"{SONG_NUMBER.maximum + 1} song slots hold {room} notes in all (define the "
            "rest when a slot has played)"
        )
    parts = [(slot * most + 1, min(count, (slot + 1) * most)) for slot in range(slots)]
    songs = ", ".join(
        f"`song: {{number: {slot}, notes: [{_notes_from_to(first, last)}]}}`"
        for slot, (first, last) in enumerate(parts)
    )
    plays = ", ".join(
        f"`play: {slot}`, `{{wait: 30s, until: {{sensor: song_playing == 0}}}}`"
        for slot in range(slots)
    )
    return (
        f"a song has at most {most} notes, got {count}: split it into {slots} songs played "
        f'one after the other: {songs}, then {plays} (roomba-bt docs missions, "Songs")'
    )


#: the note lengths the language takes, in 1/64 s: one step to the table's longest (a note
#: of 0/64 s, which the table allows, plays nothing: a slip, refused), said in words
_NOTE_STEPS = range(max(NOTE_DURATION.minimum, 1), NOTE_DURATION.maximum + 1)
_NOTE_LENGTHS = (
    f"{1000 * _NOTE_STEPS[0] / NOTE_STEPS_PER_SECOND:.0f}ms.."
    f"{_NOTE_STEPS[-1] / NOTE_STEPS_PER_SECOND:.2f}s"
)
#: the lowest and highest notes the robot plays, by name (G1, G9), and why one it does not
#: play is refused (the encoder would send it: a rest)
_LOWEST, _HIGHEST = note_name(PLAYABLE_NOTES[0]), note_name(PLAYABLE_NOTES[-1])
_RESTS = (
    f"outside the notes the robot plays, {_LOWEST} to {_HIGHEST}: it would sound as a rest "
    "(write rest for one)"
)


def _note(item: object) -> tuple[int, int]:
    """One note, ``"C4 250ms"`` -> (60, 16): a name the robot plays (or ``rest``) and a
    duration in 1/64 s, spaces between them as many as written (``"C4 250 ms"``: a duration
    takes a space before its unit everywhere else)."""
    parts = item.split(None, 1) if isinstance(item, str) else []
    if len(parts) != 2:
        raise UnitError(
            f'expected a note such as "C4 250ms" or "rest 125ms", got {described(item)}'
            + ("" if isinstance(item, str) else ": a note is one text, its name and duration")
        )
    try:
        number = note_number(parts[0])
    except ValueError:
        raise UnitError(f"unknown note {parts[0]!r}: {_note_hint(parts[0])}") from None
    if number and number not in PLAYABLE_NOTES:
        raise UnitError(f"note {parts[0]} ({number}) is {_RESTS}")
    seconds = parse_quantity("duration", parts[1])
    # the range on the length as written, not on its rounding: 8ms was sent as 1/64 s and
    # 3.992s as 255/64, both outside the range the error and the docs state
    if not _NOTE_STEPS[0] <= seconds * NOTE_STEPS_PER_SECOND <= _NOTE_STEPS[-1]:
        raise UnitError(
            f"note duration {parts[1]!r} is out of range: {_NOTE_LENGTHS} ({_NOTE_STEPS[0]}.."
            f"{_NOTE_STEPS[-1]} of 1/{NOTE_STEPS_PER_SECOND} s)"
        )
    return number, round(seconds * NOTE_STEPS_PER_SECOND)


#: a note name as a musician writes it: a letter, a sharp or a flat (``b``, ``♯``, ``♭``), an
#: octave
_SPELLED_NOTE = re.compile("([A-Ga-g])([#b\u266f\u266d]?)([0-9])")


def _note_hint(name: str) -> str:
    """What to write for a note name :func:`note_number` refuses: a flat (``Db4``), ``♯``, or
    ``E#4`` as the same pitch the way the robot's names spell it (``C#4``, ``F4``): flats are
    common and were refused with only "write A4, C#5 or rest". A MIDI number (``200``,
    ``69``) and German ``H`` (B) are named as what they are; anything else hears what a name
    is made of. A pitch the robot does not play is said to be one, never named as a note to
    write instead (``Ab9`` was told to write G#9, refused in turn; ``B#9`` C10, no name)."""
    lo, hi = PLAYABLE_NOTES[0], PLAYABLE_NOTES[-1]
    plays = f"the robot plays {note_name(lo)} ({lo}) to {note_name(hi)} ({hi})"
    if name.isdigit():
        number = int(name)
        named = f"write {note_name(number)}" if number in PLAYABLE_NOTES else plays
        return f"a note is written by its name, not its MIDI number: {named}"
    german = re.fullmatch("[Hh]([0-9])", name)
    if german is not None:
        number = note_number(f"B{german.group(1)}")
        if number not in PLAYABLE_NOTES:
            return f"H is B in German names: {name} is MIDI note {number}, {_RESTS}"
        return f"H is B in German names: write B{german.group(1)}"
    spelled = _SPELLED_NOTE.fullmatch(name)
    if spelled is None:
        return (
            f"a note is a name, one of {', '.join(NOTE_NAMES)}, and an octave 0-9 (A4, C#5; "
            f"{plays}), or rest"
        )
    letter, accidental, octave = spelled.groups()
    shift = {"#": 1, "\u266f": 1, "b": -1, "\u266d": -1}.get(accidental, 0)
    number = 12 * (int(octave) + 1) + NOTE_NAMES.index(letter.upper()) + shift
    if number not in PLAYABLE_NOTES:
        return f"{name} is MIDI note {number}, {_RESTS}"
    return (
        f"write {note_name(number)}, the same pitch (the notes are {', '.join(NOTE_NAMES)}: "
        "no flats)"
    )


NOTES = ValueType(
    "notes",
    _parse_notes,
    json_schema=(("type", "array"), ("items", {"type": "string"}),
                 ("minItems", SONG_LENGTH.minimum), ("maxItems", SONG_LENGTH.maximum)),
)  # fmt: skip

_OK, _RUN, _FAIL = Status.SUCCESS, Status.RUNNING, Status.FAILURE


# --------------------------------------------------------------------------- modes


def _mode_target(params: Mapping[str, Any]) -> OIMode:
    return OIMode[str(params.get("to", "safe")).upper()]


#: The command that enters each mode a ``mode`` leaf may ask for.
_MODE_COMMANDS = {OIMode.PASSIVE: oi.start, OIMode.SAFE: oi.safe, OIMode.FULL: oi.full}
_MODE_OPCODES = {mode: command().opcode for mode, command in _MODE_COMMANDS.items()}


def _mode_sends(params: Mapping[str, Any]) -> tuple[int, ...]:
    """``mode: passive`` sends Start (128) alone: accepted in Off, the one way back there."""
    return (_MODE_OPCODES[_mode_target(params)],)


@declare(
    "mode",
    kind="action",
    params=(
        Param("to", enum("passive", "safe", "full"), required=True, from_blackboard=False,
              doc="the OI mode to enter"),
        Param("timeout", DURATION, default="2s", minimum=0.1, maximum=60,
              doc="FAILURE if packet 35 does not show the mode by then"),
    ),
    sends=opcodes("start", "safe", "full"),
    sends_by=_mode_sends,
    leads_to=_mode_target,
    primary="to",
)  # fmt: skip
class Mode(Action):
    """Enter an OI mode (Start 128 for passive, Safe 131, Full 132) and wait for packet 35.

    Succeeds once the robot reports the mode; re-sends every 0.5 s; fails after ``timeout``.
    Leaving Safe or Full for Passive while the run's last Motors or PWM Motors command runs a
    brush or the vacuum, it sends Motors 0 (``[138][0]``) before Start: the OI spec says only
    that Passive cannot change the actuators' parameters, not that Start stops the motors
    (decided: stop them while they can still be stopped). Not in its ``sends=``, which the
    compiler reads as the modes it needs (Motors only in Safe/Full): a stop, as an action's
    ending halt is.
    ``mode: passive`` in the Passive of a built-in cycle that may still drive (Clean, Seek
    Dock: the OI is in Passive while the firmware drives) ends it, Safe, drive 0, motors off,
    Start (:meth:`~roomba_bt.robot.interface.Outbox.end_cycle`): it sent nothing there, and
    the cycle drove on after it. Not in ``sends=`` either, for the same reason.
    """

    def start(self) -> None:
        self._target = _mode_target(self.params)
        self._started = self.snapshot.time
        self._last_sent = -math.inf

    def update(self) -> Status:
        snap = self.snapshot
        if snap.mode == self._target:
            robot = self.robot
            if snap.mode is OIMode.PASSIVE and robot is not None and cycle_may_run(robot):
                robot.outbox.end_cycle(self)  # Passive, but a cycle drives: stopped in it
            return _OK
        if snap.time - self._started >= float(self.value("timeout")):
            self.feedback_message = f"robot did not enter {self._target.label}"
            return _FAIL
        if snap.time - self._last_sent >= 0.5:
            if self._target is OIMode.PASSIVE and snap.mode in DRIVING_MODES:
                self._motors_off_first()
            self.send(_MODE_COMMANDS[self._target]())
            self._last_sent = snap.time
        return _RUN

    def _motors_off_first(self) -> None:
        robot = self.robot
        assert robot is not None  # the snapshot was read
        motors = robot.outbox.last_on("motors")
        if motors is not None and sets_going(motors):
            robot.outbox.send(oi.motors_off(), self)


# --------------------------------------------------------------------------- driving


def _drive_constraints(params: Mapping[str, Any]) -> list[str]:
    errors = []
    ends = [k for k in ("distance", "angle", "duration") if k in params]
    if len(ends) > 1:
        errors.append(f"give at most one of distance, angle, duration (got {', '.join(ends)})")
    wheels = [k for k in ("left", "right") if k in params]
    if wheels and len(wheels) != 2:
        errors.append("give both left and right wheel speeds, or neither")
    if wheels and ("radius" in params or "velocity" in params):
        errors.append("give either velocity/radius or left/right wheel speeds, not both")
    radius = params.get("radius")
    if isinstance(radius, int | float) and round(radius) == 0:
        errors.append(
            f"radius {radius:g} mm is sent as 0, a radius the OI does not define (straight is "
            "32768, spinning in place 1 and -1): write straight, spin_left or spin_right, or "
            "a radius of 2 mm or more"
        )
    return errors + _never_finishes(params)


#: said of a speed the wheels do not turn at: the speed controller's nearest step is 0
_BELOW_A_STEP = (
    f" (below half the speed controller's step of about {WHEEL_SPEED_STEP_MM_S} mm/s: the "
    "wheels stand still)"
)


def _never_finishes(params: Mapping[str, Any]) -> list[str]:
    """An end the wheels can never reach: the leaf would run for ever. ``distance`` is the
    centre's path (a spin in place covers none), ``angle`` the heading (a straight drive
    keeps it). Judged on the values sent, whole mm and mm/s, as the speed controller steps
    them: 0.4 mm/s is sent as 0, 10 mm/s turns the wheels at 0 (:func:`speed_steps`), a radius
    of 1 mm is the OI's spin in place (1). Values read from the blackboard are not known here
    and pass."""
    left, right = params.get("left"), params.get("right")
    velocity, radius = params.get("velocity", 200.0), params.get("radius", "straight")
    ends = (params.get("distance"), params.get("angle"))
    given = [v for v in (left, right, velocity, radius, *ends) if v is not None]
    known = all(isinstance(v, int | float) or v in _RADIUS_WORDS for v in given)
    if not known:
        return []
    # the wheels turn at the speed controller's nearest step of what is sent (whole mm/s)
    if left is not None and right is not None:
        left_steps, right_steps = speed_steps(round(left)), speed_steps(round(right))
        centre, spins = (left_steps + right_steps) / 2, left_steps != right_steps
        how = f"left {left:g} and right {right:g} mm/s" + (
            _BELOW_A_STEP if (left_steps, right_steps) == (0, 0) else ""
        )
    else:
        steps = speed_steps(round(velocity))
        in_place = radius in ("spin_left", "spin_right") or (
            not isinstance(radius, str) and abs(round(radius)) == 1
        )
        centre = 0.0 if in_place else float(steps)
        spins = steps != 0 and radius != "straight"
        sent = " (sent as 0)" if round(velocity) == 0 and velocity != 0 else ""
        below = _BELOW_A_STEP if steps == 0 and round(velocity) != 0 else ""
        how = f"{float(velocity):g} mm/s{sent}{below}" + (
            f", radius {_shown(radius)}" if "radius" in params else ""
        )
    if left is not None and right is not None:
        fix = "wheel speeds that do not cancel"
        if (left_steps, right_steps) == (0, 0):
            fix = f"a wheel speed of at least {SLOWEST_MOVING_SPEED_MM_S} mm/s"
    else:
        fix = "a radius of 2 mm or more" if steps != 0 else "a speed"
        if round(velocity) != 0 and steps == 0:
            fix = f"a speed of at least {SLOWEST_MOVING_SPEED_MM_S} mm/s"
    if float(params.get("distance") or 0) > 0 and centre == 0:
        return [f"drive at {how} never covers its distance (its centre does not move): "
                f"it would run for ever; give {fix}, or end it by angle or duration"]  # fmt: skip
    if float(params.get("angle") or 0) > 0 and not spins:
        turning = fix if _BELOW_A_STEP in how else "a radius (or different wheel speeds)"
        return [f"drive at {how} never turns, so its angle is never reached: it would run "
                f"for ever; give {turning}, or use turn"]  # fmt: skip
    return []


def _shown(radius: object) -> str:
    """A radius as a message says it: ``1 mm (spinning in place)``, ``spin_left``."""
    if isinstance(radius, str):
        return radius
    assert isinstance(radius, int | float)
    wire = round(radius)
    return f"{radius:g} mm" + (f" (sent as {wire}: spinning in place)" if abs(wire) == 1 else "")


#: the parameters that end a drive by itself; without one it runs until something ends it
_DRIVE_ENDS = ("distance", "angle", "duration")


def _drive_reads(params: Mapping[str, Any]) -> tuple[int, ...]:
    return ENCODER_PACKETS if ("distance" in params or "angle" in params) else ()


@declare(
    "drive",
    kind="action",
    params=(
        Param("velocity", SPEED, default="200 mm/s", minimum=_VELOCITY.minimum,
              maximum=_VELOCITY.maximum, doc="average wheel speed; negative backs up"),
        Param("radius", RADIUS, default="straight", minimum=_RADIUS.minimum,
              maximum=_RADIUS.maximum,
              doc="turn radius (positive turns left), straight, spin_left or spin_right",
              # the side the turn's centre is on, which the path bends to forward and back
              signs=("left", "right")),
        Param("left", SPEED, minimum=WHEEL.minimum, maximum=WHEEL.maximum,
              doc="left wheel speed (Drive Direct 145), with right"),
        Param("right", SPEED, minimum=WHEEL.minimum, maximum=WHEEL.maximum,
              doc="right wheel speed (Drive Direct 145), with left"),
        Param("distance", DISTANCE, minimum=0, doc="stop after this path length (odometry)"),
        Param("angle", ANGLE, minimum=0, doc="stop after this heading change (odometry)"),
        Param("duration", DURATION, minimum=0, doc="stop after this mission time"),
    ),
    reads=_drive_reads,
    sends=opcodes("drive", "drive_direct"),
    constraints=_drive_constraints,
    may_succeed=lambda params: any(end in params for end in _DRIVE_ENDS),
)  # fmt: skip
class Drive(Action):
    """Drive with a velocity and radius, or wheel speeds, for a distance, an angle, a
    duration, or until a guard stops it (no end given: RUNNING until preempted).

    Sends Drive (137) ``[137][vel hi][vel lo][rad hi][rad lo]`` or Drive Direct (145)
    ``[145][right hi][right lo][left hi][left lo]`` when it starts (and again if the robot fell
    back to Passive and came back), then a halt when it ends. FAILURE if the robot stays out
    of Safe/Full for more than a second while it drives (see ``Action.stranded``), and on
    its second tick out of them when it would start there (the robot fell to Passive
    before it: see ``Action.wait_for_driving_mode``).
    """

    moves = True
    #: how it ends ("distance", "angle", "duration", or "": never by itself) and its bound
    _end: tuple[str, float] = ("", 0.0)

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        reversing.forget_run_trail()  # a new run: no floor driven yet

    def start(self) -> None:
        snap = self.snapshot
        odometry = snap.odometry
        #: the run's trail, fed every tick it drives: what ``backtrack`` may back over
        self._trail = reversing.run_trail()
        self._start_time = snap.time
        self._start_distance = odometry.distance_mm
        self._start_angle = odometry.angle_rad
        self._last_mode: OIMode | None = None
        # which end and its bound, read once a start (the parameters are resolved before it)
        distance, angle, duration = (
            self.value("distance"),
            self.value("angle"),
            self.value("duration"),
        )
        if distance is not None:
            self._end = ("distance", float(distance))
        elif angle is not None:
            self._end = ("angle", float(angle))
        elif duration is not None:
            self._end = ("duration", float(duration) - 1e-9)
        else:
            self._end = ("", 0.0)

    def command(self) -> oi.Command:
        left, right = self.value("left"), self.value("right")
        if left is not None and right is not None:
            return oi.drive_direct(round(right), round(left))
        radius = self.value("radius")
        wire_radius = _RADIUS_WORDS[radius] if isinstance(radius, str) else round(radius)
        return oi.drive(round(self.value("velocity")), wire_radius)

    def finished(self) -> bool:
        end, bound = self._end
        if not end:
            return False
        snap = self.snapshot
        if end == "distance":
            return abs(snap.odometry.distance_mm - self._start_distance) >= bound
        if end == "angle":
            return abs(math.degrees(snap.odometry.angle_rad - self._start_angle)) >= bound
        return snap.time - self._start_time >= bound

    def update(self) -> Status:
        robot = self.robot  # the snapshot read once a tick (the property's call costs)
        snap = robot.snapshot if robot is not None else self.snapshot
        self._trail.feed(snap.odometry)
        # a drive without an end (most ticks: the drive a guard ends) asks nothing of finished()
        if self._end[0] and self.finished():
            self.send(oi.halt())
            self._started_motion = False
            return _OK
        mode = snap.mode
        if mode not in DRIVING_MODES:  # the firmware stopped the wheels if it fell
            self._last_mode = mode  # (the command is sent again once back)
            return self.wait_for_driving_mode()
        self._out_of_driving_since = None  # what stranded() does in Safe/Full, without its call
        if self._last_mode not in DRIVING_MODES:
            self.send(self.command())
            self._started_motion = True
        self._last_mode = mode
        return _RUN


@declare(
    "turn",
    kind="action",
    params=(
        Param("angle", ANGLE, required=True, minimum=-3600, maximum=3600,
              doc="heading change; positive turns left (counter-clockwise)",
              signs=("left", "right")),
        Param("speed", SPEED, default="100 mm/s", minimum=moving_minimum(),
              maximum=_VELOCITY.maximum,
              doc="wheel speed while spinning in place (slower than 15 mm/s, the wheels stand "
                  "still)"),
    ),
    reads=ENCODER_PACKETS,
    sends=opcodes("drive"),
    primary="angle",
)  # fmt: skip
class Turn(Drive):
    """Turn in place by an angle measured by the wheel encoders, then halt."""

    def start(self) -> None:
        super().start()
        self._end = ("angle", abs(self.number("angle")))

    def command(self) -> oi.Command:
        return oi.spin(round(self.value("speed")), clockwise=self.value("angle") < 0)


@declare(
    "backtrack",
    kind="action",
    params=(
        Param("distance", DISTANCE, required=True, minimum=0, maximum=1000,
              doc="how far to back up at most: no further than the floor the robot just "
                  "drove, its first 6 cm (under its own body) aside"),
        Param("speed", SPEED, default="150 mm/s", minimum=moving_minimum(),
              maximum=_VELOCITY.maximum, doc="backing speed"),
    ),
    reads=ENCODER_PACKETS,
    sends=opcodes("drive"),
    primary="distance",
)  # fmt: skip
class Backtrack(Drive):
    """Back up straight, up to ``distance``, only over the floor the robot has just driven
    (its last 60 cm, faced the way it faces now; the first 6 cm, under its own body, need
    none), then halt: SUCCESS, at once when none may be backed over.

    Why: a Create 2 (a Roomba) has no sensor behind it, no bumper and no cliff sensor behind
    the wheels, and a fixed back-off after a turn in place goes over floor it never drove:
    ``patrol.yaml`` backed 15 cm after a cliff met a few centimetres after its 60 deg turn,
    along a stair's edge (the drive back is what ``drive: {velocity: -150 mm/s, distance:
    15cm}`` sends). What it may back over is the run's trail
    (:mod:`~roomba_bt.behaviours.reversing`), which ``drive``, ``turn``, ``backtrack`` and
    ``wall_follow`` keep as they drive; after a move none of them saw, only the first 6 cm.
    Its message says how far it backed when that is less than asked."""

    def start(self) -> None:
        super().start()
        wanted = self.number("distance")
        allowed = self._trail.backable(self.snapshot.odometry, wanted)
        self._end = ("distance", allowed)
        self.feedback_message = (
            f"backed {allowed / 10:.0f} cm of {wanted / 10:.0f} cm: the floor further back "
            "is floor it has not just driven"
            if allowed < wanted
            else ""
        )

    def command(self) -> oi.Command:
        return oi.drive(-round(self.value("speed")), _RADIUS_WORDS["straight"])


@declare(
    "stop",
    kind="action",
    at_once=True,
    params=(Param("motors", BOOL, default=False, doc="also switch the brushes and vacuum off"),),
    sends=opcodes("drive", "motors"),
    halts_only=True,  # Drive 0
    stops_only=lambda params: True,  # Drive 0, and Motors 0 if asked
)
class Stop(Action):
    """Stop the wheels (Drive 0: ``[137][0][0][0][0]``), and the motors if asked.

    Out of Safe and Full (the robot fell to Passive by itself: a cliff, a wheel drop, the
    charger; or ``mode: passive``), where the mode guard refuses Drive and Motors, it sends
    nothing: SUCCESS, said, when no built-in cycle may be driving (the OI stopped the wheels
    and motors already), FAILURE, said, while one may (:meth:`~.base.Action.stopped_already`,
    as ``motors`` off). ``validate`` accepts it where the tree can reach Passive with no
    cycle it started (Clean, Spot, Max, Seek Dock) still driving, and refuses it where one
    may (docs/protocol.md, "Actuators in Passive")."""

    def update(self) -> Status:
        halt = oi.halt()
        if self.will_be_refused(halt):
            return self.stopped_already(halt)
        self.send(halt)
        if self.value("motors"):
            self.send(oi.motors_off())
        return _OK


# --------------------------------------------------------------------------- built-in modes


class _BuiltIn(Action):
    opcode_helper = staticmethod(oi.clean)

    def update(self) -> Status:
        self.send(type(self).opcode_helper())
        return _OK


@declare("clean", kind="action", at_once=True, sends=opcodes("clean"))
class Clean(_BuiltIn):
    """Start the robot's own cleaning cycle (Clean 135); the OI drops to Passive."""

    opcode_helper = staticmethod(oi.clean)


@declare("spot", kind="action", at_once=True, sends=opcodes("spot"))
class Spot(_BuiltIn):
    """Start spot cleaning (Spot 134); the OI drops to Passive."""

    opcode_helper = staticmethod(oi.spot)


@declare("max", kind="action", at_once=True, sends=opcodes("max"))
class MaxClean(_BuiltIn):
    """Start a Max cleaning cycle (Max 136), until the battery runs out; Passive."""

    opcode_helper = staticmethod(oi.max_clean)


@declare(
    "seek_dock",
    kind="action",
    params=(
        Param("wait", BOOL, default=True, doc="RUNNING until packet 34 shows the home base"),
        # at least one tick: a timeout of 0 fails before the robot could have moved
        Param("timeout", DURATION, minimum=SLOT_SECONDS, doc="FAILURE if not docked by then"),
    ),
    reads=CHARGING_SOURCES_PACKETS,
    sends=opcodes("seek_dock"),
)  # fmt: skip
class SeekDock(Action):
    """Send Seek Dock (143) and, by default, wait until the home base powers the robot."""

    def start(self) -> None:
        self._start_time = self.snapshot.time
        self._sent = False

    def update(self) -> Status:
        if not self._sent:
            self.send(oi.seek_dock())
            self._sent = True
            if not self.value("wait"):
                return _OK
        snap = self.snapshot
        if on_home_base(snap.frame):
            return _OK
        timeout = self.value("timeout")
        if timeout is not None and snap.time - self._start_time >= timeout:
            self.feedback_message = f"did not reach the home base within {duration_said(timeout)}"
            return _FAIL
        return _RUN


# --------------------------------------------------------------------------- actuators


@dataclass(frozen=True, slots=True)
class PercentOfByte:
    """A byte the spec gives as a number (the power LED's intensity, a motor's duty cycle)
    that a mission writes as a percent of its full value, ``highest``: ``percent x highest
    / 100``, rounded. A bare number in the byte's range is most likely the spec's byte
    written as it reads: its refusal says the percent that sends it, where the usual hint
    (``write the unit: 128%``) led out of range."""

    lowest: int
    highest: int
    #: what the spec calls the byte (``byte``, ``duty cycle``)
    spec_word: str
    #: the percents allowed and what they mean, said first in every refusal
    allowed: str

    def byte(self, percent: float) -> int:
        """The byte sent for ``percent``: ``50%`` of the LED is 128, ``-100%`` of a brush
        -127."""
        return round(percent * self.highest / 100)

    def parse(self, value: object) -> float:
        """A percent, as the mission writes it; a bare number refused with its percent."""
        if isinstance(value, bool):  # a switch's word (``vacuum: on``) where a share is
            raise UnitError(
                f"expected a percent {self.allowed}, got {described(value)}: write "
                f"{'100%' if value else '0%'}"
            )
        said = f"expected a percent {self.allowed}, got {quoted(value)}"
        try:
            return float(PERCENT.parse(value))
        except BareNumber as exc:
            number = exc.value
            if not (number == int(number) and self.lowest <= number <= self.highest):
                raise UnitError(said) from None
            percent = round(number * 100 / self.highest)
            sent = self.byte(percent)
            byte = f"{number:g} is {percent}%" + (f" (sent as {sent})" if sent != number else "")
            percent_too = f"; or {number:g}% if that was meant" if abs(number) <= 100 else ""
            raise UnitError(
                f"{said}: the spec's {self.spec_word} {self.lowest}..{self.highest} is written "
                f"as a percent here: {byte}{percent_too}"
            ) from None

    def value_type(self) -> ValueType:
        """A percent (its schema, its unit) read by :meth:`parse`."""
        return replace(PERCENT, parse=self.parse)


#: ``motors``' switches: :func:`~roomba_bt.oi.bits.motor_bits`' keywords, brushes first
_MOTORS = ("main_brush", "side_brush", "vacuum", "side_brush_clockwise", "main_brush_outward")
#: the switches that run a motor (the others only say its direction)
_RUNNING = _MOTORS[:3]


def _switched_off(names: tuple[str, ...]) -> Callable[[Mapping[str, Any]], bool]:
    """A ``stops_only`` (validate's, for Passive): each of ``names`` is given false or left
    out (false by default): the Motors sent runs nothing. A ``@key`` may be true at run time."""
    return lambda params: all(params.get(name, False) is False for name in names)


#: the brush of each direction switch of ``motors``: ``pwm_motors`` writes it as its sign
_BRUSH_OF_DIRECTION = {
    "side_brush_clockwise": "side_brush", "main_brush_outward": "main_brush",
}  # fmt: skip


def _motor_switch(name: str) -> ValueType:
    """A switch of ``motors`` or ``vacuum`` (a bool, ``name`` its motor), whose refusal of a
    percent points to ``pwm_motors`` (a direction switch to its brush's negative percent):
    ``motors: {vacuum: 50%}`` was refused with "expected true or false" and no word of the
    leaf that takes one."""
    brush = _BRUSH_OF_DIRECTION.get(name)
    motor, sign = (name, "") if brush is None else (brush, "-")

    def parse(value: object) -> bool:
        try:
            return bool(BOOL.parse(value))
        except UnitError as exc:
            if not isinstance(value, str) or value.strip().startswith("@"):
                raise
            try:
                PERCENT.parse(value)
            except UnitError:
                raise exc from None
            raise UnitError(
                f"{exc}: a motor's power is pwm_motors's (PWM Motors 144): "
                f"`pwm_motors: {{{motor}: {sign}{value.strip()}}}`; motors switches it on at full "
                "power or off"
            ) from None

    return replace(BOOL, parse=parse)


@declare(
    "motors",
    kind="action",
    at_once=True,
    params=tuple(Param(name, _motor_switch(name), default=False) for name in _MOTORS),
    sends=opcodes("motors"),
    stops_only=_switched_off(_RUNNING),
)
class Motors(Action):
    """Switch the cleaning motors (Motors 138 ``[138][bits]``); unnamed ones go off."""

    def update(self) -> Status:
        bits = motor_bits(**{name: bool(self.value(name)) for name in _MOTORS})
        return self.send_going(oi.motors(bits))


@declare(
    "vacuum",
    kind="action",
    at_once=True,
    params=(Param("on", _motor_switch("vacuum"), required=True,
                  doc="vacuum on or off (other motors go off)"),),
    sends=opcodes("motors"),
    primary="on",
    stops_only=_switched_off(("on",)),
)  # fmt: skip
class Vacuum(Action):
    """Vacuum alone on or off (Motors 138, bit 1)."""

    def update(self) -> Status:
        return self.send_going(oi.motors(motor_bits(vacuum=bool(self.value("on")))))


#: a brush's duty cycle (PWM Motors 144: -127..127, below 0 the other way) as a percent
#: of 127: the spec's "128 * 25% = 32" is 32 here too, and 100% is the byte's 127
_BRUSH_DUTY = PercentOfByte(
    _MAIN_BRUSH_PWM.minimum,
    _MAIN_BRUSH_PWM.maximum,
    "duty cycle",
    "-100..100% (0% off, 100% full, below 0% the other way)",
)
# one percent for both brushes: the table gives them one range
assert (_SIDE_BRUSH_PWM.minimum, _SIDE_BRUSH_PWM.maximum) == (_BRUSH_DUTY.lowest, 127)
#: the vacuum's (0..127: it runs one way only)
_VACUUM_DUTY = PercentOfByte(
    _VACUUM_PWM.minimum, _VACUUM_PWM.maximum, "duty cycle", "0..100% (0% off, 100% full)"
)
#: ``pwm_motors``' parameters, in the command's order, and each one's percent
_DUTIES: dict[str, PercentOfByte] = {
    "main_brush": _BRUSH_DUTY, "side_brush": _BRUSH_DUTY, "vacuum": _VACUUM_DUTY,
}  # fmt: skip


def _duties_off(params: Mapping[str, Any]) -> bool:
    """``pwm_motors``' ``stops_only`` (validate's, for Passive): each motor given a percent
    whose duty cycle is 0, or left out (0% by default). A ``@key`` may be more at run time."""
    return all(
        isinstance(value := params.get(name, 0.0), int | float) and duty.byte(value) == 0
        for name, duty in _DUTIES.items()
    )


def _brush_param(name: str, signs: tuple[str, str]) -> Param:
    """A brush's percent; ``signs``: the way it turns above 0% and below, as the spec says
    them (positive is the cleaning direction), said after its value in the leaf's name."""
    return Param(
        name, _BRUSH_DUTY.value_type(), default="0%", minimum=-100, maximum=100, signs=signs,
        doc=f"-100% .. 100% of full power; below 0% it turns {signs[1]}",
    )  # fmt: skip


@declare(
    "pwm_motors",
    kind="action",
    at_once=True,
    params=(
        _brush_param("main_brush", ("inward", "outward")),
        _brush_param("side_brush", ("counterclockwise", "clockwise")),
        Param("vacuum", _VACUUM_DUTY.value_type(), default="0%", minimum=0, maximum=100,
              doc="0% .. 100% of full power (it runs one way only)"),
    ),
    sends=opcodes("pwm_motors"),
    stops_only=_duties_off,
)  # fmt: skip
class PwmMotors(Action):
    """Run the cleaning motors at a part of their full power (PWM Motors 144
    ``[144][main brush][side brush][vacuum]``, each a duty cycle: the percent of 127);
    unnamed ones go off.

    A gentler brush and a quieter vacuum than ``motors``' full power. The safe stop's and
    ``stop``'s Motors 0 (``[138][0]``) switches them off as it does those ``motors`` ran:
    both commands set the same three drivers (the 600 spec: with Motors "all motors will
    run at maximum speed when enabled")."""

    def update(self) -> Status:
        duties = (duty.byte(float(self.value(name))) for name, duty in _DUTIES.items())
        return self.send_going(oi.pwm_motors(*duties))


#: the power LED's intensity (LEDs 139: 0 off .. 255 full), written as a percent
_LED_BYTE = PercentOfByte(
    _LED_INTENSITY.minimum, _LED_INTENSITY.maximum, "byte", "0..100% (0% off, 100% full)"
)
LED_INTENSITY = _LED_BYTE.value_type()


#: the power LED's colours by name, as the byte LEDs (139) sends: "0 = green, 255 = red.
#: Intermediate values are intermediate colors (orange, yellow, etc)" (both specs); orange
#: (amber, the other name makers use for it) is the middle of that range
POWER_COLORS: dict[str, int] = {
    "green": _LED_COLOR.minimum,
    "orange": (_LED_COLOR.minimum + _LED_COLOR.maximum + 1) // 2,
    "amber": (_LED_COLOR.minimum + _LED_COLOR.maximum + 1) // 2,
    "red": _LED_COLOR.maximum,
}
#: the names, those of one byte together: ``green (0), orange or amber (128), red (255)``
_COLORS_SAID = ", ".join(
    f"{' or '.join(n for n, b in POWER_COLORS.items() if b == byte)} ({byte})"
    for byte in dict.fromkeys(POWER_COLORS.values())
)


def _power_color(value: object) -> int:
    """A colour's name (:data:`POWER_COLORS`) or the spec's byte as a number: the byte.
    A name too, so that ``power_color: red`` is not "expected an integer" with no word of
    what 0 and 255 are. Every refusal lists both ways to write it."""
    if isinstance(value, str) and value in POWER_COLORS:
        return POWER_COLORS[value]
    if isinstance(value, int) and not isinstance(value, bool):
        return int(INT.parse(value))  # the range is the parameter's to check, and say
    hint = closest(value, tuple(POWER_COLORS)) if isinstance(value, str) else ""
    raise UnitError(
        f"expected a power LED colour, got {described(value)}{hint}: one of {_COLORS_SAID}, "
        f"or a number {_LED_COLOR.minimum}..{_LED_COLOR.maximum} (the spec's byte: 0 green .. "
        "255 red, the colours between)"
    )


#: the schema's bounds hold the numbers only (JSON Schema's minimum ignores a text)
POWER_COLOR = ValueType(
    "power_color",
    _power_color,
    takes=("int",),
    json_schema=(
        ("anyOf", [{"enum": list(POWER_COLORS)}, *INT.schema()["anyOf"]]),
        ("minimum", _LED_COLOR.minimum),
        ("maximum", _LED_COLOR.maximum),
    ),
)


@declare(
    "leds",
    kind="action",
    at_once=True,
    params=(
        *(Param(name, BOOL, default=False, spec_name=LED_SPEC_NAMES.get(name, ""))
          for name in LED_NAMES),
        Param("power_color", POWER_COLOR, default="green", minimum=_LED_COLOR.minimum,
              maximum=_LED_COLOR.maximum,
              doc=f"{', '.join(POWER_COLORS)}, or 0 green .. 255 red (the spec's byte)"),
        Param("power_intensity", LED_INTENSITY, default="0%", minimum=0, maximum=100,
              doc="0% off .. 100% full (the spec's byte 0..255)"),
    ),
    sends=opcodes("leds"),
)  # fmt: skip
class Leds(Action):
    """Set the LEDs (LEDs 139 ``[139][led bits][power colour][power intensity]``)."""

    def update(self) -> Status:
        names = [n for n in LED_NAMES if self.value(n)]
        intensity = _LED_BYTE.byte(float(self.value("power_intensity")))
        return self.send_accepted(
            oi.leds(led_bits(*names), int(self.value("power_color")), intensity)
        )


#: the slot ``song`` stores a song in (Song 140) and ``play`` plays it from (Play 141): one
#: parameter, its range the opcode table's
_SONG_SLOT = Param("number", INT, default=0, minimum=SONG_NUMBER.minimum,
                   maximum=SONG_NUMBER.maximum, doc="song slot")  # fmt: skip


@declare(
    "song",
    kind="action",
    at_once=True,
    params=(
        _SONG_SLOT,
        Param("notes", NOTES, required=True,
              doc=f'e.g. ["C4 250ms", "rest 125ms", "G4 500ms"]; {_LOWEST}..{_HIGHEST}, '
                  f'sharps (C#4, not Db4), {_NOTE_LENGTHS} each'),
    ),
    sends=opcodes("song"),
)  # fmt: skip
class Song(Action):
    """Define a song (Song 140 ``[140][number][length][note][64ths]...``)."""

    def update(self) -> Status:
        notes = [Note(n, d) for n, d in self.value("notes")]
        self.send(oi.song(int(self.value("number")), notes))
        return _OK


#: how long after its Play a song must show in packet 37 (when streamed): the robot shows it
#: in the frame after the one the Play went out with; the rest is a real link's slack
SONG_START_S = 0.25
#: a song this short (s) may never show in packet 37: the robot updates its values every
#: 15 ms (600 spec, "Input Commands") and streams them every 15 ms, not in step, so one or
#: two of the shortest notes (1/64 s each) can start and end between two frames' values.
#: Three frames: any longer song spans an update the stream carries
SHORT_SONG_S = 3 * SLOT_SECONDS
_SONG_PLAYING = PACKETS_BY_NAME["song_playing"].id
_SONG_NUMBER = PACKETS_BY_NAME["song_number"].id


@declare(
    "play",
    kind="action",
    params=(_SONG_SLOT,),
    sends=opcodes("play"),
    primary="number",
)
class Play(Action):
    """Play a defined song (Play 141 ``[141][number]``): SUCCESS once the robot shows it
    playing (packet 37, when the mission reads ``song_playing``, and packet 36 showing its
    slot, when the mission reads ``song_number``: FAILURE if no frame shows it within
    0.25 s), else on the next frame. A song of at most 45 ms that this run defined and no
    frame showed succeeds once its length and a frame have passed: the stream can miss a
    song that short. FAILURE at once out of Safe and Full, where the robot refuses Play,
    nothing sent (in 0.1.0 it said SUCCESS).

    Packet 37 alone cannot tell this song from one still playing, which the robot goes on
    with, ignoring the Play: a mission that reads ``song_number`` too has that told apart.

    So ``play`` then ``wait ... until: {sensor: song_playing == 0}`` waits for the song's
    end. Were ``play`` to succeed on the tick it is sent, the wait would read that tick's
    frame, from before the Play, pass at once, and the next ``play`` go out in the same
    tick. :data:`SONG_START_S` is the 0.25 s; :data:`SHORT_SONG_S` the 45 ms."""

    def start(self) -> None:
        self._sent_at: float | None = None
        #: whether a frame since the Play showed a song playing (this one or another)
        self._seen_playing = False

    def update(self) -> Status:
        snap = self.snapshot
        number = int(self.value("number"))
        if self._sent_at is None:
            if self.send_accepted(oi.play(number)) is _FAIL:
                return _FAIL
            self._sent_at = snap.time
            return _RUN
        frame = snap.frame
        playing = _SONG_PLAYING not in frame or frame.song_playing
        other = None if _SONG_NUMBER not in frame else frame.song_number
        if playing and other in (None, number):
            return _OK
        self._seen_playing = self._seen_playing or playing
        elapsed = snap.time - self._sent_at
        if not self._seen_playing and self._played_unseen(number, elapsed):
            return _OK
        if elapsed < SONG_START_S:
            return _RUN
        after = f"{duration_said(SONG_START_S)} after Play"
        if playing:
            self.feedback_message = (
                f"song {number} did not start: packet 36 showed song {other} {after} (a song "
                "still playing: the robot ignores Play then; wait until song_playing == 0 first)"
            )
        else:
            self.feedback_message = (
                f"song {number} did not start: packet 37 showed no song playing {after} (a "
                "slot the robot holds no song in, or a song still playing: the robot ignores "
                "Play then)"
            )
        return _FAIL

    def _played_unseen(self, number: int, elapsed: float) -> bool:
        """Whether the song in slot ``number``, never shown by packet 37, has played: this
        run defined it no longer than :data:`SHORT_SONG_S`, and its length and a frame have
        passed since the tick of the Play (written after that tick, the Play may reach the
        robot a frame later), so the frame read now was taken after its end, and a ``play``
        after this one is not ignored for it. Said, in the feedback message."""
        robot = self.robot
        seconds = None if robot is None else robot.outbox.song_seconds(number)
        if seconds is None or seconds > SHORT_SONG_S + 1e-9:
            return False
        if elapsed < seconds + SLOT_SECONDS - 1e-9:
            return False
        self.feedback_message = (
            f"song {number} lasts {seconds * 1000:g} ms, too short for packet 37 to show it "
            "for sure: taken as played once that and a frame had passed"
        )
        return True


# --------------------------------------------------------------------------- time, log, data


@declare(
    "wait",
    kind="action",
    never_fails=True,
    params=(Param("duration", DURATION, required=True, minimum=0),),
    primary="duration",
)
class Wait(Action):
    """RUNNING for a duration of mission time, then SUCCESS."""

    def start(self) -> None:
        self._start_time = self.snapshot.time
        self._lasts = float(self.value("duration")) - 1e-9  # read once a start

    def update(self) -> Status:
        robot = self.robot  # the handle's snapshot, without the property's call (every tick)
        elapsed = (robot.snapshot if robot is not None else self.snapshot).time - self._start_time
        return _OK if elapsed >= self._lasts else _RUN


@declare(
    "log",
    kind="action",
    at_once=True,
    never_fails=True,
    params=(
        Param("message", STR, required=True),
        Param("level", enum("debug", "info", "warning", "error"), default="info"),
    ),
    primary="message",
)
class Log(Action):
    """Write a message to the mission log (logger ``roomba_bt.mission``); the last one said
    at ``info`` or above is the run summary's ``mission said`` line."""

    #: the mission time this leaf last said its message at (info or above); None: not yet
    said_at: float | None = None

    def update(self) -> Status:
        level = getattr(logging, str(self.value("level")).upper())
        # a line of the log, not a page: a message given by -p or a default may be 10 MB
        message = shortened(str(self.value("message")), TEXT_LIMIT)
        log.log(level, "%s", message)
        # one line: the tree shown at the end puts it on the leaf's own
        self.feedback_message = escaped(message, ANY_CONTROL)
        if level >= logging.INFO:  # debug is the author's own tracing, not the run's story
            self.said_at = self.snapshot.time
        return _OK


def last_said(root: Behaviour) -> str | None:
    """The message of the ``log`` leaf the run said last (info or above), for the summary;
    None where none spoke. A mission that succeeds by a way out (the patrol docked on a low
    battery before any lap) read ``outcome SUCCESS`` and nothing else: its own ``log`` says
    which way it ended. Two said in one tick are ordered as the tick went, depth first."""
    said = [
        (node.said_at, order, node.feedback_message)
        for order, node in enumerate(root.iterate())
        if isinstance(node, Log) and node.said_at is not None
    ]
    return max(said)[2] if said else None


@declare(
    "set",
    kind="action",
    at_once=True,
    never_fails=True,  # a value not of the key's type raises (KeyType), never FAILURE
    params=(
        Param("key", STR, required=True, from_blackboard=False, doc="a declared key"),
        Param("value", ANY, required=True, doc="typed by the key's declaration"),
    ),
    writes_keys=("key",),
)
class SetKey(Action):
    """Write a value to a blackboard key."""

    def update(self) -> Status:
        write_key(str(self.value("key")), self.value("value"), self.name)
        return _OK


@declare(
    "mark",
    kind="action",
    at_once=True,
    never_fails=True,  # as set: the odometry is always there to remember
    params=(Param("key", STR, required=True, from_blackboard=False,
                  doc="a key declared with type mark"),),
    reads=ENCODER_PACKETS,
    writes_keys={"key": MARK},
    primary="key",
)  # fmt: skip
class Mark(Action):
    """Remember the odometry now, for ``odometry: {since: key, ...}``."""

    def update(self) -> Status:
        write_key(str(self.value("key")), self.snapshot.odometry, self.name)
        return _OK


ACTIONS: tuple[type[Action], ...] = (
    Mode, Drive, Turn, Backtrack, Stop, Clean, Spot, MaxClean, SeekDock, Motors, Vacuum, PwmMotors,
    Leds, Song, Play, Wait, Log, SetKey, Mark,
)  # fmt: skip
