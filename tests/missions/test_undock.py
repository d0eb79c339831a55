"""Started on its powered dock, where a Roomba lives between runs, every shipped mission that
drives backs off it first (the shared ``undock`` subtree of missions/lib/undock.yaml): Safe
on a powered charger drops the robot to Passive at once, and the missions that began with
``mode: safe`` failed "left Safe/Full mode (charger)" without saying what to do. A mission
that still starts with Safe there fails with a message that says it."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.mission import load_mission
from roomba_bt.oi.encode import drive_straight
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import COMMANDS_BY_NAME
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.robot.interface import ModeChange
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .conftest import MISSIONS

SAFE, FULL = (bytes([COMMANDS_BY_NAME[name].opcode]) for name in ("safe", "full"))

SHORT = {
    "patrol": {"laps": "1"},
    "bump-and-turn": {"duration": "20s"},
    "wall-follow": {"duration": "20s"},
}


def _run_from_the_dock(
    mission: str | Path, params: dict[str, str], profile: str = "create2"
) -> tuple[Simulator, RunSummary, list[bytes]]:
    """The mission through the real runtime on the simulator, the robot on the docked pose of
    the empty room (on the contacts, the charger powering it); with the commands the robot
    heard, in order (opcode and data bytes)."""
    world = load_world("empty-room")
    assert world.dock is not None
    sim = Simulator(world, profile=PROFILES[profile], start=world.dock.docked_pose, trace=False)
    heard: list[bytes] = []
    sim.heard = lambda spec, data: heard.append(bytes([spec.opcode]) + data)
    sim.step()
    assert sim.docked, "the start pose is on the dock's contacts"
    compiled = load_mission(str(mission), params, profile=sim.profile)
    summary = RunStack(compiled, SimLink(sim), profile=sim.profile, timeout_s=400.0).run()
    return sim, summary, heard


def _modes(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "mode"]


@pytest.mark.parametrize("profile", ["create2", "roomba600"])
@pytest.mark.parametrize("name", sorted(SHORT))
def test_a_shipped_driving_mission_started_on_the_dock_backs_off_it_and_runs(
    name: str, profile: str
) -> None:
    sim, summary, heard = _run_from_the_dock(MISSIONS / f"{name}.yaml", SHORT[name], profile)
    assert summary.outcome.value == "success", summary.reason
    modes = _modes(sim)
    full = next(i for i, m in enumerate(modes) if "->Full" in m)
    safe = next(i for i, m in enumerate(modes) if "->Safe" in m)
    assert full < safe, modes  # off the dock in Full before Safe, which the charger refuses
    assert not any("charger" in m for m in modes), modes  # Safe was never refused
    assert not sim.docked and sim.mode is OIMode.PASSIVE
    # undock ends in Safe and the mission's own `mode: safe` after it sends nothing more
    # (nothing in the empty room drops the robot to Passive on the way)
    assert heard.count(SAFE) == 1 and heard.count(FULL) == 1, heard


def test_a_mission_of_your_own_is_in_safe_once_undock_is_done(tmp_path: Path) -> None:
    """undock left the robot in Full after backing off the dock: a mission that went on
    without a `mode: safe` of its own there (its mode leaf before undock, say, or `check`ed
    elsewhere) drove with no firmware cliff or wheel-drop stop. The check right after it
    reads packet 35 in the tick undock ended: Safe (2), not Full (3); the mission's own
    `mode: safe` (the static mode check wants one: off the dock undock leaves Passive) then
    sends nothing."""
    mission = tmp_path / "off-and-on.yaml"
    mission.write_text(
        "mission: off-and-on\n"
        "include: [roomba-bt:lib/undock.yaml]\n"
        "tree:\n"
        "  sequence:\n"
        "    - subtree: {id: undock}\n"
        "    - {name: in Safe after undock, sensor: oi_mode == 2}\n"
        "    - mode: safe\n"
        "    - drive: {velocity: 100 mm/s, duration: 2s}\n"
        "      until: {cliff: any}\n"
    )
    sim, summary, heard = _run_from_the_dock(mission, {})
    assert summary.outcome.value == "success", summary.reason
    ahead = drive_straight(100).data  # the mission's own drive
    assert heard.index(FULL) < heard.index(SAFE) < heard.index(ahead), heard
    assert heard.count(SAFE) == 1, heard
    assert not any("charger" in m for m in _modes(sim))


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
    _, summary, _ = _run_from_the_dock(mission, {})
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
