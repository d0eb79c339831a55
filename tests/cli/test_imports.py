"""What a command imports: only what it uses.

Every command pays for the modules it imports, at each start (``roomba-bt validate`` was
about 840 M instructions, most of them imports). These tests name modules a command must
not load, each kept out on purpose; each fails if the lazy import that keeps it out goes.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from waits import HANG_S  # tests/waits.py: a hang's bound

MISSION = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"


def modules_after(script: str) -> set[str]:
    """The modules loaded once ``script`` has run in a fresh interpreter."""
    script += "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=HANG_S, check=True
    )
    return set(json.loads(done.stdout.splitlines()[-1]))


def imported_by(*args: str) -> set[str]:
    """The modules loaded by ``roomba-bt *args`` (which must succeed; its output dropped)."""
    return modules_after(
        "import contextlib, io\n"
        "from roomba_bt.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main({list(args)!r}) == 0\n"
    )


def test_validate_loads_no_connection_mode_model_or_serial_port() -> None:
    """The behaviours import :mod:`roomba_bt.robot.interface`; the package's other modules
    (connection, hand-shake, the ``transitions`` mode model, the serial transport) are
    imported only when a name of theirs is asked for, and a mission's check asks for none."""
    modules = imported_by("validate", str(MISSION))
    assert "roomba_bt.robot.interface" in modules
    for unused in (
        "roomba_bt.robot.connection",
        "roomba_bt.robot.discovery",
        "roomba_bt.robot.modes",
        "roomba_bt.transport",
        "transitions",
        "serial",
    ):
        assert unused not in modules, unused


def test_the_parser_every_command_builds_loads_no_mission_compiler() -> None:
    """``roomba-bt --version``, ``sim`` or ``sensors`` build the whole parser, every
    subcommand's arguments; the mission package (compiler, behaviours, py_trees, YAML, the
    plugin scan's importlib.metadata) is imported when a mission argument is read."""
    modules = modules_after("from roomba_bt.cli import build_parser\nbuild_parser()")
    assert "roomba_bt.cli.arguments" in modules
    for unused in ("roomba_bt.mission", "roomba_bt.behaviours", "py_trees", "yaml"):
        assert unused not in modules, unused


#: ``roomba-bt validate`` as the process runs it (``main()``, its signals its own), with an
#: import hook that notes SIGTERM's handler when the protocol package is first imported
SIGTERM_WHEN_OI_LOADS = """
import signal, sys

class Note:
    handler = None

    def find_spec(self, name, path=None, target=None):
        if name == "roomba_bt.oi" and Note.handler is None:
            Note.handler = signal.getsignal(signal.SIGTERM)
        return None

sys.meta_path.insert(0, Note())
sys.argv = ["roomba-bt", "validate", sys.argv[1]]
from roomba_bt.cli import main
code = main()
print(getattr(Note.handler, "__name__", Note.handler))
sys.exit(code)
"""


def test_sigterm_raises_before_the_bulk_of_the_start_up_is_imported() -> None:
    """A SIGTERM in the start-up's first tenth of a second ended the process by default
    (143) instead of 130: ``roomba_bt.cli`` imported the exit codes' module, and the
    protocol tables under it (two thirds of its 52 ms import), before ``main()`` set the
    handlers. They are set before the protocol package is imported now."""
    done = subprocess.run(
        [sys.executable, "-c", SIGTERM_WHEN_OI_LOADS, str(MISSION)],
        capture_output=True, text=True, timeout=HANG_S, check=True,
    )  # fmt: skip
    assert done.stdout.splitlines()[-1] == "raise_terminated", done.stdout
