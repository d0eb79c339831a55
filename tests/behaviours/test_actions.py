"""Every action ticked against a stub robot whose frames the test sets."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import pytest
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours import actions as a
from roomba_bt.behaviours import builtin_registry
from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import BlackboardRef, read_key, write_key
from roomba_bt.behaviours.declare import declare
from roomba_bt.behaviours.units import ItemErrors
from roomba_bt.oi.encode import (
    NAMED_NOTES,
    Command,
    drive,
    drive_direct,
    drive_straight,
    motors,
    note_name,
    pwm_motors,
    song,
    turns_wheels,
)
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import mm_to_counts
from roomba_bt.oi.opcodes import (
    COMMANDS_BY_NAME,
    NOTE_DURATION,
    NOTE_NUMBER,
    PLAYABLE_NOTES,
    SONG_LENGTH,
    SONG_NUMBER,
)
from roomba_bt.robot.interface import Odometry
from roomba_bt.robot.testing import StubRobot

from .example_params import EXAMPLE_PARAMS


def tick(behaviour: Behaviour) -> Status:
    behaviour.tick_once()
    return behaviour.status


HALT = [137, 0, 0, 0, 0]
Make = Callable[..., Any]


def data(robot: StubRobot) -> list[list[int]]:
    return [list(c.data) for c in robot.flush()]


def encoders(mm_left: float, mm_right: float) -> dict[int, int]:
    return {
        43: round(mm_to_counts(mm_left)),
        44: round(mm_to_counts(mm_right)),
    }


# ------------------------------------------------------------------ mode


@pytest.mark.parametrize(
    ("target", "opcode", "mode"),
    [("safe", 131, OIMode.SAFE), ("full", 132, OIMode.FULL), ("passive", 128, OIMode.PASSIVE)],
)
def test_mode_sends_its_opcode_and_waits_for_packet_35(
    target: str, opcode: int, mode: OIMode, make: Make
) -> None:
    robot = StubRobot(mode=OIMode.OFF if target == "passive" else OIMode.PASSIVE)
    behaviour = make(a.Mode, robot=robot, to=target, timeout=2.0)
    robot.set_frame({35: int(robot.snapshot.mode)})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[opcode]]
    robot.set_frame({35: int(mode)})
    assert tick(behaviour) is Status.SUCCESS


def test_mode_resends_and_then_fails_after_its_timeout(make: Make) -> None:
    robot = StubRobot(mode=OIMode.PASSIVE)
    behaviour = make(a.Mode, robot=robot, to="safe", timeout=1.0)
    robot.set_frame({35: 1})
    statuses = [tick(behaviour)]
    while statuses[-1] is Status.RUNNING and len(statuses) < 200:
        robot.set_frame({35: 1})
        statuses.append(tick(behaviour))
        robot.flush()
    assert statuses[-1] is Status.FAILURE
    assert robot.snapshot.time == pytest.approx(1.005)  # first slot at or after 1 s
    assert sum(1 for c in robot.sent if c.opcode == 131) == 2  # at 0 s and 0.51 s


# ------------------------------------------------------------------ drive


def test_drive_sends_drive_once_and_runs_until_preempted(robot: StubRobot, make: Make) -> None:
    behaviour = make(a.Drive, velocity=-200.0, radius=500.0)
    robot.set_frame({35: 2})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[137, 0xFF, 0x38, 0x01, 0xF4]]  # the spec's example
    robot.set_frame({35: 2})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == []
    behaviour.stop(Status.INVALID)  # preempted by a guard or a higher branch
    assert data(robot) == [HALT]


def test_drive_straight_uses_the_special_radius_not_a_clamped_one(
    robot: StubRobot, make: Make
) -> None:
    behaviour = make(a.Drive, velocity=200.0, radius="straight")
    robot.set_frame({35: 2})
    tick(behaviour)
    assert data(robot) == [[137, 0, 200, 0x80, 0x00]]


def test_drive_with_wheel_speeds_uses_drive_direct(robot: StubRobot, make: Make) -> None:
    behaviour = make(a.Drive, left=100.0, right=-100.0)
    robot.set_frame({35: 2})
    tick(behaviour)
    assert data(robot) == [[145, 0xFF, 0x9C, 0x00, 0x64]]


def test_drive_for_a_distance_stops_by_odometry(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 2, **encoders(0, 0)})
    behaviour = make(a.Drive, velocity=200.0, distance=100.0)
    assert tick(behaviour) is Status.RUNNING
    robot.set_frame({35: 2, **encoders(60, 60)})
    assert tick(behaviour) is Status.RUNNING
    robot.set_frame({35: 2, **encoders(101, 101)})
    assert tick(behaviour) is Status.SUCCESS
    assert data(robot)[-1] == HALT


def test_drive_for_an_angle_stops_by_odometry(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 2, **encoders(0, 0)})
    behaviour = make(a.Drive, velocity=100.0, radius=200.0, angle=45.0)
    tick(behaviour)
    quarter = math.radians(46) * 235.0 / 2
    robot.set_frame({35: 2, **encoders(-quarter, quarter)})
    assert tick(behaviour) is Status.SUCCESS


def test_drive_for_a_duration_counts_mission_time(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 2})
    behaviour = make(a.Drive, velocity=100.0, duration=0.15)
    statuses = [tick(behaviour)]
    for _ in range(10):
        robot.set_frame({35: 2})
        statuses.append(tick(behaviour))
    assert statuses[:10] == [Status.RUNNING] * 10
    assert statuses[10] is Status.SUCCESS  # 10 slots of 15 ms


def test_drive_resends_after_a_fall_back_to_passive(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 2})
    behaviour = make(a.Drive, velocity=100.0)
    tick(behaviour)
    robot.flush()
    robot.set_frame({35: 1})
    tick(behaviour)
    robot.set_frame({35: 2})
    tick(behaviour)
    robot.flush()
    assert [c.opcode for c in robot.sent] == [137, 137]


def test_drive_fails_when_the_robot_stays_out_of_safe(robot: StubRobot, make: Make) -> None:
    """A cliff dropped the robot to Passive and nothing brings it back: after a second the
    drive fails with the cause, instead of waiting until the robot sleeps (5 minutes) and
    the run ends as a lost connection."""
    robot.set_frame({35: 2})
    behaviour = make(a.Drive, velocity=100.0)
    tick(behaviour)
    robot.flush()
    statuses = []
    while Status.FAILURE not in statuses and len(statuses) < 100:
        robot.set_frame({35: 1})
        statuses.append(tick(behaviour))
    assert statuses[:-1] == [Status.RUNNING] * 67  # a second of grace (67 slots of 15 ms)
    assert statuses[-1] is Status.FAILURE
    assert behaviour.feedback_message.startswith("the robot left Safe/Full mode")
    assert robot.flush() == []  # no halt: the firmware stopped the wheels already


def test_drive_stopped_after_a_fall_back_to_passive_sends_no_halt(
    robot: StubRobot, make: Make
) -> None:
    """A cliff dropped the robot to Passive (the firmware stopped the wheels) and the same
    frame ended the drive (``until: cliff``): a halt there is refused by the mode guard, a
    refusal in the run's summary under a mission that did nothing wrong."""
    robot.set_frame({35: 2})
    behaviour = make(a.Drive, velocity=100.0)
    tick(behaviour)
    robot.flush()
    robot.set_frame({35: 1})
    behaviour.stop(Status.INVALID)
    assert robot.flush() == []
    robot.set_frame({35: 3})  # in Full a cliff does not stop the robot: the halt is sent
    tick(behaviour)
    robot.flush()
    behaviour.stop(Status.INVALID)
    assert data(robot) == [HALT]


