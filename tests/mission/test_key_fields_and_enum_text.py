"""Two blackboard gaps: ``check`` could not read a record's field (``key: wp.distance`` was
"unknown blackboard key", though ``@wp.distance`` reads one everywhere else), and an enum
parameter could not fill a ``str`` slot (``set: {key: ks, value: "${e}"}``: "parameter ${e}
is one of a, b, but set.value needs str"; ``log: "${e}"`` the same)."""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from roomba_bt.behaviours.blackboard import read_key
from roomba_bt.mission import CompiledMission
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]

MISSION = """
mission: m
parameters:
  e: {type: enum, choices: [a, b], default: b}
blackboard:
  ks: {type: str, initial: x}
  wp: {fields: {distance: distance, turn: angle}}
tree:
  sequence:
    - log: "${e}"
    - set: {key: ks, value: "${e}"}
    - check: {key: ks, value: b}
    - set: {key: wp, value: {distance: 1m, turn: 90deg}}
    - check: {key: wp.distance, op: "<", value: 2m}
    - check: {key: wp.turn, op: ">=", value: 90deg}
    - inverter: {check: {key: wp.distance, op: ">", value: 1m}}
    - log: done
"""


def test_check_reads_a_record_s_field_and_an_enum_fills_a_str_key(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    mission = compile_text(MISSION)
    robot = StubRobot(mode=OIMode.SAFE)
    mission.setup(robot)
    robot.set_frame({7: 0, 35: 2})
    with caplog.at_level(logging.INFO, logger="roomba_bt.mission"):
        mission.root.tick_once()
    assert mission.root.status.value == "SUCCESS"
    assert [r.message for r in caplog.records if r.name == "roomba_bt.mission"] == ["b", "done"]
    assert read_key("ks") == "b"
    assert read_key("wp.distance") == 1000.0  # a field, as @wp.distance reads it
    assert read_key("wp.nothing") is None


def test_a_field_read_before_its_record_is_written_is_said_as_the_record_s_key(
    errors_of: Errors,
) -> None:
    (error,) = errors_of(
        "blackboard:\n  wp: {fields: {distance: distance, turn: angle}}\n"
        "tree:\n  check: {key: wp.distance, op: '<', value: 2m}\n"
    )
    assert "reads blackboard key 'wp' before anything writes it" in error, error


@pytest.mark.parametrize(
    ("leaf", "said"),
    [
        ("check: {key: wp.nope, value: 2m}",
         "check.key: record key 'wp': unknown field 'nope' (did you mean 'none'?)"),
        ("check: {key: n.x, value: 2}",
         "check.key: blackboard key 'n' is int, not a record: only a record's field is read "
         "as KEY.FIELD"),
        ("set: {key: wp.distance, value: 2m}",
         "set.key: 'wp.distance' is a field of record key 'wp', and set writes a whole key: a "
         "field is read (check, @wp.distance), never written alone; write 'wp' with every "
         "field (distance, turn, none)"),
        ("check: {key: wp.turn, value: 2m}", "check.value: unknown angle unit 'm'"),
    ],
)  # fmt: skip
def test_what_a_key_field_cannot_be_is_said_with_what_is_allowed(
    errors_of: Errors, leaf: str, said: str
) -> None:
    errors = errors_of(
        "blackboard:\n  wp: {fields: {distance: distance, turn: angle, none: int}}\n"
        "  n: {type: int, initial: 1}\n"
        "tree:\n  sequence:\n    - set: {key: wp, value: {distance: 1m, turn: 1deg, none: 0}}\n"
        f"    - {leaf}\n"
    )
    assert len(errors) == 1 and said in errors[0], errors
