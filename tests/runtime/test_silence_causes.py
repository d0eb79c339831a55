"""Why no valid frame comes (robot/silence.py), on the virtual clock, in process.

Nothing on the line: the robot is asked once the grace runs out; one that answers stopped
streaming, one that answers only after a BRC pulse was asleep (at any time, not only after
the OI's five minutes), one that never answers is switched off or cut off. Garbage on the
line: the robot's port changed its rate in the middle of the run (a battery swap or a reset
brings a Create 2 back at its default rate); the run names it, follows it and stops the robot
at the new rate, and noise at the run's rate is not taken for one."""

from __future__ import annotations

import contextlib
import errno
import random
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.mission import load_mission
from roomba_bt.oi import commands as oi
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, RobotProfile
from roomba_bt.robot.silence import LISTEN_S, listen_window
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import DEFAULT_GRACE, Outcome, RunSummary
from roomba_bt.sim import Faults, SimLink, Simulator, load_world
from roomba_bt.sim.world import parse_world
from roomba_bt.transport.testing import NullTransport

from .simrun import SPIN, WAIT_IN_PASSIVE, TapLink


class NoModemLines(SimLink):
    """A link whose modem lines cannot be set (a pty): BRC cannot be pulsed."""

    def set_wake_line(self, low: bool) -> None:
        raise OSError(25, "Inappropriate ioctl for device")


class DeafAtFirstListen(SimLink):
    """A link whose host hears nothing for ``deaf_s`` of simulated time from the first time it
    turns its port to another rate (a loaded host, a hiccup of the robot's port): the
    robot's frames meanwhile are lost, so a listen shorter than that finds none."""

    deaf_s = 0.15

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.deaf_until: float | None = None

    def set_baud(self, baud: int) -> None:
        super().set_baud(baud)
        if self.deaf_until is None and baud != self.simulator.profile.default_baud:
            self.deaf_until = self.simulator.time + self.deaf_s

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        deaf_until = self.deaf_until
        return b"" if deaf_until is not None and self.simulator.time < deaf_until else data


def run(
    tmp_path: Path,
    text: str,
    faults: Faults,
    link_type: type[SimLink] = SimLink,
    timeout: float = 60.0,
    robot_baud: int | None = None,
    profile: RobotProfile = CREATE2,
) -> tuple[RunSummary, Simulator]:
    path = tmp_path / "m.yaml"
    path.write_text(text)
    mission = load_mission(path, {}, profile=profile)
    simulator = Simulator(load_world("empty-room"), profile, 0, faults, trace=False)
    if robot_baud is not None:
        simulator.baud = robot_baud  # the robot's port (sim --baud), the run at 115200
    stack = RunStack(mission, link_type(simulator), profile=profile, timeout_s=timeout)
    summary = stack.run()
    stack.close()
    return summary, simulator


def test_a_robot_that_answers_after_a_pulse_too_soon_to_sleep_is_not_called_asleep(
    tmp_path: Path,
) -> None:
    """Silent 5 s into Passive, answering after a BRC pulse: the OI sleeps only after 5
    minutes in Passive with nothing from the host, so this is said as seen (the stream
    stopped and came back after a pulse), not "asleep" with advice to buy a BRC cable."""
    summary, simulator = run(tmp_path, WAIT_IN_PASSIVE, Faults(sleep_at=5.0))
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert summary.exit_code == 8
    reason = summary.reason
    assert re.search(r"the stream stopped for \d\.\d s and came back \(a frozen adapter", reason)
    assert "it answered again after a BRC pulse (pulsed BRC low for 1 s" in reason, reason
    assert "having been 5 s in Passive without a command or a pulse from us: too soon" in reason
    assert "asleep" not in reason and "-0 s" not in reason
    assert [e.kind for e in simulator.events if e.kind in ("sleep", "wake")] == ["sleep", "wake"]
    assert not simulator.asleep and simulator.mode is OIMode.PASSIVE
    assert summary.stop_delivered  # it answered after the pulse: it hears the stop


class SwitchedOffAt3s(SimLink):
    """A robot switched off (or its cable cut inside the plug) 3 s in: from then on nothing
    comes from it and nothing written reaches it, while the port stays open."""

    def _off(self) -> bool:
        return self.simulator.time >= 3.0

    def write(self, data: bytes) -> None:
        if not self._off():
            super().write(data)

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        return b"" if self._off() else data


