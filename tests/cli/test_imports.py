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

MISSION = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"


def imported_by(*args: str) -> set[str]:
    """The modules loaded by ``roomba-bt *args`` in a fresh interpreter (its output dropped)."""
    script = (
        "import contextlib, io, json, sys\n"
        "from roomba_bt.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    code = main({list(args)!r})\n"
        "print(json.dumps([code, sorted(sys.modules)]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True
    )
    code, modules = json.loads(done.stdout.splitlines()[-1])
    assert code == 0, done.stderr
    return set(modules)


def test_validate_loads_no_connection_mode_model_or_serial_port() -> None:
    """The behaviours import :mod:`roomba_bt.robot.interface`; the package's other modules
    (connection, hand-shake, the ``transitions`` mode model, the serial transport) are
    imported only when a name of theirs is asked for, and a mission's check asks for none."""
    modules = imported_by("validate", str(MISSION))
    assert "roomba_bt.robot.interface" in modules
    for unused in (
        "roomba_bt.robot.connection",
        "roomba_bt.robot.handshake",
        "roomba_bt.robot.modes",
        "roomba_bt.transport",
        "transitions",
        "serial",
    ):
        assert unused not in modules, unused
