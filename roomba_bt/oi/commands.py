"""Kept for old imports until 0.3.0: ``import roomba_bt.oi.commands`` and ``from
roomba_bt.oi.commands import drive``. ``commands`` is a name of :mod:`roomba_bt.oi` (``from
roomba_bt.oi import commands``, as docs/plugins.md writes it), the encoder's module
:mod:`roomba_bt.oi.encode` by a second name; as a module path it warns, and puts that one
module in its place, so the names are the same objects whichever way they come.
"""

import sys

from roomba_bt._lazy import warn_moved_module
from roomba_bt.oi.encode import *  # noqa: F403  (what a type checker reads here)
from roomba_bt.oi.encode import __name__ as _encoder

warn_moved_module(
    "import roomba_bt.oi.commands (as a module)", "write from roomba_bt.oi import commands"
)
sys.modules[__name__] = sys.modules[_encoder]
