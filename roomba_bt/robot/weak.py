"""A callback that does not keep its object alive: :func:`weakly`.

A session's parts (the link, the writer, the safe stop) call back into whatever told them
to. The connection's finalizer holds its safe stop, so a strong callback from any part back
to the connection (or to anything that holds it: the runtime's watch of the robot's own
cycles) keeps the connection alive for ever: the finalizer never fires, and every run's
connection, simulator and tree stayed in memory (docs/robot.md: a program that never
calls ``close()``).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import ParamSpec, TypeVar

__all__ = ["weakly"]

P = ParamSpec("P")
R = TypeVar("R")


def weakly(method: Callable[P, R], dead: R) -> Callable[P, R]:
    """``method`` called through a weak reference (``dead`` once its object is gone): a
    part's callback into the connection (the link's halt and mode report) would make a
    cycle, and a connection in one is freed only by the collector, not when its last
    reference goes: a dropped connection drove on until a collector pass. A callback into
    something the finalizer's safe stop reaches would keep it alive for ever."""
    ref = weakref.WeakMethod(method)

    def call(*args: P.args, **kwargs: P.kwargs) -> R:
        bound = ref()
        return dead if bound is None else bound(*args, **kwargs)

    return call
