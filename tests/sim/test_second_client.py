"""A second client on a ``socket://`` robot: the simulator's TCP server turns it away and
says so, and the second client is told it was turned away, not that its robot is dead
(before: "the port is gone ... Broken pipe", its stop "NOT DELIVERED", and doctor's "check
the cable" for a robot another run was driving, unharmed)."""

from __future__ import annotations

import logging
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from waits import HANG_S, accepted, received  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.oi import commands as C
from roomba_bt.sim.server import TcpEndpoint
from roomba_bt.transport import SerialTransport, TransportError

from .served import Served

BUMP = str(Path(__file__).resolve().parents[2] / "missions" / "bump-and-turn.yaml")
#: what the turned-away client is told
TURNED_AWAY = "the far end closed the connection at once, before sending a byte: another client"
#: a bound on each wait for the server, never a timing the test checks: a hang's
WAIT_S = HANG_S


@pytest.fixture
def held_robot() -> Iterator[str]:
    """The simulator on a TCP port, with a first client connected and answered (another run
    holding the robot); its ``socket://`` URL."""
    served = Served(TcpEndpoint("127.0.0.1", 0))
    first = socket.create_connection(address_of(served.endpoint.address), timeout=WAIT_S)
    try:
        first.sendall(C.start().data + C.sensors(35).data)
        # Passive: the server took this one
        assert received(first, 1, "the first client's sensor byte") == b"\x01"
        yield served.endpoint.address
    finally:
        first.close()
        served.close()


def address_of(url: str) -> tuple[str, int]:
    host, port = url.removeprefix("socket://").rsplit(":", 1)
    return host, int(port)


def test_the_tcp_server_turns_a_second_client_away_and_says_so(
    held_robot: str, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="roomba_bt.sim.server")
    second = socket.create_connection(address_of(held_robot), timeout=WAIT_S)
    try:
        # closed at once: nothing of the robot's stream
        assert received(second, 1, "the second client's close") == b""
    finally:
        second.close()
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.sim.server"]
    assert said and said[0].startswith(f"{held_robot}: turned a second client away (127.0.0.1:")
    assert "the first is still connected" in said[0]


def test_a_transport_turned_away_says_so_not_that_the_port_is_gone(held_robot: str) -> None:
    from roomba_bt.transport.open_failure import CLOSED_AT_ONCE

    transport = SerialTransport.open(held_robot)
    try:
        with pytest.raises(TransportError) as failed:
            for _ in range(int(WAIT_S / 0.05)):  # until the close is seen, read or write
                transport.write(C.start().data)
                transport.read(0.05)
        assert failed.value.cause == CLOSED_AT_ONCE
        assert str(failed.value).startswith(f"{held_robot}: could not ")
    finally:
        transport.close()


def test_a_socket_closed_after_the_robot_spoke_is_still_a_port_gone() -> None:
    """Only a far end that closed before it sent a byte was turned away: one that closes
    after (a bridge switched off mid-run) is the port gone, as before."""
    listener = socket.create_server(("127.0.0.1", 0))
    transport = SerialTransport.open(f"socket://127.0.0.1:{listener.getsockname()[1]}")
    try:
        far = accepted(listener, "the transport's connection", WAIT_S)
        far.sendall(b"\x01")
        got = b""
        for _ in range(int(WAIT_S / 0.05)):
            got += transport.read(0.05)
            if got:
                break
        assert got == b"\x01"
        far.close()
        with pytest.raises(TransportError) as failed:
            for _ in range(int(WAIT_S / 0.05)):
                transport.read(0.05)
        assert "socket disconnected" in str(failed.value)
        assert "closed the connection at once" not in str(failed.value)
    finally:
        transport.close()
        listener.close()


def test_a_run_turned_away_says_another_client_may_hold_the_robot(
    held_robot: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["run", BUMP, "--port", held_robot, "--timeout", "3s", "--display", "none",
                 "--no-keep-awake"])  # fmt: skip
    # not started (exit 3: nothing reached a robot, a retry is safe); 8 before, as a link
    # lost under a robot that may have moved, though no robot had answered
    assert code == 3
    out, err = capsys.readouterr()
    assert "outcome      NO CONNECTION (" in out
    assert f"roomba-bt: no connection: {held_robot}: {TURNED_AWAY} may hold it" in err
    assert "roomba-bt doctor" not in err  # doctor would be turned away as well
    # no robot was reached, so none was set going: said calmly, not NOT DELIVERED
    assert (
        "safe stop    nothing this run set going; not sent: the far end closed the "
        "connection at once" in out
    )
    assert "NOT DELIVERED" not in out
    assert "the port is gone" not in out + err


def test_doctor_turned_away_does_not_send_its_user_to_the_cable(
    held_robot: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["doctor", "--port", held_robot]) == 6
    out = capsys.readouterr().out
    assert TURNED_AWAY in out
    assert "fix: end the other client" in out
    assert "check the cable" not in out
