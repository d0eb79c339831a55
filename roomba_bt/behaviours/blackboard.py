"""The mission's blackboard: its keys, ``@key`` references, and reading and writing them.

A mission's keys live on py_trees' blackboard under :data:`MISSION_NAMESPACE` (``leg`` is
``/mission/leg``), read and written straight through its store (:func:`read_key`,
:func:`write_key`): no py_trees client per node, which registers every key it may touch and
checks it on every access. py_trees' store is one for the process, so each run has a part
of it of its own, a :class:`RunBoard` (:func:`claim_board`): the plain names
(``/mission/leg``, ``/roomba/snapshot``) for the run that claims them while no other run
is going, and under a prefix of its own (``/roomba-bt/run-2/mission/leg``) for a run that
starts while another goes on in the process (``stack.ticks()`` loops stepped in turn,
episodes in threads). The run's thread finds its board (:func:`run_board`), so
:func:`read_key` and :func:`write_key` (a plugin's too) read and write its own keys; its
keys are removed when the run is closed (:meth:`RunBoard.release`), so that the next run
starts with none of them. A key the mission declares (``blackboard:``, :func:`declare_keys`)
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
import itertools
import logging
import re
import sys
import threading
import uuid
import weakref
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import py_trees

from roomba_bt.behaviours.units import MARK, UnitError, ValueType, closest, closest_name, held
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
#: The run's trail, the floor it has just driven (``behaviours/reversing.py``: what
#: ``backtrack`` may back over): the run's own bookkeeping, no key a user wrote or reads.
TRAIL_KEY = "/roomba/trail"
#: Mission blackboard keys live under this namespace: ``leg`` is ``/mission/leg``.
MISSION_NAMESPACE = "/mission/"
#: A run that starts while another goes on in the process keeps its keys under this
#: namespace and a number of its own: ``/roomba-bt/run-2/mission/leg`` (:func:`claim_board`)
RUNS_NAMESPACE = "/roomba-bt/run-"


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
    reach the robot, or a command's encoder, as the behaviour's own bug.

    The fault is the writer's, not the reader's, which only refused the value: the
    message names the key's last writer and the line that wrote it (:func:`last_write`;
    ``written_at``, ``"at keys.py:9"``, what the runtime's error points to in place of the
    reader's ``read_parameters``), when :func:`write_key` wrote it. A run's error pointed
    at roomba-bt's own ``base.py`` and the user went looking for a bug in ``drive``."""

    def __init__(self, node: RobotBehaviour, pname: str, ref: BlackboardRef, problem: str):
        self.node, self.param, self.ref = node, pname, ref
        write = last_write(ref.key)
        #: who wrote the value last (``write_key``'s ``writer``), None when unknown
        self.writer: str | None = write[0] if write is not None else None
        #: ``at file:line`` of the ``write_key`` call, "" when unknown
        self.written_at = f"at {write[1]}:{write[2]}" if write is not None else ""
        blamed = ""
        if write is not None:
            by = "" if write[0] == _MISSION_WRITER_NAME else f" by {write[0]!r}"
            blamed = (
                f"; the value was written last{by} ({self.written_at}): the fault is that "
                f"writer's, {node.declaration.name} only refused the value"
            )
        super().__init__(
            f"{node.declaration.name} {node.name!r}: {pname} is {ref}, and blackboard key "
            f"{str(ref)[1:]!r} holds a value out of its range: {problem}{blamed}"
        )


#: the name write_key gives the mission's own writes in py_trees' activity stream
_MISSION_WRITER_NAME = "roomba-bt mission"
#: the py_trees client the declared keys are registered with (:func:`declare_keys`)
MISSION_CLIENT_NAME = _MISSION_WRITER_NAME
#: the id the mission's own writes (``set``, ``mark``, ``for_each``, initial values) carry in
#: py_trees' activity stream while no mission client is registered (:func:`declare_keys`)
_MISSION_WRITER = uuid.uuid4()


