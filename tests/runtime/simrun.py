"""Helpers for in-process runtime tests: missions on the simulator's virtual clock, every
byte tapped."""

from __future__ import annotations

import random
import textwrap
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world

if TYPE_CHECKING:
    from roomba_bt.runtime.stack import RunStack

#: Safe, then forward at 200 mm/s until a bump ends the drive.
DRIVE_TO_WALL = """
mission: to-the-wall
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s}
      until: {bump: {}}
"""
#: The same, then the tree's reaction to the bump: back off 5 cm.
DRIVE_TO_WALL_AND_BACK_OFF = DRIVE_TO_WALL + "    - drive: {velocity: -100 mm/s, distance: 50 mm}\n"
#: a 20 cm drive with its speed a parameter: the command line's tests run it, the
#: evaluation's set-up cache compiles it, tests/mission/test_escape.py mistypes its ``${``
SHORT_DRIVE = """
mission: short-drive
parameters:
  speed: {type: speed, default: 200 mm/s}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: "${speed}", distance: 20 cm}
"""

#: Safe, then spin in place at 100 mm/s until something ends the run: a robot that is
#: driving when a fault comes.
SPIN = """
mission: spin
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, radius: spin_left}
"""

#: A mission that leaves the robot in Passive, idle: the only mode a robot sleeps in.
WAIT_IN_PASSIVE = """
mission: wait-in-passive
tree:
  wait: 10min
"""


def spins_then_passive(name: str, *spins: tuple[str, str]) -> str:
    """A mission that goes to Safe, spins in place for each ``(wait, drive)`` of ``spins`` in
    turn (``("2s", "velocity: 100 mm/s, radius: spin_left")``: the drive for 2 s), and ends
    with ``mode: passive``: a run that ends well with the wheels last told to spin, the
    stop's bytes after its own."""
    phases = "".join(
        "    - parallel:\n        policy: one\n        children:\n"
        f"          - wait: {wait}\n          - drive: {{{drive}}}\n"
        for wait, drive in spins
    )
    return f"mission: {name}\ntree:\n  sequence:\n    - mode: safe\n{phases}    - mode: passive\n"


def write_mission(
    folder: Path, text: str, name: str = "mission.yaml", plugins: Mapping[str, str] | None = None
) -> Path:
    """``text`` (dedented) written as ``folder/name``, with each plugin file it loads (file
    name: source) beside it: the files a command line (``roomba-bt run FILE``) is given."""
    for plugin, source in (plugins or {}).items():
        (folder / plugin).write_text(source)
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


SAFE, START = bytes(opcodes("safe")), bytes(opcodes("start"))


class TapLink(SimLink):
    """A SimLink that keeps every chunk written and read, with the simulated time."""

    #: the bytes the port's buffer holds while nothing reads it (a freeze's): those the
    #: robot sent past them are lost (None: it holds every one)
    buffer: int | None = None

    def __init__(
        self,
        simulator: Simulator,
        stall_after: float | None = None,
        burst: int = 1,
        freeze: tuple[float, float] | None = None,
        jitter: float = 0.0,
    ) -> None:
        super().__init__(simulator)
        self.stall_after = stall_after
        self.burst = burst  # frames delivered per read, as a busy host or USB latency would
        #: (at, seconds): the first read after ``at`` comes ``seconds`` later, with every
        #: frame sent meanwhile: the process did not run (a laptop suspended) while the
        #: robot went on
        self.freeze = freeze
        self.writes: list[tuple[float, bytes]] = []
        self.reads: list[tuple[float, bytes]] = []
        #: each read's bytes are seen up to ``jitter`` seconds late (seeded): the arrival
        #: times (``now``) of a real-time link, a few ms late and then on time again
        self.jitter = jitter
        #: each read's arrival, as the link reads it (``now()`` after the read), as ``reads``
        self.arrivals: list[float] = []
        self._late = 0.0
        self._draws = random.Random(7)
        if jitter or burst > 1 or freeze is not None:  # reads off the simulator's steps
            self.read_step = None

    def write(self, data: bytes) -> None:
        self.writes.append((self.simulator.time, bytes(data)))
        super().write(data)

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        if self.freeze is not None and self.simulator.time >= self.freeze[0]:
            for _ in range(round(self.freeze[1] / 0.015)):
                self.simulator.step()
                data += self.simulator.read()
            self.freeze = None
            if self.buffer is not None:  # what the port's full buffer dropped meanwhile
                data = data[: self.buffer]
        if data and self.burst > 1:
            for _ in range(self.burst - 1):
                self.simulator.step()
            data += self.simulator.read()
        if self.stall_after is not None and self.simulator.time > self.stall_after:
            return b""  # the stream stalls; the port stays open
        if data:
            self.reads.append((self.simulator.time, data))
            if self.jitter:
                self._late = self._draws.uniform(0.0, self.jitter)
            self.arrivals.append(self.now())  # what the link takes for the bytes' arrival
        return data

    def now(self) -> float:
        return self.simulator.time + self._late

    @property
    def written(self) -> bytes:
        return b"".join(b for _, b in self.writes)


