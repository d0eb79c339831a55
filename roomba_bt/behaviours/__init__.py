"""The behaviour library: py_trees leaves that read the snapshot and fill the outbox.

Every behaviour declares itself once (:func:`declare`): parameters with types, units, ranges
and defaults; the sensor packets it reads; the opcodes it sends (so the OI modes it needs);
the mode it leads to. The :class:`Registry` holds the built-ins and the plugins alike.
"""

from roomba_bt.behaviours.base import Action, Condition, InvalidCheck, RobotBehaviour
from roomba_bt.behaviours.blackboard import (
    MISSION_NAMESPACE,
    SNAPSHOT_KEY,
    BlackboardRef,
    KeyRange,
    KeyType,
    RunBoard,
    SharedBlackboard,
    UnwrittenKey,
    declare_keys,
    read_key,
    write_key,
)
from roomba_bt.behaviours.declare import (
    Declaration,
    DeclarationError,
    Param,
    ParamError,
    declare,
    declare_like,
)
from roomba_bt.behaviours.registry import (
    ENTRY_POINT_GROUP,
    PluginError,
    Registry,
    builtin_registry,
    default_registry,
)
from roomba_bt.behaviours.units import (
    ANGLE,
    ANY,
    BOOL,
    DISTANCE,
    DURATION,
    FLOAT,
    INT,
    MARK,
    PERCENT,
    RADIUS,
    SPEED,
    STR,
    UnitError,
    ValueType,
    enum,
)

__all__ = [
    "ANGLE",
    "ANY",
    "BOOL",
    "DISTANCE",
    "DURATION",
    "ENTRY_POINT_GROUP",
    "FLOAT",
    "INT",
    "MARK",
    "MISSION_NAMESPACE",
    "PERCENT",
    "RADIUS",
    "SNAPSHOT_KEY",
    "SPEED",
    "STR",
    "Action",
    "BlackboardRef",
    "Condition",
    "Declaration",
    "DeclarationError",
    "InvalidCheck",
    "KeyRange",
    "KeyType",
    "ParamError",
    "UnwrittenKey",
    "Param",
    "PluginError",
    "Registry",
    "RobotBehaviour",
    "RunBoard",
    "SharedBlackboard",
    "UnitError",
    "ValueType",
    "builtin_registry",
    "declare",
    "declare_keys",
    "declare_like",
    "default_registry",
    "enum",
    "read_key",
    "write_key",
]
