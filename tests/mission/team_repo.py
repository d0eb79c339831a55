"""A team's repository in miniature (docs/ci.md): a library in ``missions/common/lib/``
that missions in sibling folders include, for the tests of include chains and of
``validate``'s output. Imported by the tests beside it (pytest puts their folder on the
path)."""

from __future__ import annotations

from pathlib import Path

ESCAPES = """\
# Team library: ways out of trouble.
subtrees:
  back_off:
    tree:
      sequence:
        - mode: safe
        - drive: {velocity: -150 mm/s, distance: 10 parsecs}
  escape_bump:
    tree: {subtree: back_off}
"""

SAFE_DRIVE = """\
# A guarded leg, built on escapes.yaml
include: [escapes.yaml]
subtrees:
  leg:
    tree:
      sequence:
        - mode: safe
        - drive: {velocity: 200 mm/s, distance: 1 m}
          until: {bump: any}
        - subtree: escape_bump
"""

TO_KITCHEN = """\
mission: to-kitchen
include: [../common/lib/safe_drive.yaml]
tree:
  sequence:
    - subtree: leg
    - mode: passive
"""

SQUARE = """\
mission: square
include: [../common/lib/escapes.yaml]
tree:
  sequence:
    - mode: safe
    - subtree: escape_bump
    - mode: passive
"""


def team_repo(root: Path) -> Path:
    """The team's layout, the library broken (``10 parsecs`` at escapes.yaml:7:50)."""
    files = {
        "missions/common/lib/escapes.yaml": ESCAPES,
        "missions/common/lib/safe_drive.yaml": SAFE_DRIVE,
        "missions/delivery/to-kitchen.yaml": TO_KITCHEN,
        "missions/delivery/square.yaml": SQUARE,
    }
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text, encoding="utf-8")
    return root
