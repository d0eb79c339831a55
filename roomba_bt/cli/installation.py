"""What an ImportError during a command says: which package to install or reinstall.

Every ImportError that reached the command line was one line, ``roomba-bt: No module named
'yarl'``, exit 2, with no traceback even under ``-v``: a half-installed extra, a broken
dependency and roomba-bt's own circular import all read as the user's mistake. Now:

- an error roomba-bt raised about the installation itself (a py_trees release the tree is
  not proven against, a subcommand's module missing) is already worded: said as it is;
- an import that failed inside a dependency, or a dependency missing, names it, what it is
  for and the ``pip install`` that repairs it (``the monitor's web server (aiohttp) is
  installed incompletely: No module named 'yarl'; reinstall it: pip install
  --force-reinstall 'roomba-bt[monitor]'``);
- a module of roomba-bt missing is a broken installation, reinstalled the same way;

all exit 2 (the installation cannot run this command; nothing was opened), the traceback
with ``-v``. An ImportError inside roomba-bt's own code with none of these behind it (a
circular import, a name that is not there) is roomba-bt's bug: None here, and the command
line reports it as any internal error (exit 70).

Standard library only: it runs when an import has just failed.
"""

from __future__ import annotations

from roomba_bt.errors import RoombaBtError

#: The optional extras' packages (import name): what each is for, and its extra.
EXTRAS = {
    "aiohttp": ("the monitor's web server", "monitor"),
    "matplotlib": ("the plots' drawing library", "plot"),
    "dask": ("the Dask engine", "cluster"),
    "distributed": ("the Dask engine", "cluster"),
}

#: roomba-bt's own dependencies (import name -> the distribution pip knows).
DEPENDENCIES = {
    "serial": "pyserial",
    "yaml": "PyYAML",
    "py_trees": "py-trees",
    "transitions": "transitions",
}

#: The top-level names of roomba-bt's own modules.
OWN = "roomba_bt"


class IncompleteInstallation(ModuleNotFoundError, RoombaBtError):
    """A module of roomba-bt itself is missing (a wheel built without it): the message says
    which, and to reinstall."""


def missing_from_installation(module: str, version: str, kind: str = "module") -> str:
    """A module of roomba-bt that is not there: the installation is broken, not the user."""
    return (f"the {kind} {module} is missing from this installation of roomba-bt {version} "
            "(reinstall it: pip install --force-reinstall roomba-bt)")  # fmt: skip


def _top(module: str | None) -> str | None:
    return module.partition(".")[0] if module else None


def failing_package(exc: ImportError) -> str | None:
    """The top-level package the failed import belongs to: the first module outside
    roomba-bt (and outside Python's import machinery) on the traceback, the one whose own
    import failed (``aiohttp``, missing its ``yarl``); else the module that was not found
    or that lacks the name asked for (``aiohttp``, not installed). None: roomba-bt's own."""
    import traceback  # here: the command line imports this module at every start

    for frame, _ in traceback.walk_tb(exc.__traceback__):
        top = _top(frame.f_globals.get("__name__"))
        if top not in (None, OWN, "importlib", "__main__"):
            return top
    top = _top(exc.name)
    return None if top == OWN else top


def import_failure(exc: ImportError, version: str) -> str | None:
    """What to say of ``exc`` (raised while a command ran, or while the commands were
    imported), naming what to install; None for roomba-bt's own bug (an internal error)."""
    if isinstance(exc, RoombaBtError):
        return str(exc)
    package = failing_package(exc)
    missing = isinstance(exc, ModuleNotFoundError) and _top(exc.name) == package
    if package is None:
        if isinstance(exc, ModuleNotFoundError) and exc.name:
            return missing_from_installation(exc.name, version)
        return None
    if package in EXTRAS:
        what, extra = EXTRAS[package]
        if missing:
            return f"{what} ({package}) is not installed: pip install 'roomba-bt[{extra}]'"
        return (f"{what} ({package}) is installed incompletely: {exc}; reinstall it: "
                f"pip install --force-reinstall 'roomba-bt[{extra}]'")  # fmt: skip
    if package in DEPENDENCIES:
        state = "not installed" if missing else f"installed incompletely: {exc}"
        return (f"roomba-bt's dependency {DEPENDENCIES[package]} ({package}) is {state}; "
                "reinstall roomba-bt: pip install --force-reinstall roomba-bt")  # fmt: skip
    distribution = _distribution(package)
    if missing:
        return f"{exc}: install it (pip install {distribution}); the traceback with -v"
    return (f"{package} is installed incompletely: {exc}; reinstall it: pip install "
            f"--force-reinstall {distribution} (the traceback with -v)")  # fmt: skip


def _distribution(package: str) -> str:
    """The distribution pip knows ``package`` by (``PyYAML`` for ``yaml``), the package's own
    name when no installed distribution names it (a package that is not installed)."""
    from importlib.metadata import packages_distributions

    return next(iter(packages_distributions().get(package, ())), package)
