"""``roomba-bt doctor`` against the simulator served on a pty and on RFC 2217, at both OI
rates, awake and asleep, as three robot models; against a pty nobody answers; and
``--baud auto`` for ``run`` and ``sensors``. Every run is a subprocess waited for until it
ends (tests/waits.py's ``ended``: a doctor still running at :data:`COMMAND_WAIT_S` is sent
SIGTERM and fails the test). No test reads the wall clock: the 10 s acceptance bar of a
line with nothing behind it, :data:`DOCTOR_TIMEOUT_S`, is read off doctor's own clock, the
link's, on a line of a clock of its own (:class:`_NobodyThere`)."""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import re
import subprocess
import sys
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from runtime.simrun import BridgeLink  # tests/runtime: a WiFi bridge on the virtual clock
from waits import HANG_S, ended  # tests/waits.py: a child's end, no fixed bet

import roomba_bt.transport as transport_package
from roomba_bt.cli.doctor_cmd import (
    CABLE_FIXES,
    PTY_FIXES,
    Report,
    _examine,
    _Failed,
    _link_fix,
    _status,
    _status_failed,
    _stream,
    doctor_command,
)
from roomba_bt.oi import commands as oi
from roomba_bt.oi.profiles import CREATE2, ROOMBA600
from roomba_bt.runtime.summary import ExitCode
from roomba_bt.sim import Faults, SimLink, Simulator, load_world
from roomba_bt.transport import SerialTransport, TransportError
from roomba_bt.transport.link_kind import link_of

#: The acceptance bar: nothing behind the port, doctor's own waits (each read, the wake
#: pulse, the settling after it, all on the link's clock) end within 10 s. It was measured
#: on the wall clock, from doctor's first line to its exit, which a loaded machine stretches
#: (a timing, not a behaviour): it is read off a line with a clock of its own now.
DOCTOR_TIMEOUT_S = 10.0
#: The most a command is waited for: it ends as soon as it is done, so this bounds only one
#: that never will. The 10 s bar as every command's timeout failed doctors under load (two
#: busy loops on 2 cores: "timed out after 10.0 seconds" at its 1 s hang-up pulse), and
#: subprocess.run's SIGKILL left the pty in the kernel's exclusive mode (a process killed
#: outright cannot clear it: transport/serial_port.py), which refuses the next open of it
#: as "another program has it open" while the simulator lives.
COMMAND_WAIT_S = HANG_S
#: What a robot whose checksum covers the header and reports the mode as is may be, with no
#: Reset tried: a 600 on firmware without the mode + 1 bug, or a 500, which may sum the
#: header too (its profile takes both rules).
CREATE2_OR_500 = "iRobot Create 2 (or a Roomba 600 series or Roomba 500 series, by its label)"
#: The profile step's line for such a robot: the default, the others for an owner's label.
CREATE2_OR_500_STEP = (
    "[ok]   profile   iRobot Create 2 (--profile create2, the default), or a Roomba 600 "
    "series (--profile roomba600) or a Roomba 500 series (--profile roomba500) if its label "
    "says so: "
)


def _started(*args: str) -> subprocess.Popen[str]:
    """``roomba-bt ARGS`` started, its output read through text pipes."""
    return subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    """``roomba-bt ARGS`` run to its end."""
    with _started(*args) as proc:
        out, err = ended(proc, COMMAND_WAIT_S)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _doctor(port: str, *extra: str) -> subprocess.CompletedProcess[str]:
    done = _cli("doctor", "--port", port, *extra)
    assert "Traceback" not in done.stderr + done.stdout
    return done


def _step(out: str, step: str) -> list[str]:
    """The lines of one step (``[ok]   baud ...``), without the mark's padding."""
    return [line for line in out.splitlines() if line[7:].startswith(f"{step:<10}")]


@pytest.mark.parametrize("baud", [19200, 115200])
def test_doctor_finds_an_awake_create2_on_a_pty_at_either_rate(
    served_sim: Callable[..., Any], baud: int
) -> None:
    sim = served_sim("--pty", "--baud", str(baud))
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.OK, done.stdout
    out = done.stdout
    assert f"found: {CREATE2_OR_500} on {sim.address} at {baud} baud, Passive, battery " in out
    assert "not charging" in out.splitlines()[-1]
    assert _step(out, "wake") == ["[--]   wake      not needed: the robot answered"]
    if baud == 19200:
        assert "[--]   baud      115200: nothing" in out, "115200 is tried first"
    assert f"[ok]   baud      {baud}: answered [1, 0, 0]" in out
    # a Create 2 owner is not warned: the default, the 600 and the 500 named for an owner
    # whose label says so (a [warn] advising --profile roomba500 met every Create 2)
    assert CREATE2_OR_500_STEP in out
    assert "[ok]   mode      Passive (35 = 1, as is)" in out
    assert any(" 0 bytes skipped" in line for line in _step(out, "stream"))
    missions = _step(out, "missions")[0]
    if baud == 19200:
        assert missions.startswith("[warn]") and "carries 28 bytes at 19200 baud" in missions
        assert "too big: " in missions and "patrol 59" in missions
        # the robot's own way back to 115200, and where Baud (129) can be sent from
        fix = out.split(missions)[1].splitlines()[1]
        # the models not told apart that share a procedure named together, said once
        assert "on the iRobot Create 2 or Roomba 600 series, 19200 comes after its Clean " \
            "button was held while it powered off" in fix  # fmt: skip
        assert fix.count("while it powered off") == 1 and "on the Roomba 500 series" in fix
        assert "Connection.set_baud(115200) sends Baud (129); no roomba-bt command does" in fix
    else:
        assert missions.startswith("[ok]") and missions.endswith("all fit")
    assert "mode Passive" in sim.stop()[1], "the robot is left in Passive"


