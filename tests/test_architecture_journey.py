"""The architecture page's "journey of one stream frame" names what the code has.

Every code span of that section that names code is looked up, within its step (a numbered
hop, or a paragraph): a file (``runtime/loop.py``) must exist in the package; a
``Class.attr`` must be an attribute of that class (a method, a property, a class attribute,
or one its methods assign to ``self``); a dotted module path (``oi.encode.drive``) must import
and hold the name; and a bare name (``tick_halted``, ``SNAPSHOT_KEY``, ``ModeError``) must be
defined or imported in a module the same step names (its files, and the modules of the
classes it names), or be py_trees' (``initialise``, ``update``). The journey named a
``StallRide.read`` and the runner's ``_tick_halted``, which no longer existed (the second is
a module function, ``tick_halted``), and nothing said so (the reader's review, session 28).
"""

from __future__ import annotations

import ast
import importlib
import re
import struct
from functools import cache
from pathlib import Path

import py_trees
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "roomba_bt"
DOC = ROOT / "docs" / "architecture.md"

#: a name, dotted or not, perhaps called: ``Connection.poll_frames(timeout)``
_CODE_NAME = re.compile(r"^(?P<name>[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)(?:\(.*\))?$")
#: a file of the package, as the page writes it: ``runtime/loop.py``, ``behaviours/lean.py``
_FILE = re.compile(r"^[a-z_]+/[a-z_/]+\.py$")
#: what the journey names that is not the package's: the root of the tree (a py_trees
#: behaviour) and the struct a layout decodes with
OUTSIDE: dict[str, type] = {"root": py_trees.behaviour.Behaviour, "": struct.Struct}


def journey(text: str) -> str:
    """The section "The journey of one stream frame", up to the next ``## `` heading."""
    start = text.index("## The journey of one stream frame")
    end = text.find("\n## ", start + 1)
    return text[start : end if end >= 0 else len(text)]


def steps(section: str) -> list[list[str]]:
    """The code spans of each step of ``section`` (a numbered hop, or a paragraph), its fenced
    blocks left out."""
    section = re.sub(r"```.*?```", "", section, flags=re.S)
    found = []
    for step in re.split(r"\n(?=\d+\. )|\n\s*\n", section):
        found.append([s.strip() for s in re.findall(r"`([^`]+)`", step.replace("\n", " "))])
    return found


