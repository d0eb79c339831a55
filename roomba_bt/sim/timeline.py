"""The world's timeline: what happens to the robot at set times (a world file's ``events``).

``bump`` holds the bumper pressed on one side or both, ``lift`` picks the robot up (both wheel
drops, every cliff, no traction), ``charger_step`` takes the dock's power away, ``plug`` puts
the wall charger's plug in the robot's socket (the internal charger: packet 34 bit 0, and in
Safe mode the spec's "charger plugged in and powered" drops the robot to Passive),
``overcurrent`` sets a motor's bit of packet 14 (a tangled brush); each for its
``duration`` seconds; ``press`` presses a button for the spec's 1/6 s (the simulator presses
it as Buttons 165 does: :meth:`~roomba_bt.sim.protocol.OIProtocol.press_button`). Every
start and end is marked in the run's events.

A component with its own state (the events still to come and those under way): the simulator
asks it only while it has any, and drops it after the last one ends.
"""

from __future__ import annotations

from roomba_bt.oi.bits import OVERCURRENT_BITS
from roomba_bt.sim.sensing import BUMP_SIDE_BITS
from roomba_bt.sim.world import TimelineEvent


class Timeline:
    """The world's timeline events, started and ended as the clock passes them."""

    def __init__(self, events: tuple[TimelineEvent, ...]) -> None:
        self.pending: list[TimelineEvent] = list(events)
        self.active: list[TimelineEvent] = []
        #: the buttons whose ``press`` the last :meth:`advance` started, for the simulator
        #: to press (a press is a moment, not a state :meth:`effects` holds)
        self.pressed: list[str] = []

    @property
    def over(self) -> bool:
        return not self.pending and not self.active

    def advance(self, now: float) -> list[tuple[str, str]]:
        """Start the events due by ``now``, end those past their duration; returns the
        (kind, detail) marks of what started and ended."""
        marks: list[tuple[str, str]] = []
        self.pressed = []
        pending = self.pending
        while pending and pending[0].time <= now:
            event = pending.pop(0)
            self.active.append(event)
            if event.kind == "press":
                self.pressed.append(event.button)
                marks.append((event.kind, f"{event.button} start"))
            elif event.kind == "overcurrent":
                marks.append((event.kind, f"{event.motor} start"))
            elif event.kind == "plug":
                marks.append((event.kind, "plugged in"))
            else:
                marks.append((event.kind, f"{event.side} start"))
        still = []
        for event in self.active:
            if now < event.time + event.duration:
                still.append(event)
            else:
                marks.append((event.kind, "unplugged" if event.kind == "plug" else "end"))
        self.active = still
        return marks

    def effects(self) -> tuple[int, bool, bool, int, bool]:
        """What the events under way do: (bumper bits held, lifted, dock powered, packet
        14's overcurrent bits held, the wall charger plugged in)."""
        bump = 0
        lifted = False
        powered = True
        overcurrents = 0
        plugged = False
        for event in self.active:
            if event.kind == "bump":
                bump |= BUMP_SIDE_BITS[event.side]
            elif event.kind == "lift":
                lifted = True
            elif event.kind == "charger_step":
                powered = False
            elif event.kind == "overcurrent":
                overcurrents |= OVERCURRENT_BITS[event.motor]
            elif event.kind == "plug":
                plugged = True
        return bump, lifted, powered, overcurrents, plugged
