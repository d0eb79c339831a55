"""Names that moved to the module a reader looks in still import from where they were.

Plugins and their tests import from ``roomba_bt.behaviours.declare``, ``roomba_bt.oi.*`` and
``roomba_bt.transport.testing``: each old path gives the very object its new home defines.
And the 15 ms slot, a protocol fact, is a number in one place only.
"""

from __future__ import annotations

import ast
import importlib
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "roomba_bt"

#: the names ``roomba_bt.behaviours.declare`` offers that other modules define now, by module
DECLARE_OFFERS = {
    "roomba_bt.behaviours.base": (
        "RobotBehaviour",
        "Action",
        "Condition",
        "CheckedParams",
        "UndeclaredCommand",
        "InvalidCheck",
        "checked_truth",
    ),
    "roomba_bt.behaviours.blackboard": (
        "SNAPSHOT_KEY",
        "KEY_TYPES_KEY",
        "MISSION_NAMESPACE",
        "BLACKBOARD_REF",
        "BlackboardRef",
        "blackboard_ref",
        "read_key",
        "write_key",
        "declare_keys",
        "KeyType",
        "UnwrittenKey",
        "KeyRange",
    ),
    "roomba_bt.behaviours.driving": (
        "WHEEL",
        "CHARGER_ADVICE",
        "left_driving_message",
        "on_home_base",
        "cycle_may_run",
    ),
    "roomba_bt.behaviours.frame_inputs": ("FrameInputs",),
    # never defined in declare, but imported there before session 28 and so found there
    # by plugins (InvalidStatus, Snapshot: the upgrade report's slowpoke.py)
    "roomba_bt.behaviours.lean": (
        "DirectLeaf",
        "InvalidStatus",
        "Selector",
        "Sequence",
        "behaviour_tick",
        "checked_status",
    ),
    "roomba_bt.robot.interface": ("ModeChange", "Odometry", "RobotHandle", "Snapshot"),
    "roomba_bt.oi.encode": ("Command", "halt", "motors_off", "turns_wheels"),
    "roomba_bt.oi.frames": ("SensorFrame", "CHARGING_SOURCES_PACKETS"),
    "roomba_bt.oi.modes": ("DRIVING_MODES",),
    "roomba_bt.oi.opcodes": ("COMMANDS_BY_NAME",),
    "roomba_bt.behaviours.units": ("MARK", "held"),
}

#: (old module, name, the module that defines it now)
MOVED = [
    ("roomba_bt.oi.stream", "SLOT_SECONDS", "roomba_bt.oi.frames"),
    ("roomba_bt.robot.interface", "SLOT_SECONDS", "roomba_bt.oi.frames"),
    *(
        ("roomba_bt.behaviours.declare", name, home)
        for home, names in DECLARE_OFFERS.items()
        for name in names
    ),
    ("roomba_bt.transport.testing", "RecordingTransport", "roomba_bt.transport.testing"),
    ("roomba_bt.mission", "compile_mission", "roomba_bt.mission.compiler"),
    ("roomba_bt.mission", "load_mission", "roomba_bt.mission.compiler"),
    ("roomba_bt.mission", "validate_files", "roomba_bt.mission.compiler"),
    ("roomba_bt.mission.ir", "Node", "roomba_bt.mission.plan"),
    ("roomba_bt.mission.ir", "KeyDecl", "roomba_bt.mission.plan"),
    ("roomba_bt.robot.handshake", "find_robot", "roomba_bt.robot.discovery"),
    ("roomba_bt.robot.handshake", "wake_pulse", "roomba_bt.robot.discovery"),
    ("roomba_bt.robot.handshake", "Probe", "roomba_bt.robot.discovery"),
]

