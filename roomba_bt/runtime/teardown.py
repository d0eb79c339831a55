"""The end of a tree's run, each step guarded, and what a behaviour's exception says.

A run (and the monitor's reload, which retires a tree) ends its tree in this order::

    (drive 0, motors off)   a run's end on the wall clock, while a node still runs: the first
                            half of the safe stop, before any terminate() (one may block);
                            the tick guard's (runtime/tick_guard.py, halt_before_stop)
    stop_nodes(root)        every node stopped: its terminate() once, in py_trees' order;
                            one that raises is noted, and the others are stopped all the same;
                            nothing written meanwhile sets the robot going (ending.py's
                            RunEnding.stop_tree: CommandWriter.hold_motion)
    the safe stop           the runner's (drive 0, motors off, pause, Passive)
    shutdown_nodes(root)    every node's shutdown() (py_trees' BehaviourTree.shutdown), each
                            guarded: one that raises is logged, the others still run

py_trees' own ``root.stop()`` stops the nodes one inside the other: a ``terminate`` that
raised skipped every node after it, and the tree was left half stopped (nodes RUNNING,
the same tree run again did nothing until its time limit).
"""

from __future__ import annotations

import contextlib
import inspect
import logging
import traceback
from collections.abc import Callable
from types import FrameType
from typing import Any

import py_trees

from roomba_bt.behaviours.base import UnkeptDeclaration
from roomba_bt.behaviours.blackboard import KeyRange
from roomba_bt.behaviours.lean import InvalidStatus
from roomba_bt.behaviours.returned import returned_from
from roomba_bt.oi.frames import SLOT_SECONDS, MissingPacket
from roomba_bt.oi.packets import PACKETS
from roomba_bt.robot.safety import (
    THE_SAFE_STOP,
    code_failure,
    failure_said,
    interrupt_reason,
    note_interrupted_in,
    signal_delivered,
    signal_interrupt,
)
from roomba_bt.runtime.recording import UNDELIVERED_STOP
from roomba_bt.runtime.summary import Outcome, RunSummary

log = logging.getLogger(__name__)

_INVALID, _RUNNING = py_trees.common.Status.INVALID, py_trees.common.Status.RUNNING
#: outcomes a failed terminate turns into ERROR: nothing had gone wrong in the run before
_CLEAN_ENDINGS = frozenset({Outcome.SUCCESS, Outcome.FAILURE, Outcome.TIMEOUT, Outcome.INPUT_ENDED})


def behaviour_error(exc: BaseException, *, method: bool = True) -> str:
    """What a behaviour's exception says to the user: the behaviour's path in the tree (the
    innermost behaviour on the traceback), the exception (:func:`failure_said` for one that
    is no ``Exception``: ``SystemExit (it called sys.exit(0))``), the behaviour's method it
    came out of (``method``: said, unless the caller names it: ``terminate() of ...``) and
    the file:line where it raised in that behaviour's own module (a plugin's file), else the
    line the exception came from; for a wrong value returned (:class:`InvalidStatus`, which
    names its method), the ``return`` that gave it when its source tells
    (:func:`returned_from`), else where the method is defined, said so."""
    frames = list(traceback.walk_tb(exc.__traceback__))
    what = failure_said(exc)
    if isinstance(exc, Exception) and str(exc):  # its lines as they are; an empty one by name
        what = f"{type(exc).__name__}: {exc}"  # ("MemoryError:  in its update()" had two spaces)
    behaviour, where = innermost_behaviour(frames)
    came_out_of: str | None = None
    if isinstance(exc, UnkeptDeclaration) and exc.returned is not None:
        # refused as it returned (a SUCCESS in a mode it passes through), after its update:
        # the return that gave it, not roomba-bt's stop that found it
        behaviour, where, came_out_of = exc.node, _top_line(frames), "update"
        with contextlib.suppress(TypeError, OSError, SyntaxError):
            where = returned_from(type(behaviour).update, exc.returned)
    if isinstance(exc, InvalidStatus):  # raised after its update (check) returned: where it is
        behaviour, where = exc.node, _top_line(frames)
        update: Any = getattr(type(behaviour), exc.method, None)
        with contextlib.suppress(TypeError, OSError, SyntaxError):
            where = returned_from(update, exc.status)
        method = False
    if isinstance(exc, KeyRange) and exc.written_at:
        # the reader refused a value: the line to look at is the writer's (the message
        # names it), not roomba-bt's read_parameters that raised
        return f"behaviour {tree_path(behaviour or exc.node)} raised {what}"
    if behaviour is None:
        return f"{what} ({where})" if where else what
    if came_out_of is None and method:
        came_out_of = _method_of(behaviour, frames)
    within = f" in its {came_out_of}()" if came_out_of else ""
    hint = _hint(exc, behaviour)
    return f"behaviour {tree_path(behaviour)} raised {what}{within} ({where}){hint}"


