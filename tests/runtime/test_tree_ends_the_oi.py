"""A tree that sends Stop (173) or Reset (7) itself (roomba600-owner finding 1). Stop ends the
sensor stream, and the frames are the run's clock: its ticks, ``--timeout``, every timeout in
the tree; the watchdog is off after Stop (silence is what it asks for). A mission that went on
after it ran for ever (11 minutes at 70 % CPU with ``--fast``, ``ticks 2``). Now the run ends
at once: the tree's outcome when it ended on that tick, else FAILURE saying why; the robot is
left in Off, and nothing is written after the Stop. The validator refuses a leaf after one
(tests/mission/test_profile_commands.py)."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.mission import Permissions
from roomba_bt.oi import commands as C
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.runtime.summary import Outcome

from .simrun import Run, RunMission

#: the owner's plugin (m/plugins/display.py, its oi_off: Stop, then success), and leaves as
#: a user may write them that send Stop or Reset and then wait for something (the validator
#: cannot see that they go on after the command: each is the last leaf)
PLUGIN = '''
from py_trees.common import Status
from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes

class SendsOnce(Action):
    """Sends its COMMAND at its start, then returns ENDS on every tick."""
    COMMAND = staticmethod(commands.stop)
    ENDS = Status.SUCCESS
    def start(self) -> None:
        self.send(self.COMMAND())
    def update(self) -> Status:
        return self.ENDS

@declare("oi_off", kind="action", sends=opcodes("stop"))
class OIOff(SendsOnce):
    """Stop (173): the OI off."""

@declare("off_and_wait", kind="action", sends=opcodes("stop"))
class OffAndWait(SendsOnce):
    """Stop (173), then wait for the OI to come back (it never does by itself)."""
    ENDS = Status.RUNNING

@declare("drive_then_off", kind="action", sends=opcodes("drive", "motors", "stop"))
class DriveThenOff(Action):
    """Drives with the brushes on, then turns the OI off in the tick it ends."""
    def start(self) -> None:
        self.started_at = self.snapshot.time
        self.send(commands.motors(0b110))  # the main brush and the vacuum
    def update(self) -> Status:
        if self.snapshot.time - self.started_at >= 0.3:
            self.send(commands.stop())
            return Status.SUCCESS
        self.send(commands.drive_straight(200))
        return Status.RUNNING

@declare("reboot_and_wait", kind="action", sends=opcodes("reset"))
class RebootAndWait(SendsOnce):
    """Reset (7), then wait for the robot to come back."""
    COMMAND = staticmethod(commands.reset)
    ENDS = Status.RUNNING
'''

#: how long the run may take in wall-clock seconds before the test calls it a hang: the run
#: itself is a few hundred simulated frames, milliseconds (the suite's hang bound)
DEADLINE_S = HANG_S


def _run_with_deadline(run_mission: RunMission, tmp_path: Path, leaf: str) -> Run:
    """The mission (Safe, a 0.5 s drive, ``leaf``) with ``--timeout 3s`` on the virtual
    clock, in a thread: one still running after :data:`DEADLINE_S` is stopped (the run's own
    request_stop) and the test fails."""
    (tmp_path / "display.py").write_text(PLUGIN)
    mission = f"""
        mission: ends the OI
        plugins: [./display.py]
        tree:
          sequence:
            - mode: safe
            - drive: {{velocity: 100 mm/s, duration: 0.5s}}
            - {leaf}
        """
    done: list[Run] = []
    runners: list[object] = []

    def observe(runner: object) -> None:
        if not runners:
            runners.append(runner)

    thread = threading.Thread(
        target=lambda: done.append(
            run_mission(
                mission,
                timeout=3.0,
                profile=PROFILES["roomba600"],
                permissions=Permissions(plugin_files=True),
                observer=observe,  # type: ignore[arg-type]
            )
        ),
        daemon=True,
    )
    thread.start()
    thread.join(DEADLINE_S)
    if thread.is_alive():
        runners[0].request_stop("the test's deadline")  # type: ignore[attr-defined]
        thread.join(DEADLINE_S)
        pytest.fail(f"{leaf}: the run was still going after {DEADLINE_S:g} s: a hang")
    return done[0]


@pytest.mark.parametrize(("leaf", "sent"), [("off_and_wait", "Stop (173)"),
                                            ("reboot_and_wait", "Reset (7)")])  # fmt: skip
def test_a_tree_that_turns_the_oi_off_ends_the_run_at_once(
    run_mission: RunMission, tmp_path: Path, leaf: str, sent: str
) -> None:
    run = _run_with_deadline(run_mission, tmp_path, leaf)
    summary = run.summary
    assert summary.outcome is Outcome.FAILURE, summary.reason
    assert summary.reason.startswith(f"the tree sent {sent} while it still ran in {leaf}: ")
    assert "must be the last the tree runs" in summary.reason
    command = bytes(opcodes("stop" if leaf == "off_and_wait" else "reset"))
    assert run.link.writes[-1][1].endswith(command)  # nothing written after it
    assert summary.final_mode is OIMode.OFF
    assert summary.safe_stop.startswith(f"nothing to send: the tree's {sent} left the robot in Off")
    assert summary.mission_time_s < 1.0  # the drive's 0.5 s and a tick, not the timeout
    if leaf == "off_and_wait":  # the page's Stop (173)
        said = str(summary)
        assert_quoted("docs/runtime.md", "safe stop nothing to send: the tree's Stop", said)
        assert_quoted("docs/runtime.md", "final mode Off", said)


def test_the_owners_stop_as_the_last_leaf_ends_the_run_with_the_tree(
    run_mission: RunMission, tmp_path: Path
) -> None:
    run = _run_with_deadline(run_mission, tmp_path, "oi_off")
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.summary.final_mode is OIMode.OFF
    assert run.link.writes[-1][1].endswith(bytes(opcodes("stop")))


OWNERS_MISSION = """\
mission: display5
plugins: [plugins/display.py]
tree:
  sequence:
    - mode: safe
    - oi_off
    - mode: passive
    - mode: safe
    - drive: {velocity: 100 mm/s, duration: 1s}