DRIVE_IN_SAFE = "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 100 mm/s}\n"


def test_a_robot_silent_in_safe_is_neither_called_asleep_nor_hung_up_on(tmp_path: Path) -> None:
    """Safe and Full never sleep: a robot last seen driving in Safe that answers no query is
    asked once more, with no BRC pulse."""
    summary, simulator = run(tmp_path, DRIVE_IN_SAFE, Faults(), SwitchedOffAt3s)
    assert "asleep" not in summary.reason, summary.reason
    assert "it answered no query, asked twice 1 s apart, and it was in Safe, which never " \
        "sleeps: switched off, a flat battery, or the cable" in summary.reason  # fmt: skip
    assert simulator.brc_pulses == 1  # keep-awake's first only: no wake pulse
    assert not summary.stop_delivered


def test_the_sleep_fault_waits_for_passive_as_safe_never_sleeps(tmp_path: Path) -> None:
    """``sim --sleep-at`` due while the robot drives in Safe: no robot sleeps there (the OI
    spec: "In Safe and Full modes, Roomba will never sleep"), so the run drives on to its end
    and the robot sleeps only once the safe stop left it in Passive. Before, the simulator
    slept in Safe and the run, rightly for a real robot, reasoned "in Safe, which never
    sleeps" and tried no BRC pulse."""
    summary, simulator = run(tmp_path, DRIVE_IN_SAFE, Faults(sleep_at=1.0), timeout=3.0)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason
    assert summary.stop_delivered
    assert not [e for e in simulator.events if e.kind == "sleep"], "no sleep in Safe"
    simulator.run(1.1)  # left powered in Passive after the run, idle a second: it sleeps
    sleeps = [e for e in simulator.events if e.kind == "sleep"]
    assert [e.detail for e in sleeps] == [
        "fault: sleep, once in Passive (Safe and Full never sleep)"
    ]
    assert simulator.asleep and simulator.mode is OIMode.PASSIVE


class FrozenAdapter(NoModemLines):
    """A USB adapter that freezes for :attr:`FREEZE_S` from :attr:`FREEZE_AT` (simulated
    time): nothing comes from the robot meanwhile, and what the host writes waits in the
    adapter's queue, to reach the robot when it thaws. A hang-up (the BRC pulse of a port
    without modem lines) throws the queue away, as speed 0 does on a pty."""

    FREEZE_AT, FREEZE_S = 3.0, 3.0

    def __init__(self, simulator: Simulator) -> None:
        super().__init__(simulator)
        self.queued: list[bytes] = []
        #: what reached the robot, at its simulated time
        self.delivered: list[tuple[float, bytes]] = []

    def _frozen(self) -> bool:
        return self.FREEZE_AT <= self.simulator.time < self.FREEZE_AT + self.FREEZE_S

    def _thaw(self) -> None:
        if not self._frozen():
            for data in self.queued:
                self.delivered.append((self.simulator.time, data))
                super().write(data)
            self.queued.clear()

    def write(self, data: bytes) -> None:
        self.queued.append(data)
        self._thaw()

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        self._thaw()
        return b"" if self._frozen() else data

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        self.queued.clear()
        yield


def test_a_line_that_froze_in_safe_is_said_frozen_and_the_watchdog_s_drive_0_arrives(
    tmp_path: Path,
) -> None:
    """The robot, driving in Safe, frozen behind its adapter for 3 s: it was called asleep
    ("answered nothing until a BRC pulse woke it"; buy a cable with BRC on RTS or DTR), and the
    hang-up that pulsed BRC threw away the watchdog's drive 0 waiting in the adapter's queue:
    the robot spun on until the final stop. Now no pulse (Safe never sleeps): the queue
    reaches the robot as the adapter thaws, the watchdog's drive 0 first, and the run says the
    stream stopped and came back."""
    (tmp_path / "m.yaml").write_text(SPIN)
    link = FrozenAdapter(Simulator(load_world("empty-room"), CREATE2, 0, trace=False))
    mission = load_mission(tmp_path / "m.yaml", {}, profile=CREATE2)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=60)
    summary = stack.run()
    stack.close()
    reason = summary.reason
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert re.search(r"the stream stopped for \d\.\d s and came back \(a frozen adapter", reason)
    assert "it answered again, in Safe, which never sleeps" in reason, reason
    assert "asleep" not in reason and "BRC on RTS" not in reason
    thawed = FrozenAdapter.FREEZE_AT + FrozenAdapter.FREEZE_S
    first_halt = min(t for t, data in link.delivered if data == oi.halt().data and t >= 3.0)
    assert first_halt < thawed + 0.05, link.delivered  # the watchdog's, as the adapter thawed
    assert summary.stop_delivered and "sent drive, motors" in summary.safe_stop


