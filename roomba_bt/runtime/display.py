"""What a user sees while a mission runs.

On a terminal: the tree with live statuses (py_trees' unicode rendering) and the key sensors,
redrawn a few times a second of wall time. Without a terminal (a log, CI): one line per status
change of any node, stamped with mission time. Both are observers called after the tick and its
flush, outside the measured tick time.
"""

from __future__ import annotations

import logging
import math
import os
import re
import shutil
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from functools import partial
from typing import TYPE_CHECKING, Literal, TextIO
from uuid import UUID

import py_trees

from roomba_bt.oi.frames import (
    BATTERY_PACKETS,
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CLIFF_PACKETS,
    IR_PACKETS,
)
from roomba_bt.oi.ir import IRCharacter
from roomba_bt.printable import ANY_CONTROL, encodes, escaped, name_shown, shortened

if TYPE_CHECKING:
    from roomba_bt.robot.interface import Snapshot
    from roomba_bt.runtime.loop import MissionRunner

log = logging.getLogger("roomba_bt.run")


class MissionClockFormatter(logging.Formatter):
    """Log lines stamped with mission time (``t=12.345``), not wall-clock time.

    What happened when, in a mission, is a question about mission time: on the virtual clock
    (``--fast``) the wall clock says nothing, and a refusal or a warning is compared with the
    tree's status lines (``t=12.345s ...``) and a recording's timestamps. Before a mission has
    a clock (or outside one: ``validate``, ``sim``) a line has no time at all.

    What a line quotes is escaped (:func:`~roomba_bt.printable.escaped`): a node's name, a
    ``log`` leaf's text, anything a mission's author wrote, passed as an argument, stays on
    its line (``"\\n[ok] robot stopped"`` faked a line of its own); no control character
    (``ESC [2J`` clears the screen) reaches the terminal from a message or a traceback."""

    clock: Callable[[], float | None] | None = None
    #: the latest stamp a line had since the run's clock was set (:func:`use_mission_clock`)
    latest = -math.inf
    #: the run's label (``run --label``), said on each line as ``[robot 3]``: two runs'
    #: lines in one terminal (started with ``&``) told apart; "" for none
    label = ""

    def format(self, record: logging.LogRecord) -> str:
        """``t=12.345 LEVEL logger: message``: the record's own ``mission_time`` (passed as
        ``extra``) if it has one, else the mission clock's now; while a run's clock is set,
        never a stamp before the line above it (:attr:`latest`)."""
        line = f"{record.levelname} {record.name}: {escaped(_quoted_message(record))}"
        label = type(self).label
        if label:
            line = f"[{label}] {line}"
        if record.exc_info and not record.exc_text:
            record.exc_text = self.formatException(record.exc_info)
        if record.exc_text:
            line += "\n" + escaped(record.exc_text)
        now: float | None = getattr(record, "mission_time", None)
        clock = type(self).clock
        if clock is not None:
            if now is None:
                now = clock()
            # never before the line above: a stall's lines read the link's clock past the
            # last frame, and the frames back count the stall's slots only once judged (the
            # schedule's run, runtime/schedule.py): a line of a tick meanwhile read a time
            # before them (t=4.305 frames are back, then t=4.240 no valid sensor frame)
            if now is not None:
                if now < MissionClockFormatter.latest:
                    now = MissionClockFormatter.latest
                else:
                    MissionClockFormatter.latest = now
        return line if now is None else f"t={now:.3f} {line}"


def _quoted_message(record: logging.LogRecord) -> str:
    """``record``'s message, each text it quotes (an argument) on one line: the format is the
    program's, and may span lines; the arguments are data, a mission's names among them."""
    args = record.args
    if not isinstance(args, tuple) or not args:
        return record.getMessage()
    one_line = tuple(escaped(a, ANY_CONTROL) if isinstance(a, str) else a for a in args)
    return str(record.msg) % one_line


def use_mission_clock(runner: MissionRunner | None, label: str = "") -> None:
    """Stamp log lines with ``runner``'s mission time from now on (None: stop stamping): the
    time on the run's clock when the line is written, a stall's lines too
    (:func:`~roomba_bt.runtime.clock.mission_time_now`), not the last frame's; and with the
    run's ``label`` (``run --label``), if any."""
    MissionClockFormatter.label = label if runner is not None else ""
    MissionClockFormatter.latest = -math.inf
    if runner is None:
        MissionClockFormatter.clock = None
        return
    # here: every command imports this module (its log formatter), only a run the clock
    from roomba_bt.runtime.clock import mission_time_now

    MissionClockFormatter.clock = partial(mission_time_now, runner)


