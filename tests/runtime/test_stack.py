"""The one run-stack assembly: a record made through it replays through it, byte for byte;
``--display`` picks its observer."""

from __future__ import annotations

import io
import re
import textwrap
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.mission import CompiledMission, load_mission
from roomba_bt.oi.profiles import CREATE2, ROOMBA500
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import ConnectionClosed
from roomba_bt.runtime.display import StatusChangeLogger, TerminalDisplay, observer_for
from roomba_bt.runtime.loop import stream_request
from roomba_bt.runtime.recording import ReplayTransport, load_record
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.runtime.summary import Outcome
from roomba_bt.sim import SimLink, Simulator, load_world

DRIVE_TO_WALL = """
mission: to-the-wall
parameters:
  speed: {type: speed, default: 200 mm/s}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: "${speed}"}
      until: {bump: {}}
"""


def test_a_record_made_by_the_stack_replays_through_it_byte_for_byte(tmp_path: Path) -> None:
    path = tmp_path / "to-the-wall.yaml"
    path.write_text(textwrap.dedent(DRIVE_TO_WALL))
    params = {"speed": "300 mm/s"}
    mission = load_mission(path, params, profile=CREATE2)
    record_path = tmp_path / "run.jsonl"
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    stack = RunStack(
        mission,
        SimLink(simulator),
        profile=CREATE2,
        timeout_s=30.0,
        record=Recording(record_path, str(path), params),
    )
    assert stack.packets == stream_request(mission.packets, 115200)
    summary = stack.run()
    stack.close()
    assert summary.outcome is Outcome.SUCCESS

    record = load_record(record_path)
    assert record.header["mission"] == str(path)
    assert record.header["parameters"] == params
    assert record.header["packets"] == list(stack.packets)
    assert record.header["profile"] == "create2" and record.header["baud"] == 115200
    replay = ReplayTransport(record)
    again = RunStack(
        load_mission(path, params, profile=CREATE2),
        replay,
        profile=CREATE2,
        packets=record.header["packets"],
        watchdog=0.0,
        input_ended=lambda: "end of the record" if replay.exhausted else None,
    )
    assert again.run().outcome is Outcome.SUCCESS
    assert replay.first_difference() is None and replay.written == record.out_bytes


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize(
    ("display", "terminal", "kind"),
    [
        ("auto", True, TerminalDisplay),
        ("auto", False, StatusChangeLogger),
        ("tree", False, TerminalDisplay),
        ("log", True, StatusChangeLogger),
        ("none", True, type(None)),
    ],
)
def test_display_picks_the_observer(display: str, terminal: bool, kind: type) -> None:
    stream = _Terminal() if terminal else io.StringIO()
    observer = observer_for(display, stream)  # type: ignore[arg-type]
    assert isinstance(observer, kind)
    if isinstance(observer, TerminalDisplay):
        observer.close()  # its writer's thread ends (left running before)


class _SlowClock:
    """A port whose clock moves on at every reading of it, by a little more each time: the
    record's line for a chunk written slowly, and more or less so (a full buffer, a
    preempted process), between the chunk's stamp and the link's own reading of the time."""

    name = "slow"
    is_open = True

    def __init__(self) -> None:
        self.t = 100.0
        self.step = 0.0

    def now(self) -> float:
        self.step += 0.003
        self.t += self.step
        return self.t

    def read(self, timeout: float) -> bytes:
        return b"\\x13\\x02\\x07\\x00\\xe4"

    def write(self, data: bytes) -> None:
        pass

    def close(self) -> None:
        pass


def test_the_arrival_the_link_reads_after_a_read_is_the_time_the_record_holds(
    tmp_path: Path,
) -> None:
    """A replay gives a chunk back at its recorded time; the live link read the clock again
    after the record's line was written, later: its ticks and mission time differed from the
    replay's by the write's delay (a 35-minute noisy run's replay differed at 112.95 s)."""
    from roomba_bt.runtime.recording import RecordingTransport

    path = tmp_path / "slow.jsonl"
    header = {"profile": "create2", "baud": 115200, "mission": "m.yaml", "packets": [7]}
    recording = RecordingTransport(_SlowClock(), path, header)  # type: ignore[arg-type]
    recording.read(0.0)
    first_arrival = recording.now()
    recording.read(0.0)
    second_arrival = recording.now()
    recording.close()
    record = load_record(path)
    recorded = [t for t, d, _ in record.chunks() if d == "in"]
    assert second_arrival - first_arrival == pytest.approx(recorded[1] - recorded[0], abs=1e-6)
    assert recording.now() > second_arrival  # only the read's own arrival is the stamp


def test_a_stack_runs_once() -> None:
    """A second run() on the same stack added up the two (duration, ticks, distance, lost
    frames): refused, saying to build a new RunStack; the tree and link may be used again."""
    import py_trees

    from roomba_bt.behaviours.actions import Drive, Mode
    from roomba_bt.runtime.stack import TreeMission

    root = py_trees.composites.Sequence("again", memory=True, children=[
        Mode("safe", {"to": "safe"}), Drive("d", {"velocity": "200 mm/s", "distance": "0.2 m"}),
    ])  # fmt: skip
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(TreeMission(root, "again"), link, profile=CREATE2, timeout_s=10.0)
    first = stack.run()
    assert first.outcome is Outcome.SUCCESS
    ticks = first.ticks
    with pytest.raises(RuntimeError, match="runs once; build a new RunStack"):
        stack.run()
    assert stack.runner.summary.ticks == ticks  # nothing added
    again = RunStack(TreeMission(root, "again"), link, profile=CREATE2, timeout_s=10.0).run()
    assert again.outcome is Outcome.SUCCESS and again.ticks <= ticks + 5


