"""The docking stages on a stub robot: frames set by hand, statuses and commands checked."""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest
from py_trees.common import Status

from roomba_bt.behaviours.declare import RobotBehaviour
from roomba_bt.behaviours.docking import (
    ApproachState,
    DockApproach,
    DockDriveOn,
    DockSearch,
    DockTimeLimit,
    DockView,
    DockWaitCharge,
    Hazard,
    SearchState,
    hazard_in,
)
from roomba_bt.behaviours.docking.common import (
    HAZARD_IN_PACKETS,
    DockWatch,
    drive_direct,
    hazard_of,
    note_stage,
    view_of,
)
from roomba_bt.evaluate.episode import failure_stage
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.ir import IR_CHARACTERS, dock_character
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

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


LIGHT_AHEAD = 0b000100  # packet 45: centre-left light bumper
#: encoder counts for a 30 deg turn in place: 30 deg x 117.5 mm / 0.4446 mm per count, + margin
TURN_30_COUNTS = 140


def follow_a_wall(robot: StubRobot, make: Make, **params: object) -> RobotBehaviour:
    """A search that has met a wall ahead and started following it."""
    search = make(DockSearch, spin_first=False, **params)
    robot.set_frame(frame())
    search.tick_once()
    ahead = frame()
    ahead.update({45: LIGHT_AHEAD, 48: 1000})
    robot.set_frame(ahead)
    search.tick_once()
    return search


def last_wheels(robot: StubRobot) -> tuple[int, int]:
    """(left, right) mm/s of the last Drive Direct this tick (its bytes are right, left)."""
    sent = [c for c in robot.flush() if c.spec.name == "drive_direct"]
    assert sent, "no Drive Direct this tick"
    right, left = sent[-1].args
    return left, right


@pytest.mark.parametrize(
    ("side", "side_packet", "spin"), [("right", 51, (-120, 120)), ("left", 46, (120, -120))]
)
def test_search_follows_every_wall_on_the_same_side(
    robot: StubRobot, make: Make, side: str, side_packet: int, spin: tuple[int, int]
) -> None:
    """A wall ahead: turn away from the chosen side (keep the wall there). The next wall is
    kept on the same side too: a one-handed follower goes round a room and out of its door;
    changing hands at every wall sent it back the way it came."""
    search = follow_a_wall(robot, make, wall_side=side)
    assert last_wheels(robot) == spin
    for _ in range(2):
        search._start_follow()  # type: ignore[attr-defined]
        robot.set_frame({**frame(), side_packet: 600})  # along the wall
        search.tick_once()
        robot.flush()
        robot.set_frame({**frame(), 45: LIGHT_AHEAD, 48: 1000})  # the next wall ahead
        search.tick_once()
        assert last_wheels(robot) == spin


def bump_and_back_off(robot: StubRobot, search: RobotBehaviour) -> None:
    bumped = frame()
    bumped[7] = 1
    robot.set_frame(bumped)
    search.tick_once()
    assert last_wheels(robot) == (-150, -150)  # backing off
    robot.set_frame(frame(), ticks=30)  # 0.45 s later: backed off
    search.tick_once()


def test_a_bump_while_following_turns_away_and_follows_on(robot: StubRobot, make: Make) -> None:
    """A door jamb, a chair leg: back off, turn 30 deg away from the wall, follow on with
    the same hand (it used to start over with the other hand, and at a jamb bumped back and
    forth between the two)."""
    search = follow_a_wall(robot, make)
    robot.flush()
    bump_and_back_off(robot, search)
    assert last_wheels(robot) == (-120, 120)  # turning left, away from a wall on the right
    turned = frame()
    turned.update({43: -TURN_30_COUNTS & 0xFFFF, 44: TURN_30_COUNTS})
    robot.set_frame(turned)
    search.tick_once()
    robot.set_frame({**turned, 51: 600})  # the wall on the right again
    search.tick_once()
    left, right = last_wheels(robot)
    assert left > 0 and right > 0  # following on, forward
    assert search._follow_side == 1  # type: ignore[attr-defined]


