"""The rates a robot talks at, from its profile: 115200 or 19200 from power-on on every model
(both OI specs, "Serial Port Settings"), any of the Baud command's (129) twelve only after a
host sent it. ``sim --baud`` refuses another rate (a simulated robot has just been powered
on); ``run`` and ``sensors --baud`` warn of one, naming the flag, the rate and the model."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.robot.discovery import OI_RATES


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_each_profile_holds_its_rates_as_data(name: str) -> None:
    profile = PROFILES[name]
    assert profile.power_on_bauds == (115200, 19200) == OI_RATES
    assert profile.default_baud == profile.power_on_bauds[0]
    assert profile.baud_command_rates == tuple(sorted(BAUD_CODES))
    assert profile.baud_problem(115200) is None and profile.baud_problem(19200) is None
    problem = profile.baud_problem(57600)
    assert problem is not None and profile.title in problem
    assert "115200 or 19200 from power-on" in problem and "Baud (129)" in problem
    assert "no rate of the OI" in (profile.baud_problem(1234) or "")


@pytest.mark.parametrize(("profile", "title"), [("roomba600", "Roomba 600 series"),
                                                ("roomba500", "Roomba 500 series")])  # fmt: skip
def test_sim_refuses_a_rate_its_robot_does_not_start_at(
    profile: str, title: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """It was argparse's ``invalid choice: 57600 (choose from 19200, 115200)``, a tuple
    written in the option, not the profile's: nothing said why, or for which robot."""
    code = main(["sim", "--pty", "--profile", profile, "--baud", "57600", "--duration", "0"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"roomba-bt sim: --baud 57600: the {title} talks at 115200 or 19200 from power-on" in err
    assert err.rstrip().endswith("allowed: 115200, 19200")
    assert "Traceback" not in err


def test_run_on_a_port_warns_of_a_rate_the_robot_does_not_start_at(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Roomba 600 opened at 57600 gave only garbage, said later as a lost stream."""
    code = main(["run", str(mission), "--port", "/dev/null", "--profile", "roomba600",
                 "--baud", "57600", "--display", "none"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 3  # /dev/null is no serial port: the warning came before the open
    assert (
        "roomba-bt run: warning: --baud 57600: the Roomba 600 series talks at 115200 or 19200 "
        "from power-on" in err
    )
    assert "--baud auto finds the rate it talks at" in err


def test_run_on_the_simulator_says_the_rate_is_only_the_stream_s(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The run went ahead at 115200 in silence, the stream checked at 57600."""
    code = main(["run", str(mission), "--fast", "--display", "none", "--baud", "57600"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "warning: --baud 57600: the iRobot Create 2 talks at 115200 or 19200" in err
    assert "the simulated robot talks at 115200 whatever --baud says" in err
    code = main(["run", str(mission), "--fast", "--display", "none", "--baud", "19200"])
    assert code == 0 and "--baud" not in capsys.readouterr().err


def test_sensors_warns_too(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sensors", "--baud", "38400", "--count", "1"]) == 0
    err = capsys.readouterr().err
    assert "roomba-bt sensors: warning: --baud 38400: the iRobot Create 2 talks at" in err
