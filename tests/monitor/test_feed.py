"""The monitor's feed: what it says of a failed node, on the page and in its event log; the
robot panel's cleaning motors."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import motors_view, state_view
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.tick_guard import stop_first
from roomba_bt.sim import SimLink, Simulator, load_world

from .live import feed_of_run

#: what a plugin's message may hold: code sets it, no file's check refuses it
HOSTILE = "\x1b[2J\n[ok] robot stopped"


class Sayer(py_trees.behaviour.Behaviour):
    """A plugin-like leaf that fails saying :data:`HOSTILE`."""

    def update(self) -> Status:
        self.feedback_message = HOSTILE
        return Status.FAILURE


def test_a_failed_leaf_s_message_is_one_line_on_the_page_and_in_the_events() -> None:
    """A leaf's ``feedback_message`` went to the page and the event log as it was (a failed
    composite's reason was escaped already, by ``failure_reason``): "\\n[ok] ..." started an
    event line of its own. Escaped where the feed takes it; the leaf keeps its message."""
    sayer = Sayer(name="sayer")
    root = py_trees.composites.Sequence("steps", memory=True, children=[sayer])
    feed = feed_of_run(root, "sayer", history=100)
    said = "\\x1b[2J\\x0a[ok] robot stopped"
    newest = feed.latest()
    assert newest is not None
    assert newest.reasons[[info.name for info in feed.infos].index("sayer")] == said
    events = [e.text for e in feed.events if e.kind == "status"]
    assert f"sayer -> FAILURE: {said}" in events, events
    assert "steps -> FAILURE: sayer: " + said in events, events
    assert sayer.feedback_message == HOSTILE


BRUSHES = Path(__file__).parent / "missions" / "brushes.yaml"


def _brushes_run(tmp_path: Path) -> tuple[RunFeed, Path, tuple[int, ...]]:
    """The brushes mission for 2 s on the virtual clock, recorded, with a live feed of it."""
    mission = load_mission(BRUSHES, {}, profile=CREATE2)
    path = tmp_path / "brushes.jsonl"
    feed = RunFeed(history=None, mission_name=mission.name)
    feed.set_tree(mission.root)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=2.0, observer=feed.observe,
                     record=Recording(path, str(BRUSHES)))  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    return feed, path, stack.packets


def _robot_at_newest(feed: RunFeed, back: int = 0) -> dict[str, Any]:
    """The robot panel at the newest tick, or ``back`` ticks before it."""
    newest = feed.latest()
    assert newest is not None
    record = feed.record(newest.seq - back)
    assert record is not None
    _, earlier = feed.at(record.tick)
    return dict(state_view(feed, record, earlier)["robot"])


def test_the_robot_panel_shows_the_brushes_and_vacuum_the_run_switched_on(
    tmp_path: Path,
) -> None:
    """The robot panel showed no cleaning motor: an owner watching a clean could not see
    whether the brushes were on. It shows what the motors' standing command (Motors (138))
    set, and what the stream carries of them (packet 14, the brushes' currents 56 and 57);
    a recorded run's view (every tick packed) shows the same."""
    feed, path, packets = _brushes_run(tmp_path)
    robot = _robot_at_newest(feed)
    assert robot["motors"] == {
        "command": "Motors (138)",
        "note": "",
        "main_brush": {"percent": 100, "direction": "inward"},
        "side_brush": {"percent": 100, "direction": "clockwise"},
        "vacuum": {"percent": 100, "direction": None},
    }
    assert robot["overcurrents"] == dict.fromkeys(
        ("main_brush", "side_brush", "left_wheel", "right_wheel"), False
    )
    assert robot["brush_currents_ma"]["main_brush"] > 0
    assert robot["brush_currents_ma"]["side_brush"] > 0
    first = feed.since(0)[0][0]
    assert first.motors is None  # before the motors' command: none stands
    mission = load_mission(BRUSHES, {}, profile=CREATE2)
    replayed, _ = replay_into_feed(load_record(path), mission, CREATE2, packets, 115200, "b")
    # the tick before the end (at the end, the view shows what the safe stop left: off)
    assert _robot_at_newest(replayed, back=1)["motors"] == robot["motors"]
    assert _robot_at_newest(replayed)["motors"]["note"] == "off: the run's safe stop"


def test_pwm_motors_show_each_motor_s_power_and_a_pause_shows_them_off() -> None:
    """PWM Motors (144): a duty cycle each, a negative brush the other way; in Passive (the
    pause's safe stop turned them off) none runs, and the panel says why."""
    pwm = oi.pwm_motors(64, -127, 127).data
    shown = motors_view(pwm, OIMode.SAFE, ticked=True)
    assert shown["command"] == "PWM Motors (144)"
    assert shown["main_brush"] == {"percent": 50, "direction": "inward"}
    assert shown["side_brush"] == {"percent": 100, "direction": "clockwise"}
    assert shown["vacuum"] == {"percent": 100, "direction": None}
    paused = motors_view(pwm, OIMode.PASSIVE, ticked=False)
    assert all(paused[m]["percent"] == 0 for m in ("main_brush", "side_brush", "vacuum"))
    assert paused["note"].startswith("off while paused")
    assert motors_view(None, OIMode.SAFE, ticked=True)["note"].startswith("off: no motor")


def _motors_after(
    halt: Callable[[MissionRunner, MonitorSession], None],
) -> list[bytes | None]:
    """The brushes mission with the monitor's session, ``halt`` done in the tick after the
    tree's Motors went out (the brushes on: the tree sends it once); the motors' bytes the
    feed keeps for that tick and the frame after it."""
    mission = load_mission(BRUSHES, {}, profile=CREATE2)
    feed = RunFeed(history=None, mission_name=mission.name)
    feed.set_tree(mission.root)
    session = MonitorSession(feed, simulator=True)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=2.0)
    stack.runner.gate = session
    at: list[int] = []

    def observe(runner: MissionRunner) -> None:  # before the session records the tick
        if "motors" in runner.last_sent and not at:
            at.append(feed.ring.count)
        elif len(at) == 1:
            at.append(feed.ring.count)
            halt(runner, session)

    stack.runner.observer = observe
    try:
        stack.run()
    finally:
        stack.close()
    records = feed.since(0)[0]
    on = records[at[0]].motors
    assert on is not None and on[0] == 138 and on[1] != 0  # the brushes on
    return [record.motors for record in records[at[1] : at[1] + 2]]


def test_the_robot_panel_shows_the_motors_a_halt_turned_off() -> None:
    """The panel showed the tree's last Motors (the brushes on) after the tick guard's or
    the safe stop's "motors off" (written in one batch, ``send_many``), and in the first
    frame of a pause, whose snapshot still says Safe: it shows the last Motors written."""

    def tick_guard(runner: MissionRunner, session: MonitorSession) -> None:
        runner.connection.send_many(stop_first())  # the run's end: halt before the tree's stop

    off = oi.motors_off().data
    assert _motors_after(tick_guard)[0] == off
    assert motors_view(off, OIMode.SAFE, ticked=True)["main_brush"]["percent"] == 0

    def pause(runner: MissionRunner, session: MonitorSession) -> None:
        session.request("pause")  # applied before the next frame's tick, which it records
        observe = session.feed.observe

        def then_stop(runner: MissionRunner, ticked: bool = True) -> tuple[int, ...]:
            changed = observe(runner, ticked)
            if not ticked:  # the paused frame is recorded: the run may end
                session.request("stop")
            return changed

        session.feed.observe = then_stop  # type: ignore[method-assign]

    assert _motors_after(pause)[1] == off
