"""One registry for built-ins and plugins; broken plugins are named, the rest still load."""

from __future__ import annotations

import importlib
import pkgutil
from importlib.metadata import EntryPoint
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from py_trees.common import Status

import roomba_bt.behaviours
from roomba_bt.behaviours import (
    INT,
    MARK,
    SPEED,
    Condition,
    Declaration,
    DeclarationError,
    Param,
    Registry,
    builtin_registry,
    declare,
    default_registry,
)
from roomba_bt.behaviours.actions import ACTIONS
from roomba_bt.behaviours.conditions import CONDITIONS
from roomba_bt.mission import compile_mission
from roomba_bt.robot.interface import Snapshot


@declare("always", kind="condition", params=(Param("n", INT, default=1),))
class Always(Condition):
    """Always true."""

    def check(self, snapshot: Snapshot) -> bool:
        return True


class Undeclared(Condition):
    def check(self, snapshot: Snapshot) -> bool:
        return True


def test_every_builtin_is_registered_with_a_valid_declaration() -> None:
    registry = builtin_registry()
    assert {cls.declaration.name for cls in (*ACTIONS, *CONDITIONS)} <= set(registry.names())
    for decl in registry:
        decl.validate()
        assert decl.doc, f"{decl.name} has no docstring"
        assert decl.origin == "builtin"


def _declared_in(package: ModuleType) -> list[type]:
    """Every class a module of ``package`` (and its subpackages) declares with ``@declare``."""
    found = []
    for info in pkgutil.walk_packages(package.__path__, f"{package.__name__}."):
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            declared = isinstance(value, type) and value.__module__ == module.__name__
            decl = vars(value).get("declaration") if declared else None
            if isinstance(decl, Declaration) and decl.cls is value:
                found.append(value)
    return found


def test_every_declared_builtin_behaviour_is_in_the_builtin_registry() -> None:
    """``@declare`` alone registers nothing: a built-in joins through its module's tuple
    (``ACTIONS``, ``CONDITIONS``, ...) read by ``builtin_registry``. Found by walking the
    modules, not from those tuples, so a class left out of them fails here."""
    registry = builtin_registry()
    declared = _declared_in(roomba_bt.behaviours)
    assert len(declared) > 40  # the walk found the modules
    missing = [
        f"{cls.__module__}.{cls.__qualname__}"
        for cls in declared
        if (entry := registry.get(cls.declaration.name)) is None or entry.cls is not cls
    ]
    assert not missing, (
        f"declared but not registered: {missing}; add each to its module's tuple (ACTIONS, "
        "CONDITIONS, ...) that behaviours.registry.builtin_registry reads"
    )


def test_default_registry_holds_builtins_and_the_installed_example_plugin() -> None:
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        distribution("roomba-bt-dirt")
    except PackageNotFoundError:
        pytest.skip("pip install -e plugins/roomba-bt-dirt")
    registry = default_registry()
    assert "drive" in registry
    assert registry.get("wall_follow").origin == "builtin"  # type: ignore[union-attr]
    assert "dirt_detect" in registry  # plugins/roomba-bt-dirt, installed in the venv
    assert "roomba_bt_dirt" in registry.get("dirt_detect").origin  # type: ignore[union-attr]


def test_a_plugin_that_fails_to_import_is_named_and_others_still_load() -> None:
    registry = Registry(entry_point_group=None)
    registry.load_entry_point(
        EntryPoint("broken", "no_such_module_xyz:Thing", "roomba_bt.behaviours")
    )
    registry.load_entry_point(EntryPoint("always", f"{__name__}:Always", "roomba_bt.behaviours"))
    assert registry.names() == ["always"]
    [error] = registry.errors
    assert "'broken' (no_such_module_xyz:Thing)" in str(error)
    assert "but there is no module 'no_such_module_xyz' (written in" in str(error)


def test_a_plugin_that_declares_itself_wrongly_is_named() -> None:
    registry = Registry(entry_point_group=None)
    registry.load_entry_point(EntryPoint("bad", f"{__name__}:Undeclared", "roomba_bt.behaviours"))
    [error] = registry.errors
    assert "plugin 'bad'" in str(error)
    assert "declares itself wrongly" in str(error)
    assert "decorate it with @declare" in str(error)


