"""``roomba-bt sim``: the simulated robot on a pty, a TCP socket or an RFC 2217 port, in real
time.

The first line on stdout is where to connect (flushed at once, so a script can read it):
the pty's device path (``/dev/pts/7``) with ``--pty``, a pyserial URL
(``socket://127.0.0.1:PORT``) with ``--tcp``, ``rfc2217://127.0.0.1:PORT`` with
``--rfc2217`` (the one that carries the modem lines, so a BRC pulse reaches the robot; see
:mod:`roomba_bt.sim.server`). All open with ``serial.serial_for_url``. ``--baud`` is the
robot's rate (a client at another rate reads garbage and is not heard, on the pty and on
RFC 2217); ``--asleep`` starts it asleep, deaf until a BRC pulse. It
serves until SIGINT or SIGTERM (or ``--duration`` seconds), then prints a summary on stderr,
optionally writes a trajectory plot, and exits 0.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from types import FrameType
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import (
    add_battery_option,
    add_command,
    add_fault_options,
    add_profile_option,
    faults_given,
    plot_file,
    seconds,
    simulated_baud_refused,
)
from roomba_bt.oi.profiles import POWER_ON_BAUDS
from roomba_bt.runtime.summary import ExitCode

if TYPE_CHECKING:
    from roomba_bt.sim import Simulator
    from roomba_bt.sim.server import Endpoint


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "sim",
        run_sim,
        """serve the simulated robot on a pty or a TCP socket

        Serve a simulated Roomba / Create 2 in real time. The first stdout line is the pty path or
        the socket:// URL to open.
        """,
    )
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--pty", action="store_true", help="serve on a new pseudo-terminal")
    where.add_argument("--tcp", metavar="HOST:PORT", help="serve on a TCP socket (port 0: any)")
    where.add_argument(
        "--rfc2217", metavar="HOST:PORT",
        help="serve RFC 2217 on a TCP socket: the client's baud rate and modem lines (BRC on "
        "RTS/DTR) reach the robot",
    )  # fmt: skip
    parser.add_argument(
        "--baud", type=int, default=None,
        help=f"the robot's baud rate, one it talks at from power-on: "
        f"{' or '.join(str(rate) for rate in POWER_ON_BAUDS)} (the first the default; 19200 "
        "after Clean held at power-on on a Roomba 500, at power-off on a 600 or Create 2)",
    )  # fmt: skip
    parser.add_argument(
        "--asleep", action="store_true",
        help="start asleep (the 5-minute Passive sleep): deaf until a BRC pulse (--rfc2217)",
    )  # fmt: skip
    parser.add_argument(
        "--firmware", default=None, metavar="RELEASE",
        help="the release the reset banner names, e.g. release-3.6.0 (before release-3.8.2 / "
        "release-stm32-3.7.7 a BRC pulse does not wake it on the dock)",
    )  # fmt: skip
    parser.add_argument("--world", default="empty-room", help="shipped world name or YAML path")
    add_profile_option(parser, "the model the simulated robot is")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--random-start", action="store_true", help="start in the start region")
    add_battery_option(parser)
    parser.add_argument(
        "--old-firmware-angle", action="store_true", help="Angle (20) as firmware <= 3.4.0"
    )
    parser.add_argument("--duration", type=seconds, help="stop after this many seconds")
    parser.add_argument(
        "--plot",
        metavar="FILE",
        type=plot_file,
        help="write the trajectory on exit (.png, .pdf, .svg: the suffix is the format)",
    )
    parser.add_argument(
        "--log", action="store_true", help="on stderr: each command heard or ignored, each event"
    )
    add_fault_options(parser, "what goes wrong on the line and in the robot")


def _fail(message: str, code: ExitCode) -> int:
    print(f"roomba-bt sim: {message}", file=sys.stderr)
    return code


def run_sim(args: argparse.Namespace) -> int:
    simulator = _simulator(args)
    if isinstance(simulator, int):
        return simulator
    endpoint = _endpoint(args, simulator.baud)
    if isinstance(endpoint, int):
        return endpoint
    failed = _serve_until_stopped(simulator, endpoint, args.duration, log=args.log)
    if failed is not None:
        return failed
    print(
        f"roomba-bt sim: {simulator.time:.1f} s simulated, {simulator.frames_sent} frames, "
        f"{len(simulator.violations)} ignored actuator commands, mode {simulator.mode.label}, "
        f"wheels {simulator.requested_left:.0f}/{simulator.requested_right:.0f} mm/s",
        file=sys.stderr,
    )
    if simulator.robot_clock.touched:  # what a client set, which no packet reads back
        from roomba_bt.cli.clock_cmd import clock_said, schedule_said

        held = simulator.robot_clock
        print(f"roomba-bt sim: the robot's clock reads {clock_said(*held.shows(simulator.time))}"
              f", its schedule {schedule_said(held.cleans)}", file=sys.stderr)  # fmt: skip
    from roomba_bt.sim.narrate import after_the_cut, what_the_line_did

    line = what_the_line_did(simulator)
    if line is not None:
        print(f"roomba-bt sim: {line}", file=sys.stderr)
    cut = after_the_cut(simulator)
    if cut is not None:
        print(f"roomba-bt sim: {cut}", file=sys.stderr)
    if args.plot:
        try:
            from roomba_bt.sim.plot import plot_run

            plot_run(simulator, args.plot)
        except ImportError as exc:
            return _fail(str(exc), ExitCode.INVALID)
        except OSError as exc:
            return _fail(f"--plot {args.plot}: {exc.strerror or exc}", ExitCode.INVALID)
        print(f"roomba-bt sim: trajectory written to {args.plot}", file=sys.stderr)
    return ExitCode.OK


def _simulator(args: argparse.Namespace) -> Simulator | int:
    """The simulated robot the options describe (faults, world, rate, firmware, asleep), or
    the exit code after saying which option is wrong."""
    from roomba_bt.cli.links import charged_world
    from roomba_bt.cli.profile_choice import chosen_profile
    from roomba_bt.oi.identify import parse_firmware
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.sim import Simulator, WorldError

    problem = chosen_profile(args, "sim")
    if problem is not None:
        return _fail(problem, ExitCode.INVALID)
    profile = get_profile(args.profile)
    faults = faults_given(args)
    if isinstance(faults, str):
        return _fail(faults, ExitCode.INVALID)
    refused = None if args.baud is None else simulated_baud_refused(args.baud, profile)
    if refused is not None:
        return _fail(refused, ExitCode.INVALID)
    try:
        world = charged_world(args.world, args.battery)
        simulator = Simulator(
            world,
            profile,
            args.seed,
            faults,
            random_start=args.random_start,
            old_firmware_angle=args.old_firmware_angle,
            # only --plot reads the trajectory: without it, memory stays flat however long
            # the robot is served (13 MB an hour with it)
            trace=bool(args.plot),
            cycle_commands_pause=True,  # as the OI spec says (docs/simulator.md)
        )
    except WorldError as exc:
        return _fail(f"invalid world:\n{exc}", ExitCode.INVALID)
    if args.baud is not None:
        simulator.baud = args.baud
    if args.firmware is not None:
        if parse_firmware(args.firmware) is None:
            return _fail(
                f"--firmware: found {args.firmware!r}; allowed: release-X.Y.Z or "
                "release-stm32-X.Y.Z",
                ExitCode.INVALID,
            )
        simulator.firmware = args.firmware
    if args.asleep:
        simulator.fall_asleep("started asleep (--asleep)")
    return simulator


def _endpoint(args: argparse.Namespace, baud: int) -> Endpoint | int:
    """Where the robot is served (``--pty``, ``--tcp``, ``--rfc2217`` at ``baud``), or the
    exit code after saying why it cannot be."""
    from roomba_bt.sim.server import PtyEndpoint, Rfc2217Endpoint, TcpEndpoint

    try:
        if args.pty:
            return PtyEndpoint()
        option, text = ("--tcp", args.tcp) if args.tcp else ("--rfc2217", args.rfc2217)
        host, sep, port_text = str(text).rpartition(":")
        if not sep or not host or not port_text.isdigit() or int(port_text) > 65535:
            return _fail(
                f"{option}: found {text!r}; allowed: HOST:PORT such as 127.0.0.1:7777",
                ExitCode.INVALID,
            )
        if args.tcp:
            return TcpEndpoint(host, int(port_text))
        return Rfc2217Endpoint(host, int(port_text), baud)
    except OSError as exc:
        return _fail(f"cannot serve: {exc}", ExitCode.CONNECTION)


def _serve_until_stopped(
    simulator: Simulator, endpoint: Endpoint, duration: float | None, *, log: bool = False
) -> int | None:
    """Serve until SIGINT or SIGTERM, or ``duration`` seconds; the endpoint is closed and the
    signal handlers restored. The exit code if the endpoint failed, else None."""
    from roomba_bt.sim.narrate import Narrator
    from roomba_bt.sim.server import serve

    narrator = (
        Narrator(simulator, lambda line: print(line, file=sys.stderr, flush=True)) if log else None
    )

    stop = {"signal": 0}

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop["signal"] = signum

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    print(endpoint.address, flush=True)
    started = time.monotonic()

    def should_stop() -> bool:
        if stop["signal"]:
            return True
        return duration is not None and time.monotonic() - started >= duration

    try:
        serve(simulator, endpoint, should_stop, narrator=narrator)
    except OSError as exc:
        return _fail(f"the {endpoint.address} endpoint failed: {exc}", ExitCode.CONNECTION)
    finally:
        endpoint.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return None
