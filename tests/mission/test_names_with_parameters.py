"""A node's ``name:`` with ``${parameter}``: replaced, as BehaviorTree.CPP and GitHub Actions
replace it there. ``name: "b ${side}"`` ended a run ``FAILURE (b ${side})``, and a subtree
used twice could not name its two uses apart. Where a name is an identifier, a
``selected:`` that picks a child by it, a name that changes with a parameter is refused at
the name (another value would pick another child, or none), and ``selected:`` itself takes
no ``${``; ``$${`` is a literal ``${`` in both."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from roomba_bt.mission import CompiledMission
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]
ESCAPE_HINT = 'a literal "${" is written "$${"'

NAMED = """
mission: m
parameters:
  side: {type: enum, choices: [left, right], default: left}
subtrees:
  heading:
    parameters: {way: {type: str, default: left}}
    tree:
      sequence:
        name: "turn ${way}"
        children: [{log: "to ${way}", name: "say ${way}, $${not} replaced"}]
tree:
  sequence:
    - log: hello
      name: "start ${side}"
    - subtree: {id: heading, way: left}
    - subtree: {id: heading, way: right}
    - force_failure: {log: bye}
      name: "end ${side}"
"""


def _names(mission: CompiledMission) -> list[str]:
    return [node.name for node in mission.root.iterate()]


def test_a_name_s_parameters_are_replaced_in_the_tree_and_the_failure(
    compile_text: Compile,
) -> None:
    mission = compile_text(NAMED, {"side": "right"})
    names = _names(mission)
    assert "start right" in names
    assert "turn left" in names and "turn right" in names  # one subtree, two uses told apart
    assert "say left, ${not} replaced" in names  # $${: a literal ${
    assert "end right" in names
    robot = StubRobot(mode=OIMode.SAFE)
    mission.setup(robot)
    robot.set_frame({7: 0, 35: 2})
    mission.root.tick_once()
    failed = mission.root.children[-1]
    assert failed.name == "end right" and failed.status.value == "FAILURE"


def test_show_says_what_a_named_node_is_with_the_name_substituted(
    compile_text: Compile,
) -> None:
    reviewed = compile_text(NAMED).reviewed()
    assert "log(hello) named 'start left'" in [node.name for node in reviewed.iterate()]


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ('"b ${sid}"', "name: unknown parameter ${sid} (did you mean 'side'?)"),
        ('"b ${side"', "name: \"${\" at character 3 of 'b ${side' starts no parameter"),
    ],
)
def test_an_unknown_or_stray_parameter_in_a_name_is_an_error_at_the_name(
    errors_of: Errors, name: str, said: str
) -> None:
    (error,) = errors_of(
        "parameters: {side: {type: enum, choices: [left, right], default: left}}\n"
        f"tree:\n  log: hi\n  name: {name}\n"
    )
    assert error.startswith(f"4:9: {said}"), error
    assert error.endswith(ESCAPE_HINT), error


SELECTING = """
parameters:
  side: {{type: enum, choices: [left, right], default: left}}
tree:
  parallel:
    policy: selected
    selected: [{selected}]
    children:
      - {{wait: 10ms, name: {first}}}
      - {{wait: 20ms, name: fixed}}
"""


@pytest.mark.parametrize(
    ("text", "said"),
    [
        # with the default it picked 'w left'; ``-p side=right`` would have named no child
        (SELECTING.format(selected='"w left"', first='"w ${side}"'),
         "8:28: parallel.selected (at 6:15) picks this child by its name 'w left', which is "
         "made with a parameter"),
        # a leaf's own name, made of its parameter
        ("parameters: {t: {type: duration, default: 10ms}}\ntree:\n  parallel:\n"
         "    policy: selected\n    selected: [wait(10ms)]\n"
         '    children: [{wait: "${t}"}, {wait: 20ms}]\n',
         "6:23: parallel.selected (at 5:15) picks this child"),
        # selected: takes no parameter
        (SELECTING.format(selected='"w ${side}"', first='"w ${side}"'),
         "6:15: parallel.selected: 'w ${side}': child names are matched as written, and "
         "${side} is not replaced here"),
    ],
    ids=["a name made with a parameter", "a leaf's parameter in its name", "in selected"],
)  # fmt: skip
def test_a_child_selected_by_a_name_made_with_a_parameter_is_refused_at_the_name(
    errors_of: Errors, text: str, said: str
) -> None:
    (error,) = errors_of(text)
    assert error.startswith(said), error
    assert error.endswith(ESCAPE_HINT), error


def test_selected_reads_the_escape_and_a_varying_name_may_stand_beside_it(
    errors_of: Errors, compile_text: Compile
) -> None:
    """A child whose name varies may stand beside the selected one; ``$${`` in selected:
    picks a literal ``${``."""
    assert errors_of(SELECTING.format(selected="fixed", first='"w ${side}"')) == []
    mission = compile_text(SELECTING.format(selected='"a $${b}"', first='"a $${b}"'))
    parallel = mission.root
    assert parallel.children[0].name == "a ${b}"
    assert [c.name for c in parallel.policy.children] == ["a ${b}"]  # type: ignore[attr-defined]