@pytest.mark.parametrize(
    ("name", "declared", "message"),
    [
        ("drive", {}, "already taken"),
        ("sequence", {}, "word of the mission language"),
        ("BadName", {}, "snake_case"),
        ("reads_junk", {"reads": (999,)}, r"unknown sensor packets \[999\]"),
        ("reads_name", {"reads": ("wall",)}, r"by name: reads=packet_ids\('wall_signal'"),
        ("sends_name", {"sends": ("drive",)}, r"by name: sends=opcodes\('drive'"),
        ("bad_default", {"params": (Param("n", INT, default="x"),)}, "default of 'n'"),
        # found by a plugin author: each was accepted, and the first broke `behaviours` and
        # `schema` for every plugin with a traceback
        (
            "text_bound",
            {"params": (Param("v", SPEED, default="0.2 m/s", minimum="0 mm/s"),)},
            r"parameter 'v': minimum must be a plain number in mm/s, got '0 mm/s'",
        ),
        (
            "out_of_range",
            {"params": (Param("v", SPEED, default="900 mm/s", maximum=500),)},
            r"default of 'v': v 900 mm/s is out of range: allowed 500 mm/s or less",
        ),
        (
            "upside_down",
            {"params": (Param("n", INT, minimum=10, maximum=5),)},
            "minimum 10 is above maximum 5",
        ),
        (
            "required_default",
            {"params": (Param("n", INT, default=3, required=True),)},
            "required and given a default",
        ),
        ("odd_param", {"params": (Param("Level-X", INT),)}, "parameter name 'Level-X'"),
        ("python_type", {"params": (Param("n", int),)}, r"type must be a ValueType .*SPEED"),  # type: ignore[arg-type]
        # a stranger's typos: the mistake said with what to write, not the list alone
        (
            "python_int",
            {"params": (Param("n", int),)},  # type: ignore[arg-type]
            r"got <class 'int'>: Python's int is not one; write INT \(from roomba_bt\.beh",
        ),
        (
            "text_type",
            {"params": (Param("v", "speed"),)},  # type: ignore[arg-type]
            r"got 'speed': the text 'speed' is not one; write SPEED \(from roomba_bt\.behav",
        ),
        (
            "tuple_type",
            {"params": (Param("side", ("left", "right")),)},  # type: ignore[arg-type]
            r"a choice of words is enum\('left', 'right'\) \(from roomba_bt\.behaviours imp",
        ),
        ("sends_drive", {"sends": (137,)}, "a condition only reads"),
        # accepted, and no mission could give it: a mark has no written form
        (
            "mark_param",
            {"params": (Param("since", MARK),)},
            r"parameter 'since': type MARK has no written form, so no mission can give it a "
            r"value \(the `mark` action writes one to a key\): a parameter that names a mark "
            r"key is Param\('since', STR, from_blackboard=False\), the key typed with "
            r"reads_keys=\{'since': MARK\} \(odometry's since\) or writes_keys=\{'since': "
            r"MARK\}$",
        ),
    ],
)
def test_declaration_errors(name: str, declared: dict[str, Any], message: str) -> None:
    registry = builtin_registry()

    @declare(name, kind="condition", **declared)
    class Declared(Condition):
        def check(self, snapshot: Snapshot) -> bool:
            return True

    with pytest.raises(DeclarationError, match=message):
        registry.register(Declared)


def test_a_plugin_file_loads_into_a_copy(tmp_path: Path) -> None:
    plugin = tmp_path / "mine.py"
    plugin.write_text(
        "from roomba_bt.behaviours import Condition, declare\n"
        "@declare('mine', kind='condition')\n"
        "class Mine(Condition):\n"
        "    '''Mine.'''\n"
        "    def check(self, snapshot):\n"
        "        return True\n"
    )
    base = builtin_registry()
    copy, errors = base.with_file(plugin)
    assert errors == []
    assert "mine" in copy
    assert "mine" not in base
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('boom')\n")
    _, [error] = base.with_file(broken)
    assert "failed to import: RuntimeError: boom" in str(error)
    # sys.exit() at import is a failed import too: its code would pass for one of the CLI's
    leaving = tmp_path / "leaving.py"
    leaving.write_text("import sys\nsys.exit(3)\n")
    _, [error] = base.with_file(leaving)
    assert "failed to import: it called sys.exit(3)" in str(error)


def test_a_declared_class_that_is_no_behaviour_is_named(tmp_path: Path) -> None:
    """A plugin author's first mistake: @declare on a plain class. Said as such, not as "it
    provides no behaviour class (decorated with @declare)", which it seems to."""
    plugin = tmp_path / "plain.py"
    plugin.write_text(
        "from roomba_bt.behaviours import declare\n"
        "@declare('near', kind='condition')\n"
        "class Near:\n"
        "    pass\n"
    )
    _, [error] = builtin_registry().with_file(plugin)
    assert (
        "class Near is decorated with @declare but is not a behaviour: derive it from "
        "roomba_bt.behaviours.Action or Condition"
    ) in str(error)