class RunBoard:
    """One run's part of py_trees' blackboard: the names its keys have there (``prefix``
    before each: ``""`` for the plain names, ``/roomba-bt/run-2`` for a run beside
    another), the mission's py_trees client, and the undeclared keys it warned of.

    py_trees keeps one store for the process (``Blackboard.storage``); two runs writing the
    same names in it read each other's values (a 200 mm leg driven 900 mm, a coverage map
    shared by two robots) and a run read the keys a run before it left (``UnwrittenKey``
    never raised). A board is what keeps them apart: :func:`claim_board` gives each run one,
    and the run's thread holds it while the run goes on (:func:`run_board`)."""

    __slots__ = (
        "__weakref__",
        "client",
        "hints",
        "meant",
        "mission",
        "prefix",
        "running",
        "said",
        "snapshot_key",
        "types_key",
        "writer",
        "written",
    )

    def __init__(self, prefix: str) -> None:
        self._named(prefix)
        #: the py_trees client holding the declared keys (:func:`declare_keys`), None: none
        self.client: py_trees.blackboard.Client | None = None
        #: the keys written this run that the mission does not declare, each warned of once,
        #: with who wrote it first and where (``" by 'writer' at plugin.py:12"``)
        self.said: dict[str, str] = {}
        #: of those keys, the declared key each may be a misspelling of (`` (did you mean
        #: 'dirt_level'?)``), "" for none: ``dirt_levl`` ran silently beside ``dirt_level``
        self.hints: dict[str, str] = {}
        #: the same as names (``{"dirt_levl": "dirt_level"}``), for an evaluation's records:
        #: its report says the hint again from them (``eval --from``)
        self.meant: dict[str, str] = {}
        #: claimed and not yet ended (:meth:`ended`): its names are not another run's to take
        self.running = False
        #: the runtime's py_trees client, the snapshot's writer (:meth:`write_snapshot`),
        #: from the run's claim (:meth:`started`) to its end
        self.writer: py_trees.blackboard.Client | None = None
        #: each key's last writer by :func:`write_key` and the line that called it
        #: (``("set_speed(key=v)", "/home/me/keys.py", 9)``): what :class:`KeyRange` names
        self.written: dict[str, tuple[str, str, int]] = {}

    def _named(self, prefix: str) -> None:
        """Its names from ``prefix`` on; the prefix set last, the names it makes first (a
        thread reading the board meanwhile finds one set or the other whole)."""
        #: the mission's keys' names begin with this: ``/mission/``, ``/roomba-bt/run-2/mission/``
        self.mission = prefix + MISSION_NAMESPACE
        #: where the runtime writes each tick's snapshot (:data:`SNAPSHOT_KEY`)
        self.snapshot_key = prefix + SNAPSHOT_KEY
        #: where :func:`declare_keys` keeps the declared types (:data:`KEY_TYPES_KEY`)
        self.types_key = prefix + KEY_TYPES_KEY
        self.prefix = prefix

    def __repr__(self) -> str:
        return f"<RunBoard {self.prefix or '(plain names)'}>"

    def name(self, key: str) -> str:
        """The name ``key`` (a name as the process's only run has it: ``/roomba/cover/map``)
        has in this run: ``/roomba-bt/run-2/roomba/cover/map`` for a run beside another."""
        return self.prefix + key

    def read(self, key: str) -> Any:
        """:func:`read_key` on this run's keys (from another thread: a program's loop, an
        evaluation reading an episode's keys at its end)."""
        storage = py_trees.blackboard.Blackboard.storage
        if "." not in key:
            return storage.get(self.mission + key)
        name, _, field = key.partition(".")
        record = storage.get(self.mission + name)
        return record.get(field) if isinstance(record, Mapping) else None

    def names(self) -> list[str]:
        """This run's names in py_trees' store: under its prefix; with the plain names,
        those under ``/mission/`` and ``/roomba/`` (the keys of the runtime and its
        behaviours), a program's own keys elsewhere being its own."""
        storage = py_trees.blackboard.Blackboard.storage
        if self.prefix:
            start = self.prefix + "/"
            return [name for name in list(storage) if name.startswith(start)]
        return [name for name in list(storage) if name.startswith(("/mission/", "/roomba/"))]

    def shown(self) -> dict[str, Any]:
        """What the monitor shows of the blackboard: every key by the name a user knows
        (``/mission/leg``, this run's prefix taken off), the snapshot, the declared types
        (not keys) and the run's trail left out; with the plain names, a program's own keys
        too, but no key of another run."""
        storage = py_trees.blackboard.Blackboard.storage
        if self.prefix:
            start, cut = self.prefix + "/", len(self.prefix)
            board = {name[cut:]: value for name, value in list(storage.items())
                     if name.startswith(start)}  # fmt: skip
        else:
            board = storage.copy()  # two C calls: a third of a comprehension's time
            if _Claims.beside:
                for name in [name for name in board if name.startswith(RUNS_NAMESPACE)]:
                    del board[name]
        board.pop(SNAPSHOT_KEY, None)
        board.pop(KEY_TYPES_KEY, None)
        board.pop(TRAIL_KEY, None)
        return board

    def values(self) -> dict[str, Any]:
        """The mission's keys and their values (``leg``, not ``/mission/leg``): those the
        mission declares, each once written; a tree that declares none (built in Python):
        every key under ``/mission/``."""
        storage = py_trees.blackboard.Blackboard.storage
        mission = self.mission
        declared = storage.get(self.types_key)
        if declared:
            return {key: storage[mission + key] for key in declared if mission + key in storage}
        cut = len(mission)
        return {name[cut:]: value for name, value in list(storage.items())
                if name.startswith(mission)}  # fmt: skip

    def replace_client(self, keys: Iterable[str]) -> None:
        """The mission's py_trees client, holding ``keys`` (read and write), in place of the
        one before. Registered, never used to read or write: py_trees' client checks every
        access (its permissions, the key's name parsed), which on the tick path cost more
        than the write itself; the store is written directly and the registration is what
        py_trees' display and ``Blackboard.keys()`` read."""
        self._drop_client()
        keys = sorted(keys)
        if not keys:
            return
        client = py_trees.blackboard.Client(
            name=MISSION_CLIENT_NAME, namespace=self.mission.rstrip("/")
        )
        for key in keys:
            client.register_key(key=key, access=py_trees.common.Access.WRITE)
            client.register_key(key=key, access=py_trees.common.Access.READ)
        self.client = client

    def move_to(self, prefix: str) -> None:
        """The keys copied under ``prefix``, the board renamed to it, the old names removed,
        in that order (:func:`_moved_aside`); the py_trees client dropped."""
        storage = py_trees.blackboard.Blackboard.storage
        names = self.names()
        for name in names:
            storage[prefix + name] = storage[name]
        self._drop_client()
        self._named(prefix)
        for name in names:
            storage.pop(name, None)

    def _drop_client(self) -> None:
        old, self.client = self.client, None
        _unregister(old)

    def writer_id(self) -> uuid.UUID:
        """The id :func:`write_key` says a mission write came from: the client's while one
        is registered (py_trees' display of the stream names it), else the module's own."""
        client = self.client
        if client is None:
            return _MISSION_WRITER
        registered: uuid.UUID = client.unique_identifier  # py_trees' Client types it Any
        return (
            registered if registered in py_trees.blackboard.Blackboard.clients else _MISSION_WRITER
        )

    def started(self) -> None:
        """The run has claimed it: the runtime's client registers the snapshot's key,
        which py_trees' display then shows, as a plain behaviour's client reads it."""
        self.running = True
        self.writer = py_trees.blackboard.Client(name="roomba-bt runtime")
        self.writer.register_key(key=self.snapshot_key, access=py_trees.common.Access.WRITE)

    def write_snapshot(self, snapshot: object) -> None:
        """The tick's snapshot written through the runtime's client, while py_trees'
        activity stream is on (``Blackboard.enable_activity_stream()``), which then shows
        it; else the runtime writes the store directly (the client's checks cost more than
        the rest of the tick's snapshot)."""
        if self.writer is not None:
            self.writer.set(self.snapshot_key, snapshot, overwrite=True)

    def ended(self) -> None:
        """The run has ended: its snapshot's key goes with the runtime's client (no frame
        comes after the end); its keys stay for the program to read (:meth:`values`,
        ``stack.runner.blackboard``) until :meth:`release`, and its names may go to the
        next run."""
        self.running = False
        writer, self.writer = self.writer, None
        if writer is not None:
            with contextlib.suppress(Exception):  # a Blackboard.clear() forgot it already
                writer.unregister(clear=True)

    def release(self) -> None:
        """The run is closed (``stack.close()``): its keys are removed from py_trees' store
        and its client unregistered, so that no later run in the process reads them (a key
        it does not write is then unwritten: ``UnwrittenKey``, as in a fresh process). Once
        is enough: a second release finds nothing of its own."""
        with _Claims.lock:
            self.running = False
            if self.prefix:
                _Claims.beside.discard(self.prefix)
            elif _Claims.plain is self:
                _Claims.plain = None
            else:
                return
            self._forget()

    def _forget(self) -> None:
        self._drop_client()
        storage = py_trees.blackboard.Blackboard.storage
        for name in self.names():
            storage.pop(name, None)
        self.said.clear()
        self.hints.clear()
        self.meant.clear()
        self.written.clear()


