"""The current folder off ``sys.path`` under ``python -m roomba_bt``.

``python -m`` puts the current folder first on ``sys.path``: run inside a downloaded mission
folder, that folder's ``typing.py`` or ``yaml.py`` ran as soon as roomba-bt imported the
module of that name, with no ``--allow-plugin-files`` (a mission folder cannot run code on
its own: docs/missions.md, "A mission file is data"). The ``roomba-bt`` command and
``python -P`` never add it. This module imports only what Python loaded at start-up
(``os``, ``sys``), so nothing it imports can come from that folder.
"""

from __future__ import annotations

import os
import sys


def drop_current_folder() -> None:
    """Take the current folder off the front of ``sys.path`` when roomba-bt is being started
    by ``python -m`` (runpy sets ``sys.argv[0]`` to "-m" while it imports the package, before
    ``__main__``); a program that imports roomba_bt keeps its ``sys.path`` as it made it.
    Plugins named by module then come from installed packages only, as under ``roomba-bt``."""
    if sys.argv[:1] == ["-m"] and sys.path and sys.path[0] in ("", os.getcwd()):
        del sys.path[0]
