"""The schedule that turns frame arrival times into stream slots (runtime/schedule.py), fed
synthetic arrival times: the robot sends a frame every 15 ms, the host reads each later."""

from __future__ import annotations

import random
from collections.abc import Iterable

import pytest

from roomba_bt.oi.stream import StreamParser
from roomba_bt.runtime.schedule import PROMPT_BATCHES, PROMPT_STEADY_BATCHES, SlotSchedule
from roomba_bt.sim import Faults

from .simrun import RunMission

T = 0.015
#: a mission that only waits, three seconds of stream
WAIT_3S = "tree:\n  sequence:\n    - mode: safe\n    - wait: {duration: 3s}\n"


def slots_of(batches: Iterable[tuple[int, float]]) -> list[int]:
    """Each batch's slots, for (frames in it, arrival) batches."""
    schedule = SlotSchedule()
    return [schedule.slots(count, arrival) for count, arrival in batches]


def jittered(sent: Iterable[int], most: float, seed: int = 1) -> list[tuple[int, float]]:
    """Frames ``sent`` (slot numbers), each read alone up to ``most`` seconds late (the first
    20 up to 3 ms: a link shows its jitter from its first frames, and until a frame came a
    ms late the schedule takes it for calm and counts a gap at once)."""
    draw = random.Random(seed)
    return [(1, k * T + draw.uniform(0.0, most if k >= 20 else 0.003)) for k in sent]


def through_a_bridge(
    sent: Iterable[int], most: float, seed: int = 1, stall: tuple[float, float] | None = None
) -> list[tuple[int, float]]:
    """Frames ``sent`` through a WiFi bridge (a TCP proxy measured on an ESP8266's link):
    each delayed up to ``most`` seconds but kept in order, as TCP keeps it (a late frame
    holds back those behind it: they come bunched); ``stall`` (at, seconds): nothing passes
    meanwhile, then the backlog comes a frame every 20 us. A host that reads every frame
    come, then ticks for half a ms, makes the batches."""
    draw = random.Random(seed)
    came: list[float] = []
    for k in sent:
        at = k * T + draw.uniform(0.0, most)
        if stall is not None and stall[0] <= at <= stall[0] + stall[1]:
            at = max(came[-1] + 0.00002, stall[0] + stall[1])
        at = max(came[-1] if came else 0.0, at)
        came.append(at)
    batches: list[tuple[int, float]] = []
    now, first = 0.0, 0
    while first < len(came):
        now = max(now, came[first])
        last = first
        while last < len(came) and came[last] <= now:
            last += 1
        batches.append((last - first, now))
        first, now = last, now + 0.0005
    return batches


def slots_through(batches: list[tuple[int, float]], restart_after: float = 0.1) -> int:
    """The slots the batches span, a gap of ``restart_after`` or more taken as the run's
    clock takes a stall ridden through (the watchdog tripped)."""
    schedule = SlotSchedule()
    before = None
    for count, arrival in batches:
        restart = before is not None and arrival - before >= restart_after
        schedule.tick += schedule.late_batch(count, arrival, schedule.tick, restart)
        before = arrival
    return schedule.tick + 1


@pytest.mark.parametrize("most", [0.02, 0.05, 0.08], ids=["20ms", "50ms", "80ms"])
def test_a_wifi_bridge_s_jitter_makes_next_to_no_slot(most: float) -> None:
    # 10 min of frames late by up to 80 ms and bunched (0-80 ms: 256 stale and 43 "lost" in
    # 10 s before session 32, mission time 6 % fast): a slot in 5000 at most
    made = slots_through(through_a_bridge(range(40_000), most)) - 40_000
    assert 0 <= made <= 8


def test_frames_lost_through_a_wifi_bridge_s_jitter_are_counted() -> None:
    lost = set(random.Random(5).sample(range(100, 39_000), 40))
    batches = through_a_bridge((k for k in range(40_000) if k not in lost), 0.05, seed=2)
    assert slots_through(batches) == 40_000