"""


def test_the_owners_mission_is_refused_before_anything_is_sent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """m/display5.yaml: the validator's old advice (mode: passive after Stop) ran for ever;
    `run` validates first, so it is refused there too (exit 2, nothing sent)."""
    (tmp_path / "plugins").mkdir()
    (tmp_path / "plugins" / "display.py").write_text(PLUGIN)
    mission = tmp_path / "display5.yaml"
    mission.write_text(OWNERS_MISSION)
    code = main(["validate", str(mission), "--profile", "roomba600", "--allow-plugin-files"])
    out, err = capsys.readouterr()
    assert code == 2, out + err  # it said "ok", and `run` ran for ever
    assert "display5.yaml:7:7: mode can run after oi_off (line 6) sent Reset (7) or Stop (173)" in (
        out + err
    )


def test_a_tree_s_stop_while_the_wheels_turn_goes_after_drive_0_and_motors_off(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """Stop (173) says nothing of the wheels or the brushes: a tree's own, sent in Safe while
    they turned, went out alone (its leaf's halt came after it, refused in Off). Now drive 0
    and motors off go first, as ``--end-in stop``'s do."""
    run = _run_with_deadline(run_mission, tmp_path, "drive_then_off")
    written = b"".join(data for _, data in run.link.writes)
    stop = bytes(opcodes("stop"))
    assert written.endswith(C.halt().data + C.motors_off().data + stop)
    assert run.summary.final_mode is OIMode.OFF


POWER_PLUGIN = '''
from py_trees.common import Status
from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes

@declare("do_power", kind="action", sends=opcodes("power"))
class DoPower(Action):
    """Power (133): the robot asleep."""
    def update(self) -> Status:
        self.send(commands.power())
        return Status.SUCCESS
'''


def test_a_plugin_that_declares_power_is_refused_before_anything_is_sent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The stranger's do_power (session 36): the robot fell asleep, its stream stopped, and
    the run said CONNECTION LOST, exit 8 ("the robot may have moved"), for a command the tree
    sent. Refused where it is declared: a mission error, exit 2, before the port is opened."""
    (tmp_path / "modes.py").write_text(POWER_PLUGIN)
    mission = tmp_path / "power.yaml"
    mission.write_text(
        "plugins: [./modes.py]\ntree:\n  sequence:\n    - mode: safe\n    - do_power\n"
    )
    code = main(["run", str(mission), "--fast", "--display", "none", "--allow-plugin-files"])
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert (
        "power.yaml:1:11: plugin " in err
        and f"DoPower ({tmp_path / 'modes.py'}:7) declares itself wrongly: sends power (133), "
        "which roomba-bt never sends: the robot falls asleep and its sensor stream stops"
        in err
    ), err
    assert "CONNECTION LOST" not in out + err
