"""The lean composites, decorators and leaf tick behave exactly as py_trees' own.

Random trees are built twice, once from py_trees' classes and once from
``roomba_bt.behaviours.lean`` (leaves with :class:`RobotBehaviour`'s ``tick``/``stop``), and
ticked side by side: every node's status after every tick, and the order of every leaf's
initialise/update/terminate calls, must be the same, on the direct path (``tick_once``) and
through the generator (``tick``), which must also yield the same nodes with the same statuses
as py_trees' own (what a visitor sees).
"""

from __future__ import annotations

import tomllib
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from packaging.requirements import Requirement
from py_trees.behaviour import Behaviour
from py_trees.common import OneShotPolicy, ParallelPolicy, Status

from roomba_bt.behaviours import lean
from roomba_bt.behaviours.declare import RobotBehaviour

STATUSES = (Status.SUCCESS, Status.FAILURE, Status.RUNNING)
Spec = tuple[Any, ...]


class ScriptLeaf(Behaviour):
    """Returns the statuses of its script in turn (cycling); logs every call."""

    def __init__(self, name: str, script: tuple[Status, ...], log: list[str]) -> None:
        super().__init__(name=name)
        self.script = script
        self.calls = 0
        self.log = log

    def initialise(self) -> None:
        self.log.append(f"{self.name}.initialise")

    def update(self) -> Status:
        status = self.script[self.calls % len(self.script)]
        self.calls += 1
        self.log.append(f"{self.name}.update={status.name}")
        return status

    def terminate(self, new_status: Status) -> None:
        self.log.append(f"{self.name}.terminate={new_status.name}")


class LeanLeaf(lean.DirectLeaf, ScriptLeaf):
    """A script leaf with :class:`RobotBehaviour`'s tick and stop."""


assert issubclass(RobotBehaviour, lean.DirectLeaf)


class GiveUpAfter(py_trees.decorators.Decorator):
    """FAILURE after ``ticks`` ticks even while the child runs (as a timeout does): the
    decorator must then stop its running child."""

    def __init__(self, name: str, child: Behaviour, ticks: int) -> None:
        super().__init__(name=name, child=child)
        self.limit = ticks
        self.count = 0

    def initialise(self) -> None:
        self.count = 0

    def update(self) -> Status:
        self.count += 1
        return Status.FAILURE if self.count >= self.limit else self.decorated.status


class LeanGiveUpAfter(lean.DecoratorTick, GiveUpAfter):
    pass


def _leaves() -> st.SearchStrategy[Spec]:
    """A leaf: its script, and whether the lean tree gets py_trees' own leaf there (a
    plugin's behaviour, ticked through its generator inside a direct-ticked tree)."""
    script = st.lists(st.sampled_from(STATUSES), min_size=1, max_size=4)
    return st.tuples(st.just("leaf"), script, st.booleans())


def _trees() -> st.SearchStrategy[Spec]:
    def extend(children: st.SearchStrategy[Spec]) -> st.SearchStrategy[Spec]:
        many = st.lists(children, min_size=1, max_size=3)
        return st.one_of(
            st.tuples(st.sampled_from(["sequence", "selector"]), st.booleans(), many),
            st.tuples(st.just("parallel"), st.sampled_from(["all", "one"]), many),
            st.tuples(st.just("retry"), st.integers(1, 3), children),
            st.tuples(st.just("give_up"), st.integers(1, 4), children),
            st.tuples(
                st.sampled_from(["inverter", "force_success", "force_failure"]),
                st.none(),
                children,
            ),
            st.tuples(st.just("oneshot"), st.booleans(), children),
        )

    return st.recursive(_leaves(), extend, max_leaves=8)


