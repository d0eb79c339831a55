"""An ImportError during a command names what to install or reinstall, the traceback with
``-v``: it was ``roomba-bt: No module named 'yarl'``, exit 2, and no traceback even with
``-v``, for a half-installed extra and for roomba-bt's own circular import alike."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.cli.arguments import plot_file
from roomba_bt.cli.run_cmd import _plot
from roomba_bt.evaluate.cluster import ClusterUnavailableError, _import_distributed
from roomba_bt.installation import import_failure
from roomba_bt.sim.plot import PlotUnavailableError, pyplot

#: a package's import that fails inside it: aiohttp without its yarl, as pip uninstall leaves it
WITHOUT_YARL = """
import sys

class NoYarl:
    def find_spec(self, name, path=None, target=None):
        if name == "yarl":
            raise ModuleNotFoundError("No module named 'yarl'", name="yarl")
        return None

sys.meta_path.insert(0, NoYarl())
from roomba_bt.cli import main
sys.exit(main(sys.argv[1:]))
"""

MONITOR_REINSTALL = "pip install --force-reinstall 'roomba-bt[monitor]'"
CIRCULAR = (
    "cannot import name 'World' from partially initialized module 'roomba_bt.sim' (most likely "
    "due to a circular import)"
)


def raised_in(module: str, error: ImportError) -> ImportError:
    """``error`` as raised by code of ``module`` (its traceback's one frame is that module's,
    as an import that failed inside a package leaves it)."""
    namespace = {"__name__": module, "error": error}
    try:
        exec("raise error", namespace)
    except ImportError as exc:
        assert exc.__traceback__ is not None
        exc.__traceback__ = exc.__traceback__.tb_next  # this function's frame left out
        return exc
    raise AssertionError("exec raised nothing")


@pytest.mark.parametrize(
    ("module", "error", "said"),
    [
        (
            "aiohttp.client",
            ModuleNotFoundError("No module named 'yarl'", name="yarl"),
            "the monitor's web server (aiohttp) is installed incompletely: No module named "
            f"'yarl'; reinstall it: {MONITOR_REINSTALL}",
        ),
        (
            "roomba_bt.monitor.server",
            ModuleNotFoundError("No module named 'aiohttp'", name="aiohttp"),
            "the monitor's web server (aiohttp) is not installed: pip install 'roomba-bt[monitor]'",
        ),
        (
            "matplotlib.colors",
            ImportError("cannot import name 'ma' from 'numpy'", name="numpy"),
            "the plots' drawing library (matplotlib) is installed incompletely: cannot import "
            "name 'ma' from 'numpy'; reinstall it: pip install --force-reinstall "
            "'roomba-bt[plot]'",
        ),
        (
            "distributed.client",
            ModuleNotFoundError("No module named 'tornado'", name="tornado"),
            "the Dask engine (distributed) is installed incompletely: No module named "
            "'tornado'; reinstall it: pip install --force-reinstall 'roomba-bt[cluster]'",
        ),
        (
            "roomba_bt.transport.serial_port",
            ModuleNotFoundError("No module named 'serial'", name="serial"),
            "roomba-bt's dependency pyserial (serial) is not installed; reinstall roomba-bt: "
            "pip install --force-reinstall roomba-bt",
        ),
        (
            "roomba_bt.cli.run_cmd",
            ModuleNotFoundError(
                "No module named 'roomba_bt.runtime.gone'", name="roomba_bt.runtime.gone"
            ),
            "the module roomba_bt.runtime.gone is missing from this installation of roomba-bt",
        ),
        (
            "lab_plugin.sensors",
            ModuleNotFoundError("No module named 'lab_helpers'", name="lab_helpers"),
            "lab_plugin is installed incompletely: No module named 'lab_helpers'; reinstall "
            "it: pip install --force-reinstall lab_plugin (the traceback with -v)",
        ),
        ("roomba_bt.runtime.loop", ImportError(CIRCULAR, name="roomba_bt.sim"), None),
    ],
)
def test_what_an_import_error_names(module: str, error: ImportError, said: str | None) -> None:
    """A dependency's import that failed inside it names the dependency, what it is for and
    the pip line that repairs it; one missing outright, its install; a module of roomba-bt
    missing, a broken installation; an import of roomba-bt's own that fails on its own
    code, no installation's fault: None, an internal error."""
    found = import_failure(raised_in(module, error), "0.2.0")
    if said is None:
        assert found is None
    else:
        assert found is not None and found.startswith(said), found


def _without_yarl(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", WITHOUT_YARL, *argv], capture_output=True, text=True,
        timeout=HANG_S, env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )  # fmt: skip


