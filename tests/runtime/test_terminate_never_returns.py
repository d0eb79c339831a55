"""A plugin's ``terminate()`` that never returns at a run's end: the run's end waits for it a
bounded time (``runtime/ending.py``, ``TREE_STOP_LIMIT_S``), then goes on without it, from
the thread that is not stuck: the safe stop (drive 0, motors off, then Passive), the
record's end, the summary (HUNG, the terminate and its line named) and the exit code; a
signal meanwhile still ends the process (130). Before, the process never ended: no summary,
no Passive, and Ctrl-C and SIGTERM were held for a stop that never came."""

from __future__ import annotations

import contextlib
import json
import signal
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import ModuleType

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import lines  # tests/waits.py: a child's lines, within the hang bound

from roomba_bt.oi import commands as oi
from roomba_bt.runtime import ending

#: drive 0, motors off, the stream paused, Start (Passive): every ending's safe stop
SAFE_END = oi.halt().data + oi.motors_off().data + oi.pause_stream().data + oi.start().data

#: how long a test waits for the run before it gives up (the old code never ended)
GIVE_UP_S = 90.0

#: a leaf that drives until stopped; its terminate() says so on stderr and then waits on an
#: Event nobody sets (in C: no exception raised into the thread could end it)
HANG_ON_STOP = '''\
import sys
import threading

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes

RELEASE = threading.Event()


@declare("hang_on_stop", kind="action", params=(), reads=(), sends=opcodes("drive"))
class HangOnStop(Action):
    """Drives until stopped; its terminate() never returns."""

    def start(self):
        self.send(commands.drive(100, 32768))

    def update(self):
        return Status.RUNNING

    def terminate(self, new_status):
        super().terminate(new_status)
        # one line: the signal the test sends once it reads this finds the thread on it
        print("terminate entered", file=sys.stderr, flush=True); RELEASE.wait()

    def shutdown(self):
        RELEASE.wait()  # never called: its terminate had not returned
'''

#: the line of its wait, which the summary names
WAIT_LINE = next(
    i for i, line in enumerate(HANG_ON_STOP.splitlines(), 1) if "RELEASE.wait()" in line
)

MISSION = (
    "mission: hang_on_stop\n"
    "plugins: [./hang.py]\n"
    "tree:\n"
    "  sequence:\n"
    "    - mode: safe\n"
    "    - motors: {vacuum: on}\n"
    "    - hang_on_stop\n"
)


#: a leaf that succeeds at once; its shutdown() waits on an Event nobody sets
HANG_ON_SHUTDOWN = '''\
import threading

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare

RELEASE = threading.Event()


@declare("hang_on_shutdown", kind="action", params=(), reads=(), sends=())
class HangOnShutdown(Action):
    """Succeeds; its shutdown() never returns."""

    def update(self):
        return Status.SUCCESS

    def shutdown(self):
        RELEASE.wait()
'''

SHUTDOWN_LINE = next(
    i for i, line in enumerate(HANG_ON_SHUTDOWN.splitlines(), 1) if "RELEASE.wait()" in line
)


@pytest.fixture
def mission(tmp_path: Path) -> Iterator[Path]:
    """The mission and its plugin file; the plugin's Event set when the test ends, so the
    thread left in its terminate() ends too."""
    yield _written(tmp_path, HANG_ON_STOP, MISSION)
    release_all(tmp_path / "hang.py")


def _written(tmp_path: Path, plugin: str, text: str) -> Path:
    (tmp_path / "hang.py").write_text(plugin)
    path = tmp_path / "m.yaml"
    path.write_text(text)
    return path


def _plugin_modules(path: Path) -> list[ModuleType]:
    return [m for m in list(sys.modules.values()) if getattr(m, "__file__", None) == str(path)]


def outbound(record: Path) -> bytes:
    """Every byte the run wrote, in order, from its record."""
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    return b"".join(bytes.fromhex(line["b"]) for line in lines if line.get("d") == "out")


