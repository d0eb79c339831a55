"""The traps of GUIDE.md §4 and the bit layouts of both specs, one test each."""

from __future__ import annotations

import math

import pytest

from roomba_bt.oi.bits import (
    DIGIT_ASCII,
    BumpsWheelDrops,
    Buttons,
    ChargingSources,
    LightBumper,
    Overcurrents,
)
from roomba_bt.oi.ir import (
    IR_CHARACTERS,
    REMOTE_BUTTONS,
    IRCharacter,
    IRSource,
    LighthouseBeam,
    dock_character,
    lighthouse_character,
)
from roomba_bt.oi.modes import OIMode, mode_from_packet
from roomba_bt.oi.odometry import (
    MM_PER_COUNT,
    arc_from_wheels,
    corrected_old_angle,
    counts_to_mm,
    encoder_delta,
    mm_to_counts,
)
from roomba_bt.oi.profiles import (
    CREATE2,
    PROFILES,
    ROOMBA500,
    ROOMBA600,
    WHEEL_BASE_MM,
    command_warning,
    get_profile,
)

# -- packet 7 and packet 14: peers have both wrong ----------------------------------------


def test_packet_7_bit_0_is_bump_right() -> None:
    assert BumpsWheelDrops.from_byte(0b0001).bump_right
    assert not BumpsWheelDrops.from_byte(0b0001).bump_left
    assert BumpsWheelDrops.from_byte(0b0010).bump_left
    assert BumpsWheelDrops.from_byte(0b0100).wheel_drop_right
    assert BumpsWheelDrops.from_byte(0b1000).wheel_drop_left
    assert BumpsWheelDrops.from_byte(0b0011).any_bump
    assert not BumpsWheelDrops.from_byte(0b1100).any_bump
    assert BumpsWheelDrops.from_byte(0b1100).any_wheel_drop


@pytest.mark.parametrize(
    ("bit", "field"),
    [(0, "side_brush"), (2, "main_brush"), (3, "right_wheel"), (4, "left_wheel")],
)
def test_packet_14_bits(bit: int, field: str) -> None:
    oc = Overcurrents.from_byte(1 << bit)
    flags = {f: getattr(oc, f) for f in ("side_brush", "main_brush", "right_wheel", "left_wheel")}
    assert flags == {f: f == field for f in flags}
    assert oc.any


def test_packet_14_bit_1_is_reserved() -> None:
    assert not Overcurrents.from_byte(0b10).any


def test_other_bit_fields() -> None:
    assert Buttons.from_byte(0b1000_0000).clock and Buttons.from_byte(0b100).dock
    assert ChargingSources.from_byte(1).internal_charger
    assert ChargingSources.from_byte(2).home_base
    assert LightBumper.from_byte(1 << 5).right and LightBumper.from_byte(1).left
    assert not LightBumper.from_byte(0b1100_0000).any  # reserved bits


# -- encoders: deltas modulo 2**16 --------------------------------------------------------


def test_encoder_rollover_forward() -> None:
    assert encoder_delta(65530, 5) == 11  # a well-known driver gets +12


def test_encoder_rollover_backward() -> None:
    assert encoder_delta(5, 65530) == -11  # ... and +65526


def test_encoder_deltas_agree_for_signed_and_unsigned_readings() -> None:
    # The 600 reports -6 where the 500 reports 65530: the same bits.
    assert encoder_delta(-6, 5) == encoder_delta(65530, 5) == 11
    assert encoder_delta(32767, -32768) == 1
    assert encoder_delta(100, 100) == 0


def test_counts_to_mm_uses_the_spec_formula() -> None:
    assert counts_to_mm(1) == MM_PER_COUNT == pytest.approx(math.pi * 72.0 / 508.8)
    assert counts_to_mm(508.8) == pytest.approx(math.pi * 72.0)  # one wheel revolution
    assert mm_to_counts(counts_to_mm(1234)) == pytest.approx(1234)


def test_angle_from_wheel_distances_and_the_wheel_base() -> None:
    assert WHEEL_BASE_MM == 235.0
    quarter = math.pi / 2 * WHEEL_BASE_MM / 2
    distance, heading = arc_from_wheels(-quarter, quarter)
    assert distance == pytest.approx(0.0)
    assert heading == pytest.approx(math.pi / 2)  # counter-clockwise positive
    assert arc_from_wheels(100.0, 100.0) == (100.0, 0.0)


def test_old_firmware_angle_correction() -> None:
    assert corrected_old_angle(29) == pytest.approx(29 / 0.324056)


# -- OI mode + 1 ----------------------------------------------------------------------------


def test_the_mode_plus_one_flag_exists_per_profile() -> None:
    assert ROOMBA600.reports_mode_plus_one
    assert not CREATE2.reports_mode_plus_one
    assert not ROOMBA500.reports_mode_plus_one


