"""Bytes in, bytes out: framing, checksums, replies, incomplete commands, the small commands."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.bits import button_bits, led_bits
from roomba_bt.oi.encode import Note
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.packets import GROUPS, PACKETS, VALID_PACKET_IDS, data_size
from roomba_bt.oi.profiles import PROFILES, ROOMBA600, RobotProfile
from roomba_bt.oi.stream import StreamParser

from .helpers import Host, make

PACKET_LISTS = [[100], [6], [0, 1, 2, 3, 4, 5], [101, 106, 107], [7, 19, 20, 35, 43, 44], [22]]


def expected_frame(host: Host, ids: list[int]) -> bytes:
    values = {pid: host.sim.values[pid] for pid in PACKETS}
    layout = layout_for(tuple(ids), host.sim.profile, True)
    return layout.stream_frame(values, include_header=host.sim.profile.checksum_includes_header)


@pytest.mark.parametrize("profile", list(PROFILES.values()), ids=list(PROFILES))
@pytest.mark.parametrize("ids", PACKET_LISTS, ids=str)
def test_every_frame_is_the_table_layout_with_a_valid_checksum(
    profile: RobotProfile, ids: list[int]
) -> None:
    host = make(profile=profile, mode="full")
    host.stream(ids)
    host.send(C.drive(300, 400))
    parser = StreamParser(ids, profile)
    bias = 0 if profile.checksum_includes_header else 19
    for _ in range(400):  # 6 s of driving: the values change every frame
        host.sim.step()
        frame = host.sim.read()
        assert frame == expected_frame(host, ids)
        assert frame[0] == 19 and frame[1] == len(frame) - 3
        assert (sum(frame) - bias) % 256 == 0
        assert len(parser.feed(frame)) == 1
    assert parser.counters.checksum_failures == 0 and parser.counters.skipped_bytes == 0


@pytest.mark.parametrize("packet_id", sorted(VALID_PACKET_IDS))
def test_sensors_142_replies_with_the_table_size_and_layout(packet_id: int) -> None:
    host = make()
    host.run(0.1)
    host.sim.read()
    host.send(C.sensors(packet_id))
    reply = host.sim.read()
    assert len(reply) == data_size(packet_id)
    values = {pid: host.sim.values[pid] for pid in PACKETS}
    assert reply == layout_for((packet_id,), host.sim.profile, False).pack(values)


def test_group_sizes_match_the_spec() -> None:
    host = make()
    sizes = {}
    for group in GROUPS:
        host.send(C.sensors(group))
        sizes[group] = len(host.sim.read())
    assert sizes == {0: 26, 1: 10, 2: 6, 3: 10, 4: 14, 5: 12, 6: 52, 100: 80, 101: 28,
                     106: 12, 107: 9}  # fmt: skip


def test_query_list_149_replies_in_order_without_header_or_checksum() -> None:
    host = make()
    reply = host.query([35, 7, 22])
    assert reply.oi_mode == 2 and reply[7] == 0 and reply[22] > 12000


def test_unread_frames_and_replies_are_read_in_the_order_sent() -> None:
    host = make()
    host.stream([7, 35])
    host.sim.read()
    host.sim.step()
    first = expected_frame(host, [7, 35])
    host.send(C.sensors(35))  # a reply after an unread frame
    mode = bytes([host.sim.values[35]])
    assert host.sim.read() == first + mode
    host.sim.step()
    second = expected_frame(host, [7, 35])
    host.sim.step()  # a second frame before the first is read
    host.send(C.sensors(35))
    host.sim.step()  # a frame after a reply
    assert host.sim.read() == second + second + mode + second
    assert host.sim.read() == b""


def test_an_invalid_packet_id_gets_no_reply() -> None:
    host = make()
    host.send(bytes([142, 99]))
    assert host.sim.read() == b""


def test_an_incomplete_command_waits_for_its_data_bytes() -> None:
    host = make()
    data = C.drive_direct(200, 200).data
    for byte in data[:-1]:
        host.send(bytes([byte]))
        host.run(0.3)
        assert host.sim.x == 2000.0
    host.send(data[-1:])
    host.run(0.3)
    assert host.sim.x > 2030.0


def test_variable_length_commands_wait_for_their_tails() -> None:
    host = make()
    song = C.song(1, [Note(60, 16), Note(62, 16), Note(64, 32)]).data
    stream = C.stream([7, 35]).data
    wire = song + stream
    for i in range(len(wire)):
        host.send(wire[i : i + 1])
    assert host.sim.songs[1] == ((60, 16), (62, 16), (64, 32))
    assert host.sim.stream_ids == (7, 35)


def test_unknown_opcodes_are_skipped_byte_by_byte() -> None:
    host = make()
    host.send(bytes([0, 200, 255]), C.sensors(35))
    assert host.sim.read() == bytes([2])
    assert host.sim.ignored_bytes == 3


def test_pause_and_resume_150() -> None:
    host = make()
    host.stream([35])
    assert len(host.frames(0.3)) == 20
    host.send(C.pause_stream())
    assert host.frames(0.3) == []
    host.send(C.resume_stream())
    assert len(host.frames(0.3)) == 20
    host.send(C.stream([]))
    assert host.frames(0.3) == []


def test_a_stream_too_long_to_frame_is_refused_and_the_old_one_goes_on() -> None:
    """n-bytes is one byte: four group-100 requests (324 bytes) cannot be framed. Neither spec
    says what the robot does; the simulator refuses the request (an event says why) and keeps
    streaming what it was asked before. It used to fail with an IndexError."""
    host = make()
    host.stream([7, 35])
    host.sim.receive(bytes([148, 4, 100, 100, 100, 100]))  # raw: our encoder refuses it
    frames = host.frames(0.3)
    assert len(frames) == 20 and all(set(dict(f)) == {7, 35} for f in frames)
    refused = [e for e in host.sim.events if e.kind == "refused"]
    assert refused and "stream of 324 bytes" in refused[0].detail


def test_stream_packet_count_38() -> None:
    host = make()
    host.stream([38, 7, 35])
    assert host.frame()[38] == 3


def test_song_and_play_show_in_packets_36_and_37_for_the_songs_length() -> None:
    host = make()
    host.stream([36, 37])
    host.send(C.song(2, [Note(69, 32), Note(71, 32)]), C.play(2))  # 1 s
    frames = host.frames(1.2)
    assert frames[0][36] == 2 and frames[0][37] == 1
    assert frames[60][37] == 1 and frames[-1][37] == 0


@pytest.mark.parametrize(
    "durations",
    [(1,), (2, 2), (32,), (64, 64), (16,) * 16],
    ids=["1/64 s", "4/64 s", "0.5 s", "2 s", "16 notes, 4 s"],
)
def test_packet_37_shows_a_song_for_the_sum_of_its_notes_then_clears(
    durations: tuple[int, ...],
) -> None:
    """Packet 37 ("1 = OI song currently playing", both specs) is 1 on every frame sampled
    before the song's length, the sum of its notes' durations in 1/64 s (Song 140), and 0
    from then on; packet 36 ("the currently selected OI song") keeps the slot played. A
    maker read the simulator as showing every song for 16 ms: a one-note 1/64 s song shows
    on one frame, and each longer one for its length. (A real robot updates these values
    every 15 ms out of step with the stream and may never show a song of a frame or two:
    ``play`` allows for it, docs/protocol.md "A song too short for packet 37".)"""
    host = make()
    host.stream([36, 37])
    notes = [Note(60 + i, d) for i, d in enumerate(durations)]
    host.send(C.song(3, notes), C.play(3))
    length = sum(durations) / 64
    frames = host.frames(length + 0.1)  # frame k is sampled at 15 ms * k after the Play
    shown = sum(1 for k in range(1, len(frames) + 1) if 0.015 * k < length)
    assert [f[37] for f in frames] == [1] * shown + [0] * (len(frames) - shown)
    assert all(f[36] == 3 for f in frames)


def test_play_while_a_song_plays_is_ignored_and_said() -> None:
    """Decided in session 32 (docs/protocol.md, "Play while a song plays"): the original
    Create OI spec says Play "does not work if a song is already playing"; the 600 and 500
    specs are silent. The simulator replaced the song until then, so a mission that chained
    songs without waiting sounded right in the simulator only. In one tick too: the second
    of two Plays written back to back is ignored."""
    host = make()
    host.stream([36, 37])
    host.send(C.song(0, [Note(69, 64)]), C.song(1, [Note(71, 16)]), C.play(0))  # 1 s, 0.25 s
    host.frames(0.3)
    host.send(C.play(1))
    frames = host.frames(0.6)  # song 1 would have ended by 0.55 s
    assert all(f[36] == 0 and f[37] == 1 for f in frames)
    refused = [e.detail for e in host.sim.events if e.kind == "refused"]
    assert refused == ["play 1 ignored: song 0 still playing"]
    frames = host.frames(0.2)
    assert frames[-1][37] == 0  # song 0 over at 1 s: now Play works again
    host.send(C.play(1), C.play(0))
    frames = host.frames(0.2)
    assert frames[0][36] == 1 and frames[0][37] == 1 and frames[-1][37] == 1
    assert len(host.sim.events) and host.sim.events[-1].detail.startswith("play 0 ignored")


def test_leds_digits_scheduling_leds_schedule_and_clock_are_kept() -> None:
    host = make()
    host.send(
        C.leds(led_bits("dock"), 0, 255),
        C.digit_leds_ascii("ABCD"),
        C.scheduling_leds(3, 1),
        C.set_day_time("wed", 15, 30),
        C.schedule({"wed": (15, 0)}),
    )
    assert host.sim.leds == (4, 0, 255)
    assert host.sim.digits == tuple(b"ABCD")
    assert host.sim.scheduling_leds == (3, 1)
    assert host.sim.robot_clock.day_time == (3, 15, 30)
    assert host.sim.robot_clock.schedule[0] == 8
    assert host.sim.day_time == (3, 15, 30) and host.sim.schedule[0] == 8  # 0.2.0's names


def test_the_clock_runs_on_from_the_time_it_was_set_and_the_week_wraps() -> None:
    """The robot's clock keeps time after Set Day/Time (168): ``roomba-bt clock`` on the
    simulator shows what it holds, as a 600's display would."""
    host = make(profile=ROOMBA600)
    assert host.sim.robot_clock.shows(host.sim.time) == (0, 0, 0)  # power-on: Sunday 00:00
    host.send(C.set_day_time("sat", 23, 59))
    assert host.sim.robot_clock.shows(host.sim.time) == (6, 23, 59)
    host.run(59.0)
    assert host.sim.robot_clock.shows(host.sim.time) == (6, 23, 59)  # whole minutes only
    host.run(1.5)
    assert host.sim.robot_clock.shows(host.sim.time) == (
        0,
        0,
        0,
    )  # Saturday 23:59 + 1 min: Sunday 00:00
    host.send(C.schedule({"mon": (9, 30), "wed": (10, 0)}))
    assert host.sim.robot_clock.cleans == {"mon": (9, 30), "wed": (10, 0)}
    host.send(C.schedule({}))
    assert host.sim.robot_clock.cleans == {}


