"""Every wheel and motor action that would start out of Safe and Full, where the mode guard
refuses its commands, fails at once, saying the mode, the robot's fall and the fix; so do
the LEDs, the display and ``play`` (they said SUCCESS for what never happened until session
33), and ``stop`` says what holds there.

A ``turn`` started after a wheel drop had dropped the robot to Passive sent nothing and
waited for ever (maker finding 2, session 32): its run ended at ``--timeout`` with "ran out
in turn", no word of Passive, and no ``retry`` or fallback of the tree could take it up.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from py_trees.common import Status

from roomba_bt.behaviours import builtin_registry
from roomba_bt.behaviours.actions import Motors, Stop, Vacuum
from roomba_bt.behaviours.declare import Declaration, RobotBehaviour
from roomba_bt.behaviours.driving import needs_mode_message
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import COMMANDS
from roomba_bt.robot.interface import ModeChange
from roomba_bt.robot.testing import StubRobot

from .example_params import EXAMPLE_PARAMS

Make = Callable[..., RobotBehaviour]

#: ``home_by_map`` succeeds at once with no ``cover`` map to go by, sending nothing
_NOT_STARTED_ALONE = {"home_by_map"}


def tick(behaviour: RobotBehaviour) -> Status:
    behaviour.tick_once()
    return behaviour.status


def _sets_going_in_safe_only(declaration: Declaration) -> bool:
    """A leaf that sends a wheel or motor command only Safe and Full take, not as a halt."""
    channels = {
        COMMANDS[opcode].channel
        for opcode in declaration.sends
        if COMMANDS[opcode].modes == DRIVING_MODES
    }
    return bool(channels & {"wheels", "motors"}) and not declaration.halts_only


MOVERS = sorted(
    d.name
    for d in builtin_registry()
    if _sets_going_in_safe_only(d) and d.name not in _NOT_STARTED_ALONE
)


def test_the_movers_are_the_wheel_and_motor_leaves() -> None:
    assert set(MOVERS) >= {
        "drive", "turn", "spiral", "lanes", "cover", "wall_follow", "dock_search",
        "dock_approach", "dock_drive_on", "motors", "vacuum",
    }  # fmt: skip


def _frame_of(declaration: Declaration, mode: OIMode) -> dict[int, int]:
    """A frame with every packet the leaf reads, zero, and packet 35 saying ``mode``."""
    return {
        **dict.fromkeys(declaration.packets(EXAMPLE_PARAMS.get(declaration.name, {})), 0),
        35: mode,
    }


@pytest.mark.parametrize("name", MOVERS)
def test_a_mover_started_in_passive_fails_within_a_tick_sending_nothing(
    make: Make, name: str
) -> None:
    """At once (an at-once leaf, a docking stage), or on its second tick: the first is the
    one a ``parallel``'s ``mode: safe`` beside it may be queued in."""
    declaration = builtin_registry().get(name)
    assert declaration is not None
    robot = StubRobot(mode=OIMode.PASSIVE)
    behaviour = make(declaration.cls, robot=robot, **EXAMPLE_PARAMS.get(name, {}))
    for _ in range(2):
        robot.set_frame(_frame_of(declaration, OIMode.PASSIVE))
        behaviour.tick_once()
        assert robot.flush() == []  # nothing the guard would refuse
        if behaviour.status is Status.FAILURE:
            break
    assert behaviour.status is Status.FAILURE
    message = behaviour.feedback_message
    assert message.endswith(
        f"the robot is in Passive: {name} needs Safe or Full; put `mode: safe` before it, "
        "e.g. in a retry"
    ), message


@pytest.mark.parametrize("name", ["drive", "turn", "spiral", "wall_follow"])
def test_a_mode_command_queued_beside_a_mover_in_its_first_tick_lets_it_drive(
    make: Make, name: str
) -> None:
    """``parallel: [drive, mode: safe]`` built in Python (the validator refuses it in a
    mission): the Safe queued in the drive's first tick is written after it, and the drive
    goes on in Safe on the next."""
    declaration = builtin_registry().get(name)
    assert declaration is not None
    robot = StubRobot(mode=OIMode.PASSIVE)
    behaviour = make(declaration.cls, robot=robot, **EXAMPLE_PARAMS.get(name, {}))
    robot.set_frame(_frame_of(declaration, OIMode.PASSIVE))
    assert tick(behaviour) is Status.RUNNING
    robot.outbox.send(oi.safe())
    assert [c.opcode for c in robot.flush()] == [131]
    robot.set_frame(_frame_of(declaration, OIMode.SAFE))
    assert tick(behaviour) is Status.RUNNING
    assert [c.spec.channel for c in robot.flush()] == ["wheels"]


