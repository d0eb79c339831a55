"""What a :class:`~roomba_bt.runtime.stack.RunStack` is given, checked when it is built.

A wrong argument was taken as it came and found out during the run: ``timeout_s="30s"``
ended the run as if a behaviour had raised (``TypeError: '>=' not supported ...`` at
``loop.py``, exit 4). Here each one is a ``TypeError`` or ``ValueError`` that names the
argument, raised before anything is written to the link.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from os import PathLike
from typing import Any

#: what a mission given to a run must have (:class:`~roomba_bt.runtime.loop.MissionLike`)
_MISSION_PARTS = ("name", "root", "packets", "setup")


def check_mission(mission: object) -> None:
    """``mission`` has what a run takes: a compiled mission or a :class:`TreeMission`."""
    missing = [part for part in _MISSION_PARTS if not hasattr(mission, part)]
    if missing:
        raise TypeError(
            f"RunStack(mission, ...): the mission is a compiled mission "
            f"(roomba_bt.load_mission(...)) or a tree built in Python "
            f"(roomba_bt.TreeMission(root)), not {type(mission).__name__} {_short(mission)} "
            f"(it has no {', '.join(missing)})"
        )


def seconds(name: str, value: object, *, none: bool, zero: bool) -> None:
    """``value`` is a number of seconds (an int or a float, not a bool; finite), above 0 or,
    with ``zero``, at least 0; None allowed with ``none``."""
    if value is None and none:
        return
    if not _is_number(value):
        unit = " (seconds, as a number: 30, not '30s')" if isinstance(value, str) else ""
        raise TypeError(
            f"RunStack({name}=...) takes a number of seconds{' or None' if none else ''}"
            f"{unit}, not {type(value).__name__} {_short(value)}"
        )
    number = float(value)  # type: ignore[arg-type]
    if math.isnan(number) or number < 0 or (number == 0 and not zero):
        least = "0 or more" if zero else "above 0"
        raise ValueError(f"RunStack({name}={value!r}): seconds {least}")


def check_arguments(
    mission: object,
    link: object,
    timeout_s: object,
    grace: object,
    watchdog: object,
    baud: object,
    tick_limit: object,
    packets: Sequence[int] | None,
) -> None:
    """The mission, the link and the numbers a :class:`RunStack` is given, each checked (a
    number None: its default)."""
    check_mission(mission)
    if isinstance(link, str | bytes | PathLike):
        raise TypeError(
            f"RunStack(mission, link): the link is a Transport or a Connection, not the "
            f"{type(link).__name__} {link!r}: open it first, "
            f"roomba_bt.Connection.open({link!r}) (and close it after)"
        )
    seconds("timeout_s", timeout_s, none=True, zero=False)
    seconds("grace", grace, none=False, zero=True)
    seconds("watchdog", watchdog, none=True, zero=True)  # 0: no watchdog (a replay's)
    if tick_limit != "default":
        seconds("tick_limit", tick_limit, none=True, zero=True)
    if baud is not None and (type(baud) is not int or baud <= 0):
        raise TypeError(f"RunStack(baud=...) takes a rate in bits/s (115200), not {baud!r}")
    if packets is not None:
        if isinstance(packets, str | bytes) or not isinstance(packets, Sequence | set | frozenset):
            raise TypeError(f"RunStack(packets=...) takes packet ids (7, 35), not {packets!r}")
        wrong = [p for p in packets if type(p) is not int]
        if wrong:
            raise TypeError(f"RunStack(packets=...): each packet is an int id, not {wrong[0]!r}")


def check_given(
    *,
    observer: Callable[..., Any] | None,
    input_ended: Callable[..., Any] | None,
    strict: bool,
    visitors: object,
) -> None:
    """``observer=``, ``input_ended=``: a function, or None; ``strict``: True or False;
    ``visitors``: py_trees visitors (:func:`check_visitors`)."""
    for name, value in (("observer", observer), ("input_ended", input_ended)):
        if value is not None and not callable(value):
            raise TypeError(
                f"RunStack({name}=...) takes a function (or None), not "
                f"{type(value).__name__} {_short(value)}"
            )
    if not isinstance(strict, bool):
        raise TypeError(f"RunStack(strict=...) takes True or False, not {strict!r}")
    check_visitors(visitors)


#: what a py_trees visitor has (``py_trees.visitors.VisitorBase``), each called on every tick
_VISITOR_PARTS = ("initialise", "run", "finalise")


def check_visitors(visitors: object) -> None:
    """``visitors=``: a list (or tuple) of py_trees visitors, each with ``initialise()``,
    ``run(behaviour)`` and ``finalise()``; one visitor not in a list is said so (it was not
    a list of visitors to run, and iterating it would have said nothing useful)."""
    if all(callable(getattr(visitors, part, None)) for part in _VISITOR_PARTS):
        raise TypeError(
            f"RunStack(visitors=...) takes a list of py_trees visitors, not one: "
            f"visitors=[{type(visitors).__name__}(...)]"
        )
    if not isinstance(visitors, list | tuple):
        raise TypeError(
            f"RunStack(visitors=...) takes a list of py_trees visitors, not "
            f"{type(visitors).__name__} {_short(visitors)}"
        )
    for visitor in visitors:
        missing = [part for part in _VISITOR_PARTS if not callable(getattr(visitor, part, None))]
        if missing:
            raise TypeError(
                f"RunStack(visitors=...): each is a py_trees visitor "
                f"(py_trees.visitors.VisitorBase: initialise(), run(behaviour), finalise()), "
                f"not {type(visitor).__name__} {_short(visitor)} (it has no {', '.join(missing)})"
            )


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
