"""docs/architecture.md's map names every module of ``roomba_bt``: in its package's row of
the layers table or on its package's line of the list below it. A contributor found ten of
the simulator's seventeen modules missing (``sim/power.py`` among them, where PWM Motors is
handled), and the map cannot go stale again unnoticed."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
PACKAGE = ROOT / "roomba_bt"


def _mentions(package: str) -> str:
    """What the page says of ``package``: its row of the layers table and its line of the
    list of the other modules (``- `sim`: ...``; ``- `roomba_bt/`: ...`` for the top)."""
    row = re.compile(rf"^\| `{package}` \|.*$|^- `{package}`: .*$", re.MULTILINE)
    return "\n".join(row.findall(PAGE))


def _unnamed() -> list[str]:
    missing = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).parts
        if path.name in ("__init__.py", "__main__.py"):
            continue
        if len(parts) == 1:  # a top-level module: named anywhere on the page
            if f"`{path.name}`" not in PAGE and f"roomba_bt/{path.name}" not in PAGE:
                missing.append(path.name)
        elif f"`{'/'.join(parts[1:])}`" not in _mentions(parts[0]):
            missing.append("/".join(parts))
    return missing


def test_every_module_is_named_on_the_architecture_page() -> None:
    missing = _unnamed()
    assert not missing, (
        f"docs/architecture.md names no {', '.join(missing)}: add each to its package's row "
        "of the layers table, or one line to the list of the other modules below it"
    )
