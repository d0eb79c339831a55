"""Runs in one process keep their blackboards apart (a library user's report): two stacks
stepped in turn (a vectorised env) shared py_trees' one store, so a 200 mm leg was driven
900 mm; episodes in two threads differed from the same episodes alone; and a run read the
keys a run before it had left, so ``UnwrittenKey`` never fired. Each run now has a board of
its own (``roomba_bt.behaviours.blackboard.claim_board``), removed when it is closed."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import py_trees
import pytest
from waits import joined  # tests/waits.py: a hang's bound

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.behaviours.blackboard import (
    RUNS_NAMESPACE,
    SharedBlackboard,
    UnwrittenKey,
    read_key,
)
from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, run_episode
from roomba_bt.mission import load_mission_text
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import MissionLike, RunStack, TreeMission
from roomba_bt.runtime.stepping import Tick
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import write_mission


@pytest.fixture(autouse=True)
def _clean(clean_blackboard: None) -> Iterator[None]:
    yield


def leg(mm: int) -> str:
    """A mission that drives the distance its key ``d`` holds, ``mm`` at the start."""
    return f"""
mission: leg{mm}
blackboard:
  d: {{type: distance, initial: {mm} mm}}
tree:
  sequence:
    - mode: safe
    - wait: 0.5 s
    - drive: {{velocity: 200 mm/s, distance: "@d"}}
"""


def stack_for(mission: MissionLike) -> RunStack:
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=1, trace=False, random_start=True)
    return RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=20)


def stepped_in_turn(stacks: list[RunStack]) -> list[Tick]:
    """Each stack's ticks taken in turn, one a stack, until every run has ended (as gym's
    SyncVectorEnv steps its envs); each one's last tick."""
    loops = [stack.ticks() for stack in stacks]
    last: list[Tick | None] = [None] * len(stacks)
    going = set(range(len(stacks)))
    while going:
        for index in sorted(going):
            tick = next(loops[index], None)
            if tick is None:
                going.discard(index)
            else:
                last[index] = tick
    assert all(tick is not None for tick in last)
    return [tick for tick in last if tick is not None]


def test_two_stacks_stepped_in_turn_each_drive_their_own_leg() -> None:
    stacks = [stack_for(load_mission_text(leg(mm), name=f"leg{mm}.yaml")) for mm in (200, 900)]
    try:
        short, long = stepped_in_turn(stacks)
        assert [stack.summary.outcome for stack in stacks] == [Outcome.SUCCESS] * 2
        assert short.snapshot.odometry.distance_mm == pytest.approx(200, abs=10)
        assert long.snapshot.odometry.distance_mm == pytest.approx(900, abs=10)
        assert dict(short.blackboard) == {"d": 200.0}
        assert dict(long.blackboard) == {"d": 900.0}
        # the second run's keys are under a prefix of its own; shown by the names a user knows
        boards = [stack.runner.blackboard for stack in stacks]
        assert boards[0] is not None and boards[1] is not None
        assert boards[0].prefix == "" and boards[1].prefix.startswith(RUNS_NAMESPACE)
        assert boards[1].shown() == {"/mission/d": 900.0}
        assert boards[0].shown() == {"/mission/d": 200.0}
    finally:
        for stack in stacks:
            stack.close()
    assert not py_trees.blackboard.Blackboard.storage  # both closed: nothing of theirs left


LEG_PARAMETER = """
mission: leg
parameters:
  leg: {type: distance, default: 200 mm}
blackboard:
  d: {type: distance, initial: "${leg}"}
tree:
  sequence:
    - mode: safe
    - wait: 0.5 s
    - drive: {velocity: 200 mm/s, distance: "@d"}
"""


def test_episodes_in_two_threads_are_the_episodes_alone(tmp_path: Path) -> None:
    """``run_episode`` is "same spec, same result" in a thread beside another too (a Dask
    worker with more than one thread): its key ``d`` at the end (``eval --key``) was the
    other thread's about four times in five. And the log is as it was after them (each
    episode silences the robot layer's lines: the two left it silenced for good)."""
    level = logging.getLogger("roomba_bt").level
    mission = str(write_mission(tmp_path, LEG_PARAMETER))
    specs = [
        EpisodeSpec(mission=mission, seed=1, timeout_s=20, trace_every=0,
                    params=(("leg", f"{mm} mm"),), keys=("d",))
        for mm in (200, 900)
    ]  # fmt: skip
    alone = [run_episode(spec) for spec in specs]
    assert [result.keys for result in alone] == [(("d", 200.0),), (("d", 900.0),)]
    for _ in range(3):
        for beside, result in zip(in_two_threads(specs), alone, strict=True):
            assert replace(beside, wall_s=result.wall_s, cpu_s=result.cpu_s) == result
    assert logging.getLogger("roomba_bt").level == level


