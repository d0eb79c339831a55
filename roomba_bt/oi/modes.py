"""OI modes as the robot reports them in packet 35.

The machine that predicts and reconciles them (which command leads where, what each mode
accepts, the falls to Passive) is :class:`~roomba_bt.robot.modes.ModeModel` in
``robot/modes.py``, built from the opcode table's ``modes`` and ``leads_to``.
"""

from __future__ import annotations

from enum import IntEnum

from roomba_bt.oi.packets import PACKETS_BY_NAME

#: The sensor packet that carries the mode: 35, ``oi_mode`` in the packet table.
OI_MODE_PACKET: int = PACKETS_BY_NAME["oi_mode"].id


class OIMode(IntEnum):
    """The four Open Interface modes; the value is what packet 35 carries."""

    OFF = 0
    PASSIVE = 1
    SAFE = 2
    FULL = 3

    @property
    def label(self) -> str:
        return self.name.capitalize()

    def __str__(self) -> str:
        # ``print(robot.mode)`` printed 2 (an IntEnum's str is its number since Python 3.11)
        return self.label

    def __format__(self, spec: str) -> str:
        return self.label if not spec else int.__format__(self, spec)


ALL_MODES: frozenset[OIMode] = frozenset(OIMode)
OPEN_MODES: frozenset[OIMode] = frozenset({OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL})
DRIVING_MODES: frozenset[OIMode] = frozenset({OIMode.SAFE, OIMode.FULL})


def mode_from_packet(raw: int, plus_one: bool = False) -> OIMode | None:
    """The mode packet 35 reports, or ``None`` if ``raw`` cannot be a mode.

    ``plus_one`` undoes the firmware bug of some Roomba 600s, which report mode + 1
    (1 = Off ... 4 = Full); deciding *whether* a robot has the bug is the robot layer's job
    (``RobotProfile.reports_mode_plus_one`` and what it observes). Never raises."""
    value = raw - 1 if plus_one else raw
    return OIMode(value) if 0 <= value <= 3 else None
