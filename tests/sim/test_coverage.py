"""The swept-area model: what a pass cleans, the floor a robot could clean, coverage per area."""

from __future__ import annotations

import itertools
import math

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.sim import Pose, Simulator, parse_world
from roomba_bt.sim.coverage import (
    CELL_MM,
    MAIN_BRUSH_WIDTH_MM,
    MAX_CURVE_SAMPLES,
    REACH_MM,
    SAMPLE_EVERY_S,
    SweptArea,
    floor_model,
    reachable_floor,
)
from roomba_bt.sim.world import ROBOT_RADIUS_MM

from .helpers import world

MAIN_AND_VACUUM = 0b110
ALL = 0b111


def drive_a_metre(sim: Simulator, swept: SweptArea, motors: int) -> None:
    """Full mode, the motors on, straight ahead at 200 mm/s until the robot has gone 1 m, then
    stopped; the swept area follows the simulator's true pose every step."""
    x0, y0 = sim.x, sim.y
    sim.receive(C.start().data + C.full().data + C.motors(motors).data + C.drive_straight(200).data)
    while math.hypot(sim.x - x0, sim.y - y0) < 1000.0:
        sim.step()
        swept.update(sim.time, sim.x, sim.y, sim.theta, sim.motor_bits)
    sim.receive(C.halt().data)
    sim.step()
    swept.update(sim.time, sim.x, sim.y, sim.theta, sim.motor_bits)
    swept.finish(sim.time, sim.x, sim.y, sim.theta)


def cleaned_centres(swept: SweptArea) -> list[tuple[float, float]]:
    return [swept.grid.centre(k) for k, state in enumerate(swept.cells) if state == 2]


def test_a_straight_metre_with_the_main_brush_cleans_its_width_by_a_metre() -> None:
    w = world()
    start = Pose(1000.0, 2003.0, 0.0)  # the brush's edges between rows of cell centres
    sim = Simulator(w, start=start)
    swept = SweptArea(w, start)
    drive_a_metre(sim, swept, MAIN_AND_VACUUM)
    xs = [x for x, _ in cleaned_centres(swept)]
    ys = {y for _, y in cleaned_centres(swept)}
    assert abs(min(xs) - start.x) <= CELL_MM and abs(max(xs) - sim.x) <= CELL_MM
    assert len(ys) == round(MAIN_BRUSH_WIDTH_MM / CELL_MM)  # 9 rows of 2 cm
    assert max(ys) - min(ys) <= MAIN_BRUSH_WIDTH_MM
    length = max(xs) - min(xs) + CELL_MM
    assert abs(length - 1000.0) <= 2 * CELL_MM  # within a cell at each end
    area = swept.area_m2(swept.cleaned_total)
    assert area == pytest.approx(MAIN_BRUSH_WIDTH_MM * 1000.0 / 1e6, abs=2 * 0.18 * 0.02)
    assert swept.cleaned_total == len(xs)  # every cleaned cell counted once


def test_brushes_off_clean_nothing() -> None:
    w = world()
    start = Pose(1000.0, 2000.0, 0.0)
    sim = Simulator(w, start=start)
    swept = SweptArea(w, start)
    drive_a_metre(sim, swept, 0)
    assert swept.cleaned_total == 0
    assert swept.coverage() == 0.0
    assert swept.cleaning_time == 0.0


def test_the_side_brush_reaches_the_wall_edge_the_main_brush_does_not() -> None:
    # along the south wall (y = 0) with the wall on the right, 10 mm between bumper and wall
    w = world()
    start = Pose(1000.0, ROBOT_RADIUS_MM + 10.0, 0.0)
    for motors, reaches in ((ALL, True), (MAIN_AND_VACUUM, False)):
        sim = Simulator(w, start=start)
        swept = SweptArea(w, start)
        drive_a_metre(sim, swept, motors)
        # the cells along the wall: centres 10 mm from it
        edge_row = [
            k
            for k in range(len(swept.cells))
            if swept.cells[k] and abs(swept.grid.centre(k)[1] - CELL_MM / 2) < 1e-6
            and 1100.0 < swept.grid.centre(k)[0] < 1900.0
        ]  # fmt: skip
        assert edge_row, "the floor along the wall is reachable"
        cleaned = [swept.cells[k] == 2 for k in edge_row]
        assert all(cleaned) if reaches else not any(cleaned)


TWO_ROOMS = """
name: two-rooms
rooms: [[[0, 0], [2.3, 0], [2.3, 0.8], [0, 0.8]]]
walls: [[1.0, 0.0, 1.0, 0.2], [1.0, 0.6, 1.0, 0.8]]   # a 0.4 m door
robot: {start: {at: [0.4, 0.4], heading: 0}}
areas:
  - {name: west, rect: [0, 0, 1.0, 0.8]}
  - {name: east, rect: [1.3, 0, 2.3, 0.8]}
"""


