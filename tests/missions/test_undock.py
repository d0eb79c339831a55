"""Started on its powered dock, where a Roomba lives between runs, every shipped mission that
drives backs off it first (the shared ``undock`` subtree of missions/lib/undock.yaml): Safe
on a powered charger drops the robot to Passive at once, and the missions that began with
``mode: safe`` failed "left Safe/Full mode (charger)" without saying what to do. A mission
that still starts with Safe there fails with a message that says it."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.robot.interface import ModeChange
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .conftest import MISSIONS

SHORT = {
    "patrol": {"laps": "1"},
    "bump-and-turn": {"duration": "20s"},
    "wall-follow": {"duration": "20s"},
}


def _run_from_the_dock(
    mission: str | Path, params: dict[str, str], profile: str = "create2"
) -> tuple[Simulator, RunSummary]:
    """The mission through the real runtime on the simulator, the robot on the docked pose of
    the empty room (on the contacts, the charger powering it)."""
    world = load_world("empty-room")
    assert world.dock is not None
    sim = Simulator(world, profile=PROFILES[profile], start=world.dock.docked_pose, trace=False)
    sim.step()
    assert sim.docked, "the start pose is on the dock's contacts"
    compiled = load_mission(str(mission), params, profile=sim.profile)
    summary = RunStack(compiled, SimLink(sim), profile=sim.profile, timeout_s=400.0).run()
    return sim, summary


def _modes(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "mode"]


@pytest.mark.parametrize("profile", ["create2", "roomba600"])
@pytest.mark.parametrize("name", sorted(SHORT))
def test_a_shipped_driving_mission_started_on_the_dock_backs_off_it_and_runs(
    name: str, profile: str
) -> None:
    sim, summary = _run_from_the_dock(MISSIONS / f"{name}.yaml", SHORT[name], profile)
    assert summary.outcome.value == "success", summary.reason
    modes = _modes(sim)
    full = next(i for i, m in enumerate(modes) if "->Full" in m)
    safe = next(i for i, m in enumerate(modes) if "->Safe" in m)
    assert full < safe, modes  # off the dock in Full before Safe, which the charger refuses
    assert not any("charger" in m for m in modes), modes  # Safe was never refused
    assert not sim.docked and sim.mode is OIMode.PASSIVE


def test_the_shipped_driving_missions_share_one_undock_subtree() -> None:
    """One definition (missions/lib/undock.yaml), used by each: not a copy per mission."""
    for name in (*SHORT, "clean"):
        text = (MISSIONS / f"{name}.yaml").read_text()
        assert "subtree: {id: undock}" in text, name
        assert "on_home_base" not in text, name
    assert "undock:" in (MISSIONS / "lib" / "undock.yaml").read_text()


def test_safe_refused_on_the_charger_says_what_to_do(tmp_path: Path) -> None:
    mission = tmp_path / "straight.yaml"
    mission.write_text(
        "mission: straight\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - drive: {velocity: 100 mm/s, duration: 2s}\n"
    )
    _, summary = _run_from_the_dock(mission, {})
    assert summary.outcome.value == "failure"
    assert "left Safe/Full mode (charger)" in summary.reason
    assert "start the robot off the dock" in summary.reason
    assert "`undock` subtree" in summary.reason and "roomba-bt:lib/undock.yaml" in summary.reason


def test_only_a_charger_fall_right_at_the_safe_command_counts_as_refused() -> None:
    """Driven onto the contacts long after Safe (a dock approach), or a cliff: no undock
    advice."""
    at_once = ModeChange(OIMode.SAFE, OIMode.PASSIVE, 3, 10.045, "charger", entered=10.0)
    later = ModeChange(OIMode.SAFE, OIMode.PASSIVE, 900, 25.0, "charger", entered=10.0)
    cliff = ModeChange(OIMode.SAFE, OIMode.PASSIVE, 3, 10.045, "cliff", entered=10.0)
    unknown_start = ModeChange(OIMode.SAFE, OIMode.PASSIVE, 3, 10.045, "charger")
    assert at_once.refused_on_charger
    assert not later.refused_on_charger
    assert not cliff.refused_on_charger
    assert not unknown_start.refused_on_charger
