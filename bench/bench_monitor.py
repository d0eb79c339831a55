"""The live monitor's cost to the run (issue 17): the same runs with and without it.

Both arms run in this process in alternating blocks (ABBA: without, with, with, without, ...)
so that the machine's load and its drift weigh on both alike; each block's p99 is printed
beside the pooled figures, so a block disturbed by other work shows as such.

* tick time: the dock mission in the apartment on the simulator paced to the wall clock (one
  frame per 15 ms, as on a robot, so the server's thread works while the tick thread waits
  for the next frame, as it would). Tick time = the runtime's own measure: from the frame's
  snapshot to the end of the flush (with the monitor, its ``before_tick`` is inside it);
  "+ record" adds the monitor's ``after_tick`` (the feed's append), which runs after the
  flush, like the terminal display. With the monitor: its server on 127.0.0.1 and one page,
  a WebSocket client reading every update in a process of its own as a browser is (a client
  thread in this process would take the tick thread's GIL, which no browser does). Target:
  p99 at most 1.10x without it. Beside it, where the slow ticks went: each arm's ticks above
  the p99 without the monitor, split into the tick thread's own CPU time and its time off
  the CPU (waiting for the GIL or for a core), and counted with a collection of the cyclic
  collector inside the tick (``gc.callbacks``) or the server thread running meanwhile (its
  CPU clock moved); the tick thread's CPU time a tick (preemption and GIL waits left out);
  the collections a second of each arm and the server thread's CPU a second.
* reaction latency: as ``bench_runtime`` measures it (a simulator subprocess on a pty bumps
  the robot every 150 ms; bump frame read -> new drive written), with and without the
  monitor and a page. "Unchanged": p99 with it at most 1.2x, or 0.2 ms above, p99 without
  it (two blocks of the same arm differ by more on a loaded 2-core machine). With the
  monitor a few bumps fall while the server and the page start, before the run reads.
* memory: RSS over 10^5 ticks on the virtual clock with the monitor and a page, sampled every
  20 000 ticks: flat once the feed's ring (20 000 ticks) is full.

``BENCH_QUICK=1``: 2 blocks of 5 s per arm instead of 4 of 15 s, shorter latency blocks.

``python -m bench.bench_monitor designs [SECONDS [BLOCKS [NAME,...]]]`` runs the tick-time
measure for the designs weighed against the p99 excess (:data:`DESIGNS`: the switch interval
lowered or raised while the monitor serves, a slower pump, the feed without the server, the
server without a page) in turn in each block, each with the attribution lines.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from roomba_bt.mission import load_mission
from roomba_bt.monitor import pump as pump_module
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.runtime.loop import MissionRunner, stream_request
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, load_world

from . import bench_runtime

ROOT = Path(__file__).resolve().parents[1]


class TimedRunner(MissionRunner):
    """Stamps each tick: snapshot start -> end of flush, and -> end of the gate's after_tick.

    Beside the wall time, each tick's share of the answer to "where did a slow tick go": the
    tick thread's own CPU time (off-CPU = wall - CPU: the thread waited, for the GIL or for a
    core), and the CPU clock of the thread that could take the GIL from it (the monitor's
    server; without the monitor this thread's own clock, so both arms read two clocks a tick).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.tick_s: list[float] = []
        self.cpu_s: list[float] = []
        self.rival_ran: list[bool] = []  # the server thread used CPU during the tick
        self.starts: list[float] = []
        self.with_record_s: list[float] = []
        self.rival_clock = time.CLOCK_THREAD_CPUTIME_ID
        self._started = self._cpu = self._rival = 0.0

    def _advance(self, batch: Sequence[SensorFrame], untick: int | None = None) -> float:
        self._rival = time.clock_gettime(self.rival_clock)
        self._cpu = time.thread_time()
        self._started = time.perf_counter()
        return super()._advance(batch, untick)

    def _flush(self) -> None:
        super()._flush()
        ended = time.perf_counter()
        self.cpu_s.append(time.thread_time() - self._cpu)
        rival = time.clock_gettime(self.rival_clock)
        self.tick_s.append(ended - self._started)
        self.starts.append(self._started)
        self.rival_ran.append(self.rival_clock != time.CLOCK_THREAD_CPUTIME_ID
                              and rival > self._rival)  # fmt: skip


class Collections:
    """The cyclic collector's runs (``gc.callbacks``): when, how long, which generation, in
    which thread."""

    def __init__(self) -> None:
        self.runs: list[tuple[float, float, int, int]] = []  # start, end, generation, thread
        self._open: dict[int, float] = {}

    def __call__(self, phase: str, info: dict[str, Any]) -> None:
        thread = threading.get_ident()
        if phase == "start":
            self._open[thread] = time.perf_counter()
        elif thread in self._open:
            start = self._open.pop(thread)
            self.runs.append((start, time.perf_counter(), int(info["generation"]), thread))

    @contextlib.contextmanager
    def watching(self) -> Iterator[Collections]:
        gc.callbacks.append(self)
        try:
            yield self
        finally:
            gc.callbacks.remove(self)

    def inside(self, starts: list[float], ticks: list[float], thread: int) -> list[bool]:
        """For each tick: did a collection run in ``thread`` during it?"""
        runs = sorted(r for r in self.runs if r[3] == thread)
        out, j = [], 0
        for start, length in zip(starts, ticks, strict=True):
            while j < len(runs) and runs[j][1] < start:
                j += 1
            out.append(j < len(runs) and runs[j][0] < start + length)
        return out


@dataclass
class Block:
    """One paced run: its ticks, and what each slow one may be blamed on."""

    tick_s: list[float]
    cpu_s: list[float]
    record_s: list[float]
    rival_ran: list[bool]
    collected: list[bool]
    collections: list[tuple[float, float, int, int]]
    seconds: float
    messages: int = 0
    server_cpu_s: float = 0.0


class TimedSession(MonitorSession):
    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        if isinstance(runner, TimedRunner):
            runner.with_record_s.append(time.perf_counter() - runner._started)


class Page:
    """A page: a WebSocket client in a process of its own, as a browser is, reading every
    update (a client thread in this process would share the tick thread's GIL, which no
    browser does). Started by ``python -m bench.bench_monitor page URL``."""

    def __init__(self, url: str) -> None:
        ws_url = url.replace("http://", "ws://").rstrip("/") + "/ws"
        self.messages = 0
        self._process = subprocess.Popen(
            [sys.executable, "-m", "bench.bench_monitor", "page", ws_url],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self._process.stdout is not None
        ready = self._process.stdout.readline().strip()  # after the server's hello
        if ready != "ready":
            raise RuntimeError(f"the page did not connect to {ws_url}: {ready!r}")

    def close(self) -> None:
        """After the server closed the socket: the page prints how many updates it read."""
        out, _ = self._process.communicate(timeout=10)
        self.messages = int(out.split()[-1]) if out.split() else 0


async def _read_page(url: str) -> None:
    import aiohttp

    messages = 0
    async with aiohttp.ClientSession() as session, session.ws_connect(url) as ws:
        async for message in ws:
            if message.type is not aiohttp.WSMsgType.TEXT:
                break
            if messages == 0:
                print("ready", flush=True)
            messages += 1
    print(messages - 1, flush=True)  # updates, the hello not counted


@contextlib.contextmanager
def monitored(
    feed: RunFeed, session: MonitorSession, page: bool = True
) -> Iterator[tuple[Page | None, MonitorServer]]:
    server = MonitorServer(feed, session, port=0)
    url = server.start()
    reader = Page(url) if page else None
    try:
        yield reader, server
    finally:
        server.close()
        if reader is not None:
            reader.close()


def _monitor_for(
    mission: Any, simulator: Simulator | None, history: int | None = 20_000
) -> tuple[RunFeed, MonitorSession]:
    truth = None
    if simulator is not None:

        def truth() -> tuple[float, float, float]:
            return (simulator.x, simulator.y, simulator.theta)

    feed = RunFeed(history=history, truth=truth, mission_name=mission.name)
    feed.set_tree(mission.root)
    return feed, TimedSession(feed, simulator=simulator is not None)


#: The designs ``python -m bench.bench_monitor designs`` compares (docs/monitor.md).
DESIGNS = {
    "without": "no monitor",
    "monitor": "the monitor and a page, as shipped",
    "feed-only": "the feed and the tick gate, no server (the hook's own cost)",
    "no-page": "the monitor's server, no page connected",
    "switch-0.5ms": "the monitor and a page, sys.setswitchinterval(0.0005) while it serves",
    "switch-50ms": "the monitor and a page, sys.setswitchinterval(0.05) while it serves",
    "poll-10ms": "the monitor and a page, the pump looking for a tick's end every 10 ms",
}


@contextlib.contextmanager
def _variant(design: str) -> Iterator[None]:
    """The process-wide settings a design changes, restored after its block."""
    interval, poll = sys.getswitchinterval(), pump_module.TICK_POLL_S
    if design.startswith("switch-"):
        sys.setswitchinterval(float(design.removeprefix("switch-").removesuffix("ms")) / 1e3)
    if design == "poll-10ms":
        pump_module.TICK_POLL_S = 0.010
    try:
        yield
    finally:
        sys.setswitchinterval(interval)
        pump_module.TICK_POLL_S = poll


def paced_dock(seconds: float, monitor: bool, design: str | None = None) -> Block:
    design = design or ("monitor" if monitor else "without")
    mission = load_mission(ROOT / "missions" / "dock.yaml", {}, profile=CREATE2)
    simulator = Simulator(load_world("apartment"), CREATE2, 3)
    connection = Connection(RealtimeSimLink(simulator), CREATE2)
    packets = stream_request(mission.packets, 115200)
    runner = TimedRunner(connection, mission, profile=CREATE2, packets=packets, timeout_s=seconds)
    messages, server_cpu = 0, 0.0
    with Collections().watching() as collections, _variant(design):
        if design == "without":
            runner.run()
        else:
            feed, session = _monitor_for(mission, simulator)
            runner.gate = session
            if design == "feed-only":
                runner.run()
            else:
                with monitored(feed, session, page=design != "no-page") as (page, server):
                    thread = server._thread
                    assert thread is not None and thread.ident is not None
                    runner.rival_clock = time.pthread_getcpuclockid(thread.ident)
                    before = time.clock_gettime(runner.rival_clock)
                    runner.run()
                    server_cpu = time.clock_gettime(runner.rival_clock) - before
                messages = page.messages if page is not None else 0
    inside = collections.inside(runner.starts, runner.tick_s, threading.get_ident())
    first, last = runner.starts[0], runner.starts[-1] + runner.tick_s[-1]
    during = [r for r in collections.runs if first <= r[0] <= last]  # not the server's start
    return Block(
        runner.tick_s, runner.cpu_s, runner.with_record_s if design != "without" else runner.tick_s,
        runner.rival_ran, inside, during, seconds, messages, server_cpu,
    )  # fmt: skip


def designs(seconds: float, blocks: int, names: Sequence[str]) -> None:
    """Each design against no monitor, all in turn in each block (the order reversed every
    other block), with the same attribution lines as the tick-time measure."""
    runs: dict[str, list[Block]] = {name: [] for name in names}
    for i in range(blocks):
        for name in names if i % 2 == 0 else list(reversed(names)):
            runs[name].append(paced_dock(seconds, name != "without", name))
    base = [t for b in runs["without"] for t in b.tick_s] if "without" in runs else []
    threshold = _p(base, 0.99) if base else 0.0
    print(f"   dock/apartment paced, {blocks} blocks of {seconds:.0f} s per design, in turn:")
    for name in names:
        ticks = [t for b in runs[name] for t in b.tick_s]
        cpu = [c for b in runs[name] for c in b.cpu_s]
        each = ", ".join(f"{_p(b.tick_s, 0.99) * 1e6:.0f}" for b in runs[name])
        ratio = f" ({_p(ticks, 0.99) / threshold:.2f}x)" if threshold else ""
        server = sum(b.server_cpu_s for b in runs[name]) / (blocks * seconds)
        print(f"   {name}: {DESIGNS[name]}")
        print(f"      tick median {statistics.median(ticks) * 1e6:.0f} us, p99 "
              f"{_p(ticks, 0.99) * 1e6:.0f} us{ratio} (per block: {each}); CPU time a tick "
              f"median {statistics.median(cpu) * 1e6:.0f} us, p99 {_p(cpu, 0.99) * 1e6:.0f} us; "
              f"server CPU {server * 1e3:.1f} ms/s")  # fmt: skip
        overlapped = sum(sum(b.rival_ran) for b in runs[name])
        print(f"      collections {_collections(runs[name])}; the server thread ran during "
              f"{overlapped} of {len(ticks)} ticks")  # fmt: skip
        if threshold:
            print(f"      above the p99 without: {_blame(runs[name], threshold)}")


def _p(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def latency(tmp: Path, seconds: float, monitor: bool) -> list[float]:
    """bench_runtime.reaction_latency, its runner given the monitor and a page when asked."""
    if not monitor:
        return bench_runtime.reaction_latency(tmp, seconds)
    pages: list[Any] = []

    class MonitoredRunner(MissionRunner):
        def __init__(self, connection: Any, mission: Any, **kwargs: Any) -> None:
            super().__init__(connection, mission, **kwargs)
            feed, session = _monitor_for(mission, None)
            self.gate = session
            context = monitored(feed, session)
            context.__enter__()
            pages.append(context)

    # bench_runtime builds its runner inside reaction_latency: hand it this one for the run
    original = bench_runtime.__dict__["MissionRunner"]
    bench_runtime.__dict__["MissionRunner"] = MonitoredRunner
    try:
        return bench_runtime.reaction_latency(tmp, seconds)
    finally:
        bench_runtime.__dict__["MissionRunner"] = original
        for context in pages:
            context.__exit__(None, None, None)


def memory(ticks: int) -> list[tuple[int, float]]:
    mission = load_mission(ROOT / "tests" / "monitor" / "missions" / "shuttle.yaml", {},
                           profile=CREATE2)  # fmt: skip
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    connection = Connection(SimLink(simulator), CREATE2, watchdog=0.0)
    packets = stream_request(mission.packets, 115200)
    observe, samples = bench_runtime.memory_observer(simulator, 20_000)
    runner = MissionRunner(connection, mission, profile=CREATE2, packets=packets,
                           timeout_s=ticks * 0.015, observer=observe)  # fmt: skip
    feed, session = _monitor_for(mission, simulator)
    runner.gate = session
    with monitored(feed, session):
        runner.run()
    return samples


def _arms(blocks: int) -> Iterator[bool]:
    """Without and with the monitor in alternating blocks, ABBA, so that the machine's load
    and its drift weigh on both arms alike."""
    for i in range(blocks):
        yield from (False, True) if i % 2 == 0 else (True, False)


def _ms(values: list[float], q: float) -> str:
    return f"{_p(values, q) * 1e3:.3f}"


#: "Reaction latency unchanged": p99 with the monitor within 1.2x of, or 0.2 ms above, p99
#: without it (what separates two runs of the same arm on a loaded 2-core machine).
LATENCY_RATIO, LATENCY_SLACK_S = 1.2, 0.2e-3


def _blame(blocks: list[Block], above: float) -> str:
    """What the ticks slower than ``above`` had: off-CPU time (a wait for the GIL or a core),
    a collection in the tick thread during the tick, the server thread running meanwhile."""
    slow = [
        (t, c, r, g)
        for b in blocks
        for t, c, r, g in zip(b.tick_s, b.cpu_s, b.rival_ran, b.collected, strict=True)
        if t > above
    ]
    if not slow:
        return "none"
    off = statistics.mean(t - c for t, c, _, _ in slow) * 1e6
    waited = sum(1 for t, c, _, _ in slow if t - c > 100e-6)
    return (f"{len(slow)}: mean {statistics.mean(t for t, _, _, _ in slow) * 1e6:.0f} us of which "
            f"off-CPU {off:.0f} us; off-CPU > 100 us in {waited}, a collection in the tick in "
            f"{sum(1 for *_, g in slow if g)}, the server thread ran during "
            f"{sum(1 for _, _, r, _ in slow if r)}")  # fmt: skip


def _collections(blocks: list[Block]) -> str:
    seconds = sum(b.seconds for b in blocks)
    main_thread = threading.get_ident()
    out = []
    for generation in (0, 1, 2):
        runs = [r for b in blocks for r in b.collections if r[2] == generation]
        if runs:
            here = sum(1 for r in runs if r[3] == main_thread)
            longest = max(r[1] - r[0] for r in runs) * 1e3
            out.append(f"gen{generation} {len(runs) / seconds:.2f}/s ({here} in the tick "
                       f"thread, longest {longest:.1f} ms)")  # fmt: skip
    inside = sum(sum(b.collected) for b in blocks)
    return f"{', '.join(out) or 'none'}; during a tick: {inside}"


def tick_time(blocks: int, seconds: float) -> None:
    runs: dict[bool, list[Block]] = {False: [], True: []}
    for monitor in _arms(blocks):
        runs[monitor].append(paced_dock(seconds, monitor))
    base = [t for b in runs[False] for t in b.tick_s]
    watched = [t for b in runs[True] for t in b.tick_s]
    with_record = [t for b in runs[True] for t in b.record_s]
    print(f"   dock/apartment paced, {blocks} blocks of {seconds:.0f} s per arm, alternating:")
    for label, values in (("without the monitor", base), ("with the monitor + a page", watched),
                          ("... + the feed's record", with_record)):  # fmt: skip
        median, p99 = statistics.median(values) * 1e6, _p(values, 0.99) * 1e6
        print(f"   {len(values)} ticks {label}: median {median:.0f} us, p99 {p99:.0f} us")
    block_p99 = {m: [_p(b.tick_s, 0.99) for b in runs[m]] for m in (False, True)}
    for monitor, label in ((False, "without"), (True, "with")):
        each = ", ".join(f"{v * 1e6:.0f}" for v in block_p99[monitor])
        print(f"   p99 per block {label}: {each} us")
    paired = statistics.median(
        w / b for w, b in zip(block_p99[True], block_p99[False], strict=True)
    )
    print(f"   p99 ratio of each block with to the block beside it without, median: {paired:.2f}x "
          "(a block disturbed by other work on the machine weighs less)")  # fmt: skip
    for monitor, label in ((False, "without"), (True, "with")):
        cpu = [c for b in runs[monitor] for c in b.cpu_s]
        median = statistics.median(cpu) * 1e6
        p99 = _p(cpu, 0.99) * 1e6
        print(f"   {label}: the tick thread's CPU time a tick, median {median:.0f} us, p99 "
              f"{p99:.0f} us; collections {_collections(runs[monitor])}")  # fmt: skip
    threshold = _p(base, 0.99)
    for monitor, label in ((False, "without"), (True, "with")):
        print(f"   ticks above the p99 without ({threshold * 1e6:.0f} us), {label}: "
              f"{_blame(runs[monitor], threshold)}")  # fmt: skip
    server_cpu = sum(b.server_cpu_s for b in runs[True]) / sum(b.seconds for b in runs[True])
    messages = sum(b.messages for b in runs[True])
    ratio, recorded = _p(watched, 0.99) / _p(base, 0.99), _p(with_record, 0.99) / _p(base, 0.99)
    verdict = "holds" if ratio <= 1.10 else "DOES NOT HOLD"
    overlapped = sum(sum(b.rival_ran) for b in runs[True])
    print(f"   tick p99 ratio {ratio:.2f}x (target <= 1.10x: {verdict}), with the record "
          f"{recorded:.2f}x; the page got {messages} updates in {blocks * seconds:.0f} s; the "
          f"server thread used {server_cpu * 1e3:.1f} ms of CPU a second and ran during "
          f"{overlapped} of {len(watched)} ticks")  # fmt: skip


def main() -> None:
    quick = os.environ.get("BENCH_QUICK") == "1"
    blocks, seconds = (2, 5.0) if quick else (4, 15.0)
    tick_time(blocks, seconds)
    lat: dict[bool, list[float]] = {False: [], True: []}
    lat_blocks: dict[bool, list[str]] = {False: [], True: []}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        for monitor in _arms(blocks if quick else 4):
            got_lat = latency(tmp, 6.0 if quick else 8.0, monitor)
            lat[monitor] += got_lat
            lat_blocks[monitor].append(_ms(got_lat, 0.99) if got_lat else "none")
    for monitor, label in ((False, "without"), (True, "with")):
        values = lat[monitor]
        if not values:
            print(f"   reaction latency {label} the monitor: no bump reactions (FAILED)")
            continue
        who = "with the monitor + a page" if monitor else "without the monitor"
        print(f"   reaction latency {who}, {len(values)} bumps: "
              f"median {_ms(values, 0.5)} ms, p99 {_ms(values, 0.99)} ms "
              f"(p99 per block: {', '.join(lat_blocks[monitor])} ms)")  # fmt: skip
    if lat[False] and lat[True]:
        without, with_ = _p(lat[False], 0.99), _p(lat[True], 0.99)
        bound = max(without * LATENCY_RATIO, without + LATENCY_SLACK_S)
        verdict = "holds" if with_ <= bound else "DOES NOT HOLD"
        print(f"   reaction latency p99 unchanged (with <= max({LATENCY_RATIO}x, "
              f"+{LATENCY_SLACK_S * 1e3:.1f} ms) of without = {bound * 1e3:.3f} ms): "
              f"{with_ * 1e3:.3f} ms, {verdict}")  # fmt: skip
    samples = memory(40_000 if quick else 100_000)
    trail = ", ".join(f"{t // 1000}k: {mb:.1f} MB" for t, mb in samples)
    full = [mb for t, mb in samples if t >= 20_000]
    print(f"   RSS with the monitor + a page: {trail}; after the ring filled (20k ticks) "
          f"{full[-1] - full[0]:+.1f} MB" if full else f"   RSS: {trail}")  # fmt: skip


if __name__ == "__main__":
    if sys.argv[1:2] == ["page"]:
        asyncio.run(_read_page(sys.argv[2]))
    elif sys.argv[1:2] == ["designs"]:
        # designs [SECONDS [BLOCKS [NAME,NAME,...]]]: defaults 10 s, 2 blocks, all designs
        chosen = sys.argv[4].split(",") if len(sys.argv) > 4 else list(DESIGNS)
        unknown = [name for name in chosen if name not in DESIGNS]
        if unknown:
            sys.exit(f"unknown design {unknown[0]!r}; known: {', '.join(DESIGNS)}")
        designs(float(sys.argv[2]) if len(sys.argv) > 2 else 10.0,
                int(sys.argv[3]) if len(sys.argv) > 3 else 2, chosen)  # fmt: skip
    else:
        main()