class BridgeLink(SimLink):
    """The simulator behind a WiFi-serial bridge, on the virtual clock: every byte takes
    ``latency`` seconds each way, plus up to ``jitter`` more (seeded; order kept, as TCP
    keeps it: a late chunk holds back those behind it), and during ``hold`` (at, seconds)
    nothing passes either way; the bytes held then come at once at its end (the bridge's
    hiccup, a power-save burst: no byte is lost). What the robot sends each step is one
    chunk; so is each write. A read takes at most ``most`` bytes (a backlog is read over
    several reads, as from a socket)."""

    read_step = None  # a read ends at its time: a record's replay waits as long

    def __init__(
        self,
        simulator: Simulator,
        latency: float = 0.02,
        jitter: float = 0.0,
        hold: tuple[float, float] | None = None,
        seed: int = 7,
        most: int = 256,
    ) -> None:
        super().__init__(simulator)
        self.most = most
        self.latency, self.jitter, self.hold = latency, jitter, hold
        self._draws = random.Random(seed)
        self._to_robot: list[tuple[float, bytes]] = []  # (when it reaches the robot, bytes)
        self._to_host: list[tuple[float, bytes]] = []  # (when the host can read it, bytes)
        self.writes: list[tuple[float, bytes]] = []  # (the simulated time of the write, bytes)

    def _passes(self, queue: list[tuple[float, bytes]], data: bytes) -> None:
        """``data`` on its way, at its time: its delay, never before what went before it,
        nor during the hold."""
        at = self.simulator.time + self.latency + self._draws.uniform(0.0, self.jitter)
        if queue:
            at = max(at, queue[-1][0])
        if self.hold is not None and self.hold[0] <= at < sum(self.hold):
            at = sum(self.hold)
        queue.append((at, data))

    def write(self, data: bytes) -> None:
        self._check()
        self.writes.append((self.simulator.time, bytes(data)))
        self._passes(self._to_robot, bytes(data))

    def read(self, timeout: float) -> bytes:
        sim = self.simulator
        deadline = sim.time + max(timeout, 0.0) - 1e-9
        while True:
            while self._to_robot and self._to_robot[0][0] <= sim.time:
                sim.receive(self._to_robot.pop(0)[1])
            sent = sim.read()
            if sent:
                self._passes(self._to_host, sent)
            came = b""
            while self._to_host and self._to_host[0][0] <= sim.time and len(came) < self.most:
                came += self._to_host.pop(0)[1]
            if came or sim.time >= deadline:
                return came
            sim.step()


@dataclass
class Run:
    summary: RunSummary
    link: TapLink
    simulator: Simulator
    runner: MissionRunner
    extra: dict[str, Any] = field(default_factory=dict)


RunMission = Callable[..., Run]


#: a room whose east half is a drop, the robot 0.8 m from its edge and facing it
LEDGE = """\
name: ledge
description: a room whose east half is a drop, the robot facing it
rooms:
  - [[0.0, 0.0], [4.0, 0.0], [4.0, 3.5], [0.0, 3.5]]
drops:
  - {name: ledge, rect: [2.0, 0.0, 4.0, 3.5]}
robot:
  start: {at: [1.2, 1.75], heading: 0}
  # for random starts (an evaluation): 0.6..1.6 m from the edge, facing it within 20 degrees
  start_region: {rect: [0.4, 0.6, 1.4, 2.9], heading: [-20, 20]}
  battery: 0.6
"""

#: For :data:`LEDGE`: over the edge, then Safe again and on over it: the robot falls to
#: Passive twice (from any start of its region).
TWICE_OVER_THE_EDGE = """\
mission: twice over the edge
tree:
  fallback:
    - sequence:
        - mode: safe
        - drive: {velocity: 200 mm/s, distance: 2 m}
    - sequence:
        - cliff: any
        - mode: safe
        - drive: {velocity: 100 mm/s, distance: 1 m}
"""


