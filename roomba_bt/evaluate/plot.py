"""All the trajectories of an evaluation on one picture of the world (matplotlib, optional).

Successful episodes are drawn in green, the others in red, each starting at a dot; the dock,
its beams, walls, obstacles and drops are drawn as the simulator knows them. matplotlib is
an optional extra: without it :func:`plot_trajectories` raises :class:`PlotUnavailable`,
which the CLI turns into a clear message.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.sim import World


class PlotUnavailable(ImportError):
    """matplotlib is not installed."""


def _pyplot() -> Any:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise PlotUnavailable(
            f"--plot needs matplotlib, an optional extra: pip install 'roomba-bt[plot]' ({exc})"
        ) from None
    return plt


def plot_trajectories(
    world: World, results: Sequence[EpisodeResult], path: str | Path, title: str = ""
) -> None:
    """Write a PNG of every episode's path in ``world`` to ``path``."""
    plt = _pyplot()
    from matplotlib.patches import Polygon as PolygonPatch
    from matplotlib.patches import Wedge

    def mm(points: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
        return [(x / 1000.0, y / 1000.0) for x, y in points]

    fig, ax = plt.subplots(figsize=(8, 7), dpi=110)
    try:
        for room in world.rooms:
            ax.add_patch(PolygonPatch(mm(room), closed=True, facecolor="#f7f7f2",
                                      edgecolor="black", lw=2))  # fmt: skip
        for x0, y0, x1, y1 in world.walls:
            ax.plot([x0 / 1000, x1 / 1000], [y0 / 1000, y1 / 1000], color="black", lw=2)
        for obstacle in world.obstacles:
            ax.add_patch(PolygonPatch(mm(obstacle), closed=True, facecolor="#b8a88a",
                                      edgecolor="#6b5a3a"))  # fmt: skip
        for drop in world.drops:
            ax.add_patch(PolygonPatch(mm(drop), closed=True, facecolor="#333333", alpha=0.5,
                                      hatch="//", edgecolor="black"))  # fmt: skip
        for vw in world.virtual_walls:
            ax.plot([vw.ax / 1000, vw.bx / 1000], [vw.ay / 1000, vw.by / 1000],
                    color="tab:orange", lw=2, ls="--")  # fmt: skip
        dock = world.dock
        if dock is not None:
            cx, cy, facing = dock.x / 1000, dock.y / 1000, math.degrees(dock.facing)
            reach = dock.buoy_range / 1000
            for beam, colour in ((dock.red, "red"), (dock.green, "green")):
                ax.add_patch(Wedge((cx, cy), reach, facing + math.degrees(beam[0]),
                                   facing + math.degrees(beam[1]), color=colour,
                                   alpha=0.15))  # fmt: skip
            ax.add_patch(Wedge((cx, cy), dock.force_field / 1000, 0, 360, fill=False, ls=":",
                               color="tab:blue"))  # fmt: skip
            x0, y0, x1, y1 = dock.plate
            ax.plot([x0 / 1000, x1 / 1000], [y0 / 1000, y1 / 1000], color="tab:green", lw=5)
        ok = sum(r.succeeded for r in results)
        for result in results:
            colour = "tab:green" if result.succeeded else "tab:red"
            xs = [p[0] for p in result.trajectory]
            ys = [p[1] for p in result.trajectory]
            ax.plot(xs, ys, color=colour, lw=0.7, alpha=0.45 if result.succeeded else 0.8)
            ax.plot(result.start[0], result.start[1], "o", color=colour, ms=2.5)
        ax.plot([], [], color="tab:green", label=f"succeeded ({ok})")
        ax.plot([], [], color="tab:red", label=f"did not ({len(results) - ok})")
        ax.legend(loc="upper right", fontsize=8)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(title or f"{world.name}: {len(results)} episodes")
        fig.savefig(str(path))
    finally:
        plt.close(fig)