@contextmanager
def stamped_logs(runner: MissionRunner | None, label: str = "") -> Iterator[None]:
    """:func:`use_mission_clock` for as long as the block runs (``runner`` None: nothing
    stamped), stopped after it whatever ends it: a replay's (``replay_record``)."""
    if runner is None:
        yield
        return
    use_mission_clock(runner, label)
    try:
        yield
    finally:
        use_mission_clock(None)


#: ``run --display``: the live tree, one log line per status change, or nothing; ``auto`` is
#: the tree on a terminal and the log elsewhere.
Display = Literal["auto", "tree", "log", "none"]


def sensor_line(snapshot: Snapshot) -> str:
    """One line of the sensors that matter most, from whatever the frame carries."""
    return "  ".join(_sensor_parts(snapshot))


def sensor_lines(snapshot: Snapshot, columns: int) -> list[str]:
    """:func:`sensor_line` wrapped between its fields to lines of at most ``columns``
    characters: cut to the width, a 40-column SSH screen lost the cliffs, the battery and
    the odometry (``t=   0.84s  mode=Safe  bump=-  drop=-  c``). A field wider than the
    screen on its own is cut."""
    lines: list[str] = []
    for part in _sensor_parts(snapshot):
        if lines and len(lines[-1]) + 2 + len(part) <= columns:
            lines[-1] += "  " + part
        else:
            lines.append(part)
    return [line[: max(columns, 10)] for line in lines]


def _sensor_parts(snapshot: Snapshot) -> list[str]:
    """The fields of :func:`sensor_line`: ``t=...``, ``mode=...``, ``bump=...``, ..."""
    frame = snapshot.frame
    parts = [f"t={snapshot.time:7.2f}s", f"mode={snapshot.mode.label}"]
    if frame.carries(BUMPS_PACKETS):
        b = frame.bumps
        bumps = "L" * b.bump_left + "R" * b.bump_right or "-"
        drops = "L" * b.wheel_drop_left + "R" * b.wheel_drop_right or "-"
        parts += [f"bump={bumps}", f"drop={drops}"]
    if frame.carries(CLIFF_PACKETS):
        cliffs = "".join(c for c, p in zip("LlrR", CLIFF_PACKETS, strict=True) if frame[p])
        parts.append(f"cliff={cliffs or '-'}")
    for pid, label in zip(IR_PACKETS, ("ir", "irL", "irR"), strict=True):
        if frame.get(pid):
            ir = IRCharacter.decode(frame[pid])
            beams = "".join(
                c
                for c, on in (("R", ir.red_buoy), ("G", ir.green_buoy), ("F", ir.force_field))
                if on
            )
            parts.append(f"{label}={ir.code}{'(' + beams + ')' if beams else ''}")
    if frame.carries(CHARGING_SOURCES_PACKETS) and frame.charging_sources.any:
        parts.append("charger=" + ("home" if frame.charging_sources.home_base else "internal"))
    if frame.carries(BATTERY_PACKETS):
        parts.append(f"battery={frame.battery_percent:.0f}%")
    odo = snapshot.odometry
    parts.append(f"odo=({odo.x_mm / 1000:+.2f},{odo.y_mm / 1000:+.2f})m")
    return parts


def node_kind(node: py_trees.behaviour.Behaviour) -> str:
    """The symbol ``py_trees.display`` draws before the node's name (its key in
    ``py_trees.display.unicode_symbols``): ``{-}`` a sequence with memory, ``-->`` a leaf."""
    if isinstance(node, py_trees.composites.Parallel):
        return "parallel"
    if isinstance(node, py_trees.decorators.Decorator):
        return "decorator"
    if isinstance(node, py_trees.composites.Sequence):
        return "sequence_with_memory" if node.memory else "sequence_without_memory"
    if isinstance(node, py_trees.composites.Selector):
        return "selector_with_memory" if node.memory else "selector_without_memory"
    # a composite py_trees does not know (a guard, behaviours.decorators.Guard) says how it is
    # drawn; read by name so that this module, which the CLI's logging set-up imports before
    # any command, does not import the behaviours (and their py_trees version check) with it
    drawn_as = getattr(node, "drawn_as", None)
    if isinstance(drawn_as, str):
        return drawn_as
    return "behaviour"


