"""Fixtures for the runtime tests."""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.mission import NO_PERMISSIONS, Permissions, load_mission
from roomba_bt.oi.profiles import CREATE2, RobotProfile
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.runtime.stack import Recording, RunStack
from roomba_bt.sim import Faults, Simulator, load_world
from roomba_bt.sim.faults import HostLine

from .simrun import Run, RunMission, TapLink


@pytest.fixture
def run_mission(tmp_path: Path) -> RunMission:
    def run(
        text: str,
        *,
        world: str = "empty-room",
        faults: Faults | None = None,
        timeout: float | None = 60.0,
        profile: RobotProfile = CREATE2,
        end_in: str = "passive",
        params: dict[str, str] | None = None,
        watchdog: float = 0.1,
        seed: int = 0,
        stall_after: float | None = None,
        burst: int = 1,
        freeze: tuple[float, float] | None = None,
        observer: Callable[[MissionRunner], None] | None = None,
        tick_limit: float | None = None,
        permissions: Permissions = NO_PERMISSIONS,
        record: Path | None = None,
        jitter: float = 0.0,
        cycle_commands_pause: bool = False,
        host_line: HostLine | None = None,
    ) -> Run:
        path = tmp_path / "mission.yaml"
        path.write_text(textwrap.dedent(text))
        mission = load_mission(path, params or {}, profile=profile, permissions=permissions)
        simulator = Simulator(
            load_world(world), profile, seed, faults, cycle_commands_pause=cycle_commands_pause
        )
        if host_line is not None:  # the bytes' way to the robot, scripted by the test
            simulator.host_line = host_line
        link = TapLink(simulator, stall_after, burst, freeze, jitter)
        stack = RunStack(
            mission,
            link,
            profile=profile,
            watchdog=watchdog,
            end_in=end_in,  # type: ignore[arg-type]
            timeout_s=timeout,
            observer=observer,
            tick_limit=tick_limit,
            record=Recording(record, str(path)) if record is not None else None,
        )
        summary = stack.run(raise_interrupts=False)  # as the CLI: Ctrl-C is a summary
        if record is not None:
            stack.close()  # the record written out
        return Run(summary, link, simulator, stack.runner)

    return run
