"""Names that moved to the module a reader looks in still import from where they were.

Plugins and their tests import from ``roomba_bt.behaviours.declare``, ``roomba_bt.oi.*`` and
``roomba_bt.transport.testing``: each old path gives the very object its new home defines,
and (until 0.3.0 drops it: docs/runtime.md, "Moved names") warns at the importer's line with
a DeprecationWarning naming the new import; the new path, and an old one the docs still
teach, does not. And the 15 ms slot, a protocol fact, is a number in one place only.
"""

from __future__ import annotations

import ast
import importlib
import sys
import warnings
from pathlib import Path

import pytest

from roomba_bt._lazy import REMOVED_IN

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
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert [name for name in DECLARE_AT_E80F20A if not hasattr(declare, name)] == []


#: what each moved name is called in its new home, where it was renamed
RENAMED = {("roomba_bt.transport.testing", "RecordingTransport"): "WriteLogTransport"}

#: old paths of :data:`MOVED` that stay, without a warning: what the docs teach
#: (docs/missions.md: ``from roomba_bt.mission import load_mission, validate_files``), and a
#: name the old module imports for its own use (the stream parser reads the slot;
#: ``declare`` checks a class against ``Action``, ...), found there as in any module
NOT_DEPRECATED = {
    ("roomba_bt.mission", "compile_mission"),
    ("roomba_bt.mission", "load_mission"),
    ("roomba_bt.mission", "validate_files"),
    ("roomba_bt.oi.stream", "SLOT_SECONDS"),
    *(
        ("roomba_bt.behaviours.declare", name)
        for name in ("Action", "Condition", "RobotBehaviour", "BlackboardRef", "blackboard_ref",
                     "WHEEL")
    ),
}  # fmt: skip


#: modules kept only for old imports -> what their warning says to write instead
MOVED_MODULES = {
    "roomba_bt.mission.ir": "import from roomba_bt.mission.plan instead",
    "roomba_bt.robot.handshake": "import from roomba_bt.robot.discovery instead",
    "roomba_bt.commands": "write from roomba_bt import commands",
    "roomba_bt.oi.commands": "write from roomba_bt.oi import commands",
}


def _imported(statement: str) -> list[warnings.WarningMessage]:
    """The warnings of ``statement`` run as a module of its own, ``importer.py``: a
    warning's place must be the importer's line, not roomba_bt's."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        exec(compile(statement, "importer.py", "exec"), {})
    return caught


def _said(caught: list[warnings.WarningMessage]) -> list[tuple[str, int, str]]:
    return [(w.filename, w.lineno, str(w.message)) for w in caught]


@pytest.mark.parametrize(("old", "name", "home"), MOVED, ids=lambda v: str(v))
def test_an_old_path_gives_the_new_home_s_object(old: str, name: str, home: str) -> None:
    new_name = RENAMED.get((old, name), name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        old_value = getattr(importlib.import_module(old), name)
    assert old_value is getattr(importlib.import_module(home), new_name)


@pytest.mark.parametrize(
    ("old", "name", "home"),
    [row for row in MOVED if row[:2] not in NOT_DEPRECATED and row[0] not in MOVED_MODULES],
    ids=lambda v: str(v),
)
def test_an_old_path_warns_at_the_importer_s_line_naming_the_new_one(
    old: str, name: str, home: str
) -> None:
    new_name = RENAMED.get((old, name), name)
    with pytest.warns(DeprecationWarning, match=rf"^{old}\.{name} is deprecated"):
        getattr(importlib.import_module(old), name)
    assert _said(_imported(f"from {old} import {name}")) == [
        (
            "importer.py",
            1,
            f"{old}.{name} is deprecated and goes in roomba-bt {REMOVED_IN}: "
            f"import {new_name} from {home} instead",
        )
    ]


@pytest.mark.parametrize(("old", "name", "home"), MOVED, ids=lambda v: str(v))
def test_a_new_path_and_a_taught_old_one_do_not_warn(old: str, name: str, home: str) -> None:
    new_name = RENAMED.get((old, name), name)
    assert _imported(f"from {home} import {new_name}") == []
    if (old, name) in NOT_DEPRECATED:
        assert _imported(f"from {old} import {name}") == []


@pytest.mark.parametrize(("old", "instead"), MOVED_MODULES.items())
def test_a_module_kept_for_old_imports_warns_at_the_import_line(
    old: str, instead: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Its first import warns (a module runs once: later ones find it imported), at the
    importer's line, through the import system's frames."""
    monkeypatch.delitem(sys.modules, old, raising=False)
    caught = _imported(f"import {old}")
    old_said = f"import {old} (as a module)" if old.endswith(".commands") else old
    assert _said(caught) == [
        (
            "importer.py",
            1,
            f"{old_said} is deprecated and goes in roomba-bt {REMOVED_IN}: {instead}",
        )
    ]
    assert caught[0].category is DeprecationWarning
    monkeypatch.delitem(sys.modules, old)
    with pytest.warns(DeprecationWarning, match=REMOVED_IN):
        importlib.import_module(old)


