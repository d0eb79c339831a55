"""``roomba-bt run --strict`` (``RunStack(..., strict=True)``): a run whose tree said SUCCESS
but whose leaf drove on, hundreds of drives refused by the mode guard, after a cliff dropped
the robot to Passive, ended SUCCESS, exit 0 (a plugin author's CI of missions on the
simulator). With ``--strict`` it exits 7, the summary naming each count and its first
instance; without it, the exit code is as ever and the summary warns of the refusals."""

from __future__ import annotations

import logging
from pathlib import Path

import py_trees
import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.cli import main
from roomba_bt.mission import Permissions
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import ExitCode, Outcome, RunFailed, RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import DRIVE_TO_WALL, LEDGE, RunMission, write_mission

#: a plugin's leaf that never looks at the mode: it sends its drive every tick for 8 s and
#: succeeds, whatever the robot did meanwhile
BLIND = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


@declare("blind_drive", kind="action", sends=opcodes("drive"))
class BlindDrive(Action):
    """Forward every tick for 8 s; never looks at a fall to Passive."""

    def start(self):
        self.began = self.snapshot.time

    def update(self):
        if self.snapshot.time - self.began >= 8.0:
            return Status.SUCCESS
        self.send(commands.drive(200, 32767))
        return Status.RUNNING


@declare("sticky", kind="action", sends=opcodes("drive"))
class Sticky(Action):
    """Drives; its terminate() does not call super() and queues a drive of its own."""

    def update(self):
        self.send(commands.drive_straight(200))
        return Status.RUNNING

    def terminate(self, new_status):
        self.send(commands.drive_straight(300))