@pytest.mark.parametrize("stall", [(2.5, 6.0), (6.0, 1.5)], ids=["6s", "1.5s"])
def test_a_stall_s_backlog_read_over_many_reads_is_no_lost_frame(
    stall: tuple[float, float],
) -> None:
    # a WiFi stall ridden through: the backlog comes in a burst, read over many reads. The
    # gap was counted at once and then the backlog's frames again: a 6 s stall made 6 s of
    # mission time (the robot's 8.34 s of a `wait: 10s`, 370 frames "lost")
    batches = through_a_bridge(range(1000), 0.02, stall=stall)
    assert max(count for count, _ in batches) < 50  # many reads
    assert slots_through(batches) == 1000


def test_jitter_makes_no_slot_and_takes_none_away() -> None:
    arrivals = jittered(range(20_000), 0.010)
    assert slots_of(arrivals) == [1] * len(arrivals)


def test_a_late_frame_then_an_early_one_are_two_slots() -> None:
    # gaps of 24 ms then 6 ms: the old gap rule took 2 slots for the first, 1 for the second
    arrivals = jittered(range(20), 0.0)
    arrivals += [(1, k * T + (0.009 if k % 2 else 0.0)) for k in range(20, 1000)]
    assert slots_of(arrivals) == [1] * 1000


def test_a_frame_read_far_too_late_alone_makes_no_slot() -> None:
    # a host that stalled between the read and its clock: one frame 65 ms late, then the
    # frames that came meanwhile in one read, on time (measured on a pty at 19200 baud)
    arrivals = jittered(range(100), 0.004)
    arrivals[60] = (1, 60 * T + 0.065)
    arrivals[61:66] = [(5, 65 * T + 0.003)]
    assert sum(slots_of(arrivals)) == 100


def test_real_gaps_are_counted_through_jitter() -> None:
    lost = {17, 18, 400, 401, 402, 999, 5000}
    slots = slots_of(jittered((k for k in range(6000) if k not in lost), 0.010, seed=2))
    assert sum(slots) == 6000  # every slot the robot sent, the lost ones too
    # counted once the frames after the gap have all come later than the jitter reaches, for
    # three batches none earlier than the first (it was once they had all come late for a
    # second and more, 1.3 s; then eight batches, 0.12 s): a lost frame delays every one
    # after it, jitter only those around it
    assert [n for n in slots if n > 1] == [3, 4, 2, 2]
    counted = [i for i, n in enumerate(slots) if n > 1]
    assert [i - gap for i, gap in zip(counted, (17, 398, 994, 4993), strict=True)] == [
        pytest.approx(PROMPT_STEADY_BATCHES, abs=1)
    ] * 4


def _counted_after(batches: list[tuple[int, float]], lost_slot: int) -> float:
    """Seconds from the lost frame's slot to the batch whose slots count it."""
    schedule = SlotSchedule()
    for count, arrival in batches:
        if schedule.slots(count, arrival) > count:
            return arrival - lost_slot * T
    raise AssertionError("the lost frame was never counted")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_frame_lost_through_a_bridge_jittery_under_a_slot_is_counted_promptly(
    seed: int,
) -> None:
    # 0-10 ms of jitter through a bridge: a lost frame was counted a run's window late (1.5 s
    # and up to 2.9 s, the mission clock a slot behind meanwhile); every batch after it
    # later than the link's jitter reaches tells it in eight batches
    batches = through_a_bridge((k for k in range(2000) if k != 1000), 0.01, seed)
    assert sum(count for count, _ in batches) == 1999
    assert _counted_after(batches, 1000) < (PROMPT_BATCHES + 6) * T
    assert slots_through(batches) == 2000


def test_clock_drift_does_not_accumulate() -> None:
    # the robot's clock 0.2 % fast or slow against the host's: 60 000 frames (15 min) drift
    # 1.8 s, 120 slots, yet no slot is made or lost
    for period in (T * 0.998, T * 1.002):
        draw = random.Random(3)
        arrivals = [(1, k * period + draw.uniform(0.0, 0.006)) for k in range(60_000)]
        arrivals[:20] = jittered(range(20), 0.0)
        assert slots_of(arrivals) == [1] * 60_000


