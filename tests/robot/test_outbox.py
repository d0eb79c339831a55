"""The outbox of one tick: of the states the last command per channel wins, the events are
all sent in order; an ending behaviour's halt yields to another behaviour's command on that
channel."""

from __future__ import annotations

import pytest

from roomba_bt.oi import commands
from roomba_bt.oi.encode import Command
from roomba_bt.oi.opcodes import COMMANDS, Delivery
from roomba_bt.robot.interface import CYCLE_END, Outbox

OLD, NEW = object(), object()  # two behaviours


def test_last_command_per_channel_wins_in_first_queued_order() -> None:
    box = Outbox()
    box.send(commands.safe(), NEW)
    box.send(commands.drive(100, 0), NEW)
    box.send(commands.drive(200, 0), NEW)
    assert [c.name for c in box.drain()] == ["safe", "drive"]
    assert len(box) == 0


def test_a_state_queued_again_after_a_mode_command_is_written_after_it() -> None:
    """A plugin that passes through Full ends with ``halt``, ``safe`` and SUCCESS; the next
    leaf's first Drive in the same tick took the halt's place, before the Safe, and the Safe
    stopped the wheels it had just set going (session 37's verifier: a 2 s drive went 4 cm).
    The Drive now comes after the Safe; a replacement with no mode command after it keeps
    its place (the test above), and an event after it (a Play) moves nothing."""
    box = Outbox()
    box.send(commands.halt(), OLD)
    box.send(commands.safe(), OLD)
    box.send(commands.drive(100, 0), NEW)
    assert [c.data for c in box.drain()] == [commands.safe().data, commands.drive(100, 0).data]
    box.send(commands.drive(100, 0), OLD)
    box.send(commands.play(0), OLD)
    box.send(commands.drive(200, 0), NEW)
    assert [c.name for c in box.drain()] == ["drive", "play"]
    box.send(commands.halt(), OLD)  # a stop keeps its place: a halt after Stop is refused in Off
    box.send(commands.stop(), OLD)
    box.send(commands.halt(), OLD)
    assert [c.name for c in box.drain()] == ["drive", "stop"]


EVENTS_IN_ONE_TICK = {
    "two plays": [commands.play(0), commands.play(1)],
    "the same play twice": [commands.play(2), commands.play(2)],
    "two button presses": [commands.buttons(1), commands.buttons(4)],
    "songs of two slots": [commands.song(0, [(60, 8)]), commands.song(1, [(62, 8)])],
    "a song, its play, the next song and its play": [
        commands.song(0, [(60, 8)]), commands.play(0),
        commands.song(1, [(62, 8)]), commands.play(1),
    ],
}  # fmt: skip


@pytest.mark.parametrize("sent", EVENTS_IN_ONE_TICK.values(), ids=list(EVENTS_IN_ONE_TICK))
def test_events_in_one_tick_are_all_written_in_order(sent: list[Command]) -> None:
    """``play: 0``, a wait that passes at once, ``play: 1``: both Plays in one tick. As the
    state of a "speaker" channel the first was dropped and song 0 never played."""
    box = Outbox()
    box.send(commands.drive(100, 0), OLD)
    for command in sent:
        box.send(command, NEW)
    box.send(commands.drive(200, 0), OLD)
    assert [c.data for c in box.drain()] == [commands.drive(200, 0).data] + [c.data for c in sent]


def test_every_state_in_the_opcode_table_has_its_channel_and_play_and_buttons_are_events() -> None:
    """The batcher's one field: a state needs the channel its last command wins on; the
    commands that happen (Play 141, Buttons 165, Song 140, Start 128) are events."""
    assert all(c.channel is not None for c in COMMANDS.values() if c.delivery is Delivery.STATE)
    assert {COMMANDS[op].delivery for op in (128, 140, 141, 165)} == {Delivery.EVENT}
    assert {COMMANDS[op].delivery for op in (137, 138, 139, 145, 148, 164)} == {Delivery.STATE}


def test_a_stop_yields_to_another_senders_command() -> None:
    box = Outbox()
    box.send(commands.drive(-100, 0), NEW)  # the branch that took over
    box.send_stop(commands.halt(), OLD)  # the branch it stopped
    assert [list(c.data) for c in box.drain()] == [list(commands.drive(-100, 0).data)]


def test_a_stop_replaces_the_senders_own_command_and_fills_an_empty_channel() -> None:
    box = Outbox()
    box.send(commands.drive(200, 0), OLD)
    box.send_stop(commands.halt(), OLD)
    assert [list(c.data) for c in box.drain()] == [[137, 0, 0, 0, 0]]
    box.send_stop(commands.halt(), OLD)
    assert [list(c.data) for c in box.drain()] == [[137, 0, 0, 0, 0]]


def test_a_command_after_a_stop_replaces_it() -> None:
    """A sequence: one drive ends (its halt), the next starts in the same tick."""
    box = Outbox()
    box.send_stop(commands.halt(), OLD)
    box.send(commands.drive_direct(-120, 120), NEW)
    assert [c.name for c in box.drain()] == ["drive_direct"]


def test_the_senders_are_forgotten_with_the_tick() -> None:
    box = Outbox()
    box.send(commands.drive(200, 0), NEW)
    box.drain()
    box.send_stop(commands.halt(), OLD)
    assert [c.name for c in box.drain()] == ["drive"]


