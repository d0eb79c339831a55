"""Where a method's source returned a value, told from its text, for an error about the value.

Once a method has returned, the value carries no trace of the ``return`` that produced it
(tracing every call to keep one would cost every tick). What can be told honestly is read
from the source: a ``return Status.INVALID`` (or ``return None``, ``return 'no'``) that is the
only statement in the method able to give that value. A computed value (``return
self.status``) could come from any such return, so then only the method's ``def`` is named.
"""

from __future__ import annotations

import ast
import enum
import inspect
import textwrap
from collections.abc import Callable, Iterator
from typing import Any


def returned_from(method: Callable[..., Any], value: object) -> str:
    """``"at FILE:LINE"`` of the one ``return`` in ``method`` that can have returned
    ``value``; ``"NAME() defined at FILE:LINE, which ends without a return"`` when only
    reaching its end gives it (``value`` None); else ``"NAME() defined at FILE:LINE"``.
    Raises ``OSError`` or ``TypeError`` when the source cannot be read (``inspect``)."""
    lines, first = inspect.getsourcelines(method)
    func = ast.parse(textwrap.dedent("".join(lines))).body[0]
    if not isinstance(func, ast.FunctionDef | ast.AsyncFunctionDef):
        raise TypeError(f"{method!r} is not a function written with def")
    path, at = inspect.getsourcefile(method), first - 1  # the text's line 1 is ``first``
    defined = f"{func.name}() defined at {path}:{func.lineno + at}"
    returns: list[int] = []  # the returns that can have given ``value``
    certain = True
    for ret in _returns(func):
        gives = _gives(ret.value, value)
        if gives is not False:
            returns.append(ret.lineno + at)
            certain = certain and gives is True
    ends = value is None and not isinstance(func.body[-1], ast.Return | ast.Raise)
    if ends and not returns:
        return f"{defined}, which ends without a return"
    if len(returns) == 1 and certain and not ends:
        return f"at {path}:{returns[0]}"
    return defined


def _returns(func: ast.FunctionDef | ast.AsyncFunctionDef) -> Iterator[ast.Return]:
    """The ``return`` statements of ``func`` itself (not of a function defined inside)."""
    todo: list[ast.AST] = list(func.body)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Return):
            yield node
        elif not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            todo.extend(ast.iter_child_nodes(node))


def _gives(expr: ast.expr | None, value: object) -> bool | None:
    """Whether a ``return expr`` gives ``value``: told for ``return``, a constant, and a
    member of ``value``'s enum spelt by name (``Status.INVALID``, ``INVALID``); None: it is
    computed, it may."""
    if expr is None:
        return value is None
    if isinstance(expr, ast.Constant):
        return type(expr.value) is type(value) and expr.value == value
    name = expr.attr if isinstance(expr, ast.Attribute) else getattr(expr, "id", None)
    if isinstance(value, enum.Enum) and name in type(value).__members__:
        return name == value.name
    return None
