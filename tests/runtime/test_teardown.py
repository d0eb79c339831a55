"""The end of a tree's run: every node stopped even when a ``terminate`` raises, the error
said (a warning with the behaviour and its file:line, and the summary), and the safe stop
sent all the same. A tree built by hand in Python, as a py_trees user builds one: plain
py_trees nodes beside roomba-bt leaves."""

from __future__ import annotations

import logging
import signal
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, NoReturn

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import TapLink

SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


class Counting(py_trees.behaviour.Behaviour):
    """RUNNING for ever; counts its terminate calls in ``calls``."""

    def __init__(self, name: str, calls: Counter[str], *, raises: bool = False) -> None:
        super().__init__(name)
        self.calls, self.raises = calls, raises

    def update(self) -> Status:
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        self.calls["terminate " + self.name] += 1
        if self.raises:
            raise RuntimeError(f"{self.name} could not let go")


@dataclass
class HandBuilt:
    """A MissionLike for a tree built in Python."""

    root: py_trees.behaviour.Behaviour
    name: str = "hand-built"
    packets: tuple[int, ...] = ()
    setups: list[str] = field(default_factory=list)

    def setup(self, robot: Any) -> None:
        for node in self.root.iterate():
            node.setup(robot=robot)


def _tree(calls: Counter[str]) -> py_trees.behaviour.Behaviour:
    """Safe, then in parallel: a spinning Drive and four counting nodes, the third of which
    raises in terminate (py_trees' own stop then skipped the fourth and every parent)."""
    parallel = py_trees.composites.Parallel(
        "together",
        policy=py_trees.common.ParallelPolicy.SuccessOnAll(),
        children=[
            Drive("spin", {"velocity": 100.0, "radius": "spin_left"}),
            py_trees.composites.Sequence("inner", memory=True, children=[Counting("a", calls)]),
            Counting("b", calls),
            Counting("bad", calls, raises=True),
            py_trees.decorators.Inverter("not", Counting("c", calls)),
        ],
    )
    return py_trees.composites.Sequence(
        "root", memory=True, children=[Mode("safe", {"to": "safe"}), parallel]
    )


def _run(root: py_trees.behaviour.Behaviour) -> tuple[Any, TapLink]:
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(HandBuilt(root), link, profile=CREATE2, timeout_s=1.0)
    return stack.run(), link


def test_a_terminate_that_raises_leaves_no_node_running(caplog: pytest.LogCaptureFixture) -> None:
    calls: Counter[str] = Counter()
    root = _tree(calls)
    with caplog.at_level(logging.WARNING):
        summary, link = _run(root)
    assert [n.name for n in root.iterate() if n.status is not Status.INVALID] == []
    assert calls == {"terminate a": 1, "terminate b": 1, "terminate bad": 1, "terminate c": 1}
    # the error said: the behaviour's path and the line that raised, in the log and summary
    warning = " ".join(r.getMessage() for r in caplog.records if r.levelno == logging.WARNING)
    assert "terminate() of behaviour root / together / bad raised RuntimeError" in warning
    assert f"{__file__}:" in warning
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4
    assert "bad could not let go" in summary.reason
    assert "the run had ended: timeout" in summary.reason
    # and the safe stop went out all the same
    assert link.written.endswith(SAFE_END)
    assert link.simulator.mode is OIMode.PASSIVE
    assert link.simulator.requested_left == link.simulator.requested_right == 0
    # the tree's own terminate is the class's again: nothing of the guard is left on a node
    assert all("terminate" not in vars(node) for node in root.iterate())


def test_an_interrupted_run_keeps_its_outcome_and_says_the_terminate_too() -> None:
    from roomba_bt.runtime.summary import RunSummary
    from roomba_bt.runtime.teardown import note_stop_failures

    summary = RunSummary("m", outcome=Outcome.INTERRUPTED, reason="Ctrl-C")
    note_stop_failures(summary, ["terminate() of behaviour x raised E: e (at f.py:1)"])
    assert summary.outcome is Outcome.INTERRUPTED
    assert summary.reason == "Ctrl-C; then terminate() of behaviour x raised E: e (at f.py:1)"


def raise_as_it_comes(exc: BaseException) -> NoReturn:
    """``exc`` raised in a behaviour; a bare ``KeyboardInterrupt`` stands for Ctrl-C, so the
    signal itself is sent (one a behaviour raises itself is its error, exit 4)."""
    if type(exc) is KeyboardInterrupt:
        signal.raise_signal(signal.SIGINT)
    raise exc


