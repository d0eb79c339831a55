"""The far end of ``run``, ``sensors`` and ``clock``: a robot's serial port, or the built-in
simulator when no ``--port`` is given.

Either way the result is a :class:`~roomba_bt.transport.Transport`, and everything above it
(connection, runner, display, record) is the same code. ``--fast`` uses
:class:`roomba_bt.sim.SimLink` as is: every read advances the virtual clock, as fast as the
host computes. Without it, :class:`roomba_bt.sim.RealtimeSimLink` paces the same simulator to
the wall clock.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable
from dataclasses import replace

from roomba_bt.cli.profile_choice import AUTO_PROFILE, ProfileChoice, profile_said
from roomba_bt.oi.identify import Identification
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.robot.connection import Connection, no_answer_causes, port_not_opened
from roomba_bt.robot.discovery import OI_RATES, describe_silence, find_robot, identify_robot
from roomba_bt.robot.errors import ConnectionFailed
from roomba_bt.sim import Faults, RealtimeSimLink, SimLink, Simulator, World, load_world
from roomba_bt.transport import SerialTransport, Transport, TransportError

DEFAULT_WORLD = "empty-room"

log = logging.getLogger(__name__)


def open_port(url: str, baud: int | None) -> SerialTransport:
    """The serial port (device path or pyserial URL) to a robot; :class:`ConnectionFailed`
    names the port and what to check if it cannot be opened.

    ``baud`` None (``--baud auto``): the rate the robot answers at, found as ``doctor`` finds
    it (:func:`roomba_bt.robot.discovery.find_robot`: 115200, then 19200, then a BRC pulse
    and both again); the port is left at that rate (``transport.baud``)."""
    try:
        transport = SerialTransport.open(url, baud or OI_RATES[0])
    except TransportError as exc:
        raise port_not_opened(url, exc) from exc
    if baud is not None:
        return transport
    try:
        found = find_robot(transport)
    except OSError as exc:
        transport.close()
        raise ConnectionFailed(url, f"the port failed while finding the baud rate ({exc})") from exc
    if found.baud is None:
        transport.close()
        raise ConnectionFailed(
            url,
            f"--baud auto: no answer at any OI rate ({describe_silence(found)})",
            (*no_answer_causes(url)[1:], f"run roomba-bt doctor --port {url} for each step"),
        )
    log.info("%s: the robot answers at %d baud (--baud auto)", url, found.baud)
    return transport


def make_simulator(
    world: str | None,
    profile: RobotProfile,
    seed: int,
    *,
    random_start: bool = False,
    faults: Faults | None = None,
    coverage: bool = False,
    battery: float | None = None,
    trace: bool = True,
) -> Simulator:
    """A simulator in ``world`` (a shipped name or a path), its battery at ``battery`` (a
    fraction) instead of the world's if given; raises WorldError if invalid.
    ``coverage``: it tracks the floor cleaned (:mod:`roomba_bt.sim.coverage`); ``trace``: it
    keeps its trajectory (for a plot)."""
    loaded = charged_world(world, battery)
    return Simulator(
        loaded, profile, seed, faults, random_start=random_start, coverage=coverage, trace=trace,
        cycle_commands_pause=True,  # as the OI spec says (docs/simulator.md)
    )  # fmt: skip


def charged_world(world: str | None, battery: float | None) -> World:
    """``world`` (a shipped name or a path; None: the default) with its battery at
    ``battery`` (a fraction, ``--battery``) instead of the world's if given: ``run``,
    ``eval`` and ``sim`` read the option the same way. Raises WorldError if invalid."""
    loaded = load_world(world or DEFAULT_WORLD)
    return loaded if battery is None else replace(loaded, battery=battery)


def make_link(simulator: Simulator, fast: bool) -> SimLink:
    """The virtual-clock link (``fast``) or the wall-clock one."""
    return SimLink(simulator) if fast else RealtimeSimLink(simulator)


def auto_baud(port: str | None, profile: RobotProfile) -> tuple[int, SerialTransport | None]:
    """``--baud auto``: on a port, the rate the robot answers at and the port left open at it
    (:func:`open_port`; :class:`ConnectionFailed` if nothing answers); on the simulator, the
    profile's default rate and no port."""
    if not port:
        return profile.default_baud, None
    opened = open_port(port, None)
    return opened.baud, opened


