"""Every condition ticked against frames set by hand: SUCCESS or FAILURE, never RUNNING."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pytest
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours import conditions as c
from roomba_bt.behaviours.blackboard import declare_keys, write_key
from roomba_bt.behaviours.units import ANGLE, DISTANCE, STR, ValueType
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import mm_to_counts
from roomba_bt.robot.interface import Odometry
from roomba_bt.robot.testing import StubRobot

Make = Callable[..., Any]


def holds(behaviour: Behaviour) -> bool:
    behaviour.tick_once()
    assert behaviour.status in (Status.SUCCESS, Status.FAILURE)
    return bool(behaviour.status is Status.SUCCESS)


@pytest.mark.parametrize(
    ("side", "raw", "expected"),
    [
        ("right", 0b01, True),  # bit 0 is bump RIGHT
        ("left", 0b01, False),
        ("left", 0b10, True),
        ("any", 0b10, True),
        ("any", 0b1100, False),  # wheel drops are not bumps
    ],
)
def test_bump(robot: StubRobot, make: Make, side: str, raw: int, expected: bool) -> None:
    robot.set_frame({7: raw})
    assert holds(make(c.Bump, side=side)) is expected


@pytest.mark.parametrize(
    ("side", "raw", "expected"),
    [
        ("right", 0b0100, True),
        ("left", 0b0100, False),
        ("left", 0b1000, True),
        ("any", 0b11, False),
    ],
)
def test_wheel_drop(robot: StubRobot, make: Make, side: str, raw: int, expected: bool) -> None:
    robot.set_frame({7: raw})
    assert holds(make(c.WheelDrop, side=side)) is expected


def test_cliff_each_sensor_and_any(robot: StubRobot, make: Make) -> None:
    robot.set_frame({9: 0, 10: 0, 11: 1, 12: 0})
    assert holds(make(c.Cliff, sensor="front_right"))
    assert not holds(make(c.Cliff, sensor="left"))
    assert holds(make(c.Cliff, sensor="any"))
    robot.set_frame({9: 0, 10: 0, 11: 0, 12: 0})
    assert not holds(make(c.Cliff, sensor="any"))
    assert c.Cliff.declaration.packets({"sensor": "left"}) == (9,)
    assert c.Cliff.declaration.packets({}) == (9, 10, 11, 12)


def test_wall_and_virtual_wall(robot: StubRobot, make: Make) -> None:
    robot.set_frame({8: 1, 13: 0})
    assert holds(make(c.Wall))
    assert not holds(make(c.VirtualWall))


def test_light_bumper_bits_and_signals(robot: StubRobot, make: Make) -> None:
    robot.set_frame({45: 0b100000, 51: 900, 46: 10})
    assert holds(make(c.LightBumper, sensor="right"))
    assert not holds(make(c.LightBumper, sensor="left"))
    assert holds(make(c.LightBumper, sensor="right", threshold=800))
    assert not holds(make(c.LightBumper, sensor="right", threshold=1000))
    assert c.LightBumper.declaration.packets({"threshold": 5}) == (46, 47, 48, 49, 50, 51)
    assert c.LightBumper.declaration.packets({"sensor": "right", "threshold": 5}) == (51,)
    assert c.LightBumper.declaration.packets({}) == (45,)


@pytest.mark.parametrize(
    ("code", "sees", "expected"),
    [
        (168, "red_buoy", True),  # 600 dock: red = bit 3
        (164, "green_buoy", True),
        (161, "force_field", True),
        (164, "red_buoy", False),
        (162, "virtual_wall", True),
        (172, "any_buoy", True),
        (248, "red_buoy", True),  # 500 / Discovery dock
        (242, "force_field", True),
        (168, "dock", True),
        (136, "remote", True),
        (0, "anything", False),
        (136, "anything", True),
        # a 560/570 Virtual Wall Lighthouse (500 spec: 0LLLL0BB): its buoys and force field
        # are not a dock's; its fence (BB = 00) is a virtual wall
        (0b0_0011_0_11, "red_buoy", False),  # lighthouse 3, red buoy beam (27)
        (0b0_0011_0_10, "green_buoy", False),
        (0b0_0011_0_01, "force_field", False),  # 25
        (0b0_0011_0_11, "any_buoy", False),
        (0b0_0011_0_11, "dock", False),
        (0b0_0011_0_00, "virtual_wall", True),  # its fence
        (0b0_0011_0_11, "anything", True),
    ],
)
def test_ir_characters(robot: StubRobot, make: Make, code: int, sees: str, expected: bool) -> None:
    robot.set_frame({17: code})
    assert holds(make(c.InfraRed, sees=sees)) is expected


def test_ir_left_and_right_receivers_and_remote_buttons(robot: StubRobot, make: Make) -> None:
    robot.set_frame({17: 0, 52: 168, 53: 136})
    assert holds(make(c.InfraRed, sees="red_buoy", receiver="left"))
    assert not holds(make(c.InfraRed, sees="red_buoy", receiver="right"))
    assert holds(make(c.InfraRed, sees="remote", receiver="right", button="clean"))
    assert not holds(make(c.InfraRed, sees="remote", receiver="right", button="spot"))
    assert c.InfraRed.declaration.packets({"receiver": "left"}) == (52,)


def test_charging_states(robot: StubRobot, make: Make) -> None:
    robot.set_frame({21: 3})
    assert holds(make(c.Charging, state="charging"))
    assert holds(make(c.Charging, state="trickle_charging"))
    assert not holds(make(c.Charging, state="not_charging"))
    robot.set_frame({21: 0})
    assert not holds(make(c.Charging, state="charging"))


def test_on_home_base(robot: StubRobot, make: Make) -> None:
    robot.set_frame({34: 2})
    assert holds(make(c.OnHomeBase))
    robot.set_frame({34: 1})
    assert not holds(make(c.OnHomeBase))


def test_battery_percent(robot: StubRobot, make: Make) -> None:
    robot.set_frame({25: 1500, 26: 3000})
    assert holds(make(c.Battery, below=60.0))
    assert not holds(make(c.Battery, below=40.0))
    assert holds(make(c.Battery, above=40.0))
    assert c.Battery.declaration.constraints is not None
    assert c.Battery.declaration.constraints({}) == ["give exactly one of above, below"]


def test_oi_mode(robot: StubRobot, make: Make) -> None:
    robot.set_frame({35: 1})
    assert holds(make(c.OIModeIs, **{"is": "passive"}))
    assert not holds(make(c.OIModeIs, **{"is": "safe"}))
    robot.set_frame({35: 3}, mode=OIMode.FULL)
    assert holds(make(c.OIModeIs, **{"is": "full"}))


def test_odometry_since_a_mark(robot: StubRobot, make: Make) -> None:
    robot.set_frame({43: 0, 44: 0})
    robot.set_frame({43: round(mm_to_counts(100)), 44: round(mm_to_counts(100))})
    write_key("here", robot.snapshot.odometry)
    robot.set_frame({43: round(mm_to_counts(250)), 44: round(mm_to_counts(250))})
    assert holds(make(c.OdometrySince, since="here", distance=140.0))
    assert not holds(make(c.OdometrySince, since="here", distance=160.0))
    assert holds(make(c.OdometrySince, distance=240.0))  # since the start


def test_odometry_distance_is_the_path_a_back_off_adds_to(robot: StubRobot, make: Make) -> None:
    """10 cm forward, then 10 cm back: 20 cm travelled, though the robot is where it began
    (the net signed distance, 0, said a "travelled too far" limit never tripped)."""
    forward = round(mm_to_counts(100))
    for counts in (0, forward, 0):
        robot.set_frame({43: counts, 44: counts})
    assert holds(make(c.OdometrySince, distance=150.0))
    assert not holds(make(c.OdometrySince, distance=210.0))


def test_odometry_angle_is_the_net_heading_change(robot: StubRobot, make: Make) -> None:
    """90 degrees left, then 90 back: the robot faces where it faced, a heading change of 0."""
    quarter = round(mm_to_counts(math.radians(90) * 235.0 / 2))
    for left, right in ((0, 0), (-quarter, quarter), (0, 0)):
        robot.set_frame({43: left, 44: right})
    assert not holds(make(c.OdometrySince, angle=45.0))
    assert holds(make(c.OdometrySince, angle=0.0))


def test_odometry_angle(robot: StubRobot, make: Make) -> None:
    write_key("start", Odometry())
    arc = math.radians(30) * 235.0 / 2
    robot.set_frame({43: 0, 44: 0})
    robot.set_frame({43: round(mm_to_counts(-arc)), 44: round(mm_to_counts(arc))})
    assert holds(make(c.OdometrySince, since="start", angle=29.0))
    assert not holds(make(c.OdometrySince, since="start", angle=31.0))


@pytest.mark.parametrize(("raw", "state"), [(0, "stuck"), (1, "moving"), (2, "dirty")])
def test_stasis(robot: StubRobot, make: Make, raw: int, state: str) -> None:
    robot.set_frame({58: raw})
    assert holds(make(c.StasisIs, state=state))
    other = "moving" if state != "moving" else "stuck"
    assert not holds(make(c.StasisIs, state=other))


def test_overcurrent_bits(robot: StubRobot, make: Make) -> None:
    robot.set_frame({14: 0b10000})  # bit 4: left wheel
    assert holds(make(c.Overcurrent, motor="left_wheel"))
    assert not holds(make(c.Overcurrent, motor="right_wheel"))
    assert holds(make(c.Overcurrent, motor="any"))
    robot.set_frame({14: 0b00010})  # bit 1 is unused
    assert not holds(make(c.Overcurrent, motor="any"))


def test_buttons(robot: StubRobot, make: Make) -> None:
    robot.set_frame({18: 0b100})
    assert holds(make(c.Button, name="dock"))
    assert not holds(make(c.Button, name="clean"))
    assert holds(make(c.Button, name="any"))


def test_button_pressed_holds_on_the_frame_a_press_begins_only(
    robot: StubRobot, make: Make
) -> None:
    """Held for three frames, released, pressed again: SUCCESS on the first frame of each
    press; ticked again within a frame (a guard and a child), the same answer."""
    pressed = make(c.ButtonPressed, name="clean")
    answers = []
    for raw in (0, 1, 1, 1, 0, 1, 0b10):
        robot.set_frame({18: raw})
        answers.append(holds(pressed))
    assert answers == [False, True, False, False, False, True, False]
    robot.set_frame({18: 1})
    assert holds(pressed) and holds(pressed)  # a press again after spot's frame


def test_button_pressed_counts_a_press_it_did_not_see_begin(robot: StubRobot, make: Make) -> None:
    """A button found down the first time, or after a gap longer than a press, counts as a
    press beginning, once; found down again after a tick or two the tree ticked without it
    (a ``play`` before it in a ``repeat``), it is the same press."""
    pressed = make(c.ButtonPressed, name="any")
    robot.set_frame({18: 0b100})
    assert holds(pressed)
    robot.set_frame({18: 0b100})  # a tick of the tree without it
    robot.set_frame({18: 0b100})
    assert not holds(pressed)
    for _ in range(c.SAME_PRESS_TICKS + 1):  # longer than any one press
        robot.set_frame({18: 0b100})
    assert holds(pressed)
    robot.set_frame({18: 0b100})
    assert not holds(pressed)


def test_sensor_comparison_by_packet_name(robot: StubRobot, make: Make) -> None:
    test = c.COMPARISON.parse("wall_signal > 100")
    assert test == (27, ">", 100.0)
    robot.set_frame({27: 150})
    assert holds(make(c.Sensor, test=test))
    robot.set_frame({27: 50})
    assert not holds(make(c.Sensor, test=test))
    assert c.Sensor.declaration.packets({"test": test}) == (27,)


def test_sensor_comparison_grammar_refuses_anything_else() -> None:
    with pytest.raises(c.UnitError, match="did you mean 'wall_signal'"):
        c.COMPARISON.parse("wal_signal > 1")
    with pytest.raises(c.UnitError, match="expected a comparison"):
        c.COMPARISON.parse("__import__('os').system('x')")


def test_check_blackboard_key(robot: StubRobot, make: Make) -> None:
    write_key("count", 2)
    assert holds(make(c.CheckKey, key="count", op="<", value=3))
    assert not holds(make(c.CheckKey, key="count", op=">=", value=3))
    write_key("count", "text")
    with pytest.raises(TypeError, match="cannot be compared"):  # incomparable: no silent False
        holds(make(c.CheckKey, key="count", op="<", value=3))


def test_a_failed_check_says_the_value_it_found(robot: StubRobot, make: Make) -> None:
    """As py_trees' CheckBlackboardVariableValue: the outcome quoted the node's name only,
    which says what was wanted, not what the key held. Cleared once it holds again."""
    write_key("count", 2)
    check = make(c.CheckKey, key="count", op="==", value=1)
    assert not holds(check)
    assert check.feedback_message == "count is 2, not == 1"
    write_key("count", 1)
    assert holds(check)
    assert check.feedback_message == ""


@pytest.mark.parametrize(
    ("key", "op", "value", "said"),
    [
        # verify session 34, chk.yaml: "d is 500.0, not < 200.0" for 50 cm and 20 cm
        ("d", "<", 200.0, "d is 500 mm, not < 200 mm"),
        ("wp.turn", "==", 45.0, "wp.turn is 90 deg, not == 45 deg"),  # a record's field
        ("s", "==", "hi", "s is 'bye', not == 'hi'"),  # a text quoted, told from a number
    ],
)
def test_a_failed_check_writes_a_quantity_in_its_unit(
    robot: StubRobot, make: Make, key: str, op: str, value: object, said: str
) -> None:
    """The key holds the canonical number; the message writes it as ``set`` and ``show``
    do, by the type the mission declares for the key."""
    record = ValueType("record", dict, fields=(("distance", DISTANCE), ("turn", ANGLE)))
    declare_keys({"d": DISTANCE, "wp": record, "s": STR})
    write_key("d", 500.0)
    write_key("wp", {"distance": 10.0, "turn": 90.0})
    write_key("s", "bye")
    check = make(c.CheckKey, key=key, op=op, value=value)
    assert not holds(check)
    assert check.feedback_message == said


def test_a_check_of_a_key_not_written_says_so(robot: StubRobot, make: Make) -> None:
    check = make(c.CheckKey, key="never_written", op="<", value=3)
    assert not holds(check)
    assert check.feedback_message == "never_written is not written yet"


def test_a_condition_with_a_lifecycle_of_its_own_gets_every_call_of_the_leaf_tick(
    robot: StubRobot, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Plain conditions take a short tick (no ``start``, ``terminate`` or ``stop`` calls,
    which do nothing for them); one that overrides any of these, or has one patched in, is
    ticked by the whole leaf tick, in py_trees' order."""
    calls: list[str] = []

    class Logged(c.Bump):
        def start(self) -> None:
            calls.append("start")

        def terminate(self, new_status: Status) -> None:
            calls.append(f"terminate={new_status.name}")

    plain, logged = c.Bump("plain", {"side": "any"}), Logged("logged", {"side": "any"})
    for node in (plain, logged):
        node.setup(robot=robot)
    robot.set_frame({7: 0b01})
    assert holds(plain) and holds(logged)
    robot.set_frame({7: 0})
    assert not holds(plain) and not holds(logged)
    assert calls == ["start", "terminate=SUCCESS", "start", "terminate=FAILURE"]
    robot.set_frame({7: 0b01})
    plain.update = lambda: Status.FAILURE  # type: ignore[method-assign]  # the monitor's force
    assert not holds(plain)
    del plain.update
    assert holds(plain)
    monkeypatch.setattr(c.Bump, "update", lambda self: Status.FAILURE)
    assert not holds(plain)


def test_one_sensor_node_compares_each_tick_s_frame(robot: StubRobot, make: Make) -> None:
    sensor = make(c.Sensor, test=c.COMPARISON.parse("wall_signal > 100"))
    for raw, expected in ((100, False), (101, True), (7, False)):
        robot.set_frame({27: raw})
        assert holds(sensor) is expected
