"""Buttons (165) pushes the robot's buttons: a Clean, Spot or Dock button pushed in Passive
starts that cycle, as its command does (both specs: Clean (135) "is the same as pressing
Roomba's Clean button", Spot (134) and Seek Dock (143) likewise for theirs); in Safe and Full
"Roomba ... does not respond to button presses", and only packet 18 shows the push. Before,
the simulator only set packet 18 (docs/simulator.md, decided)."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as oi
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600, RobotProfile
from roomba_bt.sim import Simulator, load_world

#: the Buttons bits (packet 18, the byte of opcode 165; both specs' table)
CLEAN, SPOT, DOCK, MINUTE, HOUR, DAY, SCHEDULE, CLOCK = (1 << n for n in range(8))
#: each button that starts a cycle, and the cycle it starts (the opcode table's names)
CYCLE_BUTTONS = [(CLEAN, "clean"), (SPOT, "spot"), (DOCK, "seek_dock")]


def _passive(profile: RobotProfile = CREATE2, pause: bool = True) -> Simulator:
    sim = Simulator(load_world("empty-room"), profile, 0, cycle_commands_pause=pause)
    sim.receive(oi.start().data)
    sim.step()
    return sim


def _cycles(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "builtin"]


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600, ROOMBA500], ids=lambda p: p.name)
@pytest.mark.parametrize(("button", "cycle"), CYCLE_BUTTONS, ids=[c for _, c in CYCLE_BUTTONS])
def test_a_cycle_button_pushed_in_passive_starts_its_cycle(
    profile: RobotProfile, button: int, cycle: str
) -> None:
    sim = _passive(profile)
    sim.receive(oi.buttons(button).data)
    assert sim.builtin is not None and sim.builtin.name == cycle
    assert sim.values[18] == button, "packet 18 shows the push"
    assert sim.mode is OIMode.PASSIVE
    x, y = sim.x, sim.y
    for _ in range(100):
        sim.step()
    assert (sim.x, sim.y) != (x, y), "the cycle drives the robot"
    assert sim.values[18] == 0, "released after 1/6 s"


@pytest.mark.parametrize("mode", ["safe", "full"])
def test_in_safe_and_full_a_button_push_starts_nothing(mode: str) -> None:
    sim = _passive()
    sim.receive(getattr(oi, mode)().data + oi.buttons(CLEAN).data)
    assert sim.builtin is None and sim.values[18] == CLEAN
    assert sim.mode is OIMode[mode.upper()]


def test_the_scheduling_buttons_start_nothing() -> None:
    sim = _passive()
    sim.receive(oi.buttons(MINUTE | HOUR | CLOCK).data)
    assert sim.builtin is None and sim.values[18] == MINUTE | HOUR | CLOCK


def test_clean_pushed_again_pauses_the_cycle_as_its_command_does() -> None:
    sim = _passive()
    sim.receive(oi.buttons(CLEAN).data)
    cycle = sim.builtin
    for _ in range(20):
        sim.step()
    sim.receive(oi.buttons(CLEAN).data)
    assert sim.builtin is None and sim.paused_cycle is cycle
    assert _cycles(sim)[-1] == "clean paused (clean)"


def test_several_cycle_buttons_at_once_start_the_first_in_bit_order() -> None:
    """Neither spec says; decided: Clean (bit 0), then Spot (1), then Dock (2)."""
    sim = _passive()
    sim.receive(oi.buttons(DOCK | SPOT).data)
    assert sim.builtin is not None and sim.builtin.name == "spot"
