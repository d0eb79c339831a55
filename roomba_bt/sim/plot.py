"""A picture of a simulated run: walls, drops, dirt patches, the dock and its beams, the path
coloured by time, bumps and mode changes marked, the floor cleaned shaded (when the simulator
tracks it). PNG via matplotlib, an optional extra, imported only here and only when a plot is
asked for.

:func:`draw_world` is the one drawing of a world; ``roomba-bt eval --plot``
(:mod:`roomba_bt.evaluate.plot`) draws its trajectories over it too.
"""

from __future__ import annotations

import math
import pathlib
from typing import Any

from roomba_bt.errors import RoombaBtError
from roomba_bt.installation import optional_import_failure
from roomba_bt.sim.coverage import SweptArea
from roomba_bt.sim.geometry import Polygon
from roomba_bt.sim.robot import Simulator
from roomba_bt.sim.world import World


class PlotUnavailableError(ImportError, RoombaBtError):
    """matplotlib is not installed, or installed incompletely: the message says which, and
    the pip line that repairs it."""


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the file-only Agg backend; :class:`PlotUnavailableError` if
    matplotlib is not installed or its import fails (a dependency of its own missing)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        needs = (
            f"plotting needs matplotlib, an optional extra: pip install 'roomba-bt[plot]' ({exc})"
        )
        raise PlotUnavailableError(optional_import_failure(exc, needs)) from None
    return plt


_EVENT_STYLE = {
    "bump": ("x", "tab:red", "bump"),
    "cliff": ("v", "tab:purple", "cliff"),
    "wheel_drop": ("^", "tab:brown", "wheel drop"),
    "mode": ("s", "tab:blue", "mode change"),
    "docked": ("*", "tab:green", "docked"),
    "fell": ("X", "black", "fell"),
    "disconnect": ("D", "tab:gray", "disconnect"),
}


def draw_world(ax: Any, world: World, *, labels: bool = True) -> None:
    """Rooms, dirt patches (each with the dirt-detect level, packet 15, the robot reads over
    it: a plugin's condition on it is then read against the picture), walls, obstacles,
    drops, virtual walls, lighthouses and the dock with its beams, in metres, on the
    matplotlib axes ``ax`` (legend labels unless ``labels`` is False)."""
    from matplotlib.patches import Polygon as PolygonPatch
    from matplotlib.patches import Wedge

    def label(text: str) -> str | None:
        return text if labels else None

    def polygon(points: Polygon, **style: Any) -> None:
        ax.add_patch(PolygonPatch([(x / 1000, y / 1000) for x, y in points], closed=True, **style))

    for room in world.rooms:
        polygon(room, facecolor="#f7f7f2", edgecolor="black", lw=2)
    for patch in world.dirt:  # on the floor: under everything else
        polygon(patch.area, facecolor="#c9a36b", alpha=0.45, hatch="..", edgecolor="#8a6a3a",
                label=label("dirt (level, packet 15)"))  # fmt: skip
        x, y = middle(patch.area)
        ax.text(x / 1000, y / 1000, str(patch.level), ha="center", va="center", fontsize=7,
                color="#5a4020")  # fmt: skip
    for ax0, ay0, ax1, ay1 in world.walls:
        ax.plot([ax0 / 1000, ax1 / 1000], [ay0 / 1000, ay1 / 1000], color="black", lw=2)
    for obstacle in world.obstacles:
        polygon(obstacle, facecolor="#b8a88a", edgecolor="#6b5a3a")
    for drop in world.drops:
        polygon(drop, facecolor="#333333", alpha=0.55, hatch="//", edgecolor="black",
                label=label("drop"))  # fmt: skip
    for vw in world.virtual_walls:
        ax.plot([vw.ax / 1000, vw.bx / 1000], [vw.ay / 1000, vw.by / 1000],
                color="tab:orange", lw=2, ls="--", label=label("virtual wall"))  # fmt: skip
    for lh in world.lighthouses:
        x0, y0, x1, y1 = lh.fence_segment
        ax.plot([x0 / 1000, x1 / 1000], [y0 / 1000, y1 / 1000], color="tab:orange", ls=":")
        ax.plot(lh.x / 1000, lh.y / 1000, "o", color="tab:orange")
    dock = world.dock
    if dock is not None:
        cx, cy = dock.x / 1000, dock.y / 1000
        facing = math.degrees(dock.facing)
        r = dock.buoy_range / 1000
        ax.add_patch(Wedge((cx, cy), r, facing + math.degrees(dock.red[0]),
                           facing + math.degrees(dock.red[1]), color="red", alpha=0.15,
                           label=label("red buoy")))  # fmt: skip
        ax.add_patch(Wedge((cx, cy), r, facing + math.degrees(dock.green[0]),
                           facing + math.degrees(dock.green[1]), color="green", alpha=0.15,
                           label=label("green buoy")))  # fmt: skip
        ax.add_patch(Wedge((cx, cy), dock.force_field / 1000, 0, 360, fill=False,
                           ls=":", color="tab:blue", label=label("force field")))  # fmt: skip
        x0, y0, x1, y1 = dock.plate
        ax.plot([x0 / 1000, x1 / 1000], [y0 / 1000, y1 / 1000], color="tab:green", lw=5)


