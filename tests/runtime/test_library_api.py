"""roomba-bt embedded as a Python library (a py_trees and pycreate2 user's findings): the
program's own exceptions kept, a run tick by tick, a mission from a string, a behaviour of
the program's own in YAML, a compiled mission nested in a bigger tree, arguments checked
when given, py_trees visitors on a run's ticks, and the small things (``import
roomba_bt.commands``, one base error, ``with RunStack``, a typed interrupt, a short profile
repr)."""

from __future__ import annotations

import inspect
import json
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
import pytest
from waits import HANG_S, waited  # tests/waits.py: a hang's bound

import roomba_bt
from roomba_bt import CREATE2, Outcome, RunStack, SimLink, Simulator, TreeMission, load_world
from roomba_bt.behaviours import DISTANCE, Condition, Param, declare
from roomba_bt.robot.interface import Snapshot
from roomba_bt.robot.testing import StubRobot
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, replay_record
from roomba_bt.runtime.stepping import LOOP_BODY
from roomba_bt.sim import Faults

from .simrun import guard_looks, wait_for_the_guard

TO_THE_WALL = """\
mission: lab-exp
blackboard:
  legs: {type: int, initial: 0}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s}
      until: {bump: {}}
    - drive: {velocity: -150 mm/s, distance: 20 cm}
    - set: {key: legs, value: 1}
    - stop
    - mode: passive
"""


class Mine(Exception):
    """The program's own error class."""


def _simulator() -> Simulator:
    return Simulator(load_world("empty-room"), CREATE2, seed=0)


def _stack(mission: object, simulator: Simulator, **kwargs: object) -> RunStack:
    return RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=30.0, **kwargs)  # type: ignore[arg-type]


def _stopped(simulator: Simulator) -> bool:
    return simulator.mode.label == "Passive" and (
        simulator.requested_left,
        simulator.requested_right,
    ) == (0, 0)


# ------------------------------------------------------------------ 1. the program's exceptions
class Raises(py_trees.behaviour.Behaviour):
    def update(self) -> py_trees.common.Status:
        raise Mine("sensor fusion failed")


def _observer_says_no(runner: roomba_bt.MissionRunner) -> None:
    if runner.snapshot.time > 1.0:
        raise Mine("observer says no")


class VisitorSaysNo(py_trees.visitors.VisitorBase):
    """A py_trees visitor that raises on its 100th visit (about the 50th tick)."""

    def __init__(self) -> None:
        super().__init__()
        self.visits = 0

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        self.visits += 1
        if self.visits == 100:
            raise Mine("visitor says no")


@pytest.mark.parametrize("hook", ["observer", "visitors"])
def test_an_observers_or_visitors_exception_is_kept_and_is_the_run_faileds_cause(
    hook: str,
) -> None:
    given = {"observer": _observer_says_no, "visitors": [VisitorSaysNo()]}[hook]
    simulator = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), simulator, **{hook: given}) as stack:
        summary = stack.run()
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4
    said = "observer says no" if hook == "observer" else "visitor says no"
    assert isinstance(summary.exception, Mine) and str(summary.exception) == said
    with pytest.raises(roomba_bt.RunFailed) as failed:
        summary.raise_for_outcome()
    assert failed.value.__cause__ is summary.exception  # ``except`` and pytest reach it
    assert failed.value.exception is summary.exception
    assert _stopped(simulator)


def test_a_behaviours_exception_is_kept_too_and_a_clean_run_keeps_none() -> None:
    root = py_trees.composites.Sequence("p", memory=True, children=[Raises("crash")])
    with _stack(TreeMission(root, "p"), _simulator()) as stack:
        summary = stack.run()
    assert isinstance(summary.exception, Mine)
    assert "Mine: sensor fusion failed" in summary.reason  # the text the CLI prints, as it was
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), _simulator()) as stack:
        assert stack.run().raise_for_outcome().exception is None


def _asleep() -> Simulator:
    simulator = _simulator()
    simulator.fall_asleep("test")  # deaf at every rate: no Query List answered
    return simulator


def _unplugged() -> Simulator:
    return Simulator(load_world("empty-room"), CREATE2, seed=0, faults=Faults(disconnect_at=1.0))