def _method_of(
    behaviour: py_trees.behaviour.Behaviour, frames: list[tuple[FrameType, int]]
) -> str | None:
    """The method of ``behaviour`` an exception came out of (``frames``: its traceback,
    outermost first): the outermost of the behaviour's own frames in its class's module
    (``update``, not a helper method it called; ``check``, not the base class's ``update``
    that called it), else the innermost of its frames; None when none is on it."""
    own = [frame for frame, _ in frames if frame.f_locals.get("self") is behaviour]
    if not own:
        return None
    with contextlib.suppress(TypeError, OSError):
        home = inspect.getfile(type(behaviour))
        for frame in own:
            if frame.f_code.co_filename == home:
                return frame.f_code.co_name
    return own[-1].f_code.co_name


def raised_in_tree(exc: BaseException) -> py_trees.behaviour.Behaviour | None:
    """The behaviour ``exc`` came out of (the innermost on its traceback): raised in a tick
    (or a behaviour's ``setup``); None when raised by the link, the runtime or a program's
    observer. A refused ``@key`` value (``KeyRange``): the behaviour that read it."""
    if isinstance(exc, KeyRange):
        return exc.node
    return innermost_behaviour(list(traceback.walk_tb(exc.__traceback__)))[0]


def behaviours_interrupt(exc: BaseException) -> bool:
    """Whether ``exc``, which ended a run, is a ``KeyboardInterrupt`` a behaviour's code
    raised itself, no signal having come (:func:`~roomba_bt.robot.safety.signal_delivered`):
    the behaviour's error, exit 4, not the operator's Ctrl-C (decided). One raised outside
    every behaviour (a program's observer, a link of its own, as tests stand in a Ctrl-C)
    stays the interrupt it was."""
    if not isinstance(exc, KeyboardInterrupt) or signal_delivered(exc):
        return False
    return innermost_behaviour(list(traceback.walk_tb(exc.__traceback__)))[0] is not None


def innermost_behaviour(
    frames: list[tuple[FrameType, int]],
) -> tuple[py_trees.behaviour.Behaviour | None, str]:
    """The innermost behaviour on a stack (``frames`` outermost first, a traceback's or a
    running thread's) and ``at file:line`` in its own module (a plugin's file) nearest the
    top, else the top frame's; (None, the top frame's) when no behaviour is on it."""
    found = _behaviour_frame(frames)
    if found is None:
        return None, _top_line(frames)
    behaviour = found[0]
    with contextlib.suppress(TypeError, OSError):
        home = inspect.getfile(type(behaviour))
        for frame, line in reversed(frames):
            if frame.f_code.co_filename == home:
                return behaviour, f"at {home}:{line}"
    return behaviour, _top_line(frames)


def stuck_in(
    frames: list[tuple[FrameType, int]],
) -> tuple[py_trees.behaviour.Behaviour | None, str]:
    """Where a tick that has not returned is, from its stack (``frames`` outermost first, a
    traceback's or a running thread's), as eval's HUNG, ``run --wall-limit`` and a Ctrl-C in
    a long tick say it: ``in behaviour sequence / hang (at bad.py:30)`` (its path in the
    tree, :func:`innermost_behaviour`'s line), else ``at file:line`` of the top frame outside
    every behaviour, "" with no frames; and the behaviour (None outside every one)."""
    behaviour, where = innermost_behaviour(frames)
    if behaviour is None:
        return None, where
    return behaviour, f"in behaviour {tree_path(behaviour)} ({where})"


