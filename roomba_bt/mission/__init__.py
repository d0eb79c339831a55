"""Missions: YAML compiled into py_trees behaviour trees, checked before anything moves.

    mission = load_mission("missions/examples/square.yaml", {"side": "50cm"})
    mission.setup(robot)              # the robot handle reaches every leaf
    mission.root.tick_once()          # once per 15 ms stream frame (the runtime does this)

:func:`load_mission` raises :class:`MissionError` with every :class:`Diagnostic` at once;
:func:`validate_files` returns them (:func:`validate_file`: one file's, and the files it
includes). Never opens a port. The compiler's pipeline, from the file to the tree, is
:mod:`roomba_bt.mission.compiler`; this package names its front door.
"""

from roomba_bt.mission.build import CompiledMission
from roomba_bt.mission.checks import RUNTIME_PACKETS
from roomba_bt.mission.compiler import (
    compile_mission,
    load_mission,
    load_mission_text,
    validate_file,
    validate_files,
)
from roomba_bt.mission.diagnostics import (
    Diagnostic,
    IncludeSite,
    MissionError,
    SubtreeUse,
    reported,
)
from roomba_bt.mission.loader import NO_PERMISSIONS, SHIPPED_LIBRARY, Permissions

__all__ = [
    "RUNTIME_PACKETS",
    "CompiledMission",
    "Diagnostic",
    "IncludeSite",
    "NO_PERMISSIONS",
    "MissionError",
    "Permissions",
    "SHIPPED_LIBRARY",
    "SubtreeUse",
    "compile_mission",
    "load_mission",
    "load_mission_text",
    "reported",
    "validate_file",
    "validate_files",
]
