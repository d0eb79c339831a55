"""The trajectories of an evaluation drawn over the world (matplotlib, optional).

Successful episodes are drawn in green, the others in red, each starting at a dot, over the
world as the simulator draws it (:func:`roomba_bt.sim.plot.draw_world`). Several variants
(``eval A B --plot``, a sweep) are one figure of panels side by side, one a variant, each over
the same world: :func:`plot_variants`. matplotlib is an optional extra: without it these raise
:class:`~roomba_bt.sim.plot.PlotUnavailableError`, which the CLI turns into a clear message.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.sim import World
from roomba_bt.sim.plot import PlotUnavailableError, draw_world, pyplot

__all__ = ["PlotUnavailableError", "plot_trajectories", "plot_variants"]

#: One panel: its title and the episodes drawn in it.
Panel = tuple[str, Sequence[EpisodeResult]]


def plot_trajectories(
    world: World, results: Sequence[EpisodeResult], path: str | Path, title: str = ""
) -> None:
    """Write a picture of every episode's path in ``world`` to ``path`` (its suffix: the
    format, .png, .pdf, .svg, ...)."""
    plot_variants(world, [(title or f"{world.name}: {len(results)} episodes", results)], path)


def plot_variants(world: World, panels: Sequence[Panel], path: str | Path) -> None:
    """Write one figure to ``path``: a panel a variant, side by side, each the world with that
    variant's episodes drawn over it and titled with its ``panels`` title."""
    plt = pyplot()
    fig = variants_figure(world, panels)
    try:
        # cut to fit what is drawn, the legends below the maps included
        fig.savefig(str(path), bbox_inches="tight")
    finally:
        plt.close(fig)


def variants_figure(world: World, panels: Sequence[Panel]) -> Any:
    """The figure :func:`plot_variants` writes (a matplotlib ``Figure``, for the caller to
    save and close): a panel a variant, side by side."""
    if not panels:
        raise ValueError("plot_variants: no panel to draw")
    plt = pyplot()
    fig, axes = plt.subplots(
        1, len(panels), figsize=(8 if len(panels) == 1 else 6 * len(panels), 7), dpi=110,
        squeeze=False,
    )  # fmt: skip
    for ax, (title, results) in zip(axes[0], panels, strict=True):
        _draw_trajectories(ax, world, results)
        ax.set_title(title, fontsize=10 if len(panels) > 1 else None)
    if len(panels) > 1:
        fig.tight_layout()
    return fig


def _draw_trajectories(ax: Any, world: World, results: Sequence[EpisodeResult]) -> None:
    """The world and every episode's path on the axes ``ax``, with a legend of the counts."""
    draw_world(ax, world, labels=False)
    ok = sum(r.succeeded for r in results)
    for result in results:
        colour = "tab:green" if result.succeeded else "tab:red"
        xs = [p[0] for p in result.trajectory]
        ys = [p[1] for p in result.trajectory]
        ax.plot(xs, ys, color=colour, lw=0.7, alpha=0.45 if result.succeeded else 0.8)
        ax.plot(result.start[0], result.start[1], "o", color=colour, ms=2.5)
    ax.plot([], [], color="tab:green", label=f"succeeded ({ok})")
    ax.plot([], [], color="tab:red", label=f"did not ({len(results) - ok})")
    # below the map, not on it: "upper right" hid the world's corner and the paths there
    # (an apartment's bedroom, its dock), one panel or several; as the simulator's --plot
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2, fontsize=8, frameon=False)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