@pytest.mark.parametrize(
    ("robot", "outcome", "link_error"),
    [(_asleep, Outcome.NO_CONNECTION, roomba_bt.NoAnswer),
     (_unplugged, Outcome.CONNECTION_LOST, roomba_bt.LinkDown)],
)  # fmt: skip
def test_a_run_the_link_ended_raises_from_the_links_exception(
    robot: Callable[[], Simulator], outcome: Outcome, link_error: type[Exception]
) -> None:
    """A robot that does not answer, a port that goes: ``raise_for_outcome()`` raises
    ``RunFailed`` from the link's own exception (``NoAnswer``, a ``ConnectionFailed``, as
    ``Connection.start()`` raises it; ``PortLost``, a ``LinkDown``), which a program tests
    as it tests its own; it was raised with no cause."""
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), robot()) as stack:
        summary = stack.run()
    assert summary.outcome is outcome and summary.exception is None
    with pytest.raises(roomba_bt.RunFailed) as failed:
        summary.raise_for_outcome()
    assert isinstance(failed.value.__cause__, link_error), repr(failed.value.__cause__)
    assert failed.value.__cause__ is summary.link_error is failed.value.link_error
    assert str(failed.value.__cause__) in summary.reason


# ------------------------------------------------------------------ 2. tick by tick
def test_ticks_yields_each_tick_with_its_status_and_blackboard_and_ends_with_the_run() -> None:
    simulator = _simulator()
    seen = []
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), simulator) as stack:
        for tick in stack.ticks():
            assert isinstance(tick, roomba_bt.Tick)
            seen.append((tick.number, tick.time, tick.status, dict(tick.blackboard)))
            assert tick.root is stack.mission.root
    assert [number for number, *_ in seen] == list(range(1, len(seen) + 1))
    assert seen[0][3] == {"legs": 0} and seen[-1][3] == {"legs": 1}
    assert seen[-1][2] is py_trees.common.Status.SUCCESS
    assert all(status is py_trees.common.Status.RUNNING for *_, status, _ in seen[:-1])
    assert stack.summary.outcome is Outcome.SUCCESS and stack.summary.ticks == len(seen)
    assert _stopped(simulator)


def test_the_same_run_by_ticks_and_by_run_writes_the_same_bytes() -> None:
    """The loop changes nothing of the run: the virtual clock stands still meanwhile."""
    by_run = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), by_run) as stack:
        stack.run()
    by_ticks = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), by_ticks) as stack:
        for _ in stack.ticks():
            pass
    assert by_ticks.pose == by_run.pose and by_ticks.time == by_run.time


def test_a_break_stops_the_run_with_its_safe_stop() -> None:
    simulator = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), simulator) as stack:
        for tick in stack.ticks():
            if tick.time > 1.0:
                assert simulator.requested_left > 0  # driving
                break
        summary = stack.summary  # the loop's generator closed: the run has ended
        assert summary.outcome is Outcome.INTERRUPTED and summary.stop_delivered
        assert "loop over stack.ticks() ended" in summary.reason
        assert _stopped(simulator)


def test_an_exception_in_the_loop_stops_the_run_before_it_goes_on() -> None:
    simulator = _simulator()
    stack = _stack(roomba_bt.load_mission_text(TO_THE_WALL), simulator)
    with pytest.raises(Mine):
        for tick in stack.ticks():
            if tick.time > 1.0:
                raise Mine("the program's check failed")
    assert stack.summary.outcome is Outcome.INTERRUPTED and _stopped(simulator)
    stack.close()


def test_a_loop_kept_alive_is_stopped_by_the_with_blocks_end() -> None:
    """A generator that is kept (not closed by its loop's end): ``with`` closes the stack,
    which stops the run its worker holds."""
    simulator = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), simulator) as stack:
        kept = stack.ticks()
        for _ in range(50):
            next(kept)
    assert stack.summary.outcome is Outcome.INTERRUPTED and _stopped(simulator)
    kept.close()


def test_an_observer_given_still_sees_every_tick_of_a_loop() -> None:
    observed: list[int] = []
    with _stack(
        roomba_bt.load_mission_text(TO_THE_WALL),
        _simulator(),
        observer=lambda runner: observed.append(runner.summary.ticks),
    ) as stack:
        numbers = [tick.number for tick in stack.ticks()]
    assert observed == numbers


def test_the_tick_guard_watches_the_loops_body_on_the_wall_clock() -> None:
    """On a robot the robot drives on while the body runs: a body that blocks is watched as
    a tick that blocks, and the guard's drive 0 is counted and said as the loop's, not as
    a slow tick of the tree's (``tick_halts``, "while the tree was busy", until session 40)."""
    from roomba_bt.sim import RealtimeSimLink

    simulator = _simulator()
    stack = RunStack(
        roomba_bt.load_mission_text(TO_THE_WALL), RealtimeSimLink(simulator),
        profile=CREATE2, timeout_s=20.0,
    )  # fmt: skip
    with stack:
        for tick in stack.ticks():
            if tick.number == 40:
                wait_for_the_guard(stack)  # until the guard stopped the wheels
                break
    summary = stack.summary
    assert (summary.loop_slow, summary.loop_halts, summary.tick_halts) == (1, 1, 0), summary
    assert summary.tick_guard_text() == (
        "1 slow pass(es) of the program's loop over stack.ticks(), between two ticks (the "
        "program's own time, not the tree's): the tick guard stopped the robot in 1"
    )


