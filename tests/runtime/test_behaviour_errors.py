"""A behaviour's exception says where: the behaviour's path in the tree and the file:line in
its module (a plugin file), the traceback under ``-v``, and exit code 4 (not 1, a mission
that failed), after the safe stop."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import py_trees
import pytest

from roomba_bt.behaviours.actions import Drive, Mode, SetKey
from roomba_bt.behaviours.conditions import OdometrySince
from roomba_bt.cli import main
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import ExitCode, Outcome, RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import Raises, write_mission

PLUGIN = '''
from roomba_bt.behaviours import Condition, declare


@declare("fragile", kind="condition", reads=(27,))
class Fragile(Condition):
    """Divides by the wall signal: a bug on a quiet frame."""

    def check(self, snapshot):
        return 1000 // snapshot.frame[27] > 3
'''

MISSION = """\
plugins: [./fragile.py]
tree:
  sequence:
    name: outer
    children:
      - mode: safe
      - wait: 1s
      - fragile
"""


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path, MISSION, "m.yaml", {"fragile.py": PLUGIN})


def run_tree(
    mission: TreeMission | py_trees.behaviour.Behaviour, timeout_s: float, **stack: Any
) -> RunSummary:
    """A tree built in Python (or its TreeMission) run on the simulator's empty room."""
    if not isinstance(mission, TreeMission):
        mission = TreeMission(mission, mission.name)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    runner = RunStack(mission, link, profile=CREATE2, timeout_s=timeout_s, **stack)
    try:
        return runner.run()
    finally:
        runner.close()


def _run(mission: Path, *extra: str) -> list[str]:
    return [*extra, "run", str(mission), "--fast", "--display", "none", "--timeout", "10s",
            "--allow-plugin-files"]  # fmt: skip


