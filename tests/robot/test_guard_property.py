"""Property: whatever a caller sends, in whatever order, refused commands leave no byte, every
actuator byte on the wire left while the model was in Safe or Full, and the wire carries
exactly the accepted commands, whole (it decodes back into them)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command, decode_command
from roomba_bt.oi.errors import UnsupportedCommandError
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.oi.profiles import PROFILES
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import ModeError
from roomba_bt.transport.testing import WriteLogTransport

COMMANDS: list[Command] = [
    oi.start(),
    oi.safe(),
    oi.full(),
    oi.clean(),
    oi.seek_dock(),
    oi.stop(),
    oi.reset(),
    oi.drive(200, 500),
    oi.drive_direct(-100, 100),
    oi.motors_off(),
    oi.leds(8, 0, 255),
    oi.play(1),
    oi.sensors(7),
    oi.query_list([7, 35]),
    oi.halt(),
]


@settings(max_examples=150, deadline=None)
@given(
    batches=st.lists(st.lists(st.sampled_from(COMMANDS), min_size=1, max_size=4), max_size=12),
    profile=st.sampled_from(list(PROFILES.values())),
)
def test_refused_commands_never_reach_the_wire(batches, profile) -> None:  # type: ignore[no-untyped-def]
    transport = WriteLogTransport()
    connection = Connection(transport, profile, watchdog=0)
    accepted: list[Command] = []
    for batch in batches:
        for command in batch:
            before = len(transport.writes)
            mode = connection.mode
            try:
                connection.send(command)
            except (ModeError, UnsupportedCommandError):
                assert len(transport.writes) == before
                assert not profile.has_command(command.spec) or mode not in command.spec.modes
                continue
            assert profile.has_command(command.spec)
            if command.spec.modes <= DRIVING_MODES:
                assert mode in DRIVING_MODES
            accepted.append(command)
    wire = bytearray(b"".join(transport.writes))
    decoded: list[Command] = []
    while wire:
        result = decode_command(wire)
        assert result is not None, "a command left incomplete"
        command, size = result
        decoded.append(command)
        del wire[:size]
    assert decoded == accepted


@settings(max_examples=100, deadline=None)
@given(
    batches=st.lists(st.lists(st.sampled_from(COMMANDS), min_size=1, max_size=5), max_size=10),
    profile=st.sampled_from(list(PROFILES.values())),
)
def test_send_many_is_sequential_send_in_one_write(batches, profile) -> None:  # type: ignore[no-untyped-def]
    batched, one_by_one = WriteLogTransport(), WriteLogTransport()
    many = Connection(batched, profile, watchdog=0)
    single = Connection(one_by_one, profile, watchdog=0)
    for batch in batches:
        writes_before = len(batched.writes)
        refused = []
        for command in batch:
            try:
                single.send(command)
            except (ModeError, UnsupportedCommandError) as exc:
                refused.append((type(exc), exc.command))
        try:
            many.send_many(batch)
        except (ModeError, UnsupportedCommandError) as exc:
            assert refused and (type(exc), exc.command) == refused[0]
        else:
            assert not refused
        assert len(batched.writes) - writes_before <= 1
        assert many.mode is single.mode
    assert b"".join(batched.writes) == b"".join(one_by_one.writes)
