"""The world's timeline on its own: events start and end as the clock passes them, their effects
overlap, and the simulator lets go of the timeline once the last event has ended."""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.oi.bits import OVERCURRENT_BITS
from roomba_bt.oi.modes import OIMode
from roomba_bt.sim.timeline import Timeline
from roomba_bt.sim.world import TimelineEvent

from .helpers import BOX, make


def test_events_start_and_end_as_the_clock_passes_them() -> None:
    timeline = Timeline((TimelineEvent(1.0, "bump", 0.5, "left"), TimelineEvent(1.2, "lift", 1.0)))
    assert timeline.advance(0.9) == []
    assert timeline.effects() == (0, False, True, 0, False)
    assert timeline.advance(1.2) == [("bump", "left start"), ("lift", "both start")]
    assert timeline.effects() == (2, True, True, 0, False)
    assert timeline.advance(1.5) == [("bump", "end")]
    assert timeline.effects() == (0, True, True, 0, False)
    assert not timeline.over
    assert timeline.advance(2.2) == [("lift", "end")]
    assert timeline.over


def test_a_charger_step_takes_the_docks_power_and_bumps_add_up() -> None:
    timeline = Timeline(
        (
            TimelineEvent(0.0, "bump", 1.0, "right"),
            TimelineEvent(0.0, "bump", 1.0, "left"),
            TimelineEvent(0.0, "charger_step", 1.0),
        )
    )
    timeline.advance(0.0)
    assert timeline.effects() == (3, False, False, 0, False)


def test_the_simulator_marks_every_start_and_end_and_then_drops_the_timeline() -> None:
    text = BOX + "events: [{at: 0.3, kind: bump, side: right, duration: 0.3}]\n"
    host = make(text)
    host.send(C.stream([7]))
    host.run(1.0)
    marks = [(e.kind, e.detail) for e in host.sim.events if e.kind == "bump"]
    # the timeline's start, the bumper's own bump event, the timeline's end
    assert marks == [("bump", "right start"), ("bump", "right"), ("bump", "end")]
    assert host.sim._timeline is None
    assert host.sim.values[7] == 0


PRESS_CLEAN = BOX + "events: [{at: 0.3, kind: press, button: clean}]\n"


def test_a_press_in_passive_starts_the_robots_own_cycle_as_a_finger_does() -> None:
    host = make(PRESS_CLEAN, mode="passive")
    host.run(0.45)
    assert host.sim.values[18] == 1  # packet 18: Clean, held for the spec's 1/6 s
    assert host.sim.builtin is not None and host.sim.builtin.name == "clean"
    host.run(0.2)
    assert host.sim.values[18] == 0
    marks = [(e.kind, e.detail) for e in host.sim.events if e.kind in ("press", "builtin")]
    assert marks == [("press", "clean start"), ("builtin", "clean"), ("press", "end")]


def test_a_press_in_safe_shows_in_packet_18_only() -> None:
    host = make(PRESS_CLEAN)
    host.run(0.45)
    assert host.sim.values[18] == 1
    assert host.sim.builtin is None and host.sim.mode is OIMode.SAFE


def test_a_press_of_a_button_the_robot_lacks_presses_nothing_and_is_said() -> None:
    host = make(BOX + "events: [{at: 0.3, kind: press, button: minute}]\n")
    host.run(0.45)
    assert host.sim.values[18] == 0
    refused = [e.detail for e in host.sim.events if e.kind == "refused"]
    assert refused == ["press minute: the iRobot Create 2 has no minute button"]


TANGLED_BRUSH = BOX + "events: [{at: 0.3, kind: overcurrent, motor: main_brush, duration: 0.5}]\n"