def test_names_the_behaviour_and_the_plugin_line(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR == 4
    out, err = capsys.readouterr()
    assert "behaviour outer / fragile raised ZeroDivisionError" in err
    assert f"(at {mission.parent / 'fragile.py'}:10)" in err
    assert "Traceback" not in out + err
    assert "run with -v for the traceback" in err
    assert "safe stop    sent" in out


@pytest.mark.parametrize("after", [False, True], ids=["before the command", "after it"])
def test_the_traceback_under_verbose(
    mission: Path, after: bool, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-v`` where the hint puts it, after the command, too: it was an unrecognized
    argument there (exit 2)."""
    assert main([*_run(mission), "-v"] if after else _run(mission, "-v")) == 4
    _, err = capsys.readouterr()
    assert "Traceback (most recent call last)" in err
    assert "return 1000 // snapshot.frame[27] > 3" in err


FORGETFUL = '''
from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands


@declare("forgetful", kind="action", sends=(137,))
class Forgetful(Action):
    """Drives, and forgets to say it is running."""

    def update(self):
        self.send(commands.drive(100, 32767))
'''

RAW = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("raw_bytes", kind="action", sends=(137,))
class RawBytes(Action):
    """Sends the bytes of a drive itself."""

    def update(self):
        self.send(bytes([137, 0, 100, 128, 0]))
        return Status.RUNNING
'''


UNDECLARED = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands


@declare("sneaky", kind="action", sends=(139,))
class Sneaky(Action):
    """Declares the LEDs, and drives."""

    def update(self):
        self.send(commands.drive(100, 32767))
        return Status.RUNNING
'''


UNREAD = '''
from roomba_bt.behaviours import Condition, declare


@declare("near", kind="condition", reads=(7,))
class Near(Condition):
    """Reads the wall signal (27) and declares the bumps only."""

    def check(self, snapshot):
        return snapshot.frame[27] > 100
'''


#: the stranger's k_cond_drives: a condition that calls send() anyway
COND_SENDS = '''
from roomba_bt.behaviours import Condition, declare
from roomba_bt.oi import commands


@declare("k_cond_drives", kind="condition", reads=(7,))
class KCondDrives(Condition):
    """A condition that drives."""

    def check(self, snapshot):
        self.send(commands.drive_straight(200))
        return True
'''

#: the stranger's halt_liar (session 36): says it only halts, drives; unwarned in Full
HALT_LIAR = UNDECLARED.replace("sneaky", "halt_liar").replace("class Sneaky", "class HaltLiar")
HALT_LIAR = HALT_LIAR.replace("sends=(139,))", "sends=(137,), halts_only=True)")

#: the stranger's mode_liar: says it leads to Safe, sends Full; the drive after it ran in Full
MODE_LIAR = UNDECLARED.replace("sneaky", "mode_liar").replace("class Sneaky", "class ModeLiar")
MODE_LIAR = MODE_LIAR.replace(
    '@declare("mode_liar", kind="action", sends=(139,))',
    "from roomba_bt.oi.modes import OIMode\n"
    '@declare("mode_liar", kind="action", sends=(131, 132), leads_to=OIMode.SAFE)',
).replace("commands.drive(100, 32767)", "commands.full()")

#: passes through Full by its declaration, and succeeds there: the drive after it ran in Full
STAYS_FULL = MODE_LIAR.replace("mode_liar", "stays_full").replace("ModeLiar", "StaysFull")
STAYS_FULL = STAYS_FULL.replace(
    "leads_to=OIMode.SAFE)", "leads_to=OIMode.SAFE, passes_through=OIMode.FULL)"
).replace("return Status.RUNNING", "return Status.SUCCESS")

#: the stranger's boom_check: a packet that does not exist
NO_SUCH_PACKET = UNREAD.replace("near", "far").replace("frame[27]", "frame[99]")


RET_INVALID = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("ret_invalid", kind="action")
class RetInvalid(Action):
    """Returns INVALID."""

    def update(self):
        return Status.INVALID
'''


def _says(returns: str) -> str:
    return f'''
from py_trees.common import Status

from roomba_bt.behaviours import Condition, declare


@declare("says", kind="condition")
class Says(Condition):
    """Forgets what a check returns."""

    def check(self, snapshot):
        return {returns}
'''


@pytest.mark.parametrize(
    ("word", "source", "said", "where"),
    [
        ("forgetful", FORGETFUL,
         "raised InvalidStatus: Forgetful.update() returned None, not a Status",
         "update() defined at {plugin}:10, which ends without a return"),
        ("ret_invalid", RET_INVALID,  # a sequence began again: the run drove to its timeout
         "raised InvalidStatus: RetInvalid.update() returned Status.INVALID, which py_trees",
         "at {plugin}:12"),  # its return, not its def
        ("says", _says("None"),  # silently FAILURE
         "raised InvalidCheck: Says.check() returned None, not a bool", "at {plugin}:12"),
        ("says", _says("'no'"),  # SUCCESS
         "raised InvalidCheck: Says.check() returned 'no', not a bool", "at {plugin}:12"),
        ("says", _says("Status.FAILURE"),  # SUCCESS
         "raised InvalidCheck: Says.check() returned", "at {plugin}:12"),
        ("raw_bytes", RAW,
         "raised TypeError: send() takes a Command from roomba_bt.commands (from roomba_bt "
         "import commands: commands.drive(200, 32767), commands.safe())", "at {plugin}:12"),
        ("sneaky", UNDECLARED,
         "raised UndeclaredCommand: sneaky sent drive (137), which its declaration does not "
         "list: add 137 to @declare(sends=...) (it lists leds (139))", "at {plugin}:13"),
        ("halt_liar", HALT_LIAR,  # believed: it drove 0.63 m in Full, unwarned
         "raised UnkeptDeclaration: halt_liar sent drive (137) 89 00 64 7f ff, but its "
         "@declare (at {plugin}:8) says halts_only=True", "at {plugin}:13"),
        ("mode_liar", MODE_LIAR,  # believed: the drive after it ran in Full, exit 0
         "raised UnkeptDeclaration: mode_liar sent full (132) 84, but its @declare (at "
         "{plugin}:9) says leads_to=Safe, and full leads to Full", "at {plugin}:14"),
        ("stays_full", STAYS_FULL,  # refused as it succeeds, at the return that said so
         "raised UnkeptDeclaration: stays_full sent full (132) 84, but its @declare (at "
         "{plugin}:9) says leads_to=Safe, passes_through=Full, and it returned SUCCESS with no "
         "mode command after this one: it ended in Full, not Safe", "at {plugin}:15"),
        ("near", UNREAD,  # the KeyError did not say where to declare it
         "raised MissingPacket: 'packet 27 (wall_signal) is not in this frame",
         "at {plugin}:10"),
        ("k_cond_drives", COND_SENDS,  # it said: add 137 to @declare(sends=...), refused there
         "raised UndeclaredCommand: k_cond_drives sent drive (137), but it is a condition, "
         "which only reads: a behaviour that sends commands is an action (derive KCondDrives "
         "from roomba_bt.behaviours.Action, declare kind='action', sends=opcodes('drive'), "
         "and return a Status from update())", "at {plugin}:11"),
        ("far", NO_SUCH_PACKET,  # it said: add 99 to @declare(reads=...), refused there
         "raised MissingPacket: \"packet 99 does not exist: the Open Interface's sensor "
         "packets are 7-58 (roomba_bt.oi.packets; by name: packet_ids('wall_signal', ...)); "
         "this frame carries", "at {plugin}:10"),
    ],
)  # fmt: skip
def test_a_plugin_that_breaks_the_contract_ends_the_run_as_its_error(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    word: str,
    source: str,
    said: str,
    where: str,
) -> None:
    """``update`` returning None (a forgotten ``return``) was py_trees' "invalid status" on
    stdout every tick, with the robot driving on to the timeout; raw bytes passed to
    ``send`` were an AttributeError deep in the outbox; a Drive its declaration did not list
    escaped the compiler's mode check and Full-mode warning, which read the declaration.
    Each now ends the run at once as the plugin's error, with the safe stop, naming where:
    a wrong value returned, at its ``return`` when the source shows which (it named the
    ``def`` line, session 25)."""
    (tmp_path / "plugin.py").write_text(source)
    mission = tmp_path / "m.yaml"
    mission.write_text(f"plugins: [./plugin.py]\ntree:\n  sequence: [{{mode: safe}}, {word}]\n")
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR
    out, err = capsys.readouterr()
    assert f"behaviour sequence / {word} {said.format(plugin=tmp_path / 'plugin.py')}" in err
    assert f"({where.format(plugin=tmp_path / 'plugin.py')})" in err
    if word == "near":
        assert "; add 27 to @declare(reads=...) of 'near' (it lists 7)" in err
    if word in ("k_cond_drives", "far"):  # no advice the declaration would refuse
        assert "add 99" not in err and "@declare(sends" not in err
    assert "ticks        1 " in out  # ended on the tick it happened
    assert "safe stop    sent drive, motors" in out
    assert "invalid status" not in out + err


def test_a_success_refused_in_a_mode_passed_through_is_drawn_as_the_run_decided(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """The tree drawn after the run showed ``stays_full [✓]`` (py_trees' stop had set the
    SUCCESS it returned) above the refusal of that very SUCCESS: it shows the failure the
    run decided, with the reason; the status log says FAILURE too."""
    (tmp_path / "plugin.py").write_text(STAYS_FULL)
    mission = tmp_path / "m.yaml"
    mission.write_text("plugins: [./plugin.py]\ntree:\n  sequence: [{mode: safe}, stays_full]\n")
    argv = _run(mission)
    argv[argv.index("--display") + 1] = "tree"
    assert main(argv) == ExitCode.BEHAVIOUR_ERROR
    out = capsys.readouterr().out
    assert (
        "--> stays_full [✕] -- raised UnkeptDeclaration (its SUCCESS refused: it ended in Full, "
        "not Safe)\n" in out
    ), out
    assert "stays_full [✓]" not in out
    argv[argv.index("--display") + 1] = "log"
    with caplog.at_level("INFO", logger="roomba_bt.run"):
        assert main(argv) == ExitCode.BEHAVIOUR_ERROR
    said = [r.getMessage() for r in caplog.records if r.getMessage().startswith("stays_full")]
    assert said == ["stays_full -> FAILURE"], said


#: an honest action that passes through Full: Full, a drive there, then Safe
DASH = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import opcodes


@declare("dash", kind="action", sends=opcodes("full", "drive", "safe"), reads=(9, 10, 11, 12),
         passes_through=OIMode.FULL, leads_to=OIMode.SAFE)
class Dash(Action):
    """Goes to Full, drives three ticks there, and goes back to Safe."""

    def start(self):
        self.send(commands.full())
        self.in_full = 0

    def update(self):
        if self.snapshot.mode is OIMode.FULL:
            self.in_full += 1
        if self.in_full < 3:
            self.send(commands.drive(300, 32767))
            return Status.RUNNING
        self.send(commands.halt())
        self.send(commands.safe())
        self.feedback_message = f"drove {self.in_full} ticks in Full"
        return Status.SUCCESS
'''


def _validated_dash(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], plugin: str, before: str = ""
) -> Path:
    """A mission of ``before``, the plugin's ``dash`` and a drive after it, which validates
    under ``--strict``."""
    (tmp_path / "dash.py").write_text(plugin)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        f"plugins: [./dash.py]\ntree:\n  sequence:\n{before}    - dash\n"
        "    - drive: {velocity: 100 mm/s, duration: 0.5s}\n    - mode: passive\n"
    )
    assert main(["validate", str(mission), "--allow-plugin-files", "--strict"]) == 0
    capsys.readouterr()
    return mission


def test_a_plugin_that_passes_through_full_as_declared_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An action that sends Full itself, drives, then sends Safe, declaring the end mode it
    could (``leads_to=Safe``), was refused at its Full (session 37): declared with
    ``passes_through=OIMode.FULL``, it validates, runs in Full and hands the drive after it
    Safe; the mode guard refuses none of its commands."""
    mission = _validated_dash(tmp_path, capsys, DASH, "    - mode: safe\n")
    assert main([*_run(mission), "--strict", "--display", "tree"]) == 0
    out = capsys.readouterr().out
    assert "--> dash [✓] -- drove 3 ticks in Full" in out, out
    assert "outcome      SUCCESS" in out
    assert " 0 refused by the mode guard" in out
    # the drive after it moves: its first Drive, queued in the tick dash sent halt and Safe,
    # is written after the Safe (written before it, the Safe stopped it: 0.01 m in all)
    assert "distance     0.07 m" in out, out


#: DASH that says its Full comes first, reached in Passive
DASH_FIRST = DASH.replace("leads_to=OIMode.SAFE)", "leads_to=OIMode.SAFE, mode_first=True)")
#: DASH_FIRST whose start drives before its Full: the lie is caught, not run
DASH_LIAR = DASH_FIRST.replace(
    "        self.send(commands.full())\n",
    "        self.send(commands.drive(300, 32767))\n        self.send(commands.full())\n",
)


@pytest.mark.parametrize(("plugin", "exit_code"), [(DASH_FIRST, 0), (DASH_LIAR, 4)])
def test_a_mode_first_plugin_runs_from_passive_and_a_liar_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], plugin: str, exit_code: int
) -> None:
    """Reached in Passive, ``dash`` was refused by validate for its drive, though its own
    Full came first: ``mode_first=True`` says so, it validates and runs with no mode guard
    refusal. One that said so and drove first ends the run at that send as its error,
    naming the leaf, its declaration and its line, before the drive is queued."""
    mission = _validated_dash(tmp_path, capsys, plugin)
    assert main([*_run(mission), "--strict"]) == exit_code
    out, err = capsys.readouterr()
    if exit_code == 0:
        assert " 0 refused by the mode guard" in out and "distance     0.07 m" in out, out
        return
    said = (
        f"behaviour sequence / dash raised UnkeptDeclaration: dash sent drive (137) 89 01 2c "
        f"7f ff, but its @declare (at {tmp_path / 'dash.py'}:10) says mode_first=True"
    )
    assert said in err, err
    assert f"in its start() (at {tmp_path / 'dash.py'}:16)" in err, err
    assert "commands     0 written" in out, out