@pytest.mark.parametrize("button", ["clock", "schedule"])
def test_schedule_and_day_time_are_ignored_while_the_clock_or_schedule_button_is_held(
    button: str,
) -> None:
    """Both specs: "If Roomba's schedule or clock button is pressed, this command will be
    ignored." The simulator took them whatever its buttons showed."""
    host = make(profile=ROOMBA600)
    host.send(C.buttons(button_bits(button)))  # held for the spec's 1/6 s
    host.send(C.set_day_time("wed", 15, 30), C.schedule({"wed": (15, 0)}))
    assert host.sim.robot_clock.day_time == (0, 0, 0)
    assert host.sim.robot_clock.schedule == bytes(15)
    refused = [e.detail for e in host.sim.events if e.kind == "refused"]
    assert refused == [
        f"set_day_time ignored: the {button} button is pressed",
        f"schedule ignored: the {button} button is pressed",
    ]
    host.run(0.2)  # released
    host.send(C.set_day_time("wed", 15, 30), C.schedule({"wed": (15, 0)}))
    assert host.sim.robot_clock.day_time == (3, 15, 30)
    assert host.sim.robot_clock.cleans == {"wed": (15, 0)}


def test_another_button_held_does_not_stop_the_clock_being_set() -> None:
    host = make(profile=ROOMBA600)
    host.send(C.buttons(button_bits("dock", "minute", "hour", "day")))
    host.send(C.set_day_time("fri", 8, 0))
    assert host.sim.robot_clock.day_time == (5, 8, 0)