def test_a_wall_that_keeps_bumping_is_left_for_the_open_floor(robot: StubRobot, make: Make) -> None:
    """Six bumps on one wall are followed on; the seventh sends the robot across the room
    (a corner too tight for it must not hold the search until the time limit)."""
    search = follow_a_wall(robot, make)
    counts = 0
    for bump in range(7):
        bump_and_back_off(robot, search)
        if bump < 6:
            assert last_wheels(robot) == (-120, 120), bump
            counts += TURN_30_COUNTS
            robot.set_frame({**frame(), 43: -counts & 0xFFFF, 44: counts})
            search.tick_once()
    assert search.state is SearchState.TURN  # type: ignore[attr-defined]
    assert not search._want_wall  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("packets", "expected"),
    [
        ({}, None),
        ({7: 0b0100, 9: 1, 45: LIGHT_AHEAD}, Hazard.WHEEL_DROP),  # the most serious first
        ({11: 1, 7: 0b0001}, Hazard.CLIFF),
        ({7: 0b0010, 13: 1}, Hazard.BUMP),
        ({13: 1, 45: LIGHT_AHEAD}, Hazard.CLIFF),  # a virtual wall: a line not to cross
        ({45: LIGHT_AHEAD}, Hazard.OBSTACLE),
        ({45: 0b100001}, None),  # the side light-bumper sensors: beside, not ahead
        ({7: 0b1111_0000}, None),  # packet 7's unused bits
    ],
)
def test_hazards_in_order_of_seriousness(
    robot: StubRobot, packets: dict[int, int], expected: Hazard | None
) -> None:
    snap = robot.set_frame({**frame(), **packets})
    assert hazard_in(snap.frame) is expected


def state(approach: DockApproach) -> ApproachState:
    """The state now (a call, so that a type checker does not narrow it across ticks)."""
    return approach.state


def test_the_approach_reads_no_obstacles(robot: StubRobot) -> None:
    """Near the dock its wall is always in sight of the light bumper: the approach asks
    for hazards without obstacles, and still sees a bump."""
    snap = robot.set_frame({**frame(), 45: LIGHT_AHEAD})
    assert hazard_in(snap.frame, obstacles=False) is None
    snap = robot.set_frame({**frame(), 45: LIGHT_AHEAD, 7: 0b0001})
    assert hazard_in(snap.frame, obstacles=False) is Hazard.BUMP


#: encoder counts for an 80+ deg turn in place (the approach's default cross angle)
TURN_80_COUNTS = 400


@pytest.mark.parametrize(("turn_speed", "wheel"), [(None, 200), (90.0, 90)])
def test_approach_on_the_docks_left_turns_to_the_axis_then_crosses(
    robot: StubRobot, make: Make, turn_speed: float | None, wheel: int
) -> None:
    """Facing the dock in its force field, red only (its left): turn left toward the axis
    at ``turn_speed`` (200 mm/s by default), then, turned far enough, cross toward it in
    the same tick (slowed in the force field)."""
    params = {} if turn_speed is None else {"turn_speed": turn_speed}
    approach = make(DockApproach, **params)
    assert isinstance(approach, DockApproach)
    red = dock_character(red=True, green=False, force_field=True)
    robot.set_frame(frame(omni=red, left=red, right=red))
    approach.tick_once()
    assert state(approach) is ApproachState.TURN_AWAY
    assert last_wheels(robot) == (-wheel, wheel)
    turned = frame(omni=red, left=red, right=red)
    turned.update({43: -TURN_80_COUNTS & 0xFFFF, 44: TURN_80_COUNTS})
    robot.set_frame(turned)
    approach.tick_once()
    assert status(approach) is Status.RUNNING
    assert state(approach) is ApproachState.CROSS
    assert last_wheels(robot) == (90, 90)  # 150 mm/s x 0.6 in the force field


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


