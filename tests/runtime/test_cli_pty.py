"""End to end over a real pty: `roomba-bt sim --pty` in one process, `roomba-bt run --port` in
another, every ending checked on the bytes the run wrote (its --record)."""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S, ended, finished, line, reaped  # tests/waits.py: waits that end as it does

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.discovery import PROBE_QUERY
from roomba_bt.robot.safety import signal_reason
from roomba_bt.runtime.recording import load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.transport import SerialTransport

from .bridge import ResettingBridge
from .simrun import SPIN, write_mission

SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data


def ends_with_the_safe_stop(outbound: bytes) -> bool:
    """The record's last bytes are the safe stop, or the stop and the Query List that asks
    after it when its answer did not come in the stop's window (a loaded machine starved the
    simulator's process: robot/ending.asked_after); that the robot then answered in Passive is
    the summary's to say."""
    return outbound.removesuffix(PROBE_QUERY).endswith(SAFE_END)


CLI = [sys.executable, "-m", "roomba_bt.cli"]

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pty")


@pytest.fixture
def sim_port(served_sim: Callable[..., Any]) -> str:
    port: str = served_sim("--pty").address
    assert port.startswith("/dev/"), port
    return port


def _start_run(
    port: str, mission: Path, record: Path, *extra: str, ignoring: signal.Signals | None = None
) -> subprocess.Popen[str]:
    """The run, started as ``nohup`` starts it when ``ignoring`` is SIGHUP."""
    return subprocess.Popen(
        [*CLI, "run", str(mission), "--port", port, "--record", str(record), "--display", "log",
         *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=None if ignoring is None else lambda: signal.signal(ignoring, signal.SIG_IGN),
    )  # fmt: skip


#: Frames the robot sent after the run's first Drive, in its record, before a test takes the
#: run for driving on (its tick loop running, the stream coming): 75 ms of the stream. Before,
#: a fixed 0.3 s after the Drive was seen, which the record (flushed every 0.25 s) had mostly
#: passed already, and which a loaded machine could pass with no frame read.
FRAMES_DRIVING = 5


def _frames_after_the_first_drive(record: Path) -> int:
    """Frames read after the record's first Drive (-1 before it has one)."""
    text = record.read_text() if record.exists() else ""
    drive = text.find('"out", "b": "89')
    return -1 if drive < 0 else text.count('"d": "in"', drive)


def _wait_for_driving(record: Path, proc: subprocess.Popen[str] | None = None) -> None:
    """Until the run's record has its first Drive and :data:`FRAMES_DRIVING` frames after it
    (it drives on); fails at once with what ``proc`` said if it ended first."""
    deadline = time.monotonic() + HANG_S
    while time.monotonic() < deadline:
        if _frames_after_the_first_drive(record) >= FRAMES_DRIVING:
            return
        if proc is not None and proc.poll() is not None:
            out, err = proc.communicate(timeout=HANG_S)  # a child of its may hold its pipes
            raise AssertionError(f"the run ended (exit {proc.returncode}) before it drove: "
                                 f"{out}{err}")  # fmt: skip
        time.sleep(0.05)
    raise AssertionError(f"the run never started driving in {HANG_S:g} s")


def _driving(port: str, tmp_path: Path) -> tuple[subprocess.Popen[str], Path]:
    """A run spinning for ever on ``port``, once it drives; its record's path."""
    record = tmp_path / "run.jsonl"
    proc = _start_run(port, write_mission(tmp_path, SPIN), record)
    _wait_for_driving(record, proc)
    return proc, record


@pytest.mark.parametrize(
    "signum",
    [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGTSTP, signal.SIGQUIT],
    ids=lambda s: s.name,
)
def test_signal_ends_with_the_safe_stop_and_exit_130(
    sim_port: str, tmp_path: Path, signum: int
) -> None:
    proc, record = _driving(sim_port, tmp_path)
    proc.send_signal(signum)
    out, err = ended(proc)
    assert proc.returncode == 130, err
    assert "INTERRUPTED" in out
    if signum != signal.SIGHUP:  # a key's signal, named as either sender sends it
        assert f"INTERRUPTED ({signal_reason(signum)}" in out, out
    assert ends_with_the_safe_stop(load_record(record).outbound)


def _still_running(proc: subprocess.Popen[str], record: Path) -> bool:
    """Whether the run goes on: its record grows by 20 lines (about 0.3 s of the robot's
    frames) before it ends."""
    lines = record.read_text().count("\n") + 20
    deadline = time.monotonic() + HANG_S
    while proc.poll() is None and time.monotonic() < deadline:
        if record.read_text().count("\n") >= lines:
            return proc.poll() is None
        time.sleep(0.02)
    return False


def test_a_run_started_by_nohup_outlives_a_hang_up(sim_port: str, tmp_path: Path) -> None:
    """``nohup roomba-bt run ... &`` over SSH: the hang-up when the session drops is ignored,
    as nohup set it, and the run goes on (it ended, exit 130, 'SIGHUP: the terminal was
    closed'); SIGTERM still ends it with the safe stop."""
    record = tmp_path / "run.jsonl"
    proc = _start_run(sim_port, write_mission(tmp_path, SPIN), record, ignoring=signal.SIGHUP)
    _wait_for_driving(record, proc)
    proc.send_signal(signal.SIGHUP)
    assert _still_running(proc, record), ended(proc)
    proc.send_signal(signal.SIGTERM)
    out, err = ended(proc)
    assert proc.returncode == 130, err
    assert "INTERRUPTED (SIGTERM)" in out and "SIGHUP" not in out + err
    assert ends_with_the_safe_stop(load_record(record).outbound)


def test_the_terminal_closing_ends_with_the_safe_stop_and_exit_130(
    sim_port: str, tmp_path: Path
) -> None:
    """An SSH session to the robot's computer drops: the run's terminal goes, SIGHUP comes,
    and writes to the terminal fail. The robot was left driving (SIGHUP's default ended the
    process; the OI has no command timeout); now it is stopped, and the exit code says so."""
    import pty

    record = tmp_path / "run.jsonl"
    mission = write_mission(tmp_path, SPIN)
    pid, terminal = pty.fork()
    if pid == 0:  # the run, its terminal the pty's (the live display draws on it)
        os.execv(sys.executable, [*CLI, "run", str(mission), "--port", sim_port, "--record",
                                  str(record)])  # fmt: skip

    def read_the_screen() -> None:  # as a terminal does: a full pty would block the run
        with contextlib.suppress(OSError):
            while os.read(terminal, 4096):
                pass

    reader = threading.Thread(target=read_the_screen, daemon=True)
    reader.start()
    try:
        _wait_for_driving(record)
    finally:
        os.close(terminal)  # the terminal goes: SIGHUP to the run's session
    assert reaped(pid, "the run, its terminal gone") == 130
    assert ends_with_the_safe_stop(load_record(record).outbound)


@pytest.mark.parametrize("gap", [0.0, 0.002, 0.02])
def test_a_second_ctrl_c_waits_for_the_safe_stop_and_the_summary(
    sim_port: str, tmp_path: Path, gap: float
) -> None:
    proc, record = _driving(sim_port, tmp_path)
    proc.send_signal(signal.SIGINT)
    time.sleep(gap)  # the second one lands in the unwinding, the stop or the summary
    proc.send_signal(signal.SIGINT)
    out, err = ended(proc)
    assert proc.returncode == 130, out + err
    assert "outcome      INTERRUPTED (Ctrl-C or kill -INT (SIGINT))" in out
    # a spinning run on the wall clock: drive 0 and motors off went out before the tree's
    # stop; or, on a machine so loaded that the simulator's own process sent nothing for a
    # while before the stop, the stop honestly said unconfirmed (the record's bytes below
    # show it was written all the same)
    confirmed = (
        "safe stop    drive 0, motors off before the tree's stop, then sent drive, motors, "
        "pause_resume_stream, start"
    ) in out
    starved = (
        "safe stop    NOT DELIVERED: " in out
        and "unconfirmed: the robot had sent no valid frame for" in out
    )
    assert confirmed or starved, out
    assert "Traceback" not in err
    assert ends_with_the_safe_stop(load_record(record).outbound)


def test_success_over_the_pty(sim_port: str, tmp_path: Path) -> None:
    record = tmp_path / "run.jsonl"
    mission = write_mission(
        tmp_path,
        """
        tree:
          sequence:
            - mode: safe
            - drive: {velocity: 200 mm/s, distance: 20 cm}
        """,
    )
    proc = _start_run(sim_port, mission, record)
    out, err = ended(proc)
    assert proc.returncode == 0, err
    assert "SUCCESS" in out
    outbound = load_record(record).outbound
    assert ends_with_the_safe_stop(outbound)
    # The replay of that record decides the same, byte for byte.
    replay = finished([*CLI, "replay", str(record)])
    assert replay.returncode == 0, replay.stderr
    assert "the tree wrote the same" in replay.stdout


def test_a_run_whose_watchdog_stopped_the_wheels_over_the_pty_replays_byte_for_byte(
    served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    """The robot's stream pauses half a second: the watchdog's drive 0, the stall ridden
    through, the spin again. The replay does each again and writes the same bytes; before,
    it ran no watchdog: 'first difference ... expected Drive (137) 89 00 00 00 00, sent
    nothing', exit 1, for every run with a stall (every run over a noisy cable).

    The gap comes 1.5 s after the run started the stream (``--faults-from-stream``): at 1.5 s
    of the simulator's own clock it had passed before a run slow to start (its imports on a
    loaded machine) opened the port, and no stall happened.

    On a loaded machine the simulator's process may itself be kept from running past the
    watchdog (100 ms): a stall more, which the run rides through and the replay does again
    as well; so the gap's stall is one of one or more, each ridden through. The run and
    the replay are waited for until they end (:func:`~.simrun.ended`; a run's start took
    over 10 s under load, and 30 s bounded it and the replay before)."""
    sim = served_sim(
        "--pty", "--stream-gap-at", "1.5", "--stream-gap-s", "0.5", "--faults-from-stream"
    )
    record = tmp_path / "run.jsonl"
    proc = _start_run(sim.address, write_mission(tmp_path, SPIN), record, "--timeout", "3s")
    out, err = ended(proc)
    assert proc.returncode == 1, err  # its timeout
    stalls = re.search(r"stalls +(\d+) \(watchdog drive 0\), (\d+) ridden through", out)
    assert stalls is not None and int(stalls[1]) >= 1 and stalls[1] == stalls[2], out
    replay = finished([*CLI, "replay", str(record)])
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "the tree wrote the same" in replay.stdout


def test_a_run_that_followed_a_baud_change_over_the_pty_replays_byte_for_byte(
    served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    """The robot changes its rate mid-run (a battery swap): the run follows it, stops it
    there and ends, exit 8. Its replay listened at the new rate 15 ms short of the live
    run's window (the live port settles a slot first), wrote the drive 0 a frame early (a
    difference), then its safe stop's wait for a quiet line read for ever at the record's
    end, its clock stuck at a float's last bit, deaf to Ctrl-C and SIGTERM. Now the replay
    switches where the record notes the switch, and writes the same bytes."""
    sim = served_sim("--pty", "--baud-change-at", "1.5", "--faults-from-stream")
    record = tmp_path / "run.jsonl"
    proc = _start_run(sim.address, write_mission(tmp_path, SPIN), record, "--timeout", "5s")
    out, err = ended(proc)
    assert proc.returncode == 8, out + err
    assert "the robot now talks at another baud rate: 19200" in out
    replay = finished([*CLI, "replay", str(record)])
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "the tree wrote the same" in replay.stdout
    # its stop confirmed, or not, as the live run's was (a loaded machine's live run may
    # have read frames past the quiet it waits for at the new rate)
    stop = next(line for line in out.splitlines() if line.startswith("safe stop"))
    assert stop in replay.stdout, replay.stdout


def test_timeout_over_the_pty_is_exit_1(sim_port: str, tmp_path: Path) -> None:
    record = tmp_path / "run.jsonl"
    proc = _start_run(sim_port, write_mission(tmp_path, SPIN), record, "--timeout", "1s")
    out, err = ended(proc)
    assert proc.returncode == 1, err
    assert "TIMEOUT" in out
    assert ends_with_the_safe_stop(load_record(record).outbound)


def _run_on(port: str, tmp_path: Path, *options: str) -> subprocess.CompletedProcess[str]:
    return finished([*CLI, "run", str(write_mission(tmp_path, SPIN)), "--port", port, *options])


def test_the_simulator_killed_mid_run_is_the_port_gone_and_the_stop_said_undelivered(
    served_sim: Callable[..., Any], tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The simulator on a pty killed: exit 8 naming the port gone, the stop reported
    undeliverable with what the robot was last seen doing, logged once (close() tries the
    stop again)."""
    sim = served_sim("--pty")
    proc, record = _driving(sim.address, tmp_path)
    sim.proc.kill()
    sim.proc.communicate(timeout=HANG_S)  # its pipes closed
    out, err = ended(proc)
    assert proc.returncode == 8, err
    assert "the port is gone" in err
    _the_record_view_says_no_stop_of_its_own(record, caplog)
    report = "last seen in Safe spinning left at 100 mm/s; the stop was not delivered"
    assert f"NOT DELIVERED: {report}: the port is gone" in out
    assert err.count(report) == 1, err
    assert "Traceback" not in err
    # in a hobbyist's words, and what to do now (pyserial's words alone said neither); a
    # pty's words, the outcome's as the advice's: it said "the cable was pulled or the
    # adapter reset" of a simulator that was killed
    gone = "the port is gone (the program at its other end, the simulator or a bridge such as "
    assert gone in err and "outcome      CONNECTION LOST (" + f"{sim.address}: {gone}" in out
    assert "cable" not in out + err, (out, err)
    advice = "the robot may still be moving: pick it up or press its Clean or power button"
    # a pty's own path never comes back (its number, reused, is another program's line):
    # neither reopened for the stop nor handed to doctor, which would talk to that program
    assert f"{advice}; {sim.address} will not come back (a pty's number goes to " in out
    assert "start the simulator or bridge again and use the path it prints" in out
    assert "roomba-bt doctor" not in out and "reseat" not in out
    assert "came back" not in out


def _the_record_view_says_no_stop_of_its_own(
    record: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``roomba-bt monitor RECORD`` of that run's record (its replay into the page's feed, as
    the command does it): the view says the recorded run lost its link; the replay's own
    stop, written to no robot with nothing recorded past the loss to confirm it, printed
    "ERROR ... last seen in Safe spinning left at 100 mm/s; the stop was written but is
    unconfirmed" on stderr, which docs/monitor.md says nothing of."""
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.run_cmd import load_recorded
    from roomba_bt.monitor.recorded import replay_into_feed

    recorded = load_recorded(build_parser().parse_args(["monitor", str(record)]))
    assert not isinstance(recorded, int)
    caplog.clear()
    feed, _ = replay_into_feed(
        recorded.record, recorded.mission, recorded.profile, recorded.packets, recorded.baud,
        str(record),
    )  # fmt: skip
    assert (feed.finished or "").startswith("the recorded run lost its link"), feed.finished
    said = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert not any("unconfirmed" in text or "not delivered" in text for text in said), said


def test_a_port_that_comes_back_within_the_grace_gets_the_stop_not_the_mission(
    served_sim: Callable[..., Any], tmp_path: Path
) -> None:
    """A loose connector: the device path (a link, as ``/dev/serial/by-id/...`` is) fails
    mid-drive and is there again within the grace. The run still ends as a lost port (the
    mission is not carried on), and the stop goes out through the port that came back, where
    the robot hears it."""
    first, second = served_sim("--pty"), served_sim("--pty", "--log")
    port = tmp_path / "robot"
    port.symlink_to(first.address)
    proc, _ = _driving(str(port), tmp_path)
    first.proc.kill()
    first.proc.communicate(timeout=HANG_S)
    back = tmp_path / "robot.back"
    back.symlink_to(second.address)
    back.replace(port)  # the adapter back, at the same path
    out, err = ended(proc)
    assert proc.returncode == 8, err
    assert "CONNECTION LOST" in out and "the cable was pulled or the adapter reset" in out
    assert re.search(
        r"safe stop    sent drive, motors, pause_resume_stream, start \(the port came back "
        r"after \d+\.\d\d s: the robot heard the stop written through it\)",
        out,
    ), out
    assert "final mode   Passive" in out
    _, said = second.stop(signal.SIGINT)
    assert "heard Start (128)" in said and "mode Passive, wheels 0/0 mm/s" in said, said


@pytest.fixture
def bridge(served_sim: Callable[..., Any]) -> Iterator[tuple[ResettingBridge, Any]]:
    """A Wi-Fi bridge that can reset (:class:`ResettingBridge`) in front of the simulator's
    TCP server (its log on), and the simulator."""
    sim = served_sim("--tcp", "127.0.0.1:0", "--log")
    proxy = ResettingBridge(sim.address)
    yield proxy, sim
    proxy.close()


@pytest.mark.parametrize(
    ("fault", "said", "came_back"),
    [
        pytest.param(
            lambda proxy: proxy.reset(down_s=0.3),
            re.escape("the bridge closed the connection or the network dropped"),
            "the connection came back after",
            id="it resets",
        ),
        pytest.param(
            ResettingBridge.go_silent,
            # the seconds measured: the grace's 2.0 s, more when the run looked late (a
            # loaded machine: "2.1 s" failed this test when it named 2.0 alone)
            r"the connection went silent: not a byte came through it for (?P<silent>\d+\.\d) s",
            "the connection, silent, was closed; a new one came after",
            id="it goes silent without closing",
        ),
    ],
)
def test_a_bridge_that_drops_the_run_gets_the_stop_through_a_new_connection(
    bridge: tuple[ResettingBridge, Any],
    tmp_path: Path,
    fault: Callable[[ResettingBridge], None],
    said: str,
    came_back: str,
) -> None:
    """An ESP8266 bridge reboots mid-drive and takes clients again 0.3 s later: it resets
    both connections, or (off the Wi-Fi, no reset reaching the run) leaves the run's open
    and silent, which the run takes for dead once the grace is over with not a byte. A new
    connection reaches the same robot, which drove on in Safe: the stop goes through it, as
    through a device path that came back, and the mission is not carried on (docs/robot.md,
    Losing the link). Before, a reset ended the run at once, "reseat the cable", and a
    silent bridge had the stop written into it and said "unconfirmed": the robot drove on."""
    proxy, sim = bridge
    proc, _ = _driving(proxy.url, tmp_path)
    fault(proxy)
    out, err = ended(proc)
    assert proc.returncode == 8, err
    seen = re.search(said, out)
    assert seen, out
    assert float(seen.groupdict().get("silent", "2.0")) >= 2.0  # dead once the grace is over
    assert re.search(
        r"safe stop    sent drive, motors, pause_resume_stream, start \("
        + re.escape(came_back)
        + r" \d+\.\d\d s: the robot heard the stop written through it\)",
        out,
    ), out
    assert "final mode   Passive" in out
    assert proxy.clients == 2  # the run's connection, then the stop's
    if "silent" in came_back:  # docs/robot.md's, its seconds the page's example's
        assert_quoted("docs/robot.md", "safe stop sent drive, motors, pause_resume_stream, start (",
                      out, numbers=True)  # fmt: skip
    _, logged = sim.stop(signal.SIGINT)
    assert "turned a second client away" not in logged  # the same robot took the new one
    assert logged.count("mode: Off->Passive") == 1, logged  # ... not started again
    assert "mode: Safe->Passive (start)" in logged and "mode Passive, wheels 0/0 mm/s" in logged


def test_a_bridge_that_stays_down_past_the_grace_is_said_in_the_network_s_words(
    bridge: tuple[ResettingBridge, Any], tmp_path: Path
) -> None:
    """The bridge does not come back within the grace: the stop is not delivered, and what
    to do is said for a bridge (wait for it, then doctor), not for a cable. The doctor run
    then (on the simulator's own address: the bridge back) says it found the robot driving
    and that its Start stopped it."""
    proxy, sim = bridge
    proc, _ = _driving(proxy.url, tmp_path)
    proxy.reset(down_s=30.0)
    out, err = ended(proc)
    assert proc.returncode == 8, err
    assert "NOT DELIVERED" in out and "the connection did not come back within 2 s" in out
    where = proxy.url.removeprefix("socket://")
    assert (
        f"wait for the bridge at {where} to come back (it reset, or the Wi-Fi dropped), then "
        f"roomba-bt doctor --port {proxy.url}"
    ) in out
    assert "cable" not in out
    doctor = finished([*CLI, "doctor", "--port", sim.address])
    assert re.search(
        r"\[warn\] left +a stream was running when doctor came in Safe, its wheels turning: a "
        r"run's stop did not reach the robot, which drove on; doctor's Start \(128\) has "
        r"stopped it",
        doctor.stdout,
    ), doctor.stdout
    _, said = sim.stop(signal.SIGINT)
    assert "mode Passive, wheels 0/0 mm/s" in said, said


def test_no_robot_on_the_port_is_exit_3(tmp_path: Path, silent_port: str) -> None:
    result = _run_on(silent_port, tmp_path)
    assert result.returncode == 3
    assert "did not answer" in result.stderr
    assert "Traceback" not in result.stderr


def test_missing_port_is_exit_3(tmp_path: Path) -> None:
    result = _run_on("/dev/does-not-exist", tmp_path)
    assert result.returncode == 3
    assert "/dev/does-not-exist" in result.stderr
    assert "Traceback" not in result.stderr
    # the summary as every other ending has it: a cron job's log had no outcome line
    assert "outcome      NO CONNECTION (/dev/does-not-exist: could not open" in result.stdout
    assert "safe stop    nothing sent: the port was not opened" in result.stdout


def test_no_robot_at_any_rate_has_its_summary_and_names_its_port(
    tmp_path: Path, silent_port: str
) -> None:
    """``--baud auto`` finding no robot was one line on stderr, with no summary (no
    ``outcome`` line for the evening's reader of a cron job's log to find), a hint to run
    ``doctor --port URL``, and a pty's hang-up called "a BRC pulse"."""
    result = _run_on(silent_port, tmp_path, "--baud", "auto")
    assert result.returncode == 3, result.stderr
    assert "outcome      NO CONNECTION (" in result.stdout
    assert "--baud auto: no answer at any OI rate" in result.stdout
    assert "safe stop    nothing of the mission sent, only the probe's" in result.stdout
    assert_quoted("docs/doctor.md", "outcome NO CONNECTION", result.stdout)
    assert_quoted("docs/doctor.md", "safe stop nothing of the mission sent", result.stdout)
    assert f"run roomba-bt doctor --port {silent_port} for each step" in result.stderr
    assert "URL" not in result.stderr
    assert "(the last 2 after the wake: pulsed BRC by a 1 s hang-up (" in result.stderr
    assert "Traceback" not in result.stderr


#: a status change every few ticks: a line of the status log each
BACK_AND_FORTH = """
tree:
  repeat:
    do:
      sequence:
        - mode: safe
        - drive: {velocity: 100 mm/s, distance: 1 cm}
        - drive: {velocity: -100 mm/s, distance: 1 cm}
"""


def _frames_read(record: Path) -> int:
    return record.read_text().count('"d": "in"') if record.exists() else 0


def _fill(pipe: int) -> None:
    """Write into ``pipe`` until it takes no more byte: its next writer blocks. Through a
    non-blocking opening of its own (Linux's /proc): O_NONBLOCK set on ``pipe`` itself would
    be set on the run's stdout or stderr too (one open file), its writes failing, not blocking."""
    filler = os.open(f"/proc/self/fd/{pipe}", os.O_WRONLY | os.O_NONBLOCK)
    try:
        with contextlib.suppress(BlockingIOError):
            while True:
                os.write(filler, b"x")
    finally:
        os.close(filler)


@pytest.mark.parametrize("display", ["tree", "log"])
def test_a_terminal_that_stops_reading_does_not_hold_up_the_run(
    sim_port: str, tmp_path: Path, display: str
) -> None:
    """An SSH session on a stalled network: the terminal takes nothing, its buffer fills, and
    every write to it blocks. The live tree and the status log were written from the tick
    loop, which then stopped reading frames with the robot driving on (a 4 KiB buffer held a
    run after about a second). Now they are written off the loop: the run reads on.

    Once the run reads frames, the test fills the terminal's buffer to the last byte, so the
    display's next write blocks (the tree is redrawn, the log gets a line, several times a
    second); the run must then read 3 s more of stream (200 frames) while nothing drains it."""
    import fcntl

    record = tmp_path / "run.jsonl"
    mission = write_mission(tmp_path, SPIN if display == "tree" else BACK_AND_FORTH)
    read_end, write_end = os.pipe()
    fcntl.fcntl(write_end, 1031, 4096)  # F_SETPIPE_SZ: a terminal's few KiB, never read
    quiet = subprocess.DEVNULL
    out, err = (write_end, quiet) if display == "tree" else (quiet, write_end)
    proc = subprocess.Popen(
        [*CLI, "run", str(mission), "--port", sim_port, "--record", str(record), "--display",
         display],
        stdout=out, stderr=err,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + HANG_S
        while _frames_read(record) == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        _fill(write_end)
        filled_at = _frames_read(record)
        assert filled_at > 0, "the run never read a frame"
        frames = filled_at
        deadline = time.monotonic() + HANG_S  # the 200 frames' own: 3 s unloaded
        while frames < filled_at + 200 and time.monotonic() < deadline:
            time.sleep(0.1)
            frames = _frames_read(record)
        assert frames >= filled_at + 200, (
            f"the run stopped reading after {frames} reads, {frames - filled_at} after its "
            "terminal's buffer was full"
        )
    finally:
        proc.kill()
        proc.wait(timeout=HANG_S)
        os.close(write_end)
        os.close(read_end)


#: Safe, the brushes and the vacuum on, an arc for ever: a robot busy when the line goes bad
BRUSHING_ARC = """
tree:
  sequence:
    - mode: safe
    - motors: {main_brush: true, side_brush: true, vacuum: true}
    - drive: {velocity: 200 mm/s, radius: -600 mm}
"""


def _lines_of(path: Path) -> list[str]:
    return path.read_text(errors="replace").splitlines() if path.exists() else []


def _wait_for_any(watched: dict[Path, str], proc: subprocess.Popen[str], count: int) -> str:
    """The first line of a watched file that matches its pattern ``count`` times (the first
    file's first match is enough), waiting while ``proc`` runs; "" if it ended first."""
    deadline = time.monotonic() + HANG_S
    while proc.poll() is None and time.monotonic() < deadline:
        for number, (path, pattern) in enumerate(watched.items()):
            hits = [line for line in _lines_of(path) if re.search(pattern, line)]
            if len(hits) >= (1 if number == 0 else count):
                return hits[-1]
        time.sleep(0.002)
    return ""


def test_ctrl_c_on_a_noisy_line_leaves_the_robot_stopped_in_passive(tmp_path: Path) -> None:
    """The line flips a bit in 5 % of the robot's bytes; the watchdog trips again and again.
    Before, each trip switched the port to 19200 to listen there, right after its drive 0
    (which the robot then got at the wrong rate: ``ignored 5 byte(s)``), and a Ctrl-C in
    that listen left the port there: the whole safe stop went out at 19200 and the robot
    drove on in Safe, brushes and vacuum on (10 runs of 10). Now the robot's damaged frames
    show it talks at the run's rate: no listen elsewhere, every drive 0 heard, and the stop
    goes at its rate. Ctrl-C comes at the first sign of a listen, or at the third stall."""
    sim_log, run_log = tmp_path / "sim.err", tmp_path / "run.err"
    with sim_log.open("w") as sim_err:
        sim = subprocess.Popen(
            [*CLI, "sim", "--pty", "--log", "--bit-flip-rate", "0.05", "--seed", "1"],
            stdout=subprocess.PIPE, stderr=sim_err, text=True,
        )  # fmt: skip
    try:
        assert sim.stdout is not None
        port = line(sim.stdout, "the simulator's pty").strip()
        record = tmp_path / "run.jsonl"
        with run_log.open("w") as run_err:
            proc = subprocess.Popen(
                [*CLI, "run", str(write_mission(tmp_path, BRUSHING_ARC)), "--port", port,
                 "--record", str(record), "--display", "log", "-v"],
                stdout=subprocess.PIPE, stderr=run_err, text=True,
            )  # fmt: skip
        seen = _wait_for_any(
            {
                sim_log: r"ignored \d+ byte",  # the old listen's lost drive 0
                run_log: r"listening at 19200|waiting up to 2 s for valid frames",
            },
            proc,
            count=3,
        )
        assert seen, "no watchdog trip on the noisy line"
        proc.send_signal(signal.SIGINT)
        out, _ = ended(proc)
        assert proc.returncode == 130, out + run_log.read_text()
    finally:
        if sim.poll() is None:
            sim.send_signal(signal.SIGINT)
        ended(sim)
    said = sim_log.read_text()
    final = said.strip().splitlines()[-1]
    assert "mode Passive, wheels 0/0 mm/s" in final, final
    assert not [line for line in said.splitlines() if re.search(r"ignored \d+ byte", line)], said
    assert "stalls" in out
    assert SAFE_END in load_record(record).outbound  # then close()'s again, unconfirmed


def _on_a_stream_gap(
    served_sim: Callable[..., Any], tmp_path: Path, **given: Any
) -> tuple[Any, RunStack, Path]:
    """The simulator on a pty whose stream stops 1.5 s in for 3 s, and a run of SPIN on it in
    this process (``RunStack``, ``given`` its settings), recorded: the simulator, the stack
    and the record's path."""
    sim = served_sim(
        "--pty", "--stream-gap-at", "1.5", "--stream-gap-s", "3", "--faults-from-stream"
    )
    source, path = write_mission(tmp_path, SPIN), tmp_path / "run.jsonl"
    stack = RunStack(
        load_mission(source, {}, profile=CREATE2),
        SerialTransport.open(sim.address),
        profile=CREATE2,
        record=Recording(path, str(source)),
        **{"timeout_s": 30.0, **given},
    )
    return sim, stack, path


class CtrlCAtTheTrip(logging.Handler):
    """A Ctrl-C as the watchdog trips (its log line, on the run's own thread)."""

    def emit(self, record: logging.LogRecord) -> None:
        if "waiting up to" in record.getMessage():
            raise KeyboardInterrupt


def _run_with(stack: RunStack, handler: logging.Handler | None) -> RunSummary:
    """``stack``'s run, ``handler`` on the run loop's log meanwhile; the stack closed after."""
    logger = logging.getLogger("roomba_bt.runtime.loop")
    if handler is not None:
        logger.addHandler(handler)
    try:
        return stack.run(raise_interrupts=False)
    finally:
        if handler is not None:
            logger.removeHandler(handler)
        stack.close()


@pytest.mark.parametrize("by", ["stack.stop", "Ctrl-C"])
def test_a_run_stopped_in_a_stall_over_the_pty_replays_byte_for_byte(
    served_sim: Callable[..., Any], tmp_path: Path, by: str
) -> None:
    """A run on a robot's port stopped while the watchdog rode a stall (the monitor's Stop,
    ``stack.stop()``), or interrupted there: the stop, written into the stream's gap, is not
    confirmed, and the run asks after it with a Query List (``discovery.probe``, written
    past the link). The end note's ``written`` was the link's count translated to the
    record's, which missed the probe's bytes: it said 5 bytes more than the run had written
    when it was stopped, and the replay waited for them inside the stall: "first difference
    ... expected Drive (137) 89 00 00 00 00, sent nothing", exit 1, of a faithful record.
    The note holds the record's own count at the stop, whoever wrote since.

    The run is in this process, on the pty, so that its stop is asked as the watchdog
    trips (on the run's own thread): the stall is the stop's, whatever the machine's load."""
    _, stack, path = _on_a_stream_gap(served_sim, tmp_path)
    at_the_stop: list[int] = []  # the link's count there: what an older roomba-bt noted

    class StopAtTheTrip(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if "waiting up to" in record.getMessage():
                at_the_stop.append(stack.connection.link.bytes_written)
                stack.stop("stopped by the test")

    summary = _run_with(stack, StopAtTheTrip() if by == "stack.stop" else CtrlCAtTheTrip())
    assert summary.outcome.name == "INTERRUPTED", summary.reason
    record = load_record(path)
    ending = record.ending
    assert ending is not None, record
    # the note's count ends at the stall's drive 0, the safe stop next; past it the stop,
    # unconfirmed in the gap, was asked after with a Query List (which it counted too)
    written, outbound = ending["written"], record.outbound
    assert outbound[:written].endswith(oi.halt().data), (written, outbound.hex())
    assert outbound[written:].startswith(oi.halt().data + oi.motors_off().data), outbound.hex()
    assert PROBE_QUERY in outbound[written:], summary.safe_stop
    replay = finished([*CLI, "replay", str(path)])
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "first difference" not in replay.stdout, replay.stdout
    assert "miscount" not in replay.stdout, replay.stdout
    if by == "stack.stop":
        _an_older_records_count_is_said_as_its_miscount(path, stack, at_the_stop[0])


def _an_older_records_count_is_said_as_its_miscount(
    path: Path, stack: RunStack, at_the_stop: int
) -> None:
    """The same record, its end note's count as roomba-bt wrote it before 2e6d3655 (the link's
    count at the stop, moved on at the end by what the link alone wrote since: the probe's
    Query List, written past the link after the stop, among it): its replay waited for
    bytes that came after the stop, "first difference ... expected Drive (137) 89 00 00 00
    00, sent nothing", exit 1. It is said as that record's known miscount, and the replay
    ends at the stop, byte for byte."""
    record = load_record(path)
    written = record.ending["written"] if record.ending else None
    since = stack.connection.link.bytes_written - at_the_stop
    old_count = record.out_bytes - since  # RunStack._written_when_interrupted, until then
    assert isinstance(written, int) and old_count == written + len(PROBE_QUERY), old_count
    old = path.with_name("older.jsonl")
    note = f'"written": {written}}}'
    old.write_text(path.read_text().replace(note, f'"written": {old_count}}}'))
    replay = finished([*CLI, "replay", str(old)])
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "first difference" not in replay.stdout, replay.stdout
    assert (
        f"replay: the end note counts {old_count} bytes written when the recorded run was "
        f"stopped, {old_count - written} more than the {written} it wrote before its stop: a "
        "known miscount of records made by a roomba-bt 0.2.0 development build before its "
        "stall-stop fix"
    ) in replay.stdout, replay.stdout
    assert "not a difference in behaviour" in replay.stdout
    assert_quoted(
        "docs/runtime.md", "replay: the end note counts 38 bytes", replay.stdout, numbers=True
    )


@pytest.mark.parametrize("stop", ["confirmed", "asked after"])
def test_end_in_stop_leaves_the_simulator_in_off_and_says_so(
    served_sim: Callable[..., Any], tmp_path: Path, stop: str
) -> None:
    """``end_in="stop"`` on a pty: a Stop the stream's quiet confirms (the run's time limit,
    frames coming), and one it cannot (a Ctrl-C while the watchdog rides the stream's gap:
    the robot silent before it), which is asked after: that needs Start (Off answers
    nothing), the robot answers in Passive and Stop is written again. The robot ends in Off
    either way, as the summary says; the second was left in Passive, the summary saying
    ``final mode Off``. Each record replays byte for byte."""
    confirmed = stop == "confirmed"  # the run's time limit, before the gap
    timeout = 1.0 if confirmed else 30.0
    sim, stack, path = _on_a_stream_gap(served_sim, tmp_path, timeout_s=timeout, end_in="stop")
    summary = _run_with(stack, None if confirmed else CtrlCAtTheTrip())
    _, said = sim.stop()
    assert "mode Off, wheels 0/0" in said, said  # the simulator's own word at its end
    assert summary.stop_delivered and summary.final_mode_text() == "Off", summary.safe_stop
    outbound = load_record(path).outbound
    again = "the Stop (173) was not confirmed at first" in summary.safe_stop
    assert again is (stop == "asked after"), summary.safe_stop
    assert (PROBE_QUERY in outbound) is again and outbound.endswith(oi.stop().data)
    replay = finished([*CLI, "replay", str(path)])
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "final mode   Off" in replay.stdout, replay.stdout
    if again:
        said_by_the_run = "\n".join(summary.lines())
        assert_quoted("docs/robot.md", "final mode Off$", said_by_the_run)
        assert_quoted(
            "docs/runtime.md",
            "safe stop sent drive, motors, pause_resume_stream, stop (",
            said_by_the_run,
        )
