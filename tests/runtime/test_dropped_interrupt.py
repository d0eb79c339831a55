"""A signal whose interrupt never reached the run's loop: Python drops an exception a signal
handler raises while a finalizer or a weakref callback runs ("Exception ignored in ..."),
and a plugin's ``except BaseException`` around its own code swallows one raised inside it.
Either way the tree ticked on and the robot drove, and a second Ctrl-C only waited for a
stop that never began (the run's handler had raised once: one signal per run); systemd's
single SIGTERM was lost, its stop timed out and SIGKILLed the process, the robot driving.
The run's handler keeps what it raised until the run takes it, and the run's loop raises it
again at its next frame (``docs/runtime.md``)."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import weakref
from typing import Any

import py_trees
import pytest
from quoted import ROOT  # tests/quoted.py: the repository's root
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.safety import SIGINT_SAID, Terminated
from roomba_bt.runtime.loop import THE_RUN
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import TapLink

#: the tick the signal is sent on; the run would go on for 5 s (333 ticks) without it
SIGNAL_AT = 40


def _signal_main(signum: int) -> None:
    """``signum`` to the main thread, where the handlers run (as ``test_interrupts.py``)."""
    signal.pthread_kill(threading.main_thread().ident or 0, signum)


def _signal_in_a_callback(signum: int) -> None:
    """``signum`` sent from inside a weakref callback, whose exception Python drops: the
    handler runs there (the loop below gives it its chance) and its raise is lost."""

    class Held:
        pass

    held = Held()

    def callback(_: object) -> None:
        _signal_main(signum)
        sum(range(1000))  # the handler runs here, inside the callback

    keep = weakref.ref(held, callback)
    del held  # the callback runs now
    assert keep() is None


class _SignalsOnce(py_trees.behaviour.Behaviour):
    """Runs for ever; on its tick :data:`SIGNAL_AT` it sends the signal ``how``: from a
    weakref callback (``"dropped"``), or from its own code inside ``try: ... except
    BaseException: pass`` (``"swallowed"``: a plugin that guards its code against anything),
    or none (``"none"``). Counts its ticks after that one."""

    def __init__(self, signum: int, how: str) -> None:
        super().__init__("signals")
        self.signum, self.how = signum, how
        self.ticks = 0
        self.after = 0

    def update(self) -> py_trees.common.Status:
        self.ticks += 1
        if self.ticks > SIGNAL_AT:
            self.after += 1
        elif self.ticks == SIGNAL_AT and self.how == "dropped":
            _signal_in_a_callback(self.signum)
        elif self.ticks == SIGNAL_AT and self.how == "swallowed":
            try:
                _signal_main(self.signum)
                sum(range(1000))  # the handler raises here
            except BaseException:  # the plugin's own guard, as found in the field
                pass
        return py_trees.common.Status.RUNNING


def _stack(signum: int, how: str) -> tuple[RunStack, TapLink, _SignalsOnce]:
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    signals = _SignalsOnce(signum, how)
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        py_trees.composites.Parallel(
            "both", py_trees.common.ParallelPolicy.SuccessOnOne(), children=[
                Drive("spin", {"velocity": "100 mm/s", "radius": "spin_left"}), signals,
            ],
        ),
    ])  # fmt: skip
    stack = RunStack(TreeMission(root, "dropped"), link, profile=CREATE2, timeout_s=5.0)
    return stack, link, signals


@pytest.fixture
def dropped() -> Any:
    """What Python dropped meanwhile (``sys.unraisablehook``'s calls): the test's proof that
    the interrupt was lost where the field lost it, not raised."""
    seen: list[BaseException | None] = []
    previous = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: seen.append(unraisable.exc_value)
    try:
        yield seen
    finally:
        sys.unraisablehook = previous


@pytest.mark.parametrize("how", ["dropped", "swallowed"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_whose_interrupt_was_lost_ends_the_run_at_its_next_frame(
    signum: int, how: str, dropped: list[BaseException | None]
) -> None:
    """On main the run went on to its 5 s timeout (the signal lost, exit 0 in the CLI);
    now it ends before its next tick, the safe stop sent and the interrupt raised in the
    caller, as any signal's."""
    stack, link, signals = _stack(signum, how)
    with pytest.raises(KeyboardInterrupt) as caught:
        stack.run()
    if how == "dropped":
        assert [type(exc) for exc in dropped] == [
            Terminated if signum == signal.SIGTERM else KeyboardInterrupt
        ]
    else:
        assert dropped == []
    summary = stack.runner.summary
    assert signals.after == 0, signals.after  # the tree never ticked after the signal
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    said = SIGINT_SAID if signum == signal.SIGINT else "SIGTERM"
    assert summary.reason == said, summary.reason
    assert isinstance(caught.value, Terminated) == (signum == signal.SIGTERM)
    assert summary.ended_at is not None and summary.ended_at[1] == "after"  # its tick whole
    assert summary.safe_stop.startswith("sent "), summary.safe_stop
    assert link.simulator.mode is OIMode.PASSIVE
    assert link.simulator.requested_left == link.simulator.requested_right == 0
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


class _EndsWithALostSignal(py_trees.behaviour.Behaviour):
    """Sends SIGINT from a weakref callback on its first tick and succeeds on it: the run
    ends well on the very tick whose signal was lost, before a next frame could raise it."""

    def update(self) -> py_trees.common.Status:
        _signal_in_a_callback(signal.SIGINT)
        return py_trees.common.Status.SUCCESS


def test_a_signal_lost_on_the_runs_last_tick_is_its_interrupt_all_the_same(
    dropped: list[BaseException | None],
) -> None:
    """The tree ended on the tick whose signal Python dropped: no next frame raises it, so
    the run's end takes it, as one that came during the stop: INTERRUPTED, exit 130, the
    reason saying how the run had ended (``roomba-bt run a && roomba-bt run b`` does not
    start ``b``)."""
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}), _EndsWithALostSignal("ends"),
    ])  # fmt: skip
    stack = RunStack(TreeMission(root, "last"), link, profile=CREATE2, timeout_s=5.0)
    summary = stack.run(raise_interrupts=False)
    assert len(dropped) == 1
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.reason == f"{SIGINT_SAID} during {THE_RUN} (the run had ended: success)"
    page = " ".join((ROOT / "docs" / "runtime.md").read_text(encoding="utf-8").split())
    assert f"`{summary.reason}`" in page  # the page's example is what the run says


