"""The layering contract, checked on every module's imports (no import-linter needed).

Lowest first: oi -> transport -> robot -> behaviours -> mission -> runtime -> cli; sim imports
only oi; evaluate sits at the top beside cli; monitor (the live page) below cli, beside sim.
Nothing in the main stack imports sim. Below them all, yamlsource (the shared YAML reader)
imports nothing of ours and any layer may use it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "roomba_bt"

MAIN_STACK = ("oi", "transport", "robot", "behaviours", "mission", "runtime")
#: below every layer: the one YAML-with-positions reader (missions, worlds); imports none of
#: ours, and every layer but the standard-library-only protocol may use it
BOTTOM = "yamlsource"
ALLOWED: dict[str, set[str]] = {
    BOTTOM: {BOTTOM},
    "oi": {"oi"},  # the protocol stays standard-library only, so no YAML
    "transport": {"transport", BOTTOM},
    "robot": {"oi", "transport", "robot", BOTTOM},
    "behaviours": {"oi", "transport", "robot", "behaviours", BOTTOM},
    "mission": {"oi", "transport", "robot", "behaviours", "mission", BOTTOM},
    "runtime": {"oi", "transport", "robot", "behaviours", "mission", "runtime", BOTTOM},
    "sim": {"oi", "sim", BOTTOM},
    "monitor": {*MAIN_STACK, "sim", "monitor", BOTTOM},
    "cli": {*MAIN_STACK, "sim", "cli", "evaluate", "monitor", BOTTOM},
    "evaluate": {*MAIN_STACK, "sim", "cli", "evaluate", BOTTOM},
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
