"""docs/unattended.md's systemd unit, timer and cron script are what the code does: the
command its ``ExecStart`` runs parses, its stop waits longer than the safe stop can take, and
the exit codes it retries and refuses to retry are :class:`ExitCode`'s, one retried (3, not
started), every other one not. A new exit code, or one that changes meaning, fails here
until the page says it: a service retrying a run that lost its robot would send it off again.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import build_parser
from roomba_bt.robot.baud_hunt import hunt_seconds
from roomba_bt.robot.ending import STOP_RESYNC_ZEROS
from roomba_bt.runtime.summary import DEFAULT_GRACE, ExitCode

PAGE = Path(__file__).resolve().parents[2] / "docs" / "unattended.md"
#: the one ending a service may try again: nothing of the mission was sent
RETRIED = ExitCode.CONNECTION
#: the codes ``run``, the command a service runs, can exit with: every one but ``doctor``'s
#: own (docs/runtime.md, Exit codes)
RUN_CODES = {int(code) for code in ExitCode} - {ExitCode.NO_ANSWER, ExitCode.UNHEALTHY}


def _blocks(language: str) -> list[str]:
    """The page's fenced blocks of ``language``, in order."""
    return re.findall(rf"^```{language}\n(.*?)^```$", PAGE.read_text(), re.M | re.S)


def _unit(text: str) -> dict[str, str]:
    """A unit file's ``Key=value`` lines (comments and section headers left out)."""
    lines = [line for line in text.splitlines() if line and line[0] not in "#;["]
    return dict(line.split("=", 1) for line in lines)


SERVICE, TIMER = _blocks("ini")
UNIT = _unit(SERVICE)


def test_the_service_runs_a_command_roomba_bt_parses() -> None:
    program, *argv = shlex.split(UNIT["ExecStart"])
    assert program.endswith("/roomba-bt")
    args = build_parser().parse_args(argv)
    assert args.command == "run" and args.display == "log"  # no terminal: the log display
    assert args.port.startswith("/dev/serial/by-id/")  # a name that stays the adapter's


def test_the_service_stops_with_sigterm_and_waits_for_the_safe_stop() -> None:
    """SIGTERM is what the run takes for a stop; SIGKILL after ``TimeoutStopSec`` would cut
    the safe stop short: it outlasts the stop's search at every rate and a port's grace."""
    assert UNIT["KillSignal"] == "SIGTERM"
    longest_stop = hunt_seconds(115200, bytes(11), STOP_RESYNC_ZEROS) + DEFAULT_GRACE
    assert float(UNIT["TimeoutStopSec"]) > 2 * longest_stop


def test_the_service_retries_only_a_run_that_never_started() -> None:
    assert UNIT["Restart"] == "on-failure"
    prevented = {int(code) for code in UNIT["RestartPreventExitStatus"].split()}
    assert prevented == RUN_CODES - {ExitCode.OK, RETRIED}


def test_the_page_s_table_has_every_exit_code_and_retries_one() -> None:
    rows = re.findall(r"^\| (\d+) \| (.*) \| (.*) \|$", PAGE.read_text(), re.M)
    assert {int(code) for code, _, _ in rows} == RUN_CODES
    retried = [int(code) for code, _, retry in rows if retry.startswith("**yes**")]
    assert retried == [RETRIED]
    said = {int(code): what for code, what, _ in rows}
    assert said[ExitCode.CONNECTION].startswith("**not started**")
    assert said[ExitCode.LINK_LOST].startswith("**the link was lost after the run started**")


def test_the_cron_script_retries_the_same_code() -> None:
    [script] = _blocks("sh")
    assert f'[ "$code" -eq {int(RETRIED)} ]' in script
    assert "--display log" in script


@pytest.mark.skipif(shutil.which("systemd-analyze") is None, reason="no systemd-analyze here")
def test_systemd_reads_every_option_of_the_unit_and_the_timer(tmp_path: Path) -> None:
    """``systemd-analyze verify`` on the page's files (``ExecStart``'s program made one that
    is here): a misspelt option or a value systemd would ignore fails."""
    here = Path(sys.executable).with_name("roomba-bt")
    service = tmp_path / "roomba.service"
    program = shlex.split(UNIT["ExecStart"])[0]
    service.write_text(SERVICE.replace(program, str(here if here.exists() else sys.executable)))
    timer = tmp_path / "roomba.timer"
    timer.write_text(TIMER)
    checked = subprocess.run(
        ["systemd-analyze", "verify", str(service), str(timer)],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert checked.returncode == 0 and not checked.stderr.strip(), checked.stderr
    calendar = subprocess.run(
        ["systemd-analyze", "calendar", _unit(TIMER)["OnCalendar"]],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert calendar.returncode == 0, calendar.stderr