def test_drive_reads_a_blackboard_value_when_it_starts(robot: StubRobot, make: Make) -> None:
    write_key("leg", 50.0)
    robot.set_frame({35: 2, **encoders(0, 0)})
    behaviour = make(a.Drive, velocity=100.0, distance=BlackboardRef("leg"))
    tick(behaviour)
    robot.set_frame({35: 2, **encoders(51, 51)})
    assert tick(behaviour) is Status.SUCCESS


def test_turn_spins_the_right_way_and_stops_at_the_angle(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 2, **encoders(0, 0)})
    behaviour = make(a.Turn, angle=-90.0, speed=100.0)
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[137, 0, 100, 0xFF, 0xFF]]  # clockwise: radius -1
    arc = math.radians(91) * 235.0 / 2
    robot.set_frame({35: 2, **encoders(arc, -arc)})
    assert tick(behaviour) is Status.SUCCESS
    assert data(robot) == [HALT]


def test_stop_halts_and_optionally_stops_motors(robot: StubRobot, make: Make) -> None:
    assert tick(make(a.Stop)) is Status.SUCCESS
    assert data(robot) == [HALT]
    tick(make(a.Stop, motors=True))
    assert data(robot) == [HALT, [138, 0]]


# ------------------------------------------------------------------ built-in modes


