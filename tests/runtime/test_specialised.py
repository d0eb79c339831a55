"""The tick path's objects stay in the form CPython 3.11 specialises (docs/performance.md,
session 13): no ``__getattr__`` on a class whose attributes are read every tick, and at most
30 attributes in an instance's dictionary (past that the instance's shared-key table gives
up, and every attribute read and method call on it takes the generic path: the runner's 31st
attribute cost about 11,000 instructions a tick). Structure, not timing: these fail when a
change adds what would make the tick several percent slower without a test noticing."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.behaviours.docking import DockApproach, DockDriveOn, DockSearch, DockWaitCharge
from roomba_bt.runtime.loop import MissionRunner
from roomba_bt.sim import Simulator, load_world

from .simrun import RunMission

#: CPython 3.11's limit of a class's shared key table (Objects/dictobject.c, SHARED_KEYS_MAX_SIZE)
SHARED_KEYS_MAX = 30
MISSIONS = Path(__file__).resolve().parents[2] / "missions"


def test_the_runner_keeps_few_attributes_and_no_getattr(run_mission: RunMission) -> None:
    runners: list[MissionRunner] = []
    run_mission("tree:\n  sequence:\n    - mode: safe\n    - wait: 100ms\n",
                observer=runners.append)  # fmt: skip
    runner = runners[-1]
    assert not hasattr(type(runner), "__getattr__")
    assert len(vars(runner)) <= SHARED_KEYS_MAX, sorted(vars(runner))


def test_the_simulator_keeps_its_state_in_slots() -> None:
    simulator = Simulator(load_world("empty-room"))
    simulator.step()
    assert not hasattr(simulator, "__dict__")


def test_the_docking_stages_keep_few_attributes_of_their_own(run_mission: RunMission) -> None:
    """The shipped dock mission for a while: every stage that ran, as it is after its ticks
    (the stages' state is set when they start and tick, not only when made)."""
    runners: list[MissionRunner] = []
    text = (MISSIONS / "dock.yaml").read_text()
    run_mission(text, timeout=20.0, observer=runners.append)
    stages = (DockSearch, DockApproach, DockDriveOn, DockWaitCharge)
    ran = [node for node in runners[-1].mission.root.iterate() if isinstance(node, stages)]
    assert ran
    for node in ran:
        assert len(vars(node)) <= SHARED_KEYS_MAX, (node.name, sorted(vars(node)))
        assert not hasattr(type(node), "__getattr__")
