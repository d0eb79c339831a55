"""The mission's blackboard: its keys, ``@key`` references, and reading and writing them.

A mission's keys live on py_trees' blackboard under :data:`MISSION_NAMESPACE` (``leg`` is
``/mission/leg``), read and written straight through its store (:func:`read_key`,
:func:`write_key`): no py_trees client per node, which registers every key it may touch and
checks it on every access. A key the mission declares (``blackboard:``, :func:`declare_keys`)
takes only values of its type (:class:`KeyType`), and is registered, once, with one py_trees
client of the mission's (:data:`MISSION_CLIENT_NAME`, read and write): py_trees' own
tools (``Blackboard.keys()``, ``py_trees.display.unicode_blackboard()``, its activity
stream) show the mission's keys as they show any client's, at no cost on the tick. A
parameter given as ``@key`` or ``@key.field`` (:class:`BlackboardRef`) is read when its
behaviour starts
(:meth:`RobotBehaviour.initialise <roomba_bt.behaviours.base.RobotBehaviour.initialise>`):
:class:`UnwrittenKey` when nothing wrote it, :class:`KeyRange` when its value is out of the
parameter's range.
"""

from __future__ import annotations

import contextlib
import logging
import re
import sys
import uuid
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import py_trees

from roomba_bt.behaviours.units import MARK, UnitError, ValueType, held
from roomba_bt.errors import RoombaBtError
from roomba_bt.robot.interface import Odometry
from roomba_bt.yamlsource import quoted

if TYPE_CHECKING:
    from roomba_bt.behaviours.base import RobotBehaviour

_log = logging.getLogger("roomba_bt.mission")

#: The blackboard key the runtime mirrors the snapshot under (for plugins that prefer it).
SNAPSHOT_KEY = "/roomba/snapshot"
#: The declared type of each mission key, by name (:func:`declare_keys`): not a key of its own.
KEY_TYPES_KEY = "/roomba/key_types"
#: Mission blackboard keys live under this namespace: ``leg`` is ``/mission/leg``.
MISSION_NAMESPACE = "/mission/"


#: ``@key`` or ``@key.field``: a value read from the blackboard, in YAML and from Python
BLACKBOARD_REF = re.compile(r"^@([a-z_][a-z0-9_]*)(?:\.([a-z_][a-z0-9_]*))?$")


def blackboard_ref(text: str) -> BlackboardRef:
    """``"@leg"`` -> ``BlackboardRef("leg")``; raises :class:`UnitError` for a text that is
    not one (``@Leg``, ``@a.b.c``)."""
    match = BLACKBOARD_REF.match(text)
    if match is None:
        raise UnitError(f"{text!r} is not a blackboard reference (@key or @key.field)")
    return BlackboardRef(*match.groups())


@dataclass(frozen=True, slots=True)
class BlackboardRef:
    """A parameter value read from the blackboard when the behaviour starts: ``@leg`` or
    ``@waypoint.x`` (a field of a record)."""

    key: str
    field: str | None = None

    def __str__(self) -> str:
        return f"@{self.key}" + (f".{self.field}" if self.field else "")


class UnwrittenKey(LookupError, RoombaBtError):
    """A behaviour started with a parameter ``@key`` whose key nothing had written. A
    mission's validator proves every read comes after a write; a tree built in Python has
    no such proof, and None read as a drive's distance would drive without one."""


class KeyRange(ValueError, RoombaBtError):
    """A behaviour started with a parameter ``@key`` whose key holds a value out of the
    parameter's declared range (written by a plugin, which the validator cannot see; it
    checks ``initial`` and ``set`` values and ``for_each`` items). It would otherwise
    reach the robot, or a command's encoder, as the behaviour's own bug."""

    def __init__(self, node: RobotBehaviour, pname: str, ref: BlackboardRef, problem: str):
        self.node, self.param, self.ref = node, pname, ref
        super().__init__(
            f"{node.declaration.name} {node.name!r}: {pname} is {ref}, and blackboard key "
            f"{str(ref)[1:]!r} holds a value out of its range: {problem}"
        )


def read_key(key: str) -> Any:
    """A mission blackboard key's value (None if never written); ``key.field``, a record
    key's field (None if the record was never written), as py_trees' own ``key.attribute``
    reads one and ``@key.field`` does: ``check: {key: wp.distance}``."""
    storage = py_trees.blackboard.Blackboard.storage
    if "." not in key:
        return storage.get(MISSION_NAMESPACE + key)
    name, _, field = key.partition(".")
    record = storage.get(MISSION_NAMESPACE + name)
    return record.get(field) if isinstance(record, Mapping) else None