def in_two_threads(specs: list[EpisodeSpec]) -> list[EpisodeResult]:
    """Each of the two episodes run at once, each in a thread of its own."""
    results: dict[int, EpisodeResult] = {}

    def episode(index: int) -> None:
        results[index] = run_episode(specs[index])

    threads = [threading.Thread(target=episode, args=(index,)) for index in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        joined(thread, "an episode in a thread of its own")
    return [results[0], results[1]]


def reader() -> TreeMission:
    """A tree built in Python that reads ``@d`` (:func:`leg`'s key) and never writes it."""
    root = py_trees.composites.Sequence(
        "s",
        memory=True,
        children=[
            Mode("safe", {"to": "safe"}),
            Drive("drive", {"velocity": "200 mm/s", "distance": "@d"}),
        ],
    )
    return TreeMission(root, name="reader")


def test_a_key_a_closed_run_wrote_is_unwritten_for_the_next() -> None:
    with stack_for(load_mission_text(leg(800), name="leg800.yaml")) as stack:
        assert stack.run().outcome is Outcome.SUCCESS
        assert read_key("d") == 800.0  # read back until the stack is closed
    assert read_key("d") is None
    with stack_for(reader()) as stack:
        summary = stack.run()
    assert summary.outcome is Outcome.ERROR
    assert isinstance(summary.exception, UnwrittenKey)


def test_a_run_not_closed_leaves_nothing_to_the_next() -> None:
    """A run that ended and is not closed gives the plain names to the next run: its keys
    move aside, where its board still reads them, and the next run reads none of them."""
    writer = stack_for(load_mission_text(leg(800), name="leg800.yaml"))
    writer.run()
    summary = stack_for(reader()).run()
    assert isinstance(summary.exception, UnwrittenKey)
    board = writer.runner.blackboard
    assert board is not None and board.prefix.startswith(RUNS_NAMESPACE)
    assert board.read("d") == 800.0
    writer.close()
    assert not [
        name for name in py_trees.blackboard.Blackboard.storage if name.endswith("/mission/d")
    ]


class Counts(py_trees.behaviour.Behaviour):
    """A plain py_trees behaviour with a key of its own, through a py_trees client."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.board = self.attach_blackboard_client()
        self.board.register_key(key="/count", access=py_trees.common.Access.WRITE)

    def update(self) -> py_trees.common.Status:
        self.board.count = 1
        return py_trees.common.Status.SUCCESS


def test_a_py_trees_clients_key_beside_another_run_is_an_error() -> None:
    """py_trees' own clients name their keys for the process: a run beside another would
    share them, so it ends before its first tick, saying why; alone it runs."""
    first = stack_for(load_mission_text(leg(200), name="leg200.yaml"))
    second = stack_for(TreeMission(Counts("counts"), name="counts"))
    try:
        loop = first.ticks()
        next(loop)  # the first run is going
        summary = second.run()
        assert summary.outcome is Outcome.ERROR
        assert isinstance(summary.exception, SharedBlackboard)
        assert "'counts' (Counts) uses py_trees blackboard keys /count" in summary.reason
        assert all(tick.status is not None for tick in loop)  # the first goes on to its end
        assert first.summary.outcome is Outcome.SUCCESS
    finally:
        first.close()
        second.close()
    with stack_for(TreeMission(Counts("counts"), name="counts")) as alone:
        assert alone.run().outcome is Outcome.SUCCESS


def test_a_runner_has_no_board_before_its_run() -> None:
    stack = stack_for(load_mission_text(leg(200), name="leg200.yaml"))
    runner: MissionRunner = stack.runner
    assert runner.blackboard is None
    stack.close()


def test_two_stacks_stepped_in_turn_give_back_the_signal_handlers_they_found() -> None:
    """Each ``ticks()`` makes SIGTERM raise ``Terminated`` while it runs; stepped in turn,
    the first ended first and the second gave back the first's handler: the process kept
    ours after both (a later plain ``raise Terminated`` was taken for a signal's)."""
    import signal

    found = signal.getsignal(signal.SIGTERM)
    stacks = [stack_for(load_mission_text(leg(mm), name=f"leg{mm}.yaml")) for mm in (200, 900)]
    try:
        stepped_in_turn(stacks)
    finally:
        for stack in stacks:
            stack.close()
    assert signal.getsignal(signal.SIGTERM) is found