#: a mode_first plugin whose own Safe is a parameter's choice (sends_by): with own_mode: false
#: it sends the drive alone, and is any leaf
HOP = '''
from py_trees.common import Status

from roomba_bt.behaviours import BOOL, Action, Param, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


def _sends(params):
    return opcodes("safe", "drive") if params.get("own_mode", True) else opcodes("drive")


@declare("hop", kind="action", sends=opcodes("safe", "drive"), reads=(19,), mode_first=True,
         sends_by=_sends, params=[Param("own_mode", BOOL, default=True)])
class Hop(Action):
    """Drives five ticks, sending its own Safe first where own_mode says so."""

    def start(self):
        if self.value("own_mode"):
            self.send(commands.safe())
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks < 5:
            self.send(commands.drive(100, 32767))
            return Status.RUNNING
        self.send(commands.halt())
        return Status.SUCCESS
'''


@pytest.mark.parametrize(
    ("hop", "validated"),
    [("hop", 0), ("hop: {own_mode: false}", 2), ("{mode: safe}, hop: {own_mode: false}", 0)],
    ids=["its own Safe", "no Safe, in Passive", "no Safe, after mode: safe"],
)
def test_a_mode_first_plugin_whose_parameters_send_no_mode_command_runs_as_validated(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], hop: str, validated: int
) -> None:
    """``mode_first=True`` with ``sends_by``: validate judged ``hop: {own_mode: false}``
    (no Safe of its own) as any leaf, and refused it in Passive; after ``mode: safe`` it
    validated, and the run then ended at its first drive, exit 4 (``UnkeptDeclaration``: its
    mode command did not come first). One rule for both: what validates runs, with no mode
    guard refusal."""
    (tmp_path / "hop.py").write_text(HOP)
    mission = tmp_path / "m.yaml"
    mission.write_text(f"plugins: [./hop.py]\ntree:\n  sequence: [{hop}, {{mode: passive}}]\n")
    assert main(["validate", str(mission), "--allow-plugin-files", "--strict"]) == validated
    out = capsys.readouterr().out
    if validated:
        assert "hop sends Drive (137), accepted only in Safe or Full mode, but it can be " in out
        return
    assert main([*_run(mission), "--strict"]) == 0
    out, err = capsys.readouterr()
    assert "outcome      SUCCESS" in out and " 0 refused by the mode guard" in out, out + err