class Closing(py_trees.behaviour.Behaviour):
    """What a py_trees user writes: opens something in setup(), closes it in shutdown().
    Its update gives ``ends`` after ``after`` ticks (None: RUNNING for ever; an exception:
    raised); its shutdown notes what the link had been written by then."""

    def __init__(
        self, name: str, log: list[tuple[str, bytes]], link: TapLink, *, ends: Any = Status.SUCCESS,
        after: int = 0, raises: bool = False,
    ) -> None:  # fmt: skip
        super().__init__(name)
        self.log, self.link, self.ends, self.after, self.raises = log, link, ends, after, raises
        self.ticks = 0

    def update(self) -> Status:
        self.ticks += 1
        if self.ends is None or self.ticks <= self.after:
            return Status.RUNNING
        if isinstance(self.ends, BaseException):
            raise_as_it_comes(self.ends)
        return self.ends  # type: ignore[no-any-return]

    def shutdown(self) -> None:
        self.log.append((self.name, self.link.written))
        if self.raises:
            raise OSError(f"{self.name}: the log file is gone")


ENDINGS = {
    "success": (Status.SUCCESS, None, Outcome.SUCCESS),
    "failure": (Status.FAILURE, None, Outcome.FAILURE),
    "timeout": (None, None, Outcome.TIMEOUT),
    "exception": (RuntimeError("a bug"), None, Outcome.ERROR),
    "ctrl-c": (KeyboardInterrupt(), None, Outcome.INTERRUPTED),
    "lost link": (None, 0.5, Outcome.CONNECTION_LOST),
}


INVERSE = {Status.SUCCESS: Status.FAILURE, Status.FAILURE: Status.SUCCESS}


@pytest.mark.parametrize("ending", list(ENDINGS))
def test_every_node_is_shut_down_once_after_the_safe_stop(
    ending: str, caplog: pytest.LogCaptureFixture
) -> None:
    ends, stall_after, outcome = ENDINGS[ending]
    log: list[tuple[str, bytes]] = []
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0), stall_after=stall_after)
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[
            Mode("safe", {"to": "safe"}),
            Closing("opened", log, link),
            Closing("bad", log, link, raises=True),
            py_trees.decorators.Inverter(
                "not", Closing("last", log, link, ends=INVERSE.get(ends, ends), after=20)
            ),
        ],
    )  # fmt: skip
    stack = RunStack(HandBuilt(root), link, profile=CREATE2, timeout_s=1.0)
    with caplog.at_level(logging.WARNING):
        summary = stack.run(raise_interrupts=False)
    assert summary.outcome is outcome, summary.reason
    names = [name for name, _ in log]
    assert sorted(names) == ["bad", "last", "opened"]  # each once
    assert all(written.endswith(SAFE_END) for _, written in log)  # after the safe stop
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert any(
        "shutdown() of behaviour root / bad raised OSError: bad: the log file is gone" in w
        for w in warnings
    ), warnings


def test_a_run_that_never_started_sets_up_and_shuts_down_nothing() -> None:
    log: list[tuple[str, bytes]] = []
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0), stall_after=0.0)
    stack = RunStack(HandBuilt(Closing("a", log, link)), link, profile=CREATE2, timeout_s=1.0)
    summary = stack.run()
    assert summary.outcome is Outcome.NO_CONNECTION
    assert log == []


class _FirstTick(py_trees.behaviour.Behaviour):
    """Raises ``exc`` on its first tick: the root's own first tick never ends."""

    def __init__(self, exc: BaseException) -> None:
        super().__init__("boom")
        self.exc = exc

    def update(self) -> Status:
        raise_as_it_comes(self.exc)


@pytest.mark.parametrize(
    "exc, outcome",
    [(RuntimeError("first tick"), Outcome.ERROR), (KeyboardInterrupt(), Outcome.INTERRUPTED)],
)
def test_a_first_tick_that_raises_leaves_no_node_running(
    exc: BaseException, outcome: Outcome
) -> None:
    calls: Counter[str] = Counter()
    parallel = py_trees.composites.Parallel(
        "together",
        policy=py_trees.common.ParallelPolicy.SuccessOnAll(),
        children=[
            Drive("spin", {"velocity": 100.0, "radius": "spin_left"}),
            py_trees.decorators.Inverter("not", Counting("a", calls)),
            Counting("b", calls),
            _FirstTick(exc),
        ],
    )
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Mode("safe", {"to": "safe"}), parallel]
    )
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    summary = RunStack(HandBuilt(root), link, profile=CREATE2, timeout_s=1.0).run(
        raise_interrupts=False
    )
    assert summary.outcome is outcome, summary.reason
    assert calls == {"terminate a": 1, "terminate b": 1}  # each stopped once
    assert [n.name for n in root.iterate() if n.status is Status.RUNNING] == []
    assert link.written.endswith(SAFE_END)


