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
from typing import Any

from roomba_bt.cli.arguments import plot_file, seconds
from roomba_bt.runtime.summary import ExitCode


def register(sub: Any) -> None:
    parser = sub.add_parser(
        "sim",
        help="serve the simulated robot on a pty or a TCP socket",
        description="Serve a simulated Roomba / Create 2 in real time. The first stdout line "
        "is the pty path or the socket:// URL to open.",
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
        "--baud", type=int, choices=(19200, 115200), default=None,
        help="the robot's baud rate: 115200 (the default) or 19200 (Clean held at power-off)",
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
    parser.add_argument("--profile", default="create2", help="create2, roomba600 or roomba500")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--random-start", action="store_true", help="start in the start region")
    parser.add_argument(
        "--old-firmware-angle", action="store_true", help="Angle (20) as firmware <= 3.4.0"
    )
    parser.add_argument("--duration", type=seconds, help="stop after this many seconds")
    parser.add_argument(
        "--plot", metavar="FILE.png", type=plot_file, help="write the trajectory on exit"
    )
    faults = parser.add_argument_group("faults")
    faults.add_argument("--corrupt-rate", type=float, default=0.0, help="per-byte probability")
    faults.add_argument("--drop-rate", type=float, default=0.0, help="per-frame probability")
    faults.add_argument("--latency", type=float, default=0.0, help="extra seconds per byte")
    faults.add_argument("--inject-text", default="", help="ASCII printed into the stream")
    faults.add_argument("--inject-every", type=float, default=1.0, help="seconds between texts")
    faults.add_argument("--disconnect-at", type=float, help="drop the line at this time (s)")
    faults.add_argument("--noise", type=float, default=0.0, help="analog sensor noise (raw)")
    faults.add_argument("--bit-flip-rate", type=float, default=0.0, help="per-byte probability")
    faults.add_argument("--truncate-rate", type=float, default=0.0, help="per-frame probability")
    faults.add_argument("--reset-at", type=float, help="the robot resets at this time (s)")
    faults.add_argument("--stream-stop-at", type=float, help="the stream stops at this time (s)")
    faults.add_argument("--sleep-at", type=float, help="the robot falls asleep at this time (s)")
    parser.set_defaults(func=run_sim)


def _fail(message: str, code: ExitCode) -> int:
    print(f"roomba-bt sim: {message}", file=sys.stderr)
    return code


def run_sim(args: argparse.Namespace) -> int:
    from roomba_bt.oi.identify import parse_firmware
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.sim import Faults, Simulator, WorldError, load_world
    from roomba_bt.sim.server import Endpoint, PtyEndpoint, Rfc2217Endpoint, TcpEndpoint, serve

    try:
        profile = get_profile(args.profile)
        faults = Faults(
            corrupt_rate=args.corrupt_rate,
            drop_rate=args.drop_rate,
            latency=args.latency,
            inject_text=args.inject_text,
            inject_every=args.inject_every,
            disconnect_at=args.disconnect_at,
            noise=args.noise,
            bit_flip_rate=args.bit_flip_rate,
            truncate_rate=args.truncate_rate,
            reset_at=args.reset_at,
            stream_stop_at=args.stream_stop_at,
            sleep_at=args.sleep_at,
        )
    except ValueError as exc:
        return _fail(str(exc), ExitCode.INVALID)
    try:
        world = load_world(args.world)
        simulator = Simulator(
            world,
            profile,
            args.seed,
            faults,
            random_start=args.random_start,
            old_firmware_angle=args.old_firmware_angle,
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
    endpoint: Endpoint
    try:
        if args.pty:
            endpoint = PtyEndpoint()
        else:
            option, text = ("--tcp", args.tcp) if args.tcp else ("--rfc2217", args.rfc2217)
            host, sep, port_text = str(text).rpartition(":")
            if not sep or not host or not port_text.isdigit() or int(port_text) > 65535:
                return _fail(
                    f"{option}: found {text!r}; allowed: HOST:PORT such as 127.0.0.1:7777",
                    ExitCode.INVALID,
                )
            if args.tcp:
                endpoint = TcpEndpoint(host, int(port_text))
            else:
                endpoint = Rfc2217Endpoint(host, int(port_text), simulator.baud)
    except OSError as exc:
        return _fail(f"cannot serve: {exc}", ExitCode.CONNECTION)

    stop = {"signal": 0}

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop["signal"] = signum

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    print(endpoint.address, flush=True)
    started = time.monotonic()
    duration = args.duration

    def should_stop() -> bool:
        if stop["signal"]:
            return True
        return duration is not None and time.monotonic() - started >= duration

    try:
        serve(simulator, endpoint, should_stop)
    except OSError as exc:
        return _fail(f"the {endpoint.address} endpoint failed: {exc}", ExitCode.CONNECTION)
    finally:
        endpoint.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    print(
        f"roomba-bt sim: {simulator.time:.1f} s simulated, {simulator.frames_sent} frames, "
        f"{len(simulator.violations)} ignored actuator commands, mode {simulator.mode.label}, "
        f"wheels {simulator.requested_left:.0f}/{simulator.requested_right:.0f} mm/s",
        file=sys.stderr,
    )
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
