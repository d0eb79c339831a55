"""``$${`` in a mission text is a literal ``${`` (as docker-compose's, GitHub Actions' and
string.Template's ``$$``): before it, a log line or a text parameter could not say ``${``
at all, and a ``${`` that started no parameter (``"${speed"``) was passed on as text, so a
typo in a use went unseen. Both ways: the escape gives the text, and every error about a
``${`` says how to write one."""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from roomba_bt.mission import CompiledMission
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]
ESCAPE_HINT = 'a literal "${" is written "$${"'


def _logged(mission: CompiledMission, caplog: pytest.LogCaptureFixture) -> list[str]:
    """What the mission's ``log`` leaves write in one tick (each succeeds at once)."""
    robot = StubRobot(mode=OIMode.SAFE)
    mission.setup(robot)
    robot.set_frame({7: 0, 35: 2})
    with caplog.at_level(logging.INFO, logger="roomba_bt.mission"):
        mission.root.tick_once()
    return [r.message for r in caplog.records if r.name == "roomba_bt.mission"]


def test_a_doubled_dollar_writes_a_literal_opening(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    mission = compile_text(
        """
        mission: m
        description: "Say $${who} to ${who}"
        parameters:
          who: {type: str, default: bob}
          said: {type: str, default: "it costs $${price}"}
        tree:
          sequence:
            - log: "hello ${who}, $${who} is not replaced"
            - log: "$${who}"
            - log: "${said}"
            - log: "${said}, ${who}"
            - log: "$$${who}"
        """
    )
    assert _logged(mission, caplog) == [
        "hello bob, ${who} is not replaced",
        "${who}",
        "it costs ${price}",  # an escape in a parameter's default: its value, substituted once
        "it costs ${price}, bob",
        "$${who}",  # "$$${": "$" and then the escape, as in docker-compose
    ]
    assert mission.description == "Say ${who} to bob"
    names = [node.name for node in mission.root.iterate()]
    assert "log(hello bob, ${who} is not replaced)" in names, names


def test_a_default_may_hold_the_escape_but_not_a_parameter(errors_of: Errors) -> None:
    """A default cannot refer to a parameter; ``$${x}`` refers to none."""
    head = "mission: m\nparameters:\n  a: {type: str, default: "
    assert errors_of(head + '"$${a}"}\ntree: {log: "${a}"}\n') == []
    (error,) = errors_of(head + '"${a}"}\ntree: {log: "${a}"}\n')
    assert "a default cannot refer to itself" in error


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ('"cost ${ x"',
         "4:25: log.message: \"${\" at character 6 of 'cost ${ x' starts no parameter"),
        ('"${who"', "4:25: log.message: \"${\" at character 1 of '${who' starts no parameter"),
        ('"${who} and ${"', "of '${who} and ${' starts no parameter"),
        ('"${whoo}"', "4:25: log.message: unknown parameter ${whoo} (did you mean 'who'?)"),
        ('"hi ${whoo}"', "4:25: log.message: unknown parameter ${whoo} (did you mean 'who'?)"),
    ],
)  # fmt: skip
def test_a_stray_or_unknown_opening_is_an_error_that_names_the_escape(
    errors_of: Errors, value: str, said: str
) -> None:
    """``"${who"`` was logged as written: the closing brace forgotten went unseen."""
    errors = errors_of(
        "mission: m\nparameters:\n  who: {type: str, default: bob}\ntree: {sequence: [{log: "
        + value
        + "}]}\n"
    )
    assert len(errors) == 1, errors
    assert said in errors[0], errors
    assert errors[0].endswith(ESCAPE_HINT), errors


def test_a_stray_opening_in_a_typed_value_is_named_not_its_unit(errors_of: Errors) -> None:
    """``velocity: "${speed"`` said "expected a speed", as if the text were a number."""
    (error,) = errors_of(
        """
        mission: m
        parameters:
          speed: {type: speed, default: 200 mm/s}
        tree:
          sequence:
            - mode: safe
            - drive: {velocity: "${speed", duration: 1s}
        """
    )
    assert error.startswith("7:25: drive.velocity: \"${\" at character 1 of '${speed'"), error
    assert error.endswith(ESCAPE_HINT)
