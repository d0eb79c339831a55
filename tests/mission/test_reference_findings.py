"""What a py_trees user writing missions from docs/missions.md found (session 28): words the
docs promise that the command line and the compiler did not keep."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import compile_mission

Capsys = pytest.CaptureFixture[str]


def test_a_blackboard_keys_initial_value_may_be_a_parameter(
    mission_file: Callable[..., Path],
) -> None:
    """``initial: "${p}"`` said the declared ``p`` was an unknown parameter: the blackboard
    was read before the parameters."""
    path = mission_file(
        "parameters: {p: {type: int, default: 2}, s: {type: speed, default: 100 mm/s}}\n"
        'blackboard: {k: {type: int, initial: "${p}"}, v: {type: speed, initial: "${s}"}}\n'
        'tree: {check: {key: k, value: "${p}"}}\n'
    )
    mission, diagnostics = compile_mission(path, {"p": "5"})
    assert [d.message for d in diagnostics] == []
    assert mission is not None
    assert mission.blackboard_initial == {"k": 5, "v": 100.0}


def test_validate_takes_a_shipped_library_file_by_its_path(capsys: Capsys) -> None:
    """``roomba-bt missions lib/docking.yaml`` printed it; ``validate`` said "no such
    mission file" to the same words."""
    assert main(["validate", "lib/docking.yaml"]) == 0
    assert capsys.readouterr().out == "lib/docking.yaml: ok\n"
    assert main(["validate", "lib/no-such-file.yaml"]) == 2


def test_validate_quiet_prints_only_problems(
    mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    good = mission_file("tree: wall\n", "good.yaml")
    assert main(["validate", "-q", str(good)]) == 0
    assert capsys.readouterr().out == ""
    bad = mission_file("tree: {wal: {}}\n", "bad.yaml")
    assert main(["validate", "-q", str(bad)]) == 2
    assert "unknown node 'wal'" in capsys.readouterr().out


def test_an_empty_simulated_battery_is_refused_with_why(capsys: Capsys) -> None:
    """``--battery 0`` ran, and ended NO CONNECTION blaming the baud rate and the cable: an
    empty battery switches the simulated robot off."""
    with pytest.raises(SystemExit) as exited:
        main(["run", "bump-and-turn", "--fast", "--battery", "0"])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert "an empty battery switches the simulated robot off" in err
    assert "allowed: a charge above 0, up to 1" in err
