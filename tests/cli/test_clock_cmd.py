"""``roomba-bt clock``: the robot's clock and weekly schedule set from the command line, read
back from the simulator, refused on a Create 2 and while the Clock or Schedule button is
pressed; every usage error said with what was found and what is allowed."""

from __future__ import annotations

import datetime
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from robot.sim_backend import sim_pty_server  # tests/robot: the simulator on a pty

from roomba_bt.cli import clock_cmd, links, main
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import ROOMBA600
from roomba_bt.sim import Simulator


@pytest.fixture
def simulators(monkeypatch: pytest.MonkeyPatch) -> list[Simulator]:
    """The simulators the command makes, kept to look at after it ended."""
    made: list[Simulator] = []
    make = links.make_simulator

    def keep(*args: object, **kwargs: object) -> Simulator:
        made.append(make(*args, **kwargs))  # type: ignore[arg-type]
        return made[-1]

    monkeypatch.setattr(links, "make_simulator", keep)
    return made


def test_set_now_and_a_schedule_round_trip_on_the_simulator(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], simulators: list[Simulator]
) -> None:
    """The bytes sent are the ones the simulated robot takes: its clock reads the host's
    time (to the nearest minute), its schedule the days given; it is left in Passive."""
    saturday = datetime.datetime(2026, 12, 5, 23, 59, 45)  # a Saturday: the week wraps
    monkeypatch.setattr(clock_cmd, "host_now", lambda: saturday)
    code = main(["clock", "--profile", "roomba600", "--set-now", "--schedule",
                 "mon 09:30, Wednesday 10:00"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    assert "sent clock     Sunday 00:00   [168 0 0 0]" in out
    assert "sent schedule  Mon 09:30, Wed 10:00   [167 10 0 0 9 30 0 0 10 0" in out
    assert "the simulator's clock     Sunday 00:00" in out
    assert "the simulator's schedule  Mon 09:30, Wed 10:00" in out
    [simulator] = simulators
    assert simulator.robot_clock.cleans == {"mon": (9, 30), "wed": (10, 0)}
    assert simulator.mode is OIMode.PASSIVE and not simulator.requested_left


def test_a_day_and_time_given_and_the_schedule_cleared(
    capsys: pytest.CaptureFixture[str], simulators: list[Simulator]
) -> None:
    assert main(["clock", "--profile", "roomba500", "--day", "fri", "--time", "7:05",
                 "--clear-schedule"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "sent clock     Friday 07:05   [168 5 7 5]" in out
    assert f"sent schedule  none (no scheduled cleaning)   [167{' 0' * 15}]" in out
    assert simulators[0].robot_clock.day_time == (5, 7, 5)


def test_without_an_option_it_shows_what_the_simulator_holds(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["clock", "--profile", "roomba600"]) == 0
    out = capsys.readouterr().out
    assert "the simulator's clock     Sunday 00:00" in out and "sent" not in out


@pytest.mark.parametrize(
    ("seconds", "sent"), [(29, (1, 21, 35)), (30, (1, 21, 36)), (0, (1, 21, 35))]
)
def test_set_now_sends_the_nearest_minute(seconds: int, sent: tuple[int, int, int]) -> None:
    """The OI takes no seconds: 21:35:50 is sent as 21:36, 10 s ahead, not 50 s behind."""
    monday = datetime.datetime(2026, 12, 7, 21, 35, seconds)
    assert clock_cmd.nearest_minute(monday) == sent


def test_the_create2_is_refused_before_anything_is_sent(
    capsys: pytest.CaptureFixture[str], simulators: list[Simulator]
) -> None:
    """The default profile keeps no clock: a usage error naming the models that do and the
    flag that names one (docs/protocol.md, "The clock and the schedule")."""
    assert main(["clock", "--set-now"]) == 2
    err = capsys.readouterr().err
    assert "roomba-bt clock: the iRobot Create 2 (create2) keeps no clock" in err
    assert "give --profile roomba600 (or roomba500)" in err
    assert simulators == []  # nothing made, nothing sent


def test_the_create2_is_refused_on_a_port_before_it_is_opened(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The refusal comes before the port is opened: a port that is none is never tried."""
    missing = tmp_path / "ttyNONE"
    assert main(["clock", "--port", str(missing), "--profile", "create2", "--set-now"]) == 2
    err = capsys.readouterr().err
    assert "keeps no clock" in err and "could not open" not in err


def test_set_over_a_pty_as_on_a_robot(capsys: pytest.CaptureFixture[str]) -> None:
    """The real serial path: what was sent is said; nothing is read back (no packet
    carries the clock)."""
    with sim_pty_server(ROOMBA600) as port:
        code = main(["clock", "--port", port, "--profile", "roomba600", "--day", "wed",
                     "--time", "15:00", "--schedule", "wed 15:00, fri 10:36"])  # fmt: skip
        shown = main(["clock", "--port", port, "--profile", "roomba600"])
    out = capsys.readouterr().out
    assert code == 0 and shown == 0
    assert "[167 40 0 0 0 0 0 0 15 0 0 0 10 36 0 0]" in out  # the spec's own example
    assert "the robot reports neither its clock nor its schedule" in out
    assert "its Clock and Schedule buttons are not pressed" in out


def test_a_clock_button_held_sends_nothing_and_says_why(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    simulators: list[Simulator],
) -> None:
    """Both specs: the robot ignores 167 and 168 while its Clock or Schedule button is
    pressed; sent anyway, the robot would keep its old clock with no word said."""
    monkeypatch.setattr("roomba_bt.sim.protocol.PRESS_SECONDS", 3600.0)  # a finger held on
    world = tmp_path / "held.yaml"
    world.write_text(
        "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\n"
        "robot: {start: {at: [2, 2], heading: 0}}\n"
        "events: [{at: 0, kind: press, button: clock}]\n"
    )
    code = main(["clock", "--profile", "roomba600", "--world", str(world), "--set-now"])
    captured = capsys.readouterr()
    assert code == 3
    assert_quoted("docs/robot.md", "roomba-bt clock: the robot's clock button is pressed",
                  captured.err)  # fmt: skip
    assert "sent" not in captured.out
    assert simulators[0].robot_clock.day_time == (0, 0, 0)
    assert simulators[0].mode is OIMode.PASSIVE


@pytest.mark.parametrize(
    ("arguments", "said"),
    [
        (["--day", "funday", "--time", "10:00"],
         "argument --day: found 'funday'; allowed: sun, mon, tue, wed, thu, fri, sat"),
        (["--day", "wed"], "--day needs --time too"),
        (["--time", "10:00"], "--time needs --day too"),
        (["--day", "wed", "--time", "24:00"],
         "argument --time: found '24:00'; allowed: a 24-hour time HH:MM, 00:00 to 23:59"),
        (["--day", "wed", "--time", "9:5"], "argument --time: found '9:5'"),
        (["--day", "wed", "--time", "9h30"], "argument --time: found '9h30'"),
        (["--schedule", "mon"], "argument --schedule: entry 1, 'mon': found 1 word(s)"),
        (["--schedule", "mon 09:30,"], "argument --schedule: entry 2, '': found 0 word(s)"),
        (["--schedule", "mon 09:30, monday 10:00"],
         "argument --schedule: entry 2, 'monday 10:00': Monday a second time"),
        (["--schedule", "mon 09:60"], "entry 1, 'mon 09:60': found '09:60'"),
        (["--schedule", "moon 09:30"], "entry 1, 'moon 09:30': found 'moon'"),
        (["--set-now", "--day", "mon", "--time", "10:00"],
         "argument --day: not allowed with argument --set-now"),
        (["--schedule", "mon 09:30", "--clear-schedule"],
         "argument --clear-schedule: not allowed with argument --schedule"),
    ],
)  # fmt: skip
def test_each_usage_error_says_what_was_found_and_what_is_allowed(
    arguments: list[str],
    said: str,
    capsys: pytest.CaptureFixture[str],
    simulators: list[Simulator],
) -> None:
    try:
        code = main(["clock", "--profile", "roomba600", *arguments])
    except SystemExit as exit_:  # argparse's own usage errors
        code = exit_.code  # type: ignore[assignment]
    assert code == 2
    assert said in capsys.readouterr().err
    assert simulators == []  # nothing was started


def test_a_port_that_cannot_be_opened_is_exit_3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["clock", "--profile", "roomba600", "--port", str(tmp_path / "ttyNONE"),
                 "--set-now"])  # fmt: skip
    assert code == 3
    assert "could not open the port" in capsys.readouterr().err


def test_a_schedule_file_is_read_as_the_option_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], simulators: list[Simulator]
) -> None:
    """Days to 24-hour times, one a line; an unquoted 09:30 is the text written (YAML 1.1
    would read 9:30 as the number 570), and {} clears the schedule."""
    weekly = tmp_path / "weekly.yaml"
    weekly.write_text("# the robot's week\nmon: 9:30\nThursday: '18:00'\n")
    assert main(["clock", "--profile", "roomba600", "--schedule-file", str(weekly)]) == 0
    assert "the simulator's schedule  Mon 09:30, Thu 18:00" in capsys.readouterr().out
    weekly.write_text("{}\n")
    assert main(["clock", "--profile", "roomba600", "--schedule-file", str(weekly)]) == 0
    assert "sent schedule  none (no scheduled cleaning)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("mon: 09:30\nwed: 25:00\n", "s.yaml:2:6: found '25:00'; allowed: a 24-hour time"),
        ("mon: 09:30\nMonday: 10:00\n",
         "s.yaml:2:1: Monday a second time; allowed: each day at most once"),
        ("funday: 09:30\nmon: 10:00\n", "s.yaml:1:1: found 'funday'; allowed: sun, mon,"),
        ("mon: [09:30]\n", "s.yaml:1:1: found a list or a mapping; allowed: a day and its"),
        ("mon: 09:30\n  wed: 1\n", "s.yaml:2:6: mapping values are not allowed in this context"),
        ("", "roomba-bt clock: --schedule-file 's.yaml': the file holds no days"),
        ("root:x:0:0:root:/root:/bin/bash\n",
         "roomba-bt clock: --schedule-file 's.yaml': not a schedule file: expected a mapping"),
    ],
)  # fmt: skip
def test_a_schedule_file_s_faults_are_said_at_their_line_and_column(
    text: str,
    said: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    simulators: list[Simulator],
) -> None:
    monkeypatch.chdir(tmp_path)
    Path("s.yaml").write_text(text)
    assert main(["clock", "--profile", "roomba600", "--schedule-file", "s.yaml"]) == 2
    err = capsys.readouterr().err
    assert said in err
    assert "root:/root" not in err  # another kind of file: none of it quoted
    assert simulators == []  # nothing started


def test_a_schedule_file_that_is_not_there_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nope.yaml"
    assert main(["clock", "--profile", "roomba600", "--schedule-file", str(missing)]) == 2
    assert "No such file or directory" in capsys.readouterr().err


def test_the_schedule_file_fault_docs_quote(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    Path("weekly.yaml").write_text("# weekly\nmon: 9:30\nthursday: 25:00\n")
    assert main(["clock", "--profile", "roomba600", "--schedule-file", "weekly.yaml"]) == 2
    assert_quoted("docs/robot.md", "weekly.yaml:3:11: found", capsys.readouterr().err)


def test_the_create2_is_refused_before_baud_auto_probes_the_port(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--baud auto`` opens the port and may pulse BRC to find the rate: a model the
    command refuses whatever the rate is refused first (it opened the port, and said exit
    3 of a port that is none, for a command that could never have run)."""
    missing = tmp_path / "ttyNONE"
    code = main(["clock", "--port", str(missing), "--profile", "create2", "--baud", "auto",
                 "--set-now"])  # fmt: skip
    assert code == 2
    assert "keeps no clock" in capsys.readouterr().err


def test_the_create2_s_refusal_says_the_fix_where_the_model_was_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Create 2 named by ROOMBA_BT_PROFILE or the project file was told to give
    --profile, which fixed this one command and not the next."""
    monkeypatch.setenv("ROOMBA_BT_PROFILE", "create2")
    assert main(["clock"]) == 2
    assert "set ROOMBA_BT_PROFILE=roomba600 (or roomba500)" in capsys.readouterr().err
    monkeypatch.delenv("ROOMBA_BT_PROFILE")
    monkeypatch.chdir(tmp_path)
    Path("pyproject.toml").write_text('[tool.roomba-bt]\nprofile = "create2"\n')
    assert main(["clock"]) == 2
    err = capsys.readouterr().err
    assert f'set profile = "roomba600" (or "roomba500") at {tmp_path / "pyproject.toml"}:2' in err