@pytest.mark.parametrize("how", ["dropped", "swallowed"])
def test_a_sigterm_lost_in_a_program_s_loop_over_ticks_ends_the_run_at_its_next_tick(
    how: str, dropped: list[BaseException | None]
) -> None:
    """``for tick in stack.ticks():``, the program's own loop body: a SIGTERM whose
    ``Terminated`` Python dropped there (a finalizer) or the body's ``except BaseException``
    swallowed was kept but never raised again, and the loop went on to the run's 5 s end,
    the robot driving. It is raised at the next hand-over: the run stopped, INTERRUPTED,
    and the program gets the interrupt (SIGINT there is Python's own handler's, not ours)."""
    stack, link, _ = _stack(signal.SIGTERM, "none")
    after = 0
    with pytest.raises(Terminated):
        for tick in stack.ticks():
            if tick.number > SIGNAL_AT:
                after += 1
            elif tick.number == SIGNAL_AT and how == "dropped":
                _signal_in_a_callback(signal.SIGTERM)
            elif tick.number == SIGNAL_AT:
                try:
                    _signal_main(signal.SIGTERM)
                    sum(range(1000))  # the handler raises here
                except BaseException:  # the program's own guard
                    pass
    assert len(dropped) == (how == "dropped"), dropped
    assert after == 0, after  # no tick was handed over after the signal's
    summary = stack.summary
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert link.simulator.mode is OIMode.PASSIVE


#: a program's run (``stack.run()``) whose tree's leaf sends SIGINT from inside a weakref
#: callback, as :func:`_signal_in_a_callback` does: Python drops the run's interrupt there
_PROGRAM_S_DROPPED_RUN = """
import os, signal, sys, weakref
import py_trees
import roomba_bt
from roomba_bt.behaviours.actions import Mode

class Once(py_trees.behaviour.Behaviour):
    def __init__(self):
        super().__init__("once")
        self.ticks = 0
    def update(self):
        self.ticks += 1
        if self.ticks == 5:
            class Held: pass
            held = Held()
            def lost_here(_):
                os.kill(os.getpid(), signal.SIGINT)
                sum(range(1000))
            keep = weakref.ref(held, lost_here)
            del held
        return py_trees.common.Status.RUNNING

children = [Mode("safe", {"to": "safe"}), Once()]
root = py_trees.composites.Sequence("root", memory=True, children=children)
world = roomba_bt.load_world("empty-room")
sim = roomba_bt.Simulator(world, roomba_bt.CREATE2, seed=0, trace=False)
stack = roomba_bt.RunStack(roomba_bt.TreeMission(root, "lost"), roomba_bt.SimLink(sim),
                           profile=roomba_bt.CREATE2, timeout_s=5.0)
try:
    stack.run()
except roomba_bt.Interrupted as interrupt:
    print(interrupt.summary.outcome.value, sys.unraisablehook is sys.__unraisablehook__)
"""


def test_a_program_s_run_says_in_one_line_where_python_dropped_its_interrupt() -> None:
    """Python's ``Exception ignored in: <function ...lost_here at 0x...>`` and a traceback
    ending in the run's own handler were what a program's stderr said of it; the interrupt
    is raised again all the same, and where it was lost is one line naming the callback by
    its name, file and line. The hook is Python's own again once the run has ended."""
    done = subprocess.run(
        [sys.executable, "-c", _PROGRAM_S_DROPPED_RUN],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert done.stdout.split() == ["interrupted", "True"], (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    assert (
        "roomba-bt: SIGINT came while Python ran Once.update.<locals>.lost_here (<string>:16), "
        "a finalizer or weakref callback, which drops what it raises: it is raised again at "
        "the next check"
    ) in done.stderr, done.stderr
