"""Round trips (hypothesis): commands whose values the robot echoes in sensor packets, any
packet list packed and decoded, and every command encoded and read back by the robot's side."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt.oi import commands as c
from roomba_bt.oi.encode import Command, Radius, decode_command, encode
from roomba_bt.oi.errors import EncodeError
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.opcodes import COMMANDS, ArgSpec, CommandSpec
from roomba_bt.oi.packets import VALID_PACKET_IDS, expand
from roomba_bt.oi.profiles import PROFILES, RobotProfile
from roomba_bt.oi.stream import StreamParser, decode_reply

velocities = st.integers(-500, 500)
radii = st.one_of(
    st.integers(-2000, 2000), st.sampled_from([Radius.STRAIGHT, Radius.STRAIGHT_ALT, 32768])
)
profiles = st.sampled_from(list(PROFILES.values()))


@given(velocity=velocities, radius=radii)
def test_drive_is_echoed_in_packets_39_and_40(velocity: int, radius: int) -> None:
    # The robot reports the requested velocity and radius with the same bytes it received.
    command = c.drive(velocity, radius)
    echo = decode_reply([39, 40], command.data[1:5])
    assert echo.requested_velocity == velocity
    expected = radius if -2000 <= radius <= 2000 else {0x8000: -32768, 0x7FFF: 32767}[radius]
    assert echo.requested_radius == expected


@given(right=velocities, left=velocities)
def test_drive_direct_is_echoed_in_packets_41_and_42(right: int, left: int) -> None:
    echo = decode_reply([41, 42], c.drive_direct(right, left).data[1:5])
    assert (echo.requested_right_velocity, echo.requested_left_velocity) == (right, left)


@st.composite
def packet_values(draw: st.DrawFn) -> tuple[tuple[int, ...], RobotProfile, dict[int, int]]:
    ids = tuple(draw(st.lists(st.sampled_from(sorted(VALID_PACKET_IDS)), min_size=1, max_size=6)))
    profile = draw(profiles)
    values: dict[int, int] = {}
    for pid in ids:
        for member in expand(pid):
            spec = profile.packet(member)
            values.setdefault(member, draw(st.integers(spec.minimum, spec.maximum)))
    return ids, profile, values


@settings(max_examples=300)
@given(case=packet_values())
def test_pack_then_decode_gives_the_values_back(
    case: tuple[tuple[int, ...], RobotProfile, dict[int, int]],
) -> None:
    ids, profile, values = case
    reply = layout_for(ids, profile, False)
    assert dict(reply.decode(reply.pack(values))) == values
    stream = layout_for(ids, profile, True)
    frame = stream.stream_frame(values, include_header=profile.checksum_includes_header)
    # values drawn from the table (packet 35: 0-3): the parser told the offset is 0
    (decoded,) = StreamParser(ids, profile, mode_plus_one=False).feed(frame)
    assert dict(decoded) == values


def _arg_values(arg: ArgSpec) -> st.SearchStrategy[int]:
    if arg.choices is not None:
        return st.sampled_from(sorted(arg.choices))
    return st.integers(arg.minimum, arg.maximum)


@st.composite
def any_command(draw: st.DrawFn) -> tuple[CommandSpec, list[int], list[int]]:
    spec = draw(st.sampled_from(list(COMMANDS.values())))
    args = [draw(_arg_values(a)) for a in spec.args]
    if spec.opcode == 137 and draw(st.booleans()):
        args[1] = draw(st.sampled_from([32768, 32767, -1, 1]))
    if spec.tail is not None and spec.tail.count_arg == "packet_count":
        args[0] = draw(st.integers(0 if spec.opcode == 148 else 1, 8))
    tail: list[int] = []
    if spec.tail is not None:
        item = spec.tail.item
        tail = [draw(_arg_values(item[i % len(item)])) for i in range(spec.tail_bytes(args))]
    return spec, args, tail


@settings(max_examples=500)
@given(case=any_command())
def test_every_command_round_trips_through_the_robots_reader(
    case: tuple[CommandSpec, list[int], list[int]],
) -> None:
    spec, args, tail = case
    command = encode(spec, *args, tail=tail)
    assert len(command.data) == 1 + spec.data_bytes(args)  # never a short command
    decoded = decode_command(command.data)
    assert decoded == (command, len(command.data))


#: values an argument may be given besides those it accepts: any width of integer, the
#: edges of the tables' ranges, and what is not an int
_ODD_VALUE = st.one_of(
    st.integers(-70000, 70000),
    st.sampled_from([-500, 500, -501, 501, 0, 255, 256, -128, 127, True, False, Radius.STRAIGHT]),
    st.sampled_from([1.0, "1", None]),
)


@st.composite
def any_arguments(draw: st.DrawFn) -> tuple[CommandSpec, list[object]]:
    """A command and values for it: mostly as many as it takes, each often one it accepts."""
    spec = draw(st.sampled_from(list(COMMANDS.values())))
    if draw(st.integers(0, 5)) == 0:
        return spec, draw(st.lists(_ODD_VALUE, max_size=16))
    return spec, [draw(st.one_of(_arg_values(a), _ODD_VALUE)) for a in spec.args]


@settings(max_examples=1000)
@given(case=any_arguments())
def test_encoding_by_opcode_agrees_with_the_table_entrys_full_checks(
    case: tuple[CommandSpec, list[object]],
) -> None:
    # encode(opcode, ...) packs a command of fixed arguments by its prepared form; given the
    # table's entry itself it checks in full: the same command or the same error either way
    spec, args = case

    def outcome(command: int | CommandSpec) -> object:
        try:
            return encode(command, *args)  # type: ignore[arg-type]
        except EncodeError as exc:
            return ("error", str(exc))

    by_opcode, in_full = outcome(spec.opcode), outcome(spec)
    assert by_opcode == in_full
    if isinstance(by_opcode, Command) and isinstance(in_full, Command):
        assert [type(a) for a in by_opcode.args] == [type(a) for a in in_full.args]
