"""The base every error of roomba-bt's own derives from: ``except roomba_bt.RoombaBtError``
catches what the package raises (a mission that does not compile, a run that failed, a robot
that cannot be reached, a command that cannot be encoded, a world that does not load), and
nothing of another library's.

A mix-in, last among each error's bases: each keeps the standard base it had (``ValueError``,
``ConnectionError``, ``KeyError``...) first in its order, so an ``except ValueError`` that
caught it still does. Below every layer, standard library only (``tests/test_layers.py``),
so that the protocol's errors can derive from it too.
"""

from __future__ import annotations

__all__ = ["RoombaBtError"]


class RoombaBtError(Exception):
    """Base of the errors roomba-bt raises for what a caller can act on (its own bugs aside,
    and Ctrl-C, which stays a ``KeyboardInterrupt``)."""