OS_ERRORS = [
    OSError("cannot open the log device"),
    FileNotFoundError(2, "No such file or directory", "/tmp/calibration.json"),
    TimeoutError("mqtt publish timed out"),
    ConnectionRefusedError(111, "Connection refused"),
]


@pytest.mark.parametrize("where", ["setup", "initialise", "update", "terminate"])
@pytest.mark.parametrize("exc", OS_ERRORS, ids=lambda e: type(e).__name__)
def test_an_oserror_a_behaviour_raises_is_its_error_not_a_lost_link(
    exc: OSError, where: str
) -> None:
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        py_trees.composites.Parallel(
            "par", policy=py_trees.common.ParallelPolicy.SuccessOnOne(),
            children=[Drive("d", {"velocity": "200 mm/s"}), Raises(exc, where)],
        ),
    ])  # fmt: skip
    summary = run_tree(TreeMission(root, "os"), timeout_s=5.0)
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4, summary.reason
    said = f"behaviour root / par / telemetry raised {type(exc).__name__}"
    assert summary.reason.startswith(said)
    assert f"(at {inspect.getfile(Raises)}:" in summary.reason  # the file of its code
    assert summary.traceback
    assert summary.safe_stop.startswith("sent ")


class _Forgets(py_trees.behaviour.Behaviour):
    """A plain py_trees behaviour whose update forgets its ``return`` after a few ticks."""

    def __init__(self, returns: object) -> None:
        super().__init__("forgetful")
        self.returns, self.ticks = returns, 0

    def update(self) -> py_trees.common.Status:
        self.ticks += 1
        if self.ticks < 5:
            return py_trees.common.Status.RUNNING
        return self.returns  # type: ignore[return-value]


