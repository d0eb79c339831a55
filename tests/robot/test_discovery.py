"""Finding the rate and waking the robot (robot/discovery.py), on the simulator's in-process
link (virtual clock): the same function ``doctor`` and ``--baud auto`` use."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600
from roomba_bt.robot.discovery import (
    OI_RATES,
    SAMPLE_PACKETS,
    find_robot,
    identify_robot,
    is_answer,
    probe,
    rates_to_try,
    sample_stream,
    wake_pulse,
)
from roomba_bt.robot.writer import RESYNC_ZEROS
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.link import SimLink


def _link(baud: int = 115200, *, asleep: bool = False, profile: object = CREATE2) -> SimLink:
    simulator = Simulator(load_world("empty-room"), profile, 0)  # type: ignore[arg-type]
    simulator.baud = baud
    if asleep:
        simulator.fall_asleep("test")
    return SimLink(simulator)


def test_the_rates_likeliest_first_and_a_named_rate_before_them() -> None:
    assert OI_RATES == (115200, 19200)
    assert rates_to_try() == (115200, 19200)
    assert rates_to_try(19200) == (19200, 115200)
    assert rates_to_try(57600) == (57600, 115200, 19200)


def test_an_answer_is_three_bytes_in_range_with_the_mode_passive() -> None:
    assert is_answer(bytes([1, 0, 0]))
    assert is_answer(bytes([2, 2, 2]))  # the mode + 1 firmware, charging on the home base
    assert not is_answer(bytes([3, 0, 0]))  # Start leads to Passive: 3 is Full
    assert not is_answer(bytes([1, 9, 0]))  # no charging state 9
    assert not is_answer(bytes([1, 0, 0, 0]))  # more than asked for
    assert not is_answer(b"")


def test_at_19200_the_first_probe_hears_nothing_and_the_second_finds_it() -> None:
    link = _link(19200)
    found = find_robot(link)
    assert found.baud == 19200
    assert [(p.baud, p.answered, p.reply) for p in found.probes] == [
        (115200, False, b""),
        (19200, True, bytes([1, 0, 0])),
    ]
    assert found.probes[0].seen == "nothing"
    assert link.baud == 19200, "the port is left at the rate found"
    assert found.after_wake is None


def test_a_stream_at_another_rate_is_garbage_not_an_answer() -> None:
    link = _link(19200)
    link.set_baud(19200)
    link.write(bytes([128, 148, 1, 7]))  # Start, a stream of bumps the host cannot read
    result = probe(link, 115200)
    assert not result.answered
    assert result.noise > 0
    assert "bytes that are no answer" in result.seen


def test_the_mode_plus_one_firmware_answers_2() -> None:
    found = find_robot(_link(profile=ROOMBA600))
    assert found.answer is not None and found.answer.mode_raw == 2


def test_an_asleep_robot_is_found_after_a_brc_pulse() -> None:
    link = _link(19200, asleep=True)
    found = find_robot(link)
    assert found.woken and found.baud == 19200
    assert [p.answered for p in found.before_wake.probes] == [False, False]
    assert link.simulator.brc_pulses == 1
    assert not link.simulator.brc_low, "BRC is let go after the pulse"


def test_without_wake_the_asleep_robot_stays_unfound() -> None:
    found = find_robot(_link(asleep=True), wake=False)
    assert found.baud is None and found.after_wake is None


class _NoLines:
    name = "pty"

    def set_wake_line(self, low: bool) -> None:
        raise OSError(25, "Inappropriate ioctl for device")


def test_a_port_without_modem_lines_says_why_it_cannot_pulse() -> None:
    pulse = wake_pulse(_NoLines())  # type: ignore[arg-type]
    assert pulse.how is None
    assert pulse.problem is not None and "Inappropriate ioctl" in pulse.problem


class _HangUpOnly(SimLink):
    """A link whose modem ioctl fails but whose line can be hung up: as on a pty, speed 0
    drops DTR/RTS (BRC high) and the rate's return asserts them (BRC low)."""

    writes_while_hung_up = 0
    _hung = False

    def set_wake_line(self, low: bool) -> None:
        raise OSError(25, "Inappropriate ioctl for device")

    def write(self, data: bytes) -> None:
        self.writes_while_hung_up += self._hung
        super().write(data)

    @contextlib.contextmanager
    def hung_up(self) -> Iterator[None]:
        self.simulator.set_brc(False)
        self._hung = True
        try:
            yield
        finally:
            self._hung = False
            self.simulator.set_brc(True)


def test_a_port_without_modem_lines_is_hung_up_instead_and_the_robot_wakes() -> None:
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    simulator.baud = 19200
    simulator.fall_asleep("test")
    link = _HangUpOnly(simulator)
    found = find_robot(link)
    assert found.woken and found.baud == 19200
    assert simulator.brc_pulses == 1
    assert link.writes_while_hung_up == 0
    assert wake_pulse(link).how == (
        "pulsed BRC by a 1 s hang-up (the modem lines cannot be set here: speed 0 drops DTR "
        "and RTS, the rate's return raises them)"
    )


def test_a_stream_sample_reads_each_frames_checksum_rule_and_the_widest_readings() -> None:
    """doctor's stream check and ``--profile auto``'s: a 500's frames leave the header out
    of the checksum; a half second carries 33 frames of 15 ms; the stream is paused after."""
    link = _link(profile=ROOMBA500)
    probe(link, 115200)  # Start: Passive
    sample = sample_stream(link)
    assert sample.frames >= 30 and sample.skipped == 0
    assert sample.header_in_checksum is False and set(sample.conventions) == {False}
    assert set(sample.readings) == set(SAMPLE_PACKETS) and sample.readings[35] == 1
    assert sample.latency is not None
    assert link.read(0.1) == b""  # paused: nothing more comes


def test_identify_robot_tells_a_600_and_a_500_and_names_a_create2_or_600_or_500() -> None:
    """``--profile auto``: the mode + 1 tells the 600, the checksum the 500; a Create 2's
    evidence fits a 600 without the mode + 1 bug and a 500 that sums the header too, and the
    default is assumed. No Reset (7) is written: it restarts a 600's OI, and a 500 has
    none."""
    link = _link(profile=ROOMBA600)
    written: list[bytes] = []
    write = link.write
    link.write = lambda data: (written.append(bytes(data)), write(data))[1]  # type: ignore[method-assign]
    told = identify_robot(link, 115200)
    assert not isinstance(told, str) and told.candidates == (ROOMBA600,)
    # zeros, Start and pause, query, stream
    assert written[0].startswith(RESYNC_ZEROS)
    assert [data.lstrip(b"\0")[0] for data in written] == [128, 149, 148, 150]
    told = identify_robot(_link(profile=ROOMBA500), 115200)
    assert not isinstance(told, str) and told.candidates == (ROOMBA500,)
    told = identify_robot(_link(profile=CREATE2), 115200)
    assert not isinstance(told, str) and told.candidates == (CREATE2, ROOMBA600, ROOMBA500)
    assert told.assumed is CREATE2


def test_identify_robot_says_why_when_nothing_answers() -> None:
    said = identify_robot(_link(asleep=True), 115200)
    assert said == (
        "no answer to Start and a Query List at 115200 baud (nothing); the start-up says why"
    )