#: a room whose floor drops away 0.8 m ahead of the robot, facing it
_TO_A_DROP = """
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
drops: [{rect: [1.8, 0, 4, 4]}]
robot: {start: {at: [1, 2], heading: 0}}
"""


def test_a_robot_that_answers_after_a_freeze_is_said_in_the_mode_it_answered_with(
    tmp_path: Path,
) -> None:
    """Driving in Safe toward a drop, the line frozen for 3 s: meanwhile the robot meets the
    cliff and falls to Passive by itself. It answers in Passive, and is said so: the run
    said "it answered again, in Safe, which never sleeps", the mode it was last seen in."""
    (tmp_path / "m.yaml").write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 200 mm/s}\n"
    )
    simulator = Simulator(parse_world(_TO_A_DROP, "<test>"), CREATE2, 0, trace=False)
    link = FrozenAdapter(simulator)
    mission = load_mission(tmp_path / "m.yaml", {}, profile=CREATE2)
    stack = RunStack(mission, link, profile=CREATE2, timeout_s=60)
    summary = stack.run()
    stack.close()
    falls = [e.detail for e in simulator.events if e.kind == "mode"]
    assert any("Safe->Passive (safety: cliff" in d for d in falls), falls  # in the freeze
    assert "it answered again, in Passive (last seen in Safe, which never sleeps)" in (
        summary.reason
    ), summary.reason


def test_the_oracles_stream_gap_is_ridden_through_the_wheels_stopped_within_150_ms(
    tmp_path: Path,
) -> None:
    """``sim --stream-gap-at``: no frame for 0.8 s (the oracle's stream loss), then the
    stream goes on: drive 0 within 150 ms of the last frame, the spin again after the gap,
    the run ends by its timeout, not as a lost connection."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    simulator = Simulator(
        load_world("empty-room"), CREATE2, 0, Faults(stream_gap_at=3.0), trace=False
    )
    link = TapLink(simulator)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2, timeout_s=6)
    summary = stack.run()
    stack.close()
    assert summary.outcome is Outcome.TIMEOUT, summary.reason
    assert summary.stalls == 1 and summary.stalls_ridden == 1
    last_frame = max(t for t, b in link.reads if b and t <= 3.0)
    halts = [t for t, b in link.writes if b == oi.halt().data and 3.0 <= t < 3.8]
    assert halts and halts[0] - last_frame <= 0.15
    spin = oi.drive(100, oi.Radius.TURN_COUNTER_CLOCKWISE).data
    back = min(t for t, b in link.reads if b and t > 3.0)  # the stream asked for again at
    assert 3.6 < back < 3.8  # a third of the grace: the gap ended there, not at 3.8 s
    assert any(b == spin for t, b in link.writes if back <= t < back + 0.1)  # commanded again
    assert [e.detail for e in simulator.events if e.kind == "fault"] == [
        "stream gap",
        "stream gap end",
    ]


class LosesTheAsks(SimLink):
    """A line that loses every write that begins with zeros: the stream asked for again
    (robot/stall_asks.py) never reaches the robot."""

    def write(self, data: bytes) -> None:
        if not data.startswith(b"\x00"):
            super().write(data)


def test_a_robot_that_stopped_streaming_by_itself_streams_again_when_asked(
    tmp_path: Path,
) -> None:
    """The stream asked for again within the grace comes back: the run rides the gap
    through and ends by its timeout (it ended "the robot still answers a query", exit 3)."""
    summary, simulator = run(tmp_path, SPIN, Faults(stream_stop_at=3.0), timeout=6.0)
    assert summary.outcome is Outcome.TIMEOUT, summary.reason
    assert (summary.stalls, summary.stalls_ridden) == (1, 1)
    assert summary.stop_delivered and simulator.mode is OIMode.PASSIVE


def test_a_robot_that_only_stopped_streaming_is_said_to_still_answer(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, SPIN, Faults(stream_stop_at=3.0), LosesTheAsks)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the sensor stream stopped" in summary.reason
    assert "the robot still answers a query (its OI is on)" in summary.reason
    assert "the stream was asked for again 2 times within the grace" in summary.reason
    assert "asleep" not in summary.reason
    assert simulator.brc_pulses == 1  # keep-awake's first only: it answered, no wake pulse
    assert summary.stop_delivered and simulator.mode is OIMode.PASSIVE


def test_a_robot_that_cannot_be_pulsed_is_not_called_asleep(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, WAIT_IN_PASSIVE, Faults(sleep_at=5.0), NoModemLines)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the sensor stream stopped" in summary.reason
    assert "no BRC pulse could wake it" in summary.reason
    assert [e.kind for e in simulator.events if e.kind == "wake"] == []  # no pulse woke it
    assert not summary.stop_delivered  # a robot that answers nothing: the stop not known
    assert "unconfirmed: the robot answers nothing" in summary.safe_stop


class UnpluggedInTheSilence(NoModemLines):
    """A pty whose device is gone by the time the silence is asked about: the hang-up that
    pulses BRC fails as an unplugged adapter's port does (EIO)."""

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        raise OSError(errno.EIO, "Input/output error")
        yield  # a context manager's shape


