"""The port's rate around a listen at another OI rate (robot/listen.py, robot/silence.py), on
the virtual clock, in process: each write kept with the rate the port had for it.

A safety audit (session 29) found two ways the listen hurt the robot it protects: a signal
inside it left the port at 19200 and the whole safe stop went out there (the robot, at
115200, drove on in Safe with its brushes on), and the watchdog's drive 0 just before it was
re-clocked by the switch (the robot heard 3 of 11). And a merely noisy line (bytes coming,
the robot's frames damaged) was listened at 19200 at most trips, where the robot never is."""

from __future__ import annotations

import json
import signal
import threading
from pathlib import Path

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.recording import RecordingTransport
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world
from roomba_bt.sim.link import at_wrong_baud

from .simrun import SPIN

RUN_RATE = CREATE2.default_baud
DRIVE_0 = oi.halt().data
#: when the line turns to garbage with no frame shape in it (simulated s): the robot spins
GARBLED_FROM = 3.0


class RateTap(SimLink):
    """A SimLink that keeps each write with the port's rate then, and each rate change and
    drain in order (``events``). From :data:`GARBLED_FROM` the robot's bytes reach the host
    scrambled at every rate (noise that leaves no frame's shape: the robot's rate is not
    found anywhere), so the watchdog trips and the port listens at 19200."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.events: list[tuple[str, int, bytes]] = []

    def write(self, data: bytes) -> None:
        self.events.append(("write", self.baud, bytes(data)))
        super().write(data)

    def set_baud(self, baud: int) -> None:
        self.events.append(("set_baud", baud, b""))
        super().set_baud(baud)

    def drain_output(self) -> None:
        self.events.append(("drain", self.baud, b""))

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        return at_wrong_baud(data) if self.simulator.time >= GARBLED_FROM else data

    def writes_after(self, index: int) -> list[tuple[int, bytes]]:
        return [(rate, data) for kind, rate, data in self.events[index:] if kind == "write"]


class CtrlCInTheListen(RateTap):
    """Ctrl-C (KeyboardInterrupt, as the runtime's handler raises it) at the first read with
    the port at another rate: inside the listen's window."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.interrupted_at: int | None = None

    def read(self, timeout: float) -> bytes:
        if self.baud != RUN_RATE and self.interrupted_at is None:
            self.interrupted_at = len(self.events)
            raise KeyboardInterrupt
        return super().read(timeout)


class CtrlCInTheRateChanges(RateTap):
    """Two Ctrl-Cs: one inside the change to 19200 (the port already there: a signal in
    pyserial's reconfiguration, after its ``tcsetattr``), one inside the change back (before
    it took effect). The port is left at 19200 whatever the listen does on its way out: the
    safe stop must set the robot's rate itself."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.interrupts = 0
        self.interrupted_at: int | None = None

    def set_baud(self, baud: int) -> None:
        if baud != RUN_RATE and self.interrupts == 0:
            super().set_baud(baud)
            self.interrupts, self.interrupted_at = 1, len(self.events)
            raise KeyboardInterrupt
        if self.interrupts == 1:
            self.interrupts = 2
            raise KeyboardInterrupt  # the second Ctrl-C, before the port changed back
        super().set_baud(baud)


def run_on(
    tmp_path: Path, link: SimLink, simulator: Simulator, timeout: float = 10.0
) -> RunSummary:
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    mission = load_mission(path, {}, profile=CREATE2)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=timeout)
    summary = stack.run(raise_interrupts=False)
    stack.close()
    return summary


def simulator(faults: Faults | None = None) -> Simulator:
    return Simulator(load_world("empty-room"), CREATE2, 0, faults or Faults(), trace=False)


def assert_stopped_in_passive(sim: Simulator) -> None:
    assert sim.ignored_bytes == 0, f"{sim.ignored_bytes} bytes came at another rate"
    assert sim.mode is OIMode.PASSIVE, sim.mode
    assert sim.requested_left == sim.requested_right == 0


def test_ctrl_c_inside_the_listen_the_safe_stop_goes_at_the_robots_rate(
    tmp_path: Path,
) -> None:
    """Before: the port stayed at 19200, every byte of the stop went there, and the robot
    (at 115200) spun on in Safe; the summary blamed the robot's silence."""
    sim = simulator()
    link = CtrlCInTheListen(sim)
    summary = run_on(tmp_path, link, sim)
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert link.interrupted_at is not None, "no listen at another rate happened"
    after = link.writes_after(link.interrupted_at)
    assert after, "no stop was written"
    assert {rate for rate, _ in after} == {RUN_RATE}, after
    assert b"".join(data for _, data in after).endswith(oi.pause_stream().data + oi.start().data)
    assert_stopped_in_passive(sim)


def test_a_port_left_at_another_rate_is_set_back_before_the_safe_stop(tmp_path: Path) -> None:
    """Whatever state a listen cut short leaves the port in (here at 19200, its change back
    interrupted too), the safe stop sets the robot's rate before it writes."""
    sim = simulator()
    link = CtrlCInTheRateChanges(sim)
    summary = run_on(tmp_path, link, sim)
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert link.interrupted_at is not None, "no listen at another rate happened"
    assert {rate for rate, _ in link.writes_after(link.interrupted_at)} == {RUN_RATE}
    assert_stopped_in_passive(sim)
    assert link.interrupts == 2  # the change back was cut short too: the stop set the rate
    after = link.events[link.interrupted_at :]
    first_write = next(i for i, event in enumerate(after) if event[0] == "write")
    assert ("set_baud", RUN_RATE, b"") in after[:first_write], after


def test_the_watchdogs_drive_0_is_drained_before_the_port_changes_its_rate(
    tmp_path: Path,
) -> None:
    """The switch to 19200 came right after the drive 0 was written: on a real port its
    bytes, still in the driver's buffer, went out at 19200 (the robot heard 3 of 11)."""
    sim = simulator()
    link = RateTap(sim)
    summary = run_on(tmp_path, link, sim, timeout=GARBLED_FROM + 1.0)
    assert summary.stalls >= 1
    events = link.events
    switches = [i for i, (kind, rate, _) in enumerate(events) if kind == "set_baud"]
    assert switches and events[switches[0]][1] != RUN_RATE, "no listen at another rate"
    drive_0 = max(i for i, (kind, _, data) in enumerate(events[: switches[0]]) if data == DRIVE_0)
    kinds = [kind for kind, _, _ in events[drive_0 + 1 : switches[0]]]
    assert "drain" in kinds, events[drive_0 : switches[0] + 1]
    assert events[drive_0][1] == RUN_RATE


def test_a_noisy_line_at_the_robots_rate_is_not_listened_at_another(tmp_path: Path) -> None:
    """5 % of the robot's bytes with a bit flipped: its frames come damaged (their header,
    length and packet ids in place), so the robot talks at the run's rate. The port stays
    there: every watchdog drive 0 is written at it, and the robot hears each one (before,
    the port went to 19200 at most trips)."""
    sim = simulator(Faults(bit_flip_rate=0.05))
    link = RateTap(sim)
    link_read = SimLink.read  # no scrambling: the noise is the simulator's bit flips

    def read(timeout: float) -> bytes:
        return link_read(link, timeout)

    link.read = read  # type: ignore[method-assign]
    summary = run_on(tmp_path, link, sim, timeout=6.0)
    assert summary.stalls >= 3, summary.stall_text()
    assert summary.stall_halts >= 1
    assert [e for e in link.events if e[0] == "set_baud"] == []
    assert {rate for kind, rate, _ in link.events if kind == "write"} == {RUN_RATE}
    assert "another OI rate" not in summary.reason


def test_the_record_notes_each_change_of_the_ports_rate(tmp_path: Path) -> None:
    """The record showed a well-formed stop written at 19200: nothing in it said the rate.
    Each change is a note now, the listen and the port put back."""
    sim = simulator()
    record = tmp_path / "rec.jsonl"
    link = RecordingTransport(RateTap(sim), record, {"profile": "create2", "baud": RUN_RATE})
    run_on(tmp_path, link, sim, timeout=GARBLED_FROM + 1.0)  # type: ignore[arg-type]
    notes = [
        json.loads(line)["note"]
        for line in record.read_text().splitlines()[1:]
        if '"d": "note"' in line
    ]
    rates = [note["baud"] for note in notes if "baud" in note]
    assert rates[:2] == [19200, RUN_RATE], notes


class SignalInTheListen(SimLink):
    """SIGINT to the main thread at the first read with the port at another rate: a real
    signal (not an exception raised from the read), inside the listen's window."""

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.signalled = False

    def read(self, timeout: float) -> bytes:
        if self.baud != RUN_RATE and not self.signalled:
            self.signalled = True
            signal.pthread_kill(threading.main_thread().ident or 0, signal.SIGINT)
        return super().read(timeout)


def test_a_signal_inside_a_listen_that_finds_the_robot_waits_for_the_port_to_follow(
    tmp_path: Path,
) -> None:
    """The robot did change its rate (to 19200, streaming on). A Ctrl-C inside the listen
    that finds it waits for the listen's end (a few tenths of a second at most): the port
    follows the robot and the safe stop reaches it there. Put back at once, the port would
    send the stop at 115200, which the robot no longer hears. (A guard on the put-back of
    this fix: the old code, which left the port where the listen had it, got this case
    right by accident.)"""
    sim = simulator(Faults(baud_change_at=GARBLED_FROM))
    link = SignalInTheListen(sim)
    summary = run_on(tmp_path, link, sim)
    assert link.signalled, "no listen at another rate happened"
    assert summary.outcome is Outcome.INTERRUPTED, summary.reason
    assert sim.mode is OIMode.PASSIVE, sim.mode
    assert sim.requested_left == sim.requested_right == 0
