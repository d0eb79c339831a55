"""A library user's program that never calls ``close()`` does not leave the robot driving:
the connection is stopped and closed when it is dropped, or when the program ends (a script
that opened, drove and exited left the simulated robot in Safe at 142 mm/s, silently)."""

from __future__ import annotations

import gc
import subprocess
import sys
import textwrap

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.sim import SimLink, Simulator, parse_world

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
    assert "dropped without close() while the robot was at 150 mm/s" in caplog.text
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
    from roomba_bt.sim import SimLink, Simulator, parse_world

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
    assert "the program ended without close() while the robot was at 150 mm/s" in done.stderr