def test_a_changed_plugin_file_is_imported_again_an_unchanged_one_is_not(tmp_path: Path) -> None:
    """run --watch reloads a mission whose plugin file changed: it must get the new code."""
    plugin = tmp_path / "changing.py"
    source = (
        "from roomba_bt.behaviours import Condition, declare\n"
        "@declare('changing', kind='condition')\n"
        "class Changing(Condition):\n"
        "    '''{doc}'''\n"
        "    def check(self, snapshot):\n"
        "        return True\n"
    )
    plugin.write_text(source.format(doc="First."))
    base = builtin_registry()
    first = base.with_file(plugin)[0].get("changing")
    again = base.with_file(plugin)[0].get("changing")
    assert first is not None and again is not None
    assert again.cls is first.cls  # unchanged: the module is imported once
    plugin.write_text(source.format(doc="Second, a longer text."))
    changed = base.with_file(plugin)[0].get("changing")
    assert changed is not None and changed.cls is not first.cls
    assert changed.cls.__doc__ == "Second, a longer text."
    plugin.write_text("def broken(:\n")
    _, [error] = base.with_file(plugin)
    assert "failed to import: SyntaxError" in str(error)


def test_a_registered_plugin_behaviour_ticks() -> None:
    from roomba_bt.robot.testing import StubRobot

    node = Always("always", {})
    node.setup(robot=StubRobot())
    node.tick_once()
    assert node.status is Status.SUCCESS
    assert node.value("n") == 1


def _distribution(folder: Path, name: str, entry_points_txt: str) -> None:
    info = folder / f"{name.replace('-', '_')}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(entry_points_txt)