@pytest.mark.parametrize("returns", [None, "SUCCESS"])
def test_a_plain_behaviour_returning_no_status_ends_a_hand_built_run_as_an_error(
    returns: object,
) -> None:
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}), _Forgets(returns), Drive("d", {"velocity": "200 mm/s"}),
    ])  # fmt: skip
    mission = TreeMission(root, "forgot")
    summary = run_tree(mission, timeout_s=3.0)
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4, summary.reason
    assert summary.reason.startswith(
        f"behaviour root / forgetful raised InvalidStatus: _Forgets.update() returned {returns!r}"
        if returns is None else "behaviour root / forgetful raised InvalidStatus"
    )  # fmt: skip
    assert summary.safe_stop.startswith("sent ")
    # the same tree run again is checked once, not wrapped twice
    update = root.children[1].update
    mission.setup(None)
    assert root.children[1].update is update


class _ReadsTheWall(py_trees.behaviour.Behaviour):
    """A plain behaviour reading a packet no leaf declares (27, the wall signal)."""

    def setup(self, **kwargs: object) -> None:
        self.robot = kwargs["robot"]

    def update(self) -> py_trees.common.Status:
        self.robot.snapshot.frame[27]  # type: ignore[attr-defined]
        return py_trees.common.Status.SUCCESS


