"""The command's entry point takes the ending signals before the command line's module loads
(``roomba_bt/_entry.py``): a signal in the start-up is ``roomba-bt: interrupted``, exit 130,
never Python's traceback, 143, or a script's ``kill -INT`` lost."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt._entry import INTERRUPTED
from roomba_bt.runtime.summary import ExitCode

#: ``roomba-bt validate dock`` as a script's background job starts it (SIGINT and SIGQUIT
#: ignored), with an import hook that notes each ending signal's handler when the command
#: line's module is first imported
HANDLERS_WHEN_CLI_LOADS = """
import signal, sys

class Note:
    handlers = None

    def find_spec(self, name, path=None, target=None):
        if name == "roomba_bt.cli" and Note.handlers is None:
            Note.handlers = [getattr(signal.getsignal(s), "__name__", "not ours") for s in
                             (signal.SIGINT, signal.SIGTERM, signal.SIGQUIT)]
        return None

for s in (signal.SIGINT, signal.SIGQUIT):
    signal.signal(s, signal.SIG_IGN)
sys.meta_path.insert(0, Note())
sys.argv = ["roomba-bt", "validate", "dock"]
from roomba_bt._entry import main
code = main()
print(Note.handlers)
sys.exit(code)
"""


def test_the_signals_are_taken_before_the_command_line_loads() -> None:
    """Until session 35 the handlers came once ``roomba_bt.cli`` had loaded (up to a second
    on a loaded machine): a SIGTERM then was 143, a script's SIGINT or SIGQUIT lost."""
    done = subprocess.run(
        [sys.executable, "-c", HANDLERS_WHEN_CLI_LOADS],
        capture_output=True, text=True, timeout=HANG_S, check=True,
    )  # fmt: skip
    assert done.stdout.splitlines()[-1] == str(["interrupted_early"] * 3)


#: what ``roomba-bt`` has imported when its handlers go in: a fresh interpreter without
#: ``site`` (-S: what an installed wheel's script has loaded, less the venv's editable-install
#: finder, which loads ``re`` and ``enum`` itself), each module new since Python started
MODULES_BEFORE_THE_HANDLERS = """
import sys
before = set(sys.modules)
from roomba_bt._entry import take_signals_early
take_signals_early()
imported = sorted(set(sys.modules) - before)
import json, signal
handlers = [getattr(signal.getsignal(s), "__name__", "not ours") for s in
            (signal.SIGINT, signal.SIGTERM, signal.SIGQUIT)]
print(json.dumps([handlers, imported]))
"""


def test_the_handlers_go_in_before_any_module_they_do_not_need() -> None:
    """Until session 36 the top package imported ``typing`` and the lazy names' module, and
    the entry point ``signal`` (``enum``, ``functools``, ``collections`` with it),
    ``contextlib`` and ``typing`` before a handler was in: 15 to 35 ms more in which a
    script's ``kill -INT`` was lost. Only the package, its ``sys.path`` guard (and ``os``,
    which ``site`` loads in every other start) and the entry point come first now."""
    done = subprocess.run(
        [sys.executable, "-S", "-c", MODULES_BEFORE_THE_HANDLERS],
        capture_output=True, text=True, timeout=HANG_S, check=True,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
    )  # fmt: skip
    handlers, imported = json.loads(done.stdout.splitlines()[-1])
    assert handlers == ["interrupted_early"] * 3
    ours = {"roomba_bt", "roomba_bt._safe_path", "roomba_bt._entry", "__future__"}
    assert set(imported) - ours <= OS_AND_ITS_OWN, imported
    for heavy in ("typing", "signal", "enum", "contextlib", "functools", "roomba_bt._lazy"):
        assert heavy not in imported


#: ``os`` and what it imports, which ``site`` has loaded in every start but ``python -S``'s
OS_AND_ITS_OWN = {"os", "stat", "_stat", "posixpath", "genericpath", "os.path", "_collections_abc"}


def test_the_package_names_are_found_once_the_lazy_module_loads() -> None:
    """The top package's names come through its lazy ``__getattr__``, whose module is now
    imported at the first name asked for, not as the package loads."""
    done = subprocess.run(
        [sys.executable, "-c", "import sys, roomba_bt\n"
         "print('roomba_bt._lazy' in sys.modules, roomba_bt.ExitCode.INTERRUPTED,\n"
         "      'ExitCode' in dir(roomba_bt), 'roomba_bt._lazy' in sys.modules)"],
        capture_output=True, text=True, timeout=HANG_S, check=True,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
    )  # fmt: skip
    assert done.stdout.split() == ["False", "130", "True", "True"]


def test_the_entry_points_exit_code_is_the_tables() -> None:
    assert INTERRUPTED == ExitCode.INTERRUPTED