def build(spec: Spec, stock: bool, log: list[str], counter: list[int]) -> Behaviour:
    kind = spec[0]
    if kind == "leaf":
        counter[0] += 1
        cls = ScriptLeaf if stock or spec[2] else LeanLeaf
        return cls(f"leaf{counter[0]}", tuple(spec[1]), log)
    option, body = spec[1], spec[2]
    if kind in ("sequence", "selector", "parallel"):
        children = [build(child, stock, log, counter) for child in body]
        if kind == "parallel":
            all_or_one: ParallelPolicy.Base = (
                ParallelPolicy.SuccessOnAll() if option == "all" else ParallelPolicy.SuccessOnOne()
            )
            cls_p = py_trees.composites.Parallel if stock else lean.Parallel
            return cls_p(kind, all_or_one, children)
        if kind == "sequence":
            cls_s = py_trees.composites.Sequence if stock else lean.Sequence
        else:
            cls_s = py_trees.composites.Selector if stock else lean.Selector
        return cls_s(kind, bool(option), children)
    child = build(body, stock, log, counter)
    decorators = py_trees.decorators
    if kind == "retry":
        return (decorators.Retry if stock else lean.Retry)(kind, child, int(option))
    if kind == "give_up":
        return (GiveUpAfter if stock else LeanGiveUpAfter)(kind, child, int(option))
    if kind == "oneshot":
        policy = OneShotPolicy.ON_COMPLETION if option else OneShotPolicy.ON_SUCCESSFUL_COMPLETION
        return (decorators.OneShot if stock else lean.OneShot)(kind, child, policy)
    simple: dict[str, tuple[Callable[..., Behaviour], Callable[..., Behaviour]]] = {
        "inverter": (decorators.Inverter, lean.Inverter),
        "force_success": (decorators.FailureIsSuccess, lean.FailureIsSuccess),
        "force_failure": (decorators.SuccessIsFailure, lean.SuccessIsFailure),
    }
    return simple[kind][0 if stock else 1](kind, child)


def _run(
    spec: Spec, stock: bool, ticks: int, by_generator: bool = False
) -> tuple[list[list[str]], list[str]]:
    log: list[str] = []
    root = build(spec, stock, log, [0])
    statuses = []
    for _ in range(ticks):
        yielded = []
        if by_generator:  # every node the generator yields, with its status as it is yielded
            yielded = [f"yield {node.name}={node.status.name}" for node in root.tick()]
        else:
            root.tick_once()  # the direct path for the lean classes
        statuses.append(yielded + [f"{node.name}={node.status.name}" for node in root.iterate()])
    root.stop(Status.INVALID)
    statuses.append([f"{node.name}={node.status.name}" for node in root.iterate()])
    return statuses, log


@settings(max_examples=300, deadline=None)
@given(_trees(), st.integers(1, 12))
def test_lean_trees_tick_exactly_as_py_trees(spec: Spec, ticks: int) -> None:
    assert _run(spec, False, ticks) == _run(spec, True, ticks)
    by_generator = _run(spec, True, ticks, by_generator=True)
    assert _run(spec, False, ticks, by_generator=True) == by_generator


def test_a_lean_tree_is_ticked_without_generators() -> None:
    """``tick_once`` on a lean tree never calls a ``tick`` generator of a lean node."""
    log: list[str] = []
    spec: Spec = ("sequence", True, [
        ("selector", False, [("leaf", [Status.FAILURE], False), ("leaf", [Status.RUNNING], False)]),
        ("parallel", "all", [("retry", 2, ("leaf", [Status.SUCCESS], False))]),
        ("oneshot", True, ("inverter", None, ("leaf", [Status.FAILURE], False))),
    ])  # fmt: skip
    root = build(spec, False, log, [0])
    generators: list[str] = []
    for node in root.iterate():

        def spy(node: Behaviour = node) -> typing.Iterator[Behaviour]:
            generators.append(node.name)
            yield node

        node.tick = spy  # type: ignore[method-assign]
    root.tick_once()
    assert generators == []
    assert [n.status for n in root.children] == [Status.RUNNING, Status.INVALID, Status.INVALID]


def test_a_subclass_that_overrides_tick_is_ticked_by_its_own_tick() -> None:
    """A plugin that overrides ``tick`` (py_trees warns against it, but it may) must not be
    bypassed by the inherited direct path."""
    calls: list[str] = []

    class Custom(LeanLeaf):
        def tick(self) -> typing.Iterator[Behaviour]:
            calls.append("custom tick")
            self.status = Status.SUCCESS
            yield self

    class CustomSequence(lean.Sequence):
        def tick(self) -> typing.Iterator[Behaviour]:
            calls.append("custom sequence tick")
            yield from super().tick()

    leaf = Custom("custom", (Status.FAILURE,), [])
    root = CustomSequence("root", False, [leaf])
    root.tick_once()
    assert calls == ["custom sequence tick", "custom tick"]
    assert leaf.status is Status.SUCCESS and root.status is Status.SUCCESS


