"""All the trajectories of an evaluation on one picture of the world (matplotlib, optional).

Successful episodes are drawn in green, the others in red, each starting at a dot, over the
world as the simulator draws it (:func:`roomba_bt.sim.plot.draw_world`). matplotlib is an
optional extra: without it :func:`plot_trajectories` raises
:class:`~roomba_bt.sim.plot.PlotUnavailableError`, which the CLI turns into a clear message.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.sim import World
from roomba_bt.sim.plot import PlotUnavailableError, draw_world, pyplot

__all__ = ["PlotUnavailableError", "plot_trajectories"]


def plot_trajectories(
    world: World, results: Sequence[EpisodeResult], path: str | Path, title: str = ""
) -> None:
    """Write a PNG of every episode's path in ``world`` to ``path``."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 7), dpi=110)
    try:
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
        ax.legend(loc="upper right", fontsize=8)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(title or f"{world.name}: {len(results)} episodes")
        fig.savefig(str(path))
    finally:
        plt.close(fig)