def _unregister(client: py_trees.blackboard.Client | None) -> None:
    """``client``'s keys and itself taken off py_trees' registry, the values kept (a
    client a ``Blackboard.clear()`` forgot already: nothing to do)."""
    blackboard = py_trees.blackboard.Blackboard
    if client is not None and client.unique_identifier in blackboard.clients:
        # Each key once: py_trees' own unregister() unregisters a key registered both to
        # read and to write twice, and the second raises KeyError (py_trees 2.6)
        with contextlib.suppress(KeyError):
            for key in {*client.read, *client.write}:
                client.unregister_key(key, clear=False, update_namespace_cache=False)
        del blackboard.clients[client.unique_identifier]


class _Claims:
    """Which run holds which names (:func:`claim_board`), changed under ``lock``."""

    #: re-entrant: a board let go of inside :func:`claim_board` is forgotten at once, in it
    lock = threading.RLock()
    #: the board holding the plain names (None: none since the last one was released)
    plain: RunBoard | None = None
    #: the prefixes of the boards beside it, not yet released
    beside: ClassVar[set[str]] = set()
    numbers = itertools.count(2)


def claim_board() -> RunBoard:
    """A board for a run starting now: the plain names if no run that is still going holds
    them, else a prefix of its own (``/roomba-bt/run-2``). So the process's only run has its
    keys where py_trees programs and the docs look (``/mission/leg``, ``/roomba/snapshot``),
    and runs side by side (``ticks()`` loops stepped in turn, episodes in threads) never
    share one. A run that ended and is not closed yet gives the plain names up: its keys
    move under a prefix of their own, its board with them, where its program still reads
    them (an evaluation's keys at an episode's end, read while the next episode starts in
    another thread) until it closes it; a board no longer held takes them with it."""
    with _Claims.lock:
        holder = _Claims.plain
        if holder is None or not holder.running:
            if holder is not None:
                _moved_aside(holder)
            board = _Claims.plain = RunBoard("")
        else:
            board = RunBoard(_new_prefix())
        board.started()
        return board


