"""The tick guard: the wheels (and the brushes and vacuum) stop when a tick takes too long.

A tick does not block (``docs/runtime.md``), but a behaviour can: a plugin that waits on the
network, a file, ``time.sleep``; a debugger. Meanwhile the robot drives on with its last
Drive: the Open Interface has no command timeout, and the stream watchdog does not trip
(frames keep arriving; nobody reads them). So a thread watches the tick::

    main thread   ─ port ─┤ tick ............................... ├─ port ─ flush ─
    guard         ·········│····· limit ─► drive 0 (if wheels move)│···············
                           │          and motors off (if they run) │
                           release lock                   take lock back

The main thread holds :attr:`TickGuard.lock` whenever it is not inside a tick, so the guard
can write only while the tree is busy and never between the main thread's own bytes (a
command is never cut by another). Once a tick has run for ``limit_s`` with the wheels
commanded to move in Safe or Full, the guard sends drive 0 (the watchdog's action:
:meth:`~roomba_bt.robot.connection.Connection.halt`), once per tick; with a brush or the
vacuum running too (or alone), drive 0 and motors off in one write (:func:`stop_first`, as at
the run's end): a tree that is not in control runs nothing on the robot (a blocked ``update``
of 5 s ran the brushes and vacuum on the spot for 5 s). When the tick returns, the runner
counts it and, as after a watchdog stall, sends the last wheel command and the last Motors
command again unless the tick queued another: the mission goes on where it was.

A tick past the limit with nothing moving (the robot at rest, no built-in cycle that may
drive it: a plugin's first ``update`` that blocks before its first drive) has nothing to
stop, but the guard still notes where it was: the frames the tick leaves unread are then
its own, the robot still, and the run says so (``runtime/clock.py``, ``unread_gap``), where
it said the process had been suspended or starved of CPU while the robot went on with its
last command, and counted an unread gap (whenever the block came out a second or more: a
plugin's ``time.sleep(1)`` did in 1 of 2 real-time runs). So does a tick past the limit
while a built-in cycle (Clean, Spot, Seek Dock: the opcode table's ``BUILTIN_CYCLE``) may
be driving the robot in Passive: the guard ends no cycle (that is the tree's to decide, and
Safe would end it), so it sends nothing, and the run says the cycle went on driving while
the tick blocked.

The run's end is guarded too (:meth:`TickGuard.halt_before_stop`): before the tree's stop,
whose ``terminate()`` calls may block as an ``update`` may, the runner has the guard send the
first half of the safe stop (drive 0, motors off) at once, in the main thread; the whole safe
stop still follows the tree's stop (a ``terminate`` may itself write a command, though none
that sets the robot going again: ``CommandWriter.hold_motion``).

Only a run on the wall clock has one (a robot's port, the real-time simulator); on the
virtual clock the robot does not move while the host thinks. With ``--record`` each act is a
note in the record (its tick, how long the tick had run, where; ``"at": "end"`` for the
halt before the tree's stop), and a replay does it again in the same tick
(:class:`RecordedTickGuard`): the bytes stay the recorded ones. A still tick is a note of
its own (:data:`STILL_NOTE`, which a replay reads to say its gap as the live run did; a
record made before has none, and its replay says such a gap as before).
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from pathlib import PurePath
from typing import Any, Protocol

from roomba_bt.oi import commands as oi
from roomba_bt.oi.encode import Command, turns_wheels
from roomba_bt.oi.modes import DRIVING_MODES
from roomba_bt.robot.connection import Connection
from roomba_bt.runtime.summary import DEFAULT_TICK_LIMIT
from roomba_bt.runtime.teardown import where_in

log = logging.getLogger(__name__)


#: ``slow(seconds, where, halted, cycle)``: the runner's reaction to a tick that ran past the
#: limit, in the ticking thread, lock held, once the tick is over; ``halted``: the guard
#: stopped something in it (False: it sent nothing); ``cycle``: the built-in cycle that may
#: have driven the robot meanwhile, as said (:func:`cycle_said`), "" if none (nothing moved)
Slow = Callable[[float, str, bool, str], None]

#: the record's note of a tick that ran past the limit with nothing moving (the value: how
#: long it had run when the guard saw it); a key of its own, not ``tick_guard``'s, so that an
#: earlier roomba-bt's replay, which reads only those, sends no drive 0 for it
STILL_NOTE = "tick_still"

#: the record's note of a tick that ran past the limit while a built-in cycle may have driven
#: the robot (its ``cycle``: :func:`cycle_said`); a key of its own, not :data:`STILL_NOTE`'s,
#: which an earlier roomba-bt's replay would say as the robot standing still
CYCLE_NOTE = "tick_cycle"

#: where the halt before the tree's stop is noted as done (the record's ``where``)
AT_THE_END = "the run's end, before the tree's stop"

#: the record's key of every note the guard makes of a pass it watched: true where that was
#: work done between two ticks (a program's loop over ``stack.ticks()``:
#: :func:`~roomba_bt.runtime.loop.guarded_between_ticks`), false where it was the tree's
#: tick: the replay does a loop's act there, after the tick's flush, and counts it as the
#: loop's (``loop_slow``, ``loop_halts``) as the run did. A note without it is a record's
#: made before (:func:`loop_noted`)
LOOP_NOTE = "loop"


def loop_noted(note: Mapping[str, Any]) -> bool:
    """Whether the guard's ``note`` was made between two ticks (:data:`LOOP_NOTE`). A record
    made before that key was written (a 0.2.0 development build's) says it only by its
    ``where``: the ticking thread's innermost line, no behaviour on its stack, in Python's
    ``threading.py`` (the worker of a ``stack.ticks()`` loop waiting for the loop to ask for
    the next tick). Its replay counted such a note as the tree's slow tick, and did its act
    inside the tick, before its flush: a tick early. A tree's tick can be there too, in no
    behaviour's method: a py_trees visitor's ``initialise()`` or ``finalise()`` waiting on a
    lock, an event, a full queue (all in ``threading.py``); the key, written on every note
    since, tells them apart, and so do the records that could hold no loop's note
    (:func:`tree_notes_of`). Only an older program's own record with both is read by this
    guess."""
    if LOOP_NOTE in note:
        return note[LOOP_NOTE] is True
    where = str(note.get("where", ""))
    return where.startswith("at ") and PurePath(where[3:].rsplit(":", 1)[0]).name == "threading.py"


def tree_notes_of(
    notes: Iterable[dict[str, Any]], program_since_ticks: bool
) -> list[dict[str, Any]]:
    """``notes`` as a replay reads them: where the record could hold no note of a program's
    loop (``program_since_ticks`` False: a ``run --record``'s, whose header has its options,
    or 0.1.0's, which names no release: neither ran a loop over ``stack.ticks()``), each of
    the guard's notes without :data:`LOOP_NOTE` is the tree's, said so (a copy), whatever
    its ``where`` names (:func:`loop_noted`'s guess is for the others)."""
    if program_since_ticks:
        return list(notes)
    guarded = ("tick_guard", STILL_NOTE, CYCLE_NOTE)
    return [
        {**note, LOOP_NOTE: False}
        if LOOP_NOTE not in note and any(key in note for key in guarded)
        else note
        for note in notes
    ]


def wheels_moving(connection: Connection) -> bool:
    """The last wheel command drives, in a mode where the robot obeys it: the writer's
    record of what went on the wire (``CommandWriter.last_wheels``), the runtime's own drive
    0s included (the monitor's pause, the bump reflex's hold, the watchdog's) and forgotten
    at the robot's own fall to Passive, as the outbox's ``standing`` is. The stall's ride
    reads that one instead (runtime/stall.py): it gives back the tree's command those drive
    0s replaced, which this record no longer holds."""
    wheels = connection.writer.last_wheels
    return wheels is not None and turns_wheels(wheels) and connection.mode in DRIVING_MODES


def motors_running(connection: Connection) -> bool:
    """The last Motors command written runs a brush or the vacuum, in a mode where the robot
    obeys it (:meth:`CommandWriter.motors_running
    <roomba_bt.robot.writer.CommandWriter.motors_running>`, as the watchdog asks it)."""
    return connection.writer.motors_running()


def cycle_said(connection: Connection) -> str:
    """The built-in cycle that may be driving the robot (``CommandWriter.cycle_may_drive``),
    as a sentence says it: ``the robot's Clean (135) cycle`` (one the run wrote), ``a cycle
    the robot started by itself`` (a button, its schedule); "" when none may be."""
    writer = connection.writer
    if not writer.cycle_may_drive:
        return ""
    running = writer.running_cycle
    if running is None:
        return "a cycle the robot started by itself"
    return f"the robot's {running.spec.title} ({running.spec.opcode}) cycle"


#: the guard's drive 0 as the end's report says it (``CommandWriter.own_stop``)
TICK_GUARD = "the tick guard's drive 0"


def halt_blocked(connection: Connection) -> bool:
    """The guard's act on a tick that blocks: drive 0, and motors off in the same write if a
    brush or the vacuum runs (:func:`stop_first`); True if motors off was sent. The guard's
    own drive 0 (``CommandWriter.own_stop``): a port lost after it is not said "stopped"."""
    with connection.writer.own_stop(TICK_GUARD):
        if motors_running(connection):
            connection.send_many(stop_first())
            return True
        connection.halt()
    return False


def stop_first() -> list[Command]:
    """What the run's end sends before the tree's stop: the first half of the safe stop
    (robot/ending.py), in one write."""
    return [oi.halt(), oi.motors_off()]


def _send_stop_first(connection: Connection, motors_on: bool = False) -> bool:
    """:func:`stop_first` if the wheels move (:func:`wheels_moving`) or, ``motors_on``, a brush
    or the vacuum runs, in a mode that takes the stop; True if it was written. A link already
    gone is no error here: the safe stop that follows says what became of it."""
    motors = motors_on and connection.mode in DRIVING_MODES
    if not motors and not wheels_moving(connection):
        return False
    try:
        with connection.writer.own_stop("the drive 0 before the tree's stop"):
            connection.send_many(stop_first())
    except Exception as exc:
        log.debug("drive 0 before the tree's stop not sent: %s", exc)
        return False
    return True


class TickGuardLike(Protocol):
    """What the runner asks of a tick guard: the live one or a record's."""

    limit_s: float

    def start(self) -> None: ...
    def close(self) -> None: ...
    def halt_before_stop(self, motors_on: bool = False) -> bool: ...
    def guarded(
        self, tick: Callable[[], object], slow: Slow, index: Callable[[], int], between: str = ""
    ) -> Callable[[], None]: ...


class TickGuard:
    """Watches one run's ticks from a thread of its own (see the module docstring)."""

    def __init__(
        self,
        connection: Connection,
        limit_s: float = DEFAULT_TICK_LIMIT,
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not limit_s > 0.0:
            raise ValueError(f"tick limit must be above 0 s, got {limit_s!r}")
        self.connection = connection
        self.limit_s = limit_s
        self.clock = clock
        #: held by the main thread except inside a tick
        self.lock = threading.Lock()
        #: when the running tick began (``clock``), None between ticks
        self._entered: float | None = None
        self._ticks = 0
        #: the last tick the guard saw past the limit: its count, how long it had run then,
        #: where it was (:meth:`_where`), whether the guard stopped the wheels or the motors
        #: in it (False: nothing moved; it may still, and then the stop replaces it), and the
        #: built-in cycle that may have driven the robot meanwhile (:func:`cycle_said`, "")
        self._slow: tuple[int, float, str, bool, str] | None = None
        #: the stream's tick index of the running tick (the runner's snapshot), for the note
        self._index: Callable[[], int] = lambda: 0
        self._owner = 0  # the thread that ticks
        #: what runs between two ticks while the guard watches it (``guarded``'s
        #: ``between``), "" while it watches the tree's tick: set and read with :attr:`lock` held
        self._between = ""
        self._done = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, name="roomba-bt tick guard", daemon=True
        )

    def start(self) -> None:
        """Take the lock for the main thread (the caller) and start watching."""
        self.lock.acquire()
        self._owner = threading.get_ident()
        self._thread.start()

    def close(self) -> None:
        """Stop watching; after this the guard writes nothing. The main thread may hold the
        lock or not (a tick that raised gave it back through :meth:`guarded`)."""
        self._done.set()
        if self._thread.is_alive():
            self._thread.join()

    def halt_before_stop(self, motors_on: bool = False) -> bool:
        """The run ends with nodes still running and the wheels moving (or, ``motors_on``, the
        tree's last Motors running a brush or the vacuum): drive 0 and motors off now
        (:func:`stop_first`), before their ``terminate()``, which may block as a tick may (a
        plugin's ``time.sleep``); called in the main thread once the guard is closed. Noted
        in the record (``"at": "end"``) for a replay to do it again. True if it was sent."""
        if not _send_stop_first(self.connection, motors_on):
            return False
        note = getattr(self.connection.transport, "note", None)
        if callable(note):
            note({
                "tick_guard": 0.0, "limit": self.limit_s, "where": AT_THE_END,
                "tick": self._index(), "at": "end",
            })  # fmt: skip
        return True

    def guarded(
        self, tick: Callable[[], object], slow: Slow, index: Callable[[], int], between: str = ""
    ) -> Callable[[], None]:
        """``tick`` with the lock released around it; ``slow(seconds, where, halted, cycle)``
        is called in the main thread, lock held, after a tick that ran past the limit,
        whether it returned or raised (``seconds``: how long that tick had run when the guard
        saw it; ``where``: :meth:`_where`; ``halted``: the guard stopped the wheels or the
        motors, else it sent nothing; ``cycle``: the built-in cycle that may have driven the
        robot meanwhile, "" if nothing moved). ``index()``: the running tick's index in the
        stream. ``between``: ``tick`` is work done between two ticks, said so (a program's
        loop body: the ticking thread only waits for it, and its innermost line is that
        wait): the notes say it (``where``, :data:`LOOP_NOTE`), for a replay to do their
        acts there and count them as the run did. The tree's tick is left as it was (its
        path not one store longer)."""
        lock = self.lock
        clock = self.clock
        self._index = index

        def guarded_tick() -> None:
            self._ticks += 1
            self._entered = clock()
            lock.release()
            try:
                tick()
            finally:  # also when the tick raised or was interrupted: the halt is counted
                lock.acquire()
                self._entered = None
                seen = self._slow
                if seen is not None and seen[0] == self._ticks:
                    slow(seen[1], seen[2], seen[3], seen[4])

        if not between:
            return guarded_tick

        def guarded_between() -> None:
            self._between = between  # the lock held: the guard reads it only with it
            try:
                guarded_tick()
            finally:
                self._between = ""

        return guarded_between

    def _watch(self) -> None:
        period = self.limit_s / 5.0
        while not self._done.wait(period):
            entered, tick, seen = self._entered, self._ticks, self._slow
            if entered is None or (seen is not None and seen[0] == tick and seen[3]):
                continue  # between ticks, or this one's wheels already stopped
            ran = self.clock() - entered
            if ran < self.limit_s or not self.lock.acquire(timeout=period):
                continue
            try:  # lock held: the main thread is inside a tick; is it still that one?
                if self._entered is None or self._ticks != tick:
                    continue
                if self._moving():
                    where = self._where()
                    self._slow = (tick, ran, where, True, "")  # once a tick, even if it fails
                    motors = halt_blocked(self.connection)
                    self._note(ran, where, motors)  # only a stop that went out is replayed
                elif seen is None or seen[0] != tick:
                    # nothing to stop (or a cycle, which the guard does not end): where it
                    # blocked, once a tick
                    cycle = cycle_said(self.connection)
                    where = self._where()
                    self._slow = (tick, ran, where, False, cycle)
                    self._note_still(ran, where, cycle)
            except Exception as exc:  # the port gone, say: the main thread meets it next
                log.warning("the tick guard could not send drive 0: %s", exc)
            finally:
                self.lock.release()

    def _note(self, ran: float, where: str, motors: bool) -> None:
        """The act in the record (``run --record``), for a replay to do it again; ``motors``:
        motors off went out with the drive 0 (a note without it: drive 0 alone)."""
        act: dict[str, Any] = {
            "tick_guard": round(ran, 3), "limit": self.limit_s, "where": where,
            "tick": self._index(), "at": "during",
        }  # fmt: skip
        if motors:
            act["motors"] = True
        self._write_note(act)

    def _note_still(self, ran: float, where: str, cycle: str) -> None:
        """A tick past the limit with nothing moving (:data:`STILL_NOTE`), or while ``cycle``
        may have driven the robot (:data:`CYCLE_NOTE`), in the record: its replay says the
        gap that tick left as the live run did. ``"at": "after"``: read after that tick (an
        earlier roomba-bt's monitor takes it for an operator's act it does not know, and
        passes it there, holding back no act of the next tick)."""
        kept: dict[str, Any] = {
            CYCLE_NOTE if cycle else STILL_NOTE: round(ran, 3), "limit": self.limit_s,
            "where": where, "tick": self._index(), "at": "after",
        }  # fmt: skip
        if cycle:
            kept["cycle"] = cycle
        self._write_note(kept)

    def _write_note(self, said: dict[str, Any]) -> None:
        """``said`` in the record, when the run makes one (a transport with ``note``), with
        :data:`LOOP_NOTE`: whether the pass was a program's loop body's or the tree's."""
        note = getattr(self.connection.transport, "note", None)
        if callable(note):
            said[LOOP_NOTE] = bool(self._between)  # on every note: its where cannot tell
            note(said)

    def _moving(self) -> bool:
        """The wheels move or a brush or the vacuum runs: something to stop."""
        return wheels_moving(self.connection) or motors_running(self.connection)

    def _where(self) -> str:
        """Where the ticking thread is (:func:`where_in`); "" if the thread is gone. Between
        two ticks, what runs there (``guarded``'s ``between``): the thread only waits for it."""
        if self._between:
            return self._between
        return where_in(sys._current_frames().get(self._owner))


def _ticked(notes: Iterable[dict[str, Any]], key: str) -> list[dict[str, Any]]:
    """The notes that have ``key`` and the tick they were made in."""
    return [n for n in notes if key in n and isinstance(n.get("tick"), int)]


class RecordedTickGuard:
    """A replay's tick guard: the acts of the recorded run's (its notes), each done again in
    the tick it was done in, after that tick (which does not block here) and before its
    flush, as live: drive 0 where the record has it, then the runner's reaction; and the
    ticks it saw past the limit with nothing moving (:data:`STILL_NOTE`) or a built-in
    cycle driving (:data:`CYCLE_NOTE`), told to the runner after that tick, as live
    (nothing sent). Those of work between two ticks (:func:`loop_noted`: a program's loop
    over ``stack.ticks()``) are done where that work was, by what ``guarded`` watches with
    its ``between``, not in the tree's tick (:func:`replay_record
    <roomba_bt.runtime.stack.replay_record>` has it watch that place)."""

    def __init__(self, connection: Connection, notes: Iterable[dict[str, Any]]) -> None:
        self.connection = connection
        notes = list(notes)
        acts = _ticked(notes, "tick_guard")
        stills = _ticked(notes, STILL_NOTE) + _ticked(notes, CYCLE_NOTE)
        #: the recorded run sent drive 0 before its tree's stop (:meth:`halt_before_stop`)
        self._at_end = any(n.get("at") == "end" for n in acts)
        first = (acts or stills)[:1]
        self.limit_s = float(first[0].get("limit", DEFAULT_TICK_LIMIT)) if first else 0.0
        acts = [n for n in acts if n.get("at") != "end"]
        #: the acts and the still notes of the tree's ticks (False) and of the work between
        #: two ticks (True), each in tick order
        self._notes = {
            loop: (
                deque(sorted((n for n in acts if loop_noted(n) is loop), key=_tick_of)),
                deque(sorted((n for n in stills if loop_noted(n) is loop), key=_tick_of)),
            )
            for loop in (False, True)
        }

    @property
    def between_ticks(self) -> bool:
        """Whether the recorded run's guard acted or saw a pass past its limit between two
        ticks (a program's loop over ``stack.ticks()``): the replay watches that place."""
        acts, stills = self._notes[True]
        return bool(acts or stills)

    def start(self) -> None:
        pass

    def close(self) -> None:
        pass

    def halt_before_stop(self, motors_on: bool = False) -> bool:
        """As the recorded run did at its end: drive 0 and motors off before the tree's stop
        when its record says so (its ``"at": "end"`` note)."""
        return self._at_end and _send_stop_first(self.connection, motors_on)

    def guarded(
        self, tick: Callable[[], object], slow: Slow, index: Callable[[], int], between: str = ""
    ) -> Callable[[], None]:
        acts, stills = self._notes[bool(between)]

        def replayed_tick() -> None:
            tick()
            now = index()
            act, still = _this_tick(acts, now), _this_tick(stills, now)
            if act is not None:  # the stop replaces a still note of the same tick, as live
                with self.connection.writer.own_stop(TICK_GUARD):
                    if act.get("motors"):
                        self.connection.send_many(stop_first())
                    else:
                        self.connection.halt()
                slow(float(act["tick_guard"]), str(act.get("where", "")), True, "")
            elif still is not None:
                cycle = str(still.get("cycle") or "a built-in cycle") if CYCLE_NOTE in still else ""
                ran = still[CYCLE_NOTE] if CYCLE_NOTE in still else still[STILL_NOTE]
                slow(float(ran), str(still.get("where", "")), False, cycle)

        return replayed_tick


def _tick_of(note: Mapping[str, Any]) -> int:
    return int(note["tick"])


def _this_tick(notes: deque[dict[str, Any]], now: int) -> dict[str, Any] | None:
    """The note of tick ``now`` at the head of ``notes`` (in tick order), taken off, or None;
    those of earlier ticks, which the replay did not reach as recorded, are dropped."""
    while notes and int(notes[0]["tick"]) < now:
        notes.popleft()
    if notes and int(notes[0]["tick"]) == now:
        return notes.popleft()
    return None


def recorded_tick_guard(
    connection: Connection, notes: Iterable[dict[str, Any]]
) -> RecordedTickGuard | None:
    """The record's tick guard, or None when the recorded run's guard never acted nor saw a
    tick past its limit."""
    guard = RecordedTickGuard(connection, notes)
    return guard if any(any(kept) for kept in guard._notes.values()) or guard._at_end else None
