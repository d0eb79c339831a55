"""Mission compiler and tick benchmarks (``make bench``; ``python -m bench mission``).

1. Compile time of generated missions of 250 / 500 / 1000 / 2000 nodes (YAML read, checks,
   py_trees build): the time per node should stay flat (linear), and 1000 nodes < 0.5 s.
2. The tick of a compiled mission against a hand-built py_trees tree of the same nodes (same
   leaf classes, same composites), measured in the same run, interleaved: target <= 1.15x.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import py_trees
from py_trees.behaviour import Behaviour

from roomba_bt.behaviours.actions import Wait
from roomba_bt.behaviours.conditions import COMPARISON, Bump, Cliff, Sensor, Wall
from roomba_bt.mission import load_mission
from roomba_bt.robot.testing import StubRobot

GROUP = """\
      - reactive_fallback:
          - bump: left
          - wall
          - sensor: wall_signal > 100
          - cliff: front_left
          - wait: 1h
"""
NODES_PER_GROUP = 6  # the fallback and its five leaves


def mission_text(groups: int) -> str:
    return "tree:\n  parallel:\n    policy: all\n    children:\n" + GROUP * groups


def hand_built(groups: int) -> Behaviour:
    """The same tree, built with py_trees and the leaf classes directly."""
    children = []
    for _ in range(groups):
        leaves = [
            Bump("bump(left)", {"side": "left"}),
            Wall("wall", {}),
            Sensor("sensor(wall_signal > 100)", {"test": COMPARISON.parse("wall_signal > 100")}),
            Cliff("cliff(front_left)", {"sensor": "front_left"}),
            Wait("wait(1h)", {"duration": 3600.0}),
        ]
        children.append(py_trees.composites.Selector("reactive_fallback", False, leaves))
    policy = py_trees.common.ParallelPolicy.SuccessOnAll(True)
    return py_trees.composites.Parallel("parallel", policy, children)


def compile_seconds(path: Path, repeats: int = 5) -> tuple[float, int]:
    best = float("inf")
    nodes = 0
    for _ in range(repeats):
        started = time.perf_counter()
        mission = load_mission(path)
        best = min(best, time.perf_counter() - started)
        nodes = sum(1 for _ in mission.root.iterate())
    return best, nodes


def tick_seconds(root: Behaviour, robot: StubRobot, ticks: int) -> float:
    """CPU seconds per tick (process time: other processes on a shared machine do not count)."""
    started = time.process_time()
    for _ in range(ticks):
        root.tick_once()
    return (time.process_time() - started) / ticks


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        print("   compile (read YAML, check, build py_trees):")
        per_node: list[float] = []
        warm = Path(tmp) / "warm.yaml"
        warm.write_text(mission_text(20), encoding="utf-8")
        compile_seconds(warm)
        for target in (250, 500, 1000, 2000):
            groups = max(1, target // NODES_PER_GROUP)
            path = Path(tmp) / f"m{target}.yaml"
            path.write_text(mission_text(groups), encoding="utf-8")
            seconds, nodes = compile_seconds(path)
            per_node.append(seconds / nodes)
            flag = ""
            if target == 1000:
                flag = "  (target < 0.5 s: " + ("ok)" if seconds < 0.5 else "MISSED)")
            print(
                f"   {nodes:5d} nodes  {seconds * 1000:7.1f} ms  "
                f"{seconds / nodes * 1e6:6.1f} us/node{flag}"
            )
        spread = max(per_node) / min(per_node)
        print(f"   linearity: us/node max/min = {spread:.2f} (1.00 = perfectly linear)")

        groups = 1000 // NODES_PER_GROUP
        path = Path(tmp) / "tick.yaml"
        path.write_text(mission_text(groups), encoding="utf-8")
        compiled = load_mission(path)
        robot = StubRobot()
        compiled.setup(robot)
        hand = hand_built(groups)
        for node in hand.iterate():
            node.setup(robot=robot)
        robot.set_frame({7: 0, 8: 0, 27: 0, 10: 0, 35: 2})
        n_compiled = sum(1 for _ in compiled.root.iterate())
        n_hand = sum(1 for _ in hand.iterate())
        assert n_compiled == n_hand, (n_compiled, n_hand)
        compiled_times: list[float] = []
        hand_times: list[float] = []
        for i in range(12):  # interleaved, alternating order: both see the same machine
            pair = [(compiled.root, compiled_times), (hand, hand_times)]
            for root, times in pair if i % 2 else pair[::-1]:
                times.append(tick_seconds(root, robot, 30))
        # the minimum is the least disturbed run of each (a shared machine adds only noise)
        ratio = min(compiled_times) / min(hand_times)
        print(f"   tick of a {n_compiled}-node tree (full traversal every tick):")
        print(f"   hand-built py_trees  {min(hand_times) * 1e3:6.2f} ms/tick (best of 12)")
        print(f"   compiled mission     {min(compiled_times) * 1e3:6.2f} ms/tick (best of 12)")
        median = statistics.median(compiled_times) / statistics.median(hand_times)
        print(f"   ratio of medians = {median:.3f}x")
        verdict = "ok" if ratio <= 1.15 else "MISSED"
        print(f"   ratio compiled / hand-built = {ratio:.3f}x (target <= 1.15x: {verdict})")


if __name__ == "__main__":
    main()