def _new_prefix() -> str:
    prefix = f"{RUNS_NAMESPACE}{next(_Claims.numbers)}"
    _Claims.beside.add(prefix)
    return prefix


def _moved_aside(board: RunBoard) -> None:
    """``board``'s keys (a run that ended, not closed) moved from the plain names to a new
    prefix, the board renamed to it: copied first, the board renamed, the plain names then
    removed (its program, reading it in another thread, finds its keys at every moment).
    Its py_trees client goes (the plain names are the next run's to register); its keys go
    when it is released, or when nothing holds the board any longer."""
    prefix = _new_prefix()
    board.move_to(prefix)
    weakref.finalize(board, _forgotten, prefix)


def _forgotten(prefix: str) -> None:
    """The keys under ``prefix`` of a board no longer held (its stack never closed)."""
    with _Claims.lock:
        _Claims.beside.discard(prefix)
        storage = py_trees.blackboard.Blackboard.storage
        for name in [name for name in list(storage) if name.startswith(prefix + "/")]:
            storage.pop(name, None)


class _Running(threading.local):
    """The board of the run going on in this thread (:func:`run_board`)."""

    #: outside a run: the plain names (a program's own ``write_key`` before a run, a
    #: ``CompiledMission.setup`` called by hand)
    board = RunBoard("")


_RUNNING = _Running()


def run_board() -> RunBoard:
    """The board of the run going on in this thread (the plain names outside a run): what
    :func:`read_key` and :func:`write_key` read and write."""
    return _RUNNING.board


@contextlib.contextmanager
def running_on(board: RunBoard, *, ends_run: bool = True) -> Iterator[RunBoard]:
    """``board`` this thread's run's board while the block runs (a run's set-up, ticks and
    ending), the one before it afterwards; the block's end, however it ends, is the run's
    (:meth:`RunBoard.ended`), unless ``ends_run`` is False: a thread lent the run's board for
    a part of its ending (the tree's stop, ``runtime/ending.py``), whose ``terminate()``
    calls read and write keys as they would in the run's own thread."""
    before = _RUNNING.board
    _RUNNING.board = board
    try:
        yield board
    finally:
        _RUNNING.board = before
        if ends_run:
            board.ended()


