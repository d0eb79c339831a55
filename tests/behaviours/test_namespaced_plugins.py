"""Plugin behaviours named by their package: ``package:name`` picks one of two installed
plugins that declare the same name, a plugin's behaviour that takes a built-in's name or a
word of the language, and ``roomba-bt:name`` the built-in (docs/plugins.md, "Two plugins, one
name"). Two tiny plugin distributions are installed for real (a ``.dist-info`` with its
``entry_points.txt`` and a module, on ``sys.path``), so the registry finds them as it finds
any installed plugin."""

from __future__ import annotations

from pathlib import Path

import pytest
from runtime.installed import (  # tests/runtime: plugins installed
    conditions_module,
    installed_registry,
)

from roomba_bt.behaviours import Registry
from roomba_bt.cli.mission_cmds import describe_behaviours
from roomba_bt.mission import compile_mission
from roomba_bt.mission.schema import mission_schema

#: two plugins that both declare ``sense``; Alpha's ``drive`` takes a built-in's name and
#: Beta's ``retry`` a word of the mission language
ALPHA = conditions_module(
    ("sense", "AlphaSense", "Alpha's sense: always true.", True),
    ("drive", "AlphaDrive", "Alpha's condition that takes a built-in's name.", True),
)
BETA = conditions_module(
    ("sense", "BetaSense", "Beta's sense: never true.", False),
    ("retry", "BetaRetry", "Beta's condition that takes a word of the mission language.", True),
)


@pytest.fixture
def registry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Registry:
    return installed_registry(
        tmp_path,
        monkeypatch,
        ("bt-ns-alpha", "bt_ns_alpha_plugin", ALPHA),
        ("bt-ns-beta", "bt_ns_beta_plugin", BETA),
    )


def _compile(tmp_path: Path, registry: Registry, tree: str) -> tuple[object, list]:
    path = tmp_path / "m.yaml"
    path.write_text(f"tree:\n  sequence:\n{tree}")
    mission, diagnostics = compile_mission(path, {}, registry=registry)
    return mission, list(diagnostics)


def _leaf_classes(mission: object) -> list[str]:
    root = mission.root  # type: ignore[attr-defined]
    return [type(node).__name__ for node in root.iterate() if not node.children]


def test_a_name_two_plugins_declare_names_both_packages_and_how_to_choose(
    tmp_path: Path, registry: Registry
) -> None:
    """Before, the error said to uninstall one or rename its behaviour: a mission had no way
    to say which of the two it meant."""
    mission, [error] = _compile(tmp_path, registry, "    - sense\n")
    assert mission is None and (error.line, error.column) == (3, 7)
    assert "'sense' is declared by two plugins" in error.message
    assert "from bt-ns-alpha" in error.message and "from bt-ns-beta" in error.message
    assert "write 'bt-ns-alpha:sense' or 'bt-ns-beta:sense'" in error.message


def test_a_name_a_plugin_file_declares_too_says_which_can_be_chosen(
    tmp_path: Path, registry: Registry
) -> None:
    """A mission's plugin file that declares ``sense`` too: the error said "uninstall one,
    or rename its behaviour", though each installed one is reached by its package:name and
    uninstalling one of three helped nothing; only the file's cannot be chosen."""
    from roomba_bt.mission import Permissions

    (tmp_path / "mine.py").write_text(
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        '@declare("sense", kind="condition")\nclass MySense(Condition):\n'
        '    """Mine."""\n\n    def check(self, snapshot):\n        return True\n'
    )
    path = tmp_path / "m.yaml"
    path.write_text("plugins: [./mine.py]\ntree:\n  sequence:\n    - sense\n")
    mission, diagnostics = compile_mission(
        path, {}, registry=registry, permissions=Permissions(plugin_files=True)
    )
    said = [d.message for d in diagnostics if d.line == 4]
    assert mission is None and len(said) == 1, diagnostics
    assert "'sense' is declared by three plugins" in said[0]
    assert said[0].endswith(
        "(write 'bt-ns-alpha:sense' or 'bt-ns-beta:sense' to choose an installed one; rename "
        f"the behaviour of MySense ({tmp_path / 'mine.py'}) (a plugin file has no "
        "package:name))"
    ), said[0]


