"""The robot's own clock and weekly cleaning schedule: what Set Day/Time (168) and Schedule
(167) set.

No sensor packet reports either (both specs), so the host never reads them back; the
simulator keeps them so that a test or ``roomba-bt clock`` can see what a robot would hold::

    [168][day][hour][minute]          day 0 Sunday .. 6 Saturday, 24-hour time
    [167][days][sun h][sun m] ... [sat h][sat m]
         days: bit 0 Sunday .. bit 6 Saturday; a day whose bit is clear cleans at no time

Both specs: "If Roomba's schedule or clock button is pressed, this command will be ignored"
(``oi.bits.held_clock_buttons``, which the protocol asks).
Not on the step's path: an object with its own state, as the timeline is (state.py).
"""

from __future__ import annotations

from dataclasses import dataclass

from roomba_bt.oi.encode import schedule_times

_WEEK_MINUTES = 7 * 24 * 60


@dataclass(slots=True)
class RobotClock:
    """The day and time last set, when (simulated seconds), and the schedule's data bytes.

    Power-on is Sunday 00:00 at 0 s, with no schedule (15 zero bytes: "To disable scheduled
    cleaning, send all 0s")."""

    day_time: tuple[int, int, int] = (0, 0, 0)
    set_at: float = 0.0
    schedule: bytes = bytes(15)
    #: whether a host set either since power-on (``sim``'s summary says what it holds)
    touched: bool = False

    def set(self, data: bytes, now: float) -> None:
        """Set Day/Time (168)'s three data bytes, taken at ``now``."""
        self.day_time = (data[0], data[1], data[2])
        self.set_at = now
        self.touched = True

    def set_schedule(self, data: bytes) -> None:
        """Schedule (167)'s fifteen data bytes, taken."""
        self.schedule = bytes(data)
        self.touched = True

    def shows(self, now: float) -> tuple[int, int, int]:
        """The day (0 Sunday), hour and minute the clock reads at ``now``: the time set, run
        on by the whole minutes since (the week wraps round), as a 600's display shows it."""
        day, hour, minute = self.day_time
        ran = int((now - self.set_at) // 60.0)
        minutes = ((day * 24 + hour) * 60 + minute + ran) % _WEEK_MINUTES
        return minutes // 1440, minutes // 60 % 24, minutes % 60

    @property
    def cleans(self) -> dict[str, tuple[int, int]]:
        """The schedule as days and their (hour, minute), Sunday first; {} when disabled."""
        return schedule_times(self.schedule)
