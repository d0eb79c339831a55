"""The tree's own cost per tick: a compiled mission ticked against an episode's recorded
snapshots, without the simulator, the link or the runtime around it.

Whole-episode counts (``bench/icount.py``) mix the tree's tick and the leaves' work with
everything else on the per-tick path. This isolates that part: one episode of a shipped
mission is run normally while the snapshot of every tick and the commands the tree queued
in it are recorded; then a freshly compiled copy of the mission is set up on a handle that
only hands out those snapshots, and ticked once per recorded snapshot. The replay checks
that the tree queues the same commands on the same ticks as in the episode (so a change
that alters what the tree decides fails here, not only in the golden recordings).

``python -m bench.tick_replay``: replay each case once, check the commands, print the
ticks (a wall-clock time too, a rough guide only on a shared machine).
``python -m bench.tick_replay --icount [dock|bump]``: instructions per replayed tick by
callgrind, the difference of two runs (recording and replaying all ticks, recording and
replaying none), so the recording, imports and start-up cancel out.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from roomba_bt.oi.encode import Command
    from roomba_bt.robot.interface import Snapshot

ROOT = Path(__file__).resolve().parents[1]
#: (name, mission, world, episodes, eval fields): seeds from 100, as in bench/icount.py
CASES = (
    ("dock", "dock.yaml", "empty-room", 3, {"within_m": 1.5}),
    ("bump", "bump-and-turn.yaml", "corridor", 2, {"timeout_s": 90.0}),
)


@dataclass
class Recorded:
    """One episode: the mission as run, each tick's snapshot and the commands the tree queued."""

    mission: str
    params: dict[str, str]
    snapshots: list[Snapshot]
    commands: list[list[Command]]


def record(case: str) -> list[Recorded]:
    """Run the case's episodes, recording every tick's snapshot and the tree's commands
    (the outbox as the tick left it, before the runtime's bump reflex adds to it)."""
    from roomba_bt.evaluate import episode_specs
    from roomba_bt.evaluate.episode import run_episode
    from roomba_bt.runtime.loop import MissionRunner

    _, mission, world, runs, fields = next(entry for entry in CASES if entry[0] == case)
    specs = episode_specs(
        str(ROOT / "missions" / mission), world=world, runs=runs, seed=100, **fields
    )
    episodes: list[Recorded] = []
    original = MissionRunner._flush

    def flush(runner: MissionRunner) -> None:
        episodes[-1].snapshots.append(runner.snapshot)
        episodes[-1].commands.append(runner.outbox.pending())
        original(runner)

    MissionRunner._flush = flush  # type: ignore[method-assign,assignment]
    try:
        for spec in specs:
            episodes.append(Recorded(spec.mission, dict(spec.params), [], []))
            result = run_episode(spec)
            if result.outcome == "error":  # a broken tree: nothing worth measuring
                raise RuntimeError(f"{case}, seed {spec.seed}: {result.reason}")
    finally:
        MissionRunner._flush = original  # type: ignore[method-assign]
    return episodes


class ReplayHandle:
    """A :class:`~roomba_bt.robot.interface.RobotHandle` handing out recorded snapshots."""

    def __init__(self) -> None:
        from roomba_bt.oi.profiles import DEFAULT_PROFILE
        from roomba_bt.robot.interface import Outbox

        self.snapshot: Snapshot | None = None
        self.outbox = Outbox()
        self.profile = DEFAULT_PROFILE


def prepare(episode: Recorded) -> tuple[Behaviour, ReplayHandle]:
    """A fresh copy of the episode's mission, set up on a replay handle."""
    import py_trees

    from roomba_bt.mission import load_mission

    py_trees.blackboard.Blackboard.storage.clear()  # what the recorded run left behind
    mission = load_mission(episode.mission, episode.params)
    handle = ReplayHandle()
    mission.setup(handle)  # type: ignore[arg-type]
    return mission.root, handle


def replay(root: Behaviour, handle: ReplayHandle, episode: Recorded) -> list[list[Command]]:
    """Tick ``root`` against every recorded snapshot; the commands it queued per tick."""
    outbox = handle.outbox
    tick_once = root.tick_once
    drained = []
    for snapshot in episode.snapshots:
        handle.snapshot = snapshot
        tick_once()
        drained.append(outbox.drain())
    return drained


def differences(drained: list[list[Command]], episode: Recorded) -> list[int]:
    """The ticks whose commands differ from the episode's."""
    return [
        index
        for index, (got, want) in enumerate(zip(drained, episode.commands, strict=True))
        if [c.data for c in got] != [c.data for c in want]
    ]


def _child(case: str, replaying: bool) -> None:
    episodes = record(case)
    prepared = [prepare(episode) for episode in episodes]
    ticks = 0
    for (root, handle), episode in zip(prepared, episodes, strict=True):
        if replaying:  # checked by the plain run (main), not counted here
            replay(root, handle, episode)
        ticks += len(episode.snapshots)
    print(f"TICKS {ticks}")


def _count(case: str, replaying: bool) -> tuple[int, int]:
    from bench.icount import callgrind

    count, printed = callgrind("bench.tick_replay", case, str(int(replaying)))
    ticks = re.search(r"TICKS (\d+)", printed)
    if ticks is None:
        raise RuntimeError(f"callgrind run {case} printed no tick count:\n{printed}")
    return count, int(ticks.group(1))


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        _child(argv[1], argv[2] == "1")
        return 0
    if argv[:1] == ["--icount"]:
        if shutil.which("valgrind") is None:
            print("valgrind is not installed: instruction counts need valgrind --tool=callgrind")
            return 2
        for case, *_ in CASES:
            if argv[1:] and case not in argv[1:]:
                continue
            with_ticks, ticks = _count(case, True)
            without, _ = _count(case, False)
            per_tick = (with_ticks - without) / ticks
            print(f"   {case}: {ticks} ticks, tree + leaves {per_tick:9,.0f} instructions / tick")
        return 0
    for case, *_ in CASES:
        episodes = record(case)
        ticks, seconds = 0, 0.0
        for episode in episodes:
            root, handle = prepare(episode)
            started = time.process_time()
            drained = replay(root, handle, episode)
            seconds += time.process_time() - started
            differ = differences(drained, episode)
            ticks += len(episode.snapshots)
            if differ:
                print(f"   {case}: commands differ from the episode at ticks {differ[:5]}")
                return 1
        digest = hashlib.sha1()  # of every tick's commands: compare it across versions
        for episode in episodes:
            for commands in episode.commands:
                digest.update(b"".join(c.data for c in commands) + b"|")
        print(
            f"   {case}: {ticks} ticks replayed, the same commands as in the episodes (digest "
            f"{digest.hexdigest()[:12]}); {seconds / ticks * 1e6:.1f} us/tick (CPU time: a "
            "rough guide)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
