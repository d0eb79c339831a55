"""The layering contract, checked on every module's imports (no import-linter needed).

Lowest first: oi -> transport -> robot -> behaviours -> mission -> runtime -> cli; sim imports
only oi; evaluate sits at the top beside cli; monitor (the live page) below cli, beside sim.
Nothing in the main stack imports sim. Below them all, yamlsource (the shared YAML reader)
imports nothing of ours and any layer may use it; so do ``_lazy`` (a package's names
imported when first asked for) and ``printable`` (a text's control characters escaped for a
terminal), which the protocol layer may use too.

Above them all, the top package ``roomba_bt`` (its ``__init__.py``): it names what a Python
program needs from every layer, each imported from its module when first asked for, so it
imports nothing of theirs when it runs (:func:`test_the_top_package_imports_no_layer`). No
layer takes those names from it (``from roomba_bt import Connection`` in the robot layer is
an import from above); ``from roomba_bt import yamlsource`` is the module, and
``__version__`` is the top package's own.
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
#: below every layer too, the protocol's included: lazy exports (PEP 562), standard library only
LAZY = "_lazy"
#: below every layer too: what of a text may be printed as it is (control characters
#: escaped), standard library only, so the command line's parser loads no YAML to say a name
PRINTABLE = "printable"
#: below every layer too: ``RoombaBtError``, the base of the package's own errors (every
#: layer's errors derive from it, the protocol's included), standard library only
ERRORS = "errors"
#: below every layer too: the project file (``pyproject.toml``'s ``[tool.roomba-bt]``), found
#: and read with the standard library only, so a command reads the project's robot model
#: without loading the mission compiler
PROJECT = "project"
#: below every layer too: what an ImportError says (which package to install or reinstall),
#: standard library only, so the simulator's plots say a half-installed matplotlib as the
#: command line says any other
INSTALLATION = "installation"
#: below every layer too, run first by the top package: the current folder off ``sys.path``
#: under ``python -m roomba_bt``, with only the modules Python loaded at start-up
SAFE_PATH = "_safe_path"
#: below every layer too: the command's entry point, the ending signals taken before anything
#: heavy loads, and what their handlers raise (``Terminated``, which robot.safety re-exports)
ENTRY = "_entry"
#: what every layer may import, the protocol's included
STDLIB_ONLY = {LAZY, PRINTABLE, ERRORS, PROJECT, INSTALLATION, SAFE_PATH, ENTRY}
ALLOWED: dict[str, set[str]] = {
    BOTTOM: {BOTTOM, PRINTABLE},
    "oi": {"oi", *STDLIB_ONLY},  # the protocol stays standard-library only, so no YAML
    "transport": {"transport", BOTTOM, *STDLIB_ONLY},
    "robot": {"oi", "transport", "robot", BOTTOM, *STDLIB_ONLY},
    "behaviours": {"oi", "transport", "robot", "behaviours", BOTTOM, *STDLIB_ONLY},
    "mission": {"oi", "transport", "robot", "behaviours", "mission", BOTTOM, *STDLIB_ONLY},
    "runtime": {
        "oi",
        "transport",
        "robot",
        "behaviours",
        "mission",
        "runtime",
        BOTTOM,
        *STDLIB_ONLY,
    },
    "sim": {"oi", "sim", BOTTOM, *STDLIB_ONLY},
    "monitor": {*MAIN_STACK, "sim", "monitor", BOTTOM, *STDLIB_ONLY},
    "cli": {*MAIN_STACK, "sim", "cli", "evaluate", "monitor", BOTTOM, *STDLIB_ONLY},
    "evaluate": {*MAIN_STACK, "sim", "cli", "evaluate", BOTTOM, *STDLIB_ONLY},
}


def _top_package_name(name: str) -> str:
    """What ``from roomba_bt import <name>`` takes: a layer's package or module (``name``),
    else a name of the top package's own (``roomba_bt.<name>``)."""
    if (PACKAGE / name).is_dir() or (PACKAGE / f"{name}.py").is_file():
        return name
    return f"roomba_bt.{name}"


def _layer_imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module == "roomba_bt" and not node.level:
            found.update(_top_package_name(alias.name) for alias in node.names)
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
    imported = _layer_imports(path) - {"roomba_bt.__version__"}
    forbidden = imported - ALLOWED[layer]
    assert not forbidden, f"{path.relative_to(PACKAGE)} ({layer}) imports {sorted(forbidden)}"


def _runtime_imports(path: Path) -> set[str]:
    """The modules of ours ``path`` imports when it runs: those under ``if TYPE_CHECKING:``
    (for type checkers only) left out, not those of its ``else:``."""
    tree = ast.parse(path.read_text(), filename=str(path))
    checking = [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"
    ]
    # the ``if`` body alone: its ``else`` runs (the top package's lazy names)
    skipped = {id(inner) for node in checking for stmt in node.body for inner in ast.walk(stmt)}
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and id(node) not in skipped:
            found.add(node.module)
        elif isinstance(node, ast.Import) and id(node) not in skipped:
            found.update(alias.name for alias in node.names)
    return {name for name in found if name.startswith("roomba_bt")}


def test_the_top_package_imports_no_layer() -> None:
    """``roomba_bt/__init__.py`` names every layer's exports but imports none of them when
    it runs (each when first asked for): only the lazy-export helper below them all, and
    the one that takes ``python -m``'s current folder off ``sys.path`` first."""
    assert _runtime_imports(PACKAGE / "__init__.py") == {
        f"roomba_bt.{LAZY}",
        f"roomba_bt.{SAFE_PATH}",
    }


@pytest.mark.parametrize("module", [LAZY, PRINTABLE, SAFE_PATH])
def test_the_modules_below_every_layer_import_nothing_of_ours(module: str) -> None:
    assert _runtime_imports(PACKAGE / f"{module}.py") == set()


def test_a_layer_takes_no_name_from_the_top_package() -> None:
    """The rule :func:`test_imports_respect_the_layers` applies: ``from roomba_bt import X``
    in a layer is the module X, or an import from above it."""
    assert _top_package_name("yamlsource") == "yamlsource"
    assert _top_package_name(LAZY) == LAZY
    assert _top_package_name("Connection") == "roomba_bt.Connection"
    assert "roomba_bt.Connection" not in set().union(*ALLOWED.values())


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


#: issue 13's guide: a class over about 400 lines or a function over about 60 says why
LONG_CLASS, LONG_FUNCTION = 400, 60


def _too_long_without_a_reason(path: Path) -> list[str]:
    """Each long class or function whose comment above it or docstring does not say it is
    long "on purpose" (and why, beside it)."""
    lines = path.read_text().splitlines()
    found = []
    for node in ast.walk(ast.parse("\n".join(lines), filename=str(path))):
        if isinstance(node, ast.ClassDef):
            limit = LONG_CLASS
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            limit = LONG_FUNCTION
        else:
            continue
        assert node.end_lineno is not None
        if node.end_lineno - node.lineno + 1 <= limit:
            continue
        first = node.decorator_list[0].lineno if node.decorator_list else node.lineno
        said = "\n".join(lines[max(0, first - 5) : node.lineno])
        said += ast.get_docstring(node) or ""
        if "on purpose" not in " ".join(said.lower().split()):
            found.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {node.name}")
    return found


def test_long_classes_and_functions_say_why() -> None:
    every = sorted(PACKAGE.rglob("*.py"))
    assert [name for path in every for name in _too_long_without_a_reason(path)] == []