@pytest.mark.parametrize(("cls", "opcode"), [(a.Clean, 135), (a.Spot, 134), (a.MaxClean, 136)])
def test_cleaning_modes_send_their_opcode(
    robot: StubRobot, cls: type[a.Action], opcode: int, make: Make
) -> None:
    assert tick(make(cls)) is Status.SUCCESS
    assert data(robot) == [[opcode]]
    assert cls.declaration.leads_to is OIMode.PASSIVE


def test_seek_dock_waits_for_the_home_base(robot: StubRobot, make: Make) -> None:
    behaviour = make(a.SeekDock, wait=True, timeout=1.0)
    robot.set_frame({34: 0})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[143]]
    robot.set_frame({34: 1})  # internal charger only: not docked
    assert tick(behaviour) is Status.RUNNING
    robot.set_frame({34: 2})
    assert tick(behaviour) is Status.SUCCESS


def test_seek_dock_times_out(robot: StubRobot, make: Make) -> None:
    behaviour = make(a.SeekDock, wait=True, timeout=0.03)
    robot.set_frame({34: 0})
    tick(behaviour)
    robot.set_frame({34: 0}, ticks=2)
    assert tick(behaviour) is Status.FAILURE


def test_seek_dock_without_waiting(robot: StubRobot, make: Make) -> None:
    assert tick(make(a.SeekDock, wait=False)) is Status.SUCCESS


#: Safe, drive 0, motors off, Start: a built-in cycle's end
CYCLE_END = [[131], HALT, [138, 0], [128]]
PASSIVE, HOME_BASE = {35: int(OIMode.PASSIVE), 34: 0}, {35: int(OIMode.PASSIVE), 34: 2}


@pytest.mark.parametrize("cls", [a.Clean, a.Spot, a.MaxClean])
def test_a_cleaning_cycle_is_ended_when_its_leaf_is_stopped_after_it_succeeded(
    robot: StubRobot, make: Make, cls: type[a.Action]
) -> None:
    """Its SUCCESS (the cycle started) sends nothing more; stopped later (its parent
    halted by a guard, a timeout, a higher branch), it ends the cycle: on the home base
    too, which a Clean sent from the dock is about to leave."""
    behaviour = make(cls)
    assert tick(behaviour) is Status.SUCCESS
    assert len(data(robot)) == 1
    robot.set_frame(HOME_BASE)
    assert data(robot) == []
    behaviour.stop(Status.INVALID)
    assert data(robot) == CYCLE_END
    robot.set_frame(PASSIVE)
    behaviour.stop(Status.INVALID)  # ended once: nothing more
    assert data(robot) == []


@pytest.mark.parametrize(
    ("frame", "ending", "sent"),
    [
        (PASSIVE, Status.INVALID, CYCLE_END),
        (PASSIVE, Status.FAILURE, CYCLE_END),
        (HOME_BASE, Status.INVALID, []),  # docked: Seek Dock's cycle ended there
    ],
    ids=["halted", "failed", "halted on the home base"],
)
def test_seek_dock_ends_its_cycle_unless_docked(
    robot: StubRobot, make: Make, frame: dict[int, int], ending: Status, sent: list[list[int]]
) -> None:
    behaviour = make(a.SeekDock, wait=True)
    robot.set_frame({34: 0})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[143]]
    robot.set_frame(frame)
    behaviour.stop(ending)
    assert data(robot) == sent


def test_a_cycle_started_and_stopped_in_one_tick_is_not_written(
    robot: StubRobot, make: Make
) -> None:
    # a parallel's other branch ended it in the tick it started: nothing ever drove
    behaviour = make(a.Clean)
    assert tick(behaviour) is Status.SUCCESS
    behaviour.stop(Status.INVALID)
    assert data(robot) == []


def test_mode_passive_ends_a_cycle_that_may_still_drive(robot: StubRobot, make: Make) -> None:
    tick(make(a.Clean))
    data(robot)
    robot.set_frame(PASSIVE)
    assert tick(make(a.Mode, to="passive")) is Status.SUCCESS
    assert data(robot) == CYCLE_END
    robot.set_frame(PASSIVE)  # no cycle now: Passive already, nothing to send
    assert tick(make(a.Mode, to="passive")) is Status.SUCCESS
    assert data(robot) == []


