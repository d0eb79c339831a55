"""Leaf names show parameter values, also through subtrees whose arguments are parameters."""

from __future__ import annotations

import textwrap
from pathlib import Path

from roomba_bt.mission import load_mission


def test_subtree_argument_from_a_parameter_is_shown_as_its_value(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(
        textwrap.dedent(
            """
            parameters:
              how_long: {type: duration, default: 3s}
            subtrees:
              pause:
                parameters: {length: {type: duration}}
                tree: {wait: "${length}"}
            tree:
              subtree: {id: pause, length: "${how_long}"}
            """
        )
    )
    names = [node.name for node in load_mission(path, {"how_long": "7s"}).root.iterate()]
    assert "wait(7s)" in names, names  # as -p wrote it
    assert not any("${" in name for name in names), names


DOCK = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"


def test_a_duration_passed_into_a_subtree_is_named_as_written_not_in_seconds() -> None:
    """``-p time_limit=2min`` named the shipped dock's leaf ``dock_time_limit(120 s)`` in
    ``show``, the live tree and the failure, and its default ``10min`` ``600 s``: the
    reader had to divide to find the value they gave. The library's own defaults (``2 m``)
    are named as it writes them too, and ``show``'s parameter line says ``2min``."""
    mission = load_mission(DOCK, {"time_limit": "2min"})
    names = [node.name for node in mission.root.iterate()]
    assert "dock_time_limit(2min)" in names, names
    assert "dock_search(speed=350 mm/s, leg=2 m, follow=8 m, timeout=2min)" in names, names
    assert mission.parameters_shown["time_limit"] == "2min"
    assert mission.parameters_shown["search_follow"] == "8 m"  # its default, as written
    assert mission.parameters["time_limit"] == 120.0  # the value itself is unchanged


def test_an_argument_written_with_text_around_a_parameter_is_named_as_written(
    tmp_path: Path,
) -> None:
    """An argument that is more than one ``${parameter}`` is named with the parameter's own
    text in place; an int, which YAML writes as a number, keeps its number."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "parameters:\n  minutes: {type: int, default: 2}\n"
        "subtrees:\n  pause:\n"
        "    parameters: {length: {type: duration}, times: {type: int, default: 3}}\n"
        "    tree: {repeat: {times: '${times}', do: {wait: '${length}'}}}\n"
        "tree:\n  subtree: {id: pause, length: '${minutes}min', times: '${minutes}'}\n"
    )
    names = [node.name for node in load_mission(path).root.iterate()]
    assert "wait(2min)" in names, names
