"""Kept for old imports: the compiler's tree is :mod:`roomba_bt.mission.plan` (``ir`` read
as infrared in a robot's package; ``CompiledMission.plan`` names it)."""

from roomba_bt.mission.plan import KeyDecl, Node

__all__ = ["KeyDecl", "Node"]