def test_a_terminate_that_never_returns_ends_the_run_hung_with_its_safe_stop(
    mission: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``roomba-bt run --fast`` whose time limit preempts the leaf: its terminate() blocks
    for ever. After the bound (made short here) the run ends: exit 4, HUNG naming the
    terminate and its line, the safe stop sent whole and the robot left in Passive."""

    monkeypatch.setattr(ending, "TREE_STOP_LIMIT_S", 0.5, raising=False)
    record = tmp_path / "run.jsonl"
    code = _main_given_up(tmp_path, [
        "run", str(mission), "--fast", "--allow-plugin-files", "--timeout", "0.3s",
        "--record", str(record), "--display", "none",
    ])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 4, out
    where = f"hang_on_stop (HangOnStop.terminate at {tmp_path / 'hang.py'}:{WAIT_LINE})"
    assert (
        f"outcome      HUNG (the tree's stop did not end within 0.5 s: {where} had not "
        "returned; the run's end went on without it (the safe stop, the summary; its shutdown() "
        "not called) (the run "
        "had ended: timeout: "
    ) in out, out
    assert "safe stop    sent drive, motors, pause_resume_stream, start" in out
    assert "final mode   Passive" in out
    assert outbound(record).endswith(SAFE_END)
    assert "shutdown() did not end" not in out, out  # the stuck node's was not called
    end = json.loads(record.read_text().splitlines()[-2])["note"]
    assert end["ended"] == "hung"


def test_a_shutdown_that_never_returns_ends_the_run_hung_after_its_safe_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A mission that succeeds, one of whose nodes' shutdown() blocks for ever: after the
    bound (made short here) the run ends, exit 4, HUNG naming the shutdown and its line,
    the safe stop sent whole before it and the robot left in Passive. Before, the process
    never ended after the safe stop: no summary, no exit code."""

    text = MISSION.replace("hang_on_stop", "hang_on_shutdown")
    mission = _written(tmp_path, HANG_ON_SHUTDOWN, text)
    monkeypatch.setattr(ending, "TREE_STOP_LIMIT_S", 0.5, raising=False)
    record = tmp_path / "run.jsonl"
    try:
        code = _main_given_up(tmp_path, [
            "run", str(mission), "--fast", "--allow-plugin-files", "--record", str(record),
            "--display", "none",
        ])  # fmt: skip
    finally:
        release_all(tmp_path / "hang.py")  # no fixture releases this test's plugin
    out = capsys.readouterr().out
    assert code == 4, out
    where = f"hang_on_shutdown (HangOnShutdown.shutdown at {tmp_path / 'hang.py'}:{SHUTDOWN_LINE})"
    assert (
        f"outcome      HUNG (the behaviours' shutdown() did not end within 0.5 s: {where} had "
        "not returned; the run's end went on without it (the summary) (the run had ended: "
        "success"
    ) in out, out
    assert "safe stop    sent drive, motors, pause_resume_stream, start" in out, out
    assert "final mode   Passive" in out
    assert outbound(record).endswith(SAFE_END)
    end = json.loads(record.read_text().splitlines()[-2])["note"]
    assert end["ended"] == "hung"


def _main_given_up(tmp_path: Path, argv: list[str]) -> int:
    """The CLI's ``main(argv)`` under :func:`given_up`."""
    from roomba_bt.cli import main

    with given_up(tmp_path / "hang.py"):
        return main(argv)


@contextlib.contextmanager
def given_up(plugin: Path) -> Iterator[None]:
    """The plugin file's waits released after :data:`GIVE_UP_S`: the old code, which waited
    for ever, fails rather than hangs (the monitor's reload too: tests/monitor)."""
    give_up = threading.Timer(GIVE_UP_S, release_all, (plugin,))
    give_up.daemon = True
    give_up.start()
    try:
        yield
    finally:
        give_up.cancel()


def release_all(path: Path) -> None:
    for module in _plugin_modules(path):
        module.RELEASE.set()


def test_the_bound_is_no_longer_than_the_wall_limit() -> None:
    assert ending.tree_stop_limit(None) == ending.TREE_STOP_LIMIT_S
    assert ending.tree_stop_limit(2.0) == 2.0
    assert ending.tree_stop_limit(3600.0) == ending.TREE_STOP_LIMIT_S


def test_ctrl_c_while_the_run_waits_for_a_terminate_that_never_returns_is_exit_130(
    mission: Path,
    tmp_path: Path,
    script_job: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """``roomba-bt run`` on the wall clock (the simulator in real time), its time limit
    preempting the leaf, and a Ctrl-C once the terminate() is entered: the run ends, exit
    130, its reason naming the tree's stop and the terminate, drive 0 and motors off before
    it and the whole safe stop after it in the record. Before, the Ctrl-C was held for a
    stop that never ended, and the process never did."""
    record = tmp_path / "run.jsonl"
    proc = script_job([
        "run", str(mission), "--allow-plugin-files", "--timeout", "0.3s",
        "--record", str(record), "--display", "none",
    ])  # fmt: skip
    assert proc.stderr is not None
    said = lines(proc.stderr, lambda line: "terminate entered" in line, "terminate() entered")
    assert "terminate entered" in said[-1], "".join(said)  # not the run's end before it
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=GIVE_UP_S)
    assert proc.returncode == 130, out + err
    where = f"hang_on_stop (HangOnStop.terminate at {tmp_path / 'hang.py'}:{WAIT_LINE})"
    # the signal's name as the run's reason gives it ("Ctrl-C", or longer), then where
    assert "outcome      INTERRUPTED (Ctrl-C" in out, out
    assert f" during the tree's stop, in {where} (the run had ended: timeout: " in out, out
    limit = f"{ending.TREE_STOP_LIMIT_S:g} s"
    assert f"the tree's stop did not end within {limit}: {where} had not returned" in out, out
    assert "waiting for it to end (the summary follows)" in err, err
    assert (
        "safe stop    drive 0, motors off before the tree's stop, then sent drive, motors, "
        "pause_resume_stream, start"
    ) in out, out
    assert_quoted("docs/runtime.md", "safe stop drive 0, motors off before", out)
    assert outbound(record).endswith(oi.halt().data + oi.motors_off().data + SAFE_END)