def over_the_edge(wait: str = "1s", brushes: bool = False, brushes_again: bool = False) -> str:
    """A mission for :data:`LEDGE`: forward until the robot falls to Passive by itself (at
    about 4.3 s), then, having seen the cliff, Safe again (``safe again``) and ``wait``;
    ``brushes``: the main brush and the vacuum on before the drive; ``brushes_again``: on
    after Safe again, as ``clean`` goes on after a fall (the command session 27's run1
    replay starved before)."""
    motors = "\n        - motors: {main_brush: true, vacuum: true}" if brushes else ""
    again = "\n          - motors: {main_brush: true, vacuum: true}" if brushes_again else ""
    return f"""\
mission: over the edge
tree:
  fallback:
    - sequence:
        - mode: safe{motors}
        - drive: {{velocity: 200 mm/s, distance: 2 m}}
    - sequence:
        name: after the cliff
        children:
          - cliff: any
          - {{name: safe again, mode: safe}}{again}
          - wait: {wait}
"""


class BusyAfterTheFall(SimLink):
    """The host is busy for ``busy_s`` between the frame that shows the robot's own fall to
    Passive (a cliff) and its tick's Safe: a loaded machine (a browser loading the monitor's
    page, the record's write). As the real-time simulator does at a write, the robot's world
    catches up first, so Safe goes out later on the link's clock than the frame it answers,
    and the frames sent meanwhile (still in Passive) queue up for the next read, where the
    runtime drops all but the newest as stale."""

    def __init__(self, simulator: Simulator, busy_s: float = 0.36) -> None:
        super().__init__(simulator)
        self.busy_s = busy_s
        #: the robot was in Safe or Full, and the host has sent no Start since (a monitor's
        #: pause ends in one): a Passive now is the robot's own fall
        self.driven = False

    def write(self, data: bytes) -> None:
        if self.driven and self.simulator.mode is OIMode.PASSIVE and data[:1] == SAFE:
            self.advance(self.busy_s)
            self.busy_s = 0.0
        super().write(data)
        driving = self.simulator.mode in (OIMode.SAFE, OIMode.FULL)
        self.driven = (self.driven or driving) and data[-1:] != START


#: a plugin's leaf: drives at 300 mm/s, and its terminate notes the wheel command the robot
#: last had (tests/runtime/test_tick_guard.py, test_interrupts.py)
SLOW_TERM = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes

@declare("slow_term", kind="action", sends=opcodes("drive"))
class SlowTerm(Action):
    """Drives; its terminate would block (a plugin's time.sleep): it notes the wheels then."""

    SEEN = []  # the class's: nothing is set on a node

    def start(self):
        self.send(commands.drive(300, 32767))

    def update(self):
        return Status.RUNNING

    def terminate(self, new_status):
        if new_status == Status.INVALID:
            self.SEEN.append(getattr(self.robot.connection.writer.last_wheels, "args", None))
        super().terminate(new_status)
'''


#: the source of a function a plugin's blocking method calls (the plugin's source ends with
#: it): the tick waits until the tick guard has stopped the wheels behind its back, at most
#: :data:`~waits.HANG_S` (10 s before: a guard thread kept from the 2 cores that long let the
#: tick go on unguarded), so that a test of the guard waits for its act, not for a time that
#: depends on the machine's speed (tests/runtime/test_tick_guard.py, test_stop_on_a_slow_link.py;
#: :func:`wait_for_the_guard` in the test's own process)
WAITS_FOR_THE_GUARD = f'''

import time


def wait_for_the_guard(robot):
    """Blocks until the wheels were stopped behind the tick's back (at most {HANG_S:g} s)."""
    writer = robot.connection.writer
    deadline = time.monotonic() + {HANG_S!r}
    while getattr(writer.last_wheels, "args", None) != (0, 0):
        if time.monotonic() > deadline:
            break
        time.sleep(0.002)