def test_mode_from_packet() -> None:
    assert [mode_from_packet(r) for r in range(4)] == list(OIMode)
    assert [mode_from_packet(r, plus_one=True) for r in range(1, 5)] == list(OIMode)
    assert mode_from_packet(4) is None
    assert mode_from_packet(0, plus_one=True) is None
    assert mode_from_packet(255) is None


# -- IR characters ---------------------------------------------------------------------------

#: The drive-on chargers' characters, by the beams seen (red buoy, green buoy, force field):
#: the Roomba 500/600 charger's (both specs' table) and the Roomba Discovery charger's.
DOCK_CHARACTERS = {
    # red, green, force field: 500/600, Discovery
    (False, False, True): (161, 242),
    (False, True, False): (164, 244),
    (False, True, True): (165, 246),
    (True, False, False): (168, 248),
    (True, False, True): (169, 250),
    (True, True, False): (172, 252),
    (True, True, True): (173, 254),
}


def _beams_id(beams: tuple[bool, bool, bool]) -> str:
    return "+".join(
        name for name, on in zip(("red", "green", "force_field"), beams, strict=True) if on
    )


@pytest.mark.parametrize("beams", DOCK_CHARACTERS, ids=_beams_id)
@pytest.mark.parametrize(
    ("discovery", "source"),
    [
        pytest.param(False, IRSource.DOCK, id="600"),
        pytest.param(True, IRSource.DISCOVERY_DOCK, id="discovery"),
    ],
)
def test_dock_characters(beams: tuple[bool, bool, bool], discovery: bool, source: IRSource) -> None:
    code = DOCK_CHARACTERS[beams][discovery]
    ch = IRCharacter.decode(code)
    assert ch.source is source and ch.from_dock
    assert (ch.red_buoy, ch.green_buoy, ch.force_field) == beams
    red, green, force_field = beams
    assert (
        dock_character(red=red, green=green, force_field=force_field, discovery=discovery) == code
    )


def test_no_beam_is_no_character() -> None:
    assert dock_character(red=False, green=False, force_field=False) == 0
    assert IRCharacter.decode(0).source is IRSource.NONE


def test_162_is_the_virtual_wall_not_a_dock() -> None:
    ch = IRCharacter.decode(162)
    assert ch.source is IRSource.VIRTUAL_WALL and ch.virtual_wall and not ch.from_dock


def test_remote_buttons() -> None:
    assert set(REMOTE_BUTTONS) == set(range(129, 144))
    assert IRCharacter.decode(130).remote_button == "forward"
    assert IRCharacter.decode(143).remote_button == "seek_dock"
    assert IRCharacter.decode(136).remote_button == "clean"
    assert all(IR_CHARACTERS[c].source is IRSource.REMOTE for c in range(129, 144))


@pytest.mark.parametrize("lighthouse_id", range(1, 12))
@pytest.mark.parametrize("beam", list(LighthouseBeam))
def test_lighthouse_0LLLL0BB(lighthouse_id: int, beam: LighthouseBeam) -> None:
    code = lighthouse_character(lighthouse_id, beam)
    assert code == lighthouse_id << 3 | beam.value and code < 128 and not code & 0b100
    ch = IRCharacter.decode(code)
    assert ch.source is IRSource.LIGHTHOUSE
    assert (ch.lighthouse_id, ch.lighthouse_beam) == (lighthouse_id, beam)
    assert ch.red_buoy == (beam is LighthouseBeam.RED_BUOY)
    assert ch.green_buoy == (beam is LighthouseBeam.GREEN_BUOY)
    assert ch.force_field == (beam is LighthouseBeam.FORCE_FIELD)
    assert ch.virtual_wall == (beam is LighthouseBeam.FENCE)


def test_reserved_and_unknown_characters_do_not_crash() -> None:
    for code in (0b0110_0000 | 1, 0b0000_0100 | 8, 163, 166, 200, 255, 128):
        assert IRCharacter.decode(code).source is IRSource.UNKNOWN
    assert len(IR_CHARACTERS) == 256
    assert IRCharacter.decode(0x1A8).code == 0xA8  # only the low byte is a character


# -- profiles ----------------------------------------------------------------------------------


def test_reset_and_stop_exist_only_on_600_and_create2() -> None:
    from roomba_bt.oi.errors import UnsupportedCommandError

    for opcode in (7, 173):
        assert CREATE2.has_command(opcode) and ROOMBA600.has_command(opcode)
        assert not ROOMBA500.has_command(opcode)
        CREATE2.check_supported(opcode)
        with pytest.raises(UnsupportedCommandError, match="not available on roomba500"):
            ROOMBA500.check_supported(opcode)
    assert 7 not in {c.opcode for c in ROOMBA500.commands}
    assert len(CREATE2.commands) == len(ROOMBA500.commands) + 2


