"""The real-time server behind a real pty and a TCP socket, driven by clients we did not
write (pycreate2, pyserial), through the ``roomba-bt sim`` command."""

from __future__ import annotations

import gc
import os
import signal
import socket
import subprocess
import sys
import termios
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import pytest
import serial
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi import commands as C
from roomba_bt.oi.profiles import ROOMBA500
from roomba_bt.oi.stream import StreamParser
from roomba_bt.sim import server
from roomba_bt.sim.server import PtyEndpoint, Rfc2217Endpoint, TcpEndpoint

if TYPE_CHECKING:
    from conftest import SocketsMade  # tests/conftest.py: the fixture sockets_made's


@pytest.fixture
def pty_server(served_sim: Callable[..., Any]) -> Any:
    return served_sim("--pty", "--world", "empty-room")


def test_pycreate2_reads_sensors_that_make_sense_drives_and_the_encoders_move(
    pty_server: Any,
) -> None:
    pycreate2 = pytest.importorskip("pycreate2")
    assert pty_server.address.startswith("/dev/")
    bot = pycreate2.Create2(pty_server.address)
    bot.start()
    bot.safe()
    before = bot.get_sensors()
    assert before.open_interface_mode == 2  # Safe
    assert 12000 < before.voltage < 17500 and before.battery_capacity == 2696
    assert 0 < before.battery_charge <= before.battery_capacity
    assert before.cliff_left_signal > 1000 and not before.cliff_front_left  # on the floor
    assert not before.bumps_wheeldrops.bump_left and not before.bumps_wheeldrops.bump_right
    bot.drive_direct(150, 150)
    deadline = time.monotonic() + HANG_S  # a cap on waiting for the wheels, never a timing
    moved = 0
    while moved < 300 and time.monotonic() < deadline:
        after = bot.get_sensors()
        moved = (after.encoder_counts_left - before.encoder_counts_left) & 0xFFFF
    assert after.velocity_left == after.velocity_right == 150
    assert 300 <= moved < 2000  # about 320 counts a second: 142.5 mm/s, 2.25 counts per mm
    bot.drive_stop()
    stopped = bot.get_sensors().encoder_counts_left
    time.sleep(0.3)
    assert bot.get_sensors().encoder_counts_left == stopped
    del bot  # pycreate2's destructor stops the motors and sends Stop (173)
    gc.collect()
    code, err = pty_server.stop()
    assert code == 0
    assert "mode Off" in err and "0 ignored actuator commands" in err


def test_log_shows_what_pycreate2_sent_and_what_the_robot_did(
    served_sim: Callable[..., Any],
) -> None:
    """``sim --log``: a driver's commands decoded as the robot heard them, and the mode
    changes they made, in order."""
    pycreate2 = pytest.importorskip("pycreate2")
    served = served_sim("--pty", "--log")
    bot = pycreate2.Create2(served.address)
    bot.start()
    bot.safe()
    bot.drive_direct(150, -150)
    bot.get_sensors()
    bot.drive_stop()
    del bot  # pycreate2's destructor stops the motors and sends Stop (173)
    gc.collect()
    code, err = served.stop()
    assert code == 0
    heard = [line.split(" s  ", 1)[1] for line in err.splitlines() if " s  " in line]
    words = [line.split(" (", 1)[0] for line in heard]
    assert words[:4] == ["heard Start", "mode: Off->Passive", "heard Safe", "mode: Passive->Safe"]
    assert any(line.startswith("heard Drive Direct (145) right_velocity 150, left_velocity -150")
               for line in heard), heard  # fmt: skip
    assert "heard Stop" in words and "mode: Safe->Off" in words


def test_tcp_serves_a_stream_to_pyserial_and_exits_cleanly_on_sigint(
    served_sim: Callable[..., Any],
) -> None:
    server = served_sim("--tcp", "127.0.0.1:0", "--profile", "roomba500")
    assert server.address.startswith("socket://127.0.0.1:")
    port = serial.serial_for_url(server.address, timeout=0.2)
    try:
        port.write(C.start().data + C.stream([7, 35, 43]).data)
        parser = StreamParser([7, 35, 43], ROOMBA500)  # its checksum leaves the header out
        frames = []
        deadline = time.monotonic() + HANG_S  # a cap on waiting for frames, never a timing
        while len(frames) <= 5 and time.monotonic() < deadline:
            frames += parser.feed(port.read(256))
        assert len(frames) > 5
        assert parser.counters.checksum_failures == 0
        assert {f.oi_mode_raw for f in frames} == {1}
    finally:
        port.close()
        code, err = server.stop(signal.SIGINT)
    assert code == 0 and "simulated" in err


def test_disconnect_fault_hangs_up_the_line(served_sim: Callable[..., Any]) -> None:
    server = served_sim("--tcp", "127.0.0.1:0", "--disconnect-at", "0.3")
    port = serial.serial_for_url(server.address, timeout=0.2)
    try:
        port.write(C.start().data + C.stream([35]).data)
        with pytest.raises(serial.SerialException):
            deadline = time.monotonic() + HANG_S
            while time.monotonic() < deadline:
                port.read(64)
    finally:
        port.close()
        code, _ = server.stop()
    assert code == 0