def test_a_plain_behaviour_reading_an_undeclared_packet_is_told_how_to_stream_it() -> None:
    from roomba_bt.runtime.loop import stream_request

    mission = TreeMission(_ReadsTheWall("wall"), "wall")
    summary = run_tree(mission, timeout_s=2.0)
    assert summary.outcome is Outcome.ERROR
    assert "packets=stream_request({27, *mission.packets}, baud)" in summary.reason
    # the way out it names works
    packets = stream_request({27, *mission.packets}, 115200)
    assert run_tree(mission, timeout_s=2.0, packets=packets).outcome is Outcome.SUCCESS


@pytest.mark.parametrize("written", ["other", None])
def test_a_blackboard_value_nothing_wrote_is_an_error_not_a_drive_without_a_distance(
    written: str | None,
) -> None:
    """A tree built in Python has no proof that a key is written before it is read: the
    unwritten ``@leg`` was read as None, and the drive went on without a distance until the
    robot met the dock (0.79 m). Now the run ends at once, an ERROR naming the key."""
    before = [SetKey("other", {"key": written, "value": 120.0})] if written else []
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}), *before,
        Drive("forward", {"velocity": "200 mm/s", "distance": "@leg"}),
    ])  # fmt: skip
    py_trees.blackboard.Blackboard.storage.pop("/mission/leg", None)
    summary = run_tree(TreeMission(root, "unwritten"), timeout_s=10.0)
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4, summary.reason
    assert "raised UnwrittenKey: distance is @leg, but nothing has written blackboard key " \
        "'leg' before 'forward' started" in summary.reason  # fmt: skip
    assert summary.distance_mm < 1.0


def test_a_blackboard_value_written_first_is_read_from_python() -> None:
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}), SetKey("leg", {"key": "leg", "value": 120.0}),
        Drive("forward", {"velocity": "200 mm/s", "distance": "@leg"}),
    ])  # fmt: skip
    summary = run_tree(TreeMission(root, "written"), timeout_s=10.0)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert 110.0 < summary.distance_mm < 140.0


def test_odometry_since_a_mark_nothing_made_is_an_error_not_a_count_from_the_start() -> None:
    """``since: start`` unmarked counted from the run's start: the condition held at once for
    a robot that had already driven, from a tree built in Python."""
    py_trees.blackboard.Blackboard.storage.pop("/mission/start", None)
    root = py_trees.composites.Sequence("root", memory=True, children=[
        Mode("safe", {"to": "safe"}),
        Drive("out", {"velocity": "200 mm/s", "distance": "20 cm"}),
        py_trees.composites.Selector("until", memory=False, children=[
            OdometrySince("far", {"since": "start", "distance": "10 cm"}),
            Drive("on", {"velocity": "200 mm/s"}),
        ]),
    ])  # fmt: skip
    summary = run_tree(TreeMission(root, "unmarked"), timeout_s=10.0)
    assert summary.outcome is Outcome.ERROR and summary.exit_code == 4, summary.reason
    assert "raised UnwrittenKey: since is 'start', but nothing has marked" in summary.reason


QUITTER = '''
import sys

from roomba_bt.behaviours import Condition, declare


@declare("quitter", kind="condition", reads=(27,))
class Quitter(Condition):
    """Gives up the way a script does: sys.exit()."""

    def check(self, snapshot):
        sys.exit(0)
'''


def test_a_behaviour_calling_sys_exit_is_a_behaviour_error_after_the_safe_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A plugin's ``sys.exit(0)`` in a tick: the safe stop was sent, but the SystemExit went
    on through the CLI, which exited 0 with no summary and no word. It is a behaviour's
    error now, as any exception (and as a plugin's ``sys.exit()`` at import is): exit 4."""
    (tmp_path / "quitter.py").write_text(QUITTER)
    mission = tmp_path / "m.yaml"
    mission.write_text(MISSION.replace("fragile", "quitter"))
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR
    out, err = capsys.readouterr()
    assert "behaviour outer / quitter raised SystemExit (it called sys.exit(0))" in err
    assert f"(at {tmp_path / 'quitter.py'}:12)" in err
    assert "safe stop    sent" in out
    assert "Traceback" not in out + err