def test_a_port_that_vanished_in_the_silence_is_said_gone_not_unpulsed(tmp_path: Path) -> None:
    """The robot went quiet, then the cable was pulled: the hang-up's EIO was said as "no BRC
    pulse could wake it ... Input/output error", the advice of a robot asleep or off."""
    summary, _ = run(tmp_path, WAIT_IN_PASSIVE, Faults(sleep_at=5.0), UnpluggedInTheSilence)
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert (
        "the port is gone (the cable was pulled or the adapter reset): it failed on a BRC "
        "pulse ([Errno 5] Input/output error)"
    ) in summary.reason
    assert "no BRC pulse could wake it" not in summary.reason
    assert not summary.stop_delivered and "the port had failed before it" in summary.safe_stop


def assert_followed_and_stopped(
    summary: RunSummary, simulator: Simulator, change: float, within: float
) -> None:
    """The run named the change to 19200 and sent drive 0 again there; the stop reached the
    robot at its new rate (stopped, in Passive) within ``within`` s of the change."""
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 8
    assert "the robot now talks at another baud rate: 19200, not the 115200" in summary.reason
    assert "drive 0 sent again at 19200" in summary.reason
    assert summary.stop_delivered
    assert simulator.mode is OIMode.PASSIVE
    assert simulator.requested_left == simulator.requested_right == 0
    stops = [e.time for e in simulator.events if e.kind == "mode" and "Passive" in e.detail]
    assert stops and stops[-1] - change <= within


def test_a_baud_change_mid_run_is_named_followed_and_the_robot_stopped(tmp_path: Path) -> None:
    summary, simulator = run(tmp_path, SPIN, Faults(baud_change_at=3.0), timeout=10.0)
    # the garbage as a duration and a count, like the other causes (no time of day)
    assert re.search(r"no valid sensor frame for \d+ ms while \d+ bytes arrived", summary.reason)
    assert not re.search(r"\d\d:\d\d:\d\d", summary.reason), summary.reason
    # stopped within the watchdog, the listen and a slot or two of the change
    assert_followed_and_stopped(summary, simulator, 3.0, 0.1 + 0.1 + 0.06)


class DeafAtTheNewRate(SimLink):
    """A link whose robot talks at its new rate after a change but hears nothing written
    there (its frames read valid at 19200, what is sent at 19200 is lost): the port followed
    it on its frames alone, and the stop sent there does not arrive."""

    def write(self, data: bytes) -> None:
        if self.baud != self.simulator.profile.default_baud:
            self.simulator.ignored_bytes += len(data)
            return
        super().write(data)