def test_drive_on_wiggles_on_contact_inside_the_buoys(robot: StubRobot, make: Make) -> None:
    """Touching the plate without the home-base bit: turn ``wiggle`` (12 deg) left first,
    in place at 30 mm/s with 8 mm/s forward on both wheels to keep the bumper on it."""
    drive_on = make(DockDriveOn)
    both = dock_character(red=True, green=True, force_field=True)
    robot.set_frame(frame(omni=both, left=both, right=both))
    drive_on.tick_once()
    robot.flush()
    values = frame(omni=both, left=both, right=both)
    values[7] = 3
    robot.set_frame(values)
    drive_on.tick_once()
    assert status(drive_on) is Status.RUNNING
    assert last_wheels(robot) == (-22, 38)


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


def test_wait_for_charge_names_every_charging_state_it_accepts() -> None:
    """Its help said "reconditioning, full, trickle" while it accepts waiting (4) too, which
    a full battery on the dock often reads."""
    from roomba_bt.oi.bits import ChargingState

    help_text = " ".join((DockWaitCharge.__doc__ or "").split())
    accepted = [state for state in ChargingState if state.is_charging]
    assert ChargingState.WAITING in accepted
    for state in accepted:
        assert state.name.lower().split("_")[0] in help_text, state


@pytest.mark.parametrize(
    ("seconds", "said"),
    [(120.0, "2 min"), (90.0, "1 min 30 s"), (45.0, "45 s"), (2.0, "2 s"), (1.0, "1 s")],
)
def test_time_limits_are_said_as_the_durations_they_are(
    robot: StubRobot, make: Make, seconds: float, said: str
) -> None:
    """``dock_time_limit: 2min`` gave up "after the time limit of 120 s", and a stage's own
    timeout was said in seconds too, where every other time limit says ``2 min``."""
    limit = make(DockTimeLimit, limit=seconds)
    search = make(DockSearch, timeout=seconds)
    robot.set_frame(frame())
    limit.tick_once()
    search.tick_once()
    robot.set_frame(frame(), ticks=round(seconds / 0.015) + 1)
    limit.tick_once()
    search.tick_once()
    assert status(limit) is Status.FAILURE and status(search) is Status.FAILURE
    # each names the stage it gave up in
    assert limit.feedback_message.startswith(f"search: gave up after the time limit of {said} (")
    assert search.feedback_message == f"search: no dock beam seen in {said}"


def test_a_docking_run_that_never_saw_a_beam_says_so_at_its_time_limit(
    robot: StubRobot, make: Make
) -> None:
    """A stranger's flat with the dock behind a closed door: ``clean`` ended FAILURE
    "search: gave up after the time limit of 10 min (stage search was running)", the words
    of a search that was merely slow. Where no stage past the search began in the docking
    run (a receiver seeing a beam ends the search), the message says that no receiver saw
    one and what keeps a dock out of sight; a run that got further says nothing of it."""
    for went_on in (False, True):
        limit = make(DockTimeLimit, limit=2.0)
        search = make(DockSearch, timeout=60.0)
        robot.set_frame(frame())
        limit.tick_once()  # a new docking run
        search.tick_once()
        if went_on:
            note_stage("approach")
            note_stage("search")  # the approach lost the beams: the search again
        robot.set_frame(frame(), ticks=round(2.0 / 0.015) + 1)
        limit.tick_once()
        assert status(limit) is Status.FAILURE
        said = limit.feedback_message
        assert said.startswith("search: gave up after the time limit of 2 s (stage search was")
        if went_on:
            assert said.endswith("(stage search was running)"), said
        else:
            assert said.endswith(
                "(stage search was running): no receiver saw the dock's beams; is the dock "
                "powered, and can the robot get to it (a closed door, a virtual wall)?"
            ), said
            assert failure_stage(said) == "search"  # eval's grouping reads it still


def test_wait_for_charge_fails_with_its_stage(robot: StubRobot, make: Make) -> None:
    wait = make(DockWaitCharge, timeout=0.5)
    robot.set_frame({21: 0, 34: 2, 35: 1}, mode=OIMode.PASSIVE)
    wait.tick_once()
    robot.set_frame({21: 0, 34: 2, 35: 1}, mode=OIMode.PASSIVE, ticks=40)
    wait.tick_once()
    assert status(wait) is Status.FAILURE
    assert wait.feedback_message.startswith("wait for charge: ")


