"""The docking stages on a stub robot: frames set by hand, statuses and commands checked."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from py_trees.common import Status

from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.behaviours.docking import (
    DockDriveOn,
    DockSearch,
    DockTimeLimit,
    DockView,
    DockWaitCharge,
)
from roomba_bt.oi.ir import dock_character
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.interface import StubRobot

Make = Callable[..., RobotBehaviour]


def status(behaviour: RobotBehaviour) -> Status:
    """The status now (a call, so that a type checker does not narrow it across ticks)."""
    return behaviour.status


SAFE = 2
QUIET = {7: 0, 9: 0, 10: 0, 11: 0, 12: 0, 13: 0, 45: 0, 46: 0, 47: 0, 48: 0, 49: 0, 50: 0,
         51: 0, 34: 0, 21: 0, 43: 0, 44: 0, 35: SAFE}  # fmt: skip


def frame(**ir: int) -> dict[int, int]:
    values = dict(QUIET)
    values.update({17: ir.get("omni", 0), 52: ir.get("left", 0), 53: ir.get("right", 0)})
    return values


@pytest.mark.parametrize("discovery", [False, True], ids=["drive-on", "discovery"])
def test_view_reads_both_dock_families(robot: StubRobot, discovery: bool) -> None:
    red = dock_character(red=True, green=False, force_field=True, discovery=discovery)
    both = dock_character(red=True, green=True, force_field=False, discovery=discovery)
    snap = robot.set_frame(frame(omni=red, left=both, right=0))
    view = DockView.of(snap.frame)
    assert view.seen and view.on_left and not view.facing
    assert view.side == 1 and view.force_field  # the omni receiver decides the side
    snap = robot.set_frame(frame(omni=both, left=both, right=both))
    view = DockView.of(snap.frame)
    assert view.facing and view.on_axis and view.side == 0


def test_a_virtual_wall_or_a_remote_is_not_the_dock(robot: StubRobot) -> None:
    snap = robot.set_frame(frame(omni=162, left=130, right=0))
    assert not DockView.of(snap.frame).seen


def test_search_succeeds_and_halts_when_a_beam_is_seen(robot: StubRobot, make: Make) -> None:
    search = make(DockSearch)
    robot.set_frame(frame())
    search.tick_once()
    assert status(search) is Status.RUNNING
    spin = robot.flush()
    assert spin and spin[-1].spec.name == "drive_direct"
    robot.set_frame(frame(right=dock_character(red=False, green=True, force_field=False)))
    search.tick_once()
    assert status(search) is Status.SUCCESS
    assert [c.spec.name for c in robot.flush()] == ["drive"]  # halt: [137][0][0][0][0]


def test_search_gives_up_naming_its_stage(robot: StubRobot, make: Make) -> None:
    search = make(DockSearch, timeout=1.0)
    robot.set_frame(frame())
    search.tick_once()
    robot.set_frame(frame(), ticks=70)
    search.tick_once()
    assert status(search) is Status.FAILURE
    assert search.feedback_message == "search: no dock beam seen in 1 s"


def test_drive_on_fails_on_a_bump_outside_the_buoys(robot: StubRobot, make: Make) -> None:
    drive_on = make(DockDriveOn)
    ff = dock_character(red=False, green=False, force_field=True)
    robot.set_frame(frame(omni=ff, left=ff, right=ff))
    drive_on.tick_once()
    assert status(drive_on) is Status.RUNNING
    values = frame(omni=ff, left=ff, right=ff)
    values[7] = 3
    robot.set_frame(values)
    drive_on.tick_once()
    assert status(drive_on) is Status.FAILURE
    assert drive_on.feedback_message.startswith("final alignment: bumped into something")


def test_drive_on_succeeds_on_the_home_base_bit(robot: StubRobot, make: Make) -> None:
    drive_on = make(DockDriveOn)
    values = frame()
    values[34] = 2
    robot.set_frame(values, mode=OIMode.PASSIVE)
    drive_on.tick_once()
    assert status(drive_on) is Status.SUCCESS


@pytest.mark.parametrize(
    ("sources", "state", "expected"),
    [(2, 2, Status.SUCCESS), (2, 0, Status.RUNNING), (0, 2, Status.RUNNING)],
    ids=["home-base-and-charging", "home-base-only", "charging-only"],
)
def test_wait_for_charge_needs_both_packets(
    robot: StubRobot, make: Make, sources: int, state: int, expected: Status
) -> None:
    wait = make(DockWaitCharge)
    robot.set_frame({21: state, 34: sources, 35: 1}, mode=OIMode.PASSIVE)
    wait.tick_once()
    assert wait.status is expected


def test_wait_for_charge_fails_with_its_stage(robot: StubRobot, make: Make) -> None:
    wait = make(DockWaitCharge, timeout=0.5)
    robot.set_frame({21: 0, 34: 2, 35: 1}, mode=OIMode.PASSIVE)
    wait.tick_once()
    robot.set_frame({21: 0, 34: 2, 35: 1}, mode=OIMode.PASSIVE, ticks=40)
    wait.tick_once()
    assert status(wait) is Status.FAILURE
    assert wait.feedback_message.startswith("wait for charge: ")


def test_time_limit_names_the_running_stage(robot: StubRobot, make: Make) -> None:
    limit = make(DockTimeLimit, limit=2.0)
    search = make(DockSearch)
    robot.set_frame(frame())
    limit.tick_once()
    search.tick_once()
    robot.set_frame(frame(), ticks=140)
    limit.tick_once()
    assert status(limit) is Status.FAILURE
    assert limit.feedback_message.startswith("search: gave up after the time limit of 2 s")