def test_a_loops_body_that_blocks_with_the_robot_still_is_said_as_such(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """A body that blocks before anything moves (Safe, no drive yet) gets nothing from the
    guard, and the 1.5 s of frames it left unread are said as the loop's, the robot still:
    not as a process suspended or starved while the robot went on, and not counted as
    unread, nor as a slow tick of the tree's (``tick_stills``, "1 slow tick(s) with nothing
    moving", until session 40): as a slow pass of the program's loop. The virtual clock,
    the guard given: the body waits until the guard has looked where it is
    (``TickGuard._where``), then has the robot stream on."""
    seen = guard_looks(monkeypatch)
    link = SimLink(_simulator())
    stack = RunStack(roomba_bt.load_mission_text(TO_THE_WALL), link, profile=CREATE2,
                     timeout_s=30.0, tick_limit=0.25)  # fmt: skip
    with stack:
        for index, _ in enumerate(stack.ticks()):
            if index == 0:  # Safe sent, nothing moving yet
                waited(seen, "the tick guard's look at the loop's blocked body")
                link.advance(1.5)
            if index == 5:
                break
    said = [r.getMessage() for r in caplog.records if "no frame was read" in r.getMessage()]
    assert len(said) == 1 and "no frame was read for 1.5" in said[0], said
    assert "a tick blocked (the program's loop over stack.ticks()" in said[0]
    assert "the robot stood still" in said[0] and "suspended" not in said[0]
    summary = stack.summary
    assert summary.unread_gaps == summary.tick_halts == summary.tick_stills == 0, summary
    assert (summary.loop_slow, summary.loop_halts) == (1, 0), summary
    assert summary.tick_guard_text() == (
        "1 slow pass(es) of the program's loop over stack.ticks(), between two ticks (the "
        "program's own time, not the tree's): the tick guard sent nothing in 1 (nothing "
        "moving, or a built-in cycle, which it does not end)"
    )
    assert seen.is_set()


def _loop_recorded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, halted: bool) -> Path:
    """A record of a program's loop over ``stack.ticks()`` whose body blocked past the tick
    guard's limit once: while the robot drove (the guard's drive 0, ``halted``) or stood
    still in Safe (nothing sent), on the virtual clock with the guard given."""
    seen = guard_looks(monkeypatch)
    source, path = tmp_path / "lab.yaml", tmp_path / "loop.jsonl"
    source.write_text(TO_THE_WALL)
    link = SimLink(_simulator())
    mission = roomba_bt.load_mission(str(source), profile=CREATE2)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=30.0, tick_limit=0.25,
                     record=Recording(path, str(source)))  # fmt: skip
    with stack:
        for tick in stack.ticks():
            if halted and tick.number == 40:
                wait_for_the_guard(stack)
            elif not halted and tick.number == 1:  # Safe sent, nothing moving yet
                waited(seen, "the tick guard's look at the loop's blocked body")
                link.advance(1.5)
            if tick.number == 60:
                break
    counted = (stack.summary.loop_slow, stack.summary.loop_halts, stack.summary.tick_halts)
    assert counted == (1, int(halted), 0), stack.summary
    return path


@pytest.mark.parametrize("made", ["now", "before"])
@pytest.mark.parametrize("halted", [True, False], ids=["halted", "still"])
def test_a_record_of_a_loops_slow_pass_replays_it_as_the_loops(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, halted: bool, made: str
) -> None:
    """The tick guard's note of a slow pass of the program's loop is replayed as the run
    counted it (``loop_slow``, ``loop_halts``), its drive 0 after the tick's flush as live
    (the wheels given back with the next tick's commands): byte for byte. The replay took it
    for the tree's slow tick ("1 slow tick(s): drive 0 sent while the tree was busy; the
    first in at .../threading.py:327", the worker's wait), its drive 0 and the wheels given
    back inside the tick: "first difference ... 0.02 s early", exit 1. A record made before
    the note said it was the loop's (``"loop": true``) says so by its ``where`` alone (the
    worker's wait, in ``threading.py``; ``made="before"``: the note written back so)."""
    path = _loop_recorded(tmp_path, monkeypatch, halted)
    notes = [note for _, note in load_record(path).notes if note.get("at") != "end"]
    guarded = [note for note in notes if "tick_guard" in note or "tick_still" in note]
    assert [(n.get("loop"), n["where"]) for n in guarded] == [(True, LOOP_BODY)], notes
    if made == "before":
        text = path.read_text().replace(', "loop": true', "")
        path.write_text(text.replace(LOOP_BODY, "at /usr/lib/python3.11/threading.py:327"))
    record = load_record(path)
    summary, transport = replay_record(
        record, roomba_bt.load_mission(str(tmp_path / "lab.yaml"), profile=CREATE2),
        profile=CREATE2, packets=record.header["packets"], baud=record.header["baud"],
        name="loop.jsonl",
    )  # fmt: skip
    assert transport.first_difference() is None and transport.written == record.out_bytes
    counted = (summary.loop_slow, summary.loop_halts, summary.tick_halts, summary.tick_stills)
    assert counted == (1, int(halted), 0, 0), summary.tick_guard_text()