# ------------------------------------------------------------------ actuators


def test_motors_bits_follow_the_spec_example(robot: StubRobot, make: Make) -> None:
    tick(make(a.Motors, main_brush=True, side_brush=True, side_brush_clockwise=True))
    assert data(robot) == [[138, 13]]


def test_vacuum_alone(robot: StubRobot, make: Make) -> None:
    tick(make(a.Vacuum, on=True))
    tick(make(a.Vacuum, on=False))
    assert data(robot) == [[138, 0]]  # same channel, same tick: the last wins
    assert a.Vacuum.declaration.is_actuator


@pytest.mark.parametrize(
    ("params", "sent"),
    [
        # the spec's example, 128 x 25% = 32, the side brush the other way (-32: 0xE0)
        ({"main_brush": 25.0, "side_brush": -25.0, "vacuum": 25.0}, [144, 32, 224, 32]),
        # 100% is 127, the most the byte holds (128 x 100% does not fit); -100% is -127
        ({"main_brush": -100.0, "side_brush": 100.0, "vacuum": 100.0}, [144, 129, 127, 127]),
        ({"main_brush": 40.0, "side_brush": 30.0, "vacuum": 50.0}, [144, 51, 38, 64]),
        ({"vacuum": 50.0}, [144, 0, 0, 64]),  # the motors left out go off
        ({}, [144, 0, 0, 0]),
    ],
)
def test_pwm_motors_sends_each_percent_as_the_spec_s_duty_cycle(
    robot: StubRobot, make: Make, params: dict[str, float], sent: list[int]
) -> None:
    """PWM Motors (144): a duty cycle each, main brush, side brush, vacuum; no mission leaf
    sent it until 0.2.0 (``motors`` runs each at full power or not at all)."""
    assert tick(make(a.PwmMotors, **params)) is Status.SUCCESS
    assert data(robot) == [sent]


def test_pwm_motors_started_in_passive_fails_and_one_that_runs_nothing_succeeds(
    make: Make,
) -> None:
    """Where the guard refuses PWM Motors (the robot fell to Passive), a duty cycle is not
    set: FAILURE, said, nothing queued; all at 0% asks for what Passive has already."""
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.set_frame({35: int(OIMode.PASSIVE)})
    running = make(a.PwmMotors, robot=robot, side_brush=-20.0)
    assert tick(running) is Status.FAILURE
    assert "Passive" in running.feedback_message
    assert tick(make(a.PwmMotors, robot=robot)) is Status.SUCCESS
    assert robot.flush() == []


def test_leds(robot: StubRobot, make: Make) -> None:
    tick(make(a.Leds, dock=True, power_color=255, power_intensity=100.0))
    assert data(robot) == [[139, 4, 255, 255]]


@pytest.mark.parametrize(
    ("written", "byte"), [("green", 0), ("orange", 128), ("amber", 128), ("red", 255), (200, 200)]
)
def test_the_power_led_colour_is_a_name_or_the_spec_s_byte(
    robot: StubRobot, make: Make, written: object, byte: int
) -> None:
    """``power_color: red`` said "expected an integer" until session 33."""
    tick(make(a.Leds, power_color=a.POWER_COLOR.parse(written)))
    assert data(robot) == [[139, 0, byte, 0]]


@pytest.mark.parametrize(
    ("written", "said"),
    [("rde", "got 'rde' (did you mean 'red'?): "), ("blue", "got 'blue': "), (1.5, "got 1.5: ")],
)
def test_a_power_led_colour_it_does_not_have_is_refused_listing_what_it_has(
    written: object, said: str
) -> None:
    with pytest.raises(a.UnitError) as caught:
        a.POWER_COLOR.parse(written)
    assert str(caught.value) == (
        f"expected a power LED colour, {said}one of green (0), orange or amber (128), red "
        "(255), or a number 0..255 (the spec's byte: 0 green .. 255 red, the colours between)"
    )


def test_song_and_play(robot: StubRobot, make: Make) -> None:
    tick(make(a.Song, number=1, notes=((60, 16), (0, 8))))
    tick(make(a.Play, number=1))
    assert data(robot) == [[140, 1, 2, 60, 16, 0, 8], [141, 1]]


SAFE = {35: int(OIMode.SAFE)}