#: the id the mission's own writes (``set``, ``mark``, ``for_each``, initial values) carry in
#: py_trees' activity stream while no mission client is registered (:func:`declare_keys`)
_MISSION_WRITER = uuid.uuid4()


#: the name write_key gives the mission's own writes in py_trees' activity stream
_MISSION_WRITER_NAME = "roomba-bt mission"
#: the py_trees client the declared keys are registered with (:func:`declare_keys`)
MISSION_CLIENT_NAME = _MISSION_WRITER_NAME


class _MissionClient:
    """The one py_trees client holding the mission's declared keys, replaced by each
    :func:`declare_keys`. Registered at setup, never used to read or write: py_trees'
    client checks every access (its permissions, the key's name parsed), which on the tick
    path cost more than the write itself; the store is written directly and the
    registration is what py_trees' display and ``Blackboard.keys()`` read."""

    client: py_trees.blackboard.Client | None = None

    @classmethod
    def replace(cls, keys: Iterable[str]) -> None:
        old, cls.client = cls.client, None
        blackboard = py_trees.blackboard.Blackboard
        if old is not None and old.unique_identifier in blackboard.clients:
            # (else a Blackboard.clear() since forgot it and its keys.) Each key once, the
            # values kept: py_trees' own unregister() unregisters a key registered both to
            # read and to write twice, and the second raises KeyError (py_trees 2.6)
            with contextlib.suppress(KeyError):
                for key in {*old.read, *old.write}:
                    old.unregister_key(key, clear=False, update_namespace_cache=False)
            del blackboard.clients[old.unique_identifier]
        keys = sorted(keys)
        if not keys:
            return
        client = py_trees.blackboard.Client(
            name=MISSION_CLIENT_NAME, namespace=MISSION_NAMESPACE.rstrip("/")
        )
        for key in keys:
            client.register_key(key=key, access=py_trees.common.Access.WRITE)
            client.register_key(key=key, access=py_trees.common.Access.READ)
        cls.client = client

    @classmethod
    def writer_id(cls) -> uuid.UUID:
        """The id :func:`write_key` says a mission write came from: the client's while one
        is registered (py_trees' display of the stream names it), else the module's own."""
        client = cls.client
        if client is None:
            return _MISSION_WRITER
        registered: uuid.UUID = client.unique_identifier  # py_trees' Client types it Any
        return (
            registered if registered in py_trees.blackboard.Blackboard.clients else _MISSION_WRITER
        )


def declare_keys(types: Mapping[str, ValueType]) -> None:
    """The mission's keys and their declared types (``blackboard:``), which
    :func:`write_key` holds every write to from now on; they replace those declared before
    (``declare_keys({})``: none; a write to a key not declared is then warned of, once a
    key, :func:`write_key`). ``CompiledMission.setup`` calls it before each run. Kept
    on py_trees' blackboard (:data:`KEY_TYPES_KEY`), with the values: its ``clear()``, which
    a test calls between missions, forgets them too. Each key is registered (read and
    write) with the mission's py_trees client (:data:`MISSION_CLIENT_NAME`), so that py_trees'
    display, ``Blackboard.keys()`` and its activity stream see them; the values stay after
    the run, for a program to look at."""
    storage = py_trees.blackboard.Blackboard.storage
    storage[KEY_TYPES_KEY] = dict(types)  # {}: a mission that declares none, still said
    _UNDECLARED_SAID.clear()
    _MissionClient.replace(types)


class KeyType(TypeError, RoombaBtError):
    """A value written to a mission key (a plugin's ``write_key``) that is not of the
    key's declared type in its canonical unit: ``"fast"`` in a speed, ``1`` in a bool. The
    readers take the type for granted; said where it is written, it is not blamed on the
    leaf that reads it later."""

    def __init__(self, key: str, vtype: ValueType, value: Any, problem: str, writer: str):
        self.key, self.type, self.value = key, vtype, value
        by = "" if writer == _MISSION_WRITER_NAME else f" by {writer!r}"
        super().__init__(
            f"write_key({key!r}, {quoted(value)}){by}: blackboard key {key!r} is declared "
            f"{vtype.describe()}: {problem}"
        )


