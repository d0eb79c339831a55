"""Brushes and vacuum run at a part of their power by ``pwm_motors`` (PWM Motors 144) are
off at every ending, as those ``motors`` ran are: the safe stop's Motors 0 (``[138][0]``)
goes out in Safe before its Start, after success, failure, a timeout, Ctrl-C, the monitor's
stop and a behaviour's exception; ``mode: passive`` sends it before its Start; a ``--fast``
run of the command line writes the same; the monitor's pause switches them off and its
resume sends them again at their part of power. The simulator's motors are off after each."""

from __future__ import annotations

import json
import signal
import threading
from collections.abc import Callable
from pathlib import Path

import py_trees
import pytest

from roomba_bt.behaviours.actions import Mode, PwmMotors, Wait
from roomba_bt.cli import main
from roomba_bt.mission import load_mission_text
from roomba_bt.monitor.feed import RunFeed
from roomba_bt.monitor.session import MonitorSession
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import Simulator, load_world

from .simrun import Raises, TapLink

#: 40% inward, 30% clockwise, 50%: ``[144][51][-38][64]``
GENTLE = oi.pwm_motors(51, -38, 64)
#: the safe stop: drive 0, motors off, the stream paused, Start
SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def _mission(*after: str) -> str:
    """Safe, the brushes and vacuum at a part of their power, then each of ``after``."""
    steps = "".join(f"    - {step}\n" for step in after)
    return (
        "mission: gentle\ntree:\n  sequence:\n    - mode: safe\n"
        f"    - pwm_motors: {{main_brush: 40%, side_brush: -30%, vacuum: 50%}}\n{steps}"
    )


def _signal_main(signum: int) -> None:
    signal.pthread_kill(threading.main_thread().ident or 0, signum)


def _at_tick(act: Callable[[MissionRunner], None]) -> Callable[[MissionRunner], None]:
    """An observer that does ``act`` once, after the 40th tick (0.6 s: the motors run)."""

    def observer(runner: MissionRunner) -> None:
        if runner.snapshot.tick == 40:
            act(runner)

    return observer


ENDINGS = {
    "success": ("wait: 1s", {}, Outcome.SUCCESS),
    "failure": ("force_failure: {wait: 1s}", {}, Outcome.FAILURE),
    "timeout": ("wait: 1min", {"timeout_s": 1.0}, Outcome.TIMEOUT),
    "ctrl-c": (
        "wait: 1min",
        {"observer": _at_tick(lambda _: _signal_main(signal.SIGINT))},
        Outcome.INTERRUPTED,
    ),
    "a program's stop": (
        "wait: 1min",
        {"observer": _at_tick(lambda runner: runner.request_stop("stopped by the program"))},
        Outcome.INTERRUPTED,
    ),
}


def _run(
    mission: TreeMission | str, gate: MonitorSession | None = None, **options: object
) -> tuple[TapLink, Outcome]:
    """``mission`` on the simulator's virtual clock, every byte tapped; ``gate``: the
    monitor's session, as ``run --monitor`` sets it."""
    link = TapLink(Simulator(load_world("empty-room"), CREATE2, 0))
    loaded = load_mission_text(mission) if isinstance(mission, str) else mission
    stack = RunStack(loaded, link, profile=CREATE2, **options)  # type: ignore[arg-type]
    if gate is not None:
        stack.runner.gate = gate
    try:
        summary = stack.run(raise_interrupts=False)
    finally:
        stack.close()
    return link, summary.outcome


def _assert_stopped(link: TapLink) -> None:
    written = link.written
    assert GENTLE.data in written  # the brushes ran at their part of full power
    assert written.endswith(SAFE_END), written[written.rindex(GENTLE.data) :].hex(" ")
    simulator = link.simulator
    assert simulator.brush_pwm == (0, 0, 0) and simulator.mode is OIMode.PASSIVE


