"""A blackboard value as the monitor's page shows it: readable JSON-like text.

A mission's record key holds a dict and a ``mark`` an :class:`~roomba_bt.robot.interface.
Odometry` (a NamedTuple); shown as their Python repr they read ``{'room': 'kitchen',
'turn': 90.0}`` and ``Odometry(x_mm=12.5, ..., theta_rad=1.5707963267948966,
left_counts=None, ...)``: a parent on a phone reads ``{"room": "kitchen", "turn": 90.0}`` and
``{"x_mm": 12.5, ..., "theta_rad": 1.5708, "left_counts": null, ...}``. A value whose class
says itself how it reads (its own ``__repr__``: the cover's map, a docking run) keeps its
own words.
"""

from __future__ import annotations

import dataclasses
from collections import namedtuple
from collections.abc import Iterator
from json.encoder import encode_basestring  # json.dumps's quoting of a str, in C
from typing import Any

#: the longest text a blackboard value is kept (and shown) as
TEXT_LIMIT = 200
#: the code of the ``__repr__`` every ``namedtuple`` (and ``typing.NamedTuple``) class gets
#: unless its body defines one: a NamedTuple with this repr is a plain record
_NAMEDTUPLE_REPR = namedtuple("_Probe", "field").__repr__.__code__
#: decimals a float keeps: a tenth of a micrometre in mm, of a microradian in rad
_DECIMALS = 4


def board_text(value: Any) -> str:
    """``value`` as the blackboard panel shows it, cut to :data:`TEXT_LIMIT` characters."""
    try:
        text = _readable(value, ())
    except Exception as exc:  # a plugin's repr: never the tick's end
        text = f"<{type(value).__name__}: its text failed: {exc!r}>"
    return text if len(text) <= TEXT_LIMIT else text[: TEXT_LIMIT - 3] + "..."


def _readable(value: Any, within: tuple[int, ...]) -> str:
    """JSON's words for what JSON has (``true``, ``null``, ``"text"``, ``[...]``, ``{...}``),
    floats rounded to :data:`_DECIMALS`; anything else its own repr. ``within``: the ids of
    the lists and records ``value`` is inside. One holding itself reads as Python's repr says
    it (``[[...]]``), and nesting deeper than the text is shown stops there: walked to the
    recursion limit, the ``RecursionError`` came out of whatever the interpreter ran at that
    depth too (a garbage collection's finalizers failed, unraisable)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return encode_basestring(value)
    if isinstance(value, float):
        return repr(round(value, _DECIMALS) + 0.0)  # + 0.0: no "-0.0"
    if isinstance(value, int):
        return repr(value)  # an IntEnum's too: <Side.LEFT: 1>
    fields = _record_fields(value)
    listed = type(value) is list or type(value) is tuple  # a subclass may say how it reads
    if fields is None and not listed:
        return repr(value)
    brackets = "[]" if fields is None else "{}"
    if id(value) in within:
        return f"{brackets[0]}...{brackets[1]}"
    if len(within) >= TEXT_LIMIT:  # each level writes a bracket: past what is shown
        return "..."
    inner = (*within, id(value))
    if fields is not None:
        return _joined(
            (f"{encode_basestring(str(k))}: {_readable(v, inner)}" for k, v in fields), "{}"
        )
    return _joined((_readable(item, inner) for item in value), "[]")


def _joined(parts: Iterator[str], brackets: str) -> str:
    """``parts`` between ``brackets``, comma-separated, made only until the text is longer
    than it is shown (a list of 10 000 points would be made whole, then cut to 200)."""
    text = brackets[0]
    for part in parts:
        text += part if text == brackets[0] else ", " + part
        if len(text) > TEXT_LIMIT:
            return text
    return text + brackets[1]


def _record_fields(value: Any) -> list[tuple[Any, Any]] | None:
    """A record's fields in order: a dict's items, a NamedTuple's or a dataclass's
    fields; None for anything else, or for a record whose class has its own ``__repr__``."""
    if isinstance(value, dict):  # not the Mapping ABC: its first check of a class is slow
        return list(value.items())
    kind = type(value)
    if isinstance(value, tuple) and hasattr(kind, "_fields"):
        if getattr(kind.__repr__, "__code__", None) is not _NAMEDTUPLE_REPR:
            return None
        return list(zip(kind._fields, value, strict=True))
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = [(f.name, getattr(value, f.name)) for f in dataclasses.fields(value) if f.repr]
        # the repr the decorator writes, or the class's own (kept: it says how it reads)
        generated = ", ".join(f"{name}={field!r}" for name, field in fields)
        return fields if repr(value) == f"{kind.__qualname__}({generated})" else None
    return None