def test_package_colon_name_picks_one_plugin(tmp_path: Path, registry: Registry) -> None:
    mission, diagnostics = _compile(
        tmp_path, registry, "    - bt-ns-alpha:sense\n    - bt-ns-beta:sense\n"
    )
    assert diagnostics == [] and mission is not None
    assert _leaf_classes(mission) == ["AlphaSense", "BetaSense"]
    assert not [w for w in mission.warnings if "sense" in w.message]  # type: ignore[attr-defined]
    # the package's name as pip takes it: case, '_' and '.' for '-'
    mission, diagnostics = _compile(tmp_path, registry, "    - BT_NS.Alpha:sense\n")
    assert diagnostics == [] and _leaf_classes(mission) == ["AlphaSense"]


def test_a_built_in_s_name_is_the_built_in_and_the_plugin_s_is_reachable(
    tmp_path: Path, registry: Registry
) -> None:
    """Before, a plugin's behaviour that took a built-in's name could not be used at all,
    and every use of the built-in was warned of with no way to say it was meant."""
    drive = "    - mode: safe\n    - {kind}: {{velocity: 100 mm/s, duration: 1s}}\n"
    mission, diagnostics = _compile(tmp_path, registry, drive.format(kind="drive"))
    assert diagnostics == [] and "Drive" in _leaf_classes(mission)
    [warning] = [w for w in mission.warnings if "too" in w.message]  # type: ignore[attr-defined]
    assert "the built-in is used" in warning.message
    assert "'roomba-bt:drive'" in warning.message and "'bt-ns-alpha:drive'" in warning.message
    mission, diagnostics = _compile(tmp_path, registry, drive.format(kind="roomba-bt:drive"))
    assert diagnostics == [] and "Drive" in _leaf_classes(mission)
    assert not [w for w in mission.warnings if "too" in w.message]  # type: ignore[attr-defined]
    mission, diagnostics = _compile(tmp_path, registry, "    - bt-ns-alpha:drive\n")
    assert diagnostics == [] and _leaf_classes(mission) == ["AlphaDrive"]


def test_a_word_of_the_language_stays_the_language_s(tmp_path: Path, registry: Registry) -> None:
    mission, diagnostics = _compile(tmp_path, registry, "    - bt-ns-beta:retry\n")
    assert diagnostics == [] and _leaf_classes(mission) == ["BetaRetry"]
    mission, diagnostics = _compile(tmp_path, registry, "    - retry: {times: 2, do: {wait: 1s}}\n")
    assert diagnostics == [] and _leaf_classes(mission) == ["Wait"]


def test_what_each_plugin_is_told_names_the_other_and_the_spellings(registry: Registry) -> None:
    errors = [str(e) for e in registry.errors]
    [sense] = [e for e in errors if "'sense'" in e]
    assert "bt-ns-alpha" in sense and "bt-ns-beta" in sense
    assert "'bt-ns-alpha:sense' or 'bt-ns-beta:sense'" in sense
    [drive] = [e for e in errors if "'drive'" in e]
    assert "the name of the built-in Drive" in drive and "'bt-ns-alpha:drive'" in drive
    [retry] = [e for e in errors if "'retry'" in e]
    assert "a word of the mission language" in retry and "'bt-ns-beta:retry'" in retry
    assert "wrongly" not in retry
    # what was found, why it is refused, what to do (it read "the word is the language's,
    # and a mission reaches it as ... (or rename it)")
    assert retry.endswith(
        "declares the name 'retry', which is a word of the mission language: 'retry' in a "
        "mission always means the language's own, so this behaviour is reached only as "
        "'bt-ns-beta:retry'; rename it in its @declare"
    )


@pytest.mark.parametrize(
    ("word", "said"),
    [
        ("bt-ns-gamma:sense", "no installed plugin package is called 'bt-ns-gamma'"),
        ("bt-ns-alpha:sens", "package 'bt-ns-alpha' has no behaviour 'sens' (did you mean"),
        ("roomba-bt:sense", "roomba-bt has no built-in behaviour 'sense'"),
    ],
)
def test_an_unknown_qualified_name_says_what_the_package_has(
    tmp_path: Path, registry: Registry, word: str, said: str
) -> None:
    _, [error] = _compile(tmp_path, registry, f"    - {word}\n")
    assert error.message.startswith(f"unknown node {word!r}") and said in error.message


