"""The connection as a library user meets it (a field trial's findings): a program that never
calls ``close()`` does not leave the robot driving (it is stopped and closed when dropped, or
when the program ends: a script that opened, drove and exited left the simulated robot in
Safe at 142 mm/s, silently); raw bytes, a closed connection, a rate the OI does not talk at
and a printed mode each say what they are."""

from __future__ import annotations

import gc
import subprocess
import sys
import textwrap
from typing import Any

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import RobotError
from roomba_bt.sim import SimLink, Simulator, load_world, parse_world

BOX = """
name: box
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 2], heading: 0}}
"""


def test_a_connection_dropped_while_driving_is_stopped(caplog: pytest.LogCaptureFixture) -> None:
    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    connection = Connection(SimLink(simulator), CREATE2)
    connection.start("safe", (7, 35))
    connection.send(oi.drive(150, 32767))
    connection.poll(0.05)
    assert simulator.mode is OIMode.SAFE and simulator.left_speed > 100  # accelerating
    del connection
    gc.collect()
    assert simulator.mode is OIMode.PASSIVE
    assert (simulator.requested_left, simulator.requested_right) == (0, 0)
    assert "dropped without close() (the robot at 150 mm/s)" in caplog.text
    assert "the safe stop was sent" in caplog.text


def test_a_closed_or_never_started_connection_is_left_alone(
    caplog: pytest.LogCaptureFixture,
) -> None:
    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    with Connection(SimLink(simulator), CREATE2) as connection:
        connection.start("safe", (7, 35))
    never = Connection(SimLink(simulator), CREATE2)
    del connection, never
    gc.collect()
    assert "without close()" not in caplog.text


SCRIPT = textwrap.dedent("""
    import sys
    from roomba_bt.oi import commands as oi
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.robot.connection import Connection
    from roomba_bt.sim import SimLink, Simulator, load_world, parse_world

    class Told(SimLink):
        def write(self, data):
            print("wrote", data.hex(" "), flush=True)
            super().write(data)

    world = parse_world("rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]", "<test>")
    robot = Connection(Told(Simulator(world, profile=CREATE2)), CREATE2)
    robot.start("safe", (7, 35))
    robot.send(oi.drive(150, 32767))
    print("exiting", flush=True)
""")


def test_a_program_that_ends_without_close_stops_the_robot() -> None:
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    after = done.stdout.split("exiting\n", 1)[1]
    assert "wrote 89 00 00 00 00" in after  # drive 0
    assert after.rstrip().endswith("80")  # Start: Passive
    assert "the program ended without close() (the robot at 150 mm/s)" in done.stderr


def test_raw_bytes_or_an_opcode_are_refused_naming_the_commands_module() -> None:
    """pycreate2's and PyRoombaAdapter's way; it was "'bytes' object has no attribute
    'spec'"."""
    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    with Connection(SimLink(simulator), CREATE2) as connection:
        connection.start("safe", (7, 35))
        for wrong in (b"\x89\x00\x64\x80\x00", 137):
            # the import a program writes (``roomba_bt.oi.commands`` as a path warns)
            with pytest.raises(TypeError, match=r"roomba_bt.commands \(from roomba_bt imp"):
                connection.send(wrong)  # type: ignore[arg-type]
            with pytest.raises(TypeError, match=r"raw bytes would pass it by"):
                connection.send_many([oi.safe(), wrong])  # type: ignore[list-item]
        assert simulator.requested_left == 0  # nothing of the batch was written


def test_a_closed_connection_says_it_is_closed_not_that_the_port_is_gone() -> None:
    from roomba_bt.robot import ConnectionClosed

    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    connection = Connection(SimLink(simulator), CREATE2)
    connection.start("safe", (7, 35))
    connection.close()
    for use in (lambda: connection.send(oi.drive(100, 0)), lambda: connection.poll(0.01)):
        with pytest.raises(ConnectionClosed, match=r"the connection is closed \(close\(\) was"):
            use()


@pytest.mark.parametrize("timeout", [-1, -0.5, float("nan"), None])
def test_poll_refuses_a_timeout_below_0_or_none(timeout: Any) -> None:
    """poll(-1), as "wait for ever", returned at once, and a loop over it spun the CPU; None
    (pyserial's "for ever") was a TypeError from inside the link."""
    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    connection = Connection(SimLink(simulator), CREATE2)
    connection.start("safe", (7, 35))
    try:
        with pytest.raises(ValueError, match=r"a timeout is 0 or more seconds"):
            connection.poll(timeout)
        assert connection.poll(0.05)  # and a timeout of 0 or more reads as before
    finally:
        connection.close()


def test_open_takes_only_the_ois_rates_and_a_mode_prints_its_name() -> None:
    with pytest.raises(ValueError, match=r"baud 9999: the OI talks at 300, 600, .*, 115200"):
        Connection.open("loop://", baud=9999)
    assert str(OIMode.SAFE) == "Safe" and f"{OIMode.PASSIVE}" == "Passive"  # printed 2, 1
    assert f"{OIMode.FULL:d}" == "3" and OIMode.SAFE == 2


def test_open_says_what_is_wrong_with_a_port_named_wrongly_or_not_at_all() -> None:
    """Connection.open(None) (an unset environment variable) was an AttributeError from inside
    pyserial; a URL without its port was pyserial's "'<=' not supported between instances of
    'int' and 'NoneType'" with guesses about permissions."""
    from roomba_bt.robot import ConnectionFailed

    with pytest.raises(TypeError, match=r"the port must be a device path .*socket://HOST:PORT"):
        Connection.open(None)  # type: ignore[arg-type]
    with pytest.raises(ConnectionFailed) as failed:
        Connection.open("socket://localhost")
    assert str(failed.value) == (
        "socket://localhost: could not open the port: found 'socket://localhost'; allowed: "
        "socket://HOST:PORT, a port in 1..65535"
    )