class WaitsInFinalise(py_trees.visitors.VisitorBase):
    """A py_trees visitor whose ``finalise()`` at the 40th tick (the robot driving) waits in
    Python's ``threading.py`` (an event's wait, as a put to a full queue or a lock's
    condition waits) until the tick guard has looked: that tick blocks past the guard's
    limit in no behaviour's method, so the guard's note names ``threading.py``, as a
    program's loop over ``stack.ticks()`` waiting for its next tick did."""

    def __init__(self, seen: threading.Event) -> None:
        super().__init__(full=False)
        self.seen, self.ticks = seen, 0

    def finalise(self) -> None:
        self.ticks += 1
        if self.ticks == 40:
            waited(self.seen, "the tick guard's look at the visitor's wait")


@pytest.mark.parametrize("made", ["now", "by run", "by 0.1.0"])
def test_a_trees_slow_tick_noted_in_threading_py_replays_as_the_trees(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, made: str
) -> None:
    """A record's note of a tree's tick that blocked in ``threading.py`` (a visitor's
    ``finalise()`` waiting) was read as a program's loop's, by its ``where`` alone: its
    replay did the drive 0 after the tick's flush and counted the pass as the loop's, a
    difference ("first difference ... expected Drive (137) 89 00 c8 80 00, sent nothing").
    Every note says whose it is now (``"loop":
    false``), and a record that could hold no loop's note is read so without it: ``made="by
    run"`` (a ``run --record``'s header, its options) and ``"by 0.1.0"`` (no release named),
    the key taken out."""
    seen = guard_looks(monkeypatch)
    source, path = tmp_path / "lab.yaml", tmp_path / "visited.jsonl"
    source.write_text(TO_THE_WALL)
    mission = roomba_bt.load_mission(str(source), profile=CREATE2)
    stack = RunStack(mission, SimLink(_simulator()), profile=CREATE2, timeout_s=30.0,
                     tick_limit=0.25, visitors=[WaitsInFinalise(seen)],
                     record=Recording(path, str(source)))  # fmt: skip
    with stack:
        stack.run()
    assert (stack.summary.tick_halts, stack.summary.loop_slow) == (1, 0), stack.summary
    notes = [note for _, note in load_record(path).notes if "tick_guard" in note]
    [note] = [n for n in notes if n.get("at") != "end"]
    assert note["loop"] is False and Path(note["where"].rsplit(":", 1)[0]).name == "threading.py"
    if made != "now":
        header, *lines = path.read_text().splitlines(keepends=True)
        head = json.loads(header)
        if made == "by run":
            head["options"] = {"timeout": "30s", "end_in": "passive"}
        else:
            del head["roomba_bt_version"]
        body = "".join(lines).replace(', "loop": false', "")
        path.write_text(json.dumps(head) + "\n" + body)
    record = load_record(path)
    summary, transport = replay_record(
        record, roomba_bt.load_mission(str(source), profile=CREATE2), profile=CREATE2,
        packets=record.header["packets"], baud=record.header["baud"], name="visited.jsonl",
    )  # fmt: skip
    assert transport.first_difference() is None and transport.written == record.out_bytes
    counted = (summary.tick_halts, summary.loop_slow, summary.loop_halts)
    assert counted == (1, 0, 0), summary.tick_guard_text()


# ------------------------------------------------------------------ 3. a mission from a string
def test_a_mission_compiles_from_text_its_errors_at_the_name_given() -> None:
    mission = roomba_bt.load_mission_text(TO_THE_WALL, name="lab.yaml")
    assert mission.name == "lab-exp" and mission.blackboard_initial == {"legs": 0}
    broken = "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocty: 1}\n"
    with pytest.raises(roomba_bt.MissionError) as error:
        roomba_bt.load_mission_text(broken, name="cell[3]")
    [diagnostic] = error.value.diagnostics
    assert (diagnostic.file, diagnostic.line, diagnostic.column) == ("cell[3]", 4, 15)
    assert str(error.value).splitlines()[1].startswith("cell[3]:4:15: drive: unknown parameter")