def test_buttons_165_press_for_a_sixth_of_a_second() -> None:
    host = make()
    host.stream([18])
    host.send(C.buttons(1))
    frames = host.frames(0.5)
    assert frames[0][18] == 1 and frames[5][18] == 1 and frames[-1][18] == 0


def test_baud_129_changes_the_rate() -> None:
    host = make()
    host.send(C.baud_rate(57600))
    assert host.sim.baud == 57600


@pytest.mark.parametrize("profile", list(PROFILES.values()), ids=list(PROFILES))
def test_any_bytes_from_a_client_never_break_the_simulator(profile: RobotProfile) -> None:
    """Commands with random data bytes (stream and query lists of any ids and length, songs,
    baud codes, out-of-range drives...) over 100 seeded runs: the simulator answers or
    ignores them and keeps stepping. A stream too long to frame once raised IndexError."""
    import random

    from roomba_bt.oi.opcodes import COMMANDS
    from roomba_bt.sim import Simulator, load_world

    worlds = [load_world(name) for name in ("empty-room", "apartment", "corridor")]
    opcodes = sorted(COMMANDS)
    for seed in range(100):
        rng = random.Random(seed)
        sim = Simulator(worlds[seed % 3], profile, seed=seed)
        sim.receive(bytes([128, 131]))
        for _ in range(200):
            if rng.random() < 0.3:
                tail = [rng.randrange(256) for _ in range(rng.randint(0, 8))]
                sim.receive(bytes([rng.choice(opcodes), *tail]))
            sim.step()
            sim.read()
        assert sim.time > 0
