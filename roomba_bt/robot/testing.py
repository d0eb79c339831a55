"""A robot handle for tests: behaviours ticked with no robot, frames set by hand.

:class:`StubRobot` is what the behaviour, mission and plugin tests hand to
``tree.setup(robot=...)`` in place of the runtime's handle (:class:`RobotHandle`): no port,
no simulator, no mode model; the test says what each frame holds and reads back what the
behaviours queued::

    robot = StubRobot()
    node.setup(robot=robot)
    robot.set_frame({7: 1, 35: 2})   # bump right, in Safe
    node.tick_once()
    robot.flush()                    # [Command(drive ...)], also kept in robot.sent
"""

from __future__ import annotations

from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import ENCODER_PACKETS, SLOT_SECONDS, layout_for
from roomba_bt.oi.modes import OI_MODE_PACKET, OIMode
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.robot.interface import BaseHandle, Odometry, Snapshot

__all__ = ["StubRobot"]

_MODE_VALUES = frozenset(int(mode) for mode in OIMode)


class StubRobot(BaseHandle):
    """A :class:`RobotHandle` whose frames a test sets by hand: tick behaviours with no robot.

    ``stub.set_frame({7: 1, 35: 2})`` builds a frame of exactly those packets (ids -> raw
    values) and advances the clock by one slot.
    """

    def __init__(self, profile: RobotProfile = DEFAULT_PROFILE, mode: OIMode = OIMode.SAFE) -> None:
        super().__init__(profile)
        self._tick = -1
        self._mode = mode
        self._odometry = Odometry()
        self._snapshot = Snapshot(
            frame=layout_for((OI_MODE_PACKET,), profile, False, False).decode(bytes((int(mode),))),
            tick=0,
            time=0.0,
            mode=mode,
            profile=profile,
        )
        self.sent: list[Command] = []
        self._cycle_may_run = False

    @property
    def snapshot(self) -> Snapshot:
        return self._snapshot

    def set_frame(
        self, values: dict[int, int], *, mode: OIMode | None = None, ticks: int = 1
    ) -> Snapshot:
        """Advance ``ticks`` slots and make a frame of ``values`` the current snapshot. The
        snapshot before it stays the tree's previous tick (``Snapshot.previous_tick``): the
        slots jumped over are frames lost on the way, not ticks a node missed."""
        ids = tuple(sorted(values))
        layout = layout_for(ids, self._profile, False, False)  # packet 35 holds the mode itself
        frame = layout.decode(layout.pack(values))
        if mode is not None:
            self._mode = mode
        elif values.get(OI_MODE_PACKET) in _MODE_VALUES:
            # out of range (4...): the runtime drops such a frame, the mode stays as it was
            self._mode = OIMode(values[OI_MODE_PACKET])
        if all(pid in values for pid in ENCODER_PACKETS):
            left, right = (values[pid] for pid in ENCODER_PACKETS)
            self._odometry = self._odometry.advance(left, right, self._profile.wheel_base_mm)
        self._tick += ticks
        self._snapshot = Snapshot(
            frame=frame,
            tick=self._tick,
            time=self._tick * SLOT_SECONDS,
            mode=self._mode,
            odometry=self._odometry,
            profile=self._profile,
            cycle_may_run=self._cycle_may_run,
            previous_tick=self._tick - ticks,
        )
        return self._snapshot

    def flush(self) -> list[Command]:
        """What the runtime would write after this tick (no guard): recorded in ``sent``, and
        written to the outbox's record (:meth:`Outbox.written`, the songs ``play`` times).
        A built-in cycle among them may drive until a command ends it, as the runtime's
        writer keeps it (the next frame's ``snapshot.cycle_may_run``)."""
        out = self._outbox.drain()
        self.sent.extend(out)
        for command in out:
            self._cycle_may_run = command.spec.cycle_may_run_after(self._cycle_may_run)
            self._outbox.written(command)  # as the runtime's flush: the robot obeys it now
        return out
