"""``python -m roomba_bt``: the ``roomba-bt`` command, for an environment whose scripts
folder is not on ``PATH`` (a venv not activated, ``pip install --user``, Windows)."""

from __future__ import annotations

import sys

from roomba_bt._entry import main  # the signals taken before the command line loads

if __name__ == "__main__":
    sys.exit(main())
