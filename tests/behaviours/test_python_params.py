"""Leaves built from Python are checked when built, as the compiler checks a mission's:
names, texts with units, ranges; the compiler's own (already checked) pass untouched."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from roomba_bt.behaviours import BlackboardRef, ParamError
from roomba_bt.behaviours.actions import Drive, Mode, Turn
from roomba_bt.behaviours.declare import Declaration, Param
from roomba_bt.behaviours.units import DURATION
from roomba_bt.mission import load_mission

MISSIONS = Path(__file__).resolve().parents[2] / "roomba_bt" / "missions"


def test_a_misspelt_parameter_is_refused_with_a_did_you_mean() -> None:
    with pytest.raises(TypeError) as caught:
        Drive("forward", {"velocty": 50.0, "duraton": 1.0})
    message = str(caught.value)
    assert isinstance(caught.value, ParamError)
    assert message.startswith("drive 'forward': unknown parameter 'velocty'")
    assert "(did you mean 'velocity'?)" in message
    assert "drive takes: velocity, radius, left, right" in message


def test_a_value_out_of_range_is_refused_when_built() -> None:
    with pytest.raises(ValueError, match=r"drive 'fast': velocity 900 mm/s is out of range"):
        Drive("fast", {"velocity": 900.0})


@pytest.mark.parametrize(
    ("minimum", "maximum", "said"),
    [(0.0, None, "pause -1 s is out of range: allowed 0 s or more"),
     (None, 5.0, "pause 9 s is out of range: allowed 5 s or less"),
     (0.5, 5.0, "pause -1 s is out of range: allowed 0.5..5 s")],
    ids=["no maximum", "no minimum", "closed"],
)  # fmt: skip
def test_a_range_open_at_one_end_is_said_in_words(
    minimum: float | None, maximum: float | None, said: str
) -> None:
    """``allowed 0.. s`` left the reader to guess what the missing end meant."""
    param = Param("pause", DURATION, minimum=minimum, maximum=maximum)
    value = -1.0 if minimum is not None else 9.0
    assert param.check_range(value) == said


def test_a_text_is_read_through_the_parameter_s_type_as_in_yaml() -> None:
    assert Drive("d", {"velocity": "200 mm/s", "radius": "spin_left"}).params["velocity"] == 200.0
    assert Drive("d", {"velocity": "0.1 m/s"}).params["velocity"] == pytest.approx(100.0)
    with pytest.raises(ParamError, match=r"drive 'd': velocity: .*200 mm/s"):
        Drive("d", {"velocity": "fast"})
    with pytest.raises(ParamError, match=r"out of range"):
        Drive("d", {"velocity": "2 m/s"})


def test_a_required_parameter_missing_is_refused() -> None:
    with pytest.raises(ParamError, match=r"turn 't': missing required parameter\(s\) angle"):
        Turn("t", {"speed": 100.0})
    assert Turn("t", {"angle": "90 deg"}).params["angle"] == pytest.approx(90.0)


def test_blackboard_references_pass_as_they_are() -> None:
    ref = BlackboardRef("leg")
    assert Drive("d", {"distance": ref}).params["distance"] is ref


def test_a_text_at_key_is_a_blackboard_reference_as_in_yaml() -> None:
    """``"@leg"`` from Python was refused as "expected a distance": YAML's spelling of a
    blackboard value did not work where the docs say values are written as in YAML."""
    assert Drive("d", {"distance": "@leg"}).params["distance"] == BlackboardRef("leg")
    assert Turn("t", {"angle": "@wp.turn"}).params["angle"] == BlackboardRef("wp", "turn")
    with pytest.raises(ParamError, match=r"distance: '@Leg' is not a blackboard reference"):
        Drive("d", {"distance": "@Leg"})


@pytest.mark.parametrize("value", ["@mode", BlackboardRef("mode")], ids=["text", "ref"])
def test_a_parameter_that_takes_no_blackboard_value_refuses_one(value: object) -> None:
    """A mode from the blackboard cannot be proved statically: YAML refuses it, and now so
    does Python (a BlackboardRef used to pass for any parameter)."""
    with pytest.raises(ParamError, match=r"to: a blackboard value \(@mode\) is not allowed"):
        Mode("m", {"to": value})


def test_the_compiler_s_leaves_are_not_checked_twice(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args: object) -> None:
        raise AssertionError("a compiled leaf was checked again")

    monkeypatch.setattr(Declaration, "checked", refuse)
    for path in sorted(MISSIONS.glob("*.yaml")):
        mission = load_mission(path)
        assert mission.plan is not None
        plans = [node for node in mission.plan.walk() if node.kind == "leaf"]
        leaves = [n for n in mission.root.iterate() if hasattr(n, "declaration")]
        assert plans and len(plans) == len(leaves), path
        for plan, leaf in zip(plans, leaves, strict=True):
            assert all(leaf.params[k] is v for k, v in plan.params.items())  # type: ignore[attr-defined]


def test_check_refuses_a_value_it_could_never_order() -> None:
    """``value="200 mm"`` from Python is text: 250.0 > "200 mm" raised TypeError, which the
    check turned into False on every tick."""
    from roomba_bt.behaviours.conditions import CheckKey

    with pytest.raises(ParamError, match=r"check 'leg': value '200 mm' is text.*200\.0"):
        CheckKey("leg", {"key": "leg", "op": ">", "value": "200 mm"})
    with pytest.raises(ParamError, match=r"value None \(NoneType\) cannot be ordered with <"):
        CheckKey("leg", {"key": "leg", "op": "<", "value": None})
    CheckKey("leg", {"key": "leg", "op": ">", "value": 200.0})  # a number: fine
    CheckKey("name", {"key": "name", "op": "==", "value": "home"})  # equality: anything


def test_check_raises_when_the_key_holds_what_cannot_be_compared() -> None:
    from roomba_bt.behaviours.blackboard import write_key
    from roomba_bt.behaviours.conditions import CheckKey

    node = CheckKey("leg", {"key": "leg_to_compare", "op": ">", "value": 200.0})
    assert node.check(None) is False  # type: ignore[arg-type]  # never written: False
    write_key("leg_to_compare", "long")
    with pytest.raises(TypeError, match=r"key 'leg_to_compare' holds 'long' \(str\)"):
        node.check(None)  # type: ignore[arg-type]


NAN = float("nan")


@pytest.mark.parametrize(
    "leaf, params, said",
    [
        ("drive", {"velocity": [200]}, "velocity: expected speed (mm/s): a number in mm/s"),
        ("drive", {"velocity": NAN}, "velocity: must be a finite number, got nan"),
        ("drive", {"velocity": True}, "velocity: expected speed (mm/s)"),
        ("drive", {"velocity": 200, "duration": [1]}, "duration: expected duration (s)"),
        ("drive", {"velocity": 200, "distance": NAN}, "distance: must be a finite number"),
        ("wait", {"duration": True}, "duration: expected duration (s)"),
        ("motors", {"vacuum": 2}, "vacuum: expected true or false, got 2"),
        ("mode", {"to": 1}, "to: expected one of passive, safe, full, got 1"),
        ("log", {"message": 5}, "message: expected a text, got 5 (int)"),
        ("log", {"message": "\x1b[2J hi"}, "message: control character U+001B is not allowed"),
        ("drive", {"velocity": None, "distance": None}, None),  # optional None: not given
        ("wait", {"duration": None}, "duration: required: None gives no value"),
    ],
)
def test_every_value_is_checked_by_its_declared_type(
    leaf: str, params: dict[str, object], said: str | None
) -> None:
    """Only texts went through the type: numbers were only range-checked, so True, NaN,
    lists, a bool parameter given 2 or an enum given 1 passed (NaN drove until a bump), and
    None, lists and NaN raised raw TypeError/ValueError."""
    from roomba_bt.behaviours.registry import default_registry

    cls = default_registry().get(leaf).cls
    if said is None:
        assert cls("n", params).params["velocity"] == 200.0  # the default
        return
    with pytest.raises(ParamError) as caught:
        cls("n", params)
    assert str(caught.value).startswith(f"{leaf} 'n': "), caught.value
    assert said in str(caught.value)


def test_parameters_that_are_no_mapping_are_refused() -> None:
    from roomba_bt.behaviours.actions import Wait

    with pytest.raises(ParamError, match=r"wait 'n': the parameters are a mapping .* got '2s'"):
        Wait("n", "2s")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "build, said",
    [
        (lambda c: ("Timeout", -1.0), "-1.0 s is out of range"),
        (lambda c: ("Timeout", NAN), "nan s is out of range"),
        (lambda c: ("Timeout", None), "expected seconds"),
        (lambda c: ("Timeout", "soon"), "expected a duration"),
        (lambda c: ("Delay", -2.0), "-2.0 s is out of range: at least 0 s"),
    ],
)
def test_the_language_s_decorators_check_their_times(build: object, said: str) -> None:
    import py_trees

    from roomba_bt.behaviours import decorators

    kind, value = build(None)  # type: ignore[operator]
    cls = getattr(decorators, kind)
    with pytest.raises(ParamError, match=rf"{kind} 't': duration: .*{re.escape(said)}"):
        cls("t", py_trees.behaviours.Success("c"), value)
    assert cls("t", py_trees.behaviours.Success("c"), "5 s").duration == 5.0


def test_repeat_checks_its_count_and_time() -> None:
    import py_trees

    from roomba_bt.behaviours.decorators import Repeat

    with pytest.raises(ParamError, match=r"Repeat 'r': times: .* got 0"):
        Repeat("r", py_trees.behaviours.Success("c"), times=0)
    with pytest.raises(ParamError, match=r"Repeat 'r': duration: -1 s"):
        Repeat("r", py_trees.behaviours.Success("c"), duration=-1)
    assert Repeat("r", py_trees.behaviours.Success("c"), times=3).times == 3


def test_units_are_written_as_in_yaml_and_a_bare_number_is_the_canonical_unit() -> None:
    """docs/runtime.md, a tree built by hand: a pycreate2 or ROS program writes radians and
    metres with their unit (the mission language's parser reads them); a bare number is the
    canonical unit (decided), so ``1.57`` is 1.57 degrees; a wrong unit names the leaf, the
    parameter and the units there are, as the page quotes it."""
    import math

    assert Turn("t", {"angle": "1.57 rad"}).params["angle"] == pytest.approx(math.degrees(1.57))
    assert Turn("t", {"angle": "0.25 turn"}).params["angle"] == pytest.approx(90.0)
    assert Turn("t", {"angle": 1.57}).params["angle"] == 1.57
    assert Drive("d", {"velocity": "0.2 m/s"}).params["velocity"] == pytest.approx(200.0)
    assert Drive("d", {"velocity": 0.2}).params["velocity"] == 0.2
    assert Drive("d", {"distance": "50 cm"}).params["distance"] == pytest.approx(500.0)
    with pytest.raises(ParamError) as caught:
        Turn("t", {"angle": "90 m"})
    said = "turn 't': angle: unknown angle unit 'm' in '90 m'; use one of: deg, °, rad, turn, turns"
    assert str(caught.value) == said
    page = " ".join((MISSIONS.parents[1] / "docs" / "runtime.md").read_text().split())
    assert f"`{said}`" in page
