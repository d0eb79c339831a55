"""Hazard confirmation: a bump, wheel drop or cliff ends an action only once it is confirmed.

The OI checksum is an 8-bit sum: two bit flips at the same position in opposite directions
cancel (1 pair in 16), so on a noisy line a few corrupted frames pass it with every value in
range, and one of them may show a cliff that is not there. A real hazard lasts: the bumper
stays pressed, the drop stays under the sensor for many 15 ms frames. So a hazard bit that
was clear in the frame before is held back for one frame, and shown in the next frame if it
is still set there::

    frame   n-1   n     n+1
    cliff   0     1     1        the tick of frame n sees no cliff, the tick of n+1 sees it
    cliff   0     1     0        never seen (one corrupted frame)

A hazard the robot itself reacted to in the same frame (it fell from Safe to Passive: the
mode model followed packet 35 at once because the frame shows the cause) is confirmed by
that agreement and shown at once. Either way a real hazard's reaction is late by at most one
frame (15 ms); clearing is never delayed.

A held bump must not cost the robot a step into the wall: while a bump onset waits for its
second frame, the robot layer holds forward motion at 0 (the *bump reflex*: the runtime calls
:meth:`~roomba_bt.robot.connection.Connection.hold_forward` in the onset's tick, which writes
drive 0 at once if the wheels drive forward and keeps the tree's forward wheel commands
unwritten). The action is not ended and the tree does not see the bump yet. The next frame
confirms it (the tree reacts as it would have, one frame later, from where the robot stood
still) or clears it (a corrupted frame: the forward command held is written again, as after
a ridden-through stall; the phantom cost a 15 ms pause, not a stop)::

    frame          n-1        n              n+1
    bumper         0          1              1 (confirmed)      0 (cleared)
    written        drive 200  drive 0        the tree's back-off  drive 200 again
    tree sees      no bump    no bump        bump                no bump

Without the reflex the wheels drove one more 15 ms step into the wall before the tree's
back-off (the bumper stayed pressed up to 3 frames after the bump frame, not 1). Cliffs and
wheel drops are confirmed the same way, without a reflex: a real one in Safe or Full makes the
robot fall to Passive (or the tree stop) and is shown at once by that agreement.

The hazard bits: packet 7's bump and wheel drop bits (0-3; the reserved bits 4-7 never pass
the range checks) and the four cliff packets 9-12, folded into one integer per frame so the
common case (no hazard, or the same hazards as before) is one comparison.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import itemgetter

from roomba_bt.oi.bits import BUMP_BITS, MOTOR_RUN_BITS, WHEEL_DROP_BITS
from roomba_bt.oi.encode import Command, turns_wheels
from roomba_bt.oi.frames import BUMPS_PACKETS, CLIFF_PACKETS, FrameLayout, SensorFrame
from roomba_bt.oi.opcodes import Effect

_BUMP_PACKET = BUMPS_PACKETS[0]
_PACKET_7_HAZARDS = BUMP_BITS | WHEEL_DROP_BITS  # 0b1111
#: bit of each cliff packet in the folded hazard word (above packet 7's four bits)
_CLIFF_BITS = {pid: 1 << (4 + i) for i, pid in enumerate(CLIFF_PACKETS)}
#: Drive's radius for a turn in place (the spec's -1 and 1): the velocity is a wheel's speed
_SPIN_RADII = (-1, 1)


def _no_hazard_packets(values: tuple[int, ...]) -> object:
    """What :attr:`HazardConfirmation._raw` reads of a layout without hazard packets."""
    return ()


def drives_forward(command: Command) -> bool:
    """Whether a wheel command moves the robot's centre forward (what the bump reflex holds):
    Drive (137) at a positive velocity on a straight line or an arc (a turn in place moves
    no centre), Drive Direct (145) or Drive PWM (146) with the wheels' sum positive. A
    cleaning cycle drives itself and reacts to its own bumps: never held."""
    name = command.spec.name
    if name == "drive":
        velocity, radius = command.args
        return velocity > 0 and radius not in _SPIN_RADII
    if name in ("drive_direct", "drive_pwm"):
        right, left = command.args
        return right + left > 0
    return False


def sets_going(command: Command) -> bool:
    """Whether a command sets the robot or a motor of it going: a wheel command that turns a
    wheel (:func:`~roomba_bt.oi.encode.turns_wheels`), a built-in cycle (Clean, Spot, Max,
    Seek Dock: it drives by itself, in Passive too), a Motors (138) or PWM Motors (144) that
    runs a brush or the vacuum. What a tree's stop may not write (:meth:`CommandWriter.hold_motion
    <roomba_bt.robot.writer.CommandWriter.hold_motion>`)."""
    spec = command.spec
    if spec.channel == "motors":  # Motors (138): a run bit, not a direction bit alone
        return (
            bool(command.args[0] & MOTOR_RUN_BITS) if spec.name == "motors" else any(command.args)
        )
    return turns_wheels(command) or spec.effect is Effect.BUILTIN_CYCLE


class HazardConfirmation:
    """Holds back, for one frame, hazard bits the frame before did not show.

    :meth:`frame` is called with every frame of the stream, in order (not only the ones a
    tick reads): "the frame before" is the stream's, so a tick that reads the newest of a
    batch still confirms against the one just before it. ``held`` counts frames whose
    hazards were held back; ``unconfirmed`` counts onsets that were gone in the next frame
    (what a corrupted frame would have stopped the robot for).
    """

    __slots__ = (
        "_layout", "_previous", "_previous_raw", "_raw", "_slots", "held", "pending", "unconfirmed",
    )  # fmt: skip

    def __init__(self) -> None:
        self._layout: FrameLayout | None = None
        self._slots: tuple[int | None, tuple[tuple[int, int], ...]] = (None, ())
        #: the hazard packets' raw values of a frame, read in C (``operator.itemgetter``)
        self._raw: Callable[[tuple[int, ...]], object] = _no_hazard_packets
        self._previous = 0  # the folded hazard word of the frame before
        #: the frame before's hazard packets as :attr:`_raw` read them (None: no frame yet)
        self._previous_raw: object = None
        self.pending = 0  # the bits held back from the frame before
        self.held = 0
        self.unconfirmed = 0

    @property
    def bump_pending(self) -> bool:
        """A bump onset is held back from the last frame (the next one confirms or clears
        it): what the bump reflex holds forward motion for."""
        return bool(self.pending & BUMP_BITS)

    def _bind(self, layout: FrameLayout) -> None:
        index = layout.index
        cliffs = tuple((index[pid], bit) for pid, bit in _CLIFF_BITS.items() if pid in index)
        bump = index.get(_BUMP_PACKET)
        self._slots = (bump, cliffs)
        slots = ([] if bump is None else [bump]) + [slot for slot, _ in cliffs]
        self._raw = itemgetter(*slots) if slots else _no_hazard_packets
        self._previous_raw = None  # another layout's values do not compare
        self._layout = layout

    def word(self, frame: SensorFrame) -> int:
        """The frame's hazard bits folded into one integer (0: no hazard)."""
        if frame.layout is not self._layout:
            self._bind(frame.layout)
        values = frame.values
        bump_slot, cliffs = self._slots
        word = values[bump_slot] & _PACKET_7_HAZARDS if bump_slot is not None else 0
        for slot, bit in cliffs:
            if values[slot]:
                word |= bit
        return word

    def frame(self, frame: SensorFrame, robot_reacted: bool = False) -> SensorFrame:
        """``frame`` with the hazard bits that are new since the frame before cleared, unless
        ``robot_reacted`` (the robot's own fall to Passive in this frame agrees with them).

        Most frames carry the same hazard packets as the frame before (none, or the same
        bumper held): then nothing is new, an onset held back from the frame before is
        confirmed, and the word is not folded again."""
        if frame.layout is not self._layout:
            self._bind(frame.layout)
        read_raw = self._raw  # read, then called: see StreamParser.take
        raw = read_raw(frame.values)
        if raw == self._previous_raw:
            self.pending = 0
            return frame
        self._previous_raw = raw
        word = self.word(frame)
        previous, self._previous = self._previous, word
        if self.pending and not self.pending & word:
            self.unconfirmed += 1
        new = word & ~previous
        if not new or robot_reacted:
            self.pending = 0
            return frame
        self.pending = new
        self.held += 1
        return self._without(frame, new)

    def _without(self, frame: SensorFrame, bits: int) -> SensorFrame:
        values = list(frame.values)
        bump_slot, cliffs = self._slots
        if bump_slot is not None and bits & _PACKET_7_HAZARDS:
            values[bump_slot] &= ~(bits & _PACKET_7_HAZARDS)
        for slot, bit in cliffs:
            if bits & bit:
                values[slot] = 0
        return SensorFrame(frame.layout, tuple(values))