def test_a_subclass_that_rewrites_a_step_is_ticked_by_its_steps() -> None:
    """The shortcuts of the lean classes (a running sequence or selector with memory
    resuming its child, a decorator's tick in one call, a parallel's) repeat the class's
    own steps: a subclass that rewrites one is ticked by the steps, its own included."""
    calls: list[str] = []

    class CountingSequence(lean.Sequence):
        def tick_next(self, index: int) -> int:
            calls.append(f"sequence next {index}")
            return super().tick_next(index)

    class CountingSelector(lean.Selector):
        def tick_start(self) -> int:
            calls.append("selector start")
            return super().tick_start()

    class CountingParallel(lean.Parallel):
        def tick_next(self, index: int) -> int:
            calls.append(f"parallel next {index}")
            return super().tick_next(index)

    class CountingDecorator(lean.DecoratorTick, py_trees.decorators.Decorator):
        def tick_start(self) -> int:
            calls.append("decorator start")
            return super().tick_start()

        def update(self) -> Status:
            return self.decorated.status

    def running(name: str) -> LeanLeaf:
        return LeanLeaf(name, (Status.RUNNING,), [])

    sequence = CountingSequence("sequence", True, [running("a")])
    selector = CountingSelector("selector", True, [running("b")])
    parallel = CountingParallel("parallel", ParallelPolicy.SuccessOnAll(), [running("c")])
    decorator = CountingDecorator("decorator", running("d"))
    for node in (sequence, selector, parallel, decorator):
        node.tick_once()
        node.tick_once()  # running: the resumed tick
    assert calls == [
        "sequence next 0", "sequence next 0", "selector start", "selector start",
        "parallel next -1", "parallel next 0", "parallel next -1", "parallel next 0",
        "decorator start", "decorator start",
    ]  # fmt: skip


def test_the_decorators_made_lean_do_not_define_their_own_tick_or_stop() -> None:
    """The lean classes replace py_trees' ``Decorator.tick``/``stop``; if a py_trees release
    gives one of these decorators its own, the replacement would hide it."""
    base = py_trees.decorators.Decorator
    for cls in (lean.Retry, lean.Inverter, lean.FailureIsSuccess, lean.SuccessIsFailure):
        stock = cls.__bases__[-1]
        assert stock.tick is base.tick and stock.stop is base.stop, stock
    assert lean.OneShot.__bases__[-1].stop is base.stop
    for composite in (py_trees.composites.Sequence, py_trees.composites.Selector):
        assert "stop" in vars(composite)  # only logs, then Composite.stop (replicated)


@pytest.mark.parametrize("make", [lambda: LeanLeaf("leaf", (Status.SUCCESS,), [])])
def test_debug_logging_still_logs(make: Callable[[], Behaviour], capsys: Any) -> None:
    previous = py_trees.logging.level
    py_trees.logging.level = py_trees.logging.Level.DEBUG
    try:
        root = lean.Sequence("root", True, [make()])
        root.tick_once()
    finally:
        py_trees.logging.level = previous
    out = capsys.readouterr()
    text = out.out + out.err
    assert "LeanLeaf.tick()" in text and "LeanLeaf.stop(" in text and "Sequence.stop()" in text