def cut_short(exc: BaseException, ran_s: float) -> str:
    """What the reason of a run that ``exc`` (a Ctrl-C, a SIGTERM) ended inside a tick adds,
    when that tick had run past its 15 ms slot (``ran_s``) in a behaviour: ``in a tick that
    had run 19.66 s, in behaviour sequence / hang (at bad.py:30)`` (:func:`stuck_in`): the
    operator stopped a tree that was stuck, and the summary's slowest tick is of the ticks
    that returned. "" for an ordinary tick's interrupt, or one outside every behaviour."""
    if ran_s <= SLOT_SECONDS:
        return ""
    behaviour, where = stuck_in(list(traceback.walk_tb(exc.__traceback__)))
    return f"in a tick that had run {ran_s:.2f} s, {where}" if behaviour is not None else ""


def _top_line(frames: list[tuple[FrameType, int]]) -> str:
    return f"at {frames[-1][0].f_code.co_filename}:{frames[-1][1]}" if frames else ""


def tree_path(node: py_trees.behaviour.Behaviour | None) -> str:
    """``sequence / boom(x=1)``: the names from the root down to ``node``."""
    path = []
    while node is not None:
        path.append(node.name)
        node = node.parent
    return " / ".join(reversed(path))


def _hint(exc: BaseException, behaviour: py_trees.behaviour.Behaviour) -> str:
    """What to do about a packet the behaviour read without declaring it, where it can be
    told: the declaration that should list it, or, for a plain py_trees behaviour (only a
    tree built in Python holds one), the packets to give the RunStack."""
    declaration: Any = getattr(behaviour, "declaration", None)
    if isinstance(exc, MissingPacket) and declaration is None:  # a plain py_trees behaviour
        return (
            f"; a plain behaviour declares nothing, so stream the packet yourself: RunStack("
            f"mission, ..., packets=stream_request({{{exc.packet_id}, *mission.packets}}, baud)) "
            "(stream_request from roomba_bt.runtime.loop adds what the runtime needs)"
        )
    if not isinstance(exc, MissingPacket) or declaration is None or callable(declaration.reads):
        return ""
    if exc.packet_id not in PACKETS:  # @declare refuses it: the message says it does not exist
        return ""
    listed = ", ".join(str(pid) for pid in declaration.reads) or "nothing"
    return (
        f"; add {exc.packet_id} to @declare(reads=...) of {declaration.name!r} (it lists "
        f"{listed}): the stream carries what the mission's behaviours declare"
    )


def stop_nodes(
    root: py_trees.behaviour.Behaviour, raised_in: py_trees.behaviour.Behaviour | None = None
) -> list[str]:
    """Stop the tree at ``root`` (``root.stop(INVALID)``, py_trees' order and each class's
    own ``stop``; then each node still RUNNING under one that is not: :func:`_topmost_running`)
    with every node's ``terminate`` guarded: one that raises is caught where
    it raised, so py_trees goes on to the nodes after it. Every node stopped ends INVALID, each
    ``terminate`` called once: ``raised_in``'s (:func:`terminate_raised`) is not called again,
    its failure being the run's reason already. Returns what each failure says
    (:func:`behaviour_error`, its file:line), each also logged as a warning."""
    failures: list[str] = []
    stopped: set[int] = set()
    running = _topmost_running(root, stopped)
    if not running:
        return failures
    nodes = list(root.iterate())
    own = [(node, _guard_terminate(node, failures, node is raised_in)) for node in nodes]
    try:
        while running:  # py_trees' stop passes by a node INVALID: what runs under it is next
            for node in running:
                stopped.add(id(node))
                node.stop(_INVALID)
            running = _topmost_running(root, stopped)
    except BaseException as exc:  # a stop() of its own raised, not a terminate: said, and
        if not code_failure(exc):  # the rest marked; a signal's interrupt goes on
            raise
        failures.append(f"stopping the tree: {behaviour_error(exc)}")
        for node in nodes:
            node.status = _INVALID
    finally:
        for node, patched in own:  # the class's terminate again (or the one patched in)
            if patched is None:
                del node.terminate
            else:
                node.terminate = patched  # type: ignore[method-assign]
    for failure in failures:
        log.warning("%s; the other nodes were stopped all the same", failure)
    return failures