#: what the status marks are on a stream that cannot show ``✓`` and ``✕`` (ASCII, Latin-1):
#: words, not py_trees' ``o`` and ``x``, so that ``[ok]`` reads as it means
ASCII_MARKS = {py_trees.common.Status.SUCCESS: "ok", py_trees.common.Status.FAILURE: "x"}
_COLOUR = re.compile("\x1b\\[[0-9;]*m")


def colours_wanted(stream: TextIO) -> bool:
    """Whether ``stream`` may be written colour and bold: a terminal, with no ``NO_COLOR``
    (https://no-color.org: set and not empty) and not ``TERM=dumb`` (an Emacs shell, a
    serial console: shown as ``^[[33m``). py_trees decides it once, at import, from stdout
    being a terminal only."""
    if os.environ.get("NO_COLOR") or os.environ.get("TERM") == "dumb":
        return False
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def plain_terminal() -> bool:
    """``TERM=dumb``: a terminal that cannot move its cursor or clear its screen."""
    return os.environ.get("TERM") == "dumb"


def in_foreground(fd: int) -> bool:
    """Whether this process's group owns the terminal at ``fd``: a command started with ``&``
    does not (nor one a shell's ``bg`` sent on), and the terminal stops it (SIGTTOU) when it
    changes the terminal's settings. False where it cannot be asked (not a terminal; no job
    control on the system)."""
    if not hasattr(os, "tcgetpgrp"):
        return False
    try:
        return os.tcgetpgrp(fd) == os.getpgrp()
    except OSError:
        return False


def owns_the_screen(stream: TextIO) -> bool:
    """``--display auto``'s live tree: ``stream`` is a terminal that moves its cursor and
    this run is its foreground job. A run started with ``&`` shares the screen with the shell
    and whatever else runs there: two runs in the background of one terminal each cleared it
    and drew their tree over the other's, five times a second, and neither could be read.
    A background run gets the log's plain lines instead (a line each, its own; decided: the
    tree stays the log for the whole run, even if ``fg`` brings it to the foreground later).
    Whether another program draws on the same terminal from elsewhere (another terminal
    multiplexer's pane, a second SSH session's ``write``) cannot be known, so only the job
    control's answer is taken. A stream without a descriptor that says it is a terminal (a
    test's) is taken at its word."""
    if not stream.isatty() or plain_terminal():
        return False
    try:
        fd = stream.fileno()
    except (OSError, ValueError):  # io.UnsupportedOperation is both
        return True
    return in_foreground(fd)


def tree_symbols(stream: TextIO) -> dict[object, str]:
    """The symbols :func:`text_tree` draws with on ``stream``: py_trees' unicode ones where
    its encoding has ``✓`` and ``✕``, else ASCII (``[ok]``, ``[x]``; an ASCII stdout raised
    ``UnicodeEncodeError`` after the run, exit 1 whatever its outcome); their colour and
    bold only where :func:`colours_wanted`."""
    unicode = encodes(stream, "\u2713\u2715")
    symbols: dict[object, str] = dict(
        py_trees.display.unicode_symbols if unicode else py_trees.display.ascii_symbols
    )
    if not unicode:
        for status, word in ASCII_MARKS.items():  # py_trees' "o", its colour kept
            mark = symbols[status]
            symbols[status] = mark.replace(_COLOUR.sub("", mark), word)
    if not colours_wanted(stream):
        symbols = {key: _COLOUR.sub("", value) for key, value in symbols.items()}
    return symbols


def live_names(mission: object) -> Mapping[UUID, str] | None:
    """Each node's name in the live views, the terminal's live tree and the monitor's page,
    by the live node's id: ``show``'s (``CompiledMission.reviewed_names``) for a node the
    mission did not rename (``timeout(after=2s)``, ``retry(times=40)``, where the live views
    said ``timeout`` and ``retry`` between two printed trees that said more), and the name a
    ``name:`` gave (``docking``), not ``show``'s ``subtree dock(time_limit=10min, ...):
    parallel(policy=one) named 'docking'``: that is for reviewing a name against what the
    node is, and its 200 characters pushed the node's status off a terminal's line and the
    page's panel. The one place both views take their names from; None for a mission that
    has none (a tree built in Python: its nodes' own names). The log, the events, the record
    and the monitor's API keep the nodes' own names."""
    reviewed = getattr(mission, "reviewed_names", None)
    if reviewed is None:
        return None
    names: dict[UUID, str] = reviewed()
    root = getattr(mission, "root", None)
    for node in root.iterate() if root is not None else ():
        drawn = names.get(node.id)
        if drawn is not None and drawn.endswith(f" named {shortened(node.name)!r}"):
            names[node.id] = node.name
    return names


