"""What a new user tripped on, from the command line: each a test.

A py_trees release the tree is not proven against, the help's one line per subcommand,
``validate``'s "ok" on stdout, ``--display none``, ``run --battery``, log lines stamped with
mission time, and matplotlib's INFO lines on a first ``--plot``."""

from __future__ import annotations

import json
import logging
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import build_parser, main, setup_logging
from roomba_bt.runtime.display import MissionClockFormatter, use_mission_clock


def test_an_unsupported_py_trees_is_a_message_and_exit_2_not_a_traceback(
    mission: Path,
) -> None:
    """``UnsupportedPyTrees`` is an ImportError raised while the subcommands import the tree;
    the CLI caught only ModuleNotFoundError, so the user saw a traceback."""
    script = (
        "import sys, py_trees.version\n"
        "py_trees.version.__version__ = '2.7.0'  # as if pip had installed a later release\n"
        "from roomba_bt.cli import main\n"
        f"sys.exit(main(['validate', {str(mission)!r}]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=HANG_S,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith("roomba-bt: py_trees 2.7.0 is installed")
    assert "pip install 'py-trees==2.6.0'" in done.stderr
    assert done.stdout == ""


def test_python_m_roomba_bt_is_the_command(mission: Path, tmp_path: Path) -> None:
    """``python -m roomba_bt`` where the venv's scripts are not on PATH: the same command,
    the same exit codes (0 valid, 2 invalid), named ``roomba-bt`` in its messages."""
    run = [sys.executable, "-m", "roomba_bt"]
    done = subprocess.run(
        [*run, "validate", str(mission)],
        capture_output=True,
        text=True,
        timeout=HANG_S,
        cwd=tmp_path,
    )
    assert (done.returncode, done.stdout.strip()) == (0, f"{mission}: ok"), done.stderr
    bad = tmp_path / "bad.yaml"
    bad.write_text("mission: bad\ntree:\n  drive: {velocity: 200}\n")
    done = subprocess.run(
        [*run, "validate", bad.name], capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path
    )
    assert done.returncode == 2
    # (the mode check's "drive ... can be reached in Passive" at 3:3 comes first: the same
    # pass, since session 25)
    assert "\nbad.yaml:3:21: drive.velocity" in done.stdout, done.stdout
    assert "Traceback" not in done.stdout + done.stderr
    usage = subprocess.run([*run], capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path)
    assert usage.returncode == 2 and usage.stderr.startswith("usage: roomba-bt"), usage.stderr


@pytest.mark.parametrize("module", ["typing", "yaml", "py_trees"])
def test_python_m_roomba_bt_imports_nothing_from_the_current_folder(
    mission: Path, tmp_path: Path, module: str
) -> None:
    """``python -m`` puts the current folder first on ``sys.path``: run inside a downloaded
    mission folder, its ``yaml.py`` (or ``typing.py``, which the package itself imports
    first) ran with no ``--allow-plugin-files``. The package drops that folder before it
    imports anything Python had not loaded at start-up, as ``roomba-bt`` never adds it."""
    ran = tmp_path / "ran"
    (tmp_path / f"{module}.py").write_text(
        f"import pathlib\npathlib.Path({str(ran)!r}).write_text('x')\n"
        f"raise SystemExit('{module}.py from the current folder ran')\n"
    )
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt", "validate", str(mission)],
        capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path,
    )  # fmt: skip
    assert (done.returncode, done.stdout.strip()) == (0, f"{mission}: ok"), done.stderr
    assert not ran.exists()


def test_behaviour_descriptions_survive_python_OO(tmp_path: Path) -> None:
    """``python -OO`` drops docstrings, where the behaviours' descriptions come from: they are
    read from the source then, so ``roomba-bt behaviours`` says the same either way."""
    run = [sys.executable, "-m", "roomba_bt", "behaviours", "--json"]
    plain, optimised = (
        subprocess.run(
            [*run[:1], *flags, *run[1:]],
            capture_output=True,
            text=True,
            timeout=HANG_S,
            cwd=tmp_path,
        )
        for flags in ((), ("-OO",))
    )
    assert plain.returncode == optimised.returncode == 0, optimised.stderr
    described = json.loads(optimised.stdout)
    assert optimised.stdout == plain.stdout
    assert "bumper is pressed" in str(described)