@pytest.mark.parametrize("ending", ENDINGS)
def test_the_safe_stop_switches_them_off_at_every_ending(ending: str) -> None:
    after, options, outcome = ENDINGS[ending]
    link, ended = _run(_mission(after), **options)
    assert ended is outcome
    _assert_stopped(link)


def test_the_safe_stop_switches_them_off_after_a_behaviour_raised() -> None:
    """A bug in a behaviour (exit 4) ends the run as every other ending does."""
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        PwmMotors("gentle", {"main_brush": 40.0, "side_brush": -30.0, "vacuum": 50.0}),
        py_trees.composites.Parallel(
            "par", policy=py_trees.common.ParallelPolicy.SuccessOnOne(),
            children=[Wait("w", {"duration": 60.0}), Raises(ZeroDivisionError(), "update")],
        ),
    ])  # fmt: skip
    link, ended = _run(TreeMission(root, "raises"), timeout_s=5.0)
    assert ended is Outcome.ERROR
    _assert_stopped(link)


def test_mode_passive_switches_them_off_before_its_start() -> None:
    """Start (128) is not said by the spec to stop the motors: Motors 0 goes first."""
    link, ended = _run(_mission("wait: 500ms", "mode: passive"))
    assert ended is Outcome.SUCCESS
    written = link.written
    after = written[written.rindex(GENTLE.data) + len(GENTLE.data) :]
    assert after.startswith(oi.motors_off().data + oi.start().data), after.hex(" ")
    assert link.simulator.brush_pwm == (0, 0, 0)


def test_a_fast_run_of_the_command_line_ends_with_them_off(tmp_path: Path) -> None:
    """``roomba-bt run gentle.yaml --fast``: the record's bytes out, the PWM Motors among
    them, end with the safe stop."""
    path = tmp_path / "gentle.yaml"
    path.write_text(_mission("wait: 1s"))
    record = tmp_path / "run.jsonl"
    assert main(["run", str(path), "--fast", "--display", "none", "--record", str(record)]) == 0
    events = [json.loads(line) for line in record.read_text().splitlines()[1:]]
    out = b"".join(bytes.fromhex(e["b"]) for e in events if e.get("d") == "out")
    assert GENTLE.data in out and out.endswith(SAFE_END), out.hex(" ")


def _monitor(mission: str) -> MonitorSession:
    loaded = load_mission_text(mission)
    feed = RunFeed(history=None, mission_name=loaded.name)
    feed.set_tree(loaded.root)
    return MonitorSession(feed, simulator=True)


def test_the_monitor_s_stop_switches_them_off() -> None:
    mission = _mission("wait: 1min")
    session = _monitor(mission)
    link, ended = _run(mission, session, observer=_at_tick(lambda _: session.request("stop")))
    assert ended is Outcome.INTERRUPTED
    _assert_stopped(link)


def test_the_monitor_s_pause_switches_them_off_and_its_resume_sends_them_again() -> None:
    """The pause's safe stop (motors off, Passive) and the resume's standing commands: the
    brushes at their part of power again, not at full power nor left off."""
    mission = _mission("wait: 3s")
    session = _monitor(mission)
    seen: dict[str, tuple[int, int, int]] = {}
    before_tick = session.before_tick

    def operator(runner: MissionRunner) -> bool:  # every frame's, paused or not
        tick, simulator = runner.snapshot.tick, runner.connection.link.transport.simulator
        if tick == 40:
            session.request("pause")
        elif tick == 80:
            seen["paused"] = simulator.brush_pwm
            session.request("resume")
        elif tick == 120:
            seen["resumed"] = simulator.brush_pwm
        return before_tick(runner)

    session.before_tick = operator  # type: ignore[method-assign]
    link, ended = _run(mission, session)
    assert ended is Outcome.SUCCESS
    assert seen == {"paused": (0, 0, 0), "resumed": (51, -38, 64)}
    _assert_stopped(link)