def test_play_without_packet_37_succeeds_on_the_next_frame(robot: StubRobot, make: Make) -> None:
    """The first frame the robot could show the song in: a ``wait ... until: {sensor:
    song_playing == 0}`` after it reads that frame, not the one before the Play."""
    play = make(a.Play, number=2)
    assert tick(play) is Status.RUNNING
    assert data(robot) == [[141, 2]]
    robot.set_frame(SAFE)
    assert tick(play) is Status.SUCCESS
    assert data(robot) == []  # sent once


def test_play_with_packet_37_succeeds_once_the_song_shows(robot: StubRobot, make: Make) -> None:
    play = make(a.Play, number=0)
    assert tick(play) is Status.RUNNING
    robot.set_frame({**SAFE, 37: 0})  # the frame written before the robot took the Play
    assert tick(play) is Status.RUNNING
    robot.set_frame({**SAFE, 37: 1})
    assert tick(play) is Status.SUCCESS
    assert data(robot) == [[141, 0]]


def test_play_fails_when_the_song_never_shows(robot: StubRobot, make: Make) -> None:
    """A slot the robot holds no song in, or a song still playing (the robot ignores Play):
    said, not a SUCCESS for a song that never played."""
    play = make(a.Play, number=3)
    while tick(play) is Status.RUNNING:
        robot.set_frame({**SAFE, 37: 0})
    assert play.status is Status.FAILURE  # on the first frame SONG_START_S after the Play
    assert a.SONG_START_S <= robot.snapshot.time < a.SONG_START_S + SLOT_SECONDS
    assert play.feedback_message.startswith("song 3 did not start: packet 37 showed no song")


def _defined(robot: StubRobot, make: Make, number: int, notes: tuple[tuple[int, int], ...]) -> None:
    """Song ``number`` written to the robot (its length is what ``play`` goes by)."""
    tick(make(a.Song, number=number, notes=notes))
    robot.flush()


@pytest.mark.parametrize("notes", [((60, 1),), ((60, 1), (62, 1))])
def test_play_of_a_song_too_short_for_packet_37_succeeds_once_it_is_over(
    robot: StubRobot, make: Make, notes: tuple[tuple[int, int], ...]
) -> None:
    """One or two notes of 1/64 s can start and end between two frames' values: packet 37
    never shows them, and ``play`` failed after 0.25 s although the robot played the song.
    It succeeds on the first frame taken after the song's end however late in its frame the
    Play arrived (its length and a frame after the Play's tick), said."""
    _defined(robot, make, 2, notes)
    seconds = sum(d for _, d in notes) / 64
    play = make(a.Play, number=2)
    sent_at = robot.snapshot.time
    while tick(play) is Status.RUNNING:
        robot.set_frame({**SAFE, 37: 0})
    assert play.status is Status.SUCCESS
    elapsed = robot.snapshot.time - sent_at
    assert seconds + SLOT_SECONDS <= elapsed < seconds + 2 * SLOT_SECONDS
    assert play.feedback_message.startswith(f"song 2 lasts {seconds * 1000:g} ms, too short")


def test_play_of_a_short_song_another_song_kept_off_fails(robot: StubRobot, make: Make) -> None:
    """A frame showed a song playing (another slot's, packet 36): the robot ignored this
    Play, whose song's length passing proves nothing."""
    _defined(robot, make, 2, ((60, 1),))
    play = make(a.Play, number=2)
    assert tick(play) is Status.RUNNING
    robot.set_frame({**SAFE, 36: 0, 37: 1})
    assert tick(play) is Status.RUNNING
    while tick(play) is Status.RUNNING:
        robot.set_frame({**SAFE, 36: 0, 37: 0})
    assert play.status is Status.FAILURE


@pytest.mark.parametrize("defined", [None, ((60, 4),)])
def test_play_of_a_song_unseen_fails_unless_this_run_defined_it_short(
    robot: StubRobot, make: Make, defined: tuple[tuple[int, int], ...] | None
) -> None:
    """A slot this run wrote no song to (its length unknown) or a song of 1/16 s, which the
    stream shows: not seen, not played."""
    if defined is not None:
        _defined(robot, make, 2, defined)
    play = make(a.Play, number=2)
    while tick(play) is Status.RUNNING:
        robot.set_frame({**SAFE, 37: 0})
    assert play.status is Status.FAILURE
    assert play.feedback_message.startswith("song 2 did not start")


