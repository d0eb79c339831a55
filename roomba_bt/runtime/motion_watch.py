"""Whether the robot does what it was told: bytes lost on their way to the robot, noticed by
the wheels' encoders and put right by the run.

A cable that loses bytes loses them both ways. A byte lost on its way from us leaves the
robot's OI parser waiting for the command's missing data byte: ``89 00 c8 80 00`` (Drive 200
straight) arriving as ``89 00 80 00`` moves nothing, and the next command's first byte
completes it (``89 00 80 00 89``: velocity 128, radius 137, a drive nobody sent); the rest of
that command is skipped as no opcode. Nothing comes back to say so: the Open Interface
acknowledges no command. A run on such a cable once stood for 19 s while its tree "drove",
and ended SUCCESS.

The robot's encoders (packets 43, 44: every run streams them) say what its wheels did.
Once a second of mission time (:class:`~roomba_bt.runtime.long_run.MissionTimeChecks`, which
calls :meth:`MotionWatch.look`; nothing more on the tick path, and nothing written on a line
that loses nothing), the watch compares them with the wheel command last written
(``CommandWriter.last_wheels``), when the same command stood over the whole second: written
once, before the last look, and not again since (``CommandWriter.wheel_writes``; equal bytes
are not enough: Drive 0, Drive 200, Drive 0 within the second is a stop whose wheels rightly
turned, and a look that took it for one stop that stood ended valid stop-and-go missions as a
lost link):

* it turns a wheel at a full speed step (28.5 mm/s) or more, and neither encoder moved; or
* it turns no wheel, and a wheel turned :data:`RUNAWAY_MM` or more (a robot slowing down
  after a stop written just before the last look turns its wheels a few centimetres at
  most; a drive the robot made of a lost byte and the next command's, 128 mm/s say, twice
  that or more).

It judges nothing in Passive, while a built-in cycle may drive, while the bump reflex holds
forward motion, or while the frame shows a wheel drop, a wheel's overcurrent, or a bump
under a command that drives forward (a robot lifted, stalled on a carpet's edge or pushing
a wall turns its wheels or stalls them for reasons of its own; one backing or turning away
from what it bumped is free to), nor a Drive PWM (its speed is no speed).

A finding is put right at once: :data:`~roomba_bt.robot.writer.RESYNC_ZEROS` (they complete
whatever command the parser waits in, harmlessly) and the wheel command again, and the
Motors command again if it runs a brush or the vacuum (the zeros may have completed a Motors
as "off"), in one write. At the next look the wheels obeyed (the bytes were lost: said in
the summary's ``unheard`` line) or still did not (a robot wedged with no bump shown, its
wheels stalled: said once, not resent again while that command stands). A third finding the
wheels then obeyed within a minute ends the run with the safe stop, its drive 0 after zeros
too: a line that loses that many commands cannot be trusted with the next stop.
"""

from __future__ import annotations

import logging

from roomba_bt.oi import commands as oi
from roomba_bt.oi.bits import BUMP_BITS, WHEEL_DROP_BITS
from roomba_bt.oi.encode import Command, turns_wheels
from roomba_bt.oi.frames import SensorFrame
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.odometry import WHEEL_SPEED_STEP_MM_S, encoder_delta, mm_to_counts
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.hazards import drives_forward, sets_going
from roomba_bt.robot.interface import Snapshot
from roomba_bt.robot.writer import RESYNC_ZEROS
from roomba_bt.runtime.summary import Outcome, RunSummary
from roomba_bt.transport.link_kind import link_of

log = logging.getLogger("roomba_bt.runtime.loop")

#: Findings put right within :data:`GIVE_UP_WITHIN_S` of mission time that end the run.
GIVE_UP_AFTER = 3
GIVE_UP_WITHIN_S = 60.0
#: How far a wheel turns in the second under a stop before the watch takes it for a drive
#: nobody sent (the stop lost on the line), rather than the robot slowing down.
RUNAWAY_MM = 50.0
_RUNAWAY_COUNTS = mm_to_counts(RUNAWAY_MM)
#: Packet 14's wheel bits (left 4, right 3): a wheel's motor stalled, not a byte lost.
_WHEEL_OVERCURRENT_BITS = 0b11000
#: Packet 7's bump and wheel-drop bits.
_BUMPED_OR_LIFTED = BUMP_BITS | WHEEL_DROP_BITS