def test_a_line_losing_a_third_of_the_frames_is_warned_at_run_s_bar_over_a_longer_listen(
    served_sim: Callable[..., Any],
) -> None:
    """``doctor`` said ``[ok]`` to a stream losing 35 % of its frames (it warned below half
    only) while ``run`` calls 5 % a poor link and sends its user to doctor: one bar now
    (``POOR_LINK``), and ``--listen`` samples as long as told."""
    sim = served_sim("--pty", "--drop-rate", "0.3", "--seed", "1")
    done = _doctor(sim.address, "--listen", "2s")
    assert done.returncode == ExitCode.OK, done.stdout  # a warning, not a failure
    [stream] = _step(done.stdout, "stream")
    assert stream.startswith("[warn]") and " in 2 s (one per 15 ms: " in stream, stream
    assert re.search(r"; [2-4]\d % of the frames lost$", stream), stream
    fix = done.stdout.split(stream)[1].splitlines()[1]
    assert "the line loses frames (run calls 5 % or more a poor link)" in fix
    assert "--listen 10s samples longer" in fix


def test_a_clean_line_s_stream_is_ok_over_a_longer_listen(served_sim: Callable[..., Any]) -> None:
    sim = served_sim("--pty")
    done = _doctor(sim.address, "--listen", "2s")
    [stream] = _step(done.stdout, "stream")
    assert stream.startswith("[ok]") and " in 2 s (one per 15 ms: " in stream, stream


@pytest.mark.parametrize("baud", [19200, 115200])
def test_doctor_wakes_an_asleep_robot_by_brc_over_rfc2217_and_names_it(
    served_sim: Callable[..., Any], baud: int
) -> None:
    sim = served_sim("--rfc2217", "127.0.0.1:0", "--asleep", "--baud", str(baud))
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.OK, done.stdout
    out = done.stdout
    assert "[--]   baud      115200: nothing" in out and "[--]   baud      19200: nothing" in out
    assert "[ok]   wake      silent at every rate: pulsed BRC low for 1 s (RTS and DTR)" in out
    assert "[ok]   wake      it answered after the pulse: the robot was asleep" in out
    assert f"found: {CREATE2_OR_500} on {sim.address} at {baud} baud, Passive, battery " in out


@pytest.mark.parametrize("baud", [19200, 115200])
def test_doctor_wakes_an_asleep_robot_on_a_pty_by_a_hang_up_and_names_it(
    served_sim: Callable[..., Any], baud: int
) -> None:
    """A pty's modem lines cannot be set (ENOTTY): the pulse is a 1 s hang-up (speed 0)."""
    sim = served_sim("--pty", "--asleep", "--baud", str(baud))
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.OK, done.stdout
    out = done.stdout
    assert "[--]   baud      115200: nothing" in out and "[--]   baud      19200: nothing" in out
    assert (
        "[ok]   wake      silent at every rate: pulsed BRC by a 1 s hang-up (the modem lines "
        "cannot be set here: speed 0 drops DTR and RTS, the rate's return raises them)"
    ) in out
    assert "[ok]   wake      it answered after the pulse: the robot was asleep" in out
    assert f"found: {CREATE2_OR_500} on {sim.address} at {baud} baud, Passive, battery " in out
    assert "mode Passive" in sim.stop()[1], "the robot is left in Passive"


class _NoHangUp(SerialTransport):
    """A port that refuses speed 0 as well as the modem ioctl (as a Windows port would)."""

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        raise TransportError(self.name, "hang up (set the speed to 0)", "Invalid argument")
        yield