#: Every public name of ``roomba_bt.behaviours.declare``'s namespace at e80f20a, the release
#: before session 28 (``vars()`` of the module, without ``_`` names): a plugin may have
#: imported any of them from there
DECLARE_AT_E80F20A = (
    "ALL_MODES", "Action", "Any", "B", "BLACKBOARD_REF", "BlackboardRef", "CHARGER_ADVICE",
    "CHARGING_SOURCES_PACKETS", "COMMANDS", "COMMANDS_BY_NAME", "CONTROL", "Callable",
    "CheckedParams", "Command", "ComparesOf", "Comparison", "Condition", "DRIVING_MODES",
    "Declaration", "DeclarationError", "DirectLeaf", "Effect", "FrameInputs", "InvalidCheck",
    "InvalidStatus", "KEY_TYPES_KEY", "KeyRange", "KeyType", "Kind", "Literal", "MARK",
    "MISSION_NAMESPACE", "Mapping", "ModeChange", "ModeOf", "OIMode", "Odometry", "PACKETS",
    "PacketsOf", "Param", "ParamError", "RobotBehaviour", "RobotHandle", "SNAPSHOT_KEY", "SPEED",
    "Selector", "SensorFrame", "Sequence", "Snapshot", "TypeVar", "UndeclaredCommand", "UnitError",
    "UnwrittenKey", "VALUE_TYPES", "ValueType", "WHEEL", "annotations", "behaviour_tick",
    "blackboard_ref", "character_name", "checked_status", "checked_truth", "class_doc", "closest",
    "cycle_may_run", "dataclass", "declare", "declare_keys", "field", "from_python", "halt",
    "held", "left_driving_message", "logging", "math", "mode_after_sending", "motors_off",
    "on_home_base", "operator", "py_trees", "quoted", "re", "read_key", "sys", "turns_wheels",
    "uuid", "wheel_speed_param", "write_key",
)  # fmt: skip


def test_every_name_the_old_declare_module_offered_still_imports_from_it() -> None:
    """The shim keeps more than the names defined there: ``from roomba_bt.behaviours.declare
    import InvalidStatus, Snapshot`` failed a plugin's import after session 28."""
    importlib.import_module("roomba_bt.behaviours.declare")
    declare = sys.modules["roomba_bt.behaviours.declare"]  # the package's `declare` is the function
    assert len(DECLARE_AT_E80F20A) == 88
    assert [name for name in DECLARE_AT_E80F20A if not hasattr(declare, name)] == []


#: what each moved name is called in its new home, where it was renamed
RENAMED = {("roomba_bt.transport.testing", "RecordingTransport"): "WriteLogTransport"}


@pytest.mark.parametrize(("old", "name", "home"), MOVED, ids=lambda v: str(v))
def test_an_old_path_gives_the_new_home_s_object(old: str, name: str, home: str) -> None:
    new_name = RENAMED.get((old, name), name)
    assert getattr(importlib.import_module(old), name) is getattr(
        importlib.import_module(home), new_name
    )


def test_the_simulator_steps_one_slot() -> None:
    from roomba_bt.oi.frames import SLOT_SECONDS
    from roomba_bt.sim import STEP_SECONDS

    assert STEP_SECONDS is SLOT_SECONDS


def test_the_slot_is_a_number_in_one_module() -> None:
    """0.015 as a number appears in ``oi/frames.py`` alone (``SLOT_SECONDS``); every other
    module reads that. The coverage report's odometry error of 1.5 % is another quantity."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and node.value == 0.015:
                found.append(str(path.relative_to(PACKAGE)))
    assert found == ["evaluate/coverage_report.py", "oi/frames.py"]


#: every module's ``__all__`` in 0.1.0 (e80f20a), made by reading each file of
#: ``git archive e80f20a roomba_bt`` with ``ast`` (the names a plugin or a script of 0.1.0
#: could import as public); ``NO_ANSWER_CAUSES`` left it once unseen (session 33)
NAMES_0_1_0 = Path(__file__).resolve().parent / "data" / "public_names_0_1_0.json"


def test_every_public_name_of_0_1_0_still_imports() -> None:
    """The CHANGELOG's upgrade notes promise it: a 0.1.0 program's imports all work."""
    import json

    missing = [
        f"{module}.{name}"
        for module, names in json.loads(NAMES_0_1_0.read_text()).items()
        for name in names
        if not hasattr(importlib.import_module(module), name)
    ]
    assert missing == []
