"""Wheel reversals in an episode: how often the commanded wheels change direction.

The simulator has no acceleration limit, so a behaviour that flips a wheel between forward
and backward every tick or two costs nothing there; on a real Create 2 each flip reverses
the wheel's motor (gearbox strain, current spikes, a robot that shudders). This counts them
from what the mission asked for: the wheel speeds of the Drive (137) and Drive Direct (145)
commands the simulator heard (``requested_left``/``requested_right``), read every 15 ms
step. A reversal is a wheel's sign changing between two non-zero requests (a stop between
forward and backward still reverses the motor); each wheel is followed on its own, and the
interval that matters is the time since that wheel's previous reversal.

``python -m bench.wheel_reversals`` prints the figures for the shipped missions
(docs/routines.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, _MeasuredSimulator, run_episode
from roomba_bt.sim.state import STEP_SECONDS

__all__ = ["WheelReversals", "count_reversals"]

#: a wheel reversed again sooner than this (s) after its previous reversal: chatter, not a
#: manoeuvre (a bump's back-off and turn reverse a wheel twice 0.2-0.5 s apart)
CHATTER_S = 0.15


@dataclass
class WheelReversals:
    """Reversals seen so far: when (s of mission time), and each wheel's last direction."""

    #: (time, interval since the same wheel's previous reversal, or None for its first)
    events: list[tuple[float, float | None]] = field(default_factory=list)
    duration_s: float = 0.0
    _sign: list[int] = field(default_factory=lambda: [0, 0])
    _last: list[float | None] = field(default_factory=lambda: [None, None])

    def see(self, time_s: float, left: float, right: float) -> None:
        """The wheel speeds requested at ``time_s``."""
        self.duration_s = time_s
        for wheel, speed in enumerate((left, right)):
            sign = (speed > 0) - (speed < 0)
            if sign == 0:
                continue
            if self._sign[wheel] == -sign:
                last = self._last[wheel]
                self.events.append((time_s, None if last is None else time_s - last))
                self._last[wheel] = time_s
            self._sign[wheel] = sign

    @property
    def per_minute(self) -> float:
        return 60.0 * len(self.events) / self.duration_s if self.duration_s > 0 else 0.0

    @property
    def shortest_s(self) -> float | None:
        """The shortest interval between two reversals of one wheel (None: none twice)."""
        return min((i for _, i in self.events if i is not None), default=None)

    def chatter(self, within_s: float = CHATTER_S) -> int:
        """Reversals sooner than ``within_s`` after the same wheel's previous one."""
        return sum(1 for _, i in self.events if i is not None and i < within_s - 1e-9)


def count_reversals(spec: EpisodeSpec) -> tuple[EpisodeResult, WheelReversals]:
    """Run the episode of ``spec`` (the same one :func:`run_episode` runs), counting the
    wheel reversals of every step."""
    seen = WheelReversals()

    class Counting(_MeasuredSimulator):
        def step(self, dt: float = STEP_SECONDS) -> None:
            super().step(dt)
            seen.see(self.time, self.requested_left, self.requested_right)

    return run_episode(spec, Counting), seen