def middle(points: Polygon) -> tuple[float, float]:
    """The middle of a shape's bounding box: where its label is written."""
    xs = [x for x, _ in points]
    ys = [y for _, y in points]
    return (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2


def draw_swept(ax: Any, swept: SweptArea) -> None:
    """Shade the floor: reachable in light grey, cleaned in green (one image of the grid)."""
    from matplotlib.colors import ListedColormap

    grid = swept.grid
    rows = [list(swept.cells[j * grid.columns : (j + 1) * grid.columns]) for j in range(grid.rows)]
    extent = (
        grid.x0 / 1000, (grid.x0 + grid.columns * grid.cell) / 1000,
        grid.y0 / 1000, (grid.y0 + grid.rows * grid.cell) / 1000,
    )  # fmt: skip
    colours = ListedColormap([(1, 1, 1, 0), (0.85, 0.85, 0.85, 0.7), (0.3, 0.75, 0.35, 0.6)])
    ax.imshow(rows, origin="lower", extent=extent, cmap=colours, vmin=0, vmax=2,
              interpolation="nearest", zorder=1)  # fmt: skip
    cleaned = swept.area_m2(swept.cleaned_total)
    ax.plot([], [], "s", color=(0.3, 0.75, 0.35), label=f"cleaned {cleaned:.1f} m² "
            f"({100 * swept.coverage():.0f} %)")  # fmt: skip


def plot_run(simulator: Simulator, path: str | pathlib.Path, title: str | None = None) -> None:
    """Write the trajectory of ``simulator`` so far to ``path`` (PNG)."""
    plt = pyplot()
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Wedge

    world = simulator.world
    fig, ax = plt.subplots(figsize=(8, 7), dpi=110)
    try:
        draw_world(ax, world)
        swept = simulator.swept
        if swept is not None and swept.cleaning_time:
            draw_swept(ax, swept)
        trace = simulator.trace
        points = [(p.x / 1000, p.y / 1000) for p in trace]
        points.append((simulator.x / 1000, simulator.y / 1000))
        times = [p.time for p in trace] + [simulator.time]
        if len(points) > 1:
            segments = [[points[i], points[i + 1]] for i in range(len(points) - 1)]
            lines = LineCollection(segments, cmap="viridis", lw=2)
            lines.set_array(times[:-1])
            ax.add_collection(lines)
            fig.colorbar(lines, ax=ax, label="time (s)", shrink=0.8)
        ax.plot(points[0][0], points[0][1], "o", color="black", label="start", zorder=6)
        heading = simulator.theta
        ax.arrow(simulator.x / 1000, simulator.y / 1000, 0.2 * math.cos(heading),
                 0.2 * math.sin(heading), width=0.02, color="black")  # fmt: skip
        ax.add_patch(Wedge((simulator.x / 1000, simulator.y / 1000), 0.17, 0, 360,
                           fill=False, color="black"))  # fmt: skip
        seen: set[str] = set()
        for event in simulator.events:
            style = _EVENT_STYLE.get(event.kind)
            if style is None:
                continue
            marker, colour, label = style
            ax.plot(event.x / 1000, event.y / 1000, marker, color=colour, ms=8, zorder=5,
                    label=None if label in seen else label)  # fmt: skip
            seen.add(label)
        handles, labels = ax.get_legend_handles_labels()
        unique = dict(zip(labels, handles, strict=True))
        # below the map, not on it: "upper right" hid a world's hall and step (an owner's
        # living room); the saved figure is cut to fit it (``bbox_inches``)
        ax.legend(unique.values(), unique.keys(), loc="upper center", fontsize=7,
                  bbox_to_anchor=(0.5, -0.09), ncol=4, frameon=False)  # fmt: skip
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(
            title
            or f"{world.name}: {simulator.time:.1f} s, {len(simulator.violations)} "
            f"ignored commands, final mode {simulator.mode.label}"
        )
        fig.savefig(str(path), bbox_inches="tight")
    finally:
        plt.close(fig)