def text_tree(
    root: py_trees.behaviour.Behaviour,
    *,
    show_status: bool = False,
    symbols: dict[object, str] | None = None,
    as_ticked: TreeStatuses | None = None,
    names: Mapping[UUID, str] | None = None,
) -> str:
    """The tree as ``py_trees.display.unicode_tree`` draws it (the run's tree before it
    starts, and with ``show_status`` each node's status and message at its end), each
    node's name and ``feedback_message`` escaped to one line
    (:data:`~roomba_bt.printable.ANY_CONTROL`).

    py_trees prints both as they are: a plugin's message ``"\\x1b[2J\\n[ok] robot stopped"``
    cleared the screen and faked a line under the tree. Drawn here, where the text is
    printed, so the behaviour keeps its message as it set it (a ``failure_reason`` or the
    monitor read it too, and escape it where they print it). ``symbols``: py_trees' unicode
    ones by default, the stream's own from :func:`tree_symbols`. ``as_ticked``: the statuses,
    messages and tip its last tick left (the tree's stop since marked every node INVALID).
    ``names``: a node's name to draw by its id (``show``'s, ``CompiledMission.reviewed_names``),
    its own where none is given."""
    if symbols is None:
        symbols = py_trees.display.unicode_symbols
    if as_ticked is not None and as_ticked.nodes:
        ticked, tip_id = as_ticked.nodes, as_ticked.tip_id
    else:  # the tree as it stands (before a run, or after one that ended with its tree)
        tip = root.tip()
        ticked, tip_id = {}, (tip.id if tip is not None else None)
    lines: list[str] = []

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        bold, reset = ("", "") if node.id != tip_id else (symbols["bold"], symbols["bold_reset"])
        name = name_shown(node.name if names is None else names.get(node.id, node.name))
        line = f"{'    ' * depth}{bold}{symbols[node_kind(node)]}{reset} "
        if show_status:  # py_trees' three bold spans, so that a terminal shows the same
            status, feedback = ticked.get(node.id) or (node.status, node.feedback_message)
            said = escaped(feedback, ANY_CONTROL)
            message = f" -- {said}" if said else ""
            mark = symbols[status]
            line += f"{bold}{name} [{reset}{bold}{mark}{reset}{bold}]{message}{reset}"
        else:
            line += f"{bold}{name}{reset}"
        lines.append(line)
        for child in node.children:
            walk(child, depth + 1)

    walk(root, 0)
    return "".join(f"{line}\n" for line in lines)


_MARKS = {
    py_trees.common.Status.RUNNING: "*",
    py_trees.common.Status.SUCCESS: "✓",
    py_trees.common.Status.FAILURE: "✕",
    py_trees.common.Status.INVALID: "-",
}


#: the kind symbols of :func:`node_kind` (``{-}``, ``[o]``, ``-->``): py_trees' ASCII ones,
#: the same as its unicode ones and never coloured, so any stream can show them
_KIND_SYMBOLS: dict[object, str] = py_trees.display.ascii_symbols


def fitted_tree(
    root: py_trees.behaviour.Behaviour,
    rows: int,
    columns: int,
    marks: dict[py_trees.common.Status, str] | None = None,
    as_left: TreeStatuses | None = None,
    names: Mapping[UUID, str] | None = None,
) -> list[str]:
    """The tree as at most ``rows`` lines of at most ``columns`` characters.

    Only a running node shows its children: a finished or not yet started subtree is one
    line (``[✓] +3`` says it hides three nodes), so the running path stays in view however
    large the tree. If that is still too tall, the lines off the running path go first, from
    the bottom, and one line says how many were left out. ``marks``: the status marks
    (default ``✓``, ``✕``; :func:`status_marks` for a stream's own).

    Each line starts with the node's kind as :func:`text_tree` draws it (``{-}`` a sequence
    with memory, ``[o]`` a reactive fallback, ``-->`` a leaf): without it a reactive
    composite could not be told from one with memory while the tree ran, folded or not.

    ``as_left``: the statuses the run left its tree in (``MissionRunner.tree_as_left``), for
    the last screen after the run's end has stopped the tree: the stop marks every node
    INVALID, and that screen showed ``[-]`` on every node above the tree printed under it
    with the right marks (``mode(safe) [✓]``, ``boom [-] -- raised RuntimeError``).

    ``names``: a node's name to draw by its id (:func:`live_names`), its own where none is
    given."""
    shown = marks or _MARKS
    lines: list[tuple[str, bool]] = []  # (text, on the running path)
    left = as_left.nodes if as_left is not None else {}

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        status = left[node.id][0] if node.id in left else node.status
        running = status is py_trees.common.Status.RUNNING
        children = list(node.children)
        folded = not running and children and depth > 0
        hidden = sum(1 for _ in node.iterate()) - 1 if folded else 0
        more = f" +{hidden}" if hidden else ""
        name = name_shown(node.name if names is None else names.get(node.id, node.name))
        kind = _KIND_SYMBOLS[node_kind(node)]
        line = f"{'  ' * depth}{kind} {name} [{shown[status]}]{more}"
        lines.append((line, running))
        if running or depth == 0:
            for child in children:
                walk(child, depth + 1)

    walk(root, 0)
    return [text[: max(columns, 10)] for text, _ in _within_rows(lines, max(rows, 2))]


