"""The evaluation's measured simulator skips the loop bearing while the robot stands still and
keeps the longest stall and the longest time trapped lazily: each must measure what taking
it on every step measures."""

from __future__ import annotations

import math

from roomba_bt.evaluate.episode import TRAPPED_RADIUS_MM, _MeasuredSimulator, _world_centre
from roomba_bt.oi import commands
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.sim import load_world


class EveryStep:
    """The loop angle, the longest stall and the longest time trapped, taken on every step
    (no skip, no folding)."""

    def __init__(self, simulator: _MeasuredSimulator) -> None:
        self.centre = _world_centre(simulator.world)
        self.radius = max(
            1.0, math.hypot(simulator.x - self.centre[0], simulator.y - self.centre[1])
        )
        self.bearing = math.atan2(simulator.y - self.centre[1], simulator.x - self.centre[0])
        self.angle = 0.0
        self.mark = (0.0, 0.0)
        self.longest = 0.0
        self.anchor = (simulator.x, simulator.y, 0.0)
        self.trapped = 0.0

    def after_step(self, simulator: _MeasuredSimulator) -> None:
        bearing = math.atan2(simulator.y - self.centre[1], simulator.x - self.centre[0])
        self.angle += math.remainder(bearing - self.bearing, math.tau)
        self.bearing = bearing
        if abs(self.angle - self.mark[0]) * self.radius >= 300.0:
            self.mark = (self.angle, simulator.time)
        else:
            self.longest = max(self.longest, simulator.time - self.mark[1])
        x, y, since = self.anchor
        self.trapped = max(self.trapped, simulator.time - since)
        if math.hypot(simulator.x - x, simulator.y - y) >= TRAPPED_RADIUS_MM:
            self.anchor = (simulator.x, simulator.y, simulator.time)


def test_skipped_and_folded_measures_equal_the_per_step_ones() -> None:
    simulator = _MeasuredSimulator(load_world("corridor"), CREATE2, 3)
    reference = EveryStep(simulator)
    simulator.receive(commands.start().data + commands.full().data)
    # drive, stand, arc, stand longer, spin in place, back up: stalls of several lengths
    plan = [((200, 0), 400), ((0, 0), 300), ((150, 400), 500), ((0, 0), 700), ((100, 1), 200)]
    plan += [((-150, 0), 300), ((0, 0), 100)]
    for (velocity, radius), steps in plan:
        simulator.receive(commands.drive(velocity, radius).data)
        for _ in range(steps):
            simulator.step()
            reference.after_step(simulator)
            assert simulator.loops == reference.angle / math.tau
            assert simulator.longest_stall == reference.longest
            assert simulator.longest_trapped == reference.trapped
    assert simulator.longest_stall > 10.0  # the stands were measured
    assert simulator.loops != 0.0  # and so was the driving
    assert 10.0 < simulator.longest_trapped < simulator.time  # and left behind by it


def test_time_on_the_dock_is_not_time_trapped() -> None:
    """A robot waiting on the dock's contacts is where it is meant to be; the minute it
    stands off the dock after backing away is counted."""
    world = load_world("empty-room")
    assert world.dock is not None
    simulator = _MeasuredSimulator(world, CREATE2, 3, start=world.dock.docked_pose)
    # Full: Safe falls to Passive on a powered dock, and Passive would not back off it
    simulator.receive(commands.start().data + commands.full().data)
    for _ in range(4000):  # a minute on the dock
        simulator.step()
    assert simulator.docked and simulator.longest_trapped == 0.0
    simulator.receive(commands.drive(-100, 0).data)
    for _ in range(200):  # 3 s backing off: 30 cm
        simulator.step()
    simulator.receive(commands.drive(0, 0).data)
    for _ in range(4000):  # a minute off it, a few cm from it
        simulator.step()
    assert not simulator.docked
    # the minute stood plus the back-off since it left the contacts, not the minute on them
    assert 60.0 < simulator.longest_trapped < 63.0