def test_play_with_packet_36_waits_for_its_own_slot_and_fails_on_another(
    robot: StubRobot, make: Make
) -> None:
    """Packet 37 shows a song playing when the robot ignored the Play for one still playing:
    with packet 36 streamed, SUCCESS only once it shows the slot played, else FAILURE, said."""
    play = make(a.Play, number=1)
    while tick(play) is Status.RUNNING:
        robot.set_frame({**SAFE, 36: 0, 37: 1})  # song 0 still playing
    assert play.status is Status.FAILURE
    assert play.feedback_message.startswith("song 1 did not start: packet 36 showed song 0")
    assert "wait until song_playing == 0 first" in play.feedback_message
    play = make(a.Play, number=1)
    assert tick(play) is Status.RUNNING
    robot.set_frame({**SAFE, 36: 1, 37: 1})
    assert tick(play) is Status.SUCCESS


def test_notes_parse_names_and_durations() -> None:
    assert a.NOTES.parse(["C4 250ms", "rest 125ms", "A#4 1s"]) == ((60, 16), (0, 8), (70, 64))
    with pytest.raises(a.UnitError, match="unknown note 'H4'"):
        a.NOTES.parse(["H4 1s"])
    with pytest.raises(a.UnitError, match="out of range"):
        a.NOTES.parse(["C4 5s"])
    with pytest.raises(a.UnitError, match="at most 16 notes"):
        a.NOTES.parse(["C4 100ms"] * 17)


@pytest.mark.parametrize(
    ("note", "said"),
    [
        ("200 1s", "unknown note '200': a note is written by its name, not its MIDI number: the "
                   "robot plays G1 (31) to G9 (127)"),
        ("69 1s", "unknown note '69': a note is written by its name, not its MIDI number: "
                  "write A4"),
        ("H4 1s", "unknown note 'H4': H is B in German names: write B4"),
        ("C#10 1s", "unknown note 'C#10': a note is a name, one of C, C#, D, D#, E, F, F#, G, "
                    "G#, A, A#, B, and an octave 0-9 (A4, C#5; the robot plays G1 (31) to G9 "
                    "(127)), or rest"),
        ("C1 1s", "note C1 (24) is outside the notes the robot plays, G1 to G9"),
        # a flat, a sharp or a German H whose pitch the robot does not play is said to be a
        # rest, not named as a note to write: "write G#9" (refused in turn), "write C10" and
        # "write B-1" (no such names), "write B9" (a rest)
        ("Ab9 1s", "unknown note 'Ab9': Ab9 is MIDI note 128, outside the notes the robot "
                   "plays, G1 to G9: it would sound as a rest (write rest for one)"),
        ("B#9 1s", "unknown note 'B#9': B#9 is MIDI note 132, outside the notes the robot"),
        ("Cb0 1s", "unknown note 'Cb0': Cb0 is MIDI note 11, outside the notes the robot"),
        ("Db1 1s", "unknown note 'Db1': Db1 is MIDI note 25, outside the notes the robot"),
        ("H9 1s", "unknown note 'H9': H is B in German names: H9 is MIDI note 131, outside"),
        ("C4 5s", "note duration '5s' is out of range: 16ms..3.98s (1..255 of 1/64 s)"),
    ],
)  # fmt: skip
def test_a_bad_note_says_what_it_found_and_what_is_allowed(note: str, said: str) -> None:
    """Each problem is the note's own, with its index, for the mission to say at the note
    (:class:`~roomba_bt.behaviours.units.ItemErrors`): "write A4, C#5 or rest" was all a
    MIDI number or a German H got."""
    with pytest.raises(ItemErrors) as caught:
        a.NOTES.parse(["C4 250ms", "D4 250ms", note])
    ((index, problem),) = caught.value.problems
    assert index == 2 and problem.startswith(said), problem
    assert str(caught.value) == f"note 3 of 3: {problem}"


def test_radius_type() -> None:
    assert a.RADIUS.parse("straight") == "straight"
    assert a.RADIUS.parse("50cm") == 500.0
    with pytest.raises(a.UnitError, match="spin_left"):
        a.RADIUS.parse("curvy")


# ------------------------------------------------------------------ time, log, data


def test_wait_counts_mission_time(robot: StubRobot, make: Make) -> None:
    robot.set_frame({})
    behaviour = make(a.Wait, duration=0.03)
    assert tick(behaviour) is Status.RUNNING
    robot.set_frame({})
    assert tick(behaviour) is Status.RUNNING
    robot.set_frame({})
    assert tick(behaviour) is Status.SUCCESS


