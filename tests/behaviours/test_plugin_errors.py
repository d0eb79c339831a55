"""What a broken plugin is told: each class on its own, where an import raised, and a name
two plugins declare said as a clash (session 24's field test of plugin packages)."""

from __future__ import annotations

import logging
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest

from roomba_bt.behaviours import Registry, builtin_registry

GROUP = "roomba_bt.behaviours"

MIXED = """\
from roomba_bt.behaviours import Condition, Param, declare


@declare("not_leaf", kind="action")
class NotLeaf:
    '''not a behaviour'''


@declare("bad_one", kind="condition", params=(Param("level", int, default=3),))
class BadOne(Condition):
    def check(self, snapshot):
        return True


@declare("ok_one", kind="condition")
class OkOne(Condition):
    def check(self, snapshot):
        return True
"""


def _package(root: Path, name: str, files: dict[str, str]) -> Path:
    """A package ``name`` under ``root`` (put on sys.path by the caller) with ``files``."""
    folder = root / name
    folder.mkdir(parents=True)
    (folder / "__init__.py").write_text("")
    for file, text in files.items():
        (folder / file).write_text(text)
    return folder


def _assert_mixed(registry: Registry, errors: list[str], where: Path) -> None:
    assert "ok_one" in registry.names() and "not_leaf" not in registry.names()
    [bad, plain] = errors
    assert f"BadOne ({where}:9) declares itself wrongly: parameter 'level'" in bad
    assert f"NotLeaf ({where}:4): class NotLeaf is decorated with @declare but is not" in plain


