"""What a user sees while a mission runs.

On a terminal: the tree with live statuses (py_trees' unicode rendering) and the key sensors,
redrawn a few times a second of wall time. Without a terminal (a log, CI): one line per status
change of any node, stamped with mission time. Both are observers called after the tick and its
flush, outside the measured tick time.
"""

from __future__ import annotations

import logging
import shutil
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Literal, TextIO

import py_trees

from roomba_bt.oi.frames import (
    BATTERY_PACKETS,
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CLIFF_PACKETS,
    IR_PACKETS,
)
from roomba_bt.oi.ir import IRCharacter

if TYPE_CHECKING:
    from roomba_bt.robot.interface import Snapshot
    from roomba_bt.runtime.loop import MissionRunner

log = logging.getLogger("roomba_bt.run")


class MissionClockFormatter(logging.Formatter):
    """Log lines stamped with mission time (``t=12.345``), not wall-clock time.

    What happened when, in a mission, is a question about mission time: on the virtual clock
    (``--fast``) the wall clock says nothing, and a refusal or a warning is compared with the
    tree's status lines (``t=12.345s ...``) and a recording's timestamps. Before a mission has
    a clock (or outside one: ``validate``, ``sim``) a line has no time at all."""

    clock: Callable[[], float | None] | None = None

    def format(self, record: logging.LogRecord) -> str:
        """``t=12.345 LEVEL logger: message``: the record's own ``mission_time`` (passed as
        ``extra``) if it has one, else the mission clock's now."""
        line = f"{record.levelname} {record.name}: {record.getMessage()}"
        if record.exc_info and not record.exc_text:
            record.exc_text = self.formatException(record.exc_info)
        if record.exc_text:
            line += "\n" + record.exc_text
        now: float | None = getattr(record, "mission_time", None)
        clock = type(self).clock
        if now is None and clock is not None:
            now = clock()
        return line if now is None else f"t={now:.3f} {line}"


def use_mission_clock(runner: MissionRunner | None) -> None:
    """Stamp log lines with ``runner``'s mission time from now on (None: stop stamping)."""
    MissionClockFormatter.clock = (
        None if runner is None else lambda: runner.snapshot.time if runner.has_snapshot else None
    )


#: ``run --display``: the live tree, one log line per status change, or nothing; ``auto`` is
#: the tree on a terminal and the log elsewhere.
Display = Literal["auto", "tree", "log", "none"]


def sensor_line(snapshot: Snapshot) -> str:
    """One line of the sensors that matter most, from whatever the frame carries."""
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
    return "  ".join(parts)


_MARKS = {
    py_trees.common.Status.RUNNING: "*",
    py_trees.common.Status.SUCCESS: "✓",
    py_trees.common.Status.FAILURE: "✕",
    py_trees.common.Status.INVALID: "-",
}


def fitted_tree(root: py_trees.behaviour.Behaviour, rows: int, columns: int) -> list[str]:
    """The tree as at most ``rows`` lines of at most ``columns`` characters.

    Only a running node shows its children: a finished or not yet started subtree is one
    line (``[✓] +3`` says it hides three nodes), so the running path stays in view however
    large the tree. If that is still too tall, the lines off the running path go first, from
    the bottom, and one line says how many were left out."""
    lines: list[tuple[str, bool]] = []  # (text, on the running path)

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        running = node.status is py_trees.common.Status.RUNNING
        children = list(node.children)
        folded = not running and children and depth > 0
        hidden = sum(1 for _ in node.iterate()) - 1 if folded else 0
        more = f" +{hidden}" if hidden else ""
        lines.append((f"{'  ' * depth}{node.name} [{_MARKS[node.status]}]{more}", running))
        if running or depth == 0:
            for child in children:
                walk(child, depth + 1)

    walk(root, 0)
    rows = max(rows, 2)
    if len(lines) > rows:
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
    return [text[: max(columns, 10)] for text, _ in lines]


class TerminalDisplay:
    """Redraws the tree and the sensor line at most ``refresh_hz`` times a second, within the
    terminal's size: the screen is cleared and rewritten in place, never scrolled (a tree
    taller than the terminal flooded the scrollback with a copy on every redraw)."""

    def __init__(
        self,
        stream: TextIO,
        refresh_hz: float = 5.0,
        size: Callable[[], tuple[int, int]] | None = None,
    ) -> None:
        self.stream = stream
        #: the terminal could not be written: nothing more is drawn
        self.gone = False
        self.period = 1.0 / refresh_hz
        self._last = 0.0
        self._size = size or _terminal_size

    def __call__(self, runner: MissionRunner) -> None:
        now = time.monotonic()
        if now - self._last < self.period:
            return
        self._last = now
        self.render(runner)

    def render(self, runner: MissionRunner) -> None:
        """Draw once; a terminal that is gone (EIO after a hang-up, a closed pipe) ends the
        drawing, not the run: its ``OSError`` in the tick loop read as a lost port."""
        if self.gone:
            return
        columns, rows = self._size()
        status = sensor_line(runner.snapshot)[:columns]
        # the status line, a blank line, the tree, and the cursor's line left free
        tree = fitted_tree(runner.mission.root, rows - 3, columns)
        try:
            self.stream.write("\x1b[H\x1b[J" + status + "\n\n" + "\n".join(tree) + "\n")
            self.stream.flush()
        except OSError:
            self.gone = True


def _terminal_size() -> tuple[int, int]:
    size = shutil.get_terminal_size((80, 24))
    return size.columns, size.lines


class StatusChangeLogger:
    """Logs one line per node whose status changed during the tick, the tick's mission time
    in the record (``mission_time``: :class:`MissionClockFormatter` prints it)."""

    def __init__(self, logger: logging.Logger = log) -> None:
        self.logger = logger
        self._last: dict[object, py_trees.common.Status] = {}

    def __call__(self, runner: MissionRunner) -> None:
        if not self.logger.isEnabledFor(logging.INFO):
            return
        last = self._last
        t = runner.snapshot.time
        for node in runner.mission.root.iterate():
            status = node.status
            if last.get(node.id) is not status:
                if status is not py_trees.common.Status.INVALID or node.id in last:
                    self.logger.info("%s -> %s", node.name, status.value, extra={"mission_time": t})
                last[node.id] = status


def observer_for(display: Display, stream: TextIO) -> TerminalDisplay | StatusChangeLogger | None:
    """The observer ``--display`` asks for, the tree drawn on ``stream``."""
    if display == "tree" or (display == "auto" and stream.isatty()):
        return TerminalDisplay(stream)
    if display in ("log", "auto"):
        return StatusChangeLogger()
    return None