def fastest_wheel_mm_s(command: Command) -> float | None:
    """How fast the faster wheel turns under ``command`` (mm/s, unsigned; Drive's arc turns
    its outer wheel faster than its velocity, so the velocity is the least of it), or None
    for a command whose speed is not a speed (Drive PWM, a built-in cycle)."""
    name = command.spec.name
    if name == "drive":
        return float(abs(command.args[0]))
    if name == "drive_direct":
        right, left = command.args
        return float(max(abs(right), abs(left)))
    return None


class MotionWatch:
    """The looks of one run at its robot's wheels (:meth:`look`), and what they found, in
    ``summary`` (:attr:`RunSummary.unheard`, :attr:`RunSummary.unheard_obeyed`,
    :attr:`RunSummary.unheard_first`)."""

    def __init__(self, connection: Connection, summary: RunSummary) -> None:
        self.connection = connection
        self.summary = summary
        self._writer = connection.writer
        #: what the last look saw: the writer's count of wheel commands written then (-1:
        #: none judged), whether the command standing turns a wheel, and the encoder counts
        self._written = -1
        self._turning = False
        self._counts: tuple[int, int] | None = None
        #: the command put right at the last finding, until the look after it judges it
        self._resent: Command | None = None
        #: a command the wheels did not obey after it was sent again: not resent again
        self._given_up_on: Command | None = None
        #: the mission times of the findings the wheels then obeyed (the last minute's)
        self._obeyed_at: list[float] = []

    def look(self, snapshot: Snapshot) -> bool:
        """Once a second of mission time: compare the wheels with the command (the module's
        docstring), put a finding right; False when findings keep coming and the run must
        end (the summary says why). Most looks find the command of the look before obeyed
        (a drive's wheels moved, a stop's stood still) and end at the first test: the look
        comes once a second, but on every run, and the excuses (the mode, a cycle, the bump
        reflex, the frame's bits) are weighed only when the wheels may have disobeyed
        (``python -m bench.icount --against``: within 0.1 % of the tick before it)."""
        frame = snapshot.frame
        slots = frame.layout.encoder_slots
        writer = self._writer
        command = writer.last_wheels
        if slots is None or command is None:
            self._counts = self._resent = None
            self._written = -1
            return True
        values = frame.values
        counts = (values[slots[0]], values[slots[1]])
        before, self._counts = self._counts, counts
        written = writer.wheel_writes
        if (
            written == self._written
            and self._resent is None
            and (counts != before) is self._turning
        ):
            return True
        return self._judge(snapshot, command, written, before, counts)

    def _judge(
        self,
        snapshot: Snapshot,
        command: Command,
        written: int,
        before: tuple[int, int] | None,
        counts: tuple[int, int],
    ) -> bool:
        """A look that is not the common one: a wheel command written since the last look
        (``written``: the writer's count; judged from the next look), the look after a
        finding, or wheels that may not have obeyed (the excuses weighed, then a finding put
        right)."""
        writer = self._writer
        judged = (
            snapshot.mode in DRIVING_MODES
            and not snapshot.cycle_may_run
            and not writer.forward_held
            and not _excused(snapshot.frame, drives_forward(command))
        )
        resent, self._resent = self._resent, None
        moved = None if before is None else _moved(before, counts)
        # the look after a finding, on the command put right: a drive shows it was obeyed by
        # any motion, even once the tree has gone on (its leaf ended: it was obeyed)
        if (
            resent is not None
            and (resent == command or turns_wheels(resent))
            and moved is not None
            and not self._after_resend(resent, moved, snapshot.time)
        ):
            return False
        if not judged or written != self._written or moved is None:
            self._written, self._given_up_on = (written if judged else -1), None
            self._turning = turns_wheels(command)
            return True
        if resent is None and command != self._given_up_on and self._disobeyed(command, moved):
            self._put_right(command, moved, snapshot.time)
        return True

    @staticmethod
    def _disobeyed(command: Command, moved: int) -> bool:
        """The wheels did not do what ``command`` asks over the last second, in which they
        turned ``moved`` encoder counts (the faster wheel)."""
        if turns_wheels(command):
            fastest = fastest_wheel_mm_s(command)
            return fastest is not None and fastest >= WHEEL_SPEED_STEP_MM_S and not moved
        return moved >= _RUNAWAY_COUNTS

    def _put_right(self, command: Command, moved: int, mission_time: float) -> None:
        """The zeros, then the wheel command (and the running Motors) again, in one write."""
        summary = self.summary
        summary.unheard += 1
        what = (
            f"the wheels stood still for a second under {_said(command)}"
            if not moved
            else f"the wheels turned for a second under {_said(command)}"
        )
        if not summary.unheard_first:
            summary.unheard_first = f"t={mission_time:.3f} {what}"
        writer = self._writer
        again = [command]
        motors = writer.last_motors
        if motors is not None and sets_going(motors):
            again.append(motors)
        # wheels that stood still under a going command are most often a wedge (a chair rung,
        # a sofa's lip: no bump shown); lost bytes come first only for wheels that turned
        cause = (
            "the robot may be wedged with no bump shown or its wheels stalled, or bytes from "
            "the computer to the robot were lost"
            if not moved
            else "bytes from the computer to the robot may have been lost"
        )
        log.warning(
            "%s: the robot did not do what it was told (%s): %s; its command parser set in "
            "step and the command sent again", self.connection.name, what, cause,
            extra={"mission_time": mission_time},
        )  # fmt: skip
        writer.send_many(again, prefix=RESYNC_ZEROS)
        self._resent = command
        # its own write again is no new command of the tree's: the next look judges this one
        self._written = writer.wheel_writes

    def _after_resend(self, command: Command, moved: int, mission_time: float) -> bool:
        """The look after a finding: the wheels obey now (the bytes were lost: counted, and
        the run ended at the third within a minute) or still do not (said once; that command
        is not sent again while it stands)."""
        if self._disobeyed(command, moved):
            self._given_up_on = command
            self.summary.unheard_stalled += 1
            log.warning(
                "%s: the wheels still do not obey %s after it was sent again: the robot may "
                "be wedged with no bump shown or its wheels stalled, or the line lost it "
                "again", self.connection.name, _said(command),
                extra={"mission_time": mission_time},
            )  # fmt: skip
            return True
        summary = self.summary
        summary.unheard_obeyed += 1
        # the session's evidence of a bad cable, which a fall of unknown cause then names
        self.connection.lost_on_the_way["a wheel command"] += 1
        recent = [t for t in self._obeyed_at if mission_time - t <= GIVE_UP_WITHIN_S]
        self._obeyed_at = [*recent, mission_time]
        if len(self._obeyed_at) < GIVE_UP_AFTER:
            return True
        # the stop that follows goes over the same line: the parser set in step first
        self._writer.send_many([oi.halt()], prefix=RESYNC_ZEROS)
        summary.outcome = Outcome.CONNECTION_LOST
        summary.reason = (
            f"{self.connection.name}: the robot did not do what it was told "
            f"{len(self._obeyed_at)} times within {GIVE_UP_WITHIN_S:g} s (each time it obeyed "
            "the command sent again): bytes from the computer to the robot are being lost; "
            f"{link_of(self.connection.name).check} (roomba-bt doctor)"
        )
        return False


