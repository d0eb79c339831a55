"""Runtime benchmarks (issue 6): reaction latency over a pty, fixed cost per tick, shipped
mission ticks against bare py_trees, and memory over 10^6 ticks on the virtual clock.

Every figure is measured in this process, beside its baseline:

* reaction latency: a simulator subprocess on a real pty (`roomba-bt sim --pty`) bumps the
  robot every 150 ms (world timeline events); the mission drives forward and backs off while
  bumped. Latency = perf_counter when the read that completed the bump's second frame
  returned (the one that confirms it: robot/hazards.py; the reaction is one frame, 15 ms,
  after the first) -> perf_counter just before the write of the changed drive command.
  Targets: p99 <= 1 ms.
* fixed cost per tick: the runner on pre-built frames delivered instantly (no simulator, no
  port): read + parse + mode model + snapshot + blackboard + flush, minus the tick of a
  one-leaf tree measured alone. Target <= 60 us.
* shipped missions: tick of the compiled tree against the same shape built from py_trees'
  own do-nothing behaviours, same frames: the share of the tick that is our leaves' work.
  The like-for-like target (compiled tree <= 1.15x the same tree built by hand in py_trees,
  same leaves) is measured by bench_mission.
* ``ticks()`` against ``run()``: a tick of a run stepped by the program's own loop over the
  run's (a worker thread's hand-off each tick), the same minute of bump-and-turn on the
  virtual clock; a ratio. ``python -m bench.bench_runtime ticks`` prints it alone.
* memory: RSS after 10^5 .. 10^6 ticks of a mission on the virtual clock (about 4 h of robot
  time); the simulator's trajectory trace is cleared as it goes, since it is the simulator's
  record, not the runtime's.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees

from roomba_bt.mission import RUNTIME_PACKETS, load_mission
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.oi.stream import StreamParser
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.testing import StubRobot
from roomba_bt.runtime.loop import MissionRunner, stream_request
from roomba_bt.transport.testing import NullTransport

if TYPE_CHECKING:
    from roomba_bt.sim import Simulator

ROOT = Path(__file__).resolve().parents[1]

REACTIVE = """
mission: bench-reaction
tree:
  sequence:
    - mode: safe
    - selector:
        memory: false
        children:
          - sequence:
              memory: false
              children:
                - bump: {}
                - drive: {velocity: -100 mm/s}
          - drive: {velocity: 100 mm/s}
"""


def _write(tmp: Path, name: str, text: str) -> Path:
    path = tmp / name
    path.write_text(textwrap.dedent(text))
    return path


class TimingTransport:
    """Wraps a transport; stamps every read (after it returns) and write (before it)."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.name = inner.name
        self.reads: list[tuple[float, bytes]] = []
        self.writes: list[tuple[float, bytes]] = []

    def read(self, timeout: float) -> bytes:
        data: bytes = self.inner.read(timeout)
        if data:
            self.reads.append((time.perf_counter(), data))
        return data

    def write(self, data: bytes) -> None:
        self.writes.append((time.perf_counter(), bytes(data)))
        self.inner.write(data)

    def set_baud(self, baud: int) -> None:
        self.inner.set_baud(baud)

    def close(self) -> None:
        self.inner.close()

    @property
    def is_open(self) -> bool:
        return bool(self.inner.is_open)

    def now(self) -> float:
        return float(self.inner.now())


