"""A mission on the simulator with the monitor attached, run in a background thread, every
simulator step and every byte written logged with the simulated time."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path

import py_trees
from waits import HANG_S, joined  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import world_view
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.display import live_names
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, load_world

ROOT = Path(__file__).resolve().parents[2]
MISSIONS = ROOT / "missions"


@dataclass
class Step:
    time: float
    left: float
    right: float
    mode: OIMode


@dataclass
class LiveRun:
    simulator: Simulator
    runner: MissionRunner
    feed: RunFeed
    session: MonitorSession
    server: MonitorServer
    thread: threading.Thread
    steps: list[Step] = field(default_factory=list)
    writes: list[tuple[float, bytes]] = field(default_factory=list)
    result: list[RunSummary] = field(default_factory=list)

    @property
    def url(self) -> str:
        return self.server.url

    def finish(self, timeout: float = HANG_S) -> RunSummary:
        if self.thread.is_alive():
            self.session.request("stop")
        joined(self.thread, "the live run, told to stop", timeout)
        self.server.close()
        return self.result[0]


def start_live_run(
    mission: Path | str,
    *,
    world: str = "empty-room",
    params: dict[str, str] | None = None,
    host: str = "127.0.0.1",
    readonly: bool = False,
    realtime: bool = True,
    history: int | None = 20_000,
    port: int = 0,
    robot: str = "",
    label: str = "",
) -> LiveRun:
    compiled = load_mission(mission, params or {}, profile=CREATE2)
    steps: list[Step] = []
    writes: list[tuple[float, bytes]] = []

    class LoggedSimulator(Simulator):
        """Notes the wheels and mode after every step (a subclass: the simulator's
        attributes are slots, its methods not replaceable on the instance)."""

        def step(self, dt: float = 0.015) -> None:
            super().step(dt)
            steps.append(Step(self.time, self.left_speed, self.right_speed, self.mode))

    simulator = LoggedSimulator(load_world(world), CREATE2, 0)
    link: SimLink = RealtimeSimLink(simulator) if realtime else SimLink(simulator)
    write = link.write

    def logged_write(data: bytes) -> None:
        # the time the robot got the bytes: a real-time link first steps the simulator
        # through the slots that passed while the host was busy (under load, several), so
        # the simulator's time before the write is not when they acted
        write(data)
        writes.append((simulator.time, bytes(data)))

    link.write = logged_write  # type: ignore[method-assign]
    stack = RunStack(compiled, link, profile=CREATE2, watchdog=0.5, timeout_s=600.0)
    packets = stack.packets

    def truth() -> tuple[float, float, float]:
        return (simulator.x, simulator.y, simulator.theta)

    feed = RunFeed(
        history=history,
        source="simulator",
        truth=truth,
        world=world_view(simulator),
        mission_name=compiled.name,
        robot=robot,
        label=label,
    )
    feed.set_tree(compiled.root, live_names(compiled))  # as run --monitor does
    session = MonitorSession(feed, simulator=True, stream_packets=packets)
    server = MonitorServer(feed, session, host=host, port=port, readonly=readonly)
    server.start()
    runner = stack.runner
    runner.gate = session
    result: list[RunSummary] = []

    def run() -> None:
        result.append(runner.run())
        feed.finished = result[0].outcome.value

    thread = threading.Thread(target=run, name="mission", daemon=True)
    run_ = LiveRun(simulator, runner, feed, session, server, thread, steps, writes, result)
    thread.start()
    return run_


def feed_of_run(root: py_trees.behaviour.Behaviour, name: str, history: int) -> RunFeed:
    """``root`` run to its end (or 1 s) on the empty room with a feed watching every tick."""
    feed = RunFeed(history=history, mission_name=name)
    feed.set_tree(root)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(TreeMission(root, name), link, profile=CREATE2, timeout_s=1.0,
                     observer=feed.observe)  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    return feed


def replayed_record(
    mission: Path, timeout: str, record_path: Path, *, killed: bool = False
) -> tuple[RunFeed, RunSummary]:
    """``mission`` run with ``--record`` (it fails at ``timeout``), then replayed into a feed:
    what ``roomba-bt monitor RECORD`` serves. ``killed``: its record's first half only, as
    a run killed there (``kill -9``) leaves it, without its end."""
    assert main(["run", str(mission), "--fast", "--timeout", timeout, "--display", "none",
                 "--record", str(record_path)]) == 1  # fmt: skip
    if killed:
        lines = record_path.read_text(encoding="utf-8").splitlines(keepends=True)
        record_path.write_text("".join(lines[: len(lines) // 2]), encoding="utf-8")
    record = load_record(record_path)
    loaded = load_mission(mission, {}, profile=CREATE2)
    packets = tuple(record.header["packets"])
    return replay_into_feed(record, loaded, CREATE2, packets, 115200, mission.stem)
