"""An action whose ``terminate()`` does not call ``super().terminate()`` (py_trees' own does
nothing, so its users seldom call it) is halted all the same when it ends, and the class is
named once (session 27's plugin author: ``forward_logged`` pushed on at 200 mm/s through a
whole ``wait: 5s`` after its ``until: bump`` guard fired, and the bump reflex wrote the dead
action's drive again; ``sticky2`` drove an arc for 3 s, not 1 s)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import py_trees
import pytest

from roomba_bt.mission import Permissions
from roomba_bt.oi import commands as C
from roomba_bt.runtime.summary import Outcome

from .simrun import Run, RunMission

#: the stranger's classes (their plugin packages bt-bad-halt and bt-bad-run), plus one that
#: calls super() and then drives again, and one that calls super() as it should
PLUGIN = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


class Forward(Action):
    """Drives forward at 200 mm/s until stopped (each class below ends it its own way)."""

    def update(self):
        self.send(commands.drive_straight(200))
        return Status.RUNNING


@declare("forward_logged", kind="action", sends=opcodes("drive"))
class ForwardLogged(Forward):
    """Drive forward; terminate() logs (py_trees idiom) without calling super()."""

    def terminate(self, new_status):
        self.logger.debug(f"terminate {self.status} -> {new_status}")


class StartsOnce(Action):
    """Sends its COMMAND once in start(), then only returns RUNNING; terminate does nothing
    (no super())."""

    COMMAND = staticmethod(commands.clean)

    def start(self):
        self.send(self.COMMAND())

    def update(self):
        return Status.RUNNING

    def terminate(self, new_status):
        return None


@declare("sticky2", kind="action", sends=opcodes("drive"))
class Sticky2(StartsOnce):
    """Starts the wheels once: an arc."""

    COMMAND = staticmethod(lambda: commands.drive(200, 500))


@declare("drives_after_super", kind="action", sends=opcodes("drive"))
class DrivesAfterSuper(Forward):
    """Calls super().terminate(), then sends a drive of its own."""

    def terminate(self, new_status):
        super().terminate(new_status)
        self.send(commands.drive_straight(300))


@declare("cleans_quietly", kind="action", sends=opcodes("clean"))
class CleansQuietly(StartsOnce):
    """Starts the built-in Clean once."""


@declare("polite", kind="action", sends=opcodes("drive"))
class Polite(Forward):
    """Drives; its terminate calls super()."""

    def terminate(self, new_status):
        super().terminate(new_status)


@declare("sticky", kind="action", sends=opcodes("drive"))
class Sticky(Forward):
    """Drives; its terminate() does not call super() and re-sends a drive."""

    def terminate(self, new_status):
        self.send(commands.drive_straight(300))
'''

HALT = C.drive(0, 0).data
FORWARD = C.drive_straight(200).data
PERMIT = Permissions(plugin_files=True)


@pytest.fixture
def plugin(tmp_path: Path) -> Path:
    path = tmp_path / "mine.py"
    path.write_text(PLUGIN)
    # said once per class: each test's file is a module, and its classes, of its own
    return path


@pytest.fixture
def run_warned(run_mission: RunMission, caplog: pytest.LogCaptureFixture) -> RunMission:
    """``run_mission`` with plugin files allowed (each mission loads the stranger's file) and
    the warnings it logs kept in ``caplog``, for :func:`_warnings`."""

    def run(mission: str, **options: Any) -> Run:
        with caplog.at_level(logging.WARNING):
            return run_mission(mission, permissions=PERMIT, **options)

    return run


def _drives(run_writes: list[tuple[float, bytes]]) -> list[tuple[float, bytes]]:
    """The Drive commands written, each when it first differed from the one before (an
    action sends its drive on every tick)."""
    drives: list[tuple[float, bytes]] = []
    for t, data in run_writes:
        drive = data[:5]  # the safe stop's drive 0 comes in one write with the rest
        if drive[:1] == HALT[:1] and (not drives or drives[-1][1] != drive):
            drives.append((t, drive))
    return drives


def _line_of(text: str, in_class: str) -> int:
    """The line (from 1) of :data:`PLUGIN` holding ``text`` first after ``class in_class``."""
    lines = PLUGIN.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"class {in_class}("))
    return next(i for i in range(start, len(lines)) if text in lines[i]) + 1


def _warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if "terminate" in r.getMessage()]


def test_an_until_guard_halts_an_action_whose_terminate_skips_super(
    run_warned: RunMission, plugin: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The stranger's ``m/halt.yaml``: drive 0 is written in the tick the bump guard fires,
    the bump reflex does not send the dead action's drive again, and the robot stands
    through the wait. The reflex's hold is drive 0 at the onset frame; the guard fires a
    frame later and its halt is that tick's wheel command, so the held forward drive is not
    written again."""
    mission = """
    plugins: [./mine.py]
    tree:
      sequence:
        - mode: safe
        - forward_logged: {}
          until: {bump: any}
        - log: "bumped; waiting 5 s"
        - wait: 5s
        - mode: passive
    """
    run = run_warned(mission)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    drives = _drives(run.link.writes)
    # forward, the reflex's drive 0 at the bump's onset, and nothing after it turns a wheel:
    # not the reflex's resend of the held forward drive, not the dead action's
    assert [data for _, data in drives] == [FORWARD, HALT], drives
    first_halt = drives[1][0]
    # the guard fires on the frame that confirms the bump, one slot later: its drive 0
    guard_tick = [data for t, data in run.link.writes if abs(t - (first_halt + 0.015)) < 1e-9]
    assert guard_tick == [HALT], guard_tick
    # it stood through the wait: the run went on 5 s after the bump and the robot is where
    # the bump left it
    assert run.simulator.time - first_halt > 5.0
    [said] = _warnings(caplog)
    assert said.startswith("forward_logged (ForwardLogged.terminate at ")
    assert f"{plugin}:" in said
    assert "did not call super().terminate(): the wheels were left turning; halted" in said


def test_a_timeout_halts_wheels_started_in_start_with_a_terminate_that_does_nothing(
    run_warned: RunMission, plugin: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``m/sticky2.yaml``: the arc stops at the timeout's 1 s, not at the end of the wait."""
    mission = """
    plugins: [./mine.py]
    tree:
      sequence:
        - mode: safe
        - force_success:
            timeout:
              after: 1s
              do: sticky2
        - wait: 2s
        - mode: passive
    """
    run = run_warned(mission)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    drives = _drives(run.link.writes)
    [(started, arc), (halted, stop), *_rest] = drives
    assert arc == C.drive(200, 500).data and stop == HALT
    assert halted - started == pytest.approx(1.0, abs=0.05)
    [said] = _warnings(caplog)
    assert said.startswith("sticky2 (Sticky2.terminate at ") and f"{plugin}:" in said


def test_a_drive_sent_after_super_terminate_is_halted_and_said_so(
    run_warned: RunMission, plugin: Path, caplog: pytest.LogCaptureFixture
) -> None:
    mission = """
    plugins: [./mine.py]
    tree:
      sequence:
        - mode: safe
        - force_success:
            timeout: {after: 500ms, do: drives_after_super}
        - wait: 1s
    """
    run = run_warned(mission)
    drives = [data for _, data in _drives(run.link.writes)]
    assert drives[:2] == [FORWARD, HALT], drives
    assert C.drive_straight(300).data not in drives
    [said] = _warnings(caplog)
    assert "sent a wheel command after super().terminate(): the wheels were left" in said


def test_said_once_per_class_and_not_for_a_terminate_that_calls_super(
    run_warned: RunMission, plugin: Path, caplog: pytest.LogCaptureFixture
) -> None:
    mission = """
    plugins: [./mine.py]
    tree:
      sequence:
        - mode: safe
        - repeat:
            times: 3
            do:
              sequence:
                - force_success: {timeout: {after: 150ms, do: sticky2}}
                - wait: 100ms
                - force_success: {timeout: {after: 150ms, do: polite}}
                - wait: 100ms
    """
    run = run_warned(mission)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    assert len(_warnings(caplog)) == 1
    drives = [data for _, data in _drives(run.link.writes)]
    arc = C.drive(200, 500).data
    # each time: the arc, its halt (Action.stop's), forward, its halt (Polite's super())
    assert drives == [arc, HALT, FORWARD, HALT] * 3, drives


def test_a_tree_ticked_by_the_generator_halts_it_too(plugin: Path) -> None:
    """py_trees' own ``tick()`` (a visitor's, a tree stepped by hand) stops a leaf by the
    same ``stop``: the halt does not depend on the lean tick."""
    from roomba_bt.behaviours import builtin_registry
    from roomba_bt.robot.testing import StubRobot

    registry, errors = builtin_registry().with_file(plugin)
    assert not errors
    declaration = registry.get("sticky2")
    assert declaration is not None
    robot = StubRobot()  # in Safe
    leaf = declaration.cls("sticky2", {})
    leaf.setup(robot=robot)
    for _ in leaf.tick():
        pass
    assert [c.data for c in robot.outbox.drain()] == [C.drive(200, 500).data]
    leaf.stop(py_trees.common.Status.INVALID)
    assert [c.data for c in robot.outbox.drain()] == [HALT]


def test_a_built_in_cycle_a_halted_action_left_running_is_ended(
    run_warned: RunMission, plugin: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Its terminate's super() ended the cycle (Safe, drive 0, motors off, Start); left out,
    the firmware cleaned on in Passive, where nothing else the tree sends stops it."""
    mission = """
    plugins: [./mine.py]
    tree:
      sequence:
        - force_success:
            timeout: {after: 1s, do: cleans_quietly}
        - wait: 2s
    """
    run = run_warned(mission)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary.reason
    end = [c.data for c in (C.safe(), C.halt(), C.motors_off(), C.start())]
    [(started, _)] = [(t, data) for t, data in run.link.writes if data == C.clean().data]
    after = [(t, data) for t, data in run.link.writes if t > started]
    assert [data for _, data in after[:4]] == end, after
    assert after[0][0] - started == pytest.approx(1.0, abs=0.05)
    [said] = _warnings(caplog)
    assert "the built-in cycle it started was left running; ended (Start)" in said


def test_a_drive_a_terminate_queues_at_the_run_s_end_is_dropped_with_a_warning(
    run_warned: RunMission, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``m/st.yaml`` with ``--timeout 1``: the drive was not written, as docs/runtime.md
    says, but the warning naming the behaviour it promises was not given."""
    (tmp_path / "sticky.py").write_text(PLUGIN)
    mission = "plugins: [./sticky.py]\ntree:\n  sequence:\n    - mode: safe\n    - sticky\n"
    run = run_warned(mission, timeout=1.0)
    assert run.summary.outcome is Outcome.TIMEOUT
    assert C.drive_straight(300).data not in b"".join(data for _, data in run.link.writes)
    [said] = [r.getMessage() for r in caplog.records if "sticky" in r.getMessage()]
    where = f"{tmp_path / 'sticky.py'}:{_line_of('def terminate', 'Sticky')}"
    assert said.startswith(
        f"sticky (Sticky.terminate at {where}) queued Drive (137) 89 01 2c "
        "80 00 while the tree was being stopped: not written"
    ), said
