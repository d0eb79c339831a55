"""The stream's schedule: which 15 ms slots a batch of frames read at some time spans.

The robot sends a frame every 15 ms on its own clock; the host reads each some time later,
never earlier, and by a delay that varies (a busy host, a USB adapter, a relay: a few ms, now
and then tens; a WiFi bridge: 5-80 ms, and stalls of seconds whose backlog comes in a burst).
Frames carry no number, so a frame the robot sent and the host never got (corrupted, dropped)
shows only as a slot on the schedule that passed without a frame, and stays so: every frame
after it comes a slot later than it would have. A late frame delays only itself and those
bunched behind it. The rule (docs/runtime.md, "The stream is the clock"):

* The schedule is the earliest arrival seen, moved on one slot a frame: :attr:`due` is when
  the frame of the last tick's slot was due. A frame earlier than it moves it back at once (a
  shorter delay; a robot clock faster than the host's); a later one moves it on by at most
  :data:`DRIFT` (a robot clock slower than the host's, a link that got slower, are followed
  slowly; jitter hardly moves it). Cumulative: drift and jitter never add up to a slot.
* Each frame is one slot. On a calm link (:attr:`spread`, the latest frames' lateness as a
  decaying maximum, under :data:`CALM`: the simulator's virtual clock, from its first
  frame, and a replay of it; any link once its frames show it) a
  batch half a slot late or more (:data:`LOST_LATE`) has ``int((late - 7.5 ms) / 15 ms) + 1``
  lost slots before it, counted at once, as the arrival times say.
* On a jittery link a batch 0.9 slot late (:data:`JITTER_LATE`) opens a run of late batches,
  which goes on while they come half a slot late or more. Nothing is counted while it lasts:
  the schedule waits, one slot a frame. A batch on time ends it: nothing was lost. A run that
  lasts :data:`LOST_WINDOW` (longer on a link whose frames spread wider, :func:`run_window`),
  or whose batches all came later than the link's jitter reaches (:meth:`_beyond_jitter`),
  is counted by its least lateness, what every batch of it lacked: frames lost for good.
  What is still late then goes on as a run of its own (frames lost since); a batch on time
  ends it.
* After a gap of a second or more, or a stall ridden through, the frames that waited may come
  as a backlog, over several reads (a TCP bridge, a pty relay, a host that was stopped): each
  is a slot, none lost. The gap opens a run as a late batch does, and what the backlog leaves
  short once it is read (the next batch half a slot after the one before; on a jittery link,
  the run's window, or after a stall under a second, three batches none of which came
  earlier than the first back) is counted; the schedule then moves on to the run's least
  late batch (the stream may have come back at another phase), and what the later batches
  lack past it goes on as a run: frames lost since the gap, as on a noisy cable, where 45 %
  of the frames broken trip the watchdog again and again. Counted at once, the gap was
  counted a second time by the backlog's frames: a 6 s stall over WiFi made 6 s of mission
  time that never passed.

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
#: On a jittery link, a run of late batches is counted once it has lasted this long (a second,
#: and longer on a link whose frames spread wider: :func:`run_window`): a lost frame delays
#: every frame after it for good, a late one only those bunched behind it, and over a second
#: or more some frame comes on time. A shorter rule, three late batches in a row, counts
#: 11-43 frames "lost" in 10 s through a WiFi bridge that loses none
LOST_WINDOW = 1.0
#: ... longer by this many seconds per second of the link's :attr:`SlotSchedule.spread`
#: (0-80 ms of jitter: 5.8 s; the least lateness of a second of it reached 24 ms in 1 %)
WINDOW_PER_SPREAD = 60.0
#: ... up to this spread (a power-save hold of 200 ms is a moment's, not the link's jitter)
WIDEST_SPREAD = 0.1
#: A run this late at least, or later, has lost frames: two thirds of a slot, not half, as
#: the least of a jittery run sits a few ms above the schedule (0-80 ms of jitter: 2 frames
#: made in 10 min, against 13 at half a slot, every one lost frame of 40 counted)
COUNT_LATE = 2 / 3 * SLOT_SECONDS
#: A run of this many batches, each spaced as the stream is and all later than the link's
#: jitter reaches (:attr:`SlotSchedule.spread`, and :data:`PROMPT_MARGIN`), is counted at
#: once, not after its window
PROMPT_BATCHES = 8
PROMPT_MARGIN = 0.2 * SLOT_SECONDS
#: ... or this many, the first and two more, when none came earlier than the first by more
#: than the link's jitter and the margin (a backlog read faster than the stream falls by half
#: a slot or more a batch: past that within two). Eight waited half a second at 5 % of the
#: robot's bytes lost (77 % of the frames broken: a batch every 4 slots), the run that went
#: on after each count waited for the next stall, and a `wait: 10s` ended up to 1.1 s late
PROMPT_STEADY_BATCHES = 3
#: ... on a link whose jitter reaches less than this (0.8 slot): its least lateness over
#: those batches is then a whole number of slots lost and less jitter than the count's
#: COUNT_LATE
PROMPT_REACH = 0.8 * SLOT_SECONDS
#: How fast the runs' reach is forgotten: a ms a second
REACH_DECAY = 0.001
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
        "_known", "_reach", "_run_batches", "_run_began", "_run_first", "_run_last", "_run_late",
        "_run_least", "_run_most", "_run_restart", "_run_tick",
        "due", "restart_lost", "spread", "tick",
    )  # fmt: skip

    def __init__(self, stepped: bool = False) -> None:
        #: when the frame of the last tick's slot was due
        self.due = NO_FRAME_YET
        #: how late frames came lately: the largest lateness, decaying by SPREAD_DECAY a frame.
        #: A link whose reads come on the simulator's steps (``stepped``: ``read_step``, the
        #: virtual clock) is calm from its first frame: taken for jittery at the start, a
        #: cable losing 5 % of the robot's bytes opened a run that waited its window, and a
        #: ``wait: 1s`` first in a mission took 1.7-2.5 s of the robot's time
        self.spread = 0.0 if stepped else START_SPREAD
        #: the slot index after the last batch (:meth:`slots` keeps it; the runner its own)
        self.tick = -1
        self._run_tick = -2  # the tick after the run's last late batch (none: -2)
        self._run_least = 0.0  # the least lateness of the run's batches
        self._run_late = 0.0  # how late its last batch came
        self._run_last = 0.0  # when its last batch came
        self._run_began = 0.0  # and its first
        self._run_restart = False  # it began after a long gap or a stall ridden through
        self._run_batches = 0  # its batches spaced as the stream is
        self._run_most = 0.0  # the greatest lateness of its batches
        self._run_first = 0.0  # how late its first batch came
        #: how late jitter made the runs before this one (the most of each, less what it
        #: lost), forgetting by REACH_DECAY a second
        self._reach = 0.0
        #: the link's jitter has shown past :data:`START_SPREAD` (its spread at the start):
        #: it is known, and stays so when the spread decays under that again (a run of late
        #: batches decays it a frame's share a batch: at 45 % of the frames lost, the
        #: prompt count of lost frames stopped once it had)
        self._known = False
        #: the frames lost counted by runs that began at a gap or a stall ridden through,
        #: all told (the run's clock tells the gaps nobody read from the stalls)
        self.restart_lost = 0

    def run_window(self) -> float:
        """How long a run of late batches lasts before it is counted as frames lost: a
        second, and longer the wider the link's frames spread (a calm link's gap: at once,
        once the backlog is read)."""
        return LOST_WINDOW + WINDOW_PER_SPREAD * min(self.spread, WIDEST_SPREAD)

    def gap(self, arrival: float, tick: int) -> float:
        """How long no frame came before a batch at ``arrival`` (``tick``: the slot index
        before it): since the last frame's slot was due, to a ms; in a run of late batches
        (the schedule waits), since the last of them came (a stall's backlog read over
        several reads is one gap, not one a read)."""
        return arrival - (self._run_last if self._run_tick == tick else self.due)

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
        # clock); jittery: 0.9 slot opens a run of late batches (a gap too, on either link),
        # half a slot goes on with it, and it is counted by what its batches all lack
        running = self._run_tick == tick
        lost = 0
        if late >= (LOST_LATE if calm or running else self._opens_at()):
            if calm and not restart and not running:
                lost = int((late - LOST_LATE) / SLOT_SECONDS) + 1
            else:
                least = self._run_on(count, arrival, tick, late, restart, calm)
                if least is None:  # jitter or a backlog, until the run says otherwise: the
                    self.due = on_time  # schedule waits for it
                    return count
                reach = LOST_LATE if calm else COUNT_LATE
                lost = int((least - reach) / SLOT_SECONDS) + 1 if least >= reach else 0
                # The schedule moves on by what is lost. After a gap the stream may have
                # come back at another phase: by the run's least lateness, to its least late
                # batch (the stream live again; not to this batch, whose lateness past that
                # is frames lost in the window: started again here, the schedule forgot
                # them, and 2 % of the bytes lost made 8 s of mission time in 12.5 s); the
                # gap's lateness is no jitter for the link's reach either
                if self._run_restart:
                    shift, self._run_most = least, late - least
                    self.restart_lost += lost
                else:
                    shift = lost * SLOT_SECONDS
                    self._run_most -= shift
                # What is still late goes on as a run of its own (frames lost since); a
                # batch on time once they are counted ends it (a run went on from a least
                # of none, which no prompt count passed: the next lost frame waited a window)
                rest = late - shift
                self._run_tick = tick + count + lost if rest >= LOST_LATE else -2
                # (its last batch this one: the one before the stall kept, the gap to each
                # batch after grew past a second, said as one nobody read, 5 % of the bytes)
                self._run_began, self._run_last, self._run_least = arrival, arrival, rest
                self._run_first = rest  # (the first of the run that goes on: this batch)
                self._run_late, self._run_restart, self._run_batches = rest, False, 1
                # a batch earlier than the schedule moved on moves it back, as on time (left
                # a ms or two late, it read the next lost frame 12.8 ms late, under a run's
                # 0.9 slot: jitter, whose spread then stopped every prompt count for 10 s)
                self.due = arrival if rest < DRIFT else on_time + shift
                return count + lost
        on_time += lost * SLOT_SECONDS
        late -= lost * SLOT_SECONDS
        self.due = arrival if late < DRIFT else on_time + DRIFT
        if count == 1:
            spread = self.spread
            self.spread = late if late > spread else spread - SPREAD_DECAY
        return count + lost

    def _opens_at(self) -> float:
        """How late a batch opens a run of late batches on a jittery link: 0.9 slot
        (:data:`JITTER_LATE`), or less once the link's jitter is known, past what it reaches
        by :data:`PROMPT_MARGIN` (a lost frame read 13.4 ms late, under 0.9 slot, was taken
        for jitter, and the spread it made stopped every prompt count for 10 s)."""
        if not self._known:
            return JITTER_LATE
        return min(JITTER_LATE, max(LOST_LATE, self.spread, self._reach) + PROMPT_MARGIN)

    def _beyond_jitter(self) -> bool:
        """Whether the run's batches have all come later than the link's jitter reaches
        (:attr:`spread`, and the runs before: :attr:`_reach`) by :data:`PROMPT_MARGIN`, for
        :data:`PROMPT_BATCHES` batches, or :data:`PROMPT_STEADY_BATCHES` when none came earlier
        than the first by more than that jitter: frames lost, told without waiting for the window
        (jitter holds back a few frames, never every one beyond its reach). Only on a link
        whose jitter is known (it showed more than :data:`START_SPREAD`, its spread at the
        start, once: past its first half second) and under :data:`PROMPT_REACH`:
        on a jitterier one, a run's least lateness over a few batches holds jitter of a slot
        or more, which could be read as a frame lost. After a gap (a stall ridden through),
        the frames back may be a backlog: counted so only after a stall under a second
        whose batches none came earlier than the first back by more than that jitter (a
        backlog read comes faster than the stream, and its lateness falls); after a longer
        gap, the window."""
        jitter = max(self.spread, self._reach)
        known = self._known = self._known or jitter > START_SPREAD
        first = self._run_first
        steady = self._run_least >= first - jitter - PROMPT_MARGIN  # no batch came earlier
        if self._run_restart:  # a stall under a second, and no backlog: no batch came
            beyond = first < LOST_WINDOW and steady
        else:
            beyond = self._run_least >= jitter + PROMPT_MARGIN
        needed = PROMPT_STEADY_BATCHES if steady else PROMPT_BATCHES
        return self._run_batches >= needed and known and jitter < PROMPT_REACH and beyond

    def _run_on(
        self, count: int, arrival: float, tick: int, late: float, restart: bool, calm: bool
    ) -> float | None:
        """A late batch in a run of them: how late the run's batches agree the stream is (the
        least of them), once the run has lasted :meth:`run_window` (after a gap on a calm
        link: at its next batch) and this batch came spaced as the stream is (half a slot or
        more after the one before: not the rest of a backlog, read a read at a time); None
        while that is still to come. A batch less late than the one before widens the
        link's :attr:`spread` to the fall (a lost frame makes none), as a late frame on time
        does; else the spread decays, as on time."""
        if self._run_tick != tick:  # the first of the run
            forgot = (arrival - self._run_last) * REACH_DECAY
            self._reach = max(self._run_most, self._reach - forgot)
            self._run_began, self._run_restart, self._run_least = arrival, restart, late
            self._run_first = late
            self._run_batches, self._run_most = 1, late
        else:
            fall = self._run_late - late  # (a backlog's is no jitter)
            spread = self.spread
            self.spread = fall if fall > spread and not self._run_restart else spread - SPREAD_DECAY
            self._run_least = min(late, self._run_least)
            self._run_most = max(late, self._run_most)
            self._run_restart = self._run_restart or restart
            window = 0.0 if calm else self.run_window()
            if arrival - self._run_last >= LOST_LATE:
                self._run_batches += 1
                if arrival - self._run_began >= window or self._beyond_jitter():
                    return self._run_least
        self._run_tick, self._run_late, self._run_last = tick + count, late, arrival
        return None
