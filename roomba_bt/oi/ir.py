"""IR characters (packets 17, 52, 53) decoded into what sent them.

::

    remote / scheduling remote   129..143          (one button each)
    drive-on charger, 500 & 600  1010 R G V F      160..173   red=bit3 green=bit2 ff=bit0
                                                    (162 alone: the virtual wall)
    Discovery drive-on charger   1111 R G F 0      240..254   red=bit3 green=bit2 ff=bit1
    virtual wall lighthouse      0 LLLL 0 BB       id 1-10 (11 unbound), beam BB:
                                                    00 fence, 01 force field, 10 green, 11 red

The 500 and the 600 specifications both give 160-173 to the drive-on charger sold with those
robots and 240-254 to the older "Discovery" charger; both families decode on every profile,
since any robot may meet either dock. All 256 values are decoded once at import.

A lighthouse's beams carry the spec's names (``red_buoy``, ``green_buoy``, ``force_field``
set from BB, ``virtual_wall`` for the fence) but its characters, 8-91, are none of a dock's:
``from_dock`` tells them apart (the ``ir`` condition's buoy words read docks only).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum


class IRSource(Enum):
    NONE = "none"
    REMOTE = "remote"
    DOCK = "dock"
    DISCOVERY_DOCK = "discovery_dock"
    VIRTUAL_WALL = "virtual_wall"
    LIGHTHOUSE = "lighthouse"
    UNKNOWN = "unknown"


class LighthouseBeam(Enum):
    FENCE = 0
    FORCE_FIELD = 1
    GREEN_BUOY = 2
    RED_BUOY = 3


REMOTE_BUTTONS: dict[int, str] = {
    129: "left",
    130: "forward",
    131: "right",
    132: "spot",
    133: "max",
    134: "small",
    135: "medium",
    136: "clean",
    137: "stop",
    138: "power",
    139: "arc_left",
    140: "arc_right",
    141: "stop",
    142: "download",
    143: "seek_dock",
}


@dataclass(frozen=True, slots=True)
class IRCharacter:
    """One received IR character and its meaning."""

    code: int
    source: IRSource
    red_buoy: bool = False
    green_buoy: bool = False
    force_field: bool = False
    virtual_wall: bool = False
    lighthouse_id: int | None = None
    lighthouse_beam: LighthouseBeam | None = None
    remote_button: str | None = None
    #: sent by a home base (500/600 series or Discovery); stored, not computed: docking
    #: reads it for three receivers on every tick
    from_dock: bool = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        dock = self.source is IRSource.DOCK or self.source is IRSource.DISCOVERY_DOCK
        object.__setattr__(self, "from_dock", dock)

    @property
    def any_buoy(self) -> bool:
        return self.red_buoy or self.green_buoy

    @classmethod
    def decode(cls, code: int) -> IRCharacter:
        return IR_CHARACTERS[code & 0xFF]


def _decode(code: int) -> IRCharacter:
    if code == 0:
        return IRCharacter(0, IRSource.NONE)
    if code in REMOTE_BUTTONS:
        return IRCharacter(code, IRSource.REMOTE, remote_button=REMOTE_BUTTONS[code])
    if code == 162:
        return IRCharacter(code, IRSource.VIRTUAL_WALL, virtual_wall=True)
    if 160 <= code <= 173 and code & 0b10 == 0:
        return IRCharacter(
            code, IRSource.DOCK, red_buoy=bool(code & 8), green_buoy=bool(code & 4),
            force_field=bool(code & 1),
        )  # fmt: skip
    if 240 <= code <= 254 and code & 1 == 0:
        return IRCharacter(
            code, IRSource.DISCOVERY_DOCK, red_buoy=bool(code & 8), green_buoy=bool(code & 4),
            force_field=bool(code & 2),
        )  # fmt: skip
    if code < 128 and code & 0b100 == 0 and 1 <= (code >> 3) <= 11:
        beam = LighthouseBeam(code & 0b11)
        return IRCharacter(
            code,
            IRSource.LIGHTHOUSE,
            red_buoy=beam is LighthouseBeam.RED_BUOY,
            green_buoy=beam is LighthouseBeam.GREEN_BUOY,
            force_field=beam is LighthouseBeam.FORCE_FIELD,
            virtual_wall=beam is LighthouseBeam.FENCE,
            lighthouse_id=code >> 3,
            lighthouse_beam=beam,
        )
    return IRCharacter(code, IRSource.UNKNOWN)


IR_CHARACTERS: tuple[IRCharacter, ...] = tuple(_decode(c) for c in range(256))


def dock_character(*, red: bool, green: bool, force_field: bool, discovery: bool = False) -> int:
    """The character a dock sends for a combination of beams (0 if none): the simulator's
    side of the table above."""
    if not (red or green or force_field):
        return 0
    if discovery:
        return 240 | red << 3 | green << 2 | force_field << 1
    return 160 | red << 3 | green << 2 | force_field


def lighthouse_character(lighthouse_id: int, beam: LighthouseBeam) -> int:
    return (lighthouse_id & 0xF) << 3 | beam.value
