"""The live monitor's cost to the run (issue 17): the same runs with and without it.

* tick time: the dock mission in the apartment on the simulator paced to the wall clock (one
  frame per 15 ms, as on a robot, so the server's thread works while the tick thread waits
  for the next frame, as it would). Tick time = the runtime's own measure: from the frame's
  snapshot to the end of the flush (with the monitor, its ``before_tick`` is inside it);
  "+ record" adds the monitor's ``after_tick`` (the feed's append), which runs after the
  flush, like the terminal display. With the monitor: its server on 127.0.0.1 and one page
  (a WebSocket client reading every update). Target: p99 at most 1.10x without it.
* reaction latency: as ``bench_runtime`` measures it (a simulator subprocess on a pty bumps
  the robot every 150 ms; bump frame read -> new drive written), with and without the
  monitor and a page.
* memory: RSS over 10^5 ticks on the virtual clock with the monitor and a page, sampled every
  20 000 ticks: flat once the feed's ring (20 000 ticks) is full.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import statistics
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection, TimedFrame
from roomba_bt.robot.interface import Snapshot
from roomba_bt.runtime.loop import MissionRunner, stream_request
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, load_world

from . import bench_runtime

ROOT = Path(__file__).resolve().parents[1]


class TimedRunner(MissionRunner):
    """Stamps each tick: snapshot start -> end of flush, and -> end of the gate's after_tick."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.tick_s: list[float] = []
        self.with_record_s: list[float] = []
        self._started = 0.0

    def _advance(self, batch: Sequence[TimedFrame]) -> Snapshot:
        self._started = time.perf_counter()
        return super()._advance(batch)

    def _flush(self) -> None:
        super()._flush()
        self.tick_s.append(time.perf_counter() - self._started)


class TimedSession(MonitorSession):
    def after_tick(self, runner: MissionRunner) -> None:
        super().after_tick(runner)
        if isinstance(runner, TimedRunner):
            runner.with_record_s.append(time.perf_counter() - runner._started)


class Page:
    """A page: a WebSocket client in its own thread, reading every update."""

    def __init__(self, url: str) -> None:
        self.url = url.replace("http://", "ws://").rstrip("/") + "/ws"
        self.messages = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._read()), daemon=True)
        self._thread.start()

    async def _read(self) -> None:
        import aiohttp

        async with aiohttp.ClientSession() as session, session.ws_connect(self.url) as ws:
            while not self._stop.is_set():
                with contextlib.suppress(asyncio.TimeoutError):
                    await ws.receive(timeout=0.2)
                    self.messages += 1

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)


@contextlib.contextmanager
def monitored(feed: RunFeed, session: MonitorSession) -> Iterator[Page]:
    server = MonitorServer(feed, session, port=0)
    page = Page(server.start())
    try:
        yield page
    finally:
        page.close()
        server.close()


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


def paced_dock(seconds: float, monitor: bool) -> tuple[list[float], list[float], int]:
    mission = load_mission(ROOT / "missions" / "dock.yaml", {}, profile=CREATE2)
    simulator = Simulator(load_world("apartment"), CREATE2, 3)
    connection = Connection(RealtimeSimLink(simulator), CREATE2)
    packets = stream_request(mission.packets, 115200)
    runner = TimedRunner(connection, mission, profile=CREATE2, packets=packets, timeout_s=seconds)
    if not monitor:
        runner.run()
        return runner.tick_s, runner.tick_s, 0
    feed, session = _monitor_for(mission, simulator)
    runner.gate = session
    with monitored(feed, session) as page:
        runner.run()
        messages = page.messages
    return runner.tick_s, runner.with_record_s, messages


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


def main() -> None:
    quick = os.environ.get("BENCH_QUICK") == "1"
    seconds = 10.0 if quick else 30.0
    base, _, _ = paced_dock(seconds, monitor=False)
    ticks, with_record, messages = paced_dock(seconds, monitor=True)
    for label, values in (("without the monitor", base), ("with the monitor + a page", ticks),
                          ("... + the feed's record", with_record)):  # fmt: skip
        median, p99 = statistics.median(values) * 1e6, _p(values, 0.99) * 1e6
        print(f"   dock/apartment paced, {len(values)} ticks {label}: median {median:.0f} us, "
              f"p99 {p99:.0f} us")  # fmt: skip
    ratio, recorded = _p(ticks, 0.99) / _p(base, 0.99), _p(with_record, 0.99) / _p(base, 0.99)
    print(f"   tick p99 ratio {ratio:.2f}x, with the record {recorded:.2f}x (target <= 1.10x); "
          f"the page got {messages} updates in {seconds:.0f} s")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        for label, monitor in (("without", False), ("with", True)):
            lat = latency(tmp, 6.0 if quick else 15.0, monitor)
            if lat:
                print(f"   reaction latency {label} the monitor + a page, {len(lat)} bumps: "
                      f"median {statistics.median(lat) * 1e3:.3f} ms, p99 "
                      f"{_p(lat, 0.99) * 1e3:.3f} ms")  # fmt: skip
            else:
                print(f"   reaction latency {label} the monitor: no bump reactions (FAILED)")
    samples = memory(40_000 if quick else 100_000)
    trail = ", ".join(f"{t // 1000}k: {mb:.1f} MB" for t, mb in samples)
    full = [mb for t, mb in samples if t >= 20_000]
    print(f"   RSS with the monitor + a page: {trail}; after the ring filled (20k ticks) "
          f"{full[-1] - full[0]:+.1f} MB" if full else f"   RSS: {trail}")  # fmt: skip


if __name__ == "__main__":
    main()