def test_a_port_that_can_neither_set_its_lines_nor_hang_up_says_press_clean_exit_5(
    served_sim: Callable[..., Any],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """In process: the real pty (its ioctl fails) behind a transport whose B0 fails too."""
    sim = served_sim("--pty", "--asleep")
    monkeypatch.setattr(transport_package, "SerialTransport", _NoHangUp)
    code = doctor_command(
        argparse.Namespace(port=sim.address, baud=None, allow_reset=False, listen=None)
    )
    out = capsys.readouterr().out
    assert code == ExitCode.NO_ANSWER, out
    wake = _step(out, "wake")[0]
    assert wake.startswith("[FAIL]") and "cannot pulse BRC" in wake
    assert "Inappropriate ioctl" in wake
    assert "nor by a hang-up" in wake and "Invalid argument" in wake
    assert "fix: a robot asleep (5 minutes in Passive)" in out
    assert "press Clean" in out
    assert "found:" not in out


def test_a_roomba600_is_told_by_its_mode_plus_one(served_sim: Callable[..., Any]) -> None:
    sim = served_sim("--pty", "--profile", "roomba600")
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.OK, done.stdout
    assert "Start (128): Passive; packet 35 reads 2 (this firmware reports the OI mode + 1)" in (
        done.stdout
    )
    assert "[ok]   profile   Roomba 600 series (--profile roomba600)" in done.stdout
    assert "[ok]   mode      Passive (35 = 2, mode + 1 firmware" in done.stdout


def test_with_allow_reset_a_roomba500_is_told_by_its_silence_and_its_checksum(
    served_sim: Callable[..., Any],
) -> None:
    sim = served_sim("--rfc2217", "127.0.0.1:0", "--profile", "roomba500", "--baud", "19200")
    done = _doctor(sim.address, "--allow-reset")
    assert done.returncode == ExitCode.OK, done.stdout
    profile = _step(done.stdout, "profile")[0]
    assert profile.startswith("[ok]   profile   Roomba 500 series (--profile roomba500)")
    assert "ignored Reset (7)" in profile and "leaves the header out" in profile
    assert _step(done.stdout, "firmware") == ["[--]   firmware  no banner (a Roomba 500)"]


@pytest.mark.parametrize(("firmware", "wakes"), [("release-3.6.0", False), ("release-3.8.2", True)])
def test_with_allow_reset_the_banner_gives_the_firmware_and_the_dock_wake(
    served_sim: Callable[..., Any], firmware: str, wakes: bool
) -> None:
    sim = served_sim("--pty", "--firmware", firmware)
    done = _doctor(sim.address, "--allow-reset")
    assert done.returncode == ExitCode.OK, done.stdout
    reset = _step(done.stdout, "reset")[0]
    assert f"last: 'r3_robot/tags/{firmware} CLEAN'" in reset
    line = _step(done.stdout, "firmware")[0]
    if wakes:
        assert line == f"[ok]   firmware  {firmware}: wakes by a BRC pulse on the dock too"
    else:
        assert line.startswith("[warn]") and "does not wake by a BRC pulse on the dock" in line
    assert "printed a banner after Reset (7)" in _step(done.stdout, "profile")[0]


def test_a_pty_with_nothing_behind_it_says_so_and_exits_non_zero(silent_port: str) -> None:
    """Nobody reads the other side of this pty: doctor tries each rate, pulses BRC by a
    hang-up, tries them again and ends, saying so, exit 5 (how long that takes, by doctor's
    own clock: the next test)."""
    done = _doctor(silent_port)
    assert done.returncode == ExitCode.NO_ANSWER, done.stdout
    assert "[--]   baud      115200: nothing" in done.stdout
    assert "[--]   baud      19200: nothing" in done.stdout
    assert _step(done.stdout, "wake")[0].startswith("[ok]"), "a pty can be hung up"
    assert _step(done.stdout, "baud")[-1].startswith("[FAIL]")
    assert "even after a BRC pulse" in done.stdout
    assert "found:" not in done.stdout


class _NobodyThere:
    """A pty's line with nothing behind it, on a clock of its own: a read waits out its
    whole timeout (the clock moves by it) and brings nothing; the modem lines cannot be
    set (ENOTTY, as on a pty), the line can be hung up. Every wait of doctor's is on it."""

    name = "/dev/pts/97"
    wall_clock = False

    def __init__(self) -> None:
        self.clock = 0.0
        self.written: list[bytes] = []
        self.rates: list[int] = []
        self.hang_ups = 0

    def write(self, data: bytes) -> None:
        self.written.append(bytes(data))

    def read(self, timeout: float) -> bytes:
        self.clock += max(0.0, timeout)
        return b""

    def set_baud(self, baud: int) -> None:
        self.rates.append(baud)

    def close(self) -> None:
        pass

    @property
    def is_open(self) -> bool:
        return True

    def now(self) -> float:
        return self.clock

    def set_wake_line(self, low: bool) -> None:
        raise OSError(errno.ENOTTY, "Inappropriate ioctl for device")

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        self.hang_ups += 1
        yield


def test_a_line_with_nothing_behind_it_ends_by_doctor_s_own_deadlines() -> None:
    """The 10 s bar of a silent line, read off doctor's own clock (the link's): each rate
    asked once, one BRC pulse by a hang-up, each rate once more, then the verdict, exit 5,
    all of it within :data:`DOCTOR_TIMEOUT_S` of the clock every wait of doctor's is
    timed by. (It was measured on the wall clock, under a machine's load.)"""
    line = _NobodyThere()
    report = Report(io.StringIO(), link_of(line.name))
    with pytest.raises(_Failed) as failed:  # the step that failed is said; doctor's exit
        _examine(line, (115200, 19200), False, report)
    assert failed.value.code == ExitCode.NO_ANSWER
    out = report.out.getvalue()
    assert line.hang_ups == 1 and "even after a BRC pulse" in out, out
    asked = [data for data in line.written if data.startswith(bytes([149]))]  # Query List
    assert len(asked) == 4, line.written  # two rates, before the pulse and after it
    assert 0 < line.clock <= DOCTOR_TIMEOUT_S, line.clock


def test_a_port_that_does_not_open_is_exit_3_with_what_to_check(tmp_path: Path) -> None:
    """No such device: said with the serial ports present (the cause known, no list of
    guesses); a failure whose error tells nothing more: what to check."""
    done = _doctor(str(tmp_path / "ttyUSB9"))
    assert done.returncode == ExitCode.CONNECTION
    assert "[FAIL] port      could not open" in done.stdout
    assert ": no such device: the cable unplugged, or the adapter has another name" in done.stdout
    assert "(serial ports present: " in done.stdout and "fix:" not in done.stdout
    done = _doctor("hwgrep://^no-such-adapter$")  # pyserial's search by name: no errno
    assert done.returncode == ExitCode.CONNECTION
    assert "fix: check the device path" in done.stdout
    done = _doctor("nosuchscheme://x")  # a URL typo is a usage error (it was exit 3)
    assert done.returncode == 2
    assert "a URL of no scheme pyserial knows" in done.stderr


def test_a_port_that_echoes_is_named_a_loopback_not_a_silent_robot() -> None:
    """loop:// (or a cable with its data lines joined) gives the query back: said at once,
    exit 5, with no BRC pulse and no "is the robot on?"."""
    done = _doctor("loop://")
    assert done.returncode == ExitCode.NO_ANSWER
    assert _step(done.stdout, "baud") == [
        f"[--]   baud      {rate}: the Query List itself back ([149, 3, 35, 21, 34]): "
        "the port echoes"
        for rate in (115200, 19200)
    ]
    assert "[FAIL] port      it gives back every byte written to it: a loopback" in done.stdout
    assert "wake" not in done.stdout


def test_a_bad_baud_is_a_usage_error() -> None:
    done = _cli("doctor", "--port", "/dev/null", "--baud", "1234")
    assert done.returncode == ExitCode.INVALID
    assert "allowed: " in done.stderr and "or auto" in done.stderr


MISSION = """
mission: short
tree:
  sequence:
    - mode: safe
    - wait: 0.3s
"""


def test_run_baud_auto_finds_19200_and_runs(served_sim: Callable[..., Any], tmp_path: Path) -> None:
    sim = served_sim("--pty", "--baud", "19200")
    mission = tmp_path / "short.yaml"
    mission.write_text(textwrap.dedent(MISSION))
    done = _cli(
        "run", str(mission), "--port", sim.address, "--baud", "auto", "--display", "none",
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert "outcome      SUCCESS" in done.stdout
    assert "the robot answers at 19200 baud (--baud auto)" in done.stderr


def test_sensors_baud_auto_finds_19200_and_shows_a_table(served_sim: Callable[..., Any]) -> None:
    sim = served_sim("--pty", "--baud", "19200")
    done = _cli("sensors", "--port", sim.address, "--baud", "auto", "--count", "1")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"{sim.address}  (iRobot Create 2)")
    # every packet: a Query List (149) of group 100 for the table, as the 28 bytes of a
    # 15 ms slot at 19200 stream group 1 alone (7-16: it showed no mode, battery or encoders)
    assert "bumps_wheel_drops" in done.stdout and "unused_16" in done.stdout
    assert "1 passive" in done.stdout and "left_encoder_counts" in done.stdout


def test_baud_auto_with_nothing_behind_the_port_is_a_connection_failure(silent_port: str) -> None:
    done = _cli("sensors", "--port", silent_port, "--baud", "auto", "--count", "1")
    assert done.returncode == 3
    assert "--baud auto: no answer at any OI rate (115200: nothing; 19200: nothing" in done.stderr
    assert "Traceback" not in done.stderr


class _GarbledReplies:
    """The simulator behind a line that garbles the battery charge's high byte in the
    first ``garble`` Query List replies (a reply has no checksum)."""

    def __init__(self, garble: int) -> None:
        from roomba_bt.oi import commands as oi
        from roomba_bt.oi.profiles import CREATE2
        from roomba_bt.sim import SimLink, Simulator, load_world

        self.link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=1))
        self.link.write(oi.start().data)
        self.garble = garble

    def write(self, data: bytes) -> None:
        self.link.write(data)

    def read(self, timeout: float) -> bytes:
        data = self.link.read(timeout)
        if len(data) == 11 and self.garble:  # the status reply: charge's high byte at 5
            self.garble -= 1  # each garbled another way, as noise does
            data = data[:5] + bytes([data[5] ^ (0x10 << self.garble)]) + data[6:]
        return data

    def __getattr__(self, name: str) -> Any:
        return getattr(self.link, name)