@pytest.mark.parametrize("returned", [None, "SUCCESS", ["not", "a", "status"]])
def test_an_invalid_status_is_the_nodes_error_not_invalid_as_in_py_trees(returned: object) -> None:
    """Decided: py_trees logs and sets INVALID on every tick and the tree goes on; here the
    node's bug is raised (the runner ends the run with its safe stop, exit 4)."""

    class Broken(LeanLeaf):
        def update(self) -> Status:
            return typing.cast(Status, returned)

    leaf = Broken("broken", (Status.SUCCESS,), [])
    with pytest.raises(lean.InvalidStatus, match=r"Broken.update\(\) returned .*, not a Status"):
        leaf.tick_once()
    with pytest.raises(lean.InvalidStatus) as raised:
        lean.Sequence("root", True, [Broken("inner", (Status.SUCCESS,), [])]).tick_once()
    assert raised.value.node.name == "inner" and raised.value.status == returned


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.sampled_from(STATUSES), min_size=1, max_size=6),
    st.integers(1, 4),
    st.integers(1, 15),
)
def test_retry_says_what_py_trees_retry_says(script: list[Status], times: int, ticks: int) -> None:
    """The lean retry writes py_trees' messages (formatted only when they change) on every
    tick, except its own on giving up."""
    stock = py_trees.decorators.Retry("retry", ScriptLeaf("leaf", tuple(script), []), times)
    made = lean.Retry("retry", LeanLeaf("leaf", tuple(script), []), times)
    for _ in range(ticks):
        stock.tick_once()
        made.tick_once()
        assert made.status is stock.status and made.failures == stock.failures
        if made.status is Status.FAILURE:
            assert made.feedback_message.startswith(f"gave up after {times} failed attempt")
        else:
            assert made.feedback_message == stock.feedback_message


def test_retry_writes_its_message_again_once_something_else_replaced_it() -> None:
    made = lean.Retry("retry", LeanLeaf("leaf", (Status.RUNNING,), []), 3)
    made.tick_once()
    assert made.feedback_message == "running [status: 0 failure from 3]"
    made.feedback_message = "shown by someone else"
    made.tick_once()
    assert made.feedback_message == "running [status: 0 failure from 3]"
    made.num_failures = 5
    made.tick_once()
    assert made.feedback_message == "running [status: 0 failure from 5]"


def test_a_retry_with_an_update_of_its_own_is_ticked_through_it() -> None:
    """While its child runs, the retry's tick ends without calling its ``update`` (it would
    only say RUNNING again), unless the node or a subclass has an ``update`` of its own."""
    made = lean.Retry("retry", LeanLeaf("leaf", (Status.RUNNING,), []), 3)
    made.tick_once()
    made.tick_once()
    assert made.status is Status.RUNNING
    made.update = lambda: Status.SUCCESS  # type: ignore[method-assign]
    made.tick_once()
    assert made.status is Status.SUCCESS

    class Counting(lean.Retry):
        updates = 0

        def update(self) -> Status:
            self.updates += 1
            return super().update()

    counted = Counting("retry", LeanLeaf("leaf", (Status.RUNNING,), []), 3)
    for _ in range(3):
        counted.tick_once()
    assert counted.updates == 3 and counted.status is Status.RUNNING


def test_a_parallel_still_refuses_a_selection_that_is_not_its_children() -> None:
    """py_trees validates the policy on every tick; the lean parallel skips the call only
    for the policies that check has nothing to say of."""
    other = LeanLeaf("other", (Status.SUCCESS,), [])
    policy = ParallelPolicy.SuccessOnSelected([other])
    parallel = lean.Parallel("parallel", policy, [LeanLeaf("a", (Status.SUCCESS,), [])])
    with pytest.raises(RuntimeError, match="not children of this parallel"):
        parallel.tick_once()


def test_a_py_trees_release_not_proven_is_refused_naming_both_versions() -> None:
    with pytest.raises(lean.UnsupportedPyTrees) as refused:
        lean.check_py_trees("2.7.0")
    message = str(refused.value)
    assert "py_trees 2.7.0 is installed" in message
    assert "proven against py_trees 2.6.0 only" in message
    assert "pip install 'py-trees==2.6.0'" in message
    assert isinstance(refused.value, ImportError)  # raised while importing roomba_bt


def test_the_installed_py_trees_is_one_the_tree_is_proven_against() -> None:
    lean.check_py_trees()  # what the import did
    assert py_trees.version.__version__ in lean.PROVEN_PY_TREES


def test_pyproject_pins_exactly_the_proven_py_trees_releases() -> None:
    """The pin and the check at import say the same: pip installs only what the check lets
    through."""
    project = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    pins = [
        Requirement(line)
        for line in project["project"]["dependencies"]
        if Requirement(line).name == "py-trees"
    ]
    assert len(pins) == 1
    neighbours = ("2.5.0", "2.6.1", "2.7.0", "3.0.0")
    for version in (*lean.PROVEN_PY_TREES, *neighbours):
        assert pins[0].specifier.contains(version) == (version in lean.PROVEN_PY_TREES), version