def _caught(pid: int, signum: int) -> bool:
    """Whether process ``pid``, once it runs ``python -m roomba_bt``, has a handler of its
    own for ``signum`` (``SigCgt``; the Python before its exec has one for SIGINT)."""
    if b"-m\0roomba_bt" not in Path(f"/proc/{pid}/cmdline").read_bytes():
        return False
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    return False


#: ``roomba-bt validate dock`` started as a script's job, as tests/conftest.py's script_job
_AS_A_SCRIPTS_JOB = (
    "import os, signal, sys\n"
    "for s in (signal.SIGINT, signal.SIGQUIT): signal.signal(s, signal.SIG_IGN)\n"
    "os.execv(sys.executable, [sys.executable, '-m', 'roomba_bt', 'validate', 'dock'])\n"
)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGQUIT],
                         ids=["SIGINT", "SIGTERM", "SIGQUIT"])  # fmt: skip
def test_a_signal_as_soon_as_the_command_takes_it_is_exit_130_without_a_traceback(
    signum: int,
) -> None:
    """The signal sent the moment the process has a handler for it (its first, the entry
    point's: waited for by event, not by time), many times over: each is ``roomba-bt:
    interrupted``, exit 130, no traceback (a RuntimeError Python wrapped it in included)."""
    for _ in range(5):
        proc = subprocess.Popen(
            [sys.executable, "-c", _AS_A_SCRIPTS_JOB],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        while proc.poll() is None and not _caught(proc.pid, signum):
            continue
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=HANG_S)
        assert proc.returncode == ExitCode.INTERRUPTED, err
        assert "Traceback" not in err
        assert err.startswith("roomba-bt: interrupted"), err
        if signum == signal.SIGINT:  # the pages' line of a signal in the start-up
            assert_quoted("docs/runtime.md", "roomba-bt: interrupted$", err)
            assert_quoted("docs/architecture.md", "roomba-bt: interrupted$", err)
        if signum == signal.SIGQUIT:
            assert_quoted("docs/runtime.md", "roomba-bt: interrupted by SIGQUIT", err)


#: a SIGINT sent inside a weakref callback, whose handler runs there: Python drops what it
#: raises ("Exception ignored in ..."); then ``the WHAT went on`` printed
_SIGINT_IN_A_CALLBACK = """\
import gc, os, signal, weakref
class Held: pass
held = Held()
def callback(_):  # its handler runs here: Python drops what it raises
    os.kill(os.getpid(), signal.SIGINT)
    sum(range(1000))
keep = weakref.ref(held, callback)
del held
gc.collect()
print("the {} went on", flush=True)
"""

_DROPPED_IN_A_CALLBACK = (
    "import sys\nfrom roomba_bt import _entry\n_entry.take_signals_early()\n"
    + _SIGINT_IN_A_CALLBACK.format("start-up")
    + 'sys.argv = ["roomba-bt", "--version"]\nsys.exit(_entry.main())\n'
)


def test_an_interrupt_python_dropped_in_a_callback_ends_the_start_up_at_its_end() -> None:
    """A SIGINT whose early handler ran inside a weakref callback (importlib's module locks
    run one as the CLI imports) raised where Python drops it ("Exception ignored in ..."):
    the command went on, and a run would have run its whole mission, exit 0 (seen as a
    flaky SIGINT test). The CLI raises it once its own handlers are in: exit 130, and the
    command's work (here ``--version``) is not done."""
    done = subprocess.run(
        [sys.executable, "-c", _DROPPED_IN_A_CALLBACK],
        capture_output=True, text=True, timeout=HANG_S,
    )  # fmt: skip
    assert "the start-up went on" in done.stdout  # the interrupt was dropped, as in the field
    assert "Exception ignored" not in done.stderr  # its traceback: one line instead
    assert "SIGINT came while Python ran callback (<string>:7)" in done.stderr
    assert done.returncode == ExitCode.INTERRUPTED, (done.stdout, done.stderr)
    assert "roomba-bt: interrupted" in done.stderr
    assert "roomba-bt 0." not in done.stdout  # --version's line: the command did not run


#: a plugin file whose import runs a weakref callback in which SIGINT's handler runs (the
#: CLI's own by then: raise_interrupt), as importlib's module locks run one: Python drops it
_DROPPING_PLUGIN = (
    _SIGINT_IN_A_CALLBACK.format("import")
    + """\
from roomba_bt.behaviours import Condition, declare
@declare("s43_dropper", kind="condition", reads=(27,))
class Dropper(Condition):
    \"\"\"True: the plugin's behaviour, which the mission need not use.\"\"\"
    def check(self, snapshot):
        return True
"""
)


