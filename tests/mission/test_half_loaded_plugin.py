"""An installed plugin of which one class declares itself wrongly (0.1.0's tuple
``writes_keys`` naming an undeclared parameter) and one loads: every command tells the same
story (docs/plugins.md, "A plugin that does not load"). The refused behaviour is named
exactly; the loaded one stays usable; ``validate``, ``run`` and ``replay`` warn once on
stderr, where 0.2.0 said nothing (a nightly ``validate`` hid the broken plugin), and
``behaviours`` no longer says "its behaviours are not listed" while listing the good one."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from runtime.installed import (  # tests/runtime: plugins installed
    install_distribution,
    installed_registry,
)

from roomba_bt.cli import main

Capsys = pytest.CaptureFixture[str]

#: the upgrader's second plugin package as 0.1.0 accepted it
HALF = '''from py_trees.common import Status
from roomba_bt.behaviours import STR, INT, Action, Param, declare, write_key

@declare("store_n", kind="action", params=(Param("n", INT, default=1), Param("dest", STR, default="count", from_blackboard=False)), writes_keys=("dest",))
class StoreN(Action):
    """Store n in a key."""
    def update(self):
        write_key(str(self.value("dest")), int(self.value("n")), self.name)
        return Status.SUCCESS

@declare("store_m", kind="action", params=(Param("n", INT, default=1),), writes_keys=("target",))
class StoreM(Action):
    """Store into a key param that is not declared."""
    def update(self):
        return Status.SUCCESS
'''  # noqa: E501  (as its author wrote it)
#: a mission that uses the loaded behaviour only
USES_STORE_N = (
    "mission: k\nblackboard:\n  count: int\ntree:\n  sequence:\n    - mode: safe\n"
    "    - store_n: {n: 3}\n    - stop\n    - mode: passive\n"
)
#: what each command says of the refused one, and that the other loaded
LOST = "'store_m' (refused alone: the plugin's other behaviours loaded)"


@pytest.fixture
def mission(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``bt-s33-keys`` installed (module ``s33_keys``) and a mission that uses ``store_n``."""
    import roomba_bt.behaviours.registry as registries

    registry = installed_registry(tmp_path, monkeypatch, ("bt-s33-keys", "s33_keys", HALF))
    monkeypatch.setattr(registries, "_DEFAULT", registry)  # the process's, wherever read
    path = tmp_path / "k.yaml"
    path.write_text(USES_STORE_N)
    return path


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if "s33_keys" in line]


def test_behaviours_names_exactly_what_is_not_listed(mission: Path, capsys: Capsys) -> None:
    assert main(["behaviours"]) == 2
    out, err = capsys.readouterr()
    assert "store_n  (action" in out and "store_m" not in out
    assert f"did not load (not listed: {LOST}): fix or uninstall it" in err
    assert "its behaviours are not listed" not in err


def test_schema_names_exactly_what_it_would_lack(mission: Path, capsys: Capsys) -> None:
    assert main(["schema"]) == 2
    assert f"(no schema printed: it would lack {LOST})" in capsys.readouterr().err


def test_validate_uses_the_loaded_behaviour_and_warns_once(mission: Path, capsys: Capsys) -> None:
    assert main(["validate", str(mission), str(mission.parent)]) == 0  # two files, one warning
    out, err = capsys.readouterr()
    [line] = _warnings(err)
    assert line.startswith("roomba-bt validate: warning: plugin 's33_keys' (s33_keys, from ")
    assert "StoreM (" in line and "declares itself wrongly: writes_keys names 'target'" in line
    assert line.endswith(f"; a mission cannot use {LOST}")
    assert f"{mission}: ok" in out
    assert main(["validate", "--strict", str(mission)]) == 0  # the mission is right


def test_run_uses_the_loaded_behaviour_and_warns(mission: Path, capsys: Capsys) -> None:
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    out, err = capsys.readouterr()
    assert "outcome      SUCCESS" in out
    [line] = _warnings(err)
    assert line.startswith("roomba-bt: warning: plugin 's33_keys'")
    assert line.endswith(f"; a mission cannot use {LOST}")


def test_a_nightly_validate_of_other_missions_says_it_too(
    mission: Path, tmp_path: Path, capsys: Capsys
) -> None:
    """A mission that does not use the plugin is ok, and the warning is still said: the
    broken plugin is not hidden until a mission uses its refused name."""
    plain = tmp_path / "plain.yaml"
    plain.write_text("tree:\n  sequence:\n    - mode: safe\n    - mode: passive\n")
    assert main(["validate", str(plain)]) == 0
    [line] = _warnings(capsys.readouterr().err)
    assert line.endswith(f"; a mission cannot use {LOST}")


def test_the_pages_quote_what_each_command_says_of_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """docs/plugins.md quotes ``behaviours``' last line and ``validate``'s warning of this
    plugin, installed as the page names it (``roomba-bt-keys``, its package
    ``roomba_bt_keys``, the entry point ``keys``), and docs/missions.md the warning's start."""
    import roomba_bt.behaviours.registry as registries

    registry = installed_registry(tmp_path, monkeypatch)
    install_distribution(tmp_path / "site", "roomba-bt-keys", "roomba_bt_keys", HALF,
                         entry="keys", package=True)  # fmt: skip
    monkeypatch.delitem(sys.modules, "roomba_bt_keys", raising=False)
    monkeypatch.setattr(registries, "_DEFAULT", registry)
    (tmp_path / "k.yaml").write_text(USES_STORE_N)
    assert main(["behaviours"]) == 2
    err = capsys.readouterr().err
    assert_quoted("docs/plugins.md", "roomba-bt behaviours: an installed plugin did not", err)
    assert main(["validate", str(tmp_path / "k.yaml")]) == 0
    err = capsys.readouterr().err
    assert_quoted("docs/plugins.md", "roomba-bt validate: warning: plugin 'keys'", err)
    assert_quoted("docs/missions.md", "roomba-bt validate: warning: plugin ...", err)