def test_a_stop_at_a_followed_rate_the_robot_does_not_answer_is_unconfirmed(
    tmp_path: Path,
) -> None:
    """The summary must not claim a delivered stop and a Passive it did not see: the stop at
    the followed rate is confirmed by the robot's answer to a Query List there, or not."""
    summary, simulator = run(
        tmp_path, SPIN, Faults(baud_change_at=3.0), DeafAtTheNewRate, timeout=10.0
    )
    assert "the robot now talks at another baud rate: 19200" in summary.reason
    assert not summary.stop_delivered
    # the drive 0s at either rate went unheard: it spins on, and is not said "stopped"
    assert summary.safe_stop.startswith(
        "NOT DELIVERED: last seen in Safe spinning left at 100 mm/s (then the drive 0 at the "
        "rate followed, which no frame showed heard); "
    ), summary.safe_stop
    assert "unconfirmed: the port followed the robot to 19200 baud" in summary.safe_stop
    assert summary.final_mode_text().startswith("unknown"), summary.final_mode_text()
    assert simulator.mode is not OIMode.PASSIVE, "it never heard the stop"
    said = str(summary)
    assert_quoted("docs/runtime.md", "safe stop NOT DELIVERED: ... unconfirmed: the port", said)
    assert_quoted("docs/reliability.md", "safe stop NOT DELIVERED: ... the stop was", said)
    assert_quoted("docs/reliability.md", "final mode unknown: last seen in ...", said)


def test_a_robot_at_another_rate_from_the_start_is_named_and_left_in_passive(
    tmp_path: Path,
) -> None:
    """The robot at 19200 (Clean held at power-off), the run at 115200: no answer at the
    run's rate, so the other OI rate is asked before the run gives up, and named."""
    summary, simulator = run(tmp_path, SPIN, Faults(), robot_baud=19200)
    # never connected: "no connection", not "connection lost"; the same exit code
    assert summary.outcome is Outcome.NO_CONNECTION and summary.exit_code == 3
    assert "the robot answers at 19200 baud, not at the 115200 of the run" in summary.reason
    assert (
        "open it at 19200 (--baud 19200 or --baud auto; in Python, "
        "Connection.open(port, baud=19200))" in summary.reason
    )
    assert "likely causes" not in summary.reason
    assert simulator.mode is OIMode.PASSIVE  # never driven; the stop went at 19200
    assert simulator.requested_left == simulator.requested_right == 0


def test_a_roomba500_at_19200_is_given_its_own_procedure_not_a_create2_s(tmp_path: Path) -> None:
    """The 500 spec: Clean held "when powering on"; it said "a Create 2 talks at 19200 after
    Clean was held at power-off" to a run with --profile roomba500."""
    summary, _ = run(tmp_path, SPIN, Faults(), robot_baud=19200, profile=ROOMBA500)
    assert summary.exit_code == 3
    assert "on the Roomba 500 series, 19200 comes after its Clean button was held while it " \
        "powered on" in summary.reason  # fmt: skip
    assert "Create 2" not in summary.reason and "power-off" not in summary.reason