@pytest.mark.parametrize(("garbled", "shown"), [(1, "[ok]"), (4, "[FAIL]")])
def test_a_garbled_status_reply_is_asked_again_not_reported_ok(garbled: int, shown: str) -> None:
    """It printed "[ok] battery 65105 of 2696 mAh (2415 %)" from one garbled reply."""
    import io

    from roomba_bt.cli.doctor_cmd import Report, _Failed, _status
    from roomba_bt.oi.profiles import CREATE2

    report = Report(io.StringIO())
    with contextlib.suppress(_Failed):
        _status(_GarbledReplies(garbled), CREATE2, False, report)
    battery = next(line for line in report.out.getvalue().splitlines() if "battery" in line)
    assert battery.startswith(shown), battery
    if shown == "[ok]":
        assert " of 2696 mAh (" in battery and "%)" in battery
        assert int(battery.split(" of ")[0].split()[-1]) <= 2696
    else:
        assert "never agreed twice in a row" in battery


@pytest.mark.parametrize("latency", [0.2, 0.3])
def test_a_slow_line_s_stale_stream_is_not_read_as_the_status_reply(latency: float) -> None:
    """At 0.2 s of latency the paused stream's last frames came after discovery.drain's
    30 ms of quiet: "[ok] battery 277 of 27 mAh (1026 %)", "[ok] charging unknown state
    19" (the stream's header byte), "[ok] mode Off"."""
    import io

    from roomba_bt.cli.doctor_cmd import Report, _status, _stream
    from roomba_bt.oi import commands as oi
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.sim import Faults, SimLink, Simulator, load_world

    simulator = Simulator(load_world("empty-room"), CREATE2, seed=1, faults=Faults(latency=latency))
    link = SimLink(simulator)
    link.write(oi.start().data)
    report = Report(io.StringIO())
    _stream(link, 115200, report)
    _status(link, CREATE2, False, report)
    lines = report.out.getvalue().splitlines()
    battery = next(line for line in lines if line[7:].startswith("battery"))
    assert battery.startswith("[ok]") and " of 2696 mAh (" in battery, battery
    assert any(line.startswith("[ok]   charging  not charging (21 = 0)") for line in lines)
    assert any(line.startswith("[ok]   mode      Passive (35 = 1") for line in lines)