class SharedBlackboard(RuntimeError, RoombaBtError):
    """A run started beside another in the process (its keys under a prefix of their own,
    :func:`claim_board`) whose tree has a node with keys of a py_trees client
    (``attach_blackboard_client``, ``register_key``): such a key has the one name for the
    process, so the two runs would read and write each other's value (a snapshot, a count)
    with no word. Said before the tree's first tick rather than left to a wrong result."""


def check_alone(board: RunBoard, root: py_trees.behaviour.Behaviour) -> None:
    """Raise :class:`SharedBlackboard` if ``board`` is a run's beside another and a node of
    ``root`` holds keys through a py_trees client of its own; with the plain names (the
    process's only run) its keys are its own, as they always were."""
    if not board.prefix:
        return
    for node in root.iterate():
        for client in node.blackboards:
            names = sorted({*client.read, *client.write, *client.exclusive})
            if names:
                raise SharedBlackboard(
                    f"{node.name!r} ({type(node).__name__}) uses py_trees blackboard keys "
                    f"{', '.join(names)} through a py_trees client, and another roomba-bt run "
                    "is going on in this process: py_trees keeps one blackboard for the "
                    "process, so the two runs would read each other's values. Run this tree "
                    "when no other run is going, or keep its keys with write_key and "
                    "read_key, which are each run's own"
                )


def read_key(key: str) -> Any:
    """A mission blackboard key's value (None if never written); ``key.field``, a record
    key's field (None if the record was never written), as py_trees' own ``key.attribute``
    reads one and ``@key.field`` does: ``check: {key: wp.distance}``. This thread's run's
    key (:func:`run_board`)."""
    return _RUNNING.board.read(key)


def declared_type(key: str) -> ValueType | None:
    """The type this thread's run's mission declares for ``key`` (``key.field``: the
    record's field's), None for a key it does not declare or a tree built in Python: what a
    message writes a value in (``500 mm``, where the key holds ``500.0``)."""
    types = py_trees.blackboard.Blackboard.storage.get(_RUNNING.board.types_key) or {}
    name, _, field = key.partition(".")
    vtype = types.get(name)
    return dict(vtype.fields).get(field) if vtype is not None and field else vtype


def declare_keys(types: Mapping[str, ValueType]) -> None:
    """The mission's keys and their declared types (``blackboard:``), which
    :func:`write_key` holds every write to from now on; they replace those declared before
    (``declare_keys({})``: none; a write to a key not declared is then warned of, once a
    key, :func:`write_key`). ``CompiledMission.setup`` calls it before each run. Kept
    on py_trees' blackboard (:data:`KEY_TYPES_KEY`, under this run's prefix), with the
    values: its ``clear()``, which a test calls between missions, forgets them too. Each key
    is registered (read and write) with the mission's py_trees client
    (:data:`MISSION_CLIENT_NAME`), so that py_trees' display, ``Blackboard.keys()`` and its
    activity stream see them; the values stay after the run, for a program to look at,
    until the run is closed (:meth:`RunBoard.release`)."""
    board = _RUNNING.board
    py_trees.blackboard.Blackboard.storage[board.types_key] = dict(types)  # {}: still said
    board.said.clear()
    board.hints.clear()
    board.meant.clear()
    board.written.clear()
    board.replace_client(types)


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


def undeclared_writes(board: RunBoard | None = None) -> tuple[tuple[str, str], ...]:
    """Each key written this run (since the mission's :func:`declare_keys`; ``board``'s run,
    else this thread's) that the mission does not declare, with who wrote it first and where
    (``" by 'writer' at plugin.py:12"``), in the order written: what the warning said, for
    an evaluation, whose episodes' log lines are silenced, to count the episodes it was said
    in and say it once."""
    return tuple((board or _RUNNING.board).said.items())


def undeclared_meant(board: RunBoard | None = None) -> tuple[tuple[str, str], ...]:
    """Each undeclared key written this run (:func:`undeclared_writes`) that may be a
    misspelling of a declared key, with that key: ``(("dirt_levl", "dirt_level"),)``. What
    an evaluation records beside the writes, so that its report says `` (did you mean
    'dirt_level'?)`` as ``run``'s summary does (:func:`undeclared_hinted`)."""
    return tuple((board or _RUNNING.board).meant.items())


def undeclared_hinted(board: RunBoard) -> tuple[tuple[str, str, str], ...]:
    """:func:`undeclared_writes` of ``board``'s run, each with the declared key it may be a
    misspelling of (`` (did you mean 'dirt_level'?)``, "" for none): what ``run``'s summary
    says and ``--strict`` counts."""
    return tuple((key, where, board.hints.get(key, "")) for key, where in board.said.items())


