"""Simulator speed as a multiple of real time, on one core (the simulator is single-threaded).

Real time is the baseline: one step is 15 ms of robot time, so ``15 ms / (host time per
step)`` is how many times faster than real time the simulator runs. Three cases, each the
best of several runs (the machine may be shared):

* stream and physics only, all sensors (group 100, 80 data bytes a frame): on the open floor
  (a circle in the middle of the empty room), and driving an arc from the default start, where
  the walls, the dock's plate and beams and the light bumpers are all in play;
* the same with a typical mission's packet list (bumps, IR, charging, mode, encoders);
* with a trivial client ticking: every frame is parsed by ``oi.StreamParser`` and answered
  with one Drive command, through :class:`~roomba_bt.sim.link.SimLink` (no behaviour tree);
* a robot moving as in an episode: the host bytes of a recorded dock and bump-and-turn
  episode replayed at the steps they came (``bench/sim_replay.py``), no mission running.

Times are CPU time of this process (one core), so that other work on a shared machine does
not count against the simulator.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from bench import sim_replay
from roomba_bt.oi import commands
from roomba_bt.oi.stream import StreamParser
from roomba_bt.sim import Pose, SimLink, Simulator, load_world
from roomba_bt.sim.robot import STEP_SECONDS

MISSION_PACKETS = [7, 17, 21, 34, 35, 43, 44, 45, 52, 53]
STEPS = 4000
REPEATS = 5


_WORLD = load_world("empty-room")


def _setup(packets: list[int], open_floor: bool = False) -> Simulator:
    """A fresh robot, streaming and driving (built before the clock starts: loading and
    building are not stepping)."""
    world = _WORLD
    # open floor: a 0.6 m circle in the middle of the room, away from walls and beams;
    # otherwise from the default start, 0.8 m from the dock: walls, dock plate and beams
    start = Pose(2000.0, 1750.0, 0.0) if open_floor else None
    sim = Simulator(world, start=start)
    sim.receive(
        commands.start().data
        + commands.full().data
        + commands.stream(packets).data
        + commands.drive(300, 600 if open_floor else 500).data
    )
    return sim


def _physics_only(packets: list[int], open_floor: bool = False) -> Callable[[], Callable[[], int]]:
    def prepare() -> Callable[[], int]:
        sim = _setup(packets, open_floor)  # a fresh robot each run: the same path each time

        def run() -> int:
            step, read = sim.step, sim.read
            for _ in range(STEPS):
                step()
                read()
            return STEPS

        return run

    return prepare


def _with_client() -> Callable[[], Callable[[], int]]:
    spin = commands.spin(200, clockwise=True).data
    arc = commands.drive(250, -300).data
    straight = commands.drive(250, commands.Radius.STRAIGHT).data

    def prepare() -> Callable[[], int]:
        sim = _setup(MISSION_PACKETS)
        link = SimLink(sim)
        parser = StreamParser(MISSION_PACKETS, sim.profile)
        return lambda: _client_loop(link, parser)

    def _client_loop(link: SimLink, parser: StreamParser) -> int:
        frames = 0
        while frames < STEPS:
            for frame in parser.feed(link.read(0.1)):
                frames += 1
                if frame.bumps.any_bump:
                    link.write(spin)
                elif frame.light_bumper.raw:
                    link.write(arc)
                else:
                    link.write(straight)
        return frames

    return prepare


def _best(prepare: Callable[[], Callable[[], int]]) -> float:
    """Best CPU seconds per step over REPEATS runs. CPU time of this process, not wall time:
    the development machine is shared, and wall time would measure the neighbours too.
    Each run starts from a freshly built robot; building it is not timed."""
    best = float("inf")
    for _ in range(REPEATS):
        run = prepare()
        started = time.process_time()
        steps = run()
        best = min(best, (time.process_time() - started) / steps)
    return best


def main() -> None:
    cases = [
        ("stream+physics, group 100, open floor", _physics_only([100], open_floor=True)),
        ("stream+physics, group 100 (80 B/frame)", _physics_only([100])),
        ("stream+physics, mission packets (27 B/frame)", _physics_only(MISSION_PACKETS)),
        ("with a trivial client (StreamParser + Drive/frame)", _with_client()),
        ("replay of a dock episode (empty room)", lambda: sim_replay.prepare("dock")[1]),
        ("replay of a bump-and-turn episode (corridor)", lambda: sim_replay.prepare("bump")[1]),
    ]
    for label, run in cases:
        per_step = _best(run)
        print(
            f"   {label:<50} {per_step * 1e6:7.1f} us/step  "
            f"{STEP_SECONDS / per_step:7.0f}x real time",
            flush=True,
        )


if __name__ == "__main__":
    main()
