"""``roomba-bt worlds``: the simulator's shipped worlds, listed or printed as shipped (a
wheel's user found them only by opening the package's folder)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from roomba_bt.cli.arguments import add_command
from roomba_bt.runtime.summary import ExitCode


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "worlds",
        worlds_command,
        """list the shipped simulator worlds, or print one

        List the worlds shipped with roomba-bt (give one to run, sim or eval: --world
        apartment), each with its description, size, areas and dock. With NAME, print that
        world's file as shipped, its comments included: a start for a world of your own
        (docs/simulator.md, Worlds).
        """,
    )
    parser.add_argument("name", nargs="?", metavar="NAME", help="print this shipped world")


def worlds_command(args: argparse.Namespace) -> int:
    from roomba_bt.behaviours.units import closest
    from roomba_bt.sim.world import WORLDS_DIR, load_world, shipped_worlds

    names = shipped_worlds()
    if args.name is not None:
        name = args.name.removesuffix(".yaml")
        if name not in names:
            hint = closest(name, list(names))
            print(f"roomba-bt worlds: no shipped world {args.name!r}{hint}; shipped: "
                  f"{', '.join(names)}", file=sys.stderr)  # fmt: skip
            return ExitCode.INVALID
        sys.stdout.write((WORLDS_DIR / f"{name}.yaml").read_text(encoding="utf-8"))
        return ExitCode.OK
    for name in names:
        world = load_world(name)
        xs = [x for room in world.rooms for x, _ in room]
        ys = [y for room in world.rooms for _, y in room]
        size = f"{(max(xs) - min(xs)) / 1000:g} x {(max(ys) - min(ys)) / 1000:g} m"
        areas = ", ".join(a.name for a in world.areas) or "none"
        dock = "a dock" if world.dock is not None else "no dock"
        print(f"{name}  {world.description}")
        print(f"    {size}, {dock}; areas: {areas}")
    return ExitCode.OK
