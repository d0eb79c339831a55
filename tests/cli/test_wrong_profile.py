"""A Roomba 500 read with the default profile (create2): its stream checksum leaves the header
out, so every frame fails the Create 2's checksum. The run and the sensor table ended with
"the line is garbled ... (noise on the line, or a wrong baud rate)", never naming the
profile; they name the model and the fix now."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from robot.sim_backend import sim_pty_server  # tests/robot: the simulator on a pty

from roomba_bt.cli import main
from roomba_bt.oi.profiles import ROOMBA500

MISSION = """\
mission: sit
tree:
  wait: 1s
"""


@pytest.fixture(scope="module")
def roomba500_port() -> Iterator[str]:
    with sim_pty_server(ROOMBA500) as port:
        yield port


def _says_roomba500(err: str) -> None:
    assert "failed the checksum of the create2 profile" in err, err
    assert "most likely a Roomba 500 series" in err
    assert "--profile roomba500" in err and "roomba-bt doctor" in err
    assert "Connection.open(port, profile='roomba500')" in err


def test_sensors_with_the_default_profile_on_a_roomba500_names_the_profile(
    roomba500_port: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # a setting, as run's WRONG PROFILE is: exit 2, which fails the same way again (it was
    # 3, "connection or stream failure", where run said 2)
    assert main(["sensors", "--port", roomba500_port, "--count", "2"]) == 2
    err = capsys.readouterr().err
    _says_roomba500(err)
    assert f"roomba-bt: wrong profile: {roomba500_port}: " in err, err
    assert_quoted("docs/doctor.md", "roomba-bt: wrong profile: PORT:", err,
                  names={roomba500_port: "PORT"})  # fmt: skip
    assert_quoted("docs/robot.md", "roomba-bt: wrong profile: ...$", err)
    # certain at the first trip: said once, not again after a grace waited for nothing
    assert "waiting up to" not in err and err.count("failed the checksum") == 1, err


def test_run_with_the_default_profile_on_a_roomba500_names_the_profile(
    roomba500_port: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    # a setting, found before anything of the mission was sent: exit 2, which fails the same
    # way again (it was 8, "the link was lost after the run started: a person looks first")
    assert main(["run", str(mission), "--port", roomba500_port, "--display", "none"]) == 2
    out, err = capsys.readouterr()
    _says_roomba500(out)  # the summary's outcome, whole for one who reads only the summary
    assert "outcome      WRONG PROFILE (" in out
    assert "commands     0 written" in out and "final mode   Passive" in out
    assert "then the run waited" not in out  # ended at the watchdog's trip: it was certain
    # said once: stderr's line is the short first line, the model and the fix; the warning
    # that repeated it all (a ride through the grace) is gone
    (line,) = err.splitlines()
    assert line.startswith(f"roomba-bt: wrong profile: {roomba500_port}: the robot is most ")
    assert "use --profile roomba500" in line and "failed the checksum" not in line
    assert (out + err).count("failed the checksum") == 1
    assert_quoted("docs/runtime.md", "roomba-bt: wrong profile: PORT:", err,
                  names={roomba500_port: "PORT"})  # fmt: skip
    assert_quoted("docs/unattended.md", "outcome WRONG PROFILE", out)


@pytest.mark.parametrize("where", ["environment", "project file"])
def test_a_wrong_profile_set_elsewhere_is_fixed_where_it_was_set(
    where: str,
    roomba500_port: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``ROOMBA_BT_PROFILE=create2`` on a Roomba 500: the summary said the profile came
    from ROOMBA_BT_PROFILE and its fix said "use --profile roomba500", which fixed one
    command and not the next. The fix is made where the setting is (as doctor says it)."""
    monkeypatch.delenv("ROOMBA_BT_PROFILE", raising=False)
    if where == "environment":
        monkeypatch.setenv("ROOMBA_BT_PROFILE", "create2")
        fix = "set ROOMBA_BT_PROFILE=roomba500 (or auto)"
    else:
        project = tmp_path / "pyproject.toml"
        project.write_text('[tool.roomba-bt]\nprofile = "create2"\n')
        fix = f'set profile = "roomba500" at {project}:2 (or "auto")'
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    assert main(["run", str(mission), "--port", roomba500_port, "--display", "none"]) == 2
    out, err = capsys.readouterr()
    assert fix in out and fix in err, (out, err)
    assert "use --profile" not in out + err
    if where == "environment":  # docs/robot.md's, on the page's port
        port = {roomba500_port: "/dev/ttyUSB0"}
        assert_quoted("docs/robot.md", "outcome WRONG PROFILE (", out, numbers=True, names=port)
        assert_quoted("docs/robot.md", "roomba-bt: wrong profile: /dev/ttyUSB0", err, names=port)


def test_the_right_profile_reads_it(
    roomba500_port: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["sensors", "--port", roomba500_port, "--count", "1", "--profile", "roomba500"])
    assert code == 0
    assert "oi_mode" in capsys.readouterr().out


def test_run_with_the_default_profile_on_a_roomba600_names_the_port_and_the_profile(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A 600 reports packet 35 as the mode + 1, which the create2 profile does not expect:
    the run goes on (every reading corrected), and its warning names the port and the fix
    as the 500's does. It said only "packet 35 reports the OI mode + 1 (read 2); correcting
    every reading by -1": with three robots of mixed models, neither which nor what to do."""
    import logging

    from roomba_bt.oi.profiles import ROOMBA600

    caplog.set_level(logging.INFO, logger="roomba_bt.robot.modes")
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    with sim_pty_server(ROOMBA600) as port:
        code = main(["run", str(mission), "--port", port, "--display", "none",
                     "--no-keep-awake"])  # fmt: skip
    assert code == 0
    (record,) = [r for r in caplog.records if "mode + 1" in r.getMessage()]
    assert record.levelname == "WARNING"
    line = record.getMessage()
    assert f"{port}: packet 35 reports the OI mode + 1 (read 2)" in line
    assert "which the create2 profile does not expect" in line
    assert "most likely a Roomba 600 series: use --profile roomba600" in line
    assert "Connection.open(port, profile='roomba600')" in line and "roomba-bt doctor" in line


@pytest.mark.parametrize(
    ("profile", "level", "fix"),
    [("create2", "WARNING", True), ("roomba500", "WARNING", True), ("roomba600", "INFO", False)],
)
def test_a_mode_plus_one_names_the_profile_where_the_profile_does_not_expect_it(
    profile: str, level: str, fix: bool, caplog: pytest.LogCaptureFixture
) -> None:
    """``--profile roomba500`` on a 600 ran silently with the 500's command set, but for the
    same bare warning; the 600's own profile expects it: said at INFO, no fix."""
    import logging

    from roomba_bt.oi.profiles import PROFILES
    from roomba_bt.robot.modes import ModeModel

    caplog.set_level(logging.INFO, logger="roomba_bt.robot.modes")
    assert ModeModel(PROFILES[profile]).calibrate(2, 0.0, "/dev/ttyUSB3")
    (record,) = [r for r in caplog.records if "mode + 1" in r.getMessage()]
    assert record.levelname == level
    assert record.getMessage().startswith("/dev/ttyUSB3: packet 35 reports the OI mode + 1")
    assert ("--profile roomba600" in record.getMessage()) is fix
