"""Whatever a plugin's code raises, in any method, is its behaviour's error (exit 4, the
summary, the behaviour, the method and its file:line), and a real Ctrl-C while it runs stays
the operator's (exit 130). A safety audit (session 29) found, with the robot stopped in
every case, the user told otherwise: ``sys.exit(0)`` in ``setup``, ``start`` or ``terminate``
(or ``shutdown``, after a failed mission) exited 0 with no summary, ``sys.exit(3)`` read as
a lost connection, a ``raise KeyboardInterrupt`` as ``INTERRUPTED (Ctrl-C)`` though nobody
pressed it, and a ``BaseException`` of its own (or ``GeneratorExit``) was Python's traceback
and exit 1."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest

from roomba_bt.behaviours.actions import Drive, Mode
from roomba_bt.cli import main
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import ExitCode, Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import Raises

Capsys = pytest.CaptureFixture[str]

#: an action that drives with the motors on, and misbehaves in the method ``where`` names
#: (``init``: its ``__init__``) as ``how`` says; ``ctrl_c`` is the operator's signal itself
PLUGIN = '''\
import signal
import sys

from py_trees.common import Status

from roomba_bt.behaviours import Action, Param, declare, enum
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


class Own(BaseException):
    """A BaseException of the plugin's own."""


def misbehave(how):
    if how == "exit0":
        sys.exit(0)  # line 17
    if how == "exit3":
        sys.exit(3)  # line 19
    if how == "kbint":
        raise KeyboardInterrupt  # line 21
    if how == "own":
        raise Own("the plugin's own")  # line 23
    if how == "genexit":
        raise GeneratorExit  # line 25
    if how == "ctrl_c":
        signal.raise_signal(signal.SIGINT)


@declare(
    "evil",
    kind="action",
    params=(
        Param("how", enum("exit0", "exit3", "kbint", "own", "genexit", "ctrl_c")),
        Param("where", enum("init", "setup", "start", "update", "terminate", "shutdown")),
    ),
    sends=opcodes("drive", "motors"),
)
class Evil(Action):
    """Spins in place with the brushes and vacuum on; misbehaves once, where it is told."""

    def __init__(self, name, params=None):
        super().__init__(name, params)
        self._where = self.params["where"]
        self.at("init")

    def at(self, where):
        if self._where == where:
            self._where = None
            misbehave(self.params["how"])

    def setup(self, **kwargs):
        super().setup(**kwargs)
        self.at("setup")

    def start(self):
        self.send(commands.motors(7))
        self.at("start")

    def update(self):
        self.send(commands.drive(200, 1))
        if self.snapshot.tick > 20:
            self.at("update")
        return Status.RUNNING

    def terminate(self, new_status):
        super().terminate(new_status)
        self.at("terminate")

    def shutdown(self):
        self.at("shutdown")
