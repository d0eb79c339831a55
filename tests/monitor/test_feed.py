"""The monitor's feed: what it says of a failed node, on the page and in its event log; the
robot panel's cleaning motors; every streamed packet and the world's dirt, as the page is
sent them."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

from roomba_bt.mission import load_mission
from roomba_bt.monitor.feed import RunFeed, tick_guard_said
from roomba_bt.monitor.recorded import replay_into_feed
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.monitor.views import header_view, motors_view, state_view, world_view
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.packets import expand
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import RunSummary
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


MISSIONS = Path(__file__).parent / "missions"
BRUSHES = MISSIONS / "brushes.yaml"
#: the shuttle on a patch of crumbs, reading dirt detect (15) and wall signal (27), and its
#: world (dirt detect reads 40 where it starts)
CRUMBS, DUSTY_ROOM = MISSIONS / "crumbs.yaml", MISSIONS / "dusty-room.yaml"


def _recorded_run(
    tmp_path: Path, mission_file: Path, world: str | Path = "empty-room"
) -> tuple[RunFeed, Path, tuple[int, ...]]:
    """``mission_file`` for 2 s on the virtual clock in ``world``, recorded, with a live feed
    of it: the feed, the record's path and the stream request."""
    mission = load_mission(mission_file, {}, profile=CREATE2)
    path = tmp_path / f"{mission.name}.jsonl"
    feed = RunFeed(history=None, mission_name=mission.name)
    feed.set_tree(mission.root)
    link = SimLink(Simulator(load_world(world), CREATE2, seed=0))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=2.0, observer=feed.observe,
                     record=Recording(path, str(mission_file)))  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    return feed, path, stack.packets


def _replayed(mission_file: Path, path: Path, packets: tuple[int, ...]) -> RunFeed:
    """The record at ``path`` replayed into a feed: what ``roomba-bt monitor RECORD`` shows."""
    mission = load_mission(mission_file, {}, profile=CREATE2)
    replayed, _ = replay_into_feed(load_record(path), mission, CREATE2, packets, 115200, "r")
    return replayed


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
    feed, path, packets = _recorded_run(tmp_path, BRUSHES)
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
    replayed = _replayed(BRUSHES, path, packets)
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


def test_no_motor_command_in_passive_says_no_cycle_runs_them_unless_one_does() -> None:
    """Paused with no motor command standing, the panel said "off: the robot is in Passive (a
    built-in cycle runs its own)", though the pause ends a cycle and none ran."""
    paused = motors_view(None, OIMode.PASSIVE, ticked=False)["note"]
    assert paused == "off: paused in Passive (the pause's safe stop); no motor command stands"
    passive = motors_view(None, OIMode.PASSIVE, ticked=True)["note"]
    assert "runs its own" not in passive and passive.startswith("off: no motor command stands")


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


def test_every_streamed_packet_goes_to_the_page_named_by_the_packet_table(
    tmp_path: Path,
) -> None:
    """The robot panel decodes a fixed set of sensors: dirt detect (15) and wall signal (27),
    which a plugin's condition reads and the stream carries, were nowhere on the page. Every
    packet of the stream request goes to the page raw, in the frame's order, and the header
    names each by the OI packet table (the name a mission reads it by, its unit); a recorded
    run's view (every tick packed) shows the same."""
    feed, path, packets = _recorded_run(tmp_path, CRUMBS, DUSTY_ROOM)
    streamed = _robot_at_newest(feed)["streamed"]
    assert tuple(streamed["ids"]) == tuple(m for p in packets for m in expand(p))
    values = dict(zip(streamed["ids"], streamed["values"], strict=True))
    assert (values[15], values[27]) == (40, 0)  # on the crumbs, no wall near
    names = header_view(feed, {})["packets"]
    assert (names["15"]["name"], names["27"]["name"]) == ("dirt_detect", "wall_signal")
    assert (names["22"]["unit"], names["7"]["unit"]) == ("mV", "bits")
    assert {str(pid) for pid in streamed["ids"]} <= set(names)
    replayed = _replayed(CRUMBS, path, packets)
    assert (
        _robot_at_newest(replayed, back=5)["streamed"] == _robot_at_newest(feed, back=5)["streamed"]
    )