def test_a_half_installed_extra_names_its_extra_and_shows_the_traceback_with_v() -> None:
    pytest.importorskip("aiohttp", reason="the monitor extra: pip install 'roomba-bt[monitor]'")
    argv = ("run", "dock", "--fast", "--monitor", "0", "--display", "none")
    done = _without_yarl(*argv)
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        "roomba-bt: the monitor's web server (aiohttp) is installed incompletely: No module "
        f"named 'yarl'; reinstall it: {MONITOR_REINSTALL}\n"
    )
    assert_quoted("docs/runtime.md", "roomba-bt: the monitor's web server (aiohttp)", done.stderr)
    shown = _without_yarl("-v", *argv)
    assert shown.returncode == 2
    assert "Traceback (most recent call last)" in shown.stderr and "from yarl import" in (
        shown.stderr
    )
    assert shown.stderr.endswith(f"{MONITOR_REINSTALL}\n")


def test_an_import_error_in_roomba_bts_own_code_is_an_internal_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A circular import of roomba-bt's own said "roomba-bt: cannot import name ...", exit 2,
    the user's fault by the README's table: it is roomba-bt's bug, exit 70."""
    import roomba_bt.cli.worlds_cmd as worlds_cmd

    namespace = {"__name__": worlds_cmd.__name__, "CIRCULAR": CIRCULAR}
    exec(
        "def worlds_command(args):\n    raise ImportError(CIRCULAR, name='roomba_bt.sim')\n",
        namespace,
    )
    monkeypatch.setattr(worlds_cmd, "worlds_command", namespace["worlds_command"])
    assert main(["worlds"]) == 70
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt: internal error: ImportError: {CIRCULAR}"), err
    assert "a bug in roomba-bt" in err


class _Missing:
    """A finder of the import system that finds no module ``name`` (as if uninstalled)."""

    def __init__(self, name: str) -> None:
        self.name = name

    def find_spec(self, name: str, path: object = None, target: object = None) -> None:
        if name == self.name:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)


def _installed_without(
    monkeypatch: pytest.MonkeyPatch, folder: Path, package: str, dependency: str
) -> None:
    """``package`` importable but failing inside its own import, ``dependency`` missing (as
    ``pip uninstall`` of a dependency leaves it): a stand-in package of that name in
    ``folder``, first on the path, the real ones out of ``sys.modules`` until the test ends."""
    (folder / package).mkdir()
    (folder / package / "__init__.py").write_text(f"import {dependency}\n")
    for name in [name for name in sys.modules if name.partition(".")[0] in (package, dependency)]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(sys, "meta_path", [_Missing(dependency), *sys.meta_path])
    monkeypatch.syspath_prepend(str(folder))


def _plot_file_refusal() -> str:
    with pytest.raises(argparse.ArgumentTypeError) as refused:
        plot_file("run.png")
    return str(refused.value)


def _pyplot_refusal() -> str:
    with pytest.raises(PlotUnavailableError) as refused:
        pyplot()
    return str(refused.value)


def _run_plot_said() -> str:
    return _plot(object(), "run.png")


def _dask_refusal() -> str:
    with pytest.raises(ClusterUnavailableError) as refused:
        _import_distributed()
    return str(refused.value)


PLOT_REINSTALL = (
    "the plots' drawing library (matplotlib) is installed incompletely: No module named "
    "'kiwisolver'; reinstall it: pip install --force-reinstall 'roomba-bt[plot]'"
)


@pytest.mark.parametrize(
    ("package", "dependency", "said", "expected"),
    [
        ("matplotlib", "kiwisolver", _plot_file_refusal, PLOT_REINSTALL),
        ("matplotlib", "kiwisolver", _pyplot_refusal, PLOT_REINSTALL),
        ("matplotlib", "kiwisolver", _run_plot_said, f"--plot: {PLOT_REINSTALL}"),
        (
            "distributed", "tornado", _dask_refusal,
            "the Dask engine (distributed) is installed incompletely: No module named "
            "'tornado'; reinstall it: pip install --force-reinstall 'roomba-bt[cluster]'",
        ),
    ],
    ids=["--plot's check", "the plots' pyplot", "run --plot", "eval --engine dask"],
)  # fmt: skip
def test_an_extra_installed_incompletely_says_reinstall_it_not_install_it(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    package: str,
    dependency: str,
    said: Callable[[], str],
    expected: str,
) -> None:
    """matplotlib without its kiwisolver, distributed without its tornado: each place that
    imports the extra said "needs matplotlib / the cluster extra: pip install ...", which the
    user had done. A package not installed at all is still said as before (the plot tests)."""
    _installed_without(monkeypatch, tmp_path, package, dependency)
    assert said() == expected
