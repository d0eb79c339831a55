"""The cleaning motions on the simulator: lanes sweep a room, a spiral grows, hazards stop them."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.episode import EpisodeResult

ROOM = """
name: box
rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]
robot: {{start: {{at: [0.25, 0.2], heading: 0}}}}
{extra}
"""

MISSION = """
mission: {name}
tree:
  sequence:
    - mode: full
    - motors: {{main_brush: true, side_brush: true, vacuum: true}}
    - {leaf}
    - mode: passive
"""


def run(tmp_path: Path, leaf: str, extra: str = "", timeout: float = 300.0) -> EpisodeResult:
    world = tmp_path / "box.yaml"
    world.write_text(ROOM.format(extra=extra))
    mission = tmp_path / "sweep.yaml"
    mission.write_text(MISSION.format(name="sweep", leaf=leaf))
    return run_episode(EpisodeSpec(str(mission), str(world), random_start=False, timeout_s=timeout))


def test_lanes_from_a_corner_sweep_the_room(tmp_path: Path) -> None:
    result = run(tmp_path, "lanes: {speed: 300 mm/s}")
    assert result.outcome == "success", result.reason
    assert result.coverage is not None
    assert result.coverage.overall >= 0.9
    assert result.violations == 0


def test_lanes_end_at_a_drop_and_never_fall_in_full_mode(tmp_path: Path) -> None:
    drop = "drops: [{name: stairs, rect: [2.2, 0, 3, 2.5]}]"
    result = run(tmp_path, "lanes: {speed: 300 mm/s}", drop)
    assert result.outcome == "success", result.reason
    assert result.cliffs > 0 and not result.fell
    assert result.coverage is not None and result.coverage.overall >= 0.85


def test_lanes_do_not_cross_a_virtual_wall(tmp_path: Path) -> None:
    beam = "virtual_walls: [{from: [1.8, 0], to: [1.8, 2.5]}]"
    result = run(tmp_path, "lanes: {speed: 300 mm/s}", beam)
    assert result.outcome == "success", result.reason
    assert max(x for x, _ in result.trajectory) < 1.8


def test_a_wheel_drop_fails_the_lanes(tmp_path: Path) -> None:
    lift = "events: [{at: 5, kind: lift, duration: 2}]"
    result = run(tmp_path, "lanes: {speed: 300 mm/s}", lift)
    assert result.outcome == "failure"
    assert "wheel drop" in result.reason


@pytest.mark.parametrize("radius_m", [0.5, 0.8])
def test_the_spiral_grows_to_its_radius_in_open_floor(tmp_path: Path, radius_m: float) -> None:
    open_floor = ROOM.replace("[0.25, 0.2], heading: 0", "[1.5, 1.25], heading: 0")
    world = tmp_path / "open.yaml"
    world.write_text(open_floor.format(extra=""))
    mission = tmp_path / "spiral.yaml"
    leaf = f"spiral: {{max_radius: {radius_m} m}}"
    mission.write_text(MISSION.format(name="spiral", leaf=leaf))
    result = run_episode(EpisodeSpec(str(mission), str(world), random_start=False, timeout_s=300))
    assert result.outcome == "success", result.reason
    # the spiral's centre starts 10 cm to the robot's left and drifts as the rings grow
    reach = max(math.hypot(x - 1.5, y - 1.25) for x, y in result.trajectory)
    assert radius_m <= reach <= radius_m + 0.3
    assert result.bumps == 0


def test_the_spiral_stops_at_a_wall(tmp_path: Path) -> None:
    result = run(tmp_path, "spiral: {max_radius: 3 m}")
    assert result.outcome == "success", result.reason
    assert result.time_s < 120