def _write_problem(vtype: ValueType, value: Any) -> str | None:
    if vtype is not MARK:
        return held(vtype, value)
    if isinstance(value, Odometry):  # a mark's form is the robot's, not a written one
        return None
    return f"expected an odometry mark (snapshot.odometry), got a {type(value).__name__}"


#: the keys written this run that the mission does not declare, each warned of once, with
#: who wrote it first and where (``" by 'writer' at plugin.py:12"``)
_UNDECLARED_SAID: dict[str, str] = {}


def undeclared_writes() -> tuple[tuple[str, str], ...]:
    """Each key written this run (since the mission's :func:`declare_keys`) that the mission
    does not declare, with who wrote it first and where (``" by 'writer' at plugin.py:12"``),
    in the order written: what the warning said, for an evaluation, whose episodes' log
    lines are silenced, to count the episodes it was said in and say it once."""
    return tuple(_UNDECLARED_SAID.items())


def _said_undeclared(key: str, writer: str, declared: Mapping[str, ValueType]) -> None:
    """A warning, once a key a run, that ``writer`` wrote ``key``, which the mission's
    ``blackboard:`` does not declare, and where (the line that called :func:`write_key`).
    Written all the same, as a tree built in Python writes any key: nothing drives on it,
    where an undeclared command (``UndeclaredCommand``) escapes the mode check and is
    refused; but no ``check`` or ``@key`` of the mission can read it, no type holds it, and
    the validator never saw it (a key a parameter names it checks: ``writes_keys``). A
    misspelt key ran silently."""
    caller = sys._getframe(2)  # write_key's caller: the plugin's line
    where = f" at {caller.f_code.co_filename}:{caller.f_lineno}"
    by = "" if writer == _MISSION_WRITER_NAME else f" by {writer!r}"
    _UNDECLARED_SAID[key] = by + where
    keys = ", ".join(sorted(declared)) or "none"
    _log.warning(
        "write_key(%r)%s%s: blackboard key %r is not declared by the mission (it declares: "
        "%s), so no check or @%s of the mission reads it; declare it under blackboard: "
        "(%s: {type: ...}), or name a declared key in a parameter listed in writes_keys",
        key, by, where, key, keys, key, key,
    )  # fmt: skip


def unwrite_keys(keys: Iterable[str]) -> None:
    """Forget the values of ``keys``: a run's set-up does, for the keys its mission declares
    without an ``initial:`` value, so that the run starts with them unwritten. The store is
    py_trees' one for the process, and its values stay after a run: the next run in the
    process (the next episode in an evaluation's worker, a monitor's reload) read the one
    before's as its own (``check`` True on a key it never wrote; ``eval --key`` reporting
    another episode's value)."""
    storage = py_trees.blackboard.Blackboard.storage
    for key in keys:
        storage.pop(MISSION_NAMESPACE + key, None)


def write_key(key: str, value: Any, writer: str = _MISSION_WRITER_NAME) -> None:
    """Write a mission key. Into the store directly (no py_trees client per node: a client
    registers each key it may touch and checks it on every access), and, when py_trees'
    activity stream is on (``Blackboard.enable_activity_stream()``), said there as a client's
    write would be: a py_trees user's tools show ``/mission/leg`` changing. A key the
    mission declared (:func:`declare_keys`) takes only a value of its type: else
    :class:`KeyType`, and nothing is written. One it did not declare is written, with a
    warning once a key (:func:`_said_undeclared`)."""
    blackboard = py_trees.blackboard.Blackboard
    types = blackboard.storage.get(KEY_TYPES_KEY)
    vtype = types.get(key) if types is not None else None
    if vtype is not None:
        problem = _write_problem(vtype, value)
        if problem is not None:
            raise KeyType(key, vtype, value, problem, writer)
    elif types is not None and key not in _UNDECLARED_SAID:
        _said_undeclared(key, writer, types)
    name = MISSION_NAMESPACE + key
    stream = blackboard.activity_stream
    if stream is not None:
        had = name in blackboard.storage
        kind = py_trees.blackboard.ActivityType
        stream.push(
            py_trees.blackboard.ActivityItem(
                key=name,
                client_name=writer,
                client_id=_MissionClient.writer_id(),
                # its value, as py_trees' own clients push it (its display compares with it)
                activity_type=(kind.WRITE if had else kind.INITIALISED).value,
                previous_value=blackboard.storage.get(name) if had else None,
                current_value=value,
            )
        )
    blackboard.storage[name] = value