def test_a_declared_plain_class_leaves_its_entry_point_module_s_others(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One @declare'd plain class dropped its whole module: the module's good ok_one was
    missing and its other declaration errors were not said."""
    folder = _package(tmp_path, "s24_mixed_ep", {"baddecl.py": MIXED})
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = builtin_registry()
    registry.load_entry_point(EntryPoint("bad", "s24_mixed_ep.baddecl", GROUP))
    _assert_mixed(registry, [str(e) for e in registry.errors], folder / "baddecl.py")


def test_a_declared_plain_class_leaves_its_plugin_file_s_others(tmp_path: Path) -> None:
    """A plugin file: every error of it is handed back, not the first alone."""
    path = tmp_path / "mixed.py"
    path.write_text(MIXED)
    registry, errors = builtin_registry().with_file(path)
    _assert_mixed(registry, [str(e) for e in errors], path)


def test_one_class_that_declares_itself_wrongly_leaves_its_module_s_others(
    tmp_path: Path,
) -> None:
    """The good class was dropped with the bad one, and the error said neither which class
    nor where."""
    path = tmp_path / "mixed.py"
    path.write_text(MIXED)
    registry, [bad, _plain] = Registry(entry_point_group=None).with_file(path)
    assert [d.name for d in registry] == ["ok_one"]
    assert f"BadOne ({path}:9) declares itself wrongly" in str(bad)  # its @declare
    assert "parameter 'level': type must be a ValueType" in str(bad)


def test_a_plugin_file_that_fails_to_import_says_where(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``failed to import: KeyError: 'X'`` named no line of the plugin, even with -v."""
    path = tmp_path / "nameerr.py"
    path.write_text("import os\n\nos.environ['ROOMBA_BT_S24_NOPE']\n")
    with caplog.at_level(logging.DEBUG, logger="roomba_bt.plugins"):
        _, [error] = builtin_registry().with_file(path)
    assert str(error) == (
        f"plugin {path}: failed to import: KeyError: 'ROOMBA_BT_S24_NOPE' (at {path}:3)"
    )
    [record] = caplog.records
    assert "Traceback (most recent call last)" in record.getMessage()
    assert f'File "{path}", line 3' in record.getMessage()


def test_an_entry_point_that_fails_to_import_says_where_in_its_package(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The innermost frame in the plugin's own package, not the os module's where the
    KeyError was raised, nor the import machinery's."""
    folder = _package(
        tmp_path,
        "s24_raising_ep",
        {"helpers.py": "import os\n\n\ndef setting():\n    return os.environ['S24_NOPE']\n",
         "behaviours.py": "from s24_raising_ep.helpers import setting\n\nSET = setting()\n"},
    )  # fmt: skip
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry(entry_point_group=None)
    registry.load_entry_point(EntryPoint("raising", "s24_raising_ep.behaviours", GROUP))
    registry.load_entry_point(EntryPoint("gone", "s24_no_such_package_xyz", GROUP))
    [raising, gone] = [str(e) for e in registry.errors]
    assert raising.endswith(
        f"failed to import: KeyError: 'S24_NOPE' (at {folder / 'helpers.py'}:5)"
    )
    # nothing of its own ran: no line to name, but the entry point that names it
    assert gone.endswith(
        "the entry point names s24_no_such_package_xyz, but there is no module "
        "'s24_no_such_package_xyz' (written in its distribution's metadata: "
        '[project.entry-points."roomba_bt.behaviours"] gone = "s24_no_such_package_xyz")'
    )


#: the stranger's bt-bad-units, in part: a maximum written in metres (2, taken as 2 mm) with a
#: default of 1 m, refused; a name that contains it; and a good one
UNITS = """\
from py_trees.common import Status

from roomba_bt.behaviours import DISTANCE, SPEED, Action, Param, declare
from roomba_bt.oi.opcodes import opcodes


@declare("u_metres", kind="action",
         params=(Param("reach", DISTANCE, default="1 m", minimum=0, maximum=2),),
         sends=opcodes("drive"))
class UMetres(Action):
    '''max in metres by mistake: 2 (mm) with a default of 1 m.'''
    def update(self):
        return Status.SUCCESS


@declare("u_metres_nodefault", kind="action",
         params=(Param("reach", DISTANCE, minimum=0.1, maximum=2, required=True),),
         sends=opcodes("drive"))
class UMetresNoDefault(Action):
    '''declares itself rightly, if oddly.'''
    def update(self):
        return Status.SUCCESS


@declare("u_min_str", kind="action",
         params=(Param("velocity", SPEED, default="100 mm/s", minimum="0 mm/s"),),
         sends=opcodes("drive"))
class UMinStr(Action):
    '''minimum as text: refused too, but it is not what the mission uses.'''
    def update(self):
        return Status.SUCCESS
"""


def test_an_unknown_node_a_refused_class_declares_notes_why_it_was_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``unknown node 'u_metres' (did you mean 'u_metres_nodefault'?)``, nothing more (with
    -v too): the mission's author was told of a misspelling when the plugin was at fault,
    which docs/plugins.md §5 promised to say."""
    from roomba_bt.mission import compile_mission

    folder = _package(tmp_path, "s27_bad_units", {"units.py": UNITS})
    _package(tmp_path, "s27_other_bad", {"other.py": UNITS.replace("u_", "o_")})
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = builtin_registry()
    registry.load_entry_point(EntryPoint("units", "s27_bad_units.units", GROUP))
    registry.load_entry_point(EntryPoint("other", "s27_other_bad.other", GROUP))
    path = tmp_path / "m.yaml"
    path.write_text("tree:\n  sequence:\n    - mode: safe\n    - u_metres: {reach: 50cm}\n")
    _, [error] = compile_mission(path, {}, registry=registry)
    assert (error.line, error.column) == (4, 7)
    assert error.message == (
        "unknown node 'u_metres' (note: plugin 'units' (s27_bad_units.units): UMetres "
        f"({folder / 'units.py'}:7) declares itself wrongly: default of 'reach': reach 1000 mm "
        "is out of range: allowed 0..2 mm)"
    )
    # a misspelling still gets its did-you-mean, and no plugin's error beside it
    path.write_text("tree:\n  sequence:\n    - mode: safe\n    - u_metres_nodefaul: {reach: 1}\n")
    _, [error] = compile_mission(path, {}, registry=registry)
    assert error.message == (
        "unknown node 'u_metres_nodefaul' (did you mean 'u_metres_nodefault'?)"
    )
    assert "o_metres" not in error.message


def test_a_refused_class_of_a_plugin_file_is_noted_too(tmp_path: Path) -> None:
    from roomba_bt.mission import Permissions, compile_mission

    (tmp_path / "units.py").write_text(UNITS)
    path = tmp_path / "m.yaml"
    path.write_text("plugins: [./units.py]\ntree:\n  sequence:\n    - mode: safe\n    - u_metres\n")
    _, diagnostics = compile_mission(
        path, {}, registry=builtin_registry(), permissions=Permissions(plugin_files=True)
    )
    [error] = [d for d in diagnostics if "unknown node" in d.message]
    assert (error.line, error.column) == (5, 7)
    assert f"UMetres ({tmp_path / 'units.py'}:7) declares itself wrongly" in error.message
    assert "u_min_str" not in error.message and "UMinStr" not in error.message


#: the stranger's bt-bad-kind: a kind that the class's base says otherwise
KINDS = """\
from py_trees.common import Status

from roomba_bt.behaviours import PERCENT, Action, Condition, Param, declare
from roomba_bt.oi.opcodes import opcodes


@declare("k_cond_is_action", kind="condition",
         params=(Param("below", PERCENT, default="20%", minimum=0, maximum=100),),
         reads=(25, 26))
class KCondIsAction(Action):
    '''kind condition, class Action.'''
    def update(self):
        return Status.SUCCESS


@declare("k_action_is_cond", kind="action", sends=opcodes("drive"))
class KActionIsCond(Condition):
    '''kind action, class Condition.'''
    def check(self, snapshot):
        return True


@declare("k_fine", kind="condition", reads=(7,))
class KFine(Condition):
    '''what it says it is.'''
    def check(self, snapshot):
        return True
"""


def test_a_kind_its_class_contradicts_is_refused_where_it_is_declared(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Both loaded; ``behaviours`` listed them under the declared kind, the validator
    believed it (a guard of an Action, a condition sending Drive) and the mission ran."""
    folder = _package(tmp_path, "s27_bad_kind", {"kinds.py": KINDS})
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = builtin_registry()
    registry.load_entry_point(EntryPoint("kind", "s27_bad_kind.kinds", GROUP))
    assert "k_fine" in registry.names()
    assert "k_cond_is_action" not in registry.names()
    assert "k_action_is_cond" not in registry.names()
    where = folder / "kinds.py"
    assert [e.cause for e in registry.errors] == [
        f"KActionIsCond ({where}:16) declares itself wrongly: kind='action', but KActionIsCond "
        "derives from Condition: an action derives from roomba_bt.behaviours.Action (its "
        "update() returns a Status); declare kind='condition' or derive it from Action",
        f"KCondIsAction ({where}:7) declares itself wrongly: kind='condition', but "
        "KCondIsAction derives from Action: a condition derives from "
        "roomba_bt.behaviours.Condition (its check() says whether it holds); declare "
        "kind='action' or derive it from Condition",
    ]


def test_an_entry_point_naming_a_module_that_is_not_there_says_where_it_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A misspelt module (``typo = "roomba_bt_brokn"``) said only ``failed to import:
    ModuleNotFoundError: No module named 'roomba_bt_brokn'``; a module the plugin's own code
    imports and lacks is still its import's failure, at its line."""
    _package(tmp_path, "s31_needs", {"conds.py": "import s31_not_installed_anywhere\n"})
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry(entry_point_group=None)
    for name, target in (("typo", "s31_brokn"), ("sub", "s31_needs.cnds"),
                         ("own", "s31_needs.conds")):  # fmt: skip
        registry.load_entry_point(EntryPoint(name, target, GROUP))
    [typo, sub, own] = [e.cause for e in registry.errors]
    assert typo == (
        "the entry point names s31_brokn, but there is no module 's31_brokn' (written in its "
        'distribution\'s metadata: [project.entry-points."roomba_bt.behaviours"] typo = '
        '"s31_brokn")'
    )
    assert sub.startswith("the entry point names s31_needs.cnds, but there is no module "
                          "'s31_needs.cnds' (written in its distribution's metadata: ")  # fmt: skip
    assert own.startswith(
        "failed to import: ModuleNotFoundError: No module named 's31_not_installed_anywhere' "
        f"(at {tmp_path / 's31_needs' / 'conds.py'}:1)"
    )


def test_an_entry_point_naming_an_attribute_its_module_lacks_says_where_it_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``AttributeError: module 'bad_attr' has no attribute 'NoSuchClass'``, with no word of
    the class that is there nor of where the entry point is written."""
    ok = (
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        '@declare("attr_cond", kind="condition", reads=(15,))\n'
        "class AttrCond(Condition):\n"
        "    def check(self, snapshot):\n"
        "        return True\n"
    )
    _package(tmp_path, "s27_bad_attr", {"conds.py": ok})
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry(entry_point_group=None)
    for name, target in (("attr", "NoSuchClass"), ("typo", "AttrCnd"), ("deep", "AttrCond.x")):
        registry.load_entry_point(EntryPoint(name, f"s27_bad_attr.conds:{target}", GROUP))
    [unlike, typo, deep] = [e.cause for e in registry.errors]
    assert unlike == (
        "the entry point names s27_bad_attr.conds:NoSuchClass, but module 's27_bad_attr.conds' "
        "has no attribute 'NoSuchClass'; its behaviour classes: AttrCond (written in its "
        'distribution\'s metadata: [project.entry-points."roomba_bt.behaviours"] attr = '
        '"s27_bad_attr.conds:NoSuchClass")'
    )
    assert "has no attribute 'AttrCnd' (did you mean 'AttrCond'?) (written in" in typo
    # the class is there, its attribute is not: the exception as it is
    assert deep.startswith("failed to import: AttributeError: type object 'AttrCond' has no")
