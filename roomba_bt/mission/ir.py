"""Kept for old imports until 0.3.0: the compiler's tree is :mod:`roomba_bt.mission.plan`
(``ir`` read as infrared in a robot's package; ``CompiledMission.plan`` names it). Importing
this warns, so a program written for 0.1.0 learns the new path before it goes."""

from roomba_bt._lazy import warn_moved_module
from roomba_bt.mission.plan import KeyDecl, Node

__all__ = ["KeyDecl", "Node"]

warn_moved_module("roomba_bt.mission.ir", "import from roomba_bt.mission.plan instead")
