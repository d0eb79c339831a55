"""The monitor's feed and tick gate on the simulator's virtual clock (no browser)."""

from __future__ import annotations

import itertools
import json
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from runtime.simrun import (  # tests/runtime: a room with a drop, a recorded stall
    LEDGE,
    BusyAfterTheFall,
    over_the_edge,
    record_run,
    stream_gap_link,
)
from runtime.test_terminate_never_returns import (  # a plugin whose terminate() blocks
    HANG_ON_SHUTDOWN,
    HANG_ON_STOP,
    MISSION,
    SHUTDOWN_LINE,
    WAIT_LINE,
    given_up,
    outbound,
    release_all,
)
from waits import HANG_S, joined, waited  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.cli.run_cmd import _stop_said
from roomba_bt.mission import Permissions, load_mission
from roomba_bt.monitor import session as session_module
from roomba_bt.monitor.feed import Ending, EventLogHandler, Ring, RunFeed
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.monitor.session import ControlRefused, MonitorSession
from roomba_bt.monitor.views import after_the_end, session_view, state_view
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot import silence
from roomba_bt.runtime import ending
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world
from roomba_bt.sim import robot as sim_robot

HERE = Path(__file__).resolve().parent
SHUTTLE = HERE / "missions" / "shuttle.yaml"
WAIT_THEN_DRIVE = HERE / "missions" / "wait-then-drive.yaml"
#: what a test notes after each tick (:meth:`Rig.after_each_tick`)
Noted = TypeVar("Noted")
#: The most a run is waited for to end once its operator is done (:meth:`Rig.run_with`): the
#: wait ends with the run, so this bounds only one that never ends.
RUN_END_S = HANG_S


class PacedGate:
    """The session as the run's gate, with the tick thread sleeping a little before each
    tick while the operator acts: on the virtual clock a run otherwise holds the GIL for
    thousands of ticks (the whole 60 s mission) before the operator's thread gets to act, as
    no page ever could. Once the operator is done (:meth:`Rig.run_with`), nobody else needs
    a turn: the rest of the run goes at the virtual clock's pace (its ticks unpaced, the same
    ticks), not 0.2 ms and the scheduler's slack a tick longer."""

    PACE_S = 0.0002

    def __init__(self, session: MonitorSession) -> None:
        self.session = session
        self.paced = True

    def before_tick(self, runner: MissionRunner) -> bool:
        if self.paced:
            time.sleep(self.PACE_S)
        return self.session.before_tick(runner)

    def after_tick(self, runner: MissionRunner) -> None:
        self.session.after_tick(runner)

    def holds(self, runner: MissionRunner) -> bool:
        return self.session.holds(runner)

    def between_frames(self, runner: MissionRunner) -> None:
        self.session.between_frames(runner)


class Rig:
    """A shuttle run on the virtual clock with the monitor's session as its gate."""

    def __init__(
        self,
        *,
        simulator: bool = True,
        record: Path | None = None,
        mission: Path = SHUTTLE,
        world: str | Path = "empty-room",
        keep_awake: bool | None = None,
        thin_pauses: bool = False,
        link: Callable[[Simulator], SimLink] = SimLink,
        plugin_files: bool = False,
        faults: Faults | None = None,
    ) -> None:
        allowed = Permissions(plugin_files=plugin_files)
        self.mission = load_mission(mission, {}, profile=CREATE2, permissions=allowed)
        self.sim = Simulator(load_world(world), CREATE2, 0, faults)
        recording = Recording(record, str(SHUTTLE)) if record is not None else None
        self.stack = RunStack(
            self.mission,
            link(self.sim),
            profile=CREATE2,
            watchdog=0.5,
            timeout_s=60.0,
            record=recording,
            keep_awake=keep_awake,
        )
        self.packets = self.stack.packets
        self.connection = self.stack.connection
        # every frame of a pause kept (a live page keeps one a second): these tests read the
        # stream's ticks of a pause and compare each frame with the record's replay
        self.feed = RunFeed(history=5000, mission_name=self.mission.name, thin_pauses=thin_pauses)
        self.feed.set_tree(self.mission.root)
        self.session = MonitorSession(self.feed, simulator=simulator, stream_packets=self.packets)
        self.ended = threading.Event()
        self.runner = self.stack.runner
        self.gate = PacedGate(self.session)
        self.runner.gate = self.gate

    def run_with(self, operator: Callable[[Rig], None], *, ended: bool = False) -> RunSummary:
        """Run; ``operator`` acts from another thread, as the page would. The run then goes
        on to its own end, however long a loaded machine takes over it (a stop after 10 s of
        wall time ended runs INTERRUPTED that would have succeeded); one whose operator
        failed is stopped at once. ``ended``: run as ``roomba-bt run`` does, through the
        stack, whose record then ends with the run's end note (the runner's own run writes
        none)."""
        result: list[RunSummary] = []

        def run() -> None:
            result.append(self.stack.run_here() if ended else self.runner.run())
            self.ended.set()

        thread = threading.Thread(target=run)
        thread.start()
        try:
            operator(self)
        except BaseException:
            self.session.request("stop")  # the test has failed: nothing to run on for
            raise
        finally:
            self.gate.paced = False  # the operator is done: no thread waits for a turn
            if not self.ended.wait(RUN_END_S):
                self.session.request("stop")
            joined(thread, "the run's thread")
        self.connection.close()
        return result[0]

    def node(self, name: str) -> int:
        """The feed's index of the node called ``name``."""
        return [info.name for info in self.feed.infos].index(name)

    def ticks(self, *, ticked: bool) -> int:
        return sum(1 for r in self.feed.since(0)[0] if r.ticked is ticked)

    def after_each_tick(self, note: Callable[[MissionRunner], Noted]) -> list[Noted]:
        """``note(runner)`` on the tick thread after each tick (after the session's, so a
        breakpoint's pause is in it), into the list returned: the robot as a tick left it,
        not as it was when the operator's thread got to look (on a loaded machine, after
        the run's end had put it in Passive)."""
        notes: list[Noted] = []
        after_tick = self.session.after_tick

        def noting(runner: MissionRunner) -> None:
            after_tick(runner)
            notes.append(note(runner))

        self.session.after_tick = noting  # type: ignore[method-assign]
        return notes

    def robot(self) -> tuple[OIMode, float, float]:
        """The simulated robot's mode and wheel speeds now."""
        return self.sim.mode, self.sim.left_speed, self.sim.right_speed


def paused_after(rig: Rig, until: Callable[..., None], ticks: int) -> None:
    """The operator's pause, once the tree has ticked ``ticks`` times, seen taken."""
    until(lambda: rig.ticks(ticked=True) > ticks)
    rig.session.request("pause")
    until(lambda: rig.session.state.paused)


def test_pause_freezes_the_tree_in_passive_resume_drives_again_stop_ends_as_ctrl_c(
    until: Callable[..., None],
) -> None:
    rig = Rig()
    seen: dict[str, object] = {}

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100)
        rig.session.request("pause")
        until(lambda: rig.ticks(ticked=False) > 50)
        seen["mode"] = rig.sim.mode
        seen["wheels"] = (rig.sim.left_speed, rig.sim.right_speed)
        seen["ticked while paused"] = rig.ticks(ticked=True)
        until(lambda: rig.ticks(ticked=False) > 60)
        seen["ticked later"] = rig.ticks(ticked=True)
        rig.session.request("resume")
        until(lambda: rig.ticks(ticked=True) > seen["ticked later"] + 50)  # type: ignore[operator]

        def driving() -> bool:  # read at once: the shuttle stops for a frame at each turn
            seen["resumed"] = (rig.sim.mode, rig.sim.left_speed, rig.sim.right_speed)
            return bool(rig.sim.left_speed or rig.sim.right_speed)

        until(driving)
        rig.session.request("stop")

    summary = rig.run_with(operator)
    assert seen["mode"] is OIMode.PASSIVE
    assert seen["wheels"] == (0.0, 0.0)
    assert seen["ticked while paused"] == seen["ticked later"]  # the tree was frozen
    mode, left, right = seen["resumed"]  # type: ignore[misc]
    assert mode is OIMode.SAFE and (left or right)
    assert summary.outcome is Outcome.INTERRUPTED
    assert summary.reason == "stopped by the operator"
    assert summary.exit_code == 130
    assert summary.safe_stop.startswith("sent ")
    kinds = [e.text.split(" ")[0] for e in rig.feed.events if e.kind == "control"]
    assert kinds == ["pause", "resume", "stop:"]
    # mission time stood still: the page places the events by the stream's tick (it greyed
    # a resume as past at a tick inside the pause)
    pause, resume = [e for e in rig.feed.events if e.kind == "control"][:2]
    assert resume.time - pause.time < 0.05 and resume.tick - pause.tick > 60


