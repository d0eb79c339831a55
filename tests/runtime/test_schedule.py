"""The schedule that turns frame arrival times into stream slots (runtime/schedule.py), fed
synthetic arrival times: the robot sends a frame every 15 ms, the host reads each later."""

from __future__ import annotations

import random
from collections.abc import Iterable

import pytest

from roomba_bt.oi.stream import StreamParser
from roomba_bt.runtime.schedule import SlotSchedule
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
    # counted when the two frames after the gap come late too: a lost frame delays every
    # one after it, jitter one or two
    assert [n for n in slots if n > 1] == [3, 4, 2, 2]


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


def test_a_gap_in_the_first_half_second_is_counted_two_frames_late() -> None:
    # a link is taken for jittery until its frames show it calm: a gap is counted once three
    # frames in a row came late
    slots = slots_of([(1, k * T) for k in (0, 1, 2, 4, 5, 6, 7)])
    assert slots == [1, 1, 1, 1, 1, 2, 1]


def test_a_long_gap_starts_the_schedule_again() -> None:
    schedule = SlotSchedule()
    schedule.slots(1, 0.0)  # a link taken for jittery (its first half second): 0.9 slot
    assert schedule.late_batch(1, 2.004, 0, True) == 1 + 132  # of tolerance
    assert schedule.due == 2.004
    calm = SlotSchedule()
    assert slots_of([(1, k * T) for k in range(40)]) == [1] * 40
    for k in range(40):
        calm.slots(1, k * T)
    assert calm.late_batch(1, 39 * T + 2.004, 39, True) == 134  # round(2.004 / 15 ms)


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
