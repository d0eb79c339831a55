"""Hazard confirmation: a hazard onset is shown once the next frame agrees, or at once when
the robot's own fall to Passive agrees; clearing is never delayed."""

from __future__ import annotations

from roomba_bt.oi.frames import SensorFrame, layout_for
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.robot.hazards import HazardConfirmation

PACKETS = (7, 9, 10, 11, 12, 35)
LAYOUT = layout_for(PACKETS, CREATE2, True)


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