def tree_running(root: py_trees.behaviour.Behaviour) -> bool:
    """Whether a node of the tree at ``root`` runs: its stop will call a ``terminate``."""
    return bool(_topmost_running(root, set()))


def _topmost_running(
    root: py_trees.behaviour.Behaviour, stopped: set[int]
) -> list[py_trees.behaviour.Behaviour]:
    """The RUNNING nodes with no RUNNING node above them, none of them ``stopped`` already
    (their ids): ``[root]`` when it runs. A tick that raised (or was interrupted) leaves the
    nodes it had ticked RUNNING under parents whose status was not set yet (INVALID: the root
    on its first tick, a composite on its own first), which py_trees' ``stop`` passes by:
    each is stopped from where it runs."""
    found, todo = [], [root]
    while todo:
        node = todo.pop()
        if node.status is _RUNNING and id(node) not in stopped:
            found.append(node)
        else:
            todo.extend(reversed(node.children))
    return found


def terminate_raised(exc: BaseException) -> py_trees.behaviour.Behaviour | None:
    """The node whose ``terminate`` raised ``exc`` (the innermost on its traceback), if one
    did: a tick that stopped it (a parallel ending, a sequence moving on) raised there."""
    for frame, _ in reversed(list(traceback.walk_tb(exc.__traceback__))):
        node = frame.f_locals.get("self")
        if frame.f_code.co_name == "terminate" and isinstance(node, py_trees.behaviour.Behaviour):
            return node
    return None


def _guard_terminate(
    node: py_trees.behaviour.Behaviour, failures: list[str], raised: bool = False
) -> Callable[..., None] | None:
    """Give ``node`` a ``terminate`` of its own that catches what its usual one raises
    (``raised``: its terminate raised already, in the tick: not called again); returns the
    ``terminate`` that was patched into the node before (None: the class's)."""
    usual = node.terminate
    class_own = getattr(usual, "__func__", None) is getattr(type(node), "terminate", None)

    def guarded(new_status: py_trees.common.Status) -> None:
        if raised:
            return
        try:
            usual(new_status)
        except BaseException as exc:  # sys.exit() too; a signal's interrupt goes on
            if not code_failure(exc):
                raise
            said = behaviour_error(exc, method=False)
            failures.append(f"stopping the tree: terminate() of {said}")

    node.terminate = guarded  # type: ignore[method-assign]
    return None if class_own else usual


def where_in(frame: FrameType | None) -> str:
    """Where a thread whose innermost frame is ``frame`` is: in a behaviour
    (:func:`behaviour_at`), else the innermost frame's line; "" without a frame."""
    if frame is None:
        return ""
    return behaviour_at(frame) or f"at {frame.f_code.co_filename}:{frame.f_lineno}"


def behaviour_at(frame: FrameType | None) -> str:
    """The innermost frame from ``frame`` out that is a py_trees behaviour's method (its
    ``self``), named, at its line: ``slow (Slow.terminate at plugin.py:12)``, the call that
    blocks or writes, in the behaviour's own code; "" when none is."""
    found = _behaviour_frame(list(traceback.walk_stack(frame))[::-1]) if frame else None
    if found is None:
        return ""
    owner, frame, line = found
    code = frame.f_code
    return f"{owner.name} ({type(owner).__name__}.{code.co_name} at {code.co_filename}:{line})"


def behaviour_in(frame: FrameType | None) -> py_trees.behaviour.Behaviour | None:
    """The behaviour whose method is the innermost from ``frame`` out that is one
    (:func:`behaviour_at` names it): the node a stuck thread is stuck in; None if none."""
    found = _behaviour_frame(list(traceback.walk_stack(frame))[::-1]) if frame else None
    return found[0] if found is not None else None


def _behaviour_frame(
    frames: list[tuple[FrameType, int]],
) -> tuple[py_trees.behaviour.Behaviour, FrameType, int] | None:
    """The innermost of ``frames`` (outermost first) that is a py_trees behaviour's method:
    the behaviour (its ``self``), the frame and its line."""
    for frame, line in reversed(frames):
        owner = frame.f_locals.get("self")
        if isinstance(owner, py_trees.behaviour.Behaviour):
            return owner, frame, line
    return None