def _within_rows(lines: list[tuple[str, bool]], rows: int) -> list[tuple[str, bool]]:
    """:func:`fitted_tree`'s ``lines`` (each with whether it is on the running path) cut
    to ``rows``: the lines off the running path go first, from the bottom, then the deepest
    running ones, and one line says how many were left out."""
    if len(lines) <= rows:
        return lines
    keep = [True] * len(lines)
    excess = len(lines) - (rows - 1)  # one row says how many are hidden
    for i in range(len(lines) - 1, 0, -1):
        if excess == 0:
            break
        if not lines[i][1]:
            keep[i] = False
            excess -= 1
    for i in range(len(lines) - 1, 0, -1):  # still too tall: the deepest running lines
        if excess == 0:
            break
        if keep[i]:
            keep[i] = False
            excess -= 1
    left_out = keep.count(False)
    lines = [line for line, kept in zip(lines, keep, strict=True) if kept]
    lines.append((f"... {left_out} more lines (a larger terminal shows them)", False))
    return lines


def status_marks(stream: TextIO) -> dict[py_trees.common.Status, str]:
    """The live tree's status marks on ``stream``: ``✓`` and ``✕``, or ``ok`` and ``x`` where
    its encoding has no such characters (:data:`ASCII_MARKS`)."""
    if encodes(stream, "".join(_MARKS.values())):
        return _MARKS
    return {**_MARKS, **ASCII_MARKS}


class OffTickWriter:
    """Writes text to a stream from a thread of its own, so that a terminal that stops taking
    it never holds up the tick loop.

    A terminal over SSH on a bad network stops reading; once its buffer is full (a few KiB)
    every write blocks, and a write from the tick loop blocked the loop: no frame read, no
    watchdog, no tick guard (a write is outside the tick), the robot driving on with its last
    Drive for as long as the network stalled (a 4 KiB pipe nobody read held a run after 3.8 s).
    Here the loop only hands text over; the thread writes it. A screen (``latest_only``)
    replaces the one still waiting, so a slow terminal sees fewer redraws, not older ones;
    lines (the log) wait up to :attr:`limit`, then the oldest are dropped and counted. A
    stream that fails (a terminal gone) ends the writing.

    ``blocks``: lines are never dropped, a :meth:`post` waits for room instead (``run
    --fast``: on the virtual clock nothing drives while the loop waits, and ``2>&1 | less``,
    the usual way to read a run, lost 4965 of 7033 lines behind a slow pipe). A signal
    raised while it waits (the run's Ctrl-C or SIGTERM) ends the waiting for good: the run's
    stop that follows must not wait on the same pipe, its lines are dropped and counted.

    The thread holds only the lines (:class:`_Lines`), not the writer: a writer a program
    drops without :meth:`close` (a library user's ``TerminalDisplay``) is collected, and its
    finalizer ends the thread once what was posted is written; before, the thread kept the
    writer alive and waited for ever, one per display, for the rest of the process."""

    def __init__(self, stream: TextIO, limit: int = 1000, *, blocks: bool = False) -> None:
        self._lines = lines = _Lines(stream, limit, blocks)
        self._thread = threading.Thread(target=lines.drain, name="roomba-bt terminal", daemon=True)
        self._thread.start()
        weakref.finalize(self, lines.end)

    @property
    def stream(self) -> TextIO:
        return self._lines.stream

    @property
    def limit(self) -> int:
        """Lines that wait at most (the oldest then dropped, or, with :attr:`blocks`, the
        next post waits)."""
        return self._lines.limit

    @limit.setter
    def limit(self, limit: int) -> None:
        self._lines.limit = limit

    @property
    def blocks(self) -> bool:
        return self._lines.blocks

    @property
    def dropped(self) -> int:
        """Lines dropped: the terminal did not take them."""
        return self._lines.dropped

    @property
    def gone(self) -> bool:
        """The stream failed: nothing more is written."""
        return self._lines.gone

    def post(self, text: str, *, latest_only: bool = False) -> None:
        self._lines.post(text, latest_only)

    def wait_written(self, timeout: float | None) -> bool:
        """Wait up to ``timeout`` s (None: until it is) for what was posted to be written;
        False if it was not (the terminal still stalled)."""
        return self._lines.idle.wait(timeout)

    def close(self, timeout: float | None = 1.0) -> None:
        """Write what is pending (for up to ``timeout`` s; None: all of it, however long),
        then stop posting and writing."""
        self.wait_written(timeout)
        self._lines.end()