def test_an_implausible_status_reply_is_named_not_ok() -> None:
    """A reply has no checksum: a stale stream frame read as one is out of the packet table's
    ranges (charging state 19), a charge above the capacity, a mode other than Passive."""
    import struct

    from roomba_bt.cli.doctor_cmd import STATUS_PACKETS, _implausible
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.oi.stream import ReplyParser

    # charging state, voltage, current, charge, capacity, sources, mode
    reply = struct.pack(">BHhHHBB", 19, 2820, 0, 277, 27, 0, 0)
    frame = ReplyParser(STATUS_PACKETS, CREATE2).feed(reply)
    assert frame is not None
    wrong = _implausible(frame, False)
    assert "charging_state 19 (allowed 0..5)" in wrong
    assert "a charge of 277 mAh above the capacity, 27 mAh" in wrong
    assert "oi_mode 0 (Passive right after Start)" in wrong
    good = ReplyParser(STATUS_PACKETS, CREATE2).feed(
        struct.pack(">BHhHHBB", 0, 15120, -150, 1617, 2696, 0, 1)
    )
    assert good is not None and _implausible(good, False) == ""


def test_a_line_that_garbles_every_byte_is_called_garbled_not_silent(
    served_sim: Callable[..., Any],
) -> None:
    """It said "silent at every OI rate, even after a BRC pulse" with advice on the power and
    swapped TX/RX, though it had seen bytes that were no answer at 115200."""
    sim = served_sim("--pty", "--corrupt-rate", "1.0")
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.NO_ANSWER, done.stdout
    failed = [line for line in done.stdout.splitlines() if line.startswith("[FAIL]")]
    assert len(failed) == 1 and "the line garbles them" in failed[0], done.stdout
    assert "silent at every OI rate" not in done.stdout
    assert "TX and RX not swapped" not in done.stdout
    # the pty's other end is the simulator, garbling on purpose: said first, a cable only
    # as what may be behind a bridge (it said "check the cable and the adapter (noise on a
    # long or loose cable ...)" as on a device path)
    assert _fix_of(done.stdout, "baud").startswith(
        "fix: the robot may be there, but what the program at the pty's other end sends "
        "arrives garbled: the simulator's fault options garble it on purpose (--corrupt-rate, "
    ), done.stdout
    assert "noise on a long or loose cable" not in done.stdout


def _doctor_in_process(robot: Any, allow_reset: bool) -> tuple[int, str]:
    """``_examine`` on a simulated ``robot`` (any profile, even one no ``sim --profile``
    names): its exit code and its report."""
    import io

    from roomba_bt.cli.doctor_cmd import Report, _examine
    from roomba_bt.sim import SimLink, Simulator, load_world

    report = Report(io.StringIO())
    link = SimLink(Simulator(load_world("empty-room"), robot, seed=1))
    code = _examine(link, (115200, 19200), allow_reset, report)
    return code, report.out.getvalue()