def during(phase: str) -> Callable[[FrameType | None], str]:
    """What a signal that came during ``phase`` of a run's end (the tree's stop, the nodes'
    ``shutdown()``) came during, as the run's reason says it (``InterruptGuard.stopping``):
    ``phase``, and the behaviour whose method the main thread was in then, if it was in one
    (``the tree's stop, in slow (Slow.terminate at plugin.py:12)``)."""

    def said(frame: FrameType | None) -> str:
        where = behaviour_at(frame)
        return f"{phase}, in {where}" if where else phase

    return said


def note_stop_failures(summary: RunSummary, failures: list[str]) -> None:
    """A ``terminate`` that raised is a bug in a behaviour, as one in ``update`` is: a run
    that had gone well so far (success, failure, timeout, a replay's end) ends as an ERROR
    (exit 4) saying so; one that had already ended otherwise (Ctrl-C, a lost link, an
    error) keeps its outcome, and its reason says it too (decided; ``docs/runtime.md``)."""
    if not failures:
        return
    said = failures[0] + (f" (and {len(failures) - 1} more)" if len(failures) > 1 else "")
    if summary.outcome in _CLEAN_ENDINGS:
        was = summary.outcome.value + (f": {summary.reason}" if summary.reason else "")
        summary.outcome, summary.reason = Outcome.ERROR, f"{said} (the run had ended: {was})"
    else:
        summary.reason = f"{summary.reason}; then {said}" if summary.reason else said


def note_stop_abandoned(summary: RunSummary, said: str, *, interrupted: bool = False) -> None:
    """The tree's stop did not end in time and the run's end went on without it
    (``runtime/ending.py``, ``said`` what): a run that had gone well so far (success,
    failure, timeout, a replay's end) is HUNG, exit 4, as a tick stuck past ``--wall-limit``
    is, its reason saying how the run had ended; one that had ended otherwise keeps its
    outcome, its reason followed by ``; then ...``. ``interrupted``: a signal came while the
    stop was waited for, whose interrupt the run's reason gives (:func:`note_late_interrupt`,
    exit 130 or 143): it is only followed by this."""
    if summary.outcome in _CLEAN_ENDINGS and not interrupted:
        was = summary.outcome.value + (f": {summary.reason}" if summary.reason else "")
        summary.outcome, summary.reason = Outcome.HUNG, f"{said} (the run had ended: {was})"
    else:
        summary.reason = f"{summary.reason}; then {said}" if summary.reason else said


def note_undelivered_stop(summary: RunSummary) -> None:
    """The safe stop did not reach the robot (or is unconfirmed): a run that had ended well
    (success, failure, timeout, a replay's end) is a lost connection, exit 3, its reason
    saying how it had ended (decided, ``docs/runtime.md``: a robot that may still be driving
    is no success); one that had ended otherwise keeps its outcome and exit code."""
    if summary.outcome not in _CLEAN_ENDINGS:
        return
    was = summary.outcome.value + (f": {summary.reason}" if summary.reason else "")
    summary.outcome = Outcome.CONNECTION_LOST
    summary.reason = f"{UNDELIVERED_STOP}{was})"


def note_late_interrupt(
    summary: RunSummary, interrupt: KeyboardInterrupt, came_during: str = THE_SAFE_STOP
) -> None:
    """A Ctrl-C or SIGTERM that came during the end of a run no signal had ended, the tree's
    stop, the safe stop or a node's ``shutdown()`` (``came_during`` says which, and in which
    behaviour: ``InterruptGuard.late_during``; decided, ``docs/runtime.md``): a run that had
    ended well (success, failure, timeout, a replay's end) is INTERRUPTED, exit 130, its
    reason saying how it had ended, so that ``roomba-bt run a && roomba-bt run b`` does not
    start ``b`` after the operator's Ctrl-C; one that had ended otherwise (an error, a lost
    link, the monitor's stop) keeps its outcome and exit code, its reason followed by ``;
    then Ctrl-C during ...``."""
    why = interrupt_reason(interrupt)
    said = f"{why} during {came_during}"
    if summary.outcome in _CLEAN_ENDINGS:
        was = summary.outcome.value + (f": {summary.reason}" if summary.reason else "")
        summary.outcome, summary.reason = Outcome.INTERRUPTED, f"{said} (the run had ended: {was})"
    else:
        summary.reason = f"{summary.reason}; then {said}" if summary.reason else said


