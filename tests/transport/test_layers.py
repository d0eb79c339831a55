"""The layer rule for the two packages of the robot connection: ``transport`` knows bytes and
pyserial only (no opcodes), ``robot`` sits on ``oi`` and ``transport`` (never above them, never
on ``sim``)."""

from __future__ import annotations

import ast
import pathlib
import sys

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[2] / "roomba_bt"
#: below every layer, standard library only (tests/test_layers.py): lazy exports, escaping,
#: the base of the package's errors, the entry point's signals (``Terminated``)
BELOW = {"roomba_bt._lazy", "roomba_bt.printable", "roomba_bt.errors", "roomba_bt._entry"}
ALLOWED = {
    "transport": {"roomba_bt.transport", "serial", *BELOW},
    "robot": {
        "roomba_bt.oi",
        "roomba_bt.transport",
        "roomba_bt.robot",
        "serial",
        "transitions",
        *BELOW,
    },
}


def imported_modules(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_layer_imports_only_what_is_below_it(layer: str) -> None:
    offenders = []
    for path in sorted((PACKAGE / layer).glob("*.py")):
        for name in imported_modules(path):
            top = name.split(".")[0]
            if top in sys.stdlib_module_names or top == "__future__":
                continue
            if not any(name == ok or name.startswith(ok + ".") for ok in ALLOWED[layer]):
                offenders.append(f"{path.name}: {name}")
    assert offenders == []
