"""Leaves built from Python are checked when built, as the compiler checks a mission's:
names, texts with units, ranges; the compiler's own (already checked) pass untouched."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.behaviours import BlackboardRef, ParamError
from roomba_bt.behaviours.actions import Drive, Turn
from roomba_bt.behaviours.declare import Declaration
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
    from roomba_bt.behaviours.conditions import CheckKey
    from roomba_bt.behaviours.declare import write_key

    node = CheckKey("leg", {"key": "leg_to_compare", "op": ">", "value": 200.0})
    assert node.check(None) is False  # type: ignore[arg-type]  # never written: False
    write_key("leg_to_compare", "long")
    with pytest.raises(TypeError, match=r"key 'leg_to_compare' holds 'long' \(str\)"):
        node.check(None)  # type: ignore[arg-type]