def test_a_texts_includes_are_found_from_its_base_dir(tmp_path: Path) -> None:
    (tmp_path / "lib.yaml").write_text(
        "subtrees:\n  go: {tree: {drive: {velocity: 100 mm/s, distance: 5 cm}}}\n"
    )
    text = "tree:\n  sequence:\n    - mode: safe\n    - subtree: go\ninclude: [lib.yaml]\n"
    mission = roomba_bt.load_mission_text(text, name="cell", base_dir=tmp_path)
    assert mission.files == ((tmp_path / "lib.yaml").resolve(),)
    with pytest.raises(roomba_bt.MissionError, match=r"\ncell:5:11: included file 'lib.yaml' not"):
        roomba_bt.load_mission_text(text, name="cell", base_dir=tmp_path / "..")


@pytest.mark.parametrize(
    "load",
    [
        lambda **kw: roomba_bt.load_mission_text(TO_THE_WALL, name="lab.yaml", **kw),
        lambda **kw: roomba_bt.load_mission("dock", **kw),
    ],
    ids=["load_mission_text", "load_mission"],
)
def test_profile_none_is_create2_and_a_name_its_profile(load: Callable[..., Any]) -> None:
    """``profile=None`` was an internal error inside a MissionError ("'NoneType' object has
    no attribute 'command_unavailable'"), ``profile='roomba500'`` (the name
    ``configured_profile()`` returns for it) the same with 'str'. None is ``create2``, as
    no argument is (docs/robot.md: the library reads no setting); a name is its profile."""
    from roomba_bt.oi.profiles import ROOMBA500

    none, default = load(profile=None), load()
    assert none.sends == default.sends and none.packets == default.packets
    named, given = load(profile="roomba500"), load(profile=ROOMBA500)
    assert named.sends == given.sends and named.packets == given.packets


def test_a_profile_that_names_no_model_is_refused_naming_the_function() -> None:
    with pytest.raises(ValueError, match=r"^load_mission_text\(profile='create3'\): unknown robot"):
        roomba_bt.load_mission_text(TO_THE_WALL, profile="create3")
    with pytest.raises(ValueError, match=r"^validate_file\(profile='auto'\): 'auto' names no"):
        roomba_bt.mission.validate_file("dock.yaml", profile="auto")
    with pytest.raises(TypeError, match=r"^load_mission\(profile=...\) takes a RobotProfile"):
        roomba_bt.load_mission("dock", profile=2)  # type: ignore[arg-type]


def test_load_mission_given_yaml_text_says_to_use_load_mission_text() -> None:
    with pytest.raises(roomba_bt.MissionError, match="load_mission_text"):
        roomba_bt.load_mission(TO_THE_WALL)


# ------------------------------------------------------------------ 4. the program's behaviour
@declare(
    "far_enough", kind="condition", reads=(43, 44), primary="mm",
    params=(Param("mm", DISTANCE, default="30 cm", minimum=0, maximum=10000),),
)  # fmt: skip
class FarEnough(Condition):
    """Odometry says the robot has gone far enough."""

    def check(self, snapshot: Snapshot) -> bool:
        return snapshot.odometry.distance_mm >= self.number("mm")


@declare("drive", kind="condition")
class ClashesWithDrive(Condition):
    """Declares a built-in's name."""

    def check(self, snapshot: Snapshot) -> bool:
        return True


FAR_ENOUGH = """\
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s}
      until: {far_enough: 300 mm}
    - stop
"""


def test_a_behaviour_of_the_programs_own_is_named_in_yaml_by_behaviours() -> None:
    mission = roomba_bt.load_mission_text(FAR_ENOUGH, behaviours=[FarEnough])
    with _stack(mission, _simulator()) as stack:
        summary = stack.run().raise_for_outcome()
    assert 300 <= summary.distance_mm < 330
    with pytest.raises(roomba_bt.MissionError, match="unknown node 'far_enough'"):
        roomba_bt.load_mission_text(FAR_ENOUGH)  # the default registry is left as it was


def test_a_behaviour_that_takes_a_built_ins_name_is_refused_by_name() -> None:
    with pytest.raises(roomba_bt.DeclarationError) as refused:
        roomba_bt.load_mission_text(FAR_ENOUGH, behaviours=[FarEnough, ClashesWithDrive])
    message = str(refused.value)
    assert message.startswith("behaviours=[ClashesWithDrive]: ClashesWithDrive (")
    assert (
        "declares 'drive', the name of the built-in roomba_bt.behaviours.actions.Drive" in message
    )
    with pytest.raises(roomba_bt.DeclarationError, match="Action or Condition"):
        roomba_bt.load_mission_text(FAR_ENOUGH, behaviours=[Mine])  # type: ignore[list-item]