def test_command_unavailable_names_the_model_and_where_it_exists() -> None:
    """What validation says at a node declaring Reset or Stop for a Roomba 500."""
    assert ROOMBA500.command_unavailable("reset") == (
        "reset (7) is not available on the Roomba 500 series (roomba500); it exists on "
        "create2, roomba600"
    )
    assert ROOMBA500.command_unavailable(173) is not None
    for profile in (CREATE2, ROOMBA600, ROOMBA500):
        assert profile.command_unavailable("digit_leds_raw") is None  # a warning, not this
    assert CREATE2.command_unavailable("reset") is None


def test_digit_leds_raw_warning_text() -> None:
    """Every profile warns, the Roomba 500 too: the 600 / Create 2 spec (the newer) says 163
    "does not work in current Create 2 and Roomba 500/600 firmware versions"."""
    for profile in (CREATE2, ROOMBA600, ROOMBA500):
        text = command_warning(163, profile)
        assert text is not None and "163" in text and "164" in text, profile.name
        assert f"does not work on current {profile.title} firmware" in text
        assert "Roomba 500/600 firmware versions" in text
        assert profile.command_warning("digit_leds_raw") == text
    assert all(command_warning(op, CREATE2) is None for op in (137, 164, 128))


def test_unknown_profile_lists_the_known_ones() -> None:
    assert get_profile("roomba500") is ROOMBA500
    with pytest.raises(ValueError, match="unknown robot profile 'roomba700'; known profiles: "):
        get_profile("roomba700")
    assert set(PROFILES) == {"create2", "roomba600", "roomba500"}


def test_profile_packet_ranges() -> None:
    assert CREATE2.packet(58).maximum == 3 and ROOMBA500.packet(58).maximum == 1
    assert CREATE2.packet(27).maximum == 1023 and ROOMBA500.packet(27).maximum == 4095
    assert CREATE2.packet(43).signed and not ROOMBA500.packet(43).signed


def test_digit_ascii_table_omits_star_plus_at() -> None:
    missing = set(range(32, 127)) - set(DIGIT_ASCII)
    assert missing == {ord("*"), ord("+"), ord("@")}


# -- the mode table ----------------------------------------------------------------------------


def test_mode_rules_in_the_opcode_table() -> None:
    from roomba_bt.oi.opcodes import COMMANDS

    assert OIMode.OFF in COMMANDS[128].modes  # Start is the way out of Off
    assert COMMANDS[128].leads_to is OIMode.PASSIVE
    assert COMMANDS[7].modes == frozenset(OIMode)  # Reset: "always available"
    assert COMMANDS[7].leads_to is COMMANDS[173].leads_to is OIMode.OFF
    for opcode in (130, 131):
        assert COMMANDS[opcode].leads_to is OIMode.SAFE
    assert COMMANDS[132].leads_to is OIMode.FULL
    for opcode in (133, 134, 135, 136, 143):
        assert COMMANDS[opcode].leads_to is OIMode.PASSIVE
    actuators = {137, 138, 139, 141, 144, 145, 146, 162, 163, 164}
    assert {op for op, spec in COMMANDS.items() if spec.is_actuator} == actuators
    for opcode in actuators:
        assert COMMANDS[opcode].modes == {OIMode.SAFE, OIMode.FULL}
    for spec in COMMANDS.values():
        if spec.opcode not in (7, 128):
            assert OIMode.OFF not in spec.modes, spec.name


def test_effects_in_the_opcode_table() -> None:
    """What each command does to the link besides its mode, as the specs describe it."""
    from roomba_bt.oi.opcodes import COMMANDS, Effect

    effects = {op: spec.effect for op, spec in COMMANDS.items() if spec.effect is not None}
    assert effects == {
        7: Effect.SILENCES,
        129: Effect.BAUD,
        133: Effect.POWER_DOWN,
        134: Effect.BUILTIN_CYCLE,
        135: Effect.BUILTIN_CYCLE,
        136: Effect.BUILTIN_CYCLE,
        142: Effect.QUERY,
        143: Effect.BUILTIN_CYCLE,
        148: Effect.STREAM,
        149: Effect.QUERY,
        150: Effect.PAUSE_RESUME,
        173: Effect.SILENCES,
    }
    # Safe, Full (and Control) take the wheels from a cycle; Reset and Stop end the OI. Start
    # and the cycles themselves lead to Passive, where a cycle may still drive.
    assert {op for op, spec in COMMANDS.items() if spec.ends_cycle} == {7, 130, 131, 132, 173}


def test_packet_id_arguments_accept_exactly_the_packet_table_ids() -> None:
    from roomba_bt.oi.opcodes import COMMANDS
    from roomba_bt.oi.packets import GROUPS, PACKETS

    known = set(PACKETS) | set(GROUPS)
    for opcode in (142, 148, 149):
        spec = COMMANDS[opcode]
        arg = spec.args[0] if spec.tail is None else spec.tail.item[0]
        assert {v for v in range(256) if arg.accepts(v)} == known, spec.name