def test_duration_stops_the_server_by_itself() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "sim", "--pty", "--duration", "0.2"],
        capture_output=True, text=True, timeout=HANG_S, check=False,
    )  # fmt: skip
    assert proc.returncode == 0 and proc.stdout.startswith("/dev/")


def test_an_invalid_world_exits_2_with_the_position(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\ndock: {at: [1, 0], facing: up}\n")
    proc = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "sim", "--pty", "--world", str(bad)],
        capture_output=True, text=True, timeout=HANG_S, check=False,
    )  # fmt: skip
    assert proc.returncode == 2 and proc.stdout == ""
    assert f"{bad}:2:28: dock.facing: found 'up'" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize(
    "args", [["--tcp", "localhost"], ["--pty", "--drop-rate", "2"], ["--pty", "--profile", "x"]]
)
def test_bad_options_exit_2(args: list[str]) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "sim", *args],
        capture_output=True, text=True, timeout=HANG_S, check=False,
    )  # fmt: skip
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_pyroombaadapter_streams_queries_and_drives(pty_server: Any) -> None:
    pra = pytest.importorskip("pyroombaadapter")
    adapter = pra.PyRoombaAdapter(pty_server.address)  # Start + Safe, then 1 s
    try:
        assert adapter.request_oi_mode() == 2
        assert adapter.request_capacity() == 2696
        assert adapter.request_charging_state() == 0  # not on the dock
        left0, right0 = adapter.request_encoder_counts()
        adapter.data_stream_start(["OI Mode", "Voltage"])
        readings = []
        deadline = time.monotonic() + HANG_S
        while len(readings) < 10 and time.monotonic() < deadline:
            values = adapter.data_stream_read()  # checks the checksum itself
            if values:
                readings.append(values)
        assert len(readings) == 10
        assert all(mode == 2 and 12000 < volts < 17500 for mode, volts in readings)
        adapter.data_stream_stop()
        time.sleep(0.1)
        adapter.serial_con.reset_input_buffer()
        adapter.send_drive_direct(100, 100)
        deadline = time.monotonic() + HANG_S  # a cap on waiting for the wheels
        left1, right1 = left0, right0
        while (left1 <= left0 or right1 <= right0) and time.monotonic() < deadline:
            left1, right1 = adapter.request_encoder_counts()
        adapter.send_drive_direct(0, 0)
        assert left1 > left0 and right1 > right0
    finally:
        del adapter  # its destructor sends Start (Passive) and closes the port
        gc.collect()
    code, err = pty_server.stop()
    assert code == 0 and "mode Passive" in err


@pytest.mark.extra("plot")
def test_plot_on_exit(tmp_path: Path) -> None:
    out = tmp_path / "run.png"
    proc = subprocess.run(
        [sys.executable, "-m", "roomba_bt.cli", "sim", "--pty", "--duration", "0.2",
         "--world", "corridor", "--plot", str(out)],
        capture_output=True, text=True, timeout=HANG_S, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_a_port_in_use_exits_3() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        proc = subprocess.run(
            [sys.executable, "-m", "roomba_bt.cli", "sim", "--tcp", f"127.0.0.1:{port}"],
            capture_output=True, text=True, timeout=HANG_S, check=False,
        )  # fmt: skip
    assert proc.returncode == 3 and "cannot serve" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize(
    "endpoint",
    [TcpEndpoint, lambda host, port: Rfc2217Endpoint(host, port, 115200)],
    ids=["tcp", "rfc2217"],
)
def test_a_port_in_use_leaves_no_listener_open(
    endpoint: Callable[[str, int], TcpEndpoint],
    sockets_made: Callable[[ModuleType], SocketsMade],
) -> None:
    """The listener whose bind was refused is closed: it was left to the garbage collector
    (a ``ResourceWarning`` in whichever test ran when it collected)."""
    made = sockets_made(server)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        with pytest.raises(OSError):
            endpoint("127.0.0.1", taken.getsockname()[1])
    assert made.all_closed()


def test_a_pty_that_cannot_be_made_raw_leaves_no_descriptor_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Both ends of the pty are closed when setting it up fails (``tty.setraw`` refused):
    they were left open for the rest of the process."""
    opened: list[int] = []
    openpty = server.os.openpty

    def recorded() -> tuple[int, int]:
        ends = openpty()
        opened.extend(ends)
        return ends

    def refused(fd: int) -> None:
        raise termios.error(5, "Input/output error")

    monkeypatch.setattr(server.os, "openpty", recorded)
    monkeypatch.setattr(server.tty, "setraw", refused)
    with pytest.raises(termios.error):
        PtyEndpoint()
    assert len(opened) == 2
    for fd in opened:
        with pytest.raises(OSError):
            os.fstat(fd)  # closed