def test_batches_read_late_by_a_busy_host_make_no_lost_frame() -> None:
    # the host is busy for 3 slots, then reads the frames that waited, up to a slot after
    # the newest came: no lost frame
    batches: list[tuple[int, float]] = []
    k = 0
    draw = random.Random(4)
    for i in range(1000):
        count = 3 if i % 10 == 5 else 1
        k += count
        read_late = draw.uniform(0.0, T) if count > 1 else draw.uniform(0.002, 0.006)
        batches.append((count, (k - 1) * T + read_late))
    assert sum(slots_of(batches)) == k


def test_exact_arrivals_count_lost_frames_at_once() -> None:
    # the virtual clock: frames exactly 15 ms apart. Past its first half second (a link is
    # taken for jittery until its frames show it calm), a gap is counted as soon as it is
    # seen, as the old gap rule did: the golden recordings' runs make the same decisions
    sent = [*range(40), 40, 41, 43, 44, 48, 49]
    slots = slots_of([(1, k * T) for k in sent] + [(3, 52 * T), (1, 54 * T)])
    assert slots[40:] == [1, 1, 2, 1, 4, 1, 3, 2]
    assert sum(slots) == 55


def test_a_gap_in_the_first_half_second_is_counted_once_the_link_shows_calm() -> None:
    # a link is taken for jittery until its frames show it calm: a gap waits as a run of
    # late frames, and is counted once their spread (none: exact arrivals) has decayed under
    # a ms, half a second in; the old gap rule, and the golden recordings, count it from there
    slots = slots_of([(1, k * T) for k in (0, 1, 2, *range(4, 100))])
    assert slots == [1] * 36 + [2] + [1] * 62


def test_a_long_gap_with_no_backlog_is_counted_once_the_stream_is_live_again() -> None:
    # the robot's side fell silent 2 s (its frames never sent): the first frame after the
    # gap may head a backlog, the next one half a slot later says it did not; the gap is
    # counted then, and the schedule starts again from that frame
    calm = SlotSchedule()
    for k in range(40):
        calm.slots(1, k * T)
    assert calm.late_batch(1, 39 * T + 2.004, 39, True) == 1  # the backlog's first, or not
    assert calm.late_batch(1, 40 * T + 2.004, 40, False) == 1 + 133  # round(2.004 / 15 ms)
    assert calm.due == 40 * T + 2.004
    # on a link 10 ms jittery: once the run has lasted its window (1.5 s at that spread)
    jittery = SlotSchedule()
    for count, arrival in jittered(range(200), 0.010):
        jittery.slots(count, arrival)
    assert jittery.run_window() == pytest.approx(1.54, abs=0.01)
    slots = []
    for i, (count, arrival) in enumerate(jittered(range(333, 533), 0.010, seed=3)):
        slots.append(jittery.late_batch(count, arrival, jittery.tick, i == 0))
        jittery.tick += slots[-1]
    assert sum(slots) == 333 and [n for n in slots if n > 1] == [134]
    assert slots.index(134) * T == pytest.approx(1.5, abs=0.1)


def test_the_backlog_after_a_stall_ridden_through_is_no_lost_frame() -> None:
    # a relay or host stalled 110 ms (the watchdog tripped, the run rode it through): the 8
    # frames that waited come in one read, up to a slot after the newest (measured through
    # a relay: 6 "lost" in 20 s, counted at a calm link's tolerance)
    schedule = SlotSchedule()
    for count, arrival in jittered(range(100), 0.004):
        schedule.slots(count, arrival)
    assert schedule.late_batch(8, 107 * T + 0.012, 99, True) == 8


def test_a_stalled_senders_backlog_read_a_frame_at_a_time_makes_no_slot() -> None:
    # the robot's side stalls 60 ms, then sends the 4 frames it owed back to back, read one
    # at a time 0.3 ms apart: each is late, the next a slot less, none lost (measured with
    # the simulator on a loaded host: 43 "lost" in 20 s before this)
    arrivals = jittered(range(100), 0.004)
    for i, k in enumerate(range(60, 64)):
        arrivals[k] = (1, 63 * T + 0.002 + i * 0.0003)
    assert sum(slots_of(arrivals)) == 100


