"""What an operator may ask of a run, and when a request is refused.

A request (a page's control, a key in the terminal) is checked in the asker's thread, before
it is queued: against the run's state as the requests queued before it will leave it
(:class:`Ahead`), so that a 202 is a request the run will apply (two pauses pressed at once
both got 202, and one did nothing; a pause after a stop got 202 and was never applied). The
tick thread applies it later, between two ticks (:mod:`.session`). A node is named by its
index, its name or its path from the root (:func:`find_node`).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from py_trees.common import Status

#: What a breakpoint may wait for: a node's start, or its end with a given status.
BREAK_ON = ("start", "success", "failure", "end")
#: what a condition may be forced to (``none`` releases it)
FORCEABLE = {"success": Status.SUCCESS, "failure": Status.FAILURE}
#: the requests that change whether the run goes on, pauses or ends (:meth:`Ahead.after`)
CONTROLS = ("pause", "resume", "step", "stop")


class ControlRefused(ValueError):
    """A request that cannot be carried out as asked (the page gets HTTP 409 with this text)."""


@dataclass
class Ahead:
    """The run's state as its queued requests will leave it: what :func:`check_request`
    checks a new one against."""

    paused: bool
    stepping: bool
    stopping: bool
    forced: set[int] = field(default_factory=set)

    def after(self, queued: Iterable[str]) -> Ahead:
        """This state once the ``queued`` controls (:data:`CONTROLS`, in their order) are
        applied: changed in place, and returned."""
        for action in queued:
            if action == "stop":
                self.stopping = True
            elif action == "pause":
                self.paused, self.stepping = True, False
            else:  # resume, step
                self.paused, self.stepping = False, action == "step"
        return self


@dataclass
class Request:
    action: str
    node: int | None = None
    value: str | None = None
    payload: Any = None
    #: who asked: the client's address (``192.0.2.7``) or ``the terminal's keys``; the event
    #: log says it beside the act (two pages open: whose pause was it?)
    by: str | None = None


def check_request(
    state: Ahead,
    infos: list[Any],
    allow_force: bool,
    action: str,
    node: int | None,
    value: str | None,
) -> None:
    """:meth:`.session.MonitorSession.request`'s check: :class:`ControlRefused` for a request the
    run's state (as the requests queued before it leave it) refuses, ValueError for a bad
    one; nothing when it may be queued."""
    if action in CONTROLS:
        if state.stopping:
            raise ControlRefused(
                "the run is already stopping" if action == "stop" else "the run is stopping"
            )
        if action == "pause" and state.paused:
            raise ControlRefused("the run is already paused")
        if action in ("resume", "step") and state.stepping:
            raise ControlRefused(f"a step is under way: {action} when it has paused again")
        if action == "resume" and not state.paused:
            raise ControlRefused("the run is not paused")
        if action == "step" and not state.paused:
            raise ControlRefused("step needs a paused run: pause first")
    elif action in ("break", "force"):
        if node is None or not 0 <= node < len(infos):
            raise ValueError(f"node {node!r}: allowed 0..{len(infos) - 1}")
        if action == "break":
            if value not in (*BREAK_ON, "none"):
                raise ValueError(f"break on {value!r}: allowed {', '.join(BREAK_ON)}, none")
        else:
            if value not in (*FORCEABLE, "none"):
                raise ValueError(f"force to {value!r}: allowed success, failure, none")
            if not infos[node].condition:
                raise ControlRefused(f"{infos[node].name} is not a condition: only "
                                     "conditions can be forced")  # fmt: skip
            if value == "none" and node not in state.forced:
                raise ControlRefused(f"{infos[node].name} is not forced: nothing to release")
            if not allow_force:
                raise ControlRefused(
                    "forcing a condition on a real robot is off; run with --monitor-force"
                )
    else:
        raise ValueError(f"action {action!r}: allowed pause, resume, step, stop, break, force")


def node_path(infos: list[Any], index: int) -> str:
    """A node's names from the root down, joined by ``/`` (``root/dock/search``)."""
    names: list[str] = []
    at: int | None = index
    while at is not None:
        names.append(infos[at].name)
        at = infos[at].parent
    return "/".join(reversed(names))


def find_node(infos: list[Any], wanted: str) -> int:
    """The index of the node ``wanted`` names: its path from the root (:func:`node_path`) or,
    when only one node has it, its name; else, a string of digits (``"3"``: a script that
    quoted the index, or took it from a form's text field) is that index, range-checked as a
    number is. A name wins over the index it looks like (a node may be named ``3``), so a
    mission whose node is renamed never changes which node a digit string meant without a
    word: the error listed the indices and then refused ``"3"`` as "no node has that name".
    ValueError says which nodes were meant or found."""
    paths = [node_path(infos, i) for i in range(len(infos))]
    if wanted in paths:
        return paths.index(wanted)
    named = [i for i, info in enumerate(infos) if info.name == wanted]
    if len(named) == 1:
        return named[0]
    if named:
        raise ValueError(
            f"node {wanted!r}: {len(named)} nodes have that name (indices "
            f"{', '.join(map(str, named))}); give its index or its path, e.g. "
            f"{paths[named[0]]!r}"
        )
    if wanted.isascii() and wanted.isdigit():
        return int(wanted)
    raise ValueError(
        f"node {wanted!r}: no node has that name or path; give an index 0..{len(infos) - 1}, "
        "a node's name or its path from the root (names joined by /)"
    )
