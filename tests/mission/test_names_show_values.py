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
    assert "wait(7 s)" in names, names
    assert not any("${" in name for name in names), names
