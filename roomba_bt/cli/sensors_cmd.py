"""``roomba-bt sensors``: a live table of every decoded sensor, from a robot or the simulator."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from roomba_bt.cli.exit_codes import ExitCode
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import PROFILES, get_profile

#: Group 100 carries every packet (80 bytes, 7-58): one frame is 83 bytes, within the 172-byte
#: budget at 115200 baud but not at 19200, where group 6 (52 bytes, 7-42) is asked instead.
ALL_PACKETS_GROUP = 100
SMALL_GROUP = 6


def register(sub: Any) -> None:
    parser = sub.add_parser(
        "sensors",
        help="show every decoded sensor, live (robot with --port, else the simulator)",
    )
    parser.add_argument("--port", help="serial device or URL; default: the built-in simulator")
    parser.add_argument("--profile", choices=sorted(PROFILES), default="create2")
    parser.add_argument("--baud", type=int, default=115200)
    parser.add_argument("--world", help="simulator world (without --port)")
    parser.add_argument("--count", type=int, default=0, help="stop after N refreshes (0: run)")
    parser.add_argument("--rate", type=float, default=5.0, help="refreshes per second")
    parser.set_defaults(func=sensors_command)


def format_table(frame: Any) -> str:
    rows = []
    for name, value in frame.as_dict().items():
        pid = next(p.id for p in PACKETS.values() if p.name == name)
        unit = PACKETS[pid].unit
        shown = _show(value)
        rows.append(f"{pid:>3}  {name:<32} {shown:<40} {unit}")
    return "\n".join(rows)


def _show(value: object) -> str:
    slots = getattr(value, "__slots__", None)
    if slots and hasattr(value, "raw"):
        on = [s for s in slots if s != "raw" and getattr(value, s) is True]
        return f"{value.raw} [{', '.join(on) or '-'}]"
    if hasattr(value, "code") and hasattr(value, "source"):
        flags = [
            f
            for f in ("red_buoy", "green_buoy", "force_field", "virtual_wall")
            if getattr(value, f)
        ]
        return f"{value.code} {value.source.value} {' '.join(flags)}".strip()
    if hasattr(value, "name") and hasattr(value, "value"):
        return f"{value.value} {value.name.lower()}"
    return str(value)


def sensors_command(args: argparse.Namespace) -> int:
    from roomba_bt.robot.connection import Connection
    from roomba_bt.robot.errors import ConnectionFailed, LinkDown
    from roomba_bt.robot.safety import sigterm_raises

    profile = get_profile(args.profile)
    group = ALL_PACKETS_GROUP if args.baud >= 57600 else SMALL_GROUP
    try:
        if args.port:
            connection = Connection.open(args.port, args.baud, profile)
        else:
            from roomba_bt.cli.simulated import make_link, make_simulator
            from roomba_bt.sim import WorldError

            try:
                simulator = make_simulator(args.world, profile, 0)
            except WorldError as exc:
                print(f"roomba-bt: {exc}", file=sys.stderr)
                return ExitCode.INVALID
            connection = Connection(make_link(simulator, fast=False), profile, baud=args.baud)
        interactive = sys.stdout.isatty()
        shown = 0
        with sigterm_raises(), connection:
            connection.start("passive", (group,))
            last = 0.0
            while args.count == 0 or shown < args.count:
                frames = connection.poll(0.1)
                if not frames or time.monotonic() - last < 1.0 / args.rate:
                    continue
                last = time.monotonic()
                table = format_table(frames[-1].frame)
                prefix = "\x1b[H\x1b[J" if interactive else ""
                print(f"{prefix}{connection.name}  ({profile.title})\n{table}\n", flush=True)
                shown += 1
    except ConnectionFailed as exc:
        print(f"roomba-bt: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    except LinkDown as exc:
        print(f"roomba-bt: {exc}", file=sys.stderr)
        return ExitCode.CONNECTION
    except KeyboardInterrupt:
        return ExitCode.INTERRUPTED
    return ExitCode.OK
