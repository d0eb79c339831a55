"""roomba-bt: declarative behaviour-tree missions for iRobot Open Interface robots.

The names a Python program needs, from one place: ``roomba_bt.load_mission``,
``roomba_bt.Connection``, ``roomba_bt.RunStack``, ``roomba_bt.CREATE2``... (``docs/runtime.md``,
From Python: a connection driven by hand, then a mission, whose example a test runs).

The shipped ``dock`` mission on the built-in simulator, on its virtual clock (no robot, no
waiting; on a robot, the link is ``roomba_bt.Connection.open("/dev/ttyUSB0")`` instead)::

    >>> import roomba_bt
    >>> mission = roomba_bt.load_mission("dock")  # by name, or a file's path
    >>> world = roomba_bt.load_world("empty-room")
    >>> link = roomba_bt.SimLink(roomba_bt.Simulator(world, roomba_bt.CREATE2, seed=0))
    >>> with roomba_bt.RunStack(mission, link, profile=roomba_bt.CREATE2, timeout_s=120) as stack:
    ...     summary = stack.run().raise_for_outcome()  # RunFailed unless it succeeded
    >>> print(summary.outcome.value, "in", summary.final_mode_text())
    success in Passive

``print(summary)`` shows the whole summary as ``roomba-bt run`` does; ``summary.exit_code``
is its exit code (``tests/test_package.py`` runs this example as a doctest).

This package sits above every layer (``tests/test_layers.py``): it names things from all of
them. Each name is imported from its module when first asked for (a module ``__getattr__``,
PEP 562), so ``import roomba_bt`` (which every ``roomba-bt`` command runs first) loads none
of them: the CLI's start-up and what each command imports (``tests/cli/test_imports.py``)
stay as they were. Type checkers read the imports below.
"""

from __future__ import annotations

from roomba_bt._safe_path import drop_current_folder

drop_current_folder()  # before any module not loaded yet: ``python -m`` added the cwd first

# typing's TYPE_CHECKING without typing (3 to 30 ms, as loaded a machine is) or the lazy
# names' module: every ``roomba-bt`` command imports this package before its entry point
# (roomba_bt/_entry.py) can take the signals, and each millisecond here is one more in which
# a script's ``kill -INT`` is lost. Type checkers take the name as typing's.
TYPE_CHECKING = False

__version__ = "0.2.0"

__all__ = [
    "CREATE2",
    "PROFILES",
    "ROOMBA500",
    "ROOMBA600",
    "Action",
    "BandwidthError",
    "CompiledMission",
    "Condition",
    "Connection",
    "ConnectionClosed",
    "ConnectionFailed",
    "DeclarationError",
    "EncodeError",
    "ExitCode",
    "Interrupted",
    "LinkDown",
    "MissingPacket",
    "MissionError",
    "MissionRunner",
    "ModeError",
    "NoAnswer",
    "OIMode",
    "Outcome",
    "Param",
    "ParamError",
    "Permissions",
    "RealtimeSimLink",
    "RobotError",
    "RobotHandle",
    "RobotProfile",
    "RoombaBtError",
    "RunBoard",
    "RunFailed",
    "RunStack",
    "RunSummary",
    "SensorFrame",
    "SerialTransport",
    "SharedBlackboard",
    "SimLink",
    "Simulator",
    "Snapshot",
    "StreamStalled",
    "Terminated",
    "Tick",
    "TickObserver",
    "Transport",
    "TransportError",
    "TreeMission",
    "UnwrittenKey",
    "WorldError",
    "__version__",
    "commands",
    "configured_profile",
    "declare",
    "default_registry",
    "get_profile",
    "load_mission",
    "load_mission_text",
    "load_world",
    "sigterm_raises",
    "stream_request",
    "validate_files",
]