def _connection() -> Connection:
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
    return Connection(SimLink(simulator), CREATE2, watchdog=0.2)


def _mission(tmp_path: Path) -> CompiledMission:
    path = tmp_path / "to-the-wall.yaml"
    path.write_text(textwrap.dedent(DRIVE_TO_WALL))
    return load_mission(path, {"speed": "400 mm/s"}, profile=CREATE2)


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ({"watchdog": 0.1}, "watchdog=...): a Connection is run as it was made"),
        ({"end_in": "stop", "baud": 115200}, "baud=..., end_in=...): a Connection"),
        ({"profile": ROOMBA500}, "the connection speaks to a create2; leave profile= out"),
    ],
)
def test_a_connection_is_run_as_it_was_made(
    given: dict[str, Any], said: str, tmp_path: Path
) -> None:
    """Its settings given to the stack as well are refused, not silently dropped."""
    connection = _connection()
    try:
        with pytest.raises(ValueError, match=re.escape(said)):
            RunStack(_mission(tmp_path), connection, **given)
    finally:
        connection.close()


def test_a_connection_taken_over_keeps_its_settings_and_records(tmp_path: Path) -> None:
    connection = _connection()
    path = tmp_path / "run.jsonl"
    stack = RunStack(_mission(tmp_path), connection, timeout_s=60.0,
                     record=Recording(path, "to-the-wall.yaml"))  # fmt: skip
    try:
        summary = stack.run()
    finally:
        stack.close()
    assert summary.outcome is Outcome.SUCCESS, summary
    assert stack.connection is connection and connection.watchdog == 0.2
    record = load_record(path)  # ended by stack.close(), the connection left open
    assert record.header["packets"] == list(stack.packets) and record.outbound
    assert not connection.ending.closed and connection.transport is stack.link
    connection.close()


def test_a_closed_connection_is_refused_when_handed_over(tmp_path: Path) -> None:
    """Its run had failed at the start-up's first write: "the port is gone (the cable was
    pulled ...)", of a port the program had closed itself."""
    connection = _connection()
    connection.close()
    said = "sim://empty-room: RunStack(mission, connection): the connection is closed"
    with pytest.raises(ConnectionClosed, match=re.escape(said)):
        RunStack(_mission(tmp_path), connection)


def test_a_with_runstack_leaves_a_handed_over_connection_open(tmp_path: Path) -> None:
    """Who opens closes: one connection, a ``with RunStack`` an episode (a gym-like env),
    each episode's loop over ``ticks()`` left early; every run ends stopped in Passive and
    the connection stays the program's."""
    connection = _connection()
    outcomes = []
    for _ in range(3):
        with RunStack(_mission(tmp_path), connection, timeout_s=60.0) as stack:
            for tick in stack.ticks():
                if tick.number == 20:
                    break
        outcomes.append(stack.summary.outcome)
        assert not connection.ending.closed and connection.mode.label == "Passive"
    assert outcomes == [Outcome.INTERRUPTED] * 3
    assert connection.close()


def test_a_link_needs_its_profile(tmp_path: Path) -> None:
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    with pytest.raises(TypeError, match=r"needs profile=, the robot's model: .*create2"):
        RunStack(_mission(tmp_path), link)


def test_runstack_takes_a_profile_by_its_name_as_connection_open_does(tmp_path: Path) -> None:
    """``RunStack(mission, link, profile="create2")`` was an AttributeError ('str' object has
    no attribute 'name') where ``Connection.open(port, profile="create2")`` took the name:
    every public entry now reads ``profile=`` by one rule (``oi.profiles.profile_given``)."""
    link = SimLink(Simulator(load_world("empty-room"), "create2", seed=0))
    with RunStack(_mission(tmp_path), link, profile="create2", timeout_s=60.0) as stack:
        summary = stack.run()
    assert summary.outcome is Outcome.SUCCESS, summary
    assert stack.connection.profile is CREATE2 and link.simulator.profile is CREATE2
    # the connection's own name and the stack's agree, so a handed-over one is taken
    connection = Connection(SimLink(Simulator(load_world("empty-room"), seed=0)), "create2")
    assert RunStack(_mission(tmp_path), connection, profile="create2").connection is connection
    connection.close()


@pytest.mark.parametrize(
    ("make", "said"),
    [
        (lambda m, link: RunStack(m, link, profile="auto"), r"^RunStack\(profile='auto'\): "),
        (lambda m, link: RunStack(m, link, profile="create3"), r"^RunStack\(profile='creat"),
        (lambda _, link: Connection(link, "create3"), r"^Connection\(profile='create3'\): un"),
        (lambda _, link: Connection(link, 2), r"^Connection\(profile=...\) takes a RobotProf"),
        (lambda *_: Simulator(load_world("empty-room"), "auto"), r"^Simulator\(profile='auto'"),
    ],
    ids=["runstack-auto", "runstack-unknown", "connection-unknown", "connection-int", "sim-auto"],
)
def test_a_profile_that_names_no_model_is_refused_naming_the_entry(
    make: Any, said: str, tmp_path: Path
) -> None:
    """The refusal names the entry and the models, as the mission functions' did: it was an
    AttributeError from RunStack, and an int given to Connection failed later, inside."""
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    with pytest.raises((ValueError, TypeError), match=said) as refused:
        make(_mission(tmp_path), link)
    assert "create2" in str(refused.value)