def reaction_latency(tmp: Path, seconds: float = 15.0) -> list[float]:
    period, bumped = 0.15, 0.06
    events = "\n".join(
        f"  - {{at: {1.0 + i * period:.3f}, kind: bump, side: left, duration: {bumped}}}"
        for i in range(int((seconds - 1.5) / period))
    )
    world = _write(
        tmp,
        "bump-world.yaml",
        "name: bump-bench\nrooms:\n  - [[0, 0], [20, 0], [20, 20], [0, 20]]\n"
        "dock: {at: [10, 0], facing: 90}\n"
        "robot: {start: {at: [10, 10], heading: 0}}\n"
        f"events:\n{events}\n",
    )
    mission = load_mission(_write(tmp, "reaction.yaml", REACTIVE))
    sim = subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", "sim", "--pty", "--world", str(world)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert sim.stdout is not None
        port = sim.stdout.readline().strip()
        connection = Connection.open(port, 115200, CREATE2)
        tap = TimingTransport(connection.transport)
        connection.transport = tap
        packets = stream_request(mission.packets, 115200)
        runner = MissionRunner(connection, mission, profile=CREATE2, packets=packets,
                               timeout_s=seconds)  # fmt: skip
        runner.run()
        connection.close()
    finally:
        sim.terminate()
        sim.wait(timeout=5)
        if sim.stdout is not None:
            sim.stdout.close()
    parser = StreamParser(packets)
    latencies: list[float] = []
    writes = tap.writes
    w = 0
    streak = 0
    for t_read, data in tap.reads:
        for frame in parser.feed(data):
            streak = streak + 1 if frame[7] & 0b11 else 0
            if streak == 2:  # the bump's second frame confirms it: the tree sees it here
                while w < len(writes) and writes[w][0] < t_read:
                    w += 1
                if w < len(writes) and writes[w][1][:1] == bytes((137,)):
                    latencies.append(writes[w][0] - t_read)
    return latencies


class InstantFrames(NullTransport):
    """A transport that answers the start-up handshake and then hands out pre-built stream
    frames instantly, one per read, on a clock that advances 15 ms per frame."""

    name = "instant"

    def __init__(self, packets: tuple[int, ...], count: int) -> None:
        super().__init__()
        layout = layout_for(packets, CREATE2, True)
        values = {p: 0 for p in range(7, 59)}
        values[35] = 1
        values[26] = 2696
        values[25] = 2000
        self.frame = layout.stream_frame(values)
        self.count = count
        self._pending = bytearray()
        self.sent = 0

    def write(self, data: bytes) -> None:
        if data[:1] == bytes((149,)):
            self._pending += bytes((1,))  # Query List for packet 35: Passive
        if data[:1] == bytes((148,)):
            self.sent = 0

    def read(self, timeout: float) -> bytes:
        if self._pending:
            out = bytes(self._pending)
            self._pending.clear()
            return out
        if self.sent >= self.count:
            self.clock += timeout
            return b""
        self.sent += 1
        self.clock += 0.015
        return self.frame


class _OneLeaf:
    name = "one-leaf"

    def __init__(self) -> None:
        self.root = py_trees.behaviours.Running(name="running")

    @property
    def packets(self) -> tuple[int, ...]:
        return ()

    def setup(self, robot: Any) -> None:
        self.root.setup_with_descendants()


def fixed_cost(ticks: int = 20000) -> tuple[float, float]:
    """(runner cost per tick, one-leaf tick alone), seconds."""
    packets = tuple(sorted(RUNTIME_PACKETS))
    transport = InstantFrames(packets, ticks)
    connection = Connection(transport, CREATE2, watchdog=0.0)
    mission = _OneLeaf()

    def ended() -> str | None:
        return "done" if transport.sent >= ticks else None

    runner = MissionRunner(connection, mission, profile=CREATE2, packets=packets,
                           timeout_s=ticks * 0.015 + 1, input_ended=ended)  # fmt: skip
    started = time.perf_counter()
    summary = runner.run()
    total = time.perf_counter() - started
    leaf = py_trees.behaviours.Running(name="alone")
    t0 = time.perf_counter()
    for _ in range(ticks):
        leaf.tick_once()
    alone = (time.perf_counter() - t0) / ticks
    return total / max(summary.ticks, 1), alone


