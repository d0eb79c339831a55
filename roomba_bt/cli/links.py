"""The far end of ``run`` and ``sensors``: a robot's serial port, or the built-in simulator
when no ``--port`` is given.

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
from dataclasses import replace

from roomba_bt.cli.profile_choice import AUTO_PROFILE, ProfileChoice, profile_said
from roomba_bt.oi.identify import Identification
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.robot.connection import no_answer_causes, port_not_opened
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
