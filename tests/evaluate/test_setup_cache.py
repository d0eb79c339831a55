"""An episode's set-up reuses what the episodes before it in the process parsed: the world's
text parsed once, the mission compiled once (each episode still gets a tree of its own), both
read again when their files change."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from runtime.simrun import SHORT_DRIVE, write_mission  # tests/runtime: the short drive

from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.episode import _mission, build_world
from roomba_bt.mission import NO_PERMISSIONS, load_mission
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.sim import load_world

MISSIONS = Path(__file__).resolve().parents[2] / "missions"


def test_a_world_file_is_parsed_once_and_again_when_it_changes(tmp_path: Path) -> None:
    text = Path(load_world("empty-room").source).read_text(encoding="utf-8")
    path = tmp_path / "room.yaml"
    path.write_text(text, encoding="utf-8")
    spec = EpisodeSpec(str(MISSIONS / "dock.yaml"), str(path))
    first = build_world(spec)
    assert build_world(spec) is first  # the same text: the same (frozen) world
    path.write_text(text.replace("battery: 0.6", "battery: 0.5"), encoding="utf-8")
    changed = build_world(spec)
    assert changed is not first and changed.battery == 0.5
    carried = EpisodeSpec(str(MISSIONS / "dock.yaml"), "x", world_file=("room.yaml", text))
    # a world that travels as text parses the same (its source names the file alone)
    assert dataclasses.replace(build_world(carried), source=first.source) == first


def test_each_episode_gets_a_tree_of_its_own_from_one_compile(tmp_path: Path) -> None:
    path = write_mission(tmp_path, SHORT_DRIVE)
    first = _mission(path, (), CREATE2, NO_PERMISSIONS)
    second = _mission(path, (), CREATE2, NO_PERMISSIONS)
    assert second.root is not first.root
    first_nodes, second_nodes = list(first.root.iterate()), list(second.root.iterate())
    assert [n.name for n in first_nodes] == [n.name for n in second_nodes]
    assert not {id(n) for n in first_nodes} & {id(n) for n in second_nodes}
    assert second.packets == first.packets and second.name == first.name
    # the same as a compile of its own
    fresh = load_mission(path, {}, profile=CREATE2)
    assert [n.name for n in fresh.root.iterate()] == [n.name for n in second_nodes]


def test_a_changed_mission_file_or_other_parameters_compile_again(tmp_path: Path) -> None:
    path = write_mission(tmp_path, SHORT_DRIVE)
    slow = _mission(path, (), CREATE2, NO_PERMISSIONS)
    fast = _mission(path, (("speed", "300mm/s"),), CREATE2, NO_PERMISSIONS)
    assert slow.parameters["speed"] != fast.parameters["speed"]
    path.write_text(SHORT_DRIVE.replace("200 mm/s", "100 mm/s"), encoding="utf-8")
    edited = _mission(path, (), CREATE2, NO_PERMISSIONS)
    assert edited.parameters["speed"] != slow.parameters["speed"]
    assert (
        edited.parameters["speed"]
        == _mission(path, (), CREATE2, NO_PERMISSIONS).parameters["speed"]
    )


def test_episodes_after_the_first_give_the_results_of_a_fresh_process(tmp_path: Path) -> None:
    """An episode run after others (cached world and mission) is the episode run first."""
    path = write_mission(tmp_path, SHORT_DRIVE)
    spec = EpisodeSpec(str(path), "empty-room", seed=5, timeout_s=20.0)
    first = run_episode(spec)
    again = run_episode(spec)
    assert first.outcome == "success"
    assert dataclasses.replace(again, wall_s=0.0) == dataclasses.replace(first, wall_s=0.0)


def test_a_rebuilt_mission_has_its_own_blackboard_initial_values() -> None:
    mission = load_mission(MISSIONS / "examples" / "show_off.yaml", {}, profile=CREATE2)
    again = mission.rebuilt()
    assert again.blackboard_initial == mission.blackboard_initial == {"rounds": 0}
    assert again.blackboard_initial is not mission.blackboard_initial
    assert again.root is not mission.root
    with pytest.raises(ValueError, match="no plan"):
        dataclasses.replace(mission, plan=None).rebuilt()


def test_a_coverage_grid_only_for_a_mission_that_can_run_the_brushes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import roomba_bt.sim.robot as sim_robot

    built: list[object] = []

    class Counted(sim_robot.SweptArea):
        def __init__(self, *args: object, **kwargs: object) -> None:
            built.append(self)
            super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(sim_robot, "SweptArea", Counted)
    path = write_mission(tmp_path, SHORT_DRIVE)
    assert run_episode(EpisodeSpec(str(path), "empty-room", timeout_s=5.0)).coverage is None
    assert not built  # Drive and Safe only: no grid
    brushing = SHORT_DRIVE.replace(
        "    - mode: safe\n", "    - mode: safe\n    - motors: {main_brush: true}\n"
    )
    path.write_text(brushing, encoding="utf-8")
    result = run_episode(EpisodeSpec(str(path), "empty-room", timeout_s=5.0))
    assert len(built) == 1
    assert result.coverage is not None and result.coverage.final > 0.0
