"""What a plugin's leaf returns and is given is held to its contract: ``update`` returns
SUCCESS, FAILURE or RUNNING (not INVALID), ``check`` returns a truth value, a ``@key``
value is within the parameter's range when the leaf starts, and a leaf built in Python
without its required parameters is refused when built (field test, session 24)."""

from __future__ import annotations

import typing

import numpy
import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours import Action, Condition, ParamError, declare, lean
from roomba_bt.behaviours.actions import Drive, Wait
from roomba_bt.behaviours.base import InvalidCheck
from roomba_bt.behaviours.blackboard import KeyRange, KeyType, declare_keys, read_key, write_key
from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.units import ANGLE, BOOL, DISTANCE, DURATION, INT, MARK, SPEED, ValueType
from roomba_bt.robot.interface import Odometry, Snapshot
from roomba_bt.robot.testing import StubRobot


@declare("returns_invalid", kind="action")
class ReturnsInvalid(Action):
    """Returns INVALID."""

    def update(self) -> Status:
        return Status.INVALID


def test_update_returning_invalid_is_the_node_s_error() -> None:
    """INVALID passed the status check: a sequence read it as "not started" and began again
    from its first child, so the drive before it was repeated until the run's timeout."""
    leaf = ReturnsInvalid("r")
    with pytest.raises(
        lean.InvalidStatus,
        match=r"ReturnsInvalid.update\(\) returned "
        r"Status.INVALID, which py_trees keeps for a node that has not run",
    ):
        leaf.tick_once()
    ok = py_trees.behaviours.Success("ok")
    root = lean.Sequence("root", True, [ok, ReturnsInvalid("r")])
    with pytest.raises(lean.InvalidStatus) as raised:
        root.tick_once()
    assert raised.value.node.name == "r" and raised.value.status is Status.INVALID


class _Returns(Condition):
    """A condition whose check returns what it is given."""

    returns: object = None

    def check(self, snapshot: Snapshot) -> bool:
        return typing.cast(bool, self.returns)


def _condition(returns: object) -> Condition:
    cls = type("Says", (_Returns,), {"returns": returns})
    declared = declare("says", kind="condition")(cls)
    node = declared("says")
    node.setup(robot=StubRobot())
    return node


@pytest.mark.parametrize(
    "returns", [None, "no", b"", "", Status.FAILURE, Status.SUCCESS, [], {"a": 1}]
)
def test_check_returning_no_truth_value_is_the_node_s_error(returns: object) -> None:
    """None (a forgotten ``return``) was FAILURE silently, "no" and Status.FAILURE were
    SUCCESS."""
    node = _condition(returns)
    with pytest.raises(InvalidCheck, match=r"Says.check\(\) returned .*, not a bool") as caught:
        node.tick_once()
    assert isinstance(caught.value, lean.InvalidStatus) and caught.value.method == "check"
    with pytest.raises(InvalidCheck):
        node.update()  # the update of the full leaf tick (a class with a lifecycle of its own)
    if isinstance(returns, Status):
        assert "update returns a Status" in str(caught.value)


@pytest.mark.parametrize(
    ("returns", "holds"),
    [(True, True), (False, False), (numpy.bool_(True), True), (numpy.bool_(False), False),
     (1, True), (0, False), (0.5, True), (numpy.float64(0.0), False)],
)  # fmt: skip
def test_check_returning_a_bool_or_a_number_is_its_truth(returns: object, holds: bool) -> None:
    node = _condition(returns)
    node.tick_once()
    assert node.status is (Status.SUCCESS if holds else Status.FAILURE)
    assert node.update() is node.status


def test_a_key_out_of_the_parameter_s_range_is_refused_when_the_leaf_starts() -> None:
    """900 mm/s written by a plugin reached the drive's encoder: "drive raised EncodeError",
    blamed on the built-in's code."""
    drive = Drive("fast", {"velocity": "@v", "duration": 1.0})
    drive.setup(robot=StubRobot())
    write_key("v", 900.0)
    with pytest.raises(KeyRange) as caught:
        drive.initialise()
    assert str(caught.value) == (
        "drive 'fast': velocity is @v, and blackboard key 'v' holds a value out of its range: "
        "velocity 900 mm/s is out of range: allowed -500..500 mm/s; the value was written "
        f"last (at {__file__}:100): the fault is that writer's, drive only refused the value"
    )
    assert (caught.value.writer, caught.value.written_at) == (
        "roomba-bt mission",
        f"at {__file__}:100",
    )
    write_key("v", 300.0)
    drive.initialise()
    assert drive.value("velocity") == 300.0


@declare(
    "grows",
    kind="action",
    params=(
        Param("velocity", SPEED, default="100 mm/s", minimum=0, maximum=500),
        Param("duration", DURATION, required=True, minimum=0.1),
        Param("pause", DURATION, minimum=0),
    ),
)
class Grows(Action):
    """Grows for a while."""

    def update(self) -> Status:
        return Status.SUCCESS if self.number("pause") else Status.RUNNING


@pytest.mark.parametrize("params", [{}, None], ids=["{}", "None"])
def test_no_parameters_from_python_still_checks_the_required_ones(params: object) -> None:
    """``{}`` and None skipped the check (it ran only for a non-empty mapping)."""
    with pytest.raises(ParamError, match=r"^wait 'w': missing required parameter\(s\) duration$"):
        Wait("w", params)  # type: ignore[arg-type]
    with pytest.raises(ParamError, match=r"^grows 'g': missing required parameter\(s\) duration"):
        Grows("g", params)  # type: ignore[arg-type]
    assert Drive("d", params).params["velocity"] == 200.0  # type: ignore[arg-type]


