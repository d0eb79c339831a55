"""OI modes as the robot reports them in packet 35."""

from __future__ import annotations

from enum import IntEnum


class OIMode(IntEnum):
    """The four Open Interface modes; the value is what packet 35 carries."""

    OFF = 0
    PASSIVE = 1
    SAFE = 2
    FULL = 3

    @property
    def label(self) -> str:
        return self.name.capitalize()


ALL_MODES: frozenset[OIMode] = frozenset(OIMode)
OPEN_MODES: frozenset[OIMode] = frozenset({OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL})
DRIVING_MODES: frozenset[OIMode] = frozenset({OIMode.SAFE, OIMode.FULL})