def auto_profile(args: argparse.Namespace, command: str) -> SerialTransport | None:
    """``--profile auto`` (from the flag, ``ROOMBA_BT_PROFILE`` or the project file; only
    with ``--port``: :mod:`roomba_bt.cli.profile_choice`): the port opened, at ``--baud``
    or the rate ``--baud auto`` finds (``args.baud`` then set), and the robot identified on
    it before the mission is compiled for a model (:func:`identify_robot`: no Reset);
    ``args.profile`` the model, ``args.profile_source`` how it was told, said on stderr with
    what it fell back to when it could not tell. The port, left open for the run (None: a
    model was named, nothing done). :class:`ConnectionFailed` if the port cannot be opened
    or fails."""
    if args.profile != AUTO_PROFILE:
        return None
    transport = open_port(args.port, args.baud)
    args.baud = transport.baud
    try:
        found = identify_robot(transport, transport.baud)
    except OSError as exc:
        transport.close()
        raise ConnectionFailed(
            args.port, f"the port failed while identifying the robot ({exc})"
        ) from exc
    said = profile_said(ProfileChoice(AUTO_PROFILE, args.profile_source))
    profile, how, sentence = identified(found)
    args.profile, args.profile_source = profile.name, f"{said}: {how}"
    print(f"roomba-bt {command}: {said}: {sentence}", file=sys.stderr)
    return transport


def identified(found: Identification | str) -> tuple[RobotProfile, str, str]:
    """The profile ``--profile auto`` runs with, how it was told (a few words for the
    summary's profile line) and the whole sentence: the evidence, or why none, and what it
    fell back to."""
    if isinstance(found, str):
        return DEFAULT_PROFILE, "not identified, the default", (
            f"not identified: {found}; speaking to it as the {DEFAULT_PROFILE.title} "
            f"({DEFAULT_PROFILE.name}), the default"
        )  # fmt: skip
    profile = found.assumed
    why = "; ".join(found.evidence) or "nothing seen"
    if found.decided:
        return profile, "identified", f"{profile.title} ({profile.name}): {why}"
    if found.best is None:
        return profile, "no profile fits, the default", (
            f"no profile fits ({why}); speaking to it as the {profile.title} ({profile.name}), "
            "the default; roomba-bt doctor --port URL says more"
        )  # fmt: skip
    others = " or ".join(f"a {p.title} (--profile {p.name})" for p in found.candidates
                         if p is not profile)  # fmt: skip
    return profile, f"not told apart from {others}", (
        f"the {profile.title} ({profile.name}) or {others}: not told apart ({why}); "
        f"speaking to it as the {profile.title}: give --profile NAME if its label says "
        "otherwise"
    )  # fmt: skip


def far_end(
    port: str | None,
    baud: int,
    simulator: Simulator | None,
    *,
    fast: bool = False,
    opened: SerialTransport | None = None,
) -> Transport:
    """The link a command talks over: the port ``--baud auto`` left ``opened``, else the port
    at ``baud``, else the ``simulator``'s link (:func:`make_link`)."""
    if opened is not None:
        return opened
    if port:
        return open_port(port, baud)
    if simulator is None:
        raise ValueError("no --port and no simulator to talk to")
    return make_link(simulator, fast)


#: A command's talk with the robot (:func:`talk_to_robot`): given the connection, made but not
#: started (the command starts it in the mode, and with the stream, it needs), and the
#: simulator at the far end (None on a port); returns the command's exit code.
Session = Callable[[Connection, Simulator | None], int]


