"""The byte-exact simulator: a virtual Roomba / Create 2 that speaks the Open Interface.

Imports only :mod:`roomba_bt.oi` and the YAML reader :mod:`roomba_bt.yamlsource` (for world
files), plus the standard library, PyYAML, and matplotlib lazily for plots. Nothing in the
main stack imports it; the CLI, the monitor, the evaluation and the tests do.
"""

from roomba_bt.sim.faults import Faults
from roomba_bt.sim.link import RealtimeSimLink, SimLink
from roomba_bt.sim.robot import (
    STEP_SECONDS,
    SimEvent,
    Simulator,
    TracePoint,
    Violation,
    drive_wheel_speeds,
)
from roomba_bt.sim.world import (
    DockSpec,
    Pose,
    World,
    WorldError,
    load_world,
    parse_world,
    shipped_worlds,
)

__all__ = [
    "STEP_SECONDS",
    "DockSpec",
    "Faults",
    "Pose",
    "RealtimeSimLink",
    "SimEvent",
    "SimLink",
    "Simulator",
    "TracePoint",
    "Violation",
    "World",
    "WorldError",
    "drive_wheel_speeds",
    "load_world",
    "parse_world",
    "shipped_worlds",
]