def test_motors_after_a_queued_safe_are_queued(make: Make) -> None:
    """The same for an at-once leaf, which must end in its tick: a Safe queued before its
    Motors in this tick is written before it, so the guard takes it."""
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.set_frame({35: OIMode.PASSIVE})
    robot.outbox.send(oi.safe())
    assert tick(make(Vacuum, robot=robot, on=True)) is Status.SUCCESS
    assert [list(c.data) for c in robot.flush()] == [[131], [138, 2]]


@pytest.mark.parametrize("name", MOVERS)
def test_a_mover_in_safe_does_not_fail_on_its_first_tick(make: Make, name: str) -> None:
    declaration = builtin_registry().get(name)
    assert declaration is not None
    robot = StubRobot(mode=OIMode.SAFE)
    robot.set_frame(_frame_of(declaration, OIMode.SAFE))
    behaviour = make(declaration.cls, robot=robot, **EXAMPLE_PARAMS.get(name, {}))
    assert tick(behaviour) is not Status.FAILURE, behaviour.feedback_message


def _fell(cause: str, *, seen_at: float | None, entered: float | None = None) -> ModeChange:
    return ModeChange(
        OIMode.SAFE, OIMode.PASSIVE, 10, 12.0, cause, entered=entered, mission_time=seen_at
    )


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (_fell("wheel drop", seen_at=3.015), "the robot is in Passive since t=3.015 (wheel drop)"),
        (_fell("cliff", seen_at=None), "the robot is in Passive (cliff)"),  # not in a run
    ],
)
def test_the_message_says_the_fall_that_put_the_robot_there(change: ModeChange, said: str) -> None:
    snap = StubRobot(mode=OIMode.PASSIVE).snapshot._replace(last_fallback=change)
    assert needs_mode_message("turn", DRIVING_MODES, snap) == (
        f"{said}: turn needs Safe or Full; put `mode: safe` before it, e.g. in a retry"
    )


def test_a_fall_into_another_mode_than_the_robot_s_is_not_its_cause() -> None:
    """The last fall was to Passive, but the robot is in Off now (a Stop since): the fall
    is not why."""
    snap = StubRobot(mode=OIMode.OFF).snapshot._replace(last_fallback=_fell("cliff", seen_at=1.0))
    assert needs_mode_message("drive", DRIVING_MODES, snap).startswith(
        "the robot is in Off: drive needs Safe or Full"
    )


def test_on_a_charger_that_refused_safe_the_message_says_how_to_start_off_it() -> None:
    change = _fell("charger", seen_at=0.2, entered=11.95)  # 50 ms after Safe
    snap = StubRobot(mode=OIMode.PASSIVE).snapshot._replace(last_fallback=change)
    message = needs_mode_message("drive", DRIVING_MODES, snap)
    assert "(charger): drive needs Safe or Full" in message
    assert "undock" in message


def _shows_in_safe_only(declaration: Declaration) -> bool:
    """A leaf that sends only commands Safe and Full take, none of them on the wheels or
    motors (the LEDs, the display, the speaker): nothing of it moves, and nothing of it
    happens in Passive."""
    specs = [COMMANDS[opcode] for opcode in declaration.sends]
    return bool(specs) and all(
        spec.modes == DRIVING_MODES and spec.channel not in ("wheels", "motors") for spec in specs
    )


SHOWS = sorted(d.name for d in builtin_registry() if _shows_in_safe_only(d))


def test_the_shows_are_the_led_display_and_song_leaves() -> None:
    assert set(SHOWS) >= {"leds", "display", "schedule_leds", "play"}


