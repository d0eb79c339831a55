"""Named areas of a world (rooms of an open-plan flat): parsed, checked, used as start regions."""

from __future__ import annotations

import pytest

from roomba_bt.sim import WorldError, load_world, parse_world
from roomba_bt.sim.geometry import point_in_polygon

ROOM = """
name: flat
rooms: [[[0, 0], [6, 0], [6, 3], [0, 3]]]
robot: {start: {at: [1, 1]}, start_region: {area: east, heading: any}}
areas:
  - {name: west, rect: [0, 0, 3, 3]}
  - {name: east, polygon: [[3, 0], [6, 0], [6, 3], [3, 3]]}
"""


def test_areas_are_named_polygons_and_a_start_region_may_be_one() -> None:
    world = parse_world(ROOM, "<test>")
    assert [a.name for a in world.areas] == ["west", "east"]
    east = world.area("east")
    assert east is not None and world.area("north") is None
    for seed in range(20):
        pose = world.sample_start(seed)
        assert point_in_polygon(pose.x, pose.y, east.polygon)
        assert world.pose_is_free(pose)


def test_the_apartment_names_its_rooms() -> None:
    names = [a.name for a in load_world("apartment").areas]
    assert names == ["living-room", "bedroom", "kitchen"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("{name: west, rect: [0, 0, 3, 3]}", "each area's name once"),
        ("{rect: [0, 0, 3, 3]}", "a name for the area"),
        ("{name: w2, rect: [3, 0, 1, 3]}", "x0 < x1"),
    ],
)
def test_bad_areas_are_reported_with_their_place(change: str, message: str) -> None:
    text = ROOM.replace("  - {name: east, polygon", f"  - {change}\n  - {{name: east, polygon")
    with pytest.raises(WorldError, match=message) as info:
        parse_world(text, "<test>")
    assert "<test>:" in str(info.value) and "areas[1]" in str(info.value)


def test_a_start_region_naming_no_area_is_refused() -> None:
    with pytest.raises(WorldError, match=r"robot.start_region.area: found 'north'"):
        parse_world(ROOM.replace("area: east", "area: north"), "<test>")
    with pytest.raises(WorldError, match="exactly one of near_dock, rect, area"):
        parse_world(ROOM.replace("{area: east,", "{area: east, rect: [0, 0, 1, 1],"), "<test>")
