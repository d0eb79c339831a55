"""A cycle command (Spot, Clean, Max, Seek Dock) into a running cycle pauses it, as the 600 /
Create 2 OI spec says ("will pause a cleaning cycle if one is already in progress"); the same
command resumes it, another starts its own cycle, Safe, Full, Power, Stop or Reset ends it,
Start does not (docs/simulator.md, decided). Off by default on a ``Simulator`` built
directly (the golden recordings), on in every simulator the CLI builds."""

from __future__ import annotations

import pytest

from roomba_bt.cli.links import make_simulator
from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.sim import Simulator, load_world


def _cleaning(pause: bool = True) -> Simulator:
    sim = Simulator(load_world("empty-room"), CREATE2, 0, cycle_commands_pause=pause)
    sim.receive(oi.start().data + oi.clean().data)
    for _ in range(40):
        sim.step()
    assert sim.builtin is not None and sim.builtin.name == "clean"
    return sim


def _moves(sim: Simulator, steps: int = 40) -> float:
    x, y = sim.x, sim.y
    for _ in range(steps):
        sim.step()
    return ((sim.x - x) ** 2 + (sim.y - y) ** 2) ** 0.5


def test_clean_into_a_running_clean_pauses_it_and_a_second_clean_resumes_it() -> None:
    sim = _cleaning()
    cycle = sim.builtin
    sim.receive(oi.clean().data)
    assert sim.builtin is None and sim.paused_cycle is cycle
    assert sim.mode is OIMode.PASSIVE
    assert _moves(sim) < 1.0  # paused: it stands
    started = cycle.started if cycle is not None else 0.0
    sim.receive(oi.clean().data)
    assert sim.builtin is cycle and sim.paused_cycle is None
    assert cycle is not None and cycle.started > started  # the pause does not count
    assert _moves(sim) > 50.0
    details = [e.detail for e in sim.events if e.kind == "builtin"]
    assert details[-2:] == ["clean paused (clean)", "clean resumed"]


def test_another_cycle_command_pauses_and_then_starts_its_own_cycle() -> None:
    sim = _cleaning()
    sim.receive(oi.seek_dock().data)  # Seek Dock in the middle of Clean: a pause
    assert sim.builtin is None and sim.paused_cycle is not None
    sim.receive(oi.spot().data)  # paused: Spot starts the spiral, the Clean is dropped
    assert sim.builtin is not None and sim.builtin.name == "spot"
    assert sim.paused_cycle is None


@pytest.mark.parametrize("command", ["safe", "full", "power", "stop"])
def test_a_mode_command_that_ends_a_cycle_ends_a_paused_one(command: str) -> None:
    sim = _cleaning()
    sim.receive(oi.clean().data)
    sim.receive(getattr(oi, command)().data)
    assert sim.paused_cycle is None and sim.builtin is None
    sim.receive(oi.start().data + oi.clean().data)  # nothing paused any more: a new cycle
    assert sim.builtin is not None and sim.builtin.started == sim.time


@pytest.mark.parametrize("pause", [True, False])
def test_start_ends_no_cycle_running_or_paused(pause: bool) -> None:
    """Decided (session 30, docs/protocol.md "What ends a built-in cycle"): neither spec says
    Start (128) ends a cycle, and Passive, where Start leads, is where the robot runs one
    ("watch Roomba perform a cleaning cycle"); Safe and Full end it. The simulator ended it
    at Start, which hid a runtime that ended a cycle by Start alone (the robot layer never
    relied on it: Safe first)."""
    sim = _cleaning(pause)
    cycle = sim.builtin
    sim.receive(oi.start().data)
    assert sim.builtin is cycle and sim.mode is OIMode.PASSIVE
    assert _moves(sim) > 50.0, "it drives on"
    if pause:
        sim.receive(oi.clean().data + oi.start().data)
        assert sim.paused_cycle is cycle and sim.builtin is None, "paused, still paused"
        sim.receive(oi.clean().data)
        assert sim.builtin is cycle, "and resumed by a second Clean"
    sim.receive(oi.safe().data)
    assert sim.builtin is None and sim.paused_cycle is None


def test_by_default_a_directly_built_simulator_replaces_the_cycle() -> None:
    """The behaviour the golden recordings were made with (they send Spot into Clean)."""
    sim = _cleaning(pause=False)
    sim.receive(oi.spot().data)
    assert sim.builtin is not None and sim.builtin.name == "spot"
    assert sim.paused_cycle is None


def test_the_clis_simulators_pause() -> None:
    assert make_simulator("empty-room", CREATE2, 0).cycle_commands_pause