def test_a_500_whose_checksum_covers_the_header_is_not_called_a_create2(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The roomba500 profile takes both checksum rules (which a real 500 follows is not
    certain): doctor named such a robot "iRobot Create 2 (--profile create2)" on its checksum
    alone, which allows Reset and Stop; with --allow-reset it said no profile fits and told
    the user to run doctor --allow-reset, which they just had."""
    import dataclasses

    from roomba_bt.oi.profiles import ROOMBA500

    robot = dataclasses.replace(ROOMBA500, checksum_includes_header=True)
    code, out = _doctor_in_process(robot, allow_reset=False)
    assert code == ExitCode.OK, out
    [profile] = _step(out, "profile")
    assert profile.startswith(CREATE2_OR_500_STEP), out
    fix = out.split(profile)[1].splitlines()[1]
    assert fix.lstrip().startswith("note: tell them apart by the model on its label; ")
    assert "a wall signal (27) over 1023, which only the Roomba 500 series reads" in fix
    assert "doctor --allow-reset (Reset is not in the Roomba 500 spec" in fix
    assert f"found: {CREATE2_OR_500} on " in capsys.readouterr().out
    code, out = _doctor_in_process(robot, allow_reset=True)
    assert code == ExitCode.OK, out
    [profile] = _step(out, "profile")
    assert profile.startswith("[ok]   profile   Roomba 500 series (--profile roomba500): "), out
    assert "it ignored Reset (7)" in profile
    assert "found: Roomba 500 series on " in capsys.readouterr().out


def test_a_600_that_reports_the_mode_as_is_is_named_and_its_setting_fits(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The mode + 1 is some 600 firmware's bug, not every 600's (doctor's own words: "a 600
    on fixed firmware too"), and the runtime learns the offset on any profile: a Roomba 650
    reading Passive as 1 was named "iRobot Create 2 (or a Roomba 500 series, by its
    label)", and its owner's ROOMBA_BT_PROFILE=roomba600 was a [warn], "this robot is no
    roomba600 ... set it to create2 or roomba500"."""
    import dataclasses

    monkeypatch.setenv("ROOMBA_BT_PROFILE", "roomba600")
    robot = dataclasses.replace(ROOMBA600, reports_mode_plus_one=False)
    code, out = _doctor_in_process(robot, allow_reset=False)
    assert code == ExitCode.OK, out
    [profile] = _step(out, "profile")
    assert profile.startswith(CREATE2_OR_500_STEP), out
    [setting] = _step(out, "setting")
    assert setting == "[ok]   setting   ROOMBA_BT_PROFILE=roomba600: fits this robot", out
    assert "stasis (58) over 1, which only the iRobot Create 2 or Roomba 600 series reads" in out
    found = "found: iRobot Create 2 (or a Roomba 600 series or Roomba 500 series, by its label)"
    assert found in capsys.readouterr().out
    code, out = _doctor_in_process(robot, allow_reset=True)  # the banner rules the 500 out
    assert code == ExitCode.OK, out
    assert "or a Roomba 600 series (--profile roomba600) if its label says so" in out, out


def test_no_profile_fits_does_not_advise_the_reset_just_sent() -> None:
    import io

    from roomba_bt.cli.doctor_cmd import Report, _profile

    for reset_tried in (True, False):
        report = Report(io.StringIO())
        _profile(True, False, None, reset_tried, {}, report)  # mode + 1, header left out
        out = report.out.getvalue()
        assert "no profile fits" in out and "fix: report this robot's model" in out
        assert ("--allow-reset" in out) is not reset_tried, out


def test_allow_reset_s_help_says_it_sends_reset_which_the_500_lacks() -> None:
    done = _cli("doctor", "--help")
    assert "send Reset (7)" in done.stdout
    assert "the Roomba 500 has no Reset 7" in " ".join(done.stdout.split())


def _doctor_through_a_bridge(jitter: float, hold: tuple[float, float] | None) -> str:
    """``doctor --listen 3s``'s report, in-process, of a Roomba 600 behind a WiFi bridge of
    20 ms each way (tests/runtime/simrun.py's ``BridgeLink``: on the virtual clock)."""
    link = BridgeLink(Simulator(load_world("empty-room"), ROOMBA600, seed=0), 0.02, jitter, hold)
    out = io.StringIO()
    assert _examine(link, (115200,), False, Report(out), 3.0) == ExitCode.OK
    return out.getvalue()


def test_doctor_says_a_steady_link_s_timing_is_ok() -> None:
    [timing] = _step(_doctor_through_a_bridge(0.0, None), "timing")
    assert timing == (
        "[ok]   timing    frames came every 15 ms (the median), 15 ms at the 99th percentile, "
        "the longest gap aside: 15 ms"
    )


def test_doctor_warns_of_a_wifi_link_s_jitter_and_stall_naming_watchdog_and_grace() -> None:
    # 20-100 ms of jitter, and a 1.2 s stall in the stream's 3 s (the stream asked at 0.15 s):
    # doctor said "[ok] stream" and nothing else; run's defaults stutter and end the run
    out = _doctor_through_a_bridge(0.08, (1.15, 1.2))
    [timing] = _step(out, "timing")
    assert timing.startswith("[warn] timing    frames came every ")
    assert timing.endswith("the longest gap aside: 1230 ms")
    fix = out.split(timing)[1].splitlines()[1]
    assert "a link with jitter or stalls (a network bridge: WiFi, Bluetooth): run with " in fix
    assert "--watchdog 0.15 (the default 0.1 s sends drive 0 at every gap longer" in fix
    assert "--grace 3 (a stall longer than the default 2 s ends the run)" in fix
    assert any(line.startswith("[ok]") for line in _step(out, "stream"))  # no frame lost


#: a Wi-Fi bridge's raw TCP port, as its user names it, and how doctor's fixes name it
BRIDGE_PORT = "socket://192.168.4.1:23"
BRIDGE = "the bridge at 192.168.4.1:23"


def _bridge_report() -> Report:
    """A report on :data:`BRIDGE_PORT`: its fixes worded for the network."""
    return Report(io.StringIO(), link_of(BRIDGE_PORT))


def _fix_of(out: str, step: str) -> str:
    """The fix under the step's last line."""
    return out.split(_step(out, step)[-1])[1].splitlines()[1].strip()


def test_an_asleep_robot_behind_a_raw_tcp_bridge_is_told_how_brc_crosses_a_bridge(
    served_sim: Callable[..., Any],
) -> None:
    """socket:// carries no modem lines: the fix said to "use a cable that wires BRC"."""
    sim = served_sim("--tcp", "127.0.0.1:0", "--asleep")
    done = _doctor(sim.address)
    assert done.returncode == ExitCode.NO_ANSWER, done.stdout
    fix = _fix_of(done.stdout, "wake")
    bridge = "the bridge at " + sim.address.removeprefix("socket://")
    assert fix.startswith("fix: a robot asleep (5 minutes in Passive) answers nothing"), fix
    assert f"BRC must cross {bridge}: rfc2217:// to a bridge that wires BRC" in fix
    assert f"check the serial side of {bridge}: wired to the robot's port" in fix
    assert "over socket:// the bridge keeps the rate it was set to" in fix
    assert "cable" not in done.stdout


class _Line(SimLink):
    """A line whose writes never reach the robot: it gives them back (``echoes``), or
    nothing comes (a robot that does not answer, even after a BRC pulse)."""

    def __init__(self, echoes: bool) -> None:
        super().__init__(Simulator(load_world("empty-room"), ROOMBA600, seed=1), BRIDGE_PORT)
        self.echoes = echoes
        self.given_back = b""

    def write(self, data: bytes) -> None:
        if self.echoes:
            self.given_back += data

    def read(self, timeout: float) -> bytes:
        given_back, self.given_back = self.given_back, b""
        return given_back or super().read(timeout)


def _garbling_link() -> SimLink:
    sim = Simulator(load_world("empty-room"), ROOMBA600, seed=1, faults=Faults(corrupt_rate=1.0))
    return SimLink(sim, BRIDGE_PORT)


@pytest.mark.parametrize(
    ("link", "step", "said"),
    [
        (
            lambda: _Line(echoes=True),
            "port",
            f"fix: this is not a robot's port: {BRIDGE} gives back what it is sent (an echo "
            "service, or its serial side's transmit and receive lines joined), or it is the "
            "wrong address; give the address of the robot's bridge",
        ),
        (
            lambda: _Line(echoes=False),
            "baud",
            "fix: check that the robot is on (press Clean: its light comes on) and that "
            f"{BRIDGE} wires BRC to the robot (not every bridge does); check the serial side "
            f"of {BRIDGE}: wired to the robot's port (TX and RX not swapped; ",
        ),
        (
            _garbling_link,
            "baud",
            "fix: the robot may be there, but what it sends arrives garbled (the network "
            f"delivers bytes whole): check the serial side of {BRIDGE}: wired to the robot's ",
        ),
    ],
    ids=["echo", "silent-after-the-pulse", "garbled"],
)
def test_a_robot_not_found_behind_a_network_bridge_is_told_of_the_bridge_not_a_cable(
    link: Callable[[], SimLink], step: str, said: str
) -> None:
    report = _bridge_report()
    with pytest.raises(_Failed) as failed:
        _examine(link(), (115200, 19200), False, report)
    assert failed.value.code == ExitCode.NO_ANSWER
    out = report.out.getvalue()
    assert _fix_of(out, step).startswith(said), out
    assert "cable" not in out and "adapter" not in out


PTY_PORT = "/dev/pts/7"


@pytest.mark.parametrize(
    ("link", "step", "said"),
    [
        (
            lambda: _Line(echoes=True),
            "port",
            "fix: this is not a robot's port: the program at the pty's other end gives back "
            "what it is sent, not the simulator (give the path roomba-bt sim --pty printed), "
            "or a cable or adapter behind a bridge such as socat has its transmit and receive "
            "lines joined",
        ),
        (
            lambda: _Line(echoes=False),
            "baud",
            "fix: check that the program at the pty's other end still runs and is the "
            "simulator (give the path roomba-bt sim --pty printed), not another program's pty",
        ),
        (
            _garbling_link,
            "baud",
            "fix: the robot may be there, but what the program at the pty's other end sends "
            "arrives garbled: the simulator's fault options garble it on purpose",
        ),
    ],
    ids=["echo", "silent-after-the-pulse", "garbled"],
)
def test_a_robot_not_found_on_a_pty_is_told_of_the_program_at_its_other_end(
    link: Callable[[], SimLink], step: str, said: str
) -> None:
    """A pty's other end is a program (the simulator, or a bridge such as socat): its fixes
    spoke of a cable first ("use a cable that wires BRC", "the cable is a 5 V TTL serial
    adapter", "give the robot's port (ls /dev/ttyUSB*)")."""
    report = Report(io.StringIO(), link_of(PTY_PORT))
    assert report.fixes is PTY_FIXES
    with pytest.raises(_Failed) as failed:
        _examine(link(), (115200, 19200), False, report)
    assert failed.value.code == ExitCode.NO_ANSWER
    out = report.out.getvalue()
    assert _fix_of(out, step).startswith(said), out
    assert "ls /dev/ttyUSB" not in out


def test_every_pty_fix_names_its_other_end_before_any_cable() -> None:
    """Each of the pty's fixes (the wake's, which only a port that cannot hang up reaches,
    the stream's and the status step's too) speaks first of the simulator or the program at
    the pty's other end; a cable only after it, as what may be behind a bridge."""
    for name in PTY_FIXES.__slots__:
        fix = getattr(PTY_FIXES, name)
        program = min(at for at in (fix.find("simulator"), fix.find("pty")) if at >= 0)
        assert "cable" not in fix[:program], (name, fix)
    assert "use a cable that wires BRC" not in PTY_FIXES.wake


@pytest.mark.parametrize(
    ("faults", "said"),
    [
        (
            Faults(drop_rate=1.0),
            "fix: the robot answers queries but does not stream: another program may be talking "
            f"to it, or the line drops bytes (a weak Wi-Fi signal, {BRIDGE} losing bytes on its "
            "serial side)",
        ),
        (
            Faults(drop_rate=0.3),
            "fix: the line loses frames (run calls 5 % or more a poor link): check the network: "
            f"{BRIDGE}, its power and its Wi-Fi signal; a larger --watchdog and --grace ride a "
            "Wi-Fi link's gaps through; --listen 10s samples longer",
        ),
        (
            Faults(bit_flip_rate=0.001),
            f"fix: frames are lost or damaged on this line: check {BRIDGE} (its power, its Wi-Fi "
            "signal)",
        ),
    ],
    ids=["no-frame", "frames-lost", "bytes-skipped"],
)
def test_a_stream_s_trouble_behind_a_network_bridge_names_the_bridge_and_its_wifi(
    faults: Faults, said: str
) -> None:
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=1, faults=faults), BRIDGE_PORT)
    link.write(oi.start().data)
    report = _bridge_report()
    with contextlib.suppress(_Failed):  # no frame ends the doctor
        _stream(link, 115200, report, 2.0)
    assert _fix_of(report.out.getvalue(), "stream") == said


