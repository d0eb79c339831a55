"""Each fault on request, and that the parser side survives it."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.stream import StreamParser
from roomba_bt.sim import Faults, SimLink, Simulator
from roomba_bt.sim.narrate import after_the_cut

from .helpers import BOX, box_with_a_drop, make, world

IDS = [7, 22, 35, 43, 44, 46, 48]


def stream_bytes_from(sim: Simulator, seconds: float) -> bytes:
    """What ``sim`` sends in ``seconds`` once it streams :data:`IDS`, driving in Full."""
    sim.receive(C.start().data + C.full().data + C.stream(IDS).data + C.drive(200, 500).data)
    return sim.run(seconds)


def stream_bytes(faults: Faults, seconds: float = 3.0, seed: int = 0) -> tuple[bytes, Simulator]:
    sim = Simulator(world(BOX), seed=seed, faults=faults)
    return stream_bytes_from(sim, seconds), sim


def test_corrupted_bytes_fail_the_checksum_and_the_parser_resynchronises() -> None:
    data, sim = stream_bytes(Faults(corrupt_rate=0.01))
    clean, _ = stream_bytes(Faults())
    assert len(data) == len(clean) and data != clean
    differing = sum(a != b for a, b in zip(data, clean, strict=True))
    assert 0.003 * len(data) < differing < 0.03 * len(data)
    parser = StreamParser(IDS)
    frames = parser.feed(data)
    assert parser.counters.checksum_failures > 0
    assert 0.6 * sim.frames_sent < len(frames) < sim.frames_sent


def test_dropped_frames_are_never_sent() -> None:
    sim = Simulator(world(BOX), seed=0, faults=Faults(drop_rate=0.5))
    sim.receive(C.start().data + C.full().data + C.stream(IDS).data + C.drive(200, 500).data)
    parser = StreamParser(IDS)
    frames = []
    for _ in range(200):  # fed as it arrives: frames lost whole leave a gap in time, not bytes
        sim.step()
        frames += parser.feed(sim.read(), sim.time)
    assert len(frames) == sim.frames_sent
    assert 0.35 * 200 < sim.frames_sent < 0.65 * 200


def test_latency_delays_every_robot_byte() -> None:
    sim = Simulator(world(BOX), faults=Faults(latency=0.3))
    sim.receive(C.start().data + C.sensors(35).data)
    assert sim.read() == b""
    for _ in range(19):
        sim.step()
        assert sim.read() == b""
    sim.step()
    assert sim.read() == bytes([1])


def test_a_byte_lost_from_the_robot_breaks_its_frame_and_the_parser_takes_the_next_one() -> None:
    """``byte_drop_rate``: a long, cheap cable loses a byte in the middle of a frame (the
    frame-level faults lose whole frames, or their tails); the parser loses that frame and
    takes every frame no byte was lost from, resynchronised on the checksum."""
    sim = Simulator(world(BOX), seed=5, faults=Faults(byte_drop_rate=0.02))
    clean = Simulator(world(BOX), seed=5)
    start = C.start().data + C.full().data + C.stream(IDS).data + C.drive(200, 500).data
    sim.receive(start)
    clean.receive(start)
    parser = StreamParser(IDS)
    taken = whole = 0
    for _ in range(2000):  # 30 s, fed as it arrives
        sim.step()
        clean.step()
        data, sent = sim.read(), clean.read()
        whole += data == sent
        taken += len(parser.feed(data, sim.time))
    line = sim.robot_line
    assert line is not None and clean.robot_line is None
    assert line.passed_on + line.dropped == sim.bytes_sent == clean.bytes_sent
    assert 0.015 * sim.bytes_sent < line.dropped < 0.025 * sim.bytes_sent
    # 22-byte frames: 1 - 0.98**22, 36 % of them broken
    assert sim.frames_sent == 2000 and 0.5 * 2000 < whole < 0.9 * 2000
    assert taken == whole  # no frame lost but those a byte was lost from
    assert parser.counters.checksum_failures > 0


def test_the_robot_line_is_seeded_and_leaves_the_other_faults_draws_as_they_were() -> None:
    """Its generator is its own (``robot-line:SEED``): the frames a seed drops are the same
    with bytes lost from the rest, so a fault added to a run changes only what it adds."""
    both = Faults(drop_rate=0.2, byte_drop_rate=0.05)
    data, _ = stream_bytes(both, seed=2)
    assert data == stream_bytes(both, seed=2)[0] != stream_bytes(both, seed=3)[0]

    def frames_dropped(faults: Faults) -> list[float]:
        sim = Simulator(world(BOX), seed=2, faults=faults)
        sim.receive(C.start().data + C.stream(IDS).data)
        times = []
        for _ in range(200):
            sim.step()
            if not sim.read():
                times.append(sim.time)
        return times

    lost_bytes_only = frames_dropped(Faults(drop_rate=0.2, byte_drop_rate=0.0001))
    assert lost_bytes_only == frames_dropped(Faults(drop_rate=0.2))


def test_injected_text_is_skipped_by_the_parser() -> None:
    text = "battery-current-zero 252\r\n"
    data, sim = stream_bytes(Faults(inject_text=text, inject_every=0.5))
    assert data.count(text.encode()) == 6  # at 0.5, 1.0, ... 3.0 s
    parser = StreamParser(IDS)
    assert len(parser.feed(data)) == sim.frames_sent == 200
    assert parser.counters.skipped_bytes == 6 * len(text)


def test_disconnect_at_t_ends_the_link() -> None:
    sim = Simulator(world(BOX), faults=Faults(disconnect_at=1.0))
    link = SimLink(sim)
    link.write(C.start().data + C.stream([35]).data)
    received = b""
    with pytest.raises(ConnectionError, match="simulated disconnect"):
        while True:
            received += link.read(0.1)
    assert len(received) == 66 * 5  # frames of [19][2][35][mode][checksum] until t = 1.0 s
    assert not link.is_open
    with pytest.raises(ConnectionError):
        link.write(C.start().data)


def test_sensor_noise_moves_analog_signals_not_bits() -> None:
    host = make(BOX, start=None, faults=Faults(noise=30.0))
    host.stream([7, 22, 28, 29, 45, 46, 48])
    frames = host.frames(1.0)
    assert len({f[28] for f in frames}) > 10 and len({f[22] for f in frames}) > 10
    assert {f[7] for f in frames} == {0} and {f[45] for f in frames} == {0}
    assert all(0 <= f[28] <= 4095 and 0 <= f[46] <= 4095 for f in frames)


def test_faults_are_repeatable_for_a_seed() -> None:
    faults = Faults(corrupt_rate=0.02, drop_rate=0.1, noise=5.0, inject_text="hi", inject_every=0.2)
    assert stream_bytes(faults, seed=3)[0] == stream_bytes(faults, seed=3)[0]
    assert stream_bytes(faults, seed=3)[0] != stream_bytes(faults, seed=4)[0]


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"corrupt_rate": 1.5}, "corrupt_rate"),
        ({"drop_rate": -0.1}, "drop_rate"),
        ({"latency": "slow"}, "latency"),
        ({"inject_text": "caf\u00e9"}, "inject_text"),
        ({"disconnect_at": -1}, "disconnect_at"),
        ({"from_stream": 1}, "from_stream"),
    ],
)
def test_bad_faults_name_the_field(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=f"faults.{field}: found"):
        Faults(**kwargs)  # type: ignore[arg-type]


def test_bit_flips_change_one_bit_of_a_byte_at_about_the_rate() -> None:
    data, _ = stream_bytes(Faults(bit_flip_rate=0.01), seconds=20.0)
    clean, _ = stream_bytes(Faults(), seconds=20.0)
    assert len(data) == len(clean)
    flipped = [a ^ b for a, b in zip(data, clean, strict=True) if a != b]
    assert all(bin(x).count("1") == 1 for x in flipped)  # single bits, never a new byte
    assert 0.007 * len(data) < len(flipped) < 0.013 * len(data)


def test_bit_flips_some_pass_the_checksum_and_the_parser_survives() -> None:
    data, sim = stream_bytes(Faults(bit_flip_rate=0.02), seconds=30.0)
    parser = StreamParser(IDS)
    frames = parser.feed(data)
    assert parser.counters.checksum_failures > 0
    assert 0.5 * sim.frames_sent < len(frames) <= sim.frames_sent


def test_truncated_frames_are_cut_short_and_the_next_one_follows() -> None:
    data, sim = stream_bytes(Faults(truncate_rate=0.2), seconds=6.0)
    clean, _ = stream_bytes(Faults(), seconds=6.0)
    assert len(data) < len(clean)
    parser = StreamParser(IDS)
    frames = parser.feed(data)
    # every cut frame is lost, the others are found (a cut frame hides no whole one)
    assert 0.7 * sim.frames_sent < len(frames) < 0.9 * sim.frames_sent


@pytest.mark.parametrize(
    ("faults", "event", "streaming"),
    [
        (Faults(reset_at=1.0), "reset", False),
        (Faults(stream_stop_at=1.0), "stream stop", False),
    ],
)
def test_timed_faults_happen_once_at_their_time(
    faults: Faults, event: str, streaming: bool
) -> None:
    data, sim = stream_bytes(faults, seconds=2.0)
    assert [e.detail for e in sim.events if e.kind == "fault"] == [event]
    assert sim.streaming is streaming
    parser = StreamParser(IDS)
    frames = parser.feed(data)
    assert 60 <= len(frames) <= 68  # one second of frames, then none
    if event == "reset":
        assert b"Roomba by iRobot" in data and sim.mode is OIMode.OFF


@pytest.mark.parametrize("mode", [C.safe(), C.full()], ids=["safe", "full"])
def test_the_sleep_fault_in_safe_or_full_waits_for_passive(mode: C.Command) -> None:
    """The OI spec: "In Safe and Full modes, Roomba will never sleep". The ``sleep_at`` fault
    due there leaves the robot streaming; it sleeps in Passive once the host has been quiet
    for a second (a run's stop into Passive is confirmed first)."""
    sim = Simulator(world(BOX), seed=0, faults=Faults(sleep_at=1.0))
    sim.receive(C.start().data + mode.data + C.stream(IDS).data)
    data = sim.run(2.0)
    assert not sim.asleep and sim.streaming
    assert 130 <= len(StreamParser(IDS).feed(data)) <= 136  # two seconds of frames
    sim.receive(C.start().data)  # Start: into Passive
    sim.run(0.9)
    assert not sim.asleep and sim.mode is OIMode.PASSIVE, "the host spoke under a second ago"
    sim.run(0.2)
    assert sim.asleep and sim.mode is OIMode.PASSIVE and not sim.streaming
    assert [e.detail for e in sim.events if e.kind == "fault"] == [
        "sleep, once in Passive (Safe and Full never sleep)"
    ]


def test_the_sleep_fault_in_passive_sleeps_at_its_time() -> None:
    """Passive is where a robot sleeps: the fault puts it to sleep at 1 s, the stream ended."""
    sim = Simulator(world(BOX), seed=0, faults=Faults(sleep_at=1.0))
    sim.receive(C.start().data + C.stream(IDS).data)
    data = sim.run(2.0)
    assert [e.detail for e in sim.events if e.kind == "fault"] == ["sleep"]
    assert sim.asleep and not sim.streaming
    assert 60 <= len(StreamParser(IDS).feed(data)) <= 68  # one second of frames, then none


@pytest.mark.parametrize(
    ("faults", "event"),
    [
        (Faults(stream_stop_at=1.0, from_stream=True), ("fault", "stream stop")),
        (Faults(stream_gap_at=1.0, stream_gap_s=0.5, from_stream=True), ("fault", "stream gap")),
        (Faults(disconnect_at=1.0, from_stream=True), ("disconnect", "link lost in Full")),
    ],
)
def test_fault_times_from_the_stream_count_from_the_step_it_started(
    faults: Faults, event: tuple[str, str]
) -> None:
    """``sim --faults-from-stream``: a served simulator's clock runs from its own start, and a
    host that opened the port late found a fault at 1.5 s long past. Counted from the stream,
    the fault comes 1 s after the first frame however long the robot waited for its host."""
    sim = Simulator(world(BOX), seed=0, faults=faults)
    sim.run(2.4)  # no host yet: the fault clock has not started
    assert [e for e in sim.events if e.kind in ("fault", "disconnect")] == []
    data = stream_bytes_from(sim, seconds=1.5)
    kind, detail = event
    [due] = [e for e in sim.events if e.kind == kind]
    assert due.detail.startswith(detail)
    first_frame = 2.4 + 0.015
    assert first_frame + 1.0 <= due.time < first_frame + 1.0 + 0.015  # the step it falls in
    assert 60 <= len(StreamParser(IDS).feed(data)) <= 68  # one second of frames, then none


def test_a_baud_change_mid_run_streams_on_at_the_other_rate() -> None:
    sim = Simulator(world(BOX), seed=0, faults=Faults(baud_change_at=1.0))
    link = SimLink(sim)  # the host at 115200
    link.write(C.start().data + C.full().data + C.stream(IDS).data)
    data = bytearray()
    while sim.time < 2.0:
        data += link.read(0.015)
    assert [e.detail for e in sim.events if e.kind == "fault"] == ["baud change"]
    assert sim.baud == 19200 and sim.streaming
    assert 60 <= len(StreamParser(IDS).feed(bytes(data))) <= 68  # then garbage at 115200
    link.set_baud(19200)  # the host follows: frames again
    after = bytearray()
    while sim.time < 2.5:
        after += link.read(0.015)
    assert len(StreamParser(IDS).feed(bytes(after))) >= 30


def test_fault_times_and_rates_are_checked() -> None:
    with pytest.raises(ValueError, match=r"faults.baud_change_to: found 1234; allowed: 300"):
        Faults(baud_change_to=1234)
    with pytest.raises(ValueError, match=r"faults.reset_at: found -1; allowed: seconds >= 0"):
        Faults(reset_at=-1)
    with pytest.raises(ValueError, match=r"faults.bit_flip_rate: found 2"):
        Faults(bit_flip_rate=2)


STAIRS = box_with_a_drop(3.0, start=(1, 2))


@pytest.mark.parametrize(
    ("mode", "went_on"),
    [
        (C.full(), "fell: drove off a drop"),
        (C.safe(), "mode: Safe->Passive (safety: cliff while driving forward)"),
    ],
)
def test_a_cut_link_leaves_the_robot_on_its_last_command(mode: C.Command, went_on: str) -> None:
    # The OI has no command timeout: the host gone, the robot drives on. In Full nothing
    # stops it before the drop; in Safe the cliff does. The simulator froze it where the
    # link went, and its summary read "mode Full, wheels 200/200 mm/s" beside a parked robot.
    sim = Simulator(world(STAIRS), faults=Faults(disconnect_at=1.0))
    sim.receive(C.start().data + mode.data + C.stream([35]).data + C.drive_direct(200, 200).data)
    sim.run(1.0)
    cut_x = sim.x
    assert sim.disconnected and sim.read() == b""
    sim.run(14.0)
    assert sim.x > cut_x + 1500  # from x = 1.2 m to the drop's edge at 3 m
    assert sim.read() == b"" and sim.frames_sent == 66  # nothing heard after the cut
    said = after_the_cut(sim)
    assert said is not None
    assert said.startswith("link cut at 1.0 s in ") and "wheels 200/200 mm/s" in said
    assert "went on with its last command: at " in said and went_on in said
    assert after_the_cut(Simulator(world(STAIRS))) is None


@pytest.mark.parametrize(("reset_at", "disconnect_at"), [(1.0, 2.0), (2.0, 1.0), (1.5, 1.5)])
def test_timed_faults_and_the_disconnect_each_come_at_their_time(
    reset_at: float, disconnect_at: float
) -> None:
    # The step compares the time with the first of the next timed fault and the disconnect
    # (robot.py, _fault_at): each still comes at its own time, the later one too.
    sim = Simulator(world(BOX), faults=Faults(reset_at=reset_at, disconnect_at=disconnect_at))
    sim.run(3.0)
    happened = {event.kind: event.time for event in sim.events if event.kind != "mode"}
    assert disconnect_at <= happened["disconnect"] < disconnect_at + 0.015  # the first step on
    if reset_at < disconnect_at:
        assert reset_at <= happened["fault"] < reset_at + 0.015
    else:
        assert "fault" not in happened  # the link was lost first


# ---------------------------------------------------------------- host -> robot bytes
DRIVE_200 = C.drive(200, 0x8000).data  # 89 00 c8 80 00


def test_a_clean_line_has_no_host_line_and_a_faulty_one_counts_what_it_did() -> None:
    assert Simulator(world(BOX)).host_line is None
    sim = Simulator(world(BOX), seed=3, faults=Faults(host_drop_rate=0.1, host_corrupt_rate=0.1))
    line = sim.host_line
    assert line is not None
    for _ in range(100):
        sim.receive(DRIVE_200)
    assert 25 < line.dropped < 75 and 25 < line.corrupted < 75
    assert next(e.detail for e in sim.events if e.kind == "line").endswith(
        "of 89 00 c8 80 00 from the host"
    )


def test_the_host_line_is_seeded() -> None:
    def lost(seed: int) -> list[str]:
        sim = Simulator(world(BOX), seed=seed, faults=Faults(host_drop_rate=0.2))
        for _ in range(20):
            sim.receive(DRIVE_200)
        return [e.detail for e in sim.events if e.kind == "line"]

    assert lost(1) == lost(1) != lost(2)


def test_a_lost_data_byte_makes_the_robot_take_the_next_commands_opcode_as_data() -> None:
    """What a bad cable does to a robot (the noisy-cable report): Drive 200 with its c8 lost
    waits for a fifth byte; the next command's opcode completes it, a drive nobody sent."""
    sim = Simulator(world(BOX), faults=Faults(host_drop_rate=1.0))
    sim.host_line = None  # the mode commands arrive whole
    sim.receive(C.start().data + C.full().data)
    sim.receive(DRIVE_200[:2] + DRIVE_200[3:])  # 89 00 80 00: the c8 lost
    sim.run(0.3)
    assert sim.requested_left == sim.requested_right == 0  # still waiting: it stands
    sim.receive(C.halt().data)  # the stop, 89 00 00 00 00
    assert sim.values[39] == 0x80 and sim.values[40] == 0x89  # velocity 128, radius 137
    assert sim.requested_left or sim.requested_right  # the "stop" set it going


@pytest.mark.parametrize("name", ["host_drop_rate", "host_corrupt_rate", "byte_drop_rate"])
def test_line_rates_are_checked(name: str) -> None:
    with pytest.raises(ValueError, match=f"faults.{name}: found 1.5; allowed: 0.0..1.0"):
        Faults(**{name: 1.5})