def spin_at(swept: SweptArea, time: float, x: float, y: float) -> float:
    """A full turn in place with every brush on (32 steps of 11.25 deg)."""
    for k in range(33):
        time += 0.015
        swept.update(time, x, y, math.remainder(k * math.tau / 32, math.tau), ALL)
    return time


def test_a_room_swept_everywhere_the_robot_fits_is_100_percent_the_other_0() -> None:
    w = parse_world(TWO_ROOMS, "<test>")
    swept = SweptArea(w, w.start)
    model = floor_model(w)
    assert swept.coverage_by_area() == {"west": 0.0, "east": 0.0}
    time = 0.0
    for k, free in enumerate(model.free):
        x, y = model.grid.centre(k)
        if free and x <= 1010.0:  # everywhere the robot fits in the west room and its door
            time = spin_at(swept, time, x, y)
            swept.update(time, x, y, 0.0, 0)  # brushes off between spots: no sweep across
    by_area = swept.coverage_by_area()
    assert by_area["west"] == 1.0
    assert by_area["east"] == 0.0
    assert 0.0 < swept.coverage() < 1.0


def test_reachable_floor_is_the_floor_within_reach_of_where_the_robot_fits() -> None:
    w = parse_world(
        """
name: nook
rooms: [[[0, 0], [1.4, 0], [1.4, 0.9], [0, 0.9]]]
obstacles: [{name: leg, rect: [0.6, 0.4, 0.7, 0.5]}]
robot: {start: {at: [0.3, 0.3], heading: 0}}
""",
        "<test>",
    )
    model = floor_model(w)
    reachable = reachable_floor(w, w.start)
    grid = model.grid
    window = math.ceil(REACH_MM / CELL_MM)
    for k, r in enumerate(reachable):
        if not model.floor[k]:
            assert not r
            continue
        j, i = divmod(k, grid.columns)
        near = any(
            model.free[(j + dj) * grid.columns + i + di]
            and (dj * dj + di * di) * CELL_MM**2 <= REACH_MM**2
            for dj in range(-window, window + 1)
            for di in range(-window, window + 1)
        )
        assert bool(r) == near, grid.centre(k)
    # the corners: 10 mm from both walls, 0.24 m from the nearest place the robot fits
    assert not reachable[grid.index_of(10.0, 10.0) or 0]
    assert reachable[grid.index_of(10.0, 450.0) or 0]  # along a wall: the side brush


def test_obstacles_drops_and_virtual_walls_bound_the_reachable_floor() -> None:
    w = parse_world(
        """
name: fenced
rooms: [[[0, 0], [6, 0], [6, 3], [0, 3]]]
obstacles: [{name: box, rect: [1.0, 1.0, 1.6, 1.6]}]
drops: [{name: stairs, rect: [2.5, 0, 3.0, 3.0]}]
robot: {start: {at: [0.5, 0.5], heading: 0}}
virtual_walls: [{from: [4.5, 0], to: [4.5, 3]}]
""",
        "<test>",
    )
    reachable = reachable_floor(w, w.start)
    grid = floor_model(w).grid

    def at(x: float, y: float) -> bool:
        k = grid.index_of(x, y)
        assert k is not None
        return bool(reachable[k])

    assert at(500, 500) and at(2300, 1500)
    assert not at(1300, 1300)  # under the obstacle
    assert not at(2700, 1500)  # over the drop
    assert not at(3500, 1500)  # past the drop: the robot cannot get there
    # a second start past the drop but before the virtual wall: its own region
    beyond = reachable_floor(w, Pose(3800.0, 1500.0, 0.0))
    assert beyond[grid.index_of(3500, 1500) or 0] and not beyond[grid.index_of(5000, 1500) or 0]


def test_coverage_curve_idle_time_and_marks_follow_the_time() -> None:
    w = world()
    swept = SweptArea(w, Pose(2000.0, 2000.0, 0.0))
    time = 0.0
    for k in range(int(12.0 / 0.015)):  # 6 s across the room, then 6 s standing, brushes on
        time = (k + 1) * 0.015
        x = 1000.0 + min(k, 400) * 3.0
        swept.update(time, x, 2000.0, 0.0, ALL)
    assert [t for t, _ in swept.curve] == pytest.approx([0.0, 5.0, 10.0], abs=0.02)
    assert swept.curve[1][1][0] > 0
    assert swept.longest_idle() == pytest.approx(12.0 - 6.0, abs=0.1)
    assert swept.cleaning_time == pytest.approx(12.0, abs=0.02)


