"""The dock's beams are good enough for a classic beam-following homing to dock, and docking
gives the home-base bit, charging, and a positive current (only in Passive)."""

from __future__ import annotations

import math

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.bits import ChargingState
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import OIMode
from roomba_bt.sim import Simulator

from .helpers import DOCK_WORLD, Host, docked_start, make, pose, world

HOMING_PACKETS = [7, 17, 21, 34, 35, 52, 53]


def homing_command(frame: SensorFrame, state: dict[str, int]) -> bytes | None:
    """Classic beam-following homing that reads nothing but the wire: both buoys -> head for
    the dock (steering by which receiver sees it), red only -> arc left, green only -> arc
    right, no beam on the bumper receivers -> spin, force field -> slow down, bump without
    the home-base bit -> push to seat on the contacts, then back off and try again."""
    if frame.charging_sources.home_base:
        return None
    if state.get("back", 0) > 0:
        state["back"] -= 1
        return C.drive_direct(-120, -120).data
    if state.get("seat", 0) > 0:
        state["seat"] -= 1
        if state["seat"] == 0:
            state["back"] = 40
        return C.drive_direct(60, 60).data
    if frame.bumps.any_bump:
        if frame.ir_omni.force_field:  # at the dock: push gently to seat on the contacts
            state["seat"] = 35
            return C.drive_direct(60, 60).data
        state["back"] = 40
        return C.drive_direct(-120, -120).data
    left, right = frame.ir_left, frame.ir_right
    sees_left, sees_right = left.from_dock, right.from_dock
    red = left.red_buoy or right.red_buoy
    green = left.green_buoy or right.green_buoy
    speed = 70 if frame.ir_omni.force_field else 150
    if not sees_left and not sees_right:
        return C.drive_direct(70, -70).data  # spin left until a bumper receiver sees it
    if sees_left != sees_right:  # not facing the dock: turn toward it, gently forward
        turn = 70 if sees_left else -70
        return C.drive_direct(speed // 3 + turn, speed // 3 - turn).data
    if red and green:
        return C.drive_direct(speed, speed).data
    if red:  # on the dock's left: arc left, toward its axis
        return C.drive_direct(speed + 60, speed - 60).data
    return C.drive_direct(speed - 60, speed + 60).data  # green only: arc right


def home(host: Host, seconds: float) -> list[SensorFrame]:
    host.stream(HOMING_PACKETS)
    state: dict[str, int] = {}
    seen: list[SensorFrame] = []
    for _ in range(round(seconds / 0.015)):
        for frame in host.frames(0.015):
            seen.append(frame)
            command = homing_command(frame, state)
            if command is None:
                return seen
            host.send(command)
    return seen


@pytest.mark.parametrize(
    ("x", "y", "heading"),
    [
        (2.0, 1.0, -90),
        (2.3, 0.9, 180),
        (1.75, 0.8, 0),
        (2.2, 0.55, 120),
        (1.9, 1.05, 45),
        (1.6, 0.9, -30),
        (1.5, 1.0, -45),
    ],
)
def test_a_beam_following_homing_docks_from_the_front_of_the_dock(
    x: float, y: float, heading: float
) -> None:
    host = make(DOCK_WORLD, start=pose(x, y, heading))
    frames = home(host, 60.0)
    assert frames[-1].charging_sources.home_base, host.sim.pose
    assert host.sim.docked
    host.run(0.2)
    reply = host.query([21, 23, 34, 35])
    assert reply.oi_mode is OIMode.PASSIVE  # the powered charger made Safe fall to Passive
    assert reply.charging_state is ChargingState.FULL_CHARGING
    assert reply.current_ma > 0
    assert host.sim.violations == []


def test_receivers_see_the_dock_by_heading_left_right_and_both() -> None:
    facing = make(DOCK_WORLD, start=pose(2.0, 0.9, -90))
    reply = facing.query([17, 52, 53])
    assert reply.ir_left.from_dock and reply.ir_right.from_dock
    assert reply.ir_left.red_buoy and reply.ir_left.green_buoy
    # turned 30 deg clockwise: the dock is to the robot's left, only the left receiver sees
    turned = make(DOCK_WORLD, start=pose(2.0, 0.9, -120))
    reply = turned.query([17, 52, 53])
    assert reply.ir_left.from_dock and not reply.ir_right.from_dock
    turned = make(DOCK_WORLD, start=pose(2.0, 0.9, -60))
    reply = turned.query([17, 52, 53])
    assert reply.ir_right.from_dock and not reply.ir_left.from_dock
    # facing away: the omni still sees the beam, the directional receivers do not
    away = make(DOCK_WORLD, start=pose(2.0, 0.7, 90))
    reply = away.query([17, 52, 53])
    assert reply.ir_omni.from_dock and reply[52] == 0 and reply[53] == 0


def omni_at(x: float, y: float, text: str = DOCK_WORLD) -> int:
    # the omni receiver sits 130 mm ahead of the centre: face the dock from (x, y)
    heading = math.degrees(math.atan2(0.0 - y, 2.0 - x))
    sim = Simulator(world(text), start=pose(x, y, heading))
    sim.receive(C.start().data + C.sensors(17).data)
    return sim.read()[0]


def test_red_on_the_docks_left_green_on_its_right_both_on_the_axis() -> None:
    # dock at (2, 0) facing +y: its own left is -x
    assert omni_at(2.0, 0.9) == 160 | 8 | 4  # both buoys, outside the force field
    assert omni_at(1.75, 0.8) == 160 | 8  # 17 deg to the dock's left: red only
    assert omni_at(2.25, 0.8) == 160 | 4  # green only
    assert omni_at(2.0, 0.5) == 160 | 8 | 4 | 1  # inside the force field too
    assert omni_at(3.2, 0.3) == 0  # outside the buoys and the force field
    assert omni_at(2.0, 1.3) == 0  # beyond the 1 m buoy range


def test_beam_parameters_are_world_parameters() -> None:
    narrow = DOCK_WORLD.replace(
        "facing: 90}", "facing: 90, red: [-2, 10], green: [-10, 2], buoy_range: 1.5, "
        "force_field: 0.3}"
    )  # fmt: skip
    assert omni_at(1.75, 0.8, narrow) == 0  # 17 deg is outside a 10 deg red beam
    assert omni_at(2.0, 1.3, narrow) == 160 | 8 | 4  # range 1.5 m
    assert omni_at(2.0, 0.5, narrow) == 160 | 8 | 4  # force field 0.3 m only


def test_discovery_dock_family_sends_240_characters() -> None:
    discovery = DOCK_WORLD.replace("facing: 90}", "facing: 90, family: discovery}")
    assert omni_at(2.0, 0.5, discovery) == 240 | 8 | 4 | 2
    assert omni_at(1.75, 0.8, discovery) == 240 | 8


def test_charging_only_in_passive_never_in_full() -> None:
    passive = make(DOCK_WORLD, start=docked_start(), mode="passive")
    before = passive.sim.battery_charge
    passive.run(60.0)
    assert passive.sim.battery_charge > before
    full = make(DOCK_WORLD, start=docked_start(), mode="full")
    before = full.sim.battery_charge
    full.run(60.0)
    assert full.sim.battery_charge < before
    reply = full.query([21, 23, 34])
    assert reply.charging_sources.home_base  # the charger is there, powered
    assert reply.charging_state is ChargingState.NOT_CHARGING and reply.current_ma < 0


def test_someone_stepping_on_the_charger_cuts_its_power_for_a_while() -> None:
    text = DOCK_WORLD + "events: [{at: 1.0, kind: charger_step, duration: 2.0}]\n"
    host = make(text, start=docked_start(), mode="passive")
    host.stream([17, 21, 34])
    frames = host.frames(4.0)
    assert len(frames) == 267
    before, during, after = frames[40], frames[134], frames[260]  # 0.6 s, 2.0 s, 3.9 s
    assert before.charging_sources.home_base and before[21] == ChargingState.FULL_CHARGING
    assert not during.charging_sources.home_base and during[21] == 0 and during[17] == 0
    assert after.charging_sources.home_base


def test_builtin_seek_dock_docks_and_charges() -> None:
    sim = Simulator(world(DOCK_WORLD), seed=4, start=pose(2.6, 1.2, 30))
    sim.receive(C.start().data + C.seek_dock().data)
    sim.run(120.0)
    assert sim.docked and sim.mode is OIMode.PASSIVE
    assert sim.values[21] == ChargingState.FULL_CHARGING
