"""Hours on a robot: a mission waiting in Passive keeps the robot awake (BRC pulses once a
minute); with keep-awake off the robot sleeps, and the run says so, with the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600
from roomba_bt.robot.wake import PULSE_PERIOD_S, KeepAwake
from roomba_bt.robot.wording import COMMAND_LINE, PYTHON, ConnectionWording, spoken
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.link import SimLink

#: 15 min in Safe, dock from the beams, 10 min charging in Passive, 5 min more in Passive:
#: half an hour on the virtual clock, 15 min of it in Passive (sleep is due at 5).
MISSION = """\
include: [roomba-bt:lib/docking.yaml]
tree:
  sequence:
    - mode: safe
    - wait: 15min
    - subtree: {id: dock, time_limit: 5min}
    - wait: 10min
    - charging
    - wait: 5min
"""


def _run(tmp_path: Path, keep_awake: bool | None) -> tuple[RunSummary, Simulator]:
    path = tmp_path / "hours.yaml"
    path.write_text(MISSION)
    mission = load_mission(path)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    stack = RunStack(
        mission, SimLink(simulator), profile=CREATE2, timeout_s=3600.0, keep_awake=keep_awake
    )
    summary = stack.run()
    stack.close()
    return summary, simulator


def test_half_an_hour_with_a_charge_wait_never_sleeps_with_keep_awake(tmp_path: Path) -> None:
    summary, simulator = _run(tmp_path, None)  # the default: on (Create 2 sleeps)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert simulator.time >= 30 * 60 - 60
    assert [e for e in simulator.events if e.kind == "sleep"] == []
    assert simulator.brc_pulses >= (simulator.time - 60) // PULSE_PERIOD_S
    assert not simulator.brc_low, "BRC is left high at the end"


def test_without_keep_awake_it_sleeps_and_is_reported_asleep(tmp_path: Path) -> None:
    summary, simulator = _run(tmp_path, False)
    sleeps = [e for e in simulator.events if e.kind == "sleep"]
    assert [e.detail for e in sleeps] == ["5 min idle"]
    assert simulator.brc_pulses == 0
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the robot fell asleep" in summary.reason
    # said to a Python caller in its words (it has no --no-keep-awake to drop)
    assert "leave keep-awake on (keep_awake left out, not False)" in summary.reason
    assert "--no-keep-awake" not in summary.reason
    assert "release-3.8.2 / release-stm32-3.7.7" in summary.reason
    # how the version is read, in its words too (it named doctor's flag)
    assert "read it with roomba_bt.oi.identify.parse_banner)" in summary.reason
    assert "--allow-reset" not in summary.reason
    assert "no valid sensor frame" not in summary.reason
    # the stop met the robot asleep, and says so (not "no valid frame for 0.5 s")
    assert "unconfirmed: the robot was asleep (300 s in Passive" in summary.safe_stop
    assert summary.exit_code == 8


def test_the_command_line_is_told_its_own_words_for_a_sleeping_robot(tmp_path: Path) -> None:
    """The words a Python caller gets are the flags under the ``roomba-bt`` command."""
    with spoken(COMMAND_LINE):
        summary, _ = _run(tmp_path, False)
    assert "leave keep-awake on (drop --no-keep-awake)" in summary.reason
    assert "(roomba-bt doctor --allow-reset reads the version)" in summary.reason
    assert "parse_banner" not in summary.reason


def test_a_roomba500_asleep_is_not_told_to_read_its_version_by_reset(tmp_path: Path) -> None:
    """The 500 has no Reset (7): ``doctor --allow-reset`` reads no version there (doctor
    itself says so), and the advice sent a 500 owner to it."""
    path = tmp_path / "idle.yaml"
    path.write_text("tree:\n  wait: 7min\n")
    mission = load_mission(path, profile=ROOMBA500)
    simulator = Simulator(load_world("empty-room"), ROOMBA500, 0)
    stack = RunStack(
        mission, SimLink(simulator), profile=ROOMBA500, timeout_s=600.0, keep_awake=False
    )
    summary = stack.run()
    stack.close()
    assert "the robot fell asleep" in summary.reason
    assert "--allow-reset" not in summary.reason, summary.reason
    assert "the Roomba 500 series has no Reset (7)" in summary.reason


def _patrol(keep_awake: bool | None) -> tuple[RunSummary, Simulator]:
    """The shipped patrol in the corridor from 16 % of charge: about 4 min of laps in Safe,
    then the dock below 15 %, then 10 min on the charger in Passive: 15 min in all (from
    19.5 % until session 42: 20 min of laps before the same charge, 6 s of CPU a run, not 2;
    the laps are the way onto the charger, what the tests look at is the charge after)."""
    from dataclasses import replace

    from roomba_bt.mission.shipped import shipped_missions

    params = {"laps": "1000", "charge_for": "10min"}
    mission = load_mission(shipped_missions()["patrol"], params)
    world = replace(load_world("corridor"), battery=0.16)
    simulator = Simulator(world, CREATE2, 0)
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=3600.0,
                     keep_awake=keep_awake)  # fmt: skip
    summary = stack.run()
    stack.close()
    return summary, simulator


def test_the_shipped_patrol_with_a_ten_minute_charge_wait_never_sleeps() -> None:
    summary, simulator = _patrol(None)
    assert summary.outcome is Outcome.SUCCESS, summary.reason
    assert simulator.time >= 14 * 60, "a quarter of an hour, the last ten minutes on the charger"
    assert simulator.charging
    assert [e for e in simulator.events if e.kind == "sleep"] == []
    assert simulator.brc_pulses >= 9, "a pulse a minute while it charged in Passive"


def test_the_shipped_patrol_without_keep_awake_sleeps_on_the_charger_and_says_so() -> None:
    with spoken(COMMAND_LINE):  # as `roomba-bt run --no-keep-awake` says it
        summary, simulator = _patrol(False)
    assert [e.detail for e in simulator.events if e.kind == "sleep"] == ["5 min idle"]
    assert summary.outcome is Outcome.CONNECTION_LOST
    assert "the robot fell asleep" in summary.reason
    assert "drop --no-keep-awake" in summary.reason


class _Line:
    def __init__(self) -> None:
        self.changes: list[tuple[float, bool]] = []
        self.now = 0.0

    def set_wake_line(self, low: bool) -> None:
        self.changes.append((self.now, low))


def test_the_pulse_is_one_second_low_every_minute() -> None:
    line = _Line()
    wake = KeepAwake(line)
    for step in range(int(150 / 0.015)):
        line.now = step * 0.015
        wake.tick(line.now)
    starts = [t for t, low in line.changes if low]
    ends = [t for t, low in line.changes if not low]
    assert starts == pytest.approx([0.0, 60.0, 120.0], abs=0.02)
    assert [e - s for s, e in zip(starts, ends, strict=False)] == pytest.approx([1.0] * 3, abs=0.02)
    wake.release()
    assert line.changes[-1][1] is False


def test_keep_awake_is_on_by_default_for_the_profiles_that_sleep() -> None:
    assert CREATE2.sleeps_in_passive and ROOMBA600.sleeps_in_passive
    assert ROOMBA500.sleeps_in_passive  # the 500 spec is silent: assumed, the pulse is harmless


def test_a_brc_pulse_wakes_a_sleeping_simulator_and_resets_its_counter() -> None:
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    link = SimLink(simulator)
    link.write(bytes([128]))  # Start: Passive
    link.advance(301.0)
    assert simulator.asleep
    link.set_wake_line(True)
    link.set_wake_line(False)
    assert not simulator.asleep
    assert [e.detail for e in simulator.events if e.kind == "wake"] == ["BRC pulse"]
    link.advance(240.0)
    link.set_wake_line(True)
    link.set_wake_line(False)
    link.advance(240.0)
    assert not simulator.asleep, "the pulse at 240 s reset the five-minute counter"


class _NoLines:
    def set_wake_line(self, low: bool) -> None:
        raise OSError(25, "Inappropriate ioctl for device")


@pytest.mark.parametrize(
    ("caller", "silenced"),
    [(COMMAND_LINE, "--no-keep-awake silences this (-v: why)"),
     (PYTHON, "keep_awake=False silences this (logging DEBUG: why)")],
)  # fmt: skip
def test_a_port_without_modem_lines_turns_keep_awake_off_once(
    caller: ConnectionWording, silenced: str, caplog: pytest.LogCaptureFixture
) -> None:
    """Said in the caller's words: a program has no ``--no-keep-awake`` nor ``-v``."""
    wake = KeepAwake(_NoLines())
    with caplog.at_level("DEBUG", logger="roomba_bt"), spoken(caller):
        wake.tick(0.0)
        wake.tick(61.0)
    wake.release()
    assert wake.unavailable is not None and "Inappropriate ioctl" in wake.unavailable
    assert wake.pulses == 0
    # said once, in one short line (every run on a pty said 400 characters: ten lines of a
    # 40-column SSH screen), with what to do; the rest at -v (it named only the ioctl's error)
    [warned] = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert "keep-awake (a BRC pulse a minute: Passive never sleeps) is off" in warned
    assert f"no modem lines on this port; Passive sleeps after 5 min; {silenced}" in warned
    # a pty's simulator sleeps after 5 minutes in Passive as a robot does, and a device path
    # is no simulator: it said "a simulator never sleeps" of both, and the run then slept
    assert "simulator" not in warned
    assert "Errno" not in warned  # the port's error at -v: it said nothing to a hobbyist
    assert len(warned) <= 175, warned
    [said] = [r.getMessage() for r in caplog.records if r.levelname == "DEBUG"]
    assert "--rfc2217" in said and "Inappropriate ioctl" in said
    assert f"{caller.keep_awake_off} says it is meant" in said