def test_log_writes_to_the_mission_logger(
    robot: StubRobot, caplog: pytest.LogCaptureFixture, make: Make
) -> None:
    with caplog.at_level(logging.INFO, logger="roomba_bt.mission"):
        assert tick(make(a.Log, message="hello", level="warning")) is Status.SUCCESS
    assert [(r.levelname, r.message) for r in caplog.records] == [("WARNING", "hello")]


def test_set_and_mark_write_the_blackboard(robot: StubRobot, make: Make) -> None:
    tick(make(a.SetKey, key="count", value=3))
    assert read_key("count") == 3
    robot.set_frame({43: 0, 44: 0})
    robot.set_frame(encoders(100, 100))
    tick(make(a.Mark, key="here"))
    mark = read_key("here")
    assert isinstance(mark, Odometry)
    assert mark.distance_mm == pytest.approx(100, abs=0.5)


def test_every_action_declares_modes_from_the_opcode_table() -> None:
    assert a.Drive.declaration.modes == {OIMode.SAFE, OIMode.FULL}
    assert a.Leds.declaration.is_actuator
    assert not a.SeekDock.declaration.is_actuator
    assert OIMode.PASSIVE in a.SeekDock.declaration.modes
    assert a.Wait.declaration.modes == frozenset(OIMode)
    assert a.Mode.declaration.mode_after({"to": "full"}) is OIMode.FULL


def test_a_behaviour_ticked_without_a_robot_says_so() -> None:
    behaviour = a.Wait("wait", {"duration": 1.0})
    with pytest.raises(RuntimeError, match="before setup"):
        behaviour.tick_once()


@pytest.mark.parametrize(
    ("motor", "bit"),
    [("side_brush", 0x01), ("vacuum", 0x02), ("main_brush", 0x04),
     ("side_brush_clockwise", 0x08), ("main_brush_outward", 0x10)],
)  # fmt: skip
def test_each_motor_alone_sets_its_own_bit(
    robot: StubRobot, make: Make, motor: str, bit: int
) -> None:
    """Motors 138's bits (OI spec: side brush 0, vacuum 1, main brush 2, side brush clockwise
    3, main brush outward 4): a motor forced off (or on) fails here."""
    tick(make(a.Motors, **{motor: True}))
    assert data(robot) == [[138, bit]]


def test_every_motor_on_and_the_vacuum_alone_on(robot: StubRobot, make: Make) -> None:
    everything = ("main_brush", "side_brush", "vacuum", "side_brush_clockwise",
                  "main_brush_outward")  # fmt: skip
    tick(make(a.Motors, **dict.fromkeys(everything, True)))
    assert data(robot) == [[138, 0x1F]]
    robot.sent.clear()
    tick(make(a.Vacuum, on=True))
    assert data(robot) == [[138, 0x02]]


@declare("forgets_its_flags", kind="action", sends=(137,))
class ForgetsItsFlags(Action):
    """A plugin's action that drives and says nothing of it (no ``moves``, no
    ``_started_motion``): the wheels turned on after it ended."""

    def update(self) -> Status:
        self.send(drive_straight(200))
        return Status.RUNNING


def test_an_action_that_set_the_wheels_turning_halts_them_when_it_ends_unasked(
    robot: StubRobot, make: Make
) -> None:
    behaviour = make(ForgetsItsFlags)
    robot.set_frame({35: 2})
    tick(behaviour)
    assert data(robot) == [[137, 0, 200, 0x80, 0x00]]
    behaviour.stop(Status.INVALID)
    assert data(robot) == [HALT]


def test_a_wheel_command_that_moves_nothing_leaves_nothing_to_halt() -> None:
    assert not turns_wheels(drive(0, 0x8000)) and not turns_wheels(drive_direct(0, 0))
    assert turns_wheels(drive(-1, 1)) and turns_wheels(drive_direct(0, 5))


def test_what_declares_it_succeeds_at_once_succeeds_on_its_first_tick(make: Make) -> None:
    """``at_once``: the static checks take what such a leaf does as done within the tick it
    starts (a limit under a reactive fallback, a parallel's writes), so it must be true."""
    declared = [d for d in builtin_registry() if d.at_once]
    assert {d.name for d in declared} >= {
        "stop",
        "set",
        "log",
        "mark",
        "leds",
        "motors",
        "display",
        "press",
        "schedule_leds",
    }
    for declaration in declared:
        behaviour = make(declaration.cls, **EXAMPLE_PARAMS.get(declaration.name, {}))
        assert tick(behaviour) is Status.SUCCESS, declaration.name
    assert not a.Wait.declaration.at_once and not a.Drive.declaration.at_once


