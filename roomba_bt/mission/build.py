"""Checked tree -> py_trees objects; and the :class:`CompiledMission` the runtime runs.

Every node is a py_trees class (``Sequence``, ``Selector``, ``Parallel``, ``Retry``,
``Inverter``, ``OneShot``, ...) or one of ours where py_trees would read the wall clock
(:mod:`roomba_bt.behaviours.decorators`), so py_trees' display, visitors and idioms work on
a compiled mission unchanged.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour

from roomba_bt.behaviours import decorators as ours
from roomba_bt.behaviours import lean
from roomba_bt.behaviours.declare import write_key
from roomba_bt.mission.ir import COMPOSITES, Node
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.interface import RobotHandle


def build(node: Node) -> Behaviour:
    """The py_trees (sub)tree for a checked node."""
    kind, name = node.kind, node.name
    if kind == "leaf":
        assert node.decl is not None
        return node.decl.cls(name, node.params)
    children = [build(child) for child in node.children]
    if kind in COMPOSITES:
        memory = bool(node.options.get("memory", True))
        if kind == "parallel":
            return lean.Parallel(name, _policy(node, children), children)
        cls = lean.Sequence if "sequence" in kind else lean.Selector
        return cls(name, memory, children)
    child = children[0] if children else None
    options = node.options
    if kind == "guard":
        return ours.Guard(name, children[0], children[1], until=bool(options["until"]))
    assert child is not None
    if kind == "retry":
        return lean.Retry(name, child, int(options["times"]))
    if kind == "repeat":
        return ours.Repeat(name, child, options.get("times"), options.get("for"))
    if kind == "timeout":
        return ours.Timeout(name, child, float(options["after"]))
    if kind == "delay":
        return ours.Delay(name, child, float(options["for"]))
    if kind == "inverter":
        return lean.Inverter(name, child)
    if kind == "force_success":
        return lean.FailureIsSuccess(name, child)
    if kind == "force_failure":
        return lean.SuccessIsFailure(name, child)
    if kind == "oneshot":
        policy = (
            py_trees.common.OneShotPolicy.ON_COMPLETION
            if options.get("policy") == "on_completion"
            else py_trees.common.OneShotPolicy.ON_SUCCESSFUL_COMPLETION
        )
        return lean.OneShot(name, child, policy)
    if kind == "for_each":
        return ours.ForEach(name, child, str(options["key"]), options.get("items", ()))
    raise AssertionError(f"no builder for node kind {kind!r}")


def _policy(node: Node, children: list[Behaviour]) -> py_trees.common.ParallelPolicy.Base:
    policy = node.options.get("policy", "all")
    synchronise = bool(node.options.get("synchronise", True))
    if policy == "one":
        return py_trees.common.ParallelPolicy.SuccessOnOne()
    if policy == "selected":
        wanted = set(node.options.get("selected", ()))
        chosen = [c for c in children if c.name in wanted]
        return py_trees.common.ParallelPolicy.SuccessOnSelected(chosen, synchronise)
    return py_trees.common.ParallelPolicy.SuccessOnAll(synchronise)


@dataclass
class CompiledMission:
    """A checked mission, compiled onto py_trees, ready for ``setup(robot)`` and ticking."""

    name: str
    description: str
    root: Behaviour
    packets: tuple[int, ...]
    modes_needed: frozenset[OIMode]
    parameters: Mapping[str, Any]
    source: Path
    blackboard_initial: Mapping[str, Any] = field(default_factory=dict)
    blackboard_keys: Mapping[str, str] = field(default_factory=dict)

    def setup(self, robot: RobotHandle, **kwargs: Any) -> None:
        """Hand the robot to every node (py_trees idiom: hardware arrives in ``setup``) and
        write the blackboard's initial values. Call again before each run."""
        for key, value in self.blackboard_initial.items():
            write_key(key, value)
        for node in self.root.iterate():
            node.setup(robot=robot, **kwargs)

    def reset_blackboard(self) -> None:
        for key, value in self.blackboard_initial.items():
            write_key(key, value)
