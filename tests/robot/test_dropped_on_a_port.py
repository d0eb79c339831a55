"""A connection dropped without ``close()`` on a real port (a pty): it is stopped as soon as
its last reference goes, and in a garbage-collector pass too. The field trial's finding: the
connection sat in a reference cycle (its link held its bound methods), so only the cyclic
collector freed it, and in that pass pyserial's own finalizer closed the port before the stop
could be written: the robot drove on in Safe at 150 mm/s ("the stop was not delivered: the
port is gone")."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Iterator
from typing import Any

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection

from .fake_robot import FakeRobot

DRIVE, DRIVE_DIRECT = 137, 145


@pytest.fixture
def collector_off() -> Iterator[None]:
    """Only reference counting frees what the test drops (the collector runs when asked)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _drive_and_return(url: str, robot: FakeRobot) -> weakref.ref[Connection]:
    """Open, Safe, drive_direct, and return without close(): the connection's last reference
    goes with this frame."""
    connection = Connection.open(url, profile=CREATE2, watchdog=1.0)
    connection.start("safe", (7, 35))
    connection.send(oi.drive_direct(150, 150))
    assert robot.wait_until(lambda r: DRIVE_DIRECT in r.opcodes())
    return weakref.ref(connection)


def _stopped(robot: FakeRobot) -> bool:
    """Drive 0 came after the drive, in Safe, and the robot is in Passive."""
    with robot._lock:
        after = robot.commands[robot.opcodes().index(DRIVE_DIRECT) + 1 :]
        return robot.mode is OIMode.PASSIVE and any(
            r.command.opcode == DRIVE and not any(r.command.args) and r.mode is OIMode.SAFE
            for r in after
        )


def test_a_connection_dropped_in_a_function_is_stopped_at_once(
    fake_links: Any, collector_off: None, caplog: pytest.LogCaptureFixture
) -> None:
    link = fake_links("pty")
    gone = _drive_and_return(link.url, link.robot)
    assert gone() is None  # freed by reference counting: no collector pass needed
    assert link.robot.wait_until(_stopped)
    assert "dropped without close() (the robot after drive_direct" in caplog.text
    assert "the safe stop was sent" in caplog.text


def test_a_connection_dropped_in_a_cycle_is_stopped_by_the_collector(
    fake_links: Any, collector_off: None, caplog: pytest.LogCaptureFixture
) -> None:
    """The user's own cycle keeps it to the collector: the port must still be open when the
    stop is written (pyserial's finalizer closed it first)."""
    link = fake_links("pty")
    holder: dict[str, Any] = {}
    holder["self"] = holder
    holder["robot"] = _drive_and_return(link.url, link.robot)()
    del holder
    gc.collect()
    assert link.robot.wait_until(_stopped)
    assert "the stop was not delivered" not in caplog.text
    assert "the safe stop was sent" in caplog.text