def test_time_limit_forced_by_the_monitor_ends_before_its_time(
    robot: StubRobot, make: Make
) -> None:
    """The running limit's tick is a comparison while its time is not up, unless its
    ``update`` is not the class's: the monitor forces a leaf by the node's own ``update``."""
    limit = make(DockTimeLimit, limit=60.0)
    robot.set_frame(frame())
    limit.tick_once()
    robot.set_frame(frame(), ticks=2)
    limit.tick_once()
    assert status(limit) is Status.RUNNING
    limit.__dict__["update"] = lambda: Status.FAILURE  # as monitor/session.py forces it
    robot.set_frame(frame(), ticks=3)
    limit.tick_once()
    assert status(limit) is Status.FAILURE


def test_wheels_sends_only_a_change_and_again_after_a_halt(robot: StubRobot, make: Make) -> None:
    """The same speeds asked again are not sent again (the robot keeps them); after a halt,
    or once the motion was reset (a stop), they are; speeds that round alike are not."""
    search = make(DockSearch)
    assert isinstance(search, DockSearch)
    robot.set_frame(frame())

    def sent() -> list[tuple[int, ...]]:
        return [tuple(c.args) for c in robot.flush() if c.spec.name in ("drive_direct", "drive")]

    search.wheels(100.0, 120.0)
    assert sent() == [(120, 100)]
    search.wheels(100.0, 120.0)
    search.wheels(100.2, 119.9)  # rounds to the same speeds
    search.wheels(100.2, 119.9)
    assert sent() == []
    search.wheels(100.0, 120.0)
    assert sent() == []
    search.wheels(90.0, 120.0)
    assert sent() == [(120, 90)]
    search.halt()
    assert sent() == [(0, 0)]
    search.wheels(90.0, 120.0)
    assert sent() == [(120, 90)]
    search._started_motion = False  # as a stop leaves it: the speeds are sent again
    search.wheels(90.0, 120.0)
    assert sent() == [(120, 90)]


def _reference_hazard(frame: SensorFrame, obstacles: bool) -> Hazard | None:
    """The hazard as the frame's own readings say it (what the stages asked every tick
    before they read the values by slot)."""
    if frame.any_hazard:
        if frame.any_wheel_drop:
            return Hazard.WHEEL_DROP
        return Hazard.CLIFF if frame.any_cliff else Hazard.BUMP
    if frame.virtual_wall:
        return Hazard.CLIFF
    if obstacles and frame.light_bumper_ahead:
        return Hazard.OBSTACLE
    return None


@pytest.mark.parametrize("obstacles", [True, False])
def test_hazard_of_the_values_is_the_frames_readings(robot: StubRobot, obstacles: bool) -> None:
    """Every combination of bumper and wheel-drop bits, each cliff, a virtual wall and each
    light-bumper bit: the hazard worked out from the raw values is the one the frame's
    readings give."""
    for bumps, cliff, wall, light in itertools.product(
        range(16), (None, 9, 10, 11, 12), (0, 1), (0, *(1 << bit for bit in range(6)))
    ):
        packets = {7: bumps, 13: wall, 45: light} | ({cliff: 1} if cliff else {})
        snap = robot.set_frame({**frame(), **packets})
        expected = _reference_hazard(snap.frame, obstacles)
        assert hazard_in(snap.frame, obstacles=obstacles) is expected, packets
        values = [snap.frame[packet] for packet in HAZARD_IN_PACKETS]
        assert hazard_of(*values, obstacles=obstacles) is expected, packets


#: Every kind of character the receivers meet: none, both dock families' beams, a virtual
#: wall, a remote button, a lighthouse, an unknown byte.
CHARACTERS = (
    0, 162, 130, 0b0001_1001, 255,
    *(dock_character(red=r, green=g, force_field=f, discovery=d)
      for r, g, f, d in itertools.product((False, True), repeat=4) if r or g or f),
)  # fmt: skip