def test_an_overcurrent_event_sets_the_motors_bit_of_packet_14_for_its_duration() -> None:
    """A tangled brush could not be simulated (the events were bump, lift, charger_step and
    press), so no mission's reaction to one could be tested: the event sets the bit of the
    motor it names, the one ``overcurrent: main_brush`` reads, and the run marks it."""
    host = make(TANGLED_BRUSH)
    host.send(C.stream([14]))
    host.run(0.45)
    assert host.sim.values[14] == OVERCURRENT_BITS["main_brush"] == 0b100
    host.run(0.5)
    assert host.sim.values[14] == 0
    marks = [(e.kind, e.detail) for e in host.sim.events if e.kind == "overcurrent"]
    assert marks == [("overcurrent", "main_brush start"), ("overcurrent", "end")]


def test_overcurrents_of_two_motors_add_up_as_the_packet_s_bits() -> None:
    timeline = Timeline(
        (
            TimelineEvent(0.0, "overcurrent", 1.0, motor="side_brush"),
            TimelineEvent(0.0, "overcurrent", 1.0, motor="left_wheel"),
        )
    )
    timeline.advance(0.0)
    assert timeline.effects() == (0, False, True, 0b10001, False)


PLUGGED = BOX + "events: [{at: 0.3, kind: plug, duration: 1.0}]\n"


def test_the_wall_charger_plugged_in_drops_safe_to_passive_as_the_spec_says() -> None:
    """Both specs' Safe mode: "Charger plugged in and powered" stops the motors and reverts
    to Passive; packet 34 bit 0 is the internal charger (the wall plug), bit 1 the dock."""
    host = make(PLUGGED)
    host.send(C.drive_direct(100, 100))
    host.run(0.5)
    assert host.sim.mode is OIMode.PASSIVE
    assert host.sim.left_speed == host.sim.right_speed == 0.0
    assert host.sim.values[34] == 0b01
    assert host.sim.values[21] == 2  # charging in Passive, as on the dock
    marks = [(e.kind, e.detail) for e in host.sim.events if e.kind in ("plug", "mode")]
    assert marks[-2:] == [
        ("plug", "plugged in"),
        ("mode", "Safe->Passive (safety: internal charger plugged in)"),
    ]
    host.run(1.0)
    assert host.sim.values[34] == 0 and host.sim.values[21] == 0
    assert ("plug", "unplugged") in [(e.kind, e.detail) for e in host.sim.events]


def test_full_mode_keeps_driving_with_the_wall_charger_plugged_in() -> None:
    """Full "shuts off the cliff, wheel-drop and internal charger safety features"; the
    battery does not charge there (as on the dock in Full)."""
    host = make(PLUGGED, mode="full")
    host.send(C.drive_direct(100, 100))
    host.run(0.5)
    assert host.sim.mode is OIMode.FULL and host.sim.left_speed > 0.0
    assert host.sim.values[34] == 0b01 and host.sim.values[21] == 0


def test_safe_entered_while_plugged_in_falls_back_to_passive() -> None:
    host = make(BOX + "events: [{at: 0.0, kind: plug, duration: 5.0}]\n", mode="passive")
    host.run(0.3)
    assert host.sim.values[34] == 0b01 and host.sim.values[21] == 2
    host.send(C.safe())
    host.run(0.05)
    assert host.sim.mode is OIMode.PASSIVE


def test_the_plug_put_in_and_pulled_out_is_followed_with_nothing_else_changing() -> None:
    """The battery's currents are computed again only when what they depend on changes
    (power.py's key); the timeline's effects are not in that key, so a world without events
    pays nothing for them, and the start and end of an event drop the key instead. A robot
    standing in Passive, whose speeds, brushes and mode never change, still starts and stops
    charging at the plug's start and end."""
    host = make(BOX + "events: [{at: 0.3, kind: plug, duration: 0.5}]\n", mode="passive")
    host.send(C.stream([21, 23, 34]))
    host.run(0.2)
    assert host.sim.values[34] == 0 and host.sim.values[21] == 0
    assert host.sim.values[23] < 0
    host.run(0.2)
    assert host.sim.values[34] == 0b01 and host.sim.values[21] == 2
    assert host.sim.values[23] == 1500
    host.run(0.5)
    assert host.sim.values[34] == 0 and host.sim.values[21] == 0
    assert host.sim.values[23] < 0