@pytest.mark.parametrize("jitter", [0.0, 0.010], ids=["exact", "jittery"])
def test_the_runner_s_inline_on_time_frame_keeps_the_schedule_s_rule(
    run_mission: RunMission, jitter: float
) -> None:
    """``MissionRunner._advance`` takes the common frame inline; its slots, over a whole run
    with frames lost and read late, are those :meth:`SlotSchedule.slots` gives for the same
    reads (each read's frames, at its arrival)."""
    run = run_mission(WAIT_3S, faults=Faults(drop_rate=0.2), watchdog=1.0, jitter=jitter)
    parser = StreamParser(run.runner.packets)
    schedule = SlotSchedule()
    for (_, data), arrival in zip(run.link.reads, run.link.arrivals, strict=True):
        count = len(parser.feed(data))
        if count:
            schedule.slots(count, arrival)
    assert run.summary.frames_lost > 0
    assert schedule.tick * T == pytest.approx(run.summary.mission_time_s, abs=1e-9)


def test_frames_lost_in_the_window_after_a_stall_ridden_through_are_counted() -> None:
    # a noisy cable (2 % of the bytes lost: 45 % of the frames broken): ten frames in a row
    # broken trip the watchdog, the run rides it through, and a third of the frames after it
    # are broken too. The schedule started again at the batch that counted the stall's run,
    # and the frames lost in its window (over a second) were forgotten: 8 s of mission time
    # in 12.5 s on a pty
    lost = set(range(100, 110)) | {k for k in range(110, 250) if k % 3 == 0}
    batches = jittered((k for k in range(600) if k not in lost), 0.004)
    assert slots_through(batches) == 600


def test_a_stall_s_lateness_is_no_jitter_for_the_prompt_count() -> None:
    # after a stall ridden through, a lost frame is still counted as promptly as before it:
    # the stall's run took its lateness (150 ms) for how far the link's jitter reaches, and
    # every lost frame after it waited a whole window (1.2 s) to be counted
    sent = [k for k in range(2000) if not 100 <= k < 110 and k != 1000]
    batches = jittered(sent, 0.004)
    schedule = SlotSchedule()
    before, counted = 0.0, []
    for count, arrival in batches:
        slots = schedule.late_batch(count, arrival, schedule.tick, arrival - before >= 0.1)
        schedule.tick += slots
        before = arrival
        if slots > count:
            counted.append(arrival)
    assert schedule.tick + 1 == 2000
    assert counted[-1] - 1000 * T < (PROMPT_BATCHES + 6) * T


def test_a_short_stall_with_no_backlog_is_counted_as_promptly_as_a_lost_frame() -> None:
    # ten frames broken in a row (150 ms: the watchdog tripped, the run rode it through) and
    # none after: the frames back come spaced as the stream is, none earlier than the first,
    # so no backlog; the stall was counted a window later (1.2 s, 76 batches), the mission
    # clock 150 ms behind the robot's meanwhile; then eight batches later, now three
    sent = [k for k in range(1000) if not 200 <= k < 210]
    schedule = SlotSchedule()
    before, counted = 0.0, []
    for i, (count, arrival) in enumerate(jittered(sent, 0.004)):
        slots = schedule.late_batch(count, arrival, schedule.tick, arrival - before >= 0.1)
        schedule.tick += slots
        before = arrival
        if slots > count:
            counted.append((i, slots - count))
    assert counted == [(200 + PROMPT_STEADY_BATCHES - 1, 10)]


def test_a_third_of_the_frames_lost_for_a_minute_keeps_the_clock_within_a_few_frames() -> None:
    # every third frame lost, 2 ms of jitter: a count that left its batch on time went on as
    # a run of its own from a least under a slot, which no prompt count could pass, and the
    # next lost frames waited its window (the clock up to 0.42 s behind the robot's)
    sent = [k for k in range(4000) if k < 100 or k % 3]
    schedule = SlotSchedule()
    behind = []
    for count, arrival in jittered(sent, 0.002):
        schedule.slots(count, arrival)  # (it keeps the tick)
        behind.append(arrival - schedule.tick * T)
    assert max(behind) < 0.12
    assert 4000 - (schedule.tick + 1) <= PROMPT_BATCHES
