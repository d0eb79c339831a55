"""A Roomba 500 read with the default profile (create2): its stream checksum leaves the header
out, so every frame fails the Create 2's checksum. The run and the sensor table ended with
"the line is garbled ... (noise on the line, or a wrong baud rate)", never naming the
profile; they name the model and the fix now."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
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
    assert main(["sensors", "--port", roomba500_port, "--count", "2"]) == 3
    _says_roomba500(capsys.readouterr().err)


def test_run_with_the_default_profile_on_a_roomba500_names_the_profile(
    roomba500_port: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "sit.yaml"
    mission.write_text(MISSION)
    assert main(["run", str(mission), "--port", roomba500_port, "--display", "none"]) == 3
    out, err = capsys.readouterr()
    _says_roomba500(err)
    assert "--profile roomba500" in out  # the summary's outcome and its safe stop line


def test_the_right_profile_reads_it(
    roomba500_port: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["sensors", "--port", roomba500_port, "--count", "1", "--profile", "roomba500"])
    assert code == 0
    assert "oi_mode" in capsys.readouterr().out