class _Lines:
    """What an :class:`OffTickWriter` posts and its thread writes (see there): the waiting
    texts, the stream, and the counts; the thread's whole state, so that it holds no
    writer."""

    def __init__(self, stream: TextIO, limit: int, blocks: bool) -> None:
        self.stream = stream
        self.limit = limit
        self.blocks = blocks
        self.dropped = 0
        self.gone = False
        self.items: deque[tuple[str, bool]] = deque()
        self.ready = threading.Condition()
        self.closing = False
        self.idle = threading.Event()
        self.idle.set()

    def post(self, text: str, latest_only: bool) -> None:
        with self.ready:
            if self.gone or self.closing:
                return
            items = self.items
            if latest_only and items and items[-1][1]:
                items.pop()  # the screen not drawn yet: this one replaces it
            else:
                self._wait_for_room()
                if self.gone or self.closing:
                    return
                if len(items) >= self.limit:
                    items.popleft()
                    self.dropped += 1
            items.append((text, latest_only))
            self.idle.clear()
            self.ready.notify_all()

    def _wait_for_room(self) -> None:
        """With :attr:`blocks`, wait (holding nothing but the condition) until the thread has
        written a line, the stream failed or the writing ends; a signal's exception ends the
        blocking for good and goes on up (the run unwinds into its stop)."""
        try:
            while (
                self.blocks and len(self.items) >= self.limit and not self.gone and not self.closing
            ):
                self.ready.wait()
        except BaseException:
            self.blocks = False
            raise

    def drain(self) -> None:
        """The thread: write each text posted, until the writing ends (what waits written
        first) or the stream fails."""
        while True:
            with self.ready:
                while not self.items and not self.closing:
                    self.idle.set()
                    self.ready.wait()
                if not self.items:
                    self.idle.set()
                    return
                text, _ = self.items.popleft()
                self.ready.notify_all()  # a post waiting for room (blocks) has one
            try:
                self.stream.write(text)
                self.stream.flush()
            except (OSError, ValueError):  # gone (EIO after a hang-up), or closed
                with self.ready:
                    self.gone = True
                    self.items.clear()
                    self.idle.set()
                    self.ready.notify_all()
                return

    def end(self) -> None:
        """No more posts; the thread ends once what waits is written."""
        with self.ready:
            self.closing = True
            self.ready.notify_all()


class OffTickHandler(logging.Handler):
    """A logging handler whose lines an :class:`OffTickWriter` writes: formatted here (the
    mission clock of the tick that logged), written off the tick loop."""

    def __init__(self, writer: OffTickWriter) -> None:
        super().__init__()
        self.writer = writer

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.writer.post(self.format(record) + "\n")
        except Exception:  # as StreamHandler.emit does
            self.handleError(record)


@contextmanager
def logging_off_the_tick(timeout: float = 1.0, *, blocks: bool = False) -> Iterator[None]:
    """Within the block (a run), the root logger's stream handlers write through
    :class:`OffTickHandler`s; on the way out the lines waiting are written (for up to
    ``timeout`` s) and the handlers put back, so the report that follows comes after them.
    ``blocks`` (the virtual clock): no line is dropped (:class:`OffTickWriter`), and on the
    way out every line waiting is written, however long that takes (the CLI lets a signal
    end the process meanwhile: the robot is stopped)."""
    root = logging.getLogger()
    swapped: list[tuple[logging.Handler, OffTickHandler]] = []
    for handler in list(root.handlers):
        if type(handler) is logging.StreamHandler:  # not a file's, nor a test's capture
            off = OffTickHandler(OffTickWriter(handler.stream, blocks=blocks))
            off.setFormatter(handler.formatter)
            off.setLevel(handler.level)
            root.removeHandler(handler)
            root.addHandler(off)
            swapped.append((handler, off))
    try:
        yield
    finally:
        for handler, off in swapped:
            off.writer.close(None if off.writer.blocks else timeout)
            root.removeHandler(off)
            root.addHandler(handler)
            if off.writer.dropped:  # said once, where the terminal may take it again
                log.warning(
                    "%d log line(s) of the run were dropped: the terminal did not take them",
                    off.writer.dropped,
                )


