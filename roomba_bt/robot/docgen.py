"""``python -m roomba_bt.robot.docgen [PATH]``: write the generated ``docs/modes.md``.

Kept apart from :mod:`roomba_bt.robot.modes` so that running it does not import that module
twice (once through the package, once as ``__main__``).
"""

from __future__ import annotations

import pathlib
import sys

from roomba_bt.robot.modes import render_modes_doc


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    text = render_modes_doc()
    if not args or args[0] == "-":
        sys.stdout.write(text)
    else:
        pathlib.Path(args[0]).write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