class _Levels:
    def __init__(self) -> None:
        self.levels: list[bool] = []

    def set_wake_line(self, low: bool) -> None:
        self.levels.append(low)


class _NamedLevels(_Levels):
    def __init__(self, name: str) -> None:
        super().__init__()
        self.name = name


@pytest.mark.parametrize(
    ("port", "said"),
    [("/dev/ttyUSB0", True), ("rfc2217://pi.local:7000", True), ("sim://empty-room", False)],
)
def test_the_first_pulse_says_it_wakes_a_robot_that_slept(
    caplog: pytest.LogCaptureFixture, port: str, said: bool
) -> None:
    """A robot asleep on its dock overnight was woken at a 9:00 run's start by BRC pulled
    low, and the log said nothing of it (docs/robot.md said the start-up could not wake it).
    Said once, at the first pulse; not of the simulator in this process, every run's."""
    wake = KeepAwake(_NamedLevels(port), period=60.0, length=1.0)
    with caplog.at_level("INFO", logger="roomba_bt"):
        for now in (0.0, 1.0, 60.0, 61.0):
            wake.tick(now)
    woken = [r.getMessage() for r in caplog.records if "is woken by it" in r.getMessage()]
    assert woken == (
        [f"{port}: BRC pulled low (RTS and DTR: the port's open and keep-awake's first pulse): "
         "a robot that slept (on its dock overnight) is woken by it"] if said else []
    )  # fmt: skip


def test_due_is_when_a_tick_next_has_something_to_do() -> None:
    line = _Levels()
    wake = KeepAwake(line, period=60.0, length=1.0)
    assert wake.due == float("-inf")  # the first tick starts a pulse
    wake.tick(5.0)
    assert (line.levels, wake.due) == ([True], 6.0)
    wake.tick(5.9)
    assert (line.levels, wake.due) == ([True], 6.0)  # before due: nothing
    wake.tick(6.0)
    assert (line.levels, wake.due) == ([True, False], 65.0)
    wake.tick(64.0)
    assert line.levels == [True, False]
    wake.tick(65.0)
    assert (line.levels, wake.due) == ([True, False, True], 66.0)
    wake.release()
    assert (line.levels, wake.due) == ([True, False, True, False], 125.0)


def test_a_line_that_cannot_be_driven_is_never_due_again() -> None:
    class _Broken:
        def set_wake_line(self, low: bool) -> None:
            raise OSError("no modem lines on a pty")

    wake = KeepAwake(_Broken())
    wake.tick(0.0)
    assert wake.unavailable is not None and wake.due == float("inf")