def test_a_declared_parameter_not_given_is_said_so() -> None:
    """It said the declaration "does not have" the parameter, then listed it."""
    node = Grows("g", {"duration": 1.0})
    with pytest.raises(
        KeyError,
        match=r"Grows reads parameter 'pause', which 'g' was not given "
        r"and 'grows' declares with no default",
    ):
        node.update()
    with pytest.raises(KeyError, match=r"which its declaration 'grows' does not have"):
        node.number("speed")


def test_a_plain_py_trees_behaviour_returning_invalid_is_caught_too() -> None:
    class Plain(py_trees.behaviour.Behaviour):
        def update(self) -> Status:
            return Status.INVALID

    root = py_trees.composites.Sequence("root", memory=True, children=[Plain("p")])
    assert lean.check_updates(root)
    with pytest.raises(lean.InvalidStatus, match=r"Plain.update\(\) returned Status.INVALID"):
        root.tick_once()


WAYPOINT = ValueType("record", dict, fields=(("distance", DISTANCE), ("turn", ANGLE)))


@pytest.mark.parametrize(
    ("key", "value", "problem"),
    [
        ("v", "0.2 m/s", "speed (mm/s): expected a number of mm/s, got '0.2 m/s' (a str)"),
        ("on", 1, "bool: expected true or false (a bool), got 1 (an int)"),
        ("n", 2.0, "int: expected an integer, got 2.0 (a float)"),
        ("v", True, "speed (mm/s): expected a number of mm/s, got a boolean (true)"),
        ("v", float("nan"), "speed (mm/s): expected a number of mm/s, got nan (a float)"),
        ("wp", {"distance": 500.0},
         "record: expected a mapping of distance, turn, got a mapping"),
        ("wp", {"distance": "1 m", "turn": 90.0},
         "record: field distance: expected a number of mm, got '1 m' (a str)"),
        ("start", 12.0, "mark: expected an odometry mark (snapshot.odometry), got a float"),
    ],
)  # fmt: skip
def test_write_key_refuses_a_value_not_of_the_key_s_declared_type(
    key: str, value: object, problem: str
) -> None:
    """A text in a speed key was stored as given, and blamed on the leaf that read it
    (``drive raised TypeError: type str doesn't define __round__``)."""
    declare_keys({"v": SPEED, "on": BOOL, "n": INT, "wp": WAYPOINT, "start": MARK})
    with pytest.raises(KeyType) as caught:
        write_key(key, value, "put")
    assert (
        str(caught.value)
        == f"write_key({key!r}, {value!r}) by 'put': blackboard key {key!r} is declared {problem}"
    )
    assert read_key(key) is None  # nothing written


def test_write_key_takes_values_of_the_declared_type_and_any_undeclared_key() -> None:
    declare_keys({"v": SPEED, "on": BOOL, "n": INT, "wp": WAYPOINT, "start": MARK})
    for key, value in [("v", 200.0), ("v", numpy.float64(-3)), ("v", 0), ("on", False),
                       ("n", numpy.int64(3)), ("wp", {"distance": 1.0, "turn": 90}),
                       ("start", Odometry()), ("other", "anything")]:  # fmt: skip
        write_key(key, value)
        assert read_key(key) == value
    with pytest.raises(KeyType, match=r"^write_key\('v', 'fast'\): blackboard key 'v'"):
        write_key("v", "fast")  # the mission's own writer is not named: the runtime names the node
    py_trees.blackboard.Blackboard.clear()  # a test's fixture: the types go with the keys
    write_key("v", "fast")
    assert read_key("v") == "fast"


@declare(
    "pt_forward",
    kind="action",
    params=(Param("distance", DISTANCE, default="20 cm", minimum=0, maximum=5000),),
)
class PyTreesStyleForward(Action):
    """Written as a py_trees user writes a leaf: ``initialise``, no ``super()``."""

    def initialise(self) -> None:
        self.goal = self.number("distance")

    def update(self) -> Status:
        return Status.RUNNING


@declare("pt_near", kind="condition", params=(Param("closer_than", DISTANCE, default="10 cm"),))
class PyTreesStyleNear(Condition):
    """A condition whose ``initialise`` calls ``super()`` and keeps a count of its starts."""

    starts = 0

    def initialise(self) -> None:
        super().initialise()
        self.starts += 1

    def check(self, snapshot: Snapshot) -> bool:
        return self.number("closer_than") > 150


def test_an_initialise_without_super_still_has_its_key_parameters_read() -> None:
    """py_trees' ``initialise`` does nothing, so its users override it without ``super()``:
    that left ``@key`` values as references, and ``number()`` raised ``float() argument
    must be ... not 'BlackboardRef'`` (the py_trees expert's ``pt_forward``, session 34)."""
    leaf = PyTreesStyleForward("pt", {"distance": "@d"})
    leaf.setup(robot=StubRobot())
    write_key("d", 300.0)
    leaf.tick_once()
    assert leaf.goal == 300.0 and leaf.status is Status.RUNNING
    leaf.stop(Status.INVALID)
    write_key("d", 120.0)  # read again at the next start
    leaf.tick_once()
    assert leaf.goal == 120.0


def test_an_initialise_calling_super_runs_once_and_reads_its_keys() -> None:
    """The wrapper and ``super().initialise()`` both read the parameters: the same values,
    the override itself run once per start, on the condition's whole tick."""
    robot = StubRobot()
    node = PyTreesStyleNear("near", {"closer_than": "@c"})
    node.setup(robot=robot)
    robot.set_frame({})
    write_key("c", 200.0)
    node.tick_once()
    assert node.status is Status.SUCCESS and node.starts == 1
    write_key("c", 100.0)
    node.tick_once()
    assert node.status is Status.FAILURE and node.starts == 2