'''

#: the audit's mission: the plugin under a time limit, which fails the mission (exit 1) if
#: nothing else ends it; its terminate runs inside the tick the limit fires in
MISSION = """\
plugins: [./evil.py]
parameters:
  how: {type: str, default: exit0}
  where: {type: str, default: update}
tree:
  sequence:
    name: outer
    children:
      - mode: safe
      - timeout:
          after: 1s
          do:
            evil: {how: "${how}", where: "${where}"}
      - mode: passive
"""

#: what each ``how`` is said as, and the plugin's line it raised at
SAID = {
    "exit0": ("SystemExit (it called sys.exit(0))", 17),
    "exit3": ("SystemExit (it called sys.exit(3))", 19),
    "kbint": ("KeyboardInterrupt (raised by its own code: no Ctrl-C or signal came)", 21),
    "own": ("Own: the plugin's own", 23),
    "genexit": ("GeneratorExit", 25),
}
PATH = "outer / timeout / evil(how={how}, where={where})"


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    (tmp_path / "evil.py").write_text(PLUGIN)
    path = tmp_path / "evil.yaml"
    path.write_text(MISSION)
    return path


def _run(mission: Path, how: str, where: str, *extra: str) -> list[str]:
    return ["run", str(mission), "--fast", "--display", "none", "--allow-plugin-files",
            "-p", f"how={how}", "-p", f"where={where}", *extra]  # fmt: skip


@pytest.mark.parametrize("how", list(SAID))
@pytest.mark.parametrize("where", ["setup", "start", "update", "terminate"])
def test_what_a_plugin_raises_in_a_method_is_its_error_with_the_summary(
    mission: Path, capsys: Capsys, how: str, where: str
) -> None:
    assert main(_run(mission, how, where)) == ExitCode.BEHAVIOUR_ERROR
    out, err = capsys.readouterr()
    said, line = SAID[how]
    path = PATH.format(how=how, where=where)
    assert f"behaviour {path} raised {said} in its {where}() " in err, err
    assert f"(at {mission.parent / 'evil.py'}:{line})" in err, err
    assert "outcome      ERROR (behaviour " in out
    assert "safe stop    sent" in out and "final mode   Passive" in out
    assert "Traceback" not in out + err
    assert "INTERRUPTED" not in out


@pytest.mark.parametrize("how", list(SAID))
@pytest.mark.parametrize("where", ["shutdown", "terminate"])
def test_after_the_safe_stop_and_at_the_run_s_end_it_is_the_run_s_error_too(
    mission: Path, capsys: Capsys, how: str, where: str
) -> None:
    """``shutdown()`` (after the safe stop), and ``terminate()`` in the tree's stop at a run's
    ``--timeout``: the run had ended (the mission's limit failed it: exit 1; the run's
    --timeout), and the plugin's exit is its error, exit 4, the ending said with it. From
    ``shutdown`` a failed mission exited 0 (``sys.exit(0)``), 130 or 1 with a traceback."""
    extra = ["--timeout", "0.5s"] if where == "terminate" else []
    assert main(_run(mission, how, where, *extra)) == ExitCode.BEHAVIOUR_ERROR
    out, err = capsys.readouterr()
    said, line = SAID[how]
    path = PATH.format(how=how, where=where)
    at = f"(at {mission.parent / 'evil.py'}:{line})"
    assert f"{where}() of behaviour {path} raised {said} {at}" in err, err
    ended = "timeout: --timeout 0.5 s" if where == "terminate" else "failure: timeout: the tree's"
    assert f"(the run had ended: {ended}" in out
    assert "safe stop    sent" in out
    assert "Traceback" not in out + err


def test_the_traceback_under_verbose(mission: Path, capsys: Capsys) -> None:
    assert main(["-v", *_run(mission, "own", "update")]) == ExitCode.BEHAVIOUR_ERROR
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err
    assert "Own: the plugin's own" in err


@pytest.mark.parametrize("how", list(SAID))
def test_in_its_init_it_is_a_mission_error_at_the_line_that_uses_it(
    mission: Path, capsys: Capsys, how: str
) -> None:
    """Building the tree: it exited 0 with no word (``sys.exit(0)``), 130 or 1 with a
    traceback; now the mission's error at the leaf's line, exit 2, nothing sent."""
    assert main(_run(mission, how, "init")) == ExitCode.INVALID
    out, err = capsys.readouterr()
    said, line = SAID[how]
    assert f"evil.yaml:13:13: evil: building it raised {said} (at " in err, err
    assert f"evil.py:{line})" in err
    assert "Traceback" not in out + err


@pytest.mark.parametrize("where", ["setup", "start", "update", "terminate", "shutdown"])
def test_a_real_ctrl_c_while_the_plugin_runs_is_still_the_operator_s(
    mission: Path, capsys: Capsys, where: str
) -> None:
    """The SIGINT itself, delivered while the plugin's method runs: the interrupt the
    runtime's handler raises, not the plugin's own: 130, the robot stopped first."""
    assert main(_run(mission, "ctrl_c", where)) == ExitCode.INTERRUPTED
    out = capsys.readouterr().out
    assert "outcome      INTERRUPTED (Ctrl-C" in out
    assert "safe stop    sent" in out
    if where == "setup":  # a setup() that blocked was named by --wall-limit, not by Ctrl-C
        assert "(SIGINT) while setting up, in behaviour outer / timeout / evil" in out, out
        assert f"(at {mission.parent / 'evil.py'}:27))" in out, out


def test_a_real_ctrl_c_while_the_tree_is_built_is_still_an_interrupt(
    mission: Path, capsys: Capsys
) -> None:
    """Said with the behaviour it cut short, the mission's line and the plugin's: a plugin
    whose ``__init__`` blocked (a calibration read from the network) got a bare ``roomba-bt:
    interrupted``, naming nothing to look at."""
    assert main(_run(mission, "ctrl_c", "init")) == ExitCode.INTERRUPTED
    err = capsys.readouterr().err
    assert (
        f"roomba-bt: interrupted while building evil ({mission}:13) (at "
        f"{mission.parent / 'evil.py'}:27)\n" in err
    ), err


def test_a_real_ctrl_c_while_a_plugin_imports_names_it(mission: Path, capsys: Capsys) -> None:
    """A plugin whose import blocks holds ``validate`` until Ctrl-C: the interrupt says which
    plugin, and where its code was."""
    plugin = mission.parent / "evil.py"
    plugin.write_text(PLUGIN.replace("\n\n@declare(", "\n\nmisbehave('ctrl_c')\n\n\n@declare(", 1))
    assert main(["validate", str(mission), "--allow-plugin-files"]) == ExitCode.INTERRUPTED
    err = capsys.readouterr().err
    assert f"roomba-bt: interrupted while importing plugin {plugin} (at {plugin}:27)\n" in err, err


def _tree(exc: BaseException) -> TreeMission:
    """Safe, a plain behaviour whose update raises ``exc`` on its tenth tick, a drive."""
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}), Raises(exc, "update", "rude"),
        Drive("d", {"velocity": "200 mm/s"}),
    ])  # fmt: skip
    return TreeMission(root, "rude")


@pytest.mark.parametrize("ticks", [False, True], ids=["run", "ticks"])
def test_from_python_a_behaviour_s_keyboard_interrupt_is_its_error_not_an_interrupt(
    ticks: bool,
) -> None:
    """``RunStack.run()`` raised ``Interrupted`` for it, as for the operator's Ctrl-C, and a
    program that ran missions in a row stopped; in a ``ticks()`` loop (the run in a worker
    thread, which no signal reaches) likewise. Both now return the run's ERROR."""
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    with RunStack(_tree(KeyboardInterrupt()), link, profile=CREATE2, timeout_s=5.0) as stack:
        if ticks:
            for _ in stack.ticks():
                continue
            summary = stack.summary
        else:
            summary = stack.run()
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4, summary.reason
    assert summary.reason.startswith(
        "behaviour root / rude raised KeyboardInterrupt (raised by its own code: no Ctrl-C or "
        "signal came) in its update() (at "
    ), summary.reason
    assert summary.safe_stop.startswith("sent ")


def test_an_exception_raised_into_the_run_from_outside_goes_on_after_the_safe_stop() -> None:
    """An evaluation's wall-clock limit (``WallLimitReached``, a ``RunAborted``) lands in
    whatever the run's thread runs, a behaviour too: it is not that behaviour's error, and
    goes on to the code that raised it, the robot stopped."""
    from roomba_bt.evaluate.cluster import WallLimitReached

    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(_tree(WallLimitReached()), link, profile=CREATE2, timeout_s=5.0)
    with stack, pytest.raises(WallLimitReached):
        stack.run()
    assert stack.summary.safe_stop.startswith("sent ")