def test_a_robot_silent_at_every_rate_keeps_the_likely_causes(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    simulator.fall_asleep("test")  # deaf at every rate; the run pulses no BRC at start-up
    stack = RunStack(load_mission(path, {}, profile=CREATE2), SimLink(simulator), profile=CREATE2)
    summary = stack.run()
    stack.close()
    assert summary.exit_code == 3
    assert "the robot did not answer two Query Lists (149) for packet 35" in summary.reason
    assert "likely causes: wrong baud rate" in summary.reason
    assert "answers at" not in summary.reason
    # nothing was ever heard: its mode is not known, and the stop (written: a robot that
    # hears but cannot answer is stopped by it) is not claimed delivered
    assert not summary.robot_answered
    assert "final mode   unknown: no robot answered" in str(summary)
    assert summary.safe_stop == (
        "nothing this run set going; the stop was written but is unconfirmed: no robot answered"
    )


class NoiseOnly(NullTransport):
    """A line with no robot behind it: every read brings random bytes (a pty of noise)."""

    name = "noise"

    def __init__(self) -> None:
        super().__init__()
        self.draws = random.Random(1)

    def read(self, timeout: float) -> bytes:
        self.clock += max(timeout, SLOT_SECONDS)
        return self.draws.randbytes(170)


def test_a_line_of_noise_is_no_robot_answering_not_one_left_in_passive(tmp_path: Path) -> None:
    """Bytes came, but no reply ever agreed and no frame was valid: the summary said ``final
    mode Passive`` and ``safe stop sent pause_resume_stream, start`` (the mode model's
    guess), where a silent line said ``unknown``; both now say no robot answered, calmly
    (nothing was set going)."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), NoiseOnly(), profile=CREATE2)
    summary = stack.run()
    stack.close()
    assert summary.exit_code == 3 and "never agreed" in summary.reason, summary.reason
    assert not summary.robot_answered
    assert "final mode   unknown: no robot answered" in str(summary)
    assert summary.safe_stop == (
        "nothing this run set going; the stop was written but is unconfirmed: no robot answered"
    )


def test_noise_at_the_run_rate_is_not_taken_for_a_baud_change(tmp_path: Path) -> None:
    summary, _ = run(tmp_path, SPIN, Faults(bit_flip_rate=0.02), timeout=20.0)
    assert summary.stalls >= 1  # the watchdog tripped on garbage (its frames damaged: noise)
    assert "baud rate" not in summary.reason, summary.reason


@pytest.mark.parametrize("deaf_s", [0.05, 0.15, 0.4])
@pytest.mark.parametrize("phase", [0.0, 0.004, 0.008, 0.012])
def test_a_listen_that_misses_the_change_is_tried_again_and_the_robot_stopped(
    tmp_path: Path, deaf_s: float, phase: float
) -> None:
    """The first listen at the other rate finds no frame (the host deaf for ``deaf_s`` from
    its start; the change at each phase of a 15 ms slot): the stall is ridden through and
    the other rate listened at again while garbage keeps coming, so drive 0 reaches the
    robot at its new rate within the watchdog, the deafness and two listens, not after the
    2 s grace at the old rate (where the robot understands nothing and keeps driving)."""
    link_type = type("Deaf", (DeafAtFirstListen,), {"deaf_s": deaf_s})
    change = 3.0 + phase
    summary, simulator = run(tmp_path, SPIN, Faults(baud_change_at=change), link_type, timeout=10.0)
    assert_followed_and_stopped(summary, simulator, change, 0.1 + deaf_s + 2 * LISTEN_S + 0.1)


def test_the_listen_is_long_enough_for_two_whole_frames_at_the_rate() -> None:
    """At 19200 a frame of group 100 (84 bytes) takes 44 ms: two whole frames after a cut one
    do not fit in 100 ms; the run's short frames keep the 100 ms."""
    assert listen_window((100,), 19200) == pytest.approx(3 * 84 * 10 / 19200 + 0.015)
    assert listen_window((100,), 19200) > 0.14
    assert listen_window((7, 9, 10, 11, 12, 25, 26, 34, 35, 43, 44), 19200) == LISTEN_S
    assert listen_window((100,), 115200) == LISTEN_S


def test_a_robot_found_at_another_rate_is_said_to_have_answered(tmp_path: Path) -> None:
    """It answered Start and a Query List at 19200: the summary said ``final mode unknown:
    the robot never answered`` and the stop (written at 19200, where it listens) ``NOT
    DELIVERED: ... the robot never answered``, against the outcome's own words."""
    summary, simulator = run(tmp_path, SPIN, Faults(), robot_baud=19200)
    assert "and Start and a Query List at 19200" in summary.reason
    assert summary.robot_answered
    assert "never answered" not in str(summary)
    assert "final mode   Passive" in str(summary)  # the probe's Start, at 19200
    assert summary.safe_stop == "sent pause_resume_stream, start"
    assert simulator.mode is OIMode.PASSIVE


def test_a_robot_found_at_115200_is_not_told_how_a_robot_comes_to_19200(tmp_path: Path) -> None:
    """The run at 57600, the robot at its default 115200: the message named the rate and
    then explained how a 600 comes to talk at 19200, which had nothing to do with it."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, trace=False)
    mission = load_mission(path, {}, profile=CREATE2)
    link = SimLink(simulator)
    link.set_baud(57600)  # the port opened at the run's rate
    stack = RunStack(mission, link, profile=CREATE2, baud=57600)
    summary = stack.run()
    stack.close()
    assert "the robot answers at 115200 baud, not at the 57600 of the run" in summary.reason
    assert "19200" not in summary.reason, summary.reason
    assert "open it at 115200 (--baud 115200" in summary.reason


def test_a_roomba500_read_by_the_default_profile_ends_the_run_at_the_watchdog_trip(
    tmp_path: Path,
) -> None:
    """The frames passing the 500's checksum make the diagnosis certain at the watchdog's
    trip (the robot streams all along, its frames refused by the profile alone): the run
    waited the whole 2 s grace for frames that could not come. It ends at the trip now,
    with the same safe stop (confirmed by the Pause Stream's quiet and a query)."""
    path = tmp_path / "m.yaml"
    path.write_text(SPIN)
    simulator = Simulator(load_world("empty-room"), ROOMBA500, 0, trace=False)
    link = SimLink(simulator)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), link, profile=CREATE2)
    summary = stack.run()
    ended_at = link.now()  # the virtual clock: the run's own time, not the wall's
    stack.close()
    # found before the mission's first command: a setting (exit 2), no link lost (8)
    assert summary.outcome is Outcome.WRONG_PROFILE and summary.exit_code == 2
    assert summary.commands_written == 0
    assert "then the run waited" not in summary.reason, summary.reason
    assert "use --profile roomba500" in summary.reason
    assert summary.stalls == 1 and summary.stalls_ridden == 0
    assert ended_at < DEFAULT_GRACE, ended_at  # the grace was not waited
    assert summary.safe_stop == "sent pause_resume_stream, start", summary.safe_stop
    assert summary.stop_delivered
    # the stop confirmed by a query, docs/runtime.md's table of silences
    assert_quoted("docs/runtime.md", "safe stop sent pause_resume_stream, start$", str(summary))
    assert summary.headline.startswith(f"{link.name}: the robot is most likely a Roomba 500")