@pytest.mark.parametrize("name", SHOWS)
def test_a_show_in_passive_fails_at_once_naming_its_command_sending_nothing(
    make: Make, name: str
) -> None:
    """The guard keeps the bytes off the wire (Passive takes no actuator command, both
    specs); until session 33 the leaf said SUCCESS, and the mission went on as if the LEDs
    had lit or the song had played."""
    declaration = builtin_registry().get(name)
    assert declaration is not None
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.set_frame({35: OIMode.PASSIVE})
    behaviour = make(declaration.cls, robot=robot, **EXAMPLE_PARAMS.get(name, {}))
    assert tick(behaviour) is Status.FAILURE
    assert robot.flush() == []
    (spec,) = (COMMANDS[opcode] for opcode in declaration.sends)
    assert behaviour.feedback_message == (
        f"the robot is in Passive: {name} ({spec.title} {spec.opcode}) needs Safe or Full; "
        "put `mode: safe` before it, e.g. in a retry"
    )


@pytest.mark.parametrize("name", SHOWS)
def test_a_show_after_a_safe_queued_in_its_tick_is_sent(make: Make, name: str) -> None:
    """A ``parallel``'s ``mode: safe`` queued before it in the same tick is written first."""
    declaration = builtin_registry().get(name)
    assert declaration is not None
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.set_frame({35: OIMode.PASSIVE})
    robot.outbox.send(oi.safe())
    behaviour = make(declaration.cls, robot=robot, **EXAMPLE_PARAMS.get(name, {}))
    assert tick(behaviour) is not Status.FAILURE, behaviour.feedback_message
    assert [c.opcode for c in robot.flush()] == [131, *declaration.sends]


#: the leaves whose tick out of Safe and Full asks only for what the OI stopped already when
#: it left them (the wheels, the brushes, the vacuum), with the parameters that make it so
_STOPPERS = [
    pytest.param(Stop, {"motors": False}, id="stop"),
    pytest.param(Stop, {"motors": True}, id="stop-motors"),
    pytest.param(Motors, {}, id="motors-off"),
    pytest.param(Vacuum, {"on": False}, id="vacuum-off"),
]


@pytest.mark.parametrize(("leaf", "params"), _STOPPERS)
def test_a_stop_out_of_safe_succeeds_sending_nothing_the_robot_being_stopped(
    make: Make, leaf: type[RobotBehaviour], params: dict[str, Any]
) -> None:
    """Decided (session 33, docs/protocol.md): both specs say the robot "stops all motors
    and reverts to the Passive mode" when it falls, so what ``stop`` asks for holds; the
    Drive 0 the guard would refuse is not queued (it was, and counted as a refusal). The
    motors switched off likewise since session 34: their Motors 0 was queued, refused and
    counted (failing ``--strict``) while ``stop: {motors: true}`` said SUCCESS."""
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.set_frame({35: OIMode.PASSIVE})
    behaviour = make(leaf, robot=robot, **params)
    assert tick(behaviour) is Status.SUCCESS
    assert robot.flush() == []
    assert behaviour.feedback_message.startswith(
        "the robot is in Passive: its wheels and motors are stopped already"
    )
    assert f"so {behaviour.declaration.name} sent nothing" in behaviour.feedback_message


@pytest.mark.parametrize(("leaf", "params"), _STOPPERS)
def test_a_stop_out_of_safe_fails_while_a_cycle_may_drive(
    make: Make, leaf: type[RobotBehaviour], params: dict[str, Any]
) -> None:
    """Drive 0 cannot stop a Clean in Passive, nor Motors 0 its brushes: FAILURE, with the
    way that does (Safe)."""
    robot = StubRobot(mode=OIMode.PASSIVE)
    robot.outbox.send(oi.clean())
    robot.flush()
    robot.set_frame({35: OIMode.PASSIVE})
    behaviour = make(leaf, robot=robot, **params)
    assert tick(behaviour) is Status.FAILURE
    assert robot.flush() == []
    message = behaviour.feedback_message
    assert "its own cycle may be driving it" in message
    assert f"put `mode: safe` before {behaviour.declaration.name}" in message


def test_stop_in_safe_sends_drive_0(make: Make) -> None:
    robot = StubRobot(mode=OIMode.SAFE)
    robot.set_frame({35: OIMode.SAFE})
    assert tick(make(Stop, robot=robot, motors=True)) is Status.SUCCESS
    assert [list(c.data) for c in robot.flush()] == [[137, 0, 0, 0, 0], [138, 0]]