'''

#: for :data:`LEDGE`: Safe, then the blind leaf over the edge (the robot falls at 3.33 s)
OVER_THE_EDGE_BLIND = """\
mission: blind
plugins: [./blind.py]
tree:
  sequence:
    - mode: safe
    - blind_drive
"""


@pytest.fixture
def blind(tmp_path: Path) -> list[str]:
    """``roomba-bt run`` of :data:`OVER_THE_EDGE_BLIND` in :data:`LEDGE`, its arguments."""
    (tmp_path / "blind.py").write_text(BLIND)
    (tmp_path / "blind.yaml").write_text(OVER_THE_EDGE_BLIND)
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    return [
        "run", str(tmp_path / "blind.yaml"), "--fast", "--display", "none",
        "--world", str(tmp_path / "ledge.yaml"), "--allow-plugin-files",
    ]  # fmt: skip


FIRST_REFUSAL = (
    "t=3.330 blind_drive: drive needs Safe or Full; the robot is in Passive since t=3.330, "
    "after a cliff"
)


def test_a_leaf_driving_on_after_a_fall_succeeds_without_strict_but_warns(
    blind: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Without ``--strict`` the exit code is the tree's (0), as before; the summary warns
    of the refusals, with the first, and says what ``--strict`` would make of it."""
    assert main(blind) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out
    assert "commands     222 written, 313 refused by the mode guard\n" in out
    assert (
        f"warning      the mode guard refused 313 commands the tree sent (the first: "
        f"{FIRST_REFUSAL}): --strict fails such a run (exit 7)\n"
    ) in out
    assert "\nstrict " not in out
    assert_quoted("docs/runtime.md", "outcome SUCCESS$", out)  # "the tree still succeeds"


def test_with_strict_it_exits_7_naming_each_count_and_its_first_instance(
    blind: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*blind, "--strict"]) == ExitCode.STRICT == 7
    out, err = capsys.readouterr()
    assert "outcome      SUCCESS" in out  # the tree's word, kept
    findings = (
        f"the mode guard refused 313 commands (the first: {FIRST_REFUSAL}); the robot fell "
        "to Passive by itself once (cliff) (the first: t=3.330 in blind_drive: cliff)"
    )
    assert f"strict       FAILED (exit 7): {findings}\n" in out
    assert f"roomba-bt: --strict: {findings}\n" in err
    assert "warning      " not in out  # the strict line says it
    assert_quoted("docs/runtime.md", "strict FAILED (exit 7)", out)
    assert_quoted("docs/runtime.md", "roomba-bt: --strict: the mode guard refused", err)


def test_a_clean_mission_passes_strict(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A mission that meets no hazard, and the shipped dock, whose fall to Passive on the
    charger's contacts is how docking ends, not a hazard met."""
    (tmp_path / "wall.yaml").write_text(DRIVE_TO_WALL)
    assert main(["run", str(tmp_path / "wall.yaml"), "--fast", "--display", "none",
                 "--strict"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert (
        "strict       passed: no command refused or dropped, no fall to Passive by itself, "
        "no undeclared blackboard key written\n"
    ) in out
    assert main(["run", "dock", "--fast", "--display", "none", "--strict"]) == 0
    out = capsys.readouterr().out
    assert "charger      docked once\n" in out  # the OI's own drop to Passive on the contacts
    assert "falls  " not in out  # a docking is not a fall to list (the soak: ten read as faults)
    assert (
        "strict       passed: no command refused or dropped, no fall to Passive by itself "
        "but onto the charger, no undeclared blackboard key written\n" in out
    )


def test_run_help_documents_strict_and_its_exit_code(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    said = " ".join(capsys.readouterr().out.split())
    assert "--strict" in said
    assert "7 succeeded but failed --strict" in said


def test_a_stack_run_strictly_raises_for_its_outcome(tmp_path: Path) -> None:
    """From Python: ``RunStack(..., strict=True)``; ``summary.exit_code`` is 7 and
    ``raise_for_outcome()`` raises, the findings on the exception. Without it, the same run
    is returned as a success."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    world = load_world(str(tmp_path / "ledge.yaml"))

    def run(strict: bool) -> RunSummary:
        root = py_trees.composites.Sequence("by hand", memory=True, children=[
            Mode("safe", {"to": "safe"}),
            py_trees.decorators.FailureIsSuccess(  # a fall fails the drive: the tree goes on
                "drive on", Drive("forward", {"velocity": "200 mm/s", "distance": "2 m"})
            ),
        ])  # fmt: skip
        link = SimLink(Simulator(world, CREATE2, seed=0))
        stack = RunStack(TreeMission(root, "edge"), link, profile=CREATE2, strict=strict)
        try:
            return stack.run()
        finally:
            stack.close()

    lenient = run(strict=False)
    assert lenient.falls == {"cliff": 1} and lenient.exit_code == 0
    assert lenient.raise_for_outcome() is lenient
    strict = run(strict=True)
    assert strict.outcome is Outcome.SUCCESS and strict.exit_code == ExitCode.STRICT
    with pytest.raises(RunFailed) as raised:
        strict.raise_for_outcome()
    failed = raised.value
    assert failed.exit_code is ExitCode.STRICT and failed.outcome is Outcome.SUCCESS
    assert failed.findings == (
        "the robot fell to Passive by itself once (cliff) (the first: t=3.330 in forward: cliff)",
    )
    assert (  # the caller wrote strict=True, not a flag: the check is named as a thing
        str(failed) == f"mission edge ended SUCCESS but failed the strict check: "
        f"{failed.findings[0]} (exit code 7)"
    )
    assert "--strict" not in "\n".join(strict.lines())


@pytest.mark.parametrize(
    ("falls", "fails"),
    [
        ({"charger": 2}, False),  # docking's end
        ({"cliff": 1}, True),
        ({"wheel drop": 1}, True),
        ({"unknown": 1}, True),
        ({"cliff and charger": 1}, True),  # a cliff met on the dock
    ],
)
def test_which_falls_fail_strict(falls: dict[str, int], fails: bool) -> None:
    summary = RunSummary("m", Outcome.SUCCESS, falls=falls, strict=True)
    assert summary.exit_code == (7 if fails else 0)


def test_a_failed_run_keeps_its_exit_code_and_says_the_findings_too() -> None:
    summary = RunSummary("m", Outcome.FAILURE, reason="r", refused_commands=2, strict=True)
    assert summary.exit_code == ExitCode.MISSION_FAILED
    assert "strict       also: the mode guard refused 2 commands" in summary.lines()
    lenient = RunSummary("m", Outcome.FAILURE, reason="r", refused_commands=1)
    assert "warning      the mode guard refused 1 command the tree sent" in lenient.lines()


def test_a_drive_dropped_while_the_tree_is_stopped_is_counted(
    run_mission: RunMission, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A terminate's drive at the run's end, not written: it was a warning in the log alone;
    the summary counts it, and ``--strict`` fails a successful run that had one (the
    monitor's reload stops a tree, and the run may then succeed)."""
    (tmp_path / "blind.py").write_text(BLIND)
    mission = "plugins: [./blind.py]\ntree:\n  sequence:\n    - mode: safe\n    - sticky\n"
    with caplog.at_level(logging.WARNING):
        run = run_mission(mission, permissions=Permissions(plugin_files=True), timeout=1.0)
    summary = run.summary
    assert summary.outcome is Outcome.TIMEOUT and summary.dropped_in_stop == 1
    assert summary.first_dropped.startswith("t=1.005 sticky (Sticky.terminate at ")
    assert summary.first_dropped.endswith(") queued Drive (137) 89 01 2c 80 00")
    assert any("while the tree was being stopped: not written" in r.getMessage()
               for r in caplog.records)  # fmt: skip
    assert (
        "commands     68 written, 0 refused by the mode guard, 1 dropped while the tree was stopped"
    ) in summary.lines()
    summary.outcome, summary.strict = Outcome.SUCCESS, True
    assert summary.exit_code == ExitCode.STRICT
    assert summary.strict_findings() == [
        f"1 command dropped while the tree was stopped (the first: {summary.first_dropped})"
    ]


#: compiles with one warning: a drive in Full mode with no cliff sensor read while it runs
FULL_WITH_NO_CLIFF_CHECK = """\
tree:
  sequence:
    - mode: full
    - drive: {velocity: 100 mm/s, duration: 1s}
"""


def test_strict_does_not_start_a_mission_validate_strict_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``validate --strict`` failed the mission, exit 7, and ``run --strict`` started it and
    judged only the run: exit 0, so a CI that ran its missions strictly passed what its
    validation step failed. Now it is not started, exit 7, with validate's verdict on stderr
    after the warning; without ``--strict`` it runs as before, the warning printed."""
    path = write_mission(tmp_path, FULL_WITH_NO_CLIFF_CHECK, "w1.yaml")
    assert main(["validate", "--strict", str(path)]) == ExitCode.STRICT
    verdict = f"{path}: failed --strict (1 warning)"
    assert f"{verdict}\n" in capsys.readouterr().out
    run = ["run", str(path), "--fast", "--display", "none"]
    assert main([*run, "--strict"]) == ExitCode.STRICT
    out, err = capsys.readouterr()
    assert out == ""  # no summary: nothing was opened or sent
    warning = f"{path}:4:7: warning: drive can turn the wheels in Full mode"
    assert err.startswith(warning)
    assert err.endswith(f"roomba-bt: {verdict}; not started\n")
    assert main(run) == ExitCode.OK
    out, err = capsys.readouterr()
    assert "outcome      SUCCESS" in out and err.startswith(warning)
