"""The world's timeline on its own: events start and end as the clock passes them, their effects
overlap, and the simulator lets go of the timeline once the last event has ended."""

from __future__ import annotations

from roomba_bt.oi import commands as C
from roomba_bt.sim.timeline import Timeline
from roomba_bt.sim.world import TimelineEvent

from .helpers import BOX, make


def test_events_start_and_end_as_the_clock_passes_them() -> None:
    timeline = Timeline((TimelineEvent(1.0, "bump", 0.5, "left"), TimelineEvent(1.2, "lift", 1.0)))
    assert timeline.advance(0.9) == []
    assert timeline.effects() == (0, False, True)
    assert timeline.advance(1.2) == [("bump", "left start"), ("lift", "both start")]
    assert timeline.effects() == (2, True, True)
    assert timeline.advance(1.5) == [("bump", "end")]
    assert timeline.effects() == (0, True, True)
    assert not timeline.over
    assert timeline.advance(2.2) == [("lift", "end")]
    assert timeline.over


def test_a_charger_step_takes_the_docks_power_and_bumps_add_up() -> None:
    timeline = Timeline(
        (
            TimelineEvent(0.0, "bump", 1.0, "right"),
            TimelineEvent(0.0, "bump", 1.0, "left"),
            TimelineEvent(0.0, "charger_step", 1.0),
        )
    )
    timeline.advance(0.0)
    assert timeline.effects() == (3, False, False)


def test_the_simulator_marks_every_start_and_end_and_then_drops_the_timeline() -> None:
    text = BOX + "events: [{at: 0.3, kind: bump, side: right, duration: 0.3}]\n"
    host = make(text)
    host.send(C.stream([7]))
    host.run(1.0)
    marks = [(e.kind, e.detail) for e in host.sim.events if e.kind == "bump"]
    # the timeline's start, the bumper's own bump event, the timeline's end
    assert marks == [("bump", "right start"), ("bump", "right"), ("bump", "end")]
    assert host.sim._timeline is None
    assert host.sim.values[7] == 0
