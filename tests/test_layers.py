"""The layering contract, checked on every module's imports (no import-linter needed).

Lowest first: oi -> transport -> robot -> behaviours -> mission -> runtime -> cli; sim imports
only oi; evaluate sits at the top beside cli. Nothing in the main stack imports sim.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "roomba_bt"

MAIN_STACK = ("oi", "transport", "robot", "behaviours", "mission", "runtime")
ALLOWED: dict[str, set[str]] = {
    "oi": {"oi"},
    "transport": {"transport"},
    "robot": {"oi", "transport", "robot"},
    "behaviours": {"oi", "transport", "robot", "behaviours"},
    "mission": {"oi", "transport", "robot", "behaviours", "mission"},
    "runtime": {"oi", "transport", "robot", "behaviours", "mission", "runtime"},
    "sim": {"oi", "sim"},
    "cli": {*MAIN_STACK, "sim", "cli", "evaluate"},
    "evaluate": {*MAIN_STACK, "sim", "cli", "evaluate"},
}


def _layer_imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        for name in names:
            parts = name.split(".")
            if parts[0] == "roomba_bt" and len(parts) > 1:
                found.add(parts[1])
    return found


MODULES = sorted(p for p in PACKAGE.rglob("*.py") if p.parent != PACKAGE)


def test_every_package_has_a_layer() -> None:
    packages = {p.relative_to(PACKAGE).parts[0] for p in MODULES}
    assert packages <= set(ALLOWED), packages - set(ALLOWED)


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_imports_respect_the_layers(path: Path) -> None:
    layer = path.relative_to(PACKAGE).parts[0]
    imported = _layer_imports(path) - {"__version__"}
    forbidden = imported - ALLOWED[layer]
    assert not forbidden, f"{path.relative_to(PACKAGE)} ({layer}) imports {sorted(forbidden)}"


def test_the_protocol_layer_uses_the_standard_library_only() -> None:
    allowed_third_party: set[str] = set()
    for path in (PACKAGE / "oi").rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                tops = {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                tops = {node.module.split(".")[0]}
            else:
                continue
            for top in tops - {"roomba_bt", "__future__"}:
                import sys

                assert top in sys.stdlib_module_names or top in allowed_third_party, (
                    f"{path.name} imports {top}"
                )
