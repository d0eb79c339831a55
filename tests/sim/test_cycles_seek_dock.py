"""Seek Dock (143) as the OI specifications describe it: the robot drives onto the dock "the
next time it encounters the docking beams". Until a receiver has seen a beam, the firmware
knows nothing of where the dock is, so the search must not depend on the dock's pose."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.ir import IRCharacter
from roomba_bt.oi.modes import OIMode
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.cycles import SEEK_DOCK_LIMIT_S
from roomba_bt.sim.world import Pose

from .helpers import pose, world

STEP_S = 0.015

#: Two 4 m x 4 m rooms joined by a 0.8 m door; the robot starts in the west room, the dock
#: stands in the east one, more than 3 m from the start and out of its beams' reach.
TWO_ROOMS = """
name: two-rooms
rooms: [[[0, 0], [8, 0], [8, 4], [0, 4]]]
walls:
  - [4.0, 0.0, 4.0, 1.6]
  - [4.0, 2.4, 4.0, 4.0]
dock: {{at: [{x}, {y}], facing: {facing}}}
robot: {{start: {{at: [1.5, 2.0], heading: 30}}}}
"""
DOCK_SOUTH = {"x": 7.0, "y": 0.0, "facing": 90}
DOCK_EAST = {"x": 8.0, "y": 3.0, "facing": 180}


def sees_a_dock(sim: Simulator) -> bool:
    v = sim.values
    return any(IRCharacter.decode(v[packet]).from_dock for packet in (17, 52, 53))


def search_until_a_beam(dock: dict[str, float], seed: int, seconds: float) -> list[Pose]:
    """The poses of a Seek Dock run, one a step, up to the first step a receiver sees a dock
    character (or ``seconds``)."""
    sim = Simulator(world(TWO_ROOMS.format(**dock)), seed=seed)
    sim.receive(C.start().data + C.seek_dock().data)
    poses: list[Pose] = []
    for _ in range(round(seconds / STEP_S)):
        sim.step()
        if sees_a_dock(sim):
            break
        poses.append(sim.pose)
    return poses


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_search_before_a_beam_does_not_depend_on_where_the_dock_is(seed: int) -> None:
    south = search_until_a_beam(DOCK_SOUTH, seed, 90.0)
    east = search_until_a_beam(DOCK_EAST, seed, 90.0)
    same = min(len(south), len(east))
    assert same * STEP_S > 20.0  # a real search, not a beam seen at once
    assert south[:same] == east[:same]
    travelled = abs(south[same - 1].x - south[0].x) + abs(south[same - 1].y - south[0].y)
    assert travelled > 500.0  # it moved: identical because blind, not because still


def test_seek_dock_docks_in_the_other_room_once_it_has_seen_a_beam() -> None:
    sim = Simulator(world(TWO_ROOMS.format(**DOCK_EAST)), seed=1)
    sim.receive(C.start().data + C.seek_dock().data)
    first_beam = None
    for _ in range(round(SEEK_DOCK_LIMIT_S / STEP_S)):
        sim.step()
        if first_beam is None and sees_a_dock(sim):
            first_beam = sim.time
        if sim.docked and sim.builtin is None:
            break
    assert sim.docked and sim.mode is OIMode.PASSIVE
    assert first_beam is not None and first_beam > 10.0
    assert sim.time - first_beam < 60.0  # once in sight it homes, as before


def test_seek_dock_in_sight_of_the_dock_homes_at_once() -> None:
    sim = Simulator(world(TWO_ROOMS.format(**DOCK_SOUTH)), seed=1, start=pose(7.3, 0.8, 180))
    sim.receive(C.start().data + C.seek_dock().data)
    sim.run(0.06)
    assert sees_a_dock(sim)
    for _ in range(round(40.0 / STEP_S)):
        sim.step()
        if sim.docked:
            break
    assert sim.docked


def test_without_a_dock_seek_dock_searches_until_its_limit() -> None:
    text = "name: box\nrooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\nrobot: {start: {at: [2, 2]}}"
    sim = Simulator(world(text), seed=5)
    sim.receive(C.start().data + C.seek_dock().data)
    farthest = 0.0
    for _ in range(round((SEEK_DOCK_LIMIT_S - 1.0) / STEP_S)):
        sim.step()
        farthest = max(farthest, abs(sim.x - 2000.0) + abs(sim.y - 2000.0))
    assert sim.builtin is not None and farthest > 1000.0  # still searching, all over the box
    sim.run(2.0)
    assert sim.builtin is None
    ended = [e for e in sim.events if e.kind == "builtin" and e.detail == "seek dock gave up"]
    assert len(ended) == 1 and ended[0].time == pytest.approx(SEEK_DOCK_LIMIT_S, abs=0.1)


@pytest.mark.parametrize("world_name", ["empty-room", "apartment", "corridor"])
@pytest.mark.parametrize("seed", [1, 3, 8])
def test_builtin_seek_dock_docks_from_random_starts_in_the_shipped_worlds(
    world_name: str, seed: int
) -> None:
    sim = Simulator(load_world(world_name), seed=seed, random_start=True)
    sim.receive(C.start().data + C.seek_dock().data)
    for _ in range(round(SEEK_DOCK_LIMIT_S / STEP_S)):
        sim.step()
        if sim.docked and sim.builtin is None:
            break
    assert sim.docked, (world_name, seed, sim.pose)
    assert sim.violations == [] and sim.mode is OIMode.PASSIVE


def test_the_simulator_doc_gives_each_seek_dock_quote_to_its_own_spec() -> None:
    """The 600 / Create 2 spec says "directs Roomba to drive onto the dock the next time it
    encounters the docking beams", the 500 spec "sends Roomba to the dock" (the doc had them
    the other way round)."""
    import re
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "simulator.md").read_text()
    said = " ".join(doc.split("#### Seek Dock (143)")[1].split("\n\n")[1].split())
    quotes = dict(re.findall(r"the (Roomba 500|Roomba 600 / Create 2) OI, \"([^\"]+)\"", said))
    assert "sends Roomba to the dock" in quotes["Roomba 500"]
    assert "drive onto the dock" in quotes["Roomba 600 / Create 2"]
    assert "drive onto" not in quotes["Roomba 500"]
