"""How the robot layer's messages name what their caller changes: the command line's flags
or a Python call's arguments (for connections what ``mission/wording.py`` is for missions).

A message about keep-awake says how to turn it off (or leave it on) and where the longer
story is. ``roomba-bt run``'s user types ``--no-keep-awake`` and ``-v``; a program passes
``keep_awake=False`` and has no ``-v``: told both, neither reads as its own. The robot
layer cannot take the mission layer's :class:`~roomba_bt.mission.wording.Wording` (it sits
below it), and a connection is made far from the command that knows whose it is (inside a
``RunStack``, ``doctor``, ``sensors``): the process's command sets :data:`current` for as
long as it runs (:func:`spoken`, ``cli/__init__.py``), and a program gets :data:`PYTHON`.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace

__all__ = ["COMMAND_LINE", "PYTHON", "UNATTENDED", "ConnectionWording", "current", "spoken"]


@dataclass(frozen=True, slots=True)
class ConnectionWording:
    """What the caller writes to change each thing a connection's message may name."""

    #: how the caller turns keep-awake off (which also silences the warning that it is off)
    keep_awake_off: str
    #: how the caller leaves keep-awake on, having turned it off
    keep_awake_on: str
    #: where the caller reads why (the debug log)
    why: str
    #: how the caller reads the firmware's release (the banner Reset (7) prints), said to the
    #: owner of a robot that a BRC pulse does not wake on the dock
    firmware_read: str
    #: what the caller set to limit a record's size, as "... 64 kB reached" says it
    record_max: str
    #: what the caller set to end a replay before its record does
    replay_until: str
    #: how the caller reads a robot with the profile ``{name}`` (a stop unconfirmed on
    #: another model's frames says it: robot/silence.py)
    profile_named: str
    #: what the caller set to limit a run's wall-clock time, ``{limit}`` long, as "... of
    #: wall-clock time ran out" says it (runtime/wall_limit.py)
    wall_limit: str
    #: what the robot's owner can do about a robot that answers nothing at start-up, asleep
    #: or without power: at the robot, a button; with nobody there (a service, a timer), the
    #: BRC line that wakes it and keeps it awake, and its power
    wake_asleep: str = "press Clean or the power button"
    #: the same on a pty (``{port}``), which has no modem lines: the start-up pulsed no BRC,
    #: and a 1 s hang-up is the pulse there (what wakes ``sim --pty --asleep``). A run does
    #: not hang up at start-up: on a robot's cable the port's open pulls BRC low, and a
    #: hang-up there would add a second pulse (three after power-on set 19200 baud)
    wake_on_pty: str = (
        "a pty has no modem lines, so the start-up pulsed no BRC; `roomba-bt doctor --port "
        "{port}` pulses it by a 1 s hang-up, which wakes the simulator's robot"
    )


#: A Python program's words: ``Connection``'s, ``Connection.open``'s and ``RunStack``'s
#: arguments, and the ``roomba_bt`` logger
PYTHON = ConnectionWording(
    keep_awake_off="keep_awake=False",
    keep_awake_on="keep_awake left out, not False",
    why="logging DEBUG: why",
    firmware_read=(
        "the banner Reset (7) prints names the version: write "
        "roomba_bt.oi.commands.reset().data and read it with roomba_bt.oi.identify.parse_banner"
    ),
    record_max="Recording's max_bytes",
    replay_until="replay_record's until",
    profile_named="Connection.open(port, profile='{name}')",
    wall_limit="stack.runner.wall_limit_s ({limit})",
)

#: The ``roomba-bt`` command's words: its flags
COMMAND_LINE = ConnectionWording(
    keep_awake_off="--no-keep-awake",
    keep_awake_on="drop --no-keep-awake",
    why="-v: why",
    firmware_read="roomba-bt doctor --allow-reset reads the version",
    record_max="--record-max",
    replay_until="--to",
    profile_named="--profile {name}",
    wall_limit="--wall-limit {limit}",
    wake_on_pty=(
        "a pty has no modem lines, so this run's start-up pulsed no BRC: `roomba-bt doctor "
        "--port {port}` or run --baud auto pulses it by a 1 s hang-up, which wakes the "
        "simulator's robot; a run at a set rate adds no hang-up, as on a robot's cable the "
        "port's open is the pulse"
    ),
)

#: The ``roomba-bt`` command's words where nobody is at a terminal (stdin no TTY: a systemd
#: service, a cron job or timer): "press Clean" asked a person who is not there; what the
#: robot's owner sets up instead is BRC on the port's modem lines and the dock's power
#: (docs/unattended.md, "BRC: keeping the robot awake, and waking it at 9:00")
UNATTENDED = replace(
    COMMAND_LINE,
    wake_asleep=(
        "unattended, a BRC pulse wakes it: BRC wired to the port's RTS or DTR, as iRobot's "
        "cable does, and keep-awake left on; else check the dock's power and the battery: "
        "roomba-bt docs unattended, BRC"
    ),
)

#: the words this process's connection messages use now
current = PYTHON


@contextmanager
def spoken(wording: ConnectionWording) -> Iterator[None]:
    """``wording`` for the messages of the connections made meanwhile (the command line's,
    for its command), the words before put back after (a program that called the CLI's
    ``main`` goes on in its own)."""
    global current
    before, current = current, wording
    try:
        yield
    finally:
        current = before
