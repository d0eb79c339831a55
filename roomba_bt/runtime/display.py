"""What a user sees while a mission runs.

On a terminal: the tree with live statuses (py_trees' unicode rendering) and the key sensors,
redrawn a few times a second of wall time. Without a terminal (a log, CI): one line per status
change of any node, stamped with mission time. Both are observers called after the tick and its
flush, outside the measured tick time.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Literal, TextIO

import py_trees

from roomba_bt.oi.ir import IRCharacter

if TYPE_CHECKING:
    from roomba_bt.robot.interface import Snapshot
    from roomba_bt.runtime.loop import MissionRunner

log = logging.getLogger("roomba_bt.run")

#: ``run --display``: the live tree, one log line per status change, or nothing; ``auto`` is
#: the tree on a terminal and the log elsewhere.
Display = Literal["auto", "tree", "log", "none"]


def sensor_line(snapshot: Snapshot) -> str:
    """One line of the sensors that matter most, from whatever the frame carries."""
    frame = snapshot.frame
    parts = [f"t={snapshot.time:7.2f}s", f"mode={snapshot.mode.label}"]
    if 7 in frame:
        b = frame.bumps
        bumps = "L" * b.bump_left + "R" * b.bump_right or "-"
        drops = "L" * b.wheel_drop_left + "R" * b.wheel_drop_right or "-"
        parts += [f"bump={bumps}", f"drop={drops}"]
    if all(p in frame for p in (9, 10, 11, 12)):
        cliffs = "".join(c for c, p in zip("LlrR", (9, 10, 11, 12), strict=False) if frame[p])
        parts.append(f"cliff={cliffs or '-'}")
    for pid, label in ((17, "ir"), (52, "irL"), (53, "irR")):
        if frame.get(pid):
            ir = IRCharacter.decode(frame[pid])
            beams = "".join(
                c
                for c, on in (("R", ir.red_buoy), ("G", ir.green_buoy), ("F", ir.force_field))
                if on
            )
            parts.append(f"{label}={ir.code}{'(' + beams + ')' if beams else ''}")
    if 34 in frame and frame.charging_sources.any:
        parts.append("charger=" + ("home" if frame.charging_sources.home_base else "internal"))
    if 25 in frame and 26 in frame:
        parts.append(f"battery={frame.battery_percent:.0f}%")
    odo = snapshot.odometry
    parts.append(f"odo=({odo.x_mm / 1000:+.2f},{odo.y_mm / 1000:+.2f})m")
    return "  ".join(parts)


class TerminalDisplay:
    """Redraws the tree and the sensor line at most ``refresh_hz`` times a second."""

    def __init__(self, stream: TextIO, refresh_hz: float = 5.0) -> None:
        self.stream = stream
        self.period = 1.0 / refresh_hz
        self._last = 0.0

    def __call__(self, runner: MissionRunner) -> None:
        now = time.monotonic()
        if now - self._last < self.period:
            return
        self._last = now
        self.render(runner)

    def render(self, runner: MissionRunner) -> None:
        tree = py_trees.display.unicode_tree(runner.mission.root, show_status=True)
        text = f"{sensor_line(runner.snapshot)}\n\n{tree}\n"
        self.stream.write("\x1b[H\x1b[J" + text)
        self.stream.flush()


class StatusChangeLogger:
    """Logs one line per node whose status changed during the tick."""

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
                    self.logger.info("t=%.3fs %s -> %s", t, node.name, status.value)
                last[node.id] = status


def observer_for(display: Display, stream: TextIO) -> TerminalDisplay | StatusChangeLogger | None:
    """The observer ``--display`` asks for, the tree drawn on ``stream``."""
    if display == "tree" or (display == "auto" and stream.isatty()):
        return TerminalDisplay(stream)
    if display in ("log", "auto"):
        return StatusChangeLogger()
    return None
