"""Kept for old imports until 0.3.0: ``import roomba_bt.commands``. ``commands`` is a name
of the top package (``from roomba_bt import commands``, ``roomba_bt.commands.drive(200,
32767)``: the Open Interface's commands as functions, pycreate2's methods' counterparts),
the encoder's module :mod:`roomba_bt.oi.encode` by another name; as a module path it warns,
and puts that one module in its place, so the names are the same objects whichever way
they come.
"""

import sys

from roomba_bt._lazy import warn_moved_module
from roomba_bt.oi.encode import *  # noqa: F403  (what a type checker reads here)
from roomba_bt.oi.encode import __name__ as _encoder

warn_moved_module("import roomba_bt.commands (as a module)", "write from roomba_bt import commands")
sys.modules[__name__] = sys.modules[_encoder]