class TerminalDisplay:
    """Redraws the tree and the sensor line at most ``refresh_hz`` times a second, within the
    terminal's size: the screen is cleared and rewritten in place, never scrolled (a tree
    taller than the terminal flooded the scrollback with a copy on every redraw)."""

    def __init__(
        self,
        stream: TextIO,
        refresh_hz: float = 5.0,
        size: Callable[[], tuple[int, int]] | None = None,
        label: str = "",
    ) -> None:
        self.stream = stream
        #: the run's label (``run --label``), the screen's first line: which run's tree
        #: this is, in one of several terminals; "" for none
        self.label = label
        #: what draws on the terminal, off the tick loop (a stalled terminal must not hold
        #: it up); a terminal that failed ends the drawing
        self.writer = OffTickWriter(stream)
        self.period = 1.0 / refresh_hz
        self._last = 0.0
        self._size = size or _terminal_size
        #: each screen printed under the last, no clearing, on ``TERM=dumb`` (``ESC [H ESC
        #: [J`` showed as garbage in an Emacs shell or on a serial console) and where the
        #: stream is no terminal (``--display tree > run.log``, a pipe: decided, each screen
        #: is kept as text rather than refused, and the log read with ``less`` had the cursor
        #: codes in it before every screen)
        self.plain = plain_terminal() or not stream.isatty()
        self.marks = status_marks(stream)
        #: the tree whose names :attr:`names` holds (a ``--watch`` reload brings another)
        self._named: py_trees.behaviour.Behaviour | None = None
        self.names: Mapping[UUID, str] | None = None

    def __call__(self, runner: MissionRunner) -> None:
        now = time.monotonic()
        if now - self._last < self.period:
            return
        self._last = now
        self.render(runner)

    def render(self, runner: MissionRunner, as_left: TreeStatuses | None = None) -> None:
        """Draw once, through :attr:`writer`: a terminal that stalls or is gone holds up
        nothing, and its ``OSError`` no longer reads as a lost port in the tick loop.
        ``as_left``: the statuses the run left its tree in, for the last screen, drawn
        after the run's end stopped the tree (:func:`fitted_tree`)."""
        if self.writer.gone:
            return
        columns, rows = self._size()
        status = sensor_lines(runner.snapshot, columns)
        if self.label:
            status.insert(0, self.label[:columns])
        # the status lines, a blank line, the tree, and the cursor's line left free
        mission = runner.mission
        if mission.root is not self._named:  # live_names builds the tree again: once
            self._named, self.names = mission.root, live_names(mission)
        tree = fitted_tree(
            mission.root, rows - 2 - len(status), columns, self.marks, as_left, self.names
        )
        screen = "\n".join(status) + "\n\n" + "\n".join(tree) + "\n"
        text = "\n" + screen if self.plain else "\x1b[H\x1b[J" + screen
        self.writer.post(text, latest_only=True)

    def close(self, timeout: float = 1.0) -> None:
        """The last screen written (for up to ``timeout`` s), then no more."""
        self.writer.close(timeout)


def _terminal_size() -> tuple[int, int]:
    size = shutil.get_terminal_size((80, 24))
    return size.columns, size.lines


#: The log's heartbeat by default (``run --heartbeat``): a line every this many seconds of
#: mission time. A patrol's log printed nothing from its first tick to its first docking,
#: 3.5 hours: a journal that could not tell "fine" from "hung".
HEARTBEAT_S = 600.0


