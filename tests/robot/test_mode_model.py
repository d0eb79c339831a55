"""The mode model: built from the opcode table, the guard, packet 35 reconciliation, the
"mode + 1" rule, and the generated diagram in docs/modes.md."""

from __future__ import annotations

import pathlib
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from transitions import MachineError

from roomba_bt.oi import commands as oi
from roomba_bt.oi.errors import UnsupportedCommandError
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import COMMANDS, MODE_COMMANDS
from roomba_bt.oi.profiles import CREATE2, PROFILES, ROOMBA500, ROOMBA600
from roomba_bt.robot.docgen import mermaid, render_modes_doc
from roomba_bt.robot.errors import ModeError, format_wall_time
from roomba_bt.robot.interface import ModeChange
from roomba_bt.robot.modes import ModeModel, infer_cause

DOCS = pathlib.Path(__file__).resolve().parents[2] / "docs" / "modes.md"
NOON = time.mktime((2026, 11, 22, 12, 1, 3, 0, 0, -1)) + 0.120


def frame(values: dict[int, int]):  # type: ignore[no-untyped-def]
    ids = tuple(sorted(values))
    layout = layout_for(ids, CREATE2, False)
    return layout.decode(layout.pack(values))


def model_in(mode: OIMode, profile=CREATE2, **kwargs):  # type: ignore[no-untyped-def]
    model = ModeModel(profile, wall_clock=lambda: NOON, **kwargs)
    model.apply(oi.start(), 0.0)
    assert model.calibrate(1, 0.0)  # no "mode + 1"
    if mode is OIMode.SAFE:
        model.apply(oi.safe(), 0.0)
    elif mode is OIMode.FULL:
        model.apply(oi.full(), 0.0)
    model.reconcile(frame({35: int(mode)}), 1, 0.015)
    assert model.mode is mode
    return model


def fall(model, values: dict[int, int], tick: int, time: float):  # type: ignore[no-untyped-def]
    """A change the robot made by itself, reported by two consecutive frames: the first
    changes nothing, the second is the change."""
    assert model.reconcile(frame(values), tick, time) is None
    return model.reconcile(frame(values), tick + 1, time + 0.015)


# ------------------------------------------------------------------ the machine


@pytest.mark.parametrize("profile", list(PROFILES.values()), ids=list(PROFILES))
def test_every_mode_command_of_the_profile_is_a_trigger_from_the_table(profile) -> None:  # type: ignore[no-untyped-def]
    machine = ModeModel(profile).machine
    for spec in MODE_COMMANDS:
        if profile.name not in spec.profiles:
            assert spec.name not in machine.events
            continue
        transitions = machine.events[spec.name].transitions
        assert set(transitions) == {m.label for m in spec.modes}
        assert {t.dest for ts in transitions.values() for t in ts} == {spec.leads_to.label}


def test_no_automatic_transitions_exist() -> None:
    machine = ModeModel().machine
    assert not [name for name in machine.events if name.startswith("to_")]


def test_off_accepts_start_and_reset_only() -> None:
    model = ModeModel(CREATE2)
    accepted = {spec.name for spec in CREATE2.commands if model.allows(spec)}
    assert accepted == {"start", "reset"}
    with pytest.raises(ModeError, match="safe needs Passive, Safe or Full; the robot is in Off"):
        model.check(oi.safe())


@pytest.mark.parametrize("spec", [s for s in COMMANDS.values() if s.modes == DRIVING_MODES])
def test_every_actuator_is_refused_in_passive_and_accepted_in_safe_and_full(spec) -> None:  # type: ignore[no-untyped-def]
    if not CREATE2.has_command(spec):
        pytest.skip("not on create2")
    refusal = f"^{spec.name} needs Safe or Full; the robot is in Passive"
    with pytest.raises(ModeError, match=refusal):
        model_in(OIMode.PASSIVE).check(spec)
    model_in(OIMode.SAFE).check(spec)
    model_in(OIMode.FULL).check(spec)


def test_commands_the_profile_lacks_raise_unsupported() -> None:
    model = model_in(OIMode.SAFE, ROOMBA500)
    with pytest.raises(UnsupportedCommandError, match="stop is not available on roomba500"):
        model.check(oi.stop())
    with pytest.raises(UnsupportedCommandError):
        model.check(oi.reset())