'''


def wait_for_the_guard(robot: Any) -> None:
    """:data:`WAITS_FOR_THE_GUARD`'s wait, for a tick blocked in the test's own process (a
    plain behaviour, a program's loop over ``stack.ticks()``): until the tick guard has
    stopped ``robot.connection``'s wheels behind its back, at most :data:`~waits.HANG_S`
    (3 s, then 10 s before, which a guard thread on a loaded machine may need)."""
    writer = robot.connection.writer
    deadline = time.monotonic() + HANG_S
    while getattr(writer.last_wheels, "args", None) != (0, 0) and time.monotonic() < deadline:
        time.sleep(0.002)


def guard_looks(monkeypatch: Any) -> threading.Event:
    """An event set each time a tick guard looks where a tick past its limit is
    (``TickGuard._where``, which it does when it acts, its wheels moving or not): a tick
    that blocks on it returns only once the guard has seen it, whatever the machine's
    speed. ``monkeypatch``: the test's, which puts the guard back after it."""
    from roomba_bt.runtime.tick_guard import TickGuard

    seen = threading.Event()
    looked = TickGuard._where

    def where(self: TickGuard) -> str:
        found = looked(self)
        seen.set()
        return found

    monkeypatch.setattr(TickGuard, "_where", where)
    return seen


class Raises(py_trees.behaviour.Behaviour):
    """A plain py_trees behaviour (no plugin's): RUNNING, and raises ``exc`` in ``where``
    (setup, initialise, update or terminate); its tenth update raises, or else succeeds (it
    ends a parallel around it, and its terminate comes)."""

    def __init__(self, exc: BaseException, where: str, name: str = "telemetry") -> None:
        super().__init__(name)
        self.exc, self.where, self.ticks = exc, where, 0

    def _maybe(self, where: str) -> None:
        if where == self.where:
            raise self.exc

    def setup(self, **kwargs: object) -> None:
        self._maybe("setup")

    def initialise(self) -> None:
        self._maybe("initialise")

    def update(self) -> py_trees.common.Status:
        self.ticks += 1
        if self.ticks == 10:
            self._maybe("update")
            return py_trees.common.Status.SUCCESS
        return py_trees.common.Status.RUNNING

    def terminate(self, new_status: py_trees.common.Status) -> None:
        if new_status is not py_trees.common.Status.INVALID:
            self._maybe("terminate")


def run_in_a_worker(stack: RunStack) -> tuple[threading.Thread, list[RunSummary | BaseException]]:
    """``stack.run()`` in a thread of its own, started; what it returned or raised lands in
    the list (the test says what it was)."""
    result: list[RunSummary | BaseException] = []

    def work() -> None:
        try:
            result.append(stack.run())
        except BaseException as exc:
            result.append(exc)

    worker = threading.Thread(target=work, name="worker")
    worker.start()
    return worker, result


def stream_gap_link() -> SimLink:
    """The simulator's stream pauses 0.5 s at 1 s (``sim --stream-gap-at 1``): the watchdog
    stops the wheels, and the stall is ridden through."""
    faults = Faults(stream_gap_at=1.0, stream_gap_s=0.5)
    return SimLink(Simulator(load_world("empty-room"), CREATE2, 0, faults))


def record_run(tmp_path: Path, link: SimLink, mission: str = SPIN, **options: Any) -> Path:
    """The record (``run --record``) of ``mission`` run 3 s on ``link``; ``options``: the
    rest of :class:`RunStack`'s (``tick_limit``)."""
    from roomba_bt.mission import load_mission
    from roomba_bt.runtime.stack import Recording, RunStack

    source, path = tmp_path / "m.yaml", tmp_path / "run.jsonl"
    source.write_text(mission)
    loaded = load_mission(source, {}, profile=CREATE2)
    stack = RunStack(loaded, link, profile=CREATE2, timeout_s=3.0,
                     record=Recording(path, str(source)), **options)  # fmt: skip
    stack.run()
    stack.close()  # the record's end line
    return path


class LosesTheOpcodeOf(SimLink):
    """The simulator's link on its virtual clock, losing the first byte of the first write of
    ``command`` (its opcode), as a bad cable does: the robot reads its data bytes as commands
    (a Drive's as a Song of 255 notes, or as Baud). ``written``: what reached the line."""

    def __init__(self, simulator: Simulator, command: bytes) -> None:
        super().__init__(simulator)
        self.command = command
        self.lost = False
        self.written = bytearray()

    @property
    def loses_bytes(self) -> bool:
        """A line that loses bytes to the robot: the stop is listened and asked after."""
        return True

    def write(self, data: bytes) -> None:
        if not self.lost and bytes(data) == self.command:
            self.lost = True
            data = data[1:]
        self.written += data
        super().write(data)