#: the module (below this package) that each name of :data:`__all__` is taken from
_MODULE_OF: dict[str, str] = {
    **dict.fromkeys(("Action", "Condition", "DeclarationError", "Param", "ParamError",
                     "RunBoard", "SharedBlackboard", "UnwrittenKey", "declare",
                     "default_registry"), "behaviours"),
    "RoombaBtError": "errors",
    "configured_profile": "cli.profile_choice",
    **dict.fromkeys(("CompiledMission", "MissionError", "Permissions", "load_mission",
                     "load_mission_text", "validate_files"), "mission"),
    **dict.fromkeys(("BandwidthError", "EncodeError", "OIMode", "SensorFrame", "commands"), "oi"),
    "MissingPacket": "oi.frames",
    **dict.fromkeys(("CREATE2", "PROFILES", "ROOMBA500", "ROOMBA600", "RobotProfile",
                     "get_profile"), "oi.profiles"),
    **dict.fromkeys(("Connection", "ConnectionClosed", "ConnectionFailed", "LinkDown",
                     "ModeError", "NoAnswer", "RobotError", "StreamStalled", "Terminated",
                     "sigterm_raises"), "robot"),
    **dict.fromkeys(("RobotHandle", "Snapshot"), "robot.interface"),
    **dict.fromkeys(("Interrupted", "MissionRunner", "TickObserver", "stream_request"),
                    "runtime.loop"),
    **dict.fromkeys(("RunStack", "TreeMission"), "runtime.stack"),
    "Tick": "runtime.stepping",
    **dict.fromkeys(("ExitCode", "Outcome", "RunFailed", "RunSummary"), "runtime.summary"),
    **dict.fromkeys(("RealtimeSimLink", "SimLink", "Simulator", "WorldError", "load_world"),
                    "sim"),
    **dict.fromkeys(("SerialTransport", "Transport", "TransportError"), "transport"),
}  # fmt: skip

if TYPE_CHECKING:
    from roomba_bt.behaviours import (
        Action,
        Condition,
        DeclarationError,
        Param,
        ParamError,
        RunBoard,
        SharedBlackboard,
        UnwrittenKey,
        default_registry,
    )

    # from its module: mypy, reaching this package from roomba_bt._entry inside an import
    # cycle, took the package's ``declare`` for its submodule of that name (no-redef)
    from roomba_bt.behaviours.declare import declare
    from roomba_bt.cli.profile_choice import configured_profile
    from roomba_bt.errors import RoombaBtError
    from roomba_bt.mission import (
        CompiledMission,
        MissionError,
        Permissions,
        load_mission,
        load_mission_text,
        validate_files,
    )
    from roomba_bt.oi import BandwidthError, EncodeError, OIMode, SensorFrame, commands
    from roomba_bt.oi.frames import MissingPacket
    from roomba_bt.oi.profiles import (
        CREATE2,
        PROFILES,
        ROOMBA500,
        ROOMBA600,
        RobotProfile,
        get_profile,
    )
    from roomba_bt.robot import (
        Connection,
        ConnectionClosed,
        ConnectionFailed,
        LinkDown,
        ModeError,
        NoAnswer,
        RobotError,
        StreamStalled,
        Terminated,
        sigterm_raises,
    )
    from roomba_bt.robot.interface import RobotHandle, Snapshot
    from roomba_bt.runtime.loop import Interrupted, MissionRunner, TickObserver, stream_request
    from roomba_bt.runtime.stack import RunStack, TreeMission
    from roomba_bt.runtime.stepping import Tick
    from roomba_bt.runtime.summary import ExitCode, Outcome, RunFailed, RunSummary
    from roomba_bt.sim import RealtimeSimLink, SimLink, Simulator, WorldError, load_world
    from roomba_bt.transport import SerialTransport, Transport, TransportError
else:  # a type checker reads the imports instead, and a name not there is an error to it (a
    # module __getattr__ it could see made every name Any: roomba_bt.RunStak passed)

    def __getattr__(name):
        """The first name asked for: the lazy names' own module (roomba_bt/_lazy.py) imported
        only now, not as the package loads (above), and its functions put in this one's place."""
        return _exports()[0](name)

    def __dir__():
        return _exports()[1]()

    def _exports():
        from roomba_bt._lazy import lazy_exports

        global __getattr__, __dir__
        __getattr__, __dir__ = lazy_exports(__name__, _MODULE_OF)
        return __getattr__, __dir__
