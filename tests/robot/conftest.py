"""Backends for the connection contract suite, parametrised as python-can does for its buses.

Each backend gives a :class:`Link`: a way to make a :class:`Connection` to a robot and, where
the far end is scriptable, the robot itself (a :class:`FakeRobot` behind a pty or a TCP
socket). ``real`` runs only with ``ROOMBA_BT_PORT`` set (a robot on that port, which the
tests will drive briefly: keep it on blocks); scripted tests skip it.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

from roomba_bt.oi.profiles import CREATE2, RobotProfile, get_profile
from roomba_bt.robot.connection import Connection
from roomba_bt.sim.server import PtyEndpoint, TcpEndpoint

from .fake_robot import FakeRobot
from .sim_backend import SimRobot, make_sim_link, sim_pty_server

REAL_PORT_ENV = "ROOMBA_BT_PORT"


@dataclass
class Link:
    name: str
    url: str
    robot: FakeRobot | SimRobot | None
    profile: RobotProfile = CREATE2
    opened: list[Connection] = field(default_factory=list)

    def connect(self, **kwargs: Any) -> Connection:
        kwargs.setdefault("profile", self.profile)
        # 2 cores shared by every test run: a 100 ms hiccup is not what these tests are about
        # (the watchdog tests pass their own 0.1 s)
        kwargs.setdefault("watchdog", 1.0)
        if isinstance(self.robot, SimRobot):
            kwargs.pop("write_timeout", None)
            connection = Connection(self.robot.link, **kwargs)
        else:
            connection = Connection.open(self.url, **kwargs)
        self.opened.append(connection)
        return connection

    def scripted(self) -> Any:
        """The robot at the far end (FakeRobot interface), or skip: this test scripts it."""
        if self.robot is None:
            pytest.skip(f"the {self.name} backend has no scriptable far end")
        return self.robot


def make_fake_link(kind: str, profile: RobotProfile = CREATE2, **robot_kwargs: Any) -> Link:
    endpoint = PtyEndpoint() if kind == "pty" else TcpEndpoint("127.0.0.1", 0)
    robot = FakeRobot(endpoint, profile, **robot_kwargs)
    return Link(kind, endpoint.address, robot, profile)


def _close(link: Link) -> None:
    for connection in link.opened:
        connection.close()
    if link.robot is not None:
        link.robot.stop()


@pytest.fixture
def fake_links() -> Iterator[Any]:
    """``fake_links("pty" | "tcp", profile, **robot_options)``: a started fake robot link,
    stopped at teardown."""
    links: list[Link] = []

    def factory(kind: str, profile: RobotProfile = CREATE2, **robot_kwargs: Any) -> Link:
        link = make_fake_link(kind, profile, **robot_kwargs)
        assert link.robot is not None
        link.robot.__enter__()
        links.append(link)
        return link

    yield factory
    for link in links:
        _close(link)


BACKENDS = ["pty", "tcp", "sim", "sim-pty", "real"]


@pytest.fixture(scope="session")
def sim_pty_address() -> Iterator[str]:
    """One ``roomba-bt sim --pty`` for the session: every test's start() resets the robot
    (Start, pause the stream), and its pty survives a client closing it."""
    with sim_pty_server(CREATE2) as address:
        yield address


@pytest.fixture(params=BACKENDS)
def link(request: pytest.FixtureRequest, fake_links: Any) -> Iterator[Link]:
    """One robot link per backend; the contract tests run once on each."""
    kind = request.param
    if kind == "real":
        port = os.environ.get(REAL_PORT_ENV)
        if not port:
            pytest.skip(f"set {REAL_PORT_ENV}=/dev/ttyUSB0 to run on a robot")
        profile = get_profile(os.environ.get("ROOMBA_BT_PROFILE", "create2"))
        real = Link("real", port, None, profile)
        yield real
        _close(real)
        return
    if kind in ("sim", "sim-pty"):
        if kind == "sim":
            transport, robot = make_sim_link(CREATE2)
            sim = Link("sim", transport.name, robot, CREATE2)
            yield sim
            _close(sim)
            return
        address = request.getfixturevalue("sim_pty_address")
        served = Link("sim-pty", address, None, CREATE2)
        yield served
        _close(served)
        return
    yield fake_links(kind)