def test_mode_commands_move_the_model() -> None:
    model = model_in(OIMode.PASSIVE)
    model.apply(oi.full(), 1.0)
    assert model.mode is OIMode.FULL and model.state == "Full"
    model.apply(oi.seek_dock(), 2.0)
    assert model.mode is OIMode.PASSIVE
    model.apply(oi.stop(), 3.0)
    assert model.mode is OIMode.OFF


def test_models_of_one_profile_share_the_machine_but_each_has_its_own_mode() -> None:
    """The machine is built once per profile; the state it moves is each model's own."""
    first, second = model_in(OIMode.SAFE), model_in(OIMode.PASSIVE)
    assert first.machine is second.machine
    assert first.machine is not model_in(OIMode.PASSIVE, ROOMBA500).machine
    first.apply(oi.full(), 1.0)
    second.force(OIMode.OFF, 1.0)
    assert (first.mode, first.state) == (OIMode.FULL, "Full")
    assert (second.mode, second.state) == (OIMode.OFF, "Off")
    assert ModeModel(CREATE2, initial=OIMode.SAFE).state == "Safe"
    saved = first.snapshot()
    first.apply(oi.seek_dock(), 2.0)
    second.apply(oi.start(), 2.0)
    first.restore(saved)
    assert (first.mode, first.state, second.state) == (OIMode.FULL, "Full", "Passive")
    # a trigger from a state that has none is the machine's error, as before
    with pytest.raises(MachineError, match="Can't trigger event safe from state Off"):
        ModeModel(CREATE2)._fire("safe", OIMode.SAFE, 0.0, None)
    with pytest.raises(AttributeError, match="Do not know event named 'reset'"):
        model_in(OIMode.PASSIVE, ROOMBA500)._fire("reset", OIMode.OFF, 0.0, None)


# ------------------------------------------------------------------ reconciliation


def test_packet_35_is_read_at_its_slot_in_each_layout_as_the_layout_changes() -> None:
    """The model finds packet 35's slot once per layout: a frame of another layout (35 at
    another slot, or not carried) is read at its own slot, not the last layout's."""
    model = model_in(OIMode.SAFE)  # reconciled a frame of 35 alone: its slot 0
    # 35 at slot 1 now, slot 0 holding 2 (what Safe would read at the old slot)
    assert model.reconcile(frame({22: 2, 35: 1}), 2, 0.03) is None  # one frame: unconfirmed
    assert model.reconcile(frame({22: 2}), 3, 0.045) is None  # no packet 35: nothing read
    assert model.mode is OIMode.SAFE
    change = model.reconcile(frame({22: 2, 35: 1}), 4, 0.06)  # the second report: followed
    assert change is not None
    assert (change.previous, change.current) == (OIMode.SAFE, OIMode.PASSIVE)
    assert model.reconcile(frame({35: 1}), 5, 0.075) is None  # back to 35 at slot 0
    assert model.mode is OIMode.PASSIVE


def test_fall_back_with_wheel_drop_is_a_transition_with_cause_and_message() -> None:
    model = model_in(OIMode.SAFE)
    change = model.reconcile(frame({7: 0b1000, 35: 1}), 40, 0.6)  # explained: followed at once
    assert change is not None
    assert (change.previous, change.current, change.cause) == (
        OIMode.SAFE,
        OIMode.PASSIVE,
        "wheel drop",
    )
    assert (change.tick, change.time) == (40, 0.6)
    assert model.last_fallback == change
    assert model.state == "Passive"
    with pytest.raises(ModeError) as refused:
        model.check(oi.drive(100, 0))
    assert str(refused.value) == (
        "drive needs Safe or Full; the robot is in Passive since 12:01:03.120, after a wheel drop"
    )


@pytest.mark.parametrize(
    ("values", "cause"),
    [
        ({9: 1}, "cliff"),
        ({12: 1}, "cliff"),
        ({34: 0b10}, "charger"),
        ({34: 0b01}, "internal charger"),  # the wall plug: no dock to undock from
        ({34: 0b11}, "charger"),  # plugged in on the dock: the dock's
        ({7: 0b0011}, "unknown"),  # bumps are no reason to leave Safe
        ({}, "unknown"),
        ({7: 0b0100, 11: 1}, "wheel drop and cliff"),
    ],
)
def test_cause_inferred_from_the_same_frame(values: dict[int, int], cause: str) -> None:
    full = {7: 0, 9: 0, 10: 0, 11: 0, 12: 0, 34: 0, **values, 35: 1}
    model = model_in(OIMode.SAFE)
    change = model.reconcile(frame(full), 5, 0.5)
    if cause == "unknown":  # unexplained: a second frame confirms it
        assert change is None
        change = model.reconcile(frame(full), 6, 0.515)
    assert change is not None and change.cause == cause


