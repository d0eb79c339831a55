"""The tick guard (runtime/tick_guard.py): a tick that blocks while the wheels move gets
drive 0 from the guard's thread, never in the middle of the main thread's bytes; when the
tick returns the run counts it, names the behaviour and its line, sends the last wheel
command again and goes on. Event-driven: the blocking behaviour waits until the guard has
acted (at most the suite's hang bound, tests/waits.py), so nothing here depends on the
machine's speed."""

from __future__ import annotations

import json
import sys
import threading
import types
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S, waited  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.mission import Permissions
from roomba_bt.oi import commands as C
from roomba_bt.oi.encode import turns_wheels
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.runtime.tick_guard import TickGuard

from .simrun import SLOW_TERM, WAITS_FOR_THE_GUARD, RunMission, guard_looks

PLUGIN = (
    '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("stuck", kind="action")
class Stuck(Action):
    """Blocks its first tick until the wheels were stopped behind its back."""

    def update(self):
        if not getattr(self, "waited", False):
            self.waited = True
            wait_for_the_guard(self.robot)
        return Status.SUCCESS
'''
    + WAITS_FOR_THE_GUARD
)

#: forward at 100 mm/s for 6 cm, with the blocking leaf beside the drive
MISSION = """
plugins: [./stuck.py]
tree:
  sequence:
    - mode: safe
    - parallel:
        policy: all
        children:
          - drive: {velocity: 100 mm/s, distance: 6 cm}
          - sequence: [{wait: 150ms}, stuck]
"""

HALT = C.drive(0, 0).data
FORWARD = C.drive(100, 32768).data


@pytest.fixture
def plugin_dir(tmp_path: Path) -> Path:
    (tmp_path / "stuck.py").write_text(PLUGIN)
    return tmp_path


def test_a_tick_that_blocks_gets_drive_0_and_the_run_goes_on(
    run_mission: RunMission, plugin_dir: Path
) -> None:
    run = run_mission(
        MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True), timeout=20.0
    )
    assert run.summary.outcome.value == "success", run.summary
    assert run.summary.tick_halts == 1
    assert run.summary.tick_halt_first.startswith("stuck (Stuck.update at ")
    assert f"{plugin_dir / 'stuck.py'}:" in run.summary.tick_halt_first
    assert "tick guard   1 slow tick(s)" in str(run.summary)
    written = [data for _, data in run.link.writes]
    drives = [data for data in written if data[:1] == HALT[:1]]
    # forward, the guard's drive 0, forward again (the last wheel command), the end's 0
    assert drives[:3] == [FORWARD, HALT, FORWARD], drives
    assert run.summary.distance_mm == pytest.approx(60, abs=5)


def _blocking_for(plugin: str, seconds: str) -> str:
    """The plugin with its leaf blocking ``seconds`` at the most, not the hang bound (the
    wait is :data:`WAITS_FOR_THE_GUARD`'s): a plugin without that bound fails here, not
    silently."""
    bound = f"+ {HANG_S!r}\n"
    assert plugin.count(bound) == 1, "the plugin's hang bound moved"
    return plugin.replace(bound, f"+ {seconds}\n")


def test_no_guard_no_halt(run_mission: RunMission, plugin_dir: Path) -> None:
    """Without the guard the same tick blocks until its own 0.05 s: the wheels are not
    stopped behind its back (the virtual clock: the robot did not move meanwhile)."""
    (plugin_dir / "stuck.py").write_text(_blocking_for(PLUGIN, "0.05"))
    run = run_mission(MISSION, permissions=Permissions(plugin_files=True), timeout=20.0)
    assert run.summary.tick_halts == 0
    assert [d for _, d in run.link.writes if d[:1] == HALT[:1]][:2] == [FORWARD, HALT]


def test_a_slow_tick_with_the_wheels_at_rest_sends_nothing(
    run_mission: RunMission, plugin_dir: Path
) -> None:
    (plugin_dir / "stuck.py").write_text(_blocking_for(PLUGIN, "0.1"))
    run = run_mission(
        "plugins: [./stuck.py]\ntree:\n  sequence:\n    - mode: safe\n    - stuck\n",
        tick_limit=0.25, permissions=Permissions(plugin_files=True),
    )  # fmt: skip
    assert run.summary.outcome.value == "success"
    assert run.summary.tick_halts == 0
    assert not any(data[:1] == HALT[:1] for _, data in run.link.writes[:-4])


def test_turns_wheels() -> None:
    assert turns_wheels(C.drive(100, 32768)) and turns_wheels(C.drive(-50, 1))
    assert not turns_wheels(C.drive(0, 32767)) and not turns_wheels(C.drive(0, 0))
    assert turns_wheels(C.drive_direct(0, 10)) and not turns_wheels(C.drive_direct(0, 0))
    assert turns_wheels(C.drive_pwm(0, -5)) and not turns_wheels(C.safe())


def test_the_cli_guards_wall_clock_runs_only(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``--tick-limit`` reaches the runner on the wall clock; ``--fast`` and 0 turn it off."""
    import roomba_bt.runtime.stack as stack

    seen: list[float | None] = []
    original = stack.MissionRunner.__init__

    def spy(self: object, *args: object, **kwargs: object) -> None:
        guard = kwargs.get("tick_guard")
        seen.append(guard.limit_s if isinstance(guard, TickGuard) else None)
        original(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(stack.MissionRunner, "__init__", spy)
    mission = tmp_path / "m.yaml"
    mission.write_text("tree:\n  sequence:\n    - mode: safe\n    - wait: 30ms\n")
    quiet = ["run", str(mission), "--display", "none"]
    assert main([*quiet]) == 0
    assert main([*quiet, "--tick-limit", "0.5"]) == 0
    assert main([*quiet, "--tick-limit", "0"]) == 0
    assert main([*quiet, "--fast"]) == 0
    assert seen == [0.25, 0.5, None, None]


def test_a_blocked_tick_that_then_raises_is_counted_and_the_stop_is_the_safe_stop(
    run_mission: RunMission, plugin_dir: Path
) -> None:
    (plugin_dir / "stuck.py").write_text(
        PLUGIN.replace("        return Status.SUCCESS", "        raise RuntimeError('gave up')")
    )
    run = run_mission(
        MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True), timeout=20.0
    )
    assert run.summary.outcome.value == "error"
    assert "gave up" in run.summary.reason
    assert run.summary.tick_halts == 1
    drives = [data for _, data in run.link.writes if data[:1] == HALT[:1]]
    # the guard's drive 0, then the safe stop's (one write, drive 0 first): no resend
    assert len(drives) == 3 and drives[:2] == [FORWARD, HALT] and drives[2].startswith(HALT)


def test_a_record_replays_the_guards_acts_byte_for_byte(
    run_mission: RunMission, plugin_dir: Path, tmp_path: Path
) -> None:
    """``run --record`` notes each act (its tick); ``replay`` does it again in that tick,
    where the tick does not block: the same bytes as the recorded run, the same count."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    record_path = tmp_path / "run.rec"
    allowed = Permissions(plugin_files=True)

    run = run_mission(MISSION, tick_limit=0.25, permissions=allowed, timeout=20.0,
                      record=record_path)  # fmt: skip
    assert run.summary.tick_halts == 1
    record = load_record(record_path)
    assert [n["tick_guard"] > 0 for _, n in record.notes if "ended" not in n] == [True]
    # in the replay nothing stops the wheels during the tick: do not wait the hang bound
    (plugin_dir / "stuck.py").write_text(_blocking_for(PLUGIN, "0.0"))
    mission = load_mission(plugin_dir / "mission.yaml", permissions=allowed)
    summary, transport = replay_record(
        record, mission, profile=CREATE2, packets=record.header["packets"],
        baud=record.header["baud"], name="run.rec",
    )  # fmt: skip
    assert transport.first_difference() is None
    assert transport.first_difference() is None and transport.written == record.out_bytes
    assert summary.tick_halts == 1 and summary.tick_halt_first.startswith("stuck (Stuck.update")


@pytest.mark.extra("monitor")
def test_the_monitor_shows_each_act_of_a_recorded_run(
    run_mission: RunMission, plugin_dir: Path, tmp_path: Path
) -> None:
    """``roomba-bt monitor RECORD``: the replay does the act again and its timeline says so,
    as the live page did (one event per act, naming the behaviour)."""
    from roomba_bt.mission import load_mission
    from roomba_bt.monitor.recorded import replay_into_feed
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record

    record_path = tmp_path / "run.rec"
    allowed = Permissions(plugin_files=True)
    run_mission(MISSION, tick_limit=0.25, permissions=allowed, timeout=20.0,
                record=record_path)  # fmt: skip
    (plugin_dir / "stuck.py").write_text(_blocking_for(PLUGIN, "0.0"))
    record = load_record(record_path)
    mission = load_mission(plugin_dir / "mission.yaml", permissions=allowed)
    feed, summary = replay_into_feed(
        record, mission, CREATE2, tuple(record.header["packets"]), record.header["baud"], "r"
    )
    assert summary.tick_halts == 1
    notes = [e.text for e in feed.events if e.kind == "note"]
    assert len(notes) == 1 and notes[0].startswith("tick guard: drive 0 while a tick ran over")
    assert "stuck (Stuck.update at " in notes[0] and "(1 so far)" in notes[0]


def test_the_wheels_stop_before_a_terminate_at_the_runs_end(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """A run that ends (here its --timeout) with a node running: drive 0 and motors off go
    out before any terminate() runs (one that blocks left the robot driving for as long);
    then the tree's stop, then the whole safe stop. A record holds it, and a replay does it
    again: the same bytes."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    (tmp_path / "slowterm.py").write_text(SLOW_TERM)
    allowed = Permissions(plugin_files=True)
    mission = "plugins: [./slowterm.py]\ntree:\n  sequence:\n    - mode: safe\n    - slow_term\n"
    record_path = tmp_path / "run.rec"
    run = run_mission(
        mission, tick_limit=0.25, permissions=allowed, timeout=0.5, record=record_path
    )
    leaf = next(n for n in run.runner.mission.root.iterate() if type(n).__name__ == "SlowTerm")
    seen = type(leaf).SEEN  # type: ignore[attr-defined]
    assert run.summary.outcome.value == "timeout"
    assert seen == [(0, 0)], seen  # drive 0 was written before the terminate ran
    written = b"".join(d for _, d in run.link.writes)
    first = C.drive(0, 0).data + C.motors_off().data
    stop = first + C.pause_stream().data + C.start().data
    assert written.endswith(first + stop), written[-40:]
    assert run.summary.safe_stop.startswith("drive 0, motors off before the tree's stop, then sent")
    assert run.summary.tick_halts == 0

    record = load_record(record_path)
    assert [n.get("at") for _, n in record.notes if "ended" not in n] == ["end"]
    summary, transport = replay_record(
        record, load_mission(tmp_path / "mission.yaml", permissions=allowed), profile=CREATE2,
        packets=record.header["packets"], baud=record.header["baud"], name="run.rec",
    )  # fmt: skip
    assert transport.first_difference() is None
    assert transport.first_difference() is None and transport.written == record.out_bytes
    assert summary.tick_halts == 0


#: SLOW_TERM whose terminate writes a drive and the brushes straight to the connection and
#: then blocks 2 s (the simulator's robot streams on meanwhile)
DRIVING_TERM = SLOW_TERM.replace(
    "            self.SEEN.append(",
    "            connection = self.robot.connection\n"
    "            connection.send(commands.drive(300, 32767))\n"
    "            connection.send(commands.motors(7))\n"
    "            x, y = connection.transport.simulator.x, connection.transport.simulator.y\n"
    "            connection.transport.advance(2.0)\n"
    "            self.MOVED.append(abs(connection.transport.simulator.x - x)\n"
    "                              + abs(connection.transport.simulator.y - y))\n"
    "            self.SEEN.append(",
).replace("    SEEN = []", "    SEEN, MOVED = [], []")


@pytest.mark.parametrize("tick_limit", [0.25, None])
def test_a_terminate_that_writes_a_drive_and_blocks_sets_nothing_going(
    run_mission: RunMission,
    tmp_path: Path,
    caplog: pytest.LogCaptureFixture,
    tick_limit: float | None,
) -> None:
    """A plugin's terminate() at the run's end writes a drive and the brushes straight to
    the connection, then blocks 2 s: neither is written (the tree's stop sets nothing going,
    CommandWriter.hold_motion), so the robot does not move meanwhile (it drove 0.6 m into
    whatever was there), and the warning names the behaviour and its line."""
    (tmp_path / "slowterm.py").write_text(DRIVING_TERM)
    mission = "plugins: [./slowterm.py]\ntree:\n  sequence:\n    - mode: safe\n    - slow_term\n"
    run = run_mission(
        mission, tick_limit=tick_limit, permissions=Permissions(plugin_files=True), timeout=0.5
    )
    leaf = next(n for n in run.runner.mission.root.iterate() if type(n).__name__ == "SlowTerm")
    assert run.summary.outcome.value == "timeout"
    if tick_limit is not None:  # drive 0 went out before the terminate: the robot stood
        assert type(leaf).MOVED == [0.0] and type(leaf).SEEN == [(0, 0)]  # type: ignore[attr-defined]
    written = run.link.written
    assert written.count(C.drive(300, 32767).data) == 1  # the leaf's own, at its start
    assert C.motors(7).data not in written
    assert written.endswith(C.drive(0, 0).data + C.motors_off().data + C.pause_stream().data
                            + C.start().data)  # fmt: skip
    held = [r.getMessage() for r in caplog.records if "not written" in r.getMessage()]
    assert len(held) == 2 and all(h.startswith("slow_term (SlowTerm.terminate at ") for h in held)
    assert "Drive (137) 89 01 2c 7f ff" in held[0] and "Motors (138) 8a 07" in held[1]


def test_the_brushes_stop_before_a_terminate_at_the_runs_end_with_the_wheels_at_rest(
    run_mission: RunMission,
) -> None:
    """The wheels at rest, the brushes and vacuum on, a node still running when the run
    ends: drive 0 and motors off go out before the tree's stop too (a terminate that
    blocked left the brushes running for as long), then the safe stop."""
    run = run_mission(
        "tree:\n  sequence:\n    - mode: safe\n"
        "    - motors: {main_brush: true, vacuum: true}\n    - wait: 10s\n",
        tick_limit=0.25, timeout=0.5,
    )  # fmt: skip
    assert run.summary.outcome.value == "timeout"
    first = C.drive(0, 0).data + C.motors_off().data
    assert run.link.written.endswith(first + first + C.pause_stream().data + C.start().data)
    assert run.summary.safe_stop.startswith("drive 0, motors off before the tree's stop, then")


def test_a_run_that_ended_with_its_tree_sends_no_drive_0_before_the_stop(
    run_mission: RunMission,
) -> None:
    """Nothing runs at a tree's own end (success): no terminate to wait for, nothing more
    written than the safe stop."""
    run = run_mission(
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 100 mm/s, distance: 2 cm}\n",
        tick_limit=0.25,
    )
    assert run.summary.outcome.value == "success"
    assert run.summary.safe_stop.startswith("sent ")
    assert not run.link.written.endswith(C.motors_off().data + C.drive(0, 0).data
                                         + C.motors_off().data + C.pause_stream().data
                                         + C.start().data)  # fmt: skip


def test_a_terminate_that_blocks_mid_run_is_the_tick_guards(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """A time limit that preempts a driving leaf mid-run calls its terminate() inside a
    tick: the tick guard covers it as it covers an update() (drive 0 behind its back), and
    the leaf's own halt, queued in that tick, stands: the wheels are not sent on again while
    the next branch runs."""
    blocking = (
        SLOW_TERM.replace(
            "    def terminate(self, new_status):\n",
            "    def terminate(self, new_status):\n        wait_for_the_guard(self.robot)\n",
        )
        + WAITS_FOR_THE_GUARD
    )
    (tmp_path / "slowterm.py").write_text(blocking)
    run = run_mission(
        "plugins: [./slowterm.py]\ntree:\n  sequence:\n    - mode: safe\n    - fallback:\n"
        "        - timeout: {after: 150ms, do: slow_term}\n        - wait: 300ms\n",
        tick_limit=0.25, permissions=Permissions(plugin_files=True), timeout=20.0,
    )  # fmt: skip
    assert run.summary.outcome.value == "success", run.summary
    assert run.summary.tick_halts == 1
    assert run.summary.tick_halt_first.startswith("slow_term (SlowTerm.terminate at ")
    drives = [data for _, data in run.link.writes if data[:1] == HALT[:1]]
    # forward, the guard's drive 0, the leaf's own halt; then the safe stop's: no forward again
    assert drives[:3] == [C.drive(300, 32767).data, HALT, HALT], drives
    assert len(drives) == 4 and drives[3].startswith(HALT)


def test_the_gap_a_blocked_tick_leaves_is_said_as_the_guards(
    run_mission: RunMission, plugin_dir: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A tick that blocks 2 s leaves 2 s of frames unread; the tick guard stopped the wheels
    meanwhile. The gap is said as what it was (a tick that blocked, drive 0 from the guard),
    not as a process suspended while the robot went on with its last command, and it is not
    an unread gap in the summary (the tick guard's line counts it)."""
    (plugin_dir / "stuck.py").write_text(
        PLUGIN.replace(
            "        return Status.SUCCESS",
            "            self.robot.connection.transport.advance(2.0)  # the robot streams on\n"
            "        return Status.SUCCESS",
        )
    )
    run = run_mission(
        MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True), timeout=20.0
    )
    summary = run.summary
    assert summary.outcome.value == "success", summary
    assert summary.tick_halts == 1
    assert summary.unread_gaps == 0 and "unread" not in str(summary), str(summary)
    said = [r.getMessage() for r in caplog.records if "no frame was read" in r.getMessage()]
    assert len(said) == 1, caplog.text
    assert "no frame was read for 2.0" in said[0]
    assert "a tick blocked (stuck (Stuck.update at " in said[0]
    assert "the tick guard had sent drive 0" in said[0]
    assert "suspended" not in said[0] and "went on with its last command" not in said[0]
    # stamped when it is said, at the gap's end (the next tick's time, 2 s on), not with the
    # blocked tick's own time: it came out after the guard's line from inside that tick with
    # an earlier stamp (t=1.140 "a tick ran over", then t=0.900 "no frame was read")
    [gap] = [r for r in caplog.records if "no frame was read" in r.getMessage()]
    stamp = getattr(gap, "mission_time", None)
    assert stamp is not None and 2.0 <= stamp <= summary.mission_time_s, (stamp, str(summary))


#: a leaf that blocks its first tick with nothing moving (Safe, no drive yet) until the test's
#: gate opens (``still_gate.wait()``: the test fails, saying so, if it never does), then has
#: the robot stream on for 1.5 s
STILL_PLUGIN = '''
import still_gate
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("still", kind="action")
class Still(Action):
    """Blocks its first tick, the robot at rest, until the test's gate opens."""

    def update(self):
        if not getattr(self, "waited", False):
            self.waited = True
            still_gate.wait()
            self.robot.connection.transport.advance(1.5)  # the robot streams on meanwhile
        return Status.SUCCESS
'''

STILL_MISSION = """
plugins: [./still.py]
tree:
  sequence:
    - mode: safe
    - still
    - drive: {velocity: 100 mm/s, distance: 2 cm}
"""


@pytest.fixture
def still_gate(monkeypatch: pytest.MonkeyPatch, plugin_dir: Path) -> threading.Event:
    """The still leaf's plugin beside the mission, and its gate: opened when the tick guard
    looks where the blocked tick is (``TickGuard._where``, which it does when it acts on a
    tick past its limit), so the leaf returns only once the guard has seen it: no wait
    whose length depends on the machine."""
    (plugin_dir / "still.py").write_text(STILL_PLUGIN)
    gate = types.ModuleType("still_gate")
    seen = guard_looks(monkeypatch)

    def wait() -> None:
        waited(seen, "the tick guard's look at the still tick")

    gate.wait = wait  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "still_gate", gate)
    return seen


def _gaps_said(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if "no frame was read" in r.getMessage()]


def test_the_gap_a_tick_blocked_with_the_robot_still_leaves_is_said_as_such(
    run_mission: RunMission,
    plugin_dir: Path,
    still_gate: threading.Event,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A tick that blocks before anything moves gets nothing from the guard (nothing to
    stop), but the 1.5 s it left unread is its own: said as a tick that blocked, in which
    behaviour and line, with the robot still; not as a process suspended or starved while
    the robot went on with its last command, and not counted as an unread gap (it was, in
    1 of 2 real-time runs of a plugin's 1 s sleep: the gap came out a little over or under
    the second that is said)."""
    run = run_mission(
        STILL_MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True), timeout=20.0
    )
    summary = run.summary
    assert summary.outcome.value == "success", summary
    assert summary.tick_halts == 0 and summary.tick_stills == 1, str(summary)
    assert summary.tick_still_first.startswith("still (Still.update at "), str(summary)
    assert (
        "tick guard   1 slow tick(s) with nothing moving (nothing to stop); the first in "
        "still (Still.update at " in str(summary)
    ), str(summary)
    assert summary.unread_gaps == 0 and "unread" not in str(summary), str(summary)
    said = _gaps_said(caplog)
    assert len(said) == 1, caplog.text
    assert "no frame was read for 1.5" in said[0]
    assert f"a tick blocked (still (Still.update at {plugin_dir / 'still.py'}:" in said[0]
    assert "with nothing moving: the robot stood still" in said[0]
    assert "suspended" not in said[0] and "went on with its last command" not in said[0]
    assert still_gate.is_set()
    # nothing was stopped behind the tick's back: the drive's own commands alone
    drives = [data for _, data in run.link.writes if data[:1] == HALT[:1]]
    assert drives[0] == FORWARD, drives


def _replayed_gaps(
    record_path: Path, plugin_dir: Path, caplog: pytest.LogCaptureFixture
) -> tuple[RunSummary, list[str]]:
    """``record_path`` replayed (the still leaf's own block left out: the record's arrivals
    make the gap), with what it said of the gaps and whether its bytes are the record's."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    source = (plugin_dir / "still.py").read_text()
    (plugin_dir / "still.py").write_text(
        source.replace("self.robot.connection.transport.advance(1.5)", "pass")
    )
    allowed = Permissions(plugin_files=True)
    record = load_record(record_path)
    caplog.clear()
    summary, transport = replay_record(
        record, load_mission(plugin_dir / "mission.yaml", permissions=allowed), profile=CREATE2,
        packets=record.header["packets"], baud=record.header["baud"], name="run.rec",
    )  # fmt: skip
    assert transport.first_difference() is None and transport.written == record.out_bytes
    return summary, _gaps_said(caplog)


def test_a_record_of_a_still_tick_replays_its_gap_as_the_run_said_it(
    run_mission: RunMission,
    plugin_dir: Path,
    still_gate: threading.Event,
    caplog: pytest.LogCaptureFixture,
    tmp_path: Path,
) -> None:
    """The guard notes the still tick in the record (its own key, not the acts' ``tick_guard``,
    which a replay answers with drive 0); the replay says the gap as the live run did, and
    writes the recorded bytes. A record made before (no such note: here taken out of this
    one) replays as before: the gap said as the process's, counted as unread."""
    from roomba_bt.runtime.tick_guard import STILL_NOTE

    record_path = tmp_path / "run.rec"
    run = run_mission(STILL_MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True),
                      timeout=20.0, record=record_path)  # fmt: skip
    assert run.summary.unread_gaps == 0 and len(_gaps_said(caplog)) == 1
    lines = record_path.read_text().splitlines(keepends=True)
    stills = [json.loads(line)["note"] for line in lines if STILL_NOTE in line]
    assert len(stills) == 1 and "tick_guard" not in stills[0], stills
    assert stills[0]["where"].startswith("still (Still.update at ")
    assert isinstance(stills[0]["tick"], int) and stills[0]["at"] == "after"

    summary, said = _replayed_gaps(record_path, plugin_dir, caplog)
    assert summary.unread_gaps == 0 and summary.tick_halts == 0, str(summary)
    assert summary.tick_stills == 1 and summary.tick_still_first == stills[0]["where"]
    assert len(said) == 1 and "no frame was read for 1.5" in said[0], said
    assert "a tick blocked (still (Still.update at " in said[0]
    assert "the robot stood still" in said[0]

    old = tmp_path / "old.rec"
    old.write_text("".join(line for line in lines if STILL_NOTE not in line))
    summary, said = _replayed_gaps(old, plugin_dir, caplog)
    assert summary.unread_gaps == 1 and "unread       1 gap(s)" in str(summary), str(summary)
    assert len(said) == 1 and "the process suspended or starved of CPU" in said[0], said


def test_a_still_tick_explains_only_the_gap_after_it(
    run_mission: RunMission,
    plugin_dir: Path,
    still_gate: threading.Event,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A still tick whose gap came out under a second is said nowhere (as any gap that
    short), and a later gap, the process not running (the link's reading side frozen 2 s),
    is said and counted as the process's: the still tick's mark is spent on the frames
    right after it."""
    (plugin_dir / "still.py").write_text(STILL_PLUGIN.replace("advance(1.5)", "advance(0.5)"))
    mission = STILL_MISSION.replace("distance: 2 cm", "distance: 20 cm")
    run = run_mission(mission, tick_limit=0.25, permissions=Permissions(plugin_files=True),
                      timeout=20.0, freeze=(1.2, 2.0))  # fmt: skip
    summary = run.summary
    assert summary.outcome.value == "success", summary
    assert still_gate.is_set()
    said = _gaps_said(caplog)
    assert len(said) == 1 and "the process suspended or starved of CPU" in said[0], said
    assert summary.unread_gaps == 1, str(summary)


#: the robot's own Clean cycle started (Passive: the tree drives nothing), then the still leaf
CYCLE_MISSION = """
plugins: [./still.py]
tree:
  sequence:
    - mode: safe
    - clean
    - wait: 150ms
    - still
    - wait: 100ms
"""


def test_the_gap_a_tick_blocked_while_a_cycle_drove_leaves_is_said_as_such(
    run_mission: RunMission,
    plugin_dir: Path,
    still_gate: threading.Event,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A tick that blocks while a built-in cycle (Clean) may be driving the robot in Passive:
    the guard ends no cycle, and sends nothing, but the gap is that tick's: said naming the
    behaviour and its line, and that the cycle went on driving; not as a process suspended
    or starved of CPU (what it said, and counted as unread), and counted on the summary's
    tick guard line. A record keeps the note (a key of its own), and its replay says the
    gap the same way, writing the recorded bytes."""
    from roomba_bt.runtime.tick_guard import CYCLE_NOTE

    record_path = plugin_dir / "run.rec"  # the test's folder
    run = run_mission(CYCLE_MISSION, tick_limit=0.25, permissions=Permissions(plugin_files=True),
                      timeout=20.0, record=record_path)  # fmt: skip
    summary = run.summary
    assert summary.outcome.value == "success", summary
    assert still_gate.is_set()  # the guard looked where the tick was
    assert summary.unread_gaps == 0 and "unread" not in str(summary), str(summary)
    assert summary.tick_halts == summary.tick_stills == 0 and summary.tick_cycles == 1
    assert summary.tick_cycle_first.startswith("still (Still.update at "), str(summary)
    assert "1 slow tick(s) while a built-in cycle could drive the robot" in str(summary)
    said = _gaps_said(caplog)
    assert len(said) == 1, caplog.text
    assert "no frame was read for 1.5" in said[0]
    assert f"a tick blocked (still (Still.update at {plugin_dir / 'still.py'}:" in said[0]
    assert "while the robot's Clean (135) cycle could drive it" in said[0]
    assert "the cycle went on driving" in said[0]
    assert "the tick guard does not end a built-in cycle" in said[0]
    assert "suspended" not in said[0] and "stood still" not in said[0]
    written = [data for _, data in run.link.writes]
    clean = written.index(C.clean().data)
    assert HALT not in written[clean + 1 :], written  # no drive 0 alone: nothing from the guard
    notes = [n for _, n in run_record_notes(record_path) if CYCLE_NOTE in n]
    assert len(notes) == 1 and notes[0]["cycle"] == "the robot's Clean (135) cycle", notes
    assert "tick_guard" not in notes[0] and "tick_still" not in notes[0]

    replayed, again = _replayed_gaps(record_path, plugin_dir, caplog)
    assert replayed.tick_cycles == 1 and replayed.unread_gaps == 0, str(replayed)
    assert len(again) == 1 and again[0].split(": ", 1)[1] == said[0].split(": ", 1)[1], again


def run_record_notes(path: Path) -> list[tuple[float, dict[str, object]]]:
    from roomba_bt.runtime.recording import load_record

    return list(load_record(path).notes)


@pytest.mark.extra("monitor")
def test_the_monitor_shows_a_still_tick_live_and_replayed(
    run_mission: RunMission,
    plugin_dir: Path,
    still_gate: threading.Event,
    tmp_path: Path,
) -> None:
    """A still block was a log warning only (and only when its gap came out a second or
    more): the monitor's timeline showed nothing of it. Now it is an event there, as a
    halt is, naming the behaviour and its line: on the live page (the feed watching the
    run) and on a record's (``roomba-bt monitor RECORD``: the replay's guard tells it)."""
    from roomba_bt.mission import load_mission
    from roomba_bt.monitor.feed import RunFeed
    from roomba_bt.monitor.recorded import replay_into_feed
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record

    def still_events(feed: RunFeed) -> list[str]:
        return [e.text for e in feed.events if e.kind == "note" and "tick guard" in e.text]

    allowed = Permissions(plugin_files=True)
    record_path = tmp_path / "run.rec"
    (plugin_dir / "mission.yaml").write_text(STILL_MISSION)
    live = RunFeed(history=5000, mission_name="still")
    live.set_tree(load_mission(plugin_dir / "mission.yaml", permissions=allowed).root)
    run = run_mission(STILL_MISSION, tick_limit=0.25, permissions=allowed, timeout=20.0,
                      record=record_path, observer=live.observe)  # fmt: skip
    assert run.summary.tick_stills == 1, str(run.summary)
    said = still_events(live)
    assert len(said) == 1, [e.text for e in live.events]
    assert said[0].startswith("tick guard: a tick ran over its limit with nothing moving, in ")
    assert "still (Still.update at " in said[0] and "nothing to stop; 1 so far" in said[0]

    (plugin_dir / "still.py").write_text(STILL_PLUGIN.replace(
        "self.robot.connection.transport.advance(1.5)", "pass"))  # fmt: skip
    record = load_record(record_path)
    feed, summary = replay_into_feed(
        record, load_mission(plugin_dir / "mission.yaml", permissions=allowed), CREATE2,
        tuple(record.header["packets"]), record.header["baud"], "r",
    )  # fmt: skip
    assert summary.tick_stills == 1
    assert still_events(feed) == said, [e.text for e in feed.events]


#: the brushes and vacuum on, then the drive beside the blocking leaf
MOTORS_MISSION = MISSION.replace(
    "    - mode: safe\n",
    "    - mode: safe\n    - motors: {main_brush: true, side_brush: true, vacuum: true}\n",
)
#: blocks until the motors were turned off behind its back
MOTORS_PLUGIN = PLUGIN.replace(
    'getattr(writer.last_wheels, "args", None) != (0, 0)',
    'getattr(writer.last_motors, "args", None) != (0,)',
)
MOTORS_ON = C.motors(7).data


def test_a_tick_that_blocks_with_the_motors_on_gets_them_off_and_back_after(
    run_mission: RunMission, plugin_dir: Path, tmp_path: Path
) -> None:
    """The guard sent drive 0 alone: a blocked ``update`` of 5 s ran the brushes and vacuum
    on the spot for 5 s (the audit's finding 7). Now drive 0 and motors off go in one write,
    noted in the record; when the tick returns the wheels and the motors get the tree's
    commands again, and a replay writes the same bytes."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record
    from roomba_bt.runtime.stack import replay_record

    (plugin_dir / "stuck.py").write_text(MOTORS_PLUGIN)
    record_path = tmp_path / "run.rec"
    allowed = Permissions(plugin_files=True)
    run = run_mission(MOTORS_MISSION, tick_limit=0.25, permissions=allowed, timeout=20.0,
                      record=record_path)  # fmt: skip
    assert run.summary.outcome.value == "success", run.summary
    assert run.summary.tick_halts == 1
    written = [data for _, data in run.link.writes]
    guard = written.index(HALT + C.motors_off().data)  # the guard's act, one write
    assert MOTORS_ON in written[:guard] and FORWARD in written[:guard]
    after = written[guard + 1 :]
    assert after[:2] == [FORWARD, MOTORS_ON], after  # the tree's commands back, wheels first
    notes = [n for _, n in load_record(record_path).notes if "tick_guard" in n]
    assert [n.get("motors") for n in notes] == [True]
    # docs/runtime.md's line, its leaf slow in /home/me/boom.py
    page = {
        "stuck (Stuck.update": "slow (Slow.update",
        str(plugin_dir / "stuck.py"): "/home/me/boom.py",
    }
    assert_quoted("docs/runtime.md", "tick guard 7 slow tick(s)", str(run.summary), numbers=True,
                  names=page)  # fmt: skip
    (plugin_dir / "stuck.py").write_text(_blocking_for(MOTORS_PLUGIN, "0.0"))
    mission = load_mission(plugin_dir / "mission.yaml", permissions=allowed)
    record = load_record(record_path)
    _, transport = replay_record(
        record, mission, profile=CREATE2, packets=record.header["packets"],
        baud=record.header["baud"], name="run.rec",
    )  # fmt: skip
    assert transport.first_difference() is None and transport.written == record.out_bytes