def test_a_plain_py_trees_behaviour_given_as_behaviours_is_told_of_tree_mission() -> None:
    """A py_trees user's class, refused by the YAML, still runs in a tree built in Python:
    the refusal says where (the py_trees expert, session 34); a class that is no py_trees
    behaviour at all is not pointed there."""
    with pytest.raises(roomba_bt.DeclarationError) as refused:
        roomba_bt.load_mission_text(FAR_ENOUGH, behaviours=[Noop])  # type: ignore[list-item]
    assert str(refused.value).endswith(
        "; Noop is a plain py_trees behaviour, which a mission's YAML cannot name, but a "
        "tree built in Python runs as it is: roomba_bt.TreeMission(root, name) "
        "(roomba-bt docs runtime, From Python: a tree built by hand)"
    )
    with pytest.raises(roomba_bt.DeclarationError) as other:
        roomba_bt.load_mission_text(FAR_ENOUGH, behaviours=[Mine])  # type: ignore[list-item]
    assert "TreeMission" not in str(other.value)


def _checks_n(mission: str, n: int) -> roomba_bt.CompiledMission:
    """A mission declaring key ``n`` with ``n`` its initial value, and checking it holds it."""
    return roomba_bt.load_mission_text(
        f"mission: {mission}\nblackboard:\n  n: {{type: int, initial: {n}}}\n"
        f"tree:\n  check: {{key: n, value: {n}}}\n",
        name=f"{mission}.yaml",
    )


@pytest.mark.usefixtures("clean_blackboard")
def test_missions_set_up_by_hand_share_the_plain_names_so_run_them_one_at_a_time() -> None:
    """docs/plugins.md (Test it without a robot) says so: ``setup`` claims no board (a run's
    is its thread's, and a bare ``tick_once`` has no run), so the last ``setup`` wins (the
    py_trees expert's t5.py, session 34), and set up again before its ticks each passes."""
    first, second = _checks_n("a", 1), _checks_n("b", 2)
    robot_a, robot_b = StubRobot(), StubRobot()
    first.setup(robot_a)
    second.setup(robot_b)
    robot_a.set_frame({})
    first.root.tick_once()
    assert first.root.status is py_trees.common.Status.FAILURE  # it read b's 2
    for mission, robot in ((first, robot_a), (second, robot_b)):
        mission.setup(robot)
        robot.set_frame({})
        mission.root.tick_once()
        assert mission.root.status is py_trees.common.Status.SUCCESS, mission.name


# ------------------------------------------------------------------ 5. nested in a bigger tree
class Noop(py_trees.behaviour.Behaviour):
    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS


def test_a_compiled_missions_initial_values_come_with_its_root_into_a_bigger_tree() -> None:
    text = """\
mission: bb
blackboard:
  leg: {type: distance, initial: 30 cm}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: "@leg"}
"""
    mission = roomba_bt.load_mission_text(text)
    py_trees.blackboard.Blackboard.clear()
    root = py_trees.composites.Sequence("wrap", memory=True, children=[Noop("hi"), mission.root])
    with _stack(TreeMission(root, "wrapped"), _simulator()) as stack:
        summary = stack.run().raise_for_outcome()
    assert 295 < summary.distance_mm < 320


def test_two_missions_declaring_one_key_differently_are_refused() -> None:
    one = roomba_bt.load_mission_text(
        "blackboard: {n: {type: int, initial: 1}}\ntree: {set: {key: n, value: 2}}\n", name="one"
    )
    two = roomba_bt.load_mission_text(
        "blackboard: {n: {type: int, initial: 5}}\ntree: {set: {key: n, value: 2}}\n", name="two"
    )
    root = py_trees.composites.Sequence("both", memory=True, children=[one.root, two.root])
    with _stack(TreeMission(root), _simulator()) as stack:
        summary = stack.run()
    assert summary.outcome is Outcome.ERROR
    assert "blackboard key 'n' is declared by missions 'one' and 'two'" in summary.reason