def test_the_spellings_the_docs_teach_for_the_commands_do_not_warn() -> None:
    """docs/plugins.md ``from roomba_bt.oi import commands``; docs/runtime.md ``from
    roomba_bt import commands``: the names, not the module paths, give no warning."""
    assert _imported("from roomba_bt.oi import commands\nfrom roomba_bt import commands") == []


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

    with warnings.catch_warnings():  # RecordingTransport's old name warns (tested above)
        warnings.simplefilter("ignore", DeprecationWarning)
        missing = [
            f"{module}.{name}"
            for module, names in json.loads(NAMES_0_1_0.read_text()).items()
            for name in names
            if not hasattr(importlib.import_module(module), name)
        ]
    assert missing == []


def test_doctor_s_old_table_of_exit_codes_warns_and_gives_exit_code_s_numbers() -> None:
    """0.1.0's ``DoctorExit``: doctor's codes are ``ExitCode``'s now (docs/runtime.md, Exit
    codes); the old table keeps its members' names, each the same number."""
    import roomba_bt.cli.doctor_cmd as doctor
    from roomba_bt.runtime.summary import ExitCode

    assert _said(_imported("from roomba_bt.cli.doctor_cmd import DoctorExit")) == [
        (
            "importer.py",
            1,
            f"roomba_bt.cli.doctor_cmd.DoctorExit is deprecated and goes in roomba-bt "
            f"{REMOVED_IN}: use ExitCode from roomba_bt.runtime.summary instead (FOUND is OK, "
            "PORT is CONNECTION, SILENT is NO_ANSWER)",
        )
    ]
    with pytest.warns(DeprecationWarning, match="DoctorExit is deprecated"):
        old = doctor.DoctorExit
    assert {member.name: int(member) for member in old} == {
        "FOUND": ExitCode.OK,
        "INVALID": ExitCode.INVALID,
        "PORT": ExitCode.CONNECTION,
        "SILENT": ExitCode.NO_ANSWER,
        "UNHEALTHY": ExitCode.UNHEALTHY,
        "INTERRUPTED": ExitCode.INTERRUPTED,
    }


#: the public names of ``roomba_bt.monitor.server`` and ``roomba_bt.monitor.session`` that
#: moved when session 41 gave the routes, a page's updates and the operator's requests modules
#: of their own (issue 13): not in a release's list (``public_names_0_1_0.json``), so they
#: stay without a warning, each the very object its new home defines
MONITOR_MOVED = [
    *(
        ("roomba_bt.monitor.server", name, "roomba_bt.monitor.pump")
        for name in ("UPDATE_PERIOD_S", "TICK_WAIT_S", "TICK_POLL_S", "AFTER_TICK_S",
                     "HEARTBEAT_S", "BEHIND_S", "PING_EVERY_S", "Socket", "next_look", "stamp")
    ),
    *(
        ("roomba_bt.monitor.server", name, "roomba_bt.monitor.routes")
        for name in ("STALE_VIEW_S", "MOTION_CONTROLS", "COOKIE", "VIEW_PATH", "VIEW_ONLY",
                     "STATIC_TYPES", "Handler", "cookie_name", "viewing", "NO_ENTRY_PAGE",
                     "NO_ENTRY", "late_control", "foreign_request", "see_the_view_path",
                     "given_token", "token_access")
    ),
    ("roomba_bt.monitor.server", "session_view", "roomba_bt.monitor.views"),
    *(
        ("roomba_bt.monitor.session", name, "roomba_bt.monitor.controls")
        for name in ("BREAK_ON", "FORCEABLE", "ControlRefused", "Request", "node_path",
                     "find_node")
    ),
]  # fmt: skip


@pytest.mark.extra("monitor")
@pytest.mark.parametrize(("old", "name", "home"), MONITOR_MOVED, ids=lambda v: str(v))
def test_a_monitor_name_that_moved_still_imports_from_its_old_module(
    old: str, name: str, home: str
) -> None:
    assert _imported(f"from {old} import {name}") == []
    assert getattr(importlib.import_module(old), name) is getattr(
        importlib.import_module(home), name
    )