def test_every_subcommand_has_a_one_line_description_in_the_help(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    text = build_parser().format_help()
    listing = text.split("  COMMAND\n", 1)[1].split("\noptions:")[0]
    rows = [line for line in listing.splitlines() if line.strip()]
    commands = [row.split()[0] for row in rows]
    assert {"run", "validate", "show", "sim", "sensors", "eval"} <= set(commands)
    for row in rows:  # "    name   description": no continuation lines, none empty
        assert re.match(r"^    [a-z][a-z-]* +\S", row), f"not one line per subcommand:\n{listing}"


def test_validate_says_ok_on_stdout(mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(mission)]) == 0
    out, err = capsys.readouterr()
    assert out == f"{mission}: ok\n" and err == ""


def test_display_none_prints_nothing_but_the_summary(
    mission: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Run as a user would (a new process: logging set up by the CLI itself)."""
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "run", str(mission), "--fast", "--display",
         "none"],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no INFO line about the connection
    lines = done.stdout.splitlines()
    assert lines[0].startswith("mission ") and "short-drive" in lines[0]
    assert not any("-->" in line or "{-}" in line for line in lines)  # no tree


def test_run_takes_battery_like_eval(
    mission: Path, capsys: pytest.CaptureFixture[str], usage_error: Callable[..., str]
) -> None:
    for given in ("0.3", "30%"):  # eval took the percent, run refused it
        assert main(["run", str(mission), "--fast", "--display", "none", "--battery", given]) == 0
        assert re.search(r"battery\s+30%", capsys.readouterr().out)
    refused = usage_error(main, ["run", str(mission), "--fast", "--battery", "1.5"])
    assert "argument --battery: found '1.5'; allowed: a fraction in 0..1" in refused
    assert main(["run", str(mission), "--port", "loop://", "--battery", "0.5"]) == 2
    assert "for the simulator" in capsys.readouterr().err


class _Runner:
    """A run's clock: its last tick's time, its link's clock still at that frame's arrival."""

    def __init__(self, time: float | None) -> None:
        self.has_snapshot = time is not None
        self.snapshot = type("Snap", (), {"time": time})()
        self.clock_held = False
        transport = type("Transport", (), {"now": lambda _: 5.0})()
        link = type("Link", (), {"transport": transport, "arrival": 5.0})()
        self.connection = type("Connection", (), {"link": link})()


def test_log_lines_show_mission_time_not_the_wall_clock() -> None:
    record = logging.LogRecord("roomba_bt.run", logging.WARNING, __file__, 1, "late", (), None)
    formatter = MissionClockFormatter()
    try:
        use_mission_clock(_Runner(12.3456))  # type: ignore[arg-type]
        assert formatter.format(record) == "t=12.346 WARNING roomba_bt.run: late"
        use_mission_clock(_Runner(None))  # type: ignore[arg-type]
        assert formatter.format(record) == "WARNING roomba_bt.run: late"
    finally:
        use_mission_clock(None)
    assert formatter.format(record) == "WARNING roomba_bt.run: late"  # no date, no clock


ROGUE = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands


@declare("rogue", kind="action")
class Rogue(Action):
    """Queues Drive past its declaration, straight into the outbox (``send`` would refuse
    an undeclared command): the mode guard refuses it in Passive."""

    def update(self) -> Status:
        self.robot.outbox.send(commands.drive(100, 0), self)
        return Status.SUCCESS
'''


def run_rogue(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    sequence: str,
    *extra: str,
    plugin: str = ROGUE,
) -> tuple[str, str]:
    """``run`` a mission of ``sequence`` (a YAML flow list) with the rogue plugin, which
    drives without entering Safe: its stdout and stderr."""
    (tmp_path / "rogue.py").write_text(plugin)
    path = tmp_path / "refused.yaml"
    path.write_text(f"plugins: [./rogue.py]\ntree:\n  sequence: {sequence}\n")
    main(["run", str(path), "--fast", "--display", "none", "--allow-plugin-files", *extra])
    out, err = capsys.readouterr()
    return out, err


def test_refusals_are_stamped_with_mission_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, err = run_rogue(tmp_path, capsys, "[{wait: 0.3s}, rogue]")
    assert re.search(r"^refused: t=0\.3\d\d ", err, re.M), err
    assert re.search(r"^refused: t=0\.3\d\d rogue: drive needs Safe or Full", err, re.M), err
    assert re.search(r"the robot is in Passive since t=0\.000 ", err), err


def test_a_refusal_says_when_the_mode_began_in_mission_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not the time of day, which a ``--fast`` run never saw beside its ``t=``."""
    _, err = run_rogue(
        tmp_path, capsys, "[{mode: safe}, {wait: 0.3s}, {mode: passive}, {wait: 0.45s}, rogue]"
    )
    assert re.search(
        r"^refused: t=0\.7\d\d rogue: .* in Passive since t=0\.3[0-2]\d ", err, re.M
    ), err


def test_matplotlib_info_lines_are_not_shown() -> None:
    setup_logging(0, 0)
    assert not logging.getLogger("matplotlib.font_manager").isEnabledFor(logging.INFO)
    assert logging.getLogger("roomba_bt.run").isEnabledFor(logging.INFO) or (
        logging.getLogger().level > logging.INFO  # a test runner's own level
    )


def test_a_status_change_line_carries_its_own_mission_time() -> None:
    record = logging.LogRecord("roomba_bt.run", logging.INFO, __file__, 1, "drive -> SUCCESS",
                               (), None)  # fmt: skip
    record.mission_time = 1.5
    assert MissionClockFormatter().format(record) == "t=1.500 INFO roomba_bt.run: drive -> SUCCESS"


def test_show_prints_parameter_values_with_their_units(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(
        "parameters:\n  side: {type: distance, default: 1 m}\n"
        "  speed: {type: speed, default: 200 mm/s}\n  laps: {type: int, default: 2}\n"
        "tree:\n  sequence:\n    - mode: safe\n"
        "    - drive: {velocity: '${speed}', distance: '${side}'}\n"
    )
    assert main(["show", str(path), "-p", "side=50cm"]) == 0
    out = capsys.readouterr().out
    # as written, as the leaf's name says it (it said side=500 mm beside distance=50cm)
    assert "parameters: speed=200 mm/s, laps=2, side=50cm" in out
    assert "drive(velocity=200 mm/s, distance=50cm)" in out


RADII = """
parameters:
  r: {type: radius, default: spin_left}
  d: {type: distance, default: 50 cm}
blackboard:
  k: {type: radius, initial: -1 m}
  kd: {type: distance, initial: 30 cm}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, radius: "${r}", angle: 10deg}
    - drive: {velocity: 100 mm/s, radius: "${d}", distance: 5 cm}
    - drive: {velocity: 100 mm/s, radius: "@k", distance: 5 cm}
    - drive: {velocity: 100 mm/s, radius: "@kd", distance: 5 cm}
"""


def test_drive_radius_from_a_parameter_or_a_blackboard_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``radius`` type (a distance or straight/spin_left/spin_right), and a distance fits
    a radius: both were refused ("is a distance (mm), but drive.radius needs radius")."""
    path = tmp_path / "radii.yaml"
    path.write_text(RADII)
    assert main(["validate", str(path)]) == 0, capsys.readouterr().out
    assert main(["run", str(path), "--fast", "--display", "none", "-p", "r=spin_right"]) == 0
    assert re.search(r"outcome\s+SUCCESS", capsys.readouterr().out)
    assert main(["validate", str(path), "-p", "r=sideways"]) == 2
    assert "or one of straight, spin_left, spin_right" in capsys.readouterr().out


def test_eval_names_the_stage_that_was_running_when_time_ran_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from roomba_bt.evaluate.episode import failure_stage

    path = tmp_path / "slow.yaml"
    path.write_text("tree:\n  sequence:\n    - mode: safe\n    - wait: 10s\n")
    main(["eval", str(path), "--runs", "1", "--jobs", "1", "--timeout", "2s"])
    out = capsys.readouterr().out
    assert "--timeout 2 s of mission time ran out in wait" in out, out
    assert failure_stage("--timeout 2 s of mission time ran out in dock_approach") == (
        "dock_approach"
    )
    assert failure_stage("find_dock(speed=1): lost the beam") == "find_dock"
    # a wait running beside an action is a parallel's timer: the action is named (clean's
    # "clean for the duration" said "ran out in wait" while the robot was cleaning)
    path.write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - parallel:\n        policy: one\n"
        "        children:\n          - wait: 10s\n          - drive: {velocity: 50 mm/s}\n"
    )
    main(["eval", str(path), "--runs", "1", "--jobs", "1", "--timeout", "2s"])
    out = capsys.readouterr().out
    assert "--timeout 2 s of mission time ran out in drive" in out, out


def test_a_robot_that_never_answers_is_no_connection_and_doctor_is_named(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """An asleep robot on a pty (no modem line to pulse BRC): it was "CONNECTION LOST"
    although nothing had been connected, and nothing said that doctor wakes it."""
    from robot.sim_backend import sim_pty_server

    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--asleep") as port:
        code = main(["run", "bump-and-turn", "--port", port, "--display", "none"])
    out, err = capsys.readouterr()
    assert code == 3
    assert "outcome      NO CONNECTION (" in out
    assert f"`roomba-bt doctor --port {port}` finds the robot's rate, wakes it" in err


def test_a_world_file_given_as_a_mission_is_said_to_be_a_world(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Its name: and description: are mission words too: validate listed every other key
    of it as unknown (11 lines for a field trial's flat). ``validate`` checks it as a
    world (its one problem, at its line); ``show`` says it is no mission."""
    world = tmp_path / "flat.yaml"
    world.write_text(
        "name: flat\ndescription: my flat\nrooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
        "obstacles: [{rect: [1, 1, 2, 2]}]\ndock: {at: [2, 0], facing: 90}\n"
    )
    assert main(["validate", str(world)]) == 2
    said = "".join(capsys.readouterr())
    assert said.count("\n") == 2, said  # the error, then the file's verdict
    assert said.startswith(f"{world}:5:7: dock: found no robot.start"), said
    assert said.endswith(f"{world}: failed (1 error)\n")
    assert main(["show", str(world)]) == 2
    said = "".join(capsys.readouterr())
    assert said.count("\n") == 1, said
    assert "this file is a world (rooms:, no tree:), not a mission: run a mission on it" in said
    assert f"roomba-bt validate {world} checks it" in said


def test_random_start_in_a_world_without_a_start_region_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run --random-start --seed 5`` in a world with no start region ran from the same
    pose whatever the seed, without a word (eval warns of the same)."""
    world = tmp_path / "plain.yaml"
    world.write_text("rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nrobot: {start: {at: [1, 1]}}\n")
    argv = ["run", "bump-and-turn", "-p", "duration=1s", "--fast", "--display", "none"]
    assert main([*argv, "--world", str(world), "--random-start", "--seed", "5"]) == 0
    assert "--random-start: world 'plain' has no robot.start_region" in capsys.readouterr().err
    assert main([*argv, "--world", "apartment", "--random-start", "--seed", "5"]) == 0
    assert "start_region" not in capsys.readouterr().err


def test_refusals_past_the_first_five_are_said_as_a_count(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Five refusals are printed; the rest are one line, ``... and N more``, N the summary's
    count less five (a run with 167 refusals printed five and said nothing of the others)."""
    always = ROGUE.replace("return Status.SUCCESS", "return Status.RUNNING")
    out, err = run_rogue(tmp_path, capsys, "[rogue]", "--timeout", "0.3s", plugin=always)
    count = int(re.search(r"(\d+) refused by the mode guard", out).group(1))  # type: ignore[union-attr]
    assert count > 5, out
    assert len(re.findall(r"^refused: t=", err, re.M)) == 5, err
    assert f"refused: ... and {count - 5} more (the summary counts them)\n" in err, err


def test_five_refusals_or_fewer_say_no_more(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, err = run_rogue(tmp_path, capsys, "[rogue]")
    assert len(re.findall(r"^refused: t=", err, re.M)) == 1 and "more" not in err, err


def test_a_plugin_s_refused_action_is_told_what_to_do_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stranger's first plugin sent its drive on every tick after a cliff had dropped the
    robot to Passive: 3543 refusals, each ``drive needs Safe or Full``, and what to do about
    it only on docs/plugins.md. The refused action of the user's own code is named once,
    with its class and line, and the fix."""
    always = ROGUE.replace("return Status.SUCCESS", "return Status.RUNNING")
    _, err = run_rogue(tmp_path, capsys, "[rogue]", "--timeout", "0.3s", plugin=always)
    said = re.findall(r"^refused: rogue \(Rogue \((.*):(\d+)\)\) is your code: (.*)$", err, re.M)
    assert len(said) == 1, err
    [(file, line, fix)] = said
    assert (file, line) == (str(tmp_path / "rogue.py"), "8")  # its @declare, the class's first line
    assert "checks self.snapshot.mode each tick" in fix
    assert "returns self.wait_for_driving_mode() (roomba-bt docs plugins, When the robot" in fix


def test_a_subcommand_module_missing_is_a_broken_installation_not_a_silent_skip(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every module of ``SUBCOMMAND_MODULES`` ships; the parser skipped one that was missing
    (scaffolding from before they all existed), so a wheel built without one lost that
    subcommand from the help without a word."""
    import roomba_bt.cli as cli

    missing = "roomba_bt.cli.not_built_cmd"
    monkeypatch.setattr(cli, "SUBCOMMAND_MODULES", (*cli.SUBCOMMAND_MODULES, missing))
    with pytest.raises(ModuleNotFoundError, match=f"the subcommand module {missing} is missing"):
        build_parser()
    assert main(["validate", "--help"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt: the subcommand module {missing} is missing"), err
    assert "Traceback" not in err
