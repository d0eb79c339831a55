"""``show`` says what a composite or decorator does, its options as written, as it does a
leaf's parameters: a ``name:`` cannot pass a ten-minute ``timeout`` off as a 5 s safety
limit, and ``repeat: {times: 2}`` is told from ``repeat: {for: 1s}``."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest

from roomba_bt.mission import load_mission, load_mission_text
from roomba_bt.runtime.display import node_kind


def _reviewed_root(tmp_path: Path, tree: str) -> str:
    path = tmp_path / "m.yaml"
    path.write_text(
        "parameters:\n  limit: {type: duration, default: 10min}\n"
        "blackboard:\n  leg: {type: distance, initial: 0cm}\n"
        f"tree:\n{tree}"
    )
    return load_mission(path).reviewed().name


@pytest.mark.parametrize(
    ("tree", "shown"),
    [
        (
            "  timeout: {after: 10min, do: {wait: 1s}}\n  name: 5 s safety limit\n",
            "timeout(after=10min) named '5 s safety limit'",
        ),
        ("  timeout: {after: '${limit}', do: {wait: 1s}}\n", "timeout(after=10min)"),
        ("  retry: {times: 1000, do: {wait: 1s}}\n", "retry(times=1000)"),
        ("  repeat: {for: 1s, do: {wait: 1s}}\n", "repeat(for=1s)"),
        ("  delay: {for: 200ms, do: {wait: 1s}}\n", "delay(for=200ms)"),
        ("  held: {for: 45ms, do: {bump: any}}\n", "held(for=45ms)"),
        (
            "  for_each: {key: leg, in: [10cm, 20cm], do: {wait: 1s}}\n",
            "for_each(key=leg, in=[10cm, 20cm])",
        ),
        (
            "  parallel: {policy: one, synchronise: false, children: [{wait: 1s}, {wait: 2s}]}\n",
            "parallel(policy=one, synchronise=false)",
        ),
        (
            "  parallel: {policy: one, name: both, children: [{wait: 1s}, {wait: 2s}]}\n",
            "parallel(policy=one) named 'both'",
        ),
    ],
)
def test_show_says_a_composite_or_decorators_options_as_written(
    tmp_path: Path, tree: str, shown: str
) -> None:
    assert _reviewed_root(tmp_path, tree) == shown


@pytest.mark.parametrize(
    ("tree", "shown"),
    [
        ("  inverter: {bump: any}\n", "inverter"),
        ("  sequence: [{wait: 1s}]\n", "sequence"),
        (
            "  timeout: {after: 1s, do: {wait: 1s}}\n  name: limit\n",
            "timeout(after=1s) named 'limit'",
        ),
    ],
)
def test_options_left_at_their_default_are_not_said(tmp_path: Path, tree: str, shown: str) -> None:
    """As for a leaf: what the file writes is said, nothing more."""
    assert _reviewed_root(tmp_path, tree) == shown


def test_the_run_tree_keeps_the_name_alone(tmp_path: Path) -> None:
    """The live tree, the log and the outcome say the node by its name (as a named leaf's);
    only ``show``, the review, says what it is."""
    path = tmp_path / "m.yaml"
    path.write_text("tree:\n  timeout: {after: 1s, do: {wait: 1s}}\n  name: limit\n")
    assert load_mission(path).root.name == "limit"


def test_a_checks_operator_is_quoted_in_its_name(tmp_path: Path) -> None:
    """``check(key=n, op===, value=1)``: an ``=`` (or ``,``) in a value written as
    ``name=value`` ran into the ``=`` before it; such a value is quoted."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "blackboard:\n  n: {type: int, initial: 1}\ntree:\n  check: {key: n, op: '==', value: 1}\n"
    )
    assert load_mission(path).root.name == 'check(key=n, op="==", value=1)'


GUARDED = """\
tree:
  sequence:
    - wait: 1s
      until: {bump: any}
    - wait: 1s
      while: {inverter: {bump: any}}
"""


def test_show_draws_a_guard_as_the_composite_it_ticks_as(tmp_path: Path) -> None:
    """A guard has two children and was drawn with the leaf marker ``-->``: py_trees draws
    every composite it does not know so. ``until`` ticks as a selector without memory of
    [condition, node], ``while`` as a sequence without memory, and are drawn so."""
    path = tmp_path / "m.yaml"
    path.write_text(GUARDED)
    lines = py_trees.display.ascii_tree(load_mission(path).reviewed()).splitlines()
    assert lines[1:3] == ["    [o] until bump(any)", "        --> bump(any)"], lines
    # what it tests: "while inverter" said it only in the rows under it (library report 9)
    assert lines[4] == "    [-] while not bump(any)", lines


def test_show_writes_out_a_for_each_s_records() -> None:
    """``for_each(key=wp, in=...)`` hid the waypoints a reviewer reads; a long list stays
    one line of show's tree, its first items written and the rest counted."""
    route = [{"distance": f"{i}0cm", "turn": "90deg"} for i in range(1, 11)]
    text = (
        "blackboard: {wp: {fields: {distance: distance, turn: angle}}}\n"
        f"tree: {{sequence: [{{mode: safe}}, {{for_each: {{key: wp, in: {route!r}, "
        'do: {drive: {velocity: 200 mm/s, distance: "@wp.distance"}}}}]}\n'
    ).replace("'", "")
    drawn = py_trees.display.ascii_tree(load_mission_text(text).reviewed())
    shown = ", ".join(f"{{distance: {i}0cm, turn: 90deg}}" for i in range(1, 9))
    assert f"for_each(key=wp, in=[{shown}, ... and 2 more])" in drawn, drawn


def test_the_run_display_draws_a_guard_as_a_composite(tmp_path: Path) -> None:
    """The live tree, the end-of-run tree and the monitor name each node's marker by
    :func:`node_kind`: a guard's is no leaf's."""
    path = tmp_path / "m.yaml"
    path.write_text(GUARDED)
    root = load_mission(path).root
    until, while_ = root.children
    assert (node_kind(until), node_kind(while_)) == (
        "selector_without_memory",
        "sequence_without_memory",
    )