# ------------------------------------------------------------------ 6. arguments checked
@pytest.mark.parametrize(
    ("given", "error", "said"),
    [
        ({"timeout_s": "30s"}, TypeError, "RunStack(timeout_s=...) takes a number of seconds"),
        ({"timeout_s": -1}, ValueError, "RunStack(timeout_s=-1)"),
        ({"grace": None}, TypeError, "RunStack(grace=...)"),
        ({"observer": 3}, TypeError, "RunStack(observer=...) takes a function"),
        ({"strict": 1}, TypeError, "RunStack(strict=...)"),
        ({"baud": "fast"}, TypeError, "RunStack(baud=...)"),
        ({"packets": "7"}, TypeError, "RunStack(packets=...)"),
        ({"visitors": py_trees.visitors.DebugVisitor()}, TypeError,
         "RunStack(visitors=...) takes a list of py_trees visitors, not one: "
         "visitors=[DebugVisitor(...)]"),
        ({"visitors": "snapshot"}, TypeError,
         "RunStack(visitors=...) takes a list of py_trees visitors, not str 'snapshot'"),
        ({"visitors": [print]}, TypeError,
         "RunStack(visitors=...): each is a py_trees visitor (py_trees.visitors.VisitorBase: "
         "initialise(), run(behaviour), finalise()), not builtin_function_or_method"),
    ],
)  # fmt: skip
def test_a_run_stacks_wrong_argument_is_said_when_given(
    given: dict[str, object], error: type[Exception], said: str
) -> None:
    mission = roomba_bt.load_mission_text(TO_THE_WALL)
    simulator = _simulator()
    with pytest.raises(error) as raised:
        RunStack(mission, SimLink(simulator), profile=CREATE2, **given)  # type: ignore[arg-type]
    assert said in str(raised.value)
    assert simulator.time == 0.0  # nothing written, nothing run


def test_a_run_stack_given_a_name_or_a_url_says_what_it_takes() -> None:
    with pytest.raises(TypeError, match=r"compiled mission \(roomba_bt.load_mission"):
        RunStack("bump-and-turn", SimLink(_simulator()), profile=CREATE2)  # type: ignore[arg-type]
    mission = roomba_bt.load_mission_text(TO_THE_WALL)
    with pytest.raises(TypeError, match=r"Connection.open\('socket://host:1'\)"):
        RunStack(mission, "socket://host:1", profile=CREATE2)  # type: ignore[arg-type]


def test_permissions_take_folders_as_text_and_refuse_one_bare_text(tmp_path: Path) -> None:
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "lib.yaml").write_text("subtrees:\n  s: {tree: {wait: 1 s}}\n")
    (tmp_path / "m").mkdir()
    mission_file = tmp_path / "m" / "m.yaml"
    mission_file.write_text("include: [../other/lib.yaml]\ntree: {subtree: s}\n")
    granted = roomba_bt.Permissions(include_dirs=(str(tmp_path / "other"),))  # type: ignore[arg-type]
    assert granted.include_dirs == (tmp_path / "other",)
    assert roomba_bt.load_mission(mission_file, permissions=granted).name == "m"
    with pytest.raises(TypeError, match=r"include_dirs=\.\.\.\) takes a tuple of folders"):
        roomba_bt.Permissions(include_dirs=str(tmp_path))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="plugin_files"):
        roomba_bt.Permissions(plugin_files="yes")  # type: ignore[arg-type]


# ------------------------------------------------------------------ 7. py_trees visitors
class Names(py_trees.visitors.VisitorBase):
    """Each tick's visits, by name, and its calls counted."""

    def __init__(self, full: bool = False) -> None:
        super().__init__(full=full)
        self.ticks: list[list[str]] = []
        self.finalised = 0

    def initialise(self) -> None:
        self.ticks.append([])

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        self.ticks[-1].append(behaviour.name)

    def finalise(self) -> None:
        self.finalised += 1


def test_py_trees_visitors_visit_each_tick_as_a_behaviour_tree_runs_them() -> None:
    """A py_trees user's hook on a tree's ticks (``BehaviourTree.visitors``) had no place
    in a run: ``RunStack(visitors=[...])`` runs them on every tick, each node the tick
    ticked visited as it ends (the root last), every node by a ``full`` one; the run is
    the same run, and its tree py_trees' display shows with what the last tick visited."""
    ticked, full, snapshot = Names(), Names(full=True), py_trees.visitors.SnapshotVisitor()
    simulator = _simulator()
    mission = roomba_bt.load_mission_text(TO_THE_WALL)
    with _stack(mission, simulator, visitors=[ticked, full, snapshot]) as stack:
        summary = stack.run()
    assert summary.outcome is Outcome.SUCCESS and _stopped(simulator)
    assert len(ticked.ticks) == ticked.finalised == full.finalised == summary.ticks
    assert ticked.ticks[0] == ["mode(safe)", "sequence"]  # only what the first tick ticked
    assert all(names[-1] == "sequence" for names in ticked.ticks)
    every = [node.name for node in mission.root.iterate()]
    assert all(names == every for names in full.ticks)
    assert snapshot.visited[mission.root.id] is py_trees.common.Status.SUCCESS
    shown = py_trees.display.unicode_tree(
        mission.root, show_status=True, visited=snapshot.visited,
        previously_visited=snapshot.previously_visited,
    )  # fmt: skip
    assert "mode(passive) [✓]" in shown

    without = _simulator()
    with _stack(roomba_bt.load_mission_text(TO_THE_WALL), without) as stack:
        assert stack.run().ticks == summary.ticks
    assert without.pose == simulator.pose and without.time == simulator.time