def test_cause_taken_from_the_frame_before_when_the_fall_frame_shows_none() -> None:
    model = model_in(OIMode.SAFE)
    model.reconcile(frame({10: 1, 35: 2}), 5, 0.5)
    change = fall(model, {10: 0, 35: 1}, 6, 0.515)
    assert change is not None and change.cause == "cliff"
    assert infer_cause(frame({10: 0})) == "unknown"


def test_old_mode_seen_just_after_a_mode_command_is_not_a_fall() -> None:
    model = model_in(OIMode.PASSIVE)
    model.apply(oi.safe(), 1.0)
    for tick in range(2, 8):  # the robot had not taken it yet: frames every 15 ms
        assert model.reconcile(frame({35: 1}), tick, 1.0 + 0.015 * (tick - 1)) is None
    assert model.mode is OIMode.SAFE
    change = fall(model, {35: 1}, 8, 1.105)  # still Passive after settling: a fall
    assert change is not None and change.current is OIMode.PASSIVE


def test_a_hold_of_the_link_after_a_mode_command_moves_its_settle_on() -> None:
    # a WiFi bridge holds both ways for 250 ms as Start goes out: the frames that waited
    # (Safe, the robot had not heard Start) come at the hold's end, then Passive. The old
    # mode's frames read "went from Passive to Safe by itself", then "from Safe to Passive
    # by itself (unknown)": --strict failed a run that did what it should
    model = model_in(OIMode.SAFE)
    model.apply(oi.start(), 1.0)
    assert model.reconcile(frame({35: 2}), 2, 1.015) is None
    for tick in range(3, 20):  # the backlog, read at once after the hold
        assert model.reconcile(frame({35: 2}), tick, 1.27) is None
    assert model.mode is OIMode.PASSIVE and model.last_fallback is None
    assert model.reconcile(frame({35: 1}), 20, 1.285) is None  # the Start, taken late
    assert model.mode is OIMode.PASSIVE and model.last_fallback is None
    # frames flowing: the settle is over as before, a Safe read then is the robot's own
    for tick in range(21, 40):
        model.reconcile(frame({35: 1}), tick, 1.285 + 0.015 * (tick - 20))
    model.apply(oi.safe(), 2.0)
    for tick in range(40, 60):  # still Passive, every 15 ms, past the settle: a fall
        change = model.reconcile(frame({35: 1}), tick, 2.0 + 0.015 * (tick - 39))
        if change is not None:
            break
    assert change is not None and change.current is OIMode.PASSIVE
    assert change.time == pytest.approx(2.0 + 0.1 + 0.015, abs=0.005)  # two frames past it


def test_unexpected_report_is_followed_and_logged(caplog: pytest.LogCaptureFixture) -> None:
    model = model_in(OIMode.SAFE)
    change = fall(model, {35: 3}, 9, 1.0)  # Full without a command: another client
    assert change is not None and change.current is OIMode.FULL
    assert change.cause == "unexpected report"
    assert "packet 35 reports Full" in caplog.text


# ------------------------------------------------------------------ "mode + 1"


def started(profile=ROOMBA600, raw: int = 2):  # type: ignore[no-untyped-def]
    model = ModeModel(profile)
    model.apply(oi.start(), 0.0)
    assert model.calibrate(raw, 0.01)
    return model


def test_two_right_after_start_means_passive_plus_one() -> None:
    model = started(raw=2)
    assert model.plus_one is True and model.mode is OIMode.PASSIVE
    model.apply(oi.safe(), 0.1)
    assert model.reconcile(frame({35: 3}), 1, 0.12) is None
    assert model.mode is OIMode.SAFE
    change = model.reconcile(frame({35: 2, 9: 1}), 2, 0.5)
    assert change is not None and change.current is OIMode.PASSIVE and change.cause == "cliff"


def test_one_right_after_start_rules_the_bug_out() -> None:
    model = started(raw=1)
    assert model.plus_one is False and model.mode is OIMode.PASSIVE
    model.apply(oi.safe(), 0.1)
    model.reconcile(frame({35: 2}), 1, 0.12)
    assert model.mode is OIMode.SAFE and model.last_fallback is None


