"""The simulator alone, stepping a robot that moves as in a real episode: recorded host bytes
replayed into a fresh :class:`~roomba_bt.sim.Simulator`.

An episode's cost per tick is the mission's and runtime's work plus the simulator stepping a
*moving* robot (collisions, light bumper, IR, power, the frame's bytes). To measure the
simulator's share alone, :func:`record` runs one episode of a shipped mission and keeps every
byte the host sent, with the step it arrived before; :func:`prepare` builds the same robot
(world, seed, start pose, coverage) and returns a function that feeds those bytes at the same
steps and steps through the whole episode, reading every frame, with no mission and no
runtime. The simulator is deterministic, so the robot drives the same path and sends the same
bytes (:func:`check` compares a digest of them with the recorded one).

The recordings are kept in ``bench/data/sim_replay.json`` so that the figure measures the
simulator only: a later change to a mission or the runtime does not change the path replayed.
``python -m bench.sim_replay --record`` renews them (after a change to the simulator's
behaviour, which the golden recordings would show), ``--check`` verifies them.

Used by ``bench/bench_sim.py`` (timings) and ``bench/icount.py`` (instructions per step).
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from roomba_bt.sim import Pose, Simulator, load_world

PATH = Path(__file__).resolve().parent / "data" / "sim_replay.json"
#: kind -> (mission, world, seed, evaluation fields): the episode kinds of bench_routines
EPISODES: dict[str, tuple[str, str, int, dict[str, Any]]] = {
    "dock": ("dock.yaml", "empty-room", 100, {"within_m": 1.5}),
    "bump": ("bump-and-turn.yaml", "corridor", 100, {"timeout_s": 90.0}),
}


class _Recorder(Simulator):
    """A simulator that keeps the host's bytes (with the step they came before) and a digest
    of its own."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        #: (step, "receive", the bytes in hex) or (step, "brc", low)
        self.inputs: list[tuple[int, str, str | bool]] = []
        self.digest = hashlib.sha256()

    def receive(self, data: bytes | bytearray) -> None:
        self.inputs.append((self.ticks, "receive", bytes(data).hex()))
        super().receive(data)

    def set_brc(self, low: bool) -> None:
        self.inputs.append((self.ticks, "brc", low))
        super().set_brc(low)

    def read(self) -> bytes:
        data = super().read()
        self.digest.update(data)
        return data


def record(kind: str) -> dict[str, Any]:
    """One episode of ``kind`` (:data:`EPISODES`), as the evaluation runs it, recorded."""
    from roomba_bt.evaluate import episode_specs
    from roomba_bt.evaluate.episode import build_world, start_pose
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import SimLink

    mission, world_name, seed, fields = EPISODES[kind]
    root = Path(__file__).resolve().parents[1]
    spec = episode_specs(str(root / "missions" / mission), world=world_name, runs=1, seed=seed,
                         **fields)[0]  # fmt: skip
    profile = get_profile(spec.profile)
    compiled = load_mission(
        spec.mission, dict(spec.params), profile=profile, permissions=spec.permissions
    )
    world = build_world(spec)
    pose = start_pose(world, spec)
    sim = _Recorder(world, profile, spec.seed, None, start=pose, coverage=True)
    RunStack(compiled, SimLink(sim), profile=profile, timeout_s=spec.timeout_s).run()
    sim.read()  # what is left unread counts in the digest too
    return {
        "world": world_name, "profile": spec.profile, "seed": spec.seed,
        "start": [pose.x, pose.y, pose.theta], "coverage": True, "steps": sim.ticks,
        "inputs": sim.inputs, "sha256": sim.digest.hexdigest(),
    }  # fmt: skip


def load(kind: str) -> dict[str, Any]:
    recordings: dict[str, dict[str, Any]] = json.loads(PATH.read_text(encoding="utf-8"))
    return recordings[kind]


#: one input to the robot: before which step, and the call that gives it
_Input = tuple[int, Callable[[Any], None], Any]


def _build(recording: dict[str, Any]) -> tuple[Simulator, list[_Input]]:
    from roomba_bt.oi.profiles import get_profile

    sim = Simulator(
        load_world(recording["world"]), get_profile(recording["profile"]), recording["seed"],
        start=Pose(*recording["start"]), coverage=recording["coverage"],
    )  # fmt: skip
    inputs: list[_Input] = [
        (tick, sim.receive, bytes.fromhex(arg)) if kind == "receive" else (tick, sim.set_brc, arg)
        for tick, kind, arg in recording["inputs"]
    ]
    inputs.append((recording["steps"] + 1, sim.receive, b""))  # a sentinel after the last step
    return sim, inputs


def prepare(kind: str) -> tuple[int, Callable[[], int]]:
    """The number of steps of the recording of ``kind`` and a function that replays it into
    a freshly built robot (built here: building is not stepping)."""
    recording = load(kind)
    sim, inputs = _build(recording)
    steps: int = recording["steps"]

    def run() -> int:
        step, read = sim.step, sim.read
        at = 0
        due = inputs[0][0]
        for tick in range(steps):
            while due == tick:
                _, give, arg = inputs[at]
                give(arg)
                at += 1
                due = inputs[at][0]
            step()
            read()
        return steps

    return steps, run


def sent(recording: dict[str, Any]) -> Iterator[bytes]:
    """What a freshly built robot sends each step of ``recording``, its inputs given at the
    steps they were recorded at."""
    sim, inputs = _build(recording)
    at = 0
    for tick in range(recording["steps"]):
        while inputs[at][0] == tick:
            _, give, arg = inputs[at]
            give(arg)
            at += 1
        sim.step()
        yield sim.read()


def check(kind: str) -> bool:
    """Does replaying the recording of ``kind`` give the bytes recorded?"""
    recording = load(kind)
    digest = hashlib.sha256()
    for data in sent(recording):
        digest.update(data)
    return bool(digest.hexdigest() == recording["sha256"])


def main(argv: list[str]) -> int:
    if argv == ["--record"]:
        PATH.parent.mkdir(exist_ok=True)
        recordings = {kind: record(kind) for kind in EPISODES}
        PATH.write_text(json.dumps(recordings, indent=1) + "\n", encoding="utf-8")
        for kind, found in recordings.items():
            print(f"{kind}: {found['steps']} steps, {len(found['inputs'])} writes")
        return 0
    if argv == ["--check"]:
        failed = [kind for kind in EPISODES if not check(kind)]
        print("replays give the recorded bytes" if not failed else f"differ: {failed}")
        return 1 if failed else 0
    print("usage: python -m bench.sim_replay --record | --check")
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