def test_without_visitors_the_tree_is_ticked_directly_as_before() -> None:
    """No visitor given, nothing of them is on the tick's path: the loop ticks the root's
    direct tick (``tick_of``), the function it called before visitors were taken."""
    from roomba_bt.runtime.loop import guarded_tick, tick_of

    mission = roomba_bt.load_mission_text(TO_THE_WALL)
    with _stack(mission, _simulator()) as stack:
        assert stack.runner.visitors == ()
        assert guarded_tick(stack.runner, mission.root) == tick_of(mission.root)
    with _stack(mission, _simulator(), visitors=[Names()]) as stack:
        assert guarded_tick(stack.runner, mission.root) != tick_of(mission.root)


# ------------------------------------------------------------------ 8. the small things
def test_import_roomba_bt_commands_is_the_module_from_roomba_bt_import_commands() -> None:
    """The module path still gives the module, and warns at the importer's line (here the
    script's first) naming the spelling the docs teach."""
    done = subprocess.run(
        [sys.executable, "-c", "import roomba_bt.commands as c\nfrom roomba_bt import commands\n"
         "print(c is commands, c.drive(200, 32767).args)"],
        capture_output=True, text=True, timeout=HANG_S,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
    )  # fmt: skip
    assert done.stdout == "True (200, 32767)\n", done.stderr
    assert (
        "<string>:1: DeprecationWarning: import roomba_bt.commands (as a module) is" in done.stderr
    )
    assert "write from roomba_bt import commands" in done.stderr


def test_the_packages_errors_share_one_base_and_keep_their_own() -> None:
    from roomba_bt.behaviours import UnitError
    from roomba_bt.behaviours.blackboard import KeyRange, KeyType
    from roomba_bt.oi.errors import OIError
    from roomba_bt.robot import ModeError, StreamStalled
    from roomba_bt.runtime.recording import RecordError

    base = roomba_bt.RoombaBtError
    for error, kept in [
        (roomba_bt.MissionError, Exception), (roomba_bt.RunFailed, Exception),
        (roomba_bt.RobotError, Exception), (StreamStalled, ConnectionError),
        (ModeError, ValueError), (OIError, Exception), (roomba_bt.EncodeError, ValueError),
        (roomba_bt.BandwidthError, ValueError), (roomba_bt.ParamError, TypeError),
        (roomba_bt.DeclarationError, ValueError), (roomba_bt.WorldError, ValueError),
        (roomba_bt.TransportError, OSError), (roomba_bt.MissingPacket, KeyError),
        (roomba_bt.UnwrittenKey, LookupError), (KeyRange, ValueError), (KeyType, TypeError),
        (UnitError, ValueError), (RecordError, ValueError),
    ]:  # fmt: skip
        assert issubclass(error, base) and issubclass(error, kept), error
    # a mix-in that adds nothing: each error behaves as it did, its own bases' methods used
    assert [name for name in vars(base) if not name.startswith("__")] == []


def test_the_interrupt_a_run_raises_again_is_typed_and_still_a_keyboard_interrupt() -> None:
    def observer(runner: roomba_bt.MissionRunner) -> None:
        if runner.snapshot.tick == 40:
            raise KeyboardInterrupt

    stack = _stack(roomba_bt.load_mission_text(TO_THE_WALL), _simulator(), observer=observer)
    with stack, pytest.raises(roomba_bt.Interrupted) as caught:
        stack.run()
    assert isinstance(caught.value, KeyboardInterrupt)
    assert caught.value.summary is stack.summary
    assert caught.value.summary.outcome is Outcome.INTERRUPTED


def test_a_signal_raised_again_is_typed_and_still_terminated() -> None:
    from roomba_bt.robot.safety import Terminated

    def observer(runner: roomba_bt.MissionRunner) -> None:
        if runner.snapshot.tick == 40:
            os.kill(os.getpid(), signal.SIGTERM)

    stack = _stack(roomba_bt.load_mission_text(TO_THE_WALL), _simulator(), observer=observer)
    with stack, pytest.raises(roomba_bt.Interrupted) as caught:
        stack.run()
    assert isinstance(caught.value, Terminated) and caught.value.signum == signal.SIGTERM
    assert caught.value.summary.outcome is Outcome.INTERRUPTED


def test_signatures_show_a_shipped_profile_by_its_name() -> None:
    shown = str(inspect.signature(roomba_bt.load_mission))
    assert "profile: 'RobotProfile | str | None' = roomba_bt.CREATE2" in shown
    assert "slow_baud_how" not in shown and len(shown) < 400
    import dataclasses

    custom = dataclasses.replace(CREATE2, max_velocity_mm_s=300)
    assert repr(custom).startswith("RobotProfile(name='create2', ") and "300" in repr(custom)