def test_behaviours_and_the_schema_know_the_qualified_spellings(registry: Registry) -> None:
    [entry] = describe_behaviours(["bt-ns-beta:sense"], registry)
    assert entry["name"] == "bt-ns-beta:sense" and "Beta's sense" in entry["doc"]
    [drive] = describe_behaviours(["drive"], registry)
    assert drive["clash"]["severity"] == "warning" and "'roomba-bt:drive'" in drive["clash"]["why"]
    defs = mission_schema(registry)["$defs"]
    assert {"bt-ns-alpha:sense", "bt-ns-beta:sense", "bt-ns-beta:retry"} <= set(defs)
    assert "roomba-bt:drive" in defs and "sense" not in defs


#: a plugin half loaded: ``fine`` registers, ``wrong``'s default is out of its range
HALF = (
    "from roomba_bt.behaviours import INT, Condition, Param, declare\n\n\n"
    '@declare("fine", kind="condition")\nclass Fine(Condition):\n'
    '    """Fine."""\n\n    def check(self, snapshot):\n        return True\n\n\n'
    '@declare("wrong", kind="condition", params=(Param("n", INT, default=9, maximum=3),))\n'
    'class Wrong(Condition):\n    """Wrong."""\n\n    def check(self, snapshot):\n'
    "        return True\n"
)


@pytest.fixture
def broken(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Registry:
    """Three installed packages a plugin's author breaks: one that raises on import, one
    with a class refused for its declaration, one installed with no entry point at all."""
    registry = installed_registry(
        tmp_path,
        monkeypatch,
        ("bt-ns-raises", "bt_ns_raises_plugin", 'raise RuntimeError("no calibration file")\n'),
        ("bt-ns-half", "bt_ns_half_plugin", HALF),
    )
    info = tmp_path / "site" / "bt_ns_bare-1.0.dist-info"  # pip's, with no entry_points.txt
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: bt-ns-bare\nVersion: 1.0\n")
    return registry


@pytest.mark.parametrize(
    ("word", "said"),
    [
        (
            "bt-ns-raises:sense",
            "package 'bt-ns-raises' did not load (none of its behaviours): plugin "
            "'bt_ns_raises_plugin' "
            "(bt_ns_raises_plugin, from bt-ns-raises): failed to import: RuntimeError: no "
            "calibration file",
        ),
        (
            "bt-ns-half:wrong",
            "package 'bt-ns-half' did not load 'wrong': plugin 'bt_ns_half_plugin' "
            "(bt_ns_half_plugin, from bt-ns-half): Wrong (",
        ),
        (
            "bt-ns-bare:sense",
            "package 'bt-ns-bare' is installed but has no entry point in the group "
            "roomba_bt.behaviours, so none of its behaviours is found: add [project.entry-"
            'points."roomba_bt.behaviours"] to its pyproject.toml',
        ),
    ],
)
def test_a_qualified_name_of_an_installed_broken_plugin_says_why_it_names_nothing(
    tmp_path: Path, broken: Registry, word: str, said: str
) -> None:
    """A plugin's author who breaks the package met `no installed plugin package is called
    'bt-ns-raises' (installed: none ...)` for a package installed whose import raised, or
    that had no entry point, and `package 'bt-ns-half' has no behaviour 'wrong' (it has:
    fine)` for a class refused: the package is installed, and the error is its own."""
    _, [error] = _compile(tmp_path, broken, f"    - {word}\n")
    assert error.message.startswith(f"unknown node {word!r}: {said}"), error.message
    assert "no installed plugin package" not in error.message


def test_a_qualified_name_a_half_loaded_plugin_has_still_compiles(
    tmp_path: Path, broken: Registry
) -> None:
    mission, errors = _compile(tmp_path, broken, "    - bt-ns-half:fine\n")
    assert mission is not None and not [e for e in errors if e.severity == "error"]
