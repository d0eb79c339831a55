"""The tree's commands the mode guard refused, as the run says them.

A refused command is written nowhere (robot/writer.py); the run counts it, says the first
:data:`MAX_SAID` with when and who sent it (the CLI prints some after the summary, the
monitor shows the last), and keeps the first in the summary for its warning and
``--strict``'s verdict.
"""

from __future__ import annotations

from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.registry import class_where
from roomba_bt.oi.encode import Command
from roomba_bt.robot.errors import ModeError
from roomba_bt.runtime.summary import YOUR_ACTION_FIX, RunSummary

#: the refusals a run says (every one is counted)
MAX_SAID = 100


class Refusals(list[str]):
    """The refusals said so far (:func:`refusal`), a list the CLI and the monitor read;
    :meth:`note` counts one in ``summary`` too."""

    def __init__(self, summary: RunSummary) -> None:
        super().__init__()
        self.summary = summary
        #: the names of the actions of the user's own code (a plugin's, a program's) whose
        #: commands were refused: each said once (the summary's ``refused_actions``, in the
        #: order met: :meth:`hints`)
        self.authors: set[str] = set()

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
        if (
            isinstance(sender, Action)
            and not type(sender).__module__.startswith("roomba_bt.")
            and sender.name not in self.authors
        ):
            self.authors.add(sender.name)
            summary.refused_actions += ((sender.name, class_where(type(sender))),)

    def hints(self) -> list[str]:
        """What the author of each action of theirs that was refused does about it: the
        built-in driving actions check the mode first, and a plugin's that sent its drive on
        every tick after a cliff had dropped the robot to Passive (3543 refusals, a stranger's
        first plugin) was told only ``drive needs Safe or Full``, the fix being on a page."""
        return [
            f"{name} ({where}) is your code: {YOUR_ACTION_FIX}"
            for name, where in self.summary.refused_actions
        ]


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
