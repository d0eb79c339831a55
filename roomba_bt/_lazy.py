"""A package's names, each imported from its module when first asked for (PEP 562).

Below every layer (``tests/test_layers.py``): the standard library only, and any package of
ours may use it. ``roomba_bt`` itself and :mod:`roomba_bt.robot` export their names so: an
``import`` of either runs no module of the names it exports, so a command pays only for
what it uses (``tests/cli/test_imports.py``).
"""

from __future__ import annotations

import importlib
import sys
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
