"""``import roomba_bt.commands``: the Open Interface's commands as functions, pycreate2's
methods' counterparts (``commands.drive(200, 32767)``, ``commands.song(0, [(60, 16)])``).

The one module :mod:`roomba_bt.oi.encode` is, by a third name: ``from roomba_bt import
commands`` gave it (a name of the top package) and ``import roomba_bt.commands`` failed, as
no such module was there. Importing this puts that module in its place (as
``roomba_bt.oi.commands`` does), so the names are the same objects whichever way they come.
"""

import sys

from roomba_bt.oi.encode import *  # noqa: F403  (what a type checker reads here)
from roomba_bt.oi.encode import __name__ as _encoder

sys.modules[__name__] = sys.modules[_encoder]