def test_the_view_of_the_codes_reads_as_the_receivers_do() -> None:
    """Each reading of a view built from three bytes (once, then kept) is what the three
    receivers' characters say: the omni decides the beams when it sees the dock, else the
    side receivers that do."""
    for codes in itertools.product(CHARACTERS, repeat=3):
        omni, left, right = (IR_CHARACTERS[code] for code in codes)
        view = view_of(codes)
        assert view is view_of(codes)  # built once
        beams = omni if omni.from_dock else None
        sides = [c for c in (left, right) if c.from_dock]
        red = beams.red_buoy if beams else any(c.red_buoy for c in sides)
        green = beams.green_buoy if beams else any(c.green_buoy for c in sides)
        field = beams.force_field if beams else any(c.force_field for c in sides)
        assert (view.omni, view.left, view.right) == (omni, left, right)
        assert view.seen == (omni.from_dock or left.from_dock or right.from_dock), codes
        assert view.facing == (left.from_dock and right.from_dock), codes
        assert view.on_left == (left.from_dock and not right.from_dock), codes
        assert view.on_right == (right.from_dock and not left.from_dock), codes
        assert (view.red, view.green, view.force_field) == (red, green, field), codes
        assert view.on_axis == (red and green), codes
        assert view.side == (1 if red and not green else -1 if green and not red else 0), codes


def test_a_dock_watch_reads_each_layout_at_its_own_slots(robot: StubRobot) -> None:
    """``cover``'s and ``home_by_map``'s look at the dock every tick (:class:`DockWatch`,
    its slots found once per layout) is the frame's own view, whatever the receivers say,
    on a frame of another layout too (one more packet before them: every slot moves); a
    frame without the receivers names the packet it lacks."""
    watch = DockWatch()
    red = dock_character(red=True, green=False, force_field=False)
    for codes in itertools.product((0, red, 162), repeat=3):  # nothing, the dock, a wall
        omni, left, right = codes
        for extra in ({}, {8: 0}, {}):  # the other layout, and back
            snap = robot.set_frame({**frame(omni=omni, left=left, right=right), **extra})
            assert watch.view(snap.frame) is DockView.of(snap.frame), (codes, extra)
    snap = robot.set_frame(QUIET)
    with pytest.raises(KeyError, match="packet 17"):
        watch.view(snap.frame)


def test_a_stage_reads_each_layout_at_its_own_slots(robot: StubRobot, make: Make) -> None:
    """The search finds the slots of what it reads once per frame layout: a frame of another
    layout (one more packet, so every slot after it moves) is read at its own slots."""
    search = make(DockSearch)
    robot.set_frame(frame())
    search.tick_once()
    assert status(search) is Status.RUNNING
    # packet 8 sorts before the hazards and the receivers: each of their slots moves by one
    moved = {**frame(right=dock_character(red=False, green=True, force_field=False)), 8: 0}
    robot.set_frame(moved)
    search.tick_once()
    assert status(search) is Status.SUCCESS


def test_a_stage_on_a_frame_without_its_packets_names_the_one_missing(
    robot: StubRobot, make: Make
) -> None:
    search = make(DockSearch)
    values = frame()
    del values[13]
    robot.set_frame(values)
    with pytest.raises(KeyError, match="packet 13"):
        search.tick_once()


def test_drive_direct_is_encoded_once_per_pair_of_speeds() -> None:
    command = drive_direct(120, -35)
    assert command is drive_direct(120, -35)
    assert command == oi.drive_direct(120, -35)
    assert drive_direct(-35, 120).data == oi.drive_direct(-35, 120).data != command.data