def _bare_clone(node: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    """The same shape in py_trees' own classes: composites kept, leaves replaced by dummies
    returning what the compiled leaf returned on this tick is not knowable in advance, so
    every leaf is a Running dummy and composites keep their memory flags."""
    if isinstance(node, py_trees.composites.Sequence):
        clone: py_trees.behaviour.Behaviour = py_trees.composites.Sequence(
            node.name, memory=node.memory
        )
    elif isinstance(node, py_trees.composites.Selector):
        clone = py_trees.composites.Selector(node.name, memory=node.memory)
    elif isinstance(node, py_trees.composites.Parallel):
        clone = py_trees.composites.Parallel(node.name, policy=node.policy)
    elif isinstance(node, py_trees.decorators.Decorator):
        return py_trees.decorators.PassThrough(name=node.name, child=_bare_clone(node.decorated))
    elif node.children:
        clone = py_trees.composites.Sequence(node.name, memory=False)
    else:
        return py_trees.behaviours.Running(name=node.name)
    for child in node.children:
        clone.add_child(_bare_clone(child))  # type: ignore[attr-defined]
    return clone


def mission_ticks(paths: list[Path], ticks: int = 3000) -> list[tuple[str, float, float]]:
    rows = []
    for path in paths:
        try:
            mission = load_mission(path)
        except Exception as exc:  # a mission that does not compile is reported, not fatal
            rows.append((f"{path.name} (does not compile: {exc})", float("nan"), float("nan")))
            continue
        stub = StubRobot(CREATE2)
        mission.setup(stub)
        values = {p: 0 for p in sorted(set(mission.packets) | set(RUNTIME_PACKETS))}
        values[35] = 2
        values[26] = 2696
        values[25] = 2000
        root = mission.root
        t0 = time.perf_counter()
        for _ in range(ticks):
            stub.set_frame(values)
            root.tick_once()
            stub.outbox.clear()
        compiled = (time.perf_counter() - t0) / ticks
        bare = _bare_clone(root)
        bare.setup_with_descendants()
        t0 = time.perf_counter()
        for _ in range(ticks):
            stub.set_frame(values)
            bare.tick_once()
        baseline = (time.perf_counter() - t0) / ticks
        rows.append((path.name, compiled, baseline))
    return rows


def tick_guard_cost(calls: int = 200_000) -> tuple[float, float]:
    """Seconds a call of a do-nothing tick, bare and through the tick guard (wall-clock runs
    only: the port's lock given up and taken back around the tick, the tick's start noted);
    medians of 7 timings. The guard's thread is running, as in a run."""
    from unittest import mock

    from roomba_bt.runtime.tick_guard import TickGuard

    def tick() -> None:
        pass

    guard = TickGuard(mock.Mock(), 0.25)
    guard.start()
    try:
        guarded = guard.guarded(tick, lambda seconds, where, halted, cycle: None, lambda: 0)
        bare = statistics.median(timeit.timeit(tick, number=calls) for _ in range(7))
        watched = statistics.median(timeit.timeit(guarded, number=calls) for _ in range(7))
    finally:
        guard.close()
    return bare / calls, watched / calls


def _rss_mb() -> float:
    with open(f"/proc/{os.getpid()}/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def memory_observer(
    sim: Simulator, every: int
) -> tuple[Callable[[MissionRunner], None], list[tuple[int, float]]]:
    """A runner observer that samples this process's resident memory every ``every`` ticks
    (as (ticks, MB) into the list returned with it) and empties the simulator's trace and
    events every 10,000 ticks, so that they do not count as a leak of the runtime."""
    samples: list[tuple[int, float]] = []

    def observe(runner: MissionRunner) -> None:
        ticks_done = runner.summary.ticks
        if ticks_done % 10_000 == 0:
            sim.trace.clear()
            sim.events.clear()
        if ticks_done % every == 0:
            samples.append((ticks_done, _rss_mb()))

    return observe, samples


def memory_run(tmp: Path, ticks: int = 1_000_000) -> list[tuple[int, float]]:
    from roomba_bt.sim import SimLink, Simulator, load_world

    # Back and forth and round, in place: commands every few ticks, never near the dock.
    mission = load_mission(_write(tmp, "long.yaml", """
        mission: four-hours
        tree:
          sequence:
            - mode: safe
            - repeat:
                do:
                  sequence:
                    - drive: {velocity: 200 mm/s, distance: 100 mm}
                    - drive: {velocity: -200 mm/s, distance: 100 mm}
                    - turn: {angle: 90deg}
        """))  # fmt: skip
    sim = Simulator(load_world("empty-room"), CREATE2, 0)
    link = SimLink(sim)
    connection = Connection(link, CREATE2, watchdog=0.0)
    observe, samples = memory_observer(sim, 100_000)
    packets = stream_request(mission.packets, 115200)
    runner = MissionRunner(connection, mission, profile=CREATE2, packets=packets,
                           timeout_s=ticks * 0.015, observer=observe)  # fmt: skip
    summary = runner.run()
    samples.append((-1, summary.distance_mm))
    samples.append((-2, float(summary.commands_written)))
    samples.append((-3, float(summary.refused_commands)))
    return samples


def memory_episodes(episodes: int = 1000) -> list[tuple[int, float]]:
    """RSS (MB) after so many episodes of the shipped ``dock`` mission, each a ``with
    RunStack(...)`` on a simulator of its own (a random start, a seed each), as a program
    that runs thousands in one process has them: a finished run's connection, simulator and
    tree must be freed (each one kept alive costs 105-140 KB an episode).
    Sampled after a collector pass at the first episode and every tenth of the rest."""
    import gc

    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import SimLink, Simulator, load_world

    world = load_world("empty-room")
    samples: list[tuple[int, float]] = []
    every = max(1, episodes // 10)
    for episode in range(1, episodes + 1):
        mission = load_mission("dock", profile=CREATE2)
        sim = Simulator(world, CREATE2, seed=episode, trace=False, random_start=True)
        with RunStack(mission, SimLink(sim), profile=CREATE2, timeout_s=60.0) as stack:
            stack.run(raise_interrupts=False)
        if episode == 1 or episode % every == 0:
            gc.collect()
            samples.append((episode, _rss_mb()))
    return samples


def ticks_against_run(runs: int = 7) -> tuple[float, float, int]:
    """CPU seconds (the process's, both threads) a tick of ``stack.run()`` and of ``for tick
    in stack.ticks():`` (an empty loop body), the same bump-and-turn minute on the
    simulator's virtual clock, and the ticks of one run; medians of ``runs`` runs of each,
    taken in turn. CPU, not wall, time: on a shared machine the wall time of the same runs
    went from 0.65x to 2.1x. What a program
    that steps a run itself (a gym-like env's ``step()``) pays: ``ticks()`` runs the tree
    in a worker thread and hands each tick over to the loop and back (an embedder measured
    about 2-4x, asked for the figure). The simulator's step is in both."""
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import SimLink, Simulator, load_world

    world = load_world("empty-room")

    def one(stepped: bool) -> tuple[float, int]:
        mission = load_mission("bump-and-turn", profile=CREATE2)
        sim = Simulator(world, CREATE2, seed=1, trace=False)
        with RunStack(mission, SimLink(sim), profile=CREATE2, timeout_s=120.0) as stack:
            started = time.process_time()
            if stepped:
                for _ in stack.ticks():
                    continue
            else:
                stack.run(raise_interrupts=False)
            took = time.process_time() - started
        return took, stack.summary.ticks

    by_run, by_ticks = [], []
    for _ in range(runs):
        by_run.append(one(stepped=False))
        by_ticks.append(one(stepped=True))
    ticks = by_run[0][1]
    if any(n != ticks for _, n in by_run + by_ticks):  # then no ratio of the same work
        raise RuntimeError(f"run() and ticks() ran other ticks: {by_run + by_ticks}")
    per_run = statistics.median(t for t, _ in by_run) / ticks
    per_ticks = statistics.median(t for t, _ in by_ticks) / ticks
    return per_run, per_ticks, ticks


def print_ticks_against_run(runs: int) -> None:
    """The line of :func:`ticks_against_run`, a ratio first."""
    per_run, per_ticks, ticks = ticks_against_run(runs)
    print(
        f"   stack.ticks() against stack.run(), {ticks} ticks of bump-and-turn on the virtual "
        f"clock, simulator included: {per_ticks / per_run:.2f}x ({per_ticks * 1e6:.1f} us of CPU "
        f"a tick against {per_run * 1e6:.1f} us; medians of {runs} runs each)"
    )


def main() -> None:
    quick = os.environ.get("BENCH_QUICK") == "1"
    if sys.argv[1:] == ["ticks"]:  # python -m bench.bench_runtime ticks: that figure alone
        print_ticks_against_run(3 if quick else 7)
        return
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        lat = reaction_latency(tmp, 6.0 if quick else 15.0)
        if lat:
            lat_sorted = sorted(lat)
            p99 = lat_sorted[min(len(lat_sorted) - 1, int(0.99 * len(lat_sorted)))]
            print(
                f"   reaction latency over a pty (confirming bump frame read -> new drive "
                "written), "
                f"{len(lat)} bumps: median {statistics.median(lat) * 1e3:.3f} ms, "
                f"p99 {p99 * 1e3:.3f} ms, max {lat_sorted[-1] * 1e3:.3f} ms (target p99 <= 1 ms)"
            )
        else:
            print("   reaction latency: no bump reactions observed (FAILED to measure)")
        per_tick, alone = fixed_cost(5000 if quick else 20000)
        print(
            f"   fixed runtime cost per tick (read+parse+mode+snapshot+blackboard+flush): "
            f"{(per_tick - alone) * 1e6:.1f} us (a one-leaf tick alone: {alone * 1e6:.1f} us; "
            f"target <= 60 us)"
        )
        bare_call, guarded_call = tick_guard_cost(50_000 if quick else 200_000)
        print(
            f"   tick guard (runs on the wall clock): {(guarded_call - bare_call) * 1e9:.0f} ns "
            f"a tick ({bare_call * 1e9:.0f} ns a bare call, {guarded_call * 1e9:.0f} ns "
            "guarded); none on the virtual clock"
        )
        shipped = sorted((ROOT / "missions").glob("*.yaml"))
        for name, compiled, bare in mission_ticks(shipped, 500 if quick else 3000):
            if compiled != compiled:
                print(f"   {name}")
                continue
            print(
                f"   tick {name}: compiled {compiled * 1e6:.1f} us; the same shape in bare "
                f"py_trees with do-nothing leaves {bare * 1e6:.1f} us ({compiled / bare:.2f}x: "
                f"the difference is the leaves' own work)"
            )
        print_ticks_against_run(3 if quick else 7)
        samples = memory_run(tmp, 200_000 if quick else 1_000_000)
        extra = {t: v for t, v in samples if t < 0}
        samples = [(t, v) for t, v in samples if t >= 0]
        print(f"   long run: {extra[-1] / 1000:.0f} m driven, {extra[-2]:.0f} commands written, "
              f"{extra[-3]:.0f} refused")  # fmt: skip
        if samples:
            first, last = samples[0][1], samples[-1][1]
            trail = ", ".join(f"{t // 1000}k: {mb:.1f} MB" for t, mb in samples)
            print(f"   RSS over {samples[-1][0]:,} ticks: {trail}; growth after the first "
                  f"100k ticks {last - first:+.1f} MB")  # fmt: skip
        episodes = memory_episodes(200 if quick else 1000)
        (first_at, first), (last_at, last) = episodes[min(1, len(episodes) - 1)], episodes[-1]
        trail = ", ".join(f"{n}: {mb:.1f} MB" for n, mb in episodes)
        grown = (last - first) * 1024 / max(1, last_at - first_at)
        print(f"   RSS over {last_at} dock episodes in one process (with RunStack, "
              f"random start): {trail}; {grown:+.1f} KB an episode after episode {first_at} "
              "(target: flat; 105-140 KB where each run is kept)")  # fmt: skip


if __name__ == "__main__":
    main()