def test_mission_time_stands_still_while_paused_so_a_wait_does_not_count_the_pause(
    until: Callable[..., None],
) -> None:
    rig = Rig(mission=WAIT_THEN_DRIVE)
    wait = rig.node("one second")
    rig.session.request("break", wait, "start")  # paused in the tick the wait starts

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=False) > 200)  # 3 s of frames, paused
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS
    records = rig.feed.since(0)[0]
    started = next(r for r in records if r.statuses[wait] == "R")
    waited = next(r for r in records if r.statuses[wait] == "S")
    assert 1.0 <= waited.time - started.time < 1.05  # one second of mission time...
    assert (waited.seq - started.seq) * 0.015 > 1.0 + 3.0  # ...over the pause's frames too
    paused = [r for r in records if not r.ticked]
    assert len(paused) > 200
    assert len({r.time for r in paused}) <= 2  # held; then the frame skipped after resume
    assert len({r.tick for r in paused}) == len(paused)  # the stream's ticks went on
    assert summary.mission_time_s < (len(records) - 200) * 0.015  # the pause left out


def test_the_command_rate_of_a_long_pause_is_its_own_not_the_driving_s_before_it(
    until: Callable[..., None],
) -> None:
    """The robot panel's "commands / refused per s" compared a tick with the record 67
    records back, a second of frames while driving; a pause keeps a frame a second, so 67
    back was a minute back in a long pause, or before it: 33.1 a second was shown a second
    into a pause of a robot written nothing since, and a decaying share of the driving's
    rate as long as it lasted. Now it is a second of the stream before the tick shown."""
    rig = Rig(thin_pauses=True)  # a live page's feed: a frame a second kept in a pause
    seen: dict[str, object] = {}

    def operator(rig: Rig) -> None:
        paused_after(rig, until, 200)
        written = rig.runner.summary.commands_written
        until(lambda: rig.runner.summary.paused_s > 3.0)
        newest = rig.feed.latest()
        assert newest is not None
        record, earlier = rig.feed.at(newest.tick)
        seen["robot"] = state_view(rig.feed, record, earlier)["robot"]
        seen["written"] = rig.runner.summary.commands_written - written
        seen["back"] = record.tick - earlier[0].tick
        rig.session.request("stop")

    rig.run_with(operator)
    assert seen["written"] == 0  # nothing written in the pause: the rate is 0
    assert 67 <= seen["back"] < 2 * 67, seen["back"]  # a second of the stream back, a frame kept
    robot = seen["robot"]
    assert isinstance(robot, dict)
    assert (robot["commands_per_s"], robot["refused_per_s"]) == (0.0, 0.0), robot
    record, earlier = rig.feed.at(150)  # driving: every frame kept, 67 records a second
    assert record.tick - earlier[0].tick == 67


def test_a_live_page_keeps_a_paused_frame_a_second_so_a_long_pause_keeps_the_run(
    until: Callable[..., None],
) -> None:
    """The stream goes on in a pause: at 66.7 frames a second a 5-minute pause filled the
    page's 20 000 ticks and pushed the run out (24 m driven, 0.5 m of path shown). A live
    feed keeps the pause's first frame, then one a second (and any that brings news); the
    driving before it stays in the ring."""
    rig = Rig(thin_pauses=True)
    rig.feed.ring = Ring(400)  # the page's 20 000 ticks, scaled: 6 s of frames

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100)
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        until(lambda: rig.runner.summary.paused_s > 10.0)  # 667 frames: more than the ring
        rig.session.request("stop")

    rig.run_with(operator)
    records = rig.feed.since(0)[0]
    paused = [r for r in records if not r.ticked]
    assert records[0].tick == 0  # the run's start is still held
    assert sum(r.ticked for r in records) > 100
    assert 10 <= len(paused) <= 13, [r.tick for r in paused]
    # the pause's first frame (its snapshot still in Safe), the one that shows Passive (news),
    # the first that shows the robot still (news), then a frame a second of stream time
    assert paused[0].tick == rig.session.state.paused_tick
    assert paused[1].tick == paused[0].tick + 1 and paused[1].mode != paused[0].mode
    gaps = [b.tick - a.tick for a, b in itertools.pairwise(paused[1:])]
    assert gaps[1:] == [67] * len(gaps[1:]), gaps
    assert gaps[0] <= 3, [r.tick for r in paused]  # the first frame that shows it still


def test_resume_and_step_are_refused_unless_paused_and_bad_requests_change_nothing() -> None:
    rig = Rig()
    with pytest.raises(ControlRefused, match="not paused"):
        rig.session.request("resume")
    with pytest.raises(ControlRefused, match="pause first"):
        rig.session.request("step")
    with pytest.raises(ValueError, match="allowed pause, resume"):
        rig.session.request("explode")
    with pytest.raises(ValueError, match="node 99"):
        rig.session.request("break", 99, "start")
    with pytest.raises(ValueError, match="allowed start, success, failure, end, none"):
        rig.session.request("break", 0, "sometimes")
    with pytest.raises(ControlRefused, match="not a condition"):
        rig.session.request("force", 0, "success")
    assert rig.session._requests.empty()


def test_forcing_is_refused_on_a_real_robot_unless_allowed() -> None:
    rig = Rig(simulator=False)
    no_bump = rig.node("no bump")
    with pytest.raises(ControlRefused, match="--monitor-force"):
        rig.session.request("force", no_bump, "failure")
    allowed = MonitorSession(rig.feed, simulator=False, allow_force=True)
    allowed.request("force", no_bump, "failure")