@cache
def _index() -> tuple[dict[str, list[tuple[str, ast.ClassDef]]], dict[str, frozenset[str]]]:
    """Every class of the package by name (its module and definition), and the names each
    module defines or imports: its functions, classes, globals and imports, its classes'
    methods and attributes, and what their methods assign to ``self``."""
    classes: dict[str, list[tuple[str, ast.ClassDef]]] = {}
    defined: dict[str, frozenset[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        names: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                classes.setdefault(node.name, []).append((module, node))
                names.add(node.name)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                names.add(node.name)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.add(node.id)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                names.add(node.attr)
            elif isinstance(node, ast.ImportFrom | ast.Import):
                names.update(a.asname or a.name.split(".")[0] for a in node.names)
        defined[module] = frozenset(names)
    return classes, defined


def _assigned_to_self(cls: ast.ClassDef) -> set[str]:
    return {
        node.attr
        for node in ast.walk(cls)
        if isinstance(node, ast.Attribute)
        and isinstance(node.ctx, ast.Store)
        and isinstance(node.value, ast.Name)
        and node.value.id == "self"
    }


def _has(head: str, attr: str) -> bool:
    """Whether the package's class ``head`` (any of that name) has ``attr``."""
    classes, _ = _index()
    for module, node in classes[head]:
        cls = getattr(importlib.import_module(module), head)
        if hasattr(cls, attr) or attr in _assigned_to_self(node):
            return True
        for base in cls.__mro__[1:]:  # what a base class of ours assigns to self
            if any(attr in _assigned_to_self(b) for _, b in classes.get(base.__name__, [])):
                return True
    return False


def _py_trees_has(path: list[str]) -> bool:
    """Whether ``py_trees.<path>`` exists: its module imported, the rest its attributes."""
    for cut in range(len(path), -1, -1):
        try:
            found: object = importlib.import_module(".".join(["py_trees", *path[:cut]]))
        except ImportError:
            continue
        for name in path[cut:]:
            if not hasattr(found, name):
                return False
            found = getattr(found, name)
        return True
    return False


def _scope(step: list[str]) -> set[str]:
    """The modules a step names: its files, and the modules of the classes it names."""
    classes, _ = _index()
    scope = set()
    for span in step:
        if _FILE.match(span):
            scope.add("roomba_bt." + span.removesuffix(".py").replace("/", "."))
        match = _CODE_NAME.match(span)
        if match is not None and match["name"].split(".")[0] in classes:
            scope.update(module for module, _ in classes[match["name"].split(".")[0]])
    return scope


def problem(span: str, scope: set[str]) -> str | None:
    """What is wrong with the code span ``span`` as a name of the package's code, a bare name
    looked for in the modules of ``scope``; None when it names what exists, or names no code
    (an option, bytes, a YAML word)."""
    if _FILE.match(span):
        return None if (PACKAGE / span).is_file() else f"no file roomba_bt/{span}"
    match = _CODE_NAME.match(span)
    if match is None:
        return None  # `--timeout`, `[19][n]`, `drive 0`: not a name of code
    classes, defined = _index()
    head, *rest = match["name"].split(".")
    if not rest:
        if any(head in defined.get(module, ()) for module in scope) or any(
            hasattr(outside, head) for outside in OUTSIDE.values()
        ):
            return None
        return f"{head} is in none of {', '.join(sorted(scope)) or 'no module named'}"
    if head in classes:
        if len(rest) != 1:
            return f"{span}: a class's attribute is one name"
        return None if _has(head, rest[0]) else f"{head} has no attribute {rest[0]}"
    if head in OUTSIDE and len(rest) == 1:
        return None if hasattr(OUTSIDE[head], rest[0]) else f"{head} has no {rest[0]}"
    if head == "py_trees":  # py_trees' own: py_trees.trees.BehaviourTree.tick_tock
        return None if _py_trees_has(rest) else f"py_trees has no {'.'.join(rest)}"
    path = match["name"].rsplit(".", 1)
    try:  # a module path: oi.encode.drive
        module = importlib.import_module(f"roomba_bt.{path[0]}")
    except ImportError:
        return f"{span}: neither a class of the package nor a module path"
    return None if hasattr(module, path[1]) else f"{module.__name__} has no {path[1]}"


STEPS = steps(journey(DOC.read_text()))
SPANS = [(span, tuple(sorted(_scope(step)))) for step in STEPS for span in step]


def test_the_journey_names_code() -> None:
    """The section is found and split into its steps: if the parse broke, nothing would be
    checked."""
    assert len(SPANS) > 60
    assert len(STEPS) >= 14
    assert "MissionRunner._loop" in {span for span, _ in SPANS}


@pytest.mark.parametrize(("span", "scope"), sorted(set(SPANS)), ids=lambda v: str(v)[:60])
def test_each_name_in_the_journey_exists(span: str, scope: tuple[str, ...]) -> None:
    assert problem(span, set(scope)) is None, problem(span, set(scope))


@pytest.mark.parametrize(
    ("span", "wrong"),
    [
        ("StallRide.read", "StallRide has no attribute read"),
        ("_tick_halted", "_tick_halted is in none of roomba_bt.runtime.loop"),
        ("runtime/ticking.py", "no file roomba_bt/runtime/ticking.py"),
        ("oi.encode.drive_fast(velocity)", "roomba_bt.oi.encode has no drive_fast"),
        ("py_trees.trees.BehaviourTree.tock", "py_trees has no trees.BehaviourTree.tock"),
    ],
)
def test_a_stale_name_is_found(span: str, wrong: str) -> None:
    assert problem(span, {"roomba_bt.runtime.loop"}) == wrong
