"""A tree stuck in a tick that never returns (a plugin's endless loop), on the virtual
clock where mission time stands still with it: a Ctrl-C or SIGTERM names the leaf and its
line, and ``--wall-limit`` (``MissionRunner.wall_limit_s``) ends the run there, as eval's
HUNG says it; the robot is stopped and left in Passive either way."""

from __future__ import annotations

import signal
import threading
import time

import py_trees
import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S, joined  # tests/waits.py: a hang's bound

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot import wording
from roomba_bt.robot.safety import SIGINT_SAID
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.runtime.wall_limit import WallLimit, WallLimitReached
from roomba_bt.sim import SimLink, Simulator, load_world

#: how long a stuck update spins before it gives up, so that a test of old code fails
#: rather than hangs: the suite's hang bound, as the interrupt it waits for may be that late
#: on a loaded machine (an update that gave up first was no stuck tick for the test)
GIVE_UP_S = HANG_S


class Stuck(py_trees.behaviour.Behaviour):
    """RUNNING for nine ticks; the tenth spins past its 15 ms slot, says so (:attr:`spinning`),
    and spins on: a plugin's ``while True: pass``."""

    def __init__(self) -> None:
        super().__init__("stuck")
        self.ticks = 0
        self.spinning = threading.Event()

    def update(self) -> py_trees.common.Status:
        self.ticks += 1
        if self.ticks < 10:
            return py_trees.common.Status.RUNNING
        began = time.perf_counter()
        while time.perf_counter() - began < GIVE_UP_S:
            if time.perf_counter() - began > 2 * SLOT_SECONDS:
                self.spinning.set()
        return py_trees.common.Status.RUNNING

    @staticmethod
    def named(reason: str, ending: str) -> bool:
        """Whether ``reason`` ends in ``ending`` and ``(at file:line)`` of a line of the
        spinning loop (whichever the interrupt came on)."""
        code = Stuck.update.__code__
        loop = range(code.co_firstlineno + 5, code.co_firstlineno + 8)
        return any(reason.endswith(f"{ending} (at {code.co_filename}:{line})") for line in loop)


def _stack() -> tuple[RunStack, Stuck]:
    """Safe, the stuck leaf beside a drive, on the simulator's virtual clock."""
    stuck = Stuck()
    root = py_trees.composites.Parallel(
        "root", py_trees.common.ParallelPolicy.SuccessOnAll(),
        children=[Mode("safe", {"to": "safe"}), stuck, Drive("d", {"velocity": "200 mm/s"})],
    )  # fmt: skip
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    return RunStack(TreeMission(root, "stuck"), link, profile=CREATE2, timeout_s=30.0), stuck


def _stopped(stack: RunStack, summary: RunSummary) -> None:
    """The robot stopped and in Passive: the safe stop ran."""
    simulator = stack.link.simulator  # type: ignore[attr-defined]
    assert summary.safe_stop.startswith("sent "), summary.safe_stop
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0


def _the_pages(reason: str) -> dict[str, str]:
    """The names docs/runtime.md gives the stuck leaf and its line (``sequence / hang``,
    ``/home/me/bad.py:30``), for this test's (``root / stuck``, its spinning line)."""
    at = reason.rsplit(" (at ", 1)[-1].removesuffix(")")
    return {"root / stuck": "sequence / hang", at: "/home/me/bad.py:30"}


@pytest.mark.parametrize(
    ("signum", "said"),
    [(signal.SIGINT, SIGINT_SAID), (signal.SIGTERM, "SIGTERM")],
    ids=["ctrl-c", "sigterm"],
)
def test_an_interrupt_in_a_stuck_tick_names_the_leaf_and_its_line(signum: int, said: str) -> None:
    stack, stuck = _stack()

    def interrupt_once_stuck() -> None:
        if stuck.spinning.wait(GIVE_UP_S):
            signal.pthread_kill(threading.main_thread().ident or 0, signum)

    sender = threading.Thread(target=interrupt_once_stuck)
    sender.start()
    with stack:
        summary = stack.run(raise_interrupts=False)
    joined(sender, "the interrupt's sender")  # its wait's own bound at the latest
    assert summary.outcome is Outcome.INTERRUPTED and summary.exit_code == 130
    assert summary.reason.startswith(f"{said} in a tick that had run "), summary.reason
    assert stuck.named(summary.reason, " s, in behaviour root / stuck"), summary.reason
    _stopped(stack, summary)
    if signum == signal.SIGINT:  # docs/runtime.md's, its leaf sequence / hang in bad.py
        assert_quoted("docs/runtime.md", "outcome INTERRUPTED (Ctrl-C or kill -INT", str(summary),
                      numbers=True, names=_the_pages(summary.reason))  # fmt: skip


def test_an_ordinary_tick_s_interrupt_says_only_the_signal() -> None:
    """An interrupt that comes in a tick well inside its slot is no stuck tree: the reason
    stays the signal's alone."""
    ticks = []

    class Interrupts(py_trees.behaviour.Behaviour):
        def update(self) -> py_trees.common.Status:
            ticks.append(1)
            if len(ticks) == 5:
                signal.pthread_kill(threading.main_thread().ident or 0, signal.SIGINT)
            return py_trees.common.Status.RUNNING

    root = py_trees.composites.Parallel(
        "root", py_trees.common.ParallelPolicy.SuccessOnAll(), children=[Interrupts("tick")],
    )  # fmt: skip
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    with RunStack(TreeMission(root, "quick"), link, profile=CREATE2, timeout_s=5.0) as stack:
        summary = stack.run(raise_interrupts=False)
    assert (summary.outcome, summary.reason) == (Outcome.INTERRUPTED, SIGINT_SAID)


@pytest.mark.parametrize(
    ("caller", "limit"),
    [(wording.PYTHON, "stack.runner.wall_limit_s (0.5 s)"),
     (wording.COMMAND_LINE, "--wall-limit 0.5 s")],
    ids=["a program", "the command line"],
)  # fmt: skip
def test_the_wall_limit_ends_a_stuck_run_naming_the_leaf_after_the_safe_stop(
    caller: wording.ConnectionWording, limit: str
) -> None:
    """The limit is named as the caller set it: a program has no ``--wall-limit``."""
    stack, stuck = _stack()
    stack.runner.wall_limit_s = 0.5
    with stack, wording.spoken(caller):
        summary = stack.run()
    assert stuck.spinning.is_set()
    # HUNG, eval's word for a stuck episode: not ERROR, no exception was raised in the tree
    assert summary.outcome is Outcome.HUNG and summary.exit_code == 4
    said = f"{limit} of wall-clock time ran out in behaviour root / stuck"
    assert summary.reason.startswith(said), summary.reason
    assert stuck.named(summary.reason, said), summary.reason
    _stopped(stack, summary)
    if caller is wording.COMMAND_LINE:  # docs/runtime.md's, its leaf sequence / hang in bad.py
        assert_quoted("docs/runtime.md", "outcome HUNG (--wall-limit", str(summary),
                      numbers=True, names=_the_pages(summary.reason))  # fmt: skip


def test_a_run_within_its_wall_limit_is_not_touched() -> None:
    """A limit that was not reached raises nothing after its block, even if its timer comes
    late."""
    with WallLimit(60.0) as limit:
        pass
    limit._expire()  # the timer's act, after the block: nothing is set going
    assert not limit.reached
    with pytest.raises(WallLimitReached), WallLimit(0.05) as limit:
        began = time.perf_counter()
        while time.perf_counter() - began < GIVE_UP_S:
            pass
    assert limit.reached
