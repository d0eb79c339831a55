"""A plugin distribution installed into a test's own site folder as pip leaves one: its
module and its ``.dist-info`` with the ``roomba_bt.behaviours`` entry point, so the
registry finds it as it finds any installed plugin (tests of plugins that clash, that do
not load, that raise on import)."""

from __future__ import annotations

from pathlib import Path


def install_distribution(site: Path, distribution: str, module: str, source: str) -> None:
    """``distribution`` (version 1.0) with the one module ``module`` holding ``source``,
    its entry point named after the module."""
    (site / f"{module}.py").write_text(source)
    info = site / f"{distribution.replace('-', '_')}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {distribution}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[roomba_bt.behaviours]\n{module} = {module}\n")