@pytest.mark.parametrize(
    ("last", "expected"),
    [
        (motors(0b111), [[138, 0], [128]]),
        (motors(0), [[128]]),
        (pwm_motors(0, -20, 40), [[138, 0], [128]]),  # a duty cycle: Motors 0 stops it too
        (pwm_motors(0, 0, 0), [[128]]),
    ],
)
def test_mode_passive_stops_the_motors_the_run_left_running_before_start(
    make: Make, last: Command, expected: list[list[int]]
) -> None:
    """Start (128) from Safe with the brushes on: Motors 0 first (the OI spec does not say
    Start stops them; before session 25 they were left to the firmware). Motors already off,
    only Start (the shipped missions' bytes are unchanged)."""
    robot = StubRobot(mode=OIMode.SAFE)
    robot.outbox.send(last)
    robot.flush()
    behaviour = make(a.Mode, robot=robot, to="passive", timeout=2.0)
    robot.set_frame({35: int(OIMode.SAFE)})
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == expected
    robot.set_frame({35: int(OIMode.SAFE)}, ticks=40)  # Start again after 0.5 s: no Motors
    assert tick(behaviour) is Status.RUNNING
    assert data(robot) == [[128]]


def test_the_song_leaf_and_the_encoder_check_the_opcode_tables_ranges() -> None:
    """Song (140)'s ranges live in the opcode table (``oi/opcodes.py``), and the mission
    language's ``song`` leaf and the encoder's ``song`` read them there: every note the
    language takes, the longest song, the longest note and the last slot encode; what the
    language refuses as a note the robot does not play is a byte the encoder would send as
    the rest the spec makes of it."""
    table = COMMANDS_BY_NAME["song"]
    assert table.args == (SONG_NUMBER, SONG_LENGTH) and table.tail is not None
    assert table.tail.item == (NOTE_NUMBER, NOTE_DURATION)
    assert COMMANDS_BY_NAME["play"].args == (SONG_NUMBER,)
    slot = a.Song.declaration.params[0]
    assert (slot.minimum, slot.maximum) == (SONG_NUMBER.minimum, SONG_NUMBER.maximum)
    schema = dict(a.NOTES.json_schema)
    assert (schema["minItems"], schema["maxItems"]) == (SONG_LENGTH.minimum, SONG_LENGTH.maximum)

    longest = a.NOTES.parse(["C4 3.984375s"] * SONG_LENGTH.maximum)
    assert longest[0] == (60, NOTE_DURATION.maximum)
    assert len(song(SONG_NUMBER.maximum, longest).data) == 3 + 2 * SONG_LENGTH.maximum
    with pytest.raises(a.UnitError, match=f"at most {SONG_LENGTH.maximum} notes"):
        a.NOTES.parse(["C4 100ms"] * (SONG_LENGTH.maximum + 1))
    for number in (0, *NAMED_NOTES):
        name = note_name(number)
        if number == 0 or number in PLAYABLE_NOTES:
            assert a.NOTES.parse([f"{name} 1s"]) == ((number, 64),)
        else:
            with pytest.raises(ItemErrors, match="it would sound as a rest"):
                a.NOTES.parse([f"{name} 1s"])
        assert song(0, [(number, 64)]).data == bytes([140, 0, 1, number, 64])


@pytest.mark.parametrize(
    ("written", "sent"),
    [("15.625ms", 1), ("16ms", 1), ("3.98s", 255), ("3.984375s", 255), ("100ms", 6)],
)
def test_a_note_length_in_range_is_sent_as_the_nearest_sixty_fourth(
    written: str, sent: int
) -> None:
    assert a.NOTES.parse([f"C4 {written}"]) == ((60, sent),)


@pytest.mark.parametrize("written", ["8ms", "15ms", "3.992s", "3.985s"])
def test_a_note_length_outside_the_range_is_refused_not_rounded_into_it(written: str) -> None:
    """``C4 8ms`` was sent as 1/64 s and ``C4 3.992s`` as 255/64: the range the error and
    the docs state (16ms..3.98s, 1..255 of 1/64 s) held only the rounding."""
    with pytest.raises(ItemErrors) as caught:
        a.NOTES.parse([f"C4 {written}"])
    assert "is out of range: 16ms..3.98s (1..255 of 1/64 s)" in str(caught.value)