def test_a_forced_condition_decides_the_branch_and_is_marked_in_the_events_and_the_record(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    record_path = tmp_path / "forced.jsonl"
    rig = Rig(record=record_path)
    no_bump = rig.node("no bump")

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("force", no_bump, "failure")
        waited(rig.ended, "the run's end")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.FAILURE
    # the operator's, said so: it read "no bump", as if the bumper had failed the mission
    assert summary.reason == (
        "stopped: no bump: forced to FAILURE by the operator, while 'repeat' ran"
        " (stage drive was running)"
    )
    assert any(e.kind == "force" and "no bump forced to FAILURE" in e.text for e in rig.feed.events)
    record = load_record(record_path)
    assert record.notes
    forced = record.notes[0][1]
    assert forced == {"force": "no bump", "node": no_bump, "to": "failure", "at": "before",
                      "tick": forced["tick"]}  # fmt: skip
    replayed, replay = replay_into_feed(
        record, load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2, rig.packets, 115200, "x"
    )
    assert any(e.kind == "force" and "no bump forced to FAILURE" in e.text for e in replayed.events)
    assert replay.outcome is Outcome.FAILURE  # forced at the same tick: the same branch taken
    assert _ticks(replayed) == _ticks(rig.feed)


def _ticks(feed: RunFeed) -> list[tuple[int, bool, str, float]]:
    return [(r.tick, r.ticked, r.statuses, round(r.time, 6)) for r in feed.since(0)[0]]


def test_a_replayed_pause_is_time_passing_with_the_tree_frozen(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """The record marks pause and resume with their tick: the replay pauses there too (the
    stream's ticks go on, the tree and mission time stand still), then goes on as live did."""
    record_path = tmp_path / "paused.jsonl"
    rig = Rig(record=record_path)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100)
        rig.session.request("pause")
        until(lambda: rig.ticks(ticked=False) > 50)
        rig.session.request("resume")
        after = rig.ticks(ticked=True)
        until(lambda: rig.ticks(ticked=True) > after + 100)
        rig.session.request("stop")

    rig.run_with(operator)
    rig.stack.close()
    record = load_record(record_path)
    assert [next(iter(note)) for _, note in record.notes] == ["pause", "resume"]
    replayed, _ = replay_into_feed(
        record, load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2, rig.packets, 115200, "x"
    )
    live, again = _ticks(rig.feed), _ticks(replayed)
    assert again[: len(live) - 1] == live[:-1]  # the last live frame may be the stop's
    frozen = [r for r in again if not r[1]]
    assert len(frozen) > 50
    assert len({(r[2], r[3]) for r in frozen}) == 1  # statuses and mission time held
    assert frozen[-1][0] - frozen[0][0] == len(frozen) - 1  # while the stream's ticks went on
    assert sum(1 for r in again if r[1] and r[0] > frozen[-1][0]) > 90  # and it went on after
    controls = [e.text.split(" ")[0] for e in replayed.events if e.kind == "control"]
    assert controls == ["pause", "resume"]


def test_a_breakpoint_on_an_ending_pauses_after_that_tick_and_step_ticks_once(
    until: Callable[..., None],
) -> None:
    rig = Rig()
    forth = rig.node("drive(velocity=100 mm/s, distance=3 cm)")
    seen: dict[str, int] = {}

    def operator(rig: Rig) -> None:
        rig.session.request("break", forth, "success")
        until(lambda: rig.session.state.paused)
        hit = [r for r in rig.feed.since(0)[0] if r.ticked][-1]
        assert hit.statuses[forth] == "S" and forth in hit.changed
        seen["ticked"] = rig.ticks(ticked=True)
        rig.session.request("step")
        until(lambda: rig.session.state.pause_reason == "stepped one tick")
        seen["after step"] = rig.ticks(ticked=True)
        rig.session.request("stop")  # paused for good: run_with would wait its 10 s first

    rig.run_with(operator)
    assert seen["after step"] - seen["ticked"] == 1
    texts = [e.text for e in rig.feed.events if e.kind == "breakpoint"]
    assert texts[0].startswith("break when drive(velocity=100 mm/s, distance=3 cm) ends in SUCCESS")
    assert "breakpoint: drive(velocity=100 mm/s, distance=3 cm) ends in SUCCESS at tick" in texts[1]


def test_a_step_is_one_frame_of_mission_time_live_and_replayed(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """A step ticks the tree once: mission time moved two frames (0.03 s), the tick's and
    the one its pause came with, where one step is one 15 ms frame. The record's replay
    steps alike."""
    record_path = tmp_path / "stepped.jsonl"
    rig = Rig(mission=WAIT_THEN_DRIVE, record=record_path)
    wait = rig.node("one second")
    rig.session.request("break", wait, "start")

    def stepped() -> int:
        return sum(e.text.startswith("pause (stepped one tick)") for e in rig.feed.events)

    def operator(rig: Rig) -> None:
        until(lambda: rig.session.state.paused)
        for done in range(1, 4):
            rig.session.request("step")
            until(lambda done=done: stepped() == done)
        rig.session.request("resume")

    summary = rig.run_with(operator)
    rig.stack.close()
    assert summary.outcome is Outcome.SUCCESS
    records = rig.feed.since(0)[0]
    hit = next(r for r in records if r.statuses[wait] == "R")
    steps = [r for r in records if r.ticked and r.seq > hit.seq][:3]
    times = [round(r.time - hit.time, 6) for r in (hit, *steps)]
    assert times == [0.0, 0.015, 0.03, 0.045]
    held = {
        round(r.time, 6) for r in records if not r.ticked and steps[0].seq < r.seq < steps[1].seq
    }
    assert held == {round(steps[0].time, 6)}  # paused after it: the step's own time
    replayed, _ = replay_into_feed(
        load_record(record_path), load_mission(WAIT_THEN_DRIVE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    assert _ticks(replayed)[: len(records) - 1] == _ticks(rig.feed)[:-1]


def test_a_step_whose_tick_hits_a_breakpoint_is_counted_as_a_step_live_and_replayed(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """The operator steps through a short wait, a breakpoint on its end: the step whose tick
    ends it pauses with the breakpoint's reason, and the summary counted that pause as a
    pause, not a step (``paused ... in 2 pauses, 3 steps`` for one pause and four steps).
    It counts what the operator did, and the record's replay counts alike."""
    mission, record_path = tmp_path / "waits.yaml", tmp_path / "stepped.jsonl"
    mission.write_text(
        "mission: waits\ntree:\n  sequence:\n    - mode: safe\n"
        "    - {name: short, wait: 0.05 s}\n    - {name: long, wait: 1 s}\n"
    )
    rig = Rig(mission=mission, record=record_path)
    short = rig.node("short")
    rig.session.request("break", short, "start")
    pressed: list[str] = []

    def operator(rig: Rig) -> None:
        until(lambda: rig.session.state.paused)
        rig.session.request("break", short, "success")

        def paused() -> int:
            return sum(e.text.startswith("pause (") for e in rig.feed.events)

        while not rig.session.state.pause_reason.startswith("breakpoint: short ends"):
            assert len(pressed) < 20, rig.session.state.pause_reason
            rig.session.request("step")
            pressed.append("step")
            until(lambda: paused() > len(pressed))  # the first pause and one a step
        rig.session.request("stop")

    summary = rig.run_with(operator)
    rig.stack.close()
    assert len(pressed) > 1  # steps through the wait, the last one's tick its end
    assert (summary.pauses, summary.steps) == (1, len(pressed)), summary.paused_text()
    _, replayed = replay_into_feed(
        load_record(record_path), load_mission(mission, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    assert (replayed.pauses, replayed.steps) == (1, len(pressed)), replayed.paused_text()


def test_a_pause_pressed_during_a_step_counts_the_step_and_the_pause_live_and_replayed(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """Pause pressed while a step is under way (before its own pause came): the summary
    counted one more pause and no step, as if the operator had never stepped. Both are
    counted: one pause, one step, then the pause pressed in it; the replay counts alike."""
    record_path = tmp_path / "stepped.jsonl"
    rig = Rig(record=record_path)

    def operator(rig: Rig) -> None:
        paused_after(rig, until, 50)
        rig.session.request("step")
        rig.session.request("pause")  # queued behind it: applied before the step's pause
        until(lambda: sum(e.text.startswith("pause (") for e in rig.feed.events) == 2)
        rig.session.request("stop")

    summary = rig.run_with(operator)
    rig.stack.close()
    pauses = [e.text for e in rig.feed.events if e.text.startswith("pause (")]
    assert [p.split(":")[0] for p in pauses] == ["pause (paused by the operator)"] * 2, pauses
    assert (summary.pauses, summary.steps) == (2, 1), summary.paused_text()
    _, replayed = replay_into_feed(
        load_record(record_path), load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    assert (replayed.pauses, replayed.steps) == (2, 1), replayed.paused_text()


def test_a_breakpoint_on_the_last_tick_holds_the_ended_mission_until_the_resume(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """The run used to end in the tick the breakpoint was hit, its pause logged and never
    seen; now the operator sees the end, paused, and the resume (no mode, no wheels sent
    again) ends the run with the mission's outcome; its record replays so."""
    record_path = tmp_path / "held.jsonl"
    rig = Rig(mission=WAIT_THEN_DRIVE, record=record_path)
    last = rig.node("drive(velocity=100 mm/s, distance=3 cm)")
    seen: dict[str, object] = {}

    def operator(rig: Rig) -> None:
        rig.session.request("break", last, "success")
        until(lambda: rig.session.state.paused)
        held = rig.ticks(ticked=False)
        until(lambda: rig.ticks(ticked=False) > held + 20)  # frames go on: the run is held
        seen["ended"] = rig.ended.is_set()
        seen["robot"] = (rig.sim.mode, rig.sim.left_speed, rig.sim.right_speed)
        seen["written"] = rig.runner.summary.commands_written
        seen["held_end"] = session_view(rig.session)["held_end"]  # the page's banner says it
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert seen["ended"] is False
    assert seen["robot"] == (OIMode.PASSIVE, 0.0, 0.0)
    assert seen["held_end"] == "SUCCESS"
    assert summary.outcome is Outcome.SUCCESS
    assert summary.commands_written == seen["written"]  # nothing sent again at the resume
    controls = [e.text for e in rig.feed.events if e.kind == "control"]
    assert "the mission ended: SUCCESS; held until resumed or stopped" in controls
    assert controls[-1].startswith("resume (resumed by the operator): the mission ended")
    rig.stack.close()
    replayed, again = replay_into_feed(
        load_record(record_path), load_mission(WAIT_THEN_DRIVE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    assert again.outcome is Outcome.SUCCESS and again.ticks == summary.ticks
    assert _ticks(replayed)[: len(_ticks(rig.feed)) - 1] == _ticks(rig.feed)[:-1]


def test_the_feed_is_bounded_and_shares_what_did_not_change(until: Callable[..., None]) -> None:
    rig = Rig()
    rig.feed.ring = Ring(300)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) >= 300 and rig.feed.latest().seq > 1000)  # type: ignore[union-attr]

    rig.run_with(operator)
    records = rig.feed.since(0)[0]
    assert len(records) == 300
    assert records[0].seq > 0  # the oldest fell out
    unchanged = [b for a, b in itertools.pairwise(records) if not b.changed]
    assert unchanged
    pairs = itertools.pairwise(records)
    assert all(b.statuses is a.statuses for a, b in pairs if not b.changed and a.tree == b.tree)


def test_a_reload_stops_the_old_tree_under_the_safe_stop_and_the_new_tree_is_the_runs(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """A reload while the shuttle drives: the old tree's running drive, stopped after the
    reload's safe stop, queued its halt, which went out in Passive and was refused (two
    "refused: drive needs Safe or Full" lines under a run that did nothing wrong); and the
    run's last tree, printed under the summary, was the first mission's."""
    waiting = tmp_path / "waiting.yaml"
    waiting.write_text("mission: waiting\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n")
    rig = Rig()
    new = load_mission(waiting, {}, profile=CREATE2)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.reload(new)

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.refused_commands == 0, rig.runner.refusals
    assert rig.stack.mission is new
    assert [e.text for e in rig.feed.events if e.kind == "reload"] == [
        "reloaded waiting: the new tree starts from its root"
    ]
    # a new name where it is shown: the summary, the page's header (both kept the first's)
    assert summary.mission == rig.feed.mission_name == "waiting"


def test_a_reload_on_a_link_without_keep_awake_says_the_new_tree_takes_over_not_a_pause(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """``run --watch`` on a pty (no keep-awake): the reload's safe stop was logged as
    "pause (reload): ...; tree frozen; this link cannot keep the robot awake: the run ends
    5 min into the pause unless resumed", and the new tree then drove at once, as a reload
    does: nothing was paused, nothing to resume, no sleep to count down to."""
    waiting = tmp_path / "waiting.yaml"
    waiting.write_text("mission: waiting\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n")
    rig = Rig(keep_awake=False)
    new = load_mission(waiting, {}, profile=CREATE2)
    notes: list[str] = []

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.reload(new)
        until(lambda: rig.stack.mission is new)
        notes.append(rig.session.state.sleep_note)

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert summary.pauses == 0
    controls = [e.text for e in rig.feed.events if e.kind == "control"]
    [reload] = [text for text in controls if text.startswith("reload")]
    assert reload.startswith("reload: safe stop sent drive"), reload
    assert reload.endswith(
        "the old tree stops and the new one takes over at the next frame (no pause: nothing "
        "to resume)"
    ), reload
    assert not any(text.startswith("pause (") for text in controls), controls
    assert not any("into the pause" in e.text for e in rig.feed.events)
    assert notes == [""]  # no countdown to a sleep on the banner


def test_a_reload_while_paused_resumes_into_the_new_tree_from_passive_with_no_old_command(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """Paused, reloaded, resumed: the resume sent the old tree's mode and its last Drive
    again (the actuators as *that* tree left them), so the new tree's first ``wait`` drove
    the shuttle's 100 mm/s, in Safe, although no leaf of it asked to move."""
    waiting = tmp_path / "waiting.yaml"
    waiting.write_text("mission: waiting\ntree:\n  sequence:\n    - wait: 2s\n    - mode: safe\n")
    rig = Rig()
    new = load_mission(waiting, {}, profile=CREATE2)
    ticks = rig.after_each_tick(lambda runner: (runner.mission is new, rig.robot()))

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        rig.session.reload(new)
        until(lambda: rig.stack.mission is new)
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    new_tree = [robot for is_new, robot in ticks if is_new]
    # the 2 s wait's ticks (133 of 15 ms) still, in Passive; then the new tree's own Safe
    safe = new_tree.index((OIMode.SAFE, 0.0, 0.0))
    assert safe > 130
    assert set(new_tree[:safe]) == {(OIMode.PASSIVE, 0.0, 0.0)}
    resumes = [e.text for e in rig.feed.events if e.text.startswith("resume")]
    assert resumes == ["resume (resumed by the operator): mode unchanged; the tree goes on"]


def test_a_reload_during_a_step_leaves_the_run_paused_not_driving(
    until: Callable[..., None],
) -> None:
    """A step pressed as ``--watch`` reloads (a save a moment before): the reload's own
    safe stop dropped the step's pause to come, and the run went on unpaused, the new tree
    driving the robot though the operator had asked for one tick and a pause. The run stays
    paused; the resume starts the new tree from its root."""
    rig = Rig()
    new = load_mission(SHUTTLE, {}, profile=CREATE2)  # drives at once
    ticks = rig.after_each_tick(lambda runner: runner.mission is new)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        rig.session.request("step")
        rig.session.reload(new)
        until(lambda: rig.stack.mission is new)
        frames = rig.ticks(ticked=False) + rig.ticks(ticked=True)
        until(lambda: rig.ticks(ticked=False) + rig.ticks(ticked=True) > frames + 60)
        assert rig.session.state.paused
        assert rig.session.state.pause_reason.startswith("the mission reloaded during a step")
        assert rig.robot() == (OIMode.PASSIVE, 0.0, 0.0)
        assert not any(ticks), "the new tree ticked while the run was held"
        rig.session.request("stop")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason


def test_a_pause_during_seek_dock_resumes_the_cycle(until: Callable[..., None]) -> None:
    """dock-builtin: Seek Dock (143) drives the robot in Passive. The pause's safe stop ends
    the cycle (Safe, drive 0, Start); the resume sent nothing back (the robot was in
    Passive), so the robot sat still while ``seek_dock`` waited for the dock until its time
    limit. The cycle the tree started is started again."""
    rig = Rig(mission=HERE.parents[1] / "missions" / "dock-builtin.yaml")
    seen: dict[str, object] = {}

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.request("pause")
        paused = rig.ticks(ticked=False)
        until(lambda: rig.ticks(ticked=False) > paused + 30)
        seen["paused"] = (rig.sim.left_speed, rig.sim.right_speed)
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert seen["paused"] == (0.0, 0.0)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert rig.sim.docked
    resumes = [e.text for e in rig.feed.events if e.text.startswith("resume")]
    assert resumes == [
        "resume (resumed by the operator): mode unchanged, seek_dock sent again; the tree goes on"
    ]


def test_a_resume_sends_the_actuators_state_again_not_a_song_played_earlier(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """The resume sent the last command of every channel again: the song the mission played
    at its start played again at each resume (and a Buttons press would be pressed again).
    The wheels, motors and LEDs are sent again; Play is not."""
    tune = tmp_path / "tune.yaml"
    tune.write_text(
        SHUTTLE.read_text().replace(
            "    - mode: safe\n",
            "    - mode: safe\n    - song: {notes: [C4 100ms]}\n    - play\n"
            "    - leds: {spot: true}\n",
            1,
        )
    )
    rig = Rig(mission=tune)
    written: list[str] = []
    send_many = rig.connection.send_many

    def noting(commands: Any) -> None:
        written.extend(c.name for c in commands)
        send_many(commands)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        rig.connection.send_many = noting  # type: ignore[method-assign]
        rig.session.request("resume")
        until(lambda: not rig.session.state.paused)
        rig.session.request("stop")

    rig.run_with(operator)
    assert written[0] == "safe" and "drive" in written and "leds" in written, written
    assert "play" not in written, written


def test_a_pause_on_the_home_base_does_not_start_the_cycle_again(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """Seek Dock has docked the robot, which waits there: the cycle ended on the dock, and a
    resume that sent Seek Dock again would send a docked robot looking for its dock (a
    Clean that came home would leave it again)."""
    docked = tmp_path / "seek-and-stay.yaml"
    docked.write_text(
        "mission: seek-and-stay\ntree:\n  sequence:\n    - mode: passive\n"
        "    - seek_dock: {timeout: 60s}\n    - wait: 20s\n"
    )
    rig = Rig(mission=docked)

    def operator(rig: Rig) -> None:
        until(lambda: rig.sim.docked and rig.ticks(ticked=True) > 600)  # seek_dock done
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert rig.sim.docked
    resumes = [e.text for e in rig.feed.events if e.text.startswith("resume")]
    assert resumes == ["resume (resumed by the operator): mode unchanged; the tree goes on"]


def test_a_reload_shuts_the_old_tree_down_and_the_run_s_end_the_new_one(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """py_trees' lifecycle: each node's shutdown() once, when its tree is done with; the
    old tree's at the reload (after its stop), the new tree's at the run's end."""
    waiting = tmp_path / "waiting.yaml"
    waiting.write_text("mission: waiting\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n")
    rig = Rig()
    new = load_mission(waiting, {}, profile=CREATE2)
    shut: list[str] = []
    for tree, mission in (("old", rig.mission), ("new", new)):
        for node in mission.root.iterate():
            node.shutdown = lambda n=node, t=tree: shut.append(f"{t} {n.name}")  # type: ignore[method-assign]

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.reload(new)

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    old = [f"old {node.name}" for node in rig.mission.root.iterate()]
    # the run's end shuts down its tree then, the new one: the old one's came at the reload
    assert shut == old + [f"new {node.name}" for node in new.root.iterate()]


#: the shuttle's drive after a leaf whose shutdown() never returns (its plugin's), the mission
#: running on when the reload comes
DRIVES_AFTER_A_HANGING_SHUTDOWN = (
    "mission: hang_on_shutdown\n"
    "plugins: [./hang.py]\n"
    "tree:\n"
    "  sequence:\n"
    "    - mode: safe\n"
    "    - hang_on_shutdown\n"
    "    - drive: {velocity: 100 mm/s, duration: 60s}\n"
)


@pytest.mark.parametrize("hangs_in", ["terminate", "shutdown"])
def test_a_reload_whose_old_tree_never_stops_ends_the_run_hung_with_the_robot_stopped(
    until: Callable[..., None],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capfd: pytest.CaptureFixture[str],
    hangs_in: str,
) -> None:
    """A reload while the tree drives, a plugin's terminate() (or shutdown()) never
    returning: the reload called the old tree's stop and shutdown unbounded, and the run
    hung for ever (the robot paused in Passive, no summary, no exit code). It waits as the
    run's end does (the bound made short here), then the run ends HUNG (exit 4), naming the
    method and its line; the run's end neither stops that tree a second time nor waits for
    it again, and the robot is left stopped in Passive, the safe stop the last bytes
    written."""
    monkeypatch.setattr(ending, "TREE_STOP_LIMIT_S", 0.5)
    stop = hangs_in == "terminate"
    plugin = tmp_path / "hang.py"
    plugin.write_text(HANG_ON_STOP if stop else HANG_ON_SHUTDOWN)
    (tmp_path / "hang.yaml").write_text(MISSION if stop else DRIVES_AFTER_A_HANGING_SHUTDOWN)
    waiting = tmp_path / "waiting.yaml"
    waiting.write_text("mission: waiting\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n")
    record = tmp_path / "run.jsonl"
    rig = Rig(mission=tmp_path / "hang.yaml", plugin_files=True, record=record)
    new = load_mission(waiting, {}, profile=CREATE2)
    left_before = ending.threads_left()

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.reload(new)

    try:
        with given_up(plugin):
            summary = rig.run_with(operator)
            left = ending.threads_left() - left_before  # its thread, still in the method
    finally:
        release_all(plugin)
    assert summary.outcome is Outcome.HUNG, summary.reason
    assert summary.exit_code == 4
    if stop:
        where = f"hang_on_stop (HangOnStop.terminate at {plugin}:{WAIT_LINE})"
        assert summary.reason == (
            f"the tree's stop did not end within 0.5 s: {where} had not returned; the reload "
            "of waiting was given up and the run ended (the safe stop, the summary; its "
            "shutdown() not called)"
        )
        assert capfd.readouterr().err.count("terminate entered") == 1  # not stopped twice
    else:
        where = f"hang_on_shutdown (HangOnShutdown.shutdown at {plugin}:{SHUTDOWN_LINE})"
        assert summary.reason == (
            f"the behaviours' shutdown() did not end within 0.5 s: {where} had not returned; "
            "the reload of waiting was given up and the run ended (the safe stop, the summary)"
        )
    assert rig.stack.mission is not new
    assert summary.safe_stop.startswith("sent "), summary.safe_stop
    assert rig.robot() == (OIMode.PASSIVE, 0.0, 0.0)
    # the reload's pause (drive 0, motors off, Start), then the run's end's stream pause and
    # Start: nothing between them (a terminate's thread is held from setting it going)
    paused = oi.halt().data + oi.motors_off().data + oi.start().data
    assert outbound(record).endswith(paused + oi.pause_stream().data + oi.start().data)
    assert left == 1


@pytest.mark.parametrize("brushes", [False, True])
def test_a_resume_after_the_robot_s_own_fall_does_not_send_the_drive_from_before_it(
    until: Callable[..., None], tmp_path: Path, brushes: bool
) -> None:
    """Forward into a drop: the robot falls to Passive by itself (the cliff), the tree sees
    it and enters Safe again, a breakpoint pauses there. The resume sent Safe and then the
    forward Drive the tree had sent before the fall (the robot's last wheel command), so the
    robot drove on over the edge before the tree's next tick. Only Safe is sent again: with
    the brushes and vacuum on before the fall (``brushes``), not them either (the robot
    stopped them as it fell)."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    (tmp_path / "edge.yaml").write_text(over_the_edge(brushes=brushes))
    rig = Rig(mission=tmp_path / "edge.yaml", world=tmp_path / "ledge.yaml")
    safe_again = rig.node("safe again")
    rig.session.request("break", safe_again, "success")
    written: list[str] = []
    send_many = rig.connection.send_many
    seen: dict[str, object] = {}
    ticks = rig.after_each_tick(lambda runner: (rig.session.state.paused, rig.robot()))

    def noting(commands: Any) -> None:
        written.extend(c.name for c in commands)
        send_many(commands)

    def operator(rig: Rig) -> None:
        until(lambda: rig.session.state.paused)
        seen["fell"] = rig.connection.last_fallback
        rig.connection.send_many = noting  # type: ignore[method-assign]
        rig.session.request("resume")

    summary = rig.run_with(operator)
    assert seen["fell"] is not None  # the robot's own fall, to Passive
    assert written == ["safe"], written
    breakpoint_tick = [paused for paused, _ in ticks].index(True)
    resumed = [robot for _, robot in ticks[breakpoint_tick + 1 :]]
    assert len(resumed) > 60  # the 1 s wait's ticks (67 of 15 ms), to the mission's end
    assert set(resumed) == {(OIMode.SAFE, 0.0, 0.0)}
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    resumes = [e.text for e in rig.feed.events if e.text.startswith("resume")]
    # the runner forgets the wheel command at the fall (runtime/loop.py): nothing to say
    assert resumes == ["resume (resumed by the operator): back to Safe; the tree goes on"]


def test_a_success_a_forced_condition_caused_says_so_in_the_summary(tmp_path: Path) -> None:
    """A forced FAILURE was named in the summary's reason, a forced SUCCESS not: a patrol
    with its battery check forced to SUCCESS ended SUCCESS after one tick, as if it were its
    own."""
    low = tmp_path / "low.yaml"
    low.write_text(
        "mission: low\ntree:\n  fallback:\n    - {name: low battery, battery: {below: 15%}}\n"
        "    - wait: 30s\n"
    )
    rig = Rig(mission=low)
    rig.session.request("force", rig.node("low battery"), "success")
    summary = rig.run_with(lambda rig: None)
    assert summary.outcome is Outcome.SUCCESS
    assert summary.reason == "low battery: forced to SUCCESS by the operator"
    assert "outcome      SUCCESS (low battery: forced to SUCCESS by the operator)" in str(summary)


def test_every_force_is_in_the_summary_one_released_before_the_end_too(
    tmp_path: Path, until: Callable[..., None]
) -> None:
    """Only a condition still forced at the end was named in the summary: one forced to
    SUCCESS and released before it went unsaid, though the run may have turned on it. Each
    is said, with the ticks the record gives it, and again by the record's replay."""
    record_path = tmp_path / "released.jsonl"
    rig = Rig(record=record_path)
    no_bump, no_cliff = rig.node("no bump"), rig.node("no cliff")

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("force", no_bump, "success")
        until(lambda: no_bump in rig.session.state.forced)
        until(lambda: rig.ticks(ticked=True) > 100)
        rig.session.request("force", no_bump, "none")
        rig.session.request("force", no_cliff, "success")
        until(lambda: list(rig.session.state.forced) == [no_cliff])
        until(lambda: rig.ticks(ticked=True) > 150)
        rig.session.request("stop")

    summary = rig.run_with(operator)
    rig.stack.close()
    assert summary.outcome is Outcome.INTERRUPTED
    record = load_record(record_path)
    on, off, cliff = (note["tick"] for _, note in record.notes if "force" in note)
    assert off == cliff and off > on
    first, second = summary.forced
    assert first.startswith(f"no bump to SUCCESS at tick {on} (t=")
    assert f"released at tick {off} (t=" in first
    assert second.startswith(f"no cliff to SUCCESS at tick {cliff} (t=")
    assert "released" not in second  # forced to the end
    assert f"forced       by the operator: {first}; {second}" in str(summary).splitlines()
    _, replayed = replay_into_feed(
        record, load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2, rig.packets, 115200, "x"
    )
    assert replayed.forced == summary.forced


def test_the_operator_s_acts_are_on_the_page_at_the_tick_the_log_and_the_record_say(
    until: Callable[..., None], tmp_path: Path
) -> None:
    """A control is applied before a frame's tick: the page's event log stamped it with the
    feed's newest record, the tick before (page "time 3.15, tick 210"; the log t=3.165, the
    record tick 211). Event times are to the ms (21.689999999999998 was sent)."""
    record_path = tmp_path / "acts.jsonl"
    rig = Rig(record=record_path)
    no_bump = rig.node("no bump")

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 1447)  # past 21.69 s
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        rig.session.request("force", no_bump, "failure")
        rig.session.request("resume")
        waited(rig.ended, "the run's end")

    rig.run_with(operator)
    notes = [note for _, note in load_record(record_path).notes]
    acts = {("pause" if "pause" in n else "resume" if "resume" in n else "force"): n for n in notes}
    events = {e.text.split(" ")[0]: e for e in rig.feed.events if e.kind in ("control", "force")}
    for act, word in (("pause", "pause"), ("resume", "resume"), ("force", "no")):
        assert events[word].tick == acts[act]["tick"], (act, events[word], acts[act])
    pause_tick = acts["pause"]["tick"]
    paused_at = next(r.time for r in rig.feed.since(0)[0] if r.tick == pause_tick)
    assert events["pause"].time == round(paused_at, 3)
    assert all(e.time == round(e.time, 3) for e in rig.feed.events)


def test_a_replayed_pause_says_its_safe_stop_was_replayed_not_sent(
    until: Callable[..., None], tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``roomba-bt monitor RECORD`` said "safe stop sent drive, motors, start" though it
    sends nothing to any robot; and it printed each replayed act on stderr too (INFO
    lines before the page's URL), which the page's event log has: at ``-v`` only now."""
    record_path = tmp_path / "paused.jsonl"
    rig = Rig(record=record_path)

    def operator(rig: Rig) -> None:
        paused_after(rig, until, 100)
        rig.session.request("resume")
        until(lambda: not rig.session.state.paused)
        rig.session.request("stop")

    rig.run_with(operator)
    live = [e.text for e in rig.feed.events if e.kind == "control"]
    assert any(t.startswith("pause (paused by the operator): safe stop sent drive") for t in live)
    caplog.set_level(logging.INFO)
    caplog.clear()
    replayed, _ = replay_into_feed(
        load_record(record_path), load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.monitor.session"]
    assert said == [], said
    caplog.set_level(logging.DEBUG)  # -v: said on stderr too
    replay_into_feed(
        load_record(record_path), load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x",
    )  # fmt: skip
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.monitor.session"]
    assert any(m.startswith("monitor: pause (paused by the operator)") for m in said), said
    texts = [e.text for e in replayed.events if e.kind == "control"]
    pause = next(t for t in texts if t.startswith("pause"))
    resume = next(t for t in texts if t.startswith("resume"))
    assert "safe stop sent" not in pause and "safe stop replayed drive" in pause, pause
    assert "sent to no robot" in pause and "sent to no robot" in resume, resume
    # docs/monitor.md quotes the event's words after its act ("pause (...): ")
    assert_quoted("docs/monitor.md", "safe stop replayed drive", pause.split("): ", 1)[1])


@pytest.mark.parametrize("keep_awake", [False, None])
def test_a_long_pause_without_keep_awake_counts_down_to_the_robot_s_sleep_from_its_start(
    until: Callable[..., None], monkeypatch: pytest.MonkeyPatch, keep_awake: bool | None
) -> None:
    """A robot paused in Passive on a link without keep-awake falls asleep after 5 minutes
    and the run ends (connection lost). The page's banner says so from the pause's start
    and counts down in the stream's time (it said nothing for 4 minutes, then "in about
    60 s" for the rest); the event log and the terminal's log warn once, 4 minutes in (here
    the robot sleeps at 3 s, warned at 1.5 s). Nothing of it with keep-awake on, which keeps
    the robot awake."""
    monkeypatch.setattr(session_module, "ROBOT_SLEEPS_S", 3.0)
    monkeypatch.setattr(session_module, "SLEEP_WARNING_S", 1.5)
    rig = Rig(keep_awake=keep_awake)
    notes: dict[int, str] = {}  # paused frames -> the banner's countdown then

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        began = rig.ticks(ticked=False)
        for frames in (1, 67, 134):  # the pause's start, 1 s and 2 s of stream in
            until(lambda frames=frames: rig.ticks(ticked=False) - began >= frames)
            notes[frames] = rig.session.state.sleep_note
        seen_reason = rig.session.state.pause_reason
        notes[0] = seen_reason
        rig.session.request("stop")

    logger = logging.getLogger("roomba_bt")
    handler = EventLogHandler(rig.feed)  # as the CLI's monitor has it: the log's warnings
    logger.addHandler(handler)
    try:
        rig.run_with(operator)
    finally:
        logger.removeHandler(handler)
    warnings = [e.text for e in rig.feed.events if "without keep-awake" in e.text]
    [pause] = [e.text for e in rig.feed.events if e.text.startswith("pause (")]
    assert notes[0] == "paused by the operator"  # the reason stays the reason
    if keep_awake is False:  # once: it was also there again as "monitor: paused 4 min ..."
        prefix = "this link cannot keep the robot awake: the run ends 3 s into the pause; "
        assert notes[1].startswith(prefix), notes
        # the countdown is the stream's seconds left, give or take the frame read
        left = {n: int(notes[n].removeprefix(prefix).removesuffix(" s left")) for n in (1, 67, 134)}
        assert left[1] == 3 and left[67] in (1, 2) and left[134] in (0, 1), notes
        assert pause.endswith("this link cannot keep the robot awake: the run ends 3 s into "
                              "the pause unless resumed"), pause  # fmt: skip
        assert warnings == [
            "paused 2 s without keep-awake: the robot sleeps after 3 s paused in Passive "
            "(in 2 s; the run then ends, connection lost); resume or stop"
        ]  # 1.5 s, 1.5 s left: whole seconds, rounded half to even
    else:
        assert warnings == [] and set(notes.values()) == {"", "paused by the operator"}
        assert "keep the robot awake" not in pause


def test_a_pause_the_robot_fell_asleep_in_says_the_stop_met_a_sleeping_robot(
    until: Callable[..., None], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A pause on a link without keep-awake, the robot asleep after its minutes in Passive
    (here 3 s): the run ends, connection lost (exit 8), and its summary said the stop was
    unconfirmed because "the robot had sent no valid frame for 0.51 s before it", as if the
    line had failed. It says what is known: the stop was written to a robot asleep, seen
    stopped before it slept (until session 39 under "NOT DELIVERED:", in capitals)."""
    monkeypatch.setattr(silence, "SLEEP_AFTER_S", 3.0)
    monkeypatch.setattr(sim_robot, "PASSIVE_SLEEP_SECONDS", 3.0)
    rig = Rig(keep_awake=False)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("pause")
        waited(rig.ended, "the run's end")

    summary = rig.run_with(operator)
    assert rig.sim.asleep
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 8
    assert "the robot fell asleep" in summary.reason
    # the pause's stop, confirmed by its frames, then sleep: stopped, and not said in the
    # capitals of a stop that failed to reach a robot that may be moving ("NOT DELIVERED:")
    assert summary.safe_stop.startswith(
        "asleep and stopped; last seen stopped in Passive, in the frames it sent after every "
        "command written"
    ), summary.safe_stop
    assert "the stop was written but is unconfirmed: the robot was asleep" in summary.safe_stop
    assert "no valid frame" not in summary.safe_stop
    assert summary.final_mode_text() == (
        "unknown: asleep, last seen stopped in Passive; the stop unconfirmed"
    )
    # the command line's line after an internal error says it in the same words (it said
    # "safe stop NOT DELIVERED: ..." of the robot the summary said asleep and stopped)
    rig.stack.close()
    assert _stop_said(rig.stack) == f"safe stop {summary.safe_stop}"
    # the page's robot panel in the same words: its wheels and motors said "the stop was
    # not delivered" beside the banner's "the stop unconfirmed"
    newest = rig.feed.latest()
    assert newest is not None
    robot = state_view(rig.feed, *rig.feed.at(newest.tick))["robot"]
    after_the_end(robot, Ending.of(summary))
    assert robot["mode"] == summary.final_mode_text()
    said = (robot["wheels"]["source"], robot["motors"]["note"])
    assert all(t.endswith("last seen before the end; the stop unconfirmed") for t in said), said


def test_a_stall_ridden_through_during_a_pause_says_the_run_stays_paused(
    until: Callable[..., None], caplog: pytest.LogCaptureFixture
) -> None:
    """The stream stalled while the operator held the run paused: the frames' return said
    "valid frames are back after 705 ms; the mission goes on", of a run nobody had resumed.
    It stays paused, and says so; a stall while running still says the mission goes on."""
    caplog.set_level(logging.WARNING, logger="roomba_bt.runtime.loop")
    rig = Rig(faults=Faults(stream_gap_at=2.0, stream_gap_s=0.8))
    summary = rig.runner.summary

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("pause")
        until(lambda: summary.stalls_ridden == 1)
        until(lambda: rig.ticks(ticked=False) > 200)  # frames back, the tree still frozen
        ticked = rig.ticks(ticked=True)
        assert rig.session.state.paused and rig.runner.clock_held
        assert rig.robot() == (OIMode.PASSIVE, 0.0, 0.0)
        assert rig.ticks(ticked=True) == ticked
        rig.session.request("stop")

    assert rig.run_with(operator).stalls == 1
    [back] = [r.getMessage() for r in caplog.records if "are back" in r.getMessage()]
    assert " ms; the run stays paused (the mission goes on at the resume);" in back, back
    caplog.clear()
    rig = Rig(faults=Faults(stream_gap_at=2.0, stream_gap_s=0.8))
    rig.run_with(lambda rig: until(lambda: rig.runner.summary.stalls_ridden == 1))
    [back] = [r.getMessage() for r in caplog.records if "are back" in r.getMessage()]
    assert " ms; the mission goes on;" in back, back


@pytest.mark.parametrize("by", ["the monitor", "request_stop"])
def test_a_stop_asked_for_during_a_stall_ends_the_run_without_waiting_for_a_frame(
    by: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Stop pressed while the watchdog rides a stall through: the run waited for the next
    frame (up to ``--grace``) before it ended, the robot's stop waiting with it, while the
    program's ``request_stop`` acts on an empty read. The operator's stop acts on the next
    read too, frame or not. The record of either replays to that end: the replay ended at
    the tick before and called the stall's drive 0 its first difference (exit 1). (The stop
    is asked on the run's own thread, as the watchdog trips, so that on the virtual clock
    the gap is not over before the operator's thread gets a turn.)"""
    record_path = tmp_path / "stalled.jsonl"
    rig = Rig(record=record_path, faults=Faults(stream_gap_at=2.0, stream_gap_s=1.5))
    asked: list[float] = []

    class StopAtTheTrip(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if "waiting up to" in record.getMessage():  # the watchdog's trip, said
                asked.append(rig.connection.transport.now())
                if by == "the monitor":
                    rig.session.request("stop", by="the test")
                else:
                    rig.runner.request_stop("stopped by the operator")

    logger, handler = logging.getLogger("roomba_bt.runtime.loop"), StopAtTheTrip()
    logger.addHandler(handler)
    try:
        summary = rig.run_with(lambda rig: None, ended=True)
    finally:
        logger.removeHandler(handler)
    ended = rig.connection.transport.now()
    rig.stack.close()
    assert len(asked) == 1 and asked[0] < 3.5  # in the gap (2.0 s to 3.5 s of stream)
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert summary.reason == "stopped by the operator"
    assert summary.stalls == 1 and summary.stalls_ridden == 0  # ended before frames came back
    assert ended - asked[0] < 0.2, (asked, ended)  # a read or two: not the 1.5 s to a frame
    stops = [e.text for e in rig.feed.events if e.text.startswith("stop:")]
    if by == "the monitor":
        assert stops == ["stop: the run ends (as on Ctrl-C); from the test"]
    capsys.readouterr()
    assert main(["replay", str(record_path)]) == 0
    out = capsys.readouterr().out
    assert "replay: the recorded run was stopped by the operator" in out, out
    assert "first difference" not in out, out


@pytest.mark.parametrize("lost", ["asleep", "port gone"])
def test_the_record_of_a_link_lost_while_paused_replays_to_its_loss_not_a_difference(
    lost: str,
    tmp_path: Path,
    until: Callable[..., None],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A run paused (the tree frozen) whose robot fell asleep, or whose cable was pulled,
    before the resume: its tree's last tick came long before the link's end, and the
    replay, which marked the link's loss only after a tick of the tree, never marked it.
    ``roomba-bt replay`` said "first difference" (exit 1) at the run's asking after the
    sleeping robot, and ``roomba-bt monitor RECORD`` "replay diverged from the record",
    read as a broken record or a changed mission."""
    monkeypatch.setattr(silence, "SLEEP_AFTER_S", 3.0)
    monkeypatch.setattr(sim_robot, "PASSIVE_SLEEP_SECONDS", 3.0)
    record_path = tmp_path / "lost.jsonl"
    faults = Faults(disconnect_at=2.5) if lost == "port gone" else None
    rig = Rig(record=record_path, keep_awake=False, faults=faults)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("pause")
        waited(rig.ended, "the run's end")

    summary = rig.run_with(operator, ended=True)
    rig.stack.close()
    assert summary.outcome is Outcome.CONNECTION_LOST, summary.reason
    assert summary.pauses == 1
    # the pause's stop seen taken for seconds: it said "the robot may still be moving: pick
    # it up" of a robot last seen stopped in Passive
    assert "may still be moving" not in summary.safe_stop, summary.safe_stop
    assert "last seen stopped in Passive" in summary.safe_stop, summary.safe_stop
    capsys.readouterr()
    assert main(["replay", str(record_path)]) == 0
    out = capsys.readouterr().out
    assert "replay: the recorded run lost its link at mission time" in out, out
    assert "first difference" not in out
    diverged: list[str] = []
    feed, _ = replay_into_feed(
        load_record(record_path), load_mission(SHUTTLE, {}, profile=CREATE2), CREATE2,
        rig.packets, 115200, "x", diverged_at=diverged.append,
    )  # fmt: skip
    assert diverged == []
    assert feed.finished is not None and "the recorded run lost its link" in feed.finished


def test_the_board_shows_the_mission_s_keys_not_their_declared_types(
    tmp_path: Path, clean_blackboard: None
) -> None:
    """The keys' declared types are kept on py_trees' blackboard (``write_key`` holds a
    plugin's write to them, session 25); the monitor's board lists the keys only."""
    mission = tmp_path / "keys.yaml"
    mission.write_text(
        "blackboard:\n  n: {type: int, initial: 0}\ntree:\n  sequence:\n"
        "    - set: {key: n, value: 2}\n    - wait: 0.1s\n"
    )
    rig = Rig(mission=mission)
    assert rig.run_with(lambda rig: None).outcome is Outcome.SUCCESS
    latest = rig.feed.latest()
    assert latest is not None
    assert dict(rig.feed.blackboard(latest)) == {"/mission/n": 2}


def test_the_record_of_a_stall_is_shown_whole_the_watchdogs_trip_among_its_events(
    tmp_path: Path,
) -> None:
    """``roomba-bt monitor RECORD``: a run whose watchdog stopped the wheels is replayed past
    the stall to its end. Before, the replay ran no watchdog and stopped at the stall as a
    difference: a 90 s noisy run showed '6 ticks, input ended'."""
    path = record_run(tmp_path, stream_gap_link())
    record = load_record(path)
    mission = load_mission(record.mission_file or "", {}, profile=CREATE2)
    feed, summary = replay_into_feed(
        record, mission, CREATE2, tuple(record.header["packets"]), 115200, str(path)
    )
    # not its first difference: the end of the record, where the run's --timeout ended it
    assert summary.reason.startswith("end of the record: the recorded run ended in timeout")
    assert summary.mission_time_s >= 3.0  # the run's 3 s, as recorded
    assert summary.stalls == summary.stalls_ridden == 1
    notes = [e.text for e in feed.events if e.kind == "note"]
    assert notes == ["watchdog: no valid sensor frame for 105 ms"]


class ScriptedOperator:
    """The monitor's session as the run's gate, its operator's requests made at set stream
    ticks (the first frame at or past each) through its API, from the tick thread: on the
    virtual clock a page's thread acts at no tick the test can name."""

    def __init__(self, session: MonitorSession, acts: list[tuple[Any, ...]]) -> None:
        """``acts``: ``(tick, action)``, or ``(tick, action, node, value)`` (a force)."""
        self.session = session
        self.acts = sorted(acts)

    def before_tick(self, runner: MissionRunner) -> bool:
        while self.acts and self.acts[0][0] <= runner.snapshot.tick:
            self.session.request(*self.acts.pop(0)[1:])
        return self.session.before_tick(runner)

    def after_tick(self, runner: MissionRunner) -> None:
        self.session.after_tick(runner)

    def holds(self, runner: MissionRunner) -> bool:
        return self.session.holds(runner)


def test_a_run_paused_stepped_stopped_and_late_after_a_fall_replays_byte_for_byte(
    tmp_path: Path,
) -> None:
    """Session 27's run1.jsonl, without a browser: a real-time `clean` run paused, resumed,
    stepped and stopped from the page, whose host, loaded, wrote its Safe after a cliff fall
    0.36 s after the fall's frame (stale frames dropped). The record's replay starved at the
    Motors after that Safe ('input ended' at 75 s of 92 s; the replay wrote Safe at the
    frame's time), and, past it, ticked the tree on beyond the operator's stop (the stop was
    not in the record). Now it writes the recorded bytes to the end, and says how the run
    ended."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    source, path = tmp_path / "edge.yaml", tmp_path / "run.jsonl"
    source.write_text(over_the_edge("5s", brushes_again=True))
    mission = load_mission(source, {}, profile=CREATE2)
    link = BusyAfterTheFall(Simulator(load_world(tmp_path / "ledge.yaml"), CREATE2, 0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=60.0,
                     record=Recording(path, str(source)))  # fmt: skip
    # every frame of the pauses kept (as Rig keeps them): compared with the replay's below
    feed = RunFeed(history=5000, mission_name=mission.name, thin_pauses=False)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True, stream_packets=stack.packets)
    acts = [(100, "pause"), (150, "step"), (160, "resume"),  # before the fall (at ~4.3 s)
            (420, "pause"), (440, "resume"), (500, "stop")]  # after it, in the wait  # fmt: skip
    stack.runner.gate = ScriptedOperator(session, acts)
    live = stack.run()
    stack.close()
    assert live.outcome is Outcome.INTERRUPTED and live.reason == "stopped by the operator"
    assert live.falls == {"cliff": 1} and live.stale_frames_dropped >= 20
    record = load_record(path)
    assert link.busy_s == 0.0  # the host was busy after the fall
    assert [next(iter(n)) for _, n in record.notes] == [
        "pause", "resume",  # pause, then the step: its resume and its pause
        "pause", "resume",  # the resume; after the fall, a pause
        "pause", "resume",  # and its resume
        "ended",  # the operator's stop
    ]  # fmt: skip
    differences: list[str] = []
    replayed, summary = replay_into_feed(
        record, load_mission(source, {}, profile=CREATE2), CREATE2, stack.packets,
        115200, "x", diverged_at=differences.append,
    )  # fmt: skip
    assert differences == []  # the same bytes, to the safe stop's
    assert summary.ticks == live.ticks and summary.falls == live.falls
    assert _ticks(replayed) == _ticks(feed)
    assert record.ending is not None and record.ending["time"] == round(live.mission_time_s, 3)
    ended = f"the recorded run was stopped by the operator at t={record.ending['time']:.2f} s"
    assert replayed.finished == f"{ended} (recorded run, {live.ticks} ticks)"
    assert replayed.events[-1].text == ended


#: Safe, then a wait a 300 ms hold of Safe ends (20 frames of mission time)
HELD_300MS = """
tree:
  sequence:
    - mode: safe
    - wait: 20s
      until: {held: {for: 300ms, do: {oi_mode: safe}}}
"""


def _held_run(
    tmp_path: Path, acts: list[tuple[int, str]]
) -> tuple[RunSummary, list[tuple[int, int | None, int, str]]]:
    """HELD_300MS on the virtual clock, the operator's acts at their stream ticks; per tree
    tick: its snapshot's tick and previous_tick, the steps done so far, the root's status."""
    source = tmp_path / "held.yaml"
    source.write_text(HELD_300MS)
    mission = load_mission(source, {}, profile=CREATE2)
    seen: list[tuple[int, int | None, int, str]] = []

    def observe(runner: MissionRunner) -> None:
        snapshot = runner.snapshot
        seen.append((snapshot.tick, snapshot.previous_tick, runner.summary.steps,
                     runner.mission.root.status.value))  # fmt: skip

    stack = RunStack(mission, SimLink(Simulator(load_world("empty-room"), CREATE2, 0)),
                     profile=CREATE2, timeout_s=30.0, observer=observe)  # fmt: skip
    feed = RunFeed(history=5000, mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True, stream_packets=stack.packets)
    stack.runner.gate = ScriptedOperator(session, acts)
    summary = stack.run()
    stack.close()
    return summary, seen


def test_a_hold_counts_through_single_steps_and_a_pause_is_no_gap(tmp_path: Path) -> None:
    """Paused 7 ticks into the hold, then stepped: the hold goes on counting a frame of
    mission time a step (``previous_tick`` is the tick the tree last ticked on, not the
    paused frame before), so the wait ends on a step, the 12th or so, not after the
    operator's resume (it restarted on every step's tick, and never held while stepping)."""
    steps = [(40 + 6 * n, "step") for n in range(30)]
    summary, seen = _held_run(tmp_path, [(8, "pause"), *steps, (400, "resume")])
    assert summary.outcome is Outcome.SUCCESS
    assert all(now[1] == before[0] for before, now in itertools.pairwise(seen))
    ended = next(steps_done for _, _, steps_done, status in seen if status == "SUCCESS")
    assert 8 <= ended < 20  # by a step: 20 frames of mission time, 8 of them before the pause


def test_a_pause_and_its_resume_do_not_restart_a_hold(tmp_path: Path) -> None:
    """Paused for 2 s in the middle of the hold: the wait ends 300 ms of mission time after
    the hold began (the pause's 2 s left out of both), not 300 ms after the resume."""
    summary, seen = _held_run(tmp_path, [(8, "pause"), (150, "resume")])
    assert summary.outcome is Outcome.SUCCESS and summary.pauses == 1
    assert all(now[1] == before[0] for before, now in itertools.pairwise(seen))
    paused = next(n for n, (tick, *_) in enumerate(seen) if tick > 150)
    assert len(seen) - paused < 20  # fewer ticks after the resume than the hold is long


def test_replay_does_the_operators_pauses_steps_and_forces_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``roomba-bt replay`` of a run paused, stepped twice, resumed and ended by a forced
    condition from the monitor writes the recorded bytes to the end, exit 0. Before, replay
    did none of the operator's acts: it differed at the first pause ("expected Drive (137)
    89 00 00 00 00, sent Drive (137) 89 00 64 80 00"), exit 1, and pointed to ``roomba-bt
    monitor``, which does them."""
    path = tmp_path / "run.jsonl"
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=30.0,
                     record=Recording(path, str(SHUTTLE)))  # fmt: skip
    feed = RunFeed(history=5000, mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True, stream_packets=stack.packets)
    acts = [(100, "pause"), (150, "step"), (160, "step"), (170, "resume"),
            (300, "force", "no bump", "failure")]  # fmt: skip
    stack.runner.gate = ScriptedOperator(session, acts)
    live = stack.run()
    stack.close()
    assert live.outcome is Outcome.FAILURE and "forced to FAILURE" in live.reason, live.reason
    assert (live.pauses, live.steps) == (1, 2)
    record = load_record(path)
    assert [next(iter(n)) for _, n in record.notes] == [
        "pause", "resume", "pause", "resume", "pause", "resume", "force", "ended",
    ]  # fmt: skip
    capsys.readouterr()
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"replay: the tree wrote the same {record.out_bytes} bytes as the recorded run" in out
    assert "in 1 pause, 2 steps, left out of mission time" in out, out
    assert "forced       by the operator: no bump to FAILURE at tick 300" in out
    assert f"ticks        {live.ticks} " in out
    # a reload is the one act replay cannot do again: the record has no copy of the mission
    header, *rest = path.read_text().splitlines(keepends=True)
    reload = {"t": 2.5, "d": "note", "note": {"reload": "shuttle", "at": "before", "tick": 250}}
    reloaded = tmp_path / "reloaded.jsonl"
    reloaded.write_text("".join([header, json.dumps(reload) + "\n", *rest]))
    assert main(["replay", str(reloaded)]) == 1
    out = capsys.readouterr().out
    assert (
        "replay: the recorded run holds operator acts replay cannot do again (reload at "
        "2.50 s): a reload (the record has no copy of the new mission)" in out
    ), out


def test_a_pause_longer_than_the_wall_limit_is_no_hung_run(until: Callable[..., None]) -> None:
    """``--wall-limit`` is for a behaviour stuck in a tick: the time an operator holds the run
    paused does not count (a pause longer than the limit ended the run as HUNG, exit 4,
    blaming the simulator's link where the paused loop was reading)."""
    rig = Rig()
    rig.runner.wall_limit_s = 2.0
    rig.session.request("pause")  # at the first frame: none of the limit spent on driving
    paused_at: list[float] = []

    def operator(rig: Rig) -> None:
        until(lambda: rig.session.state.paused)
        paused_at.append(time.monotonic())
        # wall time past the limit, the run held paused all along
        until(lambda: time.monotonic() - paused_at[0] > 3.0)
        rig.session.request("stop")

    summary = rig.run_with(operator)
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert summary.reason == "stopped by the operator"
    assert summary.exit_code == 130


def test_a_control_the_run_will_not_apply_is_refused_though_the_one_before_is_still_queued(
    until: Callable[..., None],
) -> None:
    """Requests are checked against the state the queued ones leave, not the state the tick
    thread has got to: two pauses pressed at once both got 202 and one did nothing, three
    steps got 202 and the run stepped once, a pause after a stop got 202."""
    rig = Rig()
    rig.session.request("pause")  # queued: the run has not started
    with pytest.raises(ControlRefused, match="already paused"):
        rig.session.request("pause")
    steps: list[str] = []

    def operator(rig: Rig) -> None:
        until(lambda: rig.session.state.paused)
        with rig.session._lock:  # both arrive before the tick thread applies the first
            rig.session.request("step")
            for _ in range(2):
                try:
                    rig.session.request("step")
                except ControlRefused as exc:
                    steps.append(str(exc))
        until(lambda: rig.runner.summary.steps == 1 and rig.session.state.paused)
        with rig.session._lock:
            rig.session.request("stop")
            with pytest.raises(ControlRefused, match="already stopping"):
                rig.session.request("stop")
            with pytest.raises(ControlRefused, match="the run is stopping"):
                rig.session.request("pause")
            with pytest.raises(ControlRefused, match="the run is stopping"):
                rig.session.request("resume")

    summary = rig.run_with(operator)
    assert steps == ["a step is under way: step when it has paused again"] * 2
    assert (summary.pauses, summary.steps) == (1, 1)
    assert summary.reason == "stopped by the operator"
    controls = [e.text.split(" ")[0] for e in rig.feed.events if e.kind == "control"]
    assert controls == ["pause", "resume", "pause", "stop:"]


class OneFrameLate(SimLink):
    """Once :attr:`late`, each read gives the bytes of the read before: a frame the robot
    sent before a command it then heard arrives after the command was written, as a
    real-time link's (a USB adapter's latency, a busy host's backlog) does."""

    late = False
    _held = b""
    #: the frames given late so far
    given_late = 0

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        if not self.late:
            return data
        out, self._held = self._held, data
        self.given_late += bool(out)
        return out


def test_a_thinned_pause_keeps_the_frame_that_shows_the_wheels_stopped(
    until: Callable[..., None],
) -> None:
    """The frames a pause comes in carry the wheels' speed from before the stop; a live page
    kept the pause's first frame, the next that brought news (Passive: its encoders' step
    from the first taking in the frames left out between) and then a frame a second, so it
    showed PAUSED, Passive and the wheels turning for a second. A paused frame that shows
    the robot moving is kept, and so is the first one that shows it still."""

    rig = Rig(thin_pauses=True, link=OneFrameLate)
    link = rig.connection.transport
    assert isinstance(link, OneFrameLate)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 30 and rig.sim.left_speed and rig.sim.right_speed)
        link.late = True
        until(lambda: link.given_late > 2)  # the pause's frame is one sent before it
        rig.session.request("pause")
        until(lambda: rig.runner.summary.paused_s > 2.0)
        rig.session.request("stop")

    rig.run_with(operator)
    shown = _paused_frames_shown(rig)
    assert shown[1][1] == "Passive" and shown[1][2] != 0, shown  # sent before the stop: moving
    still = next(d for d, mode, left, right in shown if (left, right) == (0, 0))
    assert still <= 4, shown  # the stop shown a frame or two later, not a second


def _paused_frames_shown(rig: Rig) -> list[tuple[int, str, int, int]]:
    """The first five frames a thinned pause kept, as the page shows them (each with the one
    before it, as the server does): ticks since the pause's first, mode, wheels."""
    from roomba_bt.monitor.views import state_view

    paused = [r for r in rig.feed.since(0)[0] if not r.ticked]
    shown = []
    for r in paused[:5]:
        _, earlier = rig.feed.at(r.tick)
        view = state_view(rig.feed, r, earlier)["robot"]
        wheels = view["wheels"]
        shown.append((r.tick - paused[0].tick, view["mode"], wheels["left"], wheels["right"]))
    return shown


def test_a_thinned_pause_of_a_run_in_passive_keeps_the_first_still_frame(
    until: Callable[..., None],
) -> None:
    """dock-builtin's Seek Dock drives the robot in Passive: no requested speed in its
    frames, and no mode change at the pause to keep a frame. The pause's first frame was
    compared with nothing (judged still), so the first still frame after it was left out and
    the page showed PAUSED, Passive and 296 mm/s for a second (a verifier's finding). The
    first paused frame is compared with the last ticked one."""
    rig = Rig(mission=HERE.parents[1] / "missions" / "dock-builtin.yaml", thin_pauses=True)

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 100 and bool(rig.sim.left_speed))
        rig.session.request("pause")
        until(lambda: rig.runner.summary.paused_s > 2.0)
        rig.session.request("stop")

    rig.run_with(operator)
    shown = _paused_frames_shown(rig)
    still = next(d for d, mode, left, right in shown if (left, right) == (0, 0))
    assert still <= 4, shown  # the stop shown a frame or two later, not a second
