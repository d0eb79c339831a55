"""A finished run is freed: its connection, simulator and tree go when the program lets go
of them (an embedder's report: thousands of in-process episodes, a gym-like env, grew by
105-140 KB an episode for ever).

The connection's finalizer (the safe stop of a connection dropped unclosed) holds its
``SafeStop``; the run's watch of the robot's own cycles hooked itself on the writer, and
held the connection: the finalizer's own argument kept the connection alive, so it never
fired and nothing of any run was ever freed (``robot/weak.py``)."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Callable
from typing import ClassVar

import pytest

from roomba_bt import CREATE2, RunStack, SimLink, Simulator, load_mission, load_world
from roomba_bt.evaluate.episode import EpisodeSpec, _MeasuredSimulator, run_episode
from roomba_bt.runtime.summary import Outcome

EPISODES = 5


def _all_dead(refs: list[weakref.ref[object]]) -> list[str]:
    """The objects of ``refs`` still alive after a collector pass, by type."""
    gc.collect()
    return [type(alive).__name__ for ref in refs if (alive := ref()) is not None]


def _by_run(stack: RunStack) -> None:
    assert stack.run().outcome is Outcome.SUCCESS


def _by_ticks(stack: RunStack) -> None:
    for _ in stack.ticks():
        continue
    assert stack.summary.outcome is Outcome.SUCCESS


def _by_ticks_left_early(stack: RunStack) -> None:
    for tick in stack.ticks():
        if tick.number == 10:
            break
    assert stack.summary.outcome is Outcome.INTERRUPTED


@pytest.mark.parametrize("drive", [_by_run, _by_ticks, _by_ticks_left_early])
def test_closed_runs_leave_nothing_alive(drive: Callable[[RunStack], None]) -> None:
    """``with RunStack(...)`` episodes, then a collector pass: no connection, simulator
    link, runner or tree of theirs is alive."""
    world = load_world("empty-room")
    refs: list[weakref.ref[object]] = []
    for seed in range(EPISODES):
        mission = load_mission("bump-and-turn", {"duration": "1 s"})
        link = SimLink(Simulator(world, CREATE2, seed=seed, trace=False))
        with RunStack(mission, link, profile=CREATE2, timeout_s=30.0) as stack:
            drive(stack)
        # the link, not the simulator (slotted: no weak reference), holds the simulator
        refs += [weakref.ref(o) for o in (stack.connection, link, stack.runner, mission.root)]
        del stack, link, mission
    assert _all_dead(refs) == []


class _Counted(_MeasuredSimulator):
    """The evaluation's simulator, each instance's weak reference kept."""

    made: ClassVar[list[weakref.ref[object]]] = []

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        _Counted.made.append(weakref.ref(self))


def test_evaluation_episodes_leave_nothing_alive() -> None:
    """``run_episode`` (what ``eval`` runs in each worker) frees each episode's simulator,
    and with it its connection; the compiled mission the worker keeps for the next episode
    (``episode._COMPILED``) is never run itself (it held the first episode's run)."""
    _Counted.made.clear()
    for seed in range(EPISODES):
        spec = EpisodeSpec(mission="dock", seed=seed, timeout_s=20.0, trace_every=0)
        run_episode(spec, _Counted)
    assert len(_Counted.made) == EPISODES
    assert _all_dead(_Counted.made) == []