def test_a_status_reply_garbled_behind_a_network_bridge_names_the_bridge() -> None:
    """Both of the status step's verdicts: replies that never agree, and agreeing ones that
    cannot be the robot's."""
    report = _bridge_report()
    with pytest.raises(_Failed):
        _status(_GarbledReplies(4), CREATE2, False, report)
    _status_failed(report, [], "charging_state 19 (allowed 0..5)", 0.2)
    disagree, implausible = (
        line.strip() for line in report.out.getvalue().splitlines() if line.startswith(" ")
    )
    assert disagree == (
        f"fix: the line garbles bytes (the serial side of {BRIDGE}: its wiring to the robot, a "
        f"wrong baud rate): check {BRIDGE} (its power, its Wi-Fi signal) and run doctor again"
    )
    assert implausible == (
        f"fix: the line garbles or delays bytes (a slow or busy Wi-Fi network, {BRIDGE}), or "
        f"another program talks to the robot: check {BRIDGE} (its power, its Wi-Fi signal) "
        "and run doctor again"
    )


class _BridgeThatDrops:
    """``SerialTransport`` for doctor: the simulator behind the URL, its link cut at 0.3 s (a
    bridge that lost its Wi-Fi while doctor used it)."""

    @staticmethod
    def open(url: str, baud: int, brc_high: bool) -> SimLink:
        faults = Faults(disconnect_at=0.3)
        return SimLink(Simulator(load_world("empty-room"), CREATE2, seed=1, faults=faults), url)