@pytest.mark.parametrize("raw", [0, 3, 4, 255])
def test_a_start_up_reply_that_is_no_passive_reading_teaches_nothing(raw: int) -> None:
    model = ModeModel(CREATE2)
    model.apply(oi.start(), 0.0)
    assert not model.calibrate(raw, 0.01)
    assert model.plus_one is None


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600])
def test_a_stream_frame_with_packet_35_four_changes_neither_offset_nor_mode(profile) -> None:  # type: ignore[no-untyped-def]
    """One corrupted frame with 35 = 4 once taught the "mode + 1" offset for good: every later
    Safe read as Passive, drive refused, the safe stop's drive 0 skipped."""
    model = model_in(OIMode.SAFE, profile)
    for tick in range(1, 4):  # even several in a row
        assert model.reconcile(frame({35: 4}), tick, 1.0 + tick * 0.015) is None
    assert model.plus_one is False and model.mode is OIMode.SAFE
    assert model.reconcile(frame({35: 2}), 9, 1.2) is None
    assert model.mode is OIMode.SAFE and model.last_fallback is None
    model.check(oi.drive(100, 0))  # still allowed


def test_one_corrupted_mode_reading_is_not_a_fall() -> None:
    model = model_in(OIMode.SAFE)
    assert model.reconcile(frame({35: 1}), 5, 0.5) is None  # Passive, once
    assert model.reconcile(frame({35: 2}), 6, 0.515) is None  # Safe again
    assert model.reconcile(frame({35: 1}), 7, 0.53) is None  # once more, alone
    assert model.mode is OIMode.SAFE and model.last_fallback is None


def test_readings_are_ignored_until_start_up_calibrates() -> None:
    model = ModeModel(ROOMBA600)
    model.force(OIMode.SAFE)
    for tick, raw in enumerate((2, 3, 4, 1)):
        assert model.reconcile(frame({35: raw}), tick, 1.0 + tick * 0.015) is None
    assert model.mode is OIMode.SAFE and model.plus_one is None
    assert model.invalid_readings == 4


@pytest.mark.parametrize("raw", [0, 5, 17, 255])
def test_values_that_are_no_mode_are_counted_never_raised(raw: int) -> None:
    model = started(raw=1)
    model.apply(oi.safe(), 0.1)
    assert model.reconcile(frame({35: raw}), 1, 1.0) is None
    assert model.mode is OIMode.SAFE
    assert model.invalid_readings == 1


@settings(max_examples=60, deadline=None)
@given(
    raws=st.lists(st.integers(0, 255), max_size=30),
    commands=st.lists(st.sampled_from(["safe", "full", "start", "clean"]), max_size=5),
    profile=st.sampled_from(list(PROFILES.values())),
)
def test_any_packet_35_sequence_keeps_a_valid_mode(raws, commands, profile) -> None:  # type: ignore[no-untyped-def]
    model = ModeModel(profile)
    model.apply(oi.start(), 0.0)
    model.calibrate(2 if profile.reports_mode_plus_one else 1, 0.0)
    t = 0.0
    for i, raw in enumerate(raws):
        if commands and i % 5 == 0:
            model.apply(getattr(oi, commands[i % len(commands)])(), t)
        t += 0.015
        model.reconcile(frame({35: raw}), i, t)
        assert model.mode in (OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL)
        assert model.state == model.mode.label


# ------------------------------------------------------------------ docs


def test_docs_modes_md_is_the_generated_text() -> None:
    assert DOCS.read_text(encoding="utf-8") == render_modes_doc(), (
        "docs/modes.md is stale: run `python -m roomba_bt.robot.docgen docs/modes.md`"
    )


def test_diagram_draws_every_command_transition() -> None:
    text = mermaid(CREATE2)
    assert "Passive --> Safe : control, safe" in text
    assert "Safe --> Passive : start, power, spot, clean, max, seek_dock, fall_back" in text
    assert "Safe --> Off : reset, stop" in text
    assert "stop" not in mermaid(ROOMBA500)


def test_wall_time_format() -> None:
    assert format_wall_time(NOON) == "12:01:03.120"


def test_a_fall_is_to_passive_from_safe_or_full_not_a_resync() -> None:
    """What ``Connection.falls`` (and a run's summary) counts: packet 35 read Safe while the
    model held Passive is followed (a resync), but is no fall."""
    assert ModeChange(OIMode.SAFE, OIMode.PASSIVE, 1, 0.0, "cliff").fall
    assert ModeChange(OIMode.FULL, OIMode.PASSIVE, 1, 0.0, "unknown").fall
    assert not ModeChange(OIMode.PASSIVE, OIMode.SAFE, 1, 0.0, "unexpected report").fall