def test_a_roomba500_read_by_the_default_profile_near_a_wall_is_not_called_noise(
    tmp_path: Path,
) -> None:
    """A 500 whose firmware sums the header, run with the default profile, along a wall:
    every frame passes the checksum and fails the create2 range of packet 27. The run ended
    "noise on the line, or a wrong baud rate"; it names the packet, the value and the
    profile whose range holds it."""
    from dataclasses import replace

    from roomba_bt.sim import parse_world

    path = tmp_path / "m.yaml"
    path.write_text(  # a mission that reads the wall signal: it is streamed
        "tree:\n  sequence:\n    - mode: safe\n    - wait: 3s\n"
        "      until: {sensor: wall_signal > 1000}\n"
    )
    beside_a_wall = "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\nrobot: {start: {at: [2, 0.2]}}\n"
    summing = replace(ROOMBA500, checksum_includes_header=True)
    simulator = Simulator(parse_world(beside_a_wall), summing, 0, trace=False)
    stack = RunStack(load_mission(path, {}, profile=CREATE2), SimLink(simulator), profile=CREATE2)
    summary = stack.run()
    stack.close()
    assert summary.implausible_frames > 0 and summary.checksum_failures == 0
    assert "noise on the line" not in summary.reason, summary.reason
    assert "wall signal (27) read" in summary.reason
    assert "use --profile roomba500" in summary.reason
    # its stop was "unconfirmed: its frames fail the create2 profile's range": the robot went
    # quiet after Pause Stream and answered a Query List, which no profile's range refuses
    assert summary.safe_stop == "sent pause_resume_stream, start", summary.safe_stop
    # found at the first frames, before the mission's mode: safe: a setting, exit 2
    assert summary.commands_written == 0 and summary.outcome is Outcome.WRONG_PROFILE
    assert summary.stop_delivered and summary.exit_code == 2


def test_a_wrong_profile_found_after_the_mission_wrote_a_command_is_still_a_link_lost() -> None:
    """The same 500 read by the default profile, its wall on its left at the start: frames
    pass the create2 range until its turn puts the wall on its right (wall signal over
    1023). The mission had written Safe and a turn by then: the robot may have moved, so
    the run ends as a lost stream, exit 8 (a person looks first), the fix named all the
    same; only a wrong profile found before any command of the mission is exit 2."""
    from dataclasses import replace

    from roomba_bt.mission import load_mission_text

    mission = load_mission_text(
        "tree:\n  sequence:\n    - mode: safe\n    - turn: 180deg\n    - wait: 3s\n"
        "      until: {sensor: wall_signal > 1000}\n",
        profile=CREATE2,
    )
    wall_on_the_left = (
        "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\nrobot: {start: {at: [2, 0.2], heading: 180}}\n"
    )
    summing = replace(ROOMBA500, checksum_includes_header=True)
    simulator = Simulator(parse_world(wall_on_the_left), summing, 0, trace=False)
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2)
    summary = stack.run()
    stack.close()
    assert summary.commands_written > 0 and summary.ticks > 0
    assert "use --profile roomba500" in summary.reason, summary.reason
    assert summary.outcome is Outcome.CONNECTION_LOST and summary.exit_code == 8