def _dropped_as_the_plugin_imports(
    tmp_path: Path, *command: str
) -> subprocess.CompletedProcess[str]:
    """``roomba-bt COMMAND... m.yaml [other.yaml] --allow-plugin-files`` as the process, where
    ``m.yaml``'s plugin's import runs a weakref callback in which SIGINT's handler runs
    (:data:`_DROPPING_PLUGIN`): Python drops the interrupt. ``other.yaml``, the same mission
    without the plugin, is there for a command that names it (``{other}``)."""
    (tmp_path / "drop.py").write_text(_DROPPING_PLUGIN)
    tree = "tree:\n  sequence:\n    - mode: safe\n    - wait: 0.1s\n    - mode: passive\n"
    (tmp_path / "m.yaml").write_text(f"mission: m\nplugins: [./drop.py]\n{tree}")
    (tmp_path / "other.yaml").write_text(f"mission: other\n{tree}")
    argv = [
        "roomba-bt",
        *(word.format(m=tmp_path / "m.yaml", other=tmp_path / "other.yaml") for word in command),
        "--allow-plugin-files",
    ]
    script = (
        f"import sys\nfrom roomba_bt._entry import main\nsys.argv = {argv!r}\nsys.exit(main())\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=HANG_S
    )
    assert "the import went on" in done.stdout  # the interrupt was dropped, as in the field
    assert done.returncode == ExitCode.INTERRUPTED, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    assert done.stderr.splitlines()[-1] == "roomba-bt: interrupted", done.stderr
    return done


def test_an_interrupt_python_dropped_as_a_plugin_imports_ends_the_command_before_the_run(
    tmp_path: Path,
) -> None:
    """A Ctrl-C whose handler (the CLI's, in after the start-up) ran in a weakref callback
    as a mission's plugin imported was dropped: the whole mission ran, exit 0. It is raised
    as the run begins: exit 130, nothing of the mission run."""
    done = _dropped_as_the_plugin_imports(tmp_path, "run", "{m}", "--fast", "--display", "none")
    assert "SIGINT came while Python ran callback (" in done.stderr  # where it was lost
    assert "outcome" not in done.stdout  # no run, so no summary


def test_an_interrupt_python_dropped_while_validate_reads_a_file_ends_it_at_the_next(
    tmp_path: Path,
) -> None:
    """``validate`` of many files after a Ctrl-C (or SIGTERM) that Python dropped in a
    callback (a signal sent at random moments into ``validate`` of 240 files exited 0 two
    times in 30, ``Exception ignored in: <function WeakKeyDictionary...remove>`` and its
    traceback on stderr): it went on to check and say every file, exit 0. Now it ends before
    the next file, exit 130, none said, and stderr names the callback in one line."""
    done = _dropped_as_the_plugin_imports(tmp_path, "validate", "{m}", "{other}")
    assert "ok" not in done.stdout.replace("the import went on", "")  # no file said
    assert done.stderr.splitlines() == [
        f"roomba-bt: SIGINT came while Python ran callback ({tmp_path / 'drop.py'}:4), a "
        "finalizer or weakref callback, which drops what it raises: it is raised again at the "
        "next check",
        "roomba-bt: interrupted",
    ], done.stderr
    names = {str(tmp_path): "plugins"}
    assert_quoted(
        "docs/runtime.md", "roomba-bt: SIGINT came while Python ran", done.stderr, names=names
    )


def test_an_interrupt_python_dropped_after_the_last_check_still_ends_the_command_130(
    tmp_path: Path,
) -> None:
    """A command with no check left (here ``show``, whose plugin drops the interrupt) went
    on to its end and exited 0: the operator's Ctrl-C lost. It still does its work, whole
    (nothing half-written), and exits 130 saying so."""
    _dropped_as_the_plugin_imports(tmp_path, "show", "{m}")


def test_a_dropped_interrupt_is_superseded_by_a_later_signal_s() -> None:
    """A Ctrl-C Python dropped, then a second one that the command caught on purpose (the
    monitor's way to end, exit 0): the command ends as the second said, not 130 for the
    first. One dropped and not superseded is the command's to end on."""
    import types

    from roomba_bt import _entry

    def dropped(signum: int) -> KeyboardInterrupt:
        interrupt = _entry.kept(_entry.delivered(KeyboardInterrupt(), signum))
        hook = types.SimpleNamespace(exc_value=interrupt, object=None)
        _entry.note_dropped(hook)  # type: ignore[arg-type]
        return interrupt

    first = dropped(signal.SIGINT)
    assert _entry.dropped_interrupt() is first
    dropped(signal.SIGINT)
    _entry.kept(_entry.delivered(KeyboardInterrupt(), signal.SIGINT))  # the second, caught
    assert _entry.dropped_interrupt() is None
    assert _entry.swallowed_interrupt() is not None  # (the kept one, taken: as it was)