def _moved(before: tuple[int, int], after: tuple[int, int]) -> int:
    """Encoder counts the faster wheel turned from ``before`` to ``after`` (either way)."""
    return max(abs(encoder_delta(before[0], after[0])), abs(encoder_delta(before[1], after[1])))


def _excused(frame: SensorFrame, forward: bool) -> bool:
    """The frame shows why wheels may stand or turn against their command: a bump while it
    drives ``forward`` (pushing what it hit; backing or turning away from it, the robot is
    free to move: a back-off that lost a byte stood 16 s against a wall, its bumper
    pressed), a wheel drop (packet 7), a wheel's overcurrent (packet 14), where streamed."""
    index = frame.layout.index
    values = frame.values
    at = index.get(7)
    if at is not None and values[at] & (_BUMPED_OR_LIFTED if forward else WHEEL_DROP_BITS):
        return True
    at = index.get(14)
    return at is not None and bool(values[at] & _WHEEL_OVERCURRENT_BITS)


def _said(command: Command) -> str:
    """``Drive (137) velocity 200, radius 32768``: the command as the summary names it."""
    spec = command.spec
    args = ", ".join(
        f"{arg.name} {value}" for arg, value in zip(spec.args, command.args, strict=False)
    )
    return f"{spec.title} ({spec.opcode}) {args}"