class StatusChangeLogger:
    """Logs one line per node whose status changed during the tick, the tick's mission time
    in the record (``mission_time``: :class:`MissionClockFormatter` prints it), and every
    ``heartbeat_s`` of mission time (None: never) a line of how the run is going: battery,
    distance, mode, ticks. Mission time, not the wall clock's: a ``--fast`` run shows it as
    a robot's does, and its replay at the same ticks."""

    def __init__(self, logger: logging.Logger = log, heartbeat_s: float | None = None) -> None:
        self.logger = logger
        self._last: dict[object, py_trees.common.Status] = {}
        self.heartbeat_s = heartbeat_s
        #: the mission time of the next heartbeat
        self._beat_at = heartbeat_s if heartbeat_s else float("inf")

    def __call__(self, runner: MissionRunner) -> None:
        if not self.logger.isEnabledFor(logging.INFO):
            return
        last = self._last
        t = runner.snapshot.time
        if t >= self._beat_at:
            self._beat(runner.snapshot)
        for node in runner.mission.root.iterate():
            status = node.status
            if last.get(node.id) is not status:
                if status is not py_trees.common.Status.INVALID or node.id in last:
                    name = shortened(node.name)  # a 200 KB name was a 200 KB log line
                    self.logger.info("%s -> %s", name, status.value, extra={"mission_time": t})
                last[node.id] = status

    def _beat(self, snapshot: Snapshot) -> None:
        """The heartbeat's line: ``still running: battery 43 %, 1204.31 m driven, Safe,
        tick 80266``; the next at the following whole period."""
        every = self.heartbeat_s or float("inf")
        while self._beat_at <= snapshot.time:
            self._beat_at += every
        frame = snapshot.frame
        battery = (
            f"battery {frame.battery_percent:.0f} %"
            if frame.carries(BATTERY_PACKETS)
            else "battery not streamed"
        )
        self.logger.info(
            "still running: %s, %.2f m driven, %s, tick %d", battery,
            snapshot.odometry.path_mm / 1000, snapshot.mode.name.title(), snapshot.tick,
            extra={"mission_time": snapshot.time},
        )  # fmt: skip


class TreeStatuses:
    """Each node's status and message, and the tip, as a tree stood at one moment: what a
    tree printed after the run draws (``text_tree``'s ``as_ticked``). The tree's stop
    marks every node INVALID, so a run ended by a behaviour's exception printed every node
    ``[-]``, even a ``mode(safe)`` that had succeeded: the runner keeps the tree as it
    stood before its stop (``MissionRunner.tree_as_left``)."""

    def __init__(self) -> None:
        #: each node's (status, feedback message); empty: none taken
        self.nodes: dict[UUID, tuple[py_trees.common.Status, str]] = {}
        #: the node the tree's last tick ended at (drawn bold), None where none ran
        self.tip_id: UUID | None = None

    def take(
        self,
        root: py_trees.behaviour.Behaviour,
        raised: tuple[py_trees.behaviour.Behaviour, str] | None = None,
    ) -> None:
        """The tree's statuses, messages and tip as they are now. ``raised``: the node whose
        exception ended the run and what it raised (``RuntimeError``), said as its message
        and made the tip: it never returned a status, so its mark alone told nothing."""
        self.nodes = {node.id: (node.status, node.feedback_message) for node in root.iterate()}
        tip = root.tip()
        self.tip_id = tip.id if tip is not None else None
        if raised is not None and raised[0].id in self.nodes:
            node, what = raised
            self.nodes[node.id] = (node.status, f"raised {what}")
            self.tip_id = node.id


class TreeAsTicked(TreeStatuses):
    """The tree's statuses and messages as each tick leaves them (an observer), for a tree
    printed after the run (``replay --display tree``, :func:`text_tree`'s ``as_ticked``).

    A run that does not end with its tree (a replay's first difference, ``--to``, an
    interrupt) stops the tree first, and a stopped node is INVALID: the replay's tree showed
    every node ``[-]``, even ``mode(safe)`` which had run. Kept per tick, not drawn: the
    drawing is done once, at the end."""

    def __call__(self, runner: MissionRunner) -> None:
        self.take(runner.mission.root)


def observer_for(
    display: Display, stream: TextIO, label: str = "", heartbeat_s: float | None = None
) -> TerminalDisplay | StatusChangeLogger | None:
    """The observer ``--display`` asks for, the tree drawn on ``stream``. ``auto`` on a
    ``TERM=dumb`` terminal is the log: redrawn without a cursor to move, the tree would
    scroll a copy of itself five times a second; so is ``auto`` in the background of a
    terminal (:func:`owns_the_screen`). ``tree`` draws the tree wherever it is asked, under
    the run's ``label`` (``run --label``) when it has one; the log with a line every
    ``heartbeat_s`` of mission time (``run --heartbeat``)."""
    if display == "tree" or (display == "auto" and owns_the_screen(stream)):
        return TerminalDisplay(stream, label=label)
    if display in ("log", "auto"):
        return StatusChangeLogger(heartbeat_s=heartbeat_s)
    return None