class _Opens(py_trees.behaviour.Behaviour):
    """Opens something in setup() (or raises there) and closes it in shutdown(): a node never
    set up has nothing to close (its shutdown raised AttributeError)."""

    def __init__(self, name: str, log: list[str], *, fails: bool = False) -> None:
        super().__init__(name)
        self.log, self.fails = log, fails

    def setup(self, **kwargs: object) -> None:
        if self.fails:
            raise OSError(f"{self.name}: cannot open the log device")
        self.handle = object()

    def update(self) -> Status:
        return Status.SUCCESS

    def shutdown(self) -> None:
        del self.handle  # AttributeError if setup never made it
        self.log.append(self.name)


def test_only_the_nodes_set_up_are_shut_down(caplog: pytest.LogCaptureFixture) -> None:
    log: list[str] = []
    root = py_trees.composites.Sequence("root", memory=True, children=[
        _Opens("first", log), _Opens("broken", log, fails=True), _Opens("never", log),
    ])  # fmt: skip
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    with caplog.at_level(logging.WARNING):
        summary = RunStack(TreeMission(root, "setup"), link, profile=CREATE2).run()
    assert summary.outcome is Outcome.ERROR
    assert "behaviour root / broken raised OSError: broken: cannot open" in summary.reason
    assert log == ["first"]  # the node whose setup() completed, and it alone
    assert not [r for r in caplog.records if "shutdown()" in r.getMessage()]
    assert all("setup" not in vars(node) for node in root.iterate())  # nothing patched left


def test_a_terminate_that_raises_in_a_tick_is_called_once_and_said_once() -> None:
    calls: Counter[str] = Counter()
    parallel = py_trees.composites.Parallel(
        "together",
        policy=py_trees.common.ParallelPolicy.SuccessOnOne(),
        children=[
            Drive("forward", {"velocity": "100 mm/s", "duration": "0.3 s"}),
            Counting("bad", calls, raises=True),  # stopped by the tick the drive ends in
            Counting("b", calls),
        ],
    )
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[Mode("safe", {"to": "safe"}), parallel]
    )
    summary, link = _run(root)
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4
    assert calls == {"terminate bad": 1, "terminate b": 1}
    assert summary.reason.count("bad could not let go") == 1, summary.reason
    assert summary.reason.startswith("behaviour root / together / bad raised RuntimeError")
    assert [n.name for n in root.iterate() if n.status is Status.RUNNING] == []
    assert link.written.endswith(SAFE_END)


def test_setting_a_tree_up_patches_nothing_into_its_nodes() -> None:
    """Noting which nodes were set up once patched each node's ``setup`` and took it away
    again: the nodes' attribute tables stopped being their class's shared one, and every
    later tick cost 12 % more instructions (``python -m bench.icount``, dock and
    bump-and-turn). The nodes set up are found without touching them; one whose setup
    raised, and those after it, are not set up."""
    from roomba_bt.runtime.teardown import setup_tree, shutdown_nodes

    touched: list[str] = []
    closed: list[str] = []

    class Watched(py_trees.behaviours.Success):
        def __setattr__(self, name: str, value: Any) -> None:
            touched.append(name)
            super().__setattr__(name, value)

        def __delattr__(self, name: str) -> None:
            touched.append(name)
            super().__delattr__(name)

        def shutdown(self) -> None:
            closed.append(self.name)

    class Broken(Watched):
        def setup(self, **kwargs: Any) -> None:
            raise OSError("no device")

    nodes = [Watched(name="a"), Broken(name="b"), Watched(name="c")]
    root = py_trees.composites.Sequence("root", memory=True, children=nodes)
    touched.clear()

    def setup() -> None:
        for node in root.iterate():
            node.setup()

    with pytest.raises(OSError, match="no device"):
        setup_tree(root, setup)
    assert touched == []
    shutdown_nodes(root)
    assert closed == ["a"]