def test_the_page_s_world_has_each_dirt_patch_and_its_level() -> None:
    """The Path panel drew rooms, walls, obstacles, drops, virtual walls and lighthouses, not
    the dirt: the world the page is sent has each patch's shape (mm) and level."""
    dirt = world_view(Simulator(load_world(DUSTY_ROOM), CREATE2, seed=0))["dirt"]
    assert [patch["level"] for patch in dirt] == [40, 200]
    xs, ys = zip(*dirt[0]["area"], strict=True)
    assert (min(xs), min(ys), max(xs), max(ys)) == (1500, 1500, 2500, 2500)


def test_the_page_cuts_a_long_mission_name_label_and_robot() -> None:
    """A mission's ``mission:`` of 200,000 characters, or a record's hand-edited label,
    became the page's title and header whole (and the refusal of another run's control):
    the run's view cuts each as a terminal's line does, its length said."""
    feed = RunFeed(mission_name="N" * 200_000, label="L" * 100_000, robot="R" * 90)
    header = header_view(feed, {})
    assert header["mission"] == header["run"]["mission"] == f"{'N' * 80}... (200,000 characters)"
    assert header["run"]["label"] == f"{'L' * 80}... (100,000 characters)"
    assert header["run"]["robot"] == f"{'R' * 80}... (90 characters)"


def test_the_record_of_a_run_that_lost_its_link_is_compared_up_to_there_not_diverged(
    tmp_path: Path,
) -> None:
    """A run whose simulator's link was pulled at 1 s (in-process: the port fails under
    it), recorded, then viewed as ``roomba-bt monitor RECORD`` does. Past its tree's last
    tick the recorded run wrote what the failure had it write (nothing: the port was gone),
    and the replay, on a line that cannot fail, its own stop: the view said "replay diverged
    from the record at t=...: expected nothing, sent Drive (137) ...", read as a broken
    record, where ``replay`` said "the recorded run lost its link ... compared up to there".
    Both say it with the same words now (``stack.past_the_link_loss``)."""
    from roomba_bt.sim import Faults

    mission_file = tmp_path / "m.yaml"
    mission_file.write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 100 mm/s}\n"
    )
    mission = load_mission(mission_file, {}, profile=CREATE2)
    path = tmp_path / "run.jsonl"
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, 0, Faults(disconnect_at=1.0)))
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=3.0,
                     record=Recording(path, str(mission_file)))  # fmt: skip
    try:
        assert stack.run().exit_code == 8  # the port gone under the run
    finally:
        stack.close()
    differences: list[str] = []
    feed, _ = replay_into_feed(
        load_record(path), load_mission(mission_file, {}, profile=CREATE2), CREATE2,
        stack.packets, 115200, "r", diverged_at=differences.append,
    )  # fmt: skip
    assert differences == []  # nothing said on stderr: the record is not broken
    finished = feed.finished or ""
    assert "diverged" not in finished, finished
    assert finished.startswith("the recorded run lost its link at mission time 0.9"), finished
    assert "after its tree's last tick; compared up to there: the tree wrote the same" in finished
    events = [event.text for event in feed.events]
    assert any(text.startswith("the recorded run ended in connection lost") for text in events)
    past = "past there the replay does not fail as its link did"
    assert any(text.startswith(past) for text in events), events
    # the replay's own stop is not the recorded run's (which went into a port that was gone)
    assert feed.ending is None


def test_a_programs_slow_loop_pass_is_an_event_of_its_own_not_a_ticks() -> None:
    """A pass of a program's loop over ``stack.ticks()`` past the tick limit was counted as
    the tree's slow tick and shown as "a tick ran over its limit with nothing moving, in the
    program's loop ..."; it is the loop's own event, and no tick's."""
    summary = RunSummary("m", loop_slow=2, loop_halts=1)
    assert tick_guard_said(summary, (0, 0, 0, 1)) == [
        "the program's loop over stack.ticks(), between two ticks (the program's own time, "
        "not the tree's) ran over the tick limit: the tick guard stopped the robot in 1, sent "
        "nothing in 1 (nothing moving, or a built-in cycle, which it does not end)"
    ]
    assert tick_guard_said(summary, (0, 0, 0, 2)) == []