def test_the_plugin_scan_finds_what_importlib_metadata_entry_points_finds(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Only distributions whose entry points name the group are parsed; the first of a name
    on the path still hides a later copy, with or without plugins."""
    from importlib.metadata import entry_points

    from roomba_bt.behaviours.registry import ENTRY_POINT_GROUP, group_entry_points

    _distribution(tmp_path / "c", "other-dist", (
        "[console_scripts]\nother = m:main\n# [roomba_bt.behaviours] in a comment\n"
        "[ roomba_bt.behaviours ]\nspaced = m:Spaced\n"
        "[roomba_bt.behaviours]\nmine = m:Mine\ntheirs = m:Theirs\n[pytest11]\np = m\n"
    ))  # fmt: skip
    _distribution(tmp_path / "b", "shadow-dist", "[roomba_bt.behaviours]\nshadowed = m:C\n")
    _distribution(tmp_path / "a", "shadow-dist", "[console_scripts]\nshadow = m:main\n")
    for folder in ("c", "b", "a"):  # a first on the path
        monkeypatch.syspath_prepend(str(tmp_path / folder))
    mine = group_entry_points(ENTRY_POINT_GROUP)
    assert [ep.name for ep in mine if ep.dist and ep.dist.name == "other-dist"] == [
        "mine",
        "theirs",
    ]
    assert "shadowed" not in [ep.name for ep in mine]
    for group in (ENTRY_POINT_GROUP, "console_scripts", "pytest11", " roomba_bt.behaviours "):
        ours, theirs = group_entry_points(group), list(entry_points(group=group))
        assert ours == theirs
        assert [ep.dist.name for ep in ours if ep.dist] == [
            ep.dist.name for ep in theirs if ep.dist
        ]


@declare("always", kind="condition")
class AlwaysToo(Condition):
    """Another plugin's ``always``: the same name, another class."""

    def check(self, snapshot: Snapshot) -> bool:
        return False


@declare("drive", kind="condition")
class DriveToo(Condition):
    """A plugin's behaviour that takes a built-in's name."""

    def check(self, snapshot: Snapshot) -> bool:
        return True


def _plugin(registry: Registry, name: str, target: str) -> None:
    registry.load_entry_point(EntryPoint(name, f"{__name__}:{target}", "roomba_bt.behaviours"))


def test_a_name_two_plugins_declare_is_an_error_where_a_mission_uses_it(tmp_path: Path) -> None:
    """The one whose entry point sorted first was used, silently: validate said ok and the
    run ran the other package's behaviour."""
    registry = builtin_registry()
    _plugin(registry, "first", "Always")
    _plugin(registry, "second", "AlwaysToo")
    path = tmp_path / "m.yaml"
    path.write_text("tree:\n  sequence:\n    - wait: 1s\n    - always\n")
    mission, diagnostics = compile_mission(path, {}, registry=registry)
    assert mission is None
    [error] = diagnostics
    assert (error.line, error.column) == (4, 7)
    assert "'always' is declared by two plugins" in error.message
    assert "Always ('first'" in error.message and "AlwaysToo ('second'" in error.message


def test_a_name_two_plugins_declare_is_said_as_a_clash_not_a_wrong_declaration() -> None:
    """The plugin whose entry point sorted second was told it "declares itself wrongly":
    it declared nothing wrongly."""
    registry = builtin_registry()
    _plugin(registry, "first", "Always")
    _plugin(registry, "second", "AlwaysToo")
    _plugin(registry, "mine", "DriveToo")
    [second, mine] = [str(e) for e in registry.errors]
    assert "wrongly" not in second and "wrongly" not in mine
    here = Path(__file__)
    assert second.startswith(f"plugin 'second' ({__name__}:AlwaysToo): AlwaysToo ({here}:")
    assert (
        f"declares 'always', as Always ({here}:" in second
        and f"of plugin 'first' ({__name__}:Always) does: a name clash between two "
        "plugins; a mission that uses 'always' is refused (exit 2)"
        in second
    )
    assert "declares 'drive', the name of the built-in Drive (" in mine
    # an entry point made in Python has no distribution: its own name is the package
    assert "the built-in is used and a mission reaches this one as 'mine:drive'" in mine


def test_a_plugin_that_takes_a_builtins_name_is_a_warning_where_it_is_used(
    tmp_path: Path,
) -> None:
    registry = builtin_registry()
    _plugin(registry, "shadow", "DriveToo")
    path = tmp_path / "m.yaml"
    path.write_text("tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 100 mm/s}\n")
    mission, diagnostics = compile_mission(path, {}, registry=registry)
    assert mission is not None and diagnostics == []
    [warning] = [w for w in mission.warnings if "too" in w.message]
    assert warning.severity == "warning" and (warning.line, warning.column) == (4, 7)
    assert "a plugin declares 'drive' too" in warning.message
    assert "the built-in is used" in warning.message


def test_an_unknown_node_notes_only_the_plugins_that_may_have_meant_it(tmp_path: Path) -> None:
    """The note beside an unknown node listed every broken plugin on the machine (a line of
    more than 1,000 characters): it lists those whose error names the word, else those that
    did not import at all, three at the most."""
    registry = builtin_registry()
    _plugin(registry, "wrong", "Undeclared")  # imported, declared wrongly: no name of ours
    for n in range(5):
        registry.load_entry_point(
            EntryPoint(f"gone{n}", f"no_such_module_{n}:Thing", "roomba_bt.behaviours")
        )
    path = tmp_path / "m.yaml"
    path.write_text("tree:\n  sequence:\n    - wiggle\n")
    _, [error] = compile_mission(path, {}, registry=registry)
    assert "plugin 'wrong'" not in error.message
    assert error.message.count("but there is no module") == 3  # each did not import
    assert "and 2 more (roomba-bt behaviours lists them)" in error.message
    path.write_text("tree:\n  sequence:\n    - undeclared_thing\n")
    registry = builtin_registry()
    _plugin(registry, "undeclared_thing", "Undeclared")
    registry.load_entry_point(EntryPoint("gone", "no_such_module:Thing", "roomba_bt.behaviours"))
    _, [error] = compile_mission(path, {}, registry=registry)
    assert "plugin 'undeclared_thing'" in error.message and "failed to import" not in error.message


def test_behaviours_lists_a_name_two_plugins_declare_with_the_clash() -> None:
    """`roomba-bt behaviours wiggle` showed the first plugin's and exit 0, with no sign that
    a second declares it too (a mission that uses it is refused)."""
    from roomba_bt.cli.mission_cmds import describe_behaviours

    registry = builtin_registry()
    _plugin(registry, "first", "Always")
    _plugin(registry, "second", "AlwaysToo")
    _plugin(registry, "shadow", "DriveToo")
    [always] = describe_behaviours(["always"], registry)
    assert always["clash"]["severity"] == "error"
    assert "'always' is declared by two plugins" in always["clash"]["why"]
    [drive] = describe_behaviours(["drive"], registry)
    assert (
        drive["clash"]["severity"] == "warning" and "the built-in is used" in drive["clash"]["why"]
    )
    [plain] = describe_behaviours(["wait"], registry)
    assert plain["clash"] is None
