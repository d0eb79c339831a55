"""``roomba-bt sim --log``: what the simulated robot heard, did and ignored, a line each.

A driver under test (pycreate2, a student's script, ours) writes bytes the robot either takes
or ignores, and the robot answers with mode changes, bumps and cliffs. The summary at exit
counts them; the log shows them as they happen, in the robot's own time::

       0.000 s  heard Start (128)                                            80
       0.000 s  mode: Off->Passive (start)
       0.300 s  heard Drive (137) velocity 200, radius -32768               89 00 c8 80 00
       0.300 s  ignored Drive (137): not accepted in Passive
       1.215 s  heard Safe (131)                                             83

Each command is named from the opcode table with its arguments as the robot reads them
(two-byte ones signed or not as the table says) and its bytes; the events are the
simulator's own (:attr:`Simulator.events`: modes, bumps, cliffs, docking, faults, built-in
cycles); an actuator command the mode does not accept is one of
:attr:`Simulator.violations`. A wheel command (Drive, Drive Direct, Drive PWM) repeated with
the same bytes while in force changes nothing on the robot and has no line (a client that
sends one a frame would fill the log).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable

from roomba_bt.oi.opcodes import COMMANDS, CommandSpec
from roomba_bt.sim.robot import Simulator

#: the width the command's name and arguments are padded to, before its bytes
_TEXT_WIDTH = 60
#: why bytes the robot awake ignored were ignored
NO_OPCODE = "no opcode, or sent at another baud rate"
#: why bytes a robot asleep (the five-minute Passive sleep, ``sim --asleep``) ignored were:
#: not :data:`NO_OPCODE`, which would send a run's user looking at the baud rate of a robot
#: that only slept
ASLEEP = (
    "the robot is asleep, deaf to the line until a BRC pulse wakes it (on a pty a hang-up: "
    "roomba-bt doctor or run --baud auto gives one)"
)


def command_text(spec: CommandSpec, args: bytes) -> str:
    """``Drive (137) velocity 200, radius -32768``: the name, then each fixed argument; a
    variable tail (Song's notes, Stream's packet ids) as its count of items."""
    fixed = spec.fixed_data_bytes
    codes = "".join(arg.code for arg in spec.args)
    values = struct.unpack_from(">" + codes, args) if codes and len(args) >= fixed else ()
    words = [f"{arg.name} {value}" for arg, value in zip(spec.args, values, strict=False)]
    if spec.tail is not None and len(args) > fixed:
        words.append(f"then {', '.join(str(b) for b in args[fixed:])}")
    text = f"{spec.title} ({spec.opcode})"
    return f"{text} {', '.join(words)}" if words else text


class Narrator:
    """Writes the log of one simulator (``write`` takes a line): the commands as the robot
    hears them (its :attr:`~Simulator.heard`), and what followed each (:meth:`catch_up`, also
    called by the server after the steps, for what the robot did by itself)."""

    def __init__(self, simulator: Simulator, write: Callable[[str], None]) -> None:
        self.simulator = simulator
        self.write = write
        self._events = len(simulator.events)
        self._violations = len(simulator.violations)
        self._ignored_bytes = simulator.ignored_bytes
        simulator.heard = self._heard

    def _heard(self, spec: CommandSpec, args: bytes) -> None:
        self.catch_up()  # what the commands before it did, first
        text = command_text(spec, args)
        data = bytes([spec.opcode]) + args
        self._line(f"heard {text:<{_TEXT_WIDTH}} {data.hex(' ')}")

    def catch_up(self) -> None:
        """Write the events, ignored commands and ignored bytes since the last call."""
        sim = self.simulator
        events = sim.events
        for event in events[self._events :]:
            detail = f": {event.detail}" if event.detail else ""
            self._line(f"{event.kind}{detail}", event.time)
        self._events = len(events)
        violations = sim.violations
        for v in violations[self._violations :]:
            title = COMMANDS[v.opcode].title
            self._line(f"ignored {title} ({v.opcode}): not accepted in {v.mode.label}", v.time)
        self._violations = len(violations)
        skipped = sim.ignored_bytes - self._ignored_bytes
        if skipped:
            self._ignored_bytes = sim.ignored_bytes
            self._line(f"ignored {skipped} byte(s): {ASLEEP if sim.deaf else NO_OPCODE}")

    def _line(self, text: str, time: float | None = None) -> None:
        at = self.simulator.time if time is None else time
        self.write(f"{at:10.3f} s  {text}")


#: the events that end what the robot did on its own after the link was cut
_ENDINGS = ("fell", "mode", "docked", "sleep")


def after_the_cut(simulator: Simulator) -> str | None:
    """What the robot did after ``Faults.disconnect_at`` cut its link, for the summary at
    exit (None if the link was not cut): a robot whose host is gone goes on with its last
    command, and a summary of the state at exit alone ("mode Full, wheels 314/314 mm/s")
    read as if it had stopped where the plot's line stopped.

    ``link cut at 4.0 s in Full, wheels 314/314 mm/s; the OI has no command timeout, so it
    went on: at 7.9 s it fell: drove off a drop``."""
    events = simulator.events
    cut = next((i for i, e in enumerate(events) if e.kind == "disconnect"), None)
    if cut is None:
        return None
    at = events[cut]
    said = f"link cut at {at.time:.1f} s {at.detail.removeprefix('link lost ')}"
    bumps = sum(1 for e in events[cut + 1 :] if e.kind == "bump")
    ended = next((e for e in events[cut + 1 :] if e.kind in _ENDINGS), None)
    if ended is not None:
        went = f"at {ended.time:.1f} s {ended.kind}: {ended.detail}"
    elif simulator.requested_left or simulator.requested_right:
        went = (
            f"still driving {simulator.requested_left:.0f}/{simulator.requested_right:.0f} "
            f"mm/s in {simulator.mode.label} at the end ({simulator.time:.1f} s)"
        )
    else:
        went = f"still in {simulator.mode.label} at the end ({simulator.time:.1f} s)"
    if bumps:
        went += f" ({bumps} bump{'s' if bumps > 1 else ''} on the way)"
    moved = math.hypot(simulator.x - at.x, simulator.y - at.y) / 1000
    return (
        f"{said}; the OI has no command timeout, so it went on with its last command: {went}; "
        f"it ended {moved:.2f} m from where the link was cut"
    )


def what_the_line_did(simulator: Simulator, host: str = "client") -> str | None:
    """What the simulated cable's faults did to the bytes, each way, for the summary at exit
    (None on a clean line): what the user asked it to lose, counted, beside what the run
    found lost (``run``'s ``link`` line counts frames, not bytes). ``host``: what the other
    end is called (``sim``'s client, ``run``'s computer).

    ``the line lost 412 of the 20650 bytes from the robot (2.0 %), and lost 3 and changed
    0 of the bytes from the computer``."""
    said = []
    robot = simulator.robot_line
    if robot is not None:
        sent = robot.dropped + robot.passed_on
        share = 100.0 * robot.dropped / sent if sent else 0.0
        said.append(f"lost {robot.dropped} of the {sent} bytes from the robot ({share:.1f} %)")
    line = simulator.host_line
    if line is not None:
        said.append(
            f"lost {line.dropped} and changed {line.corrupted} of the bytes from the {host}"
        )
    return f"the line {', and '.join(said)}" if said else None