# ------------------------------------------------------------------ a built-in cycle's end
END = [c.name for c in CYCLE_END]


def test_a_cycles_end_goes_before_the_ticks_other_commands() -> None:
    # the higher branch's mode: safe, queued before the halted leaf asked: Safe at the end
    box = Outbox()
    box.send(commands.safe(), NEW)
    box.end_cycle(OLD)
    box.end_cycle(NEW)  # asked twice in one tick: sent once
    assert END == ["safe", "drive", "motors", "start"]
    assert [c.name for c in box.drain()] == [*END, "safe"]
    assert box.sender_of(commands.halt()) is OLD
    assert box.drain() == []


@pytest.mark.parametrize("first", [True, False], ids=["cycle after", "cycle before"])
def test_a_cycle_started_in_the_same_tick_by_another_leaf_comes_after_the_end(
    first: bool,
) -> None:
    """A cycle command into a running cycle pauses it (600 / Create 2 spec): the old cycle
    is ended first, then the new one starts (it was left out: the robot sat paused)."""
    box = Outbox()
    if not first:
        box.send(commands.seek_dock(), NEW)
    box.end_cycle(OLD)
    if first:
        box.send(commands.seek_dock(), NEW)
    assert [c.name for c in box.drain()] == [*END, "seek_dock"]


def test_a_cycle_started_and_halted_in_one_tick_is_not_written() -> None:
    box = Outbox()
    box.send(commands.clean(), OLD)
    box.end_cycle(OLD, running=False)  # no cycle was driving before it
    assert box.drain() == []
    box.send(commands.clean(), OLD)
    box.end_cycle(OLD)  # one was: it is ended
    assert [c.name for c in box.drain()] == END


def test_a_cycles_end_is_dropped_with_the_rest() -> None:
    box = Outbox()
    box.end_cycle(OLD)
    assert box.queued
    box.clear()
    assert not box.queued and box.drain() == []


def test_the_commands_written_after_a_cycles_end_are_their_channels_last() -> None:
    """A parallel branch's drive and brushes, queued in the tick a halted leaf ends its cycle,
    are written after the end: they are the wheels' and the motors' last commands, and their
    sender is named (the end had taken both: a later ``mode: passive`` skipped its motors
    off, a refusal named the halted leaf)."""
    box = Outbox()
    drive, brushes = commands.drive(200, 0), commands.motors(0b100)
    box.send(drive, NEW)
    box.send(brushes, NEW)
    box.end_cycle(OLD)
    assert [c.name for c in box.drain()] == [*END, "drive", "motors"]
    assert box.last_on("wheels") is drive and box.last_on("motors") is brushes
    assert box.sender_of(drive) is NEW


def test_a_cycle_never_written_is_no_channels_last_command() -> None:
    box = Outbox()
    box.send(commands.seek_dock(), OLD)
    box.end_cycle(OLD, running=False)
    assert box.drain() == []
    assert box.last_on("wheels") is None and box.sender_of(commands.seek_dock()) is None


def test_what_stands_is_what_was_written_and_not_stopped_by_the_robot_since() -> None:
    """The outbox keeps each channel's last command two ways: what the tree asked for
    (``last_on``, the leaves') and what the runtime wrote and the robot still obeys
    (``standing``, what is sent again after the runtime's own drive 0 or a resume; the
    runner kept a copy of its own). A refused command was asked for and does not stand; the
    robot's own fall stops the wheels and the motors, which the tree still asked for."""
    box = Outbox()
    drive, brushes = commands.drive(200, 0), commands.motors(0b100)
    box.send(drive, NEW)
    box.send(brushes, NEW)
    assert box.last_on("wheels") is drive and dict(box.standing) == {}  # not written yet
    for command in box.drain():
        box.written(command)  # as the runner does for each command the guard lets through
    assert dict(box.standing) == {"wheels": drive, "motors": brushes}
    faster = commands.drive(300, 0)
    box.send(faster, NEW)
    assert box.drain() == [faster]  # and the mode guard refused it: not written
    assert box.last_on("wheels") is faster and box.standing["wheels"] is drive
    box.robot_stopped(("wheels", "motors"))  # a fall to Passive by itself
    assert dict(box.standing) == {} and box.last_on("motors") is brushes
    box.written(brushes)
    box.clear()  # the tree stopped: nothing it sent stands
    assert dict(box.standing) == {} and box.last_on("motors") is None


def test_a_cycle_another_leaf_queued_in_the_tick_is_written_and_ended_before_the_next() -> None:
    """``[spot, seek_dock]`` in one tick: the channel's last command alone kept Seek Dock,
    and Spot was never written. Each keeps its place; the first's cycle is ended between."""
    box = Outbox()
    box.send(commands.leds(0, 0, 255), OLD)
    box.end_queued_cycle(OLD)  # nothing queued on the wheels: nothing to end
    box.send(commands.spot(), OLD)
    box.send(commands.play(0), OLD)
    box.end_queued_cycle(OLD)  # its own: not ended
    box.end_queued_cycle(NEW)
    box.send(commands.seek_dock(), NEW)
    assert [c.name for c in box.drain()] == [
        "leds", "spot", *(c.name for c in CYCLE_END), "play", "seek_dock",
    ]  # fmt: skip
    assert box.last_on("wheels") == commands.seek_dock()
    assert box.last_on("motors") == commands.motors_off()