def _said_undeclared(
    board: RunBoard, key: str, writer: str, declared: Mapping[str, ValueType]
) -> None:
    """A warning, once a key a run, that ``writer`` wrote ``key``, which the mission's
    ``blackboard:`` does not declare, and where (the line that called :func:`write_key`),
    with the declared key it may be a misspelling of. Written all the same, as a tree built
    in Python writes any key: nothing drives on it, where an undeclared command
    (``UndeclaredCommand``) escapes the mode check and is refused; but no ``check`` or
    ``@key`` of the mission can read it, no type holds it, and the validator never saw it
    (a key a parameter names it checks: ``writes_keys``). A misspelt key ran silently."""
    caller = sys._getframe(2)  # write_key's caller: the plugin's line
    where = f" at {caller.f_code.co_filename}:{caller.f_lineno}"
    by = "" if writer == _MISSION_WRITER_NAME else f" by {writer!r}"
    board.said[key] = by + where
    names = sorted(declared)
    hint = board.hints[key] = closest(key, names)
    meant = closest_name(key, names)
    if hint and meant is not None:
        board.meant[key] = meant
    keys = ", ".join(names) or "none"
    _log.warning(
        "write_key(%r)%s%s: blackboard key %r is not declared by the mission%s (it declares: "
        "%s), so no check or @%s of the mission reads it; declare it under blackboard: "
        "(%s: {type: ...}), or name a declared key in a parameter listed in writes_keys",
        key, by, where, key, hint, keys, key, key,
    )  # fmt: skip


def unwrite_keys(keys: Iterable[str]) -> None:
    """Forget the values of ``keys``: a run's set-up does, for the keys its mission declares
    without an ``initial:`` value, so that the run starts with them unwritten (a compiled
    mission's ``setup`` called again by hand, outside a run, whose board is the plain
    names')."""
    board = _RUNNING.board
    storage = py_trees.blackboard.Blackboard.storage
    for key in keys:
        storage.pop(board.mission + key, None)
        board.written.pop(key, None)


def last_write(key: str) -> tuple[str, str, int] | None:
    """Who wrote ``key`` (``key.field``: the record) last this run, by :func:`write_key`,
    and the file and line that called it: ``("set_speed(key=v)", "/home/me/keys.py", 9)``;
    None when nothing wrote it through :func:`write_key` (a py_trees client's own write)."""
    return _RUNNING.board.written.get(key.partition(".")[0])


def write_key(key: str, value: Any, writer: str = _MISSION_WRITER_NAME) -> None:
    """Write a mission key, this thread's run's (:func:`run_board`). Into the store directly
    (no py_trees client per node: a client registers each key it may touch and checks it
    on every access), and, when py_trees' activity stream is on
    (``Blackboard.enable_activity_stream()``), said there as a client's write would be: a
    py_trees user's tools show ``/mission/leg`` changing. A key the mission declared
    (:func:`declare_keys`) takes only a value of its type: else :class:`KeyType`, and
    nothing is written. One it did not declare is written, with a warning once a key
    (:func:`_said_undeclared`)."""
    board = _RUNNING.board
    blackboard = py_trees.blackboard.Blackboard
    types = blackboard.storage.get(board.types_key)
    vtype = types.get(key) if types is not None else None
    if vtype is not None:
        problem = _write_problem(vtype, value)
        if problem is not None:
            raise KeyType(key, vtype, value, problem, writer)
    elif types is not None and key not in board.said:
        _said_undeclared(board, key, writer, types)
    caller = sys._getframe(1)  # the line a KeyRange names, should a reader refuse the value
    board.written[key] = (writer, caller.f_code.co_filename, caller.f_lineno)
    name = board.mission + key
    stream = blackboard.activity_stream
    if stream is not None:
        had = name in blackboard.storage
        kind = py_trees.blackboard.ActivityType
        stream.push(
            py_trees.blackboard.ActivityItem(
                key=name,
                client_name=writer,
                client_id=board.writer_id(),
                # its value, as py_trees' own clients push it (its display compares with it)
                activity_type=(kind.WRITE if had else kind.INITIALISED).value,
                previous_value=blackboard.storage.get(name) if had else None,
                current_value=value,
            )
        )
    blackboard.storage[name] = value
