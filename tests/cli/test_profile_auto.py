"""``--profile auto`` (``run``, ``sensors``; cli/links.py ``auto_profile``): the robot on
``--port`` identified before the mission is compiled for a model, as ``doctor`` tells it
without a Reset; what it could not tell said, with the profile it fell back to. On the
simulator served over a pty, in real time (a few seconds each)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

MISSION = """\
mission: short
tree:
  sequence:
    - mode: safe
    - wait: 0.3s
"""


def _cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", *args],
        capture_output=True, text=True, timeout=HANG_S, env={**os.environ, **(env or {})},
    )  # fmt: skip


def _run(port: str, tmp_path: Path, *extra: str, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    mission = tmp_path / "short.yaml"
    mission.write_text(textwrap.dedent(MISSION))
    return _cli("run", str(mission), "--port", port, "--display", "none", *extra, **kwargs)


@pytest.mark.parametrize(
    ("served", "said", "summary"),
    [
        ("roomba600", "--profile auto: Roomba 600 series (roomba600): ",
         "roomba600 (Roomba 600 series), from --profile auto: identified"),
        ("roomba500", "--profile auto: Roomba 500 series (roomba500): its stream checksum "
         "leaves the header out", "roomba500 (Roomba 500 series), from --profile auto: identified"),
        ("create2", "--profile auto: the iRobot Create 2 (create2) or a Roomba 600 series "
         "(--profile roomba600) or a Roomba 500 series (--profile roomba500): not told apart (",
         "create2 (iRobot Create 2), from --profile auto: not told apart from a Roomba 600 "
         "series (--profile roomba600) or a Roomba 500 series (--profile roomba500)"),
    ],
)  # fmt: skip
def test_run_profile_auto_identifies_the_robot_and_the_summary_says_how(
    served: str, said: str, summary: str, served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    sim = served_sim("--pty", "--profile", served)
    done = _run(sim.address, tmp_path, "--profile", "auto")
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"roomba-bt run: {said}" in done.stderr
    assert f"profile      {summary}\n" in done.stdout
    assert "outcome      SUCCESS" in done.stdout
    if served == "roomba600":  # docs/robot.md's verdict, on stderr and in the summary
        assert_quoted("docs/robot.md", "roomba-bt run: --profile auto:", done.stderr)
        assert_quoted("docs/robot.md", "profile roomba600", done.stdout)
    if served == "create2":  # what it fell back to, and what to give if that is wrong
        assert "speaking to it as the iRobot Create 2: give --profile NAME if its label " \
            "says otherwise" in done.stderr  # fmt: skip


def test_sensors_takes_auto_from_the_environment_and_finds_the_rate_too(
    served_sim: Callable[..., Any],
) -> None:
    sim = served_sim("--pty", "--profile", "roomba500", "--baud", "19200")
    done = _cli(
        "sensors", "--port", sim.address, "--baud", "auto", "--count", "1",
        env={"ROOMBA_BT_PROFILE": "auto"},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "roomba-bt sensors: ROOMBA_BT_PROFILE=auto: Roomba 500 series (roomba500)" in done.stderr
    assert done.stdout.startswith(f"{sim.address}  (Roomba 500 series)")


def test_auto_with_nothing_behind_the_port_says_it_could_not_tell_and_the_start_up_why(
    silent_port: str, tmp_path: Path
) -> None:
    done = _run(silent_port, tmp_path, "--profile", "auto")
    assert done.returncode == 3
    assert (
        "roomba-bt run: --profile auto: not identified: no answer to Start and a Query List at "
        "115200 baud (nothing); the start-up says why; speaking to it as the iRobot Create 2 "
        "(create2), the default"
    ) in done.stderr
    assert "did not answer two Query Lists (149)" in done.stderr  # the start-up's own diagnosis


def test_auto_on_a_roomba500_refuses_end_in_stop_once_it_is_known(
    served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    sim = served_sim("--pty", "--profile", "roomba500")
    done = _run(sim.address, tmp_path, "--profile", "auto", "--end-in", "stop")
    assert done.returncode == 2, done.stdout + done.stderr
    assert "the Roomba 500 series (--profile roomba500) has no Stop (173)" in done.stderr


def test_doctor_says_whether_the_model_named_once_fits(served_sim: Callable[..., Any]) -> None:
    sim = served_sim("--pty", "--profile", "roomba500")
    done = _cli("doctor", "--port", sim.address, env={"ROOMBA_BT_PROFILE": "create2"})
    assert done.returncode == 0, done.stdout
    assert "[warn] setting   ROOMBA_BT_PROFILE=create2: this robot is no create2" in done.stdout
    assert "fix: set it to roomba500, or to auto" in done.stdout
    done = _cli("doctor", "--port", sim.address, env={"ROOMBA_BT_PROFILE": "roomba500"})
    assert "[ok]   setting   ROOMBA_BT_PROFILE=roomba500: fits this robot" in done.stdout
