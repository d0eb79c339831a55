"""Mode rules from the opcode table, as the robot applies them (packet 35 shows them)."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import COMMANDS
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600

from .helpers import DOCK_WORLD, box_with_a_drop, docked_start, make, pose


def mode_of(host) -> int:  # type: ignore[no-untyped-def]
    return host.query([35])[35]


def test_robot_powers_up_in_off_and_answers_nothing_but_start() -> None:
    host = make(mode=None)
    assert host.sim.mode is OIMode.OFF
    host.send(C.sensors(35), C.safe(), C.drive_direct(200, 200), C.stream([7]))
    host.run(0.3)
    assert host.sim.read() == b""
    assert host.sim.mode is OIMode.OFF
    assert host.sim.x == 2000.0
    assert [v.name for v in host.sim.violations] == ["drive_direct"]
    assert host.sim.violations[0].mode is OIMode.OFF
    host.send(C.start())
    assert host.sim.mode is OIMode.PASSIVE
    assert mode_of(host) == OIMode.PASSIVE


@pytest.mark.parametrize("opcode", sorted(op for op, c in COMMANDS.items() if c.leads_to))
def test_every_mode_command_leads_where_the_table_says(opcode: int) -> None:
    spec = COMMANDS[opcode]
    host = make(mode="full")
    host.sim.receive(bytes([opcode]))
    expected = spec.leads_to
    assert host.sim.mode is expected
    if expected is not OIMode.OFF and opcode != 133:
        assert mode_of(host) == expected


def test_safe_and_full_are_reachable_from_each_other_and_from_passive() -> None:
    host = make(mode="passive")
    for command, expected in ((C.safe(), 2), (C.full(), 3), (C.safe(), 2), (C.control(), 2)):
        host.send(command)
        assert mode_of(host) == expected


def test_actuators_are_ignored_in_passive_and_counted_as_violations() -> None:
    host = make(mode="passive")
    host.send(C.drive_direct(300, 300), C.motors_off(), C.leds(4, 0, 255), C.play(0))
    host.run(1.0)
    assert host.sim.x == 2000.0
    assert [v.name for v in host.sim.violations] == ["drive_direct", "motors", "leds", "play"]
    assert all(v.mode is OIMode.PASSIVE for v in host.sim.violations)
    assert host.sim.leds == (0, 0, 0)


def test_actuators_move_the_robot_in_safe_and_full() -> None:
    for mode in ("safe", "full"):
        host = make(mode=mode)
        host.send(C.drive_direct(200, 200))
        host.run(1.0)
        assert host.sim.x > 2150.0
        assert host.sim.violations == []


def test_start_from_safe_stops_the_wheels() -> None:
    host = make()
    host.send(C.drive_direct(200, 200))
    host.run(0.5)
    host.send(C.start())
    x = host.sim.x
    host.run(0.5)
    assert host.sim.x == x


def test_stop_173_goes_to_off_and_stops_the_stream() -> None:
    host = make()
    host.stream([7])
    assert len(host.frames(0.15)) == 10
    host.send(C.stop())
    assert host.sim.mode is OIMode.OFF
    assert host.frames(0.3) == []


def test_reset_prints_the_banner_and_goes_to_off() -> None:
    host = make()
    host.sim.read()
    host.send(C.reset())
    text = host.sim.read()
    assert text.startswith(b"bl-start") and text.isascii()
    assert host.sim.mode is OIMode.OFF


def test_reset_and_stop_do_not_exist_on_the_500() -> None:
    host = make(profile=ROOMBA500)
    host.send(bytes([7]), bytes([173]))
    assert host.sim.mode is OIMode.SAFE
    assert host.sim.ignored_bytes == 2


def test_roomba600_reports_mode_plus_one_as_its_profile_says() -> None:
    assert ROOMBA600.reports_mode_plus_one and not CREATE2.reports_mode_plus_one
    host = make(profile=ROOMBA600, mode="passive")
    assert mode_of(host) == 2
    host.send(C.full())
    assert mode_of(host) == 4


#: the robot in the room's middle, facing a drop 1 m ahead
A_METRE_FROM_A_DROP = box_with_a_drop(3.0, start=(2, 2))


def test_safe_mode_cliff_while_driving_forward_drops_to_passive() -> None:
    host = make(A_METRE_FROM_A_DROP)
    host.stream([9, 10, 11, 12, 35, 41, 42])
    host.send(C.drive_direct(200, 200))
    frames = host.frames(5.0)
    last = frames[-1]
    assert last.oi_mode is OIMode.PASSIVE
    assert last.cliff_front_left and last.cliff_front_right
    assert host.sim.x < 3000.0  # stopped before the centre reached the edge
    assert any("cliff while driving forward" in e.detail for e in host.sim.events)


def test_safe_mode_acts_on_a_wheel_drop_and_not_once_the_robot_is_put_down() -> None:
    text = """
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [1, 2], heading: 0}}
events: [{at: 0.3, kind: lift, duration: 0.5}]
"""
    host = make(text)
    host.send(C.drive_direct(100, 100))
    host.run(0.6)
    assert host.sim.mode is OIMode.PASSIVE
    assert any("safety: wheel drop" in e.detail for e in host.sim.events)
    reply = host.query([7, 9, 10, 11, 12])  # still lifted: both wheels down, every cliff
    assert reply.bumps.wheel_drop_left and reply.bumps.wheel_drop_right
    assert reply.any_cliff
    host.run(0.6)  # put down again
    host.send(C.safe(), C.drive_direct(100, 100))
    host.run(1.0)
    assert host.sim.mode is OIMode.SAFE and host.sim.x > 1050.0


def test_full_mode_has_no_cliff_safety_and_the_robot_falls() -> None:
    host = make(A_METRE_FROM_A_DROP, mode="full")
    host.send(C.drive_direct(200, 200))
    host.run(8.0)
    assert host.sim.mode is OIMode.FULL
    assert host.sim.fallen
    assert host.query([7])[7] & 0b1100 == 0b1100


def test_safe_mode_powered_charger_drops_to_passive_but_full_does_not() -> None:
    host = make(DOCK_WORLD, start=docked_start())
    host.run(0.1)
    assert host.sim.mode is OIMode.PASSIVE
    host = make(DOCK_WORLD, start=docked_start(), mode="full")
    host.run(0.1)
    assert host.sim.mode is OIMode.FULL


def test_passive_sleeps_after_five_minutes_idle_deaf_until_a_brc_pulse() -> None:
    """Power saving: a sleeping robot answers no byte, Start included (a robot asleep answers
    nothing: robotics.stackexchange.com/q/10666); a BRC pulse wakes it into Passive."""
    host = make(mode="passive")
    host.stream([35])
    host.run(299.0)
    assert host.frames(0.3)
    host.run(1.0)
    assert host.sim.asleep
    assert host.frames(0.3) == []
    host.send(C.sensors(35))
    assert host.sim.read() == b""
    host.send(C.start())
    assert host.sim.asleep, "Start does not reach a sleeping robot"
    host.sim.set_brc(True)
    host.sim.set_brc(False)
    assert not host.sim.asleep
    assert mode_of(host) == OIMode.PASSIVE


def test_old_firmware_does_not_wake_by_brc_on_the_dock() -> None:
    """600 spec, Appendix B: before release-3.8.2 / release-stm32-3.7.7 a BRC pulse does not
    wake the robot on the dock; later releases do, and anywhere off the dock both do."""
    for firmware, wakes in (("release-3.6.0", False), ("release-3.8.2", True)):
        host = make(DOCK_WORLD, start=docked_start())
        host.sim.firmware = firmware
        host.sim.fall_asleep("test")
        host.sim.set_brc(True)
        host.sim.set_brc(False)
        assert host.sim.asleep is not wakes, firmware
    host = make()
    host.sim.firmware = "release-3.6.0"
    host.sim.fall_asleep("test")
    host.sim.set_brc(True)
    assert not host.sim.asleep


def test_a_flat_battery_switches_the_robot_off_until_it_has_charged() -> None:
    """Decided (the specs are silent): at an empty battery the robot switches itself off, as
    a real one does at its cut-off voltage: its wheels stop, its stream ends, it answers
    nothing, and a BRC pulse does not wake it until the charger has put some charge in."""
    host = make(mode=None)
    host.sim.battery_charge = 0.5  # mAh: about 4 s at 150 + 0.6 x 2 x 200 mA
    host.send(C.start(), C.safe(), C.drive_direct(200, 200))
    host.stream([7, 25])
    assert host.frames(1.0)
    host.run(10.0)
    assert host.sim.asleep and host.sim.battery_charge == 0.0
    assert host.sim.left_speed == host.sim.right_speed == 0.0
    assert [e.detail for e in host.sim.events if e.kind == "sleep"] == ["battery empty"]
    assert host.frames(0.5) == []
    host.send(C.sensors(35))
    assert host.sim.read() == b""
    host.sim.set_brc(True)
    host.sim.set_brc(False)
    assert host.sim.asleep, "no charge: a BRC pulse wakes nothing"


def test_a_robot_that_went_flat_on_its_powered_dock_charges_and_then_wakes() -> None:
    # in Full on the dock (Safe would fall to Passive there, and charge): no charging
    host = make(DOCK_WORLD, start=docked_start(), mode="full")
    host.sim.firmware = "release-3.8.2"  # wakes by BRC on the dock
    host.sim.battery_charge = 0.01
    host.run(1.0)
    assert host.sim.asleep
    host.run(2.0)  # asleep on the powered dock (Passive): it charges
    assert host.sim.battery_charge > 0.0
    host.sim.set_brc(True)
    host.sim.set_brc(False)
    assert not host.sim.asleep and mode_of(host) == OIMode.PASSIVE


def test_the_reset_banner_names_the_firmware() -> None:
    host = make()
    host.sim.firmware = "release-3.8.2"
    host.send(C.reset())
    banner = host.sim.read()
    assert banner.startswith(b"bl-start\r\n")
    assert b"r3_robot/tags/release-3.8.2 CLEAN\r\n" in banner


def test_safe_mode_never_sleeps() -> None:
    host = make()
    host.run(400.0)
    assert not host.sim.asleep


def test_clean_spot_max_seek_dock_lead_to_passive_with_a_builtin_motion() -> None:
    for command in (C.clean(), C.spot(), C.max_clean()):
        host = make()
        host.send(command)
        assert host.sim.mode is OIMode.PASSIVE
        host.run(2.0)
        assert host.sim.pose != pose(2, 2, 0)
        assert host.sim.violations == []


def test_power_puts_the_robot_to_sleep() -> None:
    host = make()
    host.send(C.power())
    assert host.sim.asleep
    host.send(C.sensors(35))
    assert host.sim.read() == b""


@pytest.mark.parametrize("wake", ["start", "brc"])
def test_a_robot_powered_down_by_power_wakes_by_start_or_a_brc_pulse(wake: str) -> None:
    """Decided (docs/protocol.md, "Power (133)"): neither spec says what wakes a robot that
    Power powered down. The simulator takes Start as the five-minute sleep does not (the
    golden recordings' script wakes it so) and a BRC pulse, the wake a Create 2 owner
    reports; the robot layer never sends Power, and a robot deaf to Start is what doctor
    wakes by BRC (`sim --asleep`)."""
    host = make()
    host.send(C.power())
    assert host.sim.asleep and not host.sim.deaf
    if wake == "start":
        host.send(C.start())
    else:
        host.sim.set_brc(True)
        host.sim.set_brc(False)
    assert not host.sim.asleep
    assert mode_of(host) == OIMode.PASSIVE


def test_the_same_drive_again_is_still_refused_in_passive() -> None:
    """A client re-sends its Drive every frame; the simulator's shortcut for an unchanged
    Drive must not hide the violation when the robot has fallen to Passive meanwhile."""
    host = make(mode="safe")
    drive = C.drive(200, C.Radius.STRAIGHT)
    host.send(drive)
    host.run(0.3)
    host.send(C.start())  # Passive: the wheels stop
    host.send(drive)
    host.send(drive)
    x = host.sim.x
    host.run(0.3)
    assert host.sim.x == x
    assert [v.name for v in host.sim.violations] == ["drive", "drive"]
    host.send(C.safe(), drive)  # Safe again: the same bytes drive again
    host.run(0.3)
    assert host.sim.x > x + 40.0


def test_the_same_drive_after_a_drive_direct_applies_again() -> None:
    host = make(mode="full")
    host.send(C.drive(200, C.Radius.STRAIGHT), C.drive_direct(-100, -100))
    host.send(C.drive(200, C.Radius.STRAIGHT))
    assert host.sim.requested_left == host.sim.requested_right > 0.0


@pytest.mark.parametrize(
    "mode_command",
    [C.start(), C.safe(), C.full(), C.control()],
    ids=["start", "safe", "full", "control"],
)
def test_a_mode_command_stops_the_wheels(mode_command: object) -> None:
    """The OI spec: a mode command stops the drive motors. Start then Safe must not resume
    the 200 mm/s drive sent before (it did once the stop was dropped: this test fails)."""
    host = make(mode="safe")
    host.send(C.drive(200, 0x7FFF))
    host.run(0.3)
    assert host.sim.x > 2000.0
    host.send(mode_command)  # type: ignore[arg-type]
    host.send(C.safe())
    x = host.sim.x
    host.run(1.0)
    assert host.sim.x == pytest.approx(x, abs=1.0)
    assert (host.sim.left_speed, host.sim.right_speed) == (0.0, 0.0)