def test_a_second_open_in_this_process_names_its_own_connection(fake_links: Any) -> None:
    """A notebook cell run again while the first connection drives: "another program has it
    open" sent its user looking for one; it is this process's own, with how to close it."""
    from roomba_bt.robot import ConnectionFailed

    link = fake_links("pty")
    with Connection.open(link.url, profile=CREATE2, watchdog=1.0) as first:
        first.start("safe", (7, 35))
        with pytest.raises(ConnectionFailed) as again:
            Connection.open(link.url, profile=CREATE2)
    said = str(again.value)
    assert said.startswith(f"{link.url}: could not open the port: this process has it open")
    assert "close()" in said and "another program" not in said


def test_open_takes_keep_awake_as_the_cli_option_does(fake_links: Any) -> None:
    """``run --no-keep-awake`` from Python: the keep-awake warning names this argument."""
    link = fake_links("pty")
    with Connection.open(link.url, profile=CREATE2, keep_awake=False) as quiet:
        assert quiet.keep_awake is False and quiet.wake is None
    with Connection.open(link.url, profile=CREATE2) as default:
        assert default.keep_awake is True and default.wake is not None  # a Create 2 sleeps


class _Written(SimLink):
    """The simulator's link, each write kept."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.writes: list[bytes] = []

    def write(self, data: bytes) -> None:
        self.writes.append(data)
        super().write(data)


def test_a_seek_dock_seen_docked_by_query_list_ends_without_safe() -> None:
    """pycreate2's way to dock: Seek Dock, then Query List (its ``get_sensors()``) until the
    home base powers the robot, no stream. The ending saw no stream frame on the home base,
    took the cycle for one that may still drive and sent Safe (131) first: the 600 / Create 2
    spec says charging terminates on entering Safe, so the charge the program had just
    reached was cut. A reply to a Query List is the robot seen as a stream frame is."""
    simulator = Simulator(load_world("empty-room"), profile=CREATE2, seed=0, trace=False)
    link = _Written(simulator)
    with Connection(link, CREATE2) as robot:
        robot.start("safe")  # no stream: the program asks
        robot.send(oi.seek_dock())
        for _ in range(3000):  # the dock is a few seconds away in this world
            reply = robot.query([34])
            if reply is not None and reply.charging_sources.home_base:
                break
            link.advance(0.1)
        else:
            pytest.fail("the robot never docked")
        link.writes.clear()
    assert link.writes == [oi.pause_stream().data + oi.start().data]  # no [131] first
    assert simulator.docked and simulator.mode is OIMode.PASSIVE


def test_a_query_while_streaming_says_how_to_pause_the_stream() -> None:
    simulator = Simulator(parse_world(BOX, "<test>"), profile=CREATE2)
    with Connection(SimLink(simulator), CREATE2) as robot:
        robot.start("safe", (7, 35))
        with pytest.raises(RobotError, match=r"send\(commands.pause_stream\(\)\) first"):
            robot.query([21])
        robot.send(oi.pause_stream())  # as the message says
        reply = robot.query([21, 25])
        assert reply is not None and reply.battery_charge_mah > 0
        robot.send(oi.resume_stream())
        assert robot.poll(0.1)


def test_the_connection_s_docstring_example_runs() -> None:
    """``help(Connection)`` and an editor's hover showed "see the module docstring", whose
    text is the session's parts: how to drive a robot with it, and that every ending stops
    it, were on a page of the docs alone."""
    import doctest

    [test] = doctest.DocTestFinder(recurse=False).find(Connection, "Connection")
    result = doctest.DocTestRunner().run(test)
    assert result.attempted >= 5 and result.failed == 0
    assert "pycreate2" in (Connection.__doc__ or "")


ODOMETRY = "### Odometry in a program's own loop"


def test_the_odometry_example_drives_a_square_and_comes_back(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A program's square by odometry, as pycreate2's users write one: the encoders'
    odometry the runtime keeps was a run's alone (``Snapshot.odometry``), and a program
    driving by hand added up Distance (19) and Angle (20), wrong on older firmware."""
    import re
    from pathlib import Path

    page = Path(__file__).resolve().parents[2] / "docs" / "robot.md"
    section = page.read_text(encoding="utf-8").split(f"\n{ODOMETRY}\n", 1)[1].split("\n#", 1)[0]
    [block] = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    namespace: dict[str, object] = {"__name__": "docs_example"}
    exec(compile(block, f"{page}:odometry", "exec"), namespace)
    said = capsys.readouterr().out
    found = re.fullmatch(r"at \((-?\d+), (-?\d+)\) mm, turned (\d+) deg\n", said)
    assert found is not None, said
    assert abs(int(found[1])) < 30 and abs(int(found[2])) < 30  # back where it started
    assert 360 <= int(found[3]) < 370
    assert f"at ({found[1]}, {found[2]}) mm, turned {found[3]} deg" in section  # as quoted
    simulator = namespace["simulator"]
    assert isinstance(simulator, Simulator) and simulator.mode is OIMode.PASSIVE
    assert (simulator.requested_left, simulator.requested_right) == (0, 0)
