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

Where an optional extra is asked for (``--plot``, the Dask engine), the code that imports it
says what it needs in its own words (``--plot needs matplotlib, an optional extra: pip
install 'roomba-bt[plot]'``) when the extra is not installed, and these words when it is
installed incompletely (:func:`optional_import_failure`): "pip install the extra" is no help
to a user who has it, missing a dependency of its own.

Below every layer, standard library only (the simulator's plots use it, ``tests/test_layers.py``):
it runs when an import has just failed.
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
    if package is None:
        if isinstance(exc, ModuleNotFoundError) and exc.name:
            return missing_from_installation(exc.name, version)
        return None
    missing = _missing(exc, package)
    if package in EXTRAS:
        what, extra = EXTRAS[package]
        if missing:
            return f"{what} ({package}) is not installed: pip install 'roomba-bt[{extra}]'"
        return _incomplete(exc, package)
    if package in DEPENDENCIES:
        state = "not installed" if missing else f"installed incompletely: {exc}"
        return (f"roomba-bt's dependency {DEPENDENCIES[package]} ({package}) is {state}; "
                "reinstall roomba-bt: pip install --force-reinstall roomba-bt")  # fmt: skip
    if missing:
        return f"{exc}: install it (pip install {_distribution(package)}); the traceback with -v"
    return f"{_incomplete(exc, package)} (the traceback with -v)"


def optional_import_failure(exc: ImportError, needs: str) -> str:
    """What to say of ``exc``, raised by the import of an optional extra where it is asked
    for: ``needs``, the caller's words naming the extra to install, when its package is not
    installed; when it is, but its own import failed (matplotlib without its kiwisolver,
    distributed without its tornado), that it is installed incompletely and how to reinstall
    it. An error of roomba-bt's that already says so is said as it is; a failure no extra's
    own code raised (an import hook's, a test's stand-in) is ``needs`` too."""
    if isinstance(exc, RoombaBtError):
        return str(exc)
    package = failing_package(exc)
    if package not in EXTRAS or _missing(exc, package):
        return needs
    return _incomplete(exc, package)


def _missing(exc: ImportError, package: str) -> bool:
    """Whether ``exc`` says ``package`` itself is not there (not a module it imports)."""
    return isinstance(exc, ModuleNotFoundError) and _top(exc.name) == package


def _incomplete(exc: ImportError, package: str) -> str:
    """``package`` is there but its import failed inside it: what it is, why, and the pip
    line that installs it again (its extra's, for an extra of roomba-bt)."""
    if package in EXTRAS:
        what, extra = EXTRAS[package]
        return (f"{what} ({package}) is installed incompletely: {exc}; reinstall it: "
                f"pip install --force-reinstall 'roomba-bt[{extra}]'")  # fmt: skip
    return (f"{package} is installed incompletely: {exc}; reinstall it: pip install "
            f"--force-reinstall {_distribution(package)}")  # fmt: skip


def _distribution(package: str) -> str:
    """The distribution pip knows ``package`` by (``PyYAML`` for ``yaml``), the package's own
    name when no installed distribution names it (a package that is not installed)."""
    from importlib.metadata import packages_distributions

    return next(iter(packages_distributions().get(package, ())), package)
