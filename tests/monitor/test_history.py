"""``roomba-bt monitor RECORD``: every tick of a recorded run, packed (monitor/history.py),
and the page's seek into it."""

from __future__ import annotations

import gc
import json
import tracemalloc
import urllib.request
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.monitor.server import MonitorServer
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import state_view
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

SHUTTLE = Path(__file__).resolve().parent / "missions" / "shuttle.yaml"


@pytest.fixture(scope="module")
def shuttle(tmp_path_factory: pytest.TempPathFactory) -> tuple[RunFeed, Path, tuple[int, ...]]:
    """A 60 s shuttle run on the simulator, recorded, with the live monitor's feed of it
    (every tick kept, unpacked)."""
    path = tmp_path_factory.mktemp("history") / "shuttle.jsonl"
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    stack = RunStack(
        mission,
        SimLink(Simulator(load_world("empty-room"), CREATE2, 0)),
        profile=CREATE2,
        timeout_s=60.0,
        record=Recording(path, str(SHUTTLE)),
    )
    feed = RunFeed(history=None, mission_name=mission.name)
    feed.set_tree(mission.root)
    stack.runner.gate = MonitorSession(feed, simulator=False, stream_packets=stack.packets)
    stack.run()
    stack.close()
    return feed, path, stack.packets


def _replayed(path: Path, packets: tuple[int, ...]) -> tuple[RunFeed, RunSummary]:
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    return replay_into_feed(load_record(path), mission, CREATE2, packets, 115200, "shuttle")


def test_a_recorded_runs_ticks_are_kept_packed_and_read_back_as_the_live_run_had_them(
    shuttle: tuple[RunFeed, Path, tuple[int, ...]],
) -> None:
    live, path, packets = shuttle
    replayed, _ = _replayed(path, packets)
    ticks = live.ring.count
    assert replayed.ring.count == ticks > 1000
    for seq in range(ticks):
        was, now = live.record(seq), replayed.record(seq)
        assert was is not None and now is not None
        assert now == was._replace(truth=None), seq  # a record holds no simulator truth


def test_the_record_view_answers_a_seek_to_the_middle_of_the_run(
    shuttle: tuple[RunFeed, Path, tuple[int, ...]], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The page's seek reads the ticks it shows (about twenty, and the path's up to there,
    1 500 to 3 000), not every tick: its answer built every tick of the run to send the
    events, 300 MB and 2 s for a 70-minute record."""
    live, path, packets = shuttle
    replayed, _ = _replayed(path, packets)
    read: list[int] = []
    get = replayed.ring.get
    monkeypatch.setattr(replayed.ring, "get", lambda seq: read.append(seq) or get(seq))
    middle = live.ring.count // 2
    tick = live.record(middle).tick  # type: ignore[union-attr]
    server = MonitorServer(replayed, None, port=0)
    url = server.start()
    try:
        with urllib.request.urlopen(f"{url}api/state?tick={tick}", timeout=HANG_S) as reply:
            body = json.load(reply)
    finally:
        server.close()
    record, earlier = live.at(tick)
    assert record is not None and body["state"]["tick"] == tick
    expected = json.loads(json.dumps(state_view(live, record, earlier)))
    expected["truth"] = None
    assert body["state"] == expected  # the statuses, the robot panel, the blackboard
    assert len(body["path"]["odometry"]) > 100  # the path up to there
    assert len(read) < middle + 100  # the path up to there (thinned past 1 500), the seek


def test_a_recorded_runs_ticks_take_a_few_hundred_bytes_each(
    shuttle: tuple[RunFeed, Path, tuple[int, ...]],
) -> None:
    """Kept as tuples of Python objects, a tick took about 1.5 KB: 718 MB for a 2-hour
    record, more than a Raspberry Pi has beside its robot."""
    _, path, packets = shuttle
    gc.collect()
    tracemalloc.start()
    try:
        replayed, _ = _replayed(path, packets)
        gc.collect()
        kept = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert replayed.ring.count > 1000
    assert kept / replayed.ring.count < 400, kept
