"""Hazard confirmation: a hazard onset is shown once the next frame agrees, or at once when
the robot's own fall to Passive agrees; clearing is never delayed. While a bump onset waits,
the connection holds forward motion at 0 (the bump reflex) and gives the command back after."""

from __future__ import annotations

from roomba_bt.oi import commands
from roomba_bt.oi.frames import FrameLayout, SensorFrame, layout_for
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.hazards import HazardConfirmation, drives_forward
from roomba_bt.sim import SimLink, Simulator, load_world

PACKETS = (7, 9, 10, 11, 12, 35)
LAYOUT = layout_for(PACKETS, CREATE2, True)
HALT = bytes((137, 0, 0, 0, 0))


def frame(**values: int) -> SensorFrame:
    base = {7: 0, 9: 0, 10: 0, 11: 0, 12: 0, 35: 2}
    names = {"bumps": 7, "cliff_left": 9, "cliff_front_left": 10}
    names |= {"cliff_front_right": 11, "cliff_right": 12, "mode": 35}
    return LAYOUT.decode(LAYOUT.pack(base | {names[k]: v for k, v in values.items()}))


def test_a_single_frame_hazard_is_never_shown() -> None:
    confirm = HazardConfirmation()
    shown = [confirm.frame(f) for f in (frame(), frame(cliff_front_right=1), frame(), frame())]
    assert not any(f.any_cliff for f in shown)
    assert confirm.held == 1 and confirm.unconfirmed == 1


def test_a_lasting_hazard_is_shown_one_frame_late() -> None:
    confirm = HazardConfirmation()
    stream = [frame(), frame(bumps=0b01), frame(bumps=0b01), frame(bumps=0b01), frame()]
    shown = [confirm.frame(f).any_bump for f in stream]
    assert shown == [False, False, True, True, False]
    assert confirm.unconfirmed == 0


def test_the_robots_own_reaction_confirms_at_once() -> None:
    confirm = HazardConfirmation()
    confirm.frame(frame())
    shown = confirm.frame(frame(cliff_left=1, mode=1), robot_reacted=True)
    assert shown.cliff_left and shown.any_cliff


def test_each_bit_is_confirmed_by_itself() -> None:
    # A bump already confirmed stays shown while a new wheel drop waits for its second frame.
    confirm = HazardConfirmation()
    confirm.frame(frame(bumps=0b01))
    confirm.frame(frame(bumps=0b01))
    held = confirm.frame(frame(bumps=0b0101))
    assert held.any_bump and not held.any_wheel_drop
    assert held[7] == 0b01
    assert confirm.frame(frame(bumps=0b0101)).any_wheel_drop


def test_other_packets_are_untouched_and_no_hazard_costs_no_new_frame() -> None:
    confirm = HazardConfirmation()
    quiet = frame(mode=3)
    assert confirm.frame(quiet) is quiet
    held = confirm.frame(frame(cliff_right=1, mode=3))
    assert held[35] == 3 and held.layout is LAYOUT and not held.cliff_right


def test_a_frame_without_hazard_packets_passes_through() -> None:
    layout = layout_for((35, 43, 44), CREATE2, True)
    only = layout.decode(layout.pack({35: 2, 43: 10, 44: 10}))
    confirm = HazardConfirmation()
    assert confirm.frame(only) is only and confirm.word(only) == 0


def test_a_bump_onset_is_pending_for_the_reflex_a_cliff_is_not() -> None:
    confirm = HazardConfirmation()
    confirm.frame(frame())
    confirm.frame(frame(bumps=0b10))
    assert confirm.bump_pending  # the robot layer holds forward motion for this frame
    confirm.frame(frame(bumps=0b10))
    assert not confirm.bump_pending  # confirmed: the tree sees it now
    confirm.frame(frame(bumps=0b10, cliff_left=1))
    assert confirm.pending and not confirm.bump_pending  # cliffs: confirmed, no reflex


def test_what_the_reflex_holds_is_forward_motion_only() -> None:
    assert drives_forward(commands.drive(200, commands.Radius.STRAIGHT))
    assert drives_forward(commands.drive(150, 500))  # an arc still pushes ahead
    assert drives_forward(commands.drive_direct(100, 50))
    assert drives_forward(commands.drive_pwm(60, 0))
    assert not drives_forward(commands.halt())
    assert not drives_forward(commands.drive(-150, commands.Radius.STRAIGHT))
    assert not drives_forward(commands.spin(200, clockwise=True))  # turning in place
    assert not drives_forward(commands.drive_direct(100, -100))
    assert not drives_forward(commands.clean())  # the cycle reacts to its own bumps


def _safe_connection() -> tuple[Connection, list[bytes]]:
    simulator = Simulator(load_world("empty-room"), CREATE2, 0)
    written: list[bytes] = []

    class Tap(SimLink):
        def write(self, data: bytes) -> None:
            written.append(bytes(data))
            super().write(data)

    connection = Connection(Tap(simulator), CREATE2)
    connection.start(OIMode.SAFE)
    written.clear()
    return connection, written


