"""The stream's schedule: which 15 ms slots a batch of frames read at some time spans.

The robot sends a frame every 15 ms on its own clock; the host reads each some time later,
never earlier, and by a delay that varies (a busy host, a USB adapter, a relay: a few ms, now
and then tens). Frames carry no number, so a frame the robot sent and the host never got
(corrupted, dropped) shows only as a slot on the schedule that passed without a frame. The
rule (docs/runtime.md, "The stream is the clock"):

* The schedule is the earliest arrival seen, moved on one slot a frame: :attr:`due` is when
  the frame of the last tick's slot was due. A frame earlier than it moves it back at once (a
  shorter delay; a robot clock faster than the host's); a later one moves it on by at most
  :data:`DRIFT` (a robot clock slower than the host's, a link that got slower, are followed
  slowly; jitter hardly moves it). Cumulative: drift and jitter never add up to a slot.
* A batch of ``count`` frames is on time unless its newest frame is half a slot late or
  more (:data:`LOST_LATE`; a slot and a half for a batch of several, which a busy host may
  have read up to a slot after its newest frame came): then ``int((late - tolerance) / 15 ms)
  + 1`` slots passed with no frame.
* On a calm link (:attr:`spread`, the latest frames' lateness as a decaying maximum, under
  :data:`CALM`: the simulator's virtual clock, a replay of it) such a gap is counted at once,
  as the arrival times say. On a jittery one a single late batch is jitter until the next one
  is late too (a lost frame delays every frame after it; a late one does not: the next comes
  on time), and then the slots both agree on are counted, one batch late.
* After a gap of a second or more, or a stall ridden through, the stream may have started
  again at another phase: the gap is counted at once by its length, less the link's
  tolerance (a stalled host or relay delivers the backlog in one read, late), and the
  schedule starts again.

The common frame (alone in its batch, less than half a slot late) takes :meth:`late_batch`
with nothing lost: the schedule follows it (up to :data:`DRIFT`) and its lateness is kept in
:attr:`spread`. ``MissionRunner._advance`` does exactly that inline, a call less a tick; a
change to that case changes both (``tests/runtime/test_schedule.py`` holds them alike).
"""

from __future__ import annotations

from roomba_bt.oi.frames import SLOT_SECONDS

#: A frame this late on the schedule (half a slot), or later, may have a lost one before it
LOST_LATE = 0.5 * SLOT_SECONDS
#: On a jittery link, a frame this late (0.9 slot), or later, may have a lost one before it
JITTER_LATE = 0.9 * SLOT_SECONDS
#: On a jittery link, lost frames are counted once this many batches came late in a row (two
#: late frames in a row, then on time again, were measured on a loaded host: jitter)
LATE_RUN = 3
#: How far the schedule follows a late frame, per frame (0.5 % of a slot, 75 us)
DRIFT = 0.005 * SLOT_SECONDS
#: How fast :attr:`SlotSchedule.spread` forgets a late frame, per frame (12 s from 12 ms)
SPREAD_DECAY = 0.001 * SLOT_SECONDS
#: A link whose frames came within this of the schedule lately is calm: a gap counts at once
CALM = 0.001
#: A link is taken for jittery until its frames show it calm (its first half second: the
#: first frames of a stream are often the least regular)
START_SPREAD = 1.5 * CALM
#: the schedule before the first frame: any arrival is "late", and takes the slow path
NO_FRAME_YET = float("-inf")


class SlotSchedule:
    """When the robot's frames are due on the link's clock, and what a batch spans."""

    __slots__ = (
        "_suspect_at", "_suspect_late", "_suspect_run", "_suspect_tick", "due", "spread", "tick",
    )  # fmt: skip

    def __init__(self) -> None:
        #: when the frame of the last tick's slot was due
        self.due = NO_FRAME_YET
        #: how late frames came lately: the largest lateness, decaying by SPREAD_DECAY a frame
        self.spread = START_SPREAD
        #: the slot index after the last batch (:meth:`slots` keeps it; the runner its own)
        self.tick = -1
        self._suspect_tick = -2  # the tick of the late batch not counted yet
        self._suspect_late = 0.0  # and how late it was (the least, in a run of them)
        self._suspect_at = 0.0  # and when it came
        self._suspect_run = 0  # late batches in a row

    def slots(self, count: int, arrival: float) -> int:
        """The slots a batch of ``count`` frames read at ``arrival`` spans: the schedule's
        whole rule, :meth:`late_batch` (whose on-time frame the runner inlines)."""
        slots = self.late_batch(count, arrival, self.tick, False)
        self.tick += slots
        return slots

    def late_batch(self, count: int, arrival: float, tick: int, restart: bool) -> int:
        """The slow path: the first frame, a batch of several, a late frame (``tick``: the
        slot index before this batch; ``restart``: after a long gap or a stall)."""
        if self.due == NO_FRAME_YET:
            self.due = arrival
            return 1
        on_time = self.due + count * SLOT_SECONDS
        late = arrival - on_time
        calm = self.spread < CALM
        # calm: what the arrival says (the old gap rule's count, to the frame, on the virtual
        # clock); jittery: 0.9 slot, a slot more for a batch a busy host may have read late
        # (after a stall ridden through, the backlog came in one read: a stalled relay or
        # host, not a lost frame, counted 6 in 20 s at the calm tolerance)
        tolerance = LOST_LATE if calm else JITTER_LATE + (count > 1) * SLOT_SECONDS
        lost = 0
        if late >= tolerance:
            agreed = late if calm or restart else self._agreed(count, arrival, tick, late)
            if agreed is None:  # jitter, until a later batch says otherwise: the schedule
                self.due = on_time  # waits for it
                return count
            if agreed >= tolerance:
                lost = int((agreed - tolerance) / SLOT_SECONDS) + 1
        on_time += lost * SLOT_SECONDS
        late -= lost * SLOT_SECONDS
        if restart:
            self.due = arrival
        else:
            self.due = arrival if late < DRIFT else on_time + DRIFT
            if count == 1:
                spread = self.spread
                self.spread = late if late > spread else spread - SPREAD_DECAY
        return count + lost

    def _agreed(self, count: int, arrival: float, tick: int, late: float) -> float | None:
        """On a jittery link, a late batch: how late the batches since the first late one
        agree the stream is (the least of them), once :data:`LATE_RUN` came late in a row,
        the last spaced as the stream is (half a slot or more after the one before: not the
        backlog of a stalled sender or host, read a frame at a time); None while that is
        still to come."""
        if self._suspect_tick == tick:  # the batch before was late too
            late = min(late, self._suspect_late)
            run = self._suspect_run + 1
            if run >= LATE_RUN and arrival - self._suspect_at >= LOST_LATE:
                self._suspect_tick = -2
                return late
        else:
            run = 1
        self._suspect_tick, self._suspect_late, self._suspect_at = tick + count, late, arrival
        self._suspect_run = run
        return None