def test_the_coverage_curve_of_a_run_of_days_stays_bounded_and_evenly_spaced() -> None:
    """The curve was sampled every 5 s for ever: 0.12 MB more an hour of a simulator left
    running (soak, finding 4). Past MAX_CURVE_SAMPLES it is thinned, every other sample
    dropped and the interval doubled, its first sample and its newest kept."""
    swept = SweptArea(world(), Pose(2000.0, 2000.0, 0.0))
    days = 3 * 24 * 3600.0
    time = 0.0
    while time < days:  # a step at each sample due: what the simulator's idle steps call
        time = max(swept.idle_until, time + 0.015)
        swept.update(time, 2000.0, 2000.0, 0.0, 0)
    times = [t for t, _ in swept.curve]
    assert len(times) <= MAX_CURVE_SAMPLES
    assert times[0] == 0.0 and days - times[-1] <= swept.sample_every
    assert swept.sample_every == SAMPLE_EVERY_S * 2**4  # thinned at 5.7, 11, 23 and 46 h
    gaps = {round(b - a, 3) for a, b in itertools.pairwise(times)}
    assert gaps == {swept.sample_every}


def test_the_simulator_tracks_coverage_when_asked_and_sends_the_same_bytes() -> None:
    w = world()
    start = Pose(1000.0, 2003.0, 0.0)
    host = (
        C.start().data + C.full().data + C.stream([7, 35, 43, 44]).data
        + C.motors(ALL).data + C.drive(250, 800).data
    )  # fmt: skip
    outputs = []
    for coverage in (False, True):
        sim = Simulator(w, start=start, coverage=coverage)
        sim.receive(host)
        outputs.append(sim.run(10.0))
        assert (sim.swept is not None) == coverage
    assert outputs[0] == outputs[1]
    assert sim.swept is not None and sim.swept.cleaned_total > 0


def test_the_firmware_clean_cycle_counts_as_cleaning_seek_dock_does_not() -> None:
    w = world()
    sim = Simulator(w, start=Pose(2000.0, 2000.0, 0.0), coverage=True)
    sim.receive(C.start().data + C.clean().data)
    sim.run(5.0)
    assert sim.swept is not None and sim.swept.cleaned_total > 0
    cleaned = sim.swept.cleaned_total
    sim.receive(C.seek_dock().data)
    sim.run(5.0)
    assert sim.swept.cleaned_total == cleaned


def test_steps_with_the_brushes_off_skip_the_update_and_the_coverage_is_the_same() -> None:
    # With no brush running the simulator only notes the step's time instead of updating the
    # swept area, until a mark is to be dropped or a sample is due (coverage.py, idle_until):
    # brushes on and off, across samples, the area is the one an update every step gives.
    w = world()
    sim = Simulator(w, start=Pose(1000.0, 2003.0, 0.0), coverage=True)
    every = SweptArea(w, sim.pose)
    sim.receive(C.start().data + C.full().data + C.drive(250, 800).data)
    brushes = ((3.0, 0), (4.0, ALL), (2.0, 0), (3.0, ALL), (2.0, 0b001), (6.5, 0), (3.0, 0b001))
    for seconds, motors in brushes:
        sim.receive(C.motors(motors).data)
        for _ in range(round(seconds / 0.015)):
            sim.step()
            every.update(sim.time, sim.x, sim.y, sim.theta, sim.motor_bits)
    swept = sim.swept
    assert swept is not None and swept.cleaned_total > 0
    assert swept.cleaning_time == every.cleaning_time
    assert swept.curve == every.curve and len(swept.curve) == 5
    assert swept.cells == every.cells and swept.longest_idle() == every.longest_idle()


def test_the_nearest_free_cell_is_the_one_whose_centre_is_nearest() -> None:
    """A start pose's nearest free cell (within 10 cells), against every free cell's centre
    measured by the grid itself, in each shipped world, from poses on and between cells."""
    from roomba_bt.sim import load_world
    from roomba_bt.sim.coverage import _nearest_free, floor_model

    for name in ("corridor", "apartment", "empty-room"):
        model = floor_model(load_world(name))
        grid, free = model.grid, model.free
        for n in range(400):
            x = grid.x0 + (n * 7.31 % (grid.columns * 0.8) + grid.columns * 0.1) * grid.cell
            y = grid.y0 + (n * 3.17 % (grid.rows * 0.8) + grid.rows * 0.1) * grid.cell
            if n % 5 == 0:  # on a cell's corner: four centres at one distance
                x = grid.x0 + round((x - grid.x0) / grid.cell) * grid.cell
                y = grid.y0 + round((y - grid.y0) / grid.cell) * grid.cell
            best: tuple[float, int] | None = None
            for a, b in grid.disc_spans(x, y, 10 * grid.cell):
                for k in range(a, b):
                    if free[k]:
                        cx, cy = grid.centre(k)
                        d = (cx - x) ** 2 + (cy - y) ** 2
                        if best is None or d < best[0]:
                            best = (d, k)
            assert _nearest_free(free, grid, x, y) == (None if best is None else best[1])