def test_the_hold_stops_forward_motion_at_once_and_gives_the_command_back() -> None:
    connection, written = _safe_connection()
    forward = commands.drive(200, commands.Radius.STRAIGHT)
    connection.send(forward)
    connection.hold_forward()
    assert written == [forward.data, HALT]  # drive 0 written at once
    connection.hold_forward()  # the same onset's hold: nothing more
    faster = commands.drive(300, commands.Radius.STRAIGHT)
    connection.send(faster)  # the tree, unaware, asks for more: kept, not written
    assert written == [forward.data, HALT]
    assert connection.release_forward() == faster
    assert not connection.forward_held
    connection.send(faster)
    assert written[-1] == faster.data


def test_the_hold_lets_other_wheel_commands_through_and_forgets_the_forward_one() -> None:
    connection, written = _safe_connection()
    connection.send(commands.drive(200, commands.Radius.STRAIGHT))
    connection.hold_forward()
    back = commands.drive(-150, commands.Radius.STRAIGHT)
    connection.send(back)  # the tree's own reaction: written at once
    assert written[-1] == back.data
    assert connection.release_forward() is None  # nothing to send again


def test_a_hold_while_not_driving_forward_writes_nothing() -> None:
    connection, written = _safe_connection()
    connection.send(commands.spin(100, clockwise=False))
    connection.hold_forward()
    assert written == [commands.spin(100, clockwise=False).data]
    assert connection.release_forward() is None


# ---------------------------------------------------------------- the unchanged-frame skip
# HazardConfirmation.frame skips folding the hazard word when the hazard packets' raw values
# are those of the frame before: the outcome must be the one of folding every frame.

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

OTHER_LAYOUT = layout_for((12, 35, 7, 43, 44), CREATE2, True)  # fewer cliffs, other slots


class FoldEveryFrame(HazardConfirmation):
    """The same confirmation with its skip turned off: the hazard packets' values it reads
    never equal the frame before's, so every frame's word is folded."""

    def _bind(self, layout: FrameLayout) -> None:
        super()._bind(layout)
        self._raw = lambda values: object()


FRAMES = st.tuples(
    st.integers(0, 15), st.integers(0, 1), st.integers(0, 1), st.booleans(), st.booleans()
)


@settings(max_examples=300, deadline=None)
@given(st.lists(FRAMES, min_size=1, max_size=40))
def test_skipping_unchanged_frames_changes_nothing(
    stream: list[tuple[int, int, int, bool, bool]],
) -> None:
    confirm, reference = HazardConfirmation(), FoldEveryFrame()
    for bumps, cliff_a, cliff_b, other_layout, reacted in stream:
        if other_layout:  # a new stream's layout: the values before it do not compare
            values = {7: bumps, 12: cliff_a, 35: 2, 43: 5, 44: 5}
            shown = confirm.frame(OTHER_LAYOUT.decode(OTHER_LAYOUT.pack(values)), reacted)
            expected = reference.frame(OTHER_LAYOUT.decode(OTHER_LAYOUT.pack(values)), reacted)
        else:
            shown = confirm.frame(
                frame(bumps=bumps, cliff_left=cliff_a, cliff_right=cliff_b), reacted
            )
            expected = reference.frame(
                frame(bumps=bumps, cliff_left=cliff_a, cliff_right=cliff_b), reacted
            )
        assert shown.values == expected.values
        assert (confirm.pending, confirm.held, confirm.unconfirmed) == (
            reference.pending,
            reference.held,
            reference.unconfirmed,
        )


def test_a_new_layout_is_compared_afresh() -> None:
    """The same raw values at the same slots of another layout are not "the frame before":
    a cliff on the right after one on the left is new, and held back."""
    left, right = layout_for((7, 9, 35), CREATE2, True), layout_for((7, 12, 35), CREATE2, True)
    confirm = HazardConfirmation()
    confirm.frame(left.decode(left.pack({7: 0, 9: 1, 35: 2})))
    assert confirm.frame(left.decode(left.pack({7: 0, 9: 1, 35: 2}))).cliff_left  # confirmed
    switched = confirm.frame(right.decode(right.pack({7: 0, 12: 1, 35: 2})))
    assert not switched.cliff_right and confirm.held == 2


def test_what_sets_the_robot_going_reads_the_motors_run_bits_not_their_directions() -> None:
    """Motors (138) bits 3-4 only set the brushes' directions: a terminate writing them alone
    is not held as setting the robot going (it was: 'would set the robot going')."""
    from roomba_bt.oi import commands as C
    from roomba_bt.oi.bits import motor_bits
    from roomba_bt.robot.hazards import sets_going

    directions = motor_bits(side_brush_clockwise=True, main_brush_outward=True)
    assert not sets_going(C.motors(directions))
    assert sets_going(C.motors(directions | motor_bits(vacuum=True)))
    assert not sets_going(C.motors_off()) and not sets_going(C.pwm_motors(0, 0, 0))
    assert sets_going(C.pwm_motors(0, 0, 40)) and sets_going(C.clean())
    assert sets_going(C.drive(100, 32767)) and not sets_going(C.drive(0, 1))