def test_a_follow_with_the_same_signals_sends_again_only_after_a_halt(
    robot: StubRobot, make: Make
) -> None:
    """Along a wall, the same signals ask the same speeds: nothing is sent again while the
    wheels keep them; after a halt (or other speeds asked in between) they are sent again."""
    search = follow_a_wall(robot, make)
    along = {**frame(), 51: 420}  # the wall on the right, a little far: steer toward it
    robot.set_frame(along)
    search.tick_once()
    steer = last_wheels(robot)
    assert steer[0] > steer[1] > 0
    for _ in range(3):
        robot.set_frame(along)
        search.tick_once()
        assert robot.flush() == []
    assert isinstance(search, DockSearch)
    search.halt()
    robot.flush()
    robot.set_frame(along)
    search.tick_once()
    assert last_wheels(robot) == steer
    search.wheels(10.0, 10.0)
    robot.flush()
    robot.set_frame(along)
    search.tick_once()
    assert last_wheels(robot) == steer


def test_a_stage_watching_a_packet_it_does_not_declare_is_refused_when_declared() -> None:
    """A plugin's stage adding a packet to WATCHED without declaring it would get a KeyError
    at its first tick on a robot (the stream carries only declared packets): named at once."""
    from roomba_bt.behaviours.declare import DeclarationError
    from roomba_bt.behaviours.docking.common import declare_stage

    own = tuple(p for p in DockApproach.declaration.params if p.name != "timeout")
    approach_reads = DockApproach.declaration.packets({})

    class Watching(DockApproach):
        """Approach, watching the light bumper too."""

        WATCHED = (*DockApproach.WATCHED, 45)

    declared = declare_stage("watching", timeout="60s", timeout_doc="-", params=own)
    with pytest.raises(DeclarationError, match=r"Watching.WATCHED .* 45 \(light_bumper\)"):
        declared(Watching).declaration.validate()  # as registering a plugin does
    # with the packets declared it is accepted; so is every shipped stage
    reads = (*approach_reads, 45)
    declare_stage("watching", timeout="60s", timeout_doc="-", params=own, reads=reads)(Watching)
    Watching.declaration.validate()
    for stage in (DockApproach, DockSearch, DockDriveOn, DockWaitCharge):
        assert stage.declaration_problem(stage.declaration) is None


def test_a_parameter_the_declaration_lacks_is_named_when_read() -> None:
    from roomba_bt.behaviours.docking.common import declare_stage

    class Bare(DockApproach):
        """Approach re-declared without the approach's own parameters."""

    reads = DockApproach.declaration.packets({})
    declare_stage("bare", timeout="60s", timeout_doc="-", reads=reads)(Bare)
    with pytest.raises(KeyError, match="Bare reads parameter 'speed', which its declaration "
                       "'bare' does not have; it declares: timeout"):  # fmt: skip
        Bare("bare").number("speed")
    assert Bare("bare").number("timeout") == 60.0


def test_a_leg_wedged_with_no_bump_shown_is_met_as_a_bump(robot: StubRobot, make: Make) -> None:
    """A leg ends by distance: driven with the body's side against a wall's end, beyond the
    bumper, the wheels stalled, the odometry stood still and no bump showed, and the leg went
    on until the time limit (seed 326 of the apartment, with the search backing along its
    arc, session 38: 500 s at the end of the bedroom's wall by the kitchen door). A leg that
    gets no 5 mm further in a second now backs off as from a bump; a leg that moves does not."""
    search = make(DockSearch, spin_first=False)
    robot.set_frame(frame())
    search.tick_once()
    left, right = last_wheels(robot)
    assert left > 0 and right > 0  # the leg, forward
    counts = 0
    for _ in range(6):  # 1.8 s, 13 mm every 0.3 s: moving
        counts += 30
        robot.set_frame({**frame(), 43: counts, 44: counts}, ticks=20)
        search.tick_once()
        assert search.state is SearchState.FORWARD  # type: ignore[attr-defined]
    still = {**frame(), 43: counts, 44: counts}
    robot.set_frame(still, ticks=40)  # 0.6 s without a move
    search.tick_once()
    assert search.state is SearchState.FORWARD  # type: ignore[attr-defined]
    robot.flush()
    robot.set_frame(still, ticks=40)  # 1.2 s: wedged
    search.tick_once()
    assert search.state is SearchState.BACK  # type: ignore[attr-defined]
    assert last_wheels(robot) == (-150, -150)
