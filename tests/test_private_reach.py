"""No module function reaches into an argument's private state.

A function of the module that reads or sets ``runner._schedule`` is a method moved out of its
class and left reaching back in: the class looks shorter than its object is, and the state
has two homes. ``MissionRunner`` kept under the size guide that way (``slots_spanned``,
``tick_halted``, ``stop_running_tree``, ``refusal``: the reader's review, session 28), until
the run's clock, its ending and the stall ride became objects of their own
(``runtime/clock.py``, ``runtime/ending.py``, ``runtime/stall.py``). A function that needs
an object's state takes it as arguments, or is a method of the object that owns it.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "roomba_bt"


def _reaches(path: Path) -> list[str]:
    """``file:line function: argument._name`` for each private attribute (one underscore,
    not a dunder) that a module-level function reads or sets on one of its arguments."""
    found = []
    for node in ast.parse(path.read_text()).body:
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        params = node.args.posonlyargs + node.args.args + node.args.kwonlyargs
        names = {param.arg for param in params}
        for sub in ast.walk(node):
            if (
                isinstance(sub, ast.Attribute)
                and isinstance(sub.value, ast.Name)
                and sub.value.id in names
                and sub.attr.startswith("_")
                and not sub.attr.startswith("__")
            ):
                where = f"{path.relative_to(PACKAGE.parent)}:{sub.lineno}"
                found.append(f"{where} {node.name}: {sub.value.id}.{sub.attr}")
    return found


def test_no_module_function_reads_an_arguments_private_state() -> None:
    every = sorted(PACKAGE.rglob("*.py"))
    assert [reach for path in every for reach in _reaches(path)] == []
