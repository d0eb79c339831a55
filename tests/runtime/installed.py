"""Plugin distributions installed into a test's own site folder as pip leaves one: each
module and its ``.dist-info`` with the ``roomba_bt.behaviours`` entry point, so the
registry finds it as it finds any installed plugin (tests of plugins that clash, that do
not load, that raise on import); and the source of such a module, of conditions alone.
:func:`another_installation`: the shipped missions where another venv keeps them."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

from roomba_bt.behaviours import Registry, builtin_registry
from roomba_bt.behaviours.registry import ENTRY_POINT_GROUP
from roomba_bt.mission.shipped import SHIPPED_DIR


def install_distribution(
    site: Path,
    distribution: str,
    module: str,
    source: str,
    entry: str | None = None,
    package: bool = False,
) -> None:
    """``distribution`` (version 1.0) with the one module ``module`` holding ``source`` (with
    ``package``, a package: ``module/__init__.py``), its entry point named ``entry`` (else
    after the module): a plugin as docs/plugins.md's examples name it."""
    if package:
        (site / module).mkdir()
        (site / module / "__init__.py").write_text(source)
    else:
        (site / f"{module}.py").write_text(source)
    info = site / f"{distribution.replace('-', '_')}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {distribution}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        f"[roomba_bt.behaviours]\n{entry or module} = {module}\n"
    )


def conditions_module(*declared: tuple[str, str, str, bool]) -> str:
    """The source of a plugin module of conditions that always answer the same, each
    declared by its (name, class, docstring, answer): the plugin tests' distributions differ
    in these alone."""
    classes = "".join(
        f'\n\n@declare("{name}", kind="condition")\nclass {cls}(Condition):\n'
        f'    """{doc}"""\n\n    def check(self, snapshot):\n        return {answer}\n'
        for name, cls, doc, answer in declared
    )
    return f"from roomba_bt.behaviours import Condition, declare\n{classes}"


def installed_registry(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, *distributions: tuple[str, str, str]
) -> Registry:
    """Each of ``distributions`` (its name, its module, the module's source) installed into
    the site folder ``tmp_path/site``, first on ``sys.path`` for the test; each module
    forgotten, so that this test imports its own. The built-in registry that reads the
    entry points on first use, as a command's registry does, with these among them."""
    site = tmp_path / "site"
    site.mkdir()
    for distribution, module, source in distributions:
        install_distribution(site, distribution, module, source)
        monkeypatch.delitem(sys.modules, module, raising=False)
    monkeypatch.syspath_prepend(str(site))
    registry = builtin_registry()
    registry._group = ENTRY_POINT_GROUP  # the entry points, read on first use
    registry._loaded = False
    return registry


def another_installation(monkeypatch: pytest.MonkeyPatch, venv: Path) -> Path:
    """The shipped missions copied to ``venv``'s site-packages, and that copy made the shipped
    missions' folder, as another installation's is: in each module that holds it (the code
    of before bound it by name in more of them). What names a shipped mission by its path
    there differs from one venv to the next. The copy's folder is returned."""
    import roomba_bt.mission.loader as loader

    missions = venv / "site-packages" / "roomba_bt" / "missions"
    shutil.copytree(SHIPPED_DIR, missions)
    folder = missions.resolve()
    for name, module in list(sys.modules.items()):
        if name.startswith("roomba_bt") and hasattr(module, "SHIPPED_DIR"):
            monkeypatch.setattr(module, "SHIPPED_DIR", folder)
    monkeypatch.setattr(loader, "SHIPPED_LIBRARY", (folder,))
    return folder