def talk_to_robot(
    args: argparse.Namespace,
    command: str,
    session: Session,
    *,
    refuse: Callable[[RobotProfile, int | None], str | None] | None = None,
) -> int:
    """``roomba-bt COMMAND``'s one connection to the robot on ``--port`` or the simulator
    (``sensors``, ``clock``), its exit code: the model chosen (``--profile``, its setting,
    ``auto`` identified on the port), ``refuse(profile, baud)``'s usage error if it has one
    (exit 2: nothing sent, unless ``auto`` had to ask the robot first; asked before
    ``--baud auto`` probes the port, with None, and again with the rate found), the
    simulator (``--world``), and the :class:`Connection` handed to ``session`` in a
    ``with``, so that every ending, an exception or a signal too, stops the robot and leaves
    it in Passive. A wrong profile (the robot's frames are another
    model's) is exit 2, as ``run`` says it; a port or a robot that fails, exit 3."""
    from roomba_bt.cli.arguments import baud_warning
    from roomba_bt.cli.profile_choice import chosen_profile
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.robot.errors import LinkDown
    from roomba_bt.robot.safety import sigterm_raises
    from roomba_bt.runtime.summary import ExitCode, Outcome

    problem = chosen_profile(args, command)  # the current directory's project's
    if problem is not None:
        print(f"roomba-bt {command}: {problem}", file=sys.stderr)
        return ExitCode.INVALID
    try:
        opened = auto_profile(args, command)
    except ConnectionFailed as exc:
        print(f"roomba-bt: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    profile = get_profile(args.profile)
    warned = baud_warning(args.baud, profile, simulated=not args.port)
    if warned is not None:
        print(f"roomba-bt {command}: {warned}", file=sys.stderr)
    try:
        made = _connection(args, command, profile, opened, refuse)
        if isinstance(made, int):
            return made
        connection, simulator = made
        with sigterm_raises(), connection:
            return session(connection, simulator)
    except LinkDown as exc:
        if exc.mismatch is not None:  # another model's frames: a setting, as run says it
            print(f"roomba-bt: {Outcome.WRONG_PROFILE.value}: {exc}", file=sys.stderr)
            return Outcome.WRONG_PROFILE.exit_code
        print(f"roomba-bt: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    except ConnectionFailed as exc:
        print(f"roomba-bt: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    # a Ctrl-C or a signal goes on to main, which says "roomba-bt: interrupted" (by what) and
    # exits 130, as every command


def _connection(
    args: argparse.Namespace,
    command: str,
    profile: RobotProfile,
    opened: SerialTransport | None,
    refuse: Callable[[RobotProfile, int | None], str | None] | None,
) -> tuple[Connection, Simulator | None] | int:
    """:func:`talk_to_robot`'s connection, not started, and its simulator (None on a port);
    or the exit code of a usage error, said (the port ``--baud auto`` or ``auto`` opened
    closed)."""
    from roomba_bt.cli.profile_choice import profile_setting
    from roomba_bt.cli.worlds_cmd import world_error_text
    from roomba_bt.runtime.summary import ExitCode
    from roomba_bt.sim import WorldError

    refused = None if refuse is None else refuse(profile, args.baud)  # before any probe
    if refused is None and args.baud is None:  # --baud auto: the rate found, checked too
        args.baud, opened = auto_baud(args.port, profile)
        refused = None if refuse is None else refuse(profile, args.baud)
    if refused is not None:
        if opened is not None:
            opened.close()
        print(f"roomba-bt {command}: {refused}", file=sys.stderr)
        return ExitCode.INVALID
    simulator = None
    if not args.port:
        try:
            simulator = make_simulator(args.world, profile, 0)
        except WorldError as exc:
            print(world_error_text(exc, command), file=sys.stderr)
            return ExitCode.INVALID
    link = far_end(args.port, args.baud, simulator, opened=opened)
    connection = Connection(link, profile, baud=args.baud)
    connection.profile_setting = profile_setting(args)  # a wrong profile's fix
    connection.waiter = f"roomba-bt {command}"  # a lost stream's grace: no run waited it
    return connection, simulator
