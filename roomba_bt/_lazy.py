"""A package's names, each imported from its module when first asked for (PEP 562).

Below every layer (``tests/test_layers.py``): the standard library only, and any package of
ours may use it. ``roomba_bt`` itself and :mod:`roomba_bt.robot` export their names so: an
``import`` of either runs no module of the names it exports, so a command pays only for
what it uses (``tests/cli/test_imports.py``).

Old import paths are kept here too: a module's names that moved elsewhere (:func:`moved_names`)
and whole modules kept only for old imports (:func:`warn_moved_module`) each warn with a
DeprecationWarning naming the new import, until :data:`REMOVED_IN`.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, module_of: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of ``package`` for the names of
    ``module_of`` (each name -> the module that defines it, below ``package``:
    ``"runtime.stack"`` is ``<package>.runtime.stack``). A name is imported when first
    asked for and kept in the package's namespace, so asked for once; another name is an
    AttributeError, which also lets ``from package import submodule`` import the module."""
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str) -> Any:
        module = module_of.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *module_of})

    return __getattr__, __dir__


#: The release that drops the old import paths (docs/runtime.md, "Moved names"): a 0.x
#: project keeps them one release, with a DeprecationWarning, rather than for ever.
REMOVED_IN = "0.3.0"


def moved_warning(old: str, instead: str) -> str:
    """What an old import path says: when it goes, and what to write instead (``instead``:
    ``import Node from roomba_bt.mission.plan instead``)."""
    return f"{old} is deprecated and goes in roomba-bt {REMOVED_IN}: {instead}"


def warn_moved_module(old: str, instead: str) -> None:
    """Called at the top of a module kept only for old imports: the warning is the
    importer's, at its ``import`` line (the import system's frames are skipped), once a
    process, as a module runs once."""
    warnings.warn(moved_warning(old, instead), DeprecationWarning, stacklevel=3)


def moved_names(module: str, home_of: Mapping[str, str]) -> Callable[[str], Any]:
    """The module ``__getattr__`` (PEP 562) of ``module`` for names it kept only for old
    imports: each name -> the module that holds it now (``"roomba_bt.oi.frames"``, or
    ``"roomba_bt.transport.testing:WriteLogTransport"`` for a name renamed there, the name
    itself for a module it imported, ``"logging": "logging"``). The very
    object is returned with a DeprecationWarning at the importer's line, every time it is
    asked for (nothing is cached in the namespace, so a second importer is told too; the
    warnings filter says each line once)."""

    def __getattr__(name: str) -> Any:
        home = home_of.get(name)
        if home is None:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        home_module, _, new_name = home.partition(":")
        new_name = new_name or name
        if home_module == name:  # a module the old one imported: ``declare.logging``
            instead = f"import {name} instead"
        else:
            instead = f"import {new_name} from {home_module} instead"
        warnings.warn(moved_warning(f"{module}.{name}", instead), DeprecationWarning, stacklevel=2)
        imported = importlib.import_module(home_module)
        return imported if home_module == name else getattr(imported, new_name)

    return __getattr__