#: the nodes whose setup() returned (:func:`setup_tree`), by their tree's root (held with
#: it: an id alone may be reused); taken out by :func:`shutdown_nodes`. Not a WeakSet of the
#: nodes: a weak reference to every node of a running tree raised the reaction latency's
#: p99 over a pty (``python -m bench runtime``: 0.5-0.9 ms without it, 3-4 ms with it)
_SET_UP: dict[int, tuple[py_trees.behaviour.Behaviour, list[py_trees.behaviour.Behaviour]]] = {}


def setup_tree(root: py_trees.behaviour.Behaviour, setup: Callable[[], None]) -> None:
    """Run ``setup`` (a mission's ``setup(robot)``: every node's ``setup()``, in the tree's
    order, as :class:`~roomba_bt.mission.CompiledMission` and ``TreeMission`` do), noting
    each node whose ``setup()`` returned: :func:`shutdown_nodes` shuts down those alone (one
    that raised, or was never reached, has nothing to close: its ``shutdown()`` would find
    attributes its setup never made). The node that raised is found on the traceback, and
    the nodes before it in the tree's order are the ones set up; nothing is patched into a
    node (an attribute set on it and taken away again cost every later tick 12 % more
    instructions: its attribute table was no longer the class's shared one)."""
    nodes = list(root.iterate())
    try:
        setup()
    except BaseException as exc:
        failed = _setup_raised(exc, set(nodes))
        _SET_UP[id(root)] = (root, nodes[: nodes.index(failed)] if failed is not None else [])
        if failed is not None and signal_interrupt(exc) is not None:
            # the operator's Ctrl-C cut a setup() short (a plugin's that blocked): said in
            # the run's reason, which named nothing (--wall-limit named the behaviour)
            _, where = stuck_in(list(traceback.walk_tb(exc.__traceback__)))
            note_interrupted_in(exc, f"setting up, {where}" if where else "setting up")
        raise
    _SET_UP[id(root)] = (root, nodes)


def _setup_raised(
    exc: BaseException, nodes: set[py_trees.behaviour.Behaviour]
) -> py_trees.behaviour.Behaviour | None:
    """The node of the tree whose ``setup`` raised ``exc`` (the innermost on its traceback)."""
    for frame, _ in reversed(list(traceback.walk_tb(exc.__traceback__))):
        node = frame.f_locals.get("self")
        named = frame.f_code.co_name == "setup"
        if named and isinstance(node, py_trees.behaviour.Behaviour) and node in nodes:
            return node
    return None


def shutdown_nodes(
    root: py_trees.behaviour.Behaviour, skip: py_trees.behaviour.Behaviour | None = None
) -> tuple[list[str], list[str]]:
    """Every node's ``shutdown()`` (py_trees' ``BehaviourTree.shutdown``: what a node opened
    in ``setup`` closed), each once and guarded: one that raises is logged with its
    behaviour's name and the others still run. Only the nodes whose ``setup()`` completed
    (:func:`setup_tree`) are shut down. Returns what each failure says, the exceptions first
    (logged, the run's outcome left as it is: a clean-up that failed), then each that was no
    ``Exception`` (``sys.exit()``, a ``KeyboardInterrupt`` or ``BaseException`` of its own:
    the code tried to end the program, or choose its exit code; :func:`note_stop_failures`
    makes it the run's error, decided). A signal's interrupt goes on as it came. ``skip``:
    the node whose ``terminate()`` the run's end left running (``runtime/ending.py``), not
    shut down: its ``shutdown()`` would meet what that holds, and wait as well."""
    failures: list[str] = []
    exits: list[str] = []
    held = _SET_UP.pop(id(root), None)
    for node in held[1] if held is not None and held[0] is root else ():
        if node is skip:
            log.warning("shutdown() of %s not called: its terminate() had not returned", node.name)
            continue
        try:
            node.shutdown()
        except BaseException as exc:
            if not code_failure(exc):
                raise
            said = f"shutdown() of {behaviour_error(exc, method=False)}"
            (failures if isinstance(exc, Exception) else exits).append(said)
            log.warning("%s; the other nodes were shut down all the same", said)
    return failures, exits
