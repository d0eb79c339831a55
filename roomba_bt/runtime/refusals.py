"""The tree's commands the mode guard refused, as the run says them.

A refused command is written nowhere (robot/writer.py); the run counts it, says the first
:data:`MAX_SAID` with when and who sent it (the CLI prints some after the summary, the
monitor shows the last), and keeps the first in the summary for its warning and
``--strict``'s verdict.
"""

from __future__ import annotations

from roomba_bt.oi.encode import Command
from roomba_bt.robot.errors import ModeError
from roomba_bt.runtime.summary import RunSummary

#: the refusals a run says (every one is counted)
MAX_SAID = 100


class Refusals(list[str]):
    """The refusals said so far (:func:`refusal`), a list the CLI and the monitor read;
    :meth:`note` counts one in ``summary`` too."""

    def __init__(self, summary: RunSummary) -> None:
        super().__init__()
        self.summary = summary

    def note(
        self, command: Command, exc: ModeError, sender: object, when: float | None, arrival: float
    ) -> None:
        """``command``, which ``sender`` queued, refused with ``exc`` in the tick of mission
        time ``when`` (None before the first), the link's newest frame at ``arrival``."""
        summary = self.summary
        summary.refused_commands += 1
        if len(self) < MAX_SAID:
            self.append(refusal(command, exc, sender, when, arrival))
        if not summary.first_refusal:
            summary.first_refusal = self[0]


def refusal(
    command: Command, exc: ModeError, sender: object, when: float | None, arrival: float
) -> str:
    """``t=12.345 drive_straight: drive needs Safe or Full; the robot is in Passive since
    t=12.300, after a cliff``: when (``when``, the tick's mission time; None before the
    first), who sent it (``sender``, the outbox's), and the mode's start in mission time
    (the error's own words give the time of day, which a ``--fast`` run never saw;
    ``arrival``: the link's newest, on its clock)."""
    name = getattr(sender, "name", None)
    by = f" {name}:" if isinstance(name, str) else ""
    text = str(exc)
    if exc.since is not None and when is not None:
        # the link's clock and mission time advance together: the mode began as long
        # before this tick as the link's newest arrival is after its start
        ago = max(0.0, arrival - exc.since)
        text = exc.worded(f"t={max(0.0, when - ago):.3f}")
    return f"t={0.0 if when is None else when:.3f}{by} {text}"