def test_a_network_bridge_lost_while_doctor_used_it_is_checked_not_a_cable(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """doctor_command gives the report the port's link: the fix names the bridge at its URL."""
    monkeypatch.setattr(transport_package, "SerialTransport", _BridgeThatDrops)
    args = argparse.Namespace(port=BRIDGE_PORT, baud=None, allow_reset=False, listen=None)
    assert doctor_command(args) == ExitCode.UNHEALTHY
    out = capsys.readouterr().out
    assert _step(out, "link")[0].startswith("[FAIL] link      the port failed: "), out
    assert _fix_of(out, "link") == (
        f"fix: check {BRIDGE} (its power, its Wi-Fi signal) and the robot's power, then run "
        "doctor again"
    )


def test_a_device_path_keeps_the_cable_s_words() -> None:
    """The fixes docs/doctor.md quotes, on a device path (a report told no port too)."""
    for report in (Report(io.StringIO()), Report(io.StringIO(), link_of("/dev/ttyUSB0"))):
        assert report.fixes is CABLE_FIXES
        assert _link_fix(OSError("gone"), report.fixes) == (
            "check the cable and the robot's power, then run doctor again"
        )


class _OpenFailsUntold:
    """A transport whose open fails with an error that tells no cause (no error number)."""

    @classmethod
    def open(cls, url: str, *args: Any, **kwargs: Any) -> SerialTransport:
        raise TransportError(url, "open the port", RuntimeError("the handler gave up"))


def test_a_bridge_that_does_not_open_is_told_by_its_address_not_a_device_path(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The fix of an open failure whose error told nothing was the device path's
    (``ls /dev/ttyUSB*``, the dialout group) on a bridge's URL too."""
    monkeypatch.setattr(transport_package, "SerialTransport", _OpenFailsUntold)
    code = doctor_command(
        argparse.Namespace(port=BRIDGE_PORT, baud=None, allow_reset=False, listen=None)
    )
    out = capsys.readouterr().out
    assert code == ExitCode.CONNECTION
    assert _fix_of(out, "port") == (
        f"fix: check the address, that {BRIDGE} is powered and in Wi-Fi range on this "
        "computer's network, and that no other client holds it"
    )
    assert "/dev/tty" not in out and "dialout" not in out


@pytest.mark.parametrize(("scheme", "serves"), [("socket", "--tcp"), ("rfc2217", "--rfc2217")])
def test_a_bridge_not_listening_is_named_by_its_address(scheme: str, serves: str) -> None:
    """Refused: "nothing listens there (is the bridge, or roomba-bt sim --tcp, running?)"
    named neither the address nor, on rfc2217://, the simulator's option that serves it."""
    import socket

    with socket.socket() as unused:  # a port nothing listens on
        unused.bind(("127.0.0.1", 0))
        closed = unused.getsockname()[1]
    done = _doctor(f"{scheme}://127.0.0.1:{closed}")
    assert done.returncode == ExitCode.CONNECTION
    assert f"nothing listens at 127.0.0.1:{closed}: is the bridge there running" in done.stdout
    assert f"(roomba-bt sim {serves} serves one)" in done.stdout


def test_listen_s_help_names_a_network_bridge_beside_a_cable() -> None:
    help_text = " ".join(_cli("doctor", "--help").stdout.split())
    assert "an intermittent line, a cable or a network bridge's Wi-Fi" in help_text


@pytest.mark.parametrize("baud", [19200, 115200])
def test_the_missions_line_docs_doctor_md_shows_is_what_doctor_prints(baud: int) -> None:
    """docs/doctor.md's ``missions`` lines, each shipped mission's frame at the baud, as the
    step prints them (session 37's stranger: the page said ``clean 59`` where doctor printed
    ``clean 61``)."""
    from roomba_bt.cli.doctor_cmd import _missions
    from roomba_bt.oi.profiles import CREATE2

    out = io.StringIO()
    _missions(CREATE2, baud, Report(out))
    printed = out.getvalue().splitlines()[0]
    doc = (Path(__file__).resolve().parents[2] / "docs" / "doctor.md").read_text("utf-8")
    assert printed in doc.splitlines(), printed
